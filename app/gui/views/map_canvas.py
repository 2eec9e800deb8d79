"""The map view's canvas: paints a ``MapPicture`` (``app.logic.map_picture``) with QPainter.

A new map costs colouring the samples (numpy, a few ms for a 1000 x 1000 map) and one paint
(an image scaled with nearest-neighbour sampling, some lines and text): a frame, where
matplotlib's canvas took 100-200 ms per slider step for its text and layout. The layout is
computed here: per panel the title above, the axes keeping the data's aspect (mm per pixel
equal on both axes), tick labels and axis labels, the legend of extremes below the axes
(never over the data), and one colour bar at the right of all panels. A comparison sits side
by side when the canvas is wide enough, stacked otherwise.

What is drawn over the axes: singular markers, the extremes, the overlay (band lines,
ellipses, annulus, key), the selected pose (a red cross), and while the map is older than
the design on screen a hatched veil with a note (``stale``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from PySide6.QtCore import QLineF, QPointF, QRectF, Qt, QTimer
from PySide6.QtGui import QBrush, QColor, QFont, QFontMetricsF, QImage, QPainter, QPainterPath, QPen, QPolygonF
from PySide6.QtWidgets import QSizePolicy, QWidget

from app.logic.map_marks import CUT_EDGE_STYLE, OUTLINE_COLOUR, OUTLINE_WIDTH
from app.logic.map_picture import MapPicture, PanelPicture
from app.logic.ticks import axis_ticks

#: Narrowest canvas that holds two panels side by side (and one shared bar); narrower, they stack.
SIDE_BY_SIDE_PX = 540
STALE_COLOUR = "#b00020"
#: Width of the colour bar itself, px.
BAR_PX = 18
#: Pixels between a panel's title and its frame.
TITLE_GAP_PX = 4
WRAP = Qt.TextFlag.TextWordWrap
#: Maps of more samples than this are coloured ``PREPARE_LATER_MS`` after they arrive.
LARGE_MAP_SAMPLES = 200_000
PREPARE_LATER_MS = 4
#: The most pixels a large map's image is coloured in per turn of the event loop (``_prepare``):
#: coloured in one piece, a 1000 x 1000 map on a 700 x 700 px panel held the GUI thread 12 ms of
#: CPU (~25 ns a pixel: gather, colour table; 40-100 ms of wall time under load), more than the
#: 10 ms a refinement may block it (issue 25). A band of this many pixels takes ~2.5 ms.
BAND_PIXELS = 100_000


@dataclass
class PanelLayout:
    """Where one panel went: the axes rectangle (px) and the regions of its texts."""

    axes: QRectF
    title: QRectF
    legend: QRectF


def _cut_pen() -> QPen:
    """The dashed pen of the map's edge where feasible samples reach it (``figures.CUT_EDGE_STYLE``)."""
    pen = QPen(QColor(CUT_EDGE_STYLE["color"]), CUT_EDGE_STYLE["linewidth"])
    pen.setDashPattern(list(CUT_EDGE_STYLE["linestyle"][1]))
    return pen


class MapCanvas(QWidget):
    """Paints ``picture`` (set with ``show_picture``); ``stale`` veils the current panels."""

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Expanding)
        self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)
        self.picture: MapPicture | None = None
        self.stale: str | None = None         # the veil's text, or None
        self.pose_mm: tuple[float, float] | None = None
        self.pose_note: str | None = None     # where the pose is when it is on another plane of a box
        self.layouts: list[PanelLayout] = []
        self.bar_rect: QRectF | None = None
        self.side_by_side = False
        self._images: dict = {}               # id(panel) -> (panel, QImage and the bytes it reads)
        self.title_font = QFont(self.font())
        self.title_font.setPointSizeF(max(8.0, self.font().pointSizeF()))
        self.small_font = QFont(self.font())
        self.small_font.setPointSizeF(max(7.0, self.font().pointSizeF() - 1.0))
        self.paints = 0                       # paint count (tests, benchmarks)
        self._prepare_timer = QTimer(self, singleShot=True, interval=0)
        self._prepare_timer.timeout.connect(self._prepare)
        self._bands: dict = {}                # id(panel) -> (panel, key, pixels, target, ix, iy, rows coloured)

    # -- state ----------------------------------------------------------------------------
    def show_picture(self, picture: MapPicture | None) -> None:
        """Show ``picture``: laid out now, its samples coloured at the next turn of the event loop,
        then painted (each step a few ms, none of them long: a full map's colouring is the most)."""
        self.picture = picture
        live = {id(p) for p in picture.panels} if picture is not None else set()
        self._images = {k: v for k, v in self._images.items() if k in live}
        self._bands = {k: v for k, v in self._bands.items() if k in live}
        self._layout()
        # A large map's colouring waits a few ms: what else waits for the GUI thread (input,
        # timers) goes first. A coarse one (a slider moving) is coloured now, so that its paint
        # joins the window's next repaint with the panels that changed with it (the statistics)
        # instead of a repaint of its own one turn later.
        samples = sum(p.data.size for p in picture.panels) if picture is not None else 0
        if samples > LARGE_MAP_SAMPLES:
            self._prepare_timer.start(PREPARE_LATER_MS)
        else:
            self._prepare_timer.stop()
            self._prepare(banded=False)

    def _prepare(self, banded: bool = True) -> None:
        """Colour the panels' images for the current layout (kept), then ask for a paint.

        ``banded`` (a large map's, on the timer): a panel of more pixels than ``BAND_PIXELS`` is
        coloured a band of rows per turn of the event loop (input and timers go between), and
        the paint asked for once every panel is coloured. (A paint before that colours what is
        left at once: ``_image``.)"""
        if self.picture is not None:
            for k, panel in enumerate(self.picture.panels[:len(self.layouts)]):
                if not banded:
                    self._image(k, panel)
                elif not self._colour_band(k, panel):
                    self._prepare_timer.start(0)
                    return
        self.update()

    def _colour_band(self, k: int, panel: PanelPicture) -> bool:
        """Colour the next band of rows of panel ``k``'s image (``BAND_PIXELS``); whether it is done."""
        key, target, ix, iy = self._plan(k, panel)
        kept = self._images.get(id(panel))
        if kept is not None and kept[0] is panel and kept[1] == key:
            return True
        if iy is None:                  # a coarse map: sample by sample, one piece
            self._image(k, panel)
            return True
        band = self._bands.get(id(panel))
        if band is None or band[0] is not panel or band[1] != key:
            band = (panel, key, np.empty((len(iy), len(ix), 4), np.uint8), target, ix, iy, 0)
        panel_, key_, pixels, target_, ix_, iy_, done = band
        rows = max(1, BAND_PIXELS // max(1, len(ix)))
        pixels[done:done + rows] = panel.sample_colours(ix, iy[done:done + rows])
        done = min(len(iy), done + rows)
        if done < len(iy):
            self._bands[id(panel)] = (panel_, key_, pixels, target_, ix_, iy_, done)
            return False
        self._bands.pop(id(panel), None)
        self._keep_image(panel, key, pixels, target)
        return True

    def set_stale(self, text: str | None) -> None:
        if text != self.stale:
            self.stale = text
            self.update()

    def set_pose(self, pose_mm: tuple[float, float] | None, note: str | None = None) -> None:
        """The pose's cross at ``pose_mm`` (map coordinates, mm) or none; ``note`` says where a
        pose not on the map's plane is instead (painted in the current panel's corner)."""
        if pose_mm != self.pose_mm or note != self.pose_note:
            self.pose_mm, self.pose_note = pose_mm, note
            self.update()

    def resizeEvent(self, event) -> None:   # noqa: N802 (Qt name)
        super().resizeEvent(event)
        self._layout()

    # -- layout ---------------------------------------------------------------------------
    def _layout(self) -> None:
        """Place every panel's axes, title and legend, and the colour bar, for the current size."""
        self.layouts = []
        self.bar_rect = None
        picture = self.picture
        if picture is None or not picture.panels:
            return
        fm, small = QFontMetricsF(self.title_font), QFontMetricsF(self.small_font)
        small_line = small.lineSpacing()
        bar = picture.bar
        bar_w = 0.0
        if bar is not None:
            ticks_w = max((small.horizontalAdvance(text) for _, text in bar.ticks), default=0.0)
            label_lines = bar.label.count("\n") + 1
            bar_w = BAR_PX + 4 + ticks_w + 6 + label_lines * small_line + 8
        width, height = float(self.width()), float(self.height())
        n = len(picture.panels)
        self.side_by_side = n > 1 and width >= SIDE_BY_SIDE_PX
        cols, rows = (n, 1) if self.side_by_side else (1, n)
        cell_w = (width - bar_w) / cols
        cell_h = height / rows
        for k, panel in enumerate(picture.panels):
            col, row = (k, 0) if self.side_by_side else (0, k)
            x0, y0 = col * cell_w, row * cell_h
            # A line wider than the panel wraps (side by side, "1000 x 1000 grid, ... points" can be).
            title_h = (fm.boundingRect(QRectF(0, 0, cell_w - 8, 1e4), WRAP, panel.title).height() + 2 + TITLE_GAP_PX
                       if panel.labels_shown else 6.0)
            legend_rows = len(panel.legend) if panel.labels_shown else 0
            legend_h = legend_rows * small_line + (10 if legend_rows else 0)
            tick_w = small.horizontalAdvance("-0000") + 6
            left = x0 + 6 + small_line + tick_w
            right = x0 + cell_w - 10
            top = y0 + title_h
            bottom = y0 + cell_h - legend_h - 2 * small_line - 10
            avail_w, avail_h = max(right - left, 10.0), max(bottom - top, 10.0)
            lx0, lx1, ly0, ly1 = panel.limits
            aspect = (ly1 - ly0) / (lx1 - lx0)
            w = min(avail_w, avail_h / aspect)
            h = w * aspect
            axes = QRectF(left + (avail_w - w) / 2, top + (avail_h - h) / 2, w, h)
            title = QRectF(x0, axes.top() - title_h, cell_w, title_h)
            legend = QRectF(x0, axes.bottom() + 2 * small_line + 8, cell_w, legend_h)
            self.layouts.append(PanelLayout(axes=axes, title=title, legend=legend))
        self._one_length_scale(picture.panels)
        if bar is not None:
            tops = [lay.axes.top() for lay in self.layouts]
            bottoms = [lay.axes.bottom() for lay in self.layouts]
            self.bar_rect = QRectF(width - bar_w + 4, min(tops), BAR_PX, max(bottoms) - min(tops))

    def _one_length_scale(self, panels) -> None:
        """Panels drawn at one millimetre per pixel: each shrunk about its centre to the scale of the
        one that fits least, so two devices' slices compare in size (a slice three times larger is
        drawn three times larger). Panels of one grid have equal limits, and stay as they are."""
        if len(self.layouts) < 2:
            return
        spans = [(p.limits[1] - p.limits[0], p.limits[3] - p.limits[2]) for p in panels]
        px_per_mm = min(lay.axes.width() / w for lay, (w, _) in zip(self.layouts, spans))
        for k, (lay, (w, h)) in enumerate(zip(self.layouts, spans)):
            centre = lay.axes.center()
            axes = QRectF(centre.x() - w * px_per_mm / 2, centre.y() - h * px_per_mm / 2, w * px_per_mm, h * px_per_mm)
            title = QRectF(lay.title.left(), axes.top() - lay.title.height(), lay.title.width(), lay.title.height())
            legend = QRectF(lay.legend.left(), lay.legend.top() + axes.bottom() - lay.axes.bottom(),
                            lay.legend.width(), lay.legend.height())
            self.layouts[k] = PanelLayout(axes=axes, title=title, legend=legend)

    # -- coordinates ----------------------------------------------------------------------
    def to_pixel(self, panel: int, x_mm: float, y_mm: float) -> QPointF:
        """Widget pixel of a map point (mm) in panel ``panel``."""
        axes = self.layouts[panel].axes
        x0, x1, y0, y1 = self.picture.panels[panel].limits
        return QPointF(axes.left() + (x_mm - x0) / (x1 - x0) * axes.width(),
                       axes.bottom() - (y_mm - y0) / (y1 - y0) * axes.height())

    def to_data(self, px: float, py: float) -> tuple[int, float, float] | None:
        """(panel, x mm, y mm) under a widget pixel, or None outside every panel's axes."""
        for k, lay in enumerate(self.layouts):
            if lay.axes.contains(QPointF(px, py)):
                x0, x1, y0, y1 = self.picture.panels[k].limits
                return (k, x0 + (px - lay.axes.left()) / lay.axes.width() * (x1 - x0),
                        y0 + (lay.axes.bottom() - py) / lay.axes.height() * (y1 - y0))
        return None

    # -- painting -------------------------------------------------------------------------
    def _plan(self, k: int, panel: PanelPicture) -> tuple:
        """``(key, target, ix, iy)`` of panel ``k``'s image at the current layout: ``target`` the
        rectangle (px) it is drawn into; ``ix``, ``iy`` the sample under each pixel's centre,
        columns and rows top row first, or None for a map of no more samples than pixels (a
        coarse map: coloured sample by sample and scaled by the painter)."""
        axes = self.layouts[k].axes
        ex0, ex1, ey0, ey1 = panel.extent
        top_left, bottom_right = self.to_pixel(k, ex0, ey1), self.to_pixel(k, ex1, ey0)
        box = QRectF(top_left, bottom_right).intersected(axes)
        x0, y0 = np.floor(box.left()), np.floor(box.top())
        w, h = int(np.ceil(box.right()) - x0), int(np.ceil(box.bottom()) - y0)
        key = (x0, y0, w, h)
        nx, ny = panel.data.shape
        if nx * ny <= w * h:
            return key, QRectF(top_left, bottom_right), None, None
        span_x, span_y = bottom_right.x() - top_left.x(), bottom_right.y() - top_left.y()
        # Pixel centres -> fractions of the extent -> sample indices (y down the screen, samples up).
        fx = (x0 + np.arange(max(w, 1)) + 0.5 - top_left.x()) / span_x
        fy = (bottom_right.y() - (y0 + np.arange(max(h, 1)) + 0.5)) / span_y
        ix = np.clip(np.floor(fx * nx).astype(np.intp), 0, nx - 1)
        iy = np.clip(np.floor(fy * ny).astype(np.intp), 0, ny - 1)
        return key, QRectF(x0, y0, len(ix), len(iy)), ix, iy

    def _keep_image(self, panel: PanelPicture, key, pixels: np.ndarray, target: QRectF) -> tuple[QImage, QRectF]:
        """Keep ``pixels`` (h, w, 4) RGBA bytes as the panel's image (the QImage reads them, no copy)."""
        image = QImage(pixels.data, pixels.shape[1], pixels.shape[0], 4 * pixels.shape[1],
                       QImage.Format.Format_RGBA8888)
        self._images[id(panel)] = (panel, key, image, pixels, target)
        return image, target

    def _image(self, k: int, panel: PanelPicture) -> tuple[QImage, QRectF]:
        """The panel's samples as an image, and the rectangle (px) it is drawn into.

        A map with more samples than the axes have pixels (a 1000 x 1000 map on a few hundred)
        is coloured only at the sample under each pixel's centre; a coarser one sample by
        sample, scaled by the painter. Kept while the panel and its size stay; a large map's
        bands not coloured yet (``_prepare``) are coloured now.
        """
        key, target, ix, iy = self._plan(k, panel)
        kept = self._images.get(id(panel))
        if kept is not None and kept[0] is panel and kept[1] == key:
            return kept[2], kept[4]
        nx, ny = panel.data.shape
        if iy is None:
            # Fewer samples than pixels (a coarse map while a slider moves): colour each sample
            # once and let the painter scale the image, nearest sample per pixel as below.
            pixels = np.ascontiguousarray(panel.sample_colours(np.arange(nx), np.arange(ny)[::-1]))
            return self._keep_image(panel, key, pixels, target)
        band = self._bands.pop(id(panel), None)
        if band is not None and band[0] is panel and band[1] == key:
            pixels, done = band[2], band[6]
            pixels[done:] = panel.sample_colours(ix, iy[done:])
        else:
            pixels = np.ascontiguousarray(panel.sample_colours(ix, iy))          # (h, w, 4), top row first
        return self._keep_image(panel, key, pixels, target)

    def paintEvent(self, event) -> None:   # noqa: N802 (Qt name)
        self.paints += 1
        painter = QPainter(self)
        try:
            painter.fillRect(self.rect(), Qt.GlobalColor.white)
            picture = self.picture
            if picture is None or not picture.panels:
                painter.setPen(QColor("#595959"))
                painter.drawText(self.rect(), Qt.AlignmentFlag.AlignCenter, picture.message if picture else "")
                return
            for k, (panel, lay) in enumerate(zip(picture.panels, self.layouts)):
                self._paint_panel(painter, k, panel, lay)
            if picture.bar is not None and self.bar_rect is not None:
                self._paint_bar(painter, picture.bar)
        finally:
            painter.end()

    def _paint_panel(self, painter: QPainter, k: int, panel: PanelPicture, lay: PanelLayout) -> None:
        axes = lay.axes
        small = QFontMetricsF(self.small_font)
        image, target = self._image(k, panel)
        painter.save()
        painter.setClipRect(axes)
        painter.drawImage(target, image)
        painter.restore()
        painter.setPen(QPen(QColor("black"), 1.0))
        painter.setBrush(Qt.BrushStyle.NoBrush)
        painter.drawRect(axes)
        self._paint_ticks(painter, k, panel, axes, small)
        painter.save()
        painter.setRenderHint(QPainter.RenderHint.Antialiasing, True)
        if len(panel.singular):
            self._paint_markers(painter, k, "x", "#d62728", panel.singular, 3.0)
        if panel.outline:
            painter.setPen(QPen(QColor(OUTLINE_COLOUR), OUTLINE_WIDTH))
            for line in panel.outline:
                painter.drawPolyline(QPolygonF([self.to_pixel(k, float(x), float(y)) for x, y in line]))
        if panel.cut_edges:
            painter.setPen(_cut_pen())
            for xa, xb, ya, yb in panel.cut_edges:
                painter.drawLine(QLineF(self.to_pixel(k, xa, ya), self.to_pixel(k, xb, yb)))
        if panel.overlay is not None:
            self._paint_overlay(painter, k, panel, axes)
        if panel.labels_shown:
            for marker, x, y, _ in panel.extremes:
                self._paint_markers(painter, k, marker, "black", np.array([[x, y]]), 5.5, fill="white")
        if self.pose_mm is not None and k == len(self.picture.panels) - 1:
            p = self.to_pixel(k, *self.pose_mm)
            painter.setPen(QPen(QColor("red"), 2.5))
            painter.drawLine(QLineF(p.x() - 8, p.y(), p.x() + 8, p.y()))
            painter.drawLine(QLineF(p.x(), p.y() - 8, p.x(), p.y() + 8))
        painter.restore()
        if self.pose_note and k == len(self.picture.panels) - 1:
            self._paint_pose_note(painter, axes, small)
        if panel.labels_shown:
            painter.setFont(self.title_font)
            painter.setPen(QColor("black"))
            # 4 px clear of the frame: its last line's descenders ("y = 22.3 mm") touched it.
            painter.drawText(lay.title.adjusted(4, 0, -4, -TITLE_GAP_PX), WRAP | Qt.AlignmentFlag.AlignHCenter
                             | Qt.AlignmentFlag.AlignBottom, panel.title)
            self._paint_legend(painter, panel, lay)
        if self.stale is not None and not panel.reference:
            self._paint_veil(painter, axes)

    def _paint_ticks(self, painter, k, panel, axes, small) -> None:
        painter.setFont(self.small_font)
        x0, x1, y0, y1 = panel.limits
        line = small.lineSpacing()
        for t in axis_ticks(x0, x1, axes.width()):
            px = self.to_pixel(k, t, y0).x()
            painter.drawLine(QLineF(px, axes.bottom(), px, axes.bottom() + 4))
            painter.drawText(QRectF(px - 40, axes.bottom() + 5, 80, line), Qt.AlignmentFlag.AlignHCenter, f"{t:g}")
        for t in axis_ticks(y0, y1, axes.height()):
            py = self.to_pixel(k, x0, t).y()
            painter.drawLine(QLineF(axes.left() - 4, py, axes.left(), py))
            painter.drawText(QRectF(axes.left() - 86, py - line / 2, 80, line),
                             Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter, f"{t:g}")
        painter.drawText(QRectF(axes.left(), axes.bottom() + 5 + line, axes.width(), line),
                         Qt.AlignmentFlag.AlignHCenter, panel.xlabel)
        painter.save()
        tick_w = small.horizontalAdvance("-0000") + 6
        painter.translate(axes.left() - tick_w - 4, axes.center().y())
        painter.rotate(-90)
        painter.drawText(QRectF(-axes.height() / 2, -line, axes.height(), line), Qt.AlignmentFlag.AlignHCenter,
                         panel.ylabel)
        painter.restore()

    def _paint_markers(self, painter, k, symbol: str, colour: str, points, size: float, fill: str | None = None):
        pen = QPen(QColor(colour), 1.4 if symbol == "x" else 1.2)
        painter.setPen(pen)
        painter.setBrush(QBrush(QColor(fill)) if fill else Qt.BrushStyle.NoBrush)
        for x, y in points:
            p = self.to_pixel(k, float(x), float(y))
            if symbol == "x":
                painter.drawLine(QLineF(p.x() - size, p.y() - size, p.x() + size, p.y() + size))
                painter.drawLine(QLineF(p.x() - size, p.y() + size, p.x() + size, p.y() - size))
            else:
                up = symbol == "^"
                tip, base = (-size, size * 0.8) if up else (size, -size * 0.8)
                painter.drawPolygon(QPolygonF([QPointF(p.x(), p.y() + tip), QPointF(p.x() - size, p.y() + base),
                                               QPointF(p.x() + size, p.y() + base)]))

    def _paint_overlay(self, painter, k, panel, axes) -> None:
        drawing = panel.overlay
        painter.save()
        painter.setClipRect(axes.adjusted(-6, -6, 6, 6))
        for colour, polylines in drawing.lines:
            painter.setPen(QPen(QColor(colour), 1.6))
            for line in polylines:
                path = QPainterPath()
                for i, (x, y) in enumerate(line):
                    p = self.to_pixel(k, float(x), float(y))
                    path.lineTo(p) if i else path.moveTo(p)
                painter.drawPath(path)
        for symbol, colour, points in drawing.markers:
            self._paint_markers(painter, k, symbol, colour, points, 3.0 if symbol == "x" else 4.0)
        scale = axes.width() / (panel.limits[1] - panel.limits[0])       # px per mm (equal aspect)
        painter.setBrush(Qt.BrushStyle.NoBrush)
        dashed = QPen(QColor("black"), 1.2, Qt.PenStyle.DashLine)
        for cx, cy, r in drawing.circles:
            painter.setPen(dashed)
            painter.drawEllipse(self.to_pixel(k, cx, cy), r * scale, r * scale)
        if drawing.ellipses is not None:
            painter.setPen(QPen(QColor("black"), 0.9))
            for cx, cy, w, h, angle in drawing.ellipses:
                painter.save()
                painter.translate(self.to_pixel(k, cx, cy))
                painter.rotate(-angle)             # screen y points down
                painter.drawEllipse(QPointF(0, 0), w / 2 * scale, h / 2 * scale)
                painter.restore()
        if drawing.key is not None:
            from app.plots.overlays import key_centre
            radius, text = drawing.key
            centre = self.to_pixel(k, *key_centre(panel.limits, radius))
            painter.setPen(QPen(QColor("black"), 1.4))
            painter.drawEllipse(centre, radius * scale, radius * scale)
            painter.setFont(self.small_font)
            painter.drawText(QRectF(centre.x() - radius * scale - 204, centre.y() - 10, 200, 20),
                             Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter, text)
        painter.restore()

    def _paint_pose_note(self, painter, axes, small) -> None:
        """``pose_note`` in red in the axes' top left corner, on a white box (the cross's colour:
        it stands where the cross would)."""
        width, line = small.horizontalAdvance(self.pose_note) + 10, small.lineSpacing() + 4
        box = QRectF(axes.left() + 4, axes.top() + 4, width, line)
        painter.setPen(QPen(QColor("#cccccc"), 1.0))
        painter.setBrush(QColor(255, 255, 255, 230))
        painter.drawRect(box)
        painter.setFont(self.small_font)
        painter.setPen(QColor("#c00000"))
        painter.drawText(box, Qt.AlignmentFlag.AlignCenter, self.pose_note)

    def _paint_legend(self, painter, panel, lay) -> None:
        if not panel.legend:
            return
        small = QFontMetricsF(self.small_font)
        line = small.lineSpacing()
        width = max(small.horizontalAdvance(text) for _, _, text in panel.legend) + 30
        box = QRectF(lay.legend.center().x() - width / 2, lay.legend.top(), width, line * len(panel.legend) + 6)
        painter.setPen(QPen(QColor("#cccccc"), 1.0))
        painter.setBrush(QColor(255, 255, 255, 217))
        painter.drawRoundedRect(box, 3, 3)
        painter.setFont(self.small_font)
        painter.save()
        painter.setRenderHint(QPainter.RenderHint.Antialiasing, True)
        for i, (symbol, colour, text) in enumerate(panel.legend):
            y = box.top() + 3 + (i + 0.5) * line
            centre = QPointF(box.left() + 12, y)
            pen = QPen(QColor(colour), 1.2)
            painter.setPen(pen)
            painter.setBrush(QColor("white"))
            s = 4.5
            if symbol == "x":
                painter.drawLine(QLineF(centre.x() - s, y - s, centre.x() + s, y + s))
                painter.drawLine(QLineF(centre.x() - s, y + s, centre.x() + s, y - s))
            elif symbol == "--":
                painter.setPen(_cut_pen())
                painter.drawLine(QLineF(centre.x() - 2 * s, y, centre.x() + 2 * s, y))
            else:
                tip, base = (-s, s * 0.8) if symbol == "^" else (s, -s * 0.8)
                painter.drawPolygon(QPolygonF([QPointF(centre.x(), y + tip), QPointF(centre.x() - s, y + base),
                                               QPointF(centre.x() + s, y + base)]))
            painter.setPen(QColor("black"))
            painter.drawText(QRectF(box.left() + 24, y - line / 2, width, line), Qt.AlignmentFlag.AlignVCenter, text)
        painter.restore()

    def _paint_veil(self, painter, axes) -> None:
        painter.save()
        painter.fillRect(axes, QColor(255, 255, 255, 153))
        painter.fillRect(axes, QBrush(QColor(STALE_COLOUR), Qt.BrushStyle.BDiagPattern))
        painter.setPen(QPen(QColor(STALE_COLOUR), 3.0))
        painter.setBrush(Qt.BrushStyle.NoBrush)
        painter.drawRect(axes)
        font = QFont(self.small_font)
        font.setBold(True)
        painter.setFont(font)
        fm = QFontMetricsF(font)
        lines = self.stale.split("\n")
        w = max(fm.horizontalAdvance(t) for t in lines) + 16
        h = fm.lineSpacing() * len(lines) + 10
        box = QRectF(axes.center().x() - w / 2, axes.center().y() - h / 2, w, h)
        painter.setBrush(QColor("white"))
        painter.setPen(QPen(QColor(STALE_COLOUR), 1.5))
        painter.drawRoundedRect(box, 6, 6)
        painter.drawText(box, Qt.AlignmentFlag.AlignCenter, self.stale)
        painter.restore()

    def _paint_bar(self, painter, bar) -> None:
        rect = self.bar_rect
        small = QFontMetricsF(self.small_font)
        colours = np.ascontiguousarray(bar.colours[::-1])        # top row first
        image = QImage(colours.data, 1, len(colours), 4, QImage.Format.Format_RGBA8888)
        painter.drawImage(rect, image)
        painter.setPen(QPen(QColor("black"), 1.0))
        painter.setBrush(Qt.BrushStyle.NoBrush)
        painter.drawRect(rect)
        if bar.extend_max:          # colours capped: an arrow of the top colour says so
            top = QColor(*[int(c) for c in bar.colours[-1][:3]])
            painter.setBrush(top)
            painter.drawPolygon(QPolygonF([QPointF(rect.left(), rect.top()), QPointF(rect.right(), rect.top()),
                                           QPointF(rect.center().x(), rect.top() - rect.width())]))
        painter.setFont(self.small_font)
        line = small.lineSpacing()
        ticks_w = 0.0
        for fraction, text in bar.ticks:
            y = rect.bottom() - fraction * rect.height()
            painter.drawLine(QLineF(rect.right(), y, rect.right() + 3, y))
            painter.drawText(QRectF(rect.right() + 5, y - line / 2, 200, line), Qt.AlignmentFlag.AlignVCenter, text)
            ticks_w = max(ticks_w, small.horizontalAdvance(text))
        painter.save()
        lines = bar.label.count("\n") + 1
        painter.translate(rect.right() + 8 + ticks_w + lines * line, rect.center().y())
        painter.rotate(-90)
        painter.drawText(QRectF(-rect.height() / 2, -lines * line, rect.height(), lines * line),
                         Qt.AlignmentFlag.AlignHCenter | Qt.AlignmentFlag.AlignBottom, bar.label)
        painter.restore()
