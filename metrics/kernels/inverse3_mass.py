"""The Inverse3 family's kinetic form (``kinematics.dynamics.kinetic_form``) at one point, compiled, in scalars.

The model places its bodies from the task pose (``mass_coordinates = "task"``), so the form is the
task-space inertia (``kinematics.bodies``, ``kinematics.dynamics``)

    Lambda(x) = sum_b m_b Jv_b^T Jv_b + Jw_b^T R_b I_b R_b^T Jw_b  +  G^T diag(J_u N_u^2) G,

with ``Jv_b``, ``Jw_b`` the velocity of body b's centre and its angular velocity per unit task rate
(``Inverse3.body_velocities``) and ``G = dq/dx = J^-1``. Column ``a`` of those Jacobians is the
motion at the joint rates ``qdot = G e_a``; ``inertia`` takes it in closed form per body:

=========  ===============================================  ==========================================
body       frame (``Inverse3.body_poses``)                  angular velocity; origin's velocity
=========  ===============================================  ==========================================
turret     ``[e_r, n, z]``, origin on the base axis          ``z qdot_0``; still
proximal   ``e_x = cos psi e_r + sin psi z`` from the        ``z qdot_0 + n spin`` (``plane_link_part``);
i, distal  motors' centre O (distal: from elbow i) to the    O: ``-c e_r qdot_0``; elbow i: O's plus
i          elbow (P), ``e_y = sin psi e_r - cos psi z``,     ``l1 (cos phi_i n qdot_0 + (-sin phi_i e_r
           ``e_z = n`` (``link_frames``)                      + cos phi_i z) qdot_i)``
handle     translating                                      0; ``e_a`` (``Jv = I``: ``m_h I`` exactly)
=========  ===============================================  ==========================================

with ``e_r = (cos th0, sin th0, 0)``, ``n = (-sin th0, cos th0, 0)``, ``c = plane_offset``,
``phi_i = q_i - 90 deg`` and ``spin = e_y . (b' - a') / |b - a|`` for a link from ``a`` to ``b``
(proximal: ``-qdot_i``). Each body's velocities are taken in its own axes (``R_b^T v``): ``|v|^2``
is the same in any axes, the tensor is constant there, and the in-plane frame makes most
components one or two products. The centre moves at ``do + omega x R c`` (``stack_bodies``), in
body axes ``R^T do + omega_B x c``.

``pack_mass`` packs what ``inertia`` reads; ``inertia_points`` loops it over points (tests,
benchmarks). The caller hands singular or ill-conditioned poses to the numpy path before calling.
"""
from __future__ import annotations

import math

import numpy as np

from .jit import jit

_QUARTER = math.pi / 2.0
#: The bodies ``Inverse3.bodies`` gives, in this order (``pack_mass`` checks).
BODIES = ("turret", "proximal_1", "proximal_2", "distal_1", "distal_2", "handle")
#: Offsets into ``pack_mass``'s array: the reflected rotor inertias, then each body's block of
#: ``BODY_SIZE`` (mass, centre (3), inertia (Ixx, Iyy, Izz, Ixy, Ixz, Iyz)).
ROTORS = 4
BODY0 = 7
BODY_SIZE = 10
SIZE = BODY0 + len(BODIES) * BODY_SIZE


def pack_mass(mechanism) -> np.ndarray:
    """What ``inertia`` reads of an Inverse3 model with a mass model, float64 (67,).

    Layout: ``[0]`` plane offset ``c`` (m), ``[1]`` proximal length ``l1`` (m), ``[2]`` distal
    length ``l2`` (m), ``[3]`` base height (m); ``[4:7]`` the reflected rotor inertias
    ``J_u N_u^2`` (kg m^2, ``reflected_rotor_inertias``); then for each body of ``BODIES``, at
    ``BODY0 + BODY_SIZE b``: mass (kg), centre of mass in the body frame (3, m) and the inertia
    tensor about it in body axes ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` (kg m^2, ``Body.inertia``).

    Parameters
    ----------
    mechanism : Inverse3
        With ``has_mass_model``.

    Returns
    -------
    ndarray, shape (67,)

    Raises
    ------
    ValueError
        If the model's bodies are not ``BODIES`` in this order.
    """
    bodies = mechanism.bodies()
    names = tuple(b.name for b in bodies)
    if names != BODIES:
        raise ValueError(f"inverse3_mass.pack_mass needs the bodies {BODIES}, got {names}")
    p = mechanism.params
    out = np.empty(SIZE)
    out[:ROTORS] = (p.plane_offset, p.proximal_length, p.distal_length, p.base_height)
    out[ROTORS:BODY0] = mechanism.reflected_rotor_inertias()
    for b, body in enumerate(bodies):
        k = BODY0 + BODY_SIZE * b
        out[k] = body.mass
        out[k + 1:k + 4] = body.com
        out[k + 4:k + 10] = body.inertia
    return out


@jit()
def _link_axes(cos_psi, sin_psi, g0, spin, v_r, v_z, v_n):
    """A link in the five-bar plane at angle ``psi``: body-axes angular velocity and origin velocity.

    ``omega = z g0 + n spin`` (``plane_link_part``; ``w_p . n = z . n = 0``) in the axes ``e_x``,
    ``e_y``, ``e_z = n``: ``(sin psi g0, -cos psi g0, spin)``. The origin's velocity, given by its
    ``e_r``, ``z``, ``n`` components, is ``(cos psi v_r + sin psi v_z, sin psi v_r - cos psi v_z, v_n)``.
    """
    return (sin_psi * g0, -cos_psi * g0, spin,
            cos_psi * v_r + sin_psi * v_z, sin_psi * v_r - cos_psi * v_z, v_n)


@jit()
def _centre(mp, k, wx, wy, wz, ox, oy, oz):
    """Body ``k``'s centre velocity in body axes, ``o + omega x c`` (``stack_bodies``), and ``I omega``."""
    cx, cy, cz = mp[k + 1], mp[k + 2], mp[k + 3]
    vx = ox + (wy * cz - wz * cy)
    vy = oy + (wz * cx - wx * cz)
    vz = oz + (wx * cy - wy * cx)
    ixx, iyy, izz, ixy, ixz, iyz = mp[k + 4], mp[k + 5], mp[k + 6], mp[k + 7], mp[k + 8], mp[k + 9]
    return (vx, vy, vz, ixx * wx + ixy * wy + ixz * wz, ixy * wx + iyy * wy + iyz * wz,
            ixz * wx + iyz * wy + izz * wz)


@jit()
def _body(mp, k, col0, col1, col2):
    """Body ``k``'s ``m Jv^T Jv + Jw_B^T I Jw_B`` (``kinetic_columns``), upper triangle, from its three
    task-rate columns ``(wx, wy, wz, ox, oy, oz)`` (``_link_axes``)."""
    m = mp[k]
    v0x, v0y, v0z, h0x, h0y, h0z = _centre(mp, k, *col0)
    v1x, v1y, v1z, h1x, h1y, h1z = _centre(mp, k, *col1)
    v2x, v2y, v2z, h2x, h2y, h2z = _centre(mp, k, *col2)
    w0x, w0y, w0z = col0[0], col0[1], col0[2]
    w1x, w1y, w1z = col1[0], col1[1], col1[2]
    w2x, w2y, w2z = col2[0], col2[1], col2[2]
    # Mass last: a mass scaled by 2^k scales every term exactly (kinetic_columns weights by it too).
    k00 = (v0x * v0x + v0y * v0y + v0z * v0z) * m + (w0x * h0x + w0y * h0y + w0z * h0z)
    k01 = (v0x * v1x + v0y * v1y + v0z * v1z) * m + (w0x * h1x + w0y * h1y + w0z * h1z)
    k02 = (v0x * v2x + v0y * v2y + v0z * v2z) * m + (w0x * h2x + w0y * h2y + w0z * h2z)
    k11 = (v1x * v1x + v1y * v1y + v1z * v1z) * m + (w1x * h1x + w1y * h1y + w1z * h1z)
    k12 = (v1x * v2x + v1y * v2y + v1z * v2z) * m + (w1x * h2x + w1y * h2y + w1z * h2z)
    k22 = (v2x * v2x + v2y * v2y + v2z * v2z) * m + (w2x * h2x + w2y * h2y + w2z * h2z)
    return k00, k01, k02, k11, k12, k22


@jit()
def _proximal(mp, k, cos_phi, sin_phi, g00, g01, g02, gi0, gi1, gi2):
    """Proximal link (motors' centre O to elbow i, ``psi = phi_i``): spin ``-qdot_i``, origin O at
    ``-c e_r qdot_0`` (``body_velocities``: ``dcentre = c dnormal``, ``dnormal = -e_r G_0``)."""
    c = mp[0]
    return _body(mp, k, _link_axes(cos_phi, sin_phi, g00, -gi0, -c * g00, 0.0, 0.0),
                 _link_axes(cos_phi, sin_phi, g01, -gi1, -c * g01, 0.0, 0.0),
                 _link_axes(cos_phi, sin_phi, g02, -gi2, -c * g02, 0.0, 0.0))


@jit()
def _distal_column(c, l1, cos_phi, sin_phi, cos_psi, sin_psi, length, ey_a, g0, gi):
    """One task-rate column of distal link i (elbow i to P): the elbow's velocity ``delbows``
    in ``e_r``, ``z``, ``n`` components, and ``spin = e_y . (e_a - elbow') / |P - elbow|``."""
    v_r = -c * g0 - l1 * sin_phi * gi
    v_z = l1 * cos_phi * gi
    v_n = l1 * cos_phi * g0
    wx, wy, _, ox, oy, oz = _link_axes(cos_psi, sin_psi, g0, 0.0, v_r, v_z, v_n)
    # e_y . elbow' is the origin's e_y component, oy.
    return wx, wy, (ey_a - oy) / length, ox, oy, oz


@jit()
def _distal(mp, k, u, w, cos_phi, sin_phi, cos0, sin0, g00, g01, g02, gi0, gi1, gi2):
    """Distal link from elbow i to P = O + u e_r + w z (``plane_link_part``)."""
    c, l1 = mp[0], mp[1]
    # P - elbow_i in the plane (its n part is 0 for a consistent pose), then link_frames' e_x, e_y.
    du = u - l1 * cos_phi
    dw = w - l1 * sin_phi
    length = math.sqrt(du * du + dw * dw)
    cos_psi, sin_psi = du / length, dw / length
    # e_y = sin psi e_r - cos psi z in base-frame components: e_y . e_a for the handle's rate e_a.
    ey0, ey1, ey2 = sin_psi * cos0, sin_psi * sin0, -cos_psi
    return _body(mp, k, _distal_column(c, l1, cos_phi, sin_phi, cos_psi, sin_psi, length, ey0, g00, gi0),
                 _distal_column(c, l1, cos_phi, sin_phi, cos_psi, sin_psi, length, ey1, g01, gi1),
                 _distal_column(c, l1, cos_phi, sin_phi, cos_psi, sin_psi, length, ey2, g02, gi2))


@jit()
def inertia(x0, x1, x2, q0, q1, q2, a00, a01, a02, a10, a11, a12, a20, a21, a22, mp):
    """The kinetic form ``Lambda(x)`` at one feasible, regular pose: its upper triangle, kg.

    Parameters
    ----------
    x0, x1, x2 : float
        The task point (m).
    q0, q1, q2 : float
        Its joints (``Inverse3.inverse``), rad.
    a00, ..., a22 : float
        ``J[r, c]`` (``Inverse3.jacobian``, m/rad, without gear ratios), regular.
    mp : ndarray, shape (67,)
        ``pack_mass``.

    Returns
    -------
    tuple of 6 float
        ``(k00, k01, k02, k11, k12, k22)``, row-major upper triangle.
    """
    # G = J^-1 by its adjugate, as Inverse3.body_velocities: row u is col(u+1) x col(u+2) / det J.
    g00, g01, g02 = a11 * a22 - a21 * a12, a21 * a02 - a01 * a22, a01 * a12 - a11 * a02
    g10, g11, g12 = a12 * a20 - a22 * a10, a22 * a00 - a02 * a20, a02 * a10 - a12 * a00
    g20, g21, g22 = a10 * a21 - a20 * a11, a20 * a01 - a00 * a21, a00 * a11 - a10 * a01
    det = a00 * g00 + a10 * g01 + a20 * g02
    g00, g01, g02 = g00 / det, g01 / det, g02 / det
    g10, g11, g12 = g10 / det, g11 / det, g12 / det
    g20, g21, g22 = g20 / det, g21 / det, g22 / det
    cos0, sin0 = math.cos(q0), math.sin(q0)
    cos1, sin1 = math.cos(q1 - _QUARTER), math.sin(q1 - _QUARTER)
    cos2, sin2 = math.cos(q2 - _QUARTER), math.sin(q2 - _QUARTER)
    # Turret: omega_B = (0, 0, qdot_0), origin still, centre at omega_B x c: its only entries are
    # qdot_0 qdot_0 (m (cx^2 + cy^2) + Izz).
    t = BODY0
    turret = (mp[t + 1] * mp[t + 1] + mp[t + 2] * mp[t + 2]) * mp[t] + mp[t + 6]
    k00, k01, k02 = g00 * g00 * turret, g00 * g01 * turret, g00 * g02 * turret
    k11, k12, k22 = g01 * g01 * turret, g01 * g02 * turret, g02 * g02 * turret
    # The links, in BODIES order; P in the plane: u = x . e_r, w = z - base_height.
    u = x0 * cos0 + x1 * sin0
    w = x2 - mp[3]
    for term in (_proximal(mp, BODY0 + BODY_SIZE, cos1, sin1, g00, g01, g02, g10, g11, g12),
                 _proximal(mp, BODY0 + 2 * BODY_SIZE, cos2, sin2, g00, g01, g02, g20, g21, g22),
                 _distal(mp, BODY0 + 3 * BODY_SIZE, u, w, cos1, sin1, cos0, sin0, g00, g01, g02, g10, g11, g12),
                 _distal(mp, BODY0 + 4 * BODY_SIZE, u, w, cos2, sin2, cos0, sin0, g00, g01, g02, g20, g21, g22)):
        k00, k01, k02 = k00 + term[0], k01 + term[1], k02 + term[2]
        k11, k12, k22 = k11 + term[3], k12 + term[4], k22 + term[5]
    # Handle: Jv = I per task rate (translating_part(dx)), Jw = 0.
    handle = mp[BODY0 + 5 * BODY_SIZE]
    k00, k11, k22 = k00 + handle, k11 + handle, k22 + handle
    # Rotors: G^T diag(r) G (kinetic_form), sum over u of (G_ua r_u) G_ub.
    r0, r1, r2 = mp[ROTORS], mp[ROTORS + 1], mp[ROTORS + 2]
    k00 += g00 * r0 * g00 + g10 * r1 * g10 + g20 * r2 * g20
    k01 += g00 * r0 * g01 + g10 * r1 * g11 + g20 * r2 * g21
    k02 += g00 * r0 * g02 + g10 * r1 * g12 + g20 * r2 * g22
    k11 += g01 * r0 * g01 + g11 * r1 * g11 + g21 * r2 * g21
    k12 += g01 * r0 * g02 + g11 * r1 * g12 + g21 * r2 * g22
    k22 += g02 * r0 * g02 + g12 * r1 * g12 + g22 * r2 * g22
    return k00, k01, k02, k11, k12, k22


@jit()
def inertia_points(x, q, jac, mp):
    """``inertia`` at every point, as full symmetric matrices (tests, benchmarks).

    Parameters
    ----------
    x : ndarray, shape (k, 3)
        Feasible task points, m.
    q : ndarray, shape (k, 3)
        Their joints, rad.
    jac : ndarray, shape (k, 3, 3)
        Their Jacobians ``J = dx/dq``, regular.
    mp : ndarray, shape (67,)
        ``pack_mass``.

    Returns
    -------
    ndarray, shape (k, 3, 3)
        ``Lambda(x)``, kg.
    """
    n = x.shape[0]
    out = np.empty((n, 3, 3))
    for i in range(n):
        j = jac[i]
        k00, k01, k02, k11, k12, k22 = inertia(x[i, 0], x[i, 1], x[i, 2], q[i, 0], q[i, 1], q[i, 2],
                                               j[0, 0], j[0, 1], j[0, 2], j[1, 0], j[1, 1], j[1, 2],
                                               j[2, 0], j[2, 1], j[2, 2], mp)
        out[i, 0, 0], out[i, 0, 1], out[i, 0, 2] = k00, k01, k02
        out[i, 1, 0], out[i, 1, 1], out[i, 1, 2] = k01, k11, k12
        out[i, 2, 0], out[i, 2, 1], out[i, 2, 2] = k02, k12, k22
    return out
