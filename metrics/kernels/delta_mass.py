"""The delta family's kinetic form (``kinematics.delta``: the Novint Falcon), compiled, in scalars.

``inertia`` gives at one pose what ``kinematics.dynamics.kinetic_form(mech, q, x, rotors=True)``
gives there: the task-space inertia ``Lambda(x)`` (the model's ``mass_coordinates`` is
``"task"``), kg, from the model's exact body velocities (``Delta.body_velocities``):

    Lambda = sum_b m_b Jv_b^T Jv_b + Jw_b^T R_b I_b R_b^T Jw_b + G^T diag(J_u N_u^2) G

(``kinematics.bodies.kinetic_columns``, then ``kinetic_form``'s rotors), with the bodies of
``Delta.bodies``: three arms, three bar pairs, the platform. Per leg ``i``, as the model forms them:

=====================  =========================================================================
``G``'s row i          ``n_i / (n_i . dK_i/dq_i)``: the bar ``n_i`` (``_bars``) over the arm's
                       rate ``B_ii``, the leg's loop closure (not J's adjugate, as the model)
arm i                  ``link_part(base, knee, v_i, 0, dK_i G_i)``: the knee moves at
                       ``dK_i/dq_i qdot_i``, so the arm's columns are ``G_i`` times those of one
                       unit arm rate, and its term is rank one: ``(s_i + r_i) G_i^T G_i`` with
                       ``s_i`` its kinetic form per unit ``qdot_i`` and ``r_i`` the rotor's
bar pair i             ``link_part(top, end, v_i, dtop, dend)`` with the ends following the
                       unit radial ``perp / rho`` (``unit_rate``), per task direction
platform               translates with ``x``: ``m_p I``
=====================  =========================================================================

The frames and their angular velocities follow ``kinematics.bodies.link_frame_rates`` and a
body's centre ``do + omega x R c`` (``stack_bodies``), the angular velocity taken to body axes
(``R^T omega``) to meet the tensor. Where the model forms a product per task direction and the
arm's is a multiple of one vector, the kernel forms that vector once, and it multiplies by the
reciprocals of ``rho``, ``B_ii`` and the links' lengths and widths where the model divides by
them (each divides several products): the same equations, rounded otherwise by a few ulps
(``tests/metrics/test_kernel_mass_delta.py`` bounds the difference). Every body term is a mass,
a tensor entry or a rotor inertia times products of velocities: a model with every mass, tensor
and rotor scaled by ``2^k`` gives the form times ``2^k`` exactly.

The caller hands only regular, feasible, finite poses (singular and ill-conditioned ones go to
the numpy path): ``B_ii``, the bars' radial distances and the link frames' widths are then away
from zero, so no step here guards a division.
"""
from __future__ import annotations

import math

import numpy as np

from .jit import jit

# Offsets into ``pack_mass``'s array (``pack_mass`` documents the layout).
_U, _V, _ROOT, _BASE, _SHIFT = 0, 9, 18, 27, 36
_A, _E, _DJ, _D = 45, 46, 47, 48
BODIES = 49
#: Entries per body: mass, centre (3), tensor (xx, yy, zz, xy, xz, yz), whether the tensor has a non-zero entry.
BODY_SIZE = 11
_ARMS, _BARS, _PLATFORM = 0, 3, 6
ROTORS = BODIES + 7 * BODY_SIZE
SIZE = ROTORS + 3


def pack_mass(mechanism) -> np.ndarray:
    """Everything ``inertia`` reads of a delta model with a mass model, float64 (129,).

    Parameters
    ----------
    mechanism : Delta
        With ``has_mass_model``.

    Returns
    -------
    ndarray, shape (129,)
        ======  =====================================================================
        0-8     ``u_i`` (``leg_frames``), leg by leg
        9-17    ``v_i``, leg by leg
        18-26   the knees' fixed part ``(r - c) u_i + (s - f) v_i`` (``_knees``)
        27-35   the arms' motor-axis points ``r u_i + s v_i`` (``_leg_points``' base)
        36-44   the knee's shift ``c u_i + f v_i`` from the effective knee (``_leg_points``)
        45-48   ``upper_arm`` a, ``knee_offset`` e, ``platform_joint_offset`` d, ``D = e + d``
        49-125  per body of ``bodies()`` (arms 1-3, bar pairs 1-3, platform), 11 each: mass (kg),
                centre of mass (3, m, body frame), inertia ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)``
                (kg m^2, body axes), 1.0 where the tensor has a non-zero entry (else 0.0)
        126-128 ``reflected_rotor_inertias()`` ``J_u N_u^2`` (kg m^2)
        ======  =====================================================================

    Examples
    --------
    >>> from kinematics.delta import Delta
    >>> pack_mass(Delta(mass_model="estimated")).shape
    (129,)
    """
    p = mechanism.params
    u, v = mechanism.leg_frames()
    root = (p.base_radius - p.platform_offset_u) * u + (p.base_offset_v - p.platform_offset_v) * v
    base = p.base_radius * u + p.base_offset_v * v
    shift = p.platform_offset_u * u + p.platform_offset_v * v
    bodies = []
    for body in mechanism.bodies():
        bodies += [body.mass, *body.com, *body.inertia, float(any(t != 0.0 for t in body.inertia))]
    out = np.array([*u.ravel(), *v.ravel(), *root.ravel(), *base.ravel(), *shift.ravel(),
                    p.upper_arm, p.knee_offset, p.platform_joint_offset, p.knee_offset + p.platform_joint_offset,
                    *bodies, *mechanism.reflected_rotor_inertias()], dtype=np.float64)
    if out.shape != (SIZE,):
        raise ValueError(f"a delta model has 7 bodies and 3 rotors; got {len(mechanism.bodies())} bodies")
    return out


@jit()
def _cross(a0, a1, a2, b0, b1, b2):
    """``a x b``."""
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@jit()
def _frame(a0, a1, a2, n0, n1, n2):
    """``link_frames``' axes of a link along ``a`` about the normal ``n``: ``(ex, ey, ez, 1 / |a|, 1 / |n x ex|)``.

    Reciprocals, multiplied where the model divides: a division costs several multiplications, and
    the link's length and width divide every column (one more rounding each, a few ulps in all).
    """
    inv_length = 1.0 / math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
    ex0, ex1, ex2 = a0 * inv_length, a1 * inv_length, a2 * inv_length
    s0, s1, s2 = _cross(n0, n1, n2, ex0, ex1, ex2)
    inv_width = 1.0 / math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
    ey0, ey1, ey2 = s0 * inv_width, s1 * inv_width, s2 * inv_width
    ez0, ez1, ez2 = _cross(ex0, ex1, ex2, ey0, ey1, ey2)
    return ex0, ex1, ex2, ey0, ey1, ey2, ez0, ez1, ez2, inv_length, inv_width


@jit()
def _spin(f, r0, r1, r2, nx):
    """``link_frame_rates``' angular velocity (base frame) of frame ``f`` (``_frame``) whose link's
    ends move apart at ``r``: ``omega = e_x x e_x' + e_x (e_x' . e_y)(e_x . n) / |n x e_x|``,
    ``e_x' = (r - e_x (e_x . r)) / |a|`` (``unit_rate``); ``nx = e_x . n``."""
    ex0, ex1, ex2, ey0, ey1, ey2 = f[0], f[1], f[2], f[3], f[4], f[5]
    inv_length, inv_width = f[9], f[10]
    along = ex0 * r0 + ex1 * r1 + ex2 * r2
    d0, d1, d2 = (r0 - ex0 * along) * inv_length, (r1 - ex1 * along) * inv_length, (r2 - ex2 * along) * inv_length
    twist = (d0 * ey0 + d1 * ey1 + d2 * ey2) * nx
    w0, w1, w2 = _cross(ex0, ex1, ex2, d0, d1, d2)
    turn = twist * inv_width
    return w0 + ex0 * turn, w1 + ex1 * turn, w2 + ex2 * turn


@jit()
def _body_column(f, w0, w1, w2, o0, o1, o2, c0, c1, c2):
    """A body's column: its centre's velocity ``do + omega x R c`` (``stack_bodies``) and ``R^T omega``, 6 floats."""
    rc0 = f[0] * c0 + f[3] * c1 + f[6] * c2
    rc1 = f[1] * c0 + f[4] * c1 + f[7] * c2
    rc2 = f[2] * c0 + f[5] * c1 + f[8] * c2
    m0, m1, m2 = _cross(w0, w1, w2, rc0, rc1, rc2)
    b0 = f[0] * w0 + f[1] * w1 + f[2] * w2
    b1 = f[3] * w0 + f[4] * w1 + f[5] * w2
    b2 = f[6] * w0 + f[7] * w1 + f[8] * w2
    return o0 + m0, o1 + m1, o2 + m2, b0, b1, b2


@jit()
def _body(mp, at):
    """Body entries at ``at`` of ``pack_mass``'s array as a tuple of 11 floats.

    The helpers below take tuples, not ``mp``: an array handed to a function numba does not
    inline is reference-counted at each call (atomic operations, a third of the time measured).
    """
    return (mp[at], mp[at + 1], mp[at + 2], mp[at + 3], mp[at + 4], mp[at + 5], mp[at + 6], mp[at + 7],
            mp[at + 8], mp[at + 9], mp[at + 10])


@jit()
def _pair(ca, cb, body):
    """``m Jv_a . Jv_b + (R^T Jw_a)^T I (R^T Jw_b)`` of a body's columns ``ca``, ``cb`` (``kinetic_columns``)."""
    out = body[0] * (ca[0] * cb[0] + ca[1] * cb[1] + ca[2] * cb[2])
    if body[10] != 0.0:             # a tensor with a non-zero entry (a rod with no radius has one)
        xx, yy, zz, xy, xz, yz = body[4], body[5], body[6], body[7], body[8], body[9]
        w0, w1, w2 = cb[3], cb[4], cb[5]
        out += (ca[3] * (xx * w0 + xy * w1 + xz * w2) + ca[4] * (xy * w0 + yy * w1 + yz * w2)
                + ca[5] * (xz * w0 + yz * w1 + zz * w2))
    return out


@jit()
def _six(c0, c1, c2, body):
    """The upper triangle (k00, k01, k02, k11, k12, k22) of one body's term from its three columns."""
    return (_pair(c0, c0, body), _pair(c0, c1, body), _pair(c0, c2, body),
            _pair(c1, c1, body), _pair(c1, c2, body), _pair(c2, c2, body))


@jit()
def _bar_column(d0, d1, d2, dk0, dk1, dk2, v0, v1, v2, h0, h1, h2, inv_rho, f, nx, e, dj, body):
    """Bar pair's column for the task direction ``d`` (a unit axis): ``Delta.body_velocities``' ``dtop``, ``dend``, then
    ``link_part(top, end, v, dtop, dend)``. ``dk`` the knee's velocity, ``h`` the unit radial, ``e`` and
    ``dj`` the knee and platform joint offsets."""
    # dqv = e_d - dk; dperp = dqv - v (dqv . v); dradial = unit_rate(perp / rho, dperp, rho)
    q0, q1, q2 = d0 - dk0, d1 - dk1, d2 - dk2
    qv = q0 * v0 + q1 * v1 + q2 * v2
    p0, p1, p2 = q0 - v0 * qv, q1 - v1 * qv, q2 - v2 * qv
    ep = h0 * p0 + h1 * p1 + h2 * p2
    r0, r1, r2 = (p0 - h0 * ep) * inv_rho, (p1 - h1 * ep) * inv_rho, (p2 - h2 * ep) * inv_rho
    # dtop = dk + e dradial; dend = e_d - dj dradial (``end = x + offsets - (D - e) radial``, D - e = dj)
    t0, t1, t2 = dk0 + e * r0, dk1 + e * r1, dk2 + e * r2
    n0, n1, n2 = d0 - dj * r0, d1 - dj * r1, d2 - dj * r2
    w0, w1, w2 = _spin(f, n0 - t0, n1 - t1, n2 - t2, nx)
    return _body_column(f, w0, w1, w2, t0, t1, t2, body[1], body[2], body[3])


@jit()
def _leg(x0, x1, x2, q, mp, i):
    """Leg ``i``'s arm, bar pair and rotor in the form, the upper triangle (6 floats)."""
    u, v, root, base, shift = _U + 3 * i, _V + 3 * i, _ROOT + 3 * i, _BASE + 3 * i, _SHIFT + 3 * i
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
    inv_rho = 1.0 / rho                                 # reciprocals for divisions, as in _frame
    scale = (rho - big_d) * inv_rho
    n0, n1, n2 = p0 * scale + along * v0, p1 * scale + along * v1, p2 * scale + along * v2
    inv_b = 1.0 / (n0 * dk0 + n1 * dk1 + n2 * dk2)
    g0, g1, g2 = n0 * inv_b, n1 * inv_b, n2 * inv_b
    # Arm: link_part(base, knee, v, 0, dK G_i); its columns are G_i's entries times one unit arm rate's.
    arm = _body(mp, BODIES + (_ARMS + i) * BODY_SIZE)
    kn0, kn1, kn2 = k0 + mp[shift], k1 + mp[shift + 1], k2 + mp[shift + 2]       # _leg_points' knee
    fa = _frame(kn0 - mp[base], kn1 - mp[base + 1], kn2 - mp[base + 2], v0, v1, v2)
    w0, w1, w2 = _spin(fa, dk0, dk1, dk2, fa[0] * v0 + fa[1] * v1 + fa[2] * v2)
    unit = _body_column(fa, w0, w1, w2, 0.0, 0.0, 0.0, arm[1], arm[2], arm[3])
    s = _pair(unit, unit, arm) + mp[ROTORS + i]          # kinetic_form's rotor: r_i G_i^T G_i
    # Bar pair: link_part(top, end, v, dtop, dend), top = knee + e radial, end = top + n
    bar = _body(mp, BODIES + (_BARS + i) * BODY_SIZE)
    e, dj = mp[_E], mp[_DJ]
    h0, h1, h2 = p0 * inv_rho, p1 * inv_rho, p2 * inv_rho
    fb = _frame(n0, n1, n2, v0, v1, v2)                # end - top is n (the model rounds (top + n) - top)
    nx = fb[0] * v0 + fb[1] * v1 + fb[2] * v2
    c0 = _bar_column(1.0, 0.0, 0.0, dk0 * g0, dk1 * g0, dk2 * g0, v0, v1, v2, h0, h1, h2, inv_rho, fb, nx, e, dj, bar)
    c1 = _bar_column(0.0, 1.0, 0.0, dk0 * g1, dk1 * g1, dk2 * g1, v0, v1, v2, h0, h1, h2, inv_rho, fb, nx, e, dj, bar)
    c2 = _bar_column(0.0, 0.0, 1.0, dk0 * g2, dk1 * g2, dk2 * g2, v0, v1, v2, h0, h1, h2, inv_rho, fb, nx, e, dj, bar)
    t = _six(c0, c1, c2, bar)
    return (t[0] + s * g0 * g0, t[1] + s * g0 * g1, t[2] + s * g0 * g2,
            t[3] + s * g1 * g1, t[4] + s * g1 * g2, t[5] + s * g2 * g2)


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
    mp : ndarray, shape (129,)
        ``pack_mass(mechanism)``.

    Returns
    -------
    tuple of 6 float
        ``kinetic_form(mech, q, x, rotors=True)``'s entries ``[0, 0], [0, 1], [0, 2], [1, 1], [1, 2], [2, 2]``.
    """
    l0 = _leg(x0, x1, x2, q0, mp, 0)
    l1 = _leg(x0, x1, x2, q1, mp, 1)
    l2 = _leg(x0, x1, x2, q2, mp, 2)
    m = mp[BODIES + _PLATFORM * BODY_SIZE]           # the platform translates with x: m_p I
    return (m + l0[0] + l1[0] + l2[0], l0[1] + l1[1] + l2[1], l0[2] + l1[2] + l2[2],
            m + l0[3] + l1[3] + l2[3], l0[4] + l1[4] + l2[4], m + l0[5] + l1[5] + l2[5])


@jit()
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
    mp : ndarray, shape (129,)
        ``pack_mass(mechanism)``.

    Returns
    -------
    ndarray, shape (k, 3, 3)
    """
    k = x.shape[0]
    out = np.empty((k, 3, 3))
    for i in range(k):
        j = jac[i]
        f = inertia(x[i, 0], x[i, 1], x[i, 2], q[i, 0], q[i, 1], q[i, 2],
                    j[0, 0], j[0, 1], j[0, 2], j[1, 0], j[1, 1], j[1, 2], j[2, 0], j[2, 1], j[2, 2], mp)
        out[i, 0, 0], out[i, 0, 1], out[i, 0, 2] = f[0], f[1], f[2]
        out[i, 1, 0], out[i, 1, 1], out[i, 1, 2] = f[1], f[3], f[4]
        out[i, 2, 0], out[i, 2, 1], out[i, 2, 2] = f[2], f[4], f[5]
    return out
