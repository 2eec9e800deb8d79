"""Spatial resolution: how far the end-effector moves for one encoder step on one joint.

With ``J`` the velocity Jacobian (``xdot = J qdot``) and ``delta_u`` joint u's step (rad, or m
for a prismatic joint: one encoder count through the joint's transmission), one step on
joint u alone moves the end-effector by ``J[:, u] delta_u`` to first order. The device's
spatial resolution is the largest such move, ``max_u |J[:, u]| delta_u``, and its
resolution along task axis i is ``max_u |J[i, u]| delta_u`` (paper 000, Table 2's
resolution column; paper 001, Table X's "Spatial Res"). A pen or platform mechanism's
rotation rows (rad) are kept apart from its position rows (m): the overall figure is taken
over the position rows only, never a norm mixing metres with radians.

Where actuation is redundant (``n > m``) one joint cannot step alone; ``J = K^+`` maps a
single-joint step to the least-squares end-effector move, which is what these functions
then report (the mechanism's ``jacobian`` says so).
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

from .linalg import as_jacobian


def joint_steps(counts: ArrayLike, gear_ratios: ArrayLike | None = None) -> FloatArray:
    """Joint-side step ``2 pi / (counts_u * gear_u)`` of motor-side rotary encoders, shape (n,), rad.

    Parameters
    ----------
    counts : array_like, shape (n,)
        Encoder counts per motor revolution (after quadrature decoding), positive.
    gear_ratios : array_like, shape (n,), optional
        Joint / motor transmission ratio; default 1 (an encoder on the joint itself).

    Returns
    -------
    ndarray, shape (n,)
        rad.

    Examples
    --------
    >>> joint_steps([4000.0]).round(9).tolist()
    [0.001570796]
    """
    c = np.asarray(counts, dtype=float)
    g = np.ones_like(c) if gear_ratios is None else np.asarray(gear_ratios, dtype=float)
    if c.ndim != 1 or not np.all(np.isfinite(c) & (c > 0)):
        raise ValueError(f"encoder counts must be positive and finite, one per joint, got {c.tolist()}")
    if g.shape != c.shape or not np.all(np.isfinite(g) & (g > 0)):
        raise ValueError(f"gear_ratios must be positive and finite, one per joint, got {g.tolist()}")
    return 2.0 * np.pi / (c * g)


def axis_resolution(jac: ArrayLike, steps: ArrayLike) -> FloatArray:
    """Resolution along each task axis, ``max_u |J[i, u]| delta_u``, shape (..., m).

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
        Velocity Jacobians, SI (m/rad, or rad/rad for a rotation row).
    steps : array_like, shape (n,) or (..., n)
        Joint steps ``delta_u`` (rad, or m for a prismatic joint), positive.

    Returns
    -------
    ndarray, shape (..., m)
        m for a position row, rad for a rotation row; ``inf`` where J is (an inverse singularity).

    Examples
    --------
    >>> axis_resolution([[0.1, 0.0], [0.05, 0.2]], [0.01, 0.001]).tolist()
    [0.001, 0.0005]
    """
    a = as_jacobian(jac)
    d = np.asarray(steps, dtype=float)
    if d.shape[-1] != a.shape[-1]:
        raise ValueError(f"steps must have one entry per joint ({a.shape[-1]}), got shape {d.shape}")
    return np.max(np.abs(a) * d[..., None, :], axis=-1)


def spatial_resolution(jac: ArrayLike, steps: ArrayLike, rows=None) -> FloatArray:
    """Largest end-effector move from one step on one joint, ``max_u |J[rows, u]| delta_u``, shape (...).

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
        Velocity Jacobians, SI.
    steps : array_like, shape (n,) or (..., n)
        Joint steps, rad (m for a prismatic joint).
    rows : sequence of int, optional
        Task rows of one unit (the position rows of a pen mechanism); default all.

    Returns
    -------
    ndarray, shape (...)
        In the unit of ``rows`` (m for position rows).

    Examples
    --------
    >>> round(float(spatial_resolution([[0.3, 0.0], [0.4, 0.1]], [0.01, 0.01])), 6)
    0.005
    """
    a = as_jacobian(jac)
    d = np.asarray(steps, dtype=float)
    if d.shape[-1] != a.shape[-1]:
        raise ValueError(f"steps must have one entry per joint ({a.shape[-1]}), got shape {d.shape}")
    if d.ndim == 1 and a.ndim > 2:
        return _batched_resolution(a, d, range(a.shape[-2]) if rows is None else list(rows))
    if rows is not None:
        a = a[..., list(rows), :]
    return np.max(np.sqrt(np.sum(a * a, axis=-2)) * d, axis=-1)


def _batched_resolution(a: FloatArray, d: FloatArray, rows) -> FloatArray:
    """``spatial_resolution`` of a batch ``a`` (..., m, n) and one ``d`` (n,): the same operations, the same bits.

    ``np.sum`` over the rows adds them in order, ``((a_0^2 + a_1^2) + a_2^2)`` per column (a pairwise
    sum only along a contiguous axis of 8 or more), and a maximum is exact, so summing row views in
    place and taking the columns' ``np.maximum`` in turn gives the same numbers (``nan`` where any is).
    It avoids the rows' fancy-indexed copy and ``np.max`` over an axis of n entries, which numpy reduces
    point by point: with it the Twin-Pantograph map's spatial and angular resolutions took 43 of its
    738 ms of graph time (101,344 points, one thread, load 2.5), numpy's reduction most of it.
    """
    first, *rest = rows
    sq = a[..., first, :] * a[..., first, :]
    for i in rest:
        sq += a[..., i, :] * a[..., i, :]
    np.sqrt(sq, out=sq)
    sq *= d
    out = sq[..., 0].copy()
    for u in range(1, sq.shape[-1]):
        np.maximum(out, sq[..., u], out=out)
    lost = np.isnan(out)
    if lost.any():
        out[lost] = np.nan          # np.max's nan (positive) where a J not finite gave the rows' own (negative)
    return out


def mechanism_steps(mechanism) -> FloatArray | None:
    """Joint sensor steps of a mechanism, SI (rad, m for a prismatic joint), shape (n,), or None.

    From its ``joint_resolution`` parameter (one entry per actuated joint, held in SI) where
    the model has one; None where it has none or says its sensors are not modelled
    (``joint_sensors = "none"``).

    Parameters
    ----------
    mechanism : Mechanism

    Returns
    -------
    ndarray, shape (n,), or None

    Examples
    --------
    >>> from kinematics.fivebar import FiveBar
    >>> mechanism_steps(FiveBar()) is None
    True
    """
    steps = getattr(mechanism.params, "joint_resolution", None)
    if steps is None or getattr(mechanism.params, "joint_sensors", "given") == "none":
        return None
    steps = np.asarray(steps, dtype=float)
    return steps if steps.shape == (mechanism.n_joints,) else steps[list(mechanism.actuated)]
