"""What the app's map view paints (``app.logic.map_picture``), checked against matplotlib's own drawing
of the exported figures: colours sample by sample, the colour bar's ticks, titles and legends."""
from __future__ import annotations

import numpy as np
import pytest

from app.logic.colour_scale import colour_scale
from app.logic.map_marks import CUT_EDGE_LABEL, cut_edges, grid_extent
from app.logic.map_picture import colour_bar, colour_samples, map_picture
from app.plots import figures
from app.plots.figures import matplotlib_cmap, matplotlib_norm
from metrics.workspace import compute_map
from resources import load_preset


def matplotlib_rgba(scale, data) -> np.ndarray:
    """What ``imshow`` colours: the scale's colour map of its norm, as bytes."""
    return matplotlib_cmap(scale)(matplotlib_norm(scale)(data), bytes=True)


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
    scale = colour_scale("condition_number" if log else "isotropic_force", "t", layers)
    data = scale.to_data(values, feasible)
    np.testing.assert_array_equal(colour_samples(scale, data), matplotlib_rgba(scale, data))


def test_blank_samples_are_transparent_and_categorical_classes_keep_their_colours():
    values = np.array([0.0, 1.0, np.nan, np.inf, 2.0, -np.inf])
    feasible = np.array([True, False, True, True, True, True])
    scale = colour_scale("isotropic_force", "t", [(values, feasible)])
    rgba = colour_samples(scale, scale.to_data(values, feasible))
    assert rgba[[1, 2, 3, 5], 3].tolist() == [0, 0, 0, 0]
    assert np.all(rgba[[0, 4], 3] == 255)
    preset = load_preset("inverse3_prototype")
    codes = np.array([0, 1, 2, -2, -1, 1])
    ok = np.ones(6, bool)
    scale = colour_scale("bottleneck", preset, [(codes, ok)])
    data = scale.to_data(codes, ok)
    np.testing.assert_array_equal(colour_samples(scale, data), matplotlib_rgba(scale, data))


def test_the_colour_bar_ticks_lie_on_the_bar_and_name_the_classes():
    values = np.linspace(0.2, 9.7, 50)
    ok = np.ones(50, bool)
    bar = colour_bar(colour_scale("isotropic_force", "t", [(values, ok)]))
    fractions = [f for f, _ in bar.ticks]
    assert len(fractions) >= 3 and all(0.0 <= f <= 1.0 for f in fractions)
    assert fractions == sorted(fractions)
    assert bar.colours.shape == (256, 4) and not bar.categorical
    log_bar = colour_bar(colour_scale("condition_number", "t", [(np.geomspace(1, 400, 50), ok)]))
    assert [text for _, text in log_bar.ticks][:3] == ["1", "2", "5"]
    preset = load_preset("inverse3_prototype")
    cat = colour_bar(colour_scale("bottleneck", preset, [(np.array([0, 1, 2, 2]), np.ones(4, bool))]))
    assert [text.rsplit(" (", 1)[0] for _, text in cat.ticks] == list(preset.mechanism.joint_names)
    assert cat.categorical and len(cat.colours) == 3


def test_a_panel_says_what_the_exported_figure_says():
    preset = load_preset("fivebar_singh")
    wmap = compute_map(preset.mechanism, preset.grid, ("isotropic_force",))       # 1 mm: singular points
    picture = map_picture([("", wmap, None)], "isotropic_force", preset)
    (panel,) = picture.panels
    fig = figures.map_figure(wmap, "isotropic_force", preset)
    ax = fig.axes[0]
    # The figure's title holds the loading on a first line of its own, as the app's view titles it.
    assert ax.get_title() == f"{wmap.loading.describe()}\n{panel.title}"
    assert [text for _, _, text in panel.legend] == [t.get_text() for t in ax.get_legend().get_texts()]
    assert panel.extent == tuple(ax.images[0].get_extent())
    # Singular points: as markers while few (this map's folded-arm points), at their sample positions.
    singular = wmap.feasible & np.isposinf(wmap.values["isotropic_force"])
    assert len(panel.singular) == np.count_nonzero(singular) > 0 and panel.singular_cells is None


def test_feasible_samples_on_the_maps_edge_are_marked_in_the_figure_and_the_app():
    """The five-bar's preset grid stops at y = 0 where its workspace goes on (a pose below it is
    reachable and feasible): the stretches of that edge that feasible samples reach are dashed in
    the exported figure and the app's picture alike, the legend says so, and a minimum there says
    it is on the map's edge. The Inverse3's workspace lies inside its grid: nothing is marked."""
    from metrics.pose import analyse_pose

    preset = load_preset("fivebar_singh")
    below = analyse_pose(preset.mechanism, np.array([-0.2, -0.05]))
    assert below.reachable and below.feasible
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution((105, 53)), ("isotropic_force",))
    cuts = cut_edges(wmap)
    # Brute force: per side of the frame, the dashed length is that border's feasible samples' cells.
    x0, x1, y0, y1 = grid_extent(wmap.grid)
    dx, dy = (x1 - x0) / wmap.feasible.shape[0], (y1 - y0) / wmap.feasible.shape[1]
    sides = {"bottom": (wmap.feasible[:, 0], dx, lambda s: s[2] == s[3] == y0),
             "top": (wmap.feasible[:, -1], dx, lambda s: s[2] == s[3] == y1),
             "left": (wmap.feasible[0, :], dy, lambda s: s[0] == s[1] == x0),
             "right": (wmap.feasible[-1, :], dy, lambda s: s[0] == s[1] == x1)}
    for name, (border, step, on_side) in sides.items():
        length = sum(abs(s[1] - s[0]) + abs(s[3] - s[2]) for s in cuts if on_side(s))
        assert length == pytest.approx(np.count_nonzero(border) * step, rel=1e-12), name
    assert np.count_nonzero(wmap.feasible[:, 0]) > 10 and all(s[2] == s[3] == y0 for s in cuts)

    (panel,) = map_picture([("", wmap, None)], "isotropic_force", preset).panels
    ax = figures.map_figure(wmap, "isotropic_force", preset).axes[0]
    assert panel.cut_edges == tuple(cuts)
    dashed = [line for line in ax.lines if line.get_label() in (CUT_EDGE_LABEL, "_cut")]
    assert [(*line.get_xdata(), *line.get_ydata()) for line in dashed] == [tuple(s) for s in cuts]
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert CUT_EDGE_LABEL in legend and legend == [text for _, _, text in panel.legend]
    minimum = next(text for marker, _, _, text in panel.extremes if marker == "v")
    assert minimum.endswith("on the map's edge")       # (-220, 0) mm: the stretched leg, at y = 0

    inverse3 = load_preset("inverse3_prototype")
    inside = compute_map(inverse3.mechanism, inverse3.grid.with_resolution(101), ("isotropic_force",))
    assert cut_edges(inside) == []
    (panel,) = map_picture([("", inside, None)], "isotropic_force", inverse3).panels
    assert not any("edge" in text for _, _, text in panel.legend)


def test_a_difference_draws_the_compared_regions_edge_in_the_figure_and_the_app():
    """"No change" is near white, as the background: the region both maps cover is outlined
    (its indicator's one-half contour), the same polylines in both pictures; a plain map has none."""
    preset = load_preset("inverse3_prototype")
    grid = preset.grid.with_resolution(61)
    ref = compute_map(preset.mechanism, grid, ("isotropic_force",))
    cur = compute_map(preset.mechanism.replace_display(gear_ratios=(13.75, 5.957, 5.957)), grid, ("isotropic_force",))
    both = ref.feasible & cur.feasible
    diff = np.where(both, cur.values["isotropic_force"] - ref.values["isotropic_force"], np.nan)
    (panel,) = map_picture([("current - reference", cur, diff)], "isotropic_force", preset).panels
    assert len(panel.outline) >= 1
    # Every outline vertex lies between a compared and an uncompared sample (a one-half crossing).
    x_mm, y_mm = (c * 1e3 for c in grid.coordinates())
    for line in panel.outline:
        i = np.clip(np.searchsorted(x_mm, line[:, 0]), 1, len(x_mm) - 1)
        j = np.clip(np.searchsorted(y_mm, line[:, 1]), 1, len(y_mm) - 1)
        corners = np.stack([both[i - 1, j - 1], both[i, j - 1], both[i - 1, j], both[i, j]])
        assert np.all(corners.any(axis=0) & ~corners.all(axis=0))
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    fig = Figure()
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    figures.draw_panels(fig, [ax], [("current - reference", cur, diff)], "isotropic_force", preset)
    drawn = [np.column_stack([line.get_xdata(), line.get_ydata()]) for line in ax.lines
             if line.get_label() == "_outline"]
    assert len(drawn) == len(panel.outline)
    for a, b in zip(drawn, panel.outline):
        np.testing.assert_array_equal(a, b)
    (plain,) = map_picture([("", cur, None)], "isotropic_force", preset).panels
    assert plain.outline == ()
