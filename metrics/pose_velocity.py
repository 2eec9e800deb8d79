"""The velocity polytope at one pose from the model's joint speed limits (``Mechanism.joint_speed_limits``).

The pose counterpart of the map quantities ``isotropic_velocity`` and ``peak_velocity``: the same
graph (``metrics.quantities.evaluate``) at one point, so a pose and a map agree, plus the
polytope's vertices (``metrics.velocity``):

- a square model without orientation freedoms: pycapacity's ``velocity_polytope``, the images
  ``J c`` of the speed box's corners ``c`` (a parallelepiped: every corner a vertex);
- a device with orientation freedoms (or redundant actuation): the joints turn at ``qdot = K v``,
  so the set is ``{v : |K v| <= qdot_max}``; its slice at zero angular velocity (the handle
  translating), whose vertices are where the slabs of the length rows meet
  (``wrench_facets.slab_slice_vertices``).
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .quantities import evaluate
from .quantity_nodes import speed_limits_of
from .torque_box import sign_patterns
from .velocity import PoseVelocity, velocity_polytope_vertices
from .wrench_facets import slab_slice_vertices
from .wrenches import force_rows


def analyse_pose_velocity(mechanism, x: ArrayLike) -> PoseVelocity:
    """The velocity polytope, isotropic and peak velocities at task point ``x`` (m,), SI.

    Parameters
    ----------
    mechanism : Mechanism
        With its motor speeds given (``joint_speed_limits`` not None).
    x : array_like, shape (m,)
        A feasible pose, m and rad.

    Returns
    -------
    PoseVelocity
        ``vertices`` over the length rows ``rows`` (m/s); ``isotropic_velocity`` and
        ``peak_velocity`` as the map's ``isotropic_velocity`` and ``peak_velocity``.

    Raises
    ------
    ValueError
        Without motor speeds (the reason), or at a pose outside the workspace.

    Examples
    --------
    >>> from kinematics.fivebar import FiveBar
    >>> mech = FiveBar().replace(motor_speeds=(10.0, 10.0))
    >>> v = analyse_pose_velocity(mech, [0.0, 0.2])
    >>> v.vertices.shape, v.peak_velocity.shape
    ((4, 2), (2,))
    """
    speeds = speed_limits_of(mechanism)
    x = np.asarray(x, float)
    ev = evaluate(mechanism, x[None], ("isotropic_velocity", "peak_velocity"))
    if not ev.feasible[0]:
        raise ValueError(f"x = {x.tolist()} is outside the workspace of {type(mechanism).__name__}")
    q = ev.joints[0]
    rows = force_rows(mechanism)
    if mechanism.has_orientation or mechanism.is_redundant:
        k = np.swapaxes(mechanism.force_map(q[None], x[None])[0], -1, -2)         # (n, m): qdot = K v
        verts = slab_slice_vertices(k, -speeds, speeds, rows=rows)
        rates = verts @ k[:, list(rows)].T / speeds                                # qdot / qdot_max
        signs = np.where(np.abs(rates) >= 1 - 1e-9, np.sign(rates), 0.0)
    else:
        jac = mechanism.jacobian(q[None], x[None])[0]
        verts = velocity_polytope_vertices(jac, joint_speed_limits=speeds)
        signs = sign_patterns(jac.shape[-1])
    return PoseVelocity(joint_speed_limits=np.asarray(speeds, float), vertices=verts, signs=signs,
                        isotropic_velocity=float(ev.values["isotropic_velocity"][0]), rows=tuple(rows),
                        peak_velocity=np.asarray(ev.values["peak_velocity"][0], float))
