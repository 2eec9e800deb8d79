"""Resolution quantities in readable units on screen: spatial resolution in µm, angular in deg.

The map's data stay SI (checked against ``compute_map``); the map view's heat map, colour bar
and legend and the statistics panel's rows are the SI figures times the unit's factor, the
factor taken from its definition (1 m = 1e6 µm, 1 rad = 180/pi deg), not from the code.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from test_gui import map_image

from app.gui.widgets.stats_panel import figure_texts
from app.logic.display_units import display_map
from app.logic.figure_digits import format_with_error, shown_error
from metrics.workspace import compute_map, resolution_error
from resources import load_preset

FACTORS = {"spatial_resolution": ("µm", 1e6), "angular_resolution": ("deg", 180.0 / math.pi)}


def test_display_map_scales_one_quantity_and_leaves_the_map_alone():
    preset = load_preset("twin_pantograph")
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution((9, 11)), ("spatial_resolution",
                                                                               "isotropic_force"))
    raw = wmap.values["spatial_resolution"].copy()
    shown = display_map(wmap, "spatial_resolution")
    np.testing.assert_array_equal(wmap.values["spatial_resolution"], raw)        # the original untouched
    np.testing.assert_array_equal(shown.values["spatial_resolution"], raw * 1e6)
    assert shown.values["isotropic_force"] is wmap.values["isotropic_force"]
    a, b = wmap.stats["spatial_resolution"], shown.stats["spatial_resolution"]
    for fig in ("min", "max", "mean", "sd", "median", "p05", "p95"):
        assert getattr(b, fig) == getattr(a, fig) * 1e6, fig
    assert (b.count, b.argmin, b.argmax) == (a.count, a.argmin, a.argmax)
    assert display_map(wmap, "isotropic_force") is wmap


@pytest.mark.parametrize("quantity", sorted(FACTORS))
def test_resolution_maps_read_in_display_units_on_screen(make_window, waits, qtbot, quantity):
    window = make_window("twin_pantograph", longest=30)
    st = window.state
    box = window.quantity_box
    assert box.findData(quantity) >= 0                      # offered automatically
    box.setCurrentIndex(box.findData(quantity))
    qtbot.waitUntil(lambda: waits.ready(window) and quantity in st.current.map.values, timeout=60_000)
    unit, factor = FACTORS[quantity]
    expected = compute_map(st.mechanism, st.preset.grid, window.map_quantities())
    # The data stay SI.
    np.testing.assert_array_equal(st.current.map.values[quantity], expected.values[quantity])
    # The heat map holds the values times the factor; the colour bar and legend say the unit.
    data, mask = map_image(window)
    values = expected.values[quantity]
    shown = expected.feasible & np.isfinite(values)
    np.testing.assert_array_equal(~mask, shown)
    np.testing.assert_array_equal(data[shown], values[shown] * factor)
    assert window.map_view.picture.bar.label.endswith(f"({unit})")
    stats = expected.stats[quantity]
    legend = [text for symbol, _, text in window.map_view.picture.panels[0].legend if symbol in ("v", "^")]
    # The digits its resolution error supports, in the display unit (as the statistics panel).
    error = expected.errors[quantity]["min"] * factor
    digits = format_with_error(stats.min * factor, shown_error(stats.min * factor, error))[0]
    assert legend[0].startswith(f"min {digits} {unit} at"), legend[0]
    # The statistics panel: rows for the map's quantity, in the display unit.
    panel = window.stats_panel
    errors = resolution_error(expected)[quantity]       # the independent map's estimate, SI
    for fig in ("min", "median", "max", "sd"):
        scaled = type(stats)(**{**vars(stats), **{f: getattr(stats, f) * factor
                                                   for f in ("min", "max", "mean", "sd", "median", "p05", "p95")}})
        error = None if errors.get(fig) is None else errors[fig] * factor
        assert (panel.cell(quantity, fig), panel.cell(quantity, fig, column=2)) == figure_texts(scaled, fig, error), fig
        # The unit is the quantity's heading's (the row above its first figure), once.
        heading = panel.table.item(panel.rows[(quantity, "min")] - 1, 0).text()
        assert heading.endswith(f"({unit})") and panel.cell(quantity, fig, column=0) in ("min", "median", "max", "SD")
    # Value and error with the digits the error supports (stats_panel.format_with_error), in the display unit.
