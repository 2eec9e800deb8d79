"""Runs a design study in the background for the app's optimization panel.

The study itself (``metrics.design.run_study``) is exact and headless; ``StudyRequest`` and
its job (``app.jobs.requests``) run it on the app's one kind of background worker
(``app.jobs.runner.JobRunner``): progress after each chunk, cancel between chunks, and a newer run
supersedes an older one. This class only turns the worker's signals into the panel's.
"""
from __future__ import annotations

from PySide6.QtCore import QObject, Signal

from app.gui.qt_model import QtJobRunner
from app.jobs.requests import StudyRequest, run_study_job


class StudyRunner(QObject):
    """``start(study)``; results arrive as ``finished(study, results)`` on the GUI thread."""

    progressed = Signal(float)
    finished = Signal(object, object)       # study, list of StudyResult (one per run)
    failed = Signal(str)
    cancelled = Signal()

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.worker = QtJobRunner(run_study_job, self, name="isoforce-study")
        self.worker.progressed.connect(lambda request, fraction: self.progressed.emit(fraction))
        self.worker.resultReady.connect(self._on_result)
        self.worker.cancelled.connect(lambda request: self.cancelled.emit())

    def start(self, study, *, top_k: int | None = None) -> StudyRequest:
        """Run ``study``, ranking its ``top_k`` best designs (default: the study's own ``top_k``,
        as ``isoforce optimize`` does; the panel listed ten whatever the study said)."""
        return self.worker.submit(StudyRequest(study, study.objective.top_k if top_k is None else top_k))

    def cancel(self) -> None:
        self.worker.cancel()

    def _on_result(self, request: StudyRequest, result) -> None:
        # No generation check: a result that arrives just after Cancel is still shown (the run
        # finished), as the panel would otherwise wait for a cancellation that never comes.
        if isinstance(result, Exception):     # shown in the panel, never swallowed
            self.failed.emit(f"{type(result).__name__}: {result}")
        else:
            self.finished.emit(request.study, result)

    def shutdown(self) -> None:
        self.worker.shutdown()
