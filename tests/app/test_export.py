"""app.export and app.figures: atomic writes, exact round trips, and figures that show the data.

Headless: matplotlib through the Agg canvas only, no Qt.
"""
from __future__ import annotations

import csv
import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from matplotlib import colors

from app.export import (
    atomic_write,
    check_suffix,
    map_columns,
    stats_summary,
    write_map,
    write_map_csv,
    write_map_npz,
    write_stats,
    write_stats_csv,
    write_stats_json,
)
from app.figures import colour_limits, map_figure, save_figure
from metrics.polytopes import BOTTLENECK_TIE
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
    import app.export
    target = atomic_write(tmp_path / "p.txt", lambda tmp: tmp.write_text("x"))
    assert target.stat().st_mode & 0o777 == 0o666 & ~app.export._UMASK


def test_check_suffix_names_argument_and_value():
    assert check_suffix("A.PNG", (".png",)).name == "A.PNG"
    with pytest.raises(ValueError, match=r"--out must end in \.png, \.svg or \.pdf, got 'map\.jpg'"):
        check_suffix("map.jpg", (".png", ".svg", ".pdf"), "--out")


# -- maps -----------------------------------------------------------------------------------
def test_map_csv_round_trips_every_value_exactly(tmp_path, i3_map):
    path = write_map_csv(i3_map, tmp_path / "map.csv")
    with open(path, newline="") as fh:
        header = next(csv.reader(fh))
    assert header == ["x_mm", "z_mm", "feasible", *CORE_QUANTITIES, "bottleneck"]
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    nx, nz = i3_map.grid.resolution
    assert data.shape == (nx * nz, len(header))
    points = i3_map.points.reshape(-1, 3)
    np.testing.assert_array_equal(data[:, 0], points[:, 0] * 1e3)
    np.testing.assert_array_equal(data[:, 1], points[:, 2] * 1e3)
    np.testing.assert_array_equal(data[:, 2].astype(bool), i3_map.feasible.ravel())
    for k, name in enumerate(header[3:], start=3):
        np.testing.assert_array_equal(data[:, k], i3_map.values[name].ravel(), err_msg=name)
    # Infeasible points: nan, and -1 for the categorical bottleneck.
    assert np.all(np.isnan(data[~i3_map.feasible.ravel(), 3]))
    assert np.all(data[~i3_map.feasible.ravel(), -1] == -1)


def test_map_csv_spells_inf_at_singular_points(tmp_path, fb_map):
    path = write_map_csv(fb_map, tmp_path / "fb.csv")
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    cond = fb_map.values["condition_number"].ravel()
    assert np.isinf(cond).any()                 # the test needs a singular point
    np.testing.assert_array_equal(data[:, 3], cond)


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
    assert names == ["x_mm", "y_mm", "feasible", "isotropic_force"]
    assert all(c.shape == (25,) for c in columns)


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


def test_stats_csv_one_row_per_quantity(tmp_path, i3_map):
    path = write_stats_csv(i3_map, tmp_path / "s.csv", quantities=CORE_QUANTITIES)
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["quantity"] for r in rows] == list(CORE_QUANTITIES)
    for r in rows:
        s = i3_map.stats[r["quantity"]]
        assert float(r["min"]) == s.min and float(r["sd"]) == s.sd and int(r["count"]) == s.count
        assert float(r["argmax_z_mm"]) == pytest.approx(s.argmax[2] * 1e3)


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
    s = i3_map.stats["isotropic_force"]
    assert legend[0].startswith(f"min {s.min:.4g} N") and legend[1].startswith(f"max {s.max:.4g} N")


def test_condition_number_uses_a_log_scale_and_shows_singular_points(fb_map):
    fig = map_figure(fb_map, "condition_number", "five-bar")
    assert isinstance(_image(fig).norm, colors.LogNorm)
    assert "singular" in " ".join(t.get_text() for t in fig.axes[0].get_legend().get_texts())
    assert fig.axes[0].get_title().startswith("five-bar: condition number")


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
    from app.export import _TEMPORARIES, check_output
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
    from app.export import _TEMPORARIES, atomic_write, remove_temporaries
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
