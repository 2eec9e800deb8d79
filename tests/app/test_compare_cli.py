"""``isoforce compare``: the figures equal ``compute_map`` statistics, bad input exits 2, ``--out`` files read back."""
from __future__ import annotations

import csv
import json
import math

import matplotlib.image
import numpy as np
import pytest

import app.cli.compare as compare
from app.cli import main
from metrics.bottleneck import BOTTLENECK_SHARED, BOTTLENECK_TIE
from metrics.categories import category_counts
from metrics.workspace import compute_map
from resources import list_presets, load_preset
from tests.preset_files import massless_omni

RESOLUTION = 40
DEVICES = ("fivebar_singh", "inverse3_prototype", "stewart_platform")


def run(capsys, *argv: str) -> tuple[int, str, str]:
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


def run_json(capsys, *argv: str) -> dict:
    status, out, err = run(capsys, *argv, "--json")
    assert status == 0, err
    return json.loads(out, parse_constant=lambda c: pytest.fail(f"non-standard JSON constant {c}"))


def assert_usage_error(capsys, argv, *phrases: str) -> str:
    status, out, err = run(capsys, *argv)
    assert status == 2, (out, err)
    assert out == ""
    assert err.count("\n") == 1 and err.startswith("isoforce"), err
    for phrase in phrases:
        assert phrase in err, (phrase, err)
    return err


def _number(value):
    return math.inf if value == "inf" else (math.nan if value is None else value)


@pytest.fixture(scope="module")
def summary():
    """One ``compare --json`` of three devices (in-process, so the module-scoped result is shared)."""
    import contextlib
    import io

    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):
        status = main(["compare", *DEVICES, "--resolution", str(RESOLUTION), "--json"])
    assert status == 0
    return json.loads(buffer.getvalue())


@pytest.mark.parametrize("index", range(len(DEVICES)))
def test_figures_equal_compute_map_statistics(summary, index):
    key = DEVICES[index]
    row = summary["devices"][index]
    preset = load_preset(key)
    mech, grid = preset.mechanism, preset.grid.with_resolution(RESOLUTION)
    # The request ``compare`` makes (a figure is computed the same way only within one request).
    wmap = compute_map(mech, grid, compare.map_quantities(mech), keep=False)
    iso = wmap.stats["isotropic_force"]
    assert row["key"] == key
    for k in compare.FORCE_FIGURES:
        assert _number(row["isotropic_force"][k]) == getattr(iso, k), k
    assert row["isotropic_force"]["count"] == iso.count
    aniso = wmap.stats["anisotropic_force"]
    assert row["anisotropic_force_unbounded"] == aniso.unbounded
    assert _number(row["anisotropic_force_max"]) == aniso.max
    assert row["gci"] == wmap.gci
    # Workspace: feasible points times the cell (product of the spacings), m^2 -> cm^2.
    assert row["feasible_points"] == wmap.feasible_points
    cell = math.prod(grid.spacing()) * 1e4
    assert row["workspace"] == {"kind": "area", "value": wmap.feasible_points * cell, "unit": "cm^2",
                                "cell_size": cell}
    assert row["at_zero_moment"] == (key == "stewart_platform")


@pytest.mark.parametrize("index", range(len(DEVICES)))
def test_bottleneck_shares_equal_the_counts_of_a_kept_map(summary, index):
    key = DEVICES[index]
    preset = load_preset(key)
    mech, grid = preset.mechanism, preset.grid.with_resolution(RESOLUTION)
    kept = compute_map(mech, grid, ["bottleneck"])
    codes = kept.values["bottleneck"][kept.feasible]
    names = {BOTTLENECK_TIE: "tie", BOTTLENECK_SHARED: "shared", **dict(enumerate(mech.joint_names))}
    expected = {names[int(c)]: int(np.count_nonzero(codes == c)) / codes.size for c in np.unique(codes)}
    assert summary["devices"][index]["bottleneck_shares"] == expected
    assert math.fsum(expected.values()) == pytest.approx(1.0, abs=len(expected) * 2.3e-16)


def test_category_counts_streamed_equal_one_chunk_and_refuse_scalar_quantities():
    preset = load_preset("fivebar_singh")
    grid = preset.grid.with_resolution(RESOLUTION)
    threaded = category_counts(preset.mechanism, grid)
    single = category_counts(preset.mechanism, grid, threads=False)
    assert threaded == single
    assert sum(threaded.counts.values()) == threaded.feasible_points
    with pytest.raises(ValueError, match="categorical"):
        category_counts(preset.mechanism, grid, "isotropic_force")


def test_a_volume_map_reports_cm3():
    from kinematics.grid import GridSpec

    preset = load_preset("inverse3_prototype")
    grid = GridSpec(("x", "y", "z"), (-0.05, -0.1, -0.15), (0.35, 0.1, 0.5), (5, 6, 7))
    w = compare.workspace_size(preset.mechanism, grid, 10)
    cell = 0.1 * 0.04 * (0.65 / 6) * 1e6
    assert w["kind"] == "volume" and w["unit"] == "cm^3"
    assert w["cell_size"] == pytest.approx(cell, rel=4 * 2.3e-16)
    assert w["value"] == pytest.approx(10 * cell, rel=4 * 2.3e-16)


def test_text_table_names_every_device_and_the_definitions(capsys):
    status, out, err = run(capsys, "compare", "fivebar_singh", "stewart_platform", "--resolution", "20")
    assert status == 0, err
    assert "fivebar_singh" in out and "stewart_platform" in out
    assert "at zero moment" in out and "pure force" in out
    assert "cm^2" in out and "feasible grid points times the cell size" in out
    assert "bottleneck actuator's share of the workspace" in out


def test_bad_device_names_exit_2(capsys):
    assert_usage_error(capsys, ["compare", "fivebar_singh", "no_such_device"], "DEVICE", "no_such_device")
    assert_usage_error(capsys, ["compare"], "DEVICE")


@pytest.mark.parametrize("name, phrase", [("table.txt", "must end in"), ("missing/table.csv", "does not exist")])
def test_a_bad_out_is_refused_before_computing(capsys, monkeypatch, tmp_path, name, phrase):
    def boom(*args, **kwargs):
        raise AssertionError("computed before checking --out")

    monkeypatch.setattr(compare, "compute_map", boom)
    monkeypatch.setattr(compare, "category_counts", boom)
    assert_usage_error(capsys, ["compare", "fivebar_singh", "--out", str(tmp_path / name)], "--out", phrase)
    assert list(tmp_path.iterdir()) == []


def test_out_writes_a_png_that_decodes_and_tables_that_read_back(capsys, tmp_path, summary):
    png = tmp_path / "compare.png"
    status, _, err = run(capsys, "compare", *DEVICES, "--resolution", str(RESOLUTION), "--out", str(png))
    assert status == 0, err
    image = matplotlib.image.imread(png)
    assert image.ndim == 3 and image.shape[0] > 100 and image.shape[1] > 100
    assert np.ptp(image[..., :3]) > 0.5           # not blank
    table = tmp_path / "compare.csv"
    assert run(capsys, "compare", *DEVICES, "--resolution", str(RESOLUTION), "--out", str(table))[0] == 0
    with open(table, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["device"] for r in rows] == list(DEVICES)
    for r, expected in zip(rows, summary["devices"]):
        assert float(r["isotropic_force_min"]) == expected["isotropic_force"]["min"]
        assert float(r["workspace"]) == expected["workspace"]["value"]
        assert float(r["anisotropic_force_max"]) == _number(expected["anisotropic_force_max"])
    as_json = tmp_path / "compare.json"
    assert run(capsys, "compare", *DEVICES, "--resolution", str(RESOLUTION), "--out", str(as_json))[0] == 0
    written = json.loads(as_json.read_text(encoding="utf-8"))
    for w, expected in zip(written["devices"], summary["devices"]):
        assert {k: v for k, v in w.items() if k != "seconds"} == {k: v for k, v in expected.items() if k != "seconds"}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["compare.csv", "compare.json", "compare.png"]


def test_every_shipped_preset_compares_with_the_others_of_its_map_kind(capsys):
    slices = [k for k in list_presets() if len(load_preset(k).grid.axes) == 2]
    boxes = [k for k in list_presets() if len(load_preset(k).grid.axes) == 3]
    assert slices and boxes
    for keys in (slices, boxes):
        d = run_json(capsys, "compare", *keys, "--resolution", "12")
        assert [r["key"] for r in d["devices"]] == keys
        assert len({r["workspace"]["unit"] for r in d["devices"]}) == 1          # one unit in the column


def test_a_slice_device_and_a_box_device_are_refused_with_the_reason(capsys):
    # Issue 21 sec. 2: a PHANToM's y = 0 slice (cm^2) beside the Falcon's box (cm^3) compared
    # statistics over an area with statistics over a volume, in one column.
    status, out, err = run(capsys, "compare", "phantom_premium_15", "novint_falcon", "--resolution", "12")
    assert status == 2 and out == "" and err.count("\n") == 1
    assert "phantom_premium_15: a 2D slice" in err and "novint_falcon: a 3D box" in err and "not over like" in err


def test_the_docs_script_replaces_only_its_own_section(tmp_path):
    """scripts/compare_devices.py: other sections stay; a second run changes nothing; --check sees it."""
    from scripts.compare_devices import END, START
    from scripts.compare_devices import main as script

    doc = tmp_path / "devices.md"
    doc.write_text("# Devices\n\n## PHANToM\n\nhand-written.\n", encoding="utf-8")
    argv = ["--doc", str(doc), "--resolution", "12", "--devices", "fivebar_singh", "stewart_platform"]
    assert script(argv) == 0
    first = doc.read_text(encoding="utf-8")
    assert first.startswith("# Devices\n\n## PHANToM\n\nhand-written.\n\n" + START + "\n## Comparison\n")
    assert first.endswith(END + "\n") and "`stewart_platform`" in first
    # Someone appends a section after ours: it is kept, ours is replaced in place.
    doc.write_text(first.replace("| pure force |", "| edited |") + "\n## Falcon\n\nlater.\n", encoding="utf-8")
    assert script([*argv, "--check"]) == 1
    assert script(argv) == 0
    assert doc.read_text(encoding="utf-8") == first + "\n## Falcon\n\nlater.\n"
    assert script([*argv, "--check"]) == 0
    missing = tmp_path / "new.md"
    assert script(["--doc", str(missing), "--resolution", "12", "--devices", "fivebar_singh"]) == 0
    assert missing.read_text(encoding="utf-8").startswith("# Devices\n")


def test_masses_are_compared_where_a_device_has_a_mass_model_and_refused_with_the_reason_elsewhere(capsys, tmp_path):
    # The heaviest apparent mass's median equals the statistics of the same map (independent
    # of the table code), and a device without bodies says why instead of printing a zero.
    from metrics.quantities import DYNAMIC_SUMMARY
    from metrics.workspace import compute_map

    omni_file = massless_omni(tmp_path)
    d = run_json(capsys, "compare", "phantom_premium_15", omni_file, "--resolution", "40")
    rows = {r["key"]: r for r in d["devices"]}
    omni = rows["phantom_omni"]["masses"]
    assert omni.startswith("not computed: ") and "no mass model" in omni
    preset = load_preset("phantom_premium_15")
    grid = preset.grid.with_resolution((40, 40))
    wmap = compute_map(preset.mechanism, grid, DYNAMIC_SUMMARY, keep=False)
    masses = rows["phantom_premium_15"]["masses"]
    assert masses["apparent_mass_max"]["median"] == wmap.stats["apparent_mass_max"].median
    assert masses["apparent_mass_max"]["max"] == "inf"        # the base axis: unbounded, not a grid figure
    assert 0 < masses["apparent_mass_min"]["median"] <= masses["apparent_mass_max"]["median"]
    status, out, _ = run(capsys, "compare", "phantom_premium_15", omni_file, "--resolution", "40")
    assert status == 0 and "what the hand feels" in out and "max unbounded" in out


def test_the_compare_figure_names_the_rating_and_what_its_statistics_are_over(capsys):
    from app.plots.compare_figure import compare_figure

    d = run_json(capsys, "compare", "phantom_premium_15", "phantom_omni", "--resolution", "12", "--rating", "peak")
    title = compare_figure(d["devices"]).axes[0].get_title()
    assert "peak rating, gravity off" in title and "2D slices, areas" in title


def test_a_zero_global_minimum_is_labelled_singular_above_the_axis(capsys):
    from app.plots.compare_figure import compare_figure

    d = run_json(capsys, "compare", "novint_falcon", "--resolution", "21")
    assert d["devices"][0]["isotropic_force"]["min_vanishes"]
    ax = compare_figure(d["devices"]).axes[0]
    label = next(t for t in ax.texts if t.get_text().startswith("0 N"))
    assert label.get_text() == "0 N (singular)" and label.xyann[1] > 0      # offset upwards, off the axis
