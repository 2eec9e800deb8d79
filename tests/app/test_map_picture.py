"""What the app's map view paints (``app.map_picture``), checked against matplotlib's own drawing
of the exported figures: colours sample by sample, the colour bar's ticks, titles and legends."""
from __future__ import annotations

import numpy as np
import pytest

from app import figures
from app.map_picture import colour_bar, colour_samples, map_picture
from metrics.workspace import compute_map
from resources import load_preset


def matplotlib_rgba(scale, data) -> np.ndarray:
    """What ``imshow`` colours: the scale's colour map of its norm, as bytes."""
    return scale["cmap"](scale["norm"]()(data), bytes=True)


@pytest.mark.parametrize("log", [False, True])
def test_sample_colours_are_matplotlibs_at_every_value_including_the_edges_and_beyond(log):
    rng = np.random.default_rng(3)
    lo, hi = (1.0, 1e3) if log else (-2.5, 7.25)
    inner = np.exp(rng.uniform(np.log(lo), np.log(hi), 5000)) if log else rng.uniform(lo, hi, 5000)
    # The limits themselves, values a rounding away from every colour's bin edge, and beyond the limits.
    edges = np.linspace(0.0, 1.0, 257)
    at_edges = lo * (hi / lo) ** edges if log else lo + (hi - lo) * edges
    values = np.concatenate([inner, at_edges, np.nextafter(at_edges, np.inf), np.nextafter(at_edges, -np.inf),
                             [lo, hi, hi * 3.0, lo - 1.0 if not log else lo / 3.0]])
    feasible = np.ones(values.shape, bool)
    layers = [(values, feasible)]
    scale = figures.colour_scale("condition_number" if log else "isotropic_force", "t", layers)
    data = scale["to_data"](values, feasible)
    np.testing.assert_array_equal(colour_samples(scale, data), matplotlib_rgba(scale, data))


def test_blank_samples_are_transparent_and_categorical_classes_keep_their_colours():
    values = np.array([0.0, 1.0, np.nan, np.inf, 2.0, -np.inf])
    feasible = np.array([True, False, True, True, True, True])
    scale = figures.colour_scale("isotropic_force", "t", [(values, feasible)])
    rgba = colour_samples(scale, scale["to_data"](values, feasible))
    assert rgba[[1, 2, 3, 5], 3].tolist() == [0, 0, 0, 0]
    assert np.all(rgba[[0, 4], 3] == 255)
    preset = load_preset("inverse3_prototype")
    codes = np.array([0, 1, 2, -2, -1, 1])
    ok = np.ones(6, bool)
    scale = figures.colour_scale("bottleneck", preset, [(codes, ok)])
    data = scale["to_data"](codes, ok)
    np.testing.assert_array_equal(colour_samples(scale, data), matplotlib_rgba(scale, data))


def test_the_colour_bar_ticks_lie_on_the_bar_and_name_the_classes():
    values = np.linspace(0.2, 9.7, 50)
    ok = np.ones(50, bool)
    bar = colour_bar(figures.colour_scale("isotropic_force", "t", [(values, ok)]))
    fractions = [f for f, _ in bar.ticks]
    assert len(fractions) >= 3 and all(0.0 <= f <= 1.0 for f in fractions)
    assert fractions == sorted(fractions)
    assert bar.colours.shape == (256, 4) and not bar.categorical
    log_bar = colour_bar(figures.colour_scale("condition_number", "t", [(np.geomspace(1, 400, 50), ok)]))
    assert [text for _, text in log_bar.ticks][:3] == ["1", "2", "5"]
    preset = load_preset("inverse3_prototype")
    cat = colour_bar(figures.colour_scale("bottleneck", preset, [(np.array([0, 1, 2, 2]), np.ones(4, bool))]))
    assert [text.rsplit(" (", 1)[0] for _, text in cat.ticks] == list(preset.mechanism.joint_names)
    assert cat.categorical and len(cat.colours) == 3


def test_a_panel_says_what_the_exported_figure_says():
    preset = load_preset("fivebar_singh")
    wmap = compute_map(preset.mechanism, preset.grid, ("isotropic_force",))       # 1 mm: singular points
    picture = map_picture([("", wmap, None)], "isotropic_force", preset)
    (panel,) = picture.panels
    fig = figures.map_figure(wmap, "isotropic_force", preset)
    ax = fig.axes[0]
    assert panel.title == ax.get_title()
    assert [text for _, _, text in panel.legend] == [t.get_text() for t in ax.get_legend().get_texts()]
    assert panel.extent == tuple(ax.images[0].get_extent())
    # Singular points: as markers while few (this map's folded-arm points), at their sample positions.
    singular = wmap.feasible & np.isposinf(wmap.values["isotropic_force"])
    assert len(panel.singular) == np.count_nonzero(singular) > 0 and panel.singular_cells is None
