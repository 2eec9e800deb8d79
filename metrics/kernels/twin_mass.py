"""The Twin-Pantograph's kinetic form (``kinematics.twin_pantograph``), compiled in blocks of points.

``inertia_points`` gives what ``kinematics.dynamics.kinetic_form(mech, q, x, rotors=True)`` gives
for the 5-DOF model (roll passive) with its task point on the pen's axis (``reference_offset`` 0):
``Lambda`` per task twist ``xi = [v; omega . a; omega . b]``, kg, from the bodies' exact velocities
as ``TwinPantograph.body_velocities`` forms them:

    Lambda = sym(sum_b m_b Jv_b^T Jv_b + Jw_b^T R_b I_b R_b^T Jw_b) + G^T diag(r) G

(``kinematics.bodies.kinetic_columns``, then ``kinetic_form``'s rotors). Per point, in scalars:
the tilt frame ``R = (a, p, b)`` (``twin_batch._pen_frame``), the U-joint centres ``T_s = x + lever_s
p``, each unit's waist angle ``psi``, plane frame ``e_r = (0, -sin psi, cos psi)``, ``n = (0, -cos psi,
-sin psi)`` and five-bar IK (``twin_rows.unit_pose``: ``TwinPantograph._unit_inverse``'s operations); per twist column
the tip's velocity ``v + omega x r_s``, the joint rates (``_twist_rows``' rows dotted with it: waist
``n . Tdot / w``, shoulder ``(d_u e_x + d_w e_r) . Tdot / (l2 d . t)``), then the 21 bodies in
``TwinPantograph.bodies`` order: per unit the waist (turning about ``e_x`` at ``psidot``), the upper
arms and forearms (``kinematics.bodies.plane_link_part``), the elbows, counterweights and tip joint
(points moving with the waist's frame), then the pen at unit A's U-joint.

Column ``omega . a`` is the pen turning about ``a`` (``omega = a``), ``omega . b`` about ``b``. The
numpy path forms the columns per rate of ``(rx, rz)`` and takes them to the twist with ``T^-1``
(``kinematics.dynamics.twist_columns``): the same columns in exact arithmetic, because nothing in
the 5-DOF model with the task point on the axis moves with ``omega . p`` (the U-joints and the pen's
centre are on the axis; the pen, a line, has no moment about it). At zero tilt ``T = I`` and both
paths form the same columns from the same numbers; elsewhere they differ by ``T^-1``'s rounding.
Sines and cosines are libm's here and numpy's SIMD loops there (an ulp apart at most): the two
paths differ by rounding only (``tests/metrics/test_kernel_mass_twin.py`` bounds it).

A pose with a non-finite coordinate, or that a leg does not reach (``TwinPantograph``'s ``ok``),
gets ``nan``, as the numpy path's bodies do. Points run on the calling thread (``nogil``): the numpy
path's map chunks already run in parallel threads.

Layout: ``BLOCK`` points (lanes) go through these steps together. Per lane, the IK and the pen
frame (libm's functions, one lane at a time: ``_poses``); then each step over all lanes in one
loop the compiler vectorises, in a scratch of ``ROWS`` rows of ``BLOCK``: the tips' velocities,
the joint rates, the elbows' velocities, each link's frame and angular velocity, each body's
terms added to ``Lambda``'s upper triangle in ``TwinPantograph.bodies``' order, the rotors. A
lane's operations and their order are the point's alone (the lanes share loops, no sum), so
its bits are those it gets in any block, or one point at a time as this module did before. What
depends on the design alone (whether a body's centre is off its origin, whether it has a
tensor) is decided once per call, not per point.
"""
from __future__ import annotations

import math

import numpy as np

from .jit import jit
from .twin_batch import _pen_frame
from .twin_rows import BACK, HALF, L1, L2, L3, LEVER_A, M, pack, unit_pose

#: Bodies per unit (``TwinPantograph.bodies``): waist, upper arms, forearms, elbows, counterweights, tip.
UNIT_BODIES = 10
PEN = 2 * UNIT_BODIES


def supports(mechanism) -> bool:
    """Whether ``inertia_points`` covers ``mechanism``: ``twin_rows.supports`` with a mass model.

    Parameters
    ----------
    mechanism : Mechanism

    Returns
    -------
    bool
    """
    from .twin_rows import supports as rows_support

    return rows_support(mechanism, mass=True)


def pack_mass(mechanism) -> tuple[np.ndarray, ...]:
    """The model's geometry and bodies for ``inertia_points``.

    Parameters
    ----------
    mechanism : TwinPantograph
        ``supports(mechanism)``.

    Returns
    -------
    tuple of ndarray
        ``params`` (7,) (``twin_rows.pack``), the bodies' masses (21,), centres in their frames
        (21, 3) and tensors (21, 3, 3), each of q1..q6's reflected rotor inertia (6,) and
        whether it is actuated (6,) (q4 may be passive: no rotor, no row of ``G``).
    """
    from kinematics.bodies import body_arrays

    params = pack(mechanism)
    masses, com, tensors = body_arrays(mechanism.bodies())
    rotors = np.zeros(6)
    actuated = np.zeros(6, np.int64)
    for r, joint in zip(mechanism.reflected_rotor_inertias(), mechanism.actuated):
        rotors[joint] = r
        actuated[joint] = 1
    return (params, np.ascontiguousarray(masses, dtype=np.float64), np.ascontiguousarray(com, dtype=np.float64),
            np.ascontiguousarray(tensors, dtype=np.float64), rotors, actuated)


#: Points per block in ``inertia_points``: each step runs over the block's points (lanes) in an
#: inner loop the compiler vectorises; a lane's operations are the point's alone, whatever the
#: block. The steps' rows all lie in one scratch, so the compiler vectorises a loop behind a
#: run-time test that its rows do not overlap: worth it over a long loop, not over a short one it
#: unrolls instead. Twin-Pantograph map's 101,344 feasible poses (CPU, one thread, best of 7,
#: load 4): 0.20 s one point at a time, 0.185 in blocks of 8, 0.147 of 16, 0.108 of 32, 0.082
#: of 64, 0.084 of 128, 0.080 of 256.
BLOCK = 64


def _rows(*sizes):
    """Consecutive row offsets of blocks of ``sizes`` rows, then the total."""
    offsets, at = [], 0
    for size in sizes:
        offsets.append(at)
        at += size
    return (*offsets, at)


#: The scratch's rows, each a value per lane. A pose's (``_poses``): the pen frame's columns ``a``,
#: ``p``, ``b``; per unit ``UNIT_ROWS`` (its U-joint ``T``, ``w``, ``sin psi``, ``cos psi``, then
#: per leg ``(sx, cos theta, sin theta, d_u, d_w, l2 d . t)``); 1 where it counts. Then per
#: twist column (``(3, M)`` blocks, component-major): zeros (a still point), the pen's ``omega``,
#: the tips' velocities (two units), the joint rates (6, M), the elbows' velocities (two legs), a
#: counterweight's, the waist's frame (3, 3) and angular velocity, a link's frame, angular
#: velocity and length; a body's ``R c``, ``Jv``, ``R^T Jw`` and ``I R^T Jw``; ``Lambda``'s upper
#: triangle (15, row by row).
UNIT_ROWS = 18
(_A, _P, _B, _UNIT, _OK, _STILL, _SPIN, _DTIP, _RATES, _DELBOW, _DBACK, _WROT, _WJW, _LROT, _LJW, _LEN,
 _RC, _JV, _BODY, _TURNED, _LAM, ROWS) = _rows(3, 3, 3, 2 * UNIT_ROWS, 1, 3 * M, 3 * M, 2 * 3 * M, 6 * M,
                                             2 * 3 * M, 3 * M, 9, 3 * M, 9, 3 * M, 1, 3, 3 * M, 3 * M, 3 * M,
                                             M * (M + 1) // 2)


@jit(inline=True)
def _cross(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@jit()
def _poses(x, lo, nb, params, w):
    """Points ``lo .. lo + nb`` of ``x`` into the lanes (a short block's last lanes repeat its last
    point): pen frame, both units' ``twin_rows.unit_pose``, and whether the point counts (finite,
    both units reach). A non-finite pose is computed as the zero pose (its result is never read)."""
    half, l1, l2, l3 = params[HALF], params[L1], params[L2], params[L3]
    for ln in range(BLOCK):
        pt = lo + min(ln, nb - 1)
        finite = True
        for k in range(5):
            if not np.isfinite(x[pt, k]):
                finite = False
        if finite:
            x0, x1, x2, rx, rz = x[pt, 0], x[pt, 1], x[pt, 2], x[pt, 3], x[pt, 4]
        else:
            x0, x1, x2, rx, rz = 0.0, 0.0, 0.0, 0.0, 0.0
        a, p, b = _pen_frame(rx, rz)
        for c in range(3):
            w[_A + c, ln] = a[c]
            w[_P + c, ln] = p[c]
            w[_B + c, ln] = b[c]
        ok = finite
        for k in range(2):
            reach, tip, dist, sn, cs, leg0, leg1 = unit_pose(x0, x1, x2, p, params[LEVER_A + k],
                                                             -half if k == 0 else half, l1, l2, l3)
            ok = ok and reach
            u = _UNIT + UNIT_ROWS * k
            for c in range(3):
                w[u + c, ln] = tip[c]
            w[u + 3, ln] = dist
            w[u + 4, ln] = sn
            w[u + 5, ln] = cs
            for c in range(6):
                w[u + 6 + c, ln] = leg0[c]
                w[u + 12 + c, ln] = leg1[c]
        w[_OK, ln] = 1.0 if ok else 0.0


@jit()
def _add_body(w, mass, com, tensor, moved, spins, rot, jw, do):
    """``Lambda += m Jv^T Jv + (R^T Jw)^T I (R^T Jw)`` (upper triangle) of one body, ``Jv = do + Jw x R c``.

    ``rot`` the first row of its axes (3, 3), ``jw``, ``do`` of its angular velocity and its
    origin's velocity per column (3, M). ``moved``: ``c`` is not zero; ``spins``: ``I`` is not (a
    point, or a line's axis aside, adds no rotation term, as ``kinetic_columns`` skips it).
    """
    jv = do
    if moved:
        for r in range(3):
            for ln in range(BLOCK):
                w[_RC + r, ln] = (w[rot + 3 * r, ln] * com[0] + w[rot + 3 * r + 1, ln] * com[1]
                                  + w[rot + 3 * r + 2, ln] * com[2])
        for j in range(M):
            for ln in range(BLOCK):
                w0, w1, w2 = _cross(w[jw + j, ln], w[jw + M + j, ln], w[jw + 2 * M + j, ln],
                                    w[_RC, ln], w[_RC + 1, ln], w[_RC + 2, ln])
                w[_JV + j, ln] = w[do + j, ln] + w0
                w[_JV + M + j, ln] = w[do + M + j, ln] + w1
                w[_JV + 2 * M + j, ln] = w[do + 2 * M + j, ln] + w2
        jv = _JV
    if spins:
        for c in range(3):
            for a in range(M):
                for ln in range(BLOCK):
                    w[_BODY + c * M + a, ln] = (w[rot + c, ln] * w[jw + a, ln] + w[rot + 3 + c, ln] * w[jw + M + a, ln]
                                                + w[rot + 6 + c, ln] * w[jw + 2 * M + a, ln])
        for c in range(3):
            for a in range(M):
                for ln in range(BLOCK):
                    w[_TURNED + c * M + a, ln] = (tensor[c, 0] * w[_BODY + a, ln] + tensor[c, 1] * w[_BODY + M + a, ln]
                                                  + tensor[c, 2] * w[_BODY + 2 * M + a, ln])
    e = _LAM
    for a in range(M):
        for b in range(a, M):
            if spins:
                for ln in range(BLOCK):
                    term = mass * (w[jv + a, ln] * w[jv + b, ln] + w[jv + M + a, ln] * w[jv + M + b, ln]
                                   + w[jv + 2 * M + a, ln] * w[jv + 2 * M + b, ln])
                    term += (w[_BODY + a, ln] * w[_TURNED + b, ln] + w[_BODY + M + a, ln] * w[_TURNED + M + b, ln]
                             + w[_BODY + 2 * M + a, ln] * w[_TURNED + 2 * M + b, ln])
                    w[e, ln] += term
            else:
                for ln in range(BLOCK):
                    w[e, ln] += mass * (w[jv + a, ln] * w[jv + b, ln] + w[jv + M + a, ln] * w[jv + M + b, ln]
                                        + w[jv + 2 * M + a, ln] * w[jv + 2 * M + b, ln])
            e += 1


@jit()
def _plane_link(w, fore, u, leg, y0, l2, da, db):
    """``kinematics.bodies.plane_link_part`` of unit ``u``'s (its first row) leg ``leg``: the upper
    arm from the still shoulder ``(sx, y0, 0)`` to the elbow, or (``fore``) the forearm from the
    elbow to the tip, in the plane of normal ``n = (0, -cos psi, -sin psi)`` turning at the waist's
    rate: its axes into ``_LROT``, its angular velocity into ``_LJW``; ``da``, ``db`` its ends'
    velocities (3, M)."""
    lg = u + 6 + 6 * leg
    for ln in range(BLOCK):
        sn, cs = w[u + 4, ln], w[u + 5, ln]
        er1, er2 = -sn, cs
        n1, n2 = -cs, -sn
        sx, ct, st = w[lg, ln], w[lg + 1, ln], w[lg + 2, ln]
        ex, ew = sx + l2 * ct, l2 * st                     # the elbow, in the plane
        e0, e1, e2 = ex, y0 + ew * er1, ew * er2
        if fore:
            a0, a1, a2, b0, b1, b2 = e0, e1, e2, w[u, ln], w[u + 1, ln], w[u + 2, ln]
        else:
            a0, a1, a2, b0, b1, b2 = sx, y0, 0.0, e0, e1, e2
        r0, r1, r2 = b0 - a0, b1 - a1, b2 - a2
        length = math.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
        x0, x1, x2 = r0 / length, r1 / length, r2 / length
        s0, s1, s2 = _cross(0.0, n1, n2, x0, x1, x2)
        width = math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
        y0_, y1_, y2_ = s0 / width, s1 / width, s2 / width
        z0, z1, z2 = _cross(x0, x1, x2, y0_, y1_, y2_)
        w[_LROT, ln], w[_LROT + 3, ln], w[_LROT + 6, ln] = x0, x1, x2
        w[_LROT + 1, ln], w[_LROT + 4, ln], w[_LROT + 7, ln] = y0_, y1_, y2_
        w[_LROT + 2, ln], w[_LROT + 5, ln], w[_LROT + 8, ln] = z0, z1, z2
        w[_LEN, ln] = length
    for j in range(M):
        for ln in range(BLOCK):
            y0_, y1_, y2_ = w[_LROT + 1, ln], w[_LROT + 4, ln], w[_LROT + 7, ln]
            z0, z1, z2 = w[_LROT + 2, ln], w[_LROT + 5, ln], w[_LROT + 8, ln]
            p0, p1, p2 = w[_WJW + j, ln], w[_WJW + M + j, ln], w[_WJW + 2 * M + j, ln]
            spin = (y0_ * (w[db + j, ln] - w[da + j, ln]) + y1_ * (w[db + M + j, ln] - w[da + M + j, ln])
                    + y2_ * (w[db + 2 * M + j, ln] - w[da + 2 * M + j, ln])) / w[_LEN, ln]
            turn = spin - (p0 * z0 + p1 * z1 + p2 * z2)
            w[_LJW + j, ln] = p0 + z0 * turn
            w[_LJW + M + j, ln] = p1 + z1 * turn
            w[_LJW + 2 * M + j, ln] = p2 + z2 * turn


@jit()
def _unit(w, k, params, masses, com, tensors, moved, spins):
    """Unit ``k``'s tip velocity, joint rates and 10 bodies (``TwinPantograph.bodies``' order) into the lanes."""
    half, l2 = params[HALF], params[L2]
    lever = params[LEVER_A + k]
    y0 = -half if k == 0 else half
    u = _UNIT + UNIT_ROWS * k
    dt = _DTIP + 3 * M * k
    waist = _RATES + 3 * k * M
    # The tip moves at v + omega x (lever p).
    for j in range(M):
        for ln in range(BLOCK):
            w0, w1, w2 = _cross(w[_SPIN + j, ln], w[_SPIN + M + j, ln], w[_SPIN + 2 * M + j, ln],
                                lever * w[_P, ln], lever * w[_P + 1, ln], lever * w[_P + 2, ln])
            w[dt + j, ln] = (1.0 if j == 0 else 0.0) + w0
            w[dt + M + j, ln] = (1.0 if j == 1 else 0.0) + w1
            w[dt + 2 * M + j, ln] = (1.0 if j == 2 else 0.0) + w2
    # The plane frame: e_r = (0, -sin psi, cos psi), n = (0, -cos psi, -sin psi); the waist's rate.
    for j in range(M):
        for ln in range(BLOCK):
            sn, cs = w[u + 4, ln], w[u + 5, ln]
            n1, n2 = -cs, -sn
            w[waist + j, ln] = (n1 * w[dt + M + j, ln] + n2 * w[dt + 2 * M + j, ln]) / w[u + 3, ln]
    # The waist body: axes (e_x, e_r, n), turning about e_x, its origin still.
    for ln in range(BLOCK):
        sn, cs = w[u + 4, ln], w[u + 5, ln]
        w[_WROT, ln], w[_WROT + 3, ln], w[_WROT + 6, ln] = 1.0, 0.0, 0.0
        w[_WROT + 1, ln], w[_WROT + 4, ln], w[_WROT + 7, ln] = 0.0, -sn, cs
        w[_WROT + 2, ln], w[_WROT + 5, ln], w[_WROT + 8, ln] = 0.0, -cs, -sn
    for j in range(M):
        for ln in range(BLOCK):
            w[_WJW + j, ln] = w[waist + j, ln]
            w[_WJW + M + j, ln] = 0.0
            w[_WJW + 2 * M + j, ln] = 0.0
    first = UNIT_BODIES * k
    _add_body(w, masses[first], com[first], tensors[first], moved[first], spins[first], _WROT, _WJW, _STILL)
    for leg in range(2):
        lg = u + 6 + 6 * leg
        rate = _RATES + (3 * k + 1 + leg) * M
        de = _DELBOW + 3 * M * leg
        for j in range(M):
            for ln in range(BLOCK):
                er1, er2 = -w[u + 4, ln], w[u + 5, ln]
                d0, d1, denom = w[lg + 3, ln], w[lg + 4, ln], w[lg + 5, ln]
                along_r = er1 * w[dt + M + j, ln] + er2 * w[dt + 2 * M + j, ln]
                w[rate + j, ln] = (d0 * w[dt + j, ln] + d1 * along_r) / denom
        # The elbow moves in the plane at l2 thetadot (-sin e_x + cos e_r) and with it at ew n psidot.
        for j in range(M):
            for ln in range(BLOCK):
                sn, cs = w[u + 4, ln], w[u + 5, ln]
                er1, er2 = -sn, cs
                n1, n2 = -cs, -sn
                ct, st = w[lg + 1, ln], w[lg + 2, ln]
                ew = l2 * st
                turn = w[rate + j, ln]
                dpsi = w[waist + j, ln]
                w[de + j, ln] = l2 * -st * turn
                w[de + M + j, ln] = l2 * (ct * er1) * turn + ew * (n1 * dpsi)
                w[de + 2 * M + j, ln] = l2 * (ct * er2) * turn + ew * (n2 * dpsi)
        # Upper arm from the shoulder (sx, y0, 0), which is still, to the elbow; forearm from the elbow to the tip.
        _plane_link(w, False, u, leg, y0, l2, _STILL, de)
        _add_body(w, masses[first + 1 + leg], com[first + 1 + leg], tensors[first + 1 + leg], moved[first + 1 + leg],
                  spins[first + 1 + leg], _LROT, _LJW, _STILL)
        _plane_link(w, True, u, leg, y0, l2, de, dt)
        _add_body(w, masses[first + 3 + leg], com[first + 3 + leg], tensors[first + 3 + leg], moved[first + 3 + leg],
                  spins[first + 3 + leg], _LROT, _LJW, de)
    # Elbows, counterweights (behind the still shoulder: -(offset / l2) times the elbow's rate)
    # and the tip joint: points turning with the waist's frame.
    for leg in range(2):
        _add_body(w, masses[first + 5 + leg], com[first + 5 + leg], tensors[first + 5 + leg], moved[first + 5 + leg],
                  spins[first + 5 + leg], _WROT, _WJW, _DELBOW + 3 * M * leg)
    behind = -(params[BACK] / l2)
    for leg in range(2):
        de = _DELBOW + 3 * M * leg
        for e in range(3 * M):
            for ln in range(BLOCK):
                w[_DBACK + e, ln] = behind * w[de + e, ln]
        _add_body(w, masses[first + 7 + leg], com[first + 7 + leg], tensors[first + 7 + leg], moved[first + 7 + leg],
                  spins[first + 7 + leg], _WROT, _WJW, _DBACK)
    _add_body(w, masses[first + 9], com[first + 9], tensors[first + 9], moved[first + 9], spins[first + 9], _WROT,
              _WJW, dt)


@jit(allocates=True)
def inertia_points(x, params, masses, com, tensors, rotors, actuated, out):
    """``Lambda`` (N, 5, 5) per task twist at poses ``x`` (N, 5) into ``out``.

    Parameters
    ----------
    x : ndarray, shape (N, 5)
        Poses ``(x, y, z, rx, rz)`` (m, rad).
    params, masses, com, tensors, rotors, actuated : ndarray
        ``pack_mass``.
    out : ndarray, shape (N, 5, 5)
        kg, kg m and kg m^2 entries by the twist's units; ``nan`` where the pose is not finite or
        a leg does not reach.
    """
    n_bodies = masses.shape[0]
    moved = np.zeros(n_bodies, np.bool_)
    spins = np.zeros(n_bodies, np.bool_)
    for bd in range(n_bodies):
        for c in range(3):
            if com[bd, c] != 0.0:
                moved[bd] = True
            for e in range(3):
                if tensors[bd, c, e] != 0.0:
                    spins[bd] = True
    w = np.zeros((ROWS, BLOCK))                # _STILL and the still columns of _SPIN stay 0
    n_pts = x.shape[0]
    for lo in range(0, n_pts, BLOCK):
        nb = min(BLOCK, n_pts - lo)
        _poses(x, lo, nb, params, w)
        # The task twist's omega per column: 0 for v, a and b for the pen's turns.
        for c in range(3):
            for ln in range(BLOCK):
                w[_SPIN + c * M + 3, ln] = w[_A + c, ln]
                w[_SPIN + c * M + 4, ln] = w[_B + c, ln]
        for e in range(M * (M + 1) // 2):
            for ln in range(BLOCK):
                w[_LAM + e, ln] = 0.0
        for k in range(2):
            _unit(w, k, params, masses, com, tensors, moved, spins)
        # The pen: frame R = (a, p, b) at unit A's U-joint, turning at omega.
        for r in range(3):
            for ln in range(BLOCK):
                w[_LROT + 3 * r, ln] = w[_A + r, ln]
                w[_LROT + 3 * r + 1, ln] = w[_P + r, ln]
                w[_LROT + 3 * r + 2, ln] = w[_B + r, ln]
        _add_body(w, masses[PEN], com[PEN], tensors[PEN], moved[PEN], spins[PEN], _LROT, _SPIN, _DTIP)
        # The upper triangle was summed; numpy symmetrises its full sums, the same value to
        # rounding. Then the rotors of the actuated joints, G^T diag(r) G.
        e = _LAM
        for i in range(M):
            for j in range(i, M):
                for q in range(6):
                    if actuated[q]:
                        for ln in range(BLOCK):
                            w[e, ln] += w[_RATES + q * M + i, ln] * rotors[q] * w[_RATES + q * M + j, ln]
                e += 1
        for ln in range(nb):
            pt = lo + ln
            if w[_OK, ln] == 0.0:
                out[pt] = np.nan
                continue
            e = _LAM
            for i in range(M):
                for j in range(i, M):
                    out[pt, i, j] = w[e, ln]
                    out[pt, j, i] = w[e, ln]
                    e += 1
