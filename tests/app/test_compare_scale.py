"""Issue 21 section 2: two devices compared side by side are drawn at one length scale.

The PHANToM Premium 1.5's slice is about three times the Omni's in area; drawn side by side at
the same millimetres per pixel, its panel is that much larger (``render.compare_figure``).
"""
from __future__ import annotations

import numpy as np
import pytest

from app.logic.map_marks import grid_extent
from app.render.views import compare_figure, shared_limits
from metrics.workspace import compute_map
from resources import load_preset


def small(preset, longest: int = 41):
    top = max(preset.grid.resolution)
    return preset.grid.with_resolution(tuple(max(3, round(n * longest / top)) for n in preset.grid.resolution))


@pytest.fixture(scope="module")
def two_devices():
    omni, premium = load_preset("phantom_omni"), load_preset("phantom_premium_15")
    return (omni, compute_map(omni.mechanism, small(omni), ("isotropic_force",)),
            premium, compute_map(premium.mechanism, small(premium), ("isotropic_force",)))


def mm_per_pixel(ax):
    fig = ax.get_figure()
    fig.canvas.draw()
    box = ax.get_window_extent()
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    return (x1 - x0) / box.width, (y1 - y0) / box.height


def test_the_compare_figure_draws_two_devices_at_one_length_scale(two_devices):
    omni, omni_map, premium, premium_map = two_devices
    a, b = grid_extent(omni_map.grid), grid_extent(premium_map.grid)
    assert (b[1] - b[0]) * (b[3] - b[2]) > 2.5 * (a[1] - a[0]) * (a[3] - a[2])       # a much larger slice
    fig = compare_figure(premium_map, omni_map, "isotropic_force", omni)
    ref_ax, cur_ax = [ax for ax in fig.axes if ax.images]
    ref, cur = mm_per_pixel(ref_ax), mm_per_pixel(cur_ax)
    np.testing.assert_allclose(ref, cur, rtol=1e-9)
    np.testing.assert_allclose(ref[0], ref[1], rtol=1e-6)          # and equal aspect: mm are mm on both axes
    # Both panels show every cell of both maps.
    for ax in (ref_ax, cur_ax):
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        assert x0 <= min(a[0], b[0]) and x1 >= max(a[1], b[1]) and y0 <= min(a[2], b[2]) and y1 >= max(a[3], b[3])


def test_shared_limits_leave_one_grid_and_other_axes_alone(two_devices):
    omni, omni_map, _, _ = two_devices
    assert shared_limits([omni_map]) is None
    assert shared_limits([omni_map, omni_map]) == [grid_extent(omni_map.grid)] * 2


def test_a_difference_of_maps_on_different_grids_is_refused_with_the_reason(two_devices):
    omni, omni_map, _, premium_map = two_devices
    with pytest.raises(ValueError, match="needs both maps on one grid") as info:
        compare_figure(premium_map, omni_map, "isotropic_force", omni, mode="difference")
    assert "x".join(map(str, omni_map.grid.resolution)).replace("x", " x ") in str(info.value)
