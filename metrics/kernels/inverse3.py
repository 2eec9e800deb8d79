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
costs no ``th3``, ``h``; nor does a point whose link directions put it outside the five-bar's limits by a
margin (``_limit_arcs``: a third of those past the body on the 1000 x 1000 map). Without ``fill`` (a map,
which reads no joint: ``SPARSE_JOINTS``) the joints are not written and a point inside every limit by that
margin takes no ``atan2``, ``acos`` at all (all 375k feasible points of that map); the decisions are the
exact pass's, bit for bit (``tests/metrics/test_kernels.py``).
``params`` packs the model's parameters (``pack``); the branch is 0 nearest, 1 front, 2 back. The elbow's
reach ``hypot(u, w)`` is glibc's arithmetic inlined (``hypot``), libm's own where the platform's differs.
"""
from __future__ import annotations

import math

import numba
import numpy as np
from numba import prange

from .dynamics import dynamics3, velocity3
from .hypot import hypot_covers, hypot_fast, matches_libm
from .inverse3_mass import inertia_of, pack_mass  # noqa: F401  (pack_mass: FusedKernel reads it here)
from .jit import jit, twins
from .square3 import (
    anisotropy3,
    blank,
    columns3,
    conditioning_of3,
    eigen_finish3,
    gram_shift3,
    quantities3,
    third_cosines3,
    write_conditioning3,
)
from .svd3 import settle3

_QUARTER = math.pi / 2.0
_TWO_PI = 2.0 * math.pi
_EPS = 2.220446049250313e-16
_EPS8 = 8 * _EPS
_BRANCHES = ("nearest", "front", "back")
#: Twice the model's rounding of an angle (``8 pi eps``: a sum of up to three libm results below 2 pi):
#: nearer than this (in rad, or per m of the lever) to a decision's edge, the kernel decides as the model does.
_SLACK = 16 * math.pi * 2.220446049250313e-16

def pack(mechanism) -> np.ndarray:
    """The model's parameters as the kernel reads them, float64 (16,).

    The last entry is 1 where this platform's libm ``hypot`` (the model's ``np.hypot``) is
    ``hypot.hypot_fast`` (``hypot.matches_libm``): the pass then takes the elbow's reach that way, else
    by libm.

    Parameters
    ----------
    mechanism : Inverse3
        The model.

    Returns
    -------
    ndarray, shape (16,)
    """
    p = mechanism.params
    return np.array([p.plane_offset, p.proximal_length, p.distal_length, p.base_height,
                     *p.lower_limits, *p.upper_limits, p.min_link_spread, p.max_link_spread,
                     p.body_radius, p.body_height, _BRANCHES.index(p.base_branch),
                     1.0 if matches_libm() else 0.0], dtype=np.float64)


#: Points per block of the pass (``_run``): each step of the point pipeline runs over a block's points
#: before the next step starts, so a block's scratch stays in the core's L1 cache (``ROWS`` x ``BLOCK``
#: x 8 bytes, 25 KB).
BLOCK = 64
# Scratch rows, by the step that fills them (``_run``). Candidates past the cheap reach test:
_UABS, _W, _HSQ, _REACH, _A3 = range(5)
# Past the reach and the body's test: the five-bar's inputs, the base's ratios, then the three angles.
_U, _W2, _A32, _COSH, _Y0, _X0, _COS0, _SIN0, _TH3, _H, _Q1, _Q2, _TH0 = range(5, 18)
# Feasible: J's entries (row 2 is (0, dw1, dw2)), the base's ratios, the links' cosines and sines.
_J = 18
_C0, _S0, _L1C, _L1S, _L2C, _L2S = range(26, 32)
# The conditioning's figures (``square3.conditioning_of3``) and whether J is finite.
_COND, _INV, _MAN, _FIN = range(32, 36)
# The anisotropic force and whether it stands (``square3.anisotropy3``).
_ANI, _AOK = 36, 37
# The singular values and whether the closed form is hard there (``square3.eigen_finish3``).
_S1, _S2, _S3, _HARD = 38, 39, 40, 41
# The column norms' quantities (``square3.columns3``).
_RES, _COK, _ISO, _NECK = 42, 43, 44, 45
#: Float rows of a block's scratch.
ROWS = 46


def block_scratch() -> tuple[np.ndarray, np.ndarray]:
    """One block's scratch per lane of the pass (a lane a thread, ``_run``), new for each call.

    Returns
    -------
    rows : ndarray, shape (lanes, ROWS, BLOCK)
    index : ndarray of int64, shape (lanes, 3, BLOCK)
        The block's points that reached each stage.
    """
    threads = numba.config.NUMBA_NUM_THREADS
    return np.empty((threads, ROWS, BLOCK)), np.empty((threads, 3, BLOCK), np.int64)


@jit()
def _wrap_pi(angle):
    return angle - _TWO_PI * np.floor((angle + math.pi) / _TWO_PI)


#: The margin of the five-bar's early rejection (``_limit_arcs``): four times ``_SLACK``, in rad, or per m
#: of the lever ``a3`` (a cross product with a unit vector). Derivation in ``_limit_arcs``.
_EARLY = 4 * _SLACK


@jit()
def _arc(lower, upper):
    """One joint's limits ``[lower, upper]`` as its link's directions (``phi = q - 90 deg``) for ``_outside``:
    ``(mode, ax, ay, bx, by)``, ``(ax, ay)`` the direction of ``lower``, ``(bx, by)`` of ``upper``.

    ``mode`` 0: the limits span a turn or more (nothing is outside); 1: they span more than half a turn
    less ``_SLACK`` (outside is the wedge from ``upper`` on to ``lower``); 2: at most half a turn less
    ``_SLACK`` (inside is the wedge from ``lower`` on to ``upper``). ``_SLACK`` covers the span's rounding.
    """
    span = upper - lower
    mode = 0.0 if not span < _TWO_PI else (1.0 if span > math.pi - _SLACK else 2.0)
    # The direction of q - 90 deg is (sin q, -cos q).
    return mode, math.sin(lower), -math.cos(lower), math.sin(upper), -math.cos(upper)


@jit()
def _limit_arcs(par):
    """The joints' limits as the pass's early decisions take them, once a pass (``_block``).

    A point whose ``cos_h`` is above ``lo`` (the spread below its minimum) or below ``hi`` (above its
    maximum), or whose link lies outside a joint's limits (``_outside``), by more than ``_EARLY``, fails
    ``Inverse3.feasible``'s five-bar test as the kernel takes it (``q1``, ``q2``, the spread from
    ``atan2``, ``acos``), and is rejected without those two calls. Derivation: the kernel's ``q1``, ``q2``
    are within 32 pi eps of ``th3 +- h + 90 deg`` (+ 2 pi k) for the exact ``th3 = atan2(w, u)``,
    ``h = acos(cos_h)`` of its floats (atan2 and acos 1 ulp of at most pi each, the sums, the wrap's
    product and differences half an ulp of at most 4 pi each), and the spread within 26 pi eps of ``2 h``.
    ``cos`` has slope at most 1, so ``cos_h`` beyond ``cos(spread / 2)`` (1 ulp) by ``_EARLY`` puts ``2 h``
    beyond the spread by 2 (_EARLY - eps) > 26 pi eps. A link's direction ``(u c -+ w s, w c +- u s)``
    (``c = cos_h``, ``s = sqrt(1 - c^2)``) is ``a3`` times the unit vector of ``th3 +- h`` within 16 eps
    ``a3`` (``s`` 3 eps, each entry's products and sum 3 eps, ``a3`` itself 1 ulp), its cross product with
    a limit's direction (1 ulp each entry) within 20 eps ``a3``: a cross product beyond ``_EARLY a3`` puts
    the angle beyond its edge by more than (64 pi - 20) eps > 32 pi eps, so the kernel's joint, whatever
    its 2 pi k, is outside too.

    Without ``fill`` (``SPARSE_JOINTS``) no joint is written, and the same bounds, the other way round,
    decide the limits of a point inside them by the margin, with no ``atan2``, ``acos``: the spread
    (``lo_in``, ``hi_in``), both links (``_inside``: ``q2``'s direction decides its test where ``lone``,
    below), and the base, whose direction ``(x0 u + x1 c, x1 u - x0 c)`` (``|P|^2`` times that of ``th0``)
    is inside its limits by a cross product above ``_EARLY (|.|_1)``: the kernel's ``q0`` is within
    32 pi eps of ``atan2`` of those same floats (+ 2 pi k), the cross product's rounding 5 eps of their norm.

    Parameters
    ----------
    par : ndarray, shape (15,)
        ``pack``'s.

    Returns
    -------
    tuple of 19 float
        ``lo``, ``hi``, q1's, q2's and the base's ``_arc``, ``lo_in``, ``hi_in``.
    """
    # cos(spread / 2) on [0, pi] only (there it is monotonic): beyond, no early rejection on that side.
    half_min, half_max = 0.5 * par[10], 0.5 * par[11]
    lo = math.cos(half_min) + _EARLY if half_min > 0.0 and half_min <= math.pi else math.inf
    hi = math.cos(half_max) - _EARLY if half_max >= 0.0 and half_max < math.pi else -math.inf
    m1, a1x, a1y, b1x, b1y = _arc(par[5], par[8])
    m2, a2x, a2y, b2x, b2y = _arc(par[6], par[9])
    m0, a0x, a0y, b0x, b0y = _arc(par[4], par[7])
    # Without fill, the spread within its limits by the margin: cos_h below lo_in and above hi_in.
    lo_in = math.cos(half_min) - _EARLY if half_min >= 0.0 and half_min <= math.pi else -math.inf
    hi_in = math.cos(half_max) + _EARLY if half_max >= 0.0 and half_max <= math.pi else math.inf
    # q2 = q1 - spread (the kernel wraps q1 alone): with q1 within its limits and the spread within its,
    # q2 lies in [l1 - max, u1 - min], which must miss q2's limits a turn on either side (by the margin)
    # for q2's direction to decide its test (else no early acceptance).
    lone = (par[9] - _TWO_PI < par[5] - par[11] - _EARLY and par[6] + _TWO_PI > par[8] - par[10] + _EARLY
            and m1 != 0.0 and m2 != 0.0)
    if not lone:
        lo_in, hi_in = -math.inf, math.inf
    return lo, hi, m1, a1x, a1y, b1x, b1y, m2, a2x, a2y, b2x, b2y, m0, a0x, a0y, b0x, b0y, lo_in, hi_in


@jit(inline=True)
def _outside(dx, dy, mode, ax, ay, bx, by, tol):
    """Whether the direction ``(dx, dy)`` lies outside ``_arc``'s limits by a cross product above ``tol``.

    Mode 1 (limits over half a turn): outside, the wedge from the upper limit's direction ``b`` on to the
    lower's ``a``, at most half a turn (if the limits spanned a hair under it, the two half-planes' overlap
    is a part of the outside still). Mode 2: inside is the wedge from ``a`` on to ``b``; a direction
    clockwise of ``a``, or counter-clockwise of ``b``, by a cross product above ``tol`` is outside it.
    """
    ca = ax * dy - ay * dx          # cross(a, d): > 0 where d is counter-clockwise of a
    cb = bx * dy - by * dx
    if mode == 1.0:
        return cb > tol and -ca > tol
    if mode == 2.0:
        return ca < -tol or cb > tol
    return False


@jit(inline=True)
def _inside(dx, dy, mode, ax, ay, bx, by, tol):
    """Whether the direction ``(dx, dy)`` lies inside ``_arc``'s limits by a cross product above ``tol``:
    ``_outside``'s wedges, the other way round (mode 1: limits over half a turn less ``_SLACK``, so a
    direction within half a turn of a limit, on its inner side, by more than ``tol``, is within them)."""
    ca = ax * dy - ay * dx
    cb = bx * dy - by * dx
    if mode == 1.0:
        return ca > tol or cb < -tol
    if mode == 2.0:
        return ca > tol and cb < -tol
    return False


@jit()
def _reach(sc, n, fast):
    """The model's ``a3 = hypot(u, w)`` of a block's ``n`` reach candidates (``sc`` rows ``_UABS``, ``_W`` into
    ``_A3``): glibc's arithmetic inlined (``hypot.hypot_fast``, libm's bits where ``fast``: ``pack``'s flag
    says the platform's libm is glibc's), the loop in vector registers; libm's own call where not, or
    outside the inlined form's range.

    A function of its own, called once a block, not inlined: both builds of the pass (``jit.twins``) call
    one compiled copy, so its vector loops are compiled once (as ``_conditioning``'s).
    """
    if fast:
        for k in range(n):
            sc[_A3, k] = hypot_fast(sc[_UABS, k], sc[_W, k])
    for k in range(n):
        if not (fast and hypot_covers(sc[_UABS, k], sc[_W, k])):
            sc[_A3, k] = math.hypot(sc[_UABS, k], sc[_W, k])


@jit()
def _conditioning(sc, n):
    """The conditioning of a block's ``n`` Jacobians (``sc`` rows ``_J`` on) into rows ``_S1``.. ``_HARD``,
    ``_FIN`` and ``_COND``, ``_INV``, ``_MAN``.

    The Gram matrix's shift (``square3.gram_shift3``), the eigenvalues' cosines (``square3.third_cosines3``:
    a cube root, no ``acos``, ``cos``), the singular values and the figures from them, in one loop without
    a branch or a call: its square roots and divisions run in vector registers. A J that is not finite
    (its figures are then any value: the pass's last loop hands it back) takes the steps with ``r = 0``.
    Called once a block, not inlined (``_reach``): the inlined cube root in both builds of the pass
    added 5-15 s of CPU to the kernel's cold compile.
    """
    for k in range(n):
        a00, a01, a02 = sc[_J, k], sc[_J + 1, k], sc[_J + 2, k]
        a10, a11, a12 = sc[_J + 3, k], sc[_J + 4, k], sc[_J + 5, k]
        dw1, dw2 = sc[_J + 6, k], sc[_J + 7, k]
        finite = (math.isfinite(a00) & math.isfinite(a01) & math.isfinite(a02) & math.isfinite(a10)
                  & math.isfinite(a11) & math.isfinite(a12) & math.isfinite(dw1) & math.isfinite(dw2))
        mean, p, r, det = gram_shift3(a00, a01, a02, a10, a11, a12, 0.0, dw1, dw2)
        r = r if finite else 0.0
        cos_first, cos_third = third_cosines3(r)
        s1, s2, s3, hard = eigen_finish3(mean, p, r, det, cos_first, cos_third)
        sc[_S1, k], sc[_S2, k], sc[_S3, k] = s1, s2, s3
        sc[_HARD, k] = 1.0 if hard else 0.0
        sc[_FIN, k] = 1.0 if finite else 0.0
        sc[_COND, k], sc[_INV, k], sc[_MAN, k] = conditioning_of3(s1, s2, s3)


@jit(inline=True)
def _block(x, par, t, steps, start, stop, feasible, joints, out, bottleneck, singularity, fallback, want_sv,
           want_columns, want_vertices, mp, want_mass, want_acceleration, speeds, want_velocity, fill, sc, ids, early):
    """Points ``start:stop`` (at most ``BLOCK``): ``fallback`` True to hand a point back to the numpy path.

    Each point takes the steps of ``Inverse3.inverse``, ``Inverse3.feasible``, ``Inverse3.jacobian`` and
    ``square3``/``svd3`` in the model's order, with the same operations (so the same bits) as one point
    taken alone; but each step runs over the block's points that reached it before the next step starts,
    and the arctangents and arccosines have loops of their own. A loop over one point's whole
    pipeline waits on its chain of libm calls; over a block, the calls of consecutive points overlap.
    The conditioning, ``square3.columns3`` and ``square3.anisotropy3`` are loops without a branch or a call
    (the eigenvalues' cosines by a cube root, ``square3.third_cosines3``: no libm), their hand-back tests
    kept as flags for the last loop, which takes them in ``quantities3``'s order: their square roots and
    divisions run in vector registers.
    """
    c, l1, l2, base_height = par[0], par[1], par[2], par[3]
    # -- Inverse3.inverse: the reach without hypot (an unreachable point costs no libm call).
    n1 = 0
    for i in range(start, stop):
        if fill:
            blank(i, feasible, joints, out, bottleneck, singularity, True)
        else:       # without fill: 13 stores a point fewer (the value rows and the joints)
            feasible[i] = False
            bottleneck[i] = -1
            singularity[i] = -1
        fallback[i] = False
        x0, x1, x2 = x[i, 0], x[i, 1], x[i, 2]
        if not (math.isfinite(x0) and math.isfinite(x1) and math.isfinite(x2)):
            fallback[i] = True
            continue
        horizontal_sq = x0 * x0 + x1 * x1
        radial_sq = horizontal_sq - c * c
        u_abs = math.sqrt(max(radial_sq, 0.0))
        w = x2 - base_height
        # Reach first: it needs |u| only (hypot(-u, w) is hypot(u, w) exactly), so an unreachable
        # point costs no arctangent.
        # Beyond the outer reach by a relative margin d = 64 eps (1 + l1 / l2) in a3 (2 d in a3^2, whose
        # rounding is 3 eps), the model's cos_h - 1 ~ d l2 / l1 / 2 >= 32 eps (1 + l2 / l1) is out of its
        # 8 eps slack whatever cos_h's own rounding (below 2 eps (1 + l2 / l1)): rejected without hypot.
        a3_sq = u_abs * u_abs + w * w
        if a3_sq > (l1 + l2) * (l1 + l2) * (1.0 + 128.0 * _EPS * (1.0 + l1 / l2)):
            continue
        sc[_UABS, n1], sc[_W, n1], sc[_HSQ, n1] = u_abs, w, horizontal_sq
        sc[_REACH, n1] = 1.0 if radial_sq >= -_EPS8 * (horizontal_sq + c * c) else 0.0
        ids[0, n1] = i
        n1 += 1
    _reach(sc, n1, par[15] != 0.0)
    # -- the elbow's reach, the base's branch, Inverse3.feasible's body test.
    n2 = 0
    for k in range(n1):
        i = ids[0, k]
        x0, x1, x2 = x[i, 0], x[i, 1], x[i, 2]
        u_abs, w, horizontal_sq, a3 = sc[_UABS, k], sc[_W, k], sc[_HSQ, k], sc[_A3, k]
        if a3 == 0.0:
            fallback[i] = True
            continue
        cos_h = (l1 * l1 + a3 * a3 - l2 * l2) / (2.0 * l1 * a3)
        if not (sc[_REACH, k] != 0.0 and abs(cos_h) <= 1.0 + _EPS8):
            continue
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
                th0 = math.atan2(x1 * u - x0 * c, x0 * u + x1 * c)
                q0 = th0 - _TWO_PI * np.floor((th0 - par[4]) / _TWO_PI)
                radial = x0 * math.cos(q0) + x1 * math.sin(q0)
            if not radial > par[12]:
                continue
        # The five-bar's early rejection (``_limit_arcs``): a third of the points past the body's test fail
        # its limits, and then cost no atan2, acos.
        if cos_h > early[0] or cos_h < early[1]:
            continue
        c_h = min(max(cos_h, -1.0), 1.0)
        s_h = math.sqrt((1.0 - c_h) * (1.0 + c_h))
        tol = _EARLY * a3
        if _outside(u * c_h - w * s_h, w * c_h + u * s_h, early[2], early[3], early[4], early[5], early[6], tol):
            continue
        if _outside(u * c_h + w * s_h, w * c_h - u * s_h, early[7], early[8], early[9], early[10], early[11], tol):
            continue
        # Without fill (no joints wanted), a point inside the five-bar's limits by the margin takes no th3, h
        # either (inf marks it).
        sc[_TH3, n2] = 0.0
        if (not fill and cos_h < early[17] and cos_h > early[18]
                and _inside(u * c_h - w * s_h, w * c_h + u * s_h, early[2], early[3], early[4], early[5], early[6],
                            tol)
                and _inside(u * c_h + w * s_h, w * c_h - u * s_h, early[7], early[8], early[9], early[10],
                            early[11], tol)):
            sc[_TH3, n2] = math.inf
        sc[_U, n2], sc[_W2, n2], sc[_A32, n2], sc[_COSH, n2] = u, w, a3, cos_h
        sc[_Y0, n2], sc[_X0, n2] = x1 * u - x0 * c, x0 * u + x1 * c
        sc[_COS0, n2], sc[_SIN0, n2] = cos0, sin0
        ids[1, n2] = i
        n2 += 1
    # The five-bar's angles, th3 = atan2(w, u) and h = acos(cos_h), and its joints' limits and link spread
    # (Inverse3.feasible), for the points the early decisions left open: a point they reject costs no th0.
    for k in range(n2):
        if sc[_TH3, k] != math.inf:
            sc[_TH3, k] = math.atan2(sc[_W2, k], sc[_U, k])
            sc[_H, k] = math.acos(min(max(sc[_COSH, k], -1.0), 1.0))
    n3 = 0
    for k in range(n2):
        th3, h = sc[_TH3, k], sc[_H, k]
        if th3 == math.inf:         # inside the limits (atan2's are finite): kept, no joints wanted
            for row in range(_U, _SIN0 + 1):
                sc[row, n3] = sc[row, k]
            ids[1, n3] = ids[1, k]
            n3 += 1
            continue
        p1 = th3 + h + _QUARTER
        p2 = th3 - h + _QUARTER
        p1_wrapped = p1 - _TWO_PI * np.floor((p1 - par[5]) / _TWO_PI)
        shift = p1_wrapped - p1
        q1, q2 = p1 + shift, p2 + shift
        spread = abs(q1 - q2)
        if not (math.isfinite(q1) and math.isfinite(q2) and q1 >= par[5] and q1 <= par[8] and q2 >= par[6]
                and q2 <= par[9] and spread >= par[10] and spread <= par[11]):
            continue
        # Kept in place (n3 <= k: row n3 is read already).
        for row in range(_U, _SIN0 + 1):
            sc[row, n3] = sc[row, k]
        sc[_Q1, n3], sc[_Q2, n3] = q1, q2
        ids[1, n3] = ids[1, k]
        n3 += 1
    n2 = n3
    # The base's angle th0 = atan2(x1 u - x0 c, x0 u + x1 c) and its limits; without fill, a point within
    # them by the margin (``_limit_arcs``) costs no th0: its joint is not written (``SPARSE_JOINTS``).
    for k in range(n2):
        y0, x0 = sc[_Y0, k], sc[_X0, k]
        # (y0, -x0): the direction of th0 - 90 deg, as ``_arc``'s are.
        if not fill and _inside(y0, -x0, early[12], early[13], early[14], early[15], early[16],
                                _EARLY * (abs(x0) + abs(y0))):
            sc[_TH0, k] = math.inf          # inside: no q0 wanted
        else:
            sc[_TH0, k] = math.atan2(y0, x0)
    # -- the joints and Inverse3.jacobian.
    n3 = 0
    for k in range(n2):
        i = ids[1, k]
        th0 = sc[_TH0, k]
        if th0 != math.inf:          # atan2's are finite: inf marks a point inside the base's limits
            q0 = th0 - _TWO_PI * np.floor((th0 - par[4]) / _TWO_PI)
            if not (math.isfinite(q0) and q0 >= par[4] and q0 <= par[7]):
                continue
            if fill:
                joints[i, 0], joints[i, 1], joints[i, 2] = q0, sc[_Q1, k], sc[_Q2, k]
        feasible[i] = True
        # Inverse3.jacobian, its sines and cosines from the IK's own values (h = acos(cos_h) in
        # [0, pi], th3 = atan2(w, u) + 2 pi k): no trigonometric call.
        u, w, a3, cos0, sin0 = sc[_U, k], sc[_W2, k], sc[_A32, k], sc[_COS0, k], sc[_SIN0, k]
        cos_h = min(max(sc[_COSH, k], -1.0), 1.0)
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
        sc[_J, n3], sc[_J + 1, n3], sc[_J + 2, n3] = -u * sin0 - c * cos0, du1 * cos0, du2 * cos0
        sc[_J + 3, n3], sc[_J + 4, n3], sc[_J + 5, n3] = u * cos0 - c * sin0, du1 * sin0, du2 * sin0
        sc[_J + 6, n3], sc[_J + 7, n3] = dw1, dw2
        sc[_C0, n3], sc[_S0, n3] = cos0, sin0
        sc[_L1C, n3], sc[_L1S, n3] = cos_ch - sin_sh, sin_ch + cos_sh
        sc[_L2C, n3], sc[_L2S, n3] = cos_ch + sin_sh, sin_ch - cos_sh
        ids[2, n3] = i
        n3 += 1
    # -- the conditioning (``svd3.conditioning3``'s steps: near a repeated singular value too).
    if want_sv:
        _conditioning(sc, n3)
    # -- the anisotropic force (``square3.quantities3``'s, without a branch: the loop vectorises).
    t0, t1, t2 = t[0], t[1], t[2]
    if want_columns:
        for k in range(n3):
            res, ok, iso, neck = columns3(sc[_J, k], sc[_J + 1, k], sc[_J + 2, k], sc[_J + 3, k], sc[_J + 4, k],
                                          sc[_J + 5, k], 0.0, sc[_J + 6, k], sc[_J + 7, k], t0, t1, t2, steps)
            sc[_RES, k], sc[_ISO, k], sc[_NECK, k] = res, iso, float(neck)
            sc[_COK, k] = 1.0 if ok else 0.0
    if want_vertices:
        for k in range(n3):
            ok, value = anisotropy3(sc[_J, k], sc[_J + 1, k], sc[_J + 2, k], sc[_J + 3, k], sc[_J + 4, k],
                                    sc[_J + 5, k], 0.0, sc[_J + 6, k], sc[_J + 7, k], t0, t1, t2)
            sc[_ANI, k] = value
            sc[_AOK, k] = 1.0 if ok else 0.0
    # -- the rest of ``square3.quantities3`` and the tails, point by point in the model's order.
    for k in range(n3):
        i = ids[2, k]
        a00, a01, a02 = sc[_J, k], sc[_J + 1, k], sc[_J + 2, k]
        a10, a11, a12 = sc[_J + 3, k], sc[_J + 4, k], sc[_J + 5, k]
        dw1, dw2 = sc[_J + 6, k], sc[_J + 7, k]
        if want_sv:
            if sc[_FIN, k] == 0.0:
                fallback[i] = True
                continue
            if sc[_HARD, k] != 0.0:     # near a repeated value (``svd3.settle3``), or handed back
                s1, s2, s3, hard = settle3(a00, a01, a02, a10, a11, a12, 0.0, dw1, dw2, sc[_S1, k], sc[_S2, k],
                                           sc[_S3, k], True)
                if hard:
                    fallback[i] = True
                    continue
                write_conditioning3(s1, s2, s3, out, i)
            else:
                out[0, i], out[1, i], out[2, i] = sc[_COND, k], sc[_INV, k], sc[_MAN, k]
        # Its finite test alone (its steps are taken above): with ``want_sv``, ``_FIN`` took it.
        if not want_sv and quantities3(a00, a01, a02, a10, a11, a12, 0.0, dw1, dw2, t, steps, out, bottleneck, i,
                                       False, False, False):
            fallback[i] = True
            continue
        if want_columns:
            out[5, i] = sc[_RES, k]
            if sc[_COK, k] == 0.0:
                fallback[i] = True
                continue
            out[3, i] = sc[_ISO, k]
            bottleneck[i] = int(sc[_NECK, k])
        if want_vertices:               # quantities3's last step, taken above
            if sc[_AOK, k] == 0.0:
                fallback[i] = True
                continue
            out[4, i] = sc[_ANI, k]
        if want_velocity and velocity3(a00, a01, a02, a10, a11, a12, 0.0, dw1, dw2, speeds, out, i):
            fallback[i] = True
            continue
        if not (want_mass or want_acceleration):
            continue
        kf = inertia_of(x[i, 0], x[i, 1], x[i, 2], sc[_C0, k], sc[_S0, k], sc[_L1C, k], sc[_L1S, k], sc[_L2C, k],
                        sc[_L2S, k], a00, a01, a02, a10, a11, a12, 0.0, dw1, dw2, mp)
        fallback[i] = dynamics3(kf[0], kf[1], kf[2], kf[3], kf[4], kf[5], a00, a01, a02, a10, a11, a12, 0.0, dw1,
                                dw2, False, t, out, i, want_mass, want_acceleration)


def _run(x, par, t, steps, feasible, joints, out, bottleneck, singularity, fallback,
         want_sv, want_columns, want_vertices,
         mp, want_mass, want_acceleration, speeds, want_velocity, fill, rows, index):
    """Every point of ``x`` (k, 3) into the outputs (``FusedKernel.run``): over the cores in ``run_parallel``,
    on the calling thread in ``run_serial`` (``jit.twins``), ``BLOCK`` points at a time (``_block``), each
    lane of blocks in its own ``rows``, ``index`` (``block_scratch``). ``fill``: ``nan`` in every value row of a point
    that is not feasible (else those entries are left unwritten, ``SPARSE_VALUES``), and the joints (else
    unwritten, ``SPARSE_JOINTS``).

    ``singularity`` stays -1: the family has no singularity classes.
    """
    n = x.shape[0]
    blocks = (n + BLOCK - 1) // BLOCK
    lanes = rows.shape[0]
    per_lane = (blocks + lanes - 1) // lanes
    early = _limit_arcs(par)
    # One lane a thread, each with its own scratch and its own run of consecutive blocks (as ``prange`` splits
    # a range): lanes taking every other block shared the cache lines of the outputs at the blocks' ends and
    # took 10-20 % more CPU on two threads. A point's numbers do not depend on its block or lane.
    for lane in prange(lanes):
        for b in range(lane * per_lane, min((lane + 1) * per_lane, blocks)):
            start = b * BLOCK
            _block(x, par, t, steps, start, min(start + BLOCK, n), feasible, joints, out, bottleneck, singularity,
                   fallback, want_sv, want_columns, want_vertices, mp, want_mass, want_acceleration, speeds,
                   want_velocity, fill, rows[lane], index[lane], early)


run_parallel, run_serial = twins(_run, "run")
#: The runs take a last argument ``fill`` (``FusedKernel.run``): False leaves the value rows of the points
#: that are not feasible unwritten, for a caller that reads only the feasible ones (``isoforce stats``).
SPARSE_VALUES = True
#: Without ``fill`` the joints are not written either (any point): a map reads none. The base's angle is then
#: taken only near its limits (``_limit_arcs``): 375k ``atan2`` fewer on the 1000 x 1000 map.
SPARSE_JOINTS = True
