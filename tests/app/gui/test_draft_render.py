"""While a design slider moves, the pose view renders a draft (``PlotterWidget.set_draft``):
half the pixels, scaled up to fill the view, the caption hidden; the release renders full size."""
from __future__ import annotations

import numpy as np
from conftest import widget_rgb
from scipy import ndimage

from app.gui.views.plotter_widget import DRAFT_SCALE


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
    # size in pixels a draft doubles or leaves out.) A link is a few pixels wide: a pixel or two of
    # dark grey alone is not one but the draft's smoothing, which blends an arrowhead's shaded tip
    # with the green and blue glyphs around it into a grey (90, 82, 105); an opening of the mask
    # leaves them out.
    def links_box(rgb):
        h = rgb.shape[0]
        band = rgb[h // 4: h * 3 // 4].astype(int)
        grey = (np.ptp(band, axis=2) < 24) & (band.max(axis=2) < 110)       # the links' and joints' dark grey
        rows, cols = np.nonzero(ndimage.binary_opening(grey, np.ones((3, 3), bool)))
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


def test_a_draft_draws_lines_as_wide_on_screen_as_the_full_frame(make_window, qtbot):
    """A draft's lines are ``DRAFT_SCALE`` as wide in its render window: scaled up, a polytope's
    edges cover as much of it as in the full frame. (At their own width they were twice as wide
    on screen: the Stewart platform's long thin polytope, all edges, looked dark blue in a draft.)"""
    window = make_window("stewart_platform", longest=40)
    view = window.pose_view.view
    ratio = view.devicePixelRatioF()
    edges = view.plotter.actors["polytope_edges"].prop
    width = edges.line_width

    def edge_share(rgb):
        """The share of the polytope's pixels (its edges' dark blue and its faces' light blue) that are edges."""
        d = rgb.astype(int)
        edge = np.abs(d - np.array([31, 78, 128])).sum(axis=2) < 40          # COLOURS["polytope_edges"]
        face = (d[..., 2] > 180) & (d[..., 2] - d[..., 0] > 50)
        return edge.sum() / max(1, edge.sum() + face.sum())

    gears = 1.1 * np.asarray(window.state.mechanism.params.gear_ratios)
    window.on_parameter_edited("gear_ratios", tuple(gears), True)
    qtbot.waitUntil(lambda: view._image is not None and view._image.width() < view.width() * ratio - 1, timeout=5000)
    assert edges.line_width == width * DRAFT_SCALE
    draft = edge_share(widget_rgb(view))
    window.on_parameter_edited("gear_ratios", tuple(gears), False)
    qtbot.waitUntil(lambda: view._image is not None and view._image.width() == round(view.width() * ratio),
                    timeout=5000)
    assert edges.line_width == width
    # (Measured: 0.36 in the draft, 0.43 in the full frame; 0.74 with the lines at their own width.)
    assert 0.6 < draft / edge_share(widget_rgb(view)) < 1.4
