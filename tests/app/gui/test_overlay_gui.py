"""Paper 002's overlays in the map view (issue 10 item 6): condition-number band boundaries and
ellipse fields drawn over the map on screen, from the map on screen, with their key below the
canvas, refused with the reason where they do not apply, and exported as drawn."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import wait_full_map
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import EllipseCollection

from app.plots import overlays
from metrics.workspace import compute_map
from resources import load_preset


def drawing_of(window):
    """The overlay drawn over the current map's panel (``OverlayDrawing``), or None."""
    return window.map_view.picture.panels[-1].overlay


def edge_value_at(vertex, x, y, field) -> tuple[float, float]:
    """``field`` (nx, ny) at a contour vertex on a grid edge, linear along that edge (contouring's
    rule), and the rounding bound of comparing it with the level the vertex was placed at.

    The vertex's coordinate carries a rounding of about eps |coordinate|; along the edge the
    field changes by |z1 - z0| per edge length h, so the value at the rounded vertex is off by
    up to eps (|coordinate| / h) |z1 - z0|, plus a few ulps of the interpolation itself.
    """
    eps = np.finfo(float).eps
    vx, vy = vertex
    i, j = np.argmin(abs(x - vx)), np.argmin(abs(y - vy))
    if abs(x[i] - vx) <= 4 * eps * max(abs(x).max(), 1.0):     # on a vertical edge: along y
        along, at, line = y, vy, field[i, :]
    else:
        assert abs(y[j] - vy) <= 4 * eps * max(abs(y).max(), 1.0), "a contour vertex off every grid line"
        along, at, line = x, vx, field[:, j]
    k = min(max(np.searchsorted(along, at) - 1, 0), len(along) - 2)
    z0, z1, h = line[k], line[k + 1], along[k + 1] - along[k]
    value = z0 + (at - along[k]) / h * (z1 - z0)
    bound = 16 * eps * ((abs(along).max() / h + 1) * abs(z1 - z0) + abs(z0) + abs(z1))
    return float(value), float(bound)


def test_band_boundaries_run_where_the_maps_condition_number_crosses_each_limit(make_window, qtbot):
    window = make_window("fivebar_singh", longest=80)
    window.overlay_actions["bands"].trigger()
    assert window.state.overlay == "bands"
    wait_full_map(qtbot, window)
    drawing = drawing_of(window)
    wmap = window.state.current.map
    kappa = np.where(wmap.feasible, wmap.values["condition_number"], np.nan)
    x, y = (c * 1e3 for c in wmap.grid.coordinates())
    checked = 0
    assert [colour for colour, _ in drawing.lines] == list(overlays.BAND_COLOURS[1:])
    for level, (_, polylines) in zip(overlays.BAND_LIMITS, drawing.lines):
        for line in polylines:
            for vertex in line[:: max(1, len(line) // 20)]:
                value, bound = edge_value_at(vertex, x, y, kappa)
                assert abs(value - level) <= bound, (level, vertex, value, bound)
                checked += 1
    assert checked > 10
    # The key below the canvas counts each band of this map (the bands' own classification).
    bands = overlays.condition_bands(wmap.values["condition_number"], wmap.feasible)
    text = window.map_view.overlay_legend.text()
    assert window.map_view.overlay_legend.isVisible()
    for k, (label, _) in enumerate(overlays.BANDS):
        assert f"{label.replace('<', '&lt;').replace('>', '&gt;')} ({np.count_nonzero(bands == k)} pts" in text
    assert "dexterous annulus" in text          # the five-bar's annulus, checked against this map


def test_a_coarse_map_under_a_moving_slider_carries_its_own_overlay(make_window, qtbot):
    window = make_window("fivebar_singh", longest=80)
    window.state.set_overlay("bands")
    wait_full_map(qtbot, window)
    window.on_parameter_edited("distal", 160.0, True)
    qtbot.waitUntil(lambda: window.state.current.mechanism == window.state.mechanism, timeout=30_000)
    slot = window.state.current
    bands = overlays.condition_bands(slot.map.values["condition_number"], slot.map.feasible)
    assert f"({np.count_nonzero(bands == 0)} pts" in window.map_view.overlay_legend.text()
    assert drawing_of(window) is not None and any(lines for _, lines in drawing_of(window).lines)
    # The map's own legend never lists the overlay's rows.
    labels = [text for _, _, text in window.map_view.picture.panels[-1].legend]
    assert not any("annulus" in label for label in labels)


@pytest.mark.parametrize("kind", ["force", "velocity"])
def test_an_ellipse_field_is_the_designs_own_and_switching_overlays_leaves_nothing_behind(make_window, qtbot, kind):
    window = make_window("fivebar_singh", longest=80)
    wait_full_map(qtbot, window)
    window.state.set_overlay("bands")
    window.state.set_overlay(f"{kind} ellipses")
    drawing = drawing_of(window)
    assert not drawing.lines
    slot = window.state.current
    field = overlays.ellipse_field(slot.mechanism, slot.map.grid, overlays.default_spacing(window.state.preset.grid),
                                   kind=kind)
    mm_per_unit, _ = overlays.ellipse_scale(field)
    kept = field.radii[:, 0] * mm_per_unit <= field.spacing * 1e3
    np.testing.assert_allclose(np.sort(drawing.ellipses[:, 2]), np.sort(2 * field.radii[kept, 0] * mm_per_unit),
                               rtol=1e-12)
    assert f"{kind} ellipses" in window.map_view.overlay_legend.text()
    window.state.set_overlay("none")
    assert drawing_of(window) is None
    assert not window.map_view.overlay_legend.isVisible()


def test_overlays_a_device_cannot_carry_are_disabled_with_the_reason(make_window, qtbot):
    window = make_window("inverse3_prototype", longest=60)
    actions = window.overlay_actions
    assert actions["bands"].isEnabled()
    for name in ("force ellipses", "velocity ellipses"):
        assert not actions[name].isEnabled()
        assert "planar devices" in actions[name].toolTip()
    window.state.set_overlay("bands")
    wait_full_map(qtbot, window)
    assert drawing_of(window) is not None and "condition number K bands" in window.map_view.overlay_legend.text()
    # A 3D box map carries no overlay: the device switch turns it off.
    window.load_device("novint_falcon")
    assert window.state.overlay == "none"
    assert not actions["bands"].isEnabled() and "3D box" in actions["bands"].toolTip()


def test_the_exported_map_carries_the_overlay_on_screen(make_window, qtbot, tmp_path):
    window = make_window("fivebar_singh", longest=80)
    window.state.set_overlay("force ellipses")
    wait_full_map(qtbot, window)
    path = window.export("map", tmp_path / "map.png")
    assert path.stat().st_size > 0
    slot = window.state.current
    fig = overlays.overlay_map_figure(slot.map, window.state.quantity, window.state.preset, "force ellipses",
                                      mechanism=slot.mechanism)
    FigureCanvasAgg(fig)
    (exported,) = [c for c in fig.axes[0].collections if isinstance(c, EllipseCollection)]
    shown = drawing_of(window).ellipses
    np.testing.assert_array_equal(exported.get_widths(), shown[:, 2])
    np.testing.assert_array_equal(exported.get_offsets(), shown[:, :2])


def test_overlay_refusals_name_the_reason():
    preset = load_preset("inverse3_prototype")
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution((20, 20)), ("condition_number",))
    assert overlays.overlay_available("bands", preset.mechanism, wmap.grid) is None
    assert "planar" in overlays.overlay_available("force ellipses", preset.mechanism, wmap.grid)
    with pytest.raises(ValueError, match="overlay must be one of"):
        overlays.overlay_available("stripes", preset.mechanism, wmap.grid)
