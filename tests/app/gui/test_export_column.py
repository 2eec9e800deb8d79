"""File > Export of a PDF or SVG asks a journal column's width and font (``app.gui.export_size``),
as ``isoforce figure --width-in --font-pt`` takes them, and remembers them.

The dialog is the real one, run modally (``exec``) and answered by a timer as a user would; the
file dialog is patched to name the file. The page's width is read from the PDF's MediaBox (as
the CLI's tests do): a point is 1/72 in; matplotlib writes the figure's width in inches times
72 with 10 decimals (``pdfRepr``), so 3.2 in reads 230.4 pt to within 1e-10 pt.
"""
from __future__ import annotations

import re

import pytest
from PySide6.QtCore import QTimer
from PySide6.QtWidgets import QApplication, QDialogButtonBox

import app.gui.file_actions as file_actions
import app.render.views as views
from app.gui.export_size import SETTINGS_KEYS, ColumnDialog

SMALL = 41          # points along the longer map axis: fast maps


def media_box(data: bytes) -> tuple[float, float]:
    box = re.search(rb"/MediaBox \[ *0 0 ([\d.]+) ([\d.]+) *\]", data)
    return float(box.group(1)), float(box.group(2))


def answer(qtbot, *, width=None, font=None, column=True, ok=True, seen=None) -> None:
    """Answer the next ``ColumnDialog`` once it is shown: set its fields, press OK or Cancel."""
    def respond():
        dialog = next((w for w in QApplication.topLevelWidgets() if isinstance(w, ColumnDialog) and w.isVisible()),
                      None)
        if dialog is None:                      # not shown yet: look again
            QTimer.singleShot(20, respond)
            return
        if seen is not None:
            seen.append((dialog.group.isChecked(), dialog.width_in.value(), dialog.font_pt.value()))
        dialog.group.setChecked(column)
        if width is not None:
            dialog.width_in.setValue(width)
        if font is not None:
            dialog.font_pt.setValue(font)
        button = QDialogButtonBox.StandardButton.Ok if ok else QDialogButtonBox.StandardButton.Cancel
        dialog.findChild(QDialogButtonBox).button(button).click()
    QTimer.singleShot(0, respond)


@pytest.fixture
def save_as(monkeypatch):
    """Name the file the next File > Export writes (the save dialog, patched)."""
    chosen = {}
    monkeypatch.setattr(file_actions.QFileDialog, "getSaveFileName",
                        staticmethod(lambda *args, **kwargs: (str(chosen["path"]), "")))
    return chosen


def test_a_pdf_export_is_the_column_wide_and_the_choice_is_remembered(make_window, qtbot, tmp_path, save_as,
                                                                      monkeypatch):
    window = make_window("inverse3_prototype", longest=SMALL)
    columns = []
    export = views.export_view

    def spy(what, path, **kwargs):
        columns.append(kwargs["column"])
        return export(what, path, **kwargs)

    monkeypatch.setattr(views, "export_view", spy)
    seen = []
    save_as["path"] = tmp_path / "map.pdf"
    answer(qtbot, width=3.2, font=9.0, seen=seen)
    window.export_dialog("map")
    assert seen == [(True, 3.5, 8.0)]                       # first time: one column, 8 pt
    assert columns == [(3.2, 9.0)]
    width, _ = media_box((tmp_path / "map.pdf").read_bytes())
    assert width == pytest.approx(3.2 * 72, rel=0, abs=1e-9)
    assert [window.settings.value(k) for k in SETTINGS_KEYS[1:]] == [3.2, 9.0]

    # The pose view's PDF: the dialog opens on the last answer, and the 3D figure is that wide too.
    save_as["path"] = tmp_path / "pose.pdf"
    answer(qtbot, seen=seen)
    window.export_dialog("pose")
    assert seen[-1] == (True, 3.2, 9.0) and columns[-1] == (3.2, 9.0)
    width, _ = media_box((tmp_path / "pose.pdf").read_bytes())
    assert width == pytest.approx(3.2 * 72, rel=0, abs=1e-9)


def test_cancel_writes_nothing_and_unticked_is_the_figures_own_size(make_window, qtbot, tmp_path, save_as):
    window = make_window("inverse3_prototype", longest=SMALL)
    save_as["path"] = tmp_path / "map.svg"
    answer(qtbot, ok=False)
    window.export_dialog("map")
    assert not (tmp_path / "map.svg").exists()

    save_as["path"] = tmp_path / "own.pdf"
    answer(qtbot, column=False)
    window.export_dialog("map")
    own, _ = media_box((tmp_path / "own.pdf").read_bytes())
    reference = window.export("map", tmp_path / "reference.pdf")      # no column: the figure's own page
    assert own == media_box(reference.read_bytes())[0]
    assert window.settings.value(SETTINGS_KEYS[0], type=bool) is False
