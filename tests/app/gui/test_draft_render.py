"""While a design slider moves, the pose view renders a draft (``PlotterWidget.set_draft``):
half the pixels, scaled up to fill the view, the caption hidden; the release renders full size."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import widget_rgb

from app.gui.views.plotter_widget import DRAFT_SCALE


@pytest.mark.xfail(strict=True, reason=(
    "known defect since the glyphs' depth layers (app.scenes.pose.draw_in_layer): the draft frame and the "
    "full frame disagree on what the translucent force polytope covers (the link inside it is grey in the "
    "draft, tinted in the full frame), so the links' dark pixels span differently; to be found and fixed"))
def test_a_design_drag_renders_a_draft_that_fills_the_view_and_the_release_a_full_frame(make_window, waits, qtbot):
    window = make_window("inverse3_prototype", longest=40)
    view = window.pose_view.view
    # A first drag and release settles the layout (the statistics dock fits the coarse figures
    # once): the frames compared below are of one view size.
    window.on_parameter_edited("gear_ratios", (7.5, 5.957, 5.957), True)
    window.on_parameter_edited("gear_ratios", (7.5, 5.957, 5.957), False)
    waits.full(window)
    qtbot.wait(200)
    full = tuple(view.plotter.ren_win.GetSize())
    ratio = view.devicePixelRatioF()
    assert full == (round(view.width() * ratio), round(view.height() * ratio))
    window.on_parameter_edited("gear_ratios", (8.0, 5.957, 5.957), True)
    qtbot.waitUntil(lambda: view._image is not None and view._image.width() < view.width() * ratio - 1,
                    timeout=5000)
    assert view.draft
    assert tuple(view.plotter.ren_win.GetSize()) == (round(view.width() * ratio * DRAFT_SCALE),
                                                     round(view.height() * ratio * DRAFT_SCALE))
    caption = view.caption
    assert caption and not view.caption_rect().isEmpty()     # Qt text: the draft leaves its size alone
    # The draft fills the view: the scene's dark pixels (links, joints) span the same pixels as in
    # the full frame of the same design after the release, to the draft's blur (a pixel or two).
    # (Between the legend at the top and the axes triad and caption at the bottom: text, whose
    # size in pixels a draft doubles or leaves out.)
    def links_box(rgb):
        h = rgb.shape[0]
        band = rgb[h // 4: h * 3 // 4].astype(int)
        grey = (np.ptp(band, axis=2) < 24) & (band.max(axis=2) < 110)       # the links' and joints' dark grey
        rows, cols = np.nonzero(grey)
        return np.array([rows.min(), rows.max(), cols.min(), cols.max()])
    draft, draft_size = widget_rgb(view), (view.width(), view.height())
    window.on_parameter_edited("gear_ratios", (8.0, 5.957, 5.957), False)       # released where it is
    # (Full size now: the view may have been resized meanwhile, a dock fitting the new figures.)
    def full_size():
        return round(view.width() * ratio), round(view.height() * ratio)
    qtbot.waitUntil(lambda: view._image is not None and view._image.width() == full_size()[0], timeout=5000)
    assert not view.draft and tuple(view.plotter.ren_win.GetSize()) == full_size()
    assert view.caption == caption       # released where it was dragged to: the same figures, full frame or draft
    assert (view.width(), view.height()) == draft_size
    assert np.abs(links_box(draft) - links_box(widget_rgb(view))).max() <= 4
