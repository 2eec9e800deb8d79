"""Background jobs, newest wins: one worker thread, progress, cancel, stale results dropped.

``JobRunner`` is plain Python (tested without Qt, with fake jobs). It runs every kind of
heavy work the app does off the GUI thread (maps, design studies) the same way:

- a request is a frozen dataclass with a ``tag`` (``str``: which slot it fills, e.g.
  ``"current"``, ``"reference"``, ``"study"``) and a ``generation`` (``int``, set here);
- ``submit`` numbers it and cancels the running or queued request of the same tag (the job
  checks a flag between chunks and raises ``Cancelled``); requests of other tags run on;
- a job is ``job(request, progress, cancelled)``: ``progress(fraction)`` with ``fraction``
  in [0, 1], ``cancelled() -> bool``; its return value (or the exception it raised) is
  delivered, but only while its generation is still the newest of its tag;
- ``cancel(tag)`` stops a request on the user's behalf, and ``cancelled(request)`` tells so.

Callbacks run on the worker thread; the GUI's adapter (``app.gui.qt_model.QtJobRunner``)
re-emits them as Qt signals on the GUI thread. No Qt here.
"""
from __future__ import annotations

import dataclasses
import threading
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any, Callable

from metrics.workspace import Cancelled

__all__ = ["Cancelled", "Job", "JobRunner"]

#: ``job(request, progress, cancelled) -> result``.
Job = Callable[[Any, Callable[[float], None], Callable[[], bool]], Any]


class JobRunner:
    """Newest-wins execution of requests on one worker thread.

    Parameters
    ----------
    deliver : callable ``(request, result_or_exception)``
        Called from the worker thread with the job's result, or the exception it raised
        (never swallowed: the GUI shows it), only for the newest request of its tag.
    progress : callable ``(request, fraction)``, optional
        Called from the worker thread while the request is the newest of its tag.
    job : callable ``(request, progress, cancelled)``
        The work; raises ``Cancelled`` when ``cancelled()`` turns true between chunks.
    cancelled : callable ``(request)``, optional
        Called once when a request stops because ``cancel`` was called for it (not when a
        newer request superseded it, and not at ``shutdown``).
    name : str
        Prefix of the worker thread's name.
    """

    def __init__(self, deliver: Callable[[Any, Any], None], progress: Callable[[Any, float], None] | None = None,
                 *, job: Job, cancelled: Callable[[Any], None] | None = None, name: str = "isoforce-jobs") -> None:
        self._deliver = deliver
        self._progress = progress
        self._job = job
        self._on_cancelled = cancelled
        self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix=name)
        self._lock = threading.Lock()
        self._generation = 0
        self._latest: dict[str, int] = {}
        self._cancel_flags: dict[str, threading.Event] = {}
        self._user_cancelled: set[int] = set()     # generations stopped by cancel()

    def submit(self, request):
        """Queue ``request``, cancelling any older one with the same tag; returns it numbered."""
        with self._lock:
            self._generation += 1
            numbered = dataclasses.replace(request, generation=self._generation)
            old = self._cancel_flags.get(request.tag)
            if old is not None:
                old.set()
            flag = threading.Event()
            self._cancel_flags[request.tag] = flag
            self._latest[request.tag] = numbered.generation
        self._executor.submit(self._run, numbered, flag)
        return numbered

    def is_current(self, request) -> bool:
        """Whether ``request`` is still the newest of its tag."""
        with self._lock:
            return self._latest.get(request.tag) == request.generation

    def cancel(self, tag: str | None = None) -> None:
        """Cancel the running or queued request of ``tag`` (all tags if None)."""
        self._cancel(tag, by_user=True)

    def _cancel(self, tag: str | None, by_user: bool) -> None:
        with self._lock:
            for key, flag in self._cancel_flags.items():
                if tag is None or key == tag:
                    if by_user and self._latest.get(key, -1) > 0 and not flag.is_set():
                        self._user_cancelled.add(self._latest[key])
                    flag.set()
                    self._latest[key] = -1

    def _stopped(self, request) -> None:
        """A request that will not be delivered: say so if the user cancelled it."""
        with self._lock:
            by_user = request.generation in self._user_cancelled
            self._user_cancelled.discard(request.generation)
        if by_user and self._on_cancelled is not None:
            self._on_cancelled(request)

    def _run(self, request, flag: threading.Event) -> None:
        if flag.is_set():
            self._stopped(request)
            return

        def progress(fraction: float) -> None:
            if self._progress is not None and self.is_current(request):
                self._progress(request, fraction)

        try:
            result = self._job(request, progress, flag.is_set)
        except Cancelled:
            self._stopped(request)
            return
        except Exception as exc:   # delivered, not swallowed: the GUI shows it
            result = exc
        if not flag.is_set() and self.is_current(request):
            self._deliver(request, result)
        else:
            self._stopped(request)

    def wait_idle(self, timeout: float = 30.0) -> bool:
        """Block until every queued job has run (for tests and scripts)."""
        done: Future = self._executor.submit(lambda: None)
        try:
            done.result(timeout)
            return True
        except TimeoutError:
            return False

    def shutdown(self) -> None:
        """Cancel everything (without ``cancelled`` callbacks) and wait for the worker to stop."""
        self._cancel(None, by_user=False)
        self._executor.shutdown(wait=True, cancel_futures=True)
