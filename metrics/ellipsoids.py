"""Force and velocity manipulability ellipsoids.

With ``B = diag(1/t) J^T`` the force ellipsoid is ``{f : |B f| <= 1}``: the forces whose
torques lie in the unit ball of torque limits ``t``. Its semi-axes are the left singular
vectors of ``J diag(1/t)`` and its radii ``1 / sigma``. The velocity ellipsoid
``{J qdot : |diag(1/qdot_max) qdot| <= 1}`` has the same axes for ``J diag(qdot_max)`` and
radii ``sigma``.

Rank. A singular value at rounding level, ``sigma <= max(m, n) eps sigma_max`` (the level at
which ``condition_number`` calls J singular), is taken as 0: the force radius along it is
``inf`` (the structure holds that direction without torque) and the velocity radius 0,
never ``1 / rounding noise``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray
from kinematics.validation import validate_actuator_limits

from .linalg import as_jacobian, singular_values
from .torque_box import TorqueSet


@dataclass(frozen=True)
class Ellipsoid:
    """Semi-axis lengths ``radii`` (..., m), descending, and unit axes as columns of ``axes`` (..., m, m)."""

    radii: FloatArray
    axes: FloatArray


def actuator_limits(name: str, limits: ArrayLike, n: int) -> FloatArray:
    """``kinematics.validation.validate_actuator_limits(limits, name=name, n=n)``, shape (..., n).

    Parameters
    ----------
    name : str
        The argument's name for the message.
    limits : array_like, shape (..., n)
        Positive finite limit of each actuator (torque in N m or N, speed in rad/s or m/s).
    n : int
        The number of actuators (columns of J).

    Returns
    -------
    ndarray, shape (..., n)
    """
    return validate_actuator_limits(limits, name=name, n=n)


def rated_limits(torque_limits: ArrayLike | TorqueSet, n: int) -> FloatArray:
    """The limits ``t`` (..., n) an ellipsoid is of: a ``TorqueSet``'s as they are (unbiased:
    an ellipsoid about the origin cannot stand for a shifted set), plain ones validated.

    Parameters
    ----------
    torque_limits : array_like, shape (..., n), or TorqueSet
        Joint torque limits, N m.
    n : int
        The number of actuators (columns of J).

    Returns
    -------
    ndarray, shape (..., n)
    """
    if isinstance(torque_limits, TorqueSet):
        return torque_limits.limits
    return actuator_limits("torque_limits", torque_limits, n)


def rounding_rank_values(s: FloatArray, shape: tuple[int, int]) -> FloatArray:
    """Singular values ``s`` (..., k), descending, with those ``<= max(m, n) eps sigma_max`` set to 0.

    Parameters
    ----------
    s : ndarray, shape (..., k)
        Singular values, descending.
    shape : tuple of int
        ``(m, n)``, the shape of the matrices they belong to.

    Returns
    -------
    ndarray, shape (..., k)

    Examples
    --------
    >>> rounding_rank_values(np.array([1.0, 1e-17]), (2, 2)).tolist()
    [1.0, 0.0]
    """
    tol = max(shape) * np.finfo(float).eps
    with np.errstate(invalid="ignore", over="ignore"):
        negligible = s <= tol * s[..., :1]
    return np.where(negligible & np.isfinite(s[..., :1]), 0.0, s)


def _left_svd(mat: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Left singular vectors (..., m, m) and values (..., m), for m <= n; nan where not finite.

    Values at rounding level relative to the largest are 0 (``rounding_rank_values``).
    """
    finite = np.all(np.isfinite(mat), axis=(-2, -1))
    safe = np.where(finite[..., None, None], mat, 0.0)
    u, s, _ = np.linalg.svd(safe, full_matrices=True)
    m = mat.shape[-2]
    s_full = np.zeros(mat.shape[:-1])
    s_full[..., : s.shape[-1]] = rounding_rank_values(s, mat.shape[-2:])
    u = u[..., :, :m]
    s_full[~finite] = np.nan
    u[~finite] = np.nan
    return u, s_full


def force_ellipsoid(jac: ArrayLike, *, torque_limits: ArrayLike | TorqueSet) -> Ellipsoid:
    """Force ellipsoid of ``(..., m, n)`` Jacobians with joint torque limits ``(..., n)``.

    Radii ``1 / sigma_i(J diag(1/t))`` in N (``inf`` along a direction the structure holds
    without torque), ordered largest first.

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
        Jacobians, ``m <= n``.
    torque_limits : array_like, shape (..., n), or TorqueSet
        Joint torque limits ``t``, N m; a ``TorqueSet``'s ``limits`` as they are.

    Returns
    -------
    Ellipsoid
        ``radii`` (..., m) in N, largest first; ``axes`` (..., m, m), unit columns.

    Examples
    --------
    >>> e = force_ellipsoid([[0.5, 0.0], [0.0, 0.25]], torque_limits=[1.0, 1.0])
    >>> e.radii.round(12).tolist(), e.axes.shape
    ([4.0, 2.0], (2, 2))
    """
    jac = as_jacobian(jac)
    t = rated_limits(torque_limits, jac.shape[-1])
    u, s = _left_svd(jac / t[..., None, :])
    with np.errstate(divide="ignore", over="ignore"):
        radii = 1.0 / s
    return Ellipsoid(radii=radii[..., ::-1], axes=u[..., :, ::-1])


def force_ellipsoid_min_radius(jac: ArrayLike, *, torque_limits: ArrayLike | TorqueSet) -> FloatArray:
    """Smallest force-ellipsoid radius ``1 / sigma_max(J diag(1/t))`` in N, shape ``(...)``.

    Cheap (no singular vectors); the ball of this radius lies inside the force polytope.

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
        Jacobians.
    torque_limits : array_like, shape (..., n), or TorqueSet
        Joint torque limits ``t``, N m; a ``TorqueSet``'s ``limits`` as they are.

    Returns
    -------
    ndarray, shape (...)
        N.

    Examples
    --------
    >>> force_ellipsoid_min_radius([[0.5, 0.0], [0.0, 0.25]], torque_limits=[1.0, 1.0]).tolist()
    2.0
    """
    jac = as_jacobian(jac)
    t = rated_limits(torque_limits, jac.shape[-1])
    s = singular_values(jac / t[..., None, :])
    with np.errstate(divide="ignore", over="ignore"):
        return 1.0 / s[..., 0]


def velocity_ellipsoid(jac: ArrayLike, *, joint_speed_limits: ArrayLike) -> Ellipsoid:
    """Velocity ellipsoid: radii ``sigma_i(J diag(qdot_max))`` (m/s), descending, and axes.

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
        Jacobians, ``m <= n``, m/rad.
    joint_speed_limits : array_like, shape (..., n)
        Joint speed limits ``qdot_max``, rad/s.

    Returns
    -------
    Ellipsoid
        ``radii`` (..., m) in m/s, descending; ``axes`` (..., m, m), unit columns.

    Examples
    --------
    >>> e = velocity_ellipsoid([[0.5, 0.0], [0.0, 0.25]], joint_speed_limits=[2.0, 2.0])
    >>> e.radii.round(12).tolist()
    [1.0, 0.5]
    """
    jac = as_jacobian(jac)
    v = actuator_limits("joint_speed_limits", joint_speed_limits, jac.shape[-1])
    u, s = _left_svd(jac * v[..., None, :])
    return Ellipsoid(radii=s, axes=u)
