"""The serial RRR family (``kinematics.serial_rrr``: PHANToM, Omni, WoodenHaptics) in one compiled pass.

Each point follows ``SerialRRR.inverse``, ``feasible``, ``singularity`` and ``jacobian`` operation
for operation (the model's docstrings give the equations), then ``square3.quantities3``. A pose the
model classes singular (the base axis ``r = 0``, or ``cos(q2 - q3) = 0``), or within twice its
tolerance of one, is handed back to the numpy path, which gives J its exact singular limit and the
class its label. ``pack`` packs the model's parameters; the branch is 0 nearest, 1 front, 2 back.
"""
from __future__ import annotations

import math

import numpy as np
from numba import prange

from .dynamics import dynamics3, velocity3
from .jit import jit, twins
from .serial_rrr_mass import inertia_of, pack_mass  # noqa: F401  (pack_mass: FusedKernel reads it here)
from .square3 import blank, quantities3
from .svd3 import conditioning3

_HALF_PI = 0.5 * math.pi
_TWO_PI = 2.0 * math.pi
_EPS8 = 8 * 2.220446049250313e-16
_BRANCHES = ("nearest", "front", "back")


def pack(mechanism) -> np.ndarray:
    """The model's parameters as the kernel reads them, float64 (14,).

    Parameters
    ----------
    mechanism : SerialRRR
        The model.

    Returns
    -------
    ndarray, shape (14,)
        l1, l2, the lower and upper limits, the two coupling limits, the branch, the singular
        tolerance, ``l1 + l2`` and the tolerance on ``r`` (``tolerance * (l1 + l2)``, as ``jacobian``
        forms it).
    """
    p = mechanism.params
    tol = mechanism.singular_tolerance
    l1, l2 = p.link1_length, p.link2_length
    return np.array([l1, l2, *p.lower_limits, *p.upper_limits, p.max_q2_minus_q3, p.max_q3_minus_q2,
                     _BRANCHES.index(p.base_branch), tol, l1 + l2, tol * (l1 + l2)], dtype=np.float64)


@jit()
def _wrap_pi(angle):
    return angle - _TWO_PI * np.floor((angle + math.pi) / _TWO_PI)


@jit(inline=True)
def _point(x, par, t, steps, i, feasible, joints, out, bottleneck, singularity, want_sv, want_columns, want_vertices,
           mp, want_mass, want_acceleration, speeds, want_velocity, fill):
    """Point ``i``: True to hand it back to the numpy path. Every output starts infeasible (``blank``);
    without ``fill`` the value rows are left as they are until the point's values are written."""
    blank(i, feasible, joints, out, bottleneck, singularity, fill)      # without fill: 10 stores a point fewer
    px, py, pz = x[i, 0], x[i, 1], x[i, 2]
    if not (math.isfinite(px) and math.isfinite(py) and math.isfinite(pz)):
        return True
    l1, l2 = par[0], par[1]
    # -- SerialRRR.inverse
    rho = math.hypot(px, py)
    azimuth = math.atan2(py, px)
    over = _wrap_pi(azimuth - math.pi)
    branch = par[10]
    if branch == 1.0:
        back = False
    elif branch == 2.0:
        back = True
    else:
        back = abs(over) < abs(azimuth)
    q1 = over if back else azimuth
    s = -rho if back else rho
    d_sq = s * s + pz * pz
    d = math.sqrt(d_sq)
    if not d > 0.0:
        return False
    cos_alpha = (l1 * l1 + d_sq - l2 * l2) / (2.0 * l1 * d)
    cos_beta = (l1 * l1 + l2 * l2 - d_sq) / (2.0 * l1 * l2)
    if not (abs(cos_alpha) <= 1.0 + _EPS8 and abs(cos_beta) <= 1.0 + _EPS8):
        return False
    q2 = math.atan2(pz, s) + math.acos(min(max(cos_alpha, -1.0), 1.0))
    q3 = q2 + math.acos(min(max(cos_beta, -1.0), 1.0)) - _HALF_PI
    # angles.wrap_into: q2 and q3 shifted together into q2's range
    q2_wrapped = q2 - _TWO_PI * np.floor((q2 - par[3]) / _TWO_PI)
    q3 = q3 + (q2_wrapped - q2)
    q2 = q2_wrapped
    # -- SerialRRR.feasible
    if not (math.isfinite(q1) and math.isfinite(q2) and math.isfinite(q3)):
        return False
    if not (q1 >= par[2] and q1 <= par[5] and q2 >= par[3] and q2 <= par[6] and q3 >= par[4] and q3 <= par[7]):
        return False
    if not (q2 - q3 <= par[8] and q3 - q2 <= par[9]):
        return False
    feasible[i] = True
    joints[i, 0], joints[i, 1], joints[i, 2] = q1, q2, q3
    # -- SerialRRR.singularity and jacobian: r = l1 cos q2 + l2 sin q3, det J = l1 l2 r cos(q2 - q3)
    s1, c1 = math.sin(q1), math.cos(q1)
    s2, c2 = math.sin(q2), math.cos(q2)
    s3, c3 = math.sin(q3), math.cos(q3)
    r = l1 * c2 + l2 * s3
    tol = 2.0 * par[11]
    if abs(r) <= 2.0 * par[13] or abs(r / par[12]) <= tol or abs(math.cos(q2 - q3)) <= tol:
        return True                  # at or next to a singular pose: the numpy path's exact limit and label
    singularity[i] = 0
    a00, a01, a02 = -s1 * r, -l1 * c1 * s2, l2 * c1 * c3
    a10, a11, a12 = c1 * r, -l1 * s1 * s2, l2 * s1 * c3
    a21, a22 = l1 * c2, l2 * s3
    # The conditioning first (``svd3``: near a repeated singular value too), then the rest of ``quantities3``.
    if want_sv and conditioning3(a00, a01, a02, a10, a11, a12, 0.0, a21, a22, out, i):
        return True
    if quantities3(a00, a01, a02, a10, a11, a12, 0.0, a21, a22, t, steps, out, bottleneck, i,
                   False, want_columns, want_vertices):
        return True
    if want_velocity and velocity3(a00, a01, a02, a10, a11, a12, 0.0, a21, a22, speeds, out, i):
        return True
    if not (want_mass or want_acceleration):
        return False
    k = inertia_of(s2, c2, s3, c3, mp)         # the same sines and cosines as J's: M(q) bit for bit
    return dynamics3(k[0], k[1], k[2], k[3], k[4], k[5], a00, a01, a02, a10, a11, a12, 0.0, a21, a22, True, t, out,
                     i, want_mass, want_acceleration)


def _run(x, par, t, steps, feasible, joints, out, bottleneck, singularity, fallback,
         want_sv, want_columns, want_vertices,
           mp, want_mass, want_acceleration, speeds, want_velocity, fill):
    """Every point of ``x`` (k, 3) into the outputs (``FusedKernel.run``): over the cores in ``run_parallel``,
    on the calling thread in ``run_serial`` (``jit.twins``). ``fill``: ``nan`` in every value row of a point
    that is not feasible (else those entries are left unwritten, ``SPARSE_VALUES``).
    """
    for i in prange(x.shape[0]):
        fallback[i] = _point(x, par, t, steps, i, feasible, joints, out, bottleneck, singularity,
                             want_sv, want_columns, want_vertices, mp, want_mass, want_acceleration, speeds,
                             want_velocity, fill)


run_parallel, run_serial = twins(_run, "run")
#: The runs take a last argument ``fill`` (``FusedKernel.run``): False leaves the value rows of the points
#: that are not feasible unwritten, for a caller that reads only the feasible ones (``isoforce stats``).
SPARSE_VALUES = True
