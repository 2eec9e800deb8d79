"""The pose view's legend is painted by Qt over the rendered frame (``PlotterWidget.set_legend``),
not rendered by VTK: each row's swatch and text in its glyph's colour, as sharp in a slider's
draft (half the render pixels) as in the full frame; and the caption's box follows its text."""
from __future__ import annotations

import numpy as np
from conftest import widget_rgb
from PySide6.QtCore import QRect
from PySide6.QtGui import QColor, QFontMetrics

from app.gui.views.plotter_widget import CAPTION_MARGIN_PX


def _rows_seen(view) -> list[bool]:
    """Per legend row: whether its colour is painted, exactly, in its band of the legend's box."""
    rgb = widget_rgb(view).astype(int)
    rect = view.legend_rect()
    rows = view.legend_rows
    seen = []
    for i, (_, colour) in enumerate(rows):
        c = QColor(colour)
        top = rect.top() + round(i * rect.height() / len(rows))
        bottom = rect.top() + round((i + 1) * rect.height() / len(rows))
        band = rgb[top:bottom, rect.left():rect.right() + 1]
        seen.append(bool(np.all(band == [c.red(), c.green(), c.blue()], axis=-1).any()))
    return seen


def test_the_legend_is_painted_over_the_frame_in_each_rows_colour_in_a_draft_too(make_window, qtbot):
    window = make_window("inverse3_prototype", longest=40)
    pose = window.pose_view
    view = pose.view
    qtbot.waitUntil(lambda: view._image is not None and bool(view.legend_rows), timeout=10_000)
    # The rows the view says it shows, in the colours the glyphs are drawn in; no VTK legend.
    assert [tuple(r) for r in view.legend_rows] == [tuple(r) for r in pose._legend_rows]
    props = view.plotter.renderer.GetViewProps()
    assert not any(props.GetItemAsObject(i).IsA("vtkLegendBoxActor") for i in range(props.GetNumberOfItems()))
    # At the upper left, inside the view, as tall as ``_legend_height`` says.
    rect = view.legend_rect()
    assert not rect.isEmpty() and QRect(0, 0, view.width(), view.height()).contains(rect)
    assert rect.top() < view.height() / 2 and rect.left() < view.width() / 2
    assert abs(rect.height() - pose._legend_height(len(pose._legend_rows)) * view.height()) <= 1
    qtbot.wait(100)
    assert all(_rows_seen(view))
    # A slider's draft renders half the pixels; the legend is painted at the view's own.
    window.on_parameter_edited("gear_ratios", (8.0, 5.957, 5.957), True)
    ratio = view.devicePixelRatioF()
    qtbot.waitUntil(lambda: view._image is not None and view._image.width() < view.width() * ratio - 1,
                    timeout=5000)
    assert view.draft and all(_rows_seen(view))


def test_the_caption_box_follows_the_caption_and_the_views_size(make_window, qtbot):
    window = make_window("inverse3_prototype", longest=40)
    view = window.pose_view.view
    qtbot.waitUntil(lambda: bool(view.caption), timeout=10_000)

    def expected() -> QRect:
        # The text's box as Qt lays it out, at the lower right (what ``caption_rect`` keeps).
        text, flags, _ = view._fitted_caption()
        box = QFontMetrics(view._caption_font()).boundingRect(QRect(0, 0, view._caption_width(), 10 ** 6), flags, text)
        m = CAPTION_MARGIN_PX
        return QRect(view.width() - m - box.width(), view.height() - m - box.height(), box.width(), box.height())

    first = view.caption_rect()
    assert first == expected()
    view.set_caption(view.caption + "\none more line of the caption")
    assert view.caption_rect() == expected() and view.caption_rect().height() > first.height()
    window.pose_view.resize(window.pose_view.width() - 60, window.pose_view.height())
    qtbot.wait(50)
    assert view.caption_rect() == expected()
