"""The Quantity box and Help > Quantities say what a quantity is, in the unit the app shows it in.

Before: the box had no tooltip of its own, and Help > Quantities gave the spatial resolution in m
while the map, the statistics and ``isoforce spec`` give it in µm.
"""
from __future__ import annotations

from PySide6.QtWidgets import QApplication, QMessageBox

from app.gui.widgets.view_toolbar import quantity_tooltip
from metrics.quantities import QUANTITIES


def test_the_quantity_box_tooltip_follows_the_shown_quantity(make_window, qtbot):
    window = make_window("inverse3_prototype", longest=30)
    box = window.quantity_box
    assert box.toolTip() == quantity_tooltip(window.state.quantity)
    box.setCurrentIndex(box.findData("spatial_resolution"))
    qtbot.waitUntil(lambda: window.state.quantity == "spatial_resolution", timeout=5000)
    assert box.toolTip().startswith(f"{QUANTITIES['spatial_resolution'].label} (µm): ")


def test_help_quantities_gives_display_units(make_window, qtbot):
    window = make_window("inverse3_prototype", longest=30, wait=False)
    window.show_quantity_help()
    boxes = [w for w in QApplication.topLevelWidgets() if isinstance(w, QMessageBox) and w.isVisible()]
    assert boxes
    text = boxes[-1].text()
    assert f"<b>{QUANTITIES['spatial_resolution'].label}</b> (µm)" in text
    assert f"<b>{QUANTITIES['isotropic_force'].label}</b> (N)" in text
    for box in boxes:
        box.close()
