"""Inscribed radius of a wrench set's slices, from the slabs (facet pairs) that bound the set.

The wrench set ``W = {G s : |s_u| <= 1}`` (``G = A diag(t)``) and its slices, forces at zero
moment and moments at zero force, are defined in ``metrics.wrenches``, which finds a slice's
largest norm from its vertices; this module gives a slice's inscribed radius from the facets.

How it is computed (exact up to rounding, batched)
--------------------------------------------------
``W`` (full-dimensional, rank ``G = m``) is the intersection of the slabs ``|nu_S . w| <= h_S``,
one per (m-1)-subset ``S`` of generators: ``nu_S`` is their generalised cross product
(cofactors) and ``h_S = sum_u |nu_S . g_u|`` the support value.
The slice on rows ``R`` is then ``{y : |nu_S[R] . y| <= h_S}``, and a ball about 0 of radius
``r`` lies in it iff ``r |nu_S[R]| <= h_S`` for every ``S``, so the radius is
``min_S h_S / |nu_S[R]|`` (a slab with ``nu_S[R] = 0`` bounds nothing). For square ``J``
(``tau = J^T w``) the slabs are ``|J[:, u] . w| <= t_u`` and the radius is
``min_u t_u / |J[R, u]|`` (``slice_facet_distances``). Robustness: for *any* vector ``nu``
the slab ``|nu . w| <= sum_u |nu . g_u|`` contains ``W``, so a normal spoiled by rounding
(a nearly degenerate subset) still gives a valid bound and never a radius below the true one.

Checked against linear programmes (scipy.optimize.linprog) in ``tests/metrics/test_wrenches.py``.
"""
from __future__ import annotations

import functools
import itertools
import math

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

from . import linalg
from .linalg import as_jacobian

EPS = np.finfo(float).eps


# -- square J: facet distances of a slice ----------------------------------------------------
def slice_facet_distances(jac: ArrayLike, *, torque_limits: ArrayLike, rows) -> FloatArray:
    """``t_u / |J[rows, u]|`` (..., n): distance from 0 to each facet pair of the slice on ``rows``.

    For square ``J`` with ``tau = J^T w`` the slice ``{y : w[rows] = y, w[others] = 0 in W}``
    is ``{y : |J[rows, u] . y| <= t_u}``. A zero column part gives ``inf`` (no bound);
    a non-finite column 0 (as ``isotropy.facet_distances``: J unbounded is a direct singularity).

    Parameters
    ----------
    jac : array_like, shape (..., m, m)
        Square Jacobians (``tau = J^T w``).
    torque_limits : array_like, shape (..., m)
        Actuator limits ``t`` (N m or N).
    rows : sequence of int
        The slice's task rows (``wrenches.force_rows`` or ``wrenches.moment_rows``).

    Returns
    -------
    ndarray, shape (..., m)
        In the unit of the wrench rows ``rows`` (N or N m).

    Examples
    --------
    >>> slice_facet_distances(np.diag([2.0, 4.0]), torque_limits=[1.0, 1.0], rows=[0]).tolist()
    [0.5, inf]
    """
    jac = as_jacobian(jac)
    t = np.asarray(torque_limits, float)
    part = jac[..., list(rows), :]
    with np.errstate(invalid="ignore", over="ignore"):
        big = np.max(np.abs(part), axis=-2)
        safe = np.where((big > 0) & np.isfinite(big), big, 1.0)
        norms = big * np.sqrt(np.sum((part / safe[..., None, :]) ** 2, axis=-2))
    norms = np.where(np.isnan(norms), np.inf, norms)
    with np.errstate(divide="ignore"):
        return t / norms


def slab_slice_max_norm(jac: ArrayLike, *, torque_limits: ArrayLike, rows) -> FloatArray:
    """Largest norm of the slice ``{y : |J[rows, u] . y| <= t_u for every u}`` of a square J (...).

    The slice of ``metrics.wrench_slices.slice_max_norm`` written with the slabs of ``tau = J^T w``
    instead of the generators ``J^-T diag(t)``, so it holds where ``J`` has a zero column (an
    actuator at an inverse singularity, ``kinematics.base.singular_limit``): that slab bounds
    nothing and drops out, and ``J^-T`` need not exist. A vertex of the slice (``d = len(rows)``
    coordinates) is where ``d`` slab faces meet: every ``d``-subset of actuators and sign
    pattern is solved (LAPACK on ``J[rows, subset]^T / scale``, a power of two) and kept where no
    slab is violated beyond rounding (``64 eps`` of the largest ``|J[rows, u] . y|``). A subset
    whose normals are dependent within rounding (``|det|`` at most ``64 eps`` times the product of
    their lengths) gives no vertex, as in ``slab_slice_vertex_max_norm``. In numpy, not through
    the compiled slab kernel: it runs at the few poses of a square map with a zero column of J
    (two of the Inoue platform's default map), where numba's start-up (0.4 s CPU) would be most
    of the map's time.

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
        Jacobians (``tau = J^T w``), finite.
    torque_limits : array_like, shape (n,)
        Actuator limits ``t`` (N m or N).
    rows : sequence of int
        The slice's task rows (2 or 3 of them: ``wrenches.force_rows``, ``wrenches.moment_rows``).

    Returns
    -------
    ndarray, shape (...)
        In the unit of the rows ``rows``; ``inf`` where the remaining slabs leave the slice
        unbounded (their normals span fewer than ``d`` dimensions), ``nan`` where ``J`` is not finite.

    Examples
    --------
    >>> round(float(slab_slice_max_norm(np.diag([1.0, 0.5, 0.0]), torque_limits=[1.0, 1.0, 1.0], rows=[0, 1])) ** 2, 12)
    5.0
    """
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
        lengths = np.prod(np.sqrt(np.sum(sub * sub, axis=-1)), axis=-1)
        ok = np.abs(det) > 64 * EPS * lengths               # dependent within rounding: no vertex
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


# -- zonotopes: facets -----------------------------------------------------------------------
#: Points per block in ``_packed_facets_reference``: the memoised minors of a block (about 130 arrays for the
#: Twin-Pantograph's 5 x 6) stay within a few megabytes instead of streaming the whole batch.
FACET_BLOCK = 8192


def _cofactor_normals(a: FloatArray, out: FloatArray) -> FloatArray:
    """``nu_S[i] = (-1)^i det a[rows != i, S]`` into ``out`` (m, k, N) for each (m-1)-subset ``S``.

    ``a`` holds entry arrays (m, n, N). Laplace expansion along the first row, each sub-minor
    computed once (memoised) and every product written into a buffer: the same operations in
    the same order as a plain recursive expansion, so the same numbers, without a temporary
    per term. ``S`` in ``itertools.combinations`` order.
    """
    m, n = a.shape[:2]
    if m == 1:
        out[...] = 1.0
        return out
    memo: dict[tuple, FloatArray] = {}
    term = np.empty(a.shape[2:])

    def minor(rows: tuple[int, ...], cols: tuple[int, ...], dest: FloatArray | None = None) -> FloatArray:
        if len(rows) == 1:
            return a[rows[0], cols[0]]
        key = (rows, cols)
        if key not in memo:
            r0, rest = rows[0], rows[1:]
            acc = np.multiply(a[r0, cols[0]], minor(rest, cols[1:]), out=dest)
            for j in range(1, len(cols)):
                np.multiply(a[r0, cols[j]], minor(rest, cols[:j] + cols[j + 1:]), out=term)
                (np.subtract if j % 2 else np.add)(acc, term, out=acc)
            memo[key] = acc
        return memo[key]

    for i in range(m):
        rows = tuple(r for r in range(m) if r != i)
        for k, subset in enumerate(itertools.combinations(range(n), m - 1)):
            value = minor(rows, subset, out[i, k])
            if value is not out[i, k]:
                out[i, k] = value                   # a 1 x 1 minor is an entry of ``a``
        if i % 2:
            np.negative(out[i], out=out[i])
    return out


def packed_facets(generators: ArrayLike) -> FloatArray:
    """Slabs ``|nu_k . w| <= h_k`` of ``W = {G s : |s| <= 1}``, packed (..., k, m + 1): ``nu_k`` then ``h_k``.

    The ``wrench_facets`` quantity's layout; ``facets`` gives the two parts as views.

    Parameters
    ----------
    generators : array_like, shape (..., m, n), n >= m
        ``G = A diag(t)``: each actuator's wrench at full torque.

    Returns
    -------
    ndarray, shape (..., k, m + 1)
        ``[..., :m]`` the normals ``nu_S`` for each of the ``k = C(n, m-1)`` subsets ``S``
        (``itertools.combinations`` order), cofactors of the columns scaled to unit length, not
        normalised (only ratios matter); ``[..., m]`` the offsets ``h_S = sum_u |nu_S . g_u|``
        (every ``u``: a normal spoiled by rounding still bounds ``W``). ``nan`` where ``G`` has
        a non-finite entry.

    Raises
    ------
    ValueError
        If ``generators`` has fewer columns than rows.

    Notes
    -----
    Compiled point by point (``kernels.facets``) with the operations of
    ``_packed_facets_reference`` in its order: the same bits as those numpy passes.

    Examples
    --------
    >>> packed_facets(np.diag([2.0, 3.0])) + 0.0         # slabs |y| <= 3 and |x| <= 2
    array([[ 0., -1.,  3.],
           [ 1.,  0.,  2.]])
    """
    g = as_jacobian(generators, "generators")
    m, n = g.shape[-2:]
    if n < m:
        raise ValueError(f"generators needs at least as many columns as rows (..., {m}, >= {m}), got {g.shape}")
    batch = g.shape[:-2]
    flat = np.ascontiguousarray(g.reshape((-1, m, n)), dtype=np.float64)
    ent, child, count, top, size = _facet_plan(m, n)
    out = np.empty((flat.shape[0], top.shape[1], m + 1))
    if len(flat):
        from .kernels import facets as facet_kernel

        facet_kernel.packed_facets_points(flat, ent, child, count, top, out,
                                          np.empty((size, facet_kernel.BLOCK)))
    return out.reshape(batch + (top.shape[1], m + 1))


@functools.lru_cache(maxsize=32)
def _facet_plan(m: int, n: int):
    """``kernels.facets.facet_plan`` for ``m`` rows and ``n`` generators, built once."""
    from .kernels import facets as facet_kernel

    return facet_kernel.facet_plan(m, n)


def _packed_facets_reference(generators: ArrayLike) -> FloatArray:
    """``packed_facets`` in numpy passes over blocks of points: the compiled kernel's reference (its tests).

    The same operations in the same order as ``kernels.facets.packed_facets_points``.
    """
    g = as_jacobian(generators, "generators")
    m, n = g.shape[-2:]
    if n < m:
        raise ValueError(f"generators needs at least as many columns as rows (..., {m}, >= {m}), got {g.shape}")
    batch = g.shape[:-2]
    flat = g.reshape((-1, m, n))
    k = math.comb(n, m - 1)
    out = np.empty((flat.shape[0], k, m + 1))
    for lo in range(0, flat.shape[0], FACET_BLOCK):
        block = flat[lo:lo + FACET_BLOCK]
        finite = np.all(np.isfinite(block), axis=(-2, -1))
        a = linalg.components(np.where(finite[:, None, None], block, 0.0))           # (m, n, N)
        # Unit columns: minors stay within [-1, 1] whatever the scale of G (1e-300 ... 1e300).
        big = np.max(np.abs(a), axis=0)
        length = big * np.sqrt(np.sum((a / np.where(big > 0, big, 1.0)) ** 2, axis=0))   # (n, N)
        a /= np.where(length > 0, length, 1.0)
        nu = _cofactor_normals(a, np.empty((m, k) + a.shape[2:]))
        offsets = np.zeros((k,) + a.shape[2:])
        dot, term = np.empty_like(offsets), np.empty_like(offsets)
        for u in range(n):                          # h_S += |nu_S . a_u| |g_u|, for all S at once
            np.multiply(nu[0], a[0, u], out=dot)
            for i in range(1, m):
                np.multiply(nu[i], a[i, u], out=term)
                dot += term
            np.abs(dot, out=dot)
            dot *= length[u]
            offsets += dot
        dest = out[lo:lo + FACET_BLOCK]
        dest[..., :m] = nu.transpose(2, 1, 0)
        dest[..., m] = offsets.T
        dest[~finite] = np.nan
    return out.reshape(batch + (k, m + 1))


def facets(generators: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Slabs ``|nu_k . w| <= h_k`` whose intersection is ``W = {G s : |s| <= 1}``.

    Views of ``packed_facets``.

    Parameters
    ----------
    generators : array_like, shape (..., m, n), n >= m
        ``G = A diag(t)``: each actuator's wrench at full torque.

    Returns
    -------
    normals : ndarray, shape (..., k, m)
        ``nu_S`` for each of the ``k = C(n, m-1)`` subsets ``S`` (``itertools.combinations``
        order), from columns scaled to unit length; not normalised (only ratios matter).
    offsets : ndarray, shape (..., k)
        ``h_S = sum_u |nu_S . g_u|``. ``nan`` (both) where ``G`` has a non-finite entry.

    Raises
    ------
    ValueError
        If ``generators`` has fewer columns than rows.

    Examples
    --------
    >>> nu, h = facets(np.diag([2.0, 3.0]))
    >>> nu.shape, h.tolist()
    ((2, 2), [3.0, 2.0])
    """
    packed = packed_facets(generators)
    return packed[..., :-1], packed[..., -1]


def slice_inscribed_radius(normals: ArrayLike, offsets: ArrayLike, *, rows,
                           shifts: ArrayLike | None = None) -> FloatArray:
    """Radius of the largest ball about 0 in the slice of ``W`` on ``rows``, shape (...).

    ``min_k h_k / |nu_k[rows]|`` over the slabs of ``facets``; ``nan`` where every normal is
    zero (``G`` of rank below m - 1: no slab description) or ``G`` is not finite.

    With ``shifts`` the set is ``c + W`` (a torque bias ``b`` moves the wrench set to
    ``c = -A b``): slab k is ``|nu_k . w - s_k| <= h_k`` with ``s_k = nu_k . c``, and a ball about 0
    of radius ``r`` lies in the slice iff ``r |nu_k[rows]| <= h_k - |s_k|`` for every k: the radius is
    ``max(0, min_k (h_k - |s_k|) / |nu_k[rows]|)``, 0 where the origin is outside the slice (a slab
    with ``nu_k[rows] = 0`` and ``|s_k| > h_k`` leaves the slice empty: 0 too).

    Parameters
    ----------
    normals : array_like, shape (..., k, m)
        Slab normals ``nu_k`` (``facets``).
    offsets : array_like, shape (..., k)
        Slab offsets ``h_k``.
    rows : sequence of int
        The slice's task rows.
    shifts : array_like, shape (..., k), optional
        ``nu_k . c``, each slab's centre (``slab_shifts``); default 0 (the set about 0).

    Returns
    -------
    ndarray, shape (...)
        In the unit of the wrench rows ``rows`` (N or N m).

    Examples
    --------
    >>> nu, h = facets(np.diag([2.0, 3.0, 4.0]))
    >>> round(float(slice_inscribed_radius(nu, h, rows=[0, 1])), 12)
    2.0
    """
    nu = np.asarray(normals, float)
    h = np.asarray(offsets, float)
    biased = shifts is not None
    if biased:
        with np.errstate(invalid="ignore"):
            h = h - np.abs(np.asarray(shifts, float))
    rows = list(rows)
    batch = np.broadcast_shapes(nu.shape[:-2], h.shape[:-1])
    if not rows or not nu.shape[-2] or not all(-nu.shape[-1] <= i < nu.shape[-1] for i in rows):
        return _inscribed_radius(nu, h, rows, biased)      # numpy's own answer (or IndexError)
    # The normals as they come (a view of the packed slabs: no copy); numba builds one version for a
    # contiguous and one for a strided array (``runtime.load_pieces`` loads both).
    nu = np.broadcast_to(nu, batch + nu.shape[-2:]).reshape((-1,) + nu.shape[-2:])
    # One layout: contiguous and writeable (a trivial broadcast is a read-only view, and numba
    # would build, or load, a version of its own for it).
    h = np.require(np.broadcast_to(h, batch + h.shape[-1:]).reshape((-1,) + h.shape[-1:]), requirements=("C", "W"))
    out = np.empty(nu.shape[0])
    redo = np.empty(nu.shape[0], dtype=np.bool_)
    if len(out):
        from .kernels import facets as facet_kernel

        facet_kernel.inscribed_radius_points(nu, h, np.array(rows, np.int64) % nu.shape[-1], biased, out, redo)
    if np.any(redo):
        # Normals whose sum of squares may have under- or overflowed, zero or not finite: numpy's
        # rescaled sums, in its order.
        out[redo] = _inscribed_radius(nu[redo], h[redo], rows, biased)
    return out.reshape(batch)


def _inscribed_radius(nu: FloatArray, h: FloatArray, rows: list[int], biased: bool = False) -> FloatArray:
    """``slice_inscribed_radius`` in numpy: normals (..., k, m), offsets (..., k) -> (...).

    The reference of ``kernels.facets.inscribed_radius_points`` (its tests), and its points with a
    normal out of the plain sum of squares' safe range.

    ``biased``: ``h`` is ``h - |s|``, possibly negative; the radius is clamped at 0.
    """
    with np.errstate(invalid="ignore", over="ignore", under="ignore"):
        den = nu[..., rows[0]] * nu[..., rows[0]]
        for i in rows[1:]:
            den += nu[..., i] * nu[..., i]
        np.sqrt(den, out=den)
    # Where the plain sum of squares may have over- or underflowed (or is 0, inf, nan), redo it
    # scaled by the largest entry: the few such normals get the same value as before.
    redo = ~((den > 2.0 ** -450) & (den < 2.0 ** 500))
    if np.any(redo):
        part = nu[redo][..., rows]
        with np.errstate(invalid="ignore", over="ignore"):
            big = np.max(np.abs(part), axis=-1)
            safe = np.where((big > 0) & np.isfinite(big), big, 1.0)
            scaled = big * np.sqrt(np.sum((part / safe[..., None]) ** 2, axis=-1))
        # An infinite normal (square J at a direct singularity) bounds that direction at 0, as in
        # ``isotropy.facet_distances``; a zero one bounds nothing; nan stays nan.
        den[redo] = np.where(np.isinf(big), np.inf, scaled)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(den == 0, np.where(h < 0, -np.inf, np.inf) if biased else np.inf, h / den)
    radius = np.min(ratio, axis=-1)
    if biased:
        radius = np.where(radius > 0, radius, np.where(np.isnan(radius), np.nan, 0.0))
    degenerate = ~np.any(np.abs(nu) > 0, axis=(-2, -1))
    return np.where(degenerate, np.nan, radius)


def slab_shifts(normals: ArrayLike, centre: ArrayLike) -> FloatArray:
    """``nu_k . c`` (..., k): where each slab of ``c + W`` is centred, for normals (..., k, m) and ``c`` (..., m).

    For a torque bias ``b`` the wrench set ``{A tau : -t - b <= tau <= t - b}`` is ``c + W`` with
    ``c = -A b``; for square ``J`` (``A = J^-T``, slabs ``nu_u = J[:, u]``) the shifts are ``-b``
    exactly, without ``A``.

    Examples
    --------
    >>> slab_shifts(np.eye(2), [0.5, -1.0]).tolist()
    [0.5, -1.0]
    """
    return np.einsum("...km,...m->...k", np.asarray(normals, float), np.asarray(centre, float))


def slab_slice_vertex_max_norm(normals: ArrayLike, lower: ArrayLike, upper: ArrayLike, *, rows) -> FloatArray:
    """Largest norm of the slice ``{y : lo_k <= nu_k[rows] . y <= hi_k for every k}`` (...), from its vertices.

    A vertex (``d = len(rows)`` coordinates) is where ``d`` slab faces meet: every ``d``-subset of
    slabs and choice of face is solved and kept where no slab is violated beyond rounding
    (``64 eps`` of the slab's width scale, plus the bound on the rounding of the solve's products,
    ``kernels.wrench``). Each slab is divided by ``max(|lo|, |hi|)`` and the
    whole by a power of two, so the solves neither over- nor underflow. The asymmetric
    counterpart of ``slab_slice_max_norm`` (a biased set's slabs, ``lo = s - h``, ``hi = s + h``).

    Returns
    -------
    ndarray, shape (...)
        In the unit of the rows; ``inf`` where the slabs leave the slice unbounded (their
        normals on ``rows`` span fewer than ``d`` dimensions), 0 where the slice is empty (no
        wrench on ``rows`` with the other rows 0 is in the set), ``nan`` where a normal is not finite.

    Examples
    --------
    >>> round(float(slab_slice_vertex_max_norm(np.eye(2), [-1.0, -3.0], [1.0, 1.0], rows=[0, 1])) ** 2, 12)
    10.0
    """
    a, lo_n, hi_n, scale, finite, part, batch = _unit_slabs(normals, lower, upper, rows)
    d = len(list(rows))
    best = np.full(a.shape[-1], -1.0)
    _slab_vertex_candidates(a, lo_n, hi_n, d, best)
    rank = np.linalg.matrix_rank(np.where(finite[:, None, None], part, 0.0))
    out = np.where(rank < d, np.inf, np.sqrt(np.maximum(best, 0.0)) / scale)
    return np.where(finite, out, np.nan).reshape(batch)


def slab_slice_vertices(normals: ArrayLike, lower: ArrayLike, upper: ArrayLike, *, rows) -> FloatArray:
    """Vertices (k, d) of one pose's slice ``{y : lo_j <= nu_j[rows] . y <= hi_j}`` (normals (S, m)).

    The candidates of ``slab_slice_vertex_max_norm`` that lie in every slab, duplicates merged
    (within ``1e-9`` of the largest), kept where they are vertices of their convex hull. Empty
    (0, d) where the slice is empty, unbounded or not finite.

    Examples
    --------
    >>> slab_slice_vertices(np.eye(2), [-1.0, -3.0], [1.0, 1.0], rows=[0, 1]).tolist()
    [[-1.0, -3.0], [-1.0, 1.0], [1.0, -3.0], [1.0, 1.0]]
    """
    nu = np.asarray(normals, float)
    if nu.ndim != 2:
        raise ValueError(f"normals must be one pose's (S, m), got shape {nu.shape}")
    d = len(list(rows))
    a, lo_n, hi_n, scale, finite, part, _ = _unit_slabs(nu, lower, upper, rows)
    if not finite[0] or np.linalg.matrix_rank(part[0]) < d:
        return np.zeros((0, d))
    pts = _slab_vertex_candidates(a, lo_n, hi_n, d)
    if not len(pts):
        return np.zeros((0, d))
    pts = pts / scale[0]
    size = np.max(np.abs(pts))
    _, keep = np.unique(np.round(pts / (size if size > 0 else 1.0) * 1e9), axis=0, return_index=True)
    pts = pts[np.sort(keep)]
    if len(pts) > d and np.linalg.matrix_rank(pts[1:] - pts[0]) == d:
        from scipy.spatial import ConvexHull
        pts = pts[np.sort(ConvexHull(pts).vertices)]
    return pts[np.lexsort(pts.T[::-1])]


def _unit_slabs(normals: ArrayLike, lower: ArrayLike, upper: ArrayLike, rows):
    """The slabs on ``rows``, each divided by ``max(|lo|, |hi|)`` and all by a power of two, component-first.

    Returns ``a`` (S, d, N), ``lo``, ``hi`` (S, N), the power of two (N,), where finite (N,), the
    unscaled normals on ``rows`` (N, S, d) and the batch shape.
    """
    nu = np.asarray(normals, float)
    rows = list(rows)
    d = len(rows)
    if d not in (2, 3):
        raise ValueError(f"rows must name 2 or 3 task rows, got {rows}")
    lo = np.asarray(lower, float)
    hi = np.asarray(upper, float)
    batch = np.broadcast_shapes(nu.shape[:-2], lo.shape[:-1], hi.shape[:-1])
    k = nu.shape[-2]
    part = np.broadcast_to(nu[..., rows], batch + (k, d)).reshape(-1, k, d)
    lo = np.broadcast_to(lo, batch + (k,)).reshape(-1, k)
    hi = np.broadcast_to(hi, batch + (k,)).reshape(-1, k)
    finite = np.all(np.isfinite(part), axis=(-2, -1)) & np.all(np.isfinite(lo) & np.isfinite(hi), axis=-1)
    width = np.maximum(np.abs(lo), np.abs(hi))
    width = np.where(width > 0, width, 1.0)
    a = np.where(finite[:, None, None], part / width[..., None], 0.0)
    big = np.max(np.abs(a), axis=(-2, -1))
    scale = np.where(big > 0, np.ldexp(1.0, np.frexp(np.where(big > 0, big, 1.0))[1]), 1.0)
    # Component-first (slab, coordinate, point): the solves are Cramer's rule on entry arrays.
    a = np.ascontiguousarray(np.moveaxis(a / scale[:, None, None], 0, -1))     # (k, d, N)
    lo_n = np.ascontiguousarray(np.where(finite[:, None], lo / width, 0.0).T)  # (k, N)
    hi_n = np.ascontiguousarray(np.where(finite[:, None], hi / width, 0.0).T)
    return a, lo_n, hi_n, scale, finite, part, batch


def _slab_vertex_candidates(a: FloatArray, lo_n: FloatArray, hi_n: FloatArray, d: int,
                            best: FloatArray | None = None) -> FloatArray:
    """The slab slice's vertices: every d-subset of slabs and choice of face, solved, kept where in every slab.

    ``a`` (k, d, N), ``lo_n``, ``hi_n`` (k, N) from ``_unit_slabs``. With ``best`` (N,) the
    largest ``|y|^2`` of a kept vertex at each point goes into it (-1 where none) and nothing is
    returned; without, ``a`` holds one point and its kept vertices (j, d) are returned, in the
    order of the subsets (``itertools.combinations``) and faces (``itertools.product((lo, hi))``).
    Compiled: ``kernels.wrench.slab_vertices``.

    ``y = sum_j b_j c_j / det`` with the subset's cofactor vectors ``c_j``; the slab products
    ``a_k . y`` likewise from ``a_k . c_j``. In a slab beyond rounding: ``64 eps`` of the largest
    product plus a bound on the products' own rounding, which grows with the subset's
    conditioning (``kernels.wrench``'s module doc: without it a vertex could fail its own slabs).
    A subset whose normals are dependent within rounding (``|det|`` at most ``64 eps``
    times the product of their lengths: faces parallel to 1e-14 rad) meets in no vertex: its
    ``det`` is rounding noise, and the point it gives lies ~1/noise away (the Twin-Pantograph's
    slabs under gravity at (110, 0, 60) mm: two antiparallel slabs and a third whose zero
    entry came out 1e-18, ``det`` 1e-35, a "vertex" 1.2e18 away that the products, as noisy,
    let through: an anisotropic force of 2^61 N where its neighbours have 6 N).
    """
    # Imported here: numba loads on a wrench set's first use, not with ``metrics``.
    from .kernels import wrench as compiled
    subsets = np.array(list(itertools.combinations(range(a.shape[0]), d)), np.intp).reshape(-1, d)
    faces = np.array(list(itertools.product((False, True), repeat=d)))
    if best is not None:
        compiled.slab_vertices(a, lo_n, hi_n, subsets, faces, best, np.zeros((0, d)))
        return np.zeros((0, d))
    points = np.empty((len(subsets) * len(faces), d))
    return points[:compiled.slab_vertices(a, lo_n, hi_n, subsets, faces, np.full(1, -1.0), points)]
