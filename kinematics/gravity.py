"""Gravity on a device's links: mounting orientations, potential energy, gravity torque.

A model with a mass model (``Mechanism.has_mass_model``) gives its body masses ``m_i`` (k,)
and the centres of mass ``p_i(q)`` (..., k, 3) in its base frame, with their Jacobians
``dp_i/dq`` (..., k, 3, n). With gravity ``g`` (3,), m/s^2, in the base frame the potential
energy is ``V(q) = -sum_i m_i g . p_i(q)`` (J, up to a constant) and the torque the joints
spend holding the links still is its gradient,

    tau_g(q) = dV/dq = -sum_i m_i (dp_i/dq)^T g        (N m, or N for a prismatic joint),

the ``G(q)`` of the equations of motion ``tau = M qdd + C qd + G``. It is the bias of the
force set: the motors have ``[t_min - tau_g, t_max - tau_g]`` left for the user.

Which way is down depends on how the device is mounted (paper 000 notes that the Inverse3
can be mounted any way up). ``MOUNTINGS`` names the usual ones by the base-frame axis that
points up; any other is a vector ``g`` in the base frame.
"""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from .arrays import FloatArray

#: Standard gravity, m/s^2 (CGPM 1901; also mahilab/Phantom ``PhantomModel.hpp`` ``g``).
STANDARD_GRAVITY = 9.80665

#: Mounting orientation -> the base-frame unit vector that points up; gravity is ``-g up``.
#: ``upright``: base on a table, the frame's z axis up (every shipped preset's frame is drawn
#: so); ``inverted``: hung from the ceiling; ``x-up`` ... ``y-down``: on a wall, the named
#: base axis pointing up or down.
MOUNTINGS: dict[str, tuple[float, float, float]] = {
    "upright": (0.0, 0.0, 1.0),
    "inverted": (0.0, 0.0, -1.0),
    "x-up": (1.0, 0.0, 0.0),
    "x-down": (-1.0, 0.0, 0.0),
    "y-up": (0.0, 1.0, 0.0),
    "y-down": (0.0, -1.0, 0.0),
}


def gravity_vector(mounting: str, *, g: float = STANDARD_GRAVITY) -> tuple[float, float, float]:
    """Gravity in the base frame, m/s^2, for a named mounting orientation (``MOUNTINGS``).

    Parameters
    ----------
    mounting : str
        One of ``MOUNTINGS``.
    g : float
        Magnitude, m/s^2; default ``STANDARD_GRAVITY``.

    Returns
    -------
    tuple of 3 float
        m/s^2.

    Raises
    ------
    ValueError
        Naming ``mounting`` and the choices.

    Examples
    --------
    >>> gravity_vector("upright")
    (0.0, 0.0, -9.80665)
    >>> gravity_vector("x-down", g=1.0)
    (1.0, 0.0, 0.0)
    """
    if mounting not in MOUNTINGS:
        raise ValueError(f"mounting must be one of {', '.join(MOUNTINGS)}, got {mounting!r}")
    return tuple(-g * u + 0.0 for u in MOUNTINGS[mounting])  # + 0.0: no -0.0


def check_gravity(gravity: ArrayLike, name: str = "gravity") -> tuple[float, float, float]:
    """``gravity`` as three finite floats (m/s^2), or a ValueError naming ``name``.

    Parameters
    ----------
    gravity : array_like, shape (3,)
        Gravity in the base frame, m/s^2.
    name : str
        The argument's name for the message.

    Returns
    -------
    tuple of 3 float

    Examples
    --------
    >>> check_gravity([0, 0, -9.81])
    (0.0, 0.0, -9.81)
    """
    try:
        values = tuple(float(v) for v in np.asarray(gravity, dtype=float).reshape(-1))
    except (TypeError, ValueError):
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise ValueError(f"{name} must be 3 finite numbers (gx, gy, gz) in m/s^2 in the base frame, got {gravity!r}")
    return values


def potential_energy(masses: ArrayLike, centres: ArrayLike, gravity: ArrayLike) -> FloatArray:
    """``V = -sum_i m_i g . p_i`` (...), J: potential energy of bodies at ``centres`` (..., k, 3), m.

    Parameters
    ----------
    masses : array_like, shape (k,)
        Body masses, kg.
    centres : array_like, shape (..., k, 3)
        Centres of mass in the base frame, m.
    gravity : array_like, shape (3,)
        Gravity in the base frame, m/s^2.

    Returns
    -------
    ndarray, shape (...)
        J (zero at the base frame's origin).

    Examples
    --------
    >>> float(potential_energy([2.0], [[0.0, 0.0, 0.5]], [0.0, 0.0, -10.0]))
    10.0
    """
    g = np.asarray(check_gravity(gravity))
    weights = np.asarray(masses, float)[:, None] * g                       # (k, 3), N
    return -np.einsum("...kd,kd->...", np.asarray(centres, float), weights)


def gravity_torque(masses: ArrayLike, centre_jacobians: ArrayLike, gravity: ArrayLike) -> FloatArray:
    """``tau_g = -sum_i m_i (dp_i/dq)^T g`` (..., n): the joint torque holding the bodies still, N m.

    Parameters
    ----------
    masses : array_like, shape (k,)
        Body masses, kg.
    centre_jacobians : array_like, shape (..., k, 3, n)
        ``dp_i/dq``: how each centre of mass moves with the joints, m/rad (m/m for a prismatic joint).
    gravity : array_like, shape (3,)
        Gravity in the base frame, m/s^2.

    Returns
    -------
    ndarray, shape (..., n)
        N m (N for a prismatic joint).

    Examples
    --------
    >>> # A point mass of 1 kg at the end of a 0.5 m arm about the y axis, arm horizontal along x:
    >>> # dp/dq = (0, 0, -0.5) for a positive rotation about y: gravity pulls towards +q, so the
    >>> # joint spends -4.9 N m holding it (V = -4.9 sin q J).
    >>> gravity_torque([1.0], [[[0.0], [0.0], [-0.5]]], [0.0, 0.0, -9.8]).round(12).tolist()
    [-4.9]
    """
    g = np.asarray(check_gravity(gravity))
    weights = np.asarray(masses, float)[:, None] * g                       # (k, 3), N
    return -np.einsum("...kdn,kd->...n", np.asarray(centre_jacobians, float), weights)
