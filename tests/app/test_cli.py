"""The ``isoforce`` command line: value checks against the compute layer, and bad input handled.

Driven in-process through ``main([...])`` (capsys), plus real subprocesses for
``python -m app`` and the no-Qt import check.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import types
import xml.etree.ElementTree as ET
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest

import app.cli as cli
import app.launch as launch
from app.cli import main
from app.logic.pose_report import VELOCITY_KEYS, to_dict
from metrics.pose import analyse_pose
from metrics.pose_dynamics import DYNAMIC_KEYS
from metrics.quantities import CORE_QUANTITIES, DYNAMIC_SUMMARY, summary_quantities
from metrics.workspace import compute_map
from resources import list_presets, load_preset

ROOT = Path(__file__).resolve().parents[2]


def run(capsys, *argv: str) -> tuple[int, str, str]:
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


def run_json(capsys, *argv: str) -> dict:
    status, out, err = run(capsys, *argv, "--json")
    assert status == 0, err
    # Exactly one strict JSON object: no NaN/Infinity tokens, nothing else on stdout.
    return json.loads(out, parse_constant=lambda c: pytest.fail(f"non-standard JSON constant {c}"))


def assert_usage_error(capsys, argv, *phrases: str) -> str:
    """Exit 2, nothing on stdout, one line on stderr containing each phrase, no traceback."""
    status, out, err = run(capsys, *argv)
    assert status == 2, (out, err)
    assert out == ""
    assert err.count("\n") == 1 and err.startswith("isoforce"), err
    assert "Traceback" not in err
    for phrase in phrases:
        assert phrase in err, (phrase, err)
    return err


# -- devices, show --------------------------------------------------------------------------
def test_devices_lists_every_preset(capsys):
    status, out, _ = run(capsys, "devices")
    assert status == 0
    for key in list_presets():
        assert key in out
    d = run_json(capsys, "devices")
    assert [e["key"] for e in d["devices"]] == list_presets()
    assert {e["mechanism"] for e in d["devices"]} == {load_preset(k).kind for k in list_presets()}


@pytest.mark.parametrize("key", list_presets())
def test_show_prints_every_parameter_with_unit_and_value(capsys, key):
    mech = load_preset(key).mechanism
    d = run_json(capsys, "show", key)
    table = mech.parameter_table()
    assert [p["name"] for p in d["parameters"]] == [info.name for info, _ in table]
    for entry, (info, value) in zip(d["parameters"], table):
        assert entry["unit"] == info.unit
        assert entry["value"] == (list(value) if isinstance(value, tuple) else value)
        if info.labels:
            assert entry["labels"] == list(info.labels)
    status, out, _ = run(capsys, "show", key)
    assert status == 0
    for info, _ in table:
        assert f"\n{info.name} " in out


def test_show_vectors_are_labelled_and_match_the_issue_names(capsys):
    d = run_json(capsys, "show", "inverse3_prototype")
    params = {p["name"]: p for p in d["parameters"]}
    assert {"gear_ratios", "motor_torques", "proximal_length", "distal_length"} <= set(params)
    assert params["gear_ratios"]["labels"] == ["theta_0", "p1", "p2"]
    assert params["gear_ratios"]["value"] == [6.875, 5.957, 5.957]
    assert params["upper_limits"]["value"] == [45.0, 225.0, 114.0]        # no 114.00000000000001
    _, out, _ = run(capsys, "show", "inverse3_prototype")
    assert "theta_0 = 6.875, p1 = 5.957, p2 = 5.957" in out


def test_show_applies_set(capsys):
    d = run_json(capsys, "show", "fivebar_singh", "--set", "proximal=110", "gear_ratios=5,6")
    params = {p["name"]: p["value"] for p in d["parameters"]}
    assert params["proximal"] == 110.0 and params["gear_ratios"] == [5.0, 6.0]


# -- stats ----------------------------------------------------------------------------------
def expected_stats(mechanism, grid) -> dict:
    # The request ``stats`` makes: a figure is computed the same way only within one request (a
    # request the compiled kernels cover differs from the numpy graph's in the last bits of a mean).
    wmap = compute_map(mechanism, grid, summary_quantities(mechanism))
    return wmap, {q: wmap.stats[q] for q in CORE_QUANTITIES}


def assert_stats_equal(d: dict, wmap, stats) -> None:
    assert d["feasible_points"] == wmap.feasible_points
    for q in CORE_QUANTITIES:
        entry, s = d["quantities"][q], stats[q]
        # JSON floats round-trip exactly: the same numbers, not approximately.
        assert (entry["min"], entry["max"], entry["mean"], entry["sd"], entry["count"]) == \
            (s.min, s.max, s.mean, s.sd, s.count), q
        np.testing.assert_allclose(entry["argmin"], np.array(s.argmin) * 1e3, rtol=1e-15)
        np.testing.assert_allclose(entry["argmax"], np.array(s.argmax) * 1e3, rtol=1e-15)


def test_stats_json_equals_compute_map(capsys):
    d = run_json(capsys, "stats", "inverse3_prototype", "--resolution", "60")
    assert {"device", "resolution", "feasible_points", "seconds", "quantities"} <= set(d)
    assert d["device"] == "inverse3_prototype" and d["resolution"] == [60, 60]
    # The Inverse3 models its encoders (paper 000 Table 2), so its spatial resolution is reported too.
    assert set(d["quantities"]) == set(CORE_QUANTITIES) | {"inverse_condition_number", "spatial_resolution"} \
        | set(DYNAMIC_SUMMARY)                              # the Inverse3 has a mass model
    for entry in d["quantities"].values():
        assert {"min", "max", "mean", "sd", "median", "p05", "p95", "count", "singular_points", "unbounded",
                "argmin", "argmax"} <= set(entry)
    assert 0.0 < d["gci"]["value"] <= 1.0
    preset = load_preset("inverse3_prototype")
    assert_stats_equal(d, *expected_stats(preset.mechanism, preset.grid.with_resolution(60)))
    assert d["seconds"] > 0


def test_stats_in_a_real_subprocess_equals_compute_map():
    proc = subprocess.run([sys.executable, "-m", "app", "stats", "inverse3_prototype", "--resolution", "100",
                           "--json"], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    d = json.loads(proc.stdout)
    assert d["resolution"] == [100, 100] and d["feasible_points"] > 1000
    preset = load_preset("inverse3_prototype")
    assert_stats_equal(d, *expected_stats(preset.mechanism, preset.grid.with_resolution(100)))


def test_set_gear_ratios_changes_isotropic_force_as_the_model_says(capsys):
    base = run_json(capsys, "stats", "inverse3_prototype", "--resolution", "80")
    d = run_json(capsys, "stats", "inverse3_prototype", "--resolution", "80", "--set",
                 "gear_ratios=13.75,5.957,5.957")
    preset = load_preset("inverse3_prototype")
    mech = preset.mechanism.replace(gear_ratios=(13.75, 5.957, 5.957))
    assert_stats_equal(d, *expected_stats(mech, preset.grid.with_resolution(80)))
    # A stronger base joint raises the weakest isotropic force (paper 000, Scenario 2).
    assert d["quantities"]["isotropic_force"]["min"] > base["quantities"]["isotropic_force"]["min"]
    # The condition number has no torques in it.
    assert d["quantities"]["condition_number"] == base["quantities"]["condition_number"]
    assert d["overrides"] == {"gear_ratios": [13.75, 5.957, 5.957]}
    # Scenario 2 is that very device.
    scenario2 = run_json(capsys, "stats", "inverse3_scenario2", "--resolution", "80")
    assert scenario2["quantities"] == d["quantities"]


def test_stats_of_a_device_with_singular_points_is_strict_json(capsys):
    d = run_json(capsys, "stats", "fivebar_singh", "--resolution", "53")
    assert d["quantities"]["condition_number"]["max"] == "inf"


def test_stats_text_output_names_the_quantities(capsys):
    status, out, _ = run(capsys, "stats", "fivebar_singh", "--resolution", "40")
    assert status == 0
    for q in CORE_QUANTITIES:
        assert q in out
    assert "40 x 40 grid" in out


def test_stats_can_write_json_and_csv(capsys, tmp_path):
    for name in ("s.json", "s.csv"):
        status, _, err = run(capsys, "stats", "inverse3_prototype", "--resolution", "30", "--out",
                             str(tmp_path / name))
        assert status == 0, err
    d = json.loads((tmp_path / "s.json").read_text())
    assert d["resolution"] == [30, 30]
    assert (tmp_path / "s.csv").read_text().startswith(
        "quantity,unit,min,min_resolution_error,max,max_resolution_error,mean,mean_resolution_error,sd,")


def test_device_can_be_a_toml_path(capsys, tmp_path):
    from resources import preset_to_toml
    path = tmp_path / "my_device.toml"
    path.write_text(preset_to_toml(load_preset("fivebar_singh")))
    assert run_json(capsys, "stats", str(path), "--resolution", "20")["device"] == "my_device"


# -- pose -----------------------------------------------------------------------------------
def test_pose_json_equals_analyse_pose(capsys):
    d = run_json(capsys, "pose", "inverse3_prototype", "--at", "170,22.3,230")
    preset = load_preset("inverse3_prototype")
    expected = json.loads(json.dumps(to_dict(analyse_pose(preset.mechanism, np.array([0.170, 0.0223, 0.230])))))
    d.pop("device")
    for key in DYNAMIC_KEYS + VELOCITY_KEYS:      # masses and velocity: compared in their own tests
        d.pop(key, None)
    assert d == expected
    assert d["feasible"] and len(d["vertices"]) == 8


def test_pose_defaults_to_the_preset_pose_and_takes_negative_coordinates(capsys):
    d = run_json(capsys, "pose", "fivebar_singh")
    assert d["x"] == [0.0, 150.0]
    d = run_json(capsys, "pose", "fivebar_singh", "--at", "-50,150")
    report = analyse_pose(load_preset("fivebar_singh").mechanism, np.array([-0.050, 0.150]))
    assert d["isotropic_force"] == report.isotropic_force
    assert d["singularity"] == "none"
    assert d["bottleneck_actuator"] == report.bottleneck_name


def test_pose_applies_set(capsys):
    d = run_json(capsys, "pose", "inverse3_prototype", "--set", "gear_ratios=13.75,5.957,5.957")
    assert d["torque_limits"][0] == pytest.approx(1.375)


def test_pose_text_shows_the_report(capsys):
    report = analyse_pose(load_preset("inverse3_prototype").mechanism, np.array([0.170, 0.0223, 0.230]))
    status, out, _ = run(capsys, "pose", "inverse3_prototype", "--at", "170,22.3,230")
    assert status == 0
    assert f"isotropic force           {report.isotropic_force:.6g} N, bottleneck {report.bottleneck_name}" in out
    assert f"{report.anisotropic_force:.6g} N" in out
    for heading in ("joints (deg)", "Jacobian, rows x, y, z (mm), columns theta_0, p1, p2 (rad)",
                    "singular values (mm/rad)", "actuator limits (N m)", "polytope vertices",
                    "force ellipsoid", "velocity ellipsoid"):
        assert heading in out


def test_pose_of_wrench_devices_names_units_per_row_and_column_and_the_scaling(capsys):
    """Stewart legs are prismatic: leg limits in N, J in (mm or rad) per mm; forces at zero moment."""
    d = run_json(capsys, "pose", "stewart_platform")
    u = d["units"]
    assert u["torque_limits"] == "N"
    assert u["jacobian_rows"] == ["mm"] * 3 + ["rad"] * 3 and u["jacobian_columns"] == ["mm"] * 6
    assert u["jacobian"][0][0] == "mm/mm" and u["jacobian"][3][0] == "rad/mm"
    assert u["isotropic_force"] == "N" and u["isotropic_moment"] == "N m" and u["anisotropic_moment"] == "N m"
    mech = load_preset("stewart_platform").mechanism
    assert d["condition_number_scaling"] == {"length_m": mech.params.platform_radius}
    # The zero-moment ball of six 10 N legs, not the 0.35 (N, N m) mixed one.
    assert d["isotropic_force"] > 5.0 and d["anisotropic_force"] > d["isotropic_force"]
    assert d["signs"] is None and len(d["vertices"][0]) == 3
    status, out, _ = run(capsys, "pose", "stewart_platform")
    assert status == 0
    assert "condition number (moments scaled by L = 30 mm)" in out
    assert "actuator limits (N)" in out and "isotropic moment at zero force" in out
    d = run_json(capsys, "pose", "twin_pantograph")
    assert d["units"]["torque_limits"] == "N m" and d["units"]["jacobian_columns"] == ["rad"] * 6
    # L is each U-joint's distance from the pen's centre: ujoint_lever x l6 = 1.0 x 70 mm (paper 001's reading).
    assert d["condition_number_scaling"] == {"length_m": 0.07}


def test_stats_of_a_wrench_device_reports_moments_and_names_the_scaling(capsys):
    d = run_json(capsys, "stats", "stewart_platform", "--resolution", "9")
    assert d["condition_number_scaling"]["length_m"] == pytest.approx(0.03)
    assert d["quantities"]["isotropic_moment"]["unit"] == "N m"
    assert d["quantities"]["anisotropic_force"]["unit"] == "N"


def test_point_outside_the_workspace_exits_2(capsys):
    err = assert_usage_error(capsys, ["pose", "inverse3_prototype", "--at", "2000,0,0"],
                             "--at", "outside the workspace", "no joint angles reach it")
    assert "(2000, 0, 0) mm" in err
    assert_usage_error(capsys, ["pose", "inverse3_prototype", "--at", "50,22.3,100", "--json"],
                       "outside the workspace", "joint limit or physical constraint")


# -- map ------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def i3_iso_map():
    preset = load_preset("inverse3_prototype")
    return compute_map(preset.mechanism, preset.grid.with_resolution(50), ["isotropic_force"])


@pytest.mark.parametrize("suffix", [".png", ".svg", ".pdf", ".csv", ".npz"])
def test_map_export_reads_back(capsys, tmp_path, suffix, i3_iso_map):
    out = tmp_path / f"map{suffix}"
    status, stdout, err = run(capsys, "map", "inverse3_prototype", "--quantity", "isotropic_force",
                              "--resolution", "50", "--out", str(out))
    assert status == 0, err
    assert err == "" and stdout.startswith(f"wrote {out}")
    data = out.read_bytes()
    if suffix == ".png":
        assert data[:8] == b"\x89PNG\r\n\x1a\n"
        from app.plots.figures import map_figure
        fig = map_figure(i3_iso_map, "isotropic_force", load_preset("inverse3_prototype"))
        width, height = fig.canvas.get_width_height()
        assert matplotlib.image.imread(out).shape[:2] == (height, width)
    elif suffix == ".svg":
        assert ET.fromstring(data).tag.endswith("svg")
    elif suffix == ".pdf":
        assert data.startswith(b"%PDF")
    elif suffix == ".csv":
        from app.files.export import read_map_csv
        table = read_map_csv(out)        # a row per feasible point: the grid rebuilt
        np.testing.assert_array_equal(table.values["isotropic_force"], i3_iso_map.values["isotropic_force"])
        np.testing.assert_array_equal(table.feasible, i3_iso_map.feasible)
    else:
        with np.load(out) as npz:
            np.testing.assert_array_equal(npz["isotropic_force"], i3_iso_map.values["isotropic_force"])
    assert sorted(p.name for p in tmp_path.iterdir()) == [out.name]


def test_map_data_files_take_several_quantities(capsys, tmp_path):
    out = tmp_path / "fb.npz"
    status, _, err = run(capsys, "map", "fivebar_singh", "--quantity", "condition_number,singularity",
                         "--resolution", "30", "--out", str(out))
    assert status == 0, err
    with np.load(out) as npz:
        assert list(npz["quantities"]) == ["condition_number", "singularity"]


def test_failed_figure_export_leaves_no_file(capsys, tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    def write_half_then_fail(self, fname, **kwargs):
        Path(fname).write_bytes(b"\x89PNG half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Figure, "savefig", write_half_then_fail)
    assert_usage_error(capsys, ["map", "inverse3_prototype", "--quantity", "isotropic_force", "--resolution",
                                "20", "--out", str(tmp_path / "map.png")], "No space left on device")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("argv, phrases", [
    (["show", "inverse4"], ["DEVICE", "unknown device 'inverse4'"]),
    (["stats", "inverse3_prototype", "--set", "wheels=4"], ["--set", "'wheels'"]),
    (["stats", "inverse3_prototype", "--set", "gear_ratios"], ["--set needs NAME=VALUE"]),
    (["stats", "inverse3_prototype", "--set", "gear_ratios=1,2"], ["--set", "gear_ratios needs 3 values"]),
    (["stats", "inverse3_prototype", "--set", "proximal_length=long"], ["--set", "proximal_length", "'long'"]),
    (["stats", "inverse3_prototype", "--set", "proximal_length=-140"], ["--set", "proximal_length", "positive"]),
    (["stats", "inverse3_prototype", "--resolution", "1"], ["--resolution", "integer >= 2", "'1'"]),
    (["stats", "inverse3_prototype", "--out", "stats.txt"], ["--out", "'stats.txt'"]),
    (["pose", "inverse3_prototype", "--at", "1,2"], ["--at needs X,Y,Z in millimetres, got '1,2'"]),
    (["pose", "fivebar_singh", "--at", "1,2,3"], ["--at needs X,Y in millimetres, got '1,2,3'"]),
    (["pose", "inverse3_prototype", "--at", "a,b,c"], ["--at", "'a,b,c'"]),
    (["pose", "inverse3_prototype", "--at", "nan,0,0"], ["--at", "'nan,0,0'"]),
    (["map", "inverse3_prototype", "--quantity", "grip", "--out", "m.png"], ["--quantity", "'grip'"]),
    (["map", "inverse3_prototype", "--quantity", "singularity", "--out", "m.png"], ["--quantity", "singularity"]),
    (["map", "inverse3_prototype", "--quantity", "jacobian", "--out", "m.csv"], ["--quantity", "'jacobian'"]),
    (["map", "inverse3_prototype", "--quantity", "isotropic_force,condition_number", "--out", "m.png"],
     ["--quantity", "one quantity"]),
    (["map", "inverse3_prototype", "--quantity", "isotropic_force", "--out", "m.jpg"], ["--out", "'m.jpg'"]),
    (["map", "inverse3_prototype", "--quantity", "isotropic_force", "--out", "/no/such/dir/m.png"],
     ["--out", "/no/such/dir"]),
    (["map", "inverse3_prototype", "--quantity", "isotropic_force"], ["--out"]),
    (["frobnicate"], ["frobnicate"]),
])
def test_bad_input_is_one_line_naming_the_argument(capsys, tmp_path, monkeypatch, argv, phrases):
    monkeypatch.chdir(tmp_path)      # relative --out names land here, and must not appear
    assert_usage_error(capsys, argv, *phrases)
    assert list(tmp_path.iterdir()) == []


def test_malformed_preset_file_names_file_and_key(capsys, tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('name = "x"\nmechanism = "fivebar"\n[parameters]\nproximal = -1\n')
    assert_usage_error(capsys, ["stats", str(path)], "DEVICE", "bad.toml", "key 'parameters.proximal'")


def test_unwritable_folder_is_a_usage_error(capsys, tmp_path):
    # /proc refuses new files even to root; a plain file as the folder fails for everyone.
    if Path("/proc/self").is_dir():
        assert_usage_error(capsys, ["map", "fivebar_singh", "--quantity", "isotropic_force", "--resolution", "10",
                                    "--out", "/proc/m.csv"], "--out", "cannot write in folder '/proc'")
    plain = tmp_path / "plain.txt"
    plain.write_text("not a folder")
    assert_usage_error(capsys, ["map", "fivebar_singh", "--quantity", "isotropic_force", "--resolution", "10",
                                "--out", str(plain / "m.csv")], "--out", "does not exist")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plain.txt"]


# -- the app, help, other modules' commands --------------------------------------------------
def test_no_arguments_without_the_app_says_so_and_exits_0(capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "app.gui", None)      # import fails as if absent
    status = launch.main([])
    out, _ = capsys.readouterr()
    assert status == 0 and out.strip() == launch.GUI_MISSING


def test_no_arguments_launches_the_app_when_it_exists(capsys, monkeypatch):
    calls = []
    fake = types.ModuleType("app.gui")
    fake.run_app = lambda: calls.append("run") or 0
    monkeypatch.setitem(sys.modules, "app.gui", fake)
    assert launch.main([]) == 0 and calls == ["run"]


def test_the_command_line_alone_needs_a_command(capsys):
    assert_usage_error(capsys, [], "a COMMAND is needed")


def test_a_command_goes_to_the_command_line_not_the_app(capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "app.gui", None)
    status = launch.main(["devices"])
    out, _ = capsys.readouterr()
    assert status == 0 and "inverse3_prototype" in out


def test_a_command_leaves_its_objects_out_of_the_interpreters_last_collection(capsys):
    """After a command the objects alive are frozen: the full collection at the interpreter's
    exit skips them (0.3 s of a figure command's 2.7 s); a frozen object is one gc no longer lists."""
    import gc

    marker = type("Marker", (), {})()
    assert any(o is marker for o in gc.get_objects())
    assert launch.main(["devices"]) == 0
    capsys.readouterr()
    assert gc.get_freeze_count() > 0 and not any(o is marker for o in gc.get_objects())


def test_help_exits_0(capsys):
    status, out, _ = run(capsys, "--help")
    assert status == 0
    for command in ("devices", "show", "stats", "pose", "map"):
        assert command in out


def test_other_modules_register_their_commands(capsys, monkeypatch):
    def register(subparsers):
        p = subparsers.add_parser("convergence")
        p.add_argument("device")
        p.set_defaults(func=lambda args: print(f"converging {args.device}") or 0)

    fake = types.ModuleType("app.cli.convergence")
    fake.register = register
    monkeypatch.setitem(sys.modules, "app.cli.convergence", fake)
    status, out, _ = run(capsys, "convergence", "fivebar_singh")
    assert status == 0 and out == "converging fivebar_singh\n"


def test_missing_command_module_is_skipped_and_broken_one_reported(capsys, monkeypatch):
    real = cli.importlib.import_module

    def fake_import(name, *args):
        if name == "app.cli.convergence":
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        if name == "app.cli.bench":
            raise ModuleNotFoundError("No module named 'pycapacity'", name="pycapacity")
        return real(name, *args)

    monkeypatch.setattr(cli.importlib, "import_module", fake_import)
    assert_usage_error(capsys, ["convergence", "fivebar_singh"], "invalid choice: 'convergence'")
    assert_usage_error(capsys, ["bench"], "`isoforce bench` is unavailable", "pycapacity")


def test_cli_and_figures_import_no_qt_or_vtk_nor_the_gui():
    code = ("import sys, app.cli, app.plots.figures, app.files.export, app.launch, app.logic.pose_report, "
            "metrics.pose; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('PySide6', 'pyvista', 'vtk', 'pyvistaqt')]; "
            "assert not bad, bad; "
            # every subcommand registered (`figure` renders with pyvista off-screen): still no Qt, no GUI
            "app.cli.build_parser(); "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('PySide6', 'pyvistaqt') "
            "or m.startswith('app.gui')]; "
            "assert not bad, bad")
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr


# -- issue 7, section 6: bad output paths, empty maps, bad files, messages ----------------------
@pytest.mark.parametrize("argv", [("stats", "inverse3_prototype", "--resolution", "2"),
                                  ("stats", "inverse3_prototype", "--resolution", "30", "--set", "distal_length=10")])
def test_a_map_with_no_feasible_point_says_so_in_text_and_json(capsys, argv):
    """Before: text mode crashed with "operands could not be broadcast together"."""
    status, out, err = run(capsys, *argv)
    assert status == 0, err
    assert "0 of" in out and "no feasible point" in out and err == ""
    d = run_json(capsys, *argv)
    assert d["feasible_points"] == 0 and "no feasible point" in d["message"]
    assert all(q["count"] == 0 and q["min"] is None for q in d["quantities"].values())


def test_output_paths_are_checked_before_computing(capsys, tmp_path):
    assert_usage_error(capsys, ["stats", "fivebar_singh", "--out", str(tmp_path / "s.txt")], "--out", ".json")
    assert_usage_error(capsys, ["map", "fivebar_singh", "--quantity", "isotropic_force", "--out", "/proc/m.csv"],
                       "--out", "cannot write")
    folder = tmp_path / "d.csv"
    folder.mkdir()
    assert_usage_error(capsys, ["map", "fivebar_singh", "--quantity", "isotropic_force", "--out", str(folder)],
                       "--out", "folder")
    assert_usage_error(capsys, ["figure", "fivebar_singh", "--out", "/proc/f.png"], "--out", "cannot write")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.csv"]


def test_set_errors_show_the_value_in_the_unit_typed(capsys):
    """Before: "proximal_length must be a positive finite number in m, got -0.005"."""
    err = assert_usage_error(capsys, ["show", "inverse3_prototype", "--set", "proximal_length=-5"],
                             "--set", "proximal_length = -5 mm")
    assert "0.005" not in err
    err = assert_usage_error(capsys, ["show", "inverse3_prototype", "--set", "lower_limits=0,500,0"],
                             "lower_limits[p1] must be below upper_limits[p1]", "0, 500, 0 deg")
    assert "8.72" not in err          # 500 deg in rad
    assert_usage_error(capsys, ["show", "fivebar_singh", "--set", "proximal=abc"], "'abc'")


def test_a_preset_pose_outside_its_workspace_names_the_preset_key(capsys, tmp_path):
    text = (ROOT / "resources" / "presets" / "fivebar_singh.toml").read_text(encoding="utf-8")
    lines = [("at = [900.0, 900.0]" if line.startswith("at =") else line) for line in text.splitlines()]
    path = tmp_path / "far_pose.toml"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    for argv in (["pose", str(path)], ["figure", str(path), "--view", "pose", "--out", str(tmp_path / "p.png")]):
        err = assert_usage_error(capsys, argv, "far_pose.toml", "pose.at", "(900, 900) mm", "outside the workspace")
        assert "--at (" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["far_pose.toml"]


def test_figure_pose_at_an_unreachable_point_exits_2_like_pose(capsys, tmp_path):
    """Before: it drew the figure and exited 0."""
    out = tmp_path / "p.png"
    for argv in (["pose", "fivebar_singh", "--at", "1000,1000"],
                 ["figure", "fivebar_singh", "--view", "pose", "--at", "1000,1000", "--out", str(out)]):
        assert_usage_error(capsys, argv, "--at (1000, 1000) mm", "outside the workspace", "no joint angles")
    assert not out.exists()


def test_a_map_too_large_for_memory_is_refused_with_advice(capsys, monkeypatch):
    monkeypatch.setenv("ISOFORCE_MEMORY", "4G")
    err = assert_usage_error(capsys, ["map", "fivebar_singh", "--quantity", "isotropic_force", "--resolution",
                                      "100000", "--out", "m.npz"], "--resolution", "10,000,000,000 points",
                             "4.29 GB available", "or less")
    n = int(err.split("use --resolution ")[1].split()[0])
    from metrics.budget import map_estimate
    est = map_estimate(load_preset("fivebar_singh").mechanism, (n, n), ["isotropic_force"], output="npz")
    assert est.bytes <= 0.8 * (4 << 30)
    # Streamed statistics fit at any resolution the grid can index; 2**32 per axis cannot.
    assert_usage_error(capsys, ["stats", "fivebar_singh", "--resolution", "4294967296"], "can index")


def test_pose_text_at_the_double_singularity_names_both_legs_and_no_noise(capsys):
    status, out, _ = run(capsys, "pose", "fivebar_singh", "--at", "0,40")
    assert status == 0
    assert "inverse (theta_1, theta_2 stretched or folded)" in out
    assert "isotropic force           inf N" in out and "condition number          inf" in out
    assert "force polytope is unbounded" in out and "nan" not in out


# -- pose --joints ----------------------------------------------------------------------------
@pytest.mark.parametrize("key", list_presets())
def test_pose_at_joints_equals_pose_at_the_point_of_their_forward_kinematics(capsys, key):
    """--joints A,B,C: FK gives the point, and the report is the one of that point (round trip)."""
    from app.cli._format import dumps
    from app.cli.pose import SAME_JOINTS
    from kinematics.units import joints_from_si, joints_to_si
    from metrics.pose_dynamics import analyse_dynamics, dynamics_dict

    preset = load_preset(key)
    mech = preset.mechanism
    q, ok = mech.inverse(np.array(preset.pose))
    assert bool(ok)
    typed = joints_from_si(mech, q).tolist()
    text = ",".join(repr(v) for v in typed)
    d = run_json(capsys, "pose", key, "--joints", text)
    x, assembled = mech.forward(joints_to_si(mech, typed))
    assert bool(assembled)
    expected = to_dict(analyse_pose(mech, x))
    expected.update(dynamics_dict(analyse_dynamics(mech, x), mech) if mech.has_mass_model
                    else {"dynamics": f"not computed: {mech._no_mass_model()}"})
    from app.cli.pose import pose_velocity
    from app.logic.pose_report import velocity_dict
    velocity, why_not = pose_velocity(preset, analyse_pose(mech, x))
    expected.update(velocity_dict(velocity, reason=why_not, source=preset.motor_speeds_source,
                                  task_units=mech.task_units))
    expected = json.loads(dumps(expected))
    d.pop("device")
    assert d == expected
    # The report's joints are the typed ones (same working mode), to the module's own tolerance.
    back = joints_from_si(mech, analyse_pose(mech, x).joints)
    assert np.max(np.abs(back - np.array(typed))) <= SAME_JOINTS
    # And `--at` of that point, typed in mm as the report prints it, gives the same pose: the
    # point differs from x by the mm -> m rounding (1 ulp per coordinate), so the forces agree to
    # a relative 1e-9, far above that rounding times the condition number (<= 1e3 here).
    at = ",".join(repr(v) for v in d["x"])
    d_at = run_json(capsys, "pose", key, "--at", at)
    assert d_at["isotropic_force"] == pytest.approx(d["isotropic_force"], rel=1e-9)
    assert d_at["anisotropic_force"] == pytest.approx(d["anisotropic_force"], rel=1e-9)
    assert d_at["joints"] == pytest.approx(d["joints"], rel=1e-9, abs=1e-9)


def test_pose_joints_take_negative_values_and_show_them_in_the_text(capsys):
    status, out, err = run(capsys, "pose", "fivebar_singh", "--joints", "-30,250")
    assert status == 0, err
    assert "theta_1 = -30" in out


def test_pose_joints_that_do_not_assemble_exit_2_naming_joints(capsys):
    assert_usage_error(capsys, ["pose", "stewart_platform", "--joints", "2400,240,240,240,240,240"],
                       "--joints", "does not assemble", "L1 = 2400 mm")
    assert_usage_error(capsys, ["pose", "fivebar_singh", "--joints", "1,2,3"], "--joints needs 2",
                       "theta_1 (deg)", "'1,2,3'")
    assert_usage_error(capsys, ["pose", "fivebar_singh", "--joints", "a,b"], "--joints", "'a,b'")
    # The point of joints on another IK branch than the preset's working mode: said, not silently swapped.
    assert_usage_error(capsys, ["pose", "fivebar_singh", "--joints", "0,0"], "--joints", "working mode",
                       "another assembly or IK branch")
    # Assembles, but outside the workspace (a leg limit).
    assert_usage_error(capsys, ["pose", "stewart_platform", "--joints", "240,240,240,240,240,240"],
                       "--joints 240,240,240,240,240,240: its point", "outside the workspace")


def test_pose_at_and_joints_together_is_an_error(capsys):
    assert_usage_error(capsys, ["pose", "fivebar_singh", "--at", "0,150", "--joints", "147.8,32.2"],
                       "--joints", "--at", "not allowed")


def test_show_prints_a_presets_sources_and_estimates(capsys):
    from resources import load_preset

    status, out, _ = run(capsys, "show", "novint_falcon")
    assert status == 0
    assert "source:" in out and "https://github.com/libnifalcon/libnifalcon" in out
    assert "estimated: " in out and "motor_torques" in out.split("estimated: ")[1].splitlines()[0]
    d = run_json(capsys, "show", "novint_falcon")
    assert d["provenance"] == {k: list(v) if isinstance(v, tuple) else v
                               for k, v in load_preset("novint_falcon").provenance}
    # The five-bar's paper gives its geometry; what it leaves out (the motors and the mass model) is
    # listed as estimated, each with its basis.
    five = run_json(capsys, "show", "fivebar_singh")["provenance"]
    assert set(five["estimated"]) >= {"link_masses", "rotor_inertias"}
    assert all(five[f"lines.{k}"].startswith("estimated: ") for k in ("link_masses", "rotor_inertias"))


def test_launching_the_app_gives_the_callers_ctrl_c_handler_back(monkeypatch):
    import signal

    fake = types.ModuleType("app.gui")
    fake.run_app = lambda: 7 if signal.getsignal(signal.SIGINT) is signal.SIG_DFL else 3
    monkeypatch.setitem(sys.modules, "app.gui", fake)
    before = signal.getsignal(signal.SIGINT)
    assert launch.main([]) == 7            # the app started under the system's default handler
    assert signal.getsignal(signal.SIGINT) is before


def freezes_counted(monkeypatch) -> list:
    """``gc.freeze`` replaced by one that counts its calls (and freezes): the freeze count itself
    also falls when frozen objects die, which other tests in this process decide."""
    import gc

    calls, freeze = [], gc.freeze
    monkeypatch.setattr(gc, "freeze", lambda: (calls.append(1), freeze())[1])
    return calls


def test_the_final_collections_are_skipped_at_exit_only(capsys, monkeypatch):
    """``main`` registers ``gc.freeze`` with ``atexit`` once a process: nothing is frozen while
    commands run in this process; in a fresh one the hook runs at exit (a hook registered
    before ``main`` runs after it and sees the frozen objects), and the command's JSON is whole."""
    freezes = freezes_counted(monkeypatch)
    assert main(["devices"]) == 0 and main(["devices"]) == 0
    capsys.readouterr()
    assert freezes == [] and cli._FREEZE_AT_EXIT == [True]
    code = ("import atexit, gc, sys\n"
            "atexit.register(lambda: print('frozen', gc.get_freeze_count() > 0, file=sys.stderr))\n"
            "from app.cli import main\n"
            "sys.exit(main(['stats', 'fivebar_singh', '--resolution', '40', '--json']))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=Path(cli.__file__).resolve().parents[2])
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["device"] == "fivebar_singh"
    assert done.stderr.strip().splitlines()[-1] == "frozen True"


def test_a_command_line_process_ends_without_teardown_but_with_its_output_and_handlers():
    """``python -m app.cli`` ends through ``end_process``: the output whole, the status main's, the
    ``atexit`` handlers run (after main's, as at an interpreter's exit); a bad input keeps its status 2."""
    root = Path(cli.__file__).resolve().parents[2]
    code = ("import atexit, sys\n"
            "atexit.register(lambda: print('handler ran', file=sys.stderr))\n"
            "from app.cli._process import end_process\n"
            "from app.cli import main\n"
            "end_process(main(sys.argv[1:]))\n")
    done = subprocess.run([sys.executable, "-c", code, "stats", "fivebar_singh", "--resolution", "40", "--json"],
                          capture_output=True, text=True, cwd=root, timeout=120)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["device"] == "fivebar_singh"
    assert done.stderr.strip().splitlines()[-1] == "handler ran"
    bad = subprocess.run([sys.executable, "-m", "app.cli", "stats", "no_such_device"], capture_output=True,
                         text=True, cwd=root, timeout=120)
    assert bad.returncode == 2 and bad.stdout == "" and "no_such_device" in bad.stderr


def test_end_process_skips_the_teardown_but_not_the_c_librarys_buffered_output():
    """What ``end_process`` skips is seen nowhere outside the process: an object whose finaliser
    would print at the interpreter's teardown prints nothing (the teardown is skipped: ``sys.exit``
    would run it), while a line the C library buffered for a pipe (``printf``) is written."""
    code = ("import ctypes\n"
            "from app.cli._process import end_process\n"
            "class Loud:\n"
            "    def __del__(self):\n"
            "        print('torn down')\n"
            "kept = Loud()\n"
            "ctypes.CDLL(None).printf(b'from C\\n')\n"
            "print('from Python')\n"
            "end_process(3)\n")
    # (Without PYTHONUNBUFFERED: set, Python makes the C library's stdout unbuffered too, and a
    # lost buffer could not be seen.)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                          cwd=Path(cli.__file__).resolve().parents[2], timeout=120)
    assert done.returncode == 3, done.stderr
    assert sorted(done.stdout.splitlines()) == ["from C", "from Python"]
    ended = subprocess.run([sys.executable, "-c", code.replace("end_process(3)", "raise SystemExit(3)")],
                           capture_output=True, text=True, cwd=Path(cli.__file__).resolve().parents[2], timeout=120)
    assert "torn down" in ended.stdout.splitlines()       # (the test can fail: the teardown does print)


def test_the_start_up_runs_without_collections_in_a_command_line_process_only(capsys, monkeypatch):
    """In a test's process ``main`` turns no collector off and freezes nothing; in a process whose entry
    turned it off (``python -m app.cli``), the command runs with it back on and the start-up frozen."""
    import gc

    from app.cli import _process

    freezes, enabled = freezes_counted(monkeypatch), gc.isenabled()
    assert main(["stats", "fivebar_singh", "--resolution", "40", "--json"]) == 0
    capsys.readouterr()
    with _process.start_up_window():
        assert gc.isenabled() == enabled
    assert freezes == [] and gc.isenabled() == enabled and not _process._OWNED
    code = ("import gc, sys\n"
            "from app.cli._process import start_up_without_collections\n"
            "start_up_without_collections()\n"
            "from app.cli import main\n"
            "assert not gc.isenabled()\n"
            "status = main(['stats', 'fivebar_singh', '--resolution', '40', '--json'])\n"
            "print('collector', gc.isenabled(), gc.get_freeze_count() > 0, file=sys.stderr)\n"
            "sys.exit(status)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=Path(cli.__file__).resolve().parents[2], timeout=120)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["device"] == "fivebar_singh"
    assert done.stderr.strip().splitlines()[-1] == "collector True True"


def test_importing_the_command_line_package_imports_no_numpy():
    """``python -m app.cli`` turns the collector off once ``app.cli`` is imported: the package itself
    must leave numpy and the subcommands' imports to the start-up that follows."""
    done = subprocess.run([sys.executable, "-c", "import sys, app.cli; print('numpy' in sys.modules)"],
                          capture_output=True, text=True, cwd=Path(cli.__file__).resolve().parents[2], timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "False"
