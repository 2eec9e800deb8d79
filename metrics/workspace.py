"""Workspace maps: a grid (2D slice or 3D volume), a feasibility mask, quantities, statistics.

A map is evaluated in chunks (``CHUNK`` points) on a small thread pool: numpy's ufuncs
release the GIL, so two cores give close to twice the speed, and between chunks a caller
can report progress or cancel.
"""
from __future__ import annotations

import math
import os
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from kinematics.base import FloatArray

from .quantities import QUANTITIES, check_quantities, evaluate

#: Largest chunk; small maps are split into one chunk per worker so both cores work.
CHUNK = 65536
MIN_CHUNK = 4096
_POOL: ThreadPoolExecutor | None = None
_POOL_LOCK = threading.Lock()


def _pool() -> ThreadPoolExecutor:
    global _POOL
    with _POOL_LOCK:
        if _POOL is None:
            _POOL = ThreadPoolExecutor(max_workers=max(1, os.cpu_count() or 1), thread_name_prefix="isoforce-map")
        return _POOL


class Cancelled(Exception):
    """Raised by ``compute_map`` when its ``cancelled`` callback says so."""


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
        """The same grid with ``resolution`` points per axis (an int applies to every axis)."""
        res = (resolution,) * len(self.axes) if isinstance(resolution, (int, np.integer)) else tuple(resolution)
        return GridSpec(self.axes, self.lower, self.upper, tuple(int(r) for r in res), self.fixed)

    def coordinates(self) -> list[FloatArray]:
        """The 1D coordinates of each axis, in m."""
        return [np.linspace(lo, hi, n) for lo, hi, n in zip(self.lower, self.upper, self.resolution)]

    def spacing(self) -> tuple[float, ...]:
        return tuple((hi - lo) / (n - 1) for lo, hi, n in zip(self.lower, self.upper, self.resolution))

    def points(self, task_names: tuple[str, ...], index: np.ndarray | slice | None = None) -> FloatArray:
        """Task-space points of the grid, shape ``resolution + (m,)``.

        With ``index`` (flat indices into the grid, C order), only those points, shape
        ``(len(index), m)``: a chunk of a map needs no full point array.
        """
        fixed = dict(self.fixed)
        total = int(np.prod(self.resolution))
        if index is None:
            flat = np.arange(total)
        elif isinstance(index, slice):
            flat = np.arange(*index.indices(total))
        else:
            flat = np.asarray(index)
        ijk = np.unravel_index(flat, self.resolution)
        out = np.empty((flat.size, len(task_names)))
        coords = self.coordinates()
        for j, name in enumerate(task_names):
            if name in self.axes:
                k = self.axes.index(name)
                out[:, j] = coords[k][ijk[k]]
            elif name in fixed:
                out[:, j] = fixed[name]
            else:
                raise ValueError(f"grid has no value for task coordinate {name!r}: add it to axes or fixed")
        return out if index is not None else out.reshape(tuple(self.resolution) + (len(task_names),))


@dataclass(frozen=True)
class Stats:
    """Statistics of one quantity over a map's feasible points (SD with ddof = 1)."""

    min: float
    max: float
    mean: float
    sd: float
    count: int
    argmin: tuple[float, ...]   # task-space point (m) of the minimum
    argmax: tuple[float, ...]

    def as_dict(self, scale: float = 1.0) -> dict:
        """Plain floats for JSON; ``scale`` converts points (1e3 gives millimetres)."""
        return {"min": self.min, "max": self.max, "mean": self.mean, "sd": self.sd, "count": self.count,
                "argmin": [v * scale for v in self.argmin], "argmax": [v * scale for v in self.argmax]}


def statistics(values: np.ndarray, feasible: np.ndarray, grid: GridSpec, task_names: tuple[str, ...]) -> Stats:
    """Min, max, mean, SD (ddof = 1), count and where the extremes are, over feasible points.

    ``values`` and ``feasible`` have the grid's shape. Non-finite values (``inf`` condition
    numbers at exact singularities) count: the mean is then ``inf``, as it should be.
    """
    where = np.flatnonzero(feasible)
    v = values.reshape(-1)[where]
    if v.size == 0:
        nan = float("nan")
        return Stats(nan, nan, nan, nan, 0, (), ())
    has_nan = np.isnan(v).any()
    imin = int(np.nanargmin(v) if has_nan else np.argmin(v))
    imax = int(np.nanargmax(v) if has_nan else np.argmax(v))
    extremes = grid.points(task_names, where[[imin, imax]])
    with np.errstate(invalid="ignore"):
        mean = float(np.mean(v))
        sd = float(np.sqrt(np.sum((v - mean) ** 2) / (v.size - 1))) if v.size > 1 else float("nan")
    return Stats(float(v[imin]), float(v[imax]), mean, sd, int(v.size),
                 tuple(float(c) for c in extremes[0]), tuple(float(c) for c in extremes[1]))


@dataclass
class WorkspaceMap:
    """A computed map: grid, points (..., m), feasible mask, one array per quantity, statistics."""

    grid: GridSpec
    task_names: tuple[str, ...]
    feasible: np.ndarray
    values: dict[str, np.ndarray]
    stats: dict[str, Stats]
    seconds: float
    computed: tuple[str, ...] = field(default=())

    @property
    def points(self) -> FloatArray:
        """Task-space points (m), shape ``resolution + (m,)``, made on demand."""
        return self.grid.points(self.task_names)

    @property
    def feasible_points(self) -> int:
        return int(np.count_nonzero(self.feasible))


def compute_map(mechanism, grid: GridSpec, quantities, *,
                progress: Callable[[float], None] | None = None,
                cancelled: Callable[[], bool] | None = None,
                threads: bool = True) -> WorkspaceMap:
    """Evaluate ``quantities`` over ``grid``; statistics for every non-categorical one.

    ``progress(fraction)`` is called after each chunk; when ``cancelled()`` turns true the
    remaining chunks are skipped and ``Cancelled`` is raised.
    """
    names = check_quantities(mechanism, quantities)
    start = time.perf_counter()
    total = int(np.prod(grid.resolution))
    feasible = np.zeros(total, bool)
    out: dict[str, np.ndarray] = {}
    computed: set[str] = set()
    workers = (os.cpu_count() or 1) if threads else 1
    chunk = int(min(CHUNK, max(MIN_CHUNK, -(-total // workers))))
    bounds = [(s, min(s + chunk, total)) for s in range(0, total, chunk)]
    done = 0

    def work(span: tuple[int, int]):
        if cancelled is not None and cancelled():
            raise Cancelled()
        return span, evaluate(mechanism, grid.points(mechanism.task_names, slice(*span)), names)

    runner = _pool().map(work, bounds) if threads and len(bounds) > 1 else map(work, bounds)
    for (s, e), ev in runner:
        feasible[s:e] = ev.feasible
        computed.update(ev.computed)
        for name, arr in ev.values.items():
            if name not in out:
                out[name] = np.empty((total,) + arr.shape[1:], arr.dtype)
            out[name][s:e] = arr
        done += e - s
        if progress is not None:
            progress(done / total)
    shape = tuple(grid.resolution)
    feasible = feasible.reshape(shape)
    values = {k: v.reshape(shape + v.shape[1:]) for k, v in out.items()}
    stats = {k: statistics(v, feasible, grid, mechanism.task_names) for k, v in values.items()
             if not QUANTITIES[k].categorical and v.shape == shape}
    return WorkspaceMap(grid=grid, task_names=tuple(mechanism.task_names), feasible=feasible, values=values, stats=stats,
                        seconds=time.perf_counter() - start, computed=tuple(sorted(computed)))


def resolution_error(wmap: WorkspaceMap) -> dict[str, dict[str, float]]:
    """Estimated error of each global figure from the map's resolution, per quantity.

    The same statistics on the two interleaved half-resolution grids (every second point
    per axis, starting at the first and at the second point) differ from the full map's by
    about the error the full map itself still carries for figures that converge linearly
    in the spacing (extremes, and the mean and SD through the boundary cells). The larger
    of the two differences is the estimate; two grids, because an extreme that happens to
    sit on one of them would make that one's difference zero. ``isoforce convergence``
    measures the real error against much finer maps.
    """
    out: dict[str, dict[str, float]] = {name: dict.fromkeys(("min", "max", "mean", "sd"), 0.0) for name in wmap.stats}
    for start in (0, 1):
        sub = tuple(slice(start, None, 2) for _ in wmap.grid.resolution)
        coords = [c[start::2] for c in wmap.grid.coordinates()]
        if any(len(c) < 2 for c in coords):
            continue
        half = GridSpec(wmap.grid.axes, tuple(c[0] for c in coords), tuple(c[-1] for c in coords),
                        tuple(len(c) for c in coords), wmap.grid.fixed)
        feasible = wmap.feasible[sub]
        for name, full in wmap.stats.items():
            coarse = statistics(wmap.values[name][sub], feasible, half, wmap.task_names)
            for k in out[name]:
                with np.errstate(invalid="ignore"):
                    diff = abs(getattr(full, k) - getattr(coarse, k))
                out[name][k] = max(out[name][k], diff) if not np.isnan(diff) else float("nan")
    return out
