"""Issue 26 section 7: long command-line work shows its progress, short work and ``--json`` stay clean.

A terminal gets a rich bar with the time left; a pipe a plain line every ``LINE_EVERY`` seconds;
stdout never carries progress. The clock is injected (or the thresholds set to 0 for a whole
command), so nothing here waits or measures time.
"""
from __future__ import annotations

import io
import json
import re

import pytest

import app.cli._progress as progress_module
from app.cli import main
from app.cli._progress import LINE_EVERY, PROGRESS_AFTER, Progress, progress_for

ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")


class Terminal(io.StringIO):
    """A stream that says it is a terminal."""

    def isatty(self) -> bool:
        return True


def plain(text: str) -> str:
    return ANSI.sub("", text)


@pytest.fixture(autouse=True)
def wide_terminal(monkeypatch):
    """A fake terminal 120 characters wide (rich reads COLUMNS), unless a test narrows it."""
    monkeypatch.setenv("COLUMNS", "120")


def test_a_terminal_shows_a_rich_bar_with_the_time_left_and_clears_it():
    now = [0.0]
    stream = Terminal()
    with progress_for("isoforce map", 60.0, 1000, stream=stream, clock=lambda: now[0]) as bar:
        assert isinstance(bar, Progress) and bar.terminal and not bar.refresh_thread
        for step in range(1, 5):
            now[0] = step
            bar(step / 8)
        drawn = plain(stream.getvalue())
    assert "isoforce map:" in drawn and "━" in drawn                      # rich's bar
    assert "50%" in drawn and "4 s elapsed, about" in drawn and "left" in drawn
    assert drawn.count("\n") == 0                                         # redrawn in place
    assert stream.getvalue().endswith("\x1b[2K")                          # ... and cleared at the end


def test_the_time_left_on_the_bar_is_the_blend_of_pace_and_prediction():
    now = [0.0]
    stream = Terminal()
    with Progress("isoforce stats", 100, stream=stream, terminal=True, clock=lambda: now[0], predicted=100.0) as bar:
        now[0] = 30.0
        bar(0.5)                                # past a fifth: the pace alone, 30 s
        assert "30 s elapsed, about 30 s left" in plain(stream.getvalue())


def test_a_finished_job_says_no_time_left():
    bar = Progress("isoforce optimize", 80, unit="designs", stream=io.StringIO(), terminal=False, clock=lambda: 5.0)
    bar.start, bar.fraction = 0.0, 1.0
    assert bar.text(5.0) == "isoforce optimize: 100% of 80 designs, 5 s elapsed"


def test_a_step_of_unknown_share_shows_the_time_elapsed():
    now = [0.0]
    stream = Terminal()
    with Progress("isoforce convergence", 100, stream=stream, terminal=True, clock=lambda: now[0],
                  predicted=10.0) as bar:
        bar(1.0)
        now[0] = 12.0
        bar.step("refine min isotropic_force", None)
        text = plain(stream.getvalue())
    assert "isoforce convergence: refine min isotropic_force" in text and "12 s elapsed" in text
    assert "left" not in text.rsplit("refine", 1)[1]


def test_a_share_that_goes_back_starts_the_pace_afresh():
    """A dextrous box that grows runs its region again: the time before says nothing of it."""
    now = [0.0]
    bar = Progress("isoforce dextrous", 1, unit="devices", stream=io.StringIO(), terminal=False,
                   clock=lambda: now[0], predicted=30.0)
    now[0] = 10.0
    bar(0.5)
    now[0] = 12.0
    bar(0.25)                                   # grown: a quarter again, from 12 s on
    now[0] = 14.0
    bar(0.5)
    assert bar.left(now[0]) == pytest.approx(2.0 * 0.5 / 0.25) and bar.predicted is None


def test_an_unknown_share_pulses_without_a_percentage():
    now = [0.0]
    stream = Terminal()
    with Progress("isoforce convergence", 100, stream=stream, terminal=True, clock=lambda: now[0],
                  predicted=10.0) as bar:
        now[0] = 3.0
        bar(0.4)
        mark = len(stream.getvalue())
        bar.step("refine min isotropic_force", None)
        frame = plain(stream.getvalue()[mark:])
    assert "refine min isotropic_force" in frame and "%" not in frame and "3 s elapsed" in frame


def test_a_narrow_terminal_cuts_the_step_short_and_keeps_the_times(monkeypatch):
    monkeypatch.setenv("COLUMNS", "80")
    now = [0.0]
    stream = Terminal()
    with Progress("isoforce dextrous", 2, unit="devices", stream=stream, terminal=True, clock=lambda: now[0],
                  predicted=60.0) as bar:
        bar.step("twin_pantograph, grown box 1")
        now[0] = 154.0
        bar(0.46)
        last = plain(stream.getvalue()).split("\r")[-1]
    assert last.startswith("isoforce dextrous: twin_pa") and "…" in last
    assert last.rstrip().endswith("2.6 min elapsed, about 3 min left") and len(last.rstrip()) <= 80


@pytest.mark.parametrize("terminal", [True, False])
def test_short_jobs_stay_silent(terminal):
    """Predicted short (or not predicted) and done within PROGRESS_AFTER: no bar, no line."""
    for predicted in (None, 0.5, PROGRESS_AFTER):
        now = [0.0]
        stream = Terminal() if terminal else io.StringIO()
        with progress_for("isoforce stats", predicted, 10, stream=stream, clock=lambda: now[0]) as bar:
            for step in range(1, 20):
                now[0] = step * 0.099
                bar(step / 20)
            bar.step("the last step")
            now[0] = 5 * PROGRESS_AFTER
            bar(1.0)                            # done: nothing drawn for a finished job
        assert stream.getvalue() == "", (predicted, stream.getvalue())


def test_an_unpredicted_job_shows_its_bar_once_it_has_run_progress_after():
    now = [0.0]
    stream = Terminal()
    with progress_for("isoforce optimize", None, 80, unit="designs", stream=stream, clock=lambda: now[0]) as bar:
        now[0] = 0.9 * PROGRESS_AFTER
        bar(0.4)
        assert stream.getvalue() == ""
        now[0] = PROGRESS_AFTER
        bar(0.5)
        assert "isoforce optimize:" in plain(stream.getvalue())


def test_lines_off_a_terminal_come_no_more_often_than_the_interval():
    """Irregular calls (chunks of all sizes): a line at most every LINE_EVERY seconds, each a full sentence."""
    now = [0.0]
    written: list[float] = []

    class Log(io.StringIO):
        def write(self, text: str) -> int:
            written.append(now[0])
            return super().write(text)

    stream = Log()
    calls = [0.3, 0.4, 2.9, 5.0, 5.1, 9.8, 10.2, 10.3, 16.0, 16.1, 17.0, 30.0, 30.5, 34.9, 35.0]
    with progress_for("isoforce dextrous", None, 2, unit="devices", stream=stream, clock=lambda: now[0]) as bar:
        for k, t in enumerate(calls):
            now[0] = t
            bar((k + 1) / (len(calls) + 1))
    lines = stream.getvalue().splitlines()
    assert written == [5.0, 10.2, 16.0, 30.0, 35.0] and len(lines) == len(written)
    assert all(b - a >= LINE_EVERY for a, b in zip(written, written[1:]))
    assert all(line.startswith("isoforce dextrous: ") and " of 2 devices, " in line for line in lines)
    assert lines[0] == "isoforce dextrous: 25% of 2 devices, 5 s elapsed, about 15 s left"
    assert "\x1b" not in stream.getvalue()                   # plain text for a log


def test_json_to_a_pipe_is_silent_and_to_a_terminal_shows_the_bar_on_stderr():
    now = [0.0]
    pipe = io.StringIO()
    silent = progress_for("isoforce stats", 1e6, 10, json_out=True, stream=pipe, clock=lambda: now[0])
    with silent as bar:
        now[0] = 100.0
        bar(0.5)
        assert bar.part(0, 10) is None
    assert pipe.getvalue() == ""
    with progress_for("isoforce stats", 1e6, 10, json_out=True, stream=Terminal(), clock=lambda: now[0]) as bar:
        assert isinstance(bar, Progress)


# -- whole commands: every long one is wired, and --json stays one JSON object ----------------------
STUDY = """
name = "progress five-bar"
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


@pytest.fixture
def study_file(tmp_path):
    path = tmp_path / "progress_study.toml"
    path.write_text(STUDY)
    return path


def commands(tmp_path, study_file):
    """Small runs, each of several chunks: a map of more than ``metrics.map_chunks.CHUNK`` points where the
    compiled kernels take a request (one chunk per ``CHUNK`` points then), ``MIN_CHUNK`` otherwise."""
    return {
        "optimize": ["optimize", str(study_file), "--workers", "1", "--chunks", "4", "--out", str(tmp_path / "r.npz")],
        "dextrous": ["dextrous", "twin_pantograph", "--resolution", "5", "--rings", "2", "--rolls", "2"],
        "convergence": ["convergence", "fivebar_singh", "--resolutions", "8,16", "--quantity", "isotropic_force"],
        "map": ["map", "fivebar_singh", "--quantity", "isotropic_force", "--resolution", "300",
                "--out", str(tmp_path / "m.npz")],
        "stats": ["stats", "fivebar_singh", "--resolution", "300"],
        "compare": ["compare", "fivebar_singh", "haply_2diy", "--resolution", "12"],
        "figure": ["figure", "fivebar_singh", "--view", "map", "--resolution", "300", "--size", "320x240",
                   "--out", str(tmp_path / "f.png")],
    }


@pytest.mark.parametrize("command", ["optimize", "dextrous", "convergence", "map", "stats", "compare", "figure"])
def test_every_long_command_reports_progress_lines_on_a_pipe(command, capsys, monkeypatch, tmp_path, study_file):
    """With the interval at 0, every report of the run is a line: each command is wired."""
    monkeypatch.setattr(progress_module, "LINE_EVERY", 0.0)
    monkeypatch.chdir(tmp_path)
    status = main(commands(tmp_path, study_file)[command])
    out, err = capsys.readouterr()
    assert status == 0, err
    lines = [line for line in err.splitlines() if not line.startswith("wrote ")]
    assert lines, err
    assert all(line.startswith(f"isoforce {command}: ") and "elapsed" in line for line in lines), err
    assert "elapsed" not in out                                           # stdout: the command's output only


@pytest.mark.parametrize("command", ["optimize", "dextrous", "convergence", "stats", "compare"])
def test_json_stays_one_object_with_the_bar_on_a_terminal(command, capsys, monkeypatch, tmp_path, study_file):
    """The bar at once (PROGRESS_AFTER 0) on a terminal stderr: stdout is still exactly one JSON object."""
    monkeypatch.setattr(progress_module, "PROGRESS_AFTER", 0.0)
    monkeypatch.chdir(tmp_path)
    terminal = Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    status = main(commands(tmp_path, study_file)[command] + ["--json"])
    out = capsys.readouterr().out
    assert status == 0, terminal.getvalue()
    json.loads(out)
    assert f"isoforce {command}:" in plain(terminal.getvalue())           # the bar went to stderr


@pytest.mark.parametrize("command", ["optimize", "stats"])
def test_json_to_a_pipe_prints_no_progress(command, capsys, monkeypatch, tmp_path, study_file):
    monkeypatch.setattr(progress_module, "LINE_EVERY", 0.0)
    monkeypatch.setattr(progress_module, "PROGRESS_AFTER", 0.0)
    monkeypatch.chdir(tmp_path)
    status = main(commands(tmp_path, study_file)[command] + ["--json"])
    out, err = capsys.readouterr()
    assert status == 0, err
    json.loads(out)
    assert "elapsed" not in err, err
