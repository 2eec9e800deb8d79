"""``isoforce convergence`` on its own parser: table, JSON, plot file, bad input. No Qt."""
from __future__ import annotations

import argparse
import json
import subprocess
import sys

import pytest

from app.cli import convergence

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
FAST = ["--resolutions", "40,80,160", "--tol", "0.01", "--exact-rtol", "1e-3"]


def run_cli(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="isoforce")
    sub = parser.add_subparsers(dest="command")
    convergence.register(sub)
    args = parser.parse_args(argv)
    assert args.func is convergence.run
    return args.func(args)


def test_table_has_every_rung_and_the_refinement(capsys):
    assert run_cli(["convergence", "inverse3_prototype", *FAST]) == 0
    out = capsys.readouterr().out
    for label in ("40 x 40", "80 x 80", "160 x 160"):
        assert label in out
    for q in ("condition_number", "anisotropic_force", "isotropic_force"):
        assert q in out
    assert "adaptive refinement of the global minimum isotropic_force (tol 0.01 N)" in out
    assert "evaluations" in out and "uniform grid" in out


def test_json_is_exactly_one_strict_object(capsys):
    assert run_cli(["convergence", "inverse3_prototype", *FAST, "--quantity", "isotropic_force", "--json"]) == 0
    out = capsys.readouterr().out
    data = json.loads(out)                    # one object and nothing else
    assert out.strip().startswith("{") and out.strip().endswith("}")
    json.dumps(data, allow_nan=False)
    assert data["device"] == "inverse3_prototype"
    assert data["study"]["quantities"] == ["isotropic_force"]
    assert [r["resolution"] for r in data["study"]["rows"]] == [[40, 40], [80, 80], [160, 160]]
    ref = data["refinement"]
    assert ref["result"]["certified"] and ref["result"]["evaluations"] > 0
    assert ref["error"] <= 0.01
    assert ref["uniform"]["tol"] == 0.01
    for row in data["study"]["rows"]:
        fig = row["quantities"]["isotropic_force"]["mean"]
        ref_mean = data["study"]["reference"]["quantities"]["isotropic_force"]["mean"]["value"]
        assert fig["abs_error"] == abs(fig["value"] - ref_mean)


def test_refined_quantity_is_always_studied(capsys):
    assert run_cli(["convergence", "inverse3_prototype", *FAST, "--quantity", "condition_number", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["study"]["quantities"] == ["condition_number", "isotropic_force"]


def test_plot_is_a_png_written_atomically(tmp_path, capsys):
    target = tmp_path / "plot.png"
    assert run_cli(["convergence", "inverse3_prototype", *FAST, "--out", str(target)]) == 0
    data = target.read_bytes()
    assert data.startswith(PNG_MAGIC) and len(data) > 10_000
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plot.png"]     # no temporary left
    from matplotlib import image
    pixels = image.imread(str(target))
    assert pixels.ndim == 3 and pixels.shape[0] > 200 and pixels.shape[1] > 400


def test_failed_plot_leaves_neither_file_nor_temporary(tmp_path, monkeypatch, capsys):
    from matplotlib.figure import Figure

    def broken(self, fname, **kwargs):
        with open(fname, "wb") as fh:
            fh.write(PNG_MAGIC)      # half a file, then the writer dies
        raise RuntimeError("disk full")

    monkeypatch.setattr(Figure, "savefig", broken)
    target = tmp_path / "plot.png"
    with pytest.raises(RuntimeError, match="disk full"):
        run_cli(["convergence", "inverse3_prototype", *FAST, "--out", str(target)])
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("argv, pattern", [
    (["convergence", "no_such_device"], "unknown device 'no_such_device'"),
    (["convergence", "/nonexistent/dev.toml"], "cannot be read"),
    (["convergence", "inverse3_prototype", "--resolutions", "50"], "--resolutions needs at least two"),
    (["convergence", "inverse3_prototype", "--resolutions", "50,x"], "--resolutions"),
    (["convergence", "inverse3_prototype", "--tol", "-1"], "--tol needs a positive number"),
    (["convergence", "inverse3_prototype", "--exact-rtol", "nan"], "--exact-rtol"),
    (["convergence", "inverse3_prototype", "--quantity", "bottleneck"], "--quantity: 'bottleneck'"),
    (["convergence", "inverse3_prototype", "--out", "plot.jpg"], "--out must end in .png, .svg or .pdf"),
    (["convergence", "inverse3_prototype", "--out", "/nonexistent/plot.png"], "--out: folder"),
])
def test_bad_input_exits_2_with_one_line_on_stderr(argv, pattern, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert run_cli(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert pattern in captured.err and captured.err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def test_cli_module_imports_matplotlib_only_when_drawing():
    code = ("import sys, app.cli.convergence; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('matplotlib', 'PySide6', 'pyvista', 'vtk')]; "
            "print(bad); sys.exit(1 if bad else 0)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
