"""Exported map figures and the app's screen share one display-unit table (app.logic.display_units)."""
from __future__ import annotations

from app.logic.display_units import display_map, display_unit
from app.logic.figure_digits import format_with_error, shown_error
from app.plots.figures import map_figure
from metrics.quantities import QUANTITIES
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
    texts = [t.get_text() for t in ax.get_legend().get_texts() if t.get_text().startswith(("min", "max"))]
    value, error = stats.min * factor, wmap.errors[q]["min"] * factor      # digits its error supports
    assert texts[0].startswith(f"min {format_with_error(value, shown_error(value, error))[0]} µm at"), texts


def test_the_3d_workspace_scalar_bar_and_colours_are_in_the_screen_unit():
    import numpy as np
    import pyvista as pv

    from app import scenes

    preset = load_preset("twin_pantograph")
    q = "spatial_resolution"
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution((21, 21)), (q,))
    unit, factor = display_unit(q)
    plotter = pv.Plotter(off_screen=True)
    try:
        scenes.draw_workspace(plotter, wmap, q, preset.mechanism, "cut plane", interactive=False)
        assert list(plotter.scalar_bars.keys()) == [f"{QUANTITIES[q].label} ({unit})"]
        drawn = np.asarray(plotter.actors["workspace"].mapper.dataset.point_data[q])
        si = wmap.values[q][wmap.feasible & np.isfinite(wmap.values[q])]
        # The colours span the map's values times the factor (the cut edge takes nearest samples' values).
        assert np.isclose(drawn.min(), si.min() * factor, rtol=1e-12)
        assert np.isclose(drawn.max(), si.max() * factor, rtol=1e-12)
    finally:
        plotter.close()



def test_a_3d_box_maps_image_is_in_the_screen_unit():
    import numpy as np

    from app import scenes

    preset = load_preset("novint_falcon")
    q = "spatial_resolution"
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution((6, 6, 6)), (q,))
    unit, factor = display_unit(q)
    image = scenes.box_image(wmap, q)
    si = wmap.values[q][wmap.feasible & np.isfinite(wmap.values[q])]
    drawn = np.asarray(image.point_data[q])
    assert si.size and np.array_equal(np.sort(drawn[np.isfinite(drawn)]), np.sort(si * factor))
