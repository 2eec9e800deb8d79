"""Issue 9 section 3 in the app: the torque rating and gravity controls.

Every figure the app shows under a loading is checked against the compute layer run
independently with the same ``metrics.loading.Loading`` (``compute_map``, ``analyse_pose``):
the map on screen, the statistics panel's cells, the pose report; the controls refuse what a
device cannot take (the reason from ``Loading.check``) and a new device starts from what it
supports. The loaded figures differ from the unloaded ones, so each check can fail.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from test_gui import assert_maps_equal, map_image

from app.gui.model import AppModel, loading_label, loading_refusals, supported_loading
from app.gui.widgets.stats_panel import figure_texts
from metrics.loading import Loading, LoadingError
from metrics.pose import analyse_pose
from metrics.workspace import compute_map, resolution_error
from resources import load_preset
from tests.preset_files import massless_omni

PEAK = Loading(rating="peak")
UPRIGHT_PEAK = Loading.mounted("upright", rating="peak")
SMALL = 40        # points along the longer map axis in these tests


# -- the model, without Qt ---------------------------------------------------------------------
def test_the_model_refuses_a_loading_the_device_cannot_take_and_a_new_device_keeps_what_it_supports():
    phantom, singh = load_preset("phantom_premium_15"), load_preset("fivebar_singh")
    # A five-bar without bodies (its preset's are estimated): neither a peak rating nor a mass model.
    singh = dataclasses.replace(singh, mechanism=singh.mechanism.replace(mass_model="none"))
    model = AppModel(phantom)
    seen = []
    model.events.loading.connect(lambda: seen.append(model.loading))
    model.set_loading(UPRIGHT_PEAK)
    assert model.loading == UPRIGHT_PEAK and seen == [UPRIGHT_PEAK]
    # Each device keeps what its model can take, by the model's own contract (peak rating, mass model).
    for key in ("woodenhaptics", "phantom_omni", "stewart_platform", "phantom_premium_15"):
        model.set_preset(phantom)
        model.set_loading(UPRIGHT_PEAK)
        mech = load_preset(key).mechanism
        model.set_preset(load_preset(key))
        peak = mech.peak_torque_limits() is not None
        gravity = mech.has_mass_model            # devices with orientation freedoms take it too (a biased slice)
        assert model.loading == Loading(rating="peak" if peak else "continuous",
                                        mounting="upright" if gravity else None), key
    assert model.loading == UPRIGHT_PEAK                    # the last: the Phantom itself
    model.set_preset(singh)                                 # neither: continuous, gravity off
    assert model.loading == Loading()
    for loading, argument in ((PEAK, "rating"), (Loading.mounted("x-up"), "gravity")):
        with pytest.raises(LoadingError) as info:
            model.set_loading(loading)
        assert info.value.argument == argument and singh.name in str(info.value)
        assert model.loading == Loading()
    refused = loading_refusals(singh.mechanism, singh.name)
    assert "no peak torque rating" in refused["rating"] and "no mass model" in refused["gravity"]
    assert loading_refusals(phantom.mechanism) == {"rating": None, "gravity": None}
    # A device with orientation freedoms takes gravity (its force set at zero moment, biased); the
    # Stewart platform has no peak rating, so only the mounting is kept.
    stewart = load_preset("stewart_platform")
    assert loading_refusals(stewart.mechanism)["gravity"] is None
    assert supported_loading(UPRIGHT_PEAK, stewart.mechanism) == dataclasses.replace(UPRIGHT_PEAK, rating="continuous")
    assert loading_label(UPRIGHT_PEAK) == "peak rating, gravity upright"
    assert loading_label(Loading(gravity=(0.0, 9.81, 0.0))) == "continuous rating, gravity (0, 9.81, 0) m/s^2"


def test_a_map_of_another_loading_is_stale():
    preset = load_preset("phantom_premium_15")
    preset = preset.replace(grid=preset.grid.with_resolution((5, 7)))
    model = AppModel(preset)
    from app.gui.model import MapSlot
    wmap = compute_map(preset.mechanism, preset.grid, ("isotropic_force",))
    model.set_current_map(MapSlot(wmap, preset.mechanism, "full", 0))
    assert model.stale is None
    model.set_loading(PEAK)
    assert model.stale == "loading"
    model.set_current_map(MapSlot(compute_map(preset.mechanism, preset.grid, ("isotropic_force",), loading=PEAK),
                                  preset.mechanism, "full", 1))
    assert model.stale is None


# -- the window --------------------------------------------------------------------------------
def choose(window, rating: str | None = None, mounting: str | None = "keep") -> None:
    controls = window.loading_controls
    if rating is not None:
        controls.rating.setCurrentIndex(controls.rating.findData(rating))
    if mounting != "keep":
        controls.gravity.setCurrentIndex(controls.gravity.findData(mounting))


def wait_loaded(qtbot, waits, window, loading: Loading) -> None:
    st = window.state
    qtbot.waitUntil(lambda: waits.ready(window) and st.current.map.loading == loading, timeout=60_000)


def test_peak_rating_statistics_equal_compute_map_with_a_peak_loading(make_window, waits, qtbot):
    window = make_window("phantom_premium_15", longest=SMALL)
    st, panel = window.state, window.stats_panel
    continuous = {fig: panel.cell("isotropic_force", fig) for fig in ("min", "median", "max")}
    assert window.loading_controls.rating.isEnabled() and window.loading_controls.gravity.isEnabled()
    choose(window, rating="peak")
    assert st.loading == PEAK
    wait_loaded(qtbot, waits, window, PEAK)
    expected = compute_map(st.mechanism, st.preset.grid, window.map_quantities(), loading=PEAK)
    assert_maps_equal(st.current.map, expected)
    stats, errors = expected.stats["isotropic_force"], resolution_error(expected)["isotropic_force"]
    for fig in ("min", "p05", "median", "mean", "p95", "max", "sd"):
        assert panel.cell("isotropic_force", fig) == figure_texts(stats, fig, errors.get(fig))[0], fig
    # The peak rating is larger on every actuator: the figures changed, so the check above can fail.
    assert all(panel.cell("isotropic_force", fig) != continuous[fig] for fig in continuous)
    assert "peak rating" in panel.header.text() and "gravity off" in panel.header.text()
    assert window.map_view.picture.panels[0].title.startswith("peak rating, gravity off\n")
    data, mask = map_image(window)
    shown = expected.feasible & np.isfinite(expected.values[st.quantity])
    np.testing.assert_array_equal(data[shown], expected.values[st.quantity][shown])


def test_gravity_shifts_the_map_statistics_and_pose_glyphs_as_the_compute_layer_does(make_window, waits, qtbot):
    window = make_window("phantom_premium_15", longest=SMALL)
    st = window.state
    choose(window, rating="peak", mounting="upright")
    assert st.loading == UPRIGHT_PEAK
    wait_loaded(qtbot, waits, window, UPRIGHT_PEAK)
    expected = compute_map(st.mechanism, st.preset.grid, window.map_quantities(), loading=UPRIGHT_PEAK)
    assert_maps_equal(st.current.map, expected)
    unbiased = compute_map(st.mechanism, st.preset.grid, ("isotropic_force",), loading=PEAK)
    assert not np.array_equal(unbiased.values["isotropic_force"], expected.values["isotropic_force"])
    assert window.stats_panel.cell("isotropic_force", "min") == figure_texts(
        expected.stats["isotropic_force"], "min", resolution_error(expected)["isotropic_force"]["min"])[0]
    assert "gravity upright (0, 0, -9.80665) m/s^2" in window.stats_panel.header.text()
    # The pose glyphs: the report on screen is analyse_pose's under the same loading.
    report = st.pose_report
    want = analyse_pose(st.mechanism, np.asarray(st.pose), loading=UPRIGHT_PEAK)
    assert report.loading == UPRIGHT_PEAK
    assert report.isotropic_force == pytest.approx(want.isotropic_force, rel=0, abs=0)
    assert report.isotropic_force != analyse_pose(st.mechanism, np.asarray(st.pose)).isotropic_force
    assert "peak rating, gravity upright" in window.pose_label.text()
    caption = window.pose_view.view.caption
    assert UPRIGHT_PEAK.describe() in caption
    # Off again: the unloaded map, bit for bit.
    choose(window, rating="continuous", mounting=None)
    wait_loaded(qtbot, waits, window, Loading())
    assert_maps_equal(st.current.map, compute_map(st.mechanism, st.preset.grid, window.map_quantities()))



def test_controls_say_why_a_device_cannot_take_peak_or_gravity_and_a_new_device_resets_them(make_window, waits,
                                                                                           qtbot, tmp_path):
    window = make_window("phantom_premium_15", longest=SMALL)
    st, controls = window.state, window.loading_controls
    choose(window, rating="peak", mounting="x-up")
    wait_loaded(qtbot, waits, window, Loading.mounted("x-up", rating="peak"))
    # The five-bar has (estimated) bodies but no peak rating: gravity stays, the rating goes.
    assert window.load_device("fivebar_singh")
    waits.full(window)
    assert st.loading == Loading.mounted("x-up") and st.current.map.loading == Loading.mounted("x-up")
    assert not controls.rating.isEnabled() and controls.gravity.isEnabled()
    assert controls.rating.currentData() == "continuous" and "no peak torque rating" in controls.rating.toolTip()
    # The PHANToM Omni without its (estimated) bodies has a peak rating but no mass model: the other way round.
    choose(window, mounting="x-up")
    assert window.load_device(massless_omni(tmp_path))
    waits.full(window)
    assert st.loading == Loading() and st.current.map.loading == Loading()
    assert controls.rating.isEnabled() and not controls.gravity.isEnabled()
    assert controls.gravity.currentData() is None and "no mass model" in controls.gravity.toolTip()
    # The Stewart platform (orientation freedoms, a mass model) takes gravity: its slice at zero moment, biased.
    assert window.load_device("stewart_platform")
    assert controls.gravity.isEnabled() and not controls.rating.isEnabled()
    assert window.load_device("phantom_premium_15")
    assert controls.rating.isEnabled() and controls.gravity.isEnabled()


def test_a_reference_device_is_loaded_as_far_as_it_can_be(make_window, waits, qtbot):
    window = make_window("phantom_premium_15", longest=SMALL)
    st = window.state
    choose(window, rating="peak")
    wait_loaded(qtbot, waits, window, PEAK)
    assert window.set_reference_device("phantom_omni")          # has a peak rating: compared under it
    waits.reference(window)
    assert st.reference.map.loading == PEAK
    ref_grid = st.reference_grid
    expected = compute_map(st.reference_mechanism, ref_grid, ("isotropic_force",), loading=PEAK)
    np.testing.assert_array_equal(st.reference.map.values["isotropic_force"], expected.values["isotropic_force"])
    # Back to continuous: the reference is recomputed too.
    choose(window, rating="continuous")
    qtbot.waitUntil(lambda: st.reference is not None and st.reference.map.loading == Loading()
                    and st.reference.stage == "full", timeout=60_000)


def test_a_loading_chosen_while_a_new_devices_first_map_computes_gets_its_map(make_window, waits, qtbot):
    # The first maps of a device are requested under the loading of the moment; a rating or
    # gravity chosen before they arrive must bring maps of its own (they were dropped on arrival
    # and the view said "computing" for ever).
    from test_gui import gate_maps
    window = make_window("fivebar_singh", longest=SMALL)
    release = gate_maps(window)
    assert window.load_device("phantom_premium_15")
    assert window.state.current is None
    choose(window, rating="peak", mounting="upright")
    release()
    wait_loaded(qtbot, waits, window, UPRIGHT_PEAK)
    st = window.state
    assert_maps_equal(st.current.map, compute_map(st.mechanism, st.preset.grid, window.map_quantities(),
                                                  loading=UPRIGHT_PEAK))
