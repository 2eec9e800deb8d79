"""Exported map figures and the app's screen share one display-unit table (app.display_units)."""
from __future__ import annotations

from app.display_units import display_map, display_unit
from app.figures import map_figure
from metrics.workspace import compute_map
from resources import load_preset


def test_an_exported_spatial_resolution_map_carries_the_screen_unit_and_numbers():
    preset = load_preset("twin_pantograph")
    q = "spatial_resolution"
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution((21, 21)), (q,))
    unit, factor = display_unit(q)
    assert unit == "µm" and factor == 1e6           # 1 m = 10^6 µm, by definition
    fig = map_figure(wmap, q, preset)
    ax = fig.axes[0]
    bar = fig.axes[1]
    assert f"({unit})" in bar.get_ylabel() and "(m)" not in bar.get_ylabel()
    image = ax.images[0].get_array()
    shown = display_map(wmap, q)                     # what the map view draws
    assert (image.compressed() == shown.values[q].T[~image.mask]).all()
    # The numbers are the SI data times 10^6, and the legend's extremes say so in µm.
    stats = wmap.stats[q]
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert texts[0].startswith(f"min {stats.min * factor:.4g} µm at"), texts
