"""The delta family (``kinematics.delta``: the Novint Falcon) in one compiled pass: IK, limits, classes, J, quantities.

Each point follows ``Delta.inverse`` (``_reach_terms``), ``feasible`` (``_knees``, ``_bars``,
``leg_angles``), ``singularity`` (``_ratios``, ``singular_tolerances``, ``_classes``) and
``jacobian`` operation for operation, leg by leg, then ``square3.quantities3``. The leg frames
``u_i``, ``v_i`` and the knees' fixed part come from the model itself (``pack``), so they are the
numpy path's numbers to the last bit.

Two steps are formed otherwise and so hand a point back to the numpy path where they could
disagree with it: the class (``np.linalg.det`` there, a cofactor expansion here) where a leg's
ratio or the bars' determinant is within twice the model's tolerance of singular, and
``J = A^-1 B`` (``np.linalg.inv`` there, the adjugate here) where ``A``'s Frobenius condition is
above ``FAST_COND_LIMIT`` or its scale is off the safe range (``square3``'s rule for an inverse).
"""
from __future__ import annotations

import math

import numpy as np
from numba import prange

from metrics.linalg import FAST_COND_LIMIT, SAFE_SCALE

from .delta_mass import inertia, pack_mass  # noqa: F401  (pack_mass: FusedKernel reads it here)
from .dynamics import dynamics3, velocity3
from .jit import jit, twins
from .square3 import blank, quantities3

EPS = 2.220446049250313e-16
_HALF_PI = math.pi / 2
_TWO_PI = 2.0 * math.pi
_FRO_LO, _FRO_HI = SAFE_SCALE[0] ** 2, SAFE_SCALE[1] ** 2
#: ``Delta._classes``: the bars are coplanar where ``|det A| <= sqrt(64 eps) prod |n_i|``.
_DIRECT = math.sqrt(64 * EPS)
# Offsets into ``pack``'s array: u (3 x 3), v (3 x 3), the knees' fixed part (3 x 3), then scalars.
_U, _V, _ROOT = 0, 9, 18
_A, _B, _D, _R, _C, _S, _F, _A2, _LO, _HI, _KMIN, _KMAX, _BAR, _TOL_BAR = range(27, 41)


def pack(mechanism) -> np.ndarray:
    """The model's parameters as the kernel reads them, float64 (41,).

    Parameters
    ----------
    mechanism : Delta
        The model.

    Returns
    -------
    ndarray, shape (41,)
        ``u`` and ``v`` (``leg_frames``, row by row), the knees' fixed part ``(r - c) u + (s - f) v``
        (``_knees``), then a, b, D, r, c, s, f, a^2, the arm and knee limits, the bar limit and the
        bars' term of ``singular_tolerances``.
    """
    p = mechanism.params
    u, v = mechanism.leg_frames()
    root = (p.base_radius - p.platform_offset_u) * u + (p.base_offset_v - p.platform_offset_v) * v
    tol_bar = np.sqrt(32 * EPS * mechanism.size() / p.parallelogram)
    return np.array([*u.ravel(), *v.ravel(), *root.ravel(),
                     p.upper_arm, p.parallelogram, p.knee_offset + p.platform_joint_offset, p.base_radius,
                     p.platform_offset_u, p.base_offset_v, p.platform_offset_v, p.upper_arm ** 2,
                     p.arm_lower, p.arm_upper, p.knee_min, p.knee_max, p.bar_limit, tol_bar], dtype=np.float64)


@jit()
def _reach(x0, x1, x2, par, i):
    """``Delta._reach_terms`` of leg ``i``: ``(P_u + c, P_w, cos theta3, rho, L, k)``."""
    u, v = _U + 3 * i, _V + 3 * i
    a, b = par[_A], par[_B]
    pu = x0 * par[u] + x1 * par[u + 1] + x2 * par[u + 2] - par[_R] + par[_C]
    pv = x0 * par[v] + x1 * par[v + 1] + x2 * par[v + 2] - par[_S] + par[_F]
    pw = x2 + 0.0
    cos3 = pv / b
    sin3 = math.sqrt(max(1.0 - cos3 * cos3, 0.0))
    reach = par[_D] + b * sin3
    rho = math.hypot(pu, pw)
    safe = rho if rho > 0.0 else 1.0
    k = (rho * rho + par[_A2] - reach * reach) / (2.0 * a * safe)
    return pu, pw, cos3, rho, reach, k


@jit()
def _arm(pu, pw, cos3, rho, k):
    """``Delta.inverse`` of one leg: ``(ok, q)``."""
    if not (abs(cos3) <= 1.0 and rho > 0.0 and abs(k) <= 1.0):
        return False, 0.0
    q = math.atan2(pw, pu) - math.acos(min(max(k, -1.0), 1.0))
    return True, q - _TWO_PI * np.floor((q + math.pi) / _TWO_PI)


@jit()
def _leg(x0, x1, x2, q, par, i):
    """Leg ``i`` at arm angle ``q``: ``(ok, n_0, n_1, n_2, B_ii)``, its limits (``feasible``), bar and arm rate.

    ``_knees``, ``_bars`` and ``leg_angles`` in their order of operations (``w = (0, 0, 1)``).
    """
    u, v, root = _U + 3 * i, _V + 3 * i, _ROOT + 3 * i
    u0, u1, u2 = par[u], par[u + 1], par[u + 2]
    v0, v1, v2 = par[v], par[v + 1], par[v + 2]
    a, big_d = par[_A], par[_D]
    cq, sq = math.cos(q), math.sin(q)
    k0 = par[root] + a * (cq * u0 + sq * 0.0)
    k1 = par[root + 1] + a * (cq * u1 + sq * 0.0)
    k2 = par[root + 2] + a * (cq * u2 + sq * 1.0)
    d0 = a * (-sq * u0 + cq * 0.0)
    d1 = a * (-sq * u1 + cq * 0.0)
    d2 = a * (-sq * u2 + cq * 1.0)
    qv0, qv1, qv2 = x0 - k0, x1 - k1, x2 - k2
    along = qv0 * v0 + qv1 * v1 + qv2 * v2
    p0, p1, p2 = qv0 - along * v0, qv1 - along * v1, qv2 - along * v2
    rho = math.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
    scale = (rho - big_d) / (rho if rho > 0.0 else 1.0)
    n0, n1, n2 = p0 * scale + along * v0, p1 * scale + along * v1, p2 * scale + along * v2
    theta2 = math.atan2(qv2, qv0 * u0 + qv1 * u1 + qv2 * u2)
    bend = theta2 - q
    bend = bend - _TWO_PI * np.floor((bend + math.pi) / _TWO_PI)
    theta3 = math.atan2(rho - big_d, along)
    ok = (q >= par[_LO] and q <= par[_HI] and bend >= par[_KMIN] and bend <= par[_KMAX]
          and abs(theta3 - _HALF_PI) <= par[_BAR])
    return ok, n0, n1, n2, n0 * d0 + n1 * d1 + n2 * d2


@jit()
def _near_singular_leg(n0, n1, n2, b_ii, rho, reach, par):
    """Whether a leg's ratio ``|B_ii| / (|n_i| a)`` is within twice ``singular_tolerances`` (``Delta._ratios``)."""
    a = par[_A]
    ratio = abs(b_ii) / (math.sqrt(n0 * n0 + n1 * n1 + n2 * n2) * a)
    kappa = (rho * rho + a * a + reach * reach) / (2.0 * a * rho)
    tol = min(1.0, math.sqrt(64.0 * EPS * kappa) * rho / reach) + par[_TOL_BAR]
    return not (ratio > 2.0 * tol)


@jit(inline=True)
def _point(x, par, t, steps, i, feasible, joints, out, bottleneck, singularity,
           want_sv, want_columns, want_vertices,
           mp, want_mass, want_acceleration, speeds, want_velocity):
    """Point ``i``: True to hand it back to the numpy path. Every output starts infeasible (``blank``)."""
    blank(i, feasible, joints, out, bottleneck, singularity, True)
    x0, x1, x2 = x[i, 0], x[i, 1], x[i, 2]
    if not (math.isfinite(x0) and math.isfinite(x1) and math.isfinite(x2)):
        return True
    # -- Delta.inverse, leg by leg
    pu, pw, cos3, rho_0, reach_0, k = _reach(x0, x1, x2, par, 0)
    ok_0, q0 = _arm(pu, pw, cos3, rho_0, k)
    pu, pw, cos3, rho_1, reach_1, k = _reach(x0, x1, x2, par, 1)
    ok_1, q1 = _arm(pu, pw, cos3, rho_1, k)
    pu, pw, cos3, rho_2, reach_2, k = _reach(x0, x1, x2, par, 2)
    ok_2, q2 = _arm(pu, pw, cos3, rho_2, k)
    if not (ok_0 and ok_1 and ok_2):
        return False
    # -- Delta.feasible (x given), with each leg's row of A and B of Delta._velocity_matrices
    ok_0, a00, a01, a02, b0 = _leg(x0, x1, x2, q0, par, 0)
    ok_1, a10, a11, a12, b1 = _leg(x0, x1, x2, q1, par, 1)
    ok_2, a20, a21, a22, b2 = _leg(x0, x1, x2, q2, par, 2)
    if not (ok_0 and ok_1 and ok_2):
        return False
    feasible[i] = True
    joints[i, 0], joints[i, 1], joints[i, 2] = q0, q1, q2
    # -- Delta.singularity: an arm's rate B_ii or the bars' determinant next to zero goes back to numpy
    if (_near_singular_leg(a00, a01, a02, b0, rho_0, reach_0, par)
            or _near_singular_leg(a10, a11, a12, b1, rho_1, reach_1, par)
            or _near_singular_leg(a20, a21, a22, b2, rho_2, reach_2, par)):
        return True
    c00 = a11 * a22 - a12 * a21
    c01 = a12 * a20 - a10 * a22
    c02 = a10 * a21 - a11 * a20
    c10 = a02 * a21 - a01 * a22
    c11 = a00 * a22 - a02 * a20
    c12 = a01 * a20 - a00 * a21
    c20 = a01 * a12 - a02 * a11
    c21 = a02 * a10 - a00 * a12
    c22 = a00 * a11 - a01 * a10
    det = a00 * c00 + a01 * c01 + a02 * c02
    norms = (math.sqrt(a00 * a00 + a01 * a01 + a02 * a02) * math.sqrt(a10 * a10 + a11 * a11 + a12 * a12)
             * math.sqrt(a20 * a20 + a21 * a21 + a22 * a22))
    if not (abs(det) > 2.0 * _DIRECT * norms):
        return True
    fro = (a00 * a00 + a01 * a01 + a02 * a02 + a10 * a10 + a11 * a11 + a12 * a12
           + a20 * a20 + a21 * a21 + a22 * a22)
    if not (fro > _FRO_LO and fro < _FRO_HI):
        return True
    cof = (c00 * c00 + c01 * c01 + c02 * c02 + c10 * c10 + c11 * c11 + c12 * c12
           + c20 * c20 + c21 * c21 + c22 * c22)
    if not (math.sqrt(fro * cof) / abs(det) <= FAST_COND_LIMIT):
        return True
    singularity[i] = 0
    # -- Delta.jacobian: J = A^-1 B, A^-1 = adj(A) / det (adj = the cofactors' transpose)
    j00, j01, j02 = c00 / det * b0, c10 / det * b1, c20 / det * b2
    j10, j11, j12 = c01 / det * b0, c11 / det * b1, c21 / det * b2
    j20, j21, j22 = c02 / det * b0, c12 / det * b1, c22 / det * b2
    if quantities3(j00, j01, j02, j10, j11, j12, j20, j21, j22, t, steps, out, bottleneck, i,
                   want_sv, want_columns, want_vertices):
        return True
    if want_velocity and velocity3(j00, j01, j02, j10, j11, j12, j20, j21, j22, speeds, out, i):
        return True
    if not (want_mass or want_acceleration):
        return False
    k = inertia(x0, x1, x2, q0, q1, q2, j00, j01, j02, j10, j11, j12, j20, j21, j22, mp)
    return dynamics3(k[0], k[1], k[2], k[3], k[4], k[5], j00, j01, j02, j10, j11, j12, j20, j21, j22, False, t, out,
                     i, want_mass, want_acceleration)


def _run(x, par, t, steps, feasible, joints, out, bottleneck, singularity, fallback,
         want_sv, want_columns, want_vertices,
           mp, want_mass, want_acceleration, speeds, want_velocity):
    """Every point of ``x`` (k, 3) into the outputs (``FusedKernel.run``): over the cores in ``run_parallel``,
    on the calling thread in ``run_serial`` (``jit.twins``).
    """
    for i in prange(x.shape[0]):
        fallback[i] = _point(x, par, t, steps, i, feasible, joints, out, bottleneck, singularity,
                             want_sv, want_columns, want_vertices, mp, want_mass, want_acceleration, speeds,
                             want_velocity)


run_parallel, run_serial = twins(_run, "run")
