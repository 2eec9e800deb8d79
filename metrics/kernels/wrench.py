"""A wrench set's slice bounded by slabs, compiled point by point: its candidate vertices and their largest norm.

``slab_vertices``: the vertices of a slice bounded by slabs ``lo_k <= a_k . y <= hi_k``
(``metrics.wrench_facets``): every ``d``-subset of slabs (d = 2, 3) and choice of faces, solved
by Cramer's rule, kept where no slab is violated beyond rounding, with the numpy formulas it
replaced operation for operation (so the same bits). It either keeps the largest squared norm
per point (``best``) or, for one point, writes every kept candidate (``points``, the pose
reports' vertices). Keeping only the largest, a candidate whose squared norm is not above the
best so far is not tested against the slabs, and a candidate outside a slab beyond the widest
slack its test can have is rejected without the other slabs' products: neither changes which
candidates are kept. The points run on the calling thread (``nogil``): a map's chunks already
run in parallel threads.

The inside test's slack
-----------------------
A candidate is kept where every product ``a_k . y`` is within its slab up to ``64 eps`` of the
largest (at least 1: the slabs' own rounding, ``wrench_facets``) plus a bound ``E`` on the rounding
of the products themselves, which grows with the subset's conditioning: Cramer's products of a
slab of the subset with its own vertex are exactly its face, but come out ``~ eps |a_k| |c_j| / |det|``
off it. Without ``E`` a vertex of slabs with condition 620 was dropped (80 eps off its own face
against 64 eps; a redundant model with two parallel actuators, 4.01 against the exact 4.45,
``tests/metrics/test_biased_sections.py``). With ``u = eps / 2``, ``C_j`` the cofactor ``c_j`` with its
terms' absolute values summed (``|c_j| <= C_j``), ``w_i = max_k |a_k[i]|``:

* ``c_j`` is off by at most ``gamma_2 C_j``, ``det = a_0 . c_0`` by ``delta <= (d + 2) u sum_i |a_0[i]| C_0i``
  (taken as ``(d + 2) eps ...``), and ``a_k . c_j`` by ``(d + 2) u sum_i w_i C_ji`` (``abs_bound_j``).
* ``a_k . c_j / det`` is then off by ``(d + 2) u abs_bound_j / |det|`` plus
  ``|a_k . c_j| delta / (|det| (|det| - delta))`` plus ``2 u`` of itself (the reciprocal and the
  product), and ``a_k . y = sum_j b_j (...)`` adds ``d u`` of ``sum_j |b_j| |...|``, which ``wide``
  bounds (the second and third terms both through ``wide``).
* So ``E = (sum_j |b_j| abs_bound_j (d + 4) eps / |det| + wide (delta / (|det| - delta) + (d + 2) eps))``
  times ``1 + 1e-12``: each coefficient twice its first-order value (room for the second-order terms), ``1e-12`` for
  the rounding of ``E`` itself. ``|det| <= delta`` gives no vertex (implied by the dependence test).

The determinant's share is bounded through ``wide`` (the products as computed), not through ``C_j``:
``C_j`` can exceed ``|c_j|`` by the subset's cancellation (1e2 in the case below), and ``delta / det``
times ``sum_j |b_j| abs_bound_j / |det|`` let a vertex 1.73 outside another slab through
(13.9 against the exact 5.8, the same test file).

The section of ``metrics.wrench_slices`` (the unbiased slices) is ``section``'s.
"""
from __future__ import annotations

import numpy as np

from .jit import jit

EPS = float(np.finfo(float).eps)


@jit(allocates=True)
def slab_vertices(a, lo, hi, subsets, faces, best, points):
    """Each point's slab-slice vertices: the largest squared norm into ``best``, or the kept vertices.

    Parameters
    ----------
    a : ndarray, shape (k, d, N)
        The slabs' normals on the slice's rows (``wrench_facets._unit_slabs``), d = 2 or 3.
    lo, hi : ndarray, shape (k, N)
        Their bounds: slab ``j`` is ``lo_j <= a_j . y <= hi_j``.
    subsets : ndarray of int, shape (C(k, d), d)
        Every ``d``-subset of slabs (``itertools.combinations`` order).
    faces : ndarray of bool, shape (2^d, d)
        The faces met (``True``: ``hi``), ``itertools.product`` order.
    best : ndarray, shape (N,)
        In and out: the largest ``|y|^2`` of a kept vertex so far (``-1`` none).
    points : ndarray, shape (cap, d)
        With ``cap > 0`` (one point): every kept vertex is written here, ``best`` left alone.

    Returns
    -------
    int
        The vertices written to ``points``.

    Notes
    -----
    ``y = sum_j b_j c_j / det`` with the subset's cofactor vectors ``c_j``, and ``a_k . y`` as
    ``sum_j b_j (a_k . c_j / det)``. A subset whose ``|det|`` is at most ``64 eps`` times the
    product of its normals' lengths meets in no vertex (``wrench_facets._slab_vertex_candidates``
    says why); a vertex is inside where every ``a_k . y`` is within its slab up to ``64 eps`` of
    the largest ``|a_k . y|`` (at least 1) plus the bound on the products' rounding (module doc).
    """
    k, d, n_pts = a.shape
    limit = 64.0 * EPS
    rows = np.empty((d, d))
    cof = np.empty((d, d))              # cof[j, i]: component i of the cofactor vector j
    cols = np.empty((d, d))
    proj = np.empty((d, k))
    y = np.empty(d)
    rhs = np.empty(d)
    dots = np.empty(k)
    ap = np.empty((k, d))               # this point's slabs, contiguous
    lop = np.empty(k)
    hip = np.empty(k)
    widest = np.empty(d)                # max_k |a_k[i]|: bounds every |a_k . c_j|
    proj_bound = np.empty(d)            # bounds |a_k . c_j / det| over k
    abs_bound = np.empty(d)             # sum_i widest_i C_ji: bounds sum_i |a_k[i]| C_ji over k
    growth = 0.0                        # the products' rounding: per unit of sum_j |b_j| abs_bound_j ...
    det_growth = 0.0                    # ... and per unit of ``wide`` (the determinant's, the last operations')
    done = np.zeros(k, np.int64)        # done[kk] == stamp: proj[:, kk] is this subset's
    stamp = 0
    record = points.shape[0] > 0
    count = 0
    for p in range(n_pts):
        first = 0
        for i in range(d):
            widest[i] = 0.0
        for kk in range(k):
            lop[kk], hip[kk] = lo[kk, p], hi[kk, p]
            for i in range(d):
                ap[kk, i] = a[kk, i, p]
                widest[i] = max(widest[i], abs(ap[kk, i]))
        for s in range(subsets.shape[0]):
            for j in range(d):
                for i in range(d):
                    rows[j, i] = ap[subsets[s, j], i]
            if d == 3:
                for j in range(3):
                    u, v = (j + 1) % 3, (j + 2) % 3           # c_0 = r_1 x r_2, c_1 = r_2 x r_0, c_2 = r_0 x r_1
                    cof[j, 0] = rows[u, 1] * rows[v, 2] - rows[u, 2] * rows[v, 1]
                    cof[j, 1] = rows[u, 2] * rows[v, 0] - rows[u, 0] * rows[v, 2]
                    cof[j, 2] = rows[u, 0] * rows[v, 1] - rows[u, 1] * rows[v, 0]
            else:
                cof[0, 0], cof[0, 1] = rows[1, 1], -rows[1, 0]
                cof[1, 0], cof[1, 1] = -rows[0, 1], rows[0, 0]
            det = rows[0, 0] * cof[0, 0]
            for i in range(1, d):
                det += rows[0, i] * cof[0, i]
            if det == 0.0 or det != det:
                continue
            checked = False                 # the dependence test, once a subset
            inv_det = 1.0 / det
            for j in range(d):
                bound_j = 0.0
                for i in range(d):
                    cols[j, i] = cof[j, i] * inv_det
                    bound_j += widest[i] * abs(cof[j, i])
                proj_bound[j] = bound_j * abs(inv_det)
            stamp += 1                      # no slab's products a_k . c_j / det computed yet
            for f in range(faces.shape[0]):
                for j in range(d):
                    rhs[j] = hip[subsets[s, j]] if faces[f, j] else lop[subsets[s, j]]
                for i in range(d):
                    acc = rhs[0] * cols[0, i]
                    for j in range(1, d):
                        acc += rhs[j] * cols[j, i]
                    y[i] = acc
                norm2 = y[0] * y[0]
                for i in range(1, d):
                    norm2 += y[i] * y[i]
                if not record and not norm2 > best[p]:
                    continue
                if not checked:
                    checked = True
                    lengths = 1.0
                    for j in range(d):
                        sq = rows[j, 0] * rows[j, 0]
                        for i in range(1, d):
                            sq += rows[j, i] * rows[j, i]
                        lengths = np.sqrt(sq) if j == 0 else lengths * np.sqrt(sq)
                    if not abs(det) > limit * lengths:
                        break                   # dependent within rounding: no vertex from this subset
                    # The products' rounding (module doc): C_ji = |c_ji| summed term by term.
                    d0 = 0.0
                    for j in range(d):
                        bound_j = 0.0
                        for i in range(d):
                            if d == 3:
                                u, v = (j + 1) % 3, (j + 2) % 3
                                p_, q_ = (i + 1) % 3, (i + 2) % 3
                                c_abs = abs(rows[u, p_] * rows[v, q_]) + abs(rows[u, q_] * rows[v, p_])
                            else:
                                c_abs = abs(cof[j, i])
                            bound_j += widest[i] * c_abs
                            if j == 0:
                                d0 += abs(rows[0, i]) * c_abs
                        abs_bound[j] = bound_j
                    delta = (d + 2) * EPS * d0
                    if not abs(det) > delta:
                        break
                    growth = (d + 4) * EPS * abs(inv_det)
                    det_growth = delta / (abs(det) - delta) + (d + 2) * EPS
                # A slab violated beyond the largest slack the products can have (``wide``: every
                # |a_k . y| as computed is below it) is violated beyond the slack of the test
                # below: reject at once, trying first the slab that rejected the last candidate.
                # The decision is the test's; only the products it never needs are skipped.
                wide = 0.0
                for j in range(d):
                    wide += abs(rhs[j]) * proj_bound[j]
                wide *= 1.0 + 1e-12             # covers the rounding of both sides (~20 eps)
                err = 0.0
                for j in range(d):
                    err += abs(rhs[j]) * abs_bound[j]
                err = (err * growth + wide * det_growth) * (1.0 + 1e-12)
                slack_wide = limit * (1.0 if wide <= 1.0 else wide) + err
                rejected = False
                for t in range(k):
                    kk = first + t
                    if kk >= k:
                        kk -= k
                    _slab_products(ap, cof, inv_det, kk, proj, done, stamp)
                    acc = rhs[0] * proj[0, kk]
                    for j in range(1, d):
                        acc += rhs[j] * proj[j, kk]
                    dots[kk] = acc
                    if acc < lop[kk] - slack_wide or acc > hip[kk] + slack_wide:
                        first = kk
                        rejected = True
                        break
                if rejected:
                    continue
                biggest = 0.0
                for kk in range(k):
                    v = abs(dots[kk])
                    if v > biggest or v != v:
                        biggest = v if biggest == biggest else biggest
                slack = limit * (1.0 if biggest <= 1.0 else biggest) + err
                inside = True
                for kk in range(k):
                    if not (dots[kk] >= lop[kk] - slack and dots[kk] <= hip[kk] + slack):
                        inside = False
                        break
                if not inside:
                    continue
                if record:
                    for i in range(d):
                        points[count, i] = y[i]
                    count += 1
                else:
                    best[p] = norm2
    return count


@jit(inline=True)
def _slab_products(ap, cof, inv_det, kk, proj, done, stamp):
    """``proj[j, kk] = (a_kk . c_j) / det`` for each j, unless already formed for this subset (``stamp``)."""
    if done[kk] == stamp:
        return
    done[kk] = stamp
    d = cof.shape[0]
    for j in range(d):
        acc = ap[kk, 0] * cof[j, 0]
        for i in range(1, d):
            acc += ap[kk, i] * cof[j, i]
        proj[j, kk] = acc * inv_det
