"""A PyVista plotter that renders off-screen and is painted as an image: no OpenGL widget.

Why not ``pyvistaqt.QtInteractor``: it is a ``QOpenGLWidget``, and one of those anywhere in
a window makes Qt compose the *whole window* with OpenGL on every repaint. In software
OpenGL (Mesa llvmpipe: virtual machines, Xvfb, remote desktops) that costs 30-50 ms per
repaint of a 1600 x 950 window, for any change anywhere (a map update, a table cell, the
progress bar), and blocks the GUI thread that long. Here VTK renders into its own off-screen
window and the pixels (read back in a fraction of a millisecond) are painted by Qt's raster
engine, so the window stays a plain raster window.

``plotter`` is an ordinary off-screen ``pyvista.Plotter`` (actors, cameras, widgets work as
usual; its frames are read from the back buffer and never swapped to the front one, which
``plotter.screenshot()`` reads: the view's picture is the widget's, ``grab()``). Rendering is
on demand and on the GUI thread: ``request_render()`` (after changing the scene) renders once
at the next paint, however many requests came before; a render started elsewhere
(``plotter.render()``, the camera interaction, a pyvista widget) is picked
up as well. Mouse events go to the plotter's interactor first, so 3D widgets (e.g. a clip
plane) respond to the mouse as in any VTK window; a press no widget takes moves the camera,
by hand (``camera``): left drag turns it about ``pivot()`` (the end-effector in the pose view),
middle or shift-left drag pans, the wheel zooms towards the cursor, ``R`` or the "Reset view"
button calls ``fit()``. Multisampling and depth peeling follow the OpenGL renderer
(``gl_quality``: off on software renderers, as before).

``set_caption(text)`` prints a caption in the lower right corner, painted by Qt over the
frame: wrapped to the view's width at a readable size. (VTK's corner text shrinks a long line
until it fits the view, to 5-6 px in a 370 px wide pose view, and a draft frame would draw
it twice as large.) Like napari's and ParaView's overlays it never takes more than a bounded
share of the view (``CAPTION_HEIGHT_SHARE``): in a view dragged small its lines are cut
short with "…", then its last lines are left out, and below one readable line it is not
shown at all; the widget's tooltip then holds the whole text (``caption_layout``).

``set_legend(rows, box)`` paints a legend (a colour swatch and the text in its colour per row)
over the frame as well, in a box given in the render window's normalised coordinates: drawn
once into an image and laid over each frame. (VTK's ``vtkLegendBoxActor`` cost 2-3 ms of every
render on a software renderer, a third of a slider step's pose frame; in a draft it was drawn at
half the pixels and scaled up blurred.)

(Rendering on a thread of its own would take the 10-25 ms of a frame off the GUI thread,
and VTK does release the GIL while it renders; but VTK's X11 render windows, created,
rendered and closed from two threads, crash in Xlib. So it is not done.)
"""
from __future__ import annotations

import contextlib

import numpy as np
import pyvista as pv
from PySide6.QtCore import QEvent, QRect, QRectF, Qt
from PySide6.QtGui import QColor, QFont, QFontMetrics, QImage, QPainter
from PySide6.QtWidgets import QSizePolicy, QToolButton, QToolTip, QWidget
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkUnsignedCharArray
from vtkmodules.vtkInteractionStyle import vtkInteractorStyleUser

from app.gui.views import camera, gl_quality
from app.scenes.snapshot import CAPTION_GLUE

#: Render-window pixels per widget pixel while a view is a draft (``PlotterWidget.set_draft``).
DRAFT_SCALE = 0.5
#: The caption's font size as a share of the widget's font, its margin from the view's edges
#: (px) and the alpha of the white box behind it (the scene stays faintly visible through it).
CAPTION_FONT_SHARE, CAPTION_MARGIN_PX, CAPTION_BOX_ALPHA = 0.9, 6, 210
#: The white box reaches this far (px) beyond the caption's text, left and right, top and bottom.
CAPTION_PAD_X, CAPTION_PAD_Y = 3, 2
#: The most of the view's height the caption's box takes: the scene keeps the rest.
CAPTION_HEIGHT_SHARE = 1 / 3
#: A line cut short to fewer average characters than this says nothing: narrower, no caption.
CAPTION_MIN_CHARS = 8
#: The legend's background: white at this alpha (the scene faintly visible through it, as VTK's
#: legend box at pyvista's ``background_opacity=0.8``), and its text's height as a share of a row's.
LEGEND_BOX_ALPHA, LEGEND_TEXT_SHARE = 204, 0.9
#: The legend's inner padding (px): between the box's edge, the swatches and the text.
LEGEND_PAD_PX = 3
#: The share of the view's width the axes triad takes in the lower left corner (pyvista's
#: ``add_axes`` viewport, 0 to 0.2): the caption wraps short of it.
AXES_WIDTH_SHARE = 0.2


def keep_phrases(text: str) -> str:
    """``text`` with the spaces of ``CAPTION_GLUE`` non-breaking (U+00A0), for a word wrap.

    >>> keep_phrases("anisotropic 0.0612 N m, condition 1.24 (L = 35 mm)").split(" ")
    ['anisotropic\xa00.0612\xa0N\xa0m,', 'condition\xa01.24', '(L\xa0=\xa035\xa0mm)']
    >>> keep_phrases("at 1 m/s")
    'at\xa01\xa0m/\u2060s'
    """
    # Qt also breaks a line after a slash ("m/" / "s"): a word joiner (U+2060) keeps a unit whole.
    return CAPTION_GLUE.sub("\u00a0", text).replace("/", "/\u2060")


class PlotterWidget(QWidget):
    """Shows ``self.plotter`` (an off-screen ``pyvista.Plotter``) and forwards the mouse to it."""

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Expanding)
        self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)
        self.setFocusPolicy(Qt.FocusPolicy.ClickFocus)
        self.plotter = pv.Plotter(off_screen=True, window_size=[max(16, self.width()), max(16, self.height())])
        # Until the renderer is known, software OpenGL's settings: no multisampling (8x MSAA
        # triples a frame's cost), and plain alpha blending of the translucent glyphs
        # (order-independent translucency adds full-window passes that double it).
        self.plotter.ren_win.SetMultiSamples(0)
        self.plotter.renderer.SetUseOIT(False)
        self.plotter.show(auto_close=False)          # initialise the render window, no event loop
        self.quality = gl_quality.detect(self.plotter.ren_win)
        gl_quality.apply(self.plotter, self.quality)
        # The frame is read from the back buffer (``_on_rendered``) and the render window is never
        # shown: swapping it copied every frame to the hidden X window as well (a software
        # renderer's put-image, and the X server's work: ~0.5 ms of a draft frame of the pose view).
        self.plotter.ren_win.SwapBuffersOff()
        self._iren = self.plotter.iren.interactor
        # VTK's own camera style is replaced by a style that does nothing: the camera is moved
        # here. An observer below the widgets' priority hears a press only when no widget took it.
        self._iren.SetInteractorStyle(vtkInteractorStyleUser())
        for name in ("LeftButtonPressEvent", "MiddleButtonPressEvent", "RightButtonPressEvent"):
            self._iren.AddObserver(name, self._on_free_press, -10.0)
        self._keep_all = False                         # (``_on_free_press``)
        self._drag = None                              # "orbit" | "pan" | "zoom" while the camera is dragged
        self._last = (0.0, 0.0)
        #: Callables the view sets: ``pivot()`` -> (3,) m or None (the focal point), ``fit()`` frames the scene.
        self.pivot = None
        self.fit = None
        #: Called after a resize, before a refit (the view's pixel-sized overlays follow it).
        self.resized = None
        # True from a fit until the user moves the camera: a resize (the first show of a tab,
        # a moved splitter) then frames the scene again for its new shape.
        self.fitted = False
        self.reset_button = QToolButton(self)
        self.reset_button.setText("Reset view")
        self.reset_button.setToolTip("Frame the whole scene again (R).")
        self.reset_button.clicked.connect(self.reset_camera)
        self._pixels = vtkUnsignedCharArray()
        self._image: QImage | None = None
        self._render_requested = True
        self._painting = False
        self.draft = False                             # rendering at DRAFT_SCALE (``set_draft``)
        self._widths: dict = {}                        # property -> (its width, its draft width)
        self.caption = ""                              # painted over the frame (``set_caption``)
        self._caption_key = None                       # (caption, size, font) of ``_caption_fit``
        self._caption_fit = ("", Qt.AlignmentFlag.AlignRight, True)
        self._caption_rect = (None, None)              # (``_caption_key``, its text's size) of ``caption_rect``
        self.legend_rows: tuple = ()                   # ((text, colour), ...) painted over the frame
        self.legend_box = None                         # (x, y, w, h) of the render window's, origin lower left
        self._legend_image = (None, None)              # (key, QImage) of ``_legend_picture``
        self._button = Qt.MouseButton.NoButton
        self._wheel = 0
        self.plotter.ren_win.AddObserver("EndEvent", self._on_rendered)

    def _closed(self) -> bool:
        return getattr(self.plotter, "_closed", True) or self.plotter.ren_win is None

    # -- rendering ---------------------------------------------------------------------------
    def set_draft(self, draft: bool) -> None:
        """Render at ``DRAFT_SCALE`` of the widget's pixels (scaled up, smoothed) while ``draft``.

        Level of detail for a view that follows a moving slider, as ParaView and Blender do:
        on a software renderer a frame of the pose view costs 13-17 ms at full size, ~6 ms at
        half; the full-size frame comes back with the slider's release. Lines (a polytope's
        edges, outlines) are drawn ``DRAFT_SCALE`` as wide in a draft (``_match_line_widths``):
        scaled up they are as wide on screen as in the full frame. (At their own width they
        were twice as wide: a thin polytope's edges covered its faces, which looked dark blue
        in the draft and light in the full frame.)
        """
        if draft == self.draft or self._closed():
            return
        self.draft = draft
        self._fit_window()
        self.request_render()

    def set_caption(self, text: str) -> None:
        """Print ``text`` in the lower right corner (lines as given, wrapped short of the axes triad),
        in at most ``CAPTION_HEIGHT_SHARE`` of the view's height (``caption_layout``)."""
        if text != self.caption:
            self.caption = text
            self._caption_changed()

    def caption_layout(self) -> tuple[str, bool]:
        """The caption as painted at the view's size, and whether it is the whole caption.

        Lines as given, wrapped to the width left of the axes triad, while that fits in
        ``CAPTION_HEIGHT_SHARE`` of the view's height (its box included). Else each line on a
        single row cut short with "…", as many of the first lines as fit (the first say most:
        the forces); none when not one line fits or the width holds fewer than
        ``CAPTION_MIN_CHARS`` characters. Whenever it is not the whole caption, the widget's
        tooltip holds the whole.
        """
        text, _, whole = self._fitted_caption()
        return text, whole

    def _fitted_caption(self) -> tuple[str, Qt.AlignmentFlag, bool]:
        """``(text, flags, whole)``: ``caption_layout`` and the text's drawing flags, kept for
        the caption, size and font they were made for."""
        key = (self.caption, self.width(), self.height(), self._caption_font().key())
        if self._caption_key != key:
            self._caption_key = key
            self._caption_fit = self._fit_caption()
        return self._caption_fit

    def _fit_caption(self) -> tuple[str, Qt.AlignmentFlag, bool]:
        """``(text, flags, whole)`` of the caption at the view's size, made anew (``caption_layout``)."""
        wrap = Qt.AlignmentFlag.AlignRight | Qt.TextFlag.TextWordWrap
        if not self.caption:
            return "", wrap, True
        metrics = QFontMetrics(self._caption_font())
        width = self._caption_width()
        # A kept phrase wider than the text's width is given its breaks back: unbroken, it
        # would stand out past the view's left edge (and over the axes triad).
        caption = "\n".join(" ".join(word if metrics.horizontalAdvance(word) <= width
                                      else word.replace("\u00a0", " ").replace("\u2060", "")
                                      for word in line.split(" "))
                            for line in keep_phrases(self.caption).split("\n"))
        limit = int(CAPTION_HEIGHT_SHARE * self.height()) - 2 * CAPTION_PAD_Y       # the text's height
        box = metrics.boundingRect(QRect(0, 0, width, 10 ** 6), wrap, caption)
        if box.height() <= limit:
            # Its box is the one ``caption_rect`` asks for: kept (one bounding box a slider step).
            self._caption_rect = (self._caption_key, box.size())
            return caption, wrap, True
        if width < CAPTION_MIN_CHARS * metrics.averageCharWidth():
            return "", wrap, False
        rows = [metrics.elidedText(line, Qt.TextElideMode.ElideRight, width) for line in caption.split("\n")]
        one = Qt.AlignmentFlag.AlignRight
        while rows and self._text_height(metrics, one, "\n".join(rows)) > limit:
            rows.pop()              # the last lines first
        return "\n".join(rows), one, False

    def _caption_width(self) -> int:
        """The caption's text width (px): the view's, short of the axes triad and the margins."""
        return max(1, round(self.width() * (1 - AXES_WIDTH_SHARE)) - 2 * CAPTION_MARGIN_PX)

    def _text_height(self, metrics: QFontMetrics, flags, text: str) -> int:
        return metrics.boundingRect(QRect(0, 0, self._caption_width(), 10 ** 6), flags, text).height()

    def _caption_changed(self) -> None:
        """The caption or the view's size changed: its tooltip follows, and it is painted anew."""
        self.setToolTip("" if self.caption_layout()[1] else self.caption)
        self.update()

    def caption_rect(self) -> QRect:
        """Where the caption's text goes, in widget pixels (empty without a caption, or with one
        the view is too small to show: ``caption_layout``)."""
        text, flags, _ = self._fitted_caption()
        if not text:
            return QRect()
        # Kept with the fitted caption (a word-wrapped text's bounding box is ~0.2 ms, and a
        # slider step asked for it four times: the view's framing, the paint, the box).
        if self._caption_rect[0] != self._caption_key:
            box = QFontMetrics(self._caption_font()).boundingRect(QRect(0, 0, self._caption_width(), 10 ** 6),
                                                                  flags, text)
            self._caption_rect = (self._caption_key, box.size())
        size = self._caption_rect[1]
        return QRect(self.width() - CAPTION_MARGIN_PX - size.width(),
                     self.height() - CAPTION_MARGIN_PX - size.height(), size.width(), size.height())

    def caption_box(self) -> QRect:
        """The caption's white box as painted, in widget pixels (empty without a caption)."""
        rect = self.caption_rect()
        pad_x, pad_y = CAPTION_PAD_X, CAPTION_PAD_Y
        return QRect() if rect.isEmpty() else rect.adjusted(-pad_x, -pad_y, pad_x, pad_y)

    def _caption_font(self) -> QFont:
        font = QFont(self.font())
        font.setPointSizeF(font.pointSizeF() * CAPTION_FONT_SHARE)
        return font

    def _paint_caption(self, painter: QPainter) -> None:
        rect = self.caption_rect()
        if rect.isEmpty():
            return
        text, flags, _ = self._fitted_caption()
        painter.fillRect(self.caption_box(), QColor(255, 255, 255, CAPTION_BOX_ALPHA))
        painter.setFont(self._caption_font())
        painter.setPen(Qt.GlobalColor.black)
        painter.drawText(rect, flags, text)

    def set_legend(self, rows, box) -> None:
        """Paint a legend over the frame: a swatch and the text in its colour per row of ``rows``
        (``(text, colour)``, colour a name or ``"#rrggbb"``), in ``box`` = ``(x, y, w, h)``, shares
        of the view's width and height from its lower left corner (VTK's normalised viewport
        coordinates, as ``pyvista.plotting.renderer.map_loc_to_pos`` gives them); None: no legend."""
        rows = tuple((str(text), str(colour)) for text, colour in rows or ())
        box = None if box is None or not rows else tuple(float(v) for v in box)
        if (rows, box) != (self.legend_rows, self.legend_box):
            self.legend_rows, self.legend_box = rows, box
            self.update()

    def legend_rect(self) -> QRect:
        """Where the legend's box is painted, in widget pixels (empty without a legend)."""
        if self.legend_box is None:
            return QRect()
        x, y, w, h = self.legend_box
        width, height = self.width(), self.height()
        return QRect(round(x * width), round((1 - y - h) * height), max(1, round(w * width)), max(1, round(h * height)))

    def _legend_picture(self) -> QImage | None:
        """The legend drawn (``set_legend``), kept for its rows, size and font: white box, a
        square swatch per row and its text in the row's colour, the text's size fitted to the
        rows' height and the box's width (as VTK's legend box fits its text)."""
        rect = self.legend_rect()
        if rect.isEmpty():
            return None
        ratio = self.devicePixelRatioF()
        key = (self.legend_rows, rect.width(), rect.height(), ratio, self.font().key())
        if self._legend_image[0] == key:
            return self._legend_image[1]
        image = QImage(max(1, round(rect.width() * ratio)), max(1, round(rect.height() * ratio)),
                       QImage.Format.Format_ARGB32_Premultiplied)
        image.setDevicePixelRatio(ratio)
        image.fill(QColor(255, 255, 255, LEGEND_BOX_ALPHA))
        painter = QPainter(image)
        try:
            painter.setRenderHint(QPainter.RenderHint.TextAntialiasing, True)
            row = (rect.height() - 2 * LEGEND_PAD_PX) / len(self.legend_rows)
            swatch = max(1.0, 0.5 * row)
            text_x = LEGEND_PAD_PX + swatch + LEGEND_PAD_PX
            font = QFont(self.font())
            font.setPixelSize(max(1, int(LEGEND_TEXT_SHARE * row)))
            widest = max(QFontMetrics(font).horizontalAdvance(text) for text, _ in self.legend_rows)
            room = rect.width() - text_x - LEGEND_PAD_PX
            if widest > room > 0:            # shrunk to the box's width, as VTK fits its text
                font.setPixelSize(max(1, int(font.pixelSize() * room / widest)))
            painter.setFont(font)
            for i, (text, colour) in enumerate(self.legend_rows):
                top = LEGEND_PAD_PX + i * row
                painter.fillRect(QRectF(LEGEND_PAD_PX, top + (row - swatch) / 2, swatch, swatch), QColor(colour))
                painter.setPen(QColor(colour))
                painter.drawText(QRectF(text_x, top, max(1.0, room), row),
                                 int(Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter
                                     | Qt.TextFlag.TextDontClip), text)      # (a row is less than a line: "_" stays)
        finally:
            painter.end()
        self._legend_image = (key, image)
        return image

    def event(self, event) -> bool:
        if event.type() == QEvent.Type.ToolTip:
            # A shortened caption's whole text, over the caption (over the scene it would get
            # in the way); over the whole view when the view is too small for any of it.
            box = self.caption_box()
            if self.toolTip() and (box.isEmpty() or box.contains(event.pos())):
                QToolTip.showText(event.globalPos(), self.toolTip(), self)
            else:
                QToolTip.hideText()
            return True
        if event.type() == QEvent.Type.FontChange:
            self._caption_changed()
        return super().event(event)

    def _render_ratio(self) -> float:
        """Render-window pixels per widget pixel."""
        return self.devicePixelRatioF() * (DRAFT_SCALE if self.draft else 1.0)

    def _fit_window(self) -> None:
        """The render window's size for the widget's size (and the draft scale)."""
        ratio = self._render_ratio()
        self._iren.UpdateSize(max(16, round(self.width() * ratio)), max(16, round(self.height() * ratio)))

    def _match_line_widths(self) -> None:
        """Every actor's lines ``DRAFT_SCALE`` as wide in a draft, their own width in a full frame.

        Each property's own width is kept while it is drawn narrower; an actor added during a
        draft, or given a new width, is drawn at its width scaled (a property whose width is not
        the one set here is taken as new).
        """
        widths, kept = {}, self._widths
        actors = self.plotter.renderer.GetActors()
        actors.InitTraversal()
        for _ in range(actors.GetNumberOfItems()):
            prop = actors.GetNextActor().GetProperty()
            key = prop.GetAddressAsString("vtkProperty")
            width = prop.GetLineWidth()
            own = kept[key][0] if key in kept and kept[key][1] == width else width
            if self.draft:
                drawn = own * DRAFT_SCALE
                widths[key] = (own, drawn)
            else:
                drawn = own
            if drawn != width:
                prop.SetLineWidth(drawn)
        self._widths = widths

    @contextlib.contextmanager
    def quiet(self):
        """Change the scene without rendering it: pyvista's calls that render at once by default
        (``add_legend`` twice, ``view_isometric``, ``reset_camera``, ``remove_scalar_bar``, ...)
        and VTK's interactor (a widget switched on) render nothing inside; the next paint renders
        the scene once (``request_render``). A software-OpenGL frame costs 20-180 ms: a device
        switch rendered the pose view eight times over before it was painted (a resize refitting
        the camera and rebuilding the legend)."""
        plotter, iren = self.plotter, self._iren
        before = plotter.suppress_rendering
        # VTK's own renders too: a 3D widget switched on renders through the interactor (the
        # revolved slice's cut plane: 50-115 ms for a frame the next paint renders again).
        enabled = iren is not None and iren.GetEnableRender()
        plotter.suppress_rendering = True
        if enabled:
            iren.EnableRenderOff()
        try:
            yield
        finally:
            plotter.suppress_rendering = before
            if enabled and self._iren is not None:
                self._iren.EnableRenderOn()

    def request_render(self) -> None:
        """Render the scene at the next paint (coalesced: one render for many requests)."""
        self._render_requested = True
        self.update()

    def _on_rendered(self, *_) -> None:
        """After any render of the plotter: take its pixels, and show them."""
        if self._closed():
            return
        w, h = self.plotter.ren_win.GetSize()
        if w <= 0 or h <= 0:
            return
        self.plotter.ren_win.GetRGBACharPixelData(0, 0, w - 1, h - 1, 0, self._pixels)
        frame = np.ascontiguousarray(vtk_to_numpy(self._pixels).reshape(h, w, 4)[::-1])   # VTK's rows go up
        # In Qt's own pixel format (a copy, exact: no alpha): the raster engine paints RGBX8888
        # converting every pixel on each paint, and a draft scaled smoothly took twice as long.
        image = QImage(frame.data, w, h, 4 * w, QImage.Format.Format_RGBX8888).convertToFormat(
            QImage.Format.Format_RGB32)
        image.setDevicePixelRatio(self.devicePixelRatioF())
        self._image = image
        if not self._painting:
            self.update()

    def paintEvent(self, event) -> None:   # noqa: N802 (Qt name)
        if self._render_requested and self.isVisible() and not self._closed():
            self._render_requested = False
            self._painting = True
            try:
                self._match_line_widths()
                self.plotter.render()
            finally:
                self._painting = False
        painter = QPainter(self)
        try:
            if self._image is None:
                painter.fillRect(self.rect(), Qt.GlobalColor.white)
            else:
                if self.draft:          # a draft's fewer pixels, scaled up to the widget
                    painter.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform, True)
                    painter.drawImage(QRectF(self.rect()), self._image)
                else:
                    painter.drawImage(0, 0, self._image)
            legend = self._legend_picture()
            if legend is not None:
                painter.drawImage(self.legend_rect().topLeft(), legend)
            self._paint_caption(painter)
        finally:
            painter.end()

    def resizeEvent(self, event) -> None:   # noqa: N802 (Qt name)
        super().resizeEvent(event)
        hint = self.reset_button.sizeHint()
        self.reset_button.setGeometry(self.width() - hint.width() - 6, 6, hint.width(), hint.height())
        if self.caption:
            self._caption_changed()       # before a refit: the view frames what the caption leaves
        if not self._closed() and self._iren is not None:
            self._fit_window()
            if self.resized is not None:
                with self.quiet():
                    self.resized()
            if self.fitted:
                self.reset_camera()
            self.request_render()

    def showEvent(self, event) -> None:   # noqa: N802 (Qt name)
        super().showEvent(event)
        self.request_render()

    def close_plotter(self) -> None:
        """Close the plotter and let go of its render window now (its X display connection
        must close while the X server is still there)."""
        if self.plotter.ren_win is not None:
            self.plotter.ren_win.RemoveAllObservers()
        self.plotter.close()
        self._iren = None

    # -- the camera ------------------------------------------------------------------------------
    def reset_camera(self) -> None:
        """Frame the scene (the view's ``fit``, else VTK's reset) and show it."""
        if self._closed():
            return
        with self.quiet():
            if self.fit is not None:
                self.fit()
            else:
                self.plotter.reset_camera()
        self.fitted = True
        self.request_render()

    def keyPressEvent(self, event) -> None:   # noqa: N802 (Qt name)
        if event.key() == Qt.Key.Key_R and not event.modifiers() & ~Qt.KeyboardModifier.KeypadModifier:
            self.reset_camera()
        else:
            super().keyPressEvent(event)

    def _display_xy(self, event) -> tuple[float, float]:
        """The event's position in VTK display pixels (device pixels, origin bottom-left)."""
        ratio = self._render_ratio()
        pos = event.position()
        return pos.x() * ratio, (self.height() - pos.y() - 1) * ratio

    def _on_free_press(self, *_) -> None:
        """A press no 3D widget took: it drags the camera (which way depends on button and shift)."""
        shift = self._iren.GetShiftKey()
        self._drag = {Qt.MouseButton.LeftButton: "pan" if shift else "orbit", Qt.MouseButton.MiddleButton: "pan",
                      Qt.MouseButton.RightButton: "zoom"}.get(self._button)
        # A turn keeps the whole scene in view only if it was in view when the drag began: a
        # view the user zoomed into stays zoomed.
        self._keep_all = (self._drag == "orbit" and self.pivot is not None
                          and camera.all_in_view(self.plotter.renderer, camera.shown_bounds(self.plotter)))

    def _move_camera(self, x: float, y: float) -> None:
        self.fitted = False
        x0, y0 = self._last
        renderer = self.plotter.renderer
        if self._drag == "orbit":
            pivot = self.pivot() if self.pivot is not None else None
            camera.orbit(renderer, renderer.GetActiveCamera().GetFocalPoint() if pivot is None else pivot,
                         x - x0, y - y0)
            if pivot is not None and self._keep_all:    # about its end-effector, none of it out of view
                camera.keep_in_view(renderer, pivot, camera.shown_bounds(self.plotter))
        elif self._drag == "pan":
            camera.pan(renderer, x0, y0, x, y)
        elif self._drag == "zoom":
            # Right drag: up zooms in about the point where the drag began.
            camera.zoom_at(renderer, *self._press_at, camera.ZOOM_PER_NOTCH ** ((y - y0) / 40.0))
        self.request_render()

    # -- the mouse, forwarded to VTK's interactor (3D widgets), then the camera -------------------
    def _forward(self, event, vtk_event: str, repeat: int = 0) -> None:
        if self._closed() or self._iren is None:
            return
        ratio = self.devicePixelRatioF()
        pos = event.position()
        mods = event.modifiers()
        self._iren.SetEventInformation(round(pos.x() * ratio), round((self.height() - pos.y() - 1) * ratio),
                                       int(bool(mods & Qt.KeyboardModifier.ControlModifier)),
                                       int(bool(mods & Qt.KeyboardModifier.ShiftModifier)), chr(0), repeat, None)
        self._iren.InvokeEvent(vtk_event)        # the interactor renders what it changes

    _PRESS = {Qt.MouseButton.LeftButton: "LeftButtonPressEvent", Qt.MouseButton.RightButton: "RightButtonPressEvent",
              Qt.MouseButton.MiddleButton: "MiddleButtonPressEvent"}
    _RELEASE = {Qt.MouseButton.LeftButton: "LeftButtonReleaseEvent",
                Qt.MouseButton.RightButton: "RightButtonReleaseEvent",
                Qt.MouseButton.MiddleButton: "MiddleButtonReleaseEvent"}

    def mousePressEvent(self, event) -> None:   # noqa: N802 (Qt name)
        if event.button() in self._PRESS:
            self._button = event.button()
            self._drag = None
            self._last = self._press_at = self._display_xy(event)
            self._forward(event, self._PRESS[self._button], 1 if event.type() == QEvent.Type.MouseButtonDblClick else 0)

    def mouseReleaseEvent(self, event) -> None:   # noqa: N802 (Qt name)
        if self._button in self._RELEASE:
            self._forward(event, self._RELEASE[self._button])
            self._button = Qt.MouseButton.NoButton
            self._drag = None

    def mouseMoveEvent(self, event) -> None:   # noqa: N802 (Qt name)
        if self._button == Qt.MouseButton.NoButton:
            return
        if self._drag is not None and not self._closed():
            x, y = self._display_xy(event)
            self._move_camera(x, y)
            self._last = (x, y)
        else:
            self._forward(event, "MouseMoveEvent")       # a 3D widget's drag

    def wheelEvent(self, event) -> None:   # noqa: N802 (Qt name)
        self._wheel += event.angleDelta().y()
        if abs(self._wheel) >= 120 and not self._closed():
            self.fitted = False
            notches = self._wheel / 120.0
            self._wheel = 0
            camera.zoom_at(self.plotter.renderer, *self._display_xy(event), camera.ZOOM_PER_NOTCH ** notches)
            self.request_render()
