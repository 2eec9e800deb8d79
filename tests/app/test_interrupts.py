"""Ctrl-C, SIGTERM and MemoryError stop the command line at once, with one line and no files left.

Real subprocesses (``python -m app``), real signals. Every wait is a hang guard with a generous
limit, not a timing assertion: the checks are the exit status, the single line on stderr, that
no file (hidden temporary or partial) is left, and that the worker processes are gone.
"""
from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
#: Hang guard for anything these tests wait for.
GUARD = 60.0


class Running:
    """``python -m app ARGS`` with stderr collected line by line on a thread."""

    def __init__(self, *args: str, cwd: Path, env: dict | None = None, session: bool = False, preexec=None) -> None:
        full_env = dict(os.environ, PYTHONPATH=str(ROOT), **(env or {}))
        self.proc = subprocess.Popen([sys.executable, "-m", "app", *args], cwd=cwd, env=full_env, text=True,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     start_new_session=session, preexec_fn=preexec)
        self.lines: list[str] = []
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        for line in self.proc.stderr:
            self.lines.append(line)

    def wait_for(self, condition, what: str) -> None:
        end = time.monotonic() + GUARD
        while not condition():
            assert self.proc.poll() is None, f"exited before {what}: {''.join(self.lines)}"
            assert time.monotonic() < end, f"no {what} within {GUARD} s"
            time.sleep(0.02)

    def children(self) -> list[int]:
        out = subprocess.run(["ps", "-o", "pid=", "--ppid", str(self.proc.pid)], capture_output=True, text=True)
        return [int(p) for p in out.stdout.split()]

    def finish(self) -> tuple[int, str, str]:
        out = self.proc.stdout.read()          # stderr is the reader thread's
        self.proc.wait(timeout=GUARD)
        self.reader.join(GUARD)
        self.proc.stdout.close()
        self.proc.stderr.close()
        return self.proc.returncode, out, "".join(self.lines)


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _assert_one_line(err: str, *phrases: str) -> None:
    last = err.strip().splitlines()[-1]
    assert "Traceback" not in err and "Error" not in err.replace("error:", ""), err
    for phrase in phrases:
        assert phrase in last, (phrase, err)


def test_sigterm_during_csv_export_leaves_no_temporary_or_partial_file(tmp_path):
    run = Running("map", "fivebar_singh", "--quantity", "isotropic_force", "--resolution", "2500",
                  "--out", str(tmp_path / "m.csv"), cwd=tmp_path)
    run.wait_for(lambda: any(p.name.startswith(".m-") for p in tmp_path.iterdir()), "temporary file")
    run.proc.send_signal(signal.SIGTERM)
    status, out, err = run.finish()
    assert status == 143, err
    assert out == ""
    # Before the one line of the stop, only the run's own note and progress lines (a long run).
    *before, _ = err.splitlines()
    assert all(line.startswith("isoforce map: ") and "error" not in line for line in before), err
    _assert_one_line(err, "isoforce map", "SIGTERM")
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_stops_the_study_and_its_worker_processes(tmp_path):
    """Ctrl-C in a terminal reaches the whole process group: workers must not print tracebacks."""
    run = Running("optimize", "fivebar_large", "--workers", "2", "--out", str(tmp_path / "r.npz"),
                  cwd=tmp_path, session=True)
    run.wait_for(run.children, "worker processes")     # the search has started (its lines come every few s)
    kids = run.children()
    assert kids, "the study should run on worker processes"
    os.killpg(run.proc.pid, signal.SIGINT)
    status, out, err = run.finish()
    assert status == 130, err
    assert out == ""
    _assert_one_line(err, "isoforce optimize", "interrupted")
    assert not [line for line in err.splitlines() if not line.startswith("isoforce optimize: ")], err
    end = time.monotonic() + GUARD
    while any(_alive(k) for k in kids) and time.monotonic() < end:
        time.sleep(0.05)
    assert not [k for k in kids if _alive(k)]
    assert list(tmp_path.iterdir()) == []


def test_sigterm_to_the_parent_alone_terminates_its_workers(tmp_path):
    run = Running("optimize", "fivebar_large", "--workers", "2", "--out", str(tmp_path / "r.npz"), cwd=tmp_path)
    run.wait_for(run.children, "worker processes")
    kids = run.children()
    run.proc.send_signal(signal.SIGTERM)
    status, _, err = run.finish()
    assert status == 143, err
    _assert_one_line(err, "isoforce optimize", "SIGTERM")
    end = time.monotonic() + GUARD
    while any(_alive(k) for k in kids) and time.monotonic() < end:
        time.sleep(0.05)
    assert not [k for k in kids if _alive(k)]
    assert list(tmp_path.iterdir()) == []


def test_memory_error_is_one_line_and_leaves_nothing(tmp_path):
    """An address-space limit below what the map needs (the estimate told to allow it)."""
    limit = 1500 << 20

    def cap():
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    run = Running("map", "fivebar_singh", "--quantity", "isotropic_force", "--resolution", "12000",
                  "--out", str(tmp_path / "m.npz"), "--max-time", "1d", cwd=tmp_path, env={"ISOFORCE_MEMORY": "100G"},
                  preexec=cap)
    status, out, err = run.finish()
    assert status == 1, err
    assert out == ""
    _assert_one_line(err, "isoforce map", "out of memory")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("argv", [
    ("map", "fivebar_singh", "--quantity", "isotropic_force", "--resolution", "100000", "--out", "m.npz"),
    ("stats", "fivebar_singh", "--resolution", "4294967296"),
    ("map", "fivebar_singh", "--quantity", "isotropic_force", "--resolution", "100000", "--out", "m.png"),
    ("convergence", "fivebar_singh", "--resolutions", "100,100000"),
])
def test_a_map_that_cannot_fit_is_refused_at_once(tmp_path, argv):
    """Before: a MemoryError traceback after growing to 18 GB, or an overflowed np.prod."""
    run = Running(*argv, cwd=tmp_path, env={"ISOFORCE_MEMORY": "8G"})
    status, out, err = run.finish()
    assert status == 2, err
    assert out == "" and err.count("\n") == 1 and "Traceback" not in err, err
    assert "points, about" in err and ("available" in err or "can index" in err) and "or less" in err, err
    assert list(tmp_path.iterdir()) == []


def test_the_app_scheduler_refuses_a_map_too_large_with_a_message(monkeypatch):
    """The GUI path: the request is refused (a BudgetError delivered as the reason), no crash."""
    from app.jobs.requests import MapRequest, run_map
    from app.jobs.runner import JobRunner
    from metrics.budget import BudgetError
    from resources import load_preset

    monkeypatch.setenv("ISOFORCE_MEMORY", "1G")
    preset = load_preset("fivebar_singh")
    got = []
    sched = JobRunner(lambda request, result: got.append(result), job=run_map)
    try:
        sched.submit(MapRequest(preset.mechanism, preset.grid.with_resolution(50000), ("isotropic_force",)))
        assert sched.wait_idle(GUARD)
    finally:
        sched.shutdown()
    assert len(got) == 1 and isinstance(got[0], BudgetError)
    assert "50000 x 50000 map" in str(got[0]) and "or less" in str(got[0])
