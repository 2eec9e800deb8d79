"""app.plots.figures: categorical maps for every device and bottleneck code, one colour scale for a comparison.

Headless: matplotlib through the Agg canvas only, no Qt. The expected classes come from the
mechanism's own joint names and ``metrics.bottleneck``' codes, never from the figure's code.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from matplotlib import colors

from app.cli import main as cli_main
from app.logic.colour_scale import colour_scale
from app.logic.planes import default_plane, is_volume, volume_slice
from app.plots.figures import draw_panels, map_figure
from app.render.views import compare_figure
from metrics.bottleneck import BOTTLENECK_INFEASIBLE, BOTTLENECK_SHARED, BOTTLENECK_TIE
from metrics.workspace import compute_map
from resources import list_presets, load_preset

#: What each bottleneck code that names no actuator is called on the colour bar.
CODE_NAMES = {BOTTLENECK_TIE: "tie", BOTTLENECK_SHARED: "shared (redundant)"}


def small(preset, longest: int = 31):
    top = max(preset.grid.resolution)
    return preset.grid.with_resolution(tuple(max(3, round(n * longest / top)) for n in preset.grid.resolution))


def expected_name(mechanism, code: int) -> str | None:
    """The class a bottleneck code is drawn as (None: blank)."""
    if code >= 0:
        return mechanism.joint_names[code]
    return CODE_NAMES.get(code)


def drawn_classes(fig):
    """(class name per point or None, tick labels) of a single-panel categorical figure."""
    fig.canvas.draw()
    image = fig.axes[0].images[0]
    data = image.get_array()
    labels = [t.get_text() for t in fig.axes[1].get_yticklabels()]
    names = [label.rsplit(" (", 1)[0] for label in labels]
    index = np.ma.getdata(data).T
    mask = np.ma.getmaskarray(data).T
    shown = np.empty(index.shape, object)
    shown[~mask] = [names[k] for k in index[~mask]]
    return shown, labels


def assert_bottleneck_figure(fig, mechanism, values, feasible) -> None:
    shown, labels = drawn_classes(fig)
    assert isinstance(fig.axes[0].images[0].norm, colors.BoundaryNorm)
    for idx in np.ndindex(values.shape):
        want = expected_name(mechanism, int(values[idx])) if feasible[idx] else None
        assert shown[idx] == want, (idx, values[idx], shown[idx])
    # Every actuator is listed, then the codes that occur, each with its count.
    present = {int(c) for c in np.unique(values[feasible])}
    names = list(mechanism.joint_names) + [CODE_NAMES[c] for c in (BOTTLENECK_TIE, BOTTLENECK_SHARED) if c in present]
    counts = [int(np.count_nonzero(feasible & (values == u))) for u in range(mechanism.n_joints)]
    counts += [int(np.count_nonzero(feasible & (values == c))) for c in (BOTTLENECK_TIE, BOTTLENECK_SHARED)
               if c in present]
    assert labels == [f"{n} ({c})" for n, c in zip(names, counts)]


@pytest.mark.parametrize("key", list_presets())
def test_bottleneck_map_of_every_shipped_device_draws_every_code(key):
    preset = load_preset(key)
    mech = preset.mechanism
    wmap = compute_map(mech, small(preset), ("bottleneck",))
    if is_volume(wmap.grid):        # a 3D box map (the delta's) is drawn on its plane (the app's first)
        wmap = volume_slice(wmap, *default_plane(wmap.grid, mech, preset.pose))
    values = wmap.values["bottleneck"]
    fig = map_figure(wmap, "bottleneck", preset)
    assert_bottleneck_figure(fig, mech, values, wmap.feasible)

    # Every code at once, on this device's own grid: each actuator, a tie, a shared point and
    # -1 (drawn blank, like the infeasible points, even where "feasible" says otherwise).
    codes = np.array([*range(mech.n_joints), BOTTLENECK_TIE, BOTTLENECK_SHARED, BOTTLENECK_INFEASIBLE])
    mixed = codes[np.arange(values.size).reshape(values.shape) % codes.size].astype(values.dtype)
    feasible = np.ones(values.shape, bool)
    feasible.flat[::7] = False
    fig = map_figure(dataclasses.replace(wmap, feasible=feasible, values={"bottleneck": mixed}), "bottleneck",
                     preset)
    assert_bottleneck_figure(fig, mech, mixed, feasible)
    assert {"tie", "shared (redundant)"} <= {label.rsplit(" (", 1)[0] for label in drawn_classes(fig)[1]}


@pytest.mark.parametrize("key", list_presets())
def test_isoforce_map_bottleneck_writes_a_figure_for_every_device(key, tmp_path, capsys):
    out = tmp_path / f"{key}.png"
    assert cli_main(["map", key, "--quantity", "bottleneck", "--resolution", "21", "--out", str(out)]) == 0, \
        capsys.readouterr().err
    assert out.stat().st_size > 1000


# -- one colour scale for a comparison ------------------------------------------------------------
@pytest.fixture(scope="module")
def scenarios():
    """Paper 000's Scenario 1 and 2 (g1 = 13.75) on one small slice, with the bottleneck."""
    one, two = load_preset("inverse3_prototype"), load_preset("inverse3_scenario2")
    grid = small(one, 61)
    quantities = ("condition_number", "anisotropic_force", "isotropic_force", "bottleneck")
    return one, compute_map(one.mechanism, grid, quantities), compute_map(two.mechanism, grid, quantities)


def panel_images(fig):
    return [ax.images[0] for ax in fig.axes if ax.images]


@pytest.mark.parametrize("quantity", ["isotropic_force", "anisotropic_force", "condition_number"])
def test_compare_figure_puts_both_designs_on_one_colour_scale_side_by_side(scenarios, quantity):
    preset, ref, cur = scenarios
    fig = compare_figure(ref, cur, quantity, preset)
    fig.canvas.draw()
    images = panel_images(fig)
    assert len(images) == 2
    (lo0, hi0), (lo1, hi1) = (im.get_clim() for im in images)
    assert (lo0, hi0) == (lo1, hi1)                    # one norm's limits, set once for both
    assert type(images[0].norm) is type(images[1].norm)
    # The limits span both designs' values (capping only ever lowers the top).
    both = np.concatenate([m.values[quantity][m.feasible & np.isfinite(m.values[quantity])] for m in (ref, cur)])
    # A log scale's limits come back as 10 ** log10(v) (``colour_limits``): v to within a few ulp,
    # not bit for bit. log10 and the power are each within ~1 ulp, and the exponent's rounding,
    # eps |log10 v|, is multiplied by ln 10 in 10 ** y: relative error <= eps (ln 10 |log10 v| + 2).
    def slack(v):
        return v * np.finfo(float).eps * (np.log(10) * abs(np.log10(v)) + 2) if isinstance(
            images[0].norm, colors.LogNorm) else 0.0
    assert abs(lo0 - both.min()) <= slack(both.min()) and hi0 <= both.max() + slack(both.max())
    # One colour bar beside the two panels (three axes in all), panels side by side.
    assert len(fig.axes) == 3
    a, b = (im.axes.get_position() for im in images)
    assert a.x1 <= b.x0 and a.y0 < b.y1 and b.y0 < a.y1
    # Equal values, equal colours; Scenario 2's larger isotropic force is drawn higher on the scale.
    if quantity == "isotropic_force":
        shared = ref.feasible & cur.feasible
        r, c = ref.values[quantity][shared], cur.values[quantity][shared]
        assert np.all(c >= r) and np.any(c > r)        # paper 000: a larger g1 never lowers it
        np.testing.assert_array_equal(images[0].to_rgba(r), images[1].to_rgba(r))
        # viridis brightens with the value: where Scenario 2 is better, its panel is brighter.
        brightness = [np.asarray(im.to_rgba(v))[:, :3].sum(axis=1) for im, v in zip(images, (r, c))]
        assert np.all(brightness[1] >= brightness[0] - 1e-12) and np.mean(brightness[1] > brightness[0]) > 0.5


def test_compare_figure_of_the_bottleneck_shares_its_classes(scenarios):
    preset, ref, cur = scenarios
    fig = compare_figure(ref, cur, "bottleneck", preset)
    fig.canvas.draw()
    bars = [ax for ax in fig.axes if not ax.images]
    assert len(bars) == 1
    labels = [t.get_text() for t in bars[0].get_yticklabels()]
    codes = np.unique(np.concatenate([m.values["bottleneck"][m.feasible] for m in (ref, cur)]))
    names = list(preset.mechanism.joint_names) + [CODE_NAMES[c] for c in (BOTTLENECK_TIE, BOTTLENECK_SHARED)
                                                  if c in codes]
    code_of = list(range(preset.mechanism.n_joints)) + [c for c in (BOTTLENECK_TIE, BOTTLENECK_SHARED) if c in codes]
    counts = [" / ".join(str(int(np.count_nonzero(m.feasible & (m.values["bottleneck"] == c)))) for m in (ref, cur))
              for c in code_of]
    assert labels == [f"{n} ({c})" for n, c in zip(names, counts)]


def test_colour_scale_of_one_map_equals_draw_maps_own(scenarios):
    preset, ref, _ = scenarios
    for quantity in ("isotropic_force", "condition_number"):
        fig = map_figure(ref, quantity, preset)
        scale = colour_scale(quantity, preset, [(ref.values[quantity], ref.feasible)])
        assert fig.axes[0].images[0].get_clim() == scale.limits
    with pytest.raises(ValueError, match="layers"):
        colour_scale("isotropic_force", preset, [])
    with pytest.raises(ValueError, match="axes and panels"):
        fig = map_figure(ref, "isotropic_force", preset)
        draw_panels(fig, [fig.axes[0]], [], "isotropic_force", preset)


def test_a_mixed_jacobians_condition_number_names_its_scaling_in_the_title():
    from app.plots.figures import map_figure
    from metrics.workspace import compute_map
    from resources import load_preset

    preset = load_preset("stewart_platform")
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution(20), ("condition_number",))
    title = map_figure(wmap, "condition_number", preset).axes[0].get_title()
    assert "moments scaled by L = 30 mm" in title
    five = load_preset("fivebar_singh")
    wmap = compute_map(five.mechanism, five.grid.with_resolution(20), ("condition_number",))
    assert "scaled" not in map_figure(wmap, "condition_number", five).axes[0].get_title()


def test_colour_limits_computed_with_a_map_are_the_limits_drawing_it_computes(monkeypatch):
    """The limits the app's map job computes with the map (``map_colour_limits``) are the ones
    ``colour_scale`` computes from the values, and passed in they are used as they are; the
    classes and a quantity the map lacks have none."""
    import app.logic.colour_limits as limits_module
    from app.logic.colour_limits import map_colour_limits

    preset = load_preset("inverse3_prototype")
    wmap = compute_map(preset.mechanism, small(preset), ("isotropic_force", "condition_number", "bottleneck"))
    for q in ("isotropic_force", "condition_number"):
        fresh = colour_scale(q, preset, [(wmap.values[q], wmap.feasible)]).limits
        limits = map_colour_limits(wmap, q)
        assert limits[:2] == fresh
        computed = []
        with monkeypatch.context() as m:
            m.setattr(limits_module, "colour_limits", lambda *a, **k: computed.append(1) or (0.0, 1.0, False))
            assert colour_scale(q, preset, [(wmap.values[q], wmap.feasible)], limits=limits).limits == fresh
            assert not computed
            # Without limits, the values decide (here the stand-in's).
            assert colour_scale(q, preset, [(wmap.values[q], wmap.feasible)]).limits == (0.0, 1.0)
    assert map_colour_limits(wmap, "bottleneck") is None
    assert map_colour_limits(wmap, "spatial_resolution") is None
    assert computed == [1]
