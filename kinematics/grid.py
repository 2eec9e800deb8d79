"""Regular grids over task coordinates: the sample points of workspace maps and design studies.

Only describes task-space points (``GridSpec.points``); ``metrics.workspace`` evaluates
quantities on them, ``resources`` reads them from presets and study files.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .arrays import FloatArray


@dataclass(frozen=True)
class GridSpec:
    """A regular grid over some task coordinates, the others fixed. Lengths in m.

    ``axes`` names the varied coordinates (e.g. ``("x", "z")``), ``lower``/``upper`` their
    ranges (inclusive), ``resolution`` the points per axis; ``fixed`` maps each other task
    coordinate to its value. Arrays of a map have shape ``resolution`` (``indexing="ij"``).
    """

    axes: tuple[str, ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    resolution: tuple[int, ...]
    fixed: tuple[tuple[str, float], ...] = ()

    def __post_init__(self) -> None:
        k = len(self.axes)
        if k not in (2, 3):
            raise ValueError(f"a grid varies 2 or 3 coordinates, got axes {self.axes!r}")
        for name in ("lower", "upper", "resolution"):
            if len(getattr(self, name)) != k:
                raise ValueError(f"{name} needs {k} values, one per axis {self.axes!r}, got {getattr(self, name)!r}")
        for axis, lo, hi, n in zip(self.axes, self.lower, self.upper, self.resolution):
            if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                raise ValueError(f"range of axis {axis!r} must be finite with lower < upper, got [{lo}, {hi}]")
            if int(n) != n or n < 2:
                raise ValueError(f"resolution of axis {axis!r} must be an integer >= 2, got {n!r}")

    def with_resolution(self, resolution: int | tuple[int, ...]) -> "GridSpec":
        """The same grid with ``resolution`` points per axis (an int applies to every axis).

        Parameters
        ----------
        resolution : int or tuple of int
            Points per axis (each at least 2).

        Returns
        -------
        GridSpec

        Examples
        --------
        >>> GridSpec(("x", "y"), (-0.1, 0.1), (0.1, 0.2), (3, 3)).with_resolution(5).resolution
        (5, 5)
        """
        res = (resolution,) * len(self.axes) if isinstance(resolution, (int, np.integer)) else tuple(resolution)
        return GridSpec(self.axes, self.lower, self.upper, tuple(int(r) for r in res), self.fixed)

    def coordinates(self) -> list[FloatArray]:
        """The 1D coordinates of each axis, in m.

        Returns
        -------
        list of ndarray, shape (resolution[k],)
            One per axis, from ``lower[k]`` to ``upper[k]`` inclusive.

        Examples
        --------
        >>> [c.tolist() for c in GridSpec(("x", "y"), (0.0, 0.0), (1.0, 2.0), (3, 2)).coordinates()]
        [[0.0, 0.5, 1.0], [0.0, 2.0]]
        """
        return [np.linspace(lo, hi, n) for lo, hi, n in zip(self.lower, self.upper, self.resolution)]

    def spacing(self) -> tuple[float, ...]:
        """Distance between neighbouring points along each axis, in m.

        Returns
        -------
        tuple of float, length ``len(axes)``

        Examples
        --------
        >>> GridSpec(("x", "y"), (0.0, 0.0), (1.0, 2.0), (3, 2)).spacing()
        (0.5, 2.0)
        """
        return tuple((hi - lo) / (n - 1) for lo, hi, n in zip(self.lower, self.upper, self.resolution))

    def points(self, task_names: tuple[str, ...], index: np.ndarray | slice | None = None) -> FloatArray:
        """Task-space points of the grid, shape ``resolution + (m,)``.

        With ``index`` (flat indices into the grid, C order), only those points, shape
        ``(len(index), m)``: a chunk of a map needs no full point array.

        Parameters
        ----------
        task_names : tuple of str
            The mechanism's task coordinates, in order (length ``m``); each must be an axis or fixed.
        index : ndarray of int or slice, optional
            Flat indices (C order) of the points wanted; default all.

        Returns
        -------
        ndarray, shape ``resolution + (m,)``, or ``(len(index), m)`` with ``index``
            m (and rad for orientation coordinates).

        Raises
        ------
        ValueError
            If a task coordinate is neither an axis nor fixed.

        Examples
        --------
        >>> grid = GridSpec(("x", "z"), (0.0, 0.0), (1.0, 1.0), (2, 3), fixed=(("y", 0.5),))
        >>> grid.points(("x", "y", "z")).shape
        (2, 3, 3)
        >>> grid.points(("x", "y", "z"), index=slice(0, 2)).tolist()
        [[0.0, 0.5, 0.0], [0.0, 0.5, 0.5]]
        """
        fixed = dict(self.fixed)
        total = math.prod(int(n) for n in self.resolution)
        if index is None:
            flat = np.arange(total)
        elif isinstance(index, slice):
            flat = np.arange(*index.indices(total))
        else:
            flat = np.asarray(index)
        ijk = np.unravel_index(flat, self.resolution)
        out = np.empty((flat.size, len(task_names)))
        for j, name in enumerate(task_names):
            if name in self.axes:
                k = self.axes.index(name)
                # Only the coordinates asked for: an axis of 10^6 points is 8 MB per chunk otherwise.
                out[:, j] = _axis_values(self.lower[k], self.upper[k], int(self.resolution[k]), ijk[k])
            elif name in fixed:
                out[:, j] = fixed[name]
            else:
                raise ValueError(f"grid has no value for task coordinate {name!r}: add it to axes or fixed")
        return out if index is not None else out.reshape(tuple(self.resolution) + (len(task_names),))


def _axis_values(lo: float, hi: float, n: int, index: np.ndarray) -> FloatArray:
    """``np.linspace(lo, hi, n)[index]`` without making the whole axis, to the last bit.

    numpy's own arithmetic: ``i * step + lo`` with ``step = (hi - lo) / (n - 1)`` (``i / (n - 1)
    * (hi - lo)`` where the step underflows to 0), and the last point set to ``hi``.

    Examples
    --------
    >>> _axis_values(0.0, 1.0, 3, np.array([2, 0, 1])).tolist()
    [1.0, 0.0, 0.5]
    """
    i = np.asarray(index)
    div = n - 1
    step = (hi - lo) / div
    out = i.astype(np.float64) * step if step != 0.0 else i.astype(np.float64) / div * (hi - lo)
    out += lo
    out[i == div] = hi
    return out
