"""The orientations a semi-dextrous region must hold: samples within +-angle (paper 001, sec. V).

The tool (pen) axis tipped by up to ``angle`` in any direction with a roll of up to
+-``angle`` about it, sampled as eqs. 14-16 do (``metrics.orientations``), plus the pure
rotations about the base axes by +- each ring's tip angle; expressed in a mechanism's task
orientation coordinates (``orientation_coordinates``). ``metrics.dextrous`` tests positions
against them.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray
from kinematics.rotations import rotation_matrix, rotation_vector, tilt_of_direction

from .orientations import orientation_samples, roll_angles

POSITION_AXES = ("x", "y", "z")
#: Paper 001's pen axis ``j`` (base frame ``y``), about which tips and rolls are measured.
PEN_AXIS = (0.0, 1.0, 0.0)
#: Default angular spacing of the samples (rad): rings every 10 deg of tip, rolls every 10 deg.
DEFAULT_STEP = math.radians(10.0)


@dataclass(frozen=True)
class OrientationSet:
    """Orientation samples within +-``angle``, in a mechanism's task orientation coordinates.

    Attributes
    ----------
    angle : float
        The bound, rad.
    rotations : ndarray, shape (K, 3, 3)
        The samples as rotation matrices (base frame); row 0 is the identity.
    coordinates : ndarray, shape (K, r)
        The same in the task's orientation coordinates (``orientation_names``), rad.
    orientation_names : tuple of str
        ``("rx", "ry", "rz")`` or ``("rx", "rz")``.
    rings, rolls : int
        Eq. 16's N (tip rings besides the pole) and the number of roll angles used (1 when the
        roll is free).
    roll_free : bool
        The task has no roll coordinate: the roll samples were dropped (the device rolls freely).
    tip_count : int
        ``K_r`` of eq. 16.
    """

    angle: float
    rotations: FloatArray
    coordinates: FloatArray
    orientation_names: tuple[str, ...]
    rings: int
    rolls: int
    roll_free: bool
    tip_count: int

    @property
    def count(self) -> int:
        """K, the number of samples (identity and the pure axis rotations included).

        Returns
        -------
        int
        """
        return int(self.rotations.shape[0])

    def description(self) -> str:
        """One line: the bound, the sampling, the count.

        Returns
        -------
        str

        Examples
        --------
        >>> from kinematics import StewartPlatform
        >>> orientation_set(StewartPlatform(), math.radians(30)).description()
        'tip <= 30 deg about the pen axis y (eq. 16, N = 3 rings, K_r = 37) x roll +-30 deg (7 angles), \
plus pure rotations up to +-30 deg about x, y, z: 263 distinct orientations'
        """
        deg = math.degrees(self.angle)
        roll = "roll free (not a task coordinate)" if self.roll_free else f"roll +-{deg:g} deg ({self.rolls} angles)"
        axes = "x, z" if self.roll_free else "x, y, z"
        return (f"tip <= {deg:g} deg about the pen axis y (eq. 16, N = {self.rings} rings, K_r = {self.tip_count}) "
                f"x {roll}, plus pure rotations up to +-{deg:g} deg about {axes}: {self.count} distinct orientations")


def task_orientation_names(mechanism) -> tuple[str, ...]:
    names = tuple(n for n in mechanism.task_names if n not in POSITION_AXES)
    missing = [a for a in POSITION_AXES if a not in mechanism.task_names]
    if missing or names not in (("rx", "ry", "rz"), ("rx", "rz")):
        raise ValueError(f"{type(mechanism).__name__} needs task coordinates x, y, z with orientation (rx, ry, rz) "
                         f"or (rx, rz) for a dextrous workspace, got {', '.join(mechanism.task_names)}")
    return names


def orientation_coordinates(mechanism, rotations: ArrayLike) -> FloatArray:
    """Rotation matrices as the task's orientation coordinates, (K, 3, 3) -> (K, r), rad.

    ``(rx, ry, rz)``: the rotation vector. ``(rx, rz)``: the tilt of the pen axis ``y``
    (``kinematics.rotations.tilt_matrix``), the rotation without roll that points ``y`` along
    ``R y``; the roll about the pen is dropped.

    Parameters
    ----------
    mechanism : Mechanism
        Task coordinates x, y, z and (rx, ry, rz) or (rx, rz).
    rotations : array_like, shape (K, 3, 3)
        Rotation matrices, base frame.

    Returns
    -------
    ndarray, shape (K, r)
        rad.

    Raises
    ------
    ValueError
        For a task without these coordinates.

    Examples
    --------
    >>> from kinematics import StewartPlatform
    >>> orientation_coordinates(StewartPlatform(), rotation_matrix([[0.1, 0.0, 0.0]])).round(12).tolist()
    [[0.1, 0.0, 0.0]]
    """
    names = task_orientation_names(mechanism)
    rot = np.asarray(rotations, dtype=np.float64)
    if names == ("rx", "ry", "rz"):
        return rotation_vector(rot)
    return tilt_of_direction(rot[..., :, 1])


def _pure_rotations(angles: FloatArray, axes: tuple[int, ...]) -> FloatArray:
    """Rotations by +-each of ``angles`` (rad) about each base axis in ``axes``, (2 len(angles) len(axes), 3, 3)."""
    unit = np.eye(3)[list(axes)]
    vecs = np.concatenate([a * s * unit for a in np.asarray(angles, float) for s in (1.0, -1.0)])
    return rotation_matrix(vecs)


def orientation_set(mechanism, angle: float, *, rings: int | None = None, rolls: int | None = None,
                    rule: str = "exact") -> OrientationSet:
    """The orientation samples of a semi-dextrous test: tips and rolls within +-``angle`` (module doc).

    Parameters
    ----------
    mechanism : Mechanism
        Whose task orientation coordinates the samples are given in.
    angle : float
        The bound, rad, in (0, pi/2].
    rings : int, optional
        Eq. 16's N (default: a ring every 10 deg, ``ceil(angle / 10 deg)``). Paper 001's
        Table II uses N = 7 for 30 deg.
    rolls : int, optional
        Roll angles evenly over [-angle, angle] (default: every 10 deg, ``2 ceil(angle / 10 deg) + 1``;
        Table II: 13). Ignored when the task has no roll coordinate.
    rule : {"exact", "float"}
        Eq. 16's floor rule (``metrics.orientations``).

    Returns
    -------
    OrientationSet
        Samples ordered: identity first, then the pure axis rotations, then the rest by
        decreasing ``max(tip, |roll|)`` (the extremes, likeliest to fail, first).

    Raises
    ------
    ValueError
        For a bad angle or count, or a task without orientation coordinates.

    Examples
    --------
    >>> from kinematics import TwinPantograph
    >>> s = orientation_set(TwinPantograph(), math.radians(30))
    >>> s.count, s.roll_free, s.coordinates.shape
    (41, True, (41, 2))
    """
    names = task_orientation_names(mechanism)
    try:
        bound = float(angle)
    except (TypeError, ValueError):
        bound = math.nan
    if not (0.0 < bound <= math.pi / 2):
        raise ValueError(f"angle must be a number in (0, pi/2] rad, got {angle!r}")
    steps = max(1, math.ceil(bound / DEFAULT_STEP - 1e-9))
    n_rings = steps if rings is None else rings
    roll_free = names == ("rx", "rz")
    n_rolls = 1 if roll_free else (2 * steps + 1 if rolls is None else rolls)
    roll = roll_angles(bound, n_rolls) if not roll_free else np.zeros(1)
    samples = orientation_samples(bound, n_rings, roll=roll, rule=rule, tool_axis=PEN_AXIS)
    rot = samples.rotations
    # The literal roll, pitch and yaw at every ring's tip angle (so that the sets of two bounds with the
    # same ring spacing are nested); without roll the rotation about the pen axis y is the identity.
    ring_angles = bound * np.arange(1, samples.ring_counts.size) / (samples.ring_counts.size - 1)
    pure = _pure_rotations(ring_angles, (0, 2) if roll_free else (0, 1, 2))
    extreme = np.maximum(samples.axis_angle[:, 1], np.abs(samples.axis_angle[:, 0]))
    order = np.argsort(-extreme, kind="stable")
    rot = np.concatenate([np.eye(3)[None], pure, rot[order]])
    # Drop repeats (the identity at the pole with zero roll, pure rotations on a ring): one test each.
    keep = _first_occurrences(rot)
    rot = rot[keep]
    return OrientationSet(angle=bound, rotations=rot, coordinates=orientation_coordinates(mechanism, rot),
                          orientation_names=names, rings=int(n_rings), rolls=int(n_rolls), roll_free=roll_free,
                          tip_count=samples.tip_count)


def _first_occurrences(rot: FloatArray) -> np.ndarray:
    """Indices, in order, of the first of each group of rotation matrices equal to 9 decimals.

    Repeats come from different formulas for the same rotation (1e-16 apart); a pair split by a
    rounding boundary would only be tested twice.
    """
    _, first = np.unique(np.round(rot.reshape(len(rot), 9), 9), axis=0, return_index=True)
    return np.sort(first)
