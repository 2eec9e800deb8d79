"""The delta family's kinetic form (``kinematics.delta``: the Novint Falcon), compiled, in scalars.

``inertia`` gives at one pose what ``kinematics.dynamics.kinetic_form(mech, q, x, rotors=True)``
gives there: the task-space inertia ``Lambda(x)`` (the model's ``mass_coordinates`` is
``"task"``), kg, from the model's exact body velocities (``Delta.body_velocities``):

    Lambda = sum_b m_b Jv_b^T Jv_b + Jw_b^T R_b I_b R_b^T Jw_b + G^T diag(J_u N_u^2) G

(``kinematics.bodies.kinetic_columns``, then ``kinetic_form``'s rotors), with the bodies of
``Delta.bodies``: three arms, three bar pairs, the platform. Per leg ``i`` and task direction
``d`` (the unit vector ``e_d``), with ``e`` the ``knee_offset`` and ``d'`` the ``platform_joint_offset``
(libnifalcon's e and d), the model's equations and what they come to here:

=============  ======================================================  ==============================
body           model (``Delta.body_velocities``)                       here
=============  ======================================================  ==============================
``G``'s row i  ``g = n / B``, bar ``n`` (``_bars``), ``B = n . dK``     the same (not J's adjugate)
arm i          ``link_part(base, knee, v, 0, dK g_d)``: turns about    ``(A_i + r_i) g^T g``, ``A_i =
               the motor axis ``v`` = its body z axis at ``q' = g_d``  I_zz + m (c_x^2 + c_y^2)``
bar pair i     ``dradial = unit_rate(h, dperp, rho)``,                  ``dradial = tau_d t``,
               ``dperp = (I - v v^T)(e_d - dK g_d)``                    ``t = v x h``
               ``link_part(top, end, v, dk + e dradial,                 body-axis columns, below
               e_d - d' dradial)`` (``link_frame_rates``)
platform       translates: ``Jv = I``, ``Jw = 0``                       ``m_p I``
=============  ======================================================  ==============================

The right column is the left one in closed form, by identities of the frames (exact in exact
arithmetic, so the two paths differ by rounding only):

- Arm. Its axis ``e_x = cos q u + sin q w`` is perpendicular to ``v``, so ``link_frames`` gives
  ``e_z = v`` and the arm turns at ``omega = -v g_d`` (``e_x x dK / a``; the twist term is zero):
  its kinetic form per unit arm rate is its moment about the motor axis, ``A_i = I_zz + m (c_x^2 +
  c_y^2)`` (parallel axes), the same at every pose (``pack_mass``), and its term is rank one.
- Bar's radial rate. ``h = perp / rho`` is perpendicular to ``v``, so ``(I - h h^T)(I - v v^T) =
  t t^T`` with ``t = v x h``: ``dradial_d = tau_d t``, ``tau_d = (t_d - (t . dK) g_d) / rho``.
- Bar's frame. With ``diff_d = dend_d - dtop_d = e_d - dK g_d - D tau_d t`` (``D = e + d'``),
  ``Y_d = e_y . diff_d`` and ``Z_d = e_z . diff_d``, ``link_frame_rates``' ``omega`` in body axes is
  ``(Y_d (e_x . v) / (|n| |v x e_x|), -Z_d / |n|, Y_d / |n|)`` (``e_x . (e_x x e_x') = 0``,
  ``e_y . (e_x x e_x') = -e_x' . e_z``, ``e_z . (e_x x e_x') = e_x' . e_y``), and the centre's
  velocity ``dtop + omega x R c`` in body axes is ``g_d R^T dK + e tau_d R^T t + omega_b x c``.
  Lengths are frame-independent: ``|Jv|^2`` and ``omega^T R I R^T omega`` are taken in body axes.

Every body term is a mass, a tensor entry or a rotor inertia times products of velocities: a
model with every mass, tensor and rotor scaled by ``2^k`` gives the form times ``2^k`` exactly.
The caller hands only regular, feasible, finite poses (singular and ill-conditioned ones go to
the numpy path): ``B_ii``, the bars' radial distances and the bars' widths across ``v`` are then
away from zero, so no step here guards a division.
"""
from __future__ import annotations

import math

import numpy as np

from .dynamics import inertia_points_of
from .jit import jit

# Offsets into ``pack_mass``'s array (``pack_mass`` documents the layout).
_U, _V, _ROOT = 0, 9, 18
_A, _E, _D = 27, 28, 29
BODIES = 30
#: Entries per body: mass, centre (3), tensor (xx, yy, zz, xy, xz, yz), whether the tensor has a non-zero entry.
BODY_SIZE = 11
_BARS, _PLATFORM = 3, 6
AXIS_MOMENTS = BODIES + 7 * BODY_SIZE
ROTORS = AXIS_MOMENTS + 3
SIZE = ROTORS + 3


def axis_moment(body) -> float:
    """A body's moment of inertia about its frame's z axis, ``I_zz + m (c_x^2 + c_y^2)``, kg m^2 (parallel axes).

    Parameters
    ----------
    body : Body
        Its centre and tensor in its own frame.

    Returns
    -------
    float

    Examples
    --------
    >>> from kinematics.bodies import rod
    >>> round(axis_moment(rod("arm", 0.03, 0.1)) / (0.03 * 0.1 ** 2 / 3), 12)     # a rod about its end: m L^2 / 3
    1.0
    """
    cx, cy, _ = body.com
    return body.inertia[2] + body.mass * (cx * cx + cy * cy)


def pack_mass(mechanism) -> np.ndarray:
    """Everything ``inertia`` reads of a delta model with a mass model, float64 (113,).

    Parameters
    ----------
    mechanism : Delta
        With ``has_mass_model``.

    Returns
    -------
    ndarray, shape (113,)
        ========  =====================================================================
        0-8       ``u_i`` (``leg_frames``), leg by leg
        9-17      ``v_i``, leg by leg
        18-26     the knees' fixed part ``(r - c) u_i + (s - f) v_i`` (``_knees``)
        27-29     ``upper_arm`` a, ``knee_offset`` e, ``D = knee_offset + platform_joint_offset``
        30-106    per body of ``bodies()`` (arms 1-3, bar pairs 1-3, platform), 11 each: mass (kg),
                  centre of mass (3, m, body frame), inertia ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)``
                  (kg m^2, body axes), 1.0 where the tensor has a non-zero entry (else 0.0); the
                  arms enter only through their axis moments
        107-109   each arm's ``axis_moment`` (about the motor axis, its body z axis), kg m^2
        110-112   ``reflected_rotor_inertias()`` ``J_u N_u^2``, kg m^2
        ========  =====================================================================

    Examples
    --------
    >>> from kinematics.delta import Delta
    >>> pack_mass(Delta(mass_model="estimated")).shape
    (113,)
    """
    p = mechanism.params
    u, v = mechanism.leg_frames()
    root = (p.base_radius - p.platform_offset_u) * u + (p.base_offset_v - p.platform_offset_v) * v
    bodies = mechanism.bodies()
    entries = []
    for body in bodies:
        entries += [body.mass, *body.com, *body.inertia, float(any(t != 0.0 for t in body.inertia))]
    out = np.array([*u.ravel(), *v.ravel(), *root.ravel(),
                    p.upper_arm, p.knee_offset, p.knee_offset + p.platform_joint_offset,
                    *entries, *(axis_moment(b) for b in bodies[:3]), *mechanism.reflected_rotor_inertias()],
                   dtype=np.float64)
    if out.shape != (SIZE,):
        raise ValueError(f"a delta model has 7 bodies and 3 rotors; got {len(bodies)} bodies")
    return out


@jit()
def _body(mp, at):
    """Body entries at ``at`` of ``pack_mass``'s array as a tuple of 11 floats.

    The helpers below take tuples, not ``mp``: an array handed to a function numba does not
    inline is reference-counted at each call (NRT_incref, NRT_decref calls in its machine code).
    """
    return (mp[at], mp[at + 1], mp[at + 2], mp[at + 3], mp[at + 4], mp[at + 5], mp[at + 6], mp[at + 7],
            mp[at + 8], mp[at + 9], mp[at + 10])


@jit()
def _turned(body, w0, w1, w2):
    """``I w`` of a body's tensor (body axes)."""
    xx, yy, zz, xy, xz, yz = body[4], body[5], body[6], body[7], body[8], body[9]
    return xx * w0 + xy * w1 + xz * w2, xy * w0 + yy * w1 + yz * w2, xz * w0 + yz * w1 + zz * w2


@jit()
def _bar_column(g_j, t_j, y_j, z_j, leg, body):
    """The bar pair's body-axis column for task direction ``j``: centre velocity, angular velocity, ``I`` times it.

    ``g_j``, ``t_j``, ``y_j``, ``z_j``: component ``j`` of ``G``'s row, ``t``, ``e_y`` and ``e_z``; ``leg``
    the leg's terms (``_leg``). The module's docstring derives it from ``Delta.body_velocities``.
    """
    tdk, inv_rho, big_d, e, ydk, zdk, yt, zt, kx, ky, kz, tx, ty, tz, roll, inv_len = leg
    tau = (t_j - tdk * g_j) * inv_rho                # dradial = tau t
    big_y = y_j - ydk * g_j - big_d * tau * yt        # e_y . (dend - dtop)
    big_z = z_j - zdk * g_j - big_d * tau * zt        # e_z . (dend - dtop)
    w0, w1, w2 = big_y * roll, -big_z * inv_len, big_y * inv_len
    c0, c1, c2 = body[1], body[2], body[3]
    et = e * tau
    v0 = g_j * kx + et * tx + (w1 * c2 - w2 * c1)
    v1 = g_j * ky + et * ty + (w2 * c0 - w0 * c2)
    v2 = g_j * kz + et * tz + (w0 * c1 - w1 * c0)
    if body[10] != 0.0:             # a tensor with a non-zero entry (a rod with no radius has one)
        i0, i1, i2 = _turned(body, w0, w1, w2)
    else:
        i0, i1, i2 = 0.0, 0.0, 0.0
    return v0, v1, v2, w0, w1, w2, i0, i1, i2


@jit()
def _pair(ca, cb, mass):
    """``m Jv_a . Jv_b + (R^T Jw_a)^T I (R^T Jw_b)`` of a body's columns (``kinetic_columns``; ``_bar_column``)."""
    return (mass * (ca[0] * cb[0] + ca[1] * cb[1] + ca[2] * cb[2])
            + (ca[3] * cb[6] + ca[4] * cb[7] + ca[5] * cb[8]))


@jit()
def _leg(x0, x1, x2, q, mp, i):
    """Leg ``i``'s arm, bar pair and rotor in the form, the upper triangle (6 floats)."""
    u, v, root = _U + 3 * i, _V + 3 * i, _ROOT + 3 * i
    u0, u1, u2 = mp[u], mp[u + 1], mp[u + 2]
    v0, v1, v2 = mp[v], mp[v + 1], mp[v + 2]
    a, big_d = mp[_A], mp[_D]
    # Delta._knees (w = (0, 0, 1)): the effective knee K and dK/dq
    cq, sq = math.cos(q), math.sin(q)
    k0 = mp[root] + a * (cq * u0 + sq * 0.0)
    k1 = mp[root + 1] + a * (cq * u1 + sq * 0.0)
    k2 = mp[root + 2] + a * (cq * u2 + sq * 1.0)
    dk0 = a * (-sq * u0 + cq * 0.0)
    dk1 = a * (-sq * u1 + cq * 0.0)
    dk2 = a * (-sq * u2 + cq * 1.0)
    # Delta._bars: n = perp (rho - D) / rho + (Q . v) v with Q = x - K; G's row i = n / (n . dK)
    qv0, qv1, qv2 = x0 - k0, x1 - k1, x2 - k2
    along = qv0 * v0 + qv1 * v1 + qv2 * v2
    p0, p1, p2 = qv0 - along * v0, qv1 - along * v1, qv2 - along * v2
    rho = math.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
    inv_rho = 1.0 / rho                 # reciprocals where a quotient is taken several times
    scale = (rho - big_d) * inv_rho
    n0, n1, n2 = p0 * scale + along * v0, p1 * scale + along * v1, p2 * scale + along * v2
    inv_b = 1.0 / (n0 * dk0 + n1 * dk1 + n2 * dk2)
    g0, g1, g2 = n0 * inv_b, n1 * inv_b, n2 * inv_b
    # The bar pair's frame (link_frames(top, end, v): e_x along end - top = n) and t = v x h, h = perp / rho
    inv_len = 1.0 / math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    x_0, x_1, x_2 = n0 * inv_len, n1 * inv_len, n2 * inv_len
    s0, s1, s2 = v1 * x_2 - v2 * x_1, v2 * x_0 - v0 * x_2, v0 * x_1 - v1 * x_0
    inv_width = 1.0 / math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
    y_0, y_1, y_2 = s0 * inv_width, s1 * inv_width, s2 * inv_width
    z_0, z_1, z_2 = x_1 * y_2 - x_2 * y_1, x_2 * y_0 - x_0 * y_2, x_0 * y_1 - x_1 * y_0
    h0, h1, h2 = p0 * inv_rho, p1 * inv_rho, p2 * inv_rho
    t0, t1, t2 = v1 * h2 - v2 * h1, v2 * h0 - v0 * h2, v0 * h1 - v1 * h0
    leg = (t0 * dk0 + t1 * dk1 + t2 * dk2, inv_rho, big_d, mp[_E],
           y_0 * dk0 + y_1 * dk1 + y_2 * dk2, z_0 * dk0 + z_1 * dk1 + z_2 * dk2,
           y_0 * t0 + y_1 * t1 + y_2 * t2, z_0 * t0 + z_1 * t1 + z_2 * t2,
           x_0 * dk0 + x_1 * dk1 + x_2 * dk2, y_0 * dk0 + y_1 * dk1 + y_2 * dk2, z_0 * dk0 + z_1 * dk1 + z_2 * dk2,
           x_0 * t0 + x_1 * t1 + x_2 * t2, y_0 * t0 + y_1 * t1 + y_2 * t2, z_0 * t0 + z_1 * t1 + z_2 * t2,
           (x_0 * v0 + x_1 * v1 + x_2 * v2) * inv_width * inv_len, inv_len)
    bar = _body(mp, BODIES + (_BARS + i) * BODY_SIZE)
    c0 = _bar_column(g0, t0, y_0, z_0, leg, bar)
    c1 = _bar_column(g1, t1, y_1, z_1, leg, bar)
    c2 = _bar_column(g2, t2, y_2, z_2, leg, bar)
    m = bar[0]
    # The arm and its rotor turn with the arm: (A_i + r_i) G_i^T G_i (kinetic_form's rotor term)
    s = mp[AXIS_MOMENTS + i] + mp[ROTORS + i]
    return (_pair(c0, c0, m) + s * g0 * g0, _pair(c0, c1, m) + s * g0 * g1, _pair(c0, c2, m) + s * g0 * g2,
            _pair(c1, c1, m) + s * g1 * g1, _pair(c1, c2, m) + s * g1 * g2, _pair(c2, c2, m) + s * g2 * g2)


@jit()
def inertia(x0, x1, x2, q0, q1, q2, a00, a01, a02, a10, a11, a12, a20, a21, a22, mp):
    """The kinetic form ``Lambda(x)`` at one regular pose: its upper triangle ``(k00, k01, k02, k11, k12, k22)``, kg.

    Parameters
    ----------
    x0, x1, x2 : float
        The platform point, m.
    q0, q1, q2 : float
        Its arm angles (``Delta.inverse``), rad.
    a00, a01, a02, a10, a11, a12, a20, a21, a22 : float
        ``J[r, c]`` (``Delta.jacobian``), taken for the kernels' common signature and not read: ``G = dq/dx``
        comes from the legs' bars, as ``Delta.body_velocities`` forms it.
    mp : ndarray, shape (113,)
        ``pack_mass(mechanism)``.

    Returns
    -------
    tuple of 6 float
        ``kinetic_form(mech, q, x, rotors=True)``'s entries ``[0, 0], [0, 1], [0, 2], [1, 1], [1, 2], [2, 2]``.
    """
    m = mp[BODIES + _PLATFORM * BODY_SIZE]           # the platform translates with x: m_p I
    k00, k01, k02, k11, k12, k22 = m, 0.0, 0.0, m, 0.0, m
    # A loop, not three calls with 0, 1, 2: numba would compile _leg once per literal leg number.
    for i in range(3):
        leg = _leg(x0, x1, x2, q0 if i == 0 else (q1 if i == 1 else q2), mp, i)
        k00, k01, k02 = k00 + leg[0], k01 + leg[1], k02 + leg[2]
        k11, k12, k22 = k11 + leg[3], k12 + leg[4], k22 + leg[5]
    return k00, k01, k02, k11, k12, k22


def inertia_points(x, q, jac, mp):
    """``inertia`` at k poses, as full symmetric matrices (k, 3, 3), kg.

    Parameters
    ----------
    x : ndarray, shape (k, 3)
        Platform points, m.
    q : ndarray, shape (k, 3)
        Their arm angles, rad.
    jac : ndarray, shape (k, 3, 3)
        Their ``J`` (passed through to ``inertia``).
    mp : ndarray, shape (113,)
        ``pack_mass(mechanism)``.

    Returns
    -------
    ndarray, shape (k, 3, 3)
    """
    return inertia_points_of(inertia, x, q, jac, mp)
