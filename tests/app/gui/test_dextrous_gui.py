"""Issue 10 section 2 in the app: the semi-dextrous region in the 3D workspace view.

The region on screen is checked against ``metrics.dextrous.dextrous_region`` run independently
on the box ``isoforce dextrous`` uses by default (``app.cli.dextrous.default_box``, a separate
implementation); its label against the region's volume; the surface against the box; a smaller
bound must give a region that contains the larger bound's (the orientation sets are nested);
switching off removes it and stops the job.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from PySide6.QtCore import QPoint, QRect

from app import scenes
from app.cli.dextrous import default_box
from app.gui.dextrous import FULL_POINTS, cm3, has_region, region_box, region_request
from app.gui.views.dextrous_layer import ACTOR
from app.scenes.dextrous_figure import region_mesh
from metrics.dextrous import box_grid, dextrous_region
from metrics.dextrous_orientations import orientation_set
from resources import load_preset

ORIENTED = ("stewart_platform", "twin_pantograph", "inoue_platform")


@pytest.mark.parametrize("key", ORIENTED)
def test_the_region_box_is_the_command_lines_default_box(key):
    preset = load_preset(key)
    assert has_region(preset.mechanism)
    assert region_box(preset.grid) == default_box(preset)
    request = region_request(preset.mechanism, preset.grid, 30.0, "full")
    assert request.grid == box_grid(*default_box(preset), FULL_POINTS) and request.angle == math.radians(30.0)


def test_devices_without_orientation_freedoms_have_no_region():
    for key in ("fivebar_singh", "novint_falcon", "phantom_premium_15"):
        assert not has_region(load_preset(key).mechanism), key


def on_screen(widget) -> QRect:
    """The widget's rectangle in screen coordinates."""
    return QRect(widget.mapToGlobal(QPoint(0, 0)), widget.size())


def region_shown(window, stage="full", angle=None):
    layer = window.workspace_view.dextrous
    return (layer.region is not None and layer.region[1].stage == stage
            and (angle is None or layer.region[1].angle == math.radians(angle)))


def expected_region(preset, mechanism, angle_deg: float):
    grid = box_grid(*default_box(preset), FULL_POINTS)
    return dextrous_region(mechanism, grid, orientation_set(mechanism, math.radians(angle_deg)))


def test_the_toggle_draws_the_region_coarse_then_full_with_its_volume(make_window, qtbot):
    window = make_window("fivebar_singh", longest=20)
    layer = window.workspace_view.dextrous
    assert not layer.isVisibleTo(window)                   # no orientation freedoms: not offered
    assert window.load_device("twin_pantograph")
    window.tabs.setCurrentWidget(window.workspace_view)
    assert layer.isVisible() and not layer.toggle.isChecked()       # offered, off by default
    assert layer.toggle.text() == "Semi-dextrous region (±30 deg)"
    assert ACTOR not in window.workspace_view.plotter.actors
    stages = []
    layer.runner.resultReady.connect(lambda request, _: stages.append(request.stage))
    layer.toggle.setChecked(True)
    # The worker thread posts the layer's slot and this lambda one after the other: the full
    # region can be on screen a moment before ``stages`` hears of it. The map's volume comes on
    # its own worker and may follow the region (its first map loads the compiled kernels).
    qtbot.waitUntil(lambda: region_shown(window) and stages[-1:] == ["full"]
                    and "workspace" in window.workspace_view.plotter.actors, timeout=120_000)
    assert stages[0] == "coarse"
    st = window.state
    region = layer.region[0]
    want = expected_region(st.preset, st.mechanism, 30.0)
    np.testing.assert_array_equal(region.inside, want.inside)
    assert region.volume == want.volume
    caption = layer.caption.text()
    assert layer.caption.isVisible()
    # Under the controls, not over the view's "Reset view" button (a corner text in the scene was).
    assert not on_screen(layer.caption).intersects(on_screen(window.workspace_view.view.reset_button))
    assert f"{cm3(want.volume.value)} ± {cm3(want.volume.error, 2)} cm^3" in caption and "±30 deg" in caption
    # The surface drawn is the independent region's smoothed surface (mm), in the view's metres.
    drawn = window.workspace_view.plotter.actors[ACTOR].mapper.dataset
    # VTK keeps float32 points: the view's scaling by 1e-3 is rounded to float32, within one ulp (2^-23 relative).
    np.testing.assert_allclose(drawn.points, region_mesh(want).points.astype(float) * 1e-3, rtol=2.0 ** -23, atol=0)
    # The axes in mm are round the map and the region both (round the map's flat box alone,
    # their labels were printed over the region).
    plotter = window.workspace_view.plotter
    box = np.asarray(plotter.actors[scenes.VOLUME_AXES]._isoforce_box).reshape(3, 2)
    for name in ("workspace", ACTOR):
        b = np.asarray(plotter.actors[name].GetBounds()).reshape(3, 2)
        assert np.all(box[:, 0] <= b[:, 0]) and np.all(box[:, 1] >= b[:, 1]), name

    # A smaller bound: recomputed, and every point that holds +-30 deg holds +-20 deg.
    layer.angle.setValue(20.0)
    assert layer.toggle.text() == "Semi-dextrous region (±20 deg)"
    qtbot.waitUntil(lambda: region_shown(window, angle=20.0), timeout=120_000)
    wider = layer.region[0]
    np.testing.assert_array_equal(wider.inside, expected_region(st.preset, st.mechanism, 20.0).inside)
    assert np.all(wider.inside[want.inside]) and wider.volume.value > want.volume.value

    # Off: the surface and its label go, and the axes are round the map again.
    layer.toggle.setChecked(False)
    assert ACTOR not in window.workspace_view.plotter.actors
    np.testing.assert_array_equal(plotter.actors[scenes.VOLUME_AXES]._isoforce_box,
                                  plotter.actors["workspace"].GetBounds())
    assert layer.caption.text() == "" and not layer.caption.isVisible()
    # A new device starts with it off again.
    layer.toggle.setChecked(True)
    assert window.load_device("stewart_platform")
    assert not layer.toggle.isChecked() and layer.region is None


def test_switching_off_stops_a_long_computation(make_window, qtbot):
    window = make_window("inoue_platform", longest=10)
    layer = window.workspace_view.dextrous
    layer.toggle.setChecked(True)          # the Inoue platform's full region takes tens of seconds
    qtbot.waitUntil(lambda: "computing" in layer.status.text(), timeout=5_000)
    qtbot.wait(300)
    layer.toggle.setChecked(False)
    # Cancelled between calls: the worker is idle long before the coarse and full regions could finish
    # (a hang guard, not a timing figure: ~30 s of work against a 15 s limit).
    assert layer.runner.core.wait_idle(timeout=15.0)
    qtbot.wait(100)
    assert layer.region is None and ACTOR not in window.workspace_view.plotter.actors


def test_a_design_change_recomputes_the_region(make_window, qtbot):
    window = make_window("twin_pantograph", longest=20)
    layer = window.workspace_view.dextrous
    layer.toggle.setChecked(True)
    qtbot.waitUntil(lambda: region_shown(window), timeout=120_000)
    before = layer.region[0]
    window.on_parameter_edited("pen_length", 90.0, False)
    st = window.state
    qtbot.waitUntil(lambda: region_shown(window) and layer.region[1].mechanism == st.mechanism, timeout=120_000)
    np.testing.assert_array_equal(layer.region[0].inside, expected_region(st.preset, st.mechanism, 30.0).inside)
    assert not np.array_equal(layer.region[0].inside, before.inside)


def test_the_caption_is_as_tall_as_its_wrapped_lines_in_a_narrow_view(make_window, qtbot):
    """At 1600 x 950 the Workspace (3D) tab is narrower than the controls' row: the caption was laid
    out at the row's width (fewer lines) and its last line was cut off, its first under the spin box."""
    window = make_window("twin_pantograph", longest=20, size=(1600, 950))
    window.tabs.setCurrentWidget(window.workspace_view)
    layer = window.workspace_view.dextrous
    layer._set_caption("semi-dextrous region ±30 deg: 27010 ± 3200 cm^3\n(25 x 25 x 25 grid; 41 orientations "
                       "per point)\n(reaches the box: the volume is a lower bound)")
    caption = layer.caption
    qtbot.waitUntil(lambda: caption.isVisible() and caption.height() >= caption.heightForWidth(caption.width()))
    assert layer.width() < layer.minimumSizeHint().width()      # (the case of the defect: a squeezed row)
    # Every wrapped line inside the caption, and the caption under the controls' row.
    assert caption.height() >= caption.heightForWidth(caption.width())
    assert caption.geometry().top() > layer.angle.geometry().bottom()
    assert caption.geometry().bottom() <= layer.height() - 1
