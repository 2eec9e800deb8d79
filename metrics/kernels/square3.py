"""The force and conditioning quantities of one square 3 x 3 Jacobian, compiled, in scalars.

The same formulas in the same order as the numpy kernels they stand for, so that a point
differs from them only by the last bits of ``acos``/``cos`` (libm here, numpy's own loops
there; the Inverse3 kernel takes the two cosines as a cube root instead, ``third_cosines3``,
within 3 eps of the exact ones as libm's are):

=========================  ===================================================  =====================
quantity                   formula (numpy kernel)                               hand back to numpy
=========================  ===================================================  =====================
singular values            Gram matrix's trigonometric eigenvalues, sigma_3     kappa > 100, a near-
                           from ``|det| / (sigma_1 sigma_2)`` (``linalg``)      repeated eigenvalue,
                                                                                sigma_1 off SAFE_SCALE
condition number,          ``s1 / s3``, its inverse, ``s1 s2 s3``
inverse, manipulability    (``conditioning``)
column norms, isotropic    ``sqrt(sum a_ku^2)``, ``min_u t_u / |J[:, u]|``,    a sum of squares off
force, bottleneck,         ties within ``(n + 4) eps``, ``max_u |J[:, u]|      SAFE_SUM_SQ, a
spatial resolution         delta_u`` (``columns``, ``isotropy``,                negligible column
                           ``bottleneck``, ``resolution``)
reference forces,          ``cof(J) / det * t``; ``max_s sqrt(s^T R^T R s)``    Frobenius condition
anisotropic force          (``linalg.inverse_transpose``, ``anisotropy``)       > 100, off SAFE_SCALE
=========================  ===================================================  =====================

A point the right column names is *handed back*: ``fallback`` is set and the caller recomputes
it with the numpy kernels (LAPACK, power-of-two rescaling, singular labels), which are the
reference for every hard case: so hard and singular points get exactly the numpy path's values
and labels, and only regular, unit-scale points, where the closed forms are accurate to a few
ulps, are computed here.
"""
from __future__ import annotations

import math

from metrics.columns import SAFE_SUM_SQ
from metrics.linalg import FAST_COND_LIMIT, SAFE_SCALE

from .jit import jit

EPS = 2.220446049250313e-16
#: Value columns of the kernels' output, in this order.
COLUMNS = ("condition_number", "inverse_condition_number", "manipulability", "isotropic_force", "anisotropic_force",
           "spatial_resolution")
_SCALE_LO, _SCALE_HI = SAFE_SCALE
_SUM_LO, _SUM_HI = SAFE_SUM_SQ
_FRO_LO, _FRO_HI = SAFE_SCALE[0] ** 2, SAFE_SCALE[1] ** 2
#: A third of a turn: the trigonometric form's second and third angles are ``phi`` plus it and minus it.
THIRD_TURN = _THIRD_TURN = 2.0 * math.pi / 3.0
_TIE = 1.0 + (3 + 4) * EPS           # bottleneck.tie_tolerance(3)


@jit(inline=True)
def blank(i, feasible, joints, out, bottleneck, singularity, values):
    """Point ``i`` as an infeasible one: False, ``nan`` joints (and values if ``values``: a streamed
    map reads no infeasible point's, so its kernels leave them as they are), class -1 (``evaluate``'s marks)."""
    feasible[i] = False
    for j in range(joints.shape[1]):
        joints[i, j] = math.nan
    if values:
        for c in range(out.shape[0]):
            out[c, i] = math.nan
    bottleneck[i] = -1
    singularity[i] = -1


@jit(inline=True)
def gram_shift3(a00, a01, a02, a10, a11, a12, a20, a21, a22):
    """``(mean, p, r, det)`` of a finite 3 x 3 matrix: ``singular_values3``'s arithmetic before its arccos.

    The Gram matrix's mean eigenvalue, the scale ``p`` and the cosine ``r`` of three times the angle of
    the trigonometric form (unclamped), and ``|det|``. Apart so that a kernel can take the cosines of a
    block of points its own way (``inverse3``, ``third_cosines3``): the same operations, the same bits.
    """
    g00 = a00 * a00 + a10 * a10 + a20 * a20
    g01 = a00 * a01 + a10 * a11 + a20 * a21
    g02 = a00 * a02 + a10 * a12 + a20 * a22
    g11 = a01 * a01 + a11 * a11 + a21 * a21
    g12 = a01 * a02 + a11 * a12 + a21 * a22
    g22 = a02 * a02 + a12 * a12 + a22 * a22
    mean = (g00 + g11 + g22) / 3.0
    d0, d1, d2 = g00 - mean, g11 - mean, g22 - mean
    p = math.sqrt((d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * (g01 * g01 + g02 * g02 + g12 * g12)) / 6.0)
    det_shift = d0 * (d1 * d2 - g12 * g12) - g01 * (g01 * d2 - g12 * g02) + g02 * (g01 * g12 - d1 * g02)
    r = det_shift / (2.0 * p * p * p) if p > 0.0 else 0.0
    det = abs(a00 * (a11 * a22 - a12 * a21) - a01 * (a10 * a22 - a12 * a20) + a02 * (a10 * a21 - a11 * a20))
    return mean, p, r, det


@jit()
def third_angle(r):
    """The trigonometric form's angle ``arccos(r) / 3``, ``r`` clamped to [-1, 1]."""
    return math.acos(min(max(r, -1.0), 1.0)) / 3.0


#: ``sqrt(3) / 2``: ``cos(phi + 2 pi / 3) = -cos(phi) / 2 - SIN_THIRD sin(phi)``.
SIN_THIRD = math.sqrt(3.0) / 2.0


@jit(inline=True)
def _halley_cube_root(a, b, zr, zi):
    """One Halley step towards the cube root of ``z = zr + i zi`` from ``w = a + i b``:
    ``w (w^3 + 2 z) / (2 w^3 + z)``, in real arithmetic (one division)."""
    a2, b2 = a * a - b * b, 2.0 * a * b
    a3, b3 = a2 * a - b2 * b, a2 * b + b2 * a
    nr, ni = a3 + 2.0 * zr, b3 + 2.0 * zi
    dr, di = 2.0 * a3 + zr, 2.0 * b3 + zi
    inv = 1.0 / (dr * dr + di * di)
    qr, qi = (nr * dr + ni * di) * inv, (ni * dr - nr * di) * inv
    return a * qr - b * qi, a * qi + b * qr


@jit(inline=True)
def third_cosines3(r):
    """``(cos phi, cos(phi + 2 pi / 3))`` for ``phi = arccos(r) / 3`` (``r`` clamped to [-1, 1]), without libm.

    ``third_angle``'s angle and its two cosines (the trigonometric eigenvalues' ``cos_first``,
    ``cos_third``, ``eigen_finish3``), taken as ``w = e^(i phi)``, the cube root of
    ``z = e^(i theta) = r + i sqrt((1 - r)(1 + r))`` with argument in [0, pi / 3]: square roots,
    products and three divisions, no branch, so a loop over a block of points runs them in vector
    registers (``inverse3``: 2.5 ms for 375k points against 12.5 ms for ``acos`` and two ``cos``).

    Start: ``eta = e^(i theta / 2) = sqrt((1 + r) / 2) + i sqrt((1 - r) / 2)``, and ``w0`` the unit
    vector of ``1 + 2 eta``, whose argument is within 0.060 rad of ``theta / 3`` over ``theta`` in
    [0, pi] (largest at ``theta = pi``: ``atan(2)`` against ``pi / 3``). Halley's step for
    ``w^3 = z`` takes an error ``e`` to ``(2 / 3) e^3 (1 + O(e))`` (``|w| = 1``): 0.060, 1.7e-4, 4e-12,
    5e-35, so three steps leave only rounding. ``z`` is within 2 eps of ``e^(i theta)`` for the
    clamped ``r`` (``(1 - r)``, ``(1 + r)`` round by at most half an ulp, one of them exactly), a cube
    root's error a third of that, and the last step rounds ``w`` by a few eps: both cosines are within
    3 eps of the exact ones (``tests/metrics/test_kernel_svd3.py``, against mpmath), as libm's ``acos``
    and ``cos`` of the rounded angle give them. The cube root is well conditioned wherever ``r`` lies
    (``|dw / dz| = 1 / 3``), where ``arccos`` is not at ``r = +-1``: the two forms differ there by
    the rounding of the angle that the trigonometric form carries.
    """
    x = min(max(r, -1.0), 1.0)
    zr, zi = x, math.sqrt((1.0 - x) * (1.0 + x))
    a = 1.0 + 2.0 * math.sqrt(0.5 * (1.0 + x))
    b = 2.0 * math.sqrt(0.5 * (1.0 - x))
    scale = 1.0 / math.sqrt(a * a + b * b)
    a, b = a * scale, b * scale
    a, b = _halley_cube_root(a, b, zr, zi)
    a, b = _halley_cube_root(a, b, zr, zi)
    a, b = _halley_cube_root(a, b, zr, zi)
    return a, -0.5 * a - SIN_THIRD * b


@jit(inline=True)
def eigen_finish3(mean, p, r, det, cos_first, cos_third):
    """``(s1, s2, s3, hard)`` from ``gram_shift3`` and the cosines of the angle and of the angle plus
    a third of a turn (``third_angle``): ``singular_values3``'s arithmetic after its cosines."""
    lam1 = mean + 2.0 * p * cos_first
    lam3 = mean + 2.0 * p * cos_third
    lam2 = 3.0 * mean - lam1 - lam3
    s1 = math.sqrt(max(lam1, 0.0))
    s2 = math.sqrt(min(max(lam2, 0.0), lam1))
    s3 = det / (s1 * s2) if s2 > 0.0 else 0.0
    s3 = min(s3, s2)
    hard = not (s1 <= FAST_COND_LIMIT * s3) or abs(r) > 1.0 - 1e-3
    hard = hard or not (s1 > _SCALE_LO and s1 < _SCALE_HI)
    return s1, s2, s3, hard


@jit(inline=True)
def conditioning_of3(s1, s2, s3):
    """``(condition number, its inverse, manipulability)`` from the singular values, without a branch
    (``inverse3`` takes them in a loop over a block's points, its divisions in vector registers)."""
    cond = s1 / s3 if s3 > 3 * EPS * s1 else math.inf
    return cond, 1.0 / cond, s1 * s2 * s3


@jit()
def write_conditioning3(s1, s2, s3, out, i):
    """Point ``i``'s condition number, its inverse and the manipulability from its singular values."""
    cond, inverse, manipulability = conditioning_of3(s1, s2, s3)
    out[0, i] = cond
    out[1, i] = inverse
    out[2, i] = manipulability


@jit()
def singular_values3(a00, a01, a02, a10, a11, a12, a20, a21, a22):
    """``(s1, s2, s3, hard)`` of a finite 3 x 3 matrix: ``linalg._sv_3x3``'s closed form."""
    mean, p, r, det = gram_shift3(a00, a01, a02, a10, a11, a12, a20, a21, a22)
    phi = third_angle(r)
    return eigen_finish3(mean, p, r, det, math.cos(phi), math.cos(phi + _THIRD_TURN))


@jit(inline=True)
def columns3(a00, a01, a02, a10, a11, a12, a20, a21, a22, t0, t1, t2, steps):
    """``(spatial resolution, ok, isotropic force, bottleneck)`` of a finite 3 x 3 J: ``quantities3``'s column
    norms' quantities, without a branch (as ``anisotropy3``); ``ok`` False: hand the point back."""
    c0 = a00 * a00 + a10 * a10 + a20 * a20
    c1 = a01 * a01 + a11 * a11 + a21 * a21
    c2 = a02 * a02 + a12 * a12 + a22 * a22
    # resolution.spatial_resolution: max_u |J[:, u]| delta_u, the sums formed as given.
    resolution = max(max(math.sqrt(c0) * steps[0], math.sqrt(c1) * steps[1]), math.sqrt(c2) * steps[2])
    ok = (c0 > _SUM_LO) & (c0 < _SUM_HI) & (c1 > _SUM_LO) & (c1 < _SUM_HI) & (c2 > _SUM_LO) & (c2 < _SUM_HI)
    n0, n1, n2 = math.sqrt(c0), math.sqrt(c1), math.sqrt(c2)
    level = (3 * EPS) * max(max(n0, n1), n2)
    ok = ok & (n0 > level) & (n1 > level) & (n2 > level)
    d0, d1, d2 = t0 / n0, t1 / n1, t2 / n2
    iso = min(min(d0, d1), d2)
    tie = iso * _TIE
    count = (d0 <= tie) + (d1 <= tie) + (d2 <= tie)
    neck = -2 if count > 1 else (d1 <= tie) + 2 * (d2 <= tie)
    return resolution, ok, iso, neck


@jit(inline=True)
def anisotropy3(a00, a01, a02, a10, a11, a12, a20, a21, a22, t0, t1, t2):
    """``(ok, anisotropic force)`` of a finite 3 x 3 J and torque limits ``t0, t1, t2``; ``ok`` False: hand it back.

    ``quantities3``'s reference forces and anisotropic force, without a branch: every step runs whatever
    the checks say (they are combined at the end), so in a loop over a block of points (``inverse3``)
    consecutive points' divisions and square roots overlap, with the same operations, so the same bits,
    as one point taken alone.
    """
    # Cofactor columns: cross products of J's columns (linalg._cofactors).
    f00 = a11 * a22 - a21 * a12
    f10 = a21 * a02 - a01 * a22
    f20 = a01 * a12 - a11 * a02
    f01 = a12 * a20 - a22 * a10
    f11 = a22 * a00 - a02 * a20
    f21 = a02 * a10 - a12 * a00
    f02 = a10 * a21 - a20 * a11
    f12 = a20 * a01 - a00 * a21
    f22 = a00 * a11 - a10 * a01
    det = a00 * f00
    det = det + a10 * f10
    det = det + a20 * f20
    fro = (a00 * a00 + a01 * a01 + a02 * a02 + a10 * a10 + a11 * a11 + a12 * a12
           + a20 * a20 + a21 * a21 + a22 * a22)
    ok = (fro > _FRO_LO) & (fro < _FRO_HI)
    cof = (f00 * f00 + f01 * f01 + f02 * f02 + f10 * f10 + f11 * f11 + f12 * f12
           + f20 * f20 + f21 * f21 + f22 * f22)
    ok = ok & (math.sqrt(fro * cof) / abs(det) <= FAST_COND_LIMIT)
    # R = J^-T diag(t): R[i, u] = cof[i, u] / det * t_u.
    r00, r10, r20 = f00 / det * t0, f10 / det * t0, f20 / det * t0
    r01, r11, r21 = f01 / det * t1, f11 / det * t1, f21 / det * t1
    r02, r12, r22 = f02 / det * t2, f12 / det * t2, f22 / det * t2
    g00 = r00 * r00 + r10 * r10 + r20 * r20
    g11 = r01 * r01 + r11 * r11 + r21 * r21
    g22 = r02 * r02 + r12 * r12 + r22 * r22
    g01 = r00 * r01 + r10 * r11 + r20 * r21
    g02 = r00 * r02 + r10 * r12 + r20 * r22
    g12 = r01 * r02 + r11 * r12 + r21 * r22
    diagonal = g00 + g11 + g22
    ok = ok & (diagonal > _SUM_LO) & (diagonal < _SUM_HI)
    # |R s|^2 over one sign vector of each +- pair, (+++), (++-), (+-+), (+--) (anisotropy).
    best = 0.0
    best = max(best, diagonal + 2.0 * g01 + 2.0 * g02 + 2.0 * g12)
    best = max(best, diagonal + 2.0 * g01 - 2.0 * g02 - 2.0 * g12)
    best = max(best, diagonal - 2.0 * g01 + 2.0 * g02 - 2.0 * g12)
    best = max(best, diagonal - 2.0 * g01 - 2.0 * g02 + 2.0 * g12)
    return ok, math.sqrt(best)


@jit()
def quantities3(a00, a01, a02, a10, a11, a12, a20, a21, a22, t, steps, out, bottleneck, i,
                want_sv, want_columns, want_vertices):
    """Write point ``i``'s quantities into ``out[COLUMNS, i]`` and ``bottleneck[i]``; True to hand it back.

    ``want_*`` leave out the branches nobody asked for (a quantity nobody asked for costs nothing).
    """
    if not (math.isfinite(a00) and math.isfinite(a01) and math.isfinite(a02) and math.isfinite(a10)
            and math.isfinite(a11) and math.isfinite(a12) and math.isfinite(a20) and math.isfinite(a21)
            and math.isfinite(a22)):
        return True
    if want_sv:
        s1, s2, s3, hard = singular_values3(a00, a01, a02, a10, a11, a12, a20, a21, a22)
        if hard:
            return True
        write_conditioning3(s1, s2, s3, out, i)
    t0, t1, t2 = t[0], t[1], t[2]
    if want_columns:
        resolution, ok, iso, neck = columns3(a00, a01, a02, a10, a11, a12, a20, a21, a22, t0, t1, t2, steps)
        out[5, i] = resolution
        if not ok:
            return True
        out[3, i] = iso
        bottleneck[i] = neck
    if want_vertices:
        ok, value = anisotropy3(a00, a01, a02, a10, a11, a12, a20, a21, a22, t0, t1, t2)
        if not ok:
            return True
        out[4, i] = value
    return False
