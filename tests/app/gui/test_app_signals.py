"""Ctrl+C (or SIGTERM) in the terminal that started ``isoforce`` closes the app as its close
button does: exit status 0, no traceback, the layout saved, no worker process left behind.
(Before: a KeyboardInterrupt traceback out of ``QApplication.exec``.)"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

LAUNCH = "import sys; from app.launch import main; sys.exit(main([]))"


def _map_workers(pid: int) -> list[int]:
    """The map worker processes among ``pid``'s children, by command line: Qt may start short-lived
    others (``dbus-launch --autolaunch``) which are gone a moment later."""
    out = subprocess.run(["ps", "-o", "pid=,args=", "--ppid", str(pid)], capture_output=True, text=True).stdout
    return [int(line.split()[0]) for line in out.splitlines() if "app.jobs.map_worker" in line]


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_closes_the_app_cleanly(tmp_path, signum):
    settings = tmp_path / "settings.ini"
    env = dict(os.environ, ISOFORCE_SETTINGS=str(settings))
    app = subprocess.Popen([sys.executable, "-c", LAUNCH], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True)
    try:
        # Up: the map worker process is the app's child once the window exists.
        end = time.monotonic() + 60.0
        while not (workers := _map_workers(app.pid)):
            if app.poll() is not None or time.monotonic() > end:
                app.kill()
                pytest.fail(f"no map worker came up (exit status {app.poll()}): {app.communicate()[1]}")
            time.sleep(0.1)
        worker = workers[0]
        app.send_signal(signum)
        _, err = app.communicate(timeout=30.0)
    finally:
        if app.poll() is None:
            app.kill()
            app.communicate()                   # reaps it and closes its pipes
    assert app.returncode == 0, err
    assert "Traceback" not in err, err
    assert "geometry" in settings.read_text()                     # closed as by its close button
    time.sleep(0.5)
    assert subprocess.run(["ps", "-p", str(worker)], capture_output=True).returncode != 0, "the worker outlived the app"


def test_ctrl_c_before_the_window_exists_ends_the_process_without_a_traceback():
    # Deterministic: run_app, the first thing after the GUI's imports, is replaced by Ctrl+C itself.
    script = ("import os, signal, sys\n"
              "import app.gui\n"
              "app.gui.run_app = lambda: os.kill(os.getpid(), signal.SIGINT) or 0\n"
              "from app.launch import launch_gui\n"
              "sys.exit(launch_gui())\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.returncode == -signal.SIGINT, done.stderr       # ended by the signal, as the system does
    assert "Traceback" not in done.stderr, done.stderr
