"""Batched small-matrix linear algebra: singular values and inverse transposes.

LAPACK through ``numpy.linalg`` costs about 1.4 us per 3 x 3 SVD in a batch of a million,
which alone would blow a map's time budget. For 2 x 2 and 3 x 3 matrices we use closed
forms, and hand the ill-conditioned few back to LAPACK, where the closed forms lose more
accuracy than LAPACK does:

====================  =========================================  ==========================
method                relative error of the smallest value        used where
====================  =========================================  ==========================
2 x 2 closed form     ~ eps * kappa   (same order as LAPACK)      always for 2 x 2
3 x 3 Gram + det      ~ 10 eps * kappa^2                          kappa <= FAST_COND_LIMIT and
                                                                  no near-repeated value
k x k Gram eigvalsh   ~ (max(m, n) + 6) eps * kappa^2 / 2         other shapes up to 7, where
                                                                  kappa <= FAST_COND_LIMIT
LAPACK gesdd          ~ eps * kappa                               the other 3 x 3 and
                                                                  the other shapes
====================  =========================================  ==========================

With ``FAST_COND_LIMIT = 100`` the closed form's error stays below ~2e-11 relative; the
stiff-case tests check these bounds against mpmath at 50 digits.

Non-finite matrices (a five-bar at a direct singularity has ``inf`` entries) give ``inf``
singular values rather than an exception: one bad pose must not abort a map.

Scale. The closed forms square and cube entries (Gram matrices, cofactors, determinants),
which overflow or underflow for matrices far from unit scale although their singular
values and inverses are representable (``1e-300 * I`` would look singular). Each closed
form checks a scale it computes anyway (``sigma_max``, the Frobenius norm) against
``SAFE_SCALE``; the few matrices outside are scaled by a power of two, ``ldexp(A, -e)`` with
``2^e`` bounding ``max |a_ij|`` (exact in binary floating point), run through the same
formula, and the result scaled back. Matrices inside the range never see the scaling, so
their results are bit-for-bit those of the plain formula, at no cost in speed.
"""
from __future__ import annotations

import functools
import itertools

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

#: Condition number above which the 3 x 3 closed forms defer to LAPACK.
FAST_COND_LIMIT = 100.0

#: Largest ``max(m, n)`` whose singular values come from the Gram matrix's eigenvalues (``_sv_gram``).
GRAM_MAX_SIZE = 7

#: ``(lo, hi)``: a matrix whose ``sigma_max`` (or Frobenius norm) lies strictly inside runs
#: through the closed forms as given. With entries below ``2^150`` in magnitude, their sixth
#: powers (``|A|_F^2 |cof A|_F^2`` of a 3 x 3) stay below ``2^900``; above ``2^-150`` (for the
#: largest singular value) the squares and cubes that matter stay normal numbers.
SAFE_SCALE = (2.0 ** -150, 2.0 ** 150)
#: ``metrics.dynamics.inverse_spd``'s margin: a symmetric positive definite matrix with
#: ``det > SURE_REGULAR m eps tr^m`` is regular without its eigenvalues. Here, below both
#: ``metrics.dynamics`` and the kernels that apply the same test (``kernels.spd``,
#: ``kernels.dynamics``, ``kernels.stewart``), so that neither imports the other for it.
SURE_REGULAR = 16.0


def pow2_exponents(a: ArrayLike, axis) -> np.ndarray:
    """Integer ``e`` with ``2^(e-1) <= max |a| < 2^e`` over ``axis``; 0 where the maximum is 0 or not finite.

    ``np.ldexp(a, -e)`` then has its largest entry in [0.5, 1), exactly (a power-of-two scaling).

    Parameters
    ----------
    a : array_like
        Any array, e.g. matrices (..., m, n).
    axis : int or tuple of int
        The axes to take the maximum over, e.g. ``(-2, -1)`` for each matrix.

    Returns
    -------
    ndarray of int
        ``a``'s shape without ``axis``.

    Examples
    --------
    >>> pow2_exponents(np.array([[0.75, -3.0], [0.0, 0.0]]), axis=-1).tolist()
    [2, 0]
    """
    big = np.max(np.abs(a), axis=axis)
    _, e = np.frexp(np.where(np.isfinite(big), big, 0.0))
    return e


def outside_safe_scale(scale: ArrayLike, squared: bool = False) -> np.ndarray:
    """Mask of matrices whose ``scale`` (``sigma_max``, or its square if ``squared``) is outside ``SAFE_SCALE``.

    ``nan`` is outside: a result that overflowed to ``inf - inf`` is recomputed scaled.

    Parameters
    ----------
    scale : array_like, shape (...)
        One scale per matrix.
    squared : bool
        ``scale`` is a square (compare with the squared bounds).

    Returns
    -------
    ndarray of bool, shape (...)

    Examples
    --------
    >>> outside_safe_scale([1.0, 1e-300, np.nan]).tolist()
    [False, True, True]
    """
    lo, hi = SAFE_SCALE
    if squared:
        lo, hi = lo * lo, hi * hi
    scale = np.asarray(scale)
    with np.errstate(invalid="ignore"):
        return ~((scale > lo) & (scale < hi))


def as_jacobian(jac: ArrayLike, name: str = "jac") -> FloatArray:
    """``jac`` as float64 with at least two dimensions ``(..., m, n)``, or raise.

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
        Matrices with ``m, n >= 1``.
    name : str
        The argument's name for the message.

    Returns
    -------
    ndarray, shape (..., m, n)

    Raises
    ------
    ValueError
        For fewer than two dimensions or an empty matrix axis.

    Examples
    --------
    >>> as_jacobian([[1, 0], [0, 1]]).dtype
    dtype('float64')
    """
    arr = np.asarray(jac, dtype=np.float64)
    if arr.ndim < 2 or arr.shape[-1] == 0 or arr.shape[-2] == 0:
        raise ValueError(f"{name} must have shape (..., m, n) with m, n >= 1, got {arr.shape}")
    return arr


def _finite_part(mat: FloatArray) -> tuple[np.ndarray, FloatArray]:
    """Mask of matrices with only finite entries, and the matrices with the others zeroed."""
    finite = np.all(np.isfinite(mat), axis=(-2, -1))
    return finite, (mat if finite.all() else np.where(finite[..., None, None], mat, 0.0))


def components(mat: FloatArray) -> FloatArray:
    """Move the matrix axes first, ``(..., m, n) -> (m, n, ...)``, as one contiguous array.

    The closed forms below work entry by entry; on contiguous entry arrays numpy's ufuncs
    run about three times faster than on the strided views of ``(..., m, n)``.

    Parameters
    ----------
    mat : ndarray, shape (..., m, n)
        Matrices.

    Returns
    -------
    ndarray, shape (m, n, ...)
        C-contiguous.

    Examples
    --------
    >>> components(np.zeros((7, 2, 3))).shape
    (2, 3, 7)
    """
    return np.ascontiguousarray(np.moveaxis(mat, (-2, -1), (0, 1)))


def singular_values(jac: ArrayLike) -> FloatArray:
    """Singular values of each matrix, descending, shape ``(..., min(m, n))``.

    Matrices with a non-finite entry get ``inf`` values: ``condition_number`` reports them
    singular (``inf``).

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
        Matrices (Jacobians).

    Returns
    -------
    ndarray, shape (..., min(m, n))
        Descending; ``inf`` for a matrix with a non-finite entry.

    Examples
    --------
    >>> singular_values([[3.0, 0.0], [0.0, -2.0]]).tolist()
    [3.0, 2.0]
    >>> singular_values(np.ones((10, 3, 3))).shape
    (10, 3)
    """
    jac = as_jacobian(jac)
    finite, safe = _finite_part(jac)
    m, n = jac.shape[-2:]
    if (m, n) in ((2, 2), (3, 3)):
        sv = _sv_closed(safe)
        # Far from unit scale the closed forms over- or underflow: redo those few matrices
        # scaled by a power of two (exact), and scale their values back.
        out = np.array(outside_safe_scale(sv[..., 0]) & finite)
        if np.any(out):
            sub = safe[out]
            e = pow2_exponents(sub, axis=(-2, -1))
            sv[out] = np.ldexp(_sv_closed(np.ldexp(sub, -e[:, None, None])), e[:, None])
    elif max(m, n) <= GRAM_MAX_SIZE:
        sv = _sv_gram(safe)
    else:
        sv = np.linalg.svd(safe, compute_uv=False)
    if n <= m:
        # A column of exact zeros (an actuator at an inverse singularity, ``base.singular_limit``)
        # leaves rank below n: the smallest singular value is exactly 0, not LAPACK's rounding
        # (~1e-17 sigma_1, which made the manipulability there 1e-36 where the condition number was inf).
        sv[..., -1] = np.where(np.any(np.all(safe == 0.0, axis=-2), axis=-1), 0.0, sv[..., -1])
    sv[~finite] = np.inf
    return sv


def _sv_gram(mats: FloatArray) -> FloatArray:
    """Singular values (..., k), ``k = min(m, n)``, from the eigenvalues of the k x k Gram matrix; LAPACK where hard.

    ``eigvalsh`` of ``A A^T`` (or ``A^T A``) costs about half of LAPACK's SVD for 5 x 5 and 6 x 6.
    The computed Gram matrix is within ``(k + 2) eps sigma_1^2`` of the true one (inner products
    of length ``max(m, n) <= ~k + 2`` here) and ``eigvalsh`` is backward stable, so each
    ``sigma_i^2`` is off by at most about ``(max(m, n) + 6) eps sigma_1^2``: a relative error
    ``(max(m, n) + 6) eps kappa^2 / 2`` in ``sigma_i``. With ``kappa <= FAST_COND_LIMIT`` that is
    below ``1.4e-11`` for ``max(m, n) <= 7``; the other matrices (and those outside
    ``SAFE_SCALE``, whose squares could over- or underflow) go to LAPACK's SVD.
    """
    m, n = mats.shape[-2:]
    # max |a_ij| <= sigma_1 <= sqrt(m n) max |a_ij|: inside SAFE_SCALE the Gram entries neither
    # overflow nor lose the small values to underflow.
    far = outside_safe_scale(np.max(np.abs(mats), axis=(-2, -1)))
    safe = np.where(far[..., None, None], 0.0, mats) if np.any(far) else mats
    t = np.swapaxes(safe, -1, -2)
    gram_k = safe @ t if m <= n else t @ safe
    lam = np.linalg.eigvalsh(gram_k)[..., ::-1]                          # descending
    sv = np.sqrt(np.maximum(lam, 0.0))
    with np.errstate(invalid="ignore"):
        hard = far | ~(sv[..., 0] <= FAST_COND_LIMIT * sv[..., -1])
    if np.any(hard):
        sv[hard] = np.linalg.svd(mats[hard], compute_uv=False)
    return sv


def _sv_closed(mats: FloatArray) -> FloatArray:
    """The 2 x 2 or 3 x 3 closed form on finite matrices (..., n, n), no scaling."""
    if mats.shape[-1] == 2:
        return _sv_2x2(components(mats))
    with np.errstate(over="ignore", invalid="ignore"):   # inf - inf only outside SAFE_SCALE: redone
        return _sv_3x3(components(mats), mats)


def _sv_2x2(a: FloatArray) -> FloatArray:
    """Closed form: sigma_max = (|(a+d, b-c)| + |(a-d, b+c)|) / 2, sigma_min = |det| / sigma_max."""
    p, q, r, s = a[0, 0], a[0, 1], a[1, 0], a[1, 1]
    big = 0.5 * (np.hypot(p + s, q - r) + np.hypot(p - s, q + r))
    with np.errstate(over="ignore", invalid="ignore"):   # only outside SAFE_SCALE: redone scaled
        det = np.abs(p * s - q * r)
    with np.errstate(divide="ignore", invalid="ignore"):
        small = np.where(big > 0.0, det / big, 0.0)
    return np.stack([big, np.minimum(small, big)], axis=-1)


def _det3(a: FloatArray) -> FloatArray:
    """Determinant of entry arrays ``a`` (3, 3, ...)."""
    return (a[0, 0] * (a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1])
            - a[0, 1] * (a[1, 0] * a[2, 2] - a[1, 2] * a[2, 0])
            + a[0, 2] * (a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]))


def gram(a: FloatArray) -> FloatArray:
    """``A^T A`` from entry arrays ``a`` (m, n, ...), as entry arrays (n, n, ...).

    Parameters
    ----------
    a : ndarray, shape (m, n, ...)
        Entry arrays of matrices ``A`` (``components``).

    Returns
    -------
    ndarray, shape (n, n, ...)
        Entry arrays of ``A^T A``.

    Examples
    --------
    >>> gram(components(np.array([[1.0, 2.0], [3.0, 4.0]]))).tolist()
    [[10.0, 14.0], [14.0, 20.0]]
    """
    m, n = a.shape[:2]
    g = np.empty((n, n) + a.shape[2:])
    for i in range(n):
        for j in range(i, n):
            acc = a[0, i] * a[0, j]
            for k in range(1, m):
                acc += a[k, i] * a[k, j]
            g[i, j] = acc
            g[j, i] = acc
    return g


def symmetric_eigenvalues_3x3(s: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Eigenvalues of symmetric 3 x 3 entry arrays ``s`` (3, 3, ...), the trigonometric closed form.

    Returns
    -------
    lam1, lam2, lam3 : ndarray, shape (...)
        Descending.
    r : ndarray, shape (...)
        ``cos 3 phi``: near ``|r| = 1`` (a repeated eigenvalue) ``arccos`` loses digits, about
        ``eps / sqrt(1 - |r|)`` relative; callers send those matrices to LAPACK.
    """
    mean = (s[0, 0] + s[1, 1] + s[2, 2]) / 3.0
    d0, d1, d2 = s[0, 0] - mean, s[1, 1] - mean, s[2, 2] - mean
    s01, s02, s12 = s[0, 1], s[0, 2], s[1, 2]
    p = np.sqrt((d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * (s01 * s01 + s02 * s02 + s12 * s12)) / 6.0)
    # det(S - mean I) / (2 p^3) is the cosine of 3 phi; p = 0 means S = mean * I.
    det_shift = d0 * (d1 * d2 - s12 * s12) - s01 * (s01 * d2 - s12 * s02) + s02 * (s01 * s12 - d1 * s02)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(p > 0.0, det_shift / (2.0 * p * p * p), 0.0)
    phi = np.arccos(np.clip(r, -1.0, 1.0)) / 3.0
    lam1 = mean + 2.0 * p * np.cos(phi)
    lam3 = mean + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0)
    return lam1, 3.0 * mean - lam1 - lam3, lam3, r


def _sv_3x3(a: FloatArray, mats: FloatArray) -> FloatArray:
    """Closed form on the Gram matrix (trigonometric eigenvalues), then LAPACK where ill-conditioned.

    ``a`` holds the entries (3, 3, ...), ``mats`` the same matrices as (..., 3, 3) for the
    LAPACK fallback. sigma_1 comes from the largest eigenvalue of ``G = A^T A`` (accurate to
    a few eps); sigma_3 from ``|det A| / (sigma_1 sigma_2)``, never worse than the Gram
    eigenvalue and exact when the two small values are well apart.
    """
    lam1, lam2, lam3, r = symmetric_eigenvalues_3x3(gram(a))
    s1 = np.sqrt(np.maximum(lam1, 0.0))
    s2 = np.sqrt(np.clip(lam2, 0.0, lam1))
    det = np.abs(_det3(a))
    with np.errstate(divide="ignore", invalid="ignore"):
        s3 = np.where(s2 > 0.0, det / (s1 * s2), 0.0)
    s3 = np.minimum(s3, s2)
    sv = np.stack([s1, s2, s3], axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        hard = ~(s1 <= FAST_COND_LIMIT * s3)      # also catches s3 = 0 and nan
    # Near a repeated eigenvalue of G (|r| -> 1) arccos loses half the digits of the split:
    # errors grow like eps / sqrt(1 - |r|), up to ~1e-8 relative in sigma_max and ~1e7 eps
    # kappa^2 in sigma_min at an exact repeat. Below 1 - 1e-3 they stay within the table's bounds.
    hard |= np.abs(r) > 1.0 - 1e-3
    if np.any(hard):
        sv[hard] = np.linalg.svd(mats[hard], compute_uv=False)
    return sv


def _cofactors(a: FloatArray) -> FloatArray:
    """Cofactor matrix of entry arrays ``a`` (n, n, ...) for n = 2, 3, same layout.

    For 3 x 3 its columns are the cross products of ``A``'s columns, ``c1 x c2``, ``c2 x c0``,
    ``c0 x c1``, so ``A^T cof(A) = det(A) I``.
    """
    n = a.shape[0]
    cof = np.empty_like(a)
    if n == 2:
        cof[0, 0], cof[0, 1], cof[1, 0], cof[1, 1] = a[1, 1], -a[1, 0], -a[0, 1], a[0, 0]
        return cof
    for col in range(3):
        j, k = (col + 1) % 3, (col + 2) % 3
        cof[0, col] = a[1, j] * a[2, k] - a[2, j] * a[1, k]
        cof[1, col] = a[2, j] * a[0, k] - a[0, j] * a[2, k]
        cof[2, col] = a[0, j] * a[1, k] - a[1, j] * a[0, k]
    return cof


def inverse_transpose(jac: ArrayLike) -> tuple[FloatArray, np.ndarray]:
    """``J^-T`` of square matrices ``(..., n, n)`` and a mask of where it exists.

    2 x 2 and 3 x 3 use the cofactor matrix (``J^-T = cof(J) / det J``), whose columns for
    3 x 3 are cross products of *Jacobian columns*, never of nearly parallel reference forces.
    Where the Frobenius condition estimate ``|J|_F |J^-1|_F`` exceeds ``FAST_COND_LIMIT``,
    the inverse comes from LAPACK's SVD instead (``U diag(1/sigma) V^T``), which raises for
    nothing. Singular or non-finite matrices give ``nan`` and ``False`` in the mask.

    Singular means ``sigma_min <= n eps sigma_max``: at that level rounding cannot tell the
    matrix from an exactly singular one. Matrices far from unit scale (outside
    ``SAFE_SCALE``) are inverted scaled by a power of two, ``(2^-e J)^-T 2^-e``, exactly.

    Parameters
    ----------
    jac : array_like, shape (..., n, n)
        Square matrices.

    Returns
    -------
    inv_t : ndarray, shape (..., n, n)
        ``J^-T``; ``nan`` where singular or not finite.
    ok : ndarray of bool, shape (...)

    Raises
    ------
    ValueError
        If ``jac`` is not square.

    Examples
    --------
    >>> inv_t, ok = inverse_transpose([[[1.0, 1.0], [1.0, 2.0]], [[1.0, 2.0], [2.0, 4.0]]])
    >>> inv_t[0].tolist(), ok.tolist()
    ([[2.0, -1.0], [-1.0, 1.0]], [True, False])
    """
    jac = as_jacobian(jac)
    m, n = jac.shape[-2:]
    if m != n:
        raise ValueError(f"jac must be square (..., n, n) for an inverse, got {jac.shape}")
    finite, safe = _finite_part(jac)
    return _inverse_transpose(safe, finite, rescale=True)


def _inverse_transpose(safe: FloatArray, finite: np.ndarray, rescale: bool) -> tuple[FloatArray, np.ndarray]:
    """``inverse_transpose`` on matrices with non-finite ones zeroed (``finite`` False there)."""
    n = safe.shape[-1]
    if n in (2, 3):
        a = components(safe)
        with np.errstate(over="ignore", invalid="ignore"):     # only outside SAFE_SCALE: redone below
            cof = _cofactors(a)
            det = a[0, 0] * cof[0, 0]
            for k in range(1, n):
                det = det + a[k, 0] * cof[k, 0]
            fro_sq = np.sum(a * a, axis=(0, 1))
        scaled = outside_safe_scale(fro_sq, squared=True) & finite if rescale else np.zeros(finite.shape, bool)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            fro_cond = np.sqrt(fro_sq * np.sum(cof * cof, axis=(0, 1))) / np.abs(det)
            easy = finite & ~scaled & (fro_cond <= FAST_COND_LIMIT)
            out = np.moveaxis(cof / det, (0, 1), (-2, -1))
        if not easy.all():
            out = np.where(easy[..., None, None], out, np.nan)
        hard = finite & ~easy & ~scaled
    else:
        scaled = np.zeros(finite.shape, bool)
        out = np.full(safe.shape, np.nan)
        hard = finite
    ok = np.array(finite & ~hard)   # an array even for one unbatched matrix, to assign into
    if np.any(hard):
        u, s, vt = np.linalg.svd(safe[hard])
        # sigma_min at rounding level (n eps sigma_max) is indistinguishable from 0: an exactly
        # singular matrix rarely gives LAPACK an exact 0, so test against that level.
        good = s[..., -1] > n * np.finfo(float).eps * s[..., 0]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):   # 1/0, inf * 0 where singular
            inv_t = np.matmul(u / s[..., None, :], vt)
        inv_t[~good] = np.nan
        out[hard] = inv_t
        ok[hard] = good
    if np.any(scaled):
        sub = safe[scaled]
        e = pow2_exponents(sub, axis=(-2, -1))[:, None, None]
        inv_t, good = _inverse_transpose(np.ldexp(sub, -e), np.ones(len(sub), bool), rescale=False)
        out[scaled] = np.ldexp(inv_t, -e)
        ok[scaled] = good
    return out, ok


# -- minors of small matrices, batched -----------------------------------------------------------
@functools.lru_cache(maxsize=64)
def _minor_plan(n_cols: int, row_sets: tuple[tuple[int, ...], ...]):
    """Index tables to evaluate every column-combination minor of ``row_sets`` level by level.

    Level ``k`` holds the minors of size ``k`` needed: a row set (a suffix, by Laplace
    expansion along its first row, of a requested set) with each ``k``-combination of the
    ``n_cols`` columns. Returns ``(levels, out)``: per level ``(entry, sub, sign)`` arrays of
    shape (E_k, k) (``entry`` a flat ``row * n_cols + col`` index, ``sub`` the index of the
    complementary minor in the level below, ``sign`` +-1), and ``out`` (len(row_sets), C(n, s))
    indices into the top level.
    """
    size = len(row_sets[0])
    needed: list[dict] = [dict() for _ in range(size + 1)]          # level -> {(rows, cols): index}
    for rows in row_sets:
        for t in range(size):
            suffix = rows[t:]
            for cols in itertools.combinations(range(n_cols), size - t):
                needed[size - t].setdefault((suffix, cols), len(needed[size - t]))
    levels = []
    for k in range(1, size + 1):
        keys = sorted(needed[k], key=needed[k].get)
        entry = np.empty((len(keys), k), np.intp)
        sub = np.zeros((len(keys), k), np.intp)
        for e, (rows, cols) in enumerate(keys):
            for p, col in enumerate(cols):
                entry[e, p] = rows[0] * n_cols + col
                if k > 1:
                    sub[e, p] = needed[k - 1][(rows[1:], cols[:p] + cols[p + 1:])]
        sign = np.where(np.arange(k) % 2 == 0, 1.0, -1.0)
        levels.append((entry, sub, sign))
    combos = list(itertools.combinations(range(n_cols), size))
    out = np.array([[needed[size][(rows, cols)] for cols in combos] for rows in row_sets], np.intp)
    return levels, out


def minors(a: ArrayLike, row_sets) -> FloatArray:
    """Every ``s x s`` minor of entry arrays ``a`` (m, n, ...) on the given row sets, by Laplace expansion.

    Each minor is expanded along its first row over the minors of the remaining rows, which
    are computed once and shared (index tables per level, ``_minor_plan``; each minor's terms
    are summed in place, in the order of its columns). The rounding error of a minor is that of
    the Laplace expansion: at most about ``s! s eps`` times the product of its rows' norms.

    Parameters
    ----------
    a : array_like, shape (m, n, ...)
        Entry arrays of matrices (``components``).
    row_sets : sequence of sequence of int
        Sorted row indices, all of the same size ``s <= min(m, n)``.

    Returns
    -------
    ndarray, shape (len(row_sets), C(n, s), ...)
        ``out[i, j]`` is the determinant of the rows ``row_sets[i]`` and the ``j``-th column
        combination in ``itertools.combinations(range(n), s)`` order.

    Examples
    --------
    >>> a = components(np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]))
    >>> minors(a, [(0, 1)]).tolist()
    [[-3.0, -6.0, -3.0]]
    """
    a = np.asarray(a, dtype=np.float64)
    m, n = a.shape[:2]
    row_sets = tuple(tuple(int(r) for r in rows) for rows in row_sets)
    size = len(row_sets[0])
    if any(len(rows) != size or list(rows) != sorted(set(rows)) or rows[0] < 0 or rows[-1] >= m for rows in row_sets):
        raise ValueError(f"row_sets must be sorted, distinct rows of {m}, all of one size, got {row_sets}")
    if not 1 <= size <= n:
        raise ValueError(f"row_sets' size must be between 1 and n = {n}, got {size}")
    levels, out = _minor_plan(n, row_sets)
    flat = a.reshape((m * n,) + a.shape[2:])
    prev = None
    term = np.empty(a.shape[2:])
    for k, (entry, sub, sign) in enumerate(levels, start=1):
        if k == 1:
            prev = flat[entry[:, 0]]
            continue
        # Minor by minor into its row of ``level``: the products go to one buffer, not to a
        # gathered (E_k, ...) temporary per term (2 to 4 times faster on blocks of thousands).
        level = np.empty((len(entry),) + a.shape[2:])
        for e in range(len(entry)):
            acc = np.multiply(flat[entry[e, 0]], prev[sub[e, 0]], out=level[e, ...])   # a view, also 0-d
            for p in range(1, k):
                np.multiply(flat[entry[e, p]], prev[sub[e, p]], out=term)
                (np.subtract if sign[p] < 0 else np.add)(acc, term, out=acc)
        prev = level
    return prev[out]
