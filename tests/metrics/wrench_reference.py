"""The numpy slab-slice enumeration before it was compiled (``metrics.kernels.wrench``), kept verbatim
as the reference of ``test_wrench_kernels.py``: ``_slab_vertex_candidates``,
``slab_slice_vertex_max_norm`` and ``slab_slice_vertices`` over it, and ``slab_slice_max_norm``
(LAPACK solves, no dependence test) as they were at commit 2168915, with one change made in both since:
the inside test's slack covers the rounding of the slab products (``kernels.wrench``'s module doc),
which grows with the subset's conditioning. Not collected by pytest (no ``test_`` prefix).
"""
from __future__ import annotations

import itertools

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray
from metrics.linalg import as_jacobian
from metrics.wrench_facets import _unit_slabs

EPS = np.finfo(float).eps


def slab_slice_max_norm(jac: ArrayLike, *, torque_limits: ArrayLike, rows) -> FloatArray:
    """wrench_facets.slab_slice_max_norm before: LAPACK solves, a subset used wherever det != 0."""
    jac = as_jacobian(jac)
    t = np.asarray(torque_limits, float)
    rows = list(rows)
    d = len(rows)
    if d not in (2, 3):
        raise ValueError(f"rows must name 2 or 3 task rows, got {rows}")
    normals = np.swapaxes(jac[..., rows, :], -1, -2)                  # (..., n, d)
    n = normals.shape[-2]
    finite = np.all(np.isfinite(normals), axis=(-2, -1))
    # Slab u: |normals[u] . y| <= t_u. Divide each by t_u (|a_u . y| <= 1) and by a power of two
    # of the largest entry: products of d entries then neither overflow nor underflow.
    a = np.where(finite[..., None, None], normals / t[:, None], 0.0)
    big = np.max(np.abs(a), axis=(-2, -1), keepdims=True)
    scale = np.where(big > 0, np.ldexp(1.0, np.frexp(np.where(big > 0, big, 1.0))[1]), 1.0)
    a = a / scale
    best = np.full(a.shape[:-2], -1.0)
    signs = np.array(list(itertools.product((1.0, -1.0), repeat=d)))           # (2^d, d)
    for subset in itertools.combinations(range(n), d):
        sub = a[..., list(subset), :]                                           # (..., d, d)
        det = np.linalg.det(sub)
        ok = det != 0
        safe = np.where(ok[..., None, None], sub, np.eye(d))
        y = np.linalg.solve(safe[..., None, :, :], np.broadcast_to(signs, sub.shape[:-2] + signs.shape)[..., None])
        y = y[..., 0]                                                           # (..., 2^d, d)
        dots = np.abs(np.einsum("...ud,...kd->...ku", a, y))                    # (..., 2^d, n)
        inside = np.max(dots, axis=-1) <= 1.0 + 64 * EPS * np.maximum(1.0, np.max(dots, axis=-1))
        norm2 = np.where(inside & ok[..., None], np.sum(y * y, axis=-1), -1.0)
        best = np.maximum(best, np.max(norm2, axis=-1))
    # Bounded iff the normals left span d dimensions (then some d-subset is regular).
    rank = np.linalg.matrix_rank(np.where(finite[..., None, None], a, 0.0))
    out = np.where(rank < d, np.inf, np.sqrt(np.maximum(best, 0.0)) / scale[..., 0, 0])
    return np.where(finite, out, np.nan)


def slab_slice_vertex_max_norm(normals: ArrayLike, lower: ArrayLike, upper: ArrayLike, *, rows) -> FloatArray:
    """wrench_facets.slab_slice_vertex_max_norm over the numpy enumeration below."""
    a, lo_n, hi_n, scale, finite, part, batch = _unit_slabs(normals, lower, upper, rows)
    d = len(list(rows))
    best = np.full(a.shape[-1], -1.0)
    for y, inside in _slab_vertex_candidates(a, lo_n, hi_n, d):
        np.fmax(best, np.where(inside, np.sum(y * y, axis=0), -1.0), out=best)
    rank = np.linalg.matrix_rank(np.where(finite[:, None, None], part, 0.0))
    out = np.where(rank < d, np.inf, np.sqrt(np.maximum(best, 0.0)) / scale)
    return np.where(finite, out, np.nan).reshape(batch)


def slab_slice_vertices(normals: ArrayLike, lower: ArrayLike, upper: ArrayLike, *, rows) -> FloatArray:
    """``wrench_facets.slab_slice_vertices`` over the numpy enumeration below."""
    nu = np.asarray(normals, float)
    if nu.ndim != 2:
        raise ValueError(f"normals must be one pose's (S, m), got shape {nu.shape}")
    d = len(list(rows))
    a, lo_n, hi_n, scale, finite, part, _ = _unit_slabs(nu, lower, upper, rows)
    if not finite[0] or np.linalg.matrix_rank(part[0]) < d:
        return np.zeros((0, d))
    points = [y[:, 0] for y, inside in _slab_vertex_candidates(a, lo_n, hi_n, d) if inside[0]]
    if not points:
        return np.zeros((0, d))
    pts = np.array(points) / scale[0]
    size = np.max(np.abs(pts))
    _, keep = np.unique(np.round(pts / (size if size > 0 else 1.0) * 1e9), axis=0, return_index=True)
    pts = pts[np.sort(keep)]
    if len(pts) > d and np.linalg.matrix_rank(pts[1:] - pts[0]) == d:
        from scipy.spatial import ConvexHull
        pts = pts[np.sort(ConvexHull(pts).vertices)]
    return pts[np.lexsort(pts.T[::-1])]


def _slab_vertex_candidates(a: FloatArray, lo_n: FloatArray, hi_n: FloatArray, d: int):
    """For every d-subset of slabs and choice of face: the point ``y`` (d, N) and whether it is in every slab (N,).

    ``y = sum_j b_j c_j / det`` with the subset's cofactor vectors ``c_j``; the slab products
    ``a_k . y`` likewise from ``a_k . c_j``. In a slab beyond rounding: ``64 eps`` of the largest
    product. A subset whose normals are dependent within rounding (``|det|`` at most ``64 eps``
    times the product of their lengths: faces parallel to 1e-14 rad) meets in no vertex: its
    ``det`` is rounding noise, and the point it gives lies ~1/noise away (the Twin-Pantograph's
    slabs under gravity at (110, 0, 60) mm: two antiparallel slabs and a third whose zero
    entry came out 1e-18, ``det`` 1e-35, a "vertex" 1.2e18 away that the products, as noisy,
    let through: an anisotropic force of 2^61 N where its neighbours have 6 N).
    """
    k = a.shape[0]
    widest = np.max(np.abs(a), axis=0)                                      # (d, N)
    faces = np.array(list(itertools.product((0, 1), repeat=d)), bool)      # (2^d, d): upper face where set
    for subset in itertools.combinations(range(k), d):
        rows_s = [a[u] for u in subset]                                     # d of (d, N)
        if d == 3:
            cof = [_cross_entries(rows_s[1], rows_s[2]), _cross_entries(rows_s[2], rows_s[0]),
                   _cross_entries(rows_s[0], rows_s[1])]
        else:
            (p, q), (r, t) = rows_s
            cof = [np.stack([t, -r]), np.stack([-q, p])]
        det = sum(rows_s[0][i] * cof[0][i] for i in range(d))
        lengths = np.prod([np.sqrt(sum(row[i] * row[i] for i in range(d))) for row in rows_s], axis=0)
        if d == 3:
            c_abs = [_abs_cross_entries(rows_s[1], rows_s[2]), _abs_cross_entries(rows_s[2], rows_s[0]),
                     _abs_cross_entries(rows_s[0], rows_s[1])]
        else:
            c_abs = [np.abs(c) for c in cof]
        abs_bound = [sum(widest[i] * c[i] for i in range(d)) for c in c_abs]
        delta = (d + 2) * EPS * sum(np.abs(rows_s[0][i]) * c_abs[0][i] for i in range(d))
        ok = (np.abs(det) > 64 * EPS * lengths) & (np.abs(det) > delta)
        inv_det = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        growth = (d + 4) * EPS * np.abs(inv_det)
        det_growth = np.where(ok, delta / np.where(ok, np.abs(det) - delta, 1.0) + (d + 2) * EPS, 0.0)
        proj_bound = [sum(widest[i] * np.abs(c[i]) for i in range(d)) * np.abs(inv_det) for c in cof]
        proj = [np.einsum("kin,in->kn", a, c) * inv_det for c in cof]         # a_k . c_j / det, (k, N)
        cols = [c * inv_det for c in cof]
        for face in faces:
            rhs = [np.where(face[j], hi_n[subset[j]], lo_n[subset[j]]) for j in range(d)]
            y = sum(rhs[j] * cols[j] for j in range(d))                       # (d, N)
            dots = sum(rhs[j] * proj[j] for j in range(d))                    # (k, N)
            wide = sum(np.abs(rhs[j]) * proj_bound[j] for j in range(d)) * (1.0 + 1e-12)
            err = (sum(np.abs(rhs[j]) * abs_bound[j] for j in range(d)) * growth + wide * det_growth) * (1.0 + 1e-12)
            slack = 64 * EPS * np.maximum(1.0, np.max(np.abs(dots), axis=0)) + err
            inside = np.all((dots >= lo_n - slack) & (dots <= hi_n + slack), axis=0) & ok
            yield y, inside


def _cross_entries(u: FloatArray, v: FloatArray) -> FloatArray:
    """``u x v`` of entry arrays (3, N)."""
    return np.stack([u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]])


def _abs_cross_entries(u: FloatArray, v: FloatArray) -> FloatArray:
    """``|u_1 v_2| + |u_2 v_1|``, ...: the absolute terms of ``u x v``'s entries (3, N)."""
    return np.stack([np.abs(u[1] * v[2]) + np.abs(u[2] * v[1]), np.abs(u[2] * v[0]) + np.abs(u[0] * v[2]),
                     np.abs(u[0] * v[1]) + np.abs(u[1] * v[0])])
