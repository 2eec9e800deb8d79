"""The streamed statistics of one chunk, compiled: ``statistics.chunk_partial`` of every quantity and sub-grid.

One task per (quantity, grid): the full grid, the two interleaved half grids and the two quarter
grids of ``workspace.resolution_error`` (``GRIDS``: every ``stride``-th point per axis from
``start``). Each task makes three passes over the chunk's feasible points:
the count and the sum (Neumaier-compensated: within 2 eps of the exact mean however many points,
no worse than numpy's pairwise ``np.mean``), then the largest deviation, whose power of two scales
the squared deviations (so values near 1e-300 or 1e300 neither underflow nor overflow), then their
compensated sum. Extremes keep the smallest grid index on ties, as ``np.argmin`` does in grid
order. The tasks run over the cores (``prange``); each task's arithmetic is serial and its own,
so the figures do not depend on the thread count.

``histogram`` bins a task's regular values by their key (``statistics._keys``) into a dense table
over the keys the chunk spans, when that span is at most ``DENSE_BINS``; a wider span (values over
more than 16 binades in one chunk) is left to ``statistics._histogram`` (a sort).
"""
from __future__ import annotations

import math

import numpy as np
from numba import prange

from metrics.statistics import QUANTILE_BITS, SINGULAR_LOCATIONS

from .jit import jit, twins

#: Widest key span ``histogram`` bins densely: 16 binades of ``2^QUANTILE_BITS`` bins.
DENSE_BINS = 16 << QUANTILE_BITS
_SHIFT = 52 - QUANTILE_BITS


#: The grids of a chunk's statistics, ``(stride, start)``: the full grid, the half grids, the quarter
#: grids (``map_chunks.QUARTER_STARTS``), in ``chunk_partials``' order.
GRIDS = ((1, 0), (2, 0), (2, 1), (4, 0), (4, 2))
_STRIDES = np.array([g[0] for g in GRIDS], np.int64)
_STARTS = np.array([g[1] for g in GRIDS], np.int64)


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
def _task(task, values, regular, singular, bounded, grids, ends,
          count, mean, m2, scale, lo, hi, argmin, argmax, n_singular, singular_at, member):
    """One (quantity, grid) task of ``run_parallel``: two passes over the chunk's points."""
    k = values.shape[1]
    q, g = task // grids.shape[0], task % grids.shape[0]
    if not grids[g]:
        return
    total, comp, n = 0.0, 0.0, 0
    vmin, vmax, imin, imax, ns = math.inf, -math.inf, -1, -1, 0
    rmin, rmax = math.inf, -math.inf            # over the regular points only: the deviations' extremes
    row, where = values[q], member[g]
    for i in range(k):
        at = where[i]
        if at < 0:
            continue
        v = row[i]
        finite = math.isfinite(v)
        if singular[i]:
            if ns < SINGULAR_LOCATIONS:
                singular_at[q, g, ns] = at
            ns += 1
        if finite and (regular[i] or (ends[q] and bounded[i] and singular[i])):
            if v < vmin or (v == vmin and at < imin):
                vmin, imin = v, at
            if v > vmax or (v == vmax and at < imax):
                vmax, imax = v, at
        if regular[i] and finite:
            n += 1
            rmin, rmax = min(rmin, v), max(rmax, v)
            t = total + v
            comp += (total - t) + v if abs(total) >= abs(v) else (v - t) + total
            total = t
    n_singular[q, g] = ns
    lo[q, g], hi[q, g], argmin[q, g], argmax[q, g] = vmin, vmax, imin, imax
    count[q, g] = n
    if n == 0:
        mean[q, g], m2[q, g], scale[q, g] = 0.0, 0.0, 0.0
        return
    mu = (total + comp) / n
    # max |v - mu| is at an extreme: rounding is monotone, so fl(max v - mu) is the largest fl(v - mu).
    spread = max(rmax - mu, mu - rmin)
    s = math.ldexp(1.0, math.frexp(spread)[1]) if spread > 0.0 else 0.0
    total, comp = 0.0, 0.0
    if s > 0.0:
        for i in range(k):
            v = row[i]
            if where[i] >= 0 and regular[i] and math.isfinite(v):
                d = (v - mu) / s
                v = d * d
                t = total + v
                comp += (total - t) + v if abs(total) >= abs(v) else (v - t) + total
                total = t
    mean[q, g], m2[q, g], scale[q, g] = mu, total + comp, s


def _run(values, regular, singular, bounded, index, shape, grids, ends,
         count, mean, m2, scale, lo, hi, argmin, argmax, n_singular, singular_at, member, strides, starts):
    """Fill the per-task figures (arrays (Q, G), ``singular_at`` (Q, G, SINGULAR_LOCATIONS)): over the
    cores in ``run_parallel``, on the calling thread in ``run_serial`` (``jit.twins``).

    ``values`` (Q, k) at the chunk's feasible points; ``regular``, ``singular``, ``bounded`` (k,);
    ``index`` (k,) their flat grid indices; ``shape`` the grid's resolution; ``grids`` (G,) which
    grids to take (``GRIDS``, given by ``strides`` and ``starts``); ``ends`` (Q,) whether the
    ``bounded`` singular points' finite values enter the extremes. ``member`` (G, k) is scratch: each
    point's index in each grid.
    """
    nq, k = values.shape
    ng = grids.shape[0]
    for i in prange(k):
        member[0, i] = index[i]
        for g in range(1, ng):
            member[g, i] = _sub_index(index[i], shape, strides[g], starts[g]) if grids[g] else -1
    for task in prange(nq * ng):
        _task(task, values, regular, singular, bounded, grids, ends,
              count, mean, m2, scale, lo, hi, argmin, argmax, n_singular, singular_at, member)


run_parallel, run_serial = twins(_run, "run")


@jit(allocates=True)
def histogram(values, bits, q, take):
    """Dense bins of ``values[q, take]`` (finite; ``bits`` the same array viewed as uint64):
    ``(keys, counts, lows, highs, ok)``, ``ok`` False where the span is too wide."""
    k = values.shape[1]
    kmin, kmax = np.uint64(0xFFFFFFFFFFFFFFFF), np.uint64(0)
    sign = np.uint64(1) << np.uint64(63)
    shift = np.uint64(_SHIFT)
    keys = np.empty(k, np.uint64)
    for i in range(k):
        if take[i]:
            b = bits[q, i]
            ordered = ~b if (b & sign) != 0 else b | sign
            key = ordered >> shift
            keys[i] = key
            kmin = min(kmin, key)
            kmax = max(kmax, key)
    empty = np.empty(0, np.uint64)
    if kmax < kmin:
        return empty, np.empty(0, np.int64), np.empty(0), np.empty(0), True
    span = np.int64(kmax - kmin) + 1
    if span > DENSE_BINS:
        return empty, np.empty(0, np.int64), np.empty(0), np.empty(0), False
    counts = np.zeros(span, np.int64)
    lows = np.full(span, np.inf)
    highs = np.full(span, -np.inf)
    for i in range(k):
        if take[i]:
            slot = np.int64(keys[i] - kmin)
            v = values[q, i]
            counts[slot] += 1
            lows[slot] = min(lows[slot], v)
            highs[slot] = max(highs[slot], v)
    used = 0
    for slot in range(span):
        used += counts[slot] > 0
    out_keys = np.empty(used, np.uint64)
    out_counts = np.empty(used, np.int64)
    out_lows = np.empty(used)
    out_highs = np.empty(used)
    j = 0
    for slot in range(span):
        if counts[slot] > 0:
            out_keys[j] = kmin + np.uint64(slot)
            out_counts[j], out_lows[j], out_highs[j] = counts[slot], lows[slot], highs[slot]
            j += 1
    return out_keys, out_counts, out_lows, out_highs, True


def strides(count: int) -> np.ndarray:
    """The first ``count`` grids' strides (``GRIDS``), int64 (count,)."""
    return _STRIDES[:count]


def starts(count: int) -> np.ndarray:
    """The first ``count`` grids' starts (``GRIDS``), int64 (count,)."""
    return _STARTS[:count]
