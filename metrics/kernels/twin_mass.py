"""The Twin-Pantograph's kinetic form (``kinematics.twin_pantograph``), compiled point by point.

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


@jit(inline=True)
def _cross(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@jit(inline=True)
def _add_body(lam, mass, com, tensor, rot, jw, do, jv, body, turned):
    """``lam += m Jv^T Jv + (R^T Jw)^T I (R^T Jw)`` (upper triangle) of one body, ``Jv = do + Jw x R c``.

    ``rot`` (3, 3) its axes, ``jw``, ``do`` (3, M) its angular velocity and its origin's velocity per
    column; ``jv``, ``body``, ``turned`` (3, M) scratch. A zero tensor (a point, a line's axis aside)
    adds no rotation term, as ``kinetic_columns`` skips it.
    """
    c0 = rot[0, 0] * com[0] + rot[0, 1] * com[1] + rot[0, 2] * com[2]
    c1 = rot[1, 0] * com[0] + rot[1, 1] * com[1] + rot[1, 2] * com[2]
    c2 = rot[2, 0] * com[0] + rot[2, 1] * com[1] + rot[2, 2] * com[2]
    moved = com[0] != 0.0 or com[1] != 0.0 or com[2] != 0.0
    for j in range(M):
        if moved:
            w0, w1, w2 = _cross(jw[0, j], jw[1, j], jw[2, j], c0, c1, c2)
            jv[0, j], jv[1, j], jv[2, j] = do[0, j] + w0, do[1, j] + w1, do[2, j] + w2
        else:
            jv[0, j], jv[1, j], jv[2, j] = do[0, j], do[1, j], do[2, j]
    spins = False
    for c in range(3):
        for e in range(3):
            if tensor[c, e] != 0.0:
                spins = True
    if spins:
        for c in range(3):
            for a in range(M):
                body[c, a] = rot[0, c] * jw[0, a] + rot[1, c] * jw[1, a] + rot[2, c] * jw[2, a]
        for c in range(3):
            for a in range(M):
                turned[c, a] = tensor[c, 0] * body[0, a] + tensor[c, 1] * body[1, a] + tensor[c, 2] * body[2, a]
    for a in range(M):
        for b in range(a, M):
            term = mass * (jv[0, a] * jv[0, b] + jv[1, a] * jv[1, b] + jv[2, a] * jv[2, b])
            if spins:
                term += body[0, a] * turned[0, b] + body[1, a] * turned[1, b] + body[2, a] * turned[2, b]
            lam[a, b] += term


@jit(inline=True)
def _plane_link(rot, jw, a0, a1, a2, b0, b1, b2, n0, n1, n2, da, db, plane):
    """``kinematics.bodies.plane_link_part`` of a link from ``a`` to ``b`` in the plane of normal ``n``
    turning at ``plane`` (3, M): its axes into ``rot``, its angular velocity into ``jw``."""
    r0, r1, r2 = b0 - a0, b1 - a1, b2 - a2
    length = math.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
    x0, x1, x2 = r0 / length, r1 / length, r2 / length
    s0, s1, s2 = _cross(n0, n1, n2, x0, x1, x2)
    width = math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
    y0, y1, y2 = s0 / width, s1 / width, s2 / width
    z0, z1, z2 = _cross(x0, x1, x2, y0, y1, y2)
    rot[0, 0], rot[1, 0], rot[2, 0] = x0, x1, x2
    rot[0, 1], rot[1, 1], rot[2, 1] = y0, y1, y2
    rot[0, 2], rot[1, 2], rot[2, 2] = z0, z1, z2
    for j in range(M):
        spin = (y0 * (db[0, j] - da[0, j]) + y1 * (db[1, j] - da[1, j]) + y2 * (db[2, j] - da[2, j])) / length
        turn = spin - (plane[0, j] * z0 + plane[1, j] * z1 + plane[2, j] * z2)
        jw[0, j] = plane[0, j] + z0 * turn
        jw[1, j] = plane[1, j] + z1 * turn
        jw[2, j] = plane[2, j] + z2 * turn


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
    half, l1, l2, l3, back = params[HALF], params[L1], params[L2], params[L3], params[BACK]
    lam = np.empty((M, M))
    rates = np.empty((6, M))
    vel = np.empty((3, M))         # the task twist's columns: v ...
    spin = np.empty((3, M))        # ... and omega
    dtip = np.empty((2, 3, M))
    waist_w = np.empty((3, M))
    still = np.zeros((3, M))
    delbow = np.empty((2, 3, M))
    dback = np.empty((3, M))
    wrot = np.empty((3, 3))
    lrot = np.empty((3, 3))
    jw = np.empty((3, M))
    jv = np.empty((3, M))
    body = np.empty((3, M))
    turned = np.empty((3, M))
    for pt in range(x.shape[0]):
        finite = True
        for k in range(5):
            if not np.isfinite(x[pt, k]):
                finite = False
        if not finite:
            out[pt] = np.nan
            continue
        a, p, b = _pen_frame(x[pt, 3], x[pt, 4])
        for c in range(3):
            for j in range(M):
                vel[c, j] = 1.0 if j == c else 0.0
            spin[c, 3] = a[c]
            spin[c, 4] = b[c]
            for j in range(3):
                spin[c, j] = 0.0
        for c in range(3):
            for j in range(3, M):
                vel[c, j] = 0.0
        lam[:] = 0.0
        ok = True
        for k in range(2):
            lever = params[LEVER_A + k]
            y0 = -half if k == 0 else half
            reach, tip, w, sn, cs, leg0, leg1 = unit_pose(x[pt, 0], x[pt, 1], x[pt, 2], p, lever, y0, l1, l2, l3)
            ok = ok and reach
            t0, t1, t2 = tip
            # The tip moves at v + omega x (lever p).
            for j in range(M):
                w0, w1, w2 = _cross(spin[0, j], spin[1, j], spin[2, j], lever * p[0], lever * p[1], lever * p[2])
                dtip[k, 0, j] = vel[0, j] + w0
                dtip[k, 1, j] = vel[1, j] + w1
                dtip[k, 2, j] = vel[2, j] + w2
            # The plane frame: e_r = (0, -sin psi, cos psi), n = (0, -cos psi, -sin psi).
            er1, er2 = -sn, cs
            n1, n2 = -cs, -sn
            for j in range(M):
                rates[3 * k, j] = (n1 * dtip[k, 1, j] + n2 * dtip[k, 2, j]) / w
            # The waist body: axes (e_x, e_r, n), turning about e_x, its origin still.
            wrot[0, 0], wrot[1, 0], wrot[2, 0] = 1.0, 0.0, 0.0
            wrot[0, 1], wrot[1, 1], wrot[2, 1] = 0.0, er1, er2
            wrot[0, 2], wrot[1, 2], wrot[2, 2] = 0.0, n1, n2
            for j in range(M):
                waist_w[0, j], waist_w[1, j], waist_w[2, j] = rates[3 * k, j], 0.0, 0.0
            first = UNIT_BODIES * k
            _add_body(lam, masses[first], com[first], tensors[first], wrot, waist_w, still, jv, body, turned)
            for leg in range(2):
                sx, ct, st, d0, d1, denom = leg0 if leg == 0 else leg1
                ex, ew = sx + l2 * ct, l2 * st                     # the elbow, in the plane
                row = 3 * k + 1 + leg
                for j in range(M):
                    along_r = er1 * dtip[k, 1, j] + er2 * dtip[k, 2, j]
                    rates[row, j] = (d0 * dtip[k, 0, j] + d1 * along_r) / denom
                # The elbow moves in the plane at l2 thetadot (-sin e_x + cos e_r) and with it at ew n psidot.
                for j in range(M):
                    turn = rates[row, j]
                    dpsi = rates[3 * k, j]
                    delbow[leg, 0, j] = l2 * -st * turn
                    delbow[leg, 1, j] = l2 * (ct * er1) * turn + ew * (n1 * dpsi)
                    delbow[leg, 2, j] = l2 * (ct * er2) * turn + ew * (n2 * dpsi)
                e0, e1, e2 = ex, y0 + ew * er1, ew * er2
                # Upper arm from the shoulder (sx, y0, 0), which is still, to the elbow.
                _plane_link(lrot, jw, sx, y0, 0.0, e0, e1, e2, 0.0, n1, n2, still, delbow[leg], waist_w)
                _add_body(lam, masses[first + 1 + leg], com[first + 1 + leg], tensors[first + 1 + leg], lrot, jw,
                          still, jv, body, turned)
                # Forearm from the elbow to the tip.
                _plane_link(lrot, jw, e0, e1, e2, t0, t1, t2, 0.0, n1, n2, delbow[leg], dtip[k], waist_w)
                _add_body(lam, masses[first + 3 + leg], com[first + 3 + leg], tensors[first + 3 + leg], lrot, jw,
                          delbow[leg], jv, body, turned)
            # Elbows, counterweights (behind the still shoulder: -(offset / l2) times the elbow's
            # rate) and the tip joint: points turning with the waist's frame.
            for leg in range(2):
                _add_body(lam, masses[first + 5 + leg], com[first + 5 + leg], tensors[first + 5 + leg], wrot,
                          waist_w, delbow[leg], jv, body, turned)
            for leg in range(2):
                for c in range(3):
                    for j in range(M):
                        dback[c, j] = -(back / l2) * delbow[leg, c, j]
                _add_body(lam, masses[first + 7 + leg], com[first + 7 + leg], tensors[first + 7 + leg], wrot,
                          waist_w, dback, jv, body, turned)
            _add_body(lam, masses[first + 9], com[first + 9], tensors[first + 9], wrot, waist_w, dtip[k], jv, body,
                      turned)
        if not ok:
            out[pt] = np.nan
            continue
        # The pen: frame R at unit A's U-joint, turning at omega.
        lrot[0, 0], lrot[1, 0], lrot[2, 0] = a[0], a[1], a[2]
        lrot[0, 1], lrot[1, 1], lrot[2, 1] = p[0], p[1], p[2]
        lrot[0, 2], lrot[1, 2], lrot[2, 2] = b[0], b[1], b[2]
        _add_body(lam, masses[PEN], com[PEN], tensors[PEN], lrot, spin, dtip[0], jv, body, turned)
        # The upper triangle was summed; numpy symmetrises its full sums, the same value to
        # rounding. Then the rotors of the actuated joints, G^T diag(r) G.
        for i in range(M):
            for j in range(i, M):
                acc = lam[i, j]
                for q in range(6):
                    if actuated[q]:
                        acc += rates[q, i] * rotors[q] * rates[q, j]
                out[pt, i, j] = acc
                out[pt, j, i] = acc
