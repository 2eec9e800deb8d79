"""``app.logic.map_range.fit_grid``: the map's range fitted to a design's workspace (issue 26 sec. 6).

Reference: the compute layer's feasibility (``compute_map``) over a box three times the fitted
range, its connected regions that the fitted range meets (a region apart from it, such as the
Falcon's mirror image below its base, is another workspace the fit does not look for).
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from app.logic.map_range import NoWorkspace, fit_grid
from kinematics.grid import GridSpec
from metrics.workspace import compute_map
from resources import load_preset


def _feasible_points(mechanism, grid, lo, hi, n):
    span = hi - lo
    big = GridSpec(grid.axes, tuple(lo - span), tuple(hi + span), (n,) * len(grid.axes), grid.fixed)
    wmap = compute_map(mechanism, big, ["condition_number"], keep=True)
    ix = [mechanism.task_names.index(a) for a in grid.axes]
    points = big.points(mechanism.task_names)[..., ix]
    inside = np.all((points >= lo - 1e-12) & (points <= hi + 1e-12), axis=-1)
    # Regions connected through any neighbour (faces, edges and corners: a thin tip between samples).
    labels, _ = ndimage.label(wmap.feasible, structure=np.ones((3,) * len(grid.axes)))
    met = np.unique(labels[wmap.feasible & inside])
    return points[np.isin(labels, met[met > 0])]


@pytest.mark.parametrize("device, change, n", [
    ("novint_falcon", {}, 61),                                  # a 3D box
    ("inverse3_prototype", {"proximal_length": 100.0}, 241),    # a shorter link: the range shrinks
    ("fivebar_singh", {"proximal": 130.0}, 241),                # the model reaches below the base too
    ("phantom_premium_15", {}, 241),                            # a slice at y = 0
])
def test_the_fitted_range_holds_every_feasible_point(device, change, n):
    preset = load_preset(device)
    mech = preset.mechanism.replace_display(**change) if change else preset.mechanism
    grid = fit_grid(mech, preset.grid)
    assert grid.axes == preset.grid.axes and grid.resolution == preset.grid.resolution
    lo, hi = np.array(grid.lower), np.array(grid.upper)
    pts = _feasible_points(mech, grid, lo, hi, n)
    assert len(pts) and np.all(pts >= lo - 1e-12) and np.all(pts <= hi + 1e-12)
    if device == "inverse3_prototype":                          # a shorter link: a smaller map than the preset's
        assert np.prod(hi - lo) < np.prod(np.array(preset.grid.upper) - np.array(preset.grid.lower))


def test_a_collapsed_design_has_no_workspace_to_fit():
    preset = load_preset("fivebar_singh")
    with pytest.raises(NoWorkspace, match="no workspace"):
        fit_grid(preset.mechanism.replace_display(proximal=1.0, distal=1.0), preset.grid)


def test_a_pens_angle_axes_keep_their_range():
    preset = load_preset("twin_pantograph")
    grid = fit_grid(preset.mechanism, preset.grid)
    assert grid.fixed == preset.grid.fixed          # the pen's angles stay where the preset put them
