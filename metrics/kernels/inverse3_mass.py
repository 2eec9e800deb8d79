"""The Inverse3 family's kinetic form (``kinematics.dynamics.kinetic_form``) at one point, compiled, in scalars.

The model places its bodies from the task pose (``mass_coordinates = "task"``), so the form is the
task-space inertia (``kinematics.bodies``, ``kinematics.dynamics``)

    Lambda(x) = sum_b m_b Jv_b^T Jv_b + Jw_b^T R_b I_b R_b^T Jw_b  +  G^T diag(J_u N_u^2) G,

with ``Jv_b``, ``Jw_b`` the velocity of body b's centre and its angular velocity per unit task rate
(``Inverse3.body_velocities``) and ``G = dq/dx = J^-1``. Those Jacobians are the bodies' joint-rate
ones times ``G``, so, the handle apart, ``Lambda = G^T (M(q) + diag(J_u N_u^2)) G`` with ``M`` the
links' and turret's joint-space inertia; ``inertia`` forms ``M`` from each body's motion per unit
joint rate in closed form, then ``G^T M G``. Per joint rate the motion is sparse (the turret and a
proximal link move with ``qdot_0`` and their own motor only, a distal link does not spin under
``qdot_0``), so ``M`` costs a few dozen products where the task-rate columns took three full
columns per body (the 1000 x 1000 Inverse3 pass with the mass quantities: 171-175 ms against
184-187 ms on one core):

=========  ===============================================  ==========================================
body       frame (``Inverse3.body_poses``)                  angular velocity; origin's velocity
=========  ===============================================  ==========================================
turret     ``[e_r, n, z]``, origin on the base axis          ``z qdot_0``; still
proximal   ``e_x = cos psi e_r + sin psi z`` from the        ``z qdot_0 + n spin`` (``plane_link_part``);
i, distal  motors' centre O (distal: from elbow i) to the    O: ``-c e_r qdot_0``; elbow i: O's plus
i          elbow (P), ``e_y = sin psi e_r - cos psi z``,     ``l1 (cos phi_i n qdot_0 + (-sin phi_i e_r
           ``e_z = n`` (``link_frames``)                      + cos phi_i z) qdot_i)``; P: ``J qdot``
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
def _proximal(mp, k, cos_phi, sin_phi):
    """Proximal link i (motors' centre O to elbow i, ``psi = phi_i``): its part of ``M(q)``, the entries
    ``(00, 0i, ii)`` (it moves with ``qdot_0`` and ``qdot_i`` only).

    In its axes ``e_x``, ``e_y``, ``e_z = n``, per unit ``qdot_0``: ``omega = (sin phi, -cos phi, 0)``
    (``z``), origin O at ``-c e_r`` (``dcentre = c dnormal``, ``dnormal = -e_r``), so ``(-c cos phi,
    -c sin phi, 0)``; per unit ``qdot_i``: the spin ``-n`` (``e_y . (elbow' - O') / l1``), origin still.
    The centre moves at ``o + omega x c`` (``stack_bodies``).
    """
    c = mp[0]
    m, cx, cy, cz = mp[k], mp[k + 1], mp[k + 2], mp[k + 3]
    ixx, iyy, izz, ixy, ixz, iyz = mp[k + 4], mp[k + 5], mp[k + 6], mp[k + 7], mp[k + 8], mp[k + 9]
    # qdot_0's centre velocity; qdot_i's is omega x c = (cy, -cx, 0).
    v0x, v0y, v0z = -c * cos_phi - cos_phi * cz, -c * sin_phi - sin_phi * cz, sin_phi * cy + cos_phi * cx
    # I omega for qdot_0.
    h0x, h0y = ixx * sin_phi - ixy * cos_phi, ixy * sin_phi - iyy * cos_phi
    h0z = ixz * sin_phi - iyz * cos_phi
    d00 = (v0x * v0x + v0y * v0y + v0z * v0z) * m + (sin_phi * h0x - cos_phi * h0y)
    d0i = (v0x * cy - v0y * cx) * m - h0z
    dii = (cy * cy + cx * cx) * m + izz
    return d00, d0i, dii


@_inline
def _distal(mp, k, u, w, cos_phi, sin_phi, r_i, z_i, r_k, z_k):
    """Distal link i, from elbow i to P = O + u e_r + w z (``plane_link_part``): its part of ``M(q)``,
    the entries ``(00, 0i, 0k, ii, ik, kk)``, ``k`` the other arm's joint.

    ``(r_j, z_j)``: column j of J in the five-bar plane, ``(e_r . J[:, j], J[2, j])`` (P's velocity per
    unit ``qdot_j``; ``n . J[:, j] = 0`` for j = 1, 2). With ``e_x = (P - elbow) / |P - elbow|``,
    ``e_y = sin psi e_r - cos psi z``, the link's axes ``e_x, e_y, n`` (``link_frames``), per unit
    joint rate:

    - ``qdot_0``: the whole plane turns about z, so ``omega = (sin psi, -cos psi, 0)``, no spin about
      n (P and the elbow turn together), the elbow at ``-c e_r + l1 cos phi n``: ``(-c cos psi,
      -c sin psi, l1 cos phi)``;
    - ``qdot_i``: the elbow at ``l1 (-sin phi e_r + cos phi z)``: ``(l1 sin(psi - phi), -l1 cos(psi -
      phi), 0)``, the spin ``e_y . (P' - elbow') / |P - elbow|``;
    - ``qdot_k``: the elbow still, the spin ``e_y . P' / |P - elbow|``.
    """
    c, l1 = mp[0], mp[1]
    m, cx, cy, cz = mp[k], mp[k + 1], mp[k + 2], mp[k + 3]
    ixx, iyy, izz, ixy, ixz, iyz = mp[k + 4], mp[k + 5], mp[k + 6], mp[k + 7], mp[k + 8], mp[k + 9]
    # P - elbow_i in the plane (its n part is 0 for a consistent pose), then link_frames' e_x, e_y.
    du = u - l1 * cos_phi
    dw = w - l1 * sin_phi
    length = math.sqrt(du * du + dw * dw)
    cos_psi, sin_psi = du / length, dw / length
    # The elbow's velocity per unit qdot_i, link axes (x, y).
    oix = l1 * (sin_psi * cos_phi - cos_psi * sin_phi)
    oiy = -l1 * (sin_psi * sin_phi + cos_psi * cos_phi)
    spin_i = ((sin_psi * r_i - cos_psi * z_i) - oiy) / length
    spin_k = (sin_psi * r_k - cos_psi * z_k) / length
    # Centre velocities o + omega x c.
    v0x, v0y, v0z = -c * cos_psi - cos_psi * cz, -c * sin_psi - sin_psi * cz, l1 * cos_phi + (sin_psi * cy
                                                                                             + cos_psi * cx)
    vix, viy = oix - spin_i * cy, oiy + spin_i * cx
    vkx, vky = -spin_k * cy, spin_k * cx
    # I omega for qdot_0; for qdot_i, qdot_k it is spin (Ixz, Iyz, Izz).
    h0x, h0y = ixx * sin_psi - ixy * cos_psi, ixy * sin_psi - iyy * cos_psi
    tilt = ixz * sin_psi - iyz * cos_psi            # omega_0 . I n
    d00 = (v0x * v0x + v0y * v0y + v0z * v0z) * m + (sin_psi * h0x - cos_psi * h0y)
    d0i = (v0x * vix + v0y * viy) * m + spin_i * tilt
    d0k = (v0x * vkx + v0y * vky) * m + spin_k * tilt
    dii = (vix * vix + viy * viy) * m + spin_i * spin_i * izz
    dik = (vix * vkx + viy * vky) * m + spin_i * spin_k * izz
    dkk = (vkx * vkx + vky * vky) * m + spin_k * spin_k * izz
    return d00, d0i, d0k, dii, dik, dkk


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
    # M(q), in BODIES order. Turret: omega_B = (0, 0, qdot_0), origin still, centre at omega_B x c:
    # its only entry is qdot_0 qdot_0 (m (cx^2 + cy^2) + Izz).
    t = BODY0
    m00 = (mp[t + 1] * mp[t + 1] + mp[t + 2] * mp[t + 2]) * mp[t] + mp[t + 6]
    # The links; P in the plane: u = x . e_r, w = z - base_height; J's columns 1, 2 in the plane.
    u = x0 * cos0 + x1 * sin0
    w = x2 - mp[3]
    r1, r2 = a01 * cos0 + a11 * sin0, a02 * cos0 + a12 * sin0
    p00, p01, p11 = _proximal(mp, BODY0 + BODY_SIZE, cos1, sin1)
    q00, q02, q22 = _proximal(mp, BODY0 + 2 * BODY_SIZE, cos2, sin2)
    d00, d01, d02, d11, d12, d22 = _distal(mp, BODY0 + 3 * BODY_SIZE, u, w, cos1, sin1, r1, a21, r2, a22)
    e00, e02, e01, e22, e12, e11 = _distal(mp, BODY0 + 4 * BODY_SIZE, u, w, cos2, sin2, r2, a22, r1, a21)
    # Rotors: diag(J_u N_u^2) (kinetic_form), last.
    m00 = (((m00 + p00) + q00) + d00) + e00 + mp[ROTORS]
    m01 = (p01 + d01) + e01
    m02 = (q02 + d02) + e02
    m11 = ((p11 + d11) + e11) + mp[ROTORS + 1]
    m12 = d12 + e12
    m22 = ((q22 + d22) + e22) + mp[ROTORS + 2]
    # Lambda = G^T M G: B = M G, then G^T B (upper triangle).
    b00, b01, b02 = m00 * g00 + m01 * g10 + m02 * g20, m00 * g01 + m01 * g11 + m02 * g21, \
        m00 * g02 + m01 * g12 + m02 * g22
    b10, b11, b12 = m01 * g00 + m11 * g10 + m12 * g20, m01 * g01 + m11 * g11 + m12 * g21, \
        m01 * g02 + m11 * g12 + m12 * g22
    b20, b21, b22 = m02 * g00 + m12 * g10 + m22 * g20, m02 * g01 + m12 * g11 + m22 * g21, \
        m02 * g02 + m12 * g12 + m22 * g22
    # Handle: Jv = I per task rate (translating_part(dx)), Jw = 0: m_h on the diagonal.
    handle = mp[BODY0 + 5 * BODY_SIZE]
    k00 = (g00 * b00 + g10 * b10 + g20 * b20) + handle
    k01 = g00 * b01 + g10 * b11 + g20 * b21
    k02 = g00 * b02 + g10 * b12 + g20 * b22
    k11 = (g01 * b01 + g11 * b11 + g21 * b21) + handle
    k12 = g01 * b02 + g11 * b12 + g21 * b22
    k22 = (g02 * b02 + g12 * b12 + g22 * b22) + handle
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
