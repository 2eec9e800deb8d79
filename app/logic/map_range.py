"""The map's range fitted to a design's workspace: View > Fit map to workspace (no Qt).

A preset's map range is drawn around its own link lengths; a design with longer links reaches
past it (its map is cut at the range's edge) and one with shorter links leaves most of the map
blank. ``fit_grid`` finds the workspace's extent on the map's slice (or box) and returns the
grid over it, at the same points per axis.

How: the feasible points (``Mechanism.inverse`` and ``Mechanism.feasible``, as the map decides
them) on a ``SEARCH_POINTS`` grid over a box. Where feasible points reach a side of the box,
the box grows by its span on that side and the search repeats (``GROWTH_ROUNDS`` times at
most); once no side is reached, the box shrinks to the feasible points' bounding box plus
``MARGIN_CELLS`` search cells each side (the true boundary lies between the last feasible and
the first infeasible sample), and the search repeats over it (``SHRINKS`` times): the fit ends
with a box on whose faces no search point is feasible. The search follows the workspace from
the map's range outwards: a region apart from it (a mirror image of the workspace that the
model also reaches, such as the Falcon's below its base) is not looked for.
The bounds are rounded outward to a round step (``round_step``).
"""
from __future__ import annotations

import math

import numpy as np

from kinematics.grid import GridSpec

#: Search points per axis of a 2D slice (3D box: ``SEARCH_POINTS_3D``): the extent is known to
#: one cell of the search box, 1/159 of its span (1/39).
SEARCH_POINTS = 160
SEARCH_POINTS_3D = 40
#: Search cells added beyond the feasible samples' bounding box: the boundary lies within one
#: cell of the last feasible sample along the axis, and a tip narrower than a cell across it may
#: reach one cell more between the samples.
MARGIN_CELLS = 2
#: Rounds the search box may grow by (each adds the box's span on every side that is reached).
GROWTH_ROUNDS = 6
#: Times the box shrinks to the feasible samples' bounding box plus one search cell: the
#: second narrows the margin to a cell of the first fitted box.
SHRINKS = 2


class NoWorkspace(ValueError):
    """No feasible point in or around the map's range: there is no workspace to fit."""


def feasible_mask(mechanism, grid: GridSpec) -> np.ndarray:
    """Whether each point of ``grid`` is feasible (reachable and within every limit), shape ``grid.resolution``.

    Parameters
    ----------
    mechanism : Mechanism
        The design.
    grid : GridSpec
        Task points (m).

    Returns
    -------
    ndarray of bool, shape ``grid.resolution``
    """
    points = grid.points(mechanism.task_names).reshape(-1, mechanism.task_dim)
    q, ok = mechanism.inverse(points)
    feasible = np.asarray(ok, bool).copy()
    if feasible.any():
        feasible[feasible] = mechanism.feasible(q[feasible], points[feasible])
    return feasible.reshape(tuple(grid.resolution))


def round_step(span: float) -> float:
    """A round length (1, 2 or 5 x 10^k m) of about a fiftieth of ``span`` (m) to round the bounds to.

    >>> round_step(0.52), round_step(0.2), round_step(0.0)
    (0.01, 0.002, 0.001)
    """
    if not span > 0:
        return 1e-3
    raw = span / 50.0
    k = math.floor(math.log10(raw))
    for m in (5.0, 2.0, 1.0):
        if m * 10.0 ** k <= raw * (1 + 1e-12):
            return float(f"{m * 10.0 ** k:.12g}")
    return float(f"{10.0 ** k:.12g}")


def _lengths(mechanism, grid: GridSpec) -> list[int]:
    """The grid's axes that are lengths (a pen's angles keep their range)."""
    units = dict(zip(mechanism.task_names, mechanism.task_units))
    return [k for k, a in enumerate(grid.axes) if units.get(a) == "m"]


def fit_grid(mechanism, grid: GridSpec) -> GridSpec:
    """``grid`` with the range of each length axis fitted to the workspace's extent on it.

    Parameters
    ----------
    mechanism : Mechanism
        The design whose workspace the map should show.
    grid : GridSpec
        The map's grid now: its axes, fixed coordinates, points per axis and angle ranges are kept.

    Returns
    -------
    GridSpec
        The same axes and resolution over the workspace's extent, rounded outward to
        ``round_step`` of each span.

    Raises
    ------
    NoWorkspace
        No feasible point in the range or ``GROWTH_ROUNDS`` spans around it.
    """
    lengths = _lengths(mechanism, grid)
    n = SEARCH_POINTS if len(grid.axes) == 2 else SEARCH_POINTS_3D
    lower, upper = np.array(grid.lower, float), np.array(grid.upper, float)
    angles = [k for k in range(len(lower)) if k not in lengths]
    shrinks, found = 0, False
    for _ in range(GROWTH_ROUNDS + SHRINKS + 2):
        search = GridSpec(grid.axes, tuple(lower), tuple(upper), (n,) * len(grid.axes), grid.fixed)
        mask = feasible_mask(mechanism, search)
        if not mask.any():
            if found:           # a box that held feasible points lost them: keep the last that did
                break
            # Nothing here: look at a box three times as wide (the workspace may lie beside the range).
            every = np.ones(len(lower), bool)
            lower, upper = _grow(lower, upper, lengths, every, every)
            continue
        found = True
        low_hit, high_hit = _edges(mask)
        low_hit[angles] = high_hit[angles] = False
        if low_hit.any() or high_hit.any():
            lower, upper = _grow(lower, upper, lengths, low_hit, high_hit)
            continue
        if shrinks == SHRINKS:
            break               # no feasible point on a face of a box fitted twice: done
        lo, hi = _feasible_box(search, mask)
        lower[lengths], upper[lengths] = lo[lengths], hi[lengths]
        shrinks += 1
    if not found:
        raise NoWorkspace("no feasible point in or around the map's range: this design has no workspace to fit")
    for k in lengths:
        step = round_step(upper[k] - lower[k])
        lower[k] = math.floor(lower[k] / step + 1e-9) * step
        upper[k] = math.ceil(upper[k] / step - 1e-9) * step
    return GridSpec(grid.axes, tuple(float(f"{v:.12g}") for v in lower), tuple(float(f"{v:.12g}") for v in upper),
                    grid.resolution, grid.fixed)


def _edges(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per axis, whether feasible points lie on the box's lower and upper face, shape (k,) each."""
    k = mask.ndim
    low = np.array([mask.take(0, axis=a).any() for a in range(k)])
    high = np.array([mask.take(-1, axis=a).any() for a in range(k)])
    return low, high


def _grow(lower, upper, lengths, low_hit, high_hit):
    span = upper - lower
    lower, upper = lower.copy(), upper.copy()
    for k in lengths:
        lower[k] -= span[k] if low_hit[k] else 0.0
        upper[k] += span[k] if high_hit[k] else 0.0
    return lower, upper


def _feasible_box(search: GridSpec, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The feasible samples' bounding box plus ``MARGIN_CELLS`` search cells each side (within the search box), m."""
    coords = search.coordinates()
    lo, hi = np.array(search.lower, float), np.array(search.upper, float)
    for a, c in enumerate(coords):
        others = tuple(b for b in range(mask.ndim) if b != a)
        hit = np.flatnonzero(mask.any(axis=others))
        cell = c[1] - c[0]
        lo[a] = max(c[hit[0]] - MARGIN_CELLS * cell, c[0])
        hi[a] = min(c[hit[-1]] + MARGIN_CELLS * cell, c[-1])
    return lo, hi
