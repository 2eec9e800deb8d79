"""Shared pieces of the closed chains' mass models: parameter checks, ParamInfo rows, link frames.

The closed chains (five-bar, Inverse3, delta, Stewart, Twin-Pantograph, Inoue) place their bodies
from the task pose ``x`` through their closed-form inverse kinematics (``mass_coordinates =
"task"``, ``kinematics.dynamics``). Their links are mostly slender: a uniform rod
(``kinematics.bodies.rod``) along the body frame's x axis from one joint to the next, its inertia
derived from its mass and length. ``link_frames`` builds such a frame from the two joint points and
a direction the frame's x-y plane contains the normal of (a planar link: the plane's normal).

``mass_model`` is ``"estimated"`` (masses from dimensions and a material's density, marked so in
the preset), ``"given"`` (the device's own numbers) or ``"none"`` (no mass model: dynamic quantities
are refused with the reason).
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .arrays import FloatArray
from .base import ParamInfo
from .bodies import check_body
from .validation import choice, nonnegative_vector, positive_finite, positive_vector

MASS_MODELS = ("estimated", "given", "none")
#: Labels of a principal-moments parameter, ``(Ixx, Iyy, Izz)`` about the centre of mass in body axes
#: (the body axes are its principal axes), kg m^2.
MOMENTS = ("xx", "yy", "zz")
#: Display scale of inertias: g cm^2 -> kg m^2.
G_CM2 = 1e-7


def check_mass_params(params, links: tuple[str, ...], actuators: tuple[str, ...], *,
                      scalars: tuple[str, ...] = (), moments: tuple[str, ...] = ()) -> None:
    """Validate and normalise a frozen params object's mass fields in place (errors name the field).

    ``link_masses`` (one positive kg per link), ``rotor_inertias`` (one >= 0 kg m^2 per actuator),
    each of ``scalars`` a positive kg, each of ``moments`` three principal moments >= 0 (kg m^2)
    obeying the triangle inequality, and ``mass_model`` one of ``MASS_MODELS``.
    """
    set_ = object.__setattr__
    set_(params, "link_masses", positive_vector("link_masses", params.link_masses, links, "kg"))
    set_(params, "rotor_inertias", nonnegative_vector("rotor_inertias", params.rotor_inertias, actuators, "kg m^2"))
    for name in scalars:
        set_(params, name, positive_finite(name, getattr(params, name), "kg"))
    for name in moments:
        value = nonnegative_vector(name, getattr(params, name), MOMENTS, "kg m^2")
        check_body(name, 1.0, (0.0, 0.0, 0.0), (*value, 0.0, 0.0, 0.0), key=name)
        set_(params, name, value)
    choice("mass_model", params.mass_model, MASS_MODELS)


def mass_param_info(links: tuple[str, ...], link_text: str, actuators: tuple[str, ...]) -> tuple[ParamInfo, ...]:
    """ParamInfo rows for ``link_masses``, ``rotor_inertias`` and ``mass_model``."""
    return (
        ParamInfo("link_masses", "kg", 1.0, f"Body masses ({link_text})", links),
        ParamInfo("rotor_inertias", "g cm^2", G_CM2, "Motor rotor inertia (motor side; felt at the joint "
                  "times the gear ratio squared)", actuators),
        ParamInfo("mass_model", "", 1.0, "Body masses are estimated, the device's (given), or there is no "
                  "mass model (none)", choices=MASS_MODELS),
    )


def link_frames(a: ArrayLike, b: ArrayLike, normal: ArrayLike) -> FloatArray:
    """Rotations (..., 3, 3) whose x axis runs from ``a`` to ``b`` and whose z axis is ``normal``'s
    part across the link (columns are the body axes in the base frame).

    ``y = normal x e_x / |.|``, ``z = e_x x y``. Smooth in ``a``, ``b`` wherever the link is not along
    ``normal``; for a planar link ``normal`` is the plane's normal and ``z`` equals it.

    Examples
    --------
    >>> (link_frames([0, 0, 0], [0, 2, 0], [0, 0, 1]).round(12) + 0.0).tolist()    # + 0.0: no -0.0
    [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    """
    a, b, n = (np.asarray(v, float) for v in (a, b, normal))
    ex = b - a
    ex = ex / np.linalg.norm(ex, axis=-1, keepdims=True)
    n = np.broadcast_to(n, ex.shape)
    ey = np.cross(n, ex)
    ey = ey / np.linalg.norm(ey, axis=-1, keepdims=True)
    ez = np.cross(ex, ey)
    return np.stack([ex, ey, ez], axis=-1)


def translating(shape: tuple[int, ...]) -> FloatArray:
    """Identity rotations of shape ``shape + (3, 3)`` (a body that only translates)."""
    return np.broadcast_to(np.eye(3), tuple(shape) + (3, 3)).copy()


def planar(points: FloatArray) -> FloatArray:
    """2-D points (..., 2) as 3-D points (..., 3) in the plane z = 0."""
    points = np.asarray(points, float)
    return np.concatenate([points, np.zeros(points.shape[:-1] + (1,))], axis=-1)
