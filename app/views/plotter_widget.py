"""A PyVista plotter that renders off-screen and is painted as an image: no OpenGL widget.

Why not ``pyvistaqt.QtInteractor``: it is a ``QOpenGLWidget``, and one of those anywhere in
a window makes Qt compose the *whole window* with OpenGL on every repaint. In software
OpenGL (Mesa llvmpipe: virtual machines, Xvfb, remote desktops) that costs 30-50 ms per
repaint of a 1600 x 950 window, for any change anywhere (a map update, a table cell, the
progress bar), and blocks the GUI thread that long. Here VTK renders into its own off-screen
window and the pixels (read back in a fraction of a millisecond) are painted by Qt's raster
engine, so the window stays a plain raster window.

``plotter`` is an ordinary off-screen ``pyvista.Plotter`` (actors, cameras, widgets work as
usual). Rendering is on demand: ``request_render()`` (after changing the scene) renders once
at the next paint, however many requests came before; a render started elsewhere (the
camera interaction, a pyvista widget, ``plotter.render()``) is picked up as well. Mouse
events go to the plotter's interactor, so the camera and 3D widgets (e.g. a clip plane)
respond to the mouse as in any VTK window.
"""
from __future__ import annotations

import numpy as np
import pyvista as pv
from PySide6.QtCore import QEvent, Qt
from PySide6.QtGui import QImage, QPainter
from PySide6.QtWidgets import QSizePolicy, QWidget
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkUnsignedCharArray


class PlotterWidget(QWidget):
    """Shows ``self.plotter`` (an off-screen ``pyvista.Plotter``) and forwards the mouse to it."""

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Expanding)
        self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)
        self.setMouseTracking(False)
        self.setFocusPolicy(Qt.FocusPolicy.ClickFocus)
        self.plotter = pv.Plotter(off_screen=True, window_size=[max(16, self.width()), max(16, self.height())])
        # Software OpenGL: no multisampling (8x MSAA triples a frame's cost), and plain alpha
        # blending of the translucent glyphs (order-independent translucency adds full-window
        # passes that double it).
        self.plotter.ren_win.SetMultiSamples(0)
        self.plotter.renderer.SetUseOIT(False)
        self.plotter.show(auto_close=False)          # initialise the render window, no event loop
        self._iren = self.plotter.iren.interactor
        self._pixels = vtkUnsignedCharArray()
        self._image: QImage | None = None
        self._render_requested = True
        self._painting = False
        self._button = Qt.MouseButton.NoButton
        self._wheel = 0
        self.plotter.ren_win.AddObserver("EndEvent", self._on_rendered)

    # -- rendering ---------------------------------------------------------------------------
    def request_render(self) -> None:
        """Render the scene at the next paint (coalesced: one render for many requests)."""
        self._render_requested = True
        self.update()

    def _on_rendered(self, *_) -> None:
        """After any render of the plotter: take its pixels, and show them."""
        if self.plotter.ren_win is None:
            return
        w, h = self.plotter.ren_win.GetSize()
        if w <= 0 or h <= 0:
            return
        self.plotter.ren_win.GetRGBACharPixelData(0, 0, w - 1, h - 1, 0, self._pixels)
        rgba = vtk_to_numpy(self._pixels).reshape(h, w, 4)[::-1]        # VTK's rows go up
        image = QImage(np.ascontiguousarray(rgba).data, w, h, 4 * w, QImage.Format.Format_RGBX8888).copy()
        image.setDevicePixelRatio(self.devicePixelRatioF())
        self._image = image
        if not self._painting:
            self.update()

    def paintEvent(self, event) -> None:   # noqa: N802 (Qt name)
        if self._render_requested and not getattr(self.plotter, "_closed", True) and self.isVisible():
            self._render_requested = False
            self._painting = True
            try:
                self.plotter.render()
            finally:
                self._painting = False
        painter = QPainter(self)
        try:
            if self._image is None:
                painter.fillRect(self.rect(), Qt.GlobalColor.white)
            else:
                painter.drawImage(0, 0, self._image)
        finally:
            painter.end()

    def resizeEvent(self, event) -> None:   # noqa: N802 (Qt name)
        super().resizeEvent(event)
        ratio = self.devicePixelRatioF()
        w, h = max(16, round(self.width() * ratio)), max(16, round(self.height() * ratio))
        if not getattr(self.plotter, "_closed", True):
            self._iren.UpdateSize(w, h)        # the render window too
            self.request_render()

    def showEvent(self, event) -> None:   # noqa: N802 (Qt name)
        super().showEvent(event)
        self.request_render()

    def close_plotter(self) -> None:
        self.plotter.close()
        # Release the interactor now, while its X display is still there: kept alive until the
        # interpreter exits, it would close a display whose server may be gone (Xvfb after a
        # test run), and Xlib then ends the process with exit status 1.
        self._iren = None

    # -- the mouse, forwarded to VTK's interactor ------------------------------------------------
    def _event_info(self, event, repeat: int = 0) -> None:
        ratio = self.devicePixelRatioF()
        pos = event.position()
        mods = event.modifiers()
        self._iren.SetEventInformation(round(pos.x() * ratio), round((self.height() - pos.y() - 1) * ratio),
                                       int(bool(mods & Qt.KeyboardModifier.ControlModifier)),
                                       int(bool(mods & Qt.KeyboardModifier.ShiftModifier)), chr(0), repeat, None)

    _PRESS = {Qt.MouseButton.LeftButton: "LeftButtonPressEvent", Qt.MouseButton.RightButton: "RightButtonPressEvent",
              Qt.MouseButton.MiddleButton: "MiddleButtonPressEvent"}
    _RELEASE = {Qt.MouseButton.LeftButton: "LeftButtonReleaseEvent",
                Qt.MouseButton.RightButton: "RightButtonReleaseEvent",
                Qt.MouseButton.MiddleButton: "MiddleButtonReleaseEvent"}

    def mousePressEvent(self, event) -> None:   # noqa: N802 (Qt name)
        if getattr(self.plotter, "_closed", True) or event.button() not in self._PRESS:
            return
        self._event_info(event, 1 if event.type() == QEvent.Type.MouseButtonDblClick else 0)
        self._button = event.button()
        self._iren.InvokeEvent(self._PRESS[self._button])

    def mouseReleaseEvent(self, event) -> None:   # noqa: N802 (Qt name)
        if getattr(self.plotter, "_closed", True) or self._button not in self._RELEASE:
            return
        self._event_info(event)
        self._iren.InvokeEvent(self._RELEASE[self._button])
        self._button = Qt.MouseButton.NoButton

    def mouseMoveEvent(self, event) -> None:   # noqa: N802 (Qt name)
        if getattr(self.plotter, "_closed", True):
            return
        self._event_info(event)
        self._iren.InvokeEvent("MouseMoveEvent")

    def wheelEvent(self, event) -> None:   # noqa: N802 (Qt name)
        if getattr(self.plotter, "_closed", True):
            return
        self._event_info(event)
        self._wheel += event.angleDelta().y()
        if abs(self._wheel) >= 120:
            self._iren.InvokeEvent("MouseWheelForwardEvent" if self._wheel > 0 else "MouseWheelBackwardEvent")
            self._wheel = 0
