"""Semi-dextrous workspace: the positions where the device can hold every orientation within +-angle.

Paper 001, sec. V, Figs. 13-14: "a point belongs to such a semi-dextrous workspace if the
platform origin can be placed there and rolled, pitched and yawed +-30 deg". We read the
orientation set as the paper's own angular workspace (its Table II and eq. 21): the tool (pen)
axis tipped by up to ``angle`` in any direction, combined with a roll of up to +-``angle`` about
it, sampled as eqs. 14-16 do (``metrics.orientations``), plus the pure rotations about the base
axes x, y, z by +- each ring's tip angle up to +-angle (the literal roll, pitch and yaw; eq. 16's
rings need not hold the azimuths 90 and 270 deg). A position is in the region when every sample is reachable
(``mechanism.inverse``) and feasible (``mechanism.feasible``: joint ranges, U-joint bends).

What the sampling means
-----------------------
The test is sampled twice: over positions (a grid) and over orientations (K samples). The
region is therefore an estimate from above of the true region at those positions (an
orientation between samples is not tested), and its volume carries the grid error estimated by
``indicator_volume``. Make the orientation sampling finer (``rings``, ``rolls``) to check it.

Orientation coordinates (``orientation_coordinates``)
-----------------------------------------------------
A task whose orientation coordinates are ``(rx, ry, rz)`` takes rotation vectors (Stewart,
Inoue, the 6-DOF Twin-Pantograph). A task with ``(rx, rz)`` is a pen whose roll is not a task
coordinate (the 5-DOF Twin-Pantograph: the roll joint is passive, every roll comes free), so
only the tip directions are tested, as tilts of the pen axis ``y``; the roll samples are
dropped and ``OrientationSet.roll_free`` says so.

Cost and memory
---------------
Orientation-major with early exit: all positions are tested at zero orientation first (that is
also the constant-orientation workspace, ``DextrousRegion.reachable``), then the surviving ones
against blocks of orientations (1, 2, 4, ... up to ``block``: ``_blocks``), most extreme first (the
largest tip and roll angles fail first), dropping a position at its first failure. Work is about
``(positions in the region) x K`` pose evaluations; the calls in flight evaluate at most
``chunk_poses`` poses in all, so memory is bounded by ``chunk_poses x metrics.budget.chunk_work_bytes``
plus one byte per grid point. The calls run on the maps' thread pool, ``metrics.chunk_pool`` (numpy's
loops release the GIL), the positions taken with ``x`` varying fastest (a batch holds whole lines
along ``x``); a position's result depends on it alone, so neither changes the region.

==========================  =====================================================================
function                    returns
==========================  =====================================================================
``orientation_set``         the orientation samples within +-angle (``OrientationSet``), in
                            ``metrics.dextrous_orientations`` with ``orientation_coordinates``
``dextrous_region``         the region on a 3D grid (``DextrousRegion``)
``face_test``               its test of the box's face points alone (``FaceTest``): whether a
                            default box must grow, without testing the interior it will test again
``indicator_volume``        a boolean grid's volume with its boundary-cell error estimate
``box_grid``                a 3D position grid over x, y, z
``clipped_faces``           the faces of the box a region touches (its volume is then a lower bound)
``grown_grid``              the grid with those faces moved out, the spacing kept
``region_estimate``         memory of a region job before it runs (``metrics.budget``)
==========================  =====================================================================
"""
from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import BoolArray, FloatArray
from kinematics.grid import GridSpec

from .chunk_pool import Cancelled, windowed
from .dextrous_orientations import POSITION_AXES, OrientationSet, task_orientation_names

#: Default number of poses one ``inverse`` / ``feasible`` call evaluates.
CHUNK_POSES = 1 << 16
#: What a clipped volume is (a region that touches its box may go on past it): say it wherever the
#: volume is printed, as ``">= 123 cm^3 (clipped by the box)"``.
LOWER_BOUND_NOTE = "clipped by the box"
VOLUME_ERROR_LABEL = ("boundary-cell estimate: half the volume of the grid cells on the region's boundary "
                      "(points in the region with a 6-neighbour outside it); an estimate of the grid error, "
                      "not a bound (it assumes no feature of the region is smaller than a cell, and does not "
                      "cover the orientation sampling)")


def box_grid(lower: ArrayLike, upper: ArrayLike, resolution: int | tuple[int, int, int]) -> GridSpec:
    """A 3D grid over the positions x, y, z (m), ``resolution`` points per axis.

    Parameters
    ----------
    lower, upper : array_like, shape (3,)
        Box corners, m.
    resolution : int or tuple of 3 int
        Points per axis, each >= 2.

    Returns
    -------
    GridSpec
        Axes ``("x", "y", "z")``.

    Examples
    --------
    >>> box_grid((0, 0, 0), (0.1, 0.1, 0.1), 3).spacing()
    (0.05, 0.05, 0.05)
    """
    res = (resolution,) * 3 if isinstance(resolution, (int, np.integer)) else tuple(resolution)
    lo = tuple(float(v) for v in np.asarray(lower, float).reshape(-1))
    hi = tuple(float(v) for v in np.asarray(upper, float).reshape(-1))
    if len(lo) != 3 or len(hi) != 3 or len(res) != 3:
        raise ValueError(f"a position box needs 3 lower, 3 upper values and 3 resolutions, got {lo}, {hi}, {res}")
    return GridSpec(POSITION_AXES, lo, hi, tuple(int(r) for r in res))


@dataclass(frozen=True)
class Volume:
    """A region's volume on a grid, m^3, with its boundary-cell error estimate (``VOLUME_ERROR_LABEL``)."""

    value: float
    error: float
    points: int
    boundary_points: int
    cell: float


def indicator_volume(inside: ArrayLike, spacing: ArrayLike) -> Volume:
    """Volume of a boolean grid: points inside times the cell volume, with a grid-error estimate.

    Every grid point stands for the cell around it. The true boundary passes between a point
    inside and its outside neighbour, so the cells of the inside points on the boundary (those
    with a 6-neighbour outside, or on the grid's faces) are on average about half in: the error
    estimate is half their volume (``VOLUME_ERROR_LABEL``).

    Parameters
    ----------
    inside : array_like of bool, shape (i, j, k)
        The region on the grid.
    spacing : array_like, shape (3,)
        Grid spacing per axis, m.

    Returns
    -------
    Volume
        m^3.

    Examples
    --------
    >>> cube = np.zeros((5, 5, 5), bool); cube[1:4, 1:4, 1:4] = True
    >>> v = indicator_volume(cube, (1.0, 1.0, 1.0))
    >>> v.value, v.boundary_points, v.error
    (27.0, 26, 13.0)
    """
    mask = np.asarray(inside, dtype=bool)
    if mask.ndim != 3:
        raise ValueError(f"inside must be a 3D boolean grid, got shape {mask.shape}")
    cell = float(np.prod(np.asarray(spacing, float)))
    padded = np.pad(mask, 1, constant_values=False)
    interior = padded[1:-1, 1:-1, 1:-1].copy()
    for axis in range(3):
        for shift in (-1, 1):
            interior &= np.roll(padded, shift, axis=axis)[1:-1, 1:-1, 1:-1]
    boundary = int(np.count_nonzero(mask & ~interior))
    n = int(np.count_nonzero(mask))
    return Volume(value=n * cell, error=0.5 * boundary * cell, points=n, boundary_points=boundary, cell=cell)


@dataclass(frozen=True)
class DextrousRegion:
    """The semi-dextrous region of one mechanism on a position grid.

    Attributes
    ----------
    grid : GridSpec
        Axes x, y, z (m); arrays have shape ``grid.resolution``.
    inside : ndarray of bool, shape ``grid.resolution``
        Every orientation sample reachable and feasible there.
    reachable : ndarray of bool, shape ``grid.resolution``
        Reachable and feasible at zero orientation (the constant-orientation workspace).
    orientations : OrientationSet
        The samples tested.
    volume, reachable_volume : Volume
        Of ``inside`` and of ``reachable``, m^3.
    clipped : bool
        Some point of the region lies on a face of the box: the region may extend beyond it and
        its volume is then a lower bound (``LOWER_BOUND_NOTE``).
    poses_evaluated : int
        Pose evaluations spent (early exit makes it far below positions x K).
    seconds : float
        Wall time.
    reachable_clipped : bool
        The same as ``clipped`` for ``reachable``: its volume is then a lower bound.
    """

    grid: GridSpec
    inside: BoolArray
    reachable: BoolArray
    orientations: OrientationSet
    volume: Volume
    reachable_volume: Volume
    clipped: bool
    poses_evaluated: int
    seconds: float
    reachable_clipped: bool = False

    def positions(self) -> FloatArray:
        """Positions (P, 3) of the region's grid points, m.

        Returns
        -------
        ndarray, shape (P, 3)
            m.
        """
        coords = self.grid.coordinates()
        idx = np.nonzero(self.inside)
        return np.stack([coords[k][idx[k]] for k in range(3)], -1)


def _feasible_poses(mechanism, poses: FloatArray) -> BoolArray:
    q, ok = mechanism.inverse(poses)
    return ok & mechanism.feasible(q, poses)


def _poses(mechanism, positions: FloatArray, coords: FloatArray) -> FloatArray:
    """Poses (P * B, m): every position with every orientation, position-major."""
    names = mechanism.task_names
    pos_idx = [names.index(a) for a in POSITION_AXES]
    rot_idx = [i for i in range(len(names)) if i not in pos_idx]
    p, b = len(positions), len(coords)
    out = np.empty((p, b, len(names)))
    out[..., pos_idx] = positions[:, None, :]
    out[..., rot_idx] = coords[None, :, :]
    return out.reshape(p * b, len(names))


@dataclass(frozen=True)
class FaceTest:
    """The test of a box's face points alone (``face_test``): which faces its region touches.

    Attributes
    ----------
    grid : GridSpec
        The box, axes x, y, z.
    orientations : OrientationSet
        The samples tested.
    index : ndarray of int, shape (F,)
        Flat indices of the grid points on the box's faces.
    reachable, inside : ndarray of bool, shape (F,)
        Those points' results, as ``dextrous_region`` finds them.
    poses_evaluated : int
        Pose evaluations spent on them.
    seconds : float
        Wall time spent on them.
    """

    grid: GridSpec
    orientations: OrientationSet
    index: np.ndarray
    reachable: BoolArray
    inside: BoolArray
    poses_evaluated: int
    seconds: float = 0.0

    def touched(self) -> tuple[tuple[int, int], ...]:
        """``clipped_faces`` of the region: the faces it touches, ``(axis, side)`` (only face points count)."""
        mask = np.zeros(tuple(self.grid.resolution), bool)
        mask.reshape(-1)[self.index[self.inside]] = True
        return clipped_faces(mask)


def _face_mask(shape: tuple[int, ...]) -> BoolArray:
    faces = np.ones(shape, bool)
    faces[1:-1, 1:-1, 1:-1] = False
    return faces


def _check(mechanism, grid: GridSpec, orientations: OrientationSet, chunk_poses: int, block: int) -> None:
    if tuple(grid.axes) != POSITION_AXES or grid.fixed:
        raise ValueError(f"grid must vary exactly the positions x, y, z (box_grid), got axes {grid.axes!r}")
    names = task_orientation_names(mechanism)
    if orientations.orientation_names != names:
        raise ValueError(f"orientations are in coordinates {orientations.orientation_names!r}, the mechanism's are "
                         f"{names!r}: make them with orientation_set(mechanism, ...)")
    for label, value in (("chunk_poses", chunk_poses), ("block", block)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise ValueError(f"{label} must be an integer >= 1, got {value!r}")


def _test_points(mechanism, points: FloatArray, orientations: OrientationSet, chunk_poses: int, block: int,
                 progress, cancelled, threads: bool) -> tuple[BoolArray, BoolArray, int]:
    """``(reachable, inside, poses evaluated)`` of positions ``points`` (P, 3): the module doc's order.

    Each position's result and pose count depend on it alone (not on the others tested with it, nor
    on the thread): the calls run on the maps' pool (``metrics.chunk_pool``) when ``threads``, with at
    most ``chunk_poses`` poses in flight in all.
    """
    k = orientations.count
    coords = orientations.coordinates[_largest_first(orientations.rotations)]
    evaluated = 0
    workers = (os.cpu_count() or 1) if threads else 1
    in_flight = 2 * workers if workers > 1 else 1           # chunk_pool.windowed's window

    def test(alive: np.ndarray, orient: FloatArray) -> np.ndarray:
        """The subset of ``alive`` (indices) that passes every orientation of ``orient`` (B, r)."""
        nonlocal evaluated
        per_call = max(1, chunk_poses // in_flight // len(orient))

        def starts():
            for s in range(0, len(alive), per_call):
                if cancelled is not None and cancelled():
                    raise Cancelled()
                yield s

        def work(s: int) -> tuple[np.ndarray, int]:
            idx = alive[s:s + per_call]
            ok = _feasible_poses(mechanism, _poses(mechanism, points[idx], orient))
            return idx[ok.reshape(len(idx), len(orient)).all(axis=1)], ok.size

        calls = windowed(work, starts(), workers) if workers > 1 and len(alive) > per_call else map(work, starts())
        keep = []
        for kept, size in calls:
            keep.append(kept)
            evaluated += size
        return np.concatenate(keep) if keep else alive[:0]

    alive = test(np.arange(len(points)), coords[:1])          # identity: reachable at all
    reachable = np.zeros(len(points), bool)
    reachable[alive] = True
    for b, e in _blocks(k, block):
        if progress is not None:
            progress(b / k)
        if alive.size == 0:
            break
        alive = test(alive, coords[b:e])
    if progress is not None:
        progress(1.0)
    inside = np.zeros(len(points), bool)
    inside[alive] = True
    return reachable, inside, evaluated


def _largest_first(rotations: FloatArray) -> np.ndarray:
    """The order the samples ``rotations`` (K, 3, 3) are tested in: the first (the identity), then the rest by
    decreasing rotation angle, ties in their own order.

    ``orientation_set`` puts the pure axis rotations first with the smallest angle first, and a position out of
    the region fails a large rotation far more often than a small one (``isoforce dextrous twin_pantograph``:
    61 % of them fail 30 deg about x, 16 % 10 deg), and is dropped at its first failure: tested largest first,
    1,082,499 -> 967,583 poses. The set, hence the region, is the same; the order is the set's alone, so a
    position's poses still depend on it alone. Angles are rounded to 1e-9 rad before the (stable) sort, so that
    equal angles computed by different formulas keep the set's order.

    Examples
    --------
    >>> from kinematics.rotations import rotation_matrix
    >>> _largest_first(rotation_matrix(np.array([[0, 0, 0], [0.1, 0, 0], [0, 0, -0.3], [0.3, 0, 0]]))).tolist()
    [0, 2, 3, 1]
    """
    cos = np.clip((np.trace(rotations[1:], axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    angle = np.round(np.arccos(cos), 9)
    return np.concatenate([[0], 1 + np.argsort(-angle, kind="stable")])


def _blocks(count: int, block: int):
    """``(start, stop)`` of the orientation blocks after the identity: 1, 2, 4, ... orientations, at most ``block``.

    A position out of the region fails on one of the first, most extreme orientations (the Twin-Pantograph's
    default run: most at the 1st to 12th of 41), and a block costs it every orientation in it: blocks that
    start at one orientation and double cut the poses such a position costs from a whole block to about its
    first failure's index (1,231,777 to 1,082,499 poses for ``isoforce dextrous twin_pantograph``), and a
    position inside the region costs every orientation either way. Fixed by ``count`` and ``block`` alone:
    a position's poses still depend on it alone (not on the batches, the threads or ``face_test``'s split).

    Examples
    --------
    >>> list(_blocks(41, 16))
    [(1, 2), (2, 4), (4, 8), (8, 16), (16, 32), (32, 41)]
    """
    start, size = 1, 1
    while start < count:
        stop = min(start + min(size, block), count)
        yield start, stop
        start, size = stop, 2 * size


def _x_fastest(grid: GridSpec, mask: BoolArray | None = None) -> np.ndarray:
    """Flat indices of the grid's points (of ``mask``'s, shape ``grid.resolution``), ``x`` varying fastest.

    The order the positions are tested in: a batch then holds whole lines along ``x``, which share
    their ``y, z`` (a Twin-Pantograph computes its waists once per ``y, z``: ``pose_memo.fold_rows``).
    """
    shape = tuple(grid.resolution)
    order = np.arange(int(np.prod(shape))).reshape(shape).transpose(1, 2, 0).reshape(-1)
    return order if mask is None else order[mask.transpose(1, 2, 0).reshape(-1)]


def _mesh(grid: GridSpec) -> FloatArray:
    coords = grid.coordinates()
    return np.stack(np.meshgrid(*coords, indexing="ij"), -1).reshape(-1, 3)


def face_test(mechanism, grid: GridSpec, orientations: OrientationSet, *, chunk_poses: int = CHUNK_POSES,
              block: int = 16, cancelled: Callable[[], bool] | None = None, threads: bool = True) -> FaceTest:
    """``dextrous_region``'s test of the box's face points alone: whether (and where) its region is clipped.

    A default box that grows (``app.cli.dextrous``) needs no more of the boxes it leaves: their
    faces decide the growth, the interior would be tested again in the grown box. Pass the result
    to ``dextrous_region(..., faces=...)`` when the box is kept: its face points are then not
    tested twice, and the region is the same as without it.

    Parameters
    ----------
    mechanism, grid, orientations, chunk_poses, block, cancelled, threads
        As ``dextrous_region``'s.

    Returns
    -------
    FaceTest

    Examples
    --------
    >>> from kinematics import StewartPlatform
    >>> from metrics.dextrous_orientations import orientation_set
    >>> mech = StewartPlatform()
    >>> t = face_test(mech, box_grid((-0.02, -0.02, 0.22), (0.02, 0.02, 0.26), 3), orientation_set(mech, 0.1))
    >>> len(t.index), t.touched()
    (26, ((0, 0), (0, 1), (1, 0), (1, 1), (2, 0), (2, 1)))
    """
    _check(mechanism, grid, orientations, chunk_poses, block)
    start = time.perf_counter()
    index = _x_fastest(grid, _face_mask(tuple(grid.resolution)))
    reachable, inside, evaluated = _test_points(mechanism, _mesh(grid)[index], orientations, chunk_poses, block,
                                                None, cancelled, threads)
    return FaceTest(grid=grid, orientations=orientations, index=index, reachable=reachable, inside=inside,
                    poses_evaluated=evaluated, seconds=time.perf_counter() - start)


def dextrous_region(mechanism, grid: GridSpec, orientations: OrientationSet, *, chunk_poses: int = CHUNK_POSES,
                    block: int = 16, progress: Callable[[float], None] | None = None,
                    cancelled: Callable[[], bool] | None = None, faces: FaceTest | None = None,
                    threads: bool = True) -> DextrousRegion:
    """Which grid positions can hold every orientation sample (module doc: order, early exit, memory).

    Parameters
    ----------
    mechanism : Mechanism
        Task coordinates x, y, z plus (rx, ry, rz) or (rx, rz).
    grid : GridSpec
        Axes exactly x, y, z (``box_grid``), m.
    orientations : OrientationSet
        From ``orientation_set(mechanism, ...)``.
    chunk_poses : int
        Most poses in ``inverse``/``feasible`` calls at once (bounds the working memory).
    block : int
        Most orientations tested per pass over the surviving positions (the passes take 1, 2, 4, ...).
    progress : callable ``(float) -> None``, optional
        Called with the fraction of orientations done.
    cancelled : callable ``() -> bool``, optional
        Checked between calls; ``Cancelled`` is raised when it returns true.
    faces : FaceTest, optional
        ``face_test`` of this grid with these orientations: its points are taken from it, not
        tested again (the region, and ``poses_evaluated``, are the same; ``seconds`` counts theirs).
    threads : bool
        Run the calls on the maps' thread pool, ``metrics.chunk_pool`` (one at a time in this thread
        when false); the region is the same either way.

    Returns
    -------
    DextrousRegion

    Raises
    ------
    ValueError
        For a grid that is not over x, y, z, orientations in other coordinates, bad sizes, or
        ``faces`` of another grid or other orientations (not the same ``OrientationSet`` object).
    metrics.workspace.Cancelled
        When ``cancelled()`` says so.

    Examples
    --------
    >>> from kinematics import StewartPlatform
    >>> from metrics.dextrous_orientations import orientation_set
    >>> mech = StewartPlatform()
    >>> region = dextrous_region(mech, box_grid((-0.02, -0.02, 0.22), (0.02, 0.02, 0.26), 3),
    ...                          orientation_set(mech, math.radians(10)))
    >>> region.inside.shape, region.orientations.count
    ((3, 3, 3), 23)
    """
    _check(mechanism, grid, orientations, chunk_poses, block)
    if faces is not None and (faces.grid != grid or faces.orientations is not orientations):
        raise ValueError("faces must be face_test's result for this grid and these orientations")
    start = time.perf_counter()
    mesh = _mesh(grid)
    shape = tuple(grid.resolution)
    face_mask = _face_mask(shape)
    reachable, inside = np.zeros(len(mesh), bool), np.zeros(len(mesh), bool)
    tested = _x_fastest(grid, None if faces is None else ~face_mask)
    reachable[tested], inside[tested], evaluated = _test_points(mechanism, mesh[tested], orientations, chunk_poses,
                                                                block, progress, cancelled, threads)
    if faces is not None:
        reachable[faces.index], inside[faces.index] = faces.reachable, faces.inside
        evaluated += faces.poses_evaluated
    inside, reachable = inside.reshape(shape), reachable.reshape(shape)
    spacing = grid.spacing()
    volume, reachable_volume = indicator_volume(inside, spacing), indicator_volume(reachable, spacing)
    clipped, reachable_clipped = bool(np.any(inside & face_mask)), bool(np.any(reachable & face_mask))
    seconds = time.perf_counter() - start + (faces.seconds if faces is not None else 0.0)
    return DextrousRegion(grid=grid, inside=inside, reachable=reachable, orientations=orientations,
                          volume=volume, reachable_volume=reachable_volume, clipped=clipped,
                          poses_evaluated=evaluated, seconds=seconds, reachable_clipped=reachable_clipped)


def clipped_faces(inside: ArrayLike) -> tuple[tuple[int, int], ...]:
    """The faces of the box a boolean grid touches: ``(axis, side)`` pairs, side 0 the lower face, 1 the upper.

    Parameters
    ----------
    inside : array_like of bool, shape (i, j, k)

    Returns
    -------
    tuple of (int, int)
        In axis order, lower face first.

    Examples
    --------
    >>> m = np.zeros((4, 4, 4), bool); m[0, 1, 2] = m[1, 3, 1] = True
    >>> clipped_faces(m)
    ((0, 0), (1, 1))
    """
    mask = np.asarray(inside, dtype=bool)
    if mask.ndim != 3:
        raise ValueError(f"inside must be a 3D boolean grid, got shape {mask.shape}")
    out = []
    for axis in range(3):
        for side, index in ((0, 0), (1, -1)):
            if np.take(mask, index, axis=axis).any():
                out.append((axis, side))
    return tuple(out)


def grown_grid(grid: GridSpec, faces, factor: float = 1.0) -> GridSpec:
    """``grid`` with each face of ``faces`` (``clipped_faces``) moved out by ``factor`` times the box's span
    on that axis, rounded to whole cells: the spacing, and every old grid point, are kept.

    Parameters
    ----------
    grid : GridSpec
        Axes x, y, z (``box_grid``).
    faces : iterable of (int, int)
        ``(axis, side)``, side 0 the lower face, 1 the upper.
    factor : float
        How far, in spans of the old box (> 0).

    Returns
    -------
    GridSpec

    Examples
    --------
    >>> g = grown_grid(box_grid((0, 0, 0), (0.1, 0.1, 0.1), 3), [(2, 0), (0, 0), (0, 1)])
    >>> g.lower, g.upper, g.resolution
    ((-0.1, 0.0, -0.1), (0.2, 0.1, 0.1), (7, 3, 5))
    """
    if not factor > 0:
        raise ValueError(f"factor must be positive, got {factor!r}")
    lower, upper, res = list(grid.lower), list(grid.upper), list(grid.resolution)
    spacing = grid.spacing()
    for axis, side in sorted(set(faces)):
        cells = max(1, int(math.ceil(factor * (grid.resolution[axis] - 1) - 1e-9)))
        if side == 0:
            lower[axis] -= cells * spacing[axis]
        else:
            upper[axis] += cells * spacing[axis]
        res[axis] += cells
    return GridSpec(grid.axes, tuple(lower), tuple(upper), tuple(res), grid.fixed)


#: Bytes per grid point: positions (24), flat indices of the survivors (16), the two masks and
#: the face mask (3), ``indicator_volume``'s padded copies (~8), and for a figure the padded
#: float64 indicator (8) with VTK's copy of it (8): 67, rounded up.
BYTES_PER_POINT = 72


def region_estimate(mechanism, resolution, *, chunk_poses: int = CHUNK_POSES, copies: int = 1):
    """Memory of ``dextrous_region`` on a grid of ``resolution`` points per axis, before it runs.

    Parameters
    ----------
    mechanism : Mechanism
        Sizes the per-pose working memory (``metrics.budget.chunk_work_bytes``).
    resolution : sequence of 3 int
        Points per axis.
    chunk_poses : int
        Poses per call.
    copies : int
        Regions held at once (several devices compared).

    Returns
    -------
    metrics.budget.Estimate
        Pass to ``metrics.budget.check_fits``.

    Examples
    --------
    >>> from kinematics import StewartPlatform
    >>> region_estimate(StewartPlatform(), (10, 10, 10)).points
    1000
    """
    from .budget import Estimate, chunk_work_bytes, grid_points

    points = grid_points(resolution)
    per_point = BYTES_PER_POINT * copies
    fixed = chunk_poses * chunk_work_bytes(mechanism)
    what = f"a {' x '.join(str(int(r)) for r in resolution)} position grid"
    return Estimate(what=what, points=points, bytes=points * per_point + fixed, per_point=per_point, fixed=fixed)
