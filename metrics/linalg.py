"""Batched small-matrix linear algebra: singular values and inverse transposes.

LAPACK through ``numpy.linalg`` costs about 1.4 us per 3 x 3 SVD in a batch of a million,
which alone would blow a map's time budget. For 2 x 2 and 3 x 3 matrices we use closed
forms, and hand the ill-conditioned few back to LAPACK, where the closed forms lose more
accuracy than LAPACK does:

====================  =========================================  ==========================
method                relative error of the smallest value        used where
====================  =========================================  ==========================
2 x 2 closed form     ~ eps * kappa   (same order as LAPACK)      always for 2 x 2
3 x 3 Gram + det      ~ 10 eps * kappa^2                          kappa <= FAST_COND_LIMIT
LAPACK gesdd          ~ eps * kappa                               kappa > FAST_COND_LIMIT,
                                                                  and any other shape
====================  =========================================  ==========================

With ``FAST_COND_LIMIT = 100`` the closed form's error stays below ~2e-11 relative; the
stiff-case tests check these bounds against mpmath at 50 digits.

Non-finite matrices (a five-bar at a direct singularity has ``inf`` entries) give ``inf``
singular values rather than an exception: one bad pose must not abort a map.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from kinematics.base import FloatArray

#: Condition number above which the 3 x 3 closed forms defer to LAPACK.
FAST_COND_LIMIT = 100.0


def as_jacobian(jac: ArrayLike, name: str = "jac") -> FloatArray:
    """``jac`` as float64 with at least two dimensions ``(..., m, n)``, or raise."""
    arr = np.asarray(jac, dtype=np.float64)
    if arr.ndim < 2 or arr.shape[-1] == 0 or arr.shape[-2] == 0:
        raise ValueError(f"{name} must have shape (..., m, n) with m, n >= 1, got {arr.shape}")
    return arr


def singular_values(jac: ArrayLike) -> FloatArray:
    """Singular values of each matrix, descending, shape ``(..., min(m, n))``.

    Matrices with a non-finite entry get ``inf`` for every value but the last, which is
    ``nan`` if unknown; the stable caller-facing rule is: cond = inf, see ``condition_number``.
    """
    jac = as_jacobian(jac)
    finite = np.all(np.isfinite(jac), axis=(-2, -1))
    safe = np.where(finite[..., None, None], jac, 0.0)
    m, n = jac.shape[-2:]
    if (m, n) == (2, 2):
        sv = _sv_2x2(safe)
    elif (m, n) == (3, 3):
        sv = _sv_3x3(safe)
    else:
        sv = np.linalg.svd(safe, compute_uv=False)
    sv[~finite] = np.inf
    return sv


def _sv_2x2(a: FloatArray) -> FloatArray:
    """Closed form: sigma_max = (|(a+d, b-c)| + |(a-d, b+c)|) / 2, sigma_min = |det| / sigma_max."""
    p, q, r, s = a[..., 0, 0], a[..., 0, 1], a[..., 1, 0], a[..., 1, 1]
    big = 0.5 * (np.hypot(p + s, q - r) + np.hypot(p - s, q + r))
    det = np.abs(p * s - q * r)
    with np.errstate(divide="ignore", invalid="ignore"):
        small = np.where(big > 0.0, det / big, 0.0)
    return np.stack([big, np.minimum(small, big)], axis=-1)


def _sv_3x3(a: FloatArray) -> FloatArray:
    """Closed form on the Gram matrix (trigonometric eigenvalues), then LAPACK where ill-conditioned.

    sigma_1 comes from the largest eigenvalue of ``G = A^T A`` (accurate to a few eps);
    sigma_3 from ``|det A| / (sigma_1 sigma_2)``, which is never worse than the Gram
    eigenvalue and exact when the two small values are well apart.
    """
    c0, c1, c2 = a[..., :, 0], a[..., :, 1], a[..., :, 2]
    g00 = np.einsum("...i,...i->...", c0, c0)
    g11 = np.einsum("...i,...i->...", c1, c1)
    g22 = np.einsum("...i,...i->...", c2, c2)
    g01 = np.einsum("...i,...i->...", c0, c1)
    g02 = np.einsum("...i,...i->...", c0, c2)
    g12 = np.einsum("...i,...i->...", c1, c2)
    mean = (g00 + g11 + g22) / 3.0
    d0, d1, d2 = g00 - mean, g11 - mean, g22 - mean
    off = g01 * g01 + g02 * g02 + g12 * g12
    p = np.sqrt((d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * off) / 6.0)
    # det(G - mean I) / (2 p^3) is the cosine of 3 phi; p = 0 means G = mean * I.
    det_shift = d0 * (d1 * d2 - g12 * g12) - g01 * (g01 * d2 - g12 * g02) + g02 * (g01 * g12 - d1 * g02)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(p > 0.0, det_shift / (2.0 * p * p * p), 0.0)
    phi = np.arccos(np.clip(r, -1.0, 1.0)) / 3.0
    lam1 = mean + 2.0 * p * np.cos(phi)
    lam3 = mean + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0)
    lam2 = 3.0 * mean - lam1 - lam3
    s1 = np.sqrt(np.maximum(lam1, 0.0))
    s2 = np.sqrt(np.clip(lam2, 0.0, lam1))
    det = np.abs(np.einsum("...i,...i->...", c0, np.cross(c1, c2)))
    with np.errstate(divide="ignore", invalid="ignore"):
        s3 = np.where(s2 > 0.0, det / (s1 * s2), 0.0)
    s3 = np.minimum(s3, s2)
    sv = np.stack([s1, s2, s3], axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        hard = ~(s1 <= FAST_COND_LIMIT * s3)      # also catches s3 = 0 and nan
    if np.any(hard):
        sv[hard] = np.linalg.svd(a[hard], compute_uv=False)
    return sv


def inverse_transpose(jac: ArrayLike) -> tuple[FloatArray, np.ndarray]:
    """``J^-T`` of square matrices ``(..., n, n)`` and a mask of where it exists.

    2 x 2 and 3 x 3 use the cofactor matrix (``J^-T = cof(J) / det J``), whose columns for
    3 x 3 are cross products of *Jacobian columns*, never of nearly parallel reference forces.
    Where the Frobenius condition estimate ``|J|_F |J^-1|_F`` exceeds ``FAST_COND_LIMIT``,
    the inverse comes from LAPACK's SVD instead (``U diag(1/sigma) V^T``), which raises for
    nothing. Singular or non-finite matrices give ``nan`` and ``False`` in the mask.
    """
    jac = as_jacobian(jac)
    m, n = jac.shape[-2:]
    if m != n:
        raise ValueError(f"jac must be square (..., n, n) for an inverse, got {jac.shape}")
    finite = np.all(np.isfinite(jac), axis=(-2, -1))
    safe = np.where(finite[..., None, None], jac, 0.0)
    if n == 2:
        cof = np.stack([np.stack([safe[..., 1, 1], -safe[..., 1, 0]], -1),
                        np.stack([-safe[..., 0, 1], safe[..., 0, 0]], -1)], -2)
    elif n == 3:
        c0, c1, c2 = safe[..., :, 0], safe[..., :, 1], safe[..., :, 2]
        cof = np.stack([np.cross(c1, c2), np.cross(c2, c0), np.cross(c0, c1)], axis=-1)
    else:
        cof = None
    out = np.full(jac.shape, np.nan)
    if cof is not None:
        det = np.einsum("...ij,...ij->...", safe[..., :, :1], cof[..., :, :1])
        with np.errstate(divide="ignore", invalid="ignore"):
            fro_cond = np.sqrt(np.sum(safe * safe, axis=(-2, -1)) * np.sum(cof * cof, axis=(-2, -1))) / np.abs(det)
            easy = finite & (fro_cond <= FAST_COND_LIMIT)
            out = np.where(easy[..., None, None], cof / det[..., None, None], np.nan)
        hard = finite & ~easy
    else:
        hard = finite
    ok = np.array(finite)   # an array even for one unbatched matrix (a numpy bool cannot be assigned into)
    if np.any(hard):
        u, s, vt = np.linalg.svd(safe[hard])
        good = s[..., -1] > 0.0
        with np.errstate(divide="ignore"):
            inv_t = np.einsum("kij,kj,kjl->kil", u, 1.0 / s, vt)
        inv_t[~good] = np.nan
        out[hard] = inv_t
        sub = ok[hard]
        sub &= good
        ok[hard] = sub
    return out, ok
