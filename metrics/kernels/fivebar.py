"""The planar five-bar family (``kinematics.fivebar``) in one compiled pass: IK, limits, classes, J, quantities.

Each point follows ``FiveBar.inverse``, ``feasible``, ``singularity`` and ``jacobian`` operation for
operation, then the 2 x 2 quantities (``linalg._sv_2x2``, ``columns``, ``isotropy``,
``bottleneck``, ``linalg.inverse_transpose``, ``anisotropy``). A pose the model classes singular
(inverse, direct or both) is handed back to the numpy path, which gives J its exact singular
limit and the class its label; so is every case ``square3``'s table hands back (an inverse's
Frobenius condition above 100, sums of squares off the safe range, a negligible column).
"""
from __future__ import annotations

import math

import numpy as np
from numba import prange

from metrics.columns import SAFE_SUM_SQ
from metrics.linalg import FAST_COND_LIMIT, SAFE_SCALE

from .dynamics import dynamics2, velocity2
from .fivebar_mass import inertia, pack_mass  # noqa: F401  (pack_mass: FusedKernel reads it here)
from .jit import jit, twins
from .square3 import blank

EPS = 2.220446049250313e-16
_EPS8 = 8 * EPS
_SCALE_LO, _SCALE_HI = SAFE_SCALE
_SUM_LO, _SUM_HI = SAFE_SUM_SQ
_FRO_LO, _FRO_HI = SAFE_SCALE[0] ** 2, SAFE_SCALE[1] ** 2
_TIE = 1.0 + (2 + 4) * EPS           # bottleneck.tie_tolerance(2)

def pack(mechanism) -> np.ndarray:
    """The model's parameters as the kernel reads them, float64 (11,).

    Parameters
    ----------
    mechanism : FiveBar
        The model.

    Returns
    -------
    ndarray, shape (11,)
        a1, a2, a3, the working mode's two signs, the singular tolerance, whether there are joint
        limits, and the limits (lo1, hi1, lo2, hi2).
    """
    p = mechanism.params
    limits = p.joint_limits if p.joint_limits is not None else ((0.0, 0.0), (0.0, 0.0))
    return np.array([p.proximal, p.distal, p.half_base, 1.0 if p.working_mode[0] == "+" else -1.0,
                     1.0 if p.working_mode[1] == "+" else -1.0, mechanism.singular_tolerance,
                     float(p.joint_limits is not None), limits[0][0], limits[0][1], limits[1][0], limits[1][1]],
                    dtype=np.float64)


@jit(inline=True)
def _point(x, par, t, steps, i, feasible, joints, out, bottleneck, singularity,
           want_sv, want_columns, want_vertices,
           mp, want_mass, want_acceleration, speeds, want_velocity, fill):
    """Point ``i``: True to hand it back to the numpy path. Every output starts infeasible (``blank``; its
    value rows only with ``fill``)."""
    blank(i, feasible, joints, out, bottleneck, singularity, fill)
    x0, x1 = x[i, 0], x[i, 1]
    if not (math.isfinite(x0) and math.isfinite(x1)):
        return True
    a1, a2, a3 = par[0], par[1], par[2]
    # -- FiveBar.inverse (bases at (-a3, 0) and (a3, 0))
    d00, d01 = x0 - (-a3), x1 - 0.0
    d10, d11 = x0 - a3, x1 - 0.0
    rho0, rho1 = math.hypot(d00, d01), math.hypot(d10, d11)
    if rho0 == 0.0 or rho1 == 0.0:
        return True
    cos0 = (a1 * a1 + rho0 * rho0 - a2 * a2) / (2.0 * a1 * rho0)
    cos1 = (a1 * a1 + rho1 * rho1 - a2 * a2) / (2.0 * a1 * rho1)
    if not (abs(cos0) <= 1.0 + _EPS8 and abs(cos1) <= 1.0 + _EPS8):
        return False
    q0 = math.atan2(d01, d00) + par[3] * math.acos(min(max(cos0, -1.0), 1.0))
    q1 = math.atan2(d11, d10) + par[4] * math.acos(min(max(cos1, -1.0), 1.0))
    # -- FiveBar.feasible
    if not (math.isfinite(q0) and math.isfinite(q1)):
        return False
    if par[6] != 0.0 and not (q0 >= par[7] and q0 <= par[8] and q1 >= par[9] and q1 <= par[10]):
        return False
    feasible[i] = True
    joints[i, 0], joints[i, 1] = q0, q1
    # -- FiveBar._singular_parts: distal links C - B_i, jtheta_i, det J_p
    c0, s0, c1, s1 = math.cos(q0), math.sin(q0), math.cos(q1), math.sin(q1)
    p00, p01 = x0 - (-a3 + a1 * c0), x1 - (0.0 + a1 * s0)
    p10, p11 = x0 - (a3 + a1 * c1), x1 - (0.0 + a1 * s1)
    jt0 = a1 * (p00 * -s0 + p01 * c0)
    jt1 = a1 * (p10 * -s1 + p11 * c1)
    det = p00 * p11 - p01 * p10
    tol = par[5]
    if abs(jt0) <= tol * a1 * a2 or abs(jt1) <= tol * a1 * a2 or abs(det) <= tol * a2 * a2:
        return True                  # singular: the numpy path's exact limit and label
    singularity[i] = 0
    # -- FiveBar.jacobian: J = adj(J_p) diag(jtheta) / det
    a00 = p11 * jt0 / det + 0.0
    a01 = -p01 * jt1 / det + 0.0
    a10 = -p10 * jt0 / det + 0.0
    a11 = p00 * jt1 / det + 0.0
    if not (math.isfinite(a00) and math.isfinite(a01) and math.isfinite(a10) and math.isfinite(a11)):
        return True
    if want_sv:
        big = 0.5 * (math.hypot(a00 + a11, a01 - a10) + math.hypot(a00 - a11, a01 + a10))
        if not (big > _SCALE_LO and big < _SCALE_HI):
            return True
        small = min(abs(a00 * a11 - a01 * a10) / big, big)
        if not (small > 2 * EPS * big):
            return True
        cond = big / small
        out[0, i] = cond
        out[1, i] = 1.0 / cond
        out[2, i] = big * small
    if want_columns:
        n0sq = a00 * a00 + a10 * a10
        n1sq = a01 * a01 + a11 * a11
        out[5, i] = max(math.sqrt(n0sq) * steps[0], math.sqrt(n1sq) * steps[1])
        if not (n0sq > _SUM_LO and n0sq < _SUM_HI and n1sq > _SUM_LO and n1sq < _SUM_HI):
            return True
        n0, n1 = math.sqrt(n0sq), math.sqrt(n1sq)
        level = (2 * EPS) * max(n0, n1)
        if n0 <= level or n1 <= level:
            return True
        f0, f1 = t[0] / n0, t[1] / n1
        iso = min(f0, f1)
        out[3, i] = iso
        tie = iso * _TIE
        bottleneck[i] = -2 if (f0 <= tie) and (f1 <= tie) else (f1 <= tie)
    if want_vertices:
        # linalg._cofactors (2 x 2) and the determinant as inverse_transpose forms it.
        f00, f01, f10, f11 = a11, -a10, -a01, a00
        dj = a00 * f00
        dj = dj + a10 * f10
        fro = a00 * a00 + a01 * a01 + a10 * a10 + a11 * a11
        if not (fro > _FRO_LO and fro < _FRO_HI):
            return True
        cof = f00 * f00 + f01 * f01 + f10 * f10 + f11 * f11
        if not (math.sqrt(fro * cof) / abs(dj) <= FAST_COND_LIMIT):
            return True
        r00, r10 = f00 / dj * t[0], f10 / dj * t[0]
        r01, r11 = f01 / dj * t[1], f11 / dj * t[1]
        g00 = r00 * r00 + r10 * r10
        g11 = r01 * r01 + r11 * r11
        g01 = r00 * r01 + r10 * r11
        diagonal = g00 + g11
        if not (diagonal > _SUM_LO and diagonal < _SUM_HI):
            return True
        best = max(0.0, diagonal + 2.0 * g01)
        best = max(best, diagonal - 2.0 * g01)
        out[4, i] = math.sqrt(best)
    if want_velocity and velocity2(a00, a01, a10, a11, speeds, out, i):
        return True
    if not (want_mass or want_acceleration):
        return False
    k = inertia(x0, x1, q0, q1, a00, a01, a10, a11, mp)
    return dynamics2(k[0], k[1], k[2], a00, a01, a10, a11, t, out, i, want_mass, want_acceleration)


def _run(x, par, t, steps, feasible, joints, out, bottleneck, singularity, fallback,
         want_sv, want_columns, want_vertices,
           mp, want_mass, want_acceleration, speeds, want_velocity, fill):
    """Every point of ``x`` (k, 2) into the outputs (``FusedKernel.run``): over the cores in ``run_parallel``,
    on the calling thread in ``run_serial`` (``jit.twins``). ``fill``: ``nan`` in every value row of a point
    that is not feasible (else those entries are left unwritten, ``SPARSE_VALUES``).
    """
    for i in prange(x.shape[0]):
        fallback[i] = _point(x, par, t, steps, i, feasible, joints, out, bottleneck, singularity,
                             want_sv, want_columns, want_vertices, mp, want_mass, want_acceleration, speeds,
                             want_velocity, fill)


run_parallel, run_serial = twins(_run, "run")
#: The runs take a last argument ``fill`` (``FusedKernel.run``): False leaves the value rows of the points
#: that are not feasible unwritten, for a map, which reads only the feasible ones: twelve stores a point
#: fewer on the 44 % of the five-bar's 521 x 261 map that is not feasible (7.57 against 7.23 ms of one
#: thread for 68k of its points, median of 30 interleaved, load 5).
SPARSE_VALUES = True
