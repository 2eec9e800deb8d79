"""A design study's process pool and the signals that stop it (``metrics.design.pools``)."""
from __future__ import annotations

import os
import signal
from concurrent.futures import ProcessPoolExecutor

import pytest

from metrics.design import process_pool, stop_process_pool


class Stop(Exception):
    """What the test's SIGTERM handler raises, as the CLI's raises ``Terminated``."""


def _raise_stop(signum, frame):
    raise Stop


def test_a_sigterm_during_submit_acts_once_the_worker_is_spawned_whole(monkeypatch):
    """A SIGTERM that interrupted a worker's spawn left a child printing ``EOFError`` and outside
    the pool's processes; it is held until ``submit`` returns, then raised as usual."""
    original = ProcessPoolExecutor.submit
    spawned_before_raise = []

    def submit_under_sigterm(self, *args, **kwargs):
        os.kill(os.getpid(), signal.SIGTERM)          # arrives as the workers are about to start
        future = original(self, *args, **kwargs)
        spawned_before_raise.append(len(self._processes))
        return future

    previous = signal.signal(signal.SIGTERM, _raise_stop)
    pool = process_pool(1)
    try:
        monkeypatch.setattr(ProcessPoolExecutor, "submit", submit_under_sigterm)
        with pytest.raises(Stop):
            pool.submit(int, "3")
        assert spawned_before_raise == [1]             # the worker started before the handler ran
        assert signal.getsignal(signal.SIGTERM) is _raise_stop
    finally:
        signal.signal(signal.SIGTERM, previous)
        stop_process_pool(pool)
