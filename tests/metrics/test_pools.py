"""A design study's process pool and the signals that stop it (``metrics.design.pools``)."""
from __future__ import annotations

import os
import signal
from concurrent.futures import ProcessPoolExecutor

import pytest

from metrics.design import process_pool, stop_process_pool


class Stop(Exception):
    """What the test's handler raises, as the CLI's raise ``KeyboardInterrupt`` / ``Terminated``."""


def _raise_stop(signum, frame):
    raise Stop


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_during_submit_acts_once_the_worker_is_spawned_whole(monkeypatch, signum):
    """Raised as a worker was spawned, a SIGTERM left a child printing ``EOFError`` outside the
    pool's processes, and a Ctrl-C was lost (SIGINT was ignored for the call). Both are held
    until ``submit`` returns, then raised as usual, and the worker lives on to be stopped."""
    original = ProcessPoolExecutor.submit
    spawned_before_raise = []

    def submit_under_signal(self, *args, **kwargs):
        os.kill(os.getpid(), signum)                  # arrives as the workers are about to start
        future = original(self, *args, **kwargs)
        spawned_before_raise.append(len(self._processes))
        return future

    previous = signal.signal(signum, _raise_stop)
    pool = process_pool(1)
    try:
        monkeypatch.setattr(ProcessPoolExecutor, "submit", submit_under_signal)
        with pytest.raises(Stop):
            pool.submit(int, "3")
        assert spawned_before_raise == [1]             # the worker started before the handler ran
        assert signal.getsignal(signum) is _raise_stop
        assert signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, [])
        assert all(p.is_alive() for p in pool._processes.values())
    finally:
        signal.signal(signum, previous)
        stop_process_pool(pool)
