"""Axis-angle orientation sampling of a bounded angular workspace (paper 001, eqs. 14-16).

An orientation is ``R = (theta_0, theta_1, theta_2)``: the tool axis ``a`` (a pen's axis)
is tipped by ``theta_1`` (the tip angle, ``0 <= theta_1 <= theta1_bar``) towards the
azimuth ``theta_2`` (``0 <= theta_2 < 2 pi``, unbounded), after a roll ``theta_0`` about
the tool axis itself::

    R = Rot(u, theta_1) Rot(a, theta_0),   u = -sin(theta_2) e1 + cos(theta_2) e2

so the tipped axis ``R a = sin(theta_1) (cos(theta_2) e1 + sin(theta_2) e2) + cos(theta_1) a``
points at polar angle ``theta_1`` and azimuth ``theta_2`` about ``a``. ``(e1, e2, a)`` is a
right-handed frame: for ``a = z`` it is ``(x, y, z)``, for ``a = y`` (paper 001's pen axis
``j``) ``(z, x, y)``, for ``a = x`` ``(y, z, x)``.

Sampling (the tip directions: the two "i,k" axes of paper 001's Tables II and VI)
------------------------------------------------------------------------------------
``theta_1`` is uniform, ``theta_1 = n dtheta_1`` with ``dtheta_1 = theta1_bar / N``,
``n = 0..N`` (N rings plus the pole). On ring ``n`` the tip traces a circle of radius
``sin(n dtheta_1)`` on the unit sphere; an arc spacing of ``dtheta_1`` along it needs the
azimuth step (eq. 14)

    dtheta_2,n = dtheta_1 / sin(n dtheta_1)

so the ring holds ``floor(2 pi / dtheta_2,n) = floor((2 pi N / theta1_bar) sin(n theta1_bar / N))``
samples, and in all (eq. 16)

    K_r = 1 + sum_{n=1..N} floor((2 pi N / theta1_bar) sin(n theta1_bar / N)).

We space a ring's samples evenly, ``theta_2 = 2 pi k / c_n``: the step is then the
smallest one >= dtheta_2,n that closes the ring (the literal step dtheta_2,n would leave
one gap of up to 2 dtheta_2,n). Samples on different rings are at least ``dtheta_1``
apart (their polar angles differ by that), neighbours on a ring just under it, so
nearest-neighbour distances are all close to ``dtheta_1``; uniform ``theta_2`` crowds the
samples near the pole instead.

``N`` is chosen (eq. 15) so that ``K_r`` is as close as possible to
``k_r = (k_i k_j k_k)^(d_r / d_t)``: the geometric mean of the samples per rotational axis
equals that per translational axis (``d_t`` translational axes with ``k_i, k_j, k_k``
samples; ``d_r`` rotational axes: 2 for the tip directions alone).

The floor and floating point
----------------------------
For a bound that is a rational number of degrees, ``2 pi N / theta1_bar`` is rational
(``360 N / theta1_bar[deg]``) and ``sin(n theta1_bar / N)`` is rational only when it is 0,
1/2 or 1 (Niven's theorem). Those terms are exact integers, e.g. ``theta1_bar = 45 deg``,
``N = 3``, ``n = 2``: ``24 sin(30 deg) = 12``, and for ``theta1_bar = 30 deg`` the outer ring
of every N: ``12 N sin(30 deg) = 6 N``. In double precision ``sin(pi/6)`` is
0.49999999999999994, so the literal ``floor`` gives 11, and ``6 N - 1`` for most N (at 30 deg
every N <= 15 but 5, 9, 10 and 13): one sample fewer than fits. Every other term is
irrational, so it cannot land on an integer.

* ``rule="exact"`` (default) counts what fits in exact arithmetic: a term within
  ``1e-9`` (relative) of an integer is that integer. Irrational terms are far from
  integers at practical sizes (the tests check > 1e-6 for N <= 60 at 30 and 45 deg).
* ``rule="float"`` evaluates eq. 16 literally in IEEE double,
  ``floor((2 pi N / theta1_bar) * sin(n theta1_bar / N))``; it reproduces paper 001:
  its K_r = 34 for 45 deg, N = 3 (exact: 35), and the 168 of its Table II for 30 deg,
  N = 7 (exact: 169). Its result depends on the evaluation order and on the platform's
  ``sin`` at the exact-integer terms, and only there.

================================  ==========================================================
function                          returns
================================  ==========================================================
``ring_counts``                   samples per ring ``(1, c_1, ..., c_N)`` (eq. 14/16 terms)
``rotation_count``                ``K_r`` (eq. 16)
``balanced_rotation_count``       ``k_r`` (eq. 15)
``choose_ring_count``             the N whose ``K_r`` is closest to a target
``axis_angle_matrix``             ``R(theta_0, theta_1, theta_2)``, shape (..., 3, 3)
``tip_angle``                     ``theta_1`` of rotation matrices, shape (...)
``roll_angles``                   evenly spaced ``theta_0`` in ``[-bound, bound]``
``orientation_samples``           the samples: matrices, triples, rings
================================  ==========================================================
"""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kinematics.arrays import FloatArray

Rule = Literal["exact", "float"]
RULES: tuple[str, ...] = ("exact", "float")
#: Relative distance from an integer within which ``rule="exact"`` takes a term as that integer.
INTEGER_TOL = 1e-9


def _bound(theta1_bar: float) -> float:
    try:
        value = float(theta1_bar)
    except (TypeError, ValueError):
        value = float("nan")
    if not (0.0 < value < math.pi):
        raise ValueError(f"theta1_bar must be a tip-angle bound in (0, pi) rad, got {theta1_bar!r}")
    return value


def _count(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def _rule(rule: str) -> str:
    if rule not in RULES:
        raise ValueError(f"rule must be one of {', '.join(map(repr, RULES))}, got {rule!r}")
    return rule


def ring_terms(theta1_bar: float, n_rings: int) -> FloatArray:
    """The unrounded terms of eq. 16, ``(2 pi N / theta1_bar) sin(n theta1_bar / N)``, n = 1..N.

    Evaluated in that order in double precision, term by term with ``math.sin``.

    Parameters
    ----------
    theta1_bar : float
        Tip-angle bound in rad, in (0, pi).
    n_rings : int
        N >= 1.

    Returns
    -------
    ndarray, shape (N,)
        The terms for n = 1..N (real numbers of samples, before the floor).

    Examples
    --------
    >>> ring_terms(np.pi / 2, 2).round(6).tolist()
    [5.656854, 8.0]
    """
    tb = _bound(theta1_bar)
    big_n = _count("n_rings", n_rings, 1)
    factor = 2.0 * math.pi * big_n / tb
    return np.array([factor * math.sin(n * tb / big_n) for n in range(1, big_n + 1)])


def ring_counts(theta1_bar: float, n_rings: int, *, rule: Rule = "exact") -> NDArray[np.int64]:
    """Samples per ring, ``(1, c_1, ..., c_N)``, shape (N + 1,): the pole, then eq. 16's terms.

    Parameters
    ----------
    theta1_bar : float
        Tip-angle bound in rad, in (0, pi).
    n_rings : int
        N >= 1, the number of ``theta_1`` samples besides the pole.
    rule : {"exact", "float"}
        How to floor terms that are exact integers in real arithmetic (module docstring).

    Returns
    -------
    ndarray of int64, shape (N + 1,)

    Examples
    --------
    >>> ring_counts(np.pi / 2, 2).tolist()
    [1, 5, 8]
    """
    _rule(rule)
    x = ring_terms(theta1_bar, n_rings)
    floor = np.floor(x)
    if rule == "exact":
        nearest = np.rint(x)
        floor = np.where(np.abs(x - nearest) <= INTEGER_TOL * np.maximum(1.0, np.abs(x)), nearest, floor)
    return np.concatenate([[1], floor.astype(np.int64)])


def rotation_count(theta1_bar: float, n_rings: int, *, rule: Rule = "exact") -> int:
    """``K_r`` of eq. 16: tip directions sampled within ``theta1_bar`` with N rings.

    Parameters
    ----------
    theta1_bar : float
        Tip-angle bound in rad, in (0, pi).
    n_rings : int
        N >= 1.
    rule : {"exact", "float"}
        Floor rule of ``ring_counts``.

    Returns
    -------
    int
        The sum of ``ring_counts``.

    Examples
    --------
    >>> rotation_count(np.pi / 2, 2)
    14
    """
    return int(ring_counts(theta1_bar, n_rings, rule=rule).sum())


def balanced_rotation_count(translational_counts, rotational_axes: int) -> float:
    """``k_r = (k_i k_j k_k)^(d_r / d_t)`` of eq. 15, with ``d_t = len(translational_counts)``.

    Parameters
    ----------
    translational_counts : sequence of int
        Samples along each translational axis (``d_t`` of them).
    rotational_axes : int
        ``d_r``: 2 for tip directions, 3 with roll as well.

    Returns
    -------
    float
        The target number of rotational samples (not rounded).

    Examples
    --------
    >>> round(balanced_rotation_count((10, 10, 10), 2), 9)
    100.0
    """
    counts = [_count("translational_counts entries", k, 1) for k in translational_counts]
    if not counts:
        raise ValueError("translational_counts must name at least one axis, got none")
    d_r = _count("rotational_axes", rotational_axes, 1)
    return float(math.prod(counts)) ** (d_r / len(counts))


def choose_ring_count(theta1_bar: float, target: float, *, rule: Rule = "exact", max_rings: int = 1000) -> int:
    """The N whose ``K_r`` is closest to ``target`` (eq. 15's ``k_r``); the smaller N on a tie.

    ``K_r`` grows about like ``2 pi N^2 (1 - cos theta1_bar) / theta1_bar^2``, so the search
    stops once ``K_r`` exceeds the target.

    Parameters
    ----------
    theta1_bar : float
        Tip-angle bound in rad, in (0, pi).
    target : float
        The wanted number of tip directions, > 0 (``balanced_rotation_count``).
    rule : {"exact", "float"}
        Floor rule of ``ring_counts``.
    max_rings : int
        Largest N tried.

    Returns
    -------
    int
        N, in ``[1, max_rings]``.

    Examples
    --------
    >>> choose_ring_count(np.pi / 2, 14)
    2
    """
    goal = float(target)
    if not (math.isfinite(goal) and goal > 0):
        raise ValueError(f"target must be a positive finite number of samples, got {target!r}")
    best_n, best_err = 1, math.inf
    for big_n in range(1, _count("max_rings", max_rings, 1) + 1):
        k_r = rotation_count(theta1_bar, big_n, rule=rule)
        if abs(k_r - goal) < best_err:
            best_n, best_err = big_n, abs(k_r - goal)
        if k_r > goal:
            break
    return best_n


def _frame(tool_axis: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Right-handed orthonormal ``(e1, e2, a)`` for a tool axis; see the module docstring."""
    a = np.asarray(tool_axis, dtype=np.float64)
    norm = np.linalg.norm(a) if a.shape == (3,) else 0.0
    if not (np.isfinite(norm) and norm > 0.0):
        raise ValueError(f"tool_axis must be a non-zero finite 3-vector, got {np.asarray(tool_axis).tolist()}")
    a = a / norm
    c = np.zeros(3)
    c[(int(np.argmax(np.abs(a))) + 1) % 3] = 1.0
    e1 = c - (c @ a) * a
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(a, e1), a


def _rodrigues(axis: FloatArray, angle: FloatArray) -> FloatArray:
    """Rotation matrices about unit ``axis`` (..., 3) by ``angle`` (...), shape (..., 3, 3)."""
    c, s = np.cos(angle)[..., None, None], np.sin(angle)[..., None, None]
    x, y, z = axis[..., 0], axis[..., 1], axis[..., 2]
    zero = np.zeros_like(x)
    cross = np.stack([np.stack([zero, -z, y], -1), np.stack([z, zero, -x], -1),
                      np.stack([-y, x, zero], -1)], -2)
    return c * np.eye(3) + s * cross + (1.0 - c) * axis[..., :, None] * axis[..., None, :]


def axis_angle_matrix(theta0: ArrayLike, theta1: ArrayLike, theta2: ArrayLike, *,
                      tool_axis: ArrayLike = (0.0, 0.0, 1.0)) -> FloatArray:
    """``R = Rot(u(theta_2), theta_1) Rot(a, theta_0)``, shape (..., 3, 3) (module docstring).

    Parameters
    ----------
    theta0, theta1, theta2 : array_like, broadcastable to (...)
        Roll about the tool axis, tip angle, azimuth of the tip, in rad.
    tool_axis : array_like, shape (3,)
        The tool (pen) axis ``a`` in the base frame; normalised here.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rotation matrices (base frame).

    Examples
    --------
    >>> axis_angle_matrix(0.0, np.pi / 2, 0.0).round(6).tolist()   # z tipped towards x
    [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]
    >>> axis_angle_matrix(np.zeros(4), np.zeros(4), np.zeros(4)).shape
    (4, 3, 3)
    """
    e1, e2, a = _frame(tool_axis)
    t0, t1, t2 = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (theta0, theta1, theta2)))
    u = -np.sin(t2)[..., None] * e1 + np.cos(t2)[..., None] * e2
    roll = _rodrigues(np.broadcast_to(a, t0.shape + (3,)), t0)
    return _rodrigues(u, t1) @ roll


def tip_angle(rotations: ArrayLike, *, tool_axis: ArrayLike = (0.0, 0.0, 1.0)) -> FloatArray:
    """``theta_1``, the angle between ``a`` and ``R a``, shape (...); atan2 keeps small angles exact.

    Parameters
    ----------
    rotations : array_like, shape (..., 3, 3)
        Rotation matrices.
    tool_axis : array_like, shape (3,)
        The tool axis ``a``; normalised here.

    Returns
    -------
    ndarray, shape (...)
        In rad, in [0, pi].

    Examples
    --------
    >>> round(float(tip_angle(axis_angle_matrix(0.3, 0.25, 1.0))), 9)
    0.25
    """
    _, _, a = _frame(tool_axis)
    rot = np.asarray(rotations, dtype=np.float64)
    if rot.ndim < 2 or rot.shape[-2:] != (3, 3):
        raise ValueError(f"rotations must have shape (..., 3, 3), got {rot.shape}")
    tipped = rot @ a
    return np.arctan2(np.linalg.norm(np.cross(a, tipped), axis=-1), tipped @ a)


def roll_angles(bound: float, count: int) -> FloatArray:
    """``count`` evenly spaced roll angles ``theta_0`` in ``[-bound, bound]`` (rad); ``[0]`` for 1.

    Parameters
    ----------
    bound : float
        Roll bound in rad, >= 0.
    count : int
        Number of angles, >= 1.

    Returns
    -------
    ndarray, shape (count,)
        In rad.

    Examples
    --------
    >>> roll_angles(1.0, 3).tolist(), roll_angles(1.0, 1).tolist()
    ([-1.0, 0.0, 1.0], [0.0])
    """
    b = float(bound)
    if not (math.isfinite(b) and b >= 0.0):
        raise ValueError(f"bound must be a finite roll bound >= 0 in rad, got {bound!r}")
    n = _count("count", count, 1)
    return np.zeros(1) if n == 1 else np.linspace(-b, b, n)


@dataclass(frozen=True)
class OrientationSamples:
    """Orientation samples, tip direction first, then roll (index = tip * n_roll + roll).

    ``axis_angle`` (K, 3) holds ``(theta_0, theta_1, theta_2)`` in rad; ``rotations``
    (K, 3, 3) the matrices; ``ring`` (K,) the ring index n (0 is the pole);
    ``ring_counts`` (N + 1,) the tip directions per ring; ``roll`` the roll angles.
    """

    axis_angle: FloatArray
    rotations: FloatArray
    ring: NDArray[np.int64]
    ring_counts: NDArray[np.int64]
    roll: FloatArray
    tool_axis: FloatArray

    @property
    def count(self) -> int:
        """K = K_r x (number of roll angles).

        Returns
        -------
        int
        """
        return int(self.rotations.shape[0])

    @property
    def tip_count(self) -> int:
        """``K_r`` of eq. 16.

        Returns
        -------
        int
        """
        return int(self.ring_counts.sum())

    @property
    def directions(self) -> FloatArray:
        """The tipped tool axes ``R a``, shape (K, 3).

        Returns
        -------
        ndarray, shape (K, 3)
            Unit vectors in the base frame.
        """
        return self.rotations @ self.tool_axis

    @property
    def tilt_vectors(self) -> FloatArray:
        """Rotation vectors ``theta_1 u(theta_2)`` of the tip part, shape (K, 3).

        Perpendicular to the tool axis, of length ``theta_1``; the whole rotation's
        rotation vector where the roll is 0. With the pen axis ``y`` these are the tilts
        ``(rx, 0, rz)`` of ``kinematics.rotations.tilt_matrix``.

        Returns
        -------
        ndarray, shape (K, 3)
            In rad.
        """
        e1, e2, _ = _frame(self.tool_axis)
        t1, t2 = self.axis_angle[:, 1:2], self.axis_angle[:, 2:3]
        return t1 * (-np.sin(t2) * e1 + np.cos(t2) * e2)


def orientation_samples(theta1_bar: float, n_rings: int, *, roll: ArrayLike = (0.0,), rule: Rule = "exact",
                        tool_axis: ArrayLike = (0.0, 0.0, 1.0)) -> OrientationSamples:
    """The axis-angle samples of eqs. 14 and 16, each combined with every roll angle.

    Parameters
    ----------
    theta1_bar : float
        Tip-angle bound in rad, in (0, pi); every sample has ``theta_1 <= theta1_bar``.
    n_rings : int
        N >= 1 (choose it with ``choose_ring_count``).
    roll : array_like, shape (r,)
        Roll angles ``theta_0`` in rad (e.g. ``roll_angles(np.radians(30), 13)``).
    rule : {"exact", "float"}
        Floor rule of ``ring_counts``.
    tool_axis : array_like, shape (3,)
        The tool axis ``a``; paper 001's pen axis is ``j``, ``(0, 1, 0)``.

    Returns
    -------
    OrientationSamples
        K = ``K_r * r`` samples, arrays (K, 3) and (K, 3, 3).

    Examples
    --------
    >>> s = orientation_samples(np.pi / 2, 2, roll=roll_angles(0.5, 3))
    >>> s.tip_count, s.count, s.rotations.shape
    (14, 42, (42, 3, 3))
    """
    tb = _bound(theta1_bar)
    big_n = _count("n_rings", n_rings, 1)
    counts = ring_counts(tb, big_n, rule=rule)
    rolls = np.asarray(roll, dtype=np.float64).reshape(-1)
    if rolls.size == 0 or not np.all(np.isfinite(rolls)):
        raise ValueError(f"roll must be one or more finite angles in rad, got {np.asarray(roll).tolist()}")
    ring = np.repeat(np.arange(big_n + 1), counts)
    # Azimuths 2 pi k / c_n within each ring: k restarts at 0 on every ring.
    starts = np.repeat(np.cumsum(counts) - counts, counts)
    k = np.arange(ring.size) - starts
    theta1 = np.minimum(ring * tb / big_n, tb)      # n = N is the bound itself, never above it
    theta2 = 2.0 * np.pi * k / counts[ring]
    t0 = np.tile(rolls, ring.size)
    t1 = np.repeat(theta1, rolls.size)
    t2 = np.repeat(theta2, rolls.size)
    rot = axis_angle_matrix(t0, t1, t2, tool_axis=tool_axis)
    return OrientationSamples(axis_angle=np.stack([t0, t1, t2], axis=-1), rotations=rot,
                              ring=np.repeat(ring, rolls.size), ring_counts=counts, roll=rolls,
                              tool_axis=_frame(tool_axis)[2])
