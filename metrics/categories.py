"""How often each value of a categorical quantity occurs over a map, streamed chunk by chunk.

``compute_map`` takes statistics of the scalar quantities only; a categorical one (the
``bottleneck`` actuator, the ``singularity`` class) has no mean, but its share of the
workspace says which actuator limits a device where. ``category_counts`` counts it over the
feasible points of a grid with the memory of a few chunks, whatever the resolution.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from kinematics.grid import GridSpec

from .map_chunks import chunk_results
from .quantities import QUANTITIES, check_quantities, evaluate


@dataclass(frozen=True)
class CategoryCounts:
    """Counts of each code of one categorical quantity over a grid's feasible points.

    ``counts`` maps a code (an actuator index, or ``bottleneck.BOTTLENECK_TIE`` /
    ``BOTTLENECK_SHARED``) to its number of feasible points; they add up to ``feasible_points``.
    """

    quantity: str
    counts: dict[int, int]
    feasible_points: int
    total_points: int

    def shares(self) -> dict[int, float]:
        """Each code's fraction of the feasible points (empty when there is none).

        Returns
        -------
        dict of int to float
            Fractions in [0, 1] adding up to 1.
        """
        if not self.feasible_points:
            return {}
        return {code: n / self.feasible_points for code, n in self.counts.items()}


def category_counts(mechanism, grid: GridSpec, quantity: str = "bottleneck", *, threads: bool = True,
                    loading=None) -> CategoryCounts:
    """Count each value of the categorical ``quantity`` over the feasible points of ``grid``.

    Parameters
    ----------
    mechanism : Mechanism
        The model (task points ``(..., m)``).
    grid : GridSpec
        The grid, lengths in m.
    quantity : str
        A categorical quantity of ``metrics.quantities.QUANTITIES`` (``bottleneck``, ``singularity``).
    threads : bool
        Use the shared thread pool of ``metrics.workspace``.
    loading : metrics.loading.Loading, optional
        Torque rating and gravity (``evaluate``'s ``loading``); default continuous, gravity off.

    Returns
    -------
    CategoryCounts
        Codes in increasing order; singular feasible points count like any other.

    Raises
    ------
    ValueError
        If ``quantity`` is unknown, not categorical, or not provided by the mechanism.

    Examples
    --------
    >>> from kinematics.fivebar import FiveBar
    >>> g = GridSpec(("x", "y"), (-0.1, 0.1), (0.1, 0.3), (11, 11))
    >>> c = category_counts(FiveBar(), g)
    >>> sum(c.counts.values()) == c.feasible_points
    True
    """
    (name,) = check_quantities(mechanism, [quantity])
    if not QUANTITIES[name].categorical:
        raise ValueError(f"quantity must be categorical (e.g. 'bottleneck'), got {quantity!r}")
    total = math.prod(int(r) for r in grid.resolution)

    def work(span: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
        ev = evaluate(mechanism, grid.points(mechanism.task_names, slice(*span)), [name], loading=loading)
        codes = np.asarray(ev.values[name])[ev.feasible]
        return np.unique(codes.astype(np.int64), return_counts=True)

    counts: dict[int, int] = {}
    for codes, n in chunk_results(work, total, threads=threads):
        for code, k in zip(codes.tolist(), n.tolist()):
            counts[code] = counts.get(code, 0) + k
    counts = dict(sorted(counts.items()))
    return CategoryCounts(name, counts, sum(counts.values()), total)
