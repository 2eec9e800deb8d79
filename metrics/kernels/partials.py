"""The streamed statistics of one chunk, compiled: ``statistics.chunk_partial`` of every quantity and sub-grid.

The grids are the full grid, the two interleaved half grids and the two quarter grids of
``workspace.resolution_error`` (``GRIDS``: every ``stride``-th point per axis from ``start``).
``prepare`` lists each grid's members, in chunk order, from each point's residues per axis, and
counts and locates each grid's singular points: these do not depend on the quantity. Then
``quantity`` takes one quantity on every grid, in two passes over each grid's members:

1. the count and the sum (Neumaier-compensated: within 2 eps of the exact mean however many
   points, no worse than numpy's pairwise ``np.mean``) and the extremes;
2. the squared deviations, scaled by the power of two of the largest deviation (so values near
   1e-300 or 1e300 neither underflow nor overflow), in a compensated sum, and the histogram's
   counts and ends per bin.

Extremes keep the smallest grid index on ties, as ``np.argmin`` does in grid order; they are
tracked by full-grid index and mapped to the sub-grid at the end (``_sub_index`` is monotone on a
sub-grid's members, so the tie rule is the same). Each figure is summed serially in chunk order,
so the figures are those of the per-(quantity, grid) loops this replaces, bit for bit.

The histogram bins a grid's regular values by their key (``statistics._keys``) into a dense table
over the keys they span, when that span is at most ``DENSE_BINS``; a wider span (values over more
than 16 binades in one chunk) is left to ``statistics._histogram`` (a sort) by the caller.

``shared`` runs the quantities on the calling thread and a helper thread, each taking the next
quantity not yet taken: no parallel region to start and join, and the caller never waits for the
helper to be scheduled (on a loaded machine it takes every quantity itself).
"""
from __future__ import annotations

import contextlib
import itertools
import math
import os
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from metrics.statistics import QUANTILE_BITS, QUANTILES, SINGULAR_LOCATIONS

from .jit import jit

#: Widest key span the histogram bins densely: 16 binades of ``2^QUANTILE_BITS`` bins.
DENSE_BINS = 16 << QUANTILE_BITS
_SHIFT = 52 - QUANTILE_BITS

#: The grids of a chunk's statistics, ``(stride, start)``: the full grid, the half grids, the quarter
#: grids (``map_chunks.QUARTER_STARTS``), in ``chunk_partials``' order.
GRIDS = ((1, 0), (2, 0), (2, 1), (4, 0), (4, 2))
_STRIDES = np.array([g[0] for g in GRIDS], np.int64)
_STARTS = np.array([g[1] for g in GRIDS], np.int64)
#: A coordinate's residue modulo ``_PERIOD`` (a power of two all strides divide) decides its membership
#: of every grid along that axis: ``_AXIS_BITS[r]`` has bit g set where grid g takes residue r.
_PERIOD = math.lcm(*_STRIDES.tolist())
if _PERIOD & (_PERIOD - 1):
    raise ValueError(f"the grids' strides must divide a power of two, got {_STRIDES.tolist()}")
_AXIS_BITS = np.array([sum(1 << g for g, (stride, start) in enumerate(GRIDS) if r % stride == start)
                       for r in range(_PERIOD)], np.int64)


@jit()
def _sub_index(index, shape, stride, start):
    """Flat index in the sub-grid (``stride``, ``start``) of full-grid flat ``index`` (C order), or -1."""
    out, mult, rest = 0, 1, index
    for d in range(shape.shape[0] - 1, -1, -1):
        c = rest % shape[d]
        rest //= shape[d]
        if c % stride != start:
            return -1
        out += ((c - start) // stride) * mult
        mult *= (shape[d] - start + stride - 1) // stride
    return out


@jit()
def _masks(index, shape, wanted, mask):
    """``mask[i]``: bit g set where point i is in grid g (and ``wanted`` has bit g).

    A point's membership is the AND over its axes of ``_AXIS_BITS`` at the coordinate's residue. The
    coordinates are unravelled by division only when a point leaves the previous point's row (the
    last axis): a chunk is a run of flat indices, so that is about once a row.
    """
    nd = shape.shape[0]
    last = shape[nd - 1]
    low = _PERIOD - 1
    base, outer = -1, 0
    for i in range(index.shape[0]):
        f = index[i]
        c = f - base
        if base < 0 or c < 0 or c >= last:
            row = f // last
            base = row * last
            c = f - base
            outer = wanted
            for d in range(nd - 2, -1, -1):
                outer &= _AXIS_BITS[(row % shape[d]) & low]
                row //= shape[d]
        mask[i] = outer & _AXIS_BITS[c & low]


@jit()
def _key(b):
    """``statistics._keys`` of one float's bit pattern ``b`` (uint64)."""
    if (b & np.uint64(0x8000000000000000)) != np.uint64(0):
        return ~b >> np.uint64(_SHIFT)
    return (b | np.uint64(0x8000000000000000)) >> np.uint64(_SHIFT)


@jit()
def _full_key(b):
    """The order key of one float's bit pattern ``b`` (uint64), untruncated: ``_key`` before its shift."""
    if (b & np.uint64(0x8000000000000000)) != np.uint64(0):
        return ~b
    return b | np.uint64(0x8000000000000000)


@jit()
def _first_pass(row, index, pos, ident, size):
    """Pass 1 over a grid's regular members (``pos[:size]``, or ``range(size)`` where ``ident``), the finite
    values: ``(n, mean, lo, hi, ilo, ihi)``.

    The compensated mean, and the extremes with their full-grid indices (the smallest on ties). The
    index is read only where a value reaches an extreme: the common point costs a load and two compares.
    ``ident`` is loop-invariant, so the compiler makes two loops of this one, the full grid's without
    the indirection (a third faster).
    """
    total, comp, n = 0.0, 0.0, 0
    lo, hi, ilo, ihi = math.inf, -math.inf, -1, -1
    for j in range(size):
        i = j if ident else pos[j]
        v = row[i]
        if not math.isfinite(v):
            continue
        n += 1
        t = total + v
        comp += (total - t) + v if abs(total) >= abs(v) else (v - t) + total
        total = t
        if v <= lo and (v < lo or index[i] < ilo):
            lo, ilo = v, index[i]
        if v >= hi and (v > hi or index[i] < ihi):
            hi, ihi = v, index[i]
    return n, (total + comp) / n if n else 0.0, lo, hi, ilo, ihi


@jit()
def _edge_extremes(row, index, edge, n_edge, mask, g, lo, hi, ilo, ihi):
    """``lo, hi, ilo, ihi`` widened by the finite values at grid g's ``bounded`` singular points (``edge``)."""
    for j in range(n_edge):
        i = edge[j]
        v = row[i]
        if not ((mask[i] >> g) & 1 and math.isfinite(v)):
            continue
        if v <= lo and (v < lo or index[i] < ilo):
            lo, ilo = v, index[i]
        if v >= hi and (v > hi or index[i] < ihi):
            hi, ihi = v, index[i]
    return lo, hi, ilo, ihi


@jit()
def _key_span(row, bits, pos, ident, size, lo, hi):
    """The smallest and largest key of a grid's finite regular values, which span ``[lo, hi]``.

    Keys order as the values do, so they are the keys of ``lo`` and ``hi``; but -0.0 and +0.0 compare
    equal and have keys of their own, so a zero at either end is settled by looking at every member.
    """
    kmin, kmax = _key(np.float64(lo).view(np.uint64)), _key(np.float64(hi).view(np.uint64))
    if lo != 0.0 and hi != 0.0:
        return kmin, kmax
    kmin, kmax = np.uint64(0xFFFFFFFFFFFFFFFF), np.uint64(0)
    for j in range(size):
        i = j if ident else pos[j]
        if math.isfinite(row[i]):
            key = _key(bits[i])
            kmin = min(kmin, key)
            kmax = max(kmax, key)
    return kmin, kmax


@jit()
def _second_pass(row, bits, pos, ident, size, mu, s, kmin, dense, table):
    """Pass 2 over a grid's finite regular values: the compensated sum of ``((v - mu) / s)^2`` (0 unless ``s`` > 0)
    and, when ``dense``, the histogram: ``table`` (span, 3) rows ``[count, low, high]`` from key ``kmin``.

    ``s`` is a power of two: where ``1 / s`` is one as well, ``x * (1 / s)`` is ``x / s`` bit for bit (both
    round the same exact product once), and a multiplication is several times cheaper than a division.
    """
    total, comp = 0.0, 0.0
    if s <= 0.0 and not dense:
        return 0.0
    r = 1.0 / s if s > 0.0 else 0.0
    exact = math.isfinite(r) and r * s == 1.0
    for j in range(size):
        i = j if ident else pos[j]
        v = row[i]
        if not math.isfinite(v):
            continue
        if s > 0.0:
            d = (v - mu) * r if exact else (v - mu) / s
            w = d * d
            t = total + w
            comp += (total - t) + w if abs(total) >= abs(w) else (w - t) + total
            total = t
        if dense:
            slot = np.int64(_key(bits[i]) - kmin)
            table[slot, 0] += 1.0
            table[slot, 1] = min(table[slot, 1], v)
            table[slot, 2] = max(table[slot, 2], v)
    return total + comp


@jit()
def _drain(span, kmin, table, at, keys, counts, lows, highs):
    """Copy the used bins of ``table[:span]`` to the outputs from ``at`` on and clear them; the new end."""
    for slot in range(span):
        c = table[slot, 0]
        if c > 0.0:
            keys[at] = kmin + np.uint64(slot)
            counts[at], lows[at], highs[at] = np.int64(c), table[slot, 1], table[slot, 2]
            at += 1
            table[slot, 0], table[slot, 1], table[slot, 2] = 0.0, math.inf, -math.inf
    return at


@jit()
def prepare(index, shape, grids, regular, singular, bounded, members, mask, edge, sizes, n_singular, singular_at):
    """What every quantity of a chunk shares: each grid's regular points, its singular points, the bounded ones.

    Parameters
    ----------
    index : ndarray of int64, shape (k,)
        The chunk's feasible points' flat grid indices.
    shape : ndarray of int64, shape (d,)
        The grid's resolution.
    grids : ndarray of bool, shape (G,)
        Which grids (``GRIDS``, the first G) to take.
    regular, singular, bounded : ndarray of bool, shape (k,)
        As ``statistics.chunk_partial`` takes them.
    members : ndarray of int64, shape (G, >= k)
        Filled: ``members[g, :sizes[g]]``, grid g's regular points (positions in the chunk), in chunk order.
    mask : ndarray of int64, shape (>= k,)
        Filled: each point's grids, as bits.
    edge : ndarray of int64, shape (>= k,)
        Filled: the ``bounded`` singular points that are not regular, in chunk order.
    sizes, n_singular : ndarray of int64, shape (G,)
        Filled: each grid's regular points, and its singular points (the same for every quantity).
    singular_at : ndarray of int64, shape (G, SINGULAR_LOCATIONS)
        Filled: the first singular points, in each grid's own flat order.

    Returns
    -------
    int
        How many ``edge`` points.
    """
    k, ng = index.shape[0], grids.shape[0]
    wanted = 0
    for g in range(ng):
        n_singular[g] = 0
        if grids[g]:
            wanted |= 1 << g
    _masks(index, shape, wanted, mask)
    for g in range(ng):
        # Branch-free: every point is written, and the next one overwrites it unless this one is taken.
        n, row = 0, members[g]
        for i in range(k):
            row[n] = i
            n += (mask[i] >> g) & regular[i]
        sizes[g] = n
    n_edge = 0
    for i in range(k):
        if not singular[i]:
            continue
        if bounded[i] and not regular[i]:
            edge[n_edge] = i
            n_edge += 1
        for g in range(ng):
            if (mask[i] >> g) & 1:
                if n_singular[g] < SINGULAR_LOCATIONS:
                    singular_at[g, n_singular[g]] = _sub_index(index[i], shape, _STRIDES[g], _STARTS[g])
                n_singular[g] += 1
    return n_edge


@jit()
def quantity(row, index, shape, grids, members, sizes, mask, edge, n_edge, end, histogram, whole, real, bins, dense,
             table, keys, counts, lows, highs):
    """One quantity's figures on every grid (as ``prepare`` listed them), and their histograms.

    Parameters
    ----------
    row : ndarray, shape (k,)
        The quantity at the chunk's feasible points.
    index, shape, grids, members, sizes, mask, edge, n_edge
        As ``prepare`` took, filled and returned them.
    end : bool
        Whether the ``edge`` points' finite values enter the extremes.
    histogram : bool
        Also bin the values.
    whole : ndarray of int64, shape (3, G)
        Filled: count, argmin, argmax (indices in each grid's own flat order).
    real : ndarray, shape (5, G)
        Filled: mean, m2, scale, min, max (``statistics.Partial``).
    bins : ndarray of int64, shape (G, 2)
        Filled: each grid's ``[start, stop)`` in ``keys``, ``counts``, ``lows``, ``highs`` (empty without one).
    dense : ndarray of bool, shape (G,)
        Filled: False where the keys span more than ``DENSE_BINS`` (that histogram is left to the caller).
    table : ndarray, shape (>= DENSE_BINS, 3)
        Scratch, rows ``[0, inf, -inf]`` on entry and on return: the dense bins ``[count, low, high]``.
    keys, counts, lows, highs : ndarray, shape (>= sum of min(sizes, DENSE_BINS),)
        Filled: the grids' bins (uint64 keys, int64 counts, the smallest and largest value), grid after grid.
    """
    ng = grids.shape[0]
    bits = row.view(np.uint64)
    ident = sizes[0] == row.shape[0]           # every point regular: the full grid's list is 0, 1, 2, ...
    at = 0
    for g in range(ng):
        dense[g] = True
        bins[g, 0] = bins[g, 1] = at
        if not grids[g]:
            continue
        pos, size, flat = members[g], sizes[g], ident and g == 0
        n, mu, rlo, rhi, ilo, ihi = _first_pass(row, index, pos, flat, size)
        lo, hi = rlo, rhi
        if end:
            lo, hi, ilo, ihi = _edge_extremes(row, index, edge, n_edge, mask, g, lo, hi, ilo, ihi)
        whole[0, g] = n
        whole[1, g] = _sub_index(ilo, shape, _STRIDES[g], _STARTS[g]) if ilo >= 0 else -1
        whole[2, g] = _sub_index(ihi, shape, _STRIDES[g], _STARTS[g]) if ihi >= 0 else -1
        # max |v - mu| is at an extreme: rounding is monotone, so fl(max v - mu) is the largest fl(v - mu).
        spread = max(rhi - mu, mu - rlo) if n else 0.0
        s = math.ldexp(1.0, math.frexp(spread)[1]) if spread > 0.0 else 0.0
        real[0, g], real[2, g], real[3, g], real[4, g] = mu, s, lo, hi
        kmin, span = np.uint64(0), 0
        if histogram and n:
            kmin, kmax = _key_span(row, bits, pos, flat, size, rlo, rhi)
            span = np.int64(kmax - kmin) + 1
            if span > DENSE_BINS:
                dense[g], span = False, 0
        real[1, g] = _second_pass(row, bits, pos, flat, size, mu, s, kmin, span > 0, table)
        if span > 0:
            at = _drain(span, kmin, table, at, keys, counts, lows, highs)
            bins[g, 1] = at


#: Buckets of ``grid_quantiles``' histogram: the keys between a quantity's extremes cut into this many.
QUANTILE_BUCKETS = 1 << 12


@jit()
def _bucket(key, kmin, shift):
    """Bucket of order key ``key``: ``(key - kmin) >> shift``, clamped to ``[0, QUANTILE_BUCKETS)`` (monotone)."""
    if key <= kmin:
        return 0
    return min(np.int64((key - kmin) >> np.uint64(shift)), QUANTILE_BUCKETS - 1)


@jit()
def _members(f, shape, wanted):
    """The grids (bits, ``GRIDS``) that flat index ``f`` of a grid of ``shape`` belongs to, of ``wanted``."""
    bits = wanted
    for d in range(shape.shape[0] - 1, -1, -1):
        bits &= _AXIS_BITS[(f % shape[d]) & (_PERIOD - 1)]
        f //= shape[d]
    return bits


@jit(allocates=True)
def grid_quantiles(values, regular, shape, grids, fractions, lo, hi, out):
    """Exact ``inverted_cdf`` quantiles of one quantity of a kept map on every grid (``GRIDS``), in two passes.

    ``statistics.exact_quantiles(v[regular & isfinite(v)])`` of each grid, without the masked copies
    and the partitions: pass 1 counts each grid's finite regular values per bucket of their order
    keys (``_key`` unshifted: keys order as the values do, so a quantile's bucket is found from the
    counts), pass 2 collects the values of the buckets holding the wanted ranks, and each rank is
    then read from its bucket's values, sorted. Buckets span the keys of ``[lo, hi]`` (any range
    is correct: the bucket of a key outside it is the nearest end, still in order; the map's extremes
    make the buckets small).

    Parameters
    ----------
    values : ndarray, shape (N,)
        The quantity at every grid point, flat C order.
    regular : ndarray of bool, shape (N,)
        The regular points.
    shape : ndarray of int64, shape (d,)
        The grid's resolution.
    grids : ndarray of bool, shape (G,)
        Which grids of ``GRIDS`` (the first G) to take.
    fractions : ndarray of int64, shape (R, 2)
        Each quantile as numerator, denominator: the 1-based rank of ``n`` values is ``max(1, ceil(num n / den))``.
    lo, hi : float
        Finite; the buckets' range.
    out : ndarray, shape (G, R)
        Filled: the quantiles (``nan`` for a grid without values or not taken).
    """
    ng, nr, n = grids.shape[0], fractions.shape[0], values.shape[0]
    wanted = 0
    for g in range(ng):
        if grids[g]:
            wanted |= 1 << g
    kmin = _full_key(np.float64(lo).view(np.uint64))
    kmax = _full_key(np.float64(hi).view(np.uint64))
    kmin = min(kmin, kmax)
    span, shift = kmax - kmin, 0
    while (span >> np.uint64(shift)) >= np.uint64(QUANTILE_BUCKETS):
        shift += 1
    bits = values.view(np.uint64)
    counts = np.zeros((QUANTILE_BUCKETS, ng), np.int64)       # a bucket's grids side by side: one cache line
    last = shape[shape.shape[0] - 1]
    low = _PERIOD - 1
    for row in range(n // last):
        outer = _members(row, shape[:-1], wanted) if shape.shape[0] > 1 else wanted
        base = row * last
        for c in range(last):
            f = base + c
            if not regular[f] or not math.isfinite(values[f]):
                continue
            b = _bucket(_full_key(bits[f]), kmin, shift)
            m = outer & _AXIS_BITS[c & low]
            for g in range(ng):
                counts[b, g] += (m >> g) & 1
    # Each rank's bucket and its rank among the bucket's values (0-based).
    target = np.full((ng, nr), -1, np.int64)
    within = np.zeros((ng, nr), np.int64)
    size = np.zeros(ng * nr + 1, np.int64)
    wanted_bucket = np.zeros(QUANTILE_BUCKETS, np.bool_)     # the buckets pass 2 collects from
    for g in range(ng):
        total = 0
        for b in range(QUANTILE_BUCKETS):
            total += counts[b, g]
        for r in range(nr):
            out[g, r] = math.nan
            if total == 0:
                continue
            rank = max(1, (fractions[r, 0] * total + fractions[r, 1] - 1) // fractions[r, 1]) - 1
            seen = 0
            for b in range(QUANTILE_BUCKETS):
                if rank < seen + counts[b, g]:
                    target[g, r], within[g, r] = b, rank - seen
                    size[g * nr + r + 1] = counts[b, g]
                    wanted_bucket[b] = True
                    break
                seen += counts[b, g]
    for j in range(ng * nr):
        size[j + 1] += size[j]
    held = np.empty(size[ng * nr])
    fill = size[:ng * nr].copy()
    for row in range(n // last):
        outer = _members(row, shape[:-1], wanted) if shape.shape[0] > 1 else wanted
        base = row * last
        for c in range(last):
            f = base + c
            if not regular[f] or not math.isfinite(values[f]):
                continue
            b = _bucket(_full_key(bits[f]), kmin, shift)
            if not wanted_bucket[b]:
                continue
            m = outer & _AXIS_BITS[c & low]
            for g in range(ng):
                if (m >> g) & 1:
                    for r in range(nr):
                        if target[g, r] == b:
                            held[fill[g * nr + r]] = values[f]
                            fill[g * nr + r] += 1
    for g in range(ng):
        for r in range(nr):
            if target[g, r] >= 0:
                out[g, r] = np.sort(held[size[g * nr + r]:size[g * nr + r + 1]])[within[g, r]]


_LOADED: list[bool] = []


def load_grid_quantiles() -> float:
    """Compile ``grid_quantiles`` (or load it from the cache) on first use; the seconds it took (0 if done).

    ``metrics.kernels.exact_grid_quantiles`` adds them to ``kernels.compile_seconds`` (this module
    does not import its package: no import cycle).

    Returns
    -------
    float
    """
    if _LOADED:
        return 0.0
    start = time.perf_counter()
    grid_quantiles(np.zeros(2), np.ones(2, bool), np.array([1, 2], np.int64), np.ones(1, bool),
                   np.ones((1, 2), np.int64), 0.0, 0.0, np.empty((1, 1)))
    _LOADED.append(True)
    return time.perf_counter() - start


def exact_grid_quantiles(values: np.ndarray, regular: np.ndarray, grids, lo: float, hi: float) -> list:
    """``statistics.exact_quantiles`` of a kept map's regular finite values on each of ``GRIDS`` (``grid_quantiles``).

    Parameters
    ----------
    values : ndarray, shape ``resolution``
        One quantity over the grid (2 or 3 axes).
    regular : ndarray of bool, shape ``resolution``
        The regular points.
    grids : sequence of bool
        Which grids of ``GRIDS`` (the first ``len(grids)``) to take.
    lo, hi : float
        Finite: where the values mostly lie (the map's extremes); any range gives the same quantiles.

    Returns
    -------
    list of dict or None
        Per grid, ``QUANTILES`` by name (``nan`` without values), or None where not taken.

    Examples
    --------
    >>> v = np.arange(16.0).reshape(4, 4)
    >>> exact_grid_quantiles(v, v > 0, [True, True], 1.0, 15.0)
    [{'p05': 1.0, 'median': 8.0, 'p95': 15.0}, {'p05': 2.0, 'median': 8.0, 'p95': 10.0}]
    """
    load_grid_quantiles()
    fractions = np.array([[q.numerator, q.denominator] for q in QUANTILES.values()], np.int64)
    grids = np.array(grids, bool)
    out = np.empty((len(grids), len(fractions)))
    flat = np.ascontiguousarray(values, np.float64).reshape(-1)
    grid_quantiles(flat, np.ascontiguousarray(regular, bool).reshape(-1), np.array(values.shape, np.int64), grids,
                   fractions, float(lo), float(hi), out)
    return [dict(zip(QUANTILES, row)) if take else None for take, row in zip(grids.tolist(), out.tolist())]


class _Scratch(threading.local):
    """Per thread, reused from chunk to chunk: ``prepare``'s lists, the dense bins (kept cleared), the bins out."""

    def __init__(self) -> None:
        self.points = np.empty((len(GRIDS) + 2, 0), np.int64)
        self.table = np.empty((DENSE_BINS, 3))
        self.table[:, 0], self.table[:, 1], self.table[:, 2] = 0.0, math.inf, -math.inf
        self.bins = (np.empty(0, np.uint64), np.empty(0, np.int64), np.empty(0), np.empty(0))


_SCRATCH = _Scratch()


def scratch(k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """This thread's ``(members, mask, edge)`` for ``prepare`` on a chunk of ``k`` points (reused).

    Fresh chunk-sized arrays are fresh pages, faulted in on first touch: on this machine, copying
    the values into one fresh (Q, k) table cost 9-21 ms over a 1000 x 1000 map (1000-3600 faults).

    Parameters
    ----------
    k : int
        Points in the chunk.

    Returns
    -------
    members : ndarray of int64, shape (len(GRIDS), >= k)
    mask, edge : ndarray of int64, shape (>= k,)
    """
    if _SCRATCH.points.shape[1] < k:
        _SCRATCH.points = np.empty((len(GRIDS) + 2, k), np.int64)
    points = _SCRATCH.points
    return points[:len(GRIDS)], points[len(GRIDS)], points[len(GRIDS) + 1]


def table() -> np.ndarray:
    """This thread's dense bins for ``quantity``, rows ``[0, inf, -inf]``, shape (DENSE_BINS, 3).

    Returns
    -------
    ndarray
    """
    return _SCRATCH.table


def bins_out(room: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """This thread's ``(keys, counts, lows, highs)`` for ``quantity``, at least ``room`` long (reused).

    Parameters
    ----------
    room : int
        Bins needed.

    Returns
    -------
    tuple of ndarray
        uint64, int64, float64, float64, shape (>= room,).
    """
    if _SCRATCH.bins[0].shape[0] < room:
        _SCRATCH.bins = (np.empty(room, np.uint64), np.empty(room, np.int64), np.empty(room), np.empty(room))
    return _SCRATCH.bins


#: Fewest point-quantities (points x quantities) a chunk shares with the helper: handing work over
#: cost 0.06-0.10 ms a chunk (measured on this 2-core machine at a load average of 6, empty to 23k
#: point chunks), which is ``quantity``'s time for about 4k points x 8 quantities.
SHARED_MIN = 1 << 15


def shares(count: int, k: int) -> bool:
    """Whether ``chunk_partials`` (with ``threads``) offers ``count`` quantities of ``k`` points to the helper.

    Parameters
    ----------
    count : int
        Quantities.
    k : int
        Feasible points of the chunk.

    Returns
    -------
    bool
    """
    return count > 1 and k * count >= SHARED_MIN


@contextlib.contextmanager
def fresh_scratch():
    """Every thread's scratch empty in the block, as in a fresh process, then the one before back.

    A traced chunk (``workspace.chunk_bytes_per_point``) then grows the buffers as a job's first
    chunk does, whatever the process ran before. The calling thread's dense bins are made here,
    outside the block's work (a process makes its main thread's at import); another thread makes
    its own in the block, on its first quantity.

    Yields
    ------
    None
    """
    global _SCRATCH
    held, _SCRATCH = _SCRATCH, _Scratch()
    try:
        yield
    finally:
        _SCRATCH = held


def quantity_bytes() -> int:
    """Bytes of this thread's scratch that ``quantity`` uses: its dense bins and its bins out.

    The helper thread of ``shared`` holds as much once it has taken a quantity of a chunk (its
    own dense bins, and bins out grown to the chunk's ``room``); ``prepare``'s lists are the
    calling thread's only.

    Returns
    -------
    int
    """
    return _SCRATCH.table.nbytes + sum(b.nbytes for b in _SCRATCH.bins)

_HELPER: list[ThreadPoolExecutor] = []
_HELPER_LOCK = threading.Lock()
# A forked child has no helper thread, only its executor's record of one: it starts its own.
os.register_at_fork(after_in_child=_HELPER.clear)


def shared(count: int, one, *, helper: bool) -> list:
    """``[one(0), ..., one(count - 1)]``, this thread and (``helper``) a second one taking items in turn.

    Each thread takes the next item not yet taken, so this thread never waits for the helper to
    start: on a loaded machine it does every item itself and waits at most for the one item the
    helper took, if any. ``one`` runs the compiled kernels without the interpreter lock.

    Parameters
    ----------
    count : int
        Items.
    one : callable ``(int) -> object``
        One item's work; thread-safe for distinct items.
    helper : bool
        Share the items with the helper thread.

    Returns
    -------
    list
        The items' results, in order.
    """
    results: list = [None] * count
    if not helper or count < 2:
        return [one(i) for i in range(count)]
    taken = itertools.count()        # next() on it is atomic under the interpreter lock
    done = [threading.Event() for _ in range(count)]
    errors: list[BaseException] = []

    def work() -> None:
        for i in iter(taken.__next__, None):
            if i >= count:
                return
            try:
                results[i] = one(i)
            except BaseException as exc:    # re-raised in the caller's thread
                errors.append(exc)
            finally:
                done[i].set()

    with _HELPER_LOCK:
        if not _HELPER:
            _HELPER.append(ThreadPoolExecutor(max_workers=1, thread_name_prefix="isoforce-partials"))
    _HELPER[0].submit(work)
    work()
    for event in done:
        event.wait()
    if errors:
        raise errors[0]
    return results
