"""File > Export report in the background: one file at a time on a worker, with progress and cancel.

The report's files (``app.render.views.report_files``) are written by ``render.export_view`` on a
``JobRunner`` worker thread (``QtJobRunner``), so the event loop keeps running: the window
repaints and the progress dialog moves file by file. The folder is created if it is missing.

Cancel stops between files (a file being written is finished first: ``export_view`` has no
cancel of its own, at most ~1.5 s for the 3D view). Every file is written atomically
(``app.files.export.atomic_write``), so no partial file is ever seen; a cancelled report also
**removes the files it wrote** (and the folders it created, if left empty), so the folder
is as before, never half a report. A file of the same name that was there before is
replaced as soon as its new version is complete, and is not restored.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

from PySide6.QtCore import QEvent, QObject, Qt, Signal
from PySide6.QtGui import QKeySequence
from PySide6.QtWidgets import QApplication, QProgressDialog
from shiboken6 import isValid

from app.gui.qt_model import QtJobRunner
from app.jobs.runner import Cancelled
from app.render import views as render

TAG = "report"


@dataclasses.dataclass(frozen=True, eq=False)
class ReportRequest:
    """One report: ``files`` (``(what, name)``) into ``folder`` from ``inputs`` (``export_view``'s keywords).

    ``written`` (filled by the worker) and ``created`` (folders made for it, outermost first)
    say what to remove if it is cancelled.
    """

    folder: Path
    files: tuple[tuple[str, str], ...]
    inputs: dict
    created: tuple[Path, ...] = ()
    written: list = dataclasses.field(default_factory=list)
    tag: str = TAG
    generation: int = 0


def make_folder(folder) -> tuple[Path, ...]:
    """Create ``folder`` and its missing parents; returns the folders created, outermost first."""
    folder = Path(folder)
    missing = [p for p in (folder, *folder.parents) if not p.exists()][::-1]
    folder.mkdir(parents=True, exist_ok=True)
    return tuple(missing)


def remove_written(request: ReportRequest) -> None:
    """Undo a cancelled report: its files, then the folders it created if they are empty."""
    for path in list(request.written):
        Path(path).unlink(missing_ok=True)
    request.written.clear()
    for folder in reversed(request.created):
        try:
            folder.rmdir()
        except OSError:        # not empty (someone else's files) or gone: left as it is
            pass


def write_report(request: ReportRequest, progress, cancelled) -> list[Path]:
    """The job: every file of ``request`` in turn; ``progress(k / n)`` before file ``k`` (0-based)."""
    n = len(request.files)
    try:
        for k, (what, name) in enumerate(request.files):
            if cancelled():
                raise Cancelled()
            progress(k / n)
            request.written.append(render.export_view(what, request.folder / name, **request.inputs))
        if cancelled():
            raise Cancelled()
    except BaseException:
        remove_written(request)     # cancelled or failed: no half report
        raise
    progress(1.0)
    return list(request.written)


class ReportExporter(QObject):
    """Runs reports for ``window`` (a ``MainWindow``: ``statusBar``, ``show_error``) with a progress dialog."""

    finished = Signal(object)       # list of written paths
    failed = Signal(str)
    stopped = Signal()              # cancelled, files removed

    def __init__(self, window) -> None:
        super().__init__(window)
        self.window = window
        self.runner = QtJobRunner(write_report, self, name="isoforce-report")
        self.runner.resultReady.connect(self._on_result)
        self.runner.progressed.connect(self._on_progress)
        self.runner.cancelled.connect(self._on_cancelled)
        self.request: ReportRequest | None = None
        self.dialog: QProgressDialog | None = None

    def busy(self) -> bool:
        return self.request is not None

    def start(self, folder, inputs: dict) -> ReportRequest:
        """Create ``folder`` if missing and write the report there in the background.

        Raises ``OSError`` when the folder cannot be made (nothing started).
        """
        if self.request is not None:
            raise ValueError("a report is already being written; wait for it or cancel it")
        folder = Path(folder)
        created = make_folder(folder)
        files = tuple(render.report_files(inputs["quantity"], pose=inputs.get("pose"),
                                          reference_map=inputs.get("reference_map")))
        self.request = self.runner.submit(ReportRequest(folder, files, dict(inputs), created))
        dialog = QProgressDialog(f"Writing {files[0][1]} (1 of {len(files)})", "Cancel", 0, len(files), self.window)
        dialog.setWindowTitle("Export report")
        dialog.setWindowModality(Qt.WindowModality.WindowModal)    # the window repaints; its inputs wait
        dialog.setMinimumDuration(0)
        dialog.setAutoClose(False)
        dialog.setAutoReset(False)
        dialog.canceled.connect(self.cancel)
        dialog.setValue(0)
        dialog.show()
        self.dialog = dialog
        return self.request

    def cancel(self) -> None:
        if self.request is not None:
            self.runner.cancel(TAG)
            if self.dialog is not None:
                self.dialog.setLabelText("Cancelling (the file being written is finished, then removed)...")

    def _on_progress(self, request, fraction: float) -> None:
        dialog = self.dialog
        if request is not self.request or dialog is None:
            return
        n = len(request.files)
        k = min(n - 1, round(fraction * n))
        dialog.setValue(round(fraction * n))
        # A modal dialog's setValue runs the event loop: the report's result, queued behind this
        # progress, may have closed the dialog in there.
        if fraction < 1.0 and self.dialog is dialog:
            dialog.setLabelText(f"Writing {request.files[k][1]} ({k + 1} of {n})")

    def _close(self) -> ReportRequest | None:
        request, self.request = self.request, None
        if self.dialog is not None:
            self.dialog.canceled.disconnect(self.cancel)
            self.dialog.close()
            self.dialog.deleteLater()
            self.dialog = None
        return request

    def _on_result(self, request, result) -> None:
        if request is not self.request:
            return
        self._close()
        if isinstance(result, BaseException):
            self.window.show_error(f"Report export failed, nothing was left in {request.folder}: {result}")
            self.failed.emit(str(result))
            return
        self.window.statusBar().showMessage(f"Wrote {len(result)} files to {request.folder}", 5000)
        self.finished.emit(result)

    def _on_cancelled(self, request) -> None:
        if request is not self.request:
            return
        self._close()
        remove_written(request)      # again, should a cancel have come after the last file
        self.window.statusBar().showMessage(f"Report cancelled; nothing left in {request.folder}", 5000)
        self.stopped.emit()


def exporter_of(window) -> ReportExporter:
    """The window's one ``ReportExporter``, made on first use."""
    exporter = getattr(window, "_report_exporter", None)
    if exporter is None:
        exporter = window._report_exporter = ReportExporter(window)
    return exporter


class _KeepShortcuts(QObject):
    """Lets the actions' shortcuts through where a text field would take the key for itself.

    A spin box's line edit claims Ctrl+E (end of line) in its ``ShortcutOverride``, so no
    shortcut of that key fires while it has focus, whatever the context. Eating that one
    event (not accepting it) leaves the key to the shortcut map. One filter for the whole
    application and every such action: each event Qt delivers passes through it (a device
    switch, building its panel, delivered ~3,400; with one filter per action, three Python
    calls each, 20-30 ms of the switch).
    """

    def __init__(self, parent) -> None:
        super().__init__(parent)
        self.actions: list = []

    def eventFilter(self, obj, event) -> bool:   # noqa: N802 (Qt name)
        if event.type() != QEvent.Type.ShortcutOverride:
            return False
        self.actions = [a for a in self.actions if isValid(a)]      # (a closed window's are gone)
        pressed = QKeySequence(event.keyCombination())
        return any(action.isEnabled() and any(pressed.matches(s) == QKeySequence.SequenceMatch.ExactMatch
                                              for s in action.shortcuts()) for action in self.actions)


def application_shortcut(action) -> None:
    """``action``'s shortcut works anywhere in the application, also while a spin box has focus."""
    action.setShortcutContext(Qt.ShortcutContext.ApplicationShortcut)
    app = QApplication.instance()
    keep = getattr(app, "_isoforce_keep_shortcuts", None)
    if keep is None or not isValid(keep):
        keep = _KeepShortcuts(app)
        app._isoforce_keep_shortcuts = keep
        app.installEventFilter(keep)
    keep.actions.append(action)
