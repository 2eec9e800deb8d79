"""A mechanism's mass matrices from its bodies (``kinematics.bodies``): ``M(q)`` and ``Lambda(x)``.

The functions here take any mechanism whose ``bodies``, ``rotor_inertias`` and ``body_poses``
are defined (``has_mass_model``) and place its bodies from the coordinates it names in
``mass_coordinates``:

- ``"joint"`` (serial arms): bodies from ``q``, the pose ``x = forward(q)``; the kinetic form
  is the joint-space mass matrix ``M(q)`` (n x n) plus the rotors ``diag(J_u N_u^2)``, and
  ``Lambda^-1 = J M^-1 J^T``.
- ``"task"`` (closed chains with a closed-form inverse kinematics): bodies from ``x``, the
  joints ``q = inverse(x)``; the kinetic form is the task-space inertia ``Lambda(x)`` (m x m)
  plus the rotors ``G^T diag(J_u N_u^2) G`` with ``G = dq/dxi`` (n x m, from the loop closure),
  and ``M = J^T Lambda J`` where ``J`` is square. For a device with orientation freedoms the
  coordinates are the twist ``xi = T(x) xdot`` (``coordinate_rates_to_twist``) that ``J`` maps
  to, not the pose coordinates' rates: ``Lambda`` is ``T^-T Lambda_x T^-1`` (``twist_columns``),
  right at every orientation (the two agree at zero orientation, ``T = I``).

Every model with a mass model gives its bodies' exact velocity Jacobians (``body_velocities``,
from its own chain Jacobians and loop-closure constraints); ``differenced_velocities``, central
differences of ``body_poses``, is kept only as the tests' independent reference.

Units: a task coordinate in m gives kg, in rad kg m^2; a prismatic joint's rotor inertia is
felt as a mass ``J_u N_u^2`` (kg, ``N_u`` in rad/m).
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .arrays import FloatArray
from .bodies import FD_STEP, body_arrays, body_jacobians, kinetic_columns

#: Size (m) of a length coordinate for the difference step: steps are ``FD_STEP * max(|u|, this)``.
LENGTH_SCALE = 0.05
#: Poses per block in ``kinetic_form``.
KINETIC_BLOCK = 8192


def _coordinate_scales(units: tuple[str, ...]) -> FloatArray:
    return np.array([1.0 if unit == "rad" else LENGTH_SCALE for unit in units])


def _placer(mech, by_task: bool):
    """``u -> (R, o, q)`` (task) or ``u -> (R, o, empty)`` (joint) for ``body_jacobians``."""
    def place(u: FloatArray):
        if by_task:
            q, _ = mech.inverse(u)
            rot, org = mech.body_poses(q, u)
            return rot, org, q
        x, _ = mech.forward(u)
        rot, org = mech.body_poses(u, x)
        return rot, org, u[..., :0]
    return place


def differenced_velocities(mech, q: FloatArray, x: FloatArray, *, step: float = FD_STEP):
    """Body Jacobians by central differences of ``body_poses`` (relative step ``step``), and ``G = dq/dx``.

    The independent reference the tests compare ``body_velocities`` with; not used by the maps.
    Returns ``(jv, jw, rotations, G)`` as ``body_velocities`` does (``G`` is ``None`` for joint
    coordinates).
    """
    _, com, _ = body_arrays(mech.bodies())
    by_task = mech.mass_coordinates == "task"
    u = x if by_task else q
    units = mech.task_units if by_task else mech.joint_units
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        jv, jw, rot, jq = body_jacobians(_placer(mech, by_task), u, com, _coordinate_scales(units), step=step)
    return jv, jw, rot, (jq if by_task else None)


def _velocities(mech, q: FloatArray, x: FloatArray):
    """Masses (k,), tensors (k, 3, 3), the exact body velocities per task twist and the batch shape.

    ``body_velocities`` takes the poses flattened to (N, n), (N, m) and answers component-first
    (``kinematics.bodies``): ``jv``, ``jw`` per body (3, d, N), ``R`` per body (3, 3, N) (each a
    list of k or a (k, ...) array) and ``G`` (n, d, N). A task-placed model with orientation
    freedoms answers per rate of its pose coordinates; they are taken to the twist ``xi`` its
    ``jacobian`` maps to (``twist_columns``), so ``Lambda``, the gravity wrench and ``K = dq/dxi``
    meet ``J`` in the same coordinates at every orientation.
    """
    masses, _, tensors = body_arrays(mech.bodies())
    batch = np.broadcast_shapes(q.shape[:-1], x.shape[:-1])
    q, x = np.broadcast_to(q, batch + q.shape[-1:]), np.broadcast_to(x, batch + x.shape[-1:])
    flat_x = x.reshape(-1, x.shape[-1])
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        jv, jw, rot, g = mech.body_velocities(q.reshape(-1, q.shape[-1]), flat_x)
        if mech.mass_coordinates == "task" and mech.has_orientation:
            jv, jw, g = twist_columns(mech, flat_x, (jv, jw, g))
    return masses, tensors, jv, jw, rot, g, batch


def twist_columns(mech, x: FloatArray, columns_per_rate):
    """Component-first columns per pose-coordinate rate ``(..., d, N)`` taken to columns per twist: ``C T^-1``.

    ``T = coordinate_rates_to_twist(x)`` (``xi = T xdot``): a velocity ``C xdot`` is ``C T^-1 xi``.
    Where every angle of ``x`` is 0, ``T = I`` and the columns are returned as they are (the
    maps' slices, at no cost); elsewhere ``T^-1`` by ``rotations.batched_inverse``.

    Parameters
    ----------
    mech : Mechanism
        A task-placed model with orientation freedoms.
    x : ndarray, shape (N, m)
        Its poses.
    columns_per_rate : tuple
        Arrays (..., m, N) or lists of them (``None`` passes through).

    Returns
    -------
    tuple
        The same structure, per twist.
    """
    from .rotations import batched_inverse
    angles = [i for i, unit in enumerate(mech.task_units) if unit == "rad"]
    turned = np.flatnonzero(np.any(x[:, angles] != 0, axis=-1))
    if not len(turned):
        return columns_per_rate
    inv, _ = batched_inverse(mech.coordinate_rates_to_twist(x[turned]))            # (k, m, m)
    inv = np.moveaxis(inv, 0, -1)                                                    # (m, m, k)

    def convert(c):
        if c is None:
            return None
        if isinstance(c, (list, tuple)):
            return [convert(a) for a in c]
        out = np.array(c, float)
        out[..., turned] = np.einsum("...ak,abk->...bk", out[..., turned], inv)
        return out

    return tuple(convert(c) for c in columns_per_rate)


def _batch_first(values: FloatArray, batch: tuple[int, ...]) -> FloatArray:
    """Component-first (..., N) -> batch-first ``batch + (...)``."""
    return np.moveaxis(values, -1, 0).reshape(batch + values.shape[:-1])


def kinetic_form(mech, q: ArrayLike, x: ArrayLike, *, rotors: bool = True) -> FloatArray:
    """The kinetic energy's matrix in ``mass_coordinates``: ``M(q)`` (..., n, n) or ``Lambda(x)`` (..., m, m).

    From the model's exact body velocity Jacobians (``body_velocities``).

    Parameters
    ----------
    mech : Mechanism
        With ``has_mass_model``.
    q : array_like, shape (..., n)
    x : array_like, shape (..., m)
        A consistent pose (``x = forward(q)``); ``nan`` rows give ``nan``.
    rotors : bool
        Include the rotors' reflected inertia (default); ``False`` gives the links alone.

    Returns
    -------
    ndarray
        Symmetric; kg, kg m and kg m^2 entries by the coordinates' units.
    """
    q, x = np.asarray(q, float), np.asarray(x, float)
    batch = np.broadcast_shapes(q.shape[:-1], x.shape[:-1])
    q = np.broadcast_to(q, batch + q.shape[-1:]).reshape(-1, q.shape[-1])
    x = np.broadcast_to(x, batch + x.shape[-1:]).reshape(-1, x.shape[-1])
    r = mech.reflected_rotor_inertias() if rotors else None
    blocks = []
    # Blocks of KINETIC_BLOCK poses: the per-body temporaries (3, d, block) stay in cache instead
    # of streaming fresh megabytes through memory for every product.
    for lo in range(0, max(len(q), 1), KINETIC_BLOCK):
        masses, tensors, jv, jw, rot, g, _ = _velocities(mech, q[lo:lo + KINETIC_BLOCK], x[lo:lo + KINETIC_BLOCK])
        form = kinetic_columns(masses, tensors, jv, jw, rot)
        if r is not None:
            if g is None:
                form += np.diag(r)[..., None]
            else:
                with np.errstate(invalid="ignore", over="ignore"):      # an unbounded rotor (ratio 1e300): inf
                    form += np.einsum("uan,u,ubn->abn", g, r, g)
        blocks.append(form)
    form = blocks[0] if len(blocks) == 1 else np.concatenate(blocks, axis=-1)
    return _batch_first(form, batch)


def centre_jacobians(mech, q: ArrayLike, x: ArrayLike) -> FloatArray:
    """``dc_b/dq`` (..., k, 3, n): how each centre of mass moves with the actuated joints.

    Joint coordinates: the model's ``body_velocities``. Task coordinates: ``dc_b/dx J`` (square ``J``).
    """
    q, x = np.asarray(q, float), np.asarray(x, float)
    _, _, jv, _, _, _, batch = _velocities(mech, q, x)
    jv = _batch_first(np.stack(jv), batch)
    if mech.mass_coordinates == "task":
        jv = np.einsum("...kim,...mn->...kin", jv, mech.jacobian(q, x))
    return jv


def task_gravity_force(mech, q: ArrayLike, x: ArrayLike, gravity: ArrayLike) -> FloatArray:
    """``w = -sum_b m_b (dc_b/dxi)^T g`` (..., m): the wrench a hand holds to keep the handle still.

    N for a length coordinate, N m for an angle; per twist ``xi`` (``T^-T grad_x V`` for a device
    with orientation coordinates, ``coordinate_rates_to_twist``). Task coordinates from
    ``body_velocities`` directly; joint coordinates through ``J^-T`` applied to the gravity torque
    (``force_map``).
    """
    from .gravity import check_gravity
    g = np.asarray(check_gravity(gravity))
    q, x = np.asarray(q, float), np.asarray(x, float)
    masses, _, jv, _, _, _, batch = _velocities(mech, q, x)
    generalised = _batch_first(-sum(m * np.einsum("ian,i->an", v, g) for m, v in zip(masses, jv)), batch)
    if mech.mass_coordinates == "task":
        return generalised
    return np.einsum("...mn,...n->...m", mech.force_map(q, x), generalised)
