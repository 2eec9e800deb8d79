"""metrics.dextrous: the semi-dextrous workspace (paper 001 sec. V, Figs. 13-14).

The region is checked against a brute force that builds every pose on its own (scipy's
rotation vectors, one ``inverse``/``feasible`` call per pose, no ordering, no early exit), the
volume estimator against a ball's exact volume, and the paper's qualitative claims on the
comparison footprints of ``docs/dextrous/`` (and on the Inoue platform when its preset exists).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from metrics.dextrous import (
    box_grid,
    clipped_faces,
    dextrous_region,
    face_test,
    grown_grid,
    indicator_volume,
    region_estimate,
)
from metrics.dextrous_orientations import DEFAULT_STEP, PEN_AXIS, orientation_set
from metrics.orientations import tip_angle
from metrics.workspace import Cancelled
from resources import list_presets, load_preset

ROOT = Path(__file__).resolve().parents[2]
STEWART = ROOT / "docs" / "dextrous" / "stewart_fig13.toml"
TWIN = ROOT / "docs" / "dextrous" / "twin_pantograph_fig13.toml"
DEG = math.pi / 180


def _brute_force(mech, grid, rotations) -> tuple[np.ndarray, np.ndarray]:
    """(inside, reachable) by testing every position with every rotation, one pose per call."""
    names = mech.task_names
    coords = grid.coordinates()
    inside = np.zeros(grid.resolution, bool)
    reachable = np.zeros(grid.resolution, bool)
    for idx in np.ndindex(*grid.resolution):
        oks = []
        for rot in rotations:
            x = np.zeros(len(names))
            x[[names.index(a) for a in "xyz"]] = [coords[k][idx[k]] for k in range(3)]
            if names[3:] == ("rx", "ry", "rz"):
                x[3:] = Rotation.from_matrix(rot).as_rotvec()
            else:     # (rx, rz): the rotation without roll taking y to R y, as a rotation vector
                y, d = np.array(PEN_AXIS), rot[:, 1]
                axis = np.cross(y, d)
                angle = math.atan2(np.linalg.norm(axis), y @ d)
                vec = axis / np.linalg.norm(axis) * angle if angle > 0 else np.zeros(3)
                x[3:] = vec[[0, 2]]
            q, ok = mech.inverse(x)
            oks.append(bool(ok) and bool(mech.feasible(q, x)))
        inside[idx] = all(oks)
        reachable[idx] = oks[0]
    return inside, reachable


@pytest.mark.parametrize("case", ["stewart", "twin_5dof", "twin_6dof"])
def test_region_equals_brute_force(case):
    if case == "stewart":
        mech = load_preset(str(STEWART)).mechanism
        grid = box_grid((-0.06, -0.06, 0.08), (0.06, 0.06, 0.16), 4)     # straddles the lens (docs/dextrous.md)
        orient = orientation_set(mech, 20 * DEG, rings=1, rolls=3)
    else:
        mech = load_preset(str(TWIN)).mechanism
        if case == "twin_5dof":
            mech = mech.replace(redundant_waist="active", roll_actuator="passive")
        grid = box_grid((-0.16, -0.08, 0.02), (0.16, 0.08, 0.18), 5 if case == "twin_5dof" else 4)
        orient = orientation_set(mech, 30 * DEG, rings=1, rolls=3)
    region = dextrous_region(mech, grid, orient, chunk_poses=37, block=4)      # odd sizes: every seam exercised
    inside, reachable = _brute_force(mech, grid, orient.rotations)
    assert inside.any() and (~inside).any()                                    # the test can tell them apart
    np.testing.assert_array_equal(region.inside, inside)
    np.testing.assert_array_equal(region.reachable, reachable)
    assert region.poses_evaluated < grid.resolution[0] ** 3 * orient.count      # early exit saved work


def test_batch_sizes_do_not_change_the_region():
    mech = load_preset(str(TWIN)).mechanism
    grid = box_grid((-0.16, -0.12, 0.0), (0.16, 0.12, 0.2), 9)
    orient = orientation_set(mech, 30 * DEG)
    a = dextrous_region(mech, grid, orient)
    b = dextrous_region(mech, grid, orient, chunk_poses=101, block=1)
    np.testing.assert_array_equal(a.inside, b.inside)
    np.testing.assert_array_equal(a.reachable, b.reachable)
    # On the thread pool (several calls in flight) or one call at a time here: the same region and work.
    for threads in (True, False):
        c = dextrous_region(mech, grid, orient, chunk_poses=997, threads=threads)
        np.testing.assert_array_equal(c.inside, a.inside)
        np.testing.assert_array_equal(c.reachable, a.reachable)
        assert c.poses_evaluated == a.poses_evaluated


@pytest.mark.parametrize("key", ["stewart", "twin"])
def test_orientation_set_is_within_the_bound_and_holds_roll_pitch_yaw(key):
    mech = load_preset(str(STEWART if key == "stewart" else TWIN)).mechanism
    angle = 30 * DEG
    s = orientation_set(mech, angle)
    np.testing.assert_allclose(s.rotations[0], np.eye(3), atol=0)
    tips = tip_angle(s.rotations, tool_axis=PEN_AXIS)
    # Tips are built as n * (angle / N) <= angle; the float tip of a matrix is within ~1e-15 rad.
    assert tips.max() == pytest.approx(angle, abs=1e-12)
    # The roll about the pen is the angle of the rotation left after undoing the tip: within +-angle.
    tilts = Rotation.from_rotvec(np.cross(np.array(PEN_AXIS), s.rotations[:, :, 1])
                                 / np.maximum(np.sin(tips), 1e-300)[:, None] * tips[:, None])
    roll = (tilts.inv() * Rotation.from_matrix(s.rotations)).magnitude()
    assert roll.max() <= angle + 1e-12
    # Roll, pitch and yaw of +-angle about x, y, z are samples (y is the roll, free for the 5-DOF pen).
    axes = range(3) if not s.roll_free else (0, 2)
    for k in axes:
        for sign in (1, -1):
            want = Rotation.from_rotvec(sign * angle * np.eye(3)[k]).as_matrix()
            assert np.min(np.abs(s.rotations - want).max(axis=(1, 2))) < 1e-12, (k, sign)
    # No repeats: distinct matrices only.
    flat = s.rotations.reshape(len(s.rotations), 9)
    gaps = np.abs(flat[:, None] - flat[None]).max(-1) + np.eye(len(flat))
    assert gaps.min() > 1e-9


def test_default_sampling_is_nested_so_the_region_shrinks_with_the_angle():
    """With rings and rolls every 10 deg the 10-deg samples are among the 20-deg ones, which are among the
    30-deg ones (same ring spacing, so the same azimuths per ring, and pure rotations at every ring's
    angle): a position that holds the larger set holds the smaller. The same rotation may be computed
    by two formulas (1e-16 apart), so a pose within rounding of a limit could differ; none is here."""
    mech = load_preset(str(STEWART)).mechanism
    grid = box_grid((-0.08, -0.08, 0.06), (0.08, 0.08, 0.2), 9)
    sets = [orientation_set(mech, a * DEG) for a in (10, 20, 30)]
    for small, big in zip(sets, sets[1:]):
        d = np.abs(small.rotations[:, None] - big.rotations[None]).max(axis=(2, 3))
        assert d.min(axis=1).max() < 1e-12                    # every small sample is a big sample
    regions = [dextrous_region(mech, grid, s) for s in sets]
    for small, big in zip(regions, regions[1:]):
        assert not (big.inside & ~small.inside).any()
        assert big.volume.points < small.volume.points
    assert DEFAULT_STEP == pytest.approx(10 * DEG)


@pytest.mark.parametrize("res", [17, 24, 33])
@pytest.mark.parametrize("centre", [(0.0, 0.0, 0.0), (0.013, -0.021, 0.007)])
def test_volume_of_a_ball_is_within_the_boundary_cell_estimate(res, centre):
    radius = 0.08
    c = [np.linspace(-0.1, 0.1, res)] * 3
    x, y, z = np.meshgrid(*c, indexing="ij")
    ball = (x - centre[0]) ** 2 + (y - centre[1]) ** 2 + (z - centre[2]) ** 2 <= radius ** 2
    h = 0.2 / (res - 1)
    v = indicator_volume(ball, (h, h, h))
    exact = 4 / 3 * math.pi * radius ** 3
    assert abs(v.value - exact) <= v.error
    assert v.error < 0.25 * exact             # and the estimate is not vacuous


def test_volume_counts_and_grid_faces():
    inside = np.ones((4, 4, 4), bool)                # the whole box: every point is on a face
    v = indicator_volume(inside, (0.5, 0.5, 0.5))
    assert (v.points, v.boundary_points, v.value, v.error) == (64, 56, 8.0, 3.5)


def test_stewart_void_from_the_leg_retraction_limit():
    """Paper 001 Fig. 13: the Stewart platform's central void is due to its legs' retraction limit.

    On the axis (x = y = 0, zero orientation) the six legs have one length, ``sqrt(z^2 + d^2)`` with
    ``d`` the horizontal distance between a leg's base and platform joints, so the axis is reachable
    only from ``z_min = sqrt(min_leg^2 - d^2)`` up; off the axis the legs lean and some get longer, so
    points beside the axis and below ``z_min`` are reachable: a void in the centre, under the platform.
    """
    mech = load_preset(str(STEWART)).mechanism
    grid = box_grid((-0.12, -0.12, 0.0), (0.12, 0.12, 0.24), 25)
    region = dextrous_region(mech, grid, orientation_set(mech, 30 * DEG))
    b, p = mech.base_joints(), mech.platform_joints()
    d = np.hypot(*(p[0, :2] - b[0, :2]))
    z_min = math.sqrt(mech.params.min_leg ** 2 - d ** 2)
    z = grid.coordinates()[2]
    c = 12                                                   # x = y = 0
    axis = region.reachable[c, c, :]
    assert z[np.argmax(axis)] == z[z >= z_min - 1e-12][0]    # the axis starts at the first grid z above z_min
    below = z < z_min
    r = region.reachable
    ring = [k for k in np.flatnonzero(below)
            if r[:c, c, k].any() and r[c + 1:, c, k].any() and r[c, :c, k].any() and r[c, c + 1:, k].any()]
    assert len(ring) >= 3                                     # reachable all round the empty axis: the void
    # Its cause: on the axis below z_min every leg is shorter than min_leg (and no other limit is hit).
    x = np.zeros((len(ring), 6))
    x[:, 2] = z[ring]
    q, ok = mech.inverse(x)
    assert ok.all() and (q < mech.params.min_leg).all()
    assert mech.replace(min_leg=0.5 * mech.params.min_leg).feasible(q, x).all()
    # The semi-dextrous region lies above the void (Fig. 13's region with the void beneath it).
    pos = region.positions()
    assert len(pos) and pos[:, 2].min() >= z_min - grid.spacing()[2]


def test_stewart_region_is_much_smaller_than_the_twin_pantographs():
    """Paper 001 sec. V: the Stewart platform's semi-dextrous volume "is much less than the others"."""
    angle = 30 * DEG
    out = {}
    for key, path, box in (("stewart", STEWART, ((-0.12, -0.12, 0.0), (0.12, 0.12, 0.24))),
                           ("twin", TWIN, ((-0.2, -0.2, 0.0), (0.2, 0.2, 0.24)))):
        mech = load_preset(str(path)).mechanism
        out[key] = dextrous_region(mech, box_grid(*box, 17), orientation_set(mech, angle))
    s, t = out["stewart"], out["twin"]
    assert not s.clipped and not t.clipped
    # Less than half, even with each volume moved by its grid-error estimate against the claim.
    assert s.volume.value + s.volume.error < 0.5 * (t.volume.value - t.volume.error)


def _ujoint_devices():
    """The Twin-Pantograph's footprint, and the Inoue platform's once its model is installed
    (``kinematics.inoue``, preset ``inoue_platform``, built alongside this module)."""
    devices = [("twin_pantograph_fig13", str(TWIN))]
    if "inoue_platform" in list_presets():
        devices.append(("inoue_fig13", str(ROOT / "docs" / "dextrous" / "inoue_fig13.toml")))
    return devices


@pytest.mark.parametrize("name,key", _ujoint_devices())
def test_ujoint_limit_shrinks_the_region(name, key):
    """Paper 001 Fig. 14: U-joints limited to +-85 deg shrink the Inoue platform's and the
    Twin-Pantograph's regions (Fig. 13: unconstrained; 90 deg is the largest our models accept)."""
    preset = load_preset(key)
    base = preset.mechanism
    free, limited = (base.replace_display(ujoint_limit=v) for v in (90.0, 85.0))
    box = _box(preset)
    grid = box_grid(*box, 15)
    a, b = (dextrous_region(m, grid, orientation_set(m, 30 * DEG)) for m in (free, limited))
    assert not (b.inside & ~a.inside).any()                     # a stricter limit never adds a point
    lost = a.inside & ~b.inside
    assert lost.sum() >= 0.05 * a.inside.sum()                  # and it takes a visible part away
    if name.startswith("twin"):
        # Each lost point is lost to a U-joint bend between 85 and 90 deg at some sample.
        pos = np.stack([c[i] for c, i in zip(grid.coordinates(), np.nonzero(lost))], -1)
        coords = a.orientations.coordinates
        for p in pos[:20]:
            x = np.concatenate([np.repeat(p[None], len(coords), 0), coords], -1)
            bends = limited.bend_angles(x).max(-1)
            assert np.any((bends > 85 * DEG) & (bends <= 90 * DEG + 1e-12))


def _box(preset):
    from app.cli.dextrous import default_box
    return default_box(preset)


def test_bad_input_names_the_argument():
    mech = load_preset(str(STEWART)).mechanism
    with pytest.raises(ValueError, match="angle"):
        orientation_set(mech, 0.0)
    with pytest.raises(ValueError, match="angle"):
        orientation_set(mech, 2.0)
    with pytest.raises(ValueError, match="task coordinates"):
        orientation_set(load_preset("fivebar_singh").mechanism, 0.5)
    with pytest.raises(ValueError, match="grid"):
        from kinematics.grid import GridSpec
        dextrous_region(mech, GridSpec(("x", "z"), (0, 0), (1, 1), (3, 3), (("y", 0.0),)), orientation_set(mech, 0.5))
    with pytest.raises(ValueError, match="orientations"):
        twin = load_preset("twin_pantograph").mechanism
        dextrous_region(mech, box_grid((0, 0, 0), (1, 1, 1), 3), orientation_set(twin, 0.5))
    with pytest.raises(ValueError, match="chunk_poses"):
        dextrous_region(mech, box_grid((0, 0, 0), (1, 1, 1), 3), orientation_set(mech, 0.5), chunk_poses=0)


def test_cancel_and_progress():
    mech = load_preset(str(STEWART)).mechanism
    grid = box_grid((-0.06, -0.06, 0.08), (0.06, 0.06, 0.16), 5)
    seen = []
    dextrous_region(mech, grid, orientation_set(mech, 20 * DEG), progress=seen.append)
    assert seen[-1] == 1.0 and seen == sorted(seen)
    with pytest.raises(Cancelled):
        dextrous_region(mech, grid, orientation_set(mech, 20 * DEG), cancelled=lambda: True)


def test_memory_estimate_grows_with_the_grid():
    mech = load_preset(str(STEWART)).mechanism
    small, big = region_estimate(mech, (10, 10, 10)), region_estimate(mech, (20, 20, 20))
    assert big.bytes - small.bytes == 7000 * small.per_point
    assert small.fixed == big.fixed > 0


def test_clipped_faces_and_grown_grid_keep_the_spacing_and_every_point():
    grid = box_grid((-0.1, -0.05, 0.0), (0.1, 0.05, 0.2), (5, 3, 9))
    inside = np.zeros(grid.resolution, bool)
    inside[0, 1, 4] = inside[2, 2, 8] = True                          # lower x face, upper y and z faces
    faces = clipped_faces(inside)
    assert faces == ((0, 0), (1, 1), (2, 1))
    big = grown_grid(grid, faces)
    assert big.lower == pytest.approx((-0.3, -0.05, 0.0)) and big.upper == pytest.approx((0.1, 0.15, 0.4))
    assert big.resolution == (9, 5, 17)
    np.testing.assert_allclose(big.spacing(), grid.spacing(), rtol=1e-12)
    old, new = grid.coordinates(), big.coordinates()
    for a, b in zip(old, new):                                          # the old grid points are grid points
        assert np.min(np.abs(a[:, None] - b[None]), axis=1).max() < 1e-12
    assert clipped_faces(np.zeros((3, 3, 3), bool)) == ()
    with pytest.raises(ValueError, match="factor"):
        grown_grid(grid, faces, factor=0.0)


def test_reachable_clipped_is_its_own_flag():
    """A box inside the Stewart footprint's reach but around its semi-dextrous lens: the reachable set
    touches the box, the region does not; each flag says so for its own volume."""
    mech = load_preset(str(STEWART)).mechanism
    grid = box_grid((-0.08, -0.08, 0.06), (0.08, 0.08, 0.2), 9)
    region = dextrous_region(mech, grid, orientation_set(mech, 30 * DEG))
    assert region.inside.any()
    assert region.reachable_clipped and not region.clipped


def test_twin_is_clearly_larger_than_inoue_at_85_deg():
    """Paper 001 Fig. 14: "The Twin-Pantograph's workspace is clearly larger" (U-joints +-85 deg). On the
    comparison footprints, with both volumes moved by their grid-error estimates against the claim."""
    out = {}
    for key, path in (("twin", TWIN), ("inoue", ROOT / "docs" / "dextrous" / "inoue_fig13.toml")):
        mech = load_preset(str(path)).mechanism
        out[key] = dextrous_region(mech, box_grid((-0.2, -0.2, 0.0), (0.2, 0.2, 0.24), 17),
                                   orientation_set(mech, 30 * DEG))
    t, i = out["twin"], out["inoue"]
    assert not t.clipped and not i.clipped
    assert t.volume.value - t.volume.error > 1.5 * (i.volume.value + i.volume.error)    # 1828 > 1.5 x 1022 cm^3


def test_the_footprint_twin_is_the_same_pen_under_the_adopted_reading():
    """Issue 23 sec. 1 adopts ``ujoint_lever = 1.0`` (each U-joint l6 from the pen's centre). The Fig. 13
    footprint is a physical pen, its U-joints 60 mm apart (half the 120 mm base): under the adopted
    reading that is l6 = 30 mm, and the region is the same grid point for grid point."""
    base = load_preset(str(TWIN)).mechanism
    adopted = base.replace_display(pen_length=30.0, ujoint_lever=1.0)
    grid = box_grid((-0.16, -0.12, 0.0), (0.16, 0.12, 0.2), 9)
    a, b = (dextrous_region(m, grid, orientation_set(m, 30 * DEG)) for m in (base, adopted))
    assert a.inside.any()
    np.testing.assert_array_equal(a.inside, b.inside)
    np.testing.assert_array_equal(a.reachable, b.reachable)


@pytest.mark.parametrize("box", [((-0.16, -0.12, 0.0), (0.16, 0.12, 0.2)), ((-0.5, -0.5, -0.3), (0.5, 0.5, 0.6))])
def test_face_test_then_the_interior_is_the_whole_region(box):
    """``face_test`` finds the faces the whole region touches, and ``dextrous_region(faces=...)`` is the region
    (masks and pose count) computed on the whole grid at once: once on a box the region is clipped by, once
    on one that holds it."""
    mech = load_preset(str(TWIN)).mechanism
    grid = box_grid(*box, 9)
    orient = orientation_set(mech, 30 * DEG)
    whole = dextrous_region(mech, grid, orient)
    faces = face_test(mech, grid, orient, chunk_poses=101)              # another batch size: the same results
    assert faces.touched() == clipped_faces(whole.inside)
    part = dextrous_region(mech, grid, orient, faces=faces)
    np.testing.assert_array_equal(part.inside, whole.inside)
    np.testing.assert_array_equal(part.reachable, whole.reachable)
    assert (part.poses_evaluated, part.clipped, part.reachable_clipped) == (
        whole.poses_evaluated, whole.clipped, whole.reachable_clipped)
    assert whole.inside.any() and bool(faces.touched()) == whole.clipped


def test_face_test_of_another_grid_or_orientations_is_refused():
    mech = load_preset(str(TWIN)).mechanism
    grid = box_grid((-0.16, -0.12, 0.0), (0.16, 0.12, 0.2), 4)
    orient = orientation_set(mech, 30 * DEG)
    faces = face_test(mech, grid, orient)
    with pytest.raises(ValueError, match="face_test"):
        dextrous_region(mech, box_grid((-0.16, -0.12, 0.0), (0.16, 0.12, 0.2), 5), orient, faces=faces)
    with pytest.raises(ValueError, match="face_test"):
        dextrous_region(mech, grid, orientation_set(mech, 20 * DEG), faces=faces)
