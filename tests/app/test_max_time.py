"""``--max-time``: a map predicted to run longer than allowed is refused before it starts, and a long
one reports its progress on stderr.

Before: ``isoforce stats novint_falcon --resolution 1000000`` (10^18 points) started and grew
past 3.5 GB in 10 s; ``stats novint_falcon --resolution 8000`` would have run for weeks. The
rate is injected where a test needs numbers, so nothing depends on the machine's speed.
"""
from __future__ import annotations

import io
import subprocess
import sys
from pathlib import Path

import pytest

import metrics.runtime
from app.cli import main
from app.cli._progress import LINE_EVERY, Progress

ROOT = Path(__file__).resolve().parents[2]


def _refused(capsys, argv, *phrases):
    status = main(argv)
    out, err = capsys.readouterr()
    assert status == 2 and out == "", (status, out, err)
    assert err.count("\n") == 1 and err.startswith(f"isoforce {argv[0]}: error: --max-time: "), err
    for phrase in phrases:
        assert phrase in err, (phrase, err)
    return err


@pytest.mark.parametrize("argv", [
    ["stats", "fivebar_singh", "--resolution", "100000"],
    ["stats", "novint_falcon", "--resolution", "1000000", "--json"],
    ["map", "fivebar_singh", "--quantity", "isotropic_force", "--resolution", "5000", "--out", "{tmp}/m.npz"],
    ["compare", "fivebar_singh", "haply_2diy", "--resolution", "5000", "--out", "{tmp}/c.csv"],
    ["convergence", "fivebar_singh", "--resolutions", "100,5000", "--quantity", "isotropic_force",
     "--out", "{tmp}/c.png"],
    ["figure", "novint_falcon", "--view", "map", "--resolution", "3000", "--out", "{tmp}/f.png"],
])
def test_a_tiny_max_time_refuses_a_large_map_with_the_prediction(capsys, tmp_path, argv):
    """The measured rate, whatever it is, predicts more than 10^-9 s: refused, nothing written."""
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv] + ["--max-time", "1e-9"]
    _refused(capsys, argv, "would take about", "measured on a sample",
             "finishes within 1 ns", "--max-time SECONDS allows longer")
    assert list(tmp_path.iterdir()) == []


def test_the_default_hour_refuses_with_the_largest_resolution_that_fits(capsys, tmp_path, monkeypatch):
    """An injected rate of 1 µs a point: 10^10 points take 2.8 h; 60000 x 60000 is exactly an hour."""
    monkeypatch.setattr(metrics.runtime, "seconds_per_point", lambda *a, **k: 1e-6)
    out = tmp_path / "s.json"
    _refused(capsys, ["stats", "fivebar_singh", "--resolution", "100000", "--out", str(out)],
             "a 100000 x 100000 map (statistics streamed) would take about 2.8 h",
             "10,000,000,000 points at 1 µs each",
             "the largest that finishes within 1 h is --resolution 60000 (about 1 h)")
    assert not out.exists()


def test_max_time_allows_a_long_job_and_takes_units(capsys, monkeypatch):
    # 200 x 200 points at an injected 1 ms each: 40 s.
    monkeypatch.setattr(metrics.runtime, "seconds_per_point", lambda *a, **k: 1e-3)
    _refused(capsys, ["stats", "fivebar_singh", "--resolution", "200", "--max-time", "30s"],
             "would take about 40 s", "the largest that finishes within 30 s is --resolution 173")
    status = main(["stats", "fivebar_singh", "--resolution", "200", "--max-time", "1min", "--json"])
    out, err = capsys.readouterr()
    assert status == 0 and out.startswith("{"), err
    # One note of what it will take, and no progress (JSON on stdout, stderr not a terminal).
    assert err.count("\n") == 1 and err.startswith("isoforce stats: note: ") and "about 40 s" in err, err


@pytest.mark.parametrize("text", ["soon", "0", "-5", "1e400", "3 weeks", "nan"])
def test_a_bad_max_time_names_the_option(capsys, text):
    status = main(["stats", "fivebar_singh", "--resolution", "400", "--max-time", text])
    out, err = capsys.readouterr()
    assert status == 2 and out == "" and err.count("\n") == 1
    assert "--max-time needs a positive duration" in err and repr(text) in err, err


def test_progress_lines_every_few_seconds_with_an_eta():
    now = [0.0]
    stream = io.StringIO()
    bar = Progress("isoforce stats", 10 ** 9, stream=stream, terminal=False, clock=lambda: now[0])
    for step in range(1, 60):
        now[0] = step * 1.0
        bar(step / 100)
    lines = stream.getvalue().splitlines()
    assert len(lines) == 59 // LINE_EVERY                   # one every LINE_EVERY seconds, not one a chunk
    assert lines[0] == "isoforce stats: 5% of 1,000,000,000 points, 5 s elapsed, about 1.6 min left"
    bar.close()
    assert stream.getvalue().count("\n") == len(lines)


def test_the_time_left_leans_on_the_prediction_until_a_fifth_is_done():
    """A grid's first chunks (a corner, often infeasible) run fast: their pace alone said 32 days
    left of a run predicted at 230."""
    now = [0.0]
    bar = Progress("isoforce stats", 5 * 10 ** 11, stream=io.StringIO(), terminal=False, clock=lambda: now[0],
                   predicted=1000.0)
    now[0], bar.fraction = 1.0, 0.01          # pace: 99 s left; prediction: 990 s; a twentieth of the way
    assert bar.left(now[0]) == pytest.approx(0.05 * 99.0 + 0.95 * 990.0)
    assert bar.text(now[0]).endswith("1% of 500,000,000,000 points, 1 s elapsed, about 16 min left")
    now[0], bar.fraction = 300.0, 0.5          # past a fifth: the pace alone
    assert bar.left(now[0]) == pytest.approx(300.0)
    bar.fraction = 2e-6
    assert "0.0002% of" in bar.text(now[0])


def test_the_refusal_is_one_line_from_the_installed_command(tmp_path):
    """As a user runs it: a process, exit 2, one line, no file."""
    out = tmp_path / "s.json"
    proc = subprocess.run([sys.executable, "-m", "app", "stats", "novint_falcon", "--resolution", "1000000",
                           "--max-time", "1e-9", "--out", str(out)], cwd=ROOT, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 2 and proc.stdout == "", proc.stderr
    assert proc.stderr.count("\n") == 1 and "1,000,000,000,000,000,000 points" in proc.stderr, proc.stderr
    assert not out.exists()
