"""The 3D box map's boundary and iso-surfaces are smoothed (no voxel terraces), stay where the
grid put them to within a grid step, and keep their levels (issue 11 sec. 3). Headless."""
from __future__ import annotations

import numpy as np

from app import scenes
from app.scenes import workspace
from metrics.workspace import compute_map
from resources import load_preset


def _axis_aligned_share(mesh) -> float:
    """Share of the triangles whose normal is within 5 deg of a coordinate axis (terrace steps)."""
    normals = np.asarray(mesh.compute_normals(cell_normals=True, point_normals=False).cell_data["Normals"])
    return float(np.mean(np.abs(normals).max(axis=1) > np.cos(np.radians(5.0))))


def test_the_box_maps_contours_are_smoothed_within_a_grid_step_and_keep_their_levels():
    preset = load_preset("novint_falcon")
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution(25), ["isotropic_force"])
    parts = workspace._box_volume_parts(wmap, "isotropic_force")
    image = parts["image"]
    raw_hull = image.contour([0.5], scalars="edge", method="flying_edges")          # the same field, unsmoothed
    indicator_hull = image.contour([0.5], scalars="feasible", method="flying_edges")  # the 0/1 indicator's
    # The unsmoothed iso-surfaces: the same contour and cut, not smoothed.
    original = workspace._smoothed
    workspace._smoothed = lambda mesh: mesh
    try:
        raw_surfaces = workspace._iso_surfaces(parts["filled"], "isotropic_force", parts["levels"])
    finally:
        workspace._smoothed = original
    assert not np.isnan(np.asarray(raw_surfaces.points)).any()
    step = float(np.max(image.spacing))
    for raw, smooth in ((raw_hull, parts["hull"]), (raw_surfaces, parts["surfaces"])):
        assert smooth.n_points == raw.n_points
        # Every point stays within one grid step of where the contour put it.
        assert np.max(np.linalg.norm(np.asarray(smooth.points) - np.asarray(raw.points), axis=1)) < step
        # ... and within half a step of the unsmoothed surface (its nearest point, on any face).
        _, nearest = raw.find_closest_cell(np.asarray(smooth.points), return_closest_point=True)
        assert np.max(np.linalg.norm(np.asarray(smooth.points) - nearest, axis=1)) < 0.5 * step
    # The terraces are gone: far fewer faces lie flat along an axis than on the raw 0/1 contour.
    assert _axis_aligned_share(parts["hull"]) < 0.5 * _axis_aligned_share(indicator_hull)
    # Each iso-surface still carries its level exactly (the scalars are carried, not re-interpolated).
    np.testing.assert_array_equal(np.unique(parts["surfaces"].point_data["isotropic_force"]),
                                  np.unique(raw_surfaces.point_data["isotropic_force"]))


def test_every_box_iso_surface_gets_one_label_at_its_level():
    preset = load_preset("novint_falcon")
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution(25), ["isotropic_force"])
    parts = workspace._box_volume_parts(wmap, "isotropic_force")
    points, levels = scenes.iso_label_points(parts["surfaces"], "isotropic_force")
    # One label per level drawn (the cut at the edge interpolates a level to rounding only).
    drawn = [v for v in parts["levels"]
             if np.any(np.isclose(parts["surfaces"].point_data["isotropic_force"], v, rtol=1e-9, atol=0))]
    assert len(levels) == len(drawn) >= 2
    np.testing.assert_allclose(levels, drawn, rtol=1e-9)
    assert points.shape == (len(levels), 3)
