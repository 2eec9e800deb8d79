"""Design sliders edit finely around the preset's value (issue 26 sec. 6): a 76 px drag of the
Inverse3's proximal length moved it from 140 to 317 mm; the slider now spans +-50 % of the value
in round steps, the spin box takes anything beyond (the slider's span then moves to the typed
value), and undo still names each edit.

The reference for a drag is Qt's own mapping of a pixel to a slider value
(``QStyle.sliderValueFromPosition`` over the groove), and the edit's name is ``history.edit_label``.
"""
from __future__ import annotations

import pytest
from PySide6.QtCore import QPoint, Qt
from PySide6.QtWidgets import QStyle, QStyleOptionSlider

from app.gui.widgets.parameter_panel import FINE_SPAN, slider_range, slider_step

PRESET_MM = 140.0
DRAG_PX = 76


def _handle_and_groove(slider):
    opt = QStyleOptionSlider()
    slider.initStyleOption(opt)
    style = slider.style()
    handle = style.subControlRect(QStyle.ComplexControl.CC_Slider, opt, QStyle.SubControl.SC_SliderHandle, slider)
    groove = style.subControlRect(QStyle.ComplexControl.CC_Slider, opt, QStyle.SubControl.SC_SliderGroove, slider)
    return handle, groove


@pytest.mark.parametrize("drag_px", [12, DRAG_PX])
def test_a_76_px_drag_is_a_fine_edit_and_undo_names_it(make_window, qtbot, drag_px):
    window = make_window("inverse3_prototype", longest=40, size=(1600, 950))
    row = window.param_panel.rows[("proximal_length", -1)]
    assert row.value() == PRESET_MM
    lo, hi = slider_range(PRESET_MM, "mm")
    assert (row.lo, row.hi) == (lo, hi) == (PRESET_MM * (1 - FINE_SPAN), PRESET_MM * (1 + FINE_SPAN))
    assert row.step == slider_step(FINE_SPAN * PRESET_MM) == 1.0          # round 1 mm steps
    assert row.lo + row.step * row.slider.value() == PRESET_MM            # the preset is a slider position

    handle, groove = _handle_and_groove(row.slider)
    start = handle.center()
    qtbot.mousePress(row.slider, Qt.MouseButton.LeftButton, pos=start)
    for dx in range(4, drag_px + 1, 4):
        qtbot.mouseMove(row.slider, QPoint(start.x() + dx, start.y()))
    qtbot.mouseRelease(row.slider, Qt.MouseButton.LeftButton, pos=QPoint(start.x() + drag_px, start.y()))
    qtbot.waitUntil(lambda: not row.slider.isSliderDown(), timeout=5000)

    # Qt's mapping of the handle's new position to a slider value, and that value in mm.
    span_px = groove.width() - handle.width()
    steps = QStyle.sliderValueFromPosition(row.slider.minimum(), row.slider.maximum(),
                                           handle.left() - groove.left() + drag_px, span_px)
    expected = row.lo + row.step * steps
    assert row.slider.value() == steps
    assert row.value() == expected
    moved = expected - PRESET_MM
    assert 0 < moved <= FINE_SPAN * PRESET_MM                          # 76 px: was 177 mm; now within +-50 %
    # Each pixel of the groove moves the value by the span over the groove's travel, or less.
    assert moved <= drag_px * (row.hi - row.lo) / span_px + row.step
    assert moved == round(moved)                                      # whole millimetres
    qtbot.waitUntil(lambda: window.state.mechanism.parameter_table()[0][1] == expected, timeout=5000)

    # One undo step for the drag, named with the values it went between.
    label = f"proximal_length {PRESET_MM:g} -> {expected:g} mm"
    assert window.state.history.undo_text() == label
    assert window.undo_action.text() == f"&Undo {label}"


def test_the_spin_box_goes_beyond_the_slider_and_the_span_follows(make_window, qtbot):
    window = make_window("inverse3_prototype", longest=40, size=(1600, 950))
    row = window.param_panel.rows[("proximal_length", -1)]
    row.spin.setValue(400.0)                                  # typed: far beyond the slider's 210 mm
    qtbot.waitUntil(lambda: window.state.mechanism.parameter_table()[0][1] == 400.0, timeout=5000)
    assert (row.lo, row.hi) == slider_range(400.0, "mm") == (200.0, 600.0)
    assert row.lo + row.step * row.slider.value() == 400.0    # the handle at the value, not at an end
    assert window.state.history.undo_text() == "proximal_length 140 -> 400 mm"
    window.undo()
    qtbot.waitUntil(lambda: row.value() == PRESET_MM, timeout=5000)
    assert (row.lo, row.hi) == slider_range(PRESET_MM, "mm")   # back around the preset's value
    assert row.lo + row.step * row.slider.value() == PRESET_MM
    assert window.state.history.redo_text() == "proximal_length 140 -> 400 mm"
