"""The largest norm in a slice of a gravity-biased wrench set, compiled point by point.

``metrics.biased_sections.biased_slice_max_norm``: with a torque bias ``b`` (per unit ``beta = b / t``)
the wrench set is ``{G (s - beta) : s in [-1, 1]^n}`` and its slice on rows ``R`` (the rows ``O``
held at 0) the image under ``G_R`` of the section ``{sigma = s - beta : G_O sigma = 0}``. Its vertices
are the unbiased section's (``kernels.section``) with the box shifted: for a free set ``F`` the
Cramer and Schur coefficients of each fixed ``sigma_j`` are the same minors of ``G`` (the tables of
``wrench_slices._section_plan``), and a sign pattern ``eps`` of the fixed coordinates
(``sigma_j = eps_j - beta_j``) gives the candidate ``o + sum_j eps_j z_j`` with a constant ``o`` per
free set. So a point costs the unbiased section's minors plus ``C(n, r) 2^b`` sums of ``b + 1``
numbers (Twin-Pantograph force slice: 15 free sets x 16 patterns), instead of the slab
enumeration's ``C(k, d) 2^d`` solves (455 x 8). On the Twin's 13,016 finite feasible poses of its
120 x 120 default map under gravity (CPU, one thread, load 3.1): 4.3-4.4 us a point for the force
slice and 3.0-3.3 for the moment slice, against 2.0-2.1 and 1.7-1.8 for the unbiased section and
110-220 for the slab enumeration it replaces.

Each candidate carries a rounding bound; where the bounds cannot tell the answer, the point is
left ``undecided`` (``decided[p] = False``) for the caller's slab path. The rules are
``metrics.biased_sections``' module doc.

The points run on the calling thread (``nogil``): a map's chunks already run in parallel threads.
"""
from __future__ import annotations

import numpy as np

from .jit import jit
from .section import _minors

EPS = float(np.finfo(float).eps)


@jit()
def biased_section_max_norm(g, beta, others, slice_rows, levels_a, levels_b, out_a, out_b, free, index, fixed,
                            fixed_sign, k_eps, tol, out, decided, work):
    """Each point's largest norm of ``G_R (s - beta)`` over the biased section's vertices, where decidable.

    Parameters
    ----------
    g : ndarray, shape (N, m, n)
        The generators ``A diag(t)``, batch-first and C-contiguous; overwritten (the slice rows
        scaled by their largest entry, the rows ``others`` equilibrated: neither moves a vertex).
    beta : ndarray, shape (N, n)
        The torque bias per unit of the rating, ``b / t``.
    others, slice_rows, levels_a, levels_b, out_a, out_b, free, index
        ``wrench_slices._section_kernel_plan``'s tables (``kernels.section.section_max_norm``).
    fixed : ndarray of int, shape (k, b)
        Each free set's fixed columns, ascending (``wrench_slices._section_plan``).
    fixed_sign : ndarray, shape (k, b)
        ``sigma_j`` of each free set's fixed column (``biased_sections._fixed_signs``): the sign the
        plan moved onto the Cramer coefficients of ``s_j``.
    k_eps : float
        ``K eps`` of ``wrench_slices._det_rounding_bound``, for every ``r``-minor.
    tol : float
        ``VERTEX_TOL``: the relative excess over the box a kept candidate may carry.
    out : ndarray, shape (N,)
        The largest norm, in the unit of ``g``'s slice rows, where ``decided``.
    decided : ndarray of bool, shape (N,)
        Where ``out`` holds the answer (module doc of ``metrics.biased_sections``).
    work : ndarray, shape (W,)
        Scratch, at least ``biased_scratch_size`` long.
    """
    n_pts, m, n = g.shape
    flat = g.reshape(n_pts, m * n)
    r = others.shape[0]
    d = slice_rows.shape[0]
    k = free.shape[0]
    b = n - r
    patterns = 1
    for _ in range(b):
        patterns *= 2
    e_a = levels_a.shape[1]
    e_b = levels_b.shape[1]
    wide_n = out_b.shape[1]
    o_prev_a, o_cur_a = 0, e_a
    o_prev_b, o_cur_b = 2 * e_a, 2 * e_a + e_b
    o_table = 2 * e_a + 2 * e_b            # [det; -det; wide] as kernels.section
    o_c = o_table + 2 * k + d * wide_n     # column sums of G_O (n)
    o_bnd = o_c + n                        # each r-minor's rounding bound (k)
    o_off = o_bnd + k                      # the free set's offsets o (r + d)
    o_err = o_off + r + d                  # the Cramer values' rounding bounds E (r)
    o_z = o_err + r                        # the free set's coefficients z_j[c], gathered (r + d, b)
    for p in range(n_pts):
        gp = flat[p]
        out[p] = np.nan
        decided[p] = False
        finite = True
        for e in range(m * n):
            if not np.isfinite(gp[e]):
                finite = False
        for u in range(n):
            if not np.isfinite(beta[p, u]):
                finite = False
        if not finite:
            continue
        size = 0.0
        for i in range(d):
            for u in range(n):
                size = max(size, abs(gp[slice_rows[i] * n + u]))
        if not size > 0.0:
            size = 1.0
        for i in range(d):
            for u in range(n):
                gp[slice_rows[i] * n + u] = gp[slice_rows[i] * n + u] / size
        for i in range(r):
            o = others[i] * n
            big = 0.0
            for u in range(n):
                big = max(big, abs(gp[o + u]))
            if big > 0.0:
                for u in range(n):
                    gp[o + u] = gp[o + u] / big
        last_a = _minors(gp, levels_a, work, o_prev_a, o_cur_a)
        for f in range(k):
            v = work[last_a + out_a[0, f]]
            work[o_table + f] = v
            work[o_table + k + f] = -v
        last_b = _minors(gp, levels_b, work, o_prev_b, o_cur_b)
        for i in range(d):
            for c in range(wide_n):
                work[o_table + 2 * k + i * wide_n + c] = work[last_b + out_b[i, c]]
        for u in range(n):
            s = abs(gp[others[0] * n + u])
            for i in range(1, r):
                s += abs(gp[others[i] * n + u])
            work[o_c + u] = s
        for f in range(k):                  # the r-minor of the columns free[f]: its rounding bound
            prod = work[o_c + free[f, 0]]
            for kk in range(1, r):
                prod = prod * work[o_c + free[f, kk]]
            work[o_bnd + f] = k_eps * prod
        best = -1.0                         # largest |image|^2 of a kept candidate
        best_sure = -1.0                    # ... of one within ``tol`` of the box
        regular = False
        doubtful = False
        for f in range(k):
            det = work[o_table + f]
            bound_det = work[o_bnd + f]
            if not abs(det) > bound_det:
                continue                    # singular within rounding (nan too): no candidate
            regular = True
            for c in range(r + d):          # gathered once: every pattern reads them
                for j in range(b):
                    work[o_z + c * b + j] = work[o_table + index[f, j, c]]
            _offsets(work, o_table, o_bnd, o_off, o_err, index, fixed, fixed_sign, free, beta, p, f, det, bound_det,
                     b, r, d, k)
            reach = abs(det) + bound_det    # |true det| at most this
            low = abs(det) - bound_det      # and at least this
            for q in range(patterns):
                inside = True
                excess = 0.0
                for c in range(r):
                    v = _candidate(work, o_z, o_off, c, q, b)
                    if not abs(v) <= reach + work[o_err + c]:
                        inside = False
                        break
                    excess = max(excess, abs(v) + work[o_err + c])
                if not inside:
                    continue
                excess = excess / low - 1.0
                value = 0.0                 # |image|^2: each coordinate over det first, so a
                for c in range(r, r + d):   # det^2 that underflows cannot make it inf or nan
                    v = _candidate(work, o_z, o_off, c, q, b) / det
                    value += v * v
                if not value == value:
                    doubtful = True
                    break
                best = max(best, value)
                if excess <= tol:
                    best_sure = max(best_sure, value)
            if doubtful:
                break
        if doubtful or not regular or best < 0.0 or best > best_sure:
            continue
        out[p] = size * np.sqrt(best)
        decided[p] = True


@jit(inline=True)
def _offsets(work, o_table, o_bnd, o_off, o_err, index, fixed, fixed_sign, free, beta, p, f, det, bound_det, b, r, d,
             k):
    """Free set ``f``'s constant ``o`` (r + d) and the Cramer values' rounding bounds ``E`` (r).

    ``o_c = det beta_F[c] - sum_j sigma_j beta_j z_j[c]`` (``c < r``; without the first term for the
    image rows). A candidate's Cramer value ``o_c + sum_j eps_j z_j[c]`` is a sum of the minors
    ``z_j[c]`` and ``det`` with weights at most ``1 + |beta_j|`` and ``|beta_F[c]|``: its error from
    the minors' rounding is at most ``sum_j (1 + |beta_j|) bnd_j + |beta_F[c]| bnd_det``, and from
    the ``2 b + 2`` products and sums that form it at most ``(2 b + 2) u`` of the sum of their
    magnitudes (``S``); ``(2 b + 4) eps S`` covers that with room for the bound's own rounding.
    """
    for c in range(r + d):
        acc = 0.0
        mag = 0.0
        err = 0.0
        if c < r:
            acc = det * beta[p, free[f, c]]
            mag = abs(acc)
            err = abs(beta[p, free[f, c]]) * bound_det
        for j in range(b):
            row = index[f, j, c]
            z = work[o_table + row]
            bj = beta[p, fixed[f, j]]
            acc -= fixed_sign[f, j] * bj * z
            mag += (1.0 + abs(bj)) * abs(z)
            if c < r:
                err += (1.0 + abs(bj)) * work[o_bnd + (row % k)]
        work[o_off + c] = acc
        if c < r:
            work[o_err + c] = err + (2 * b + 4) * EPS * mag


@jit(inline=True)
def _candidate(work, o_z, o_off, c, q, b):
    """Coefficient ``c`` of pattern ``q`` (bit ``j`` set: ``eps_j = -1``): ``o_c + sum_j eps_j z_j[c]``, in order."""
    v = work[o_off + c]
    for j in range(b):
        z = work[o_z + c * b + j]
        v = v - z if (q >> j) & 1 else v + z
    return v


def biased_scratch_size(levels_a: np.ndarray, levels_b: np.ndarray, out_b: np.ndarray, k: int, d: int, n: int) -> int:
    """Length of ``biased_section_max_norm``'s ``work`` (``kernels.section``'s layout plus bounds and offsets).

    Returns
    -------
    int
    """
    r = levels_a.shape[0]
    return 2 * levels_a.shape[1] + 2 * levels_b.shape[1] + 2 * k + d * out_b.shape[1] + n + k + 2 * r + d + (
        (d + r) * (n - r))
