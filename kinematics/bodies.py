"""Rigid bodies of a mechanism and what they weigh in motion: the joint-space mass matrix.

A mass model is a list of rigid bodies, each with its mass ``m_b`` (kg), its centre of mass
``c_b`` and its inertia tensor ``I_b`` about that centre (kg m^2), both in the body's own frame,
plus each actuator's rotor inertia ``J_u`` (kg m^2, motor side). A mechanism places its bodies:
``body_poses`` gives each body frame's orientation ``R_b`` (..., k, 3, 3) and origin ``o_b``
(..., k, 3) in the base frame at a pose. The kinetic energy is

    T = 1/2 sum_b ( m_b |v_b|^2 + w_b^T R_b I_b R_b^T w_b ) + 1/2 sum_u J_u N_u^2 qdot_u^2,

with ``v_b`` the velocity of the body's centre of mass, ``w_b`` its angular velocity (base
frame) and ``N_u`` the transmission ratio (joint side per motor side, so a rotor turns at
``N_u qdot_u`` and its inertia is felt at the joint as ``J_u N_u^2``).

``T`` is a quadratic form in the velocity of whichever coordinates place the bodies. A serial
arm places them from its joints ``q`` (``mass_coordinates = "joint"``); a parallel mechanism
from its task pose ``x``, through its closed-form inverse kinematics (``"task"``). The body
velocity Jacobians ``dv_b/du`` and ``dw_b/du`` with respect to those coordinates ``u`` are each
model's exact ``body_velocities`` (from its chain Jacobians and loop closures, with the
component-first helpers below: ``link_frame_rates``, ``stack_bodies``, ``kinetic_columns``).
``body_jacobians``, central differences of the body poses (truncation of order ``h^2``,
rounding of order ``eps / h``, ``h = eps^(1/3)`` relative), is kept as the tests' independent
reference, with ``kinetic_energy`` along random velocities. Then

    K(u) = sum_b m_b Jv_b^T Jv_b + Jw_b^T (R_b I_b R_b^T) Jw_b  (+ rotors),

which is ``M(q)`` for joint coordinates and the task-space inertia ``Lambda(x)`` for task
coordinates (the rotors then enter as ``G^T diag(J_u N_u^2) G``, ``G = dq/dx``).
``M = J^T Lambda J`` and ``Lambda = (J M^-1 J^T)^-1`` convert between the two where ``J`` is
square and regular.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from numpy.typing import ArrayLike

from .arrays import FloatArray

#: Relative central-difference step: ``eps^(1/3)`` balances the ``h^2`` truncation error
#: against the ``eps / h`` rounding error of a central difference.
FD_STEP = float(np.finfo(float).eps) ** (1.0 / 3.0)


@dataclass(frozen=True)
class Body:
    """One rigid body: mass (kg), centre of mass (m) and inertia about it (kg m^2), body frame.

    Attributes
    ----------
    name : str
    mass : float
        kg, positive.
    com : tuple of 3 float
        Centre of mass in the body frame, m.
    inertia : tuple of 6 float
        ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` about the centre of mass, body axes, kg m^2 (the
        tensor's off-diagonal entries are these, not their negatives).
    """

    name: str
    mass: float
    com: tuple[float, float, float]
    inertia: tuple[float, float, float, float, float, float]

    def __post_init__(self) -> None:
        check_body(self.name, self.mass, self.com, self.inertia)

    def tensor(self) -> FloatArray:
        """The inertia tensor (3, 3), kg m^2, about the centre of mass in body axes."""
        xx, yy, zz, xy, xz, yz = self.inertia
        return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]], float)


def check_body(name: str, mass: float, com, inertia, *, key: str | None = None) -> None:
    """Raise a ValueError naming ``name`` and the key unless the body is physical.

    The mass is positive and finite; the centre three finite numbers; the inertia tensor is
    positive semi-definite and its principal moments obey the triangle inequality
    ``I_1 + I_2 >= I_3`` (a rigid body's moments are sums of squared distances).

    Examples
    --------
    >>> check_body("link", 0.1, (0, 0, 0), (1e-4, 1e-4, 1e-4, 0, 0, 0))
    >>> check_body("link", 0.1, (0, 0, 0), (1e-4, 1e-4, 3e-4, 0, 0, 0))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: bodies.link.inertia: principal moments 0.0001, 0.0001, 0.0003 kg m^2 break the triangle ...
    """
    where = f"bodies.{name}" if key is None else key
    tensor = where if key else f"{where}.inertia"
    if not (isinstance(mass, (int, float)) and math.isfinite(mass) and mass > 0):
        raise ValueError(f"{where}.mass must be a positive finite number in kg, got {mass!r}")
    c = np.asarray(com, float) if _numeric(com) else None
    if c is None or c.shape != (3,) or not np.all(np.isfinite(c)):
        raise ValueError(f"{where}.com must be 3 finite numbers (x, y, z) in m, got {com!r}")
    i = np.asarray(inertia, float) if _numeric(inertia) else None
    if i is None or i.shape != (6,) or not np.all(np.isfinite(i)):
        raise ValueError(f"{tensor} must be 6 finite numbers (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) "
                         f"in kg m^2, got {inertia!r}")
    xx, yy, zz, xy, xz, yz = i
    moments = np.linalg.eigvalsh(np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]))
    scale = float(np.abs(i).max()) or 1.0
    slack = 8 * np.finfo(float).eps * scale               # eigvalsh's backward error, a few eps |I|
    if moments[0] < -slack:
        raise ValueError(f"{tensor} is not positive semi-definite: principal moments "
                         f"{', '.join(f'{m:.4g}' for m in moments)} kg m^2")
    if moments[0] + moments[1] < moments[2] - slack:
        listed = ", ".join(f"{m:.4g}" for m in moments)
        raise ValueError(f"{tensor}: principal moments {listed} kg m^2 break the triangle inequality (I1 + I2 >= I3)")


def _numeric(values) -> bool:
    try:
        np.asarray(values, float)
    except (TypeError, ValueError):
        return False
    return True


def rod(name: str, mass: float, length: float, axis: int = 0, *, radius: float = 0.0) -> Body:
    """A uniform slender rod (a thin cylinder) along body ``axis`` from the origin to ``length``.

    Its centre of mass is at ``length / 2`` on that axis; about it the moments are
    ``m L^2 / 12 + m r^2 / 4`` across and ``m r^2 / 2`` along the rod.

    Examples
    --------
    >>> [round(v, 12) for v in rod("l1", 0.012, 0.1, radius=0.01).inertia[:3]]
    [6e-07, 1.03e-05, 1.03e-05]
    """
    across = mass * length**2 / 12 + mass * radius**2 / 4
    along = mass * radius**2 / 2
    moments = [across] * 3
    moments[axis] = along
    com = [0.0, 0.0, 0.0]
    com[axis] = length / 2
    # A rod with no radius has a zero moment about its axis: positive semi-definite, allowed.
    return Body(name, mass, tuple(com), (*(float(m) for m in moments), 0.0, 0.0, 0.0))


def point_mass(name: str, mass: float) -> Body:
    """A body whose inertia about its centre is negligible (a handle, a joint block), at its origin."""
    return Body(name, mass, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0, 0.0, 0.0))


def body_arrays(bodies: tuple[Body, ...]) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Masses (k,), centres (k, 3) and inertia tensors (k, 3, 3) of ``bodies``."""
    return (np.array([b.mass for b in bodies], float), np.array([b.com for b in bodies], float),
            np.array([b.tensor() for b in bodies], float).reshape(len(bodies), 3, 3))


def centres(rotations: FloatArray, origins: FloatArray, com: FloatArray) -> FloatArray:
    """Centres of mass in the base frame, ``o_b + R_b c_b``, shape (..., k, 3)."""
    return origins + (rotations @ com[:, :, None])[..., 0]


def _axial(spin: FloatArray) -> FloatArray:
    """The axial vector (..., 3) of the skew part of ``spin`` (..., 3, 3)."""
    return 0.5 * np.stack([spin[..., 2, 1] - spin[..., 1, 2], spin[..., 0, 2] - spin[..., 2, 0],
                           spin[..., 1, 0] - spin[..., 0, 1]], axis=-1)


PoseFunction = Callable[[FloatArray], tuple[FloatArray, FloatArray, FloatArray]]


def body_jacobians(poses: PoseFunction, u: FloatArray, com: FloatArray, scale: FloatArray, *,
                   step: float = FD_STEP) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Velocity Jacobians of each body's centre and angular velocity, by central differences.

    Parameters
    ----------
    poses : callable
        ``u (..., d) -> (R (..., k, 3, 3), o (..., k, 3), extra (..., e))``: body frames at
        coordinates ``u``, and any other function of ``u`` to differentiate alongside (the
        actuated joints ``q`` when ``u`` is the task pose; ``e = 0`` otherwise). ``nan`` where
        the mechanism does not assemble.
    u : ndarray, shape (..., d)
        Coordinates the bodies are placed from.
    com : ndarray, shape (k, 3)
        Centres of mass in the body frames, m.
    scale : ndarray, shape (d,)
        Size of each coordinate (m or rad); the step is ``FD_STEP * max(|u_j|, scale_j)``.

    Returns
    -------
    jv : ndarray, shape (..., k, 3, d)
        ``dc_b/du``: velocity of each centre of mass per unit coordinate rate.
    jw : ndarray, shape (..., k, 3, d)
        Angular velocity of each body (base frame) per unit coordinate rate.
    rotations : ndarray, shape (..., k, 3, 3)
        ``R_b(u)``.
    jextra : ndarray, shape (..., e, d)
        ``d extra / du``.
    """
    rot, _, _ = poses(u)
    d = u.shape[-1]
    jv, jw, je = [], [], []
    for j in range(d):
        h = step * np.maximum(np.abs(u[..., j]), scale[j])                     # (...)
        shift = np.zeros_like(u)
        shift[..., j] = h
        # The step actually taken, (u + h) - u, is exact in binary; dividing by it removes the
        # representation error of h from the quotient.
        up, down = u + shift, u - shift
        span = (up - down)[..., j][..., None]
        r_up, o_up, e_up = poses(up)
        r_dn, o_dn, e_dn = poses(down)
        jv.append((centres(r_up, o_up, com) - centres(r_dn, o_dn, com)) / span[..., None])
        # dR/du R^T is skew-symmetric; its axial vector is the angular velocity per unit rate.
        jw.append(_axial((r_up - r_dn) @ np.swapaxes(rot, -1, -2)) / span[..., None])
        je.append((e_up - e_dn) / span)
    return np.stack(jv, axis=-1), np.stack(jw, axis=-1), rot, np.stack(je, axis=-1)


# -- exact body velocities, component-first ------------------------------------------------
# The models' ``body_velocities`` work on component-first arrays with the (flattened) batch last:
# a vector field is (3, N), a Jacobian (3, d, N), a rotation (3, 3, N) (row i, column c). Every
# operation is then on contiguous length-N slabs: sums over a 3-axis are three adds, not a
# reduction over a short strided axis, and no batch of 3 x 3 matrix products is formed.


def columns(values: ArrayLike) -> FloatArray:
    """``(..., *shape)`` batch-first -> component-first ``(*shape, N)`` for one trailing axis group.

    ``values`` (N, ...) with the batch already flattened to N; the batch axis moves last.
    """
    values = np.asarray(values, float)
    return np.ascontiguousarray(np.moveaxis(values, 0, -1))


def dot3(a: FloatArray, b: FloatArray) -> FloatArray:
    """``a . b`` over the leading 3-axis of component-first arrays (broadcasting the rest)."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross3(a: FloatArray, b: FloatArray) -> FloatArray:
    """``a x b`` over the leading 3-axis of component-first arrays (broadcasting the rest)."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        np.multiply(a[j], b[k], out=out[i])
        out[i] -= a[k] * b[j]
    return out


def unit_rate(unit: FloatArray, raw_rate: FloatArray, length: FloatArray) -> FloatArray:
    """Rate (3, d, N) of ``e = r / |r|`` (``unit`` (3, N), ``length`` (N,)) from ``r``'s: ``(I - e e^T) r' / |r|``."""
    e = unit[:, None]
    return (raw_rate - e * dot3(e, raw_rate)) / length


def link_frame_rates(a: FloatArray, b: FloatArray, normal: FloatArray, da: FloatArray, db: FloatArray,
                     dnormal: FloatArray | None = None) -> tuple[FloatArray, FloatArray]:
    """``kinematics.mass_params.link_frames(a, b, normal)`` (3, 3, N) and its angular velocity (3, d, N), exactly.

    ``e_x = (b - a) / |b - a|``, ``e_y = s / |s|`` with ``s = n x e_x``, ``e_z = e_x x e_y``
    (the columns), moving with the points' rates ``da``, ``db`` (3, d, N) and the normal's
    ``dnormal`` (``None``: a fixed normal, ``normal`` then (3, 1) or (3, N)). The frame turns at
    ``omega = e_x x e_x' + (e_y' . e_z) e_x``: the first term turns the link's axis, the second
    spins the frame about it, with ``e_y' . e_z = s' . e_z / |s|`` and
    ``s' . e_z = e_x' . (e_z x n) - n' . e_y`` (``s' = n' x e_x + n x e_x'``, triple products).
    """
    raw = b - a
    length = np.sqrt(dot3(raw, raw))
    ex = raw / length
    dex = unit_rate(ex, db - da, length)
    side = cross3(normal, ex)
    width = np.sqrt(dot3(side, side))
    ey = side / width
    ez = cross3(ex, ey)
    # s' . e_z = e_x' . (e_z x n) - n' . e_y, and e_z x n = (e_x x e_y) x n = e_y (e_x . n) (e_y . n = 0).
    twist = dot3(dex, ey[:, None]) * dot3(ex, normal)
    if dnormal is not None:
        twist = twist - dot3(dnormal, ey[:, None])
    omega = cross3(ex[:, None], dex)
    omega += ex[:, None] * (twist / width)
    return np.stack([ex, ey, ez], axis=1), omega


def link_part(a: FloatArray, b: FloatArray, normal: FloatArray, da: FloatArray, db: FloatArray,
              dnormal: FloatArray | None = None) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(R, omega, do)`` of a link from ``a`` to ``b`` (``link_frame_rates``), its origin at ``a``."""
    rot, omega = link_frame_rates(a, b, normal, da, db, dnormal)
    return rot, omega, da


def plane_link_part(a: FloatArray, b: FloatArray, normal: FloatArray, da: FloatArray, db: FloatArray,
                    plane_omega: FloatArray | None = None) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``link_part`` of a link lying in a plane of unit ``normal`` that turns at ``plane_omega`` (3, d, N).

    The frame is ``link_frames``' (``e_x`` along the link, ``e_z = normal``); it turns with the plane
    and about the normal at the link's in-plane rate: ``omega = w_p + n (e_y . (b' - a') / |b - a| - w_p . n)``
    (the points' rates less the plane's own turning, ``w_p x (b - a)``, whose ``e_y`` component is
    ``-(w_p . n) |b - a|``). ``link_frame_rates``' general formula gives the same where ``b - a`` is
    in the plane, with fewer passes over the (3, d, N) rates. ``plane_omega`` None: a fixed plane.
    """
    raw = b - a
    length = np.sqrt(dot3(raw, raw))
    ex = raw / length
    side = cross3(normal, ex)
    ey = side / np.sqrt(dot3(side, side))
    ez = cross3(ex, ey)
    spin = dot3(ey[:, None], db - da) / length                                          # (d, N)
    if plane_omega is None:
        omega = ez[:, None] * spin
    else:
        omega = plane_omega + ez[:, None] * (spin - dot3(plane_omega, ez[:, None]))
    return np.stack([ex, ey, ez], axis=1), omega, da


def translating_part(dorigin: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(R, omega, do)`` of a body that only translates (identity axes), its origin moving at ``dorigin``."""
    _, d, n = dorigin.shape
    return np.broadcast_to(np.eye(3)[..., None], (3, 3, n)), np.zeros((3, d, n)), dorigin


def stack_bodies(parts: list[tuple[FloatArray, FloatArray, FloatArray]], com: FloatArray
                 ) -> tuple[list[FloatArray], list[FloatArray], list[FloatArray]]:
    """``jv``, ``jw`` (k of (3, d, N)) and ``R`` (k of (3, 3, N)) of the bodies' ``(R, omega, do)`` parts.

    Lists, one array per body, not stacked: ``kinetic_columns`` takes them body by body, so no
    (k, 3, d, N) copy is made (``np.stack`` them where one is wanted).

    Each body: ``R`` (3, 3, N) its axes, ``omega`` (3, d, N) its angular velocity and ``do``
    (3, d, N) its origin's velocity per unit coordinate rate; ``com`` (k, 3) the centres in the
    body frames. The centre moves at ``do + omega x R c``.
    """
    rot, omega, dorigin = zip(*parts)
    jv = []
    for r, w, do, c in zip(rot, omega, dorigin, com):
        if not np.any(c):
            jv.append(do)
            continue
        arm = sum(r[:, i] * c[i] for i in range(3) if c[i] != 0.0)                     # R c, (3, N)
        jv.append(do + cross3(w, arm[:, None]))
    return jv, list(omega), list(rot)


def kinetic_columns(masses: FloatArray, tensors: FloatArray, jv, jw, rot) -> FloatArray:
    """``sum_b m_b Jv_b^T Jv_b + Jw_b^T R_b I_b R_b^T Jw_b`` component-first, (d, d, N).

    ``jv``, ``jw``: per body (3, d, N) (a (k, 3, d, N) array or a list of k), ``rot`` per body
    (3, 3, N), ``tensors`` (k, 3, 3) in body axes. The angular velocity is taken to body axes
    (``R^T Jw``) to meet the constant tensor there. Each body's terms are weighted by its mass
    (not ``sqrt(m) Jv``: a scaled mass scales the form exactly).
    """
    out = None
    for b, mass in enumerate(masses):
        term = np.einsum("ian,ibn->abn", mass * jv[b], jv[b])
        if np.any(tensors[b]):
            body = np.einsum("icn,idn->cdn", rot[b], jw[b])                               # R^T Jw
            term += np.einsum("cdn,cen->den", body, np.einsum("ce,edn->cdn", tensors[b], body))
        out = term if out is None else out + term
    return 0.5 * (out + np.swapaxes(out, 0, 1))      # exactly symmetric


def kinetic_energy(masses: FloatArray, tensors: FloatArray, com: FloatArray, poses: PoseFunction,
                   u: ArrayLike, udot: ArrayLike, dt: float) -> FloatArray:
    """Kinetic energy of the bodies moving along ``udot`` from finite differences of their poses.

    An independent check of ``kinetic_matrix``: the bodies are placed at ``u -+ dt udot``, their
    centres' velocities and angular velocities differenced over ``2 dt``, and the energy summed
    body by body, with no Jacobian formed.

    Returns
    -------
    ndarray, shape (...)
        J.
    """
    u, udot = np.asarray(u, float), np.asarray(udot, float)
    r0, _, _ = poses(u)
    r_up, o_up, _ = poses(u + dt * udot)
    r_dn, o_dn, _ = poses(u - dt * udot)
    v = (centres(r_up, o_up, com) - centres(r_dn, o_dn, com)) / (2 * dt)
    w = _axial((r_up - r_dn) / (2 * dt) @ np.swapaxes(r0, -1, -2))
    w_body = np.einsum("...kji,...kj->...ki", r0, w)                                   # R^T w
    return 0.5 * (np.einsum("k,...ki,...ki->...", masses, v, v)
                  + np.einsum("...ki,kij,...kj->...", w_body, tensors, w_body))
