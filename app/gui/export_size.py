"""File > Export's page size for PDF and SVG: a journal column's width and font, as ``isoforce figure``.

``--width-in`` and ``--font-pt`` lay a figure out for a column (``app.render.views.export_view``'s
``column``); the app's export asks for the same two numbers in ``ColumnDialog`` before writing a
PDF or SVG. The box can be unticked for the figure's own size (the app's exports before the
column existed). The last answer is kept in the window's ``QSettings`` (``SETTINGS_KEYS``), so
a paper's figures are exported alike without retyping.
"""
from __future__ import annotations

from PySide6.QtCore import QSettings
from PySide6.QtWidgets import (
    QDialog,
    QDialogButtonBox,
    QDoubleSpinBox,
    QFormLayout,
    QGroupBox,
    QVBoxLayout,
    QWidget,
)

from app.render.views import COLUMN_INCHES, DEFAULT_COLUMN, FONT_POINTS

#: The settings the dialog keeps: whether to size for a column, its width (in) and font (pt).
SETTINGS_KEYS = ("export/column", "export/width_in", "export/font_pt")


def _spin(limits: tuple[float, float], value: float, step: float, suffix: str, tip: str) -> QDoubleSpinBox:
    spin = QDoubleSpinBox()
    spin.setRange(*limits)
    spin.setDecimals(2 if step < 0.5 else 1)
    spin.setSingleStep(step)
    spin.setSuffix(suffix)
    spin.setValue(value)
    spin.setToolTip(tip)
    return spin


def _clip(value: float, limits: tuple[float, float]) -> float:
    return min(max(float(value), limits[0]), limits[1])


def remembered_column(settings: QSettings) -> tuple[bool, float, float]:
    """``(size for a column, width in, font pt)`` last chosen (first time: ``DEFAULT_COLUMN``),
    each clipped to its bounds (a settings file edited by hand)."""
    on_key, width_key, font_key = SETTINGS_KEYS
    on = settings.value(on_key, True, type=bool)
    width = settings.value(width_key, DEFAULT_COLUMN[0], type=float)
    font = settings.value(font_key, DEFAULT_COLUMN[1], type=float)
    return bool(on), _clip(width, COLUMN_INCHES), _clip(font, FONT_POINTS)


class ColumnDialog(QDialog):
    """Asks the page's width (in) and font (pt) of a PDF or SVG export; ``column()`` after ``exec``."""

    def __init__(self, settings: QSettings, what: str, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.settings = settings
        self.setWindowTitle(f"Export {what}: page size")
        on, width, font = remembered_column(settings)
        self.group = QGroupBox("Size for a journal column")
        self.group.setCheckable(True)
        self.group.setChecked(on)
        self.group.setToolTip("The page that many inches wide with its text at that size, nothing clipped "
                              "(isoforce figure --width-in --font-pt). Unticked: the figure's own size.")
        self.width_in = _spin(COLUMN_INCHES, width, 0.05, " in",
                              "The page's width: about 3.3-3.5 in for one journal column, 7 in for two")
        self.font_pt = _spin(FONT_POINTS, font, 0.5, " pt", "The body text's size (titles and labels follow it)")
        form = QFormLayout(self.group)
        form.addRow("Width", self.width_in)
        form.addRow("Font", self.font_pt)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        layout = QVBoxLayout(self)
        layout.addWidget(self.group)
        layout.addWidget(buttons)

    def column(self) -> tuple[float, float] | None:
        """``(width in, font pt)`` for ``export_view``'s ``column``, or None for the figure's own size."""
        if not self.group.isChecked():
            return None
        return float(self.width_in.value()), float(self.font_pt.value())

    def accept(self) -> None:
        """Keep the answer for the next export, then close."""
        for key, value in zip(SETTINGS_KEYS, (self.group.isChecked(), self.width_in.value(), self.font_pt.value())):
            self.settings.setValue(key, value)
        super().accept()


def ask_column(parent, settings: QSettings, what: str) -> tuple[bool, tuple[float, float] | None]:
    """``(go on, column)`` from a ``ColumnDialog``: ``(False, None)`` when it is cancelled."""
    dialog = ColumnDialog(settings, what, parent)
    try:
        if dialog.exec() != QDialog.DialogCode.Accepted:
            return False, None
        return True, dialog.column()
    finally:
        dialog.deleteLater()
