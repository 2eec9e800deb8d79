"""A PyVista plotter that renders off-screen and is painted as an image: no OpenGL widget.

Why not ``pyvistaqt.QtInteractor``: it is a ``QOpenGLWidget``, and one of those anywhere in
a window makes Qt compose the *whole window* with OpenGL on every repaint. In software
OpenGL (Mesa llvmpipe: virtual machines, Xvfb, remote desktops) that costs 30-50 ms per
repaint of a 1600 x 950 window, for any change anywhere (a map update, a table cell, the
progress bar), and blocks the GUI thread that long. Here VTK renders into its own off-screen
window and the pixels (read back in a fraction of a millisecond) are painted by Qt's raster
engine, so the window stays a plain raster window.

``plotter`` is an ordinary off-screen ``pyvista.Plotter`` (actors, cameras, widgets work as
usual). Rendering is on demand and on the GUI thread: ``request_render()`` (after changing
the scene) renders once at the next paint, however many requests came before; a render
started elsewhere (``plotter.render()``, the camera interaction, a pyvista widget) is picked
up as well. Mouse events go to the plotter's interactor, so the camera and 3D widgets (e.g.
a clip plane) respond to the mouse as in any VTK window.

(Rendering on a thread of its own would take the 10-25 ms of a frame off the GUI thread,
and VTK does release the GIL while it renders; but VTK's X11 render windows, created,
rendered and closed from two threads, crash in Xlib. So it is not done.)
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
        self._frame = None                             # keeps the QImage's pixels alive
        self._render_requested = True
        self._painting = False
        self._button = Qt.MouseButton.NoButton
        self._wheel = 0
        self.plotter.ren_win.AddObserver("EndEvent", self._on_rendered)

    def _closed(self) -> bool:
        return getattr(self.plotter, "_closed", True) or self.plotter.ren_win is None

    # -- rendering ---------------------------------------------------------------------------
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
        image = QImage(frame.data, w, h, 4 * w, QImage.Format.Format_RGBX8888)
        image.setDevicePixelRatio(self.devicePixelRatioF())
        self._frame, self._image = frame, image
        if not self._painting:
            self.update()

    def paintEvent(self, event) -> None:   # noqa: N802 (Qt name)
        if self._render_requested and self.isVisible() and not self._closed():
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
        if not self._closed() and self._iren is not None:
            self._iren.UpdateSize(max(16, round(self.width() * ratio)), max(16, round(self.height() * ratio)))
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

    # -- the mouse, forwarded to VTK's interactor ------------------------------------------------
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
            self._forward(event, self._PRESS[self._button], 1 if event.type() == QEvent.Type.MouseButtonDblClick else 0)

    def mouseReleaseEvent(self, event) -> None:   # noqa: N802 (Qt name)
        if self._button in self._RELEASE:
            self._forward(event, self._RELEASE[self._button])
            self._button = Qt.MouseButton.NoButton

    def mouseMoveEvent(self, event) -> None:   # noqa: N802 (Qt name)
        if self._button != Qt.MouseButton.NoButton:
            self._forward(event, "MouseMoveEvent")

    def wheelEvent(self, event) -> None:   # noqa: N802 (Qt name)
        self._wheel += event.angleDelta().y()
        if abs(self._wheel) >= 120:
            self._forward(event, "MouseWheelForwardEvent" if self._wheel > 0 else "MouseWheelBackwardEvent")
            self._wheel = 0
