"""``isoforce optimize``: JSON output checked against the compute layer, the results file, bad input."""
from __future__ import annotations

import json
import textwrap
from pathlib import Path

import numpy as np
import pytest

from app.cli import main
from app.cli.optimize import shipped_studies
from metrics.design import build_study, run_study
from resources.study_schema import read_study_file

ROOT = Path(__file__).resolve().parents[2]

STUDY = """
name = "cli five-bar"
[mechanism]
preset = "fivebar_singh"
[grid]
proximal = { min = 60.0, max = 120.0, step = 20.0 }
distal = [110.0, 130.0, 150.0, 170.0]
half_base = { min = 10.0, max = 70.0, step = 15.0 }
[workspace]
kind = "grid"
axes = ["x", "y"]
lower = [-50.0, 110.0]
upper = [50.0, 170.0]
resolution = [8, 6]
[objective]
kind = "min_isotropic_force"
infeasible = "fail"
top_k = 4
"""


def run(capsys, *argv):
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


def run_json(capsys, *argv) -> dict:
    status, out, err = run(capsys, *argv, "--json")
    assert status == 0, err
    return json.loads(out, parse_constant=lambda c: pytest.fail(f"non-standard JSON constant {c}"))


def usage_error(capsys, argv, *phrases):
    status, out, err = run(capsys, *argv)
    assert status == 2 and out == "", (out, err)
    lines = [line for line in err.splitlines() if line.startswith("isoforce")]
    assert len(lines) == 1 and "Traceback" not in err, err
    for p in phrases:
        assert p in lines[0], (p, lines[0])


@pytest.fixture
def study_file(tmp_path) -> Path:
    path = tmp_path / "cli_study.toml"
    path.write_text(textwrap.dedent(STUDY), encoding="utf-8")
    return path


def test_json_matches_the_compute_layer_and_the_results_file(capsys, tmp_path, study_file):
    out = tmp_path / "res.npz"
    data = run_json(capsys, "optimize", str(study_file), "--out", str(out), "--workers", "1")
    st = build_study(read_study_file(study_file))
    ref = run_study(st, method="brute_force")
    assert data["study"] == "cli_study" and data["objective"]["kind"] == "min_isotropic_force"
    (r,) = data["runs"]
    assert [t["design"] for t in r["top"]] == ref.top_designs.tolist()
    assert [t["value"] for t in r["top"]] == ref.top_values.tolist()          # exact, same order
    assert r["optimum"] == r["top"][0]
    assert set(r["optimum"]) == {"rank", "design", "proximal", "distal", "half_base", "value"}
    assert r["brute_force_evaluations"] == st.n_designs * st.n_samples == 80 * 48
    assert 0 < r["evaluations"] <= r["brute_force_evaluations"]
    assert r["ratio"] == r["evaluations"] / r["brute_force_evaluations"]
    assert r["wall_seconds"] > 0 and data["results_file"] == str(out)
    assert "upper bound" in data["culled_value_means"]
    with np.load(out) as f:
        assert f["design"].tolist() == list(range(80))
        exact = f["exact"]
        truth = ref.records["value"]
        assert np.array_equal(f["value"][exact], truth[exact])
        assert np.all(f["value"][~exact] >= truth[~exact])                    # culled: upper bounds
        assert exact.sum() == r["exact_designs"]
        assert f["proximal"][27] == st.design_display([27])["proximal"][0]
        assert str(f["objective"]) == "min_isotropic_force"


def test_text_output_csv_and_top(capsys, tmp_path, study_file, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status, out, err = run(capsys, "optimize", str(study_file), "--top", "2", "--out", "r.csv", "--workers", "1")
    assert status == 0, err
    assert "optimum: proximal = " in out and "ratio" in out and "wall time" in out
    assert "evaluations: " in out and "culled fraction " in out           # what a study costs
    assert err == ""                                           # a short search shows no progress
    lines = (tmp_path / "r.csv").read_text().splitlines()
    assert lines[0].startswith("# cli five-bar") and lines[1] == "design,proximal,distal,half_base,value,exact," \
                                                                 "samples_evaluated"
    assert len(lines) == 2 + 80
    data = run_json(capsys, "optimize", str(study_file), "--top", "2", "--workers", "1")
    assert len(data["runs"][0]["top"]) == 2
    r0 = data["runs"][0]
    assert r0["culled_designs"] == r0["designs"] - r0["exact_designs"]
    assert r0["culled_fraction"] == r0["culled_designs"] / r0["designs"]
    assert (tmp_path / "cli_study_results.npz").is_file()     # the default results file


def test_shipped_table1_study(capsys, tmp_path):
    data = run_json(capsys, "optimize", "fivebar_table1", "--out", str(tmp_path / "t1.npz"))
    (r,) = data["runs"]
    assert {k: r["optimum"][k] for k in ("proximal", "distal", "half_base", "value")} == \
        {"proximal": 100.0, "distal": 150.0, "half_base": 30.0, "value": 454.0}      # paper 002's winner
    assert r["top"][1]["value"] == 456.0 and r["brute_force_evaluations"] == 60 * 27000
    assert r["ratio"] < 0.5


def test_shipped_gear_ratio_study_reports_plus_60_percent(capsys, tmp_path):
    data = run_json(capsys, "optimize", "inverse3_gear_ratio", "--out", str(tmp_path / "g.npz"))
    (r,) = data["runs"]
    rep = r["report"]
    smallest = rep["smallest"]["gear_ratios.theta_0"]
    assert 11.5 < smallest < 11.85                             # not 11.0: the +60 % claim fails
    checks = {c["label"]: c for c in rep["checks"]}
    plus60 = next(c for label, c in checks.items() if label.startswith("+60"))
    assert plus60["reaches"] is False and plus60["vs_reference"] < -0.05
    assert r["optimum"]["value"] == rep["reference_value"]     # the plateau is Scenario 2's value


def test_list_and_bad_input(capsys, tmp_path, study_file):
    data = run_json(capsys, "optimize", "--list")
    assert [s["key"] for s in data["studies"]] == shipped_studies()
    usage_error(capsys, ["optimize", "no_such_study"], "STUDY", "unknown study 'no_such_study'")
    usage_error(capsys, ["optimize"], "STUDY is needed")
    bad = tmp_path / "bad.toml"
    bad.write_text(textwrap.dedent(STUDY).replace("step = 20.0", "step = 25.0"), encoding="utf-8")
    usage_error(capsys, ["optimize", str(bad)], "bad.toml", "grid.proximal.step")
    usage_error(capsys, ["optimize", str(study_file), "--out", str(tmp_path / "r.txt")], "--out", ".npz")
    usage_error(capsys, ["optimize", str(study_file), "--out", str(tmp_path / "nope" / "r.npz")], "--out", "folder")
    usage_error(capsys, ["optimize", str(study_file), "--scheduler", "tcp://x:1", "--workers", "2"],
                "--scheduler and --workers")
    usage_error(capsys, ["optimize", str(study_file), "--workers", "0"], "--workers")
    usage_error(capsys, ["optimize", str(study_file), "--dask", "--scheduler", "tcp://x:1"],
                "--dask and --scheduler")
    assert not list(tmp_path.glob("*.npz"))                    # nothing written on bad input


def test_scheduler_runs_on_a_dask_cluster(capsys, tmp_path, study_file):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        data = run_json(capsys, "optimize", str(study_file), "--scheduler", cluster.scheduler_address,
                        "--out", str(tmp_path / "d.npz"))
    single = run_json(capsys, "optimize", str(study_file), "--workers", "1", "--out", str(tmp_path / "s.npz"))
    assert data["runs"][0]["engine"] == "dask"
    assert data["runs"][0]["top"] == single["runs"][0]["top"]


def test_dask_flag_starts_a_local_cluster(capsys, tmp_path, study_file):
    pytest.importorskip("distributed", reason="dask.distributed is not installed: --dask cannot run")
    data = run_json(capsys, "optimize", str(study_file), "--dask", "--workers", "2", "--out", str(tmp_path / "d.npz"))
    single = run_json(capsys, "optimize", str(study_file), "--workers", "1", "--out", str(tmp_path / "s.npz"))
    assert data["runs"][0]["engine"] == "dask" and data["runs"][0]["workers"] == 2
    assert data["runs"][0]["top"] == single["runs"][0]["top"]


def test_series_runs_one_optimization_per_value(capsys, tmp_path, study_file):
    text = study_file.read_text() + '[series]\nkey = "workspace.centre.y"\nvalues = [0.0, 20.0]\npaper = [1.0, 2.0]\n'
    path = tmp_path / "series.toml"
    path.write_text(text, encoding="utf-8")
    out = tmp_path / "series.csv"
    data = run_json(capsys, "optimize", str(path), "--workers", "1", "--out", str(out))
    assert [r["series_value"] for r in data["runs"]] == [0.0, 20.0]
    assert [r["paper"] for r in data["runs"]] == [1.0, 2.0]
    st = build_study(read_study_file(path))
    for r, sub in zip(data["runs"], st.runs()):
        ref = run_study(sub, method="brute_force")
        assert [t["design"] for t in r["top"]] == ref.top_designs.tolist()
        assert [t["value"] for t in r["top"]] == ref.top_values.tolist()
    assert data["runs"][0]["top"] != data["runs"][1]["top"]         # the workspace moved
    rows = np.loadtxt(out, delimiter=",", skiprows=2)
    assert rows.shape == (160, 8) and set(rows[:, 0]) == {0.0, 20.0}
    status, text_out, _ = run(capsys, "optimize", str(path), "--workers", "1", "--out", str(out))
    assert status == 0 and "workspace.centre.y (mm) against the optimum:" in text_out


# -- issue 7, section 6 --------------------------------------------------------------------
def test_unwritable_out_is_refused_before_the_search(capsys, study_file):
    """Before: the whole search ran, then the results were lost on the read-only --out."""
    usage_error(capsys, ["optimize", str(study_file), "--out", "/proc/results.npz"], "--out", "cannot write")
    usage_error(capsys, ["optimize", str(study_file), "--out", str(study_file.parent)], "--out")
    _, _, err = run(capsys, "optimize", str(study_file), "--out", "/proc/results.npz")
    assert "optimize [" not in err          # no progress: nothing was searched


def test_any_worker_count_gives_the_single_worker_result(capsys, tmp_path):
    """Before: --workers 16 on the 60-design Table 1 study crashed after the search
    ("designs and samples must be non-empty, got 0 and 27000")."""
    one = run_json(capsys, "optimize", "fivebar_table1", "--workers", "1", "--out", str(tmp_path / "a.npz"))
    many = run_json(capsys, "optimize", "fivebar_table1", "--workers", "16", "--out", str(tmp_path / "b.npz"))
    assert [(r["design"], r["value"]) for r in many["runs"][0]["top"]] == \
        [(r["design"], r["value"]) for r in one["runs"][0]["top"]]        # integer counts: exact
    assert many["runs"][0]["workers"] <= max(1, __import__("os").cpu_count() or 1)
    a, b = np.load(tmp_path / "a.npz"), np.load(tmp_path / "b.npz")
    exact = a["exact"] & b["exact"]
    assert np.array_equal(a["value"][exact], b["value"][exact])


def test_sensor_study_text_names_its_objective_and_claims_no_optimum_where_none_is_feasible(capsys, tmp_path):
    status = main(["optimize", "twin_pantograph_sensor", "--out", str(tmp_path / "r.npz")])
    out, err = capsys.readouterr()
    assert status == 0, err
    assert "sensor-resolution GII" in out
    first, rest = out.split("workspace.centre.z = 150 mm", 1)
    # 10 cm: every design is -inf; no optimum is named and no ranking is printed.
    assert "no optimum" in first and "optimum:" not in first and "-inf\n" not in first.split("no optimum")[1]
    assert "optimum: Q1 = " in rest


def test_write_npz_reads_back_as_savez_compressed(tmp_path):
    """The results file's writer (deflate level 1) against numpy's own ``savez_compressed``:
    the same members, dtypes, shapes and values, bit for bit (nan, -0.0, 0-d strings included)."""
    import zipfile

    from app.cli.optimize import write_npz
    rng = np.random.default_rng(3)
    value = rng.normal(size=5000)
    value[::7] = np.nan
    value[1::11] = -0.0
    arrays = {"design": np.arange(5000, dtype=np.int64), "value": value, "exact": rng.random(5000) < 0.1,
              "objective": np.array("gii"), "columns": np.array(["design", "value", "exact"])}
    ours, ref = tmp_path / "ours.npz", tmp_path / "ref.npz"
    with open(ours, "wb") as fh:
        write_npz(fh, arrays)
    np.savez_compressed(ref, **arrays)
    with np.load(ours) as a, np.load(ref) as b:
        assert a.files == b.files == list(arrays)
        for name in arrays:
            assert a[name].dtype == b[name].dtype and a[name].shape == b[name].shape
            assert a[name].tobytes() == b[name].tobytes()
    with zipfile.ZipFile(ours) as zf:
        assert {i.compress_type for i in zf.infolist()} == {zipfile.ZIP_DEFLATED}
