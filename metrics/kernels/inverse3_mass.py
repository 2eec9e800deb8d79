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

import numba
import numpy as np

from .dynamics import BODY_FLOATS, inertia_points_of, pack_bodies
from .jit import jit

_QUARTER = math.pi / 2.0
#: The bodies ``Inverse3.bodies`` gives, in this order (``pack_mass`` checks).
BODIES = ("turret", "proximal_1", "proximal_2", "distal_1", "distal_2", "handle")
#: Offsets into ``pack_mass``'s array: the reflected rotor inertias, then each body's block of
#: ``BODY_SIZE`` (mass, centre (3), inertia (Ixx, Iyy, Izz, Ixy, Ixz, Iyz)).
ROTORS = 4
BODY0 = 7
BODY_SIZE = BODY_FLOATS
SIZE = BODY0 + len(BODIES) * BODY_SIZE
#: The private helpers are inlined into ``inertia`` by numba (its IR), not called: numba keeps
#: calls between compiled functions, and at 9 calls a point they took a third of the time
#: (300 000 points: 75-86 ms called, 53-60 ms inlined, load average 3 on 2 cores). They are
#: compiled only as part of ``inertia``, which is cached (``jit``).
_inline = numba.njit(inline="always", nogil=True, error_model="numpy")


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
    p = mechanism.params
    out = np.empty(SIZE)
    pack_bodies(mechanism, BODIES, out, BODY0)
    out[:ROTORS] = (p.plane_offset, p.proximal_length, p.distal_length, p.base_height)
    out[ROTORS:BODY0] = mechanism.reflected_rotor_inertias()
    return out


@_inline
def _plane_link(mp, k, cos_psi, sin_psi, g0, spin, v_r, v_z, v_n):
    """Body ``k``, a link in the five-bar plane at angle ``psi``: its ``m Jv^T Jv + Jw_B^T I Jw_B``
    (``kinetic_columns``), upper triangle.

    Per task rate ``a`` (the tuples' entries): the base joint's rate ``g0[a]``, the link's
    ``spin[a]`` about ``n``, its origin's velocity by ``e_r``, ``z``, ``n`` components ``v_r[a]``,
    ``v_z[a]``, ``v_n[a]``. In the axes ``e_x``, ``e_y``, ``e_z = n`` the angular velocity
    ``omega = z g0 + n spin`` (``plane_link_part``; ``w_p . n = z . n = 0``) is
    ``(sin psi g0, -cos psi g0, spin)``, the origin's velocity ``(cos psi v_r + sin psi v_z,
    sin psi v_r - cos psi v_z, v_n)`` and the centre's ``o + omega x c`` (``stack_bodies``).
    """
    m, cx, cy, cz = mp[k], mp[k + 1], mp[k + 2], mp[k + 3]
    ixx, iyy, izz, ixy, ixz, iyz = mp[k + 4], mp[k + 5], mp[k + 6], mp[k + 7], mp[k + 8], mp[k + 9]
    # Angular velocities and origin velocities, body axes.
    w0x, w0y, w0z = sin_psi * g0[0], -cos_psi * g0[0], spin[0]
    w1x, w1y, w1z = sin_psi * g0[1], -cos_psi * g0[1], spin[1]
    w2x, w2y, w2z = sin_psi * g0[2], -cos_psi * g0[2], spin[2]
    o0x, o0y = cos_psi * v_r[0] + sin_psi * v_z[0], sin_psi * v_r[0] - cos_psi * v_z[0]
    o1x, o1y = cos_psi * v_r[1] + sin_psi * v_z[1], sin_psi * v_r[1] - cos_psi * v_z[1]
    o2x, o2y = cos_psi * v_r[2] + sin_psi * v_z[2], sin_psi * v_r[2] - cos_psi * v_z[2]
    # The centre's velocities, o + omega x c.
    v0x, v0y, v0z = o0x + (w0y * cz - w0z * cy), o0y + (w0z * cx - w0x * cz), v_n[0] + (w0x * cy - w0y * cx)
    v1x, v1y, v1z = o1x + (w1y * cz - w1z * cy), o1y + (w1z * cx - w1x * cz), v_n[1] + (w1x * cy - w1y * cx)
    v2x, v2y, v2z = o2x + (w2y * cz - w2z * cy), o2y + (w2z * cx - w2x * cz), v_n[2] + (w2x * cy - w2y * cx)
    # I omega, body axes.
    h0x = ixx * w0x + ixy * w0y + ixz * w0z
    h0y = ixy * w0x + iyy * w0y + iyz * w0z
    h0z = ixz * w0x + iyz * w0y + izz * w0z
    h1x = ixx * w1x + ixy * w1y + ixz * w1z
    h1y = ixy * w1x + iyy * w1y + iyz * w1z
    h1z = ixz * w1x + iyz * w1y + izz * w1z
    h2x = ixx * w2x + ixy * w2y + ixz * w2z
    h2y = ixy * w2x + iyy * w2y + iyz * w2z
    h2z = ixz * w2x + iyz * w2y + izz * w2z
    # Mass last: a mass scaled by 2^k scales every term exactly (kinetic_columns weights by it too).
    k00 = (v0x * v0x + v0y * v0y + v0z * v0z) * m + (w0x * h0x + w0y * h0y + w0z * h0z)
    k01 = (v0x * v1x + v0y * v1y + v0z * v1z) * m + (w0x * h1x + w0y * h1y + w0z * h1z)
    k02 = (v0x * v2x + v0y * v2y + v0z * v2z) * m + (w0x * h2x + w0y * h2y + w0z * h2z)
    k11 = (v1x * v1x + v1y * v1y + v1z * v1z) * m + (w1x * h1x + w1y * h1y + w1z * h1z)
    k12 = (v1x * v2x + v1y * v2y + v1z * v2z) * m + (w1x * h2x + w1y * h2y + w1z * h2z)
    k22 = (v2x * v2x + v2y * v2y + v2z * v2z) * m + (w2x * h2x + w2y * h2y + w2z * h2z)
    return k00, k01, k02, k11, k12, k22


@_inline
def _proximal(mp, k, cos_phi, sin_phi, g0, gi):
    """Proximal link i (motors' centre O to elbow i, ``psi = phi_i``): spin ``-qdot_i``
    (``e_y . (elbow' - O') / l1``), origin O at ``-c e_r qdot_0`` (``body_velocities``:
    ``dcentre = c dnormal``, ``dnormal = -e_r G_0``). ``g0``, ``gi``: rows 0 and i of G."""
    c = mp[0]
    zero = (0.0, 0.0, 0.0)
    return _plane_link(mp, k, cos_phi, sin_phi, g0, (-gi[0], -gi[1], -gi[2]),
                       (-c * g0[0], -c * g0[1], -c * g0[2]), zero, zero)


@_inline
def _distal(mp, k, u, w, cos_phi, sin_phi, cos0, sin0, g0, gi):
    """Distal link i from elbow i to P = O + u e_r + w z (``plane_link_part``). ``g0``, ``gi``: rows
    0 and i of G.

    The elbow moves at ``delbows = -c e_r qdot_0 + l1 (cos phi n qdot_0 + (-sin phi e_r + cos phi z)
    qdot_i)``; P at ``e_a`` per task rate ``a``; the spin is ``e_y . (e_a - elbow') / |P - elbow|``.
    """
    c, l1 = mp[0], mp[1]
    # P - elbow_i in the plane (its n part is 0 for a consistent pose), then link_frames' e_x, e_y.
    du = u - l1 * cos_phi
    dw = w - l1 * sin_phi
    length = math.sqrt(du * du + dw * dw)
    cos_psi, sin_psi = du / length, dw / length
    v_r0, v_r1, v_r2 = -c * g0[0] - l1 * sin_phi * gi[0], -c * g0[1] - l1 * sin_phi * gi[1], \
        -c * g0[2] - l1 * sin_phi * gi[2]
    v_z0, v_z1, v_z2 = l1 * cos_phi * gi[0], l1 * cos_phi * gi[1], l1 * cos_phi * gi[2]
    v_n = (l1 * cos_phi * g0[0], l1 * cos_phi * g0[1], l1 * cos_phi * g0[2])
    # e_y = sin psi e_r - cos psi z has base-frame components (sin psi cos th0, sin psi sin th0,
    # -cos psi): e_y . e_a. e_y . elbow' is the origin's e_y component (_plane_link's o_y).
    spin = ((sin_psi * cos0 - (sin_psi * v_r0 - cos_psi * v_z0)) / length,
            (sin_psi * sin0 - (sin_psi * v_r1 - cos_psi * v_z1)) / length,
            (-cos_psi - (sin_psi * v_r2 - cos_psi * v_z2)) / length)
    return _plane_link(mp, k, cos_psi, sin_psi, g0, spin, (v_r0, v_r1, v_r2), (v_z0, v_z1, v_z2), v_n)


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
    return inertia_of(x0, x1, x2, math.cos(q0), math.sin(q0), math.cos(q1 - _QUARTER), math.sin(q1 - _QUARTER),
                      math.cos(q2 - _QUARTER), math.sin(q2 - _QUARTER), a00, a01, a02, a10, a11, a12, a20, a21, a22,
                      mp)


@jit()
def inertia_of(x0, x1, x2, cos0, sin0, cos1, sin1, cos2, sin2, a00, a01, a02, a10, a11, a12, a20, a21, a22, mp):
    """``inertia`` from the joints' cosines and sines: ``(cos q0, sin q0)`` and ``(cos phi_i, sin phi_i)``,
    ``phi_i = q_i - 90 deg``, wherever they come from (the Inverse3 kernel forms them from its IK's
    ratios, as it forms J's, with no trigonometric call).

    Returns
    -------
    tuple of 6 float
        ``(k00, k01, k02, k11, k12, k22)``, row-major upper triangle, kg.
    """
    # G = J^-1 by its adjugate, as Inverse3.body_velocities: row u is col(u+1) x col(u+2) / det J.
    g00, g01, g02 = a11 * a22 - a21 * a12, a21 * a02 - a01 * a22, a01 * a12 - a11 * a02
    g10, g11, g12 = a12 * a20 - a22 * a10, a22 * a00 - a02 * a20, a02 * a10 - a12 * a00
    g20, g21, g22 = a10 * a21 - a20 * a11, a20 * a01 - a00 * a21, a00 * a11 - a10 * a01
    det = a00 * g00 + a10 * g01 + a20 * g02
    g00, g01, g02 = g00 / det, g01 / det, g02 / det
    g10, g11, g12 = g10 / det, g11 / det, g12 / det
    g20, g21, g22 = g20 / det, g21 / det, g22 / det
    # Turret: omega_B = (0, 0, qdot_0), origin still, centre at omega_B x c: its only entries are
    # qdot_0 qdot_0 (m (cx^2 + cy^2) + Izz).
    t = BODY0
    turret = (mp[t + 1] * mp[t + 1] + mp[t + 2] * mp[t + 2]) * mp[t] + mp[t + 6]
    k00, k01, k02 = g00 * g00 * turret, g00 * g01 * turret, g00 * g02 * turret
    k11, k12, k22 = g01 * g01 * turret, g01 * g02 * turret, g02 * g02 * turret
    # The links, in BODIES order; P in the plane: u = x . e_r, w = z - base_height.
    u = x0 * cos0 + x1 * sin0
    w = x2 - mp[3]
    g0 = (g00, g01, g02)
    for term in (_proximal(mp, BODY0 + BODY_SIZE, cos1, sin1, g0, (g10, g11, g12)),
                 _proximal(mp, BODY0 + 2 * BODY_SIZE, cos2, sin2, g0, (g20, g21, g22)),
                 _distal(mp, BODY0 + 3 * BODY_SIZE, u, w, cos1, sin1, cos0, sin0, g0, (g10, g11, g12)),
                 _distal(mp, BODY0 + 4 * BODY_SIZE, u, w, cos2, sin2, cos0, sin0, g0, (g20, g21, g22))):
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
    return inertia_points_of(inertia, x, q, jac, mp)
