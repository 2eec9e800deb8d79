"""The largest norm in a slice of a wrench set, compiled point by point (``metrics.wrench_slices.slice_max_norm``).

The section ``Q = {s in [-1, 1]^n : G_O s = 0}``'s candidate vertices, imaged by ``G_R``
(``wrench_slices``' module doc), with the numpy formulas of ``wrench_slices._section_candidates``
operation for operation, so the same bits: the rows ``O`` equilibrated, every minor by
``linalg.minors``' Laplace expansion in its order (its index tables, ``linalg._minor_plan``), the
free sets' rounding bounds (``_det_rounding_bound``), the sign patterns summed by doubling, the
largest squared norm of the kept candidates over ``det^2`` and its running ``fmax``.

What differs is the layout. numpy went through every free set's ``(r + d) 2^(b-1)`` candidate
values in passes over a block of points; here one point's minors and candidates stay in a few
hundred bytes of scratch. A free set's ``r`` Cramer values of every sign pattern are formed by
the doubling first and tested against the box; its ``d`` image coordinates, which numpy formed
for every free set, are formed (by the same doubling, the same bits) only where a candidate is
kept, and summed only for the kept ones, in the same order. Skipping them changes no result: a
candidate outside the box never entered the maximum. The doubling for ``b = 3, 4`` and the
minors of sizes 2 and 3 are written out (the same operations, in registers), and the box test
has no branch per coefficient. Twin-Pantograph map's 101,344 feasible 5 x 6 generators (its
force and moment slices, CPU, one thread, load 1.5-2.5, best of 7): 2.05 and 1.67 us a point
before those three changes, 1.30 and 1.35 after; the first version was 2.2 against numpy's 2.2,
and on the Stewart's 6 x 6 1.8-2.2 against numpy's 3.3-3.7.

The points run on the calling thread (``nogil``): a map's chunks already run in parallel threads.
"""
from __future__ import annotations

import numpy as np

from .jit import jit


@jit()
def section_max_norm(g, others, slice_rows, levels_a, levels_b, out_a, out_b, free, index, k_eps, box, out, work):
    """Each point's largest norm of ``G_R s`` over the section's kept candidates ``s``, into ``out`` (``nan``: none).

    Parameters
    ----------
    g : ndarray, shape (N, m, n)
        The generators, batch-first and C-contiguous; overwritten (the slice rows scaled by their
        largest entry, the rows ``others`` equilibrated). A point with a non-finite entry gets ``nan``.
    others : ndarray of int, shape (r,)
        The rows ``O`` set to zero, sorted.
    slice_rows : ndarray of int, shape (d,)
        The slice's rows ``R``, in the caller's order (the wide minors' order).
    levels_a, levels_b : ndarray of int, shape (s, E, 2 s + 1)
        ``linalg._minor_plan``'s levels for the ``r``-minors of ``G_O`` (``s = r``) and for the
        ``(r + 1)``-minors of rows ``O`` plus one slice row (``s = r + 1``), packed (``pack_levels``):
        per level and minor, its count of terms' entries and sub-minors, -1 past the level's end.
    out_a, out_b : ndarray of int, shape (row sets, C(n, s))
        ``_minor_plan``'s last level's rows of each minor.
    free : ndarray of int, shape (k, r)
        ``wrench_slices._section_plan``'s free sets.
    index : ndarray of int, shape (k, b, r + d)
        ``wrench_slices._coefficient_index``: rows of ``[det; -det; wide]``.
    k_eps : float
        ``K eps`` of ``_det_rounding_bound``.
    box : float
        ``1 + VERTEX_TOL``.
    out : ndarray, shape (N,)
        The largest norm, in the unit of ``g``'s slice rows.
    work : ndarray, shape (W,)
        Scratch, at least ``scratch_size`` long.
    """
    n_pts, m, n = g.shape
    flat = g.reshape(n_pts, m * n)
    for p in range(n_pts):
        # entry (i, u) at i n + u: linalg.minors' flat index
        out[p] = section_point(flat[p], n, others, slice_rows, levels_a, levels_b, out_a, out_b, free, index, k_eps,
                               box, work)


@jit(inline=True)
def section_point(gp, n, others, slice_rows, levels_a, levels_b, out_a, out_b, free, index, k_eps, box, work):
    """One point's ``section_max_norm`` (its value; ``nan``: none), for a kernel that forms the generators itself.

    ``gp`` (m n,): the point's generators row by row (entry (i, u) at ``i n + u``), overwritten;
    ``n`` the generators' count; the other arguments as ``section_max_norm``'s (``kernels.stewart``).
    """
    m = gp.shape[0] // n
    r = others.shape[0]
    d = slice_rows.shape[0]
    k = free.shape[0]
    b = n - r
    p_count = 1
    for _ in range(b - 1):
        p_count *= 2
    e_a = levels_a.shape[1]
    e_b = levels_b.shape[1]
    # Scratch (``scratch_size``): two levels of each plan, the table [det; -det; wide], the column sums,
    # the r + d coefficients of every sign pattern, the patterns' inside flags.
    wide_n = out_b.shape[1]
    o_prev_a, o_cur_a = 0, e_a
    o_prev_b, o_cur_b = 2 * e_a, 2 * e_a + e_b
    o_table = 2 * e_a + 2 * e_b
    o_c = o_table + 2 * k + d * wide_n
    o_w = o_c + n
    o_in = o_w + (r + d) * p_count
    finite = True
    for e in range(m * n):
        if not np.isfinite(gp[e]):
            finite = False
    if not finite:
        return np.nan
    # |G_R s| computed near 1: no under/overflow (the slice rows over their largest entry).
    size = 0.0
    for i in range(d):
        for u in range(n):
            size = max(size, abs(gp[slice_rows[i] * n + u]))
    if not size > 0.0:
        size = 1.0
    for i in range(d):
        for u in range(n):
            gp[slice_rows[i] * n + u] = gp[slice_rows[i] * n + u] / size
    best = -1.0
    for i in range(r):
        o = others[i] * n
        big = 0.0
        for u in range(n):
            big = max(big, abs(gp[o + u]))
        if big > 0.0:
            for u in range(n):
                gp[o + u] = gp[o + u] / big
    # det G_O[:, F] for every F, then the wide minors, as linalg.minors computes them.
    last_a = _minors(gp, levels_a, work, o_prev_a, o_cur_a)
    for f in range(k):
        v = work[last_a + out_a[0, f]]
        work[o_table + f] = v
        work[o_table + k + f] = -v
    if b > 0:
        last_b = _minors(gp, levels_b, work, o_prev_b, o_cur_b)
        for i in range(d):
            for c in range(wide_n):
                work[o_table + 2 * k + i * wide_n + c] = work[last_b + out_b[i, c]]
    for u in range(n):
        s = abs(gp[others[0] * n + u])
        for i in range(1, r):
            s += abs(gp[others[i] * n + u])
        work[o_c + u] = s
    for f in range(k):
        det = work[o_table + f]
        prod = work[o_c + free[f, 0]]
        for kk in range(1, r):
            prod = prod * work[o_c + free[f, kk]]
        if not abs(det) > k_eps * prod:
            continue                       # bound -1 (nan too): no candidate of this free set
        bound = box * abs(det)
        # The r Cramer values of every sign pattern, numpy's doubling, in the same order.
        _doubling(work, o_table, index, f, 0, r, b, o_w, p_count)
        kept = 0
        for q in range(p_count):
            # max_c |w_c| <= bound (numpy's np.maximum then <=): every one within, nan failing;
            # tested without a branch per coefficient (the outcome is all but random).
            inside = abs(work[o_w + q]) <= bound
            for c in range(1, r):
                inside = inside & (abs(work[o_w + c * p_count + q]) <= bound)
            work[o_in + q] = 1.0 if inside else 0.0
            kept += inside
        if kept == 0:
            continue
        # The d image coordinates of every pattern, by the same doubling (numpy formed them for
        # every free set; here only for one with a kept candidate: the same bits where used).
        _doubling(work, o_table, index, f, r, r + d, b, o_w, p_count)
        largest = -1.0
        lost = False                        # a kept candidate's norm is nan: numpy's max is nan, then -1
        for q in range(p_count):
            if work[o_in + q] == 0.0:
                continue
            v = work[o_w + r * p_count + q]
            norm2 = v * v
            for c in range(r + 1, r + d):
                v = work[o_w + c * p_count + q]
                norm2 = norm2 + v * v
            if norm2 != norm2:
                lost = True
            elif norm2 > largest:
                largest = norm2
        if lost or not largest >= 0:
            continue
        value = largest / (det * det)
        if value > best:                    # np.fmax: a nan (0 / 0 where det^2 underflows) never wins
            best = value
    if best >= 0.0:
        return size * np.sqrt(max(best, 0.0))
    return np.nan


@jit(inline=True)
def _doubling(work, o_table, index, f, c0, c1, b, o_w, p_count):
    """Coefficients ``c0 .. c1 - 1`` of free set ``f``'s every sign pattern into ``work[o_w + c p_count + q]``.

    numpy's doubling: ``w[:, 0] = z[0]``, then for ``j = 1 .. b - 1`` ``w[:, h:2h] = w[:, :h] -
    z[j]`` and ``w[:, :h] += z[j]`` (``h = 2^(j-1)``), ``z[j]`` the table's row ``index[f, j, c]``.
    ``b = 3`` and ``4`` (a 6-generator device's moment and force slices) are written out with the
    same operations on the same operands, so the same bits, in registers: the loop's stores and
    reloads took a third of ``section_max_norm``'s time.
    """
    for c in range(c0, c1):
        row = o_w + c * p_count
        if b == 4:
            w0 = work[o_table + index[f, 0, c]]
            z = work[o_table + index[f, 1, c]]
            w1 = w0 - z
            w0 = w0 + z
            z = work[o_table + index[f, 2, c]]
            w2 = w0 - z
            w3 = w1 - z
            w0 = w0 + z
            w1 = w1 + z
            z = work[o_table + index[f, 3, c]]
            work[row + 4] = w0 - z
            work[row + 5] = w1 - z
            work[row + 6] = w2 - z
            work[row + 7] = w3 - z
            work[row] = w0 + z
            work[row + 1] = w1 + z
            work[row + 2] = w2 + z
            work[row + 3] = w3 + z
            continue
        if b == 3:
            w0 = work[o_table + index[f, 0, c]]
            z = work[o_table + index[f, 1, c]]
            w1 = w0 - z
            w0 = w0 + z
            z = work[o_table + index[f, 2, c]]
            work[row + 2] = w0 - z
            work[row + 3] = w1 - z
            work[row] = w0 + z
            work[row + 1] = w1 + z
            continue
        work[row] = 0.0 if b == 0 else work[o_table + index[f, 0, c]]
        h = 1
        for j in range(1, b):
            z = work[o_table + index[f, j, c]]
            for t in range(h):
                work[row + h + t] = work[row + t] - z
                work[row + t] = work[row + t] + z
            h *= 2


@jit(inline=True)
def _minors(gp, levels, work, o_a, o_b):
    """``linalg.minors``' levels at one point into ``work``, by turns at ``o_a`` and ``o_b``; the last one's offset."""
    dst, src = o_a, o_b
    for lv in range(levels.shape[0]):
        kk = lv + 1
        for e in range(levels.shape[1]):
            if levels[lv, e, 0] < 0:
                break
            if kk == 1:
                work[dst + e] = gp[levels[lv, e, 1]]
                continue
            # Sizes 2 and 3 written out: the loop's products and sums below, in its order.
            if kk == 2:
                work[dst + e] = (gp[levels[lv, e, 1]] * work[src + levels[lv, e, 3]]
                                 - gp[levels[lv, e, 2]] * work[src + levels[lv, e, 4]])
                continue
            if kk == 3:
                acc = gp[levels[lv, e, 1]] * work[src + levels[lv, e, 4]]
                acc = acc - gp[levels[lv, e, 2]] * work[src + levels[lv, e, 5]]
                work[dst + e] = acc + gp[levels[lv, e, 3]] * work[src + levels[lv, e, 6]]
                continue
            acc = gp[levels[lv, e, 1]] * work[src + levels[lv, e, 1 + kk]]
            for t in range(1, kk):
                term = gp[levels[lv, e, 1 + t]] * work[src + levels[lv, e, 1 + kk + t]]
                acc = acc - term if t % 2 == 1 else acc + term
            work[dst + e] = acc
        dst, src = src, dst
    return src


def scratch_size(levels_a: np.ndarray, levels_b: np.ndarray, out_b: np.ndarray, k: int, d: int, n: int) -> int:
    """Length of ``section_max_norm``'s ``work``.

    Parameters
    ----------
    levels_a, levels_b : ndarray
        ``pack_levels`` of the two plans.
    out_b : ndarray
        The wide plan's last level's rows.
    k, d, n : int
        Free sets, slice rows, generators.

    Returns
    -------
    int
    """
    r = levels_a.shape[0]
    p_count = 2 ** max(n - r - 1, 0)
    return 2 * levels_a.shape[1] + 2 * levels_b.shape[1] + 2 * k + d * out_b.shape[1] + n + (r + d + 1) * p_count


def pack_levels(levels) -> np.ndarray:
    """``linalg._minor_plan``'s levels as one array (s, E, 2 s + 1): ``[1, entry (s), sub (s)]``, -1 past the end.

    Parameters
    ----------
    levels : list of (entry, sub, sign)
        Level ``k``: ``entry`` and ``sub`` (E_k, k).

    Returns
    -------
    ndarray of int64
    """
    s = len(levels)
    width = max(len(entry) for entry, _, _ in levels)
    out = np.full((s, width, 2 * s + 1), -1, np.int64)
    for lv, (entry, sub, _) in enumerate(levels):
        k = lv + 1
        out[lv, :len(entry), 0] = 1
        out[lv, :len(entry), 1:1 + k] = entry
        out[lv, :len(entry), 1 + k:1 + 2 * k] = sub
    return out
