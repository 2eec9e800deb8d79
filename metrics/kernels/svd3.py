"""A 3 x 3 J's conditioning (condition number, its inverse, manipulability), compiled, near a repeated value too.

``square3.singular_values3`` takes the Gram matrix's trigonometric eigenvalues, as ``linalg._sv_3x3``
does; near a repeated eigenvalue (``|r| > 1 - 1e-3``) its ``arccos`` loses digits, and the point was
handed back to the numpy path, which calls LAPACK's SVD there. Those points are not hard: on the
1000 x 1000 Inverse3 map all 942 handed-back points had ``kappa < 4``, and on the PHANToM's map 4172 of
4486; the numpy path's fixed cost per call (its quantity graph, in Python, once per chunk) then
took 20-100 ms of ``isoforce stats``. ``conditioning3`` takes them here with one-sided (Hestenes) Jacobi on J's columns:

=============================  ===============================================  ==========================
case                           singular values                                  error
=============================  ===============================================  ==========================
``|r| <= 1 - 1e-3``, regular   ``singular_values3`` (the numpy path's formula)  ``square3``'s table
near a repeated eigenvalue,    column norms after plane rotations that make     ``(6 R + 3) eps |J|_F``
``kappa <= FAST_COND_LIMIT``   J's columns orthogonal (``_hestenes3``)          absolute, R rotations
``kappa > FAST_COND_LIMIT``,   handed back (LAPACK in the numpy path, its        exact: numpy's
off ``SAFE_SCALE``, not        labels and limits)
finite, not converged
=============================  ===============================================  ==========================

Each rotation is an exact orthogonal transformation of the columns up to rounding (at most ``6 eps`` of
``|J|_F`` per rotation: its cosine and sine within 3 ulps of an orthogonal pair, the update's products
and sum; Demmel and Veselic 1992), so the computed values are the singular values of a matrix within
``6 R eps |J|_F`` of J (Weyl), and the norms add ``3 eps`` relative. The ``R`` of a 3 x 3 matrix is a
few sweeps of three rotations (quadratic convergence); ``SWEEPS`` sweeps without converging hand the
point back (``tests/metrics/test_kernel_svd3.py`` checks the bound against LAPACK).

References
----------
Demmel and Veselic, "Jacobi's method is more accurate than QR", SIAM J. Matrix Anal. Appl. 13 (1992).
"""
from __future__ import annotations

import math

import numpy as np

from metrics.linalg import FAST_COND_LIMIT, SAFE_SCALE

from .jit import jit
from .square3 import singular_values3, write_conditioning3

EPS = 2.220446049250313e-16
#: Sweeps (three rotations each) after which ``_hestenes3`` gives up and the point is handed back.
SWEEPS = 12
_FRO_LO, _FRO_HI = SAFE_SCALE[0] ** 2, SAFE_SCALE[1] ** 2


@jit()
def _rotation(alpha, beta, gamma):
    """``(c, s)`` of the plane rotation that makes two columns orthogonal: ``alpha``, ``beta`` their squared
    norms, ``gamma`` their inner product (nonzero). Rutishauser's form, the smaller angle."""
    zeta = (beta - alpha) / (2.0 * gamma)
    if abs(zeta) > 1e150:           # zeta^2 would overflow: t = 1 / (2 zeta) to working precision
        t = 0.5 / zeta
    else:
        t = math.copysign(1.0, zeta) / (abs(zeta) + math.sqrt(zeta * zeta + 1.0))
    c = 1.0 / math.sqrt(t * t + 1.0)
    return c, c * t


@jit()
def _hestenes3(a00, a01, a02, a10, a11, a12, a20, a21, a22):
    """``(converged, s1, s2, s3, rotations)``: J's singular values, descending, by one-sided Jacobi.

    Columns ``p``, ``q`` are rotated while ``|c_p . c_q| > eps |c_p| |c_q|``; once no pair is (a
    sweep without a rotation) the columns are orthogonal to working precision and their norms are
    the singular values.
    """
    # Columns 0, 1, 2 as (x, y, z) triples.
    x0, y0, z0 = a00, a10, a20
    x1, y1, z1 = a01, a11, a21
    x2, y2, z2 = a02, a12, a22
    rotations = 0
    for _ in range(SWEEPS):
        turned = False
        # (0, 1)
        alpha, beta = x0 * x0 + y0 * y0 + z0 * z0, x1 * x1 + y1 * y1 + z1 * z1
        gamma = x0 * x1 + y0 * y1 + z0 * z1
        if abs(gamma) > EPS * math.sqrt(alpha * beta):
            c, s = _rotation(alpha, beta, gamma)
            x0, x1 = c * x0 - s * x1, s * x0 + c * x1
            y0, y1 = c * y0 - s * y1, s * y0 + c * y1
            z0, z1 = c * z0 - s * z1, s * z0 + c * z1
            turned, rotations = True, rotations + 1
        # (0, 2)
        alpha, beta = x0 * x0 + y0 * y0 + z0 * z0, x2 * x2 + y2 * y2 + z2 * z2
        gamma = x0 * x2 + y0 * y2 + z0 * z2
        if abs(gamma) > EPS * math.sqrt(alpha * beta):
            c, s = _rotation(alpha, beta, gamma)
            x0, x2 = c * x0 - s * x2, s * x0 + c * x2
            y0, y2 = c * y0 - s * y2, s * y0 + c * y2
            z0, z2 = c * z0 - s * z2, s * z0 + c * z2
            turned, rotations = True, rotations + 1
        # (1, 2)
        alpha, beta = x1 * x1 + y1 * y1 + z1 * z1, x2 * x2 + y2 * y2 + z2 * z2
        gamma = x1 * x2 + y1 * y2 + z1 * z2
        if abs(gamma) > EPS * math.sqrt(alpha * beta):
            c, s = _rotation(alpha, beta, gamma)
            x1, x2 = c * x1 - s * x2, s * x1 + c * x2
            y1, y2 = c * y1 - s * y2, s * y1 + c * y2
            z1, z2 = c * z1 - s * z2, s * z1 + c * z2
            turned, rotations = True, rotations + 1
        if not turned:
            n0 = math.sqrt(x0 * x0 + y0 * y0 + z0 * z0)
            n1 = math.sqrt(x1 * x1 + y1 * y1 + z1 * z1)
            n2 = math.sqrt(x2 * x2 + y2 * y2 + z2 * z2)
            hi, lo = max(n0, n1), min(n0, n1)                # sorted, descending
            return True, max(hi, n2), max(lo, min(hi, n2)), min(lo, n2), rotations
    return False, 0.0, 0.0, 0.0, rotations


@jit()
def settle3(a00, a01, a02, a10, a11, a12, a20, a21, a22, s1, s2, s3, hard):
    """``singular_values_any3`` after ``singular_values3`` gave ``(s1, s2, s3, hard)``: those, or
    ``_hestenes3``'s where they are hard only for a near-repeated eigenvalue; ``hard``: hand the point back."""
    if not hard:
        return s1, s2, s3, False
    fro = a00 * a00 + a01 * a01 + a02 * a02 + a10 * a10 + a11 * a11 + a12 * a12 + a20 * a20 + a21 * a21 + a22 * a22
    if not (fro > _FRO_LO and fro < _FRO_HI):
        return s1, s2, s3, True     # far from unit scale: the numpy path rescales
    ok, s1, s2, s3, _ = _hestenes3(a00, a01, a02, a10, a11, a12, a20, a21, a22)
    return s1, s2, s3, not (ok and s1 <= FAST_COND_LIMIT * s3)


@jit(inline=True)
def singular_values_any3(a00, a01, a02, a10, a11, a12, a20, a21, a22):
    """``(s1, s2, s3, hard)`` of a finite 3 x 3 matrix: ``singular_values3``, or ``_hestenes3`` where that
    is hard only for a near-repeated eigenvalue (module docstring); ``hard``: hand the point back."""
    s1, s2, s3, hard = singular_values3(a00, a01, a02, a10, a11, a12, a20, a21, a22)
    return settle3(a00, a01, a02, a10, a11, a12, a20, a21, a22, s1, s2, s3, hard)


@jit()
def finite3(a00, a01, a02, a10, a11, a12, a20, a21, a22):
    """Whether every entry of a 3 x 3 matrix is finite."""
    return (math.isfinite(a00) and math.isfinite(a01) and math.isfinite(a02) and math.isfinite(a10)
            and math.isfinite(a11) and math.isfinite(a12) and math.isfinite(a20) and math.isfinite(a21)
            and math.isfinite(a22))


@jit()
def conditioning3(a00, a01, a02, a10, a11, a12, a20, a21, a22, out, i):
    """Point ``i``'s condition number, its inverse and the manipulability into ``out[0:3, i]``
    (``square3.COLUMNS``); True to hand the point back (not finite, or ``singular_values_any3`` hard).

    The family kernels call it before ``square3.quantities3`` with ``want_sv`` off: the same columns,
    the same order of hand-back decisions. (``inverse3`` takes its steps a block of points at a time:
    ``finite3``, ``square3.gram_shift3`` ... ``eigen_finish3``, ``settle3``, ``square3.write_conditioning3``.)
    """
    if not finite3(a00, a01, a02, a10, a11, a12, a20, a21, a22):
        return True
    s1, s2, s3, hard = singular_values_any3(a00, a01, a02, a10, a11, a12, a20, a21, a22)
    if hard:
        return True
    write_conditioning3(s1, s2, s3, out, i)
    return False


def hestenes_points(mats):
    """``_hestenes3`` over matrices (k, 3, 3), for tests: ``(converged (k,), values (k, 3), rotations (k,))``.

    Parameters
    ----------
    mats : ndarray, shape (k, 3, 3)

    Returns
    -------
    converged : ndarray of bool, shape (k,)
    values : ndarray, shape (k, 3)
        Descending.
    rotations : ndarray of int64, shape (k,)
    """
    mats = np.ascontiguousarray(mats, dtype=np.float64)
    converged, values, rotations = np.empty(len(mats), bool), np.empty((len(mats), 3)), np.empty(len(mats), np.int64)
    _hestenes_loop(mats, converged, values, rotations)
    return converged, values, rotations


@jit()
def _hestenes_loop(mats, converged, values, rotations):
    for k in range(mats.shape[0]):
        m = mats[k]
        ok, s1, s2, s3, r = _hestenes3(m[0, 0], m[0, 1], m[0, 2], m[1, 0], m[1, 1], m[1, 2], m[2, 0], m[2, 1],
                                       m[2, 2])
        converged[k], rotations[k] = ok, r
        values[k, 0], values[k, 1], values[k, 2] = s1, s2, s3
