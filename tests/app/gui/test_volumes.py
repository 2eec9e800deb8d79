"""The Qt-free helpers of 3D box maps (``app.gui.volumes``) against the compute layer.

Slices are checked element for element against the volume ``compute_map`` returns and their
statistics against ``metrics.workspace.statistics`` of the same plane computed as a 2D map
(an independent run of the compute layer on that plane's grid); the workspace volume against
a count of feasible points; joints against the model's forward kinematics.
"""
from __future__ import annotations

import sys

import numpy as np
import pytest

from app.gui.volumes import (
    coarse_volume,
    comparison_problem,
    parse_joints,
    point_of_joints,
    slice_grid,
    volume_slice,
    workspace_size,
)
from kinematics.units import joints_to_si
from metrics.workspace import compute_map
from resources import load_preset

QUANTITIES = ("isotropic_force", "condition_number", "bottleneck")


@pytest.fixture(scope="module")
def falcon():
    preset = load_preset("novint_falcon")
    grid = preset.grid.with_resolution((13, 11, 9))
    return preset, compute_map(preset.mechanism, grid, QUANTITIES)


def test_helpers_import_no_qt():
    assert "app.gui.volumes" in sys.modules
    import app.gui.volumes as v
    assert not any(name.startswith("PySide6") for name in vars(v))


@pytest.mark.parametrize("axis", ["x", "y", "z"])
def test_a_plane_of_the_volume_is_the_volume_sliced_and_equals_a_2d_map_of_that_plane(falcon, axis):
    preset, wmap = falcon
    grid = wmap.grid
    k = grid.axes.index(axis)
    coords = grid.coordinates()[k]
    i = len(coords) // 2
    # A position between two planes, nearer plane i: the nearest plane is shown.
    value = coords[i] + 0.3 * (coords[1] - coords[0])
    plane = volume_slice(wmap, axis, value)
    assert dict(plane.grid.fixed)[axis] == coords[i]
    assert plane.grid.axes == tuple(a for a in grid.axes if a != axis)
    index = tuple(i if j == k else slice(None) for j in range(3))
    np.testing.assert_array_equal(plane.feasible, wmap.feasible[index])
    for q in QUANTITIES:
        np.testing.assert_array_equal(plane.values[q], wmap.values[q][index])
    # The compute layer's own 2D map of that plane: same points, same values, same statistics.
    direct = compute_map(preset.mechanism, slice_grid(grid, axis, value), QUANTITIES)
    np.testing.assert_array_equal(direct.feasible, plane.feasible)
    np.testing.assert_array_equal(direct.values["isotropic_force"], plane.values["isotropic_force"])
    for fig in ("min", "max", "mean", "median", "count"):
        a, b = getattr(direct.stats["isotropic_force"], fig), getattr(plane.stats["isotropic_force"], fig)
        # Streamed (chunked) against one-pass sums: equal to rounding of a sum of ~100 terms.
        assert a == pytest.approx(b, rel=1e-12, abs=0), fig
    assert direct.stats["isotropic_force"].argmin == plane.stats["isotropic_force"].argmin


def test_a_difference_volume_is_sliced_along(falcon):
    _, wmap = falcon
    extra = wmap.values["isotropic_force"] * 2.0
    plane = volume_slice(wmap, "z", 0.1, extra={"_d": extra})
    np.testing.assert_array_equal(plane.values["_d"], 2.0 * plane.values["isotropic_force"])
    with pytest.raises(ValueError, match="axes"):
        volume_slice(wmap, "q", 0.1)


def test_workspace_volume_is_feasible_points_times_the_cell(falcon):
    preset, wmap = falcon
    kind, value, unit = workspace_size(preset.mechanism, wmap.grid, wmap.feasible_points)
    dx, dy, dz = (np.diff(c)[0] * 100.0 for c in wmap.grid.coordinates())      # cm
    assert (kind, unit) == ("volume", "cm^3")
    assert value == pytest.approx(np.count_nonzero(wmap.feasible) * dx * dy * dz, rel=1e-12)


def test_coarse_volume_keeps_the_box_and_caps_each_axis():
    grid = load_preset("novint_falcon").grid.with_resolution((60, 60, 60))
    coarse = coarse_volume(grid)
    assert coarse.resolution == (24, 24, 24) and (coarse.lower, coarse.upper) == (grid.lower, grid.upper)
    small = grid.with_resolution((10, 30, 5))
    assert coarse_volume(small).resolution == (10, 24, 5)


def test_maps_of_other_coordinates_or_classes_are_not_compared(falcon):
    preset, wmap = falcon
    inverse3 = load_preset("inverse3_prototype")
    fivebar = load_preset("fivebar_singh")
    i3 = compute_map(inverse3.mechanism, inverse3.grid.with_resolution(9), QUANTITIES[:2])
    fb = compute_map(fivebar.mechanism, fivebar.grid.with_resolution(9), QUANTITIES[:2])
    q = "isotropic_force"
    assert comparison_problem(wmap, preset.mechanism, wmap, preset.mechanism, q) is None
    box_vs_slice = comparison_problem(wmap, preset.mechanism, i3, inverse3.mechanism, q)
    assert "different coordinates" in box_vs_slice and "x (mm), y (mm), z (mm)" in box_vs_slice
    assert "x (mm), z (mm)" in box_vs_slice
    assert "different coordinates" in comparison_problem(i3, inverse3.mechanism, fb, fivebar.mechanism, q)
    # Two (x, z) slices of different devices compare (each in its own plane).
    omni = load_preset("phantom_omni")
    om = compute_map(omni.mechanism, omni.grid.with_resolution(9), QUANTITIES)
    assert comparison_problem(i3, inverse3.mechanism, om, omni.mechanism, q) is None
    assert "no " in comparison_problem(om, omni.mechanism, i3, inverse3.mechanism, "bottleneck")


def test_typed_joints_give_the_models_forward_kinematics_point_and_bad_ones_a_clear_error():
    mech = load_preset("novint_falcon").mechanism
    x0 = np.array([0.01, -0.02, 0.11])
    q, ok = mech.inverse(x0)
    assert bool(ok)
    text = ", ".join(repr(float(v)) for v in np.degrees(q))     # round-trip exact decimal text
    q_typed = parse_joints(text, mech)
    np.testing.assert_allclose(q_typed, joints_to_si(mech, np.degrees(q)), rtol=0, atol=0)
    x = point_of_joints(mech, q_typed)
    expected, _ = mech.forward(q_typed)
    np.testing.assert_array_equal(x, expected)
    # FK(IK(x0)) returns x0 up to the Newton tolerance of the delta's FK (well below a micrometre).
    np.testing.assert_allclose(x, x0, atol=1e-9)
    with pytest.raises(ValueError, match=r"3 comma-separated numbers: q1 \(deg\)"):
        parse_joints("1, 2", mech)
    with pytest.raises(ValueError, match="does not assemble"):
        point_of_joints(mech, np.radians([180.0, 0.0, 0.0]))
