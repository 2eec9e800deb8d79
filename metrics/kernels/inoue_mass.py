"""The Inoue platform's kinetic form (``kinematics.inoue``), compiled point by point.

``inertia_points`` gives what ``kinematics.dynamics.kinetic_form(mech, q, x, rotors=True)`` gives
for the model's poses: ``Lambda`` per rate of the pose coordinates, kg, from the bodies' exact
velocities as ``InouePlatform.body_velocities`` forms them (its docstring has the equations), body
by body in ``InouePlatform.bodies`` order: per leg the waist body (axes ``e_t, e_r, n``, turning
about ``e_t`` at ``psi'``), the two upper arms and two forearms (``bodies.plane_link_part``: in the
leg's plane, which turns with the waist), the two elbows, the two counterweights and the tip (each
carried by the waist's frame), then the platform. The same formulas in the same steps, summed in
another order: the two paths differ by rounding only (``tests/metrics/test_kernel_mass_inoue.py``).

The pose's configuration (the model's IK: ``InouePlatform.kinetic_configuration``) and ``J_l`` come
from the caller, in numpy; a pose the model does not reach gets ``nan``.
"""
from __future__ import annotations

import numpy as np

from .jit import jit
from .stewart_mass import add_body, centre_velocity, cross

#: Bodies per leg in ``InouePlatform.bodies``: waist, 2 upper arms, 2 forearms, 2 elbows, 2 counterweights, tip.
PER_LEG = 10


def pack_mass(mechanism) -> tuple[np.ndarray, ...]:
    """The model's geometry, bodies and rotors for ``inertia_points``.

    Parameters
    ----------
    mechanism : InouePlatform
        With a mass model.

    Returns
    -------
    tuple of ndarray
        ``e_t`` (3, 3) and the waist centres (3, 3); ``[shoulder separation, upper arm,
        counterweight offset]`` (3,); the actuated joints among the nine (n,) and their reflected
        rotor inertias (n,); the bodies' masses (31,), centres (31, 3) and tensors (31, 3, 3).
    """
    from kinematics.bodies import body_arrays

    e_t, base = mechanism.waist_axes()
    p = mechanism.params
    masses, com, tensors = body_arrays(mechanism.bodies())
    return (np.ascontiguousarray(e_t, dtype=np.float64), np.ascontiguousarray(base, dtype=np.float64),
            np.array([p.shoulder_separation, p.upper_arm, p.counterweight_offset], np.float64),
            np.array(mechanism.actuated, np.int64),
            np.ascontiguousarray(mechanism.reflected_rotor_inertias(), dtype=np.float64),
            np.ascontiguousarray(masses, dtype=np.float64), np.ascontiguousarray(com, dtype=np.float64),
            np.ascontiguousarray(tensors, dtype=np.float64))


@jit(inline=True)
def _plane_link(a, b, nrm, da, db, pw, frame, jw):
    """``bodies.plane_link_part``: the frame (3, 3) and angular velocity (3, 6) of a link from ``a`` to ``b``."""
    r0, r1, r2 = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    length = np.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
    e0, e1, e2 = r0 / length, r1 / length, r2 / length
    s0, s1, s2 = cross(nrm[0], nrm[1], nrm[2], e0, e1, e2)
    side = np.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
    y0, y1, y2 = s0 / side, s1 / side, s2 / side
    z0, z1, z2 = cross(e0, e1, e2, y0, y1, y2)
    frame[0, 0], frame[1, 0], frame[2, 0] = e0, e1, e2
    frame[0, 1], frame[1, 1], frame[2, 1] = y0, y1, y2
    frame[0, 2], frame[1, 2], frame[2, 2] = z0, z1, z2
    for j in range(6):
        spin = (y0 * (db[0, j] - da[0, j]) + y1 * (db[1, j] - da[1, j]) + y2 * (db[2, j] - da[2, j])) / length
        turn = spin - (pw[0, j] * z0 + pw[1, j] * z1 + pw[2, j] * z2)
        jw[0, j] = pw[0, j] + z0 * turn
        jw[1, j] = pw[1, j] + z1 * turn
        jw[2, j] = pw[2, j] + z2 * turn


@jit(allocates=True)
def inertia_points(x, ok, rot, left, arm, tips, er, nrm, w, distal, tangent, elbows, e_t, base, lengths, actuated,
                   rotors, masses, com, tensors, out):
    """``Lambda`` (N, 6, 6) per pose-coordinate rate at poses ``x`` (N, 6) into ``out``.

    Parameters
    ----------
    x : ndarray, shape (N, 6)
        Poses (m, rad).
    ok : ndarray of bool, shape (N,)
        Where the model reaches the pose (else ``nan``).
    rot, left : ndarray, shape (N, 3, 3)
        ``R(x)`` and ``J_l`` of the rotation vectors.
    arm, tips, er, nrm : ndarray, shape (N, 3, 3)
        Per leg ``R a_k``, the tip, ``e_r`` and the plane's normal.
    w : ndarray, shape (N, 3)
        The tips' distances from the waist axes.
    distal, tangent, elbows : ndarray, shape (N, 3, 2, 2)
        Per leg and shoulder, in the plane: tip - elbow, ``d(cos, sin)/d theta`` and the elbow.
    e_t, base, lengths, actuated, rotors, masses, com, tensors : ndarray
        ``pack_mass``.
    out : ndarray, shape (N, 6, 6)
    """
    sep, upper, offset = lengths[0], lengths[1], lengths[2]
    lam = np.empty((6, 6))
    jv = np.empty((3, 6))
    jw = np.empty((3, 6))
    zero = np.zeros((3, 6))
    dpos = np.zeros((3, 6))
    dtip = np.empty((3, 6))
    der = np.empty((3, 6))
    waist_w = np.empty((3, 6))
    platform_w = np.empty((3, 6))
    dshoulder = np.zeros((3, 6))               # the shoulders sit on the waist axis: still
    delbow = np.empty((2, 3, 6))
    dback = np.empty((3, 6))
    waist = np.empty((3, 3))
    frame = np.empty((3, 3))
    body = np.empty((3, 6))
    turned = np.empty((3, 6))
    rates = np.empty((9, 6))
    a = np.empty(3)
    b = np.empty(3)
    tip = np.empty(3)
    for c in range(3):
        dpos[c, c] = 1.0
    for p in range(x.shape[0]):
        if not ok[p]:
            out[p] = np.nan
            continue
        lam[:] = 0.0
        # The platform turns at [0 | J_l], its origin (the task point) moves at [I | 0].
        for c in range(3):
            for j in range(6):
                platform_w[c, j] = left[p, c, j - 3] if j >= 3 else 0.0
        r = rot[p]
        for k in range(3):
            t0, t1, t2 = e_t[k, 0], e_t[k, 1], e_t[k, 2]
            q0, q1, q2 = er[p, k, 0], er[p, k, 1], er[p, k, 2]
            n0, n1, n2 = nrm[p, k, 0], nrm[p, k, 1], nrm[p, k, 2]
            for c in range(3):
                tip[c] = tips[p, k, c]
            for j in range(6):
                m0, m1, m2 = cross(platform_w[0, j], platform_w[1, j], platform_w[2, j],
                                   arm[p, k, 0], arm[p, k, 1], arm[p, k, 2])
                dtip[0, j], dtip[1, j], dtip[2, j] = dpos[0, j] + m0, dpos[1, j] + m1, dpos[2, j] + m2
                dpsi = (n0 * dtip[0, j] + n1 * dtip[1, j] + n2 * dtip[2, j]) / w[p, k]
                rates[6 + k, j] = dpsi
                der[0, j], der[1, j], der[2, j] = n0 * dpsi, n1 * dpsi, n2 * dpsi
                waist_w[0, j], waist_w[1, j], waist_w[2, j] = t0 * dpsi, t1 * dpsi, t2 * dpsi
            waist[0, 0], waist[1, 0], waist[2, 0] = t0, t1, t2
            waist[0, 1], waist[1, 1], waist[2, 1] = q0, q1, q2
            waist[0, 2], waist[1, 2], waist[2, 2] = n0, n1, n2
            first = k * PER_LEG
            centre_velocity(jv, zero, waist_w, waist, com[first])
            add_body(lam, masses[first], tensors[first], waist, jv, waist_w, body, turned)
            for s in range(2):
                d0, d1 = distal[p, k, s, 0], distal[p, k, s, 1]
                g0, g1, g2 = d0 * t0 + d1 * q0, d0 * t1 + d1 * q1, d0 * t2 + d1 * q2
                scale = upper * (d0 * tangent[p, k, s, 0] + d1 * tangent[p, k, s, 1])
                u0 = tangent[p, k, s, 0] * t0 + tangent[p, k, s, 1] * q0
                u1 = tangent[p, k, s, 0] * t1 + tangent[p, k, s, 1] * q1
                u2 = tangent[p, k, s, 0] * t2 + tangent[p, k, s, 1] * q2
                ew = elbows[p, k, s, 1]
                for j in range(6):
                    dtheta = (g0 * dtip[0, j] + g1 * dtip[1, j] + g2 * dtip[2, j]) / scale
                    rates[2 * k + s, j] = dtheta
                    delbow[s, 0, j] = upper * u0 * dtheta + ew * der[0, j]
                    delbow[s, 1, j] = upper * u1 * dtheta + ew * der[1, j]
                    delbow[s, 2, j] = upper * u2 * dtheta + ew * der[2, j]
            for s in range(2):
                # Shoulder s on the waist axis, its elbow in the plane.
                half = -0.5 * sep if s == 0 else 0.5 * sep
                eu, ew = elbows[p, k, s, 0], elbows[p, k, s, 1]
                for c in range(3):
                    a[c] = base[k, c] + half * e_t[k, c]
                b[0] = base[k, 0] + eu * t0 + ew * q0
                b[1] = base[k, 1] + eu * t1 + ew * q1
                b[2] = base[k, 2] + eu * t2 + ew * q2
                _plane_link(a, b, nrm[p, k], dshoulder, delbow[s], waist_w, frame, jw)
                centre_velocity(jv, dshoulder, jw, frame, com[first + 1 + s])
                add_body(lam, masses[first + 1 + s], tensors[first + 1 + s], frame, jv, jw, body, turned)
                _plane_link(b, tip, nrm[p, k], delbow[s], dtip, waist_w, frame, jw)
                centre_velocity(jv, delbow[s], jw, frame, com[first + 3 + s])
                add_body(lam, masses[first + 3 + s], tensors[first + 3 + s], frame, jv, jw, body, turned)
            # Carried by the waist's frame: the elbows, the counterweights (behind the shoulders), the tip.
            for s in range(2):
                centre_velocity(jv, delbow[s], waist_w, waist, com[first + 5 + s])
                add_body(lam, masses[first + 5 + s], tensors[first + 5 + s], waist, jv, waist_w, body, turned)
            for s in range(2):
                for c in range(3):
                    for j in range(6):
                        dback[c, j] = -(offset / upper) * (delbow[s, c, j] - dshoulder[c, j]) + dshoulder[c, j]
                centre_velocity(jv, dback, waist_w, waist, com[first + 7 + s])
                add_body(lam, masses[first + 7 + s], tensors[first + 7 + s], waist, jv, waist_w, body, turned)
            centre_velocity(jv, dtip, waist_w, waist, com[first + 9])
            add_body(lam, masses[first + 9], tensors[first + 9], waist, jv, waist_w, body, turned)
        centre_velocity(jv, dpos, platform_w, r, com[3 * PER_LEG])
        add_body(lam, masses[3 * PER_LEG], tensors[3 * PER_LEG], r, jv, platform_w, body, turned)
        for i in range(6):
            for j in range(i, 6):
                acc = lam[i, j]
                for u in range(actuated.shape[0]):
                    acc += rates[actuated[u], i] * rotors[u] * rates[actuated[u], j]
                out[p, i, j] = acc
                out[p, j, i] = acc
