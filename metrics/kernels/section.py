"""The largest norm in a slice of a wrench set, compiled point by point (``metrics.wrench_slices.slice_max_norm``).

The section ``Q = {s in [-1, 1]^n : G_O s = 0}``'s candidate vertices, imaged by ``G_R``
(``wrench_slices``' module doc), with the numpy formulas of ``wrench_slices._section_candidates``
operation for operation, so the same bits: the rows ``O`` equilibrated, every minor by
``linalg.minors``' Laplace expansion in its order (its index tables, ``linalg._minor_plan``), the
free sets' rounding bounds (``_det_rounding_bound``), the sign patterns summed by doubling, the
largest squared norm of the kept candidates over ``det^2`` and its running ``fmax``.

What differs is the layout. numpy went through every free set's ``(r + d) 2^(b-1)`` candidate
values in passes over a block of points; here a block of ``BLOCK`` points (lanes) goes through
the same steps together, each step's operations over the lanes in one loop the compiler
vectorises, in a scratch of a few hundred rows of ``BLOCK``: the entries, scaled (``_load``), the
minors (``_block_minors``), the table ``[det; -det; wide]``, the column sums; then per free set
the rounding bound of each lane, and where one lane has a live free set the doubling of its
``r + d`` coefficients (``_doubling``), and each lane's box test and norms, without a branch per
coefficient. A lane's values are those of the point alone, in numpy's order (the lanes share
loops, no sum). A lane whose free set is skipped gets the bound -1, which no candidate meets,
nan included: what skipping it did. ``section_point`` (a fused kernel's one point) is a block of
one lane. Twin-Pantograph map's 101,344 feasible 5 x 6 generators, its force and moment slices
(CPU, one thread, load 5, best of 7): 0.95 and 0.94 us a point, against 1.96 and 1.63 one
point at a time with a branch per coefficient and the coefficients' doubling in loops (this
module before); that one was 2.2 against numpy's 2.2, and on the Stewart's 6 x 6 1.8-2.2
against numpy's 3.3-3.7.

The points run on the calling thread (``nogil``): a map's chunks already run in parallel threads.
"""
from __future__ import annotations

import numpy as np

from .jit import jit

#: Points per block in ``section_max_norm``: the minors, the doubling and the box test run over a
#: block's points in inner loops the compiler vectorises; per point the operations are the same
#: whatever the block. Twin-Pantograph's force and moment slices (CPU, one thread, load 5, best
#: of 7): 1.29 and 1.31 us a point one point at a time, 1.22 / 1.21 in blocks of 4, 1.11 / 1.06
#: of 8, 1.06 / 1.01 of 16 (before ``_doubling`` was written out for b = 3, 4).
BLOCK = 16


@jit()
def section_max_norm(g, others, slice_rows, levels_a, levels_b, out_a, out_b, free, index, k_eps, box, out, work):
    """Each point's largest norm of ``G_R s`` over the section's kept candidates ``s``, into ``out`` (``nan``: none).

    Parameters
    ----------
    g : ndarray, shape (N, m, n)
        The generators, batch-first and C-contiguous (read only). A point with a non-finite entry
        gets ``nan``.
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
    width = BLOCK                       # a constant: the lanes' loops unrolled and vectorised
    w = work[:_rows(m, n, others.shape[0], slice_rows.shape[0], levels_a, levels_b, out_b, free) * width]
    w = w.reshape(w.shape[0] // width, width)
    for lo in range(0, n_pts, width):
        nb = min(width, n_pts - lo)
        for ln in range(width):
            # entry (i, u) at i n + u: linalg.minors' flat index; a short block's last lanes get
            # zeros (their results are never read)
            _load(flat[lo + min(ln, nb - 1)], n, others, slice_rows, w, ln, ln < nb)
        o_size = _block(w, width, m, n, others, levels_a, levels_b, out_a, out_b, free, index, k_eps, box)
        for ln in range(nb):
            out[lo + ln] = _result(w, o_size, ln)


# Called, not inlined: inlined into the Stewart kernel's two slices and its two builds, the blocked
# code's unrolled loops took LLVM 131.5 + 234 s to compile (serial + prange) against 32.9 + 52.9 s
# called (one cold compile each, this machine); a point's section is ~2 us, beside which the call is nothing.
@jit()
def section_point(gp, n, others, slice_rows, levels_a, levels_b, out_a, out_b, free, index, k_eps, box, work):
    """One point's ``section_max_norm`` (its value; ``nan``: none), for a kernel that forms the generators itself.

    ``gp`` (m n,): the point's generators row by row (entry (i, u) at ``i n + u``), read only;
    ``n`` the generators' count; the other arguments as ``section_max_norm``'s (``kernels.stewart``):
    a block of one point.
    """
    m = gp.shape[0] // n
    w = work[:_rows(m, n, others.shape[0], slice_rows.shape[0], levels_a, levels_b, out_b, free)]
    w = w.reshape(w.shape[0], 1)
    _load(gp, n, others, slice_rows, w, 0, True)
    o_size = _block(w, 1, m, n, others, levels_a, levels_b, out_a, out_b, free, index, k_eps, box)
    return _result(w, o_size, 0)


@jit(inline=True)
def _offsets(m, n, r, d, k, e_a, e_b, wide_n, p_count):
    """Rows of the block's scratch (``scratch_size``): the scaled entries, two levels of each plan, the
    table [det; -det; wide], the column sums, the r + d coefficients of every sign pattern, then
    per point its scale, whether finite, its best value and its free set's bound."""
    o_g = 0
    o_a = o_g + m * n
    o_b = o_a + 2 * e_a
    o_table = o_b + 2 * e_b
    o_c = o_table + 2 * k + d * wide_n
    o_w = o_c + n
    o_size = o_w + (r + d) * p_count
    return o_g, o_a, o_b, o_table, o_c, o_w, o_size


@jit(inline=True)
def _rows(m, n, r, d, levels_a, levels_b, out_b, free):
    """The scratch's rows (``_offsets``' last and its four per-point rows)."""
    p_count = 2 ** max(n - r - 1, 0)
    return _offsets(m, n, r, d, free.shape[0], levels_a.shape[1], levels_b.shape[1], out_b.shape[1], p_count)[6] + 4


@jit(inline=True)
def _load(gp, n, others, slice_rows, w, ln, use):
    """Point ``gp``'s entries into lane ``ln`` (row ``i n + u``): the slice rows over their largest entry, the
    rows ``others`` equilibrated; its scale and whether it is finite (zeros and not finite where not ``use``)."""
    m = gp.shape[0] // n
    r = others.shape[0]
    d = slice_rows.shape[0]
    o_size = w.shape[0] - 4
    finite = use
    for e in range(m * n):
        if not np.isfinite(gp[e]):
            finite = False
    w[o_size + 1, ln] = 1.0 if finite else 0.0
    w[o_size, ln] = 1.0
    if not finite:                      # its result is nan; zeros keep the lane's arithmetic quiet
        for e in range(m * n):
            w[e, ln] = 0.0
        return
    for e in range(m * n):
        w[e, ln] = gp[e]
    # |G_R s| computed near 1: no under/overflow (the slice rows over their largest entry).
    size = 0.0
    for i in range(d):
        for u in range(n):
            size = max(size, abs(gp[slice_rows[i] * n + u]))
    if not size > 0.0:
        size = 1.0
    for i in range(d):
        for u in range(n):
            w[slice_rows[i] * n + u, ln] = gp[slice_rows[i] * n + u] / size
    w[o_size, ln] = size
    for i in range(r):
        o = others[i] * n
        big = 0.0
        for u in range(n):
            big = max(big, abs(gp[o + u]))
        if big > 0.0:
            for u in range(n):
                w[o + u, ln] = gp[o + u] / big


@jit(inline=True)
def _result(w, o_size, ln):
    """Lane ``ln``'s largest norm (``nan``: none, or an entry not finite)."""
    best = w[o_size + 2, ln]
    if w[o_size + 1, ln] != 0.0 and best >= 0.0:
        return w[o_size, ln] * np.sqrt(max(best, 0.0))
    return np.nan


@jit(inline=True)
def _block(w, width, m, n, others, levels_a, levels_b, out_a, out_b, free, index, k_eps, box):
    """The largest ``|G_R s|^2 / det^2`` of each lane's kept candidates into row ``o_size + 2`` (-1: none); ``o_size``.

    ``w`` (rows, width): lanes loaded by ``_load``. Each lane's operations are those of one point
    alone, in numpy's order; the lanes only share the loops.
    """
    r = others.shape[0]
    d = out_b.shape[0]
    k = free.shape[0]
    b = n - r
    p_count = 1
    for _ in range(b - 1):
        p_count *= 2
    e_a = levels_a.shape[1]
    e_b = levels_b.shape[1]
    wide_n = out_b.shape[1]
    o_g, o_a, o_b, o_table, o_c, o_w, o_size = _offsets(m, n, r, d, k, e_a, e_b, wide_n, p_count)
    o_best, o_bound = o_size + 2, o_size + 3
    # det G_O[:, F] for every F, then the wide minors, as linalg.minors computes them.
    last_a = _block_minors(w, width, o_g, levels_a, o_a, o_a + e_a)
    for f in range(k):
        src = last_a + out_a[0, f]
        for ln in range(width):
            v = w[src, ln]
            w[o_table + f, ln] = v
            w[o_table + k + f, ln] = -v
    if b > 0:
        last_b = _block_minors(w, width, o_g, levels_b, o_b, o_b + e_b)
        for i in range(d):
            for c in range(wide_n):
                src = last_b + out_b[i, c]
                dst = o_table + 2 * k + i * wide_n + c
                for ln in range(width):
                    w[dst, ln] = w[src, ln]
    for u in range(n):
        for ln in range(width):
            w[o_c + u, ln] = abs(w[o_g + others[0] * n + u, ln])
        for i in range(1, r):
            for ln in range(width):
                w[o_c + u, ln] = w[o_c + u, ln] + abs(w[o_g + others[i] * n + u, ln])
    for ln in range(width):
        w[o_best, ln] = -1.0
    for f in range(k):
        live = False
        for ln in range(width):
            det = w[o_table + f, ln]
            prod = w[o_c + free[f, 0], ln]
            for kk in range(1, r):
                prod = prod * w[o_c + free[f, kk], ln]
            # bound -1 (det nan too): no candidate of this free set at this point
            keep = abs(det) > k_eps * prod
            w[o_bound, ln] = box * abs(det) if keep else -1.0
            live = live | keep
        if not live:
            continue
        # The r Cramer values and the d image coordinates of every sign pattern, numpy's doubling.
        _doubling(w, width, o_table, index, f, r + d, b, o_w, p_count)
        for ln in range(width):
            bound = w[o_bound, ln]
            largest = -1.0
            lost = False                # a kept candidate's norm is nan: numpy's max is nan, then -1
            for q in range(p_count):
                # max_c |w_c| <= bound (numpy's np.maximum then <=): every one within, nan failing;
                # tested without a branch per coefficient (the outcome is all but random).
                inside = abs(w[o_w + q, ln]) <= bound
                for c in range(1, r):
                    inside = inside & (abs(w[o_w + c * p_count + q, ln]) <= bound)
                v = w[o_w + r * p_count + q, ln]
                norm2 = v * v
                for c in range(r + 1, r + d):
                    v = w[o_w + c * p_count + q, ln]
                    norm2 = norm2 + v * v
                lost = lost | (inside & (norm2 != norm2))
                largest = norm2 if inside & (norm2 > largest) else largest
            det = w[o_table + f, ln]
            value = largest / (det * det)
            # np.fmax: a nan (0 / 0 where det^2 underflows) never wins
            if not lost and largest >= 0 and value > w[o_best, ln]:
                w[o_best, ln] = value
    return o_size


@jit(inline=True)
def _doubling(w, width, o_table, index, f, count, b, o_w, p_count):
    """Coefficients ``0 .. count - 1`` of free set ``f``'s every sign pattern into rows ``o_w + c p_count + q``.

    numpy's doubling: ``w[:, 0] = z[0]``, then for ``j = 1 .. b - 1`` ``w[:, h:2h] = w[:, :h] -
    z[j]`` and ``w[:, :h] += z[j]`` (``h = 2^(j-1)``), ``z[j]`` the table's row ``index[f, j, c]``.
    ``b = 3`` and ``4`` (a 6-generator device's moment and force slices) are written out with the
    same operations on the same operands, so the same bits.
    """
    for c in range(count):
        row = o_w + c * p_count
        if b == 0:
            for ln in range(width):
                w[row, ln] = 0.0
            continue
        s0 = o_table + index[f, 0, c]
        if b == 4:
            s1, s2, s3 = o_table + index[f, 1, c], o_table + index[f, 2, c], o_table + index[f, 3, c]
            for ln in range(width):
                w0 = w[s0, ln]
                z = w[s1, ln]
                w1 = w0 - z
                w0 = w0 + z
                z = w[s2, ln]
                w2 = w0 - z
                w3 = w1 - z
                w0 = w0 + z
                w1 = w1 + z
                z = w[s3, ln]
                w[row + 4, ln] = w0 - z
                w[row + 5, ln] = w1 - z
                w[row + 6, ln] = w2 - z
                w[row + 7, ln] = w3 - z
                w[row, ln] = w0 + z
                w[row + 1, ln] = w1 + z
                w[row + 2, ln] = w2 + z
                w[row + 3, ln] = w3 + z
            continue
        if b == 3:
            s1, s2 = o_table + index[f, 1, c], o_table + index[f, 2, c]
            for ln in range(width):
                w0 = w[s0, ln]
                z = w[s1, ln]
                w1 = w0 - z
                w0 = w0 + z
                z = w[s2, ln]
                w[row + 2, ln] = w0 - z
                w[row + 3, ln] = w1 - z
                w[row, ln] = w0 + z
                w[row + 1, ln] = w1 + z
            continue
        for ln in range(width):
            w[row, ln] = w[s0, ln]
        h = 1
        for j in range(1, b):
            zr = o_table + index[f, j, c]
            for t in range(h):
                for ln in range(width):
                    z = w[zr, ln]
                    w[row + h + t, ln] = w[row + t, ln] - z
                    w[row + t, ln] = w[row + t, ln] + z
            h *= 2


@jit(inline=True)
def _block_minors(w, width, o_g, levels, o_a, o_b):
    """``linalg.minors``' levels over a block's lanes, the entries at rows ``o_g + i n + u``, by turns at
    ``o_a`` and ``o_b``; the last one's offset. Each minor's terms in ``_minors``' order."""
    dst, src = o_a, o_b
    for lv in range(levels.shape[0]):
        kk = lv + 1
        for e in range(levels.shape[1]):
            if levels[lv, e, 0] < 0:
                break
            if kk == 1:
                s = o_g + levels[lv, e, 1]
                for ln in range(width):
                    w[dst + e, ln] = w[s, ln]
                continue
            e1, s1 = o_g + levels[lv, e, 1], src + levels[lv, e, 1 + kk]
            for ln in range(width):
                w[dst + e, ln] = w[e1, ln] * w[s1, ln]
            for t in range(1, kk):
                et, st = o_g + levels[lv, e, 1 + t], src + levels[lv, e, 1 + kk + t]
                if t % 2 == 1:
                    for ln in range(width):
                        w[dst + e, ln] = w[dst + e, ln] - w[et, ln] * w[st, ln]
                else:
                    for ln in range(width):
                        w[dst + e, ln] = w[dst + e, ln] + w[et, ln] * w[st, ln]
        dst, src = src, dst
    return src


@jit(inline=True)
def _minors(gp, levels, work, o_a, o_b):
    """``linalg.minors``' levels at one point into ``work``, by turns at ``o_a`` and ``o_b``; the last one's offset.

    ``kernels.biased_section``'s, point by point; ``_block_minors`` is the same over a block's lanes.
    """
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
    rows = ((r + d) * n + 2 * levels_a.shape[1] + 2 * levels_b.shape[1] + 2 * k + d * out_b.shape[1] + n
            + (r + d) * p_count + 4)                    # _offsets' rows, then the four per point
    return rows * BLOCK


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
