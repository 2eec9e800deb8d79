"""A PyVista plotter that renders off-screen, on its own thread, and is painted as an image.

Why not ``pyvistaqt.QtInteractor``: it is a ``QOpenGLWidget``, and one of those anywhere in
a window makes Qt compose the *whole window* with OpenGL on every repaint. In software
OpenGL (Mesa llvmpipe: virtual machines, Xvfb, remote desktops) that costs 30-50 ms per
repaint of a 1600 x 950 window, for any change anywhere (a map update, a table cell, the
progress bar), and blocks the GUI thread that long. Here VTK renders into an off-screen
EGL surface and the pixels (read back in a fraction of a millisecond) are painted by Qt's
raster engine, so the window stays a plain raster window.

Rendering runs on a thread of its own (VTK releases the GIL while it renders), so a frame
of the 3D view (10-25 ms in software OpenGL) does not hold up the GUI thread. The rules:

- Change the scene (actors, camera, widgets) only inside ``with widget.lock:``; the render
  thread holds the lock while it renders, so it never sees a half-changed scene.
- Then call ``request_render()``: the render thread renders once for however many requests
  came meanwhile, and the image is shown at the next paint.
- Nothing else renders: ``plotter.render()`` is suppressed and the interactor's own renders
  are off. Resizing and closing the render window happen on the render thread too.
- The render window is EGL (no X11: Xlib connections used from two threads crash), when
  VTK has it (Linux); elsewhere VTK's default window, rendered on the same terms.
"""
from __future__ import annotations

import os
import sys
import threading

if sys.platform.startswith("linux"):
    # Before VTK makes its first render window (see the module's docstring).
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numpy as np  # noqa: E402
import pyvista as pv  # noqa: E402
from PySide6.QtCore import QEvent, Qt, Signal  # noqa: E402
from PySide6.QtGui import QImage, QPainter  # noqa: E402
from PySide6.QtWidgets import QSizePolicy, QWidget  # noqa: E402
from vtkmodules.util.numpy_support import vtk_to_numpy  # noqa: E402
from vtkmodules.vtkCommonCore import vtkUnsignedCharArray  # noqa: E402


class PlotterWidget(QWidget):
    """Shows ``self.plotter`` (an off-screen ``pyvista.Plotter``) and forwards the mouse to it."""

    #: A frame from the render thread: rows top first, RGBX (h, w, 4) uint8.
    frameRendered = Signal(object)

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
        self.plotter.ren_win.ReleaseCurrent()          # from now on current on the render thread only
        self.plotter.suppress_rendering = True         # plotter.render(): a no-op; see request_render
        self._iren = self.plotter.iren.interactor
        self._iren.EnableRenderOff()                   # the camera's interaction: rendered by request
        self.lock = threading.RLock()
        self._wake = threading.Condition()
        self._render_pending = False
        self._new_size: tuple[int, int] | None = None
        self._stopping = False
        self._image: QImage | None = None
        self._frame = None                             # keeps the QImage's pixels alive
        self._button = Qt.MouseButton.NoButton
        self._wheel = 0
        self.frameRendered.connect(self._show_frame)
        self._thread = threading.Thread(target=self._render_loop, name="isoforce-render", daemon=True)
        self._thread.start()

    # -- rendering ---------------------------------------------------------------------------
    def request_render(self) -> None:
        """Render the scene soon, on the render thread (one render for many requests)."""
        with self._wake:
            self._render_pending = True
            self._wake.notify()

    def _render_loop(self) -> None:
        pixels = vtkUnsignedCharArray()
        while True:
            with self._wake:
                while not self._render_pending and not self._stopping:
                    self._wake.wait()
                stopping, size = self._stopping, self._new_size
                self._render_pending, self._new_size = False, None
            with self.lock:
                if stopping:
                    if self.plotter.ren_win is not None:
                        self.plotter.ren_win.RemoveAllObservers()
                    self.plotter.close()             # on this thread, like every other GL call
                    self._iren = None
                    return
                ren_win = self.plotter.ren_win
                if size is not None:
                    self._iren.UpdateSize(*size)      # the render window too
                ren_win.Render()
                w, h = ren_win.GetSize()
                ren_win.GetRGBACharPixelData(0, 0, w - 1, h - 1, 0, pixels)
                frame = np.ascontiguousarray(vtk_to_numpy(pixels).reshape(h, w, 4)[::-1])   # VTK's rows go up
            try:
                self.frameRendered.emit(frame)
            except RuntimeError:                      # the widget was deleted meanwhile
                return

    def _show_frame(self, frame) -> None:
        h, w = frame.shape[:2]
        image = QImage(frame.data, w, h, 4 * w, QImage.Format.Format_RGBX8888)
        image.setDevicePixelRatio(self.devicePixelRatioF())
        self._frame, self._image = frame, image
        self.update()

    def paintEvent(self, event) -> None:   # noqa: N802 (Qt name)
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
        with self._wake:                      # the render thread resizes, then renders
            self._new_size = (max(16, round(self.width() * ratio)), max(16, round(self.height() * ratio)))
            self._render_pending = True
            self._wake.notify()

    def showEvent(self, event) -> None:   # noqa: N802 (Qt name)
        super().showEvent(event)
        self.request_render()

    def close_plotter(self) -> None:
        """Close the plotter (on the render thread, which then ends)."""
        with self._wake:
            self._stopping = True
            self._wake.notify()
        self._thread.join(timeout=10.0)

    # -- the mouse, forwarded to VTK's interactor ------------------------------------------------
    def _forward(self, event, vtk_event: str, repeat: int = 0) -> None:
        ratio = self.devicePixelRatioF()
        pos = event.position()
        mods = event.modifiers()
        with self.lock:
            if self._stopping or self._iren is None:
                return
            self._iren.SetEventInformation(round(pos.x() * ratio), round((self.height() - pos.y() - 1) * ratio),
                                           int(bool(mods & Qt.KeyboardModifier.ControlModifier)),
                                           int(bool(mods & Qt.KeyboardModifier.ShiftModifier)), chr(0), repeat, None)
            self._iren.InvokeEvent(vtk_event)
        self.request_render()

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
