"""The Inverse3 family (``kinematics.inverse3``) in one compiled pass: IK, limits, J, the quantities.

Each point follows ``Inverse3.inverse``, ``Inverse3.feasible`` and ``Inverse3.jacobian`` (the model's
docstrings give the equations), then ``square3.quantities3``, with fewer transcendental calls: the
base angle is one arctangent of the point's rotation, ``(x0, x1) = Rot(th0) (u, c)``, where the model
takes two, and J's sines and cosines are the IK's own ratios (``cos th0 = (x0 u + x1 c) / |(x0, x1)|^2``,
``cos th3 = u / a3``, ``sin h = sqrt(1 - cos_h^2)``) instead of functions of the joint angles, and so
are the kinetic form's (``inverse3_mass.inertia_of``: the links' ``th3 +- h`` by the angle-sum rule). The
joints differ from the model's by rounding (at most ``8 pi eps`` each, as the libm results did);
a decision that rounding could turn (the nearest branch, the body's test) is taken as the model
takes it within ``_SLACK`` of its edge, so the feasible set differs only at a pose within rounding
of a joint limit. The body's test comes before the five-bar's angles: a point inside the body
costs no ``th3``, ``h``.
``params`` packs the model's parameters (``pack``); the branch is 0 nearest, 1 front, 2 back.
"""
from __future__ import annotations

import math

import numpy as np
from numba import prange

from .dynamics import dynamics3, velocity3
from .inverse3_mass import inertia_of, pack_mass  # noqa: F401  (pack_mass: FusedKernel reads it here)
from .jit import jit, twins
from .square3 import blank, quantities3
from .svd3 import conditioning3

_QUARTER = math.pi / 2.0
_TWO_PI = 2.0 * math.pi
_EPS = 2.220446049250313e-16
_EPS8 = 8 * _EPS
_BRANCHES = ("nearest", "front", "back")
#: Twice the model's rounding of an angle (``8 pi eps``: a sum of up to three libm results below 2 pi):
#: nearer than this (in rad, or per m of the lever) to a decision's edge, the kernel decides as the model does.
_SLACK = 16 * math.pi * 2.220446049250313e-16

def pack(mechanism) -> np.ndarray:
    """The model's parameters as the kernel reads them, float64 (15,).

    Parameters
    ----------
    mechanism : Inverse3
        The model.

    Returns
    -------
    ndarray, shape (15,)
    """
    p = mechanism.params
    return np.array([p.plane_offset, p.proximal_length, p.distal_length, p.base_height,
                     *p.lower_limits, *p.upper_limits, p.min_link_spread, p.max_link_spread,
                     p.body_radius, p.body_height, _BRANCHES.index(p.base_branch)], dtype=np.float64)


@jit()
def _wrap_pi(angle):
    return angle - _TWO_PI * np.floor((angle + math.pi) / _TWO_PI)


@jit(inline=True)
def _point(x, par, t, steps, i, feasible, joints, out, bottleneck, singularity, want_sv, want_columns, want_vertices,
           mp, want_mass, want_acceleration, speeds, want_velocity, fill):
    """Point ``i``: True to hand it back to the numpy path. Every output starts infeasible (``blank``);
    without ``fill`` the value rows are left as they are until the point's values are written."""
    blank(i, feasible, joints, out, bottleneck, singularity, fill)      # without fill: 10 stores a point fewer
    x0, x1, x2 = x[i, 0], x[i, 1], x[i, 2]
    if not (math.isfinite(x0) and math.isfinite(x1) and math.isfinite(x2)):
        return True
    c, l1, l2, base_height = par[0], par[1], par[2], par[3]
    # -- Inverse3.inverse
    horizontal_sq = x0 * x0 + x1 * x1
    radial_sq = horizontal_sq - c * c
    reach_ok = radial_sq >= -_EPS8 * (horizontal_sq + c * c)
    u_abs = math.sqrt(max(radial_sq, 0.0))
    w = x2 - base_height
    # Reach first: it needs |u| only (hypot(-u, w) is hypot(u, w) exactly), so an unreachable
    # point costs no arctangent.
    # Beyond the outer reach by a relative margin d = 64 eps (1 + l1 / l2) in a3 (2 d in a3^2, whose
    # rounding is 3 eps), the model's cos_h - 1 ~ d l2 / l1 / 2 >= 32 eps (1 + l2 / l1) is out of its
    # 8 eps slack whatever cos_h's own rounding (below 2 eps (1 + l2 / l1)): rejected without hypot.
    a3_sq = u_abs * u_abs + w * w
    if a3_sq > (l1 + l2) * (l1 + l2) * (1.0 + 128.0 * _EPS * (1.0 + l1 / l2)):
        return False
    a3 = math.hypot(u_abs, w)
    if a3 == 0.0:
        return True
    cos_h = (l1 * l1 + a3 * a3 - l2 * l2) / (2.0 * l1 * a3)
    if not (reach_ok and abs(cos_h) <= 1.0 + _EPS8):
        return False
    # The branch and th0 from the point's rotation: (x0, x1) = Rot(th0) (u, c) (the model's P), so
    # th0 = atan2(x1 u - x0 c, x0 u + x1 c), one arctangent where the model takes two (azimuth, beta).
    branch = par[14]
    if branch == 1.0:
        back = False
    elif branch == 2.0:
        back = True
    elif abs(x0) * u_abs > _SLACK * horizontal_sq:
        # "nearest": the smaller |th0| has the larger cos th0 = (x0 u + x1 c) / |(x0, x1)|^2, the back
        # branch's (u = -u_abs) where x0 < 0. The two |th0| differ by at least the cosines' difference,
        # 2 |x0| u_abs / |(x0, x1)|^2, more than twice the model's rounding of either (8 pi eps): its choice.
        back = x0 < 0.0
    else:                           # within the model's rounding of a tie: its own comparison decides
        azimuth = math.atan2(x1, x0)
        beta = math.atan2(c, u_abs)
        back = abs(_wrap_pi(azimuth + beta - math.pi)) < abs(_wrap_pi(azimuth - beta))
    u = -u_abs if back else u_abs
    th0 = math.atan2(x1 * u - x0 * c, x0 * u + x1 * c)
    q0 = th0 - _TWO_PI * np.floor((th0 - par[4]) / _TWO_PI)
    # cos q0, sin q0 from the point instead of the angle (q0 = th0 + 2 pi k): the model's P gives
    # (x0, x1) = Rot(th0) (u, c), so (cos th0, sin th0) = (x0 u + x1 c, x1 u - x0 c) / (u^2 + c^2),
    # and u^2 + c^2 is |(x0, x1)|^2.
    cos0 = (x0 * u + x1 * c) / horizontal_sq
    sin0 = (x1 * u - x0 * c) / horizontal_sq
    # -- Inverse3.feasible's body test (x: the requested point) first: a point it rejects costs no th3, h.
    if not x2 > par[13]:
        # The body's test: radial = u here. Within the reach of both cosines' rounding of the
        # radius (``_SLACK``), decide it with the model's own cosines of q0, as the numpy model
        # does, so the feasible set is the same however close a point comes to the body.
        radial = x0 * cos0 + x1 * sin0
        if abs(radial - par[12]) <= _SLACK * (abs(x0) + abs(x1)):
            radial = x0 * math.cos(q0) + x1 * math.sin(q0)
        if not radial > par[12]:
            return False
    th3 = math.atan2(w, u)
    h = math.acos(min(max(cos_h, -1.0), 1.0))
    p1 = th3 + h + _QUARTER
    p2 = th3 - h + _QUARTER
    p1_wrapped = p1 - _TWO_PI * np.floor((p1 - par[5]) / _TWO_PI)
    shift = p1_wrapped - p1
    q1, q2 = p1 + shift, p2 + shift
    # -- Inverse3.feasible's joint limits and link spread
    ok = math.isfinite(q0) and math.isfinite(q1) and math.isfinite(q2)
    ok = ok and q0 >= par[4] and q0 <= par[7] and q1 >= par[5] and q1 <= par[8] and q2 >= par[6] and q2 <= par[9]
    spread = abs(q1 - q2)
    ok = ok and spread >= par[10] and spread <= par[11]
    if not ok:
        return False
    feasible[i] = True
    joints[i, 0], joints[i, 1], joints[i, 2] = q0, q1, q2
    # -- Inverse3.jacobian, its sines and cosines from the IK's own values (h = acos(cos_h) in
    # [0, pi], th3 = atan2(w, u) + 2 pi k): no trigonometric call.
    cos_h = min(max(cos_h, -1.0), 1.0)
    sin_h = math.sqrt((1.0 - cos_h) * (1.0 + cos_h))
    root = math.sqrt(max(l2 * l2 - (l1 * sin_h) * (l1 * sin_h), 0.0))
    cos3, sin3 = u / a3, w / a3
    # The links' angles phi_i = q_i - 90 deg = th3 +- h (+ 2 pi k), their sines and cosines by the
    # angle-sum rule from the same ratios (the kinetic form's, ``inertia_of``): no trigonometric call.
    cos_ch, sin_sh = cos3 * cos_h, sin3 * sin_h
    sin_ch, cos_sh = sin3 * cos_h, cos3 * sin_h
    a3 = l1 * cos_h + root
    da3 = -l1 * sin_h * (1.0 + l1 * cos_h / root)
    u = a3 * cos3
    du_th3, dw_th3 = -a3 * sin3, a3 * cos3
    du_h, dw_h = da3 * cos3, da3 * sin3
    du1, dw1 = 0.5 * (du_th3 + du_h), 0.5 * (dw_th3 + dw_h)
    du2, dw2 = 0.5 * (du_th3 - du_h), 0.5 * (dw_th3 - dw_h)
    a00, a01, a02 = -u * sin0 - c * cos0, du1 * cos0, du2 * cos0
    a10, a11, a12 = u * cos0 - c * sin0, du1 * sin0, du2 * sin0
    # The conditioning first (``svd3``: near a repeated singular value too), then the rest of ``quantities3``.
    if want_sv and conditioning3(a00, a01, a02, a10, a11, a12, 0.0, dw1, dw2, out, i):
        return True
    if quantities3(a00, a01, a02, a10, a11, a12, 0.0, dw1, dw2, t, steps, out, bottleneck, i,
                   False, want_columns, want_vertices):
        return True
    if want_velocity and velocity3(a00, a01, a02, a10, a11, a12, 0.0, dw1, dw2, speeds, out, i):
        return True
    if not (want_mass or want_acceleration):
        return False
    k = inertia_of(x0, x1, x2, cos0, sin0, cos_ch - sin_sh, sin_ch + cos_sh, cos_ch + sin_sh, sin_ch - cos_sh,
                   a00, a01, a02, a10, a11, a12, 0.0, dw1, dw2, mp)
    return dynamics3(k[0], k[1], k[2], k[3], k[4], k[5], a00, a01, a02, a10, a11, a12, 0.0, dw1, dw2, False, t, out,
                     i, want_mass, want_acceleration)


def _run(x, par, t, steps, feasible, joints, out, bottleneck, singularity, fallback,
         want_sv, want_columns, want_vertices,
           mp, want_mass, want_acceleration, speeds, want_velocity, fill):
    """Every point of ``x`` (k, 3) into the outputs (``FusedKernel.run``): over the cores in ``run_parallel``,
    on the calling thread in ``run_serial`` (``jit.twins``). ``fill``: ``nan`` in every value row of a point
    that is not feasible (else those entries are left unwritten, ``SPARSE_VALUES``).

    ``singularity`` stays -1: the family has no singularity classes.
    """
    for i in prange(x.shape[0]):
        fallback[i] = _point(x, par, t, steps, i, feasible, joints, out, bottleneck, singularity,
                             want_sv, want_columns, want_vertices, mp, want_mass, want_acceleration, speeds,
                             want_velocity, fill)


run_parallel, run_serial = twins(_run, "run")
#: The runs take a last argument ``fill`` (``FusedKernel.run``): False leaves the value rows of the points
#: that are not feasible unwritten, for a caller that reads only the feasible ones (``isoforce stats``).
SPARSE_VALUES = True
