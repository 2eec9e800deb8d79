"""Coarse maps in a worker process of their own, so that they run beside the GUI thread's Python.

A slider step computes a coarse map (~14,000 points, ~11 ms) on the map worker thread while the
GUI thread updates the pose glyphs (~9 ms of Python) and renders them. Both need the one
interpreter lock: the map's many small NumPy calls and the glyphs' PyVista calls take turns,
and the step reached the screen only after the sum of the two. In a process of its own the map
runs truly beside the GUI (``scripts/bench_gui.py``, five alternating pairs on a quiet 2-core
machine: slider step to screen median 24.7, 30.3, 30.2, 28.1, 42.3 ms against 32.7, 33.4, 34.2,
39.1, 30.3 ms in the thread; the map worker thread's wait for an answer 15-16 ms against 18-21 ms
of computing).

Only small maps go there: a full map runs on the thread pool of the GUI's process, where its
chunks release the lock for long array operations, and its arrays (tens of MB) would cost more
to send than to compute. The process is an optimization and nothing else: when it is not
started, not yet ready (importing NumPy and the models takes it ~0.5 s), has died, or fails
in any way, ``compute`` returns None and the caller computes in its own thread, which then
also raises whatever error the request deserves (a bad quantity, a bad loading). A process
that answered wrongly or not at all is stopped and not asked again in this session.

The child runs in a session of its own (Ctrl+C in the app's terminal does not reach it) with
``python -P``: the app's package root first on its path, never the current directory, so it
imports the very modules the app runs.

Protocol: frames of an 8-byte little-endian length and a pickle, over the child's stdin and
stdout (the child's ``print`` goes to stderr). The child says it is ready with a first frame,
then answers each request ``(mechanism, grid, quantities, loading)`` with ``("map", map)`` or
``("error", text)``; it exits when its stdin closes, so it never outlives the app.
"""
from __future__ import annotations

import atexit
import os
import pickle
import select
import signal
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

__all__ = ["MapWorker", "shared"]

_HEADER = struct.Struct("<Q")
#: The package root: the child imports ``app`` and ``metrics`` from where this app runs.
_ROOT = str(Path(__file__).resolve().parents[2])
#: Longest wait (s) for one answer before the process is given up: a coarse map takes 0.01 s
#: (the Inverse3) to 0.25 s (the Twin-Pantograph, the Stewart platform).
ANSWER_TIMEOUT_S = 10.0


def _write_frame(stream, payload: bytes) -> None:
    stream.write(_HEADER.pack(len(payload)) + payload)
    stream.flush()


def _read_exact(fd: int, n: int, deadline: float | None) -> bytes:
    """``n`` bytes from the file descriptor ``fd``; EOFError at its end, TimeoutError past ``deadline``."""
    parts, got = [], 0
    while got < n:
        if deadline is not None:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([fd], [], [], left)[0]:
                raise TimeoutError("the map worker process did not answer")
        chunk = os.read(fd, min(n - got, 1 << 20))
        if not chunk:
            raise EOFError("the map worker process closed its output")
        parts.append(chunk)
        got += len(chunk)
    return b"".join(parts)


def _read_payload(fd: int, deadline: float | None = None) -> bytes:
    (size,) = _HEADER.unpack(_read_exact(fd, _HEADER.size, deadline))
    return _read_exact(fd, size, deadline)


def _child_command() -> list[str]:
    """The child's command line: this Python, ``-P`` (no current directory on its path)."""
    return [sys.executable, "-P", "-c", "from app.jobs.map_worker import serve; serve()"]


def serve() -> None:
    """The child's loop: answer requests on stdin until it closes."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)    # the app decides when it ends: its input closes
    from metrics.workspace import compute_map

    out, fd = sys.stdout.buffer, sys.stdin.fileno()
    sys.stdout = sys.stderr                     # a stray print must not corrupt the frames
    try:
        _write_frame(out, pickle.dumps("ready"))
        _answer_requests(out, fd, compute_map)
    except EOFError:                            # the app closed its end: the work is over
        return
    except BrokenPipeError:                     # the app is gone: leave, flushing nothing it will read
        os._exit(0)


def _answer_requests(out, fd: int, compute_map) -> None:
    """Answer each request read from ``fd`` on ``out`` until EOFError (its input closed)."""
    while True:
        payload = _read_payload(fd)
        try:
            mechanism, grid, quantities, loading = pickle.loads(payload)
            answer = ("map", compute_map(mechanism, grid, quantities, threads=False, loading=loading))
            payload = pickle.dumps(answer, protocol=pickle.HIGHEST_PROTOCOL)
        except Exception as exc:                # the caller computes it again itself, and raises there
            payload = pickle.dumps(("error", f"{type(exc).__name__}: {exc}"))
        _write_frame(out, payload)


class MapWorker:
    """One worker process computing maps on request (``compute``), started by ``start``."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._process: subprocess.Popen | None = None
        self._ready = False
        self._broken = False

    def start(self) -> None:
        """Start the process (returns at once; it is ready about half a second later)."""
        with self._lock:
            if self._process is not None or self._broken or os.name != "posix":
                return
            env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [_ROOT, os.environ.get("PYTHONPATH")])))
            try:
                self._process = subprocess.Popen(_child_command(), stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                                 env=env, start_new_session=True)
            except OSError:
                self._broken = True

    @property
    def ready(self) -> bool:
        """Whether the process has started and said it is ready (never waits)."""
        with self._lock:
            return self._poll_ready()

    def _poll_ready(self) -> bool:
        if self._ready or self._broken or self._process is None:
            return self._ready
        try:
            if select.select([self._process.stdout], [], [], 0)[0]:
                payload = _read_payload(self._process.stdout.fileno(), time.monotonic() + ANSWER_TIMEOUT_S)
                self._ready = pickle.loads(payload) == "ready"
                if not self._ready:
                    self._give_up()
        except Exception:                        # whatever went wrong, the caller computes from now on
            self._give_up()
        return self._ready

    def compute(self, mechanism, grid, quantities, loading):
        """``compute_map(mechanism, grid, quantities, threads=False, loading=loading)`` in the process.

        Returns
        -------
        WorkspaceMap or None
            None when the process cannot answer (not ready, gone, or the request failed there):
            the caller then computes the map itself.
        """
        try:
            payload = pickle.dumps((mechanism, grid, tuple(quantities), loading), protocol=pickle.HIGHEST_PROTOCOL)
        except Exception:                        # something the process cannot be sent: the caller computes
            return None
        with self._lock:
            if not self._poll_ready():
                return None
            try:
                _write_frame(self._process.stdin, payload)
                kind, value = pickle.loads(_read_payload(self._process.stdout.fileno(),
                                                         time.monotonic() + ANSWER_TIMEOUT_S))
                if kind not in ("map", "error"):
                    raise ValueError(f"an answer of kind {kind!r}")
            except Exception:                    # dead, silent or garbled: the caller computes from now on
                self._give_up()
                return None
        return value if kind == "map" else None

    def _give_up(self) -> None:
        """The process misbehaved: stop it and compute in the caller's thread from now on."""
        self._broken, self._ready = True, False
        process, self._process = self._process, None
        if process is not None:
            process.kill()
            _release(process)

    def close(self) -> None:
        """Close the process's input (it exits) and wait for it, briefly."""
        with self._lock:
            process, self._process, self._ready = self._process, None, False
        if process is not None:
            _release(process)


def _release(process: subprocess.Popen) -> None:
    """Close ``process``'s input (it exits at the end of its input), wait for it (killed after
    2 s), and close its output."""
    try:
        process.stdin.close()
    except OSError:                              # a request half written to a process that died
        pass
    try:
        process.wait(timeout=2.0)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
    process.stdout.close()


_SHARED: MapWorker | None = None
_SHARED_LOCK = threading.Lock()


def shared() -> MapWorker:
    """The app's one worker process (made on first use, closed at exit)."""
    global _SHARED
    with _SHARED_LOCK:
        if _SHARED is None:
            _SHARED = MapWorker()
            atexit.register(_SHARED.close)
        return _SHARED
