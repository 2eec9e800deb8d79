"""app.figures: categorical maps for every device and bottleneck code, one colour scale for a comparison.

Headless: matplotlib through the Agg canvas only, no Qt. The expected classes come from the
mechanism's own joint names and ``metrics.polytopes``' codes, never from the figure's code.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from matplotlib import colors

from app.cli import main as cli_main
from app.figures import colour_scale, draw_map, map_figure
from app.render import compare_figure
from metrics.polytopes import BOTTLENECK_INFEASIBLE, BOTTLENECK_SHARED, BOTTLENECK_TIE
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
