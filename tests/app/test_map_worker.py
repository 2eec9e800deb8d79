"""The coarse-map worker process (``app.jobs.map_worker``): the same map as computed in the thread,
and on any failure no answer (the caller computes the map itself), never a wrong one or a hang."""
from __future__ import annotations

import time

import numpy as np
import pytest

from app.jobs.map_worker import MapWorker
from app.jobs.requests import MapRequest, run_map
from metrics.loading import DEFAULT_LOADING
from metrics.workspace import compute_map
from resources import load_preset

QUANTITIES = ("anisotropic_force", "condition_number", "isotropic_force")


def _ready(worker: MapWorker, timeout: float = 60.0) -> MapWorker:
    worker.start()
    end = time.monotonic() + timeout
    while not worker.ready:
        assert time.monotonic() < end, "the worker process never said it was ready"
        time.sleep(0.01)
    return worker


@pytest.fixture(scope="module")
def worker():
    w = _ready(MapWorker())
    yield w
    w.close()


def _same_map(a, b) -> None:
    assert a.values.keys() == b.values.keys()
    for name in a.values:
        np.testing.assert_array_equal(a.values[name], b.values[name])
    np.testing.assert_array_equal(a.feasible, b.feasible)
    np.testing.assert_array_equal(a.singular, b.singular)
    # Equal floats print alike (nan included, which == would call unequal).
    assert repr(a.stats) == repr(b.stats) and repr(a.errors) == repr(b.errors)


@pytest.mark.parametrize("key", ["inverse3_prototype", "fivebar_singh", "phantom_premium_15"])
def test_the_process_computes_the_threads_map(worker, key):
    preset = load_preset(key)
    grid = preset.grid.with_resolution((60,) * len(preset.grid.resolution))
    names = tuple(q for q in QUANTITIES if q != "anisotropic_force" or preset.mechanism.task_dim == 3)
    # The same code, NumPy and data on one thread in both: the same numbers, bit for bit.
    _same_map(worker.compute(preset.mechanism, grid, names, DEFAULT_LOADING),
              compute_map(preset.mechanism, grid, names, threads=False))


def test_a_failing_request_gets_no_answer_and_the_caller_raises(worker):
    preset = load_preset("inverse3_prototype")
    grid = preset.grid.with_resolution((20, 20))
    assert worker.compute(preset.mechanism, grid, ("no_such_quantity",), DEFAULT_LOADING) is None
    with pytest.raises(ValueError, match="no_such_quantity"):
        request = MapRequest(preset.mechanism, grid, ("no_such_quantity",), stage="coarse")
        run_map(request, lambda f: None, lambda: False)
    # The process still answers the next request.
    assert worker.compute(preset.mechanism, grid, ("isotropic_force",), DEFAULT_LOADING) is not None


def test_no_answer_before_start_and_after_the_process_died():
    preset = load_preset("inverse3_prototype")
    grid = preset.grid.with_resolution((20, 20))
    w = MapWorker()
    assert w.compute(preset.mechanism, grid, ("isotropic_force",), DEFAULT_LOADING) is None   # not started
    _ready(w)
    w._process.kill()
    w._process.wait()
    assert w.compute(preset.mechanism, grid, ("isotropic_force",), DEFAULT_LOADING) is None
    assert w.compute(preset.mechanism, grid, ("isotropic_force",), DEFAULT_LOADING) is None   # given up, at once
    w.close()


def test_the_process_exits_when_its_input_closes():
    w = _ready(MapWorker())
    process = w._process
    w.close()
    assert process.returncode == 0


def test_a_coarse_request_goes_to_the_ready_process(monkeypatch):
    from app.jobs import map_worker, requests

    _ready(map_worker.shared())
    preset = load_preset("inverse3_prototype")
    grid = preset.grid.with_resolution((40, 40))
    expected = compute_map(preset.mechanism, grid, QUANTITIES, threads=False)

    def not_here(*args, **kwargs):
        raise AssertionError("a coarse map was computed in the thread, not in the ready process")

    monkeypatch.setattr(requests, "compute_map", not_here)
    request = MapRequest(preset.mechanism, grid, QUANTITIES, stage="coarse")
    _same_map(run_map(request, lambda f: None, lambda: False), expected)


class _NotInTheChild:
    """A class the child cannot import (tests are not on its path)."""


def test_a_request_the_child_cannot_read_gets_no_answer_and_the_child_lives_on(worker):
    preset = load_preset("inverse3_prototype")
    grid = preset.grid.with_resolution((20, 20))
    assert worker.compute(_NotInTheChild(), grid, ("isotropic_force",), DEFAULT_LOADING) is None
    assert worker.compute(preset.mechanism, grid, ("isotropic_force",), DEFAULT_LOADING) is not None


def test_ctrl_c_in_the_terminal_does_not_reach_the_child(worker):
    import os
    import signal

    assert os.getsid(worker._process.pid) != os.getsid(0)        # a session of its own
    worker._process.send_signal(signal.SIGINT)                    # and it ignores one sent to it
    preset = load_preset("inverse3_prototype")
    grid = preset.grid.with_resolution((20, 20))
    assert worker.compute(preset.mechanism, grid, ("isotropic_force",), DEFAULT_LOADING) is not None


#: What a stand-in child answers every request with: the bytes of its answer frame.
FAKE_ANSWERS = {
    "a bare number": "pickle.dumps(1)",
    "a pair of an unknown kind": "pickle.dumps(('surprise', 2))",
    "a class the parent cannot import": "only_in_child()",
    "not a pickle": "b'not a pickle'",
}
FAKE_CHILD = """
import os, pickle, struct, sys, types
def send(b):
    sys.stdout.buffer.write(struct.pack('<Q', len(b)) + b)
    sys.stdout.buffer.flush()
def only_in_child():
    module = types.ModuleType('only_in_child')
    sys.modules['only_in_child'] = module
    class Thing:
        pass
    Thing.__module__, Thing.__qualname__ = 'only_in_child', 'Thing'
    module.Thing = Thing
    return pickle.dumps(('map', Thing()))
send(pickle.dumps('ready'))
while True:
    head = os.read(0, 8)
    if len(head) < 8:
        break
    n = struct.unpack('<Q', head)[0]
    while n:
        n -= len(os.read(0, n))
    send(ANSWER)
"""


@pytest.mark.parametrize("answer", FAKE_ANSWERS)
def test_a_garbled_answer_gives_no_map_and_the_process_is_given_up(monkeypatch, answer):
    import sys

    from app.jobs import map_worker

    script = FAKE_CHILD.replace("ANSWER", FAKE_ANSWERS[answer])
    monkeypatch.setattr(map_worker, "_child_command", lambda: [sys.executable, "-c", script])
    w = _ready(MapWorker())
    preset = load_preset("inverse3_prototype")
    grid = preset.grid.with_resolution((20, 20))
    assert w.compute(preset.mechanism, grid, ("isotropic_force",), DEFAULT_LOADING) is None
    assert w._process is None and not w.ready            # given up: the caller computes from now on
    w.close()


def test_the_worker_imports_the_packages_from_this_checkout():
    """The child's PYTHONPATH starts with the folder that holds ``app``, ``metrics`` and ``kinematics``
    (after the move to ``app/jobs`` it was ``app/`` itself, and a worktree's child ran another tree)."""
    from pathlib import Path

    from app.jobs import map_worker

    root = Path(map_worker._ROOT)
    assert all((root / package / "__init__.py").is_file() for package in ("app", "metrics", "kinematics"))
