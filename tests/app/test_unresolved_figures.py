"""Errors the grid cannot see and figures it does not resolve, said one way in the CLI and the figures
(issue 26 sec. 5): no "+- 0.000", and an error at least its figure names the grid that would resolve it.

References: the observed order of the grid error is recomputed here from a kept map's own values
on the half and quarter grids (numpy slicing, independent of the streamed accumulators), and the
resolution a note names is checked by computing the map at that resolution.
"""
from __future__ import annotations

import contextlib
import dataclasses
import io
import math
import re

import numpy as np
import pytest

from app.cli import main
from app.cli._args import device_grid
from app.cli.compare import force_cells, summaries
from app.logic.figure_digits import (
    FASTEST_ORDER,
    format_with_error,
    resolving_points,
    shown_error,
    unresolved,
    unresolved_note,
)
from app.logic.map_marks import extreme_marks
from metrics.workspace import compute_map, error_orders
from resources import load_preset

#: A zero error in any notation: "+- 0", "+- 0.000", "+- 0.000e-05".
ZERO_ERROR = re.compile(r"\+- 0(\.0*)?(e[+-]\d+)?(\s|$)")


def _run(argv) -> str:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(argv) == 0
    return out.getvalue()


@pytest.mark.parametrize("value", [2.5, 1.5290001, 0.877, 2.998e-05, 1234.6, 1.5e6, 9.9996e-05])
def test_an_error_the_half_grids_cannot_see_reads_below_the_last_digit(value):
    v_text, e_text = format_with_error(value, 0.0)
    assert e_text.startswith("<"), e_text
    # "<" half a unit of the value's last written place, in the value's own notation.
    mantissa, _, exponent = v_text.partition("e")
    places = len(mantissa.split(".")[1]) if "." in mantissa else 0
    bound = 0.5 * 10.0 ** (-places + (int(exponent) if exponent else 0))
    assert math.isclose(float(e_text[1:]), bound, rel_tol=1e-12), (v_text, e_text)
    assert e_text.endswith(f"e{exponent}") if exponent else "e" not in e_text
    # shown_error's rounding residue reads the same way.
    assert format_with_error(value, shown_error(value, 1e-14 * value)) == (v_text, e_text)


def test_no_cli_table_prints_a_zero_error():
    # The WoodenHaptics' isotropic-force maximum is a plateau both half grids reach: the same figure.
    text = _run(["stats", "woodenhaptics", "--resolution", "30"])
    assert not ZERO_ERROR.search(text), text
    assert re.search(r"\+- <0\.0*5(\s|$)", text), text
    assert "below half a unit of its last digit" in text


def test_observed_order_follows_the_half_and_quarter_grids_of_the_kept_values():
    preset = load_preset("inverse3_prototype")
    grid = device_grid(preset, 81)
    wmap = compute_map(preset.mechanism, grid, ["isotropic_force"], keep=True)
    values = wmap.values["isotropic_force"]
    regular = wmap.feasible & ~wmap.singular

    def figures(sl):
        v = values[sl][regular[sl]]
        return {"min": v.min(), "max": v.max(), "mean": v.mean()}

    full, h0, h1 = figures(np.s_[:, :]), figures(np.s_[::2, ::2]), figures(np.s_[1::2, 1::2])
    q0, q2 = figures(np.s_[::4, ::4]), figures(np.s_[2::4, 2::4])
    for k in ("min", "max", "mean"):
        fine = max(abs(full[k] - h0[k]), abs(full[k] - h1[k]))
        coarse = max(abs(h0[k] - q0[k]), abs(h0[k] - q2[k]))
        assert math.isclose(wmap.errors["isotropic_force"][k], fine, rel_tol=1e-9, abs_tol=1e-12), k
        expected = math.log2(coarse / fine) if fine > 0 and coarse > 0 else math.nan
        got = wmap.error_orders["isotropic_force"][k]
        if math.isnan(expected) or expected <= 0:
            assert math.isnan(got), k
        else:
            assert math.isclose(got, expected, rel_tol=1e-6), k
    # The streamed map finds the same orders for the figures it holds exactly.
    streamed = compute_map(preset.mechanism, grid, ["isotropic_force"], keep=False)
    for k in ("min", "max", "mean"):
        a, b = streamed.error_orders["isotropic_force"][k], wmap.error_orders["isotropic_force"][k]
        assert (math.isnan(a) and math.isnan(b)) or math.isclose(a, b, rel_tol=1e-6), k


def test_no_order_where_the_error_does_not_shrink():
    assert math.isnan(error_orders({"sd": 0.1}, {"sd": 0.05})["sd"])       # grows as the grid refines
    assert math.isnan(error_orders({"sd": 0.0}, {"sd": 0.05})["sd"])
    assert error_orders({"sd": 0.1}, {"sd": 0.4})["sd"] == 2.0


def test_the_resolution_named_extrapolates_the_error_to_half_the_figure():
    value, error, n = 3e-06, 7e-06, (100, 40)
    for order in (0.7, 1.0, 1.6, 2.0, 3.5):
        points = resolving_points(value, error, order, n)
        p = min(order, FASTEST_ORDER)
        for old, new in zip(n, points):
            assert error * ((old - 1) / (new - 1)) ** p <= abs(value) / 2      # resolved there
            # and not by much more than needed: the unrounded count is at most two digits below.
            exact = (old - 1) * (2 * error / value) ** (1 / p) + 1
            assert new - exact <= 10 ** max(0, len(str(new)) - 2)
    assert resolving_points(value, error, 0.2, n) is None          # no trend: "a finer grid"
    assert unresolved_note(value, error, 0.2, n).endswith("a finer grid would resolve it")
    assert unresolved_note(2.28, 0.003, 1.0, n) == "" and not unresolved(2.28, 0.003)


@pytest.mark.parametrize("resolution, figure", [((10, 16), "mean"), ((19, 30), "p95")])
def test_the_grid_a_note_names_resolves_the_figure(resolution, figure):
    # The PHANToM Premium's heaviest direction on coarse slices: its error is larger than itself.
    quantity = "apparent_mass_max"
    preset = load_preset("phantom_premium_15")
    coarse = preset.grid.with_resolution(resolution)
    wmap = compute_map(preset.mechanism, coarse, [quantity], keep=True)
    value, error = getattr(wmap.stats[quantity], figure), wmap.errors[quantity][figure]
    assert unresolved(value, error)
    points = resolving_points(value, error, wmap.error_orders[quantity][figure], coarse.resolution)
    assert points is not None
    finer = compute_map(preset.mechanism, coarse.with_resolution(points), [quantity], keep=True)
    assert not unresolved(getattr(finer.stats[quantity], figure), finer.errors[quantity][figure])


@pytest.fixture(scope="module")
def omni_24():
    preset = load_preset("phantom_omni")
    grid = device_grid(preset, 24)
    text = _run(["stats", "phantom_omni", "--resolution", "24"])
    from metrics.quantities import summary_quantities
    return preset, grid, compute_map(preset.mechanism, grid, summary_quantities(preset.mechanism), keep=False), text


def test_stats_names_the_grid_for_each_unresolved_figure(omni_24):
    _, grid, wmap, text = omni_24
    expected = []
    for q, errors in wmap.errors.items():
        for k, e in errors.items():
            value = getattr(wmap.stats[q], k)
            if k == "max" and wmap.stats[q].unbounded:
                continue
            note = unresolved_note(value, shown_error(value, e), wmap.error_orders[q][k], grid.resolution)
            if note:
                expected.append(f"{q} {k}: {note}")
    assert expected, "the 24-point Omni map resolves everything: pick a coarser one"
    assert any("points per axis would resolve it" in line for line in expected)
    for line in expected:
        assert line in text.splitlines(), line


def test_compare_writes_each_figure_as_stats_does():
    # One rule: compare's cells are the value texts stats prints next to their errors.
    text = _run(["stats", "haply_2diy", "--resolution", "24"])
    row = next(line for line in text.splitlines() if line.startswith("isotropic_force"))
    cells = re.findall(r"(\S+) \+- \S+", row)                      # min, p05, median, mean, p95, sd
    stats_cells = dict(zip(("min", "p05", "median", "mean", "p95", "sd"), cells))
    (summary,) = summaries(["haply_2diy"], 24)
    compare_cells = dict(zip(("min", "mean", "sd", "median", "p05", "p95"),
                             force_cells(summary["isotropic_force"])))
    for k, cell in compare_cells.items():
        assert cell.removesuffix(" *") == stats_cells[k], k


def test_a_map_legend_names_the_grid_for_an_unresolved_extreme():
    preset = load_preset("phantom_premium_15")
    grid = preset.grid.with_resolution((10, 16))
    wmap = compute_map(preset.mechanism, grid, ["isotropic_force"], keep=True)
    stats = wmap.stats["isotropic_force"]
    # The same map with its minimum's error read as the figure's own size twice over.
    errors = {**wmap.errors["isotropic_force"], "min": 2 * abs(stats.min)}
    doubted = dataclasses.replace(wmap, errors={"isotropic_force": errors})
    (_, _, _, text), _ = extreme_marks(doubted, "isotropic_force")
    note = unresolved_note(stats.min, errors["min"], wmap.error_orders["isotropic_force"]["min"], grid.resolution)
    assert note and f"({note})" in text, text
    (_, _, _, plain), _ = extreme_marks(wmap, "isotropic_force")
    assert "not resolved" not in plain
