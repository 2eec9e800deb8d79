"""The Stewart platform's kinetic form (``kinematics.stewart``), compiled point by point.

``inertia_points`` gives what ``kinematics.dynamics.kinetic_form(mech, q, x, rotors=True)`` gives
for the model's poses: ``Lambda`` per rate of the pose coordinates (position and rotation vector),
kg, from the bodies' exact velocities as ``StewartPlatform.body_velocities`` forms them:

    Lambda = sym(sum_b m_b Jv_b^T Jv_b + Jw_b^T R_b I_b R_b^T Jw_b) + G^T diag(r) G

(``kinematics.bodies.kinetic_columns``, then ``kinetic_form``'s rotors). Per leg ``i`` the platform
joint moves at ``dleg = [I | (J_l e_j) x R p_i]`` (3 x 6), the cylinder's frame is ``link_frames``'
from the base joint to the platform joint (``link_frame_rates``: ``e_x`` along the leg, ``e_y`` across
it and the base's tangent ``t_i``), its angular velocity ``e_x x e_x' + e_x (e_x' . e_y)(e_x . t_i) / |t_i
x e_x|``, its origin still; the piston's frame is the cylinder's with ``e_x`` and ``e_y`` reversed, the
same angular velocity, its origin at the platform joint; ``G``'s row i is ``L_i . dleg / |L_i|``. The
platform turns at ``[0 | J_l]`` and its origin, the task point, moves at ``[I | 0]``. The same
formulas in the same steps, summed in another order (one point's 3-vectors here, numpy's passes
there): the two paths differ by rounding only (``tests/metrics/test_kernel_mass_stewart.py``
bounds it).

The rotation ``R`` and the left Jacobian ``J_l`` of the rotation vector come from the caller
(``kinematics.rotations``, numpy), with their small-angle forms. A pose with a non-finite
coordinate gets ``nan``.
"""
from __future__ import annotations

import numpy as np

from .jit import jit

#: Bodies in ``StewartPlatform.bodies`` order: six cylinders, six pistons, the platform.
CYLINDER, PISTON, PLATFORM = 0, 6, 12


def pack_mass(mechanism) -> tuple[np.ndarray, ...]:
    """The model's geometry and bodies for ``inertia_points``.

    Parameters
    ----------
    mechanism : StewartPlatform
        With a mass model.

    Returns
    -------
    tuple of ndarray
        ``base`` (6, 3) and ``platform`` (6, 3) joints, the base tangents (6, 3), the bodies'
        masses (13,), centres in their frames (13, 3) and tensors (13, 3, 3), the reflected rotor
        inertias (6,).
    """
    from kinematics.bodies import body_arrays

    base = np.ascontiguousarray(mechanism.base_joints(), dtype=np.float64)
    tangent = np.cross([0.0, 0.0, 1.0], base)
    tangent /= np.linalg.norm(tangent, axis=-1, keepdims=True)
    masses, com, tensors = body_arrays(mechanism.bodies())
    return (base, np.ascontiguousarray(mechanism.platform_joints(), dtype=np.float64), np.ascontiguousarray(tangent),
            np.ascontiguousarray(masses, dtype=np.float64), np.ascontiguousarray(com, dtype=np.float64),
            np.ascontiguousarray(tensors, dtype=np.float64),
            np.ascontiguousarray(mechanism.reflected_rotor_inertias(), dtype=np.float64))


@jit(inline=True)
def cross(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@jit(inline=True)
def add_body(lam, mass, tensor, rot, jv, jw, body, turned):
    """``lam += m Jv^T Jv + (R^T Jw)^T I (R^T Jw)`` (6 x 6, upper triangle) of one body; ``body``,
    ``turned`` (3, 6) scratch: ``R^T Jw`` and ``I R^T Jw``."""
    for c in range(3):
        for a in range(6):
            body[c, a] = rot[0, c] * jw[0, a] + rot[1, c] * jw[1, a] + rot[2, c] * jw[2, a]
    for c in range(3):
        for a in range(6):
            turned[c, a] = tensor[c, 0] * body[0, a] + tensor[c, 1] * body[1, a] + tensor[c, 2] * body[2, a]
    for a in range(6):
        for b in range(a, 6):
            lam[a, b] += (mass * (jv[0, a] * jv[0, b] + jv[1, a] * jv[1, b] + jv[2, a] * jv[2, b])
                          + (body[0, a] * turned[0, b] + body[1, a] * turned[1, b] + body[2, a] * turned[2, b]))


@jit(inline=True)
def centre_velocity(jv, do, jw, rot, com):
    """``jv = do + jw x (R c)`` (3, 6) per column."""
    c0 = rot[0, 0] * com[0] + rot[0, 1] * com[1] + rot[0, 2] * com[2]
    c1 = rot[1, 0] * com[0] + rot[1, 1] * com[1] + rot[1, 2] * com[2]
    c2 = rot[2, 0] * com[0] + rot[2, 1] * com[1] + rot[2, 2] * com[2]
    for j in range(6):
        w0, w1, w2 = cross(jw[0, j], jw[1, j], jw[2, j], c0, c1, c2)
        jv[0, j] = do[0, j] + w0
        jv[1, j] = do[1, j] + w1
        jv[2, j] = do[2, j] + w2


@jit(allocates=True)
def inertia_points(x, rot, left, base, platform, tangent, masses, com, tensors, rotors, out):
    """``Lambda`` (N, 6, 6) per pose-coordinate rate at poses ``x`` (N, 6) into ``out``.

    Parameters
    ----------
    x : ndarray, shape (N, 6)
        Poses (m, rad).
    rot, left : ndarray, shape (N, 3, 3)
        ``R(x)`` and ``J_l`` of the rotation vectors (``kinematics.rotations``).
    base, platform, tangent, masses, com, tensors, rotors : ndarray
        ``pack_mass``.
    out : ndarray, shape (N, 6, 6)
        kg, kg m and kg m^2 entries by the coordinates' units.
    """
    scratch = np.empty(SCRATCH)
    for p in range(x.shape[0]):
        finite = True
        for k in range(6):
            if not np.isfinite(x[p, k]):
                finite = False
        if not finite:
            out[p] = np.nan
            continue
        inertia_point(x[p, 0], x[p, 1], x[p, 2], rot[p], left[p], base, platform, tangent, masses, com, tensors,
                      rotors, out[p], scratch)


#: Length of ``inertia_point``'s scratch: ``lam`` (6 x 6), seven 3 x 6 blocks, ``frame`` (3 x 3), ``G`` (6 x 6).
SCRATCH = 36 + 7 * 18 + 9 + 36


@jit(inline=True)
def inertia_point(o0, o1, o2, r, left, base, platform, tangent, masses, com, tensors, rotors, out, scratch):
    """``Lambda`` (6, 6) of one finite pose into ``out``: task point ``(o0, o1, o2)``, ``R`` and ``J_l`` ``r``,
    ``left`` (3, 3), the model's arrays as ``inertia_points``'; ``scratch`` (``SCRATCH``,) is overwritten."""
    lam = scratch[0:36].reshape(6, 6)
    jv = scratch[36:54].reshape(3, 6)
    jw = scratch[54:72].reshape(3, 6)
    do = scratch[72:90].reshape(3, 6)
    dleg = scratch[90:108].reshape(3, 6)
    dex = scratch[108:126].reshape(3, 6)
    body = scratch[126:144].reshape(3, 6)
    turned = scratch[144:162].reshape(3, 6)
    frame = scratch[162:171].reshape(3, 3)
    g = scratch[171:207].reshape(6, 6)
    lam[:] = 0.0
    # The platform: turns at [0 | J_l], its origin (the task point) moves at [I | 0].
    for c in range(3):
        for j in range(6):
            do[c, j] = 1.0 if j == c else 0.0
            jw[c, j] = left[c, j - 3] if j >= 3 else 0.0
    centre_velocity(jv, do, jw, r, com[PLATFORM])
    add_body(lam, masses[PLATFORM], tensors[PLATFORM], r, jv, jw, body, turned)
    for i in range(6):
        # R p_i, the leg L_i = o + R p_i - b_i and its unit e_x.
        a0 = r[0, 0] * platform[i, 0] + r[0, 1] * platform[i, 1] + r[0, 2] * platform[i, 2]
        a1 = r[1, 0] * platform[i, 0] + r[1, 1] * platform[i, 1] + r[1, 2] * platform[i, 2]
        a2 = r[2, 0] * platform[i, 0] + r[2, 1] * platform[i, 1] + r[2, 2] * platform[i, 2]
        l0 = o0 + a0 - base[i, 0]
        l1 = o1 + a1 - base[i, 1]
        l2 = o2 + a2 - base[i, 2]
        length = np.sqrt(l0 * l0 + l1 * l1 + l2 * l2)
        e0, e1, e2 = l0 / length, l1 / length, l2 / length
        for j in range(6):
            if j < 3:
                dleg[0, j], dleg[1, j], dleg[2, j] = (1.0 if j == 0 else 0.0), (1.0 if j == 1 else 0.0), (
                    1.0 if j == 2 else 0.0)
            else:
                dleg[0, j], dleg[1, j], dleg[2, j] = cross(left[0, j - 3], left[1, j - 3],
                                                            left[2, j - 3], a0, a1, a2)
            along = e0 * dleg[0, j] + e1 * dleg[1, j] + e2 * dleg[2, j]
            dex[0, j] = (dleg[0, j] - e0 * along) / length
            dex[1, j] = (dleg[1, j] - e1 * along) / length
            dex[2, j] = (dleg[2, j] - e2 * along) / length
            g[i, j] = (l0 * dleg[0, j] + l1 * dleg[1, j] + l2 * dleg[2, j]) / length
        t0, t1, t2 = tangent[i, 0], tangent[i, 1], tangent[i, 2]
        s0, s1, s2 = cross(t0, t1, t2, e0, e1, e2)
        width = np.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
        y0, y1, y2 = s0 / width, s1 / width, s2 / width
        z0, z1, z2 = cross(e0, e1, e2, y0, y1, y2)
        slope = e0 * t0 + e1 * t1 + e2 * t2
        for j in range(6):
            twist = (dex[0, j] * y0 + dex[1, j] * y1 + dex[2, j] * y2) * slope
            w0, w1, w2 = cross(e0, e1, e2, dex[0, j], dex[1, j], dex[2, j])
            spin = twist / width
            jw[0, j], jw[1, j], jw[2, j] = w0 + e0 * spin, w1 + e1 * spin, w2 + e2 * spin
        # The cylinder: frame [e_x e_y e_z] at the base joint, which is still.
        frame[0, 0], frame[1, 0], frame[2, 0] = e0, e1, e2
        frame[0, 1], frame[1, 1], frame[2, 1] = y0, y1, y2
        frame[0, 2], frame[1, 2], frame[2, 2] = z0, z1, z2
        do[:] = 0.0
        centre_velocity(jv, do, jw, frame, com[CYLINDER + i])
        add_body(lam, masses[CYLINDER + i], tensors[CYLINDER + i], frame, jv, jw, body, turned)
        # The piston: the same frame from the other end, e_x and e_y reversed, at the platform joint.
        for c in range(3):
            frame[c, 0] = -frame[c, 0]
            frame[c, 1] = -frame[c, 1]
        centre_velocity(jv, dleg, jw, frame, com[PISTON + i])
        add_body(lam, masses[PISTON + i], tensors[PISTON + i], frame, jv, jw, body, turned)
    # The upper triangle was summed; numpy symmetrises its full sums, 0.5 (L + L^T), the same
    # value to rounding. Then the rotors, G^T diag(r) G.
    for a in range(6):
        for b in range(a, 6):
            acc = lam[a, b]
            for u in range(6):
                acc += g[u, a] * rotors[u] * g[u, b]
            out[a, b] = acc
            out[b, a] = acc
