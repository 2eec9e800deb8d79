"""How long a map will run, predicted from a measured rate before it starts.

``--resolution 8000`` on a 3D box is 5.1e11 points: weeks of work that would start as readily
as a second's. Before a big job starts, ``seconds_per_point`` runs a sample grid over the same
range through the same path (``compute_map``: the compiled kernel or the thread pool, the
streamed statistics) and times it; the rate times the job's points is the prediction.
``check_run_time`` refuses a job predicted above its limit (``MAX_SECONDS``, an hour, unless the
caller allows more) with the prediction and the largest resolution that finishes in time.

The sample spreads over the whole range, so feasible and infeasible regions weigh in it as
they do in the job (a job's first chunks, a corner of the box, are often all infeasible and
several times faster than its interior). A job's chunks hold ``metrics.map_chunks.CHUNK``
points, and each call costs a few milliseconds whatever its size (the statistics' tables, the
kernel's launch): a sample of two chunks of 4,096 points paid that cost on every 4,096 points
and predicted the Inverse3's convergence ladder at 2.2 µs a point, about four times the rate
its maps ran at. So two sample grids of different sizes are timed (one chunk each): the
slope between them is the per-point cost, and the rest of the smaller one's time, the call's
own cost, is added back spread over a full chunk, as the job's chunks spread it. The sample
is a 32nd of the job (``sample_points``), at most half a chunk and at least ``MIN_SAMPLE``
points: a grid of half of it and one of an eighth, each timed twice, the faster counting. The
rungs of a convergence ladder are timed on the finest (a sample grid has no more points per
axis than its grid: on the 50 x 50 rung the sample was 2,500 points). A job
smaller than a chunk pays the call's cost once, on fewer points than a chunk: its prediction
is low by that cost (a few milliseconds). The time after the last chunk (the search for
singular extremes) does not grow with the points and is left out. On a busy machine the
prediction moves with the load, as the job's run time does. The clock is a parameter, so the
rules are tested without depending on the machine's speed.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from kinematics.grid import GridSpec

from .budget import CHUNK_POINTS, grid_points

# ``metrics.kernels`` and ``metrics.workspace`` (the map, with its quantities and the models'
# registry: 0.15 s) are imported in the functions that time or warm a map: ``format_duration``
# and the refusals are needed by commands that run no map (``isoforce dextrous``'s progress).

#: The largest sample that times a job (``seconds_per_point``): half a chunk
#: (``metrics.map_chunks.CHUNK``). The call's cost is measured apart, so a larger one would add
#: only time.
SAMPLE_POINTS = CHUNK_POINTS // 2
#: The smallest: two chunks of ``metrics.map_chunks.MIN_CHUNK``, so that two workers run it.
MIN_SAMPLE = 8192
#: Jobs of at most this many points start untimed: a sample would cost a quarter of them.
UNTIMED_POINTS = 4 * MIN_SAMPLE
#: A job's sample holds at most this share of its points (above ``MIN_SAMPLE``).
SAMPLE_SHARE = 1 / 32
#: A job predicted to run longer than this is refused unless its caller allows more.
MAX_SECONDS = 3600.0


class RunTimeError(ValueError):
    """A job predicted to run longer than allowed: the message gives the prediction and what to do."""


#: Set once ``load_pieces`` has run in this process.
_PIECES_LOADED: list[bool] = []


def sample_points(points: int) -> int:
    """Points of the sample that times a job of ``points`` points: a 32nd, within [MIN_SAMPLE, SAMPLE_POINTS].

    Parameters
    ----------
    points : int
        The job's points (all its maps).

    Returns
    -------
    int

    Examples
    --------
    >>> sample_points(40_000), sample_points(500_000), sample_points(10 ** 12)
    (8192, 15625, 32768)
    """
    return int(min(SAMPLE_POINTS, max(MIN_SAMPLE, int(points * SAMPLE_SHARE))))


def warm_up(mechanism, grid: GridSpec, quantities, *, keep: bool = False, loading=None) -> None:
    """A map of ``2**d`` points over ``grid``'s range, for what a first map pays once per process.

    Lazy imports, the compiled kernels' and pieces' loads from numba's cache (numba's own import
    with them, 0.35-0.9 s) and the pool's threads: not a map's rate, and not its run time (a
    command that times its map warms up before its clock starts).

    Parameters
    ----------
    mechanism, grid, quantities, keep, loading
        As ``seconds_per_point``'s.
    """
    from .workspace import compute_map, sample_grid

    compute_map(mechanism, sample_grid(grid, 2 ** len(grid.axes)), quantities, keep=keep, loading=loading)


def load_pieces() -> float:
    """Compile (or load from numba's cache) the numpy path's compiled pieces now; seconds it took (0 when loaded).

    ``wrench_slices.slice_max_norm``'s section (``kernels.section``), its gravity-biased counterpart
    (``biased_sections``, ``kernels.biased_section``), the Stewart and Inoue platforms' and the
    Twin-Pantograph's kinetic forms (``kernels.stewart_mass``, ``kernels.inoue_mass``,
    ``kernels.twin_mass``), the Twin-Pantograph's ``K`` and ``J`` (``kernels.twin_rows``) and its graph's steps
    (``kernels.twin_nodes``, ``facets.acceleration_radius_points``), and
    ``inverse_spd``'s Cholesky (``kernels.spd``), ``wrench_facets``' slabs and radii (``kernels.facets``), timed into
    ``kernels.compile_seconds``. A map loads them on its first chunk otherwise. Here, above
    ``metrics.kernels``, because they are reached through the modules that use them
    (``wrench_slices``, ``dynamics``, ``quantity_nodes``), which import ``metrics.kernels``
    themselves.

    Returns
    -------
    float
    """
    if _PIECES_LOADED:
        return 0.0
    from kinematics.registry import MECHANISMS

    from . import kernels
    from .biased_sections import biased_slice_max_norm
    from .dynamics import inverse_spd, task_inertia
    from .quantities import evaluate
    from .quantity_nodes import twin_rows
    from .wrench_facets import packed_facets, slice_inscribed_radius
    from .wrench_slices import slice_max_norm

    with kernels.timing() as took:
        slice_max_norm(np.eye(6), rows=[0, 1, 2])
        biased_slice_max_norm(np.eye(5, 6), np.zeros(6), rows=[0, 1, 2])
        for kind in ("stewart", "inoue", "twin_pantograph"):
            mech = MECHANISMS[kind]().replace(mass_model="estimated")      # the Inoue, Twin defaults have none
            x = mech.home_pose()
            q = mech.inverse(x)[0]
            task_inertia(mech, q, x)
        twin_rows({"pose": x[None], "joints": q[None]}, mech)           # the twin is the last one
        # Its graph's compiled steps (``kernels.twin_nodes``, ``facets.acceleration_radius_points``) with a
        # map's array layouts: two points, so that ``Lambda``, a view of the mass matrices, is strided.
        evaluate(mech, np.stack([x, x]), ("condition_number", "anisotropic_force", "isotropic_acceleration"))
        inverse_spd(np.eye(4)[None])
        packed = packed_facets(np.eye(5, 6))
        for normals in (packed[..., :-1], np.ascontiguousarray(packed[..., :-1])):   # a view, a matmul's
            slice_inscribed_radius(normals, packed[..., -1], rows=[0, 1, 2])
    _PIECES_LOADED.append(True)
    return took[0]


def warm(threads: bool = True) -> float:
    """Every compiled kernel and piece loaded now (``run.sh``'s install step); seconds it took.

    Parameters
    ----------
    threads : bool
        Also the kernels' ``prange`` builds (``kernels.warm``).

    Returns
    -------
    float
    """
    from . import kernels

    return kernels.warm(threads) + load_pieces()


def seconds_per_point(mechanism, grid: GridSpec, quantities, *, keep: bool = False, loading=None,
                      sample: int = SAMPLE_POINTS, clock: Callable[[], float] = time.perf_counter) -> float:
    """Measured run time of ``compute_map`` per point of ``grid`` in full chunks, from sample grids over its range.

    Parameters
    ----------
    mechanism : Mechanism
        The device.
    grid : GridSpec
        The job's grid (only its range and axes are used).
    quantities : iterable of str
        The job's quantities.
    keep : bool
        Whether the job keeps its arrays (``compute_map``'s ``keep``).
    loading : metrics.loading.Loading, optional
        The job's torque rating and gravity.
    sample : int
        Points of the sample (``sample_points``): a grid of half of them over the range
        (``metrics.workspace.sample_grid``) and one of a quarter of that, each timed twice.
    clock : callable ``() -> float``
        Seconds; read when each timed map starts and after its last chunk: the smaller grid
        twice, then the larger twice (a warm-up map of ``2**k`` points runs before, untimed).

    Returns
    -------
    float
        Seconds per point (> 0): the larger grid's faster time less the smaller's, over the
        points between them, plus what is left of the smaller's time (the call's own cost)
        over ``CHUNK_POINTS``, a full chunk's points.
    """
    from .workspace import compute_map, sample_grid

    large = sample_grid(grid, max(sample // 2, 2))
    small = sample_grid(grid, max(sample // 8, 2))
    warm_up(mechanism, grid, quantities, keep=keep, loading=loading)

    def timed(g: GridSpec) -> float:
        ends: list[float] = []

        def progress(fraction: float) -> None:
            if fraction >= 1.0:
                ends.append(clock())

        start = clock()
        compute_map(mechanism, g, quantities, keep=keep, loading=loading, progress=progress)
        return (ends[-1] if ends else clock()) - start

    # Each twice, the faster kept: a busy machine's one stall of a few milliseconds, in a sample
    # of some 20 ms, doubled the prediction.
    short = max(min(timed(small), timed(small)), 0.0)
    elapsed = max(min(timed(large), timed(large)), 0.0)
    points, fewer = grid_points(large.resolution), grid_points(small.resolution)
    # The slope between two chunk sizes, not from a map of 2**k points: a chunk's cost beside its
    # points (its statistics' tables) grows until a few thousand points are in it.
    per_point = (elapsed - short) / (points - fewer) if points > fewer else 0.0
    if per_point <= 0.0:
        # Noise (or a grid too small for two sizes): the larger sample's whole time over its points.
        per_point, call = elapsed / points, 0.0
    else:
        call = max(short - per_point * fewer, 0.0)
    # A clock too coarse to see the sample still must not predict "free".
    floor = time.get_clock_info("perf_counter").resolution / points
    return max(per_point + call / CHUNK_POINTS, floor)


def format_duration(seconds: float) -> str:
    """A duration as a person reads it: ``"40 s"``, ``"12 min"``, ``"3.2 h"``, ``"41 days"``, ``"2,540 years"``.

    Below 1 ns (an absurd ``--max-time``) the number is in exponent form, in ns.

    Parameters
    ----------
    seconds : float
        A duration >= 0.

    Returns
    -------
    str

    Examples
    --------
    >>> format_duration(0.0042), format_duration(42), format_duration(3600), format_duration(1e12)
    ('4.2 ms', '42 s', '1 h', '31,700 years')
    >>> format_duration(1e-9), format_duration(2.6e-4), format_duration(1.18 * 365.25 * 86400)
    ('1 ns', '260 µs', '1.2 years')
    """
    s = float(seconds)
    if not math.isfinite(s):
        return "forever"
    for unit, size, below in (("ns", 1e-9, 1e-6), ("µs", 1e-6, 1e-3), ("ms", 1e-3, 1.0), ("s", 1.0, 60.0),
                              ("min", 60.0, 3600.0), ("h", 3600.0, 2 * 86400.0), ("days", 86400.0, 365.25 * 86400.0),
                              ("years", 365.25 * 86400.0, math.inf)):
        if s < below:
            return f"{_figures(s / size)} {unit}"
    return f"{_figures(s)} s"      # pragma: no cover


def _figures(value: float) -> str:
    """Two significant figures, three from 100 on, never in exponent form: ``"4.2"``, ``"260"``, ``"31,700"``."""
    if value >= 100:
        return f"{float(f'{value:.3g}'):,.0f}"
    return f"{value:.2g}" if value >= 1e-4 else f"{value:.2e}"


@dataclass(frozen=True)
class Prediction:
    """A job's predicted run time: ``seconds`` for ``points`` points."""

    points: int
    seconds: float

    @property
    def seconds_per_point(self) -> float:
        """The rate the prediction is made of."""
        return self.seconds / self.points if self.points else 0.0


def largest_within(seconds_at: Callable[[int], float], max_seconds: float) -> int | None:
    """The largest ``n >= 2`` whose job is predicted to finish in ``max_seconds``.

    Parameters
    ----------
    seconds_at : callable ``(int) -> float``
        Predicted seconds of the job at resolution ``n`` (non-decreasing in ``n``).
    max_seconds : float
        The limit.

    Returns
    -------
    int or None
        ``None`` when even ``n = 2`` takes longer.

    Examples
    --------
    >>> largest_within(lambda n: 1e-6 * n * n, 1.0)      # 1000 x 1000 points in exactly 1 s
    1000
    >>> largest_within(lambda n: 1.0 * n ** 3, 1.0) is None
    True
    """
    def fits(n: int) -> bool:
        return seconds_at(n) <= max_seconds

    if not fits(2):
        return None
    lo, hi = 2, 4
    while fits(hi):
        lo, hi = hi, hi * 2
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if fits(mid) else (lo, mid)
    return lo


def check_run_time(what: str, points: int, seconds: float, *, seconds_at: Callable[[int], float],
                   max_seconds: float = MAX_SECONDS, option: str = "--resolution",
                   limit_option: str = "--max-time") -> Prediction:
    """Return the job's ``Prediction`` if it finishes within ``max_seconds``, else raise ``RunTimeError``.

    Parameters
    ----------
    what : str
        The job, e.g. ``"a 8000 x 8000 x 8000 map"``.
    points : int
        Its points.
    seconds : float
        Its predicted run time (points times the rate ``seconds_per_point`` measured).
    seconds_at : callable ``(int) -> float``
        Predicted seconds of the job at ``option n``, for the advice.
    max_seconds : float
        The limit (default an hour).
    option, limit_option : str
        The options the advice names.

    Returns
    -------
    Prediction

    Raises
    ------
    RunTimeError
        ``"a 8000 x 8000 x 8000 map would take about 48 days (512,000,000,000 points at 8.1 µs each,
        measured on a sample); the largest that finishes within 1 h is --resolution 765 (about
        1 h); --max-time SECONDS allows longer"``.

    Examples
    --------
    >>> check_run_time("a map", 10 ** 6, 1.0, seconds_at=lambda n: 1e-6 * n * n).seconds
    1.0
    >>> check_run_time("a map", 10 ** 12, 1e6, seconds_at=lambda n: 1e-6 * n * n)
    Traceback (most recent call last):
    ...
    metrics.runtime.RunTimeError: a map would take about 12 days (1,000,000,000,000 points at 1 µs each, \
measured on a sample); the largest that finishes within 1 h is --resolution 60000 (about 1 h); --max-time \
SECONDS allows longer
    """
    prediction = Prediction(int(points), float(seconds))
    if prediction.seconds <= max_seconds:
        return prediction
    limit = format_duration(max_seconds)
    n = largest_within(seconds_at, max_seconds)
    if n is None:
        advice = f"no {option} finishes within {limit} ({option} 2 takes about {format_duration(seconds_at(2))})"
    else:
        advice = (f"the largest that finishes within {limit} is {option} {n} (about "
                  f"{format_duration(seconds_at(n))})")
    raise RunTimeError(f"{what} would take about {format_duration(prediction.seconds)} ({prediction.points:,} "
                       f"points at {format_duration(prediction.seconds_per_point)} each, measured on a sample); "
                       f"{advice}; {limit_option} SECONDS allows longer")
