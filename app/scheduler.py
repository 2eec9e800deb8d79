"""Runs map requests off the GUI thread: newest wins, stale results are dropped.

``MapScheduler`` is plain Python (tested without Qt, with fake jobs): it owns a one-worker
executor, numbers every request, cancels the running one when a newer arrives (the job
checks a flag between chunks), and hands back only results whose generation is still the
newest. ``QtMapScheduler`` wraps it so results and progress arrive as Qt signals on the GUI
thread, where the generation is checked once more before anything is shown.
"""
from __future__ import annotations

import threading
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Callable

from metrics.budget import check_map
from metrics.workspace import Cancelled, GridSpec, WorkspaceMap, compute_map


@dataclass(frozen=True)
class MapRequest:
    """An immutable description of one map to compute."""

    mechanism: Any
    grid: GridSpec
    quantities: tuple[str, ...]
    stage: str = "full"          # "coarse" while a slider moves, "full" when it stops
    tag: str = "current"         # "current" or "reference" (a pinned design)
    generation: int = field(default=-1, compare=False)


def run_map(request: MapRequest, progress: Callable[[float], None], cancelled: Callable[[], bool]) -> WorkspaceMap:
    """The default job: ``compute_map`` of the request."""
    # A map that cannot fit in memory is refused before it starts (a BudgetError, delivered
    # to the GUI as the reason the map could not be computed), instead of a MemoryError later.
    check_map(request.mechanism, request.grid.resolution, request.quantities, option="the map's resolution")
    # A coarse map (a slider moving) runs on one core, leaving the other to the GUI thread,
    # which draws the pose glyphs of the same change meanwhile.
    return compute_map(request.mechanism, request.grid, request.quantities, progress=progress, cancelled=cancelled,
                       threads=request.stage != "coarse")


class MapScheduler:
    """Newest-wins execution of map requests on one worker thread.

    ``deliver(request, result_or_exception)`` and ``progress(request, fraction)`` are called
    from the worker thread, and only for the newest request of its ``tag``.
    """

    def __init__(self, deliver: Callable[[MapRequest, Any], None],
                 progress: Callable[[MapRequest, float], None] | None = None,
                 job: Callable[..., Any] = run_map) -> None:
        self._deliver = deliver
        self._progress = progress
        self._job = job
        self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="isoforce-scheduler")
        self._lock = threading.Lock()
        self._generation = 0
        self._latest: dict[str, int] = {}
        self._cancel_flags: dict[str, threading.Event] = {}

    def submit(self, request: MapRequest) -> MapRequest:
        """Queue ``request``, cancelling any older one with the same tag; returns it numbered."""
        with self._lock:
            self._generation += 1
            numbered = MapRequest(request.mechanism, request.grid, request.quantities, request.stage,
                                  request.tag, self._generation)
            old = self._cancel_flags.get(request.tag)
            if old is not None:
                old.set()
            flag = threading.Event()
            self._cancel_flags[request.tag] = flag
            self._latest[request.tag] = numbered.generation
        self._executor.submit(self._run, numbered, flag)
        return numbered

    def is_current(self, request: MapRequest) -> bool:
        """Whether ``request`` is still the newest of its tag."""
        with self._lock:
            return self._latest.get(request.tag) == request.generation

    def cancel(self, tag: str | None = None) -> None:
        """Cancel the running or queued request of ``tag`` (all tags if None)."""
        with self._lock:
            for key, flag in self._cancel_flags.items():
                if tag is None or key == tag:
                    flag.set()
                    self._latest[key] = -1

    def _run(self, request: MapRequest, flag: threading.Event) -> None:
        if flag.is_set():
            return
        def progress(fraction: float) -> None:
            if self._progress is not None and self.is_current(request):
                self._progress(request, fraction)
        try:
            result = self._job(request, progress, flag.is_set)
        except Cancelled:
            return
        except Exception as exc:   # delivered, not swallowed: the GUI shows it
            result = exc
        if not flag.is_set() and self.is_current(request):
            self._deliver(request, result)

    def wait_idle(self, timeout: float = 30.0) -> bool:
        """Block until every queued job has run (for tests and scripts)."""
        done: Future = self._executor.submit(lambda: None)
        try:
            done.result(timeout)
            return True
        except TimeoutError:
            return False

    def shutdown(self) -> None:
        self.cancel()
        self._executor.shutdown(wait=True, cancel_futures=True)
