"""The serial RRR family's kinetic form (``kinematics.serial_rrr``: PHANToM, Omni, WoodenHaptics), compiled.

``inertia`` is ``kinematics.dynamics.kinetic_form(mech, q, x, rotors=True)`` at one pose, in scalars:
the joint-space mass matrix (``mass_coordinates = "joint"``)

    M(q) = sum_b m_b Jv_b^T Jv_b + Jw_b^T R_b I_b R_b^T Jw_b  +  diag(J_u N_u^2)

(``kinematics.bodies.kinetic_columns`` plus the rotors). It is evaluated in the arm's turning frame
``(r, t, k)`` of ``SerialRRR._body_coordinates`` rather than in frame {0}: every column of
``body_velocities`` is a combination of ``r``, ``t``, ``k`` with coefficients that do not involve q1:

=======================  ===============================  ========================================
column                   ``Jv_b`` (centre's velocity)     ``R_b^T Jw_b`` (body axes)
=======================  ===============================  ========================================
q1                       ``rad t - tan r``                ``(x_k, y_k, 0)``: ``R_b^T k``
q2, q3                   ``d_rad r + d_h k``              ``(0, 0, 1)``: ``R_b^T (-t)`` at the body's
                                                          own joint, 0 at the other
=======================  ===============================  ========================================

with ``x_k``, ``y_k`` the k components of the body's x and y axes (``body_poses``' ``plane``; the turret
``g`` has ``R_b^T k = (0, 0, 1)``). ``r``, ``t``, ``k`` being orthonormal, the products are

    m (rad^2 + tan^2),  -m tan d_rad_j,  m (d_rad_i d_rad_j + d_h_i d_h_j)     (translation)
    w^T I w with w = (x_k, y_k, 0),  I_xz x_k + I_yz y_k,  I_zz               (rotation)

so ``M`` does not depend on q1 (nor on ``x`` or J: their arguments are accepted for the kernels'
uniform signature and not read). The sums are those of frame {0} without the ``cos^2 q1 + sin^2 q1``
round trip; they agree with the numpy path to rounding (``tests/metrics/test_kernel_mass_serial_rrr``).
Every term is linear in exactly one mass, tensor entry or rotor inertia, so scaling all of them by a
power of two scales the result exactly.
"""
from __future__ import annotations

import math

import numpy as np

from .dynamics import BODY_FLOATS, inertia_points_of, pack_bodies
from .jit import jit

#: The bodies ``SerialRRR.bodies`` gives, in this order (``pack_mass`` checks; the kernels name no model).
BODIES = ("a", "c", "be", "df", "g")
#: ``pack_mass`` layout: the two lengths, then ``_STRIDE`` numbers per body of ``BODIES``, then the rotors.
_BODY0 = 2
_STRIDE = BODY_FLOATS
_ROTORS = _BODY0 + _STRIDE * len(BODIES)
#: Offsets of the bodies (a, c, be, df, g) in the packed array.
_A, _C, _BE, _DF, _G = (_BODY0 + _STRIDE * BODIES.index(name) for name in ("a", "c", "be", "df", "g"))
SIZE = _ROTORS + 3


def pack_mass(mechanism) -> np.ndarray:
    """The mass model as ``inertia`` reads it, float64 (55,).

    Parameters
    ----------
    mechanism : SerialRRR
        A model with ``has_mass_model`` (``bodies()`` raises otherwise).

    Returns
    -------
    ndarray, shape (55,)
        ``[0]`` the first link ``l1`` and ``[1]`` the crank ``l3`` (m: the origins of bodies a and c);
        then per body ``b`` of ``BODIES`` (a, c, be, df, g), at ``2 + 10 b``: its mass (kg), its centre
        of mass ``(x, y, z)`` in its body frame (m) and its inertia tensor about that centre, body
        axes, ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` (kg m^2, tensor entries: ``Body.inertia``); ``[52:55]``
        the rotors as felt at the joints, ``reflected_rotor_inertias()`` (kg m^2).

    Examples
    --------
    >>> from kinematics.serial_rrr import SerialRRR
    >>> mp = pack_mass(SerialRRR())
    >>> mp.shape, float(mp[2]), mp[52:55].round(8).tolist()
    ((55,), 0.02622, [0.00019104, 0.00013548, 0.00013548])
    """
    p = mechanism.params
    out = np.empty(SIZE)
    pack_bodies(mechanism, BODIES, out, _BODY0)
    out[0], out[1] = p.link1_length, p.crank_length
    out[_ROTORS:] = mechanism.reflected_rotor_inertias()
    return out


@jit()
def _moving(m, rad, tan, dr1, dh1, dr2, dh2):
    """``m Jv^T Jv`` of one body, upper triangle ``(00, 01, 02, 11, 12, 22)``.

    ``Jv = [rad t - tan r, dr1 r + dh1 k, dr2 r + dh2 k]`` (``body_velocities``' ``jv``); the mass
    multiplies the first factor, as in ``kinetic_columns``.
    """
    mt = m * tan
    return (m * rad * rad + mt * tan, -mt * dr1, -mt * dr2,
            m * dr1 * dr1 + m * dh1 * dh1, m * dr1 * dr2 + m * dh1 * dh2, m * dr2 * dr2 + m * dh2 * dh2)


@jit()
def _spinning(mp, at, xk, yk):
    """``(R^T Jw)^T I (R^T Jw)`` of a body turning about its z axis at one joint: ``(00, 0j, jj)``.

    The q1 column in body axes is ``w = (xk, yk, 0)``, the joint's ``(0, 0, 1)``; ``I w`` first, then
    ``w^T (I w)``, as ``kinetic_columns`` contracts.
    """
    ixx, iyy, izz = mp[at + 4], mp[at + 5], mp[at + 6]
    ixy, ixz, iyz = mp[at + 7], mp[at + 8], mp[at + 9]
    u0 = ixx * xk + ixy * yk
    u1 = ixy * xk + iyy * yk
    return xk * u0 + yk * u1, ixz * xk + iyz * yk, izz


@jit()
def inertia(x0, x1, x2, q0, q1, q2, a00, a01, a02, a10, a11, a12, a20, a21, a22, mp):
    """``M(q)``'s upper triangle ``(k00, k01, k02, k11, k12, k22)``, kg m^2, for ``mp = pack_mass(mech)``.

    Parameters
    ----------
    x0, x1, x2 : float
        The tip (m); not read (``M`` depends on q2 and q3 only).
    q0, q1, q2 : float
        The joints ``(q1, q2, q3)`` of the model (rad); ``q0`` is not read.
    a00, a01, a02, a10, a11, a12, a20, a21, a22 : float
        ``J[r, c]``; not read (joint coordinates need no ``G``).
    mp : ndarray, shape (55,)
        ``pack_mass``.

    Returns
    -------
    tuple of 6 float
        Row-major upper triangle of ``kinetic_form(mech, q, x)``.
    """
    return inertia_of(math.sin(q1), math.cos(q1), math.sin(q2), math.cos(q2), mp)


@jit()
def inertia_of(s2, c2, s3, c3, mp):
    """``inertia`` from the sines and cosines of the model's ``q2`` and ``q3`` (``s2, c2, s3, c3``): the
    serial RRR kernel has them from its Jacobian, so the kinetic form costs no trigonometric call.

    Returns
    -------
    tuple of 6 float
        Row-major upper triangle of ``kinetic_form(mech, q, x)``, kg m^2.
    """
    l1, l3 = mp[0], mp[1]
    # Centres and their (q2, q3) derivatives: SerialRRR._body_coordinates, row by row; tan = -z
    # for the four bodies whose z axis is -t, the turret's y for g.
    # a, link 2: origin at the elbow l1 (cos q2, sin q2), turns with q3 (x_k, y_k = sin q3, cos q3).
    x, y, z = mp[_A + 1], mp[_A + 2], mp[_A + 3]
    k = _moving(mp[_A], l1 * c2 + x * c3 - y * s3, -z, -l1 * s2, l1 * c2, -x * s3 - y * c3, x * c3 - y * s3)
    w00, w0j, wjj = _spinning(mp, _A, s3, c3)
    k00, k01, k02, k11, k12, k22 = k[0] + w00, k[1], k[2] + w0j, k[3], k[4], k[5] + wjj
    # c, follower: origin at the crank's end l3 (sin q3, -cos q3), turns with q2 (-cos q2, sin q2).
    x, y, z = mp[_C + 1], mp[_C + 2], mp[_C + 3]
    k = _moving(mp[_C], l3 * s3 + x * s2 + y * c2, -z, x * c2 - y * s2, x * s2 + y * c2, l3 * c3, l3 * s3)
    w00, w0j, wjj = _spinning(mp, _C, -c2, s2)
    k00, k01, k02 = k00 + (k[0] + w00), k01 + (k[1] + w0j), k02 + k[2]
    k11, k12, k22 = k11 + (k[3] + wjj), k12 + k[4], k22 + k[5]
    # be, link 1: at the shoulder, turns with q2 (sin q2, cos q2).
    x, y, z = mp[_BE + 1], mp[_BE + 2], mp[_BE + 3]
    k = _moving(mp[_BE], x * c2 - y * s2, -z, -x * s2 - y * c2, x * c2 - y * s2, 0.0, 0.0)
    w00, w0j, wjj = _spinning(mp, _BE, s2, c2)
    k00, k01, k11 = k00 + (k[0] + w00), k01 + (k[1] + w0j), k11 + (k[3] + wjj)
    # df, drum and crank: at the shoulder, turns with q3 (-cos q3, sin q3).
    x, y, z = mp[_DF + 1], mp[_DF + 2], mp[_DF + 3]
    k = _moving(mp[_DF], x * s3 + y * c3, -z, 0.0, 0.0, x * c3 - y * s3, x * s3 + y * c3)
    w00, w0j, wjj = _spinning(mp, _DF, -c3, s3)
    k00, k02, k22 = k00 + (k[0] + w00), k02 + (k[2] + w0j), k22 + (k[5] + wjj)
    # g, turret: the turning frame itself, centre (x, y, z); only q1 moves it, about its z axis.
    x, y = mp[_G + 1], mp[_G + 2]
    m = mp[_G]
    k00 = k00 + (m * x * x + m * y * y + mp[_G + 6])
    # Rotors on the diagonal (kinetic_form: form += diag(r), joint coordinates).
    return (k00 + mp[_ROTORS], k01, k02, k11 + mp[_ROTORS + 1], k12, k22 + mp[_ROTORS + 2])


def inertia_points(x, q, jac, mp):
    """``inertia`` at k poses, as full symmetric matrices.

    Parameters
    ----------
    x : ndarray, shape (k, 3)
        Tips, m.
    q : ndarray, shape (k, 3)
        Joints, rad.
    jac : ndarray, shape (k, 3, 3)
        ``jacobian(q, x)``.
    mp : ndarray, shape (55,)
        ``pack_mass``.

    Returns
    -------
    ndarray, shape (k, 3, 3)
        ``kinetic_form(mech, q, x)``, kg m^2.
    """
    return inertia_points_of(inertia, x, q, jac, mp)
