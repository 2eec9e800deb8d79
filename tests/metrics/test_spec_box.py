"""The largest held box (metrics.spec_box) against closed forms and a brute-force check of its poses.

References: two stand-in mechanisms whose feasible sets are known in closed form (a ball of
positions; a box of positions with a tilt limit), where the largest box of a shape follows by
hand; and for the Twin-Pantograph prototype the found box's corners and grid re-tested pose by
pose through ``inverse`` and ``feasible`` directly, with a slightly larger box that must fail.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from metrics.dextrous_orientations import orientation_set
from metrics.spec_box import (
    DEFAULT_RESOLUTION,
    TABLE_X_ANGLE,
    TABLE_X_HALF_WIDTHS,
    box_positions,
    largest_held_box,
)
from resources import load_preset

SHAPE = np.array(TABLE_X_HALF_WIDTHS)


class Ball:
    """Positions x, y, z feasible inside a ball of radius ``r`` about ``centre``."""

    task_names = ("x", "y", "z")

    def __init__(self, r, centre=(0.0, 0.0, 0.0)):
        self.r, self.centre = r, np.asarray(centre, float)

    def inverse(self, x):
        x = np.asarray(x, float)
        return x.copy(), np.linalg.norm(x - self.centre, axis=-1) <= self.r

    def feasible(self, q, x=None):
        return np.ones(np.shape(q)[:-1], bool)


class TiltedPen:
    """A pen (x, y, z, rx, rz): positions within ``|x_i| <= a_i``, tilt (the norm of (rx, rz)) within ``limit``."""

    task_names = ("x", "y", "z", "rx", "rz")

    def __init__(self, a, limit):
        self.a, self.limit = np.asarray(a, float), limit

    def inverse(self, x):
        x = np.asarray(x, float)
        return x.copy(), np.all(np.abs(x[..., :3]) <= self.a, axis=-1)

    def feasible(self, q, x=None):
        return np.linalg.norm(np.asarray(q)[..., 3:], axis=-1) <= self.limit + 1e-12


def test_box_in_a_ball_is_limited_by_its_corners():
    # The box centre +- s h fits the ball of radius r exactly when its corners do: s* = r / |h|.
    r = 0.1
    box = largest_held_box(Ball(r, (0.0, 0.0, 0.2)), (0.0, 0.0, 0.2), SHAPE)
    exact = r / np.linalg.norm(SHAPE)
    assert box.orientations is None
    assert box.scale <= exact < box.failed_scale <= box.scale + DEFAULT_RESOLUTION
    assert np.linalg.norm(box.failure[:3] - (0.0, 0.0, 0.2)) > r
    assert np.allclose(box.half_widths, box.scale * SHAPE)


def test_box_of_a_pen_with_a_tilt_limit():
    a = np.array([0.08, 0.03, 0.05])
    # Tilts within 50 deg: every +-45 deg sample passes, the positions decide: s* = min a_i / h_i.
    box = largest_held_box(TiltedPen(a, math.radians(50)), np.zeros(3), SHAPE)
    exact = np.min(a / SHAPE)
    assert box.scale <= exact < box.failed_scale <= box.scale + DEFAULT_RESOLUTION
    assert box.orientations.count == orientation_set(TiltedPen(a, 1.0), TABLE_X_ANGLE).count
    # Tilts within 40 deg: the centre itself fails at +-45 deg, so no box holds.
    none = largest_held_box(TiltedPen(a, math.radians(40)), np.zeros(3), SHAPE)
    assert none.scale == 0.0 and none.failed_scale == 0.0
    assert np.linalg.norm(none.failure[3:]) > math.radians(40)
    # ... and at +-30 deg it holds again.
    assert largest_held_box(TiltedPen(a, math.radians(40)), np.zeros(3), SHAPE,
                            angle=math.radians(30)).scale == box.scale


def test_a_box_held_everywhere_stops_at_the_largest_scale():
    box = largest_held_box(Ball(1e9), np.zeros(3), SHAPE, max_scale=8.0)
    assert box.scale == 8.0 and box.failed_scale is None and box.failure is None


def test_box_positions_are_the_grid_with_its_corners_first():
    pts = box_positions((1.0, 2.0, 3.0), (0.1, 0.2, 0.3), 5)
    assert pts.shape == (125, 3) and len(np.unique(pts, axis=0)) == 125
    corners = {(1.0 + i * 0.1, 2.0 + j * 0.2, 3.0 + k * 0.3) for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)}
    assert {tuple(p) for p in pts[:8]} == corners
    assert np.allclose(pts.min(axis=0), (0.9, 1.8, 2.7)) and np.allclose(pts.max(axis=0), (1.1, 2.2, 3.3))


@pytest.mark.parametrize("bad", [dict(points=1), dict(resolution=0.0), dict(shape=(0.1, 0.0, 0.1))])
def test_bad_arguments_are_refused(bad):
    args = dict(shape=SHAPE) | bad
    with pytest.raises(ValueError):
        largest_held_box(Ball(0.1), np.zeros(3), **args)


def test_planar_task_is_refused():
    class Planar:
        task_names = ("x", "y")
    with pytest.raises(ValueError, match="x, y and z"):
        largest_held_box(Planar(), np.zeros(3))


# -- the prototype: brute force over the found box and a slightly larger one ------------------------
PROTO = load_preset("twin_pantograph_prototype")


def _poses(centre, half, points, coords):
    """Every grid position with every orientation, built here (x, y, z, rx, rz)."""
    axes = [np.linspace(c - h, c + h, points) for c, h in zip(centre, half)]
    pos = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    return np.concatenate([np.repeat(pos, len(coords), axis=0), np.tile(coords, (len(pos), 1))], axis=1)


def _ok(mech, poses):
    q, reach = mech.inverse(poses)
    return reach & mech.feasible(q, poses)


@pytest.fixture(scope="module")
def proto_box():
    mech = PROTO.mechanism
    return mech, largest_held_box(mech, np.array(PROTO.pose)[:3], SHAPE)


def test_prototype_box_holds_at_every_sample_and_a_larger_one_fails(proto_box):
    mech, box = proto_box
    coords = orientation_set(mech, TABLE_X_ANGLE).coordinates
    assert mech.task_names == ("x", "y", "z", "rx", "rz") and len(coords) == box.orientations.count
    # Every pose of the found box (9^3 positions x 95 orientations), corners included, holds.
    assert _ok(mech, _poses(box.centre, box.half_widths, box.points, coords)).all()
    # 1 % larger: some pose fails, and the module's recorded failure is one of the failing poses.
    larger = _poses(box.centre, 1.01 * box.half_widths, box.points, coords)
    assert not _ok(mech, larger).all()
    assert not _ok(mech, box.failure[None])[0]
    assert box.scale < box.failed_scale <= box.scale + DEFAULT_RESOLUTION < 1.01 * box.scale
    # The limit is a corner: the failing pose is at the corner of the failing box.
    assert np.allclose(np.abs(box.failure[:3] - box.centre), box.failed_scale * SHAPE, rtol=1e-12)


def test_prototype_box_is_set_by_a_corner_at_every_grid(proto_box):
    # The corners are in every grid, and they decide: a coarser grid finds the same scale.
    mech, box = proto_box
    coarse = largest_held_box(mech, box.centre, SHAPE, points=3)
    assert coarse.scale == box.scale and coarse.failed_scale == box.failed_scale
