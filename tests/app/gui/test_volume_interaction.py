"""Issue 9 section 4 in the real window: a 3D box map stays interactive while a slider is held.

While the plane slider is held the map view redraws only the heat map (titles, legends and
extreme markers hidden, so nothing of another plane is on screen) and the workspace view only
the plane; on release everything is drawn for the plane shown. A design slider's coarse volume
reaches the screen even when the refinement is requested before it is done. A heat-map update
keeps the colour bar when the volume's scale is unchanged. Values on screen are
checked against the computed volume as in ``test_volume_gui``.
"""
from __future__ import annotations

import pytest
from test_volume_gui import assert_plane_drawn

from app.gui.model import AppModel
from app.gui.volumes import COARSE_VOLUME_POINTS
from app.logic.colour_scale import colour_scale
from resources import load_preset

FALCON = 12


def test_the_model_says_what_a_held_slider_moves():
    model = AppModel(load_preset("fivebar_singh"))
    seen = []
    model.events.interaction.connect(lambda: seen.append(model.interaction))
    model.set_interaction("plane")
    model.set_interaction("plane")
    model.set_interaction(None)
    assert seen == ["plane", None]
    with pytest.raises(ValueError, match="interaction must be one of"):
        model.set_interaction("zoom")


def test_a_held_plane_slider_draws_only_the_plane_and_release_draws_everything(make_window, qtbot):
    window = make_window("novint_falcon", longest=FALCON)
    window.tabs.setCurrentWidget(window.workspace_view)
    st, view, ws = window.state, window.map_view, window.workspace_view
    qtbot.waitUntil(lambda: ws._drawn is not None and ws._drawn[0] == st.current.generation, timeout=10_000)
    actors = ws.plotter.actors
    hull, surfaces, plane = actors["box_hull"], actors["workspace"], actors["box_plane"]
    own = (hull.prop.opacity, surfaces.prop.opacity, tuple(plane.mapper.lookup_table.GetNanColor()))
    assert own[0] < 1 and own[1] < 1 and own[2][3] == 0      # see-through as drawn by scenes
    slider = view.slice_controls.slider

    slider.setSliderDown(True)                  # a mouse press: sliderPressed
    assert st.interaction == "plane"
    assert not hull.GetVisibility() and not surfaces.GetVisibility()
    assert tuple(plane.mapper.lookup_table.GetNanColor()) == (1.0, 1.0, 1.0, 1.0)
    start = slider.value()
    for step in (1, 2):
        slider.setValue(start - step)
        qtbot.wait(30)
        assert_plane_drawn(window)              # the heat map follows the held slider, plane by plane
        assert not view.picture.panels[0].labels_shown       # no title, legend or extremes of another plane
    slider.setSliderDown(False)                 # release
    assert st.interaction is None
    assert hull.GetVisibility() and surfaces.GetVisibility()
    assert (hull.prop.opacity, surfaces.prop.opacity, tuple(plane.mapper.lookup_table.GetNanColor())) == own
    panel = view.picture.panels[0]
    assert panel.labels_shown and panel.legend
    assert f"z = {st.slice_value * 1e3:g} mm" in panel.title
    # The legend names this plane's extremes (volume_slice's statistics of the plane shown).
    stats = view.planes(view.panels())[0][0][1].stats[st.quantity]
    assert f"min {stats.min:.4g}" in panel.legend[0][2]
    assert_plane_drawn(window)


def test_a_design_drag_shows_the_coarse_volume_even_when_the_refinement_comes_first(waits, make_window, qtbot,
                                                                                    monkeypatch):
    import app.gui.main_window as mw
    original = mw.load_preset
    monkeypatch.setattr(mw, "load_preset", lambda key: (lambda p: p.replace(grid=p.grid.with_resolution(30)))(
        original(key)))
    window = make_window("novint_falcon")
    window.tabs.setCurrentWidget(window.workspace_view)
    st, ws = window.state, window.workspace_view
    seen = []
    st.mapChanged.connect(lambda: seen.append((st.current.stage, st.current.map.grid.resolution,
                                               st.current.mechanism)))
    window.on_parameter_edited("upper_arm", 61.3, True)
    assert st.interaction == "design"
    # The refinement asked for at once, before the coarse volume (a new design's singular loci
    # take the worker about a second) is done: it must not cancel it.
    window.refine_timer.stop()
    window.request_map("full")
    waits.full(window)
    stages = [(s, r) for s, r, m in seen if m == st.mechanism]
    assert stages[0] == ("coarse", (COARSE_VOLUME_POINTS,) * 3) and stages[-1] == ("full", (30, 30, 30))
    # Still held: cheap geometry (opaque surfaces, no boundary); released: the scene's own look.
    qtbot.waitUntil(lambda: ws._drawn is not None and ws._drawn[0] == st.current.generation, timeout=10_000)
    hull, surfaces = ws.plotter.actors["box_hull"], ws.plotter.actors["workspace"]
    assert not hull.GetVisibility() and surfaces.prop.opacity == 1.0
    before = st.current
    window.on_parameter_edited("upper_arm", 61.3, False)        # released where it rests: no new map
    assert st.interaction is None and st.current is before and not window.refine_timer.isActive()
    assert hull.GetVisibility() and surfaces.prop.opacity < 1.0


def test_a_plane_step_keeps_the_volumes_colour_scale_and_bar(make_window, qtbot):
    window = make_window("novint_falcon", longest=FALCON)
    view = window.map_view
    qtbot.waitUntil(lambda: view.picture is not None and bool(view.picture.panels), timeout=10_000)
    view.slice_controls.colours.setCurrentIndex(view.slice_controls.colours.findData("volume"))
    before = view.picture
    slider = view.slice_controls.slider
    slider.setValue(slider.value() - 1)        # a keyboard step: title and legend change, the scale does not
    qtbot.waitUntil(lambda: view.picture is not before, timeout=5_000)
    after = view.picture
    assert after.panels[0].title != before.panels[0].title
    assert after.panels[0].scale is before.panels[0].scale        # one scale kept for the whole volume
    assert after.bar.ticks == before.bar.ticks and after.bar.label == before.bar.label
    assert_plane_drawn(window)
    # What the bar shows: the whole volume's scale.
    st = window.state
    wmap = st.current.map
    scale = colour_scale(st.quantity, st.preset, [(wmap.values[st.quantity], wmap.feasible)])
    assert after.panels[0].scale.limits == scale.limits
