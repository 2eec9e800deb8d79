"""Memory and point-count estimates of a map, a convergence study or a design study, before it runs.

A job that cannot fit in the machine's memory should be refused at once, with the estimate and
what to do instead, rather than start, grow for minutes and die with a ``MemoryError`` (or be
killed by the kernel). Every product here is taken with Python integers, so a resolution of
2**32 per axis gives the exact point count (2**64) instead of an overflowed ``np.prod``.

The byte counts are upper estimates of what the job holds, and were checked against the peak
resident size of the process (``ru_maxrss``, GNU ``time -f %M``); ``tests/metrics/test_budget.py``
checks the arithmetic and ``tests/metrics/test_streamed_memory.py`` the peak itself:

==========================  ===============================================================
kept whole (``keep_maps``)  the feasible mask (1 byte), each requested quantity (8 bytes a
                            float, 2 a category, ``8 m n`` a Jacobian ...), and the
                            temporaries of the statistics of one quantity (24 bytes: its
                            feasible indices, values and squared deviations)
output                      CSV/NPZ: the coordinate columns (16 bytes per axis or task
                            coordinate); a figure: ~160 bytes (matplotlib's RGBA image and
                            masked arrays)
per chunk                   the bytes a chunk allocates per point, times the chunk size, the
                            chunks in flight (``workers``: one per pool worker, a compiled
                            kernel's chunks too; ``metrics.workspace.chunks_in_flight``)
                            and ``RESIDENT_PER_TRACED``: measured on samples when the caller
                            gives them (``work_bytes``, from
                            ``metrics.workspace.chunk_bytes_per_point``), else the formula
                            ``chunk_work_bytes`` (calibrated on the force figures; quantities of a
                            mass model cost several times more, which only a measurement sees)
streamed statistics         the quantile sketch of each accumulator (``SKETCH_BYTES``; five
                            per scalar quantity: the grid, its two half grids and two quarter
                            grids)
the program itself          the process's resident size when the estimate is made
                            (``Estimate.baseline``: the interpreter, numpy and the loaded
                            modules, 40-90 MB)
==========================  ===============================================================

With ``keep_maps=False`` (statistics streamed chunk by chunk) nothing grows with the point
count: the estimate is the same at any resolution. With measured ``work_bytes`` and
``workers`` it is an upper estimate for chunks whose every point is feasible, the interior of
any large grid: the peak resident size of streamed maps of 393,216 points inside the workspace
of the Inverse3, five-bar, Falcon, PHANToM Omni, Stewart platform and Twin-Pantograph was 0.57
to 0.74 of it (a corner of infeasible chunks needs less). The rest is mostly the sketches'
allowance (each is sized for its largest table; a map of one device fills a fraction of it).

No Qt, no file access other than ``/proc/meminfo`` and ``/proc/self/statm``.
"""
from __future__ import annotations

import math
import operator
import os
from dataclasses import dataclass
from typing import Sequence


#: Working memory per point of a chunk under evaluation (inverse kinematics, Jacobians, SVD
#: workspaces, masks): ``256 + 72 m n`` bytes, plus ``12 m 2**n`` for redundant actuation (the
#: zonotope's signed sums). Peaks numpy allocates (tracemalloc) for a chunk of feasible points
#: of the summary quantities: five-bar 306 B, serial RRR and Inverse3 466 B, delta 812 B,
#: Stewart 2.3 kB, Inoue 2.7 kB, Twin-Pantograph 3.3 kB; the formula gives 544 B, 904 B, 904 B,
#: 2.8 kB, 2.8 kB and 6.3 kB.
def chunk_work_bytes(mechanism) -> int:
    """Bytes of working memory per point of a chunk being evaluated (see above).

    Parameters
    ----------
    mechanism : Mechanism
        Its ``task_dim`` (m) and ``n_joints`` (n) size the estimate.

    Returns
    -------
    int
        Bytes per point.

    Examples
    --------
    >>> from kinematics import FiveBar
    >>> chunk_work_bytes(FiveBar(proximal=0.1, distal=0.1, half_base=0.05))
    544
    """
    m, n = int(mechanism.task_dim), int(mechanism.n_joints)
    return 256 + 72 * m * n + (12 * m * 2 ** n if n > m else 0)


#: Accumulators of a streamed map per scalar quantity, each with its sketch: the grid, its two
#: half grids and its two quarter grids (``metrics.map_chunks.QUARTER_STARTS``).
SKETCHES_PER_QUANTITY = 5
#: Resident bytes per byte a chunk in flight allocates: freed buffers stay in each worker
#: thread's malloc arena. Peaks of streamed maps of feasible chunks were 0.90 to 1.09 times the
#: traced chunk bytes in flight plus the sketches; 1.25 covers them.
RESIDENT_PER_TRACED = 1.25
#: Points per chunk (``metrics.map_chunks.CHUNK``; repeated here so the estimate needs no import
#: of the map code).
CHUNK_POINTS = 65536
#: Temporaries of ``metrics.workspace.statistics`` per point, for one quantity at a time.
STATS_BYTES = 24
#: The quantile histogram of one streamed accumulator (``metrics.statistics.StatsAccumulator``):
#: 32 bytes a bin (key, count, lowest and highest value), at most twice the compacted table plus
#: 65,536 entries between compactions; 2**17 entries covers a compacted table of 8 binades
#: (the most held by any shipped device's map, 100,629 entries, was the five-bar's condition number).
SKETCH_BYTES = 32 << 17
#: Extra bytes per point of an export, by kind (per coordinate for the data files).
OUTPUT_BYTES_PER_COORD = {"csv": 16, "npz": 16}
FIGURE_BYTES = 160
#: Share of the available memory a job may plan to use: the rest is for the interpreter,
#: libraries and whatever else the machine runs.
USABLE_FRACTION = 0.8
#: Used when the available memory cannot be read (no /proc/meminfo and no sysconf).
FALLBACK_AVAILABLE = 4 << 30
#: The most points a map can index with numpy's int64 flat indices.
MAX_POINTS = 1 << 62
#: Per design of a design study: its record (id, value, exact flag, samples: 25 bytes),
#: the merge, sort and concatenation copies of the records and the chunk plan.
STUDY_DESIGN_BYTES = 128
#: Per (design, sample) pair of one evaluation block (``metrics.culling.BLOCK_PAIRS`` of them
#: per worker): the objective, the feasible mask and the evaluator's temporaries.
STUDY_PAIR_BYTES = 256
STUDY_BLOCK_PAIRS = 1 << 20


class BudgetError(ValueError):
    """A job that would not fit in memory (or cannot be indexed): the message says what to do."""


@dataclass(frozen=True)
class Estimate:
    """The memory and size of a job, estimated before it runs.

    Attributes
    ----------
    what : str
        The job, e.g. ``"a 100000 x 100000 map"``.
    points : int
        Grid points (maps) or (design, sample) pairs (studies): a Python int, never overflowed.
    bytes : int
        Estimated peak bytes the job allocates.
    per_point : int
        Bytes that grow with each point (0 when streamed).
    fixed : int
        Bytes that do not grow with the point count (chunk buffers, worker blocks).
    counted : str
        What ``points`` counts, for the text.
    baseline : int
        The process's resident bytes when the estimate was made (0: not counted); ``bytes``
        is what the job adds to it, and what must fit in the available memory.
    """

    what: str
    points: int
    bytes: int
    per_point: int
    fixed: int
    counted: str = "points"
    baseline: int = 0

    @property
    def peak(self) -> int:
        """Estimated peak resident size of the process running the job: ``baseline + bytes``."""
        return self.baseline + self.bytes

    def text(self) -> str:
        """``"a 100000 x 100000 map: 10,000,000,000 points, about 490 GB"``.

        Returns
        -------
        str

        Examples
        --------
        >>> study_estimate(1000, 0, 3).text()
        'a design grid: 1,000 designs, about 128 kB'
        """
        return f"{self.what}: {self.points:,} {self.counted}, about {format_bytes(self.peak)}"


def format_bytes(n: int | float) -> str:
    """Bytes as ``"1.5 GB"`` (powers of 1000, 2 or 3 significant figures).

    Parameters
    ----------
    n : int or float
        A number of bytes.

    Returns
    -------
    str

    Examples
    --------
    >>> format_bytes(1.5e9), format_bytes(999)
    ('1.5 GB', '999 B')
    """
    n = float(n)
    for unit in ("B", "kB", "MB", "GB", "TB", "PB", "EB"):
        if abs(n) < 1000 or unit == "EB":
            return f"{n:.3g} {unit}" if unit != "B" else f"{int(n)} B"
        n /= 1000.0
    return f"{n:.3g} EB"      # pragma: no cover


def grid_points(resolution: Sequence[int]) -> int:
    """Points of a grid with ``resolution`` points per axis, exactly (Python ints).

    Parameters
    ----------
    resolution : sequence of int, shape (k,)
        Points per axis.

    Returns
    -------
    int
        The product, never overflowed.

    Raises
    ------
    ValueError
        If an entry is not an integer >= 1, naming ``resolution``.

    Examples
    --------
    >>> grid_points((2**32, 2**32))
    18446744073709551616
    """
    total = 1
    for n in resolution:
        try:
            n = operator.index(n)
        except TypeError:
            raise ValueError(f"resolution needs integers, got {tuple(resolution)!r}") from None
        if n < 1:
            raise ValueError(f"resolution needs integers >= 1, got {tuple(resolution)!r}")
        total *= n
    return total


def quantity_bytes(mechanism, name: str) -> int:
    """Bytes per point a map stores for quantity ``name`` of ``mechanism``.

    Scalars are float64 (8), categories int16 (2); vector nodes hold their per-point array,
    measured by evaluating the node at one point (``jacobian`` ``8 m n``, ``singular_values``
    ``8 min(m, n)``, ``column_norms`` ``8 n`` for m task coordinates and n joints).

    Parameters
    ----------
    mechanism : Mechanism
        The device (its ``task_dim`` and ``n_joints``).
    name : str
        A quantity of ``metrics.quantities.QUANTITIES``.

    Returns
    -------
    int
        Bytes per point.

    Examples
    --------
    >>> from kinematics import FiveBar
    >>> mech = FiveBar(proximal=0.1, distal=0.1, half_base=0.05)
    >>> quantity_bytes(mech, "isotropic_force"), quantity_bytes(mech, "jacobian"), quantity_bytes(mech, "singularity")
    (8, 32, 2)
    """
    # Imported here: the graph and its nodes (0.1 s) are not needed by the callers of the other
    # functions (``check_fits`` of a semi-dextrous region, the command line's start-up).
    from .quantities import QUANTITIES

    node = QUANTITIES.get(name)
    if node is None:
        raise ValueError(f"quantities: unknown quantity {name!r}")
    if node.categorical:
        return 2
    if node.scalar:
        return 8
    try:
        # The node's own per-point shape, from one (probably infeasible) point: exact for any
        # vector node, also ones added later.
        import numpy as np

        from .quantities import evaluate

        with np.errstate(all="ignore"):
            arr = evaluate(mechanism, np.zeros((1, int(mechanism.task_dim))), [name]).values[name]
        return int(arr.nbytes)
    except Exception:       # a node that cannot take an empty batch: the usual shapes
        m, n = int(mechanism.task_dim), int(mechanism.n_joints)
        shapes = {"singular_values": min(m, n), "column_norms": n}
        return 8 * shapes.get(name, m * n)


def resident_bytes() -> int:
    """The resident size of this process now, in bytes (0 where it cannot be read).

    ``/proc/self/statm`` (Linux); else the peak so far (``ru_maxrss``), an upper estimate.

    Returns
    -------
    int
        Bytes.
    """
    try:
        with open("/proc/self/statm", encoding="ascii") as fh:
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError, AttributeError):
        pass
    try:
        import resource
        import sys

        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        return int(peak) * (1 if sys.platform == "darwin" else 1024)      # bytes on macOS, kB elsewhere
    except (ImportError, OSError, ValueError):
        return 0


def map_estimate(mechanism, resolution: Sequence[int], quantities: Sequence[str], *, keep_maps: bool = True,
                 output: str | None = None, workers: int | None = None, chunk: int = CHUNK_POINTS,
                 copies: int = 1, baseline: int | None = None, work_bytes: float | None = None) -> Estimate:
    """Estimated peak memory of a workspace map of ``quantities`` at ``resolution``.

    Parameters
    ----------
    mechanism : Mechanism
        The device (its ``task_dim`` and ``n_joints`` size the vector quantities).
    resolution : sequence of int, shape (k,)
        Points per axis.
    quantities : sequence of str
        The requested quantities.
    keep_maps : bool
        True when the whole map is held (shown or exported); False when statistics are streamed
        chunk by chunk, so only the chunks in flight count.
    output : {None, "csv", "npz", "figure"}
        The export, which adds its own per-point arrays (only with ``keep_maps``).
    workers : int, optional
        Chunks in flight at once (default: the CPU count, one per pool worker, a compiled
        kernel's chunks too; ``metrics.workspace.chunks_in_flight``).
    chunk : int
        Points per chunk.
    copies : int
        Maps of this size held at once (2 for a comparison of two designs).
    baseline : int, optional
        Resident bytes of the process before the job (default: ``resident_bytes()`` now).
    work_bytes : float, optional
        Bytes a chunk allocates per point, measured (``metrics.workspace.chunk_bytes_per_point``);
        default ``chunk_work_bytes`` and the quantities' own arrays.

    Returns
    -------
    Estimate
        ``bytes`` is what the job adds, ``peak`` the process's resident size at its peak.
    """
    from .quantities import QUANTITIES  # (imported here: see quantity_bytes)

    res = tuple(resolution)
    points = grid_points(res)
    if output not in (None, "csv", "npz", "figure"):
        raise ValueError(f"output must be None, 'csv', 'npz' or 'figure', got {output!r}")
    names = list(dict.fromkeys(quantities))
    workers = max(1, int(workers if workers is not None else (os.cpu_count() or 1)))
    in_flight = min(points, workers * int(chunk))
    if work_bytes is None:
        work_bytes = chunk_work_bytes(mechanism) + sum(quantity_bytes(mechanism, q) for q in names) + 1
    fixed = math.ceil(in_flight * RESIDENT_PER_TRACED * float(work_bytes))
    scalar = sum(1 for q in names if not QUANTITIES[q].categorical and QUANTITIES[q].scalar)
    if not keep_maps:
        fixed += SKETCHES_PER_QUANTITY * scalar * SKETCH_BYTES
    per_point = 0
    if keep_maps:
        per_point = 1 + sum(quantity_bytes(mechanism, q) for q in names)
        if scalar:
            per_point += STATS_BYTES
        if output == "figure":
            per_point += FIGURE_BYTES
        elif output is not None:
            per_point += OUTPUT_BYTES_PER_COORD[output] * (len(res) + int(mechanism.task_dim)) + 8
    per_point *= max(1, int(copies))
    what = (f"{'a' if copies == 1 else copies} {' x '.join(str(n) for n in res)} map{'' if copies == 1 else 's'}"
            + ("" if keep_maps else " (statistics streamed)"))
    return Estimate(what=what, points=points, bytes=points * per_point + fixed, per_point=per_point, fixed=fixed,
                    baseline=resident_bytes() if baseline is None else int(baseline))


def study_estimate(n_designs: int, n_samples: int, task_dim: int, *, workers: int = 1) -> Estimate:
    """Estimated peak memory of a design study of ``n_designs`` designs on ``n_samples`` samples.

    Counts the records of every design, each process's copy of the sample points
    (``8 task_dim`` bytes each, sent to every worker), and one evaluation block of
    ``STUDY_BLOCK_PAIRS`` (design, sample) pairs per process. ``points`` is the brute-force
    pair count ``D x S``; with ``n_samples = 0`` (a design grid being parsed) it is ``D``.

    Parameters
    ----------
    n_designs : int
        ``D``, designs in the study.
    n_samples : int
        ``S``, workspace samples per design (0: the design grid alone).
    task_dim : int
        Task coordinates per sample.
    workers : int
        Worker processes (one more, the parent, when above 1).

    Returns
    -------
    Estimate

    Examples
    --------
    >>> study_estimate(1000, 0, 3).bytes
    128000
    """
    d, s = int(n_designs), int(n_samples)
    procs = max(1, int(workers)) + (1 if workers > 1 else 0)
    block = min(d * s, STUDY_BLOCK_PAIRS) * STUDY_PAIR_BYTES
    fixed = procs * (8 * int(task_dim) * s + block)
    if s == 0:
        return Estimate(what="a design grid", points=d, bytes=d * STUDY_DESIGN_BYTES, per_point=STUDY_DESIGN_BYTES,
                        fixed=0, counted="designs")
    return Estimate(what=f"a study of {d:,} designs x {s:,} samples", points=d * s,
                    bytes=d * STUDY_DESIGN_BYTES + fixed, per_point=STUDY_DESIGN_BYTES, fixed=fixed,
                    counted="(design, sample) pairs")


def available_memory() -> int:
    """Bytes of memory available to a new job.

    ``MemAvailable`` of ``/proc/meminfo`` (Linux: free memory plus the caches the kernel can
    drop); else ``sysconf`` free physical pages; else ``FALLBACK_AVAILABLE`` (4 GiB). The
    environment variable ``ISOFORCE_MEMORY`` (bytes, or with a ``k``/``M``/``G`` suffix, powers
    of 1024) overrides it, e.g. to stay within a container's or a batch job's limit.

    Returns
    -------
    int
        Bytes.
    """
    override = os.environ.get("ISOFORCE_MEMORY", "").strip()
    if override:
        return parse_bytes(override, "ISOFORCE_MEMORY")
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    parts = line.split()
                    return int(parts[1]) * (1024 if parts[2:3] == ["kB"] else 1)
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, OSError, ValueError):
        return FALLBACK_AVAILABLE


def parse_bytes(text: str, name: str = "memory") -> int:
    """``"512M"``, ``"2G"``, ``"1048576"`` as bytes (suffixes k, M, G, T in powers of 1024).

    Parameters
    ----------
    text : str
        A positive number, optionally with a suffix (and ``B`` / ``iB``), any case.
    name : str
        What the text sets, for the ValueError's message.

    Returns
    -------
    int
        Bytes.

    Examples
    --------
    >>> parse_bytes("512M"), parse_bytes("2GiB"), parse_bytes("1048576")
    (536870912, 2147483648, 1048576)
    """
    units = {"": 1, "k": 1 << 10, "m": 1 << 20, "g": 1 << 30, "t": 1 << 40}
    t = text.strip().lower().removesuffix("b").removesuffix("i")
    suffix = t[-1:] if t[-1:] in units and t[-1:] != "" and not t[-1:].isdigit() else ""
    number = t[:-1] if suffix else t
    try:
        value = float(number) * units[suffix]
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} needs a positive number of bytes (e.g. 2G, 512M), got {text!r}")
    return int(value)


def check_fits(estimate: Estimate, *, advice: str, available: int | None = None) -> Estimate:
    """Return ``estimate`` if it fits in ``USABLE_FRACTION`` of the available memory, else raise.

    Parameters
    ----------
    estimate : Estimate
        The job's estimate (``map_estimate``, ``study_estimate``).
    advice : str
        What to do instead, appended to the message (e.g. ``"use --resolution 9000 or less"``).
    available : int, optional
        Bytes available (default ``available_memory()``).

    Returns
    -------
    Estimate
        ``estimate`` itself.

    Raises
    ------
    BudgetError
        ``"a 100000 x 100000 map: 10,000,000,000 points, about 490 GB; this machine has 24.8 GB
        available: use --resolution 9000 or less"``.

    Examples
    --------
    >>> check_fits(study_estimate(1000, 0, 3), advice="use fewer designs", available=10**9).points
    1000
    """
    if estimate.points > MAX_POINTS and estimate.counted == "points":
        raise BudgetError(f"{estimate.text()}: more than the {MAX_POINTS:,} points a map can index; {advice}")
    avail = available_memory() if available is None else int(available)
    if estimate.bytes > USABLE_FRACTION * avail:
        raise BudgetError(f"{estimate.text()}; this machine has {format_bytes(avail)} available "
                          f"(ISOFORCE_MEMORY overrides): {advice}")
    return estimate


def largest_resolution(mechanism, resolution: Sequence[int], quantities: Sequence[str], *, keep_maps: bool = True,
                       output: str | None = None, available: int | None = None, copies: int = 1,
                       work_bytes: float | None = None, workers: int | None = None) -> int:
    """The largest ``n`` such that a map with the grid's shape scaled to ``n`` points on its longest
    axis (the others in proportion, as ``isoforce --resolution`` sets every axis to ``n``) fits.

    Used in the advice of a refusal: every axis at ``n`` (``--resolution n``). Returns at least 2
    (the caller still checks that one).

    Parameters
    ----------
    mechanism : Mechanism
        The device.
    resolution : sequence of int, shape (k,)
        The requested points per axis (only ``k`` is used).
    quantities : sequence of str
        The requested quantities.
    keep_maps : bool
        Whole map held (True) or statistics streamed (False), as in ``map_estimate``.
    output : {None, "csv", "npz", "figure"}
        The export.
    available : int, optional
        Bytes available (default ``available_memory()``).
    copies : int
        Maps of this size held at once.
    work_bytes : float, optional
        A chunk's bytes per point, measured (``map_estimate``).
    workers : int, optional
        Chunks in flight (``map_estimate``).

    Returns
    -------
    int
        ``n`` >= 2, points per axis.
    """
    avail = available_memory() if available is None else int(available)
    k = len(tuple(resolution))

    def fits(n: int) -> bool:
        est = map_estimate(mechanism, (n,) * k, quantities, keep_maps=keep_maps, output=output, copies=copies,
                           baseline=0, work_bytes=work_bytes, workers=workers)
        return est.bytes <= USABLE_FRACTION * avail and est.points <= MAX_POINTS

    lo, hi = 2, 4
    while fits(hi):
        lo, hi = hi, hi * 2
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if fits(mid) else (lo, mid)
    return lo


def check_map(mechanism, resolution: Sequence[int], quantities: Sequence[str], *, keep_maps: bool = True,
              output: str | None = None, available: int | None = None, option: str = "--resolution",
              copies: int = 1, work_bytes: float | None = None, workers: int | None = None) -> Estimate:
    """``check_fits`` for a map, with advice naming the largest ``option`` that fits.

    Parameters
    ----------
    mechanism : Mechanism
        The device.
    resolution : sequence of int, shape (k,)
        Points per axis.
    quantities : sequence of str
        The requested quantities.
    keep_maps : bool
        Whole map held (True) or statistics streamed (False), as in ``map_estimate``.
    output : {None, "csv", "npz", "figure"}
        The export.
    available : int, optional
        Bytes available (default ``available_memory()``).
    option : str
        The command-line option the advice names.
    copies : int
        Maps of this size held at once.
    work_bytes : float, optional
        A chunk's bytes per point, measured (``map_estimate``).
    workers : int, optional
        Chunks in flight (``map_estimate``; default the CPU count).

    Returns
    -------
    Estimate
        The map's estimate, when it fits.

    Raises
    ------
    BudgetError
        When the map does not fit, e.g. ``"... : use --resolution 9000 or less, or ask for
        fewer quantities"``.
    """
    est = map_estimate(mechanism, resolution, quantities, keep_maps=keep_maps, output=output, copies=copies,
                       work_bytes=work_bytes, workers=workers)
    avail = available_memory() if available is None else int(available)
    if est.points <= MAX_POINTS and est.bytes <= USABLE_FRACTION * avail:
        return est
    n = largest_resolution(mechanism, resolution, quantities, keep_maps=keep_maps, output=output, available=avail,
                           copies=copies, work_bytes=work_bytes, workers=workers)
    fitting = map_estimate(mechanism, (n,) * len(tuple(resolution)), quantities, keep_maps=keep_maps, output=output,
                           copies=copies, baseline=est.baseline, work_bytes=work_bytes, workers=workers)
    advice = f"use {option} {n} or less (about {format_bytes(fitting.peak)})"
    if output is not None:
        advice += ", or statistics only (isoforce stats)"
    return check_fits(est, advice=advice, available=avail)
