"""A map's points in chunks: each chunk's quantities and statistics partials, in parallel, cancellable.

``compute_map`` (``metrics.workspace``) plans a ``ChunkWork`` for its request and runs it over
spans of the grid with ``chunk_results``: a thread pool (numpy releases the interpreter lock in
its loops) or the compiled kernels (``metrics.kernels``), at most a window of chunks in flight
so memory stays bounded, in grid order so streamed statistics merge deterministically.
"""
from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from typing import Callable

import numpy as np

from kinematics.grid import GridSpec

from . import kernels
from .chunk_pool import Cancelled, chunk_pool, windowed  # noqa: F401  (re-exported: the map's pool and its signal)
from .loading import DEFAULT_LOADING, Loading
from .quantities import (
    QUANTITIES,
    Evaluation,
    available_quantities,
    check_quantities,
    closure,
    compiled_kernel,
    evaluate,
)
from .statistics import chunk_partial
from .suprema import LOCATIONS, finite_at_inverse

#: Largest chunk; a small map is split into ``SPLIT`` chunks (of at least ``MIN_CHUNK`` points) so
#: that the cores share it. The split is the same for any core count and with threads off: the
#: streamed means and SDs are summed per chunk, so chunks that followed the cores gave a platform's
#: mean another last bit on another machine (and between ``threads=True`` and ``False``).
CHUNK = 65536
MIN_CHUNK = 4096
SPLIT = 4

#: The quarter grids: every fourth point per axis from the first and from the third, i.e. the
#: two interleaved half grids of half grid 0. Their change from it against the half grids'
#: change from the full grid is the observed order of the grid error (``workspace.error_orders``).
QUARTER_STARTS = (0, 2)

#: Families without a kernel whose maps' statistics are compiled all the same (``kernels.chunk_partials``, with
#: kernels on): the Twin-Pantograph's graph runs compiled pieces (``kernels.twin_rows``, ``section``, ``facets``,
#: ``twin_mass``), beside which ``statistics.chunk_partial``'s numpy passes took a fifth of its map's CPU, all
#: of it holding the GIL (0.21 of 1.1 s, ``isoforce stats twin_pantograph``'s map on one thread, cProfile).
COMPILED_STATISTICS = frozenset({"twin_pantograph"})


def sub_members(index: np.ndarray, shape: tuple[int, ...], stride: int, starts) -> list[np.ndarray]:
    """For the sub-grids of every ``stride``-th point from each of ``starts``, membership, each shape (k,)."""
    ijk = np.unravel_index(index, shape)
    return [np.logical_and.reduce([c % stride == start for c in ijk]) for start in starts]


def half_members(index: np.ndarray, shape: tuple[int, ...]) -> list[np.ndarray]:
    """For the two interleaved half grids (every second point from the first / second), membership (k,)."""
    return sub_members(index, shape, 2, (0, 1))


@functools.lru_cache(maxsize=64)
def sub_grid(grid: GridSpec, stride: int, start: int) -> GridSpec | None:
    """Every ``stride``-th point per axis of ``grid`` from point ``start``; None below 2 points on an axis.

    Kept per grid (a ``GridSpec`` is immutable): every map plans its four (``ChunkWork.plan``), and
    made anew they took ~0.4 ms of a dragged five-bar map's ~10 (its coordinates, ``np.linspace``).
    """
    coords = [c[start::stride] for c in grid.coordinates()]
    if any(len(c) < 2 for c in coords):
        return None
    return GridSpec(grid.axes, tuple(float(c[0]) for c in coords), tuple(float(c[-1]) for c in coords),
                    tuple(len(c) for c in coords), grid.fixed)


def half_grid(grid: GridSpec, start: int) -> GridSpec | None:
    return sub_grid(grid, 2, start)


def sub_flat(index: np.ndarray, shape: tuple[int, ...], stride: int, start: int) -> np.ndarray:
    """Flat indices in the sub-grid (``stride``, ``start``) of full-grid flat indices (members only)."""
    ijk = np.unravel_index(index, shape)
    sub_shape = tuple((n - start + stride - 1) // stride for n in shape)
    return np.ravel_multi_index(tuple((c - start) // stride for c in ijk), sub_shape)


def half_flat(index: np.ndarray, shape: tuple[int, ...], start: int) -> np.ndarray:
    """Flat indices in the half grid ``start`` of full-grid flat indices (members only)."""
    return sub_flat(index, shape, 2, start)


def chunk_size(total: int) -> int:
    """Points per span of a grid of ``total`` points (``chunk_results``): ``CHUNK``, or a ``SPLIT``-th of a small grid.

    Parameters
    ----------
    total : int
        Points in the grid.

    Returns
    -------
    int

    Examples
    --------
    >>> chunk_size(10 ** 6), chunk_size(40000), chunk_size(100)
    (65536, 10000, 4096)
    """
    return int(min(CHUNK, max(MIN_CHUNK, -(-total // SPLIT))))


def worker_chunk(total: int, workers: int) -> int:
    """Points per span of a map whose figures do not depend on its spans (``compute_map(figures="extremes")``).

    One span per worker where the grid holds at most ``2 * workers`` full chunks (the most
    ``chunk_pool.windowed`` holds in flight, so memory stays within what ``CHUNK`` bounds); else
    ``chunk_size``. Each span costs a fixed part (the points the kernel hands back to the numpy path,
    ~0.6 ms however few; the statistics' set-up): the five-bar's 521 x 261 map took four spans
    on two workers, two of them paying it in turn on each.

    Parameters
    ----------
    total : int
        Points in the grid.
    workers : int
        The pool's workers (1: the caller's thread alone).

    Returns
    -------
    int

    Examples
    --------
    >>> worker_chunk(135981, 2), worker_chunk(100000, 1), worker_chunk(10 ** 6, 2)
    (67991, 100000, 65536)
    """
    if total > 2 * workers * CHUNK:
        return chunk_size(total)
    return int(max(chunk_size(total), -(-total // max(1, workers)), 1))


def pooled(threads: bool, total: int) -> bool:
    """Whether ``chunk_results`` runs the spans of a grid of ``total`` points on the pool, a span a worker.

    A compiled kernel's chunks take this route too (``workspace.compute_map``), each on its kernel's
    serial build; a grid of a single span keeps the caller's thread.

    Parameters
    ----------
    threads : bool
        The caller allows the pool.
    total : int
        Points in the grid.

    Returns
    -------
    bool
    """
    return threads and total > chunk_size(total)


def chunk_results(work, total: int, *, threads: bool = True, by_worker: bool = False):
    """``work((start, stop))`` over consecutive spans of a grid's ``total`` flat indices, results in order.

    Spans are ``CHUNK`` points (fewer for a small grid: ``SPLIT`` spans, whatever the workers,
    so the spans and the results are the same on any machine and with ``threads`` false) and are
    made one at a time as the window takes them: memory is a few chunks at any resolution
    (a list of every span held 1.2 GB at 8000^3 points and never ended at 10^6 per axis).

    Parameters
    ----------
    work : callable ``((int, int)) -> T``
        Evaluates one span ``[start, stop)``; run on the shared pool when ``threads``.
    total : int
        Points in the grid (a Python int: any size numpy's int64 indices reach).
    threads : bool
        Use the shared thread pool (one chunk at a time in the caller's thread when false).
    by_worker : bool
        Spans of ``worker_chunk`` (one per worker for a grid of a few chunks), for a caller whose
        results do not depend on the spans; the spans then follow the machine's cores.

    Returns
    -------
    iterator of T
        One result per span, in grid order; stopping early cancels the spans not yet started.

    Examples
    --------
    >>> list(chunk_results(lambda span: span, 10, threads=False))
    [(0, 10)]
    >>> next(iter(chunk_results(lambda span: span, 10 ** 18, threads=False)))
    (0, 65536)
    """
    workers = (os.cpu_count() or 1) if threads else 1
    chunk = worker_chunk(total, workers) if by_worker else chunk_size(total)
    spans = ((s, min(s + chunk, total)) for s in range(0, total, chunk))
    return windowed(work, spans, workers) if threads and total > chunk else map(work, spans)


@dataclass(frozen=True)
class ChunkWork:
    """What ``compute_map`` does with one chunk of points, on a worker: evaluate, classify, take statistics.

    ``plan`` checks the request once; calling the object with a span ``(start, stop)`` of flat
    grid indices returns ``(span, evaluation, (singular, inverse), parts, loci)``; ``at`` does
    the same for any points with their flat indices (``chunk_bytes_per_point`` measures it).
    ``parts`` holds per scalar quantity the partials of the full grid, the two half grids and
    the two quarter grids (``QUARTER_STARTS``; ``None`` for a grid too small to have one).
    """

    mechanism: object
    grid: GridSpec
    names: tuple[str, ...]
    request: tuple[str, ...]
    scalar: tuple[str, ...]
    loading: Loading
    has_classes: bool
    inverse_code: int | None
    finite_there: tuple[str, ...]
    halves: tuple[GridSpec | None, GridSpec | None]
    keep: bool
    cancelled: Callable[[], bool] | None = None
    #: The compiled kernel of this request (``metrics.kernels.find``), or None: the numpy path.
    kernel: object | None = None
    #: Whether the compiled passes may use every core.
    threads: bool = True
    #: The quarter grids (``QUARTER_STARTS``), or None where an axis has fewer than 2 of their points.
    quarters: tuple[GridSpec | None, ...] = (None, None)
    #: Whether the compiled statistics may share a chunk's quantities with their helper thread (with
    #: ``threads``); off, this thread takes them all (``workspace.chunk_bytes_per_point`` traces that).
    helper: bool = True
    #: Whether the chunk's statistics are taken by the compiled partials (``kernels.chunk_partials``): with a
    #: kernel, and on the numpy path of a family whose graph's pieces are compiled (``COMPILED_STATISTICS``).
    compiled_stats: bool = False

    @classmethod
    def plan(cls, mechanism, grid: GridSpec, quantities, *, keep: bool, loading: Loading | None = None,
             cancelled: Callable[[], bool] | None = None, threads: bool = True) -> "ChunkWork":
        names = check_quantities(mechanism, quantities)
        loading = DEFAULT_LOADING if loading is None else loading
        loading.check(mechanism)
        has_classes = "singularity" in available_quantities(mechanism)
        inverse_code = (mechanism.singularity_classes.index("inverse")
                        if has_classes and "inverse" in mechanism.singularity_classes else None)
        request = names + (("singularity",) if has_classes and "singularity" not in names else ())
        scalar = tuple(q for q in names if not QUANTITIES[q].categorical and QUANTITIES[q].scalar)
        finite_there = tuple(finite_at_inverse(mechanism, scalar)) if inverse_code is not None else ()
        halves = (half_grid(grid, 0), half_grid(grid, 1))
        quarters = tuple(sub_grid(grid, 4, start) for start in QUARTER_STARTS)
        kernel = compiled_kernel(mechanism, request, loading)
        if kernel is not None and not kernel.covers(grid):
            kernel = None           # every point would go back: the numpy path, its chunks over the cores
        compiled_stats = kernel is not None or (kernels.enabled()
                                                and kernels.registered_kind(mechanism) in COMPILED_STATISTICS)
        return cls(mechanism, grid, tuple(names), tuple(request), scalar, loading, has_classes, inverse_code,
                   finite_there, halves, keep, cancelled, kernel, threads, quarters, compiled_stats=compiled_stats)

    def __call__(self, span: tuple[int, int]):
        if self.cancelled is not None and self.cancelled():
            raise Cancelled()
        if self.kernel is not None:
            points = kernels.grid_points(self.grid, self.mechanism.task_names, span, threads=self.threads)
        else:
            points = self.grid.points(self.mechanism.task_names, slice(*span))
        return self.at(None, points, span)

    def at(self, index: np.ndarray | None, points: np.ndarray, span=None):
        """The work of ``__call__`` at ``points`` (k, m) whose flat grid indices are ``index`` (k,), or, with
        ``index`` None, the span ``span`` (``start + arange(k)``: none made, the selected ones computed)."""
        shape, halves, scalar = tuple(int(r) for r in self.grid.resolution), self.halves, self.scalar

        def flat(where: np.ndarray) -> np.ndarray:
            """The flat grid indices of the points at positions ``where`` (int64)."""
            return where + span[0] if index is None else index[where]

        if self.kernel is not None:
            ev = self._compiled_values(points)
        else:           # the numpy path, also on a pool thread whose own default is the kernels
            with kernels.use_compiled(False):
                ev = evaluate(self.mechanism, points, self.request, loading=self.loading)
        # Statistics see only the feasible points: select them once, and the half grids' members.
        at = np.flatnonzero(ev.feasible)
        idx = flat(at)
        # The feasible points' values: the compiled statistics' input, and where a family without classes is singular.
        values = [ev.values[q][at] for q in scalar] if self.compiled_stats or not self.has_classes else []
        if self.has_classes:
            classes = ev.values["singularity"]
            singular = ev.feasible & (classes > 0)
            direct = ev.feasible & (classes >= 2)
            inverse = (ev.feasible & (classes == self.inverse_code) if self.inverse_code is not None
                       else np.zeros_like(singular))
            held = classes[at]          # the feasible points' classes, gathered once
            sing = held > 0
            bounded = held == self.inverse_code if self.inverse_code is not None else np.zeros(at.size, bool)
            loci = tuple(flat(np.flatnonzero(found)[:LOCATIONS]) for found in (direct, inverse))
        else:
            # Singular where a quantity is infinite, found on the feasible points' values only.
            sing = np.zeros(at.size, bool)
            for v in values:
                sing |= np.isinf(v)
            singular = np.zeros_like(ev.feasible)
            singular[at] = sing
            inverse = np.zeros_like(ev.feasible)
            bounded = np.zeros(at.size, bool)
            loci = (np.empty(0, np.int64), np.empty(0, np.int64))      # no classes: no singular point located
        reg = ~sing
        if self.compiled_stats:
            parts = dict(zip(scalar, kernels.chunk_partials(
                values, reg, sing, bounded, idx, shape,
                tuple(g is not None for g in (*halves, *self.quarters)), [q in self.finite_there for q in scalar],
                histogram=not self.keep, threads=self.threads and self.helper)))
        else:
            parts = self._partials(ev, at, idx, reg, sing, bounded, shape)
            self._add_quarters(parts, ev, at, idx, reg, sing, bounded, shape)
        if not self.keep:       # a streamed map hands back only its statistics
            ev = Evaluation(feasible=np.empty(0, bool), joints=np.empty((0, 0)), values={}, computed=ev.computed)
            return span, ev, (int(at.size), None), parts, loci
        return span, ev, (singular, inverse), parts, loci

    def _compiled_values(self, points: np.ndarray) -> Evaluation:
        """``compiled_evaluate``, the same numbers: the kernel leaves the values of the points that are not
        feasible unwritten (``kernels.evaluate(fill=False)``); a streamed map reads the feasible points only,
        a kept one gets ``nan`` there in the requested rows alone.

        A kernel that fills (``nan`` in every row of its values table, twelve, where three are asked
        for) spent a quarter of the 1000 x 1000 Inverse3 map's kernel time on it (101 against 76 ms of
        CPU, ``kernels.FusedKernel.run`` over the map's chunks, ``fill`` True and False); the requested
        rows' ``nan`` cost a few ms. The points the kernel hands back hold the numpy path's values,
        ``nan`` where not feasible (``quantities.evaluate``), as they did.
        """
        def fallback(at):
            return evaluate(self.mechanism, at, self.request, loading=self.loading)

        sparse = getattr(self.kernel.module, "SPARSE_VALUES", False)
        feasible, joints, values = kernels.evaluate(self.kernel, points, self.request, fallback, threads=self.threads,
                                                    fill=False)
        if sparse and self.keep:
            outside = ~feasible
            for v in values.values():
                if v.dtype.kind == "f":         # the classes are -1 there already
                    np.copyto(v, np.nan, where=outside)
        if getattr(self.kernel.module, "SPARSE_JOINTS", False):
            # Unwritten (``kernels.evaluate(fill=False)``): a map reads no joint; none handed on.
            joints = np.empty((0, self.mechanism.n_joints))
        return Evaluation(feasible=feasible, joints=joints, values=values,
                          computed=("joints",) + tuple(closure(self.request, self.mechanism, self.loading)))

    def _partials(self, ev, at, idx, reg, sing, bounded, shape):
        """``chunk_partial`` of every scalar quantity on the full grid and the half grids (numpy)."""
        halves, scalar = self.halves, self.scalar
        members = half_members(idx, shape)
        half_idx = [half_flat(idx[m], shape, h) if halves[h] is not None else None for h, m in enumerate(members)]
        parts = {}
        for q in scalar:
            v = ev.values[q][at]
            ends = bounded if q in self.finite_there else None
            parts[q] = [chunk_partial(v, reg, sing, idx, histogram=not self.keep, bounded=ends)]
            for h, member in enumerate(members):
                parts[q].append(None if halves[h] is None else
                                chunk_partial(v[member], reg[member], sing[member], half_idx[h],
                                              histogram=not self.keep, bounded=None if ends is None else ends[member]))
        return parts

    def _add_quarters(self, parts, ev, at, idx, reg, sing, bounded, shape) -> None:
        """Append to each quantity's partials those of the quarter grids (numpy, on their 1/4^k of
        the points; the compiled partials take them with the half grids)."""
        if all(g is None for g in self.quarters):
            for q in self.scalar:
                parts[q] = [*parts[q], *(None for _ in self.quarters)]
            return
        members = sub_members(idx, shape, 4, QUARTER_STARTS)
        flat = [sub_flat(idx[m], shape, 4, s) if g is not None else None
                for g, m, s in zip(self.quarters, members, QUARTER_STARTS)]
        for q in self.scalar:
            v = ev.values[q][at]
            ends = bounded if q in self.finite_there else None
            parts[q] = [*parts[q], *(
                None if g is None else
                chunk_partial(v[m], reg[m], sing[m], f, histogram=not self.keep,
                              bounded=None if ends is None else ends[m])
                for g, m, f in zip(self.quarters, members, flat))]
