"""app.files.export and app.plots.figures: atomic writes, exact round trips, and figures that show the data.

Headless: matplotlib through the Agg canvas only, no Qt.
"""
from __future__ import annotations

import csv
import json
import math
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from matplotlib import colors

from app.files.export import (
    atomic_write,
    check_suffix,
    grid_coordinates_mm,
    map_columns,
    read_map_csv,
    write_map,
    write_map_csv,
    write_map_npz,
)
from app.files.stats_files import STATS_FIGURES, stats_summary, write_stats, write_stats_csv, write_stats_json
from app.logic.colour_limits import colour_limits
from app.logic.figure_digits import format_with_error, shown_error
from app.logic.map_marks import extreme_marks
from app.plots.figures import map_figure, save_figure
from metrics.bottleneck import BOTTLENECK_TIE
from metrics.quantities import CORE_QUANTITIES
from metrics.workspace import GridSpec, compute_map
from resources import load_preset

I3 = load_preset("inverse3_prototype")
FB = load_preset("fivebar_singh")


@pytest.fixture(scope="module")
def i3_map():
    # Not square on purpose: a transposed axis would show.
    return compute_map(I3.mechanism, I3.grid.with_resolution((41, 53)), CORE_QUANTITIES + ("bottleneck",))


@pytest.fixture(scope="module")
def fb_map():
    # 10 mm spacing from (-260, 0) hits (+-220, 0), where a leg is stretched: inf condition numbers.
    return compute_map(FB.mechanism, FB.grid.with_resolution((53, 27)),
                       ("condition_number", "isotropic_force", "singularity"))


def leftovers(folder) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


# -- atomic_write ---------------------------------------------------------------------------
def test_atomic_write_creates_the_file_and_nothing_else(tmp_path):
    target = tmp_path / "out.txt"
    assert atomic_write(target, lambda tmp: tmp.write_text("hello")) == target
    assert target.read_text() == "hello"
    assert leftovers(tmp_path) == ["out.txt"]


def test_temporary_file_keeps_the_suffix_for_format_sniffing_writers(tmp_path):
    seen = []
    atomic_write(tmp_path / "fig.svg", lambda tmp: (seen.append(tmp), tmp.write_text("<svg/>")))
    assert seen[0].suffix == ".svg" and seen[0].parent == tmp_path and seen[0].name != "fig.svg"


def test_failing_writer_leaves_no_file_and_no_temporary(tmp_path):
    target = tmp_path / "map.csv"

    def half_then_fail(tmp):
        tmp.write_text("x_mm,feasible\n1.0,")
        raise OSError(28, "No space left on device")

    with pytest.raises(OSError, match="No space"):
        atomic_write(target, half_then_fail)
    assert leftovers(tmp_path) == []


def test_failing_writer_leaves_an_older_file_untouched(tmp_path):
    target = tmp_path / "stats.json"
    target.write_text('{"old": true}')
    with pytest.raises(RuntimeError):
        atomic_write(target, lambda tmp: (tmp.write_text("{"), (_ for _ in ()).throw(RuntimeError("boom"))))
    assert target.read_text() == '{"old": true}'
    assert leftovers(tmp_path) == ["stats.json"]


def test_writer_that_removes_its_file_is_an_error(tmp_path):
    with pytest.raises(RuntimeError, match="did not leave a file"):
        atomic_write(tmp_path / "a.txt", lambda tmp: tmp.unlink())
    assert leftovers(tmp_path) == []


def test_missing_folder_and_folder_target_raise_naming_the_argument(tmp_path):
    missing = tmp_path / "no" / "such" / "map.png"
    with pytest.raises(ValueError, match=r"--out: folder .*no/such.* does not exist"):
        atomic_write(missing, lambda tmp: tmp.write_text("x"), name="--out")
    with pytest.raises(ValueError, match="--out is a folder"):
        atomic_write(tmp_path, lambda tmp: tmp.write_text("x"), name="--out")
    assert leftovers(tmp_path) == []


def test_finished_file_has_ordinary_permissions_not_mkstemps_private_ones(tmp_path):
    import app.files.export
    target = atomic_write(tmp_path / "p.txt", lambda tmp: tmp.write_text("x"))
    assert target.stat().st_mode & 0o777 == 0o666 & ~app.files.export._UMASK


def test_check_suffix_names_argument_and_value():
    assert check_suffix("A.PNG", (".png",)).name == "A.PNG"
    with pytest.raises(ValueError, match=r"--out must end in \.png, \.svg or \.pdf, got 'map\.jpg'"):
        check_suffix("map.jpg", (".png", ".svg", ".pdf"), "--out")


# -- maps -----------------------------------------------------------------------------------
def data_lines(path) -> list[str]:
    """The lines after the comment block and the column names."""
    lines = path.read_text(encoding="utf-8").splitlines()
    first = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    return lines[first + 1:]


def test_map_csv_reads_back_every_value_bit_for_bit_and_the_grid(tmp_path, i3_map):
    path = write_map_csv(i3_map, tmp_path / "map.csv", device="inverse3_prototype")
    table = read_map_csv(path)
    assert table.axes == ("x", "z") and table.fixed == {"y": 22.3}
    # Every value, nan at the infeasible points and -1 for the categorical bottleneck there, as the map holds.
    np.testing.assert_array_equal(table.feasible, i3_map.feasible)
    assert list(table.values) == [*CORE_QUANTITIES, "bottleneck"]
    for name, values in i3_map.values.items():
        np.testing.assert_array_equal(table.values[name], values, err_msg=name)     # nan == nan here
        assert table.values[name].dtype.kind == values.dtype.kind
    # The coordinates are the grid's: numpy.linspace of its ends in mm, written exactly.
    for got, mm, metres in zip(table.coordinates, grid_coordinates_mm(i3_map.grid), i3_map.grid.coordinates()):
        np.testing.assert_array_equal(got, mm)
        # Against the map's own SI coordinates: linspace (step rounding, product, sum: 1.5 eps of the
        # largest end each way) and the m -> mm product (0.5 eps): at most 4 eps of the largest end apart.
        bound = 4 * np.finfo(float).eps * np.abs(mm).max()
        assert np.abs(got - metres * 1e3).max() <= bound


def test_map_csv_has_rows_for_the_feasible_points_only_and_says_so(tmp_path, i3_map):
    path = write_map_csv(i3_map, tmp_path / "map.csv", device="inverse3_prototype")
    text = path.read_text(encoding="utf-8")
    comments = [line for line in text.splitlines() if line.startswith("# ")]
    assert comments[0].startswith("# isoforce workspace map of inverse3_prototype: one row per feasible grid point "
                                  f"({i3_map.feasible_points} of {41 * 53})")
    assert any("a grid point without a row is infeasible" in c for c in comments)
    assert any("isotropic_force: N" in c and "x_mm: mm" in c for c in comments)
    assert any(c.startswith("# forces: continuous rating, gravity off") for c in comments)
    rows = data_lines(path)
    assert 0 < len(rows) == i3_map.feasible_points < i3_map.feasible.size
    assert not any(cell in ("", "nan") for row in rows for cell in row.split(","))     # all defined here
    # numpy.loadtxt with the skiprows the file names reads the same table.
    skip = int(re.search(r"skiprows=(\d+)", comments[1]).group(1))
    data = np.loadtxt(path, delimiter=",", skiprows=skip)
    names, columns = map_columns(i3_map)
    assert text.splitlines()[skip - 1].split(",") == names == ["x_mm", "z_mm", *CORE_QUANTITIES, "bottleneck"]
    for k, column in enumerate(columns):
        np.testing.assert_array_equal(data[:, k], column, err_msg=names[k])


def test_map_csv_writes_the_grids_own_digits_and_spells_inf(tmp_path, fb_map):
    path = write_map_csv(fb_map, tmp_path / "fb.csv")
    rows = [row.split(",") for row in data_lines(path)]
    # A 10 mm grid (-260 .. 260 mm, 53 points): every coordinate is a whole number of mm, written as such.
    assert all(re.fullmatch(r"-?\d*0\.0", row[0]) and re.fullmatch(r"\d*0\.0", row[1]) for row in rows)
    # Each float cell is the shortest decimal that reads back: repr of the value it stands for.
    cond = fb_map.values["condition_number"][fb_map.feasible]
    assert np.isinf(cond).any()                 # the test needs a singular point
    assert [row[2] for row in rows] == [repr(float(v)) for v in cond]
    table = read_map_csv(path)
    np.testing.assert_array_equal(table.values["condition_number"], fb_map.values["condition_number"])
    np.testing.assert_array_equal(table.values["singularity"], fb_map.values["singularity"])


def test_read_map_csv_names_a_file_that_is_no_map(tmp_path):
    other = tmp_path / "other.csv"
    other.write_text("a,b\n1,2\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"other\.csv: not an isoforce map CSV"):
        read_map_csv(other)


def test_map_npz_holds_the_arrays_without_pickle(tmp_path, i3_map):
    path = write_map_npz(i3_map, tmp_path / "map.npz")
    with np.load(path) as data:         # allow_pickle=False by default
        assert list(data["axes"]) == ["x", "z"]
        assert list(data["quantities"]) == [*CORE_QUANTITIES, "bottleneck"]
        np.testing.assert_array_equal(data["x_mm"], i3_map.grid.coordinates()[0] * 1e3)
        np.testing.assert_array_equal(data["points_mm"], i3_map.points * 1e3)
        np.testing.assert_array_equal(data["feasible"], i3_map.feasible)
        for name in i3_map.values:
            np.testing.assert_array_equal(data[name], i3_map.values[name])
        assert dict(zip(data["quantities"], data["units"]))["isotropic_force"] == "N"


def test_write_map_dispatches_on_suffix_and_rejects_others(tmp_path, i3_map):
    write_map(i3_map, tmp_path / "a.NPZ")
    write_map(i3_map, tmp_path / "a.csv")
    with pytest.raises(ValueError, match=r"out must end in \.csv or \.npz, got '.*a\.xlsx'"):
        write_map(i3_map, tmp_path / "a.xlsx", name="out")
    assert leftovers(tmp_path) == ["a.NPZ", "a.csv"]


def test_map_columns_skip_vector_quantities(tmp_path):
    wmap = compute_map(FB.mechanism, FB.grid.with_resolution(5), ("jacobian", "isotropic_force"))
    names, columns = map_columns(wmap)
    assert names == ["x_mm", "y_mm", "isotropic_force"]
    assert all(c.shape == (wmap.feasible_points,) for c in columns) and 0 < wmap.feasible_points < 25


# -- statistics -----------------------------------------------------------------------------
def test_stats_json_is_strict_and_equals_the_map(tmp_path, i3_map, fb_map):
    path = write_stats_json(i3_map, tmp_path / "s.json", device="inverse3_prototype")
    text = path.read_text()
    d = json.loads(text, parse_constant=lambda c: pytest.fail(f"non-standard JSON constant {c}"))
    assert d["device"] == "inverse3_prototype" and d["resolution"] == [41, 53]
    assert d["feasible_points"] == i3_map.feasible_points
    for name, s in i3_map.stats.items():
        entry = d["quantities"][name]
        assert (entry["min"], entry["max"], entry["mean"], entry["sd"], entry["count"]) == \
            (s.min, s.max, s.mean, s.sd, s.count)
        np.testing.assert_allclose(entry["argmin"], np.array(s.argmin) * 1e3)
    # A map with singular points: its maximum condition number is the string "inf".
    fb = stats_summary(fb_map)
    assert fb["quantities"]["condition_number"]["max"] == "inf"
    json.dumps(fb, allow_nan=False)


def assert_stats_csv_matches_summary(rows: list[dict], summary: dict) -> None:
    """Every figure and its resolution error in the CSV rows equal the JSON summary's, unit per row."""
    assert [r["quantity"] for r in rows] == list(summary["quantities"])
    for r in rows:
        entry = summary["quantities"][r["quantity"]]
        assert r["unit"] == (entry["unit"] or "1")
        for fig in STATS_FIGURES:
            # JSON: "inf" for an unbounded figure, null for nan; the CSV spells inf, and leaves a
            # figure without an error estimate empty.
            value = entry[fig]
            assert float(r[fig]) == (math.nan if value is None else float(value)) or (
                value is None and math.isnan(float(r[fig]))), (r["quantity"], fig)
            error = entry["resolution_error"][fig]
            assert r[f"{fig}_resolution_error"] == ("" if error is None else repr(float(error))), (r["quantity"], fig)
        assert int(r["count"]) == entry["count"] and int(r["singular_points"]) == entry["singular_points"]
        assert r["unbounded"] == ("true" if entry["unbounded"] else "false")


def test_stats_csv_carries_every_figures_error_next_to_it_as_the_json_does(tmp_path, i3_map, fb_map):
    for wmap in (i3_map, fb_map):
        path = write_stats_csv(wmap, tmp_path / "s.csv")
        with open(path, newline="") as fh:
            header = next(csv.reader(fh))
            fh.seek(0)
            rows = list(csv.DictReader(fh))
        for fig in STATS_FIGURES:
            assert header[header.index(fig) + 1] == f"{fig}_resolution_error"
        summary = stats_summary(wmap)
        assert_stats_csv_matches_summary(rows, summary)
        for r in rows:      # and the figures are the map's, exactly
            s = wmap.stats[r["quantity"]]
            assert float(r["min"]) == s.min and float(r["sd"]) == s.sd and int(r["count"]) == s.count
            assert float(r["argmax_y_mm" if "argmax_y_mm" in r else "argmax_x_mm"]) == pytest.approx(
                (s.argmax[1] if "argmax_y_mm" in r else s.argmax[0]) * 1e3)
    # The five-bar's unbounded maxima: "inf", no error estimate, flagged.
    row = next(r for r in rows if r["quantity"] == "isotropic_force")
    assert (row["max"], row["max_resolution_error"], row["unbounded"]) == ("inf", "", "true")
    assert float(row["min_resolution_error"]) > 0


def test_isoforce_stats_csv_equals_its_json_figure_by_figure(tmp_path, capsys):
    from app.cli import main

    out = tmp_path / "s.csv"
    assert main(["stats", "fivebar_singh", "--resolution", "40", "--out", str(out)]) == 0
    capsys.readouterr()
    assert main(["stats", "fivebar_singh", "--resolution", "40", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    with open(out, newline="") as fh:
        assert_stats_csv_matches_summary(list(csv.DictReader(fh)), summary)


def test_write_stats_rejects_other_suffixes(tmp_path, i3_map):
    with pytest.raises(ValueError, match=r"--out must end in \.json or \.csv"):
        write_stats(i3_map, tmp_path / "s.txt", name="--out")
    assert leftovers(tmp_path) == []


# -- figures --------------------------------------------------------------------------------
def _image(fig):
    return fig.axes[0].images[0]


def test_heat_map_masks_infeasible_points_with_axes_in_mm(i3_map):
    fig = map_figure(i3_map, "isotropic_force", I3)
    ax = fig.axes[0]
    assert ax.get_xlabel() == "x (mm)" and ax.get_ylabel() == "z (mm)"
    data = _image(fig).get_array()
    # imshow takes rows = z: the array is the map transposed, masked exactly off the workspace.
    assert data.shape == (53, 41)
    np.testing.assert_array_equal(np.ma.getmaskarray(data), ~i3_map.feasible.T)
    np.testing.assert_array_equal(data.data[i3_map.feasible.T], i3_map.values["isotropic_force"].T[i3_map.feasible.T])
    x_mm = i3_map.grid.coordinates()[0] * 1e3
    left, right, _, _ = _image(fig).get_extent()
    assert left < x_mm[0] < x_mm[-1] < right
    assert ax.get_aspect() == 1.0
    colour_bar = fig.axes[1]
    assert colour_bar.get_ylabel() == "Max. isotropic force (N)"
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    s, e = i3_map.stats["isotropic_force"], i3_map.errors["isotropic_force"]
    # With the digits each figure's resolution error supports, as the statistics panel writes it.
    for row, fig_name in zip(legend, ("min", "max")):
        value = getattr(s, fig_name)
        assert row.startswith(f"{fig_name} {format_with_error(value, shown_error(value, e[fig_name]))[0]} N"), row


def test_condition_number_uses_a_log_scale_and_shows_singular_points(fb_map):
    fig = map_figure(fb_map, "condition_number", "five-bar")
    assert isinstance(_image(fig).norm, colors.LogNorm)
    assert "unbounded here" in " ".join(t.get_text() for t in fig.axes[0].get_legend().get_texts())
    assert fig.axes[0].get_title().startswith("continuous rating, gravity off\nfive-bar: condition number")


def test_categorical_map_labels_its_classes_by_actuator_name(i3_map, fb_map):
    fig = map_figure(i3_map, "bottleneck", I3)
    assert isinstance(_image(fig).norm, colors.BoundaryNorm)
    fig.canvas.draw()
    labels = [t.get_text() for t in fig.axes[1].get_yticklabels()]
    # p1 and p2 have equal column norms on the whole slice (the five-bar's symmetry): where they
    # limit, they limit together, shown as a tie (BOTTLENECK_TIE), not split by rounding.
    codes = i3_map.values["bottleneck"][i3_map.feasible]
    names = {0: "theta_0", 1: "p1", 2: "p2", BOTTLENECK_TIE: "tie"}
    shown = [0, 1, 2] + [c for c in (BOTTLENECK_TIE,) if np.any(codes == c)]   # every actuator, then ties
    assert BOTTLENECK_TIE in shown
    assert labels == [f"{names[c]} ({np.count_nonzero(codes == c)})" for c in shown]
    fig = map_figure(fb_map, "singularity", FB)
    fig.canvas.draw()
    assert [t.get_text().split(" ")[0] for t in fig.axes[1].get_yticklabels()] == \
        ["none", "inverse", "direct", "combined"]


def test_colour_limits_cap_a_singular_tail_and_say_so():
    rng = np.random.default_rng(0)
    bulk = rng.uniform(1.0, 5.0, 10000)
    assert colour_limits(bulk) == (bulk.min(), bulk.max(), False)
    lo, hi, capped = colour_limits(np.append(bulk, 1e9))
    assert capped and hi < 20
    lo, hi, capped = colour_limits(np.append(bulk, 1e9), log=True)
    assert capped and 1.0 <= lo and hi < 100


def test_figure_refuses_a_3d_map_and_a_missing_quantity(i3_map):
    grid = GridSpec(("x", "y", "z"), (0.1, 0.0, 0.1), (0.2, 0.05, 0.2), (3, 3, 3))
    volume = compute_map(I3.mechanism, grid, ["isotropic_force"])
    with pytest.raises(ValueError, match="2D slice"):
        map_figure(volume, "isotropic_force", I3)
    with pytest.raises(ValueError, match="'manipulability' is not in this map"):
        map_figure(i3_map, "manipulability", I3)


@pytest.mark.parametrize("suffix", [".png", ".svg", ".pdf"])
def test_save_figure_writes_each_format(tmp_path, i3_map, suffix):
    fig = map_figure(i3_map, "condition_number", I3)
    path = save_figure(fig, tmp_path / f"map{suffix}")
    head = path.read_bytes()[:8]
    if suffix == ".png":
        assert head == b"\x89PNG\r\n\x1a\n"
    elif suffix == ".pdf":
        assert head.startswith(b"%PDF")
    else:
        assert ET.parse(path).getroot().tag.endswith("svg")
    assert leftovers(tmp_path) == [f"map{suffix}"]


def test_save_figure_rejects_raster_formats_it_does_not_promise(tmp_path, i3_map):
    with pytest.raises(ValueError, match=r"must end in \.png, \.svg or \.pdf, got '.*map\.jpg'"):
        save_figure(map_figure(i3_map, "isotropic_force", I3), tmp_path / "map.jpg")
    assert leftovers(tmp_path) == []


def test_check_output_refuses_before_any_work_and_leaves_nothing(tmp_path):
    from app.files.export import _TEMPORARIES, check_output
    assert check_output(tmp_path / "m.csv", (".csv",)) == tmp_path / "m.csv"
    with pytest.raises(ValueError, match="--out.*cannot write"):
        check_output("/proc/m.csv", (".csv",))               # read-only for root too
    with pytest.raises(ValueError, match="--out.*does not exist"):
        check_output(tmp_path / "no" / "m.csv", (".csv",))
    (tmp_path / "d.csv").mkdir()
    with pytest.raises(ValueError, match="--out is a folder"):
        check_output(tmp_path / "d.csv", (".csv",))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.csv"] and not _TEMPORARIES


def test_an_interrupt_inside_the_writer_removes_the_registered_temporary(tmp_path):
    from app.files.export import _TEMPORARIES, atomic_write, remove_temporaries
    seen = []

    def writer(tmp):
        seen.append(tmp)
        assert tmp in _TEMPORARIES              # registered before it was created
        tmp.write_text("partial")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_write(tmp_path / "m.csv", writer)
    remove_temporaries()
    assert seen and list(tmp_path.iterdir()) == [] and not _TEMPORARIES


def test_a_plateau_extreme_says_how_much_of_the_map_reaches_it():
    """The PHANToM Premium's isotropic force is at its maximum, one motor's limit, over most of
    its map: the legend says so instead of naming one point of the plateau as "the" maximum.
    A unique extreme (the Inverse3's) keeps its point."""
    preset = load_preset("phantom_premium_15")
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution(121), ["isotropic_force"])
    values, regular = wmap.values["isotropic_force"], wmap.feasible & ~wmap.singular
    top = np.max(values[regular])
    share = np.count_nonzero(regular & (np.abs(values - top) <= 1e-9 * top)) / np.count_nonzero(regular)
    assert share > 0.5                                       # a plateau: the same value, to rounding
    legend = [text for *_, text in extreme_marks(wmap, "isotropic_force")]
    assert legend[1].endswith(f"on {100 * share:.0f} % of the map"), legend
    assert legend[0].startswith("min ") and " at (" in legend[0]
    i3 = load_preset("inverse3_prototype")
    legend = [text for *_, text in extreme_marks(compute_map(i3.mechanism, i3.grid.with_resolution(121),
                                                             ["isotropic_force"]), "isotropic_force")]
    assert all(" at (" in text for text in legend), legend
