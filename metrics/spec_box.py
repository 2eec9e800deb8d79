"""The largest box of a given shape that a device holds at every orientation within a bound.

Paper 001's Table X gives the haptic pen's workspace as a box, +-6 x +-3.75 x +-3.75 cm at
+-45 deg: a region the device holds at every orientation within the bound (the optimization's
workspace of Table VI, +-8 x +-5 x +-5 cm at +-45 deg, scaled by 0.75). This module finds the
largest box of such a shape, centred at a point, that a device holds:

- **shape**: half-widths ``h = (h_x, h_y, h_z)`` at scale 1 (``TABLE_X_HALF_WIDTHS``); the box at
  scale ``s`` is ``centre +- s h``.
- **holds**: every pose of a sample set is reachable (``mechanism.inverse``) and feasible
  (``mechanism.feasible``: joint ranges, U-joint bends). The positions are a regular grid of
  ``points`` per axis over the box, faces, edges and corners included; the orientations are
  ``metrics.dextrous_orientations.orientation_set`` at the bound (the semi-dextrous test's sampling: the pen
  axis y tipped in every direction on eq. 16's rings, the roll about it where the task has one,
  and the pure rotations about the base axes). Every position is tested with every orientation.
  A task of positions alone (x, y, z) is tested at its positions.
- **largest**: bisection on the scale ``s``. The scale is bracketed first (from 1, doubled while
  the box holds, halved while it fails) and the bracket halved until it is narrower than
  ``resolution``: the box holds at ``scale`` and fails at ``failed_scale`` (at most
  ``resolution`` above), with a pose that fails recorded.

What the answer means
---------------------
The test is sampled: a pose between grid points or between orientation samples is not tested, so
the scale is an estimate from above of the scale at which the continuous box holds (finer
``points`` or ``rings`` can only lower it). Bisection assumes the scales that hold form one
interval ``[0, s*]``; a box that fails at some scale and holds at a larger one (a void in the
region that the coarser grid steps over) is not looked for.

==========================  =====================================================================
name                        what
==========================  =====================================================================
``box_positions``           the grid of positions in a box
``box_failure``             the first pose of a box's samples that fails, or None
``largest_held_box``        the largest held scale by bisection (``HeldBox``)
==========================  =====================================================================
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

from .dextrous_orientations import OrientationSet, orientation_set

POSITION_AXES = ("x", "y", "z")
#: Table X's box, half-widths in m (x, y, z: +-6, +-3.75, +-3.75 cm).
TABLE_X_HALF_WIDTHS = (0.06, 0.0375, 0.0375)
#: Table X's orientation bound, rad (+-45 deg).
TABLE_X_ANGLE = math.radians(45.0)
#: Default grid points per axis over the box (corners, edge and face centres included: odd).
DEFAULT_POINTS = 9
#: Default width of the final bisection bracket, in units of the shape (1e-3: 0.06 mm along x for Table X's).
DEFAULT_RESOLUTION = 1e-3
#: Largest scale tried before the search stops with the box still held.
MAX_SCALE = 64.0
#: Poses per ``inverse`` / ``feasible`` call.
CHUNK_POSES = 1 << 16


@dataclass(frozen=True)
class HeldBox:
    """The largest box found, of a given shape, held at every sampled pose.

    Attributes
    ----------
    centre : ndarray, shape (3,)
        m.
    shape : ndarray, shape (3,)
        Half-widths at scale 1, m.
    scale : float
        The largest scale found to hold (0 when the centre itself fails).
    failed_scale : float or None
        The smallest scale found to fail (``scale < failed_scale <= scale + resolution``); None when
        the box still held at ``MAX_SCALE``.
    failure : ndarray or None, shape (m,)
        A pose (task coordinates, SI) of the box at ``failed_scale`` that is unreachable or infeasible.
    resolution : float
        The bisection's final bracket width, in units of the shape.
    points : int
        Grid points per axis.
    orientations : OrientationSet or None
        The orientation samples; None for a task of positions alone.
    boxes_tested : int
        Boxes tested by the search.
    poses_evaluated : int
        Pose evaluations spent.
    seconds : float
        Wall time.
    """

    centre: FloatArray
    shape: FloatArray
    scale: float
    failed_scale: float | None
    failure: FloatArray | None
    resolution: float
    points: int
    orientations: OrientationSet | None
    boxes_tested: int
    poses_evaluated: int
    seconds: float

    @property
    def half_widths(self) -> FloatArray:
        """``scale * shape``, m, shape (3,).

        Returns
        -------
        ndarray, shape (3,)
        """
        return self.scale * self.shape

    def sampling(self) -> str:
        """One line: the position grid and the orientation samples.

        Returns
        -------
        str
        """
        grid = f"{self.points} x {self.points} x {self.points} grid points (corners and faces included)"
        if self.orientations is None:
            return f"{grid}; a task of positions alone, no orientation tested"
        return f"{grid}, each with {self.orientations.description()}"


def _position_indices(mechanism) -> list[int]:
    names = tuple(mechanism.task_names)
    missing = [a for a in POSITION_AXES if a not in names]
    if missing:
        raise ValueError(f"a box needs task coordinates x, y and z, {type(mechanism).__name__} has "
                         f"{', '.join(names)}")
    return [names.index(a) for a in POSITION_AXES]


def box_orientations(mechanism, angle: float, *, rings: int | None = None) -> OrientationSet | None:
    """The orientation samples a box is tested with: ``orientation_set`` at ``angle``, None for positions alone.

    Parameters
    ----------
    mechanism : Mechanism
        Task x, y, z, with (rx, ry, rz), (rx, rz) or no orientation coordinates.
    angle : float
        The bound, rad, in (0, pi/2].
    rings : int, optional
        Eq. 16's N (default: a ring every 10 deg).

    Returns
    -------
    OrientationSet or None

    Raises
    ------
    ValueError
        For a task without x, y, z, or with orientation coordinates ``orientation_set`` does not know.

    Examples
    --------
    >>> from kinematics import TwinPantograph
    >>> box_orientations(TwinPantograph(), math.radians(45)).count
    95
    """
    _position_indices(mechanism)
    if len(mechanism.task_names) == 3:
        return None
    return orientation_set(mechanism, angle, rings=rings)


def box_positions(centre: ArrayLike, half_widths: ArrayLike, points: int) -> FloatArray:
    """The ``points ** 3`` positions of a regular grid over ``centre +- half_widths``, corners first, m.

    Parameters
    ----------
    centre, half_widths : array_like, shape (3,)
        m.
    points : int
        Per axis, >= 2; 1 gives the centre alone.

    Returns
    -------
    ndarray, shape (points ** 3, 3)
        The 8 corners first (the likeliest to fail), then every other grid point.

    Examples
    --------
    >>> box_positions((0, 0, 0), (1, 2, 3), 3)[:2].tolist()
    [[-1.0, -2.0, -3.0], [-1.0, -2.0, 3.0]]
    """
    if isinstance(points, bool) or not isinstance(points, (int, np.integer)) or points < 1:
        raise ValueError(f"points must be an integer >= 1, got {points!r}")
    c = np.asarray(centre, float).reshape(3)
    h = np.asarray(half_widths, float).reshape(3)
    if points == 1:
        return c[None].copy()
    axes = [np.linspace(ci - hi, ci + hi, points) for ci, hi in zip(c, h)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    ends = np.array([0, points - 1])
    corner = np.isin(np.arange(points), ends)
    is_corner = np.stack(np.meshgrid(corner, corner, corner, indexing="ij"), -1).reshape(-1, 3).all(axis=1)
    return np.concatenate([grid[is_corner], grid[~is_corner]])


def _poses(mechanism, positions: FloatArray, coords: FloatArray | None) -> FloatArray:
    """Every position with every orientation (position-major), task coordinates (P * K, m)."""
    pos_idx = _position_indices(mechanism)
    m = len(mechanism.task_names)
    if coords is None:
        out = np.zeros((len(positions), m))
        out[:, pos_idx] = positions
        return out
    rot_idx = [i for i in range(m) if i not in pos_idx]
    out = np.empty((len(positions), len(coords), m))
    out[..., pos_idx] = positions[:, None, :]
    out[..., rot_idx] = coords[None, :, :]
    return out.reshape(-1, m)


def box_failure(mechanism, centre: ArrayLike, half_widths: ArrayLike, orientations: OrientationSet | None,
                points: int, *, chunk_poses: int = CHUNK_POSES) -> tuple[FloatArray | None, int]:
    """The first sampled pose of the box ``centre +- half_widths`` that fails, and the poses evaluated.

    Corners are tested before the rest of the grid, each against every orientation, in chunks
    of at most ``chunk_poses`` poses; the search stops at the first chunk with a failure.

    Parameters
    ----------
    mechanism : Mechanism
    centre, half_widths : array_like, shape (3,)
        m.
    orientations : OrientationSet or None
        From ``box_orientations``; None for a task of positions alone.
    points : int
        Grid points per axis.
    chunk_poses : int
        Poses per call.

    Returns
    -------
    failure : ndarray, shape (m,), or None
        A pose that is unreachable or infeasible; None when the box holds.
    evaluated : int
        Poses evaluated.
    """
    positions = box_positions(centre, half_widths, points)
    coords = None if orientations is None else orientations.coordinates
    k = 1 if coords is None else len(coords)
    per_call = max(1, chunk_poses // k)
    evaluated = 0
    for s in range(0, len(positions), per_call):
        poses = _poses(mechanism, positions[s:s + per_call], coords)
        q, ok = mechanism.inverse(poses)
        ok = ok & mechanism.feasible(q, poses)
        evaluated += len(poses)
        if not ok.all():
            return poses[int(np.argmin(ok))].copy(), evaluated
    return None, evaluated


def largest_held_box(mechanism, centre: ArrayLike, shape: ArrayLike = TABLE_X_HALF_WIDTHS, *,
                     angle: float = TABLE_X_ANGLE, orientations: OrientationSet | None = None,
                     points: int = DEFAULT_POINTS, resolution: float = DEFAULT_RESOLUTION,
                     max_scale: float = MAX_SCALE) -> HeldBox:
    """The largest scale ``s`` at which the box ``centre +- s shape`` holds every sampled pose (module doc).

    Parameters
    ----------
    mechanism : Mechanism
        Task x, y, z, with (rx, ry, rz), (rx, rz) or no orientation coordinates.
    centre : array_like, shape (3,)
        m.
    shape : array_like, shape (3,)
        Half-widths at scale 1, m, each > 0 (default Table X's).
    angle : float
        Orientation bound, rad (default Table X's 45 deg); unused for a task of positions alone.
    orientations : OrientationSet, optional
        The samples (default ``box_orientations(mechanism, angle)``).
    points : int
        Grid points per axis, >= 2.
    resolution : float
        Final bracket width in units of the shape, > 0.
    max_scale : float
        The search stops with the box still held at this scale.

    Returns
    -------
    HeldBox

    Raises
    ------
    ValueError
        For a task without x, y, z, or bad sizes.

    Examples
    --------
    >>> from kinematics.serial_rrr import SerialRRR
    >>> box = largest_held_box(SerialRRR(), (0.15, 0.0, 0.0), resolution=0.01)
    >>> box.orientations is None, box.scale < box.failed_scale <= box.scale + 0.01
    (True, True)
    """
    start = time.perf_counter()
    c = np.asarray(centre, float).reshape(3)
    h = np.asarray(shape, float).reshape(3)
    if not (np.all(np.isfinite(h)) and np.all(h > 0)):
        raise ValueError(f"shape must be three positive half-widths, got {shape!r}")
    if isinstance(points, bool) or not isinstance(points, (int, np.integer)) or points < 2:
        raise ValueError(f"points must be an integer >= 2, got {points!r}")
    if not (math.isfinite(resolution) and resolution > 0):
        raise ValueError(f"resolution must be a positive number, got {resolution!r}")
    if orientations is None:
        orientations = box_orientations(mechanism, angle)
    else:
        _position_indices(mechanism)
    evaluated = 0
    tested = 0

    def fails(scale: float) -> FloatArray | None:
        nonlocal evaluated, tested
        bad, n = box_failure(mechanism, c, scale * h, orientations, points)
        evaluated += n
        tested += 1
        return bad

    def result(scale: float, failed: float | None, failure: FloatArray | None) -> HeldBox:
        return HeldBox(centre=c, shape=h, scale=float(scale), failed_scale=None if failed is None else float(failed),
                       failure=failure, resolution=float(resolution), points=int(points), orientations=orientations,
                       boxes_tested=tested, poses_evaluated=evaluated, seconds=time.perf_counter() - start)

    at_centre, n = box_failure(mechanism, c, np.zeros(3), orientations, 1)     # the centre, every orientation
    evaluated += n
    tested += 1
    if at_centre is not None:
        return result(0.0, 0.0, at_centre)
    lo, hi, failure = 0.0, 1.0, fails(1.0)
    if failure is None:                          # held at 1: double until it fails
        lo = 1.0
        while failure is None:
            if hi >= max_scale:
                return result(hi, None, None)
            lo, hi = hi, min(2.0 * hi, max_scale)
            failure = fails(hi)
    while hi - lo > resolution:
        mid = 0.5 * (lo + hi)
        bad = fails(mid)
        if bad is None:
            lo = mid
        else:
            hi, failure = mid, bad
    return result(lo, hi, failure)
