"""The implementations of ``metrics.wrenches`` (and friends) before the speed-up of issue 11, kept
verbatim as references for ``test_fast_kernels.py``: the optimised kernels must give these
numbers to a derived tolerance. Not collected by pytest (no ``test_`` prefix); docstrings trimmed
to one line where they were long.
"""
from __future__ import annotations

import itertools

import numpy as np
from numpy.typing import ArrayLike

from kinematics.base import FloatArray
from metrics.linalg import as_jacobian
from metrics.polytopes import sign_patterns

VERTEX_TOL = 1e-8


def _minor_table(a: FloatArray):
    """A memoised ``minor(rows, cols)`` of entry arrays ``a`` (m, n, N), by Laplace expansion."""
    memo: dict[tuple, FloatArray] = {}

    def minor(rows: tuple[int, ...], cols: tuple[int, ...]) -> FloatArray:
        if len(rows) == 1:
            return a[rows[0], cols[0]]
        key = (rows, cols)
        if key not in memo:
            r0, rest = rows[0], rows[1:]
            acc = a[r0, cols[0]] * minor(rest, cols[1:])
            for j in range(1, len(cols)):
                term = a[r0, cols[j]] * minor(rest, cols[:j] + cols[j + 1:])
                acc = acc - term if j % 2 else acc + term
            memo[key] = acc
        return memo[key]

    return minor


def facets(generators: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Slabs ``|nu_k . w| <= h_k`` whose intersection is ``W = {G s : |s| <= 1}``.

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
    """
    g = as_jacobian(generators, "generators")
    m, n = g.shape[-2:]
    if n < m:
        raise ValueError(f"generators needs at least as many columns as rows (..., {m}, >= {m}), got {g.shape}")
    batch = g.shape[:-2]
    flat = g.reshape((-1, m, n))
    finite = np.all(np.isfinite(flat), axis=(-2, -1))
    flat = np.where(finite[:, None, None], flat, 0.0)
    # Unit columns: minors stay within [-1, 1] whatever the scale of G (1e-300 ... 1e300).
    big = np.max(np.abs(flat), axis=-2)
    length = big * np.sqrt(np.sum((flat / np.where(big > 0, big, 1.0)[:, None, :]) ** 2, axis=-2))   # (N, n)
    unit = flat / np.where(length > 0, length, 1.0)[:, None, :]
    a = np.ascontiguousarray(np.moveaxis(unit, 0, -1))                      # (m, n, N)
    minor = _minor_table(a)
    subsets = list(itertools.combinations(range(n), m - 1))
    normals = np.empty((len(subsets), m) + a.shape[2:])
    for k, subset in enumerate(subsets):
        for i in range(m):
            rows = tuple(r for r in range(m) if r != i)
            value = minor(rows, subset) if m > 1 else np.ones(a.shape[2:])
            normals[k, i] = -value if i % 2 else value
    dots = np.einsum("kiN,iuN->kuN", normals, a)
    offsets = np.einsum("kuN,uN->kN", np.abs(dots), np.moveaxis(length, 0, -1))
    normals = np.moveaxis(normals, -1, 0)
    offsets = np.moveaxis(offsets, -1, 0)
    normals[~finite] = np.nan
    offsets[~finite] = np.nan
    return normals.reshape(batch + normals.shape[1:]), offsets.reshape(batch + offsets.shape[1:])



def slice_inscribed_radius(normals: ArrayLike, offsets: ArrayLike, *, rows) -> FloatArray:
    """Radius of the largest ball about 0 in the slice of ``W`` on ``rows``, shape (...).

    ``min_k h_k / |nu_k[rows]|`` over the slabs of ``facets``; ``nan`` where every normal is
    zero (``G`` of rank below m - 1: no slab description) or ``G`` is not finite.

    Parameters
    ----------
    normals : array_like, shape (..., k, m)
        Slab normals ``nu_k`` (``facets``).
    offsets : array_like, shape (..., k)
        Slab offsets ``h_k``.
    rows : sequence of int
        The slice's task rows.

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
    part = nu[..., list(rows)]
    with np.errstate(invalid="ignore"):
        big = np.max(np.abs(part), axis=-1)
        safe = np.where((big > 0) & np.isfinite(big), big, 1.0)
        den = big * np.sqrt(np.sum((part / safe[..., None]) ** 2, axis=-1))
    # An infinite normal (square J at a direct singularity) bounds that direction at 0, as in
    # ``polytopes.facet_distances``; a zero one bounds nothing; nan stays nan.
    den = np.where(np.isinf(big), np.inf, den)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(den == 0, np.inf, h / den)
    radius = np.min(ratio, axis=-1)
    degenerate = ~np.any(np.abs(nu) > 0, axis=(-2, -1))
    return np.where(degenerate, np.nan, radius)



def _adjugate(m: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Adjugate (r, r, ...) and determinant (...) of entry arrays ``m`` (r, r, ...), r <= 3."""
    r = m.shape[0]
    if r == 1:
        return np.ones_like(m), m[0, 0]
    if r == 2:
        adj = np.stack([np.stack([m[1, 1], -m[0, 1]]), np.stack([-m[1, 0], m[0, 0]])])
        return adj, m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0]
    c = np.empty_like(m)
    for i in range(3):
        for j in range(3):
            i1, i2 = [k for k in range(3) if k != i]
            j1, j2 = [k for k in range(3) if k != j]
            c[i, j] = m[i1, j1] * m[i2, j2] - m[i1, j2] * m[i2, j1]
            if (i + j) % 2:
                c[i, j] = -c[i, j]
    det = m[0, 0] * c[0, 0] + m[0, 1] * c[0, 1] + m[0, 2] * c[0, 2]
    return np.swapaxes(c, 0, 1), det


def _section_candidates(generators: ArrayLike, rows):
    """Yield ``(points (p, d, N), inside (p, N))``: images ``G_R s`` of candidate vertices of Q.

    ``generators`` (N, m, n) finite; one block per free set ``F``; ``p = 2^(n-r-1)`` sign
    patterns (one of each +-pair). ``G_O`` rows are equilibrated (the solution is unchanged).
    """
    g = np.asarray(generators, float)
    m, n = g.shape[-2:]
    rows = list(rows)
    others = [i for i in range(m) if i not in rows]
    r = len(others)
    if not rows or r == 0 or r > 3 or r > n:
        raise ValueError(f"rows must leave 1 to 3 other rows of {m} (and at most n = {n}), got {rows}")
    a = np.ascontiguousarray(np.moveaxis(g, 0, -1))                      # (m, n, N)
    go = a[others]
    scale = np.max(np.abs(go), axis=(0, 1))
    go = go / np.where(scale > 0, scale, 1.0)
    # Equilibrate each row of G_O (an exact-solution-preserving scaling).
    row_big = np.max(np.abs(go), axis=1, keepdims=True)
    go = go / np.where(row_big > 0, row_big, 1.0)
    gr = a[rows]
    signs = sign_patterns(n - r, half=True) if n > r else np.ones((1, 0))
    for free in itertools.combinations(range(n), r):
        fixed = [u for u in range(n) if u not in free]
        adj, det = _adjugate(go[:, list(free)])
        c = go[:, fixed]                                                    # (r, b, N)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            x = -np.einsum("ijN,jbN->ibN", adj, c) / det                     # s_F = x s_B
            s_free = np.einsum("pb,ibN->piN", signs, x)                      # (p, r, N)
            inside = np.all(np.abs(s_free) <= 1.0 + VERTEX_TOL, axis=1) & (det != 0)
            h = np.einsum("dfN,fbN->dbN", gr[:, list(free)], x) + gr[:, fixed]
            points = np.einsum("pb,dbN->pdN", signs, h)
        yield points, inside


def slice_max_norm(generators: ArrayLike, *, rows) -> FloatArray:
    """Largest norm of ``w[rows]`` over ``w in W`` with ``w[others] = 0``, shape (...).

    Parameters
    ----------
    generators : array_like, shape (..., m, n)
        ``G = A diag(t)``, n >= m.
    rows : sequence of int
        The slice's coordinates (e.g. the force rows); 1 to 3 other rows.

    Returns
    -------
    ndarray, shape (...)
        In the unit of ``G``'s rows ``rows``. ``nan`` where ``G`` is not finite or no
        candidate vertex exists (``G_O`` of rank below ``r``).
    """
    g = as_jacobian(generators, "generators")
    m, n = g.shape[-2:]
    batch = g.shape[:-2]
    flat = g.reshape((-1, m, n))
    finite = np.all(np.isfinite(flat), axis=(-2, -1))
    flat = np.where(finite[:, None, None], flat, 0.0)
    part = flat[:, list(rows), :]
    size = np.max(np.abs(part), axis=(-2, -1))
    size = np.where(size > 0, size, 1.0)
    scaled = flat.copy()
    scaled[:, list(rows), :] = part / size[:, None, None]      # |G_R s| computed near 1: no under/overflow
    best = np.full(flat.shape[0], -1.0)
    for points, inside in _section_candidates(scaled, rows):
        norm2 = np.sum(points * points, axis=1)                  # (p, N)
        best = np.maximum(best, np.max(np.where(inside, norm2, -1.0), axis=0))
    out = np.where(finite & (best >= 0), size * np.sqrt(np.maximum(best, 0.0)), np.nan)
    return out.reshape(batch)


