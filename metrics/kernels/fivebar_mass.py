"""The planar five-bar's kinetic form ``Lambda(x)`` at one pose, compiled, in scalars.

``kinematics.dynamics.kinetic_form(mech, q, x)`` for ``kinematics.fivebar.FiveBar``
(``mass_coordinates = "task"``): ``sum_b m_b Jv_b^T Jv_b + Jw_b^T R_b I_b R_b^T Jw_b`` over the
model's bodies (``FiveBar.bodies``: four links, then the handle) with their exact velocities
(``FiveBar.body_velocities``), plus the rotors ``G^T diag(r) G``. Every body moves in the plane
z = 0 and turns about its body z axis (the plane's normal, ``link_frames``), so per body and per
task direction j:

=============  ==========================================  ==========================================
body           velocities per unit task rate ``xdot_j``     its part of ``Lambda``
=============  ==========================================  ==========================================
proximal i     turns about its base joint at ``g_ij``       ``(I_zz + m (c_x^2 + c_y^2) + r_i) g_i g_i^T``
               (``G`` row i)                                (the link's inertia about its joint and
                                                            the rotor's, parallel axes)
distal i       elbow ``B_i' = a1 t_i g_ij``, spin           ``m v_j . v_k + I_zz s_j s_k``
               ``s_j = e_y . (e_j - B_i') / |C - B_i|``,
               centre ``v_j = B_i' + s_j e_z x R c``
handle         translates with C: ``v_j = e_j``              ``m I``
=============  ==========================================  ==========================================

with ``G`` row i ``g_i = (C - B_i) / (a1 (C - B_i) . t_i)`` and ``t_i = (-sin q_i, cos q_i)``
(``body_velocities``: the loop closure ``|C - B_i| = a2`` differentiated), ``e_x`` along the
link, ``e_y = e_z x e_x`` (``plane_link_part``). What the planar motion makes exactly zero for
every five-bar, whatever its parameters (``R^T Jw = (0, 0, s)`` with ``0`` entries exactly, as
in the numpy path): the tensor entries other than ``I_zz``, the centre's z and every part of the
handle's tensor and centre (it only translates). ``pack_mass`` still packs them all, so the
layout says what the model holds.
"""
from __future__ import annotations

import math

import numpy as np

from .dynamics import BODY_FLOATS, inertia_points_of, pack_bodies
from .jit import jit

#: Bodies in ``FiveBar.bodies``' order.
BODIES = ("proximal_1", "proximal_2", "distal_1", "distal_2", "handle")
#: Entries per body in the packed array: mass, centre (3), tensor (Ixx, Iyy, Izz, Ixy, Ixz, Iyz).
BODY_SIZE = BODY_FLOATS
_FIRST_BODY = 3
_ROTORS = _FIRST_BODY + BODY_SIZE * len(BODIES)
#: Length of ``pack_mass``' array.
SIZE = _ROTORS + 2
_MASS, _CX, _CY, _IZZ = 0, 1, 2, 6


def pack_mass(mechanism, *, rotors: bool = True) -> np.ndarray:
    """The five-bar's geometry, bodies and reflected rotor inertias as ``inertia`` reads them.

    Parameters
    ----------
    mechanism : FiveBar
        With ``has_mass_model``.
    rotors : bool
        Pack ``reflected_rotor_inertias()`` (default); ``False`` packs zeros (the links alone,
        ``kinetic_form(..., rotors=False)``).

    Returns
    -------
    ndarray, shape (SIZE,) = (55,), float64
        ====================  =====================================================================
        index                 entry
        ====================  =====================================================================
        0, 1, 2               ``a1`` (proximal), ``a2`` (distal), ``a3`` (half base), m
        3 + 10 b + 0          body b's mass, kg (b in ``BODIES``' order, ``FiveBar.bodies``)
        3 + 10 b + 1 .. 3     its centre of mass in its body frame, m
        3 + 10 b + 4 .. 9     its inertia tensor about the centre, body axes,
                              ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` as ``Body.inertia``, kg m^2
        53, 54                ``J_u N_u^2`` of the two rotors, kg m^2
        ====================  =====================================================================

    Raises
    ------
    ValueError
        Without a mass model (``bodies``), or when the model's bodies are not ``BODIES``.
    """
    p = mechanism.params
    out = np.zeros(SIZE, dtype=np.float64)
    pack_bodies(mechanism, BODIES, out, _FIRST_BODY)
    out[:_FIRST_BODY] = p.proximal, p.distal, p.half_base
    if rotors:
        out[_ROTORS:] = mechanism.reflected_rotor_inertias()
    return out


@jit()
def _about_joint(mp, body, rotor):
    """``I_zz + m (c_x^2 + c_y^2) + r``: a link turning about its base joint, and the rotor on that joint."""
    at = _FIRST_BODY + BODY_SIZE * body
    cx, cy = mp[at + _CX], mp[at + _CY]
    return mp[at + _IZZ] + mp[at + _MASS] * (cx * cx + cy * cy) + mp[_ROTORS + rotor]


@jit()
def _distal(p0, p1, c, s, g0, g1, a1, mp, body):
    """Distal link ``body`` from its elbow to C: its ``(k00, k01, k11)``.

    ``p = C - B_i`` (2), the proximal's ``cos q_i``, ``sin q_i`` and ``G`` row i ``(g0, g1)``.
    ``plane_link_part`` and ``stack_bodies`` with the plane's normal fixed (``e_z = (0, 0, 1)``).
    """
    at = _FIRST_BODY + BODY_SIZE * body
    length = math.sqrt(p0 * p0 + p1 * p1)
    inv = 1.0 / length                    # one division for four (each then within 1.5 ulps)
    ex0, ex1 = p0 * inv, p1 * inv
    ey0, ey1 = -ex1, ex0
    # Elbow velocity a1 t_i g_ij (t_i = (-sin q_i, cos q_i)); the link's rates: C's (e_j) less the elbow's.
    b00, b01 = a1 * -s * g0, a1 * c * g0
    b10, b11 = a1 * -s * g1, a1 * c * g1
    s0 = (ey0 * (1.0 - b00) + ey1 * (0.0 - b01)) * inv
    s1 = (ey0 * (0.0 - b10) + ey1 * (1.0 - b11)) * inv
    # Centre: elbow + omega x R c, with e_z x R c = (-arm_y, arm_x) and arm = c_x e_x + c_y e_y.
    cx, cy = mp[at + _CX], mp[at + _CY]
    arm0, arm1 = cx * ex0 + cy * ey0, cx * ex1 + cy * ey1
    v00, v01 = b00 + s0 * -arm1, b01 + s0 * arm0
    v10, v11 = b10 + s1 * -arm1, b11 + s1 * arm0
    m, izz = mp[at + _MASS], mp[at + _IZZ]
    return (m * (v00 * v00 + v01 * v01) + izz * (s0 * s0),
            m * (v00 * v10 + v01 * v11) + izz * (s0 * s1),
            m * (v10 * v10 + v11 * v11) + izz * (s1 * s1))


@jit()
def inertia(x0, x1, q0, q1, a00, a01, a10, a11, mp):
    """The upper triangle ``(k00, k01, k11)`` of ``Lambda(x)`` at one regular pose, kg.

    Parameters
    ----------
    x0, x1 : float
        The end-effector C, m.
    q0, q1 : float
        Its joints (``FiveBar.inverse``), rad.
    a00, a01, a10, a11 : float
        ``J = dx/dq`` (``FiveBar.jacobian``), for the families' common signature. Not read:
        the five-bar's ``G = J^-1`` has rows in closed form from the loop closure
        (``body_velocities``), as the numpy path forms them, at the cost of the adjugate and
        without its cancellation in ``det J`` near a direct singularity.
    mp : ndarray, shape (SIZE,)
        ``pack_mass``.

    Returns
    -------
    tuple of 3 float
        ``Lambda[0, 0]``, ``Lambda[0, 1]``, ``Lambda[1, 1]``.

    Notes
    -----
    The pose must be feasible, finite and not singular (``jt_i != 0``); the caller hands the
    others to ``kinetic_form``.
    """
    a1, a3 = mp[0], mp[2]
    c0, s0, c1, s1 = math.cos(q0), math.sin(q0), math.cos(q1), math.sin(q1)
    # body_velocities: elbows B_i = O_i + a1 (cos q_i, sin q_i), O_i = (-+a3, 0); p_i = C - B_i.
    p00, p01 = x0 - (-a3 + a1 * c0), x1 - (0.0 + a1 * s0)
    p10, p11 = x0 - (a3 + a1 * c1), x1 - (0.0 + a1 * s1)
    # G row i = p_i / (a1 p_i . t_i), by one reciprocal per row (divisions were half the time left
    # after the four sines and cosines; within 1.5 ulps of the quotient).
    r0 = 1.0 / (a1 * (p00 * -s0 + p01 * c0))
    r1 = 1.0 / (a1 * (p10 * -s1 + p11 * c1))
    g00, g01 = p00 * r0, p01 * r0
    g10, g11 = p10 * r1, p11 * r1
    # Proximal links and rotors: each turns with its joint, qdot_i = g_i . xdot.
    j0, j1 = _about_joint(mp, 0, 0), _about_joint(mp, 1, 1)
    k00 = j0 * (g00 * g00) + j1 * (g10 * g10)
    k01 = j0 * (g00 * g01) + j1 * (g10 * g11)
    k11 = j0 * (g01 * g01) + j1 * (g11 * g11)
    d00, d01, d11 = _distal(p00, p01, c0, s0, g00, g01, a1, mp, 2)
    e00, e01, e11 = _distal(p10, p11, c1, s1, g10, g11, a1, mp, 3)
    handle = mp[_FIRST_BODY + BODY_SIZE * 4 + _MASS]
    return (k00 + d00 + e00 + handle, k01 + d01 + e01, k11 + d11 + e11 + handle)


def inertia_points(x, q, jac, mp):
    """``inertia`` at every point, full symmetric matrices.

    Parameters
    ----------
    x : ndarray, shape (k, 2)
        End-effector points, m.
    q : ndarray, shape (k, 2)
        Their joints, rad.
    jac : ndarray, shape (k, 2, 2)
        ``J`` at each.
    mp : ndarray, shape (SIZE,)
        ``pack_mass``.

    Returns
    -------
    ndarray, shape (k, 2, 2)
        ``Lambda(x)``, kg.
    """
    return inertia_points_of(inertia, x, q, jac, mp)
