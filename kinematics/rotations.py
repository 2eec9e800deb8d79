"""Rotations and small helpers shared by the spatial mechanisms (Twin-Pantograph, Stewart).

Orientation coordinates are rotation vectors ``r = theta * k`` (axis-angle, ``R = exp([r]x)``),
in the base frame, as in paper 001's axis-angle workspace sampling (sec. IV): the tip angle
is ``|r|`` for a rotation about an axis perpendicular to the pen.

Angular velocity ``omega`` is always the *spatial* one, ``Rdot R^T = [omega]x`` (base frame).
Rates of the coordinates relate to it by the left Jacobian of SO(3)::

    omega = left_jacobian(r) @ rdot,
    J_l(r) = I + (1 - cos t) / t^2 [r]x + (t - sin t) / t^3 [r]x^2,    t = |r|.

Batch axes lead: vectors ``(..., 3)``, matrices ``(..., 3, 3)``. The ratios above are
evaluated with ``np.where`` over a Taylor series (small ``t``) and the closed form (the rest);
the closed form sees a dummy ``t = 1`` where the series is used, so no 0/0 is ever formed.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .arrays import BoolArray, FloatArray
from .validation import validate_angle_in

#: Below this angle (rad) the Taylor series are used; their truncation error is < t^6 ~ 1e-24.
_SMALL = 1e-4
_EY = np.array([0.0, 1.0, 0.0])


def skew(v: ArrayLike) -> FloatArray:
    """Cross-product matrix ``[v]x`` with ``[v]x @ w = v x w``, (..., 3) -> (..., 3, 3).

    Parameters
    ----------
    v : array_like, shape (..., 3)
        Vectors.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Antisymmetric matrices.

    Examples
    --------
    >>> skew([1.0, 2.0, 3.0]).tolist()
    [[0.0, -3.0, 2.0], [3.0, 0.0, -1.0], [-2.0, 1.0, 0.0]]
    >>> skew(np.zeros((4, 3))).shape
    (4, 3, 3)
    """
    v = np.asarray(v, dtype=np.float64)
    zero = np.zeros(v.shape[:-1])
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([np.stack([zero, -z, y], -1), np.stack([z, zero, -x], -1),
                     np.stack([-y, x, zero], -1)], -2)


def _ratios(theta: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``sin t / t``, ``(1 - cos t) / t^2``, ``(t - sin t) / t^3``, safe at ``t = 0``."""
    small = theta < _SMALL
    t = np.where(small, 1.0, theta)
    t2 = theta * theta
    a = np.where(small, 1.0 - t2 / 6.0 + t2 * t2 / 120.0, np.sin(t) / t)
    b = np.where(small, 0.5 - t2 / 24.0 + t2 * t2 / 720.0, (1.0 - np.cos(t)) / (t * t))
    c = np.where(small, 1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0, (t - np.sin(t)) / (t * t * t))
    return a, b, c


def rotation_matrix(rotvec: ArrayLike) -> FloatArray:
    """``exp([r]x)`` (Rodrigues), (..., 3) -> (..., 3, 3).

    Parameters
    ----------
    rotvec : array_like, shape (..., 3)
        Rotation vectors ``theta * k``, rad.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rotation matrices.

    Examples
    --------
    >>> quarter_turn = rotation_matrix([0.0, 0.0, np.pi / 2])
    >>> bool(np.allclose(quarter_turn, [[0, -1, 0], [1, 0, 0], [0, 0, 1]], rtol=0.0, atol=1e-15))
    True
    >>> rotation_matrix(np.zeros((4, 5, 3))).shape
    (4, 5, 3, 3)
    """
    r = np.asarray(rotvec, dtype=np.float64)
    theta = np.linalg.norm(r, axis=-1)
    a, b, _ = _ratios(theta)
    k = skew(r)
    eye = np.broadcast_to(np.eye(3), k.shape)
    return eye + a[..., None, None] * k + b[..., None, None] * (k @ k)


def left_jacobian(rotvec: ArrayLike) -> FloatArray:
    """``J_l(r)`` with ``omega = J_l(r) @ rdot`` (spatial angular velocity), (..., 3, 3).

    Parameters
    ----------
    rotvec : array_like, shape (..., 3)
        Rotation vectors, rad.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Examples
    --------
    >>> left_jacobian(np.zeros(3)).tolist()
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    """
    r = np.asarray(rotvec, dtype=np.float64)
    theta = np.linalg.norm(r, axis=-1)
    _, b, c = _ratios(theta)
    k = skew(r)
    eye = np.broadcast_to(np.eye(3), k.shape)
    return eye + b[..., None, None] * k + c[..., None, None] * (k @ k)


def pose_rates_to_twist(pose: ArrayLike) -> FloatArray:
    """``T = blockdiag(I, J_l(r))`` (..., 6, 6): the twist ``[v; omega]`` of the rates of ``(p, r)``.

    For a pose ``(x, y, z, rx, ry, rz)`` (a position and a rotation vector, base frame), ``xi = T xdot``;
    ``nan`` where the pose is not finite.

    Parameters
    ----------
    pose : array_like, shape (..., 6)
        m and rad.

    Returns
    -------
    ndarray, shape (..., 6, 6)

    Examples
    --------
    >>> bool(np.array_equal(pose_rates_to_twist(np.zeros(6)), np.eye(6)))
    True
    """
    x, finite = finite_rows(pose, np.zeros(6))
    t = np.zeros(x.shape[:-1] + (6, 6))
    t[..., :3, :3] = np.eye(3)
    t[..., 3:, 3:] = left_jacobian(x[..., 3:6])
    return np.where(finite[..., None, None], t, np.nan)


def rotation_vector(matrix: ArrayLike) -> FloatArray:
    """``log(R)`` as a rotation vector with ``|r| <= pi``, (..., 3, 3) -> (..., 3).

    Via the unit quaternion (Shepperd's method: the largest of ``w, x, y, z`` is computed from
    the diagonal, the others from off-diagonal sums, so no component loses precision), then
    ``r = 2 atan2(|v|, w) v / |v|`` with ``w >= 0``; near ``|v| = 0`` the ratio is ``2 / w``.

    Parameters
    ----------
    matrix : array_like, shape (..., 3, 3)
        Rotation matrices.

    Returns
    -------
    ndarray, shape (..., 3)
        Rotation vectors, rad, with ``|r| <= pi``.

    Examples
    --------
    >>> r = np.array([[0.1, -0.2, 0.3], [0.0, 0.0, 0.0]])
    >>> bool(np.allclose(rotation_vector(rotation_matrix(r)), r, rtol=0.0, atol=1e-12))
    True
    """
    m = np.asarray(matrix, dtype=np.float64)
    m00, m11, m22 = m[..., 0, 0], m[..., 1, 1], m[..., 2, 2]
    trace = m00 + m11 + m22
    # Four candidate quaternions (w, x, y, z), each exact when its leading term is largest.
    d = np.stack([1.0 + trace, 1.0 + 2.0 * m00 - trace, 1.0 + 2.0 * m11 - trace, 1.0 + 2.0 * m22 - trace], -1)
    choice = np.argmax(d, axis=-1)
    s = np.sqrt(np.maximum(np.take_along_axis(d, choice[..., None], -1)[..., 0], 1e-300))
    a21, a12 = m[..., 2, 1], m[..., 1, 2]
    a02, a20 = m[..., 0, 2], m[..., 2, 0]
    a10, a01 = m[..., 1, 0], m[..., 0, 1]
    cands = np.stack([
        np.stack([s * s, a21 - a12, a02 - a20, a10 - a01], -1),
        np.stack([a21 - a12, s * s, a01 + a10, a02 + a20], -1),
        np.stack([a02 - a20, a01 + a10, s * s, a12 + a21], -1),
        np.stack([a10 - a01, a02 + a20, a12 + a21, s * s], -1),
    ], -2)                                                   # (..., 4 candidates, 4)
    quat = np.take_along_axis(cands, choice[..., None, None], -2)[..., 0, :] / (2.0 * s[..., None])
    quat = np.where(quat[..., :1] < 0.0, -quat, quat)        # w >= 0: the angle is at most pi
    w, v = quat[..., 0], quat[..., 1:]
    vnorm = np.linalg.norm(v, axis=-1)
    small = vnorm < _SMALL
    angle = 2.0 * np.arctan2(vnorm, w)
    scale = np.where(small, 2.0 / np.where(w > 0, w, 1.0) * (1.0 - vnorm * vnorm / (3.0 * np.maximum(w * w, 1e-300))),
                     angle / np.where(small, 1.0, vnorm))
    return scale[..., None] * v


# -- tilts: the pen direction without roll -------------------------------------------------
def tilt_matrix(tilt: ArrayLike) -> FloatArray:
    """Rotation ``exp([rx, 0, rz]x)`` of a tilt ``(rx, rz)`` (..., 2) -> (..., 3, 3).

    A tilt is a rotation about an axis perpendicular to the home pen axis ``y``: the pen
    direction ``R e_y`` tips by ``|tilt|`` (paper 001's tip angle theta_1) towards the
    azimuth set by the axis (its theta_2). Every direction but ``-e_y`` has exactly one tilt.

    Parameters
    ----------
    tilt : array_like, shape (..., 2)
        ``(rx, rz)``, rad.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rotation matrices.
    """
    t = np.asarray(tilt, dtype=np.float64)
    zero = np.zeros(t.shape[:-1])
    return rotation_matrix(np.stack([t[..., 0], zero, t[..., 1]], -1))


def tilt_direction(tilt: ArrayLike) -> FloatArray:
    """Pen direction ``R e_y = (-rz sinc t, cos t, rx sinc t)`` of a tilt ``(rx, rz)``, (..., 3).

    Parameters
    ----------
    tilt : array_like, shape (..., 2)
        ``(rx, rz)``, rad.

    Returns
    -------
    ndarray, shape (..., 3)
        Unit pen directions.

    Examples
    --------
    >>> tilt_direction([0.0, 0.0]).tolist() == [0.0, 1.0, 0.0]
    True
    """
    t = np.asarray(tilt, dtype=np.float64)
    theta = np.hypot(t[..., 0], t[..., 1])
    a, _, _ = _ratios(theta)
    return np.stack([-t[..., 1] * a, np.cos(theta), t[..., 0] * a], -1)


def tilt_of_direction(direction: ArrayLike) -> FloatArray:
    """The tilt ``(rx, rz)`` (..., 2) whose pen direction is the unit vector ``direction`` (..., 3).

    ``theta = atan2(|e_y x p|, p_y)``, ``(rx, rz) = (p_z, -p_x) theta / sin theta``.

    Parameters
    ----------
    direction : array_like, shape (..., 3)
        Unit vectors (any but ``-e_y``).

    Returns
    -------
    ndarray, shape (..., 2)
        ``(rx, rz)``, rad.

    Examples
    --------
    >>> t = np.array([0.3, -0.2])
    >>> bool(np.allclose(tilt_of_direction(tilt_direction(t)), t, rtol=0.0, atol=1e-12))
    True
    """
    p = np.asarray(direction, dtype=np.float64)
    sin_t = np.hypot(p[..., 0], p[..., 2])
    theta = np.arctan2(sin_t, p[..., 1])
    a, _, _ = _ratios(theta)
    # theta / sin(theta) = 1 / sinc(theta); sinc > 0 for theta < pi.
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = 1.0 / a
    return np.stack([p[..., 2] * ratio, -p[..., 0] * ratio], -1)


# -- linear algebra --------------------------------------------------------------------------
def batched_inverse(matrix: ArrayLike) -> tuple[FloatArray, BoolArray]:
    """Inverse of each square matrix (..., k, k) and whether it exists (...).

    A singular matrix (exactly zero determinant) gets ``inf`` entries, a non-finite one
    ``nan``: one bad pose never aborts a batch (``np.linalg.inv`` would raise for all).

    Parameters
    ----------
    matrix : array_like, shape (..., k, k)
        Square matrices.

    Returns
    -------
    inverse : ndarray, shape (..., k, k)
        ``inf`` where singular, ``nan`` where not finite.
    ok : ndarray of bool, shape (...)

    Examples
    --------
    >>> inv, ok = batched_inverse([[[2.0, 0.0], [0.0, 4.0]], [[1.0, 1.0], [1.0, 1.0]]])
    >>> inv[0].tolist(), ok.tolist()
    ([[0.5, 0.0], [0.0, 0.25]], [True, False])
    """
    m = np.asarray(matrix, dtype=np.float64)
    k = m.shape[-1]
    finite = np.all(np.isfinite(m), axis=(-2, -1))
    safe = np.where(finite[..., None, None], m, np.eye(k))
    sign, _ = np.linalg.slogdet(safe)
    ok = finite & (sign != 0)
    inv = np.linalg.inv(np.where(ok[..., None, None], safe, np.eye(k)))
    bad = np.where(finite, np.inf, np.nan)[..., None, None]
    return np.where(ok[..., None, None], inv, bad), ok


#: A Cholesky pivot below this fraction of its diagonal entry sends the matrix to ``batched_inverse``.
SPD_PIVOT_FLOOR = 1e-8


def spd_inverse(matrix: ArrayLike) -> tuple[FloatArray, BoolArray]:
    """Inverse of each symmetric positive definite matrix (..., k, k) (a Gram matrix ``K^T K``).

    An entry-wise Cholesky factorisation ``M = L L^T`` over the batch (numpy ufuncs on the
    entries, no per-matrix LAPACK call), then ``M^-1 = L^-T L^-1``: several times faster than
    ``np.linalg.inv`` for k <= 6 and backward stable like it, so the two agree to about
    ``k^2 eps kappa(M)`` relative. A matrix whose pivot ``d_j`` falls below ``SPD_PIVOT_FLOOR``
    times its diagonal entry ``m_jj`` (``kappa(M)`` of order 1e8 or more, not positive
    definite, or not finite) is inverted by ``batched_inverse`` instead, so those get exactly
    its result (``inf`` where singular, ``nan`` where not finite).

    Parameters
    ----------
    matrix : array_like, shape (..., k, k)
        Symmetric positive (semi)definite matrices; only the lower triangle is read.

    Returns
    -------
    inverse : ndarray, shape (..., k, k)
        Symmetric.
    ok : ndarray of bool, shape (...)
        As ``batched_inverse``'s.

    Examples
    --------
    >>> inv, ok = spd_inverse([[[4.0, 2.0], [2.0, 2.0]], [[1.0, 1.0], [1.0, 1.0]]])
    >>> inv[0].tolist(), ok.tolist()
    ([[0.5, -0.5], [-0.5, 1.0]], [True, False])
    """
    m = np.asarray(matrix, dtype=np.float64)
    k = m.shape[-1]
    a = np.ascontiguousarray(np.moveaxis(m, (-2, -1), (0, 1)))             # (k, k, ...)
    low = np.zeros_like(a)
    inv_l = np.zeros_like(a)
    good = np.ones(a.shape[2:], bool)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for j in range(k):
            d = a[j, j] - sum((low[j, i] * low[j, i] for i in range(j)), np.zeros(a.shape[2:]))
            good &= d > SPD_PIVOT_FLOOR * a[j, j]            # False for nan, inf, d <= 0
            root = np.sqrt(np.where(good, d, 1.0))
            low[j, j] = root
            for r in range(j + 1, k):
                acc = a[r, j] - sum((low[r, i] * low[j, i] for i in range(j)), np.zeros(a.shape[2:]))
                low[r, j] = acc / root
        for j in range(k):                                   # L^-1, lower triangular, column by column
            inv_l[j, j] = 1.0 / low[j, j]
            for r in range(j + 1, k):
                acc = sum((low[r, i] * inv_l[i, j] for i in range(j, r)), np.zeros(a.shape[2:]))
                inv_l[r, j] = -acc / low[r, r]
        out = np.empty_like(a)
        for r in range(k):                                   # (L^-T L^-1)[r, c] = sum_i L^-1[i, r] L^-1[i, c]
            for c in range(r + 1):
                acc = inv_l[r, r] * inv_l[r, c]
                for i in range(r + 1, k):
                    acc = acc + inv_l[i, r] * inv_l[i, c]
                out[r, c] = acc
                out[c, r] = acc
    out = np.moveaxis(out, (0, 1), (-2, -1))
    ok = np.array(good)
    if not good.all():
        hard = ~good
        out = np.array(out)
        out[hard], ok[hard] = batched_inverse(m[hard])
    return out, ok


def angle_between(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Angle in [0, pi] between vectors ``a`` and ``b`` (..., 3): ``atan2(|a x b|, a . b)``.

    Accurate near 0 and pi, where ``arccos`` of the dot product loses half the digits.

    Parameters
    ----------
    a, b : array_like, shape (..., 3)
        Vectors (any length, not zero), broadcast together.

    Returns
    -------
    ndarray, shape (...)
        rad.

    Examples
    --------
    >>> f"{angle_between([1.0, 0.0, 0.0], [0.0, 2.0, 0.0]):.6f}"
    '1.570796'
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


def finite_rows(values: ArrayLike, fill: ArrayLike) -> tuple[FloatArray, BoolArray]:
    """``values`` (..., k) with every non-finite row replaced by ``fill`` (k,), and which rows were finite.

    Lets a model compute on a whole batch without floating-point warnings (``inf - inf``,
    ``sin(inf)``) and mask the bad rows afterwards.

    Parameters
    ----------
    values : array_like, shape (..., k)
        Rows to check.
    fill : array_like, shape (k,)
        Placeholder row for the non-finite ones.

    Returns
    -------
    rows : ndarray, shape (..., k)
    finite : ndarray of bool, shape (...)

    Examples
    --------
    >>> rows, ok = finite_rows([[1.0, 2.0], [np.nan, 0.0]], [0.0, 0.0])
    >>> rows.tolist(), ok.tolist()
    ([[1.0, 2.0], [0.0, 0.0]], [True, False])
    """
    arr = np.asarray(values, dtype=np.float64)
    finite = np.all(np.isfinite(arr), axis=-1)
    if finite.all():
        return arr, finite
    return np.where(finite[..., None], arr, np.asarray(fill, dtype=np.float64)), finite


# -- validation -------------------------------------------------------------------------------
def angle_in(name: str, value: Any, lower: float, upper: float, *, open_lower: bool = False) -> float:
    """``validation.validate_angle_in(value, name=name, ...)``: a float (rad) in the open range, or raise.

    Parameters
    ----------
    name : str
        The argument's name for the message.
    value : object
        An angle in rad.
    lower, upper : float
        The open range, rad.
    open_lower : bool
        Include ``upper`` (the range is open at ``lower`` only).

    Returns
    -------
    float
        rad.
    """
    return validate_angle_in(value, name=name, lower=lower, upper=upper, open_lower=open_lower)
