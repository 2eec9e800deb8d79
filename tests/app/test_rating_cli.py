"""``--rating`` and ``--gravity`` on ``stats``, ``pose``, ``map``, ``compare`` and ``show``.

Each output is checked against the compute layer run with the same ``metrics.loading.Loading``,
and each refusal is one line on stderr, exit 2, naming the option and the device.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from app.cli import main
from app.logic.pose_report import VELOCITY_KEYS, to_dict
from metrics.loading import Loading
from metrics.pose import analyse_pose
from metrics.pose_dynamics import DYNAMIC_KEYS
from metrics.workspace import compute_map
from resources import load_preset
from tests.preset_files import massless_omni


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
    assert out == "" and err.count("\n") == 1 and err.startswith("isoforce") and "Traceback" not in err, err
    for phrase in phrases:
        assert phrase in err, (phrase, err)
    return err



# -- stats ---------------------------------------------------------------------------------------
def test_stats_with_gravity_equals_the_loaded_map(capsys):
    d = run_json(capsys, "stats", "phantom_premium_15", "--resolution", "40", "--gravity")
    assert d["loading"]["rating"] == "continuous"
    assert d["loading"]["gravity"] == {"mounting": "upright", "vector": [0.0, 0.0, -9.80665], "unit": "m/s^2",
                                       "frame": "base"}
    preset = load_preset("phantom_premium_15")
    assert d["loading"]["torque_limits"] == preset.mechanism.torque_limits().tolist()
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution(40), ["isotropic_force"], keep=False,
                       loading=Loading.mounted("upright"))
    assert d["quantities"]["isotropic_force"]["mean"] == wmap.stats["isotropic_force"].mean
    assert d["quantities"]["isotropic_force"]["min"] == wmap.stats["isotropic_force"].min
    off = run_json(capsys, "stats", "phantom_premium_15", "--resolution", "40")
    assert off["loading"]["gravity"] == "off"
    assert off["quantities"]["isotropic_force"]["mean"] != d["quantities"]["isotropic_force"]["mean"]


def test_stats_text_says_the_rating_and_gravity(capsys):
    status, out, _ = run(capsys, "stats", "phantom_premium_15", "--resolution", "30", "--rating", "peak",
                         "--gravity", "0,9.80665,0")
    assert status == 0
    assert "torque rating: peak (q1 = 1.7157 N m, q2 = 1.4448 N m, q3 = 1.4448 N m)" in out
    assert "gravity (0, 9.80665, 0) m/s^2 in the base frame" in out
    status, out, _ = run(capsys, "stats", "phantom_premium_15", "--resolution", "30")
    assert "torque rating: continuous (q1 = 0.38038 N m" in out and "gravity off" in out


def test_stats_out_json_carries_the_loading(capsys, tmp_path):
    target = tmp_path / "s.json"
    status, _, err = run(capsys, "stats", "phantom_premium_15", "--resolution", "20", "--gravity", "inverted",
                         "--out", str(target))
    assert status == 0, err
    assert json.loads(target.read_text())["loading"]["gravity"]["mounting"] == "inverted"


@pytest.mark.parametrize(("argv", "phrases"), [
    (["stats", "inverse3_prototype", "--rating", "peak"],
     ["--rating peak", "device inverse3_prototype has no peak torque rating", "--rating continuous"]),
    (["stats", "novint_falcon", "--rating", "peak"], ["--rating peak", "device novint_falcon"]),
    (["stats", "phantom_omni", "--gravity"], ["--gravity upright", "device phantom_omni has no mass model"]),
    (["pose", "phantom_omni", "--gravity", "x-up"], ["--gravity x-up", "device phantom_omni"]),
    (["map", "inverse3_prototype", "--quantity", "isotropic_force", "--out", "m.npz", "--rating", "peak"],
     ["--rating peak", "inverse3_prototype"]),
    (["stats", "phantom_premium_15", "--gravity", "1,2"], ["--gravity needs a mounting", "'1,2'"]),
    (["stats", "phantom_premium_15", "--gravity", "sideways"], ["--gravity needs a mounting", "upright"]),
    (["stats", "phantom_premium_15", "--gravity", "0,0,nan"], ["--gravity needs", "'0,0,nan'"]),
    (["compare", "phantom_premium_15", "inverse3_prototype", "--rating", "peak"],
     ["--rating peak", "device inverse3_prototype"]),
])
def test_loading_refusals_name_the_option_and_device(capsys, tmp_path, monkeypatch, argv, phrases):
    monkeypatch.chdir(tmp_path)
    argv = [massless_omni(tmp_path) if a == "phantom_omni" else a for a in argv]
    assert_usage_error(capsys, argv, *phrases)
    assert not (tmp_path / "m.npz").exists()


def test_rating_choices_are_checked_by_argparse(capsys):
    assert_usage_error(capsys, ["stats", "phantom_premium_15", "--rating", "max"], "--rating", "invalid choice: 'max'")


# -- pose ----------------------------------------------------------------------------------------
def test_pose_json_equals_the_loaded_report(capsys):
    d = run_json(capsys, "pose", "phantom_premium_15", "--rating", "peak", "--gravity", "y-up")
    preset = load_preset("phantom_premium_15")
    loading = Loading.mounted("y-up", rating="peak")
    expected = json.loads(json.dumps(to_dict(analyse_pose(preset.mechanism, np.array(preset.pose),
                                                          loading=loading))))
    d.pop("device")
    for key in DYNAMIC_KEYS + VELOCITY_KEYS:      # masses, weight, velocity: compared in their own tests
        d.pop(key, None)
    assert d == expected
    assert d["loading"] == loading.as_dict()
    assert d["units"]["torque_bias"] == "N m" and d["units"]["force_centre"] == "N"
    assert np.allclose(d["torque_bias"], preset.mechanism.gravity_torque(
        analyse_pose(preset.mechanism, np.array(preset.pose)).joints, loading.gravity), rtol=0, atol=0)


def test_pose_text_shows_the_gravity_torque_and_the_shifted_set(capsys):
    status, out, _ = run(capsys, "pose", "phantom_premium_15", "--gravity")
    assert status == 0
    for phrase in ("torque rating: continuous", "gravity upright (0, 0, -9.80665) m/s^2", "gravity torque (N m)",
                   "force set centre (N)", "half-edges of the shifted polytope", "(shifted by the gravity torque)",
                   "force ellipsoid (unbiased"):
        assert phrase in out, phrase
    status, out, _ = run(capsys, "pose", "phantom_premium_15")
    assert "gravity off" in out and "gravity torque" not in out


# -- map, compare, show --------------------------------------------------------------------------
def test_map_data_is_the_loaded_map(capsys, tmp_path):
    target = tmp_path / "m.npz"
    status, out, err = run(capsys, "map", "phantom_premium_15", "--quantity", "isotropic_force", "--resolution",
                           "25", "--out", str(target), "--gravity", "inverted")
    assert status == 0 and err == "", err
    assert "continuous rating, gravity inverted (0, 0, 9.80665) m/s^2" in out
    preset = load_preset("phantom_premium_15")
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution(25), ["isotropic_force"],
                       loading=Loading.mounted("inverted"))
    with np.load(target) as data:
        assert np.array_equal(data["isotropic_force"], wmap.values["isotropic_force"], equal_nan=True)


def test_compare_at_the_peak_rating(capsys, tmp_path):
    d = run_json(capsys, "compare", "phantom_premium_15", "phantom_omni", "--resolution", "25", "--rating", "peak")
    assert d["loading"] == "at the peak torque rating, gravity off"
    for row in d["devices"]:
        preset = load_preset(row["key"])
        assert row["loading"]["torque_limits"] == preset.mechanism.peak_torque_limits().tolist()
        wmap = compute_map(preset.mechanism, preset.grid.with_resolution(25), ["isotropic_force"], keep=False,
                           loading=Loading(rating="peak"))
        assert row["isotropic_force"]["min"] == wmap.stats["isotropic_force"].min
    status, out, _ = run(capsys, "compare", "phantom_premium_15", "--resolution", "20", "--gravity",
                         "--out", str(tmp_path / "c.csv"))
    assert status == 0 and out.startswith("forces at the continuous torque rating, gravity upright")
    header, row = (tmp_path / "c.csv").read_text().splitlines()
    assert header.endswith(",rating,gravity_m_s2") and row.endswith(",continuous,0.0 0.0 -9.80665")


def test_show_lists_the_ratings_and_the_gravity_model(capsys, tmp_path):
    d = run_json(capsys, "show", "phantom_premium_15")
    mech = load_preset("phantom_premium_15").mechanism
    assert d["ratings"]["continuous"] == mech.torque_limits().tolist()
    assert d["ratings"]["peak"] == mech.peak_torque_limits().tolist()
    assert d["ratings"]["gravity_model"] and "upright" in d["ratings"]["mountings"]
    d = run_json(capsys, "show", "inverse3_prototype")
    assert d["ratings"]["peak"] is None and d["ratings"]["gravity_model"]        # estimated bodies
    assert not run_json(capsys, "show", massless_omni(tmp_path))["ratings"]["gravity_model"]
    _, out, _ = run(capsys, "show", "inverse3_prototype")
    assert "torque rating, peak (--rating peak): none" in out
