"""Runs a design study in the background for the app's optimisation panel.

The study itself (``metrics.studies.run_study``) is exact and headless; this wrapper runs it
on one worker thread (in-process: chunks in sequence), reports progress after each chunk,
and cancels by raising from the progress callback. A newer run supersedes an older one.
"""
from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

from PySide6.QtCore import QObject, Signal

from metrics.studies import run_study


class StudyCancelled(Exception):
    """Raised inside ``run_study``'s progress callback to stop a cancelled run."""


class StudyRunner(QObject):
    """``start(study)``; results arrive as ``finished(study, result)`` on the GUI thread."""

    progressed = Signal(float)
    finished = Signal(object, object)       # study, StudyResult
    failed = Signal(str)
    cancelled = Signal()

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="isoforce-study")
        self._flag: threading.Event | None = None

    def start(self, study, *, top_k: int = 10) -> None:
        self.cancel()
        flag = threading.Event()
        self._flag = flag
        self._executor.submit(self._run, study, top_k, flag)

    def cancel(self) -> None:
        if self._flag is not None:
            self._flag.set()

    def _run(self, study, top_k: int, flag: threading.Event) -> None:
        def progress(info: dict) -> None:
            if flag.is_set():
                raise StudyCancelled()
            self.progressed.emit(info["chunks_done"] / max(1, info["chunks"]))

        try:
            runs = study.runs() if study.series is not None else [study]
            results = [run_study(run, workers=1, top_k=top_k, progress=progress) for run in runs]
        except StudyCancelled:
            self.cancelled.emit()
            return
        except Exception as exc:     # shown in the panel, never swallowed
            self.failed.emit(f"{type(exc).__name__}: {exc}")
            return
        if not flag.is_set():
            self.finished.emit(study, results)

    def shutdown(self) -> None:
        self.cancel()
        self._executor.shutdown(wait=True, cancel_futures=True)
