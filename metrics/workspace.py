"""Workspace maps: a grid (2D slice or 3D volume), a feasibility mask, quantities, statistics.

A map is evaluated in chunks (``CHUNK`` points); between chunks a caller can report progress
or cancel. Where the mechanism's family has a compiled kernel for the request
(``metrics.kernels``), each chunk is one fused pass (IK, J, quantities) spread over the cores
by the kernel itself and its statistics are taken by ``kernels.chunk_partials``, chunk after
chunk in the caller's thread; otherwise the numpy path runs the chunks on a small thread pool
(numpy's ufuncs release the GIL, so two cores give close to twice the speed).
"""
from __future__ import annotations

import contextlib
import dataclasses
import math
import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from kinematics.arrays import FloatArray
from kinematics.grid import GridSpec  # noqa: F401  (re-exported: maps are built on it)

from . import kernels, wrenches
from .chunk_pool import chunk_pool
from .loading import DEFAULT_LOADING, Loading
from .map_chunks import (
    CHUNK,
    QUARTER_STARTS,
    Cancelled,  # noqa: F401  (re-exported: compute_map is cancelled with it)
    ChunkWork,
    chunk_results,
    pooled,
)
from .quantities import (
    evaluate,
)
from .statistics import QUANTILE_REL_ERROR, QUANTILES, StatsAccumulator, chunk_partial, exact_quantiles
from .suprema import LOCATIONS, singular_extremes

_POOL: ThreadPoolExecutor | None = None


@dataclass(frozen=True)
class Stats:
    """Statistics of one quantity over a map's regular points (feasible, not singular; SD with ddof = 1).

    ``count`` counts the regular points; ``singular_points`` the feasible points the mechanism
    calls singular, left out of the mean, SD and quantiles and located (the first few) in
    ``singular_at``. ``min`` and ``max`` of a quantity with a finite limit where one actuator is
    singular (``metrics.suprema.finite_at_inverse``) also take its values at singular points of
    the inverse kind: it may reach its extreme there (the five-bar's isotropic force at a
    stretched leg).
    ``unbounded`` says that the supremum is infinite in truth (``metrics.suprema``): ``max`` is
    then ``inf`` and ``unbounded_at`` says where. Quantiles are ``inverted_cdf`` order
    statistics (exact for a kept map, within ``statistics.QUANTILE_REL_ERROR`` when streamed).
    Points are task-space tuples in m.
    """

    min: float
    max: float
    mean: float
    sd: float
    count: int
    argmin: tuple[float, ...]   # task-space point (m) of the minimum
    argmax: tuple[float, ...]
    median: float = math.nan
    p05: float = math.nan
    p95: float = math.nan
    singular_points: int = 0
    singular_at: tuple[tuple[float, ...], ...] = ()
    unbounded: bool = False
    unbounded_at: tuple[tuple[float, ...], ...] = ()
    #: The infimum is 0 in truth (the feasible set reaches a singularity where the quantity
    #: vanishes, ``metrics.suprema.VANISHING_NEAR``): ``min`` is then 0 and ``vanishes_at`` says where.
    vanishes: bool = False
    vanishes_at: tuple[tuple[float, ...], ...] = ()

    def as_dict(self, scale: float = 1.0) -> dict:
        """Plain floats for JSON; ``scale`` converts points (1e3 gives millimetres).

        Parameters
        ----------
        scale : float
            Factor applied to every point coordinate (m); the figures are left as they are.

        Returns
        -------
        dict
            The fields by name; points as lists of floats.
        """
        def pts(points):
            return [[v * scale for v in p] for p in points]
        return {"min": self.min, "max": self.max, "mean": self.mean, "sd": self.sd, "median": self.median,
                "p05": self.p05, "p95": self.p95, "count": self.count,
                "argmin": [v * scale for v in self.argmin], "argmax": [v * scale for v in self.argmax],
                "singular_points": self.singular_points, "singular_at": pts(self.singular_at),
                "unbounded": self.unbounded, "unbounded_at": pts(self.unbounded_at),
                "vanishes": self.vanishes, "vanishes_at": pts(self.vanishes_at)}


#: The figures of a ``Stats`` that carry a resolution error.
FIGURES = ("min", "max", "mean", "sd", "median", "p05", "p95")
#: What ``compute_map(figures=...)`` takes: every figure, or the extremes alone (``EXTREMES``).
FIGURE_SETS = ("all", "extremes")
#: The figures of an ``"extremes"`` map: what a map's legend shows (``app.logic.map_marks``).
EXTREMES = ("min", "max")


def statistics(values: np.ndarray, feasible: np.ndarray, grid: GridSpec, task_names: tuple[str, ...],
               singular: np.ndarray | None = None, bounded: np.ndarray | None = None) -> Stats:
    """Statistics over the regular points of one array (a kept map or a sub-grid of one).

    ``values``, ``feasible`` and ``singular`` have the grid's shape; non-finite values and
    singular points are left out of the figures (singular ones are counted), except that the
    finite values at ``bounded`` singular points enter the extremes (``chunk_partial``).

    Parameters
    ----------
    values : ndarray, shape ``grid.resolution``
        One scalar quantity at every grid point.
    feasible : ndarray of bool, shape ``grid.resolution``
        Where the pose is reachable.
    grid : GridSpec
        The grid ``values`` was sampled on (locates the extremes).
    task_names : tuple of str, length m
        The mechanism's task coordinates, in order.
    singular : ndarray of bool, shape ``grid.resolution``, optional
        Where the mechanism calls the pose singular; none when not given.
    bounded : ndarray of bool, shape ``grid.resolution``, optional
        The singular points of the inverse kind (``WorkspaceMap.inverse_singular``).

    Returns
    -------
    Stats
        Exact quantiles; points are task-space tuples, length m, in m.

    Examples
    --------
    >>> g = GridSpec(("x", "y"), (0.0, 0.0), (0.1, 0.2), (2, 3))
    >>> v = np.array([[1.0, 2.0, 4.0], [3.0, 5.0, np.nan]])
    >>> s = statistics(v, np.isfinite(v), g, ("x", "y"))
    >>> s.count, s.min, s.max, s.median
    (5, 1.0, 5.0, 3.0)
    >>> [round(c, 6) for c in s.argmax]
    [0.1, 0.1]
    """
    flat_singular = (np.zeros(values.size, bool) if singular is None else singular.reshape(-1)) & feasible.reshape(-1)
    regular = feasible.reshape(-1) & ~flat_singular
    index = np.arange(values.size)
    acc = StatsAccumulator()
    acc.merge(chunk_partial(values.reshape(-1), regular, flat_singular, index, histogram=False,
                            bounded=None if bounded is None else bounded.reshape(-1)))
    keep = regular & np.isfinite(values.reshape(-1))
    return _stats_from(acc, exact_quantiles(values.reshape(-1)[keep]), grid, task_names)


def _stats_from(acc: StatsAccumulator, quantiles: dict[str, float], grid: GridSpec, task_names,
                unbounded_at: np.ndarray | None = None, vanishes_at: np.ndarray | None = None) -> Stats:
    ends = 2 if acc.count and acc.argmin >= 0 else 0     # no regular point: no figures
    located = [acc.argmin, acc.argmax][:ends] + list(acc.singular_index)
    points = grid.points(task_names, np.array(located, dtype=np.int64)) if located else np.empty((0, len(task_names)))
    extremes, singular_at = points[:ends], points[ends:]
    nan = math.nan
    vmin, vmax = (acc.min, acc.max) if acc.count else (nan, nan)
    argmin = tuple(float(c) for c in extremes[0]) if len(extremes) else ()
    argmax = tuple(float(c) for c in extremes[1]) if len(extremes) else ()
    unbounded = unbounded_at is not None and len(unbounded_at) > 0
    if unbounded:
        vmax, argmax = math.inf, tuple(float(c) for c in unbounded_at[0])
    vanishes = vanishes_at is not None and len(vanishes_at) > 0 and acc.count > 0
    if vanishes:
        vmin, argmin = 0.0, tuple(float(c) for c in vanishes_at[0])
    return Stats(vmin, vmax, acc.mean if acc.count else nan, acc.sd, acc.count, argmin, argmax,
                 median=quantiles["median"], p05=quantiles["p05"], p95=quantiles["p95"],
                 singular_points=acc.singular,
                 singular_at=tuple(tuple(float(c) for c in p) for p in singular_at),
                 unbounded=unbounded,
                 unbounded_at=tuple(tuple(float(c) for c in p) for p in (unbounded_at if unbounded else ())),
                 vanishes=vanishes,
                 vanishes_at=tuple(tuple(float(c) for c in p) for p in (vanishes_at if vanishes else ())))


@dataclass
class WorkspaceMap:
    """A computed map: grid, feasible and singular masks, one array per quantity, statistics.

    A streamed map (``compute_map(..., keep=False)``) has statistics only: ``values`` is
    empty and ``feasible``/``singular`` are ``None``.
    """

    grid: GridSpec
    task_names: tuple[str, ...]
    feasible: np.ndarray | None
    values: dict[str, np.ndarray]
    stats: dict[str, Stats]
    seconds: float
    computed: tuple[str, ...] = field(default=())
    singular: np.ndarray | None = None
    #: The singular points of the inverse kind (an actuator's column of J vanishes); ``None`` when
    #: the mechanism classes none. Their values enter the extremes of ``finite_at_inverse``'s
    #: quantities (``metrics.suprema.finite_at_inverse``: those with a finite limit there).
    inverse_singular: np.ndarray | None = None
    finite_at_inverse: tuple[str, ...] = ()
    #: Estimated error of each figure from the resolution (``resolution_error``), per quantity.
    errors: dict[str, dict[str, float]] = field(default_factory=dict)
    #: The observed order p of each figure's grid error (error ~ h^p, ``error_orders``), per
    #: quantity; ``nan`` where no order is measurable.
    error_orders: dict[str, dict[str, float]] = field(default_factory=dict)
    feasible_count: int = 0
    #: Global conditioning index (Gosselin and Angeles 1991) and its resolution error, if computed.
    gci: float | None = None
    gci_error: float | None = None
    gci_error_order: float = math.nan
    #: The task scaling of the condition number where J mixes m and rad (``{"length_m": L}``), else None.
    condition_number_scaling: dict | None = None
    #: The torque rating and gravity the force quantities were computed under (``metrics.loading``).
    loading: Loading = DEFAULT_LOADING
    #: The statistics it holds (``compute_map(figures=...)``): ``"all"``, or ``"extremes"``, its legend's
    #: alone (the mean, SD, quantiles and GCI ``nan``: a dragged slider's map, never exported).
    figures: str = "all"

    @property
    def points(self) -> FloatArray:
        """Task-space points (m), shape ``resolution + (m,)``, made on demand.

        Returns
        -------
        ndarray, shape ``grid.resolution + (m,)``
        """
        return self.grid.points(self.task_names)

    @property
    def feasible_points(self) -> int:
        """Number of feasible grid points (kept or streamed map).

        Returns
        -------
        int
        """
        return int(np.count_nonzero(self.feasible)) if self.feasible is not None else self.feasible_count

    @property
    def singular_points(self) -> int:
        """Feasible points the mechanism calls singular.

        Returns
        -------
        int
            ``0`` when the map has no statistics.
        """
        return next((s.singular_points for s in self.stats.values()), 0)


def sample_grid(grid: GridSpec, points: int) -> GridSpec:
    """A grid over ``grid``'s range with about ``points`` points (never more per axis than ``grid``).

    Its points spread over the whole range, so the feasible and infeasible regions weigh in it
    as they do in ``grid``: what a job costs per point is measured on it.

    Parameters
    ----------
    grid : GridSpec
        The job's grid.
    points : int
        Points wanted.

    Returns
    -------
    GridSpec
        The same axes, range and fixed coordinates, ``round(points ** (1 / k))`` points per axis.

    Examples
    --------
    >>> sample_grid(GridSpec(("x", "y"), (0.0, 0.0), (1.0, 1.0), (1000, 1000)), 8192).resolution
    (91, 91)
    """
    n = max(2, round(points ** (1.0 / len(grid.axes))))
    return grid.with_resolution(tuple(min(int(r), n) for r in grid.resolution))


#: Feasible points of the smaller of the two chunks ``chunk_bytes_per_point`` traces (the larger
#: has four times as many).
MEMORY_SAMPLE = 2048


def chunk_bytes_per_point(mechanism, grid: GridSpec, quantities, *, keep: bool = False,
                          loading: Loading | None = None, sample: int = MEMORY_SAMPLE) -> float | None:
    """Peak bytes per point that ``compute_map`` allocates for a full chunk whose every point is feasible, measured.

    The chunk work (evaluation, singular classes, statistics) runs under ``tracemalloc``, which
    sees numpy's allocations, on ``sample`` and on ``4 * sample`` feasible points of ``grid``'s
    range; the line through the two peaks, taken at ``map_chunks.CHUNK`` points, is a full
    chunk's peak. A chunk holds a part that does not grow with its points (the statistics'
    tables, the kernel's scratch) beside the per-point arrays: one small chunk's peak over its
    points (what this measured before, on 256 points) counted that part once per point: 4.7 times
    the traced peak of a full Inverse3 chunk of distinct feasible points.

    The measurement is the same whatever the process ran before and however its threads are
    scheduled: the chunks' statistics run on this thread alone, and the chunks run once untraced,
    then each traced on the statistics' scratch made empty (``partials.fresh_scratch``), as a job's
    first chunk grows it. A full chunk runs on a pool worker (``map_chunks.pooled``) and takes its
    statistics there, on that worker's own scratch; a chunk run alone (a grid of one chunk) shares
    them with a helper thread (``partials.shares``) that holds its own dense bins and bins out
    (``partials.quantity_bytes``, 5 MB at a full chunk): those are added to both peaks, a margin for
    the pool's chunks. Over the eight shipped devices with a compiled kernel, the line gave 0.996
    (five-bar, Stewart) to 1.07 (Omni) of the traced peak of a full chunk whose helper took a
    quantity, 1.21 to 1.32 of one without; on the numpy path (no helper) 1.21 (Twin-Pantograph) and
    1.51 (Inoue). The estimate's ``RESIDENT_PER_TRACED`` covers the low end. What a point costs
    depends on the quantities asked for (a mass model's apparent mass costs ten times the force
    figures), which no formula of the joint count follows. The interior chunks of a large grid are
    all feasible, so this is what they hold.

    Parameters
    ----------
    mechanism : Mechanism
        The device.
    grid : GridSpec
        The job's grid (its range and axes).
    quantities : iterable of str
        The job's quantities.
    keep : bool
        Whether the job keeps its arrays (streamed statistics also bin their values).
    loading : Loading, optional
        The job's torque rating and gravity.
    sample : int
        Feasible points of the smaller traced chunk (those of a sample grid of ``4 * sample``
        points over the range, repeated as needed).

    Returns
    -------
    float or None
        Bytes per point of a full chunk; ``None`` when ``tracemalloc`` is already tracing (its
        caller is measuring its own peak, which a nested measurement would reset) or no point
        of the range is feasible.
    """
    import tracemalloc

    if tracemalloc.is_tracing():
        return None
    # The statistics on this thread alone (``helper=False``), their helper thread's share added
    # below: whether the helper took a quantity of a traced chunk was up to the scheduler. Its
    # first one made its dense bins (1.5 MB); made in the larger chunk only, the line multiplied
    # them by 10, and the estimate of a full chunk went from 26 to 53 MB (five-bar) from one run
    # to the next. (The kernel's pass over the cores traces the same bytes as on one thread.)
    work = dataclasses.replace(ChunkWork.plan(mechanism, grid, quantities, keep=keep, loading=loading), helper=False)
    pts = sample_grid(grid, 4 * sample).points(mechanism.task_names).reshape(-1, mechanism.task_dim)
    with np.errstate(all="ignore"):
        inside = pts[evaluate(mechanism, pts, (), loading=work.loading).feasible]
    if inside.shape[0] == 0:
        return None
    total = math.prod(int(r) for r in grid.resolution)
    # Once untraced on the larger chunk's points (the smaller's are its first): the kernel compiled or
    # loaded from the cache, and whatever else a chunk does the first time in a process, are not a
    # chunk's. On 16 points, the Falcon's first traced chunk imported the Twin-Pantograph's model
    # (for the points its kernel hands back: 3.3 MB traced), which put the line at 5.9 MB, not 24.9.
    work.at(np.arange(4 * sample) % total, np.resize(inside, (4 * sample, mechanism.task_dim)))
    scratch, helper = contextlib.nullcontext, None
    if work.compiled_stats:             # a kernel's chunks, or the compiled statistics of a graph's
        from .kernels import partials

        # Each traced chunk grows the statistics' scratch from empty, as a job's first chunk
        # does, whatever this process ran before (a larger sample left it grown: not traced).
        scratch = partials.fresh_scratch
        if partials.shares(len(work.scalar), CHUNK):
            helper = partials.quantity_bytes
    peaks = []
    for size in (sample, 4 * sample):
        chunk = np.resize(inside, (size, mechanism.task_dim))
        index = np.arange(size) % total
        with scratch():
            tracemalloc.start()
            try:
                work.at(index, chunk)
                peaks.append(tracemalloc.get_traced_memory()[1])
            finally:
                tracemalloc.stop()
            if helper is not None:
                # A full chunk's helper holds what this thread's ``quantity`` scratch holds after the same chunk.
                peaks[-1] += helper()
    per_point = max(peaks[1] - peaks[0], 0) / (3 * sample)
    fixed = max(peaks[0] - per_point * sample, 0.0)
    return per_point + fixed / CHUNK


def chunks_in_flight(mechanism, grid: GridSpec, quantities, *, loading: Loading | None = None) -> int:
    """Chunks ``compute_map`` works on at once: one per pool worker, 1 for a grid of a single chunk.

    A compiled kernel's chunks take the pool as the numpy path's do, a chunk a worker, each on the
    kernel's serial build (``compute_map``); a grid of one chunk (``map_chunks.pooled``) runs in the
    caller's thread.

    Parameters
    ----------
    mechanism : Mechanism
        The device (the count is the same for every device and request: kept for the callers).
    grid : GridSpec
        The job's grid.
    quantities : iterable of str
        The job's quantities.
    loading : Loading, optional
        The job's torque rating and gravity.

    Returns
    -------
    int
    """
    del mechanism, quantities, loading
    return max(1, os.cpu_count() or 1) if pooled(True, math.prod(int(r) for r in grid.resolution)) else 1


def compute_map(mechanism, grid: GridSpec, quantities, *,
                progress: Callable[[float], None] | None = None,
                cancelled: Callable[[], bool] | None = None,
                threads: bool = True, keep: bool = True, loading: Loading | None = None,
                figures: str = "all") -> WorkspaceMap:
    """Evaluate ``quantities`` over ``grid``; statistics for every non-categorical one.

    Statistics are taken chunk by chunk (``metrics.statistics``) over the regular points:
    feasible and not singular by the mechanism's ``singularity`` (or, without one, where a
    quantity is infinite). ``keep=False`` keeps only the statistics, so memory does not grow
    with the resolution (``isoforce stats``, convergence studies). Suprema that are infinite in
    truth are marked ``unbounded`` (``metrics.suprema``).

    ``progress(fraction)`` is called after each chunk; when ``cancelled()`` turns true the
    remaining chunks are skipped and ``Cancelled`` is raised.

    Parameters
    ----------
    mechanism : Mechanism
        The model evaluated at each grid point (task points ``(..., m)``).
    grid : GridSpec
        The grid (2D slice or 3D volume), lengths in m.
    quantities : iterable of str
        Names in ``metrics.quantities.QUANTITIES`` the mechanism provides.
    progress : callable ``(float) -> None``, optional
        Called with the fraction done (0 to 1) after each chunk.
    cancelled : callable ``() -> bool``, optional
        Polled before each chunk; true stops the map.
    threads : bool
        Use the shared thread pool (one chunk at a time when false).
    keep : bool
        Keep the arrays (``False``: statistics only).
    loading : Loading, optional
        Torque rating and gravity (``metrics.loading``); default continuous, gravity off.
    figures : {"all", "extremes"}
        ``"extremes"``: the figures a map's legend shows alone (``EXTREMES``: the minimum and maximum,
        where, their resolution errors and orders, whether unbounded or vanishing; the counts and
        the singular points), for a dragged slider's map (``app.jobs.requests``); the mean, SD
        and quantiles are ``nan`` (no exact quantiles), and so is the GCI. Those figures are the
        same bits however the grid is split, so its spans follow the cores (``map_chunks.worker_chunk``).

    Returns
    -------
    WorkspaceMap
        Arrays of shape ``grid.resolution`` (plus a quantity's own trailing axes) when ``keep``,
        statistics and their resolution errors for every scalar quantity.

    Raises
    ------
    Cancelled
        When ``cancelled()`` returned true.
    ValueError
        For an unknown quantity or a ``loading`` the mechanism cannot take (``Loading.check``).
    """
    start = time.perf_counter()
    if figures not in FIGURE_SETS:
        raise ValueError(f"figures must be one of {', '.join(FIGURE_SETS)}, got {figures!r}")
    extremes = figures == "extremes"
    work = ChunkWork.plan(mechanism, grid, quantities, keep=keep, loading=loading, cancelled=cancelled,
                           threads=threads)
    names, scalar, halves, loading = work.names, work.scalar, work.halves, work.loading
    subgrids = (*halves, *work.quarters)        # the accumulators after the full grid's, in order
    shape = tuple(int(r) for r in grid.resolution)
    total = math.prod(shape)
    feasible = np.zeros(total, bool) if keep else None
    singular_all = np.zeros(total, bool) if keep else None
    inverse_all = np.zeros(total, bool) if keep and work.inverse_code is not None else None
    out: dict[str, np.ndarray] = {}
    computed: set[str] = set()
    # Full grid, half 0, half 1, quarter 0, quarter 2 (``map_chunks.QUARTER_STARTS``).
    acc = {q: [StatsAccumulator() for _ in range(1 + len(subgrids))] for q in scalar}
    state = {"done": 0, "feasible": 0, "direct": [], "inverse": []}

    # A compiled kernel's chunks go over the cores as the numpy path's do, a chunk a pool worker, each on
    # the kernel's serial build (its statistics too): each chunk's glue (grid points, feasible values,
    # partials) then runs beside the other chunks' kernels. Chunks one at a time, each kernel over the
    # cores (``prange``), left that glue serial (a fifth of the map's CPU): the 1000 x 1000 Inverse3 map
    # took 132-138 ms wall this way against 88-95 ms on the pool (kept, in one process, interleaved, load
    # 1.0-1.3). ``chunk_results`` keeps the results in grid order: the same bits. A grid of one chunk
    # (at most ``map_chunks.MIN_CHUNK`` points, a millisecond) takes the serial build too: a process
    # then loads one build of the kernel, not both (the second took 13-22 ms more), and starts no
    # ``prange`` threads.
    if work.kernel is not None:
        work = dataclasses.replace(work, threads=False)
    elif work.compiled_stats and pooled(threads, total):
        # The numpy path's compiled statistics (``map_chunks.COMPILED_STATISTICS``) on the chunk's worker alone:
        # the other workers' chunks keep the cores busy, a helper thread would only queue beside them.
        work = dataclasses.replace(work, threads=False)
    results = chunk_results(work, total, threads=threads, by_worker=extremes)
    for (s, e), ev, (singular, inverse), parts, (direct_idx, inverse_idx) in results:
        computed.update(ev.computed)
        state["feasible"] += int(np.count_nonzero(ev.feasible)) if keep else singular
        for kind, found in (("direct", direct_idx), ("inverse", inverse_idx)):
            held = state[kind]          # only the first LOCATIONS are used: keep no more
            held.extend(int(i) for i in found[:LOCATIONS - len(held)])
        for q, (full, *subs) in parts.items():
            acc[q][0].merge(full)
            for a, part in zip(acc[q][1:], subs):
                if part is not None:
                    a.merge(part)
        if keep:
            feasible[s:e] = ev.feasible
            singular_all[s:e] = singular
            if inverse_all is not None:
                inverse_all[s:e] = inverse
            for name in names:
                arr = ev.values[name]
                if name not in out:
                    out[name] = np.empty((total,) + arr.shape[1:], arr.dtype)
                out[name][s:e] = arr
        state["done"] += e - s
        if progress is not None:
            progress(state["done"] / total)
    values = {k: v.reshape(shape + v.shape[1:]) for k, v in out.items()}
    direct_points, inverse_points = (
        grid.points(mechanism.task_names, np.array(state[kind][:LOCATIONS], dtype=np.int64)) if state[kind] else None
        for kind in ("direct", "inverse"))
    unbounded, vanishing = singular_extremes(mechanism, grid, scalar, direct_points=direct_points,
                                             inverse_points=inverse_points)
    stats, errors = {}, {}
    if keep:
        regular_all = (feasible & ~singular_all).reshape(shape)
        subs = [tuple(slice(start, None, stride) for _ in shape)
                for stride, start in ((2, 0), (2, 1), *((4, s) for s in QUARTER_STARTS))]
    orders = {}
    exacts = (_exact_quantiles(values, regular_all, [q for q in scalar if acc[q][0].count], acc,
                               (True, *(g is not None for g in subgrids)), threads=threads)
              if keep and work.kernel is not None and not extremes else {})
    for q in scalar:
        quants = []
        exact = exacts.get(q)
        for k, a in enumerate(acc[q]):
            if extremes:
                quants.append(dict.fromkeys(QUANTILES, math.nan))
            elif exact is not None and exact[k] is not None:
                quants.append(exact[k])
            elif keep and (k == 0 or subgrids[k - 1] is not None):
                sub = subs[k - 1] if k else ()
                v, regular = values[q][sub], regular_all[sub]
                quants.append(exact_quantiles(v[regular & np.isfinite(v)]))
            else:
                quants.append(a.quantiles())
        stats[q] = _stats_from(acc[q][0], quants[0], grid, mechanism.task_names, unbounded.get(q), vanishing.get(q))
        errors[q] = _figure_errors(stats[q],
                                   [(a, qs) for a, qs, h in zip(acc[q][1:], quants[1:], halves) if h is not None],
                                   streamed=not keep)
        half = [(a, qs) for a, qs, h in zip(acc[q][1:3], quants[1:3], halves) if h is not None]
        quarter = [(a, qs) for a, qs, g in zip(acc[q][3:], quants[3:], work.quarters) if g is not None]
        orders[q] = error_orders(_figure_errors(stats[q], half, streamed=False),
                                 _figure_errors(dataclasses.replace(stats[q], **_figures(acc[q][1], quants[1])),
                                                quarter, streamed=False) if halves[0] is not None else {})
        if extremes:            # (the span-dependent sums' last bits: not taken, as the quantiles)
            stats[q] = dataclasses.replace(stats[q], mean=math.nan, sd=math.nan)
            for figs in (errors[q], orders[q]):
                figs.update({k: math.nan for k in figs if k not in EXTREMES})
    wmap = WorkspaceMap(grid=grid, task_names=tuple(mechanism.task_names),
                        feasible=feasible.reshape(shape) if keep else None, values=values, stats=stats,
                        seconds=0.0, computed=tuple(sorted(computed)),
                        singular=singular_all.reshape(shape) if keep else None,
                        inverse_singular=inverse_all.reshape(shape) if inverse_all is not None else None,
                        finite_at_inverse=work.finite_there, errors=errors, error_orders=orders,
                        feasible_count=state["feasible"], loading=loading, figures=figures)
    wmap.condition_number_scaling = wrenches.condition_number_scaling(mechanism)
    if "inverse_condition_number" in stats and not extremes:
        wmap.gci, wmap.gci_error, wmap.gci_error_order = _gci(acc["inverse_condition_number"], subgrids)
    wmap.seconds = time.perf_counter() - start
    return wmap


def _exact_quantiles(values: dict[str, np.ndarray], regular: np.ndarray, names: list[str],
                     acc: dict[str, list[StatsAccumulator]], grids: tuple[bool, ...], *, threads: bool) -> dict:
    """Each quantity's exact quantiles on every grid, compiled (``kernels.exact_grid_quantiles``): two passes
    over the kept array, no masked copies; a quantity a thread, the map's pool's beside this one.

    After the chunks the pool's workers are idle: the quantities after the first go to them, this thread
    takes the first, then, last first, any the pool has not started (``Future.cancel``), so a busy pool
    (another map's chunks, a loaded machine) costs no wait. Three quantities on two cores then take
    about one and a half quantities' time, where this thread and the statistics' helper thread took two
    (``partials.shared``): the tail of the 1000 x 1000 Inverse3 map after its last chunk. Each quantity's
    figures are its own, whatever thread takes it.

    Parameters
    ----------
    values : dict of str to ndarray, shape ``resolution``
        The kept map's arrays.
    regular : ndarray of bool, shape ``resolution``
        The regular points.
    names : list of str
        The quantities with a regular point.
    acc : dict of str to list of StatsAccumulator
        Each quantity's accumulated full grid first (its extremes bound the values).
    grids : tuple of bool
        Which grids (``partials.GRIDS``) to take.
    threads : bool
        Use the pool (else every quantity on this thread).

    Returns
    -------
    dict of str to list
        Per quantity of ``names``, per grid the quantiles by name, or None where not taken.
    """
    def one(i: int) -> list:
        q = names[i]
        return kernels.exact_grid_quantiles(values[q], regular, grids, acc[q][0].min, acc[q][0].max)

    if not threads or len(names) < 2:
        return {q: one(i) for i, q in enumerate(names)}
    pool = chunk_pool()
    futures = {i: pool.submit(one, i) for i in range(1, len(names))}
    results = {0: one(0)}
    for i in reversed(futures):
        if futures[i].cancel():
            results[i] = one(i)
    for i, future in futures.items():
        if i not in results:
            results[i] = future.result()
    return {q: results[i] for i, q in enumerate(names)}


def _gci(accs: list[StatsAccumulator], subgrids) -> tuple[float, float | None, float]:
    """Mean of 1 / kappa over every feasible point, singular ones counting 0 (their exact value);
    its error from the half grids, and the error's observed order (``error_orders``)."""
    def value(a: StatsAccumulator) -> float:
        n = a.count + a.singular
        return a.mean * a.count / n if n else math.nan
    full = value(accs[0])
    halves, quarters = subgrids[:2], subgrids[2:]
    diffs = [abs(full - value(a)) for a, h in zip(accs[1:3], halves) if h is not None]
    if not diffs:
        return full, None, math.nan
    coarse = [abs(value(accs[1]) - value(a)) for a, g in zip(accs[3:], quarters) if g is not None]
    order = error_orders({"gci": max(diffs)}, {"gci": max(coarse)} if coarse and halves[0] is not None else {})
    return full, max(diffs), order["gci"]


def _figures(a: StatsAccumulator, quants: dict) -> dict[str, float]:
    """The ``FIGURES`` of one accumulated grid (``nan`` without regular points)."""
    return {"min": a.min if a.count else math.nan, "max": a.max if a.count else math.nan,
            "mean": a.mean if a.count else math.nan, "sd": a.sd, **quants}


def _figure_errors(full: Stats, coarse: list[tuple[StatsAccumulator, dict]], *, streamed: bool) -> dict[str, float]:
    """The larger change of each figure from the two half grids; plus the histogram's half bin when streamed."""
    out = dict.fromkeys(FIGURES, 0.0)
    if not coarse:
        return {}
    for a, quants in coarse:
        other = _figures(a, quants)
        for k in FIGURES:
            # As Python floats: inf - inf is nan without numpy's warning (no errstate a figure: 126 a map).
            diff = abs(float(getattr(full, k)) - float(other[k]))
            out[k] = max(out[k], diff) if not math.isnan(diff) else math.nan
    if full.unbounded:
        out["max"] = math.nan          # no grid estimate of an infinite figure
    if full.vanishes:
        out["min"] = 0.0               # exactly 0 in truth, whatever the grid
    if streamed:
        for k in QUANTILES:
            out[k] += 2.0 * QUANTILE_REL_ERROR * abs(getattr(full, k))   # this map's bin and the halves'
    return out


def error_orders(fine: dict[str, float], coarse: dict[str, float]) -> dict[str, float]:
    """The observed order p of each figure's grid error, error ~ h^p, from two grid steps.

    ``fine`` is a figure's change from the full grid (spacing h) to the half grids (2h),
    ``coarse`` its change from half grid 0 to its own two halves, the quarter grids (4h):
    p = log2(coarse / fine). ``nan`` where either change is 0 or not finite, or where the
    change does not shrink with the spacing (p <= 0): no order is measurable there.

    Parameters
    ----------
    fine, coarse : dict of str to float
        Per figure, the larger change over the two finer and the two coarser sub-grids.

    Returns
    -------
    dict of str to float
        Per figure of ``fine``, p or ``nan``.

    Examples
    --------
    >>> error_orders({"min": 0.01, "max": 0.0, "mean": 0.02}, {"min": 0.04, "max": 0.1, "mean": 0.01})
    {'min': 2.0, 'max': nan, 'mean': nan}
    """
    out = {}
    for k, d1 in fine.items():
        d2 = coarse.get(k, math.nan)
        ok = all(d is not None and math.isfinite(d) and d > 0.0 for d in (d1, d2))
        p = math.log2(d2 / d1) if ok else math.nan
        out[k] = p if p > 0.0 else math.nan
    return out


def resolution_error(wmap: WorkspaceMap) -> dict[str, dict[str, float]]:
    """Estimated error of each global figure from the map's resolution, per quantity.

    The same statistics on the two interleaved half-resolution grids (every second point
    per axis, starting at the first and at the second point) differ from the full map's by
    about the error the full map itself still carries for figures that converge linearly
    in the spacing (extremes, and the mean and SD through the boundary cells). The larger
    of the two differences is the estimate; two grids, because an extreme that happens to
    sit on one of them would make that one's difference zero. ``compute_map`` accumulates
    the half grids in the same pass (``WorkspaceMap.errors``); an unbounded maximum has no
    estimate (``nan``). ``isoforce convergence`` measures the real error against much finer maps.

    Parameters
    ----------
    wmap : WorkspaceMap
        A map from ``compute_map``.

    Returns
    -------
    dict of str to dict of str to float
        Per quantity, the estimated error of each figure in ``FIGURES`` (the quantity's unit).
    """
    return wmap.errors
