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

CHUNK = 32768
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

    def points(self, task_names: tuple[str, ...]) -> FloatArray:
        """Task-space points of the grid, shape ``resolution + (m,)``."""
        fixed = dict(self.fixed)
        grids = np.meshgrid(*self.coordinates(), indexing="ij")
        out = np.empty(tuple(self.resolution) + (len(task_names),))
        for j, name in enumerate(task_names):
            if name in self.axes:
                out[..., j] = grids[self.axes.index(name)]
            elif name in fixed:
                out[..., j] = fixed[name]
            else:
                raise ValueError(f"grid has no value for task coordinate {name!r}: add it to axes or fixed")
        return out


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


def statistics(values: np.ndarray, feasible: np.ndarray, points: FloatArray) -> Stats:
    """Min, max, mean, SD (ddof = 1), count and where the extremes are, over feasible points."""
    v = values[feasible]
    p = points[feasible]
    if v.size == 0:
        nan = float("nan")
        return Stats(nan, nan, nan, nan, 0, (), ())
    imin, imax = int(np.nanargmin(v)), int(np.nanargmax(v))
    with np.errstate(invalid="ignore"):
        sd = float(np.std(v, ddof=1)) if v.size > 1 else float("nan")
        mean = float(np.mean(v))
    return Stats(float(v[imin]), float(v[imax]), mean, sd, int(v.size),
                 tuple(float(c) for c in p[imin]), tuple(float(c) for c in p[imax]))


@dataclass
class WorkspaceMap:
    """A computed map: grid, points (..., m), feasible mask, one array per quantity, statistics."""

    grid: GridSpec
    points: FloatArray
    feasible: np.ndarray
    values: dict[str, np.ndarray]
    stats: dict[str, Stats]
    seconds: float
    computed: tuple[str, ...] = field(default=())

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
    points = grid.points(mechanism.task_names)
    flat = points.reshape(-1, mechanism.task_dim)
    total = flat.shape[0]
    feasible = np.zeros(total, bool)
    out: dict[str, np.ndarray] = {}
    computed: set[str] = set()
    bounds = [(s, min(s + CHUNK, total)) for s in range(0, total, CHUNK)]
    done = 0

    def work(span: tuple[int, int]):
        if cancelled is not None and cancelled():
            raise Cancelled()
        return span, evaluate(mechanism, flat[span[0]:span[1]], names)

    runner = _pool().map(work, bounds) if threads and len(bounds) > 1 else map(work, bounds)
    try:
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
    except Cancelled:
        raise
    shape = tuple(grid.resolution)
    feasible = feasible.reshape(shape)
    values = {k: v.reshape(shape + v.shape[1:]) for k, v in out.items()}
    stats = {k: statistics(v, feasible, points) for k, v in values.items()
             if not QUANTITIES[k].categorical and v.shape == shape}
    return WorkspaceMap(grid=grid, points=points, feasible=feasible, values=values, stats=stats,
                        seconds=time.perf_counter() - start, computed=tuple(sorted(computed)))
