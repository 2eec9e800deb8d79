"""File > Export report in the background (issue 11 sec. 4): progress per file, cancel, folder, Ctrl+E."""
from __future__ import annotations

import time

import pytest
from PySide6.QtCore import Qt, QTimer
from PySide6.QtWidgets import QPushButton

import app.render.views
from app.gui import export_job
from app.gui.export_job import exporter_of

SMALL = 61     # points along the longer map axis: fast maps, the export's cost is the figures


@pytest.fixture
def window(make_window, monkeypatch):
    monkeypatch.setattr(app.render.views, "DEFAULT_SIZE", (400, 300))
    return make_window("fivebar_singh", longest=SMALL)


def test_report_is_written_in_the_background_into_a_new_folder(window, qtbot, tmp_path):
    folder = tmp_path / "new" / "report"                   # missing: created
    exporter = exporter_of(window)
    ticks = []                                              # timer ticks while a file was being written
    timer = QTimer()
    timer.setInterval(20)
    timer.timeout.connect(lambda: ticks.append(len(exporter.request.written)) if exporter.busy() else None)
    timer.start()
    done = []
    exporter.finished.connect(done.append)
    request = exporter.start(folder, window._export_inputs())
    # The dialog's labels as the exporter sets them (a lambda on ``progressed`` reading the label
    # may run before or after the exporter's own slot: PySide does not order the two).
    labels = []
    set_label = exporter.dialog.setLabelText
    exporter.dialog.setLabelText = lambda text: (labels.append(text), set_label(text))[1]
    qtbot.waitUntil(lambda: bool(done), timeout=120_000)
    timer.stop()
    expected = [name for _, name in request.files]
    assert sorted(p.name for p in folder.iterdir()) == sorted(expected)      # no temporaries left
    assert [p.name for p in done[0]] == expected
    # The event loop ran throughout: the timer fired while files 1..n were still to come.
    assert len(set(ticks)) >= len(expected) // 2, ticks
    assert labels[-1].startswith(f"Writing {expected[-1]} ({len(expected)} of {len(expected)})"), labels
    assert not exporter.busy() and exporter.dialog is None


def test_a_cancelled_report_leaves_nothing(window, qtbot, tmp_path, monkeypatch):
    folder = tmp_path / "cancelled"
    real = app.render.views.export_view

    def slow(*args, **kwargs):                              # time to press Cancel between files
        time.sleep(0.2)
        return real(*args, **kwargs)
    monkeypatch.setattr(export_job.render, "export_view", slow)
    exporter = exporter_of(window)
    stopped = []
    exporter.stopped.connect(lambda: stopped.append(True))
    request = exporter.start(folder, window._export_inputs())
    qtbot.waitUntil(lambda: len(request.written) >= 2, timeout=60_000)
    exporter.dialog.findChild(QPushButton).click()           # the dialog's Cancel button
    qtbot.waitUntil(lambda: bool(stopped), timeout=60_000)
    assert not folder.exists()                              # its files removed, the folder it made too
    assert not exporter.busy()
    # An existing folder with other files keeps them and only them.
    folder.mkdir()
    (folder / "mine.txt").write_text("keep")
    stopped.clear()
    request = exporter.start(folder, window._export_inputs())
    qtbot.waitUntil(lambda: len(request.written) >= 1, timeout=60_000)
    exporter.cancel()
    qtbot.waitUntil(lambda: bool(stopped), timeout=60_000)
    assert [p.name for p in folder.iterdir()] == ["mine.txt"]


def test_ctrl_e_opens_the_report_dialog_while_a_spin_box_has_focus(window, qtbot, monkeypatch):
    from PySide6.QtWidgets import QFileDialog
    asked = []
    monkeypatch.setattr(QFileDialog, "getExistingDirectory", lambda *a, **k: asked.append(a) or "")
    spin = next(iter(window.param_panel.rows.values())).spin
    window.activateWindow()
    spin.setFocus()
    qtbot.waitUntil(lambda: spin.hasFocus() or spin.lineEdit().hasFocus(), timeout=5_000)
    qtbot.keyClick(spin.lineEdit(), Qt.Key.Key_E, Qt.KeyboardModifier.ControlModifier)
    qtbot.waitUntil(lambda: bool(asked), timeout=5_000)
    assert len(asked) == 1


def test_progress_that_arrives_with_the_result_finds_the_dialog_gone(window, qtbot, tmp_path, monkeypatch):
    """The modal dialog's ``setValue`` runs the event loop; the report's result, queued behind its
    progress (files written in no time, as the Inverse3's last ones are), closed the dialog in
    there, and the next line raised ``'NoneType' object has no attribute 'setLabelText'``."""
    from pathlib import Path

    def instant(what, path, **kwargs):
        Path(path).write_text(what)
        return Path(path)
    monkeypatch.setattr(export_job.render, "export_view", instant)
    exporter = exporter_of(window)
    done = []
    exporter.finished.connect(done.append)
    with qtbot.captureExceptions() as raised:
        request = exporter.start(tmp_path / "report", window._export_inputs())
        qtbot.waitUntil(lambda: bool(done), timeout=30_000)
        qtbot.wait(50)
    assert not raised, [str(e[1]) for e in raised]
    assert [p.name for p in done[0]] == [name for _, name in request.files]
    assert not exporter.busy() and exporter.dialog is None
