"""``isoforce optimize`` with the apparent mass: the bound's report, the N/kg objective, bad input."""
from __future__ import annotations

import json

from app.cli import main

STUDY = """
name = "cli mass"
[mechanism]
{mechanism}
[grid]
gear_ratios.theta_0 = {{ min = 4.0, max = 20.0, step = 2.0 }}
[workspace]
kind = "grid"
axes = ["x", "z"]
lower = [100.0, 100.0]
upper = [250.0, 300.0]
resolution = [5, 6]
fixed = {{ y = 22.3 }}
[objective]
kind = "{kind}"
{bound}
top_k = 2
"""


def write(tmp_path, kind="min_isotropic_force", bound="max_apparent_mass = 0.2",
          mechanism='preset = "inverse3_prototype"'):
    path = tmp_path / "mass.toml"
    path.write_text(STUDY.format(kind=kind, bound=bound, mechanism=mechanism), encoding="utf-8")
    return path


def test_json_reports_the_bound_and_the_masses(capsys, tmp_path):
    path = write(tmp_path)
    status = main(["optimize", str(path), "--json", "--out", str(tmp_path / "r.npz"), "--method", "brute_force"])
    data = json.loads(capsys.readouterr().out)
    assert status == 0
    run = data["runs"][0]
    assert data["objective"]["max_apparent_mass"] == 0.2
    assert 0 < run["over_mass_bound"] < run["designs"]
    assert all(row["max_apparent_mass"] <= 0.2 for row in run["top"])


def test_text_names_the_force_per_mass_unit(capsys, tmp_path):
    path = write(tmp_path, kind="min_force_per_apparent_mass", bound="")
    assert main(["optimize", str(path), "--out", str(tmp_path / "r.csv")]) == 0
    out = capsys.readouterr().out
    assert "N/kg = m/s^2" in out and "value (N/kg)" in out and "largest apparent mass" in out


def test_no_mass_model_is_a_usage_error(capsys, tmp_path):
    path = write(tmp_path, mechanism='kind = "inverse3"\nparameters = { mass_model = "none" }')
    status = main(["optimize", str(path), "--out", str(tmp_path / "r.npz")])
    out, err = capsys.readouterr()
    assert status == 2 and out == ""
    line = err.strip().splitlines()[-1]
    assert "mass.toml" in line and "'objective.max_apparent_mass'" in line and "no mass model" in line
