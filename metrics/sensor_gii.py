"""The sensor (velocity) Global Isotropy Index of paper 001, eqs. 23-27.

A haptic device's joint sensors (resolution ``r_u`` per joint) resolve the hand's motion, whose
speeds ``v`` (m/s, rad/s) are alike in every direction; the index rates how evenly the joint
rates ``qdot = K xdot`` (``K``: the velocity map, n x m) see those motions across the workspace,
on ``metrics.gii``'s scaling core: singular values of ``diag(1/r) K diag(v)``, reduced to the
ratio of their workspace extremes.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

from .gii import GIIResult, feasible_mask, reduce_extremes, scale_vector, scaled_matrix, scaled_singular_values
from .linalg import as_jacobian


def velocity_scaled_matrix(vel_map: ArrayLike, resolutions: ArrayLike, velocities: ArrayLike) -> FloatArray:
    """The sensor GII's matrix ``S_J K S_T`` (paper 001 eqs. 23, 26, 27), shape (..., n, m).

    Parameters
    ----------
    vel_map : array_like, shape (..., n, m)
        ``K`` with ``qdot = K xi`` (eq. 23; ``force_map`` transposed), rad/m on translation
        columns, rad/rad on rotation columns.
    resolutions : array_like, shape (..., n)
        Each joint's position-sensor resolution (counts per joint radian) or their ratios
        (eq. 26); normalised by the first here.
    velocities : array_like, shape (..., m)
        The hand's velocity capabilities per task direction, SI (m/s, rad/s; eq. 27, e.g.
        ``HUMAN_HAND_VELOCITIES``); normalised by the first here, so rotation entries are in 1/m.

    Returns
    -------
    ndarray, shape (..., n, m)
        ``diag(R / R_1) K diag(v / v_1)``: normalised joint count rates per normalised hand
        velocity, every entry in 1/m (see the module doc).

    Examples
    --------
    >>> velocity_scaled_matrix(np.eye(2), (1.0, 2.0), (1.0, 3.0)).tolist()
    [[1.0, 0.0], [0.0, 6.0]]
    """
    k = as_jacobian(vel_map, "vel_map")
    n, m = k.shape[-2:]
    scale_vector("resolutions", resolutions, n, f"the {n} joint rows of vel_map")
    v = scale_vector("velocities", velocities, m, f"the {m} task columns of vel_map")
    # M^T = S_T A S_J with A = K^T: scaled_matrix's force-map form with task factors 1/v.
    return np.swapaxes(scaled_matrix(np.swapaxes(k, -1, -2), resolutions, 1.0 / v, kind="force_map"), -1, -2)


def velocity_singular_values(vel_map: ArrayLike, resolutions: ArrayLike, velocities: ArrayLike) -> FloatArray:
    """Singular values of ``velocity_scaled_matrix``, descending, shape (..., m).

    Always ``m`` values (task dimension): with fewer joints than task directions (n < m) the
    missing ones are 0 (a hand motion no sensor sees). ``inf`` where ``K`` has a non-finite
    entry (an inverse singularity: a joint rate without bound).

    Parameters
    ----------
    vel_map : array_like, shape (..., n, m)
        ``K`` (eq. 23).
    resolutions : array_like, shape (..., n)
        Sensor resolutions or ratios (eq. 26).
    velocities : array_like, shape (..., m)
        Hand velocity capabilities, SI (eq. 27).

    Returns
    -------
    ndarray, shape (..., m)
        Descending, in 1/m.

    Examples
    --------
    >>> K = np.array([[1.0, 0.0], [0.0, 2.0], [0.0, 0.0]])     # 3 joints, 2 task directions
    >>> velocity_singular_values(K, (1.0, 1.0, 1.0), (1.0, 2.0)).round(6).tolist()
    [4.0, 1.0]
    """
    k = as_jacobian(vel_map, "vel_map")
    n, m = k.shape[-2:]
    scale_vector("resolutions", resolutions, n, f"the {n} joint rows of vel_map")
    v = scale_vector("velocities", velocities, m, f"the {m} task columns of vel_map")
    return scaled_singular_values(np.swapaxes(k, -1, -2), resolutions, 1.0 / v, kind="force_map")


def velocity_gii(vel_maps: ArrayLike, resolutions: ArrayLike, velocities: ArrayLike,
                 feasible: ArrayLike | None = None) -> GIIResult:
    """The sensor-resolution (velocity) GII over a workspace (paper 001 eqs. 11, 23-27).

    Parameters
    ----------
    vel_maps : array_like, shape (..., n, m)
        One ``K`` per workspace sample (every batch axis is the workspace).
    resolutions : array_like, shape (n,)
        Sensor resolutions or ratios (eq. 26).
    velocities : array_like, shape (m,)
        Hand velocity capabilities, SI (eq. 27).
    feasible : array_like of bool, shape (...), optional
        Samples to use; the others are neither computed nor counted.

    Returns
    -------
    GIIResult
        ``kind="velocity_map"``; ``value`` in [0, 1] (``nan`` with no feasible sample).

    Examples
    --------
    >>> K = np.stack([np.eye(2), np.diag([1.0, 4.0])])
    >>> r = velocity_gii(K, (1.0, 1.0), (1.0, 1.0))
    >>> round(r.value, 6), r.weakest, r.strongest
    (0.25, (0,), (1,))
    """
    k = as_jacobian(vel_maps, "vel_maps")
    n, m = k.shape[-2:]
    for name, vec, size in (("resolutions", resolutions, n), ("velocities", velocities, m)):
        if np.ndim(vec) != 1:
            raise ValueError(f"{name} must have shape ({size},) for a GII over one workspace, got {np.shape(vec)}")
    batch = k.shape[:-2]
    idx = np.flatnonzero(feasible_mask(feasible, batch))
    sv = velocity_singular_values(k.reshape((-1, n, m))[idx], resolutions, velocities)
    return reduce_extremes(sv[:, -1], sv[:, 0], idx, batch, "velocity_map")
