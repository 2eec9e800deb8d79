"""The one place plain-Python events become Qt signals.

``QtAppState`` wraps an ``AppModel``: each model event is re-emitted as the Qt signal the
widgets connect to (``presetChanged``, ``mechanismChanged``, ...); reading an attribute or
calling a setter goes straight to the model, which stays the only truth.

``QtJobRunner`` wraps an ``app.jobs.runner.JobRunner``: results, progress and cancellations,
reported on the worker thread, arrive as Qt signals on the GUI thread (queued connections),
where the generation is checked once more before anything is shown.
"""
from __future__ import annotations

from PySide6.QtCore import QObject, Signal

from app.gui.model import AppModel
from app.jobs.runner import Job, JobRunner


class QtAppState(QObject):
    """Qt signals for an ``AppModel``; attributes and setters are the model's."""

    presetChanged = Signal()
    mechanismChanged = Signal()
    quantityChanged = Signal()
    poseChanged = Signal()
    poseReportChanged = Signal()
    glyphsChanged = Signal()
    mapChanged = Signal()          # current map replaced
    referenceChanged = Signal()    # pinned reference set, cleared or its map replaced
    compareModeChanged = Signal()
    progressChanged = Signal(float)
    busyChanged = Signal(bool)
    staleChanged = Signal(object)  # the reason (str) or None
    sliceChanged = Signal()        # the plane shown of a 3D box map moved
    loadingChanged = Signal()      # the torque rating or gravity changed
    interactionChanged = Signal()  # a slider pressed or released (``AppModel.interaction``)
    overlayChanged = Signal()      # the map view's overlay
    notice = Signal(str)           # a choice the model changed on its own (``AppModel``'s ``notice`` event)
    historyChanged = Signal()      # the undo history, or the design last saved (``AppModel.history``)

    def __init__(self, model: AppModel, parent=None) -> None:
        super().__init__(parent)
        self.model = model
        events = model.events
        for event, signal in ((events.preset, self.presetChanged), (events.mechanism, self.mechanismChanged),
                              (events.quantity, self.quantityChanged), (events.pose, self.poseChanged),
                              (events.pose_report, self.poseReportChanged), (events.glyphs, self.glyphsChanged),
                              (events.map, self.mapChanged), (events.reference, self.referenceChanged),
                              (events.compare_mode, self.compareModeChanged),
                              (events.progress, self.progressChanged), (events.busy, self.busyChanged),
                              (events.stale, self.staleChanged), (events.slice, self.sliceChanged),
                              (events.loading, self.loadingChanged),
                              (events.interaction, self.interactionChanged), (events.overlay, self.overlayChanged),
                              (events.notice, self.notice), (events.history, self.historyChanged)):
            event.connect(signal.emit)

    def __getattr__(self, name: str):
        # Only reached for names this adapter does not define: the model's state and setters.
        if name == "model":
            raise AttributeError(name)
        return getattr(self.model, name)


class QtJobRunner(QObject):
    """A ``JobRunner`` whose results, progress and cancellations arrive as GUI-thread signals."""

    resultReady = Signal(object, object)     # request, result or exception
    progressed = Signal(object, float)       # request, fraction
    cancelled = Signal(object)               # request stopped by cancel()

    def __init__(self, job: Job, parent=None, *, name: str = "isoforce-jobs") -> None:
        super().__init__(parent)
        self.core = JobRunner(deliver=self.resultReady.emit, progress=self.progressed.emit, job=job,
                              cancelled=self.cancelled.emit, name=name)

    def submit(self, request):
        return self.core.submit(request)

    def is_current(self, request) -> bool:
        return self.core.is_current(request)

    def cancel(self, tag: str | None = None) -> None:
        self.core.cancel(tag)

    def shutdown(self) -> None:
        self.core.shutdown()
