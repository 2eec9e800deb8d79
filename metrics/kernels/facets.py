"""A zonotope's slabs and a slice's inscribed radius, compiled point by point (``metrics.wrench_facets``).

``packed_facets_points`` gives ``wrench_facets.packed_facets``'s numbers with its numpy
operations in their order (``_packed_facets_reference``, kept as the tests' reference): each
column scaled by its length ``big sqrt(sum_i (a_i / big)^2)``, the cofactor normals by the same
memoised Laplace expansion along the first row (``facet_plan`` lists the memo's minors in the
order the recursion fills them), the offsets ``sum_u |nu . a_u| length_u`` summed over ``u`` in
order. No transcendental function and no reordered sum: the same bits.

``acceleration_radius_points`` is the acceleration set's (``quantity_nodes.acceleration_slabs``):
the same radius over the normals ``nu_k^T Lambda``, whose force rows it forms per slab as numpy's
``matmul`` does (``fma``) instead of the (N, k, m) product: 0.2 us a point against 0.5-1.3 us
(Twin-Pantograph, CPU, one thread, load 3-4).

``inscribed_radius_points`` is ``wrench_facets._inscribed_radius``'s common case:
``min_k h_k / sqrt(sum_rows nu_k[i]^2)``. A point with a normal whose plain sum of squares is out
of ``(2^-450, 2^500)`` (under- or overflow possible, or 0, inf, nan) is flagged and left to the
numpy function, whose rescaled sum numpy orders its own way: those points then have its values
exactly.

What differs is the layout: numpy went through blocks of 8192 points with a temporary array per
minor (200 for the Twin-Pantograph's 5 x 6); here a block of ``BLOCK`` points' minors, normals and
offsets stay in a scratch of about 160 kB, each row's products over the block in one vectorised
loop. Twin-Pantograph generators (5 x 6), CPU per point, one thread, load 2.4: packed facets
0.68 us against numpy's 1.3-1.5; the inscribed radius of one slice 0.07 us against 0.28-0.30
(``wrench_facets.packed_facets`` against ``_packed_facets_reference`` on 20,000 points).
The points run on the calling thread (``nogil``): a map's chunks already run in parallel threads.
"""
from __future__ import annotations

import itertools

import numpy as np
from numba.core import types
from numba.extending import intrinsic

from .jit import jit

#: Points per block in ``packed_facets_points``: each minor's terms run over a block's points
#: in an inner loop the compiler vectorises. Per point the operations are the same whatever the block.
#: On the Twin-Pantograph's 5 x 6 (200 minors, 630 products) the minors took 0.87 us a point one
#: point at a time (table look-ups in series), 0.68 / 0.38 / 0.28 / 0.33 us in blocks of 4 / 8 / 16 / 32.
#: The whole kernel on the Twin-Pantograph stats map's 101,344 generators (CPU, one thread, best of
#: 7, load 2.5-3.9): 0.076 s in blocks of 16, 0.052-0.065 of 64, 0.059 of 128. The rows all lie in
#: one scratch, so a row's loop is vectorised behind a run-time test that its rows do not overlap:
#: the longer the loop, the less that test costs (the scratch, about 160 kB, stays in L2).
BLOCK = 64


@jit()
def packed_facets_points(g, ent, child, count, top, out, work):
    """Each point's slabs ``[nu_S, h_S]`` of ``{G s : |s| <= 1}`` into ``out`` (``packed_facets``' layout).

    Parameters
    ----------
    g : ndarray, shape (N, m, n)
        The generators, batch-first, C-contiguous. A point with a non-finite entry gets ``nan``.
    ent, child : ndarray of int, shape (M, m - 1)
        ``facet_plan``: minor ``j``'s term ``t`` is ``work[ent[j, t]] * work[child[j, t]]``
        (an entry of the unit columns times a smaller minor or an entry).
    count : ndarray of int, shape (M,)
        Minor ``j``'s number of terms.
    top : ndarray of int, shape (m, k)
        Where in ``work`` cofactor ``(i, S)`` lies, before its sign ``(-1)^i``; -1: ``m = 1`` (1).
    out : ndarray, shape (N, k, m + 1)
        Normals then offset.
    work : ndarray, shape (W, BLOCK)
        Scratch, ``m n + M + n + 1 + k (m + 1)`` rows (``facet_plan``): the unit entries
        (``i n + u``), the minors, the column lengths, a dot product, the normals (``s m + i``),
        the offsets; one column per point of a block.
    """
    n_pts, m, n = g.shape
    k = top.shape[1]
    n_minors = ent.shape[0]
    width = BLOCK                       # a constant: the inner loops unrolled and vectorised
    flat = g.reshape(n_pts, m * n)
    res = out.reshape(n_pts, k * (m + 1))
    o_len = m * n + n_minors
    o_dot = o_len + n
    o_nu = o_dot + 1
    o_h = o_nu + k * m
    for lo in range(0, n_pts, width):
        nb = min(width, n_pts - lo)
        # Unit columns: minors within [-1, 1] whatever the scale of G (1e-300 ... 1e300); a
        # non-finite point's entries are 0 (as numpy's ``where``), its results nan below.
        for b in range(nb):
            gp = flat[lo + b]
            finite = True
            for e in range(m * n):
                if not np.isfinite(gp[e]):
                    finite = False
            for u in range(n):
                big = 0.0
                for i in range(m):
                    v = gp[i * n + u] if finite else 0.0
                    big = max(big, abs(v))
                safe = big if big > 0 else 1.0
                acc = 0.0
                for i in range(m):
                    v = (gp[i * n + u] if finite else 0.0) / safe
                    acc = v * v if i == 0 else acc + v * v      # numpy's sum over axis 0: in order
                length = big * np.sqrt(acc)
                work[o_len + u, b] = length
                div = length if length > 0 else 1.0
                for i in range(m):
                    work[i * n + u, b] = (gp[i * n + u] if finite else 0.0) / div
        for b in range(nb, width):              # a short last block: zeros, never read back
            for e in range(o_len + n):
                work[e, b] = 0.0
        # Indexed in place, no row views: a view costs as much as a block's products.
        for j in range(n_minors):
            d, e0, c0 = m * n + j, ent[j, 0], child[j, 0]
            for b in range(width):
                work[d, b] = work[e0, b] * work[c0, b]
            for t in range(1, count[j]):
                e1, c1 = ent[j, t], child[j, t]
                if t % 2 == 1:
                    for b in range(width):
                        work[d, b] = work[d, b] - work[e1, b] * work[c1, b]
                else:
                    for b in range(width):
                        work[d, b] = work[d, b] + work[e1, b] * work[c1, b]
        for s in range(k):
            for i in range(m):
                d, src = o_nu + s * m + i, top[i, s]
                for b in range(width):
                    v = 1.0 if src < 0 else work[src, b]
                    work[d, b] = -v if i % 2 == 1 else v
            d = o_h + s
            for b in range(width):
                work[d, b] = 0.0
            for u in range(n):                  # h_S += |nu_S . a_u| |g_u|, u in order
                nu0 = o_nu + s * m
                for b in range(width):
                    work[o_dot, b] = work[nu0, b] * work[u, b]
                for i in range(1, m):
                    for b in range(width):
                        work[o_dot, b] = work[o_dot, b] + work[nu0 + i, b] * work[i * n + u, b]
                for b in range(width):
                    work[d, b] = work[d, b] + abs(work[o_dot, b]) * work[o_len + u, b]
        for b in range(nb):
            for s in range(k):
                for i in range(m):
                    res[lo + b, s * (m + 1) + i] = work[o_nu + s * m + i, b]
                res[lo + b, s * (m + 1) + m] = work[o_h + s, b]
        for b in range(nb):
            gp = flat[lo + b]
            for e in range(m * n):
                if not np.isfinite(gp[e]):
                    for c in range(k * (m + 1)):
                        res[lo + b, c] = np.nan
                    break


@jit()
def inscribed_radius_points(nu, h, rows, biased, out, redo):
    """``min_k h_k / |nu_k[rows]|`` per point into ``out``; ``redo[p]`` set where numpy must take the point.

    Parameters
    ----------
    nu : ndarray, shape (N, k, m)
        Slab normals.
    h : ndarray, shape (N, k)
        Offsets (``h - |s|`` when ``biased``, possibly negative).
    rows : ndarray of int, shape (d,)
        The slice's rows.
    biased : bool
        Clamp the radius at 0 and give a zero normal ``-inf`` where its ``h < 0``.
    out : ndarray, shape (N,)
        The radius (left unset where ``redo``).
    redo : ndarray of bool, shape (N,)
        A normal's sum of squares out of ``(2^-450, 2^500)``: ``_inscribed_radius`` decides.
    """
    n_pts, k, m = nu.shape
    d = rows.shape[0]
    lo = 2.0 ** -450
    hi = 2.0 ** 500
    for p in range(n_pts):
        redo[p] = False
        radius = np.inf
        lost = False                            # np.min: a nan ratio makes the minimum nan
        for s in range(k):
            v = nu[p, s, rows[0]]
            den = v * v
            for i in range(1, d):
                v = nu[p, s, rows[i]]
                den += v * v
            den = np.sqrt(den)
            if not (den > lo and den < hi):
                redo[p] = True
                break
            ratio = h[p, s] / den
            if ratio != ratio:
                lost = True
            elif ratio < radius:
                radius = ratio
        if redo[p]:
            continue
        if lost:
            radius = np.nan
        elif biased and not radius > 0:
            radius = 0.0
        # Every den > 2^-450 here: some normal is non-zero, the point is not degenerate.
        out[p] = radius


def facet_plan(m: int, n: int):
    """``packed_facets_points``' tables: ``_cofactor_normals``' memoised minors in the recursion's order.

    Parameters
    ----------
    m, n : int
        Rows and generators, ``n >= m``.

    Returns
    -------
    ent, child : ndarray of int64, shape (M, max(m - 1, 1))
    count : ndarray of int64, shape (M,)
    top : ndarray of int64, shape (m, C(n, m - 1))
    scratch : int
        ``work``'s rows.
    """
    base = m * n
    ent: list[list[int]] = []
    child: list[list[int]] = []
    memo: dict[tuple, int] = {}

    def minor(rows: tuple[int, ...], cols: tuple[int, ...]) -> int:
        if len(rows) == 1:
            return rows[0] * n + cols[0]            # an entry of the unit columns
        key = (rows, cols)
        if key not in memo:
            r0, rest = rows[0], rows[1:]
            es, cs = [r0 * n + cols[0]], [minor(rest, cols[1:])]
            for j in range(1, len(cols)):
                es.append(r0 * n + cols[j])
                cs.append(minor(rest, cols[:j] + cols[j + 1:]))
            memo[key] = base + len(ent)
            ent.append(es)
            child.append(cs)
        return memo[key]

    subsets = list(itertools.combinations(range(n), m - 1))
    top = np.full((m, len(subsets)), -1, np.int64)
    if m > 1:
        for i in range(m):
            rows = tuple(r for r in range(m) if r != i)
            for s, subset in enumerate(subsets):
                top[i, s] = minor(rows, subset)
    width = max(m - 1, 1)
    ent_a = np.zeros((max(len(ent), 1), width), np.int64)
    child_a = np.zeros_like(ent_a)
    count = np.zeros(len(ent_a), np.int64)
    for j, (es, cs) in enumerate(zip(ent, child)):
        ent_a[j, :len(es)], child_a[j, :len(cs)], count[j] = es, cs, len(es)
    return ent_a[:len(ent)], child_a[:len(ent)], count[:len(ent)], top, base + len(ent) + n + 1 + len(subsets) * (m + 1)


@intrinsic
def fma(typingctx, x, y, z):
    """``x y + z`` rounded once (LLVM's ``llvm.fma.f64``): a dot product summed as numpy's ``matmul`` sums it.

    numpy's ``matmul`` of float64 stacks calls BLAS once per matrix, and OpenBLAS's kernels for this
    machine (Haswell's, FMA) form each entry as ``acc = fma(a_k, b_k, acc)`` from 0 over ``k`` in order:
    a loop of ``fma`` gives their bits. Another BLAS may order its sums otherwise; the compiled
    steps built on this are checked against ``matmul`` with the dot product's rounding bound, and
    for bit identity where they match (``tests/metrics/test_kernel_twin_nodes.py``).
    """
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        return builder.fma(*args)
    return sig, codegen


@jit()
def acceleration_radius_points(nu, h, lam, rows, out, redo):
    """``min_k h_k / |(nu_k^T Lambda)[rows]|`` per point into ``out``; ``redo[p]`` where numpy must take it.

    ``inscribed_radius_points`` of the acceleration set's normals ``nu_k^T Lambda``
    (``dynamics.acceleration_facets``, numpy's ``matmul``), whose entries on ``rows`` are formed here
    in ``matmul``'s order (``fma``, ``k`` from 0) as they are needed: no (N, k, m) product.

    Parameters
    ----------
    nu : ndarray, shape (N, k, m)
        The wrench set's slab normals (a view of the packed slabs is fine).
    h : ndarray, shape (N, k)
        Offsets (the set about 0: no torque bias).
    lam : ndarray, shape (N, m, m)
        ``Lambda``.
    rows : ndarray of int, shape (d,)
        The slice's rows, 1 <= d <= 3.
    out : ndarray, shape (N,)
        The radius (left unset where ``redo``).
    redo : ndarray of bool, shape (N,)
        ``Lambda`` not finite (a singular pose's marked mass), or a normal's sum of squares out of
        ``(2^-450, 2^500)``: the numpy path decides (``_inscribed_radius``).
    """
    n_pts, k, m = nu.shape
    d = rows.shape[0]
    lo = 2.0 ** -450
    hi = 2.0 ** 500
    for p in range(n_pts):
        redo[p] = False
        for i in range(m):
            for j in range(m):
                if not np.isfinite(lam[p, i, j]):
                    redo[p] = True
        if redo[p]:
            continue
        radius = np.inf
        lost = False                            # np.min: a nan ratio makes the minimum nan
        for s in range(k):
            # The rows' dot products side by side (independent chains), each in matmul's order.
            v0 = 0.0
            v1 = 0.0
            v2 = 0.0
            for i in range(m):
                a = nu[p, s, i]
                v0 = fma(a, lam[p, i, rows[0]], v0)
                if d > 1:
                    v1 = fma(a, lam[p, i, rows[1]], v1)
                if d > 2:
                    v2 = fma(a, lam[p, i, rows[2]], v2)
            den = v0 * v0                       # inscribed_radius_points' sum, in rows' order
            if d > 1:
                den += v1 * v1
            if d > 2:
                den += v2 * v2
            den = np.sqrt(den)
            if not (den > lo and den < hi):
                redo[p] = True
                break
            ratio = h[p, s] / den
            if ratio != ratio:
                lost = True
            elif ratio < radius:
                radius = ratio
        if redo[p]:
            continue
        out[p] = np.nan if lost else radius
