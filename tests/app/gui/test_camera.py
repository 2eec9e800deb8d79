"""The 3D views' camera, moved by hand (issue 11 sec. 3): turn about the end-effector, zoom
towards the cursor, reset with R, one camera per device and tab; the renderer's settings."""
from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import QPoint, QPointF, Qt
from PySide6.QtGui import QWheelEvent
from PySide6.QtWidgets import QApplication

from app.gui.views import camera, gl_quality
from app.gui.views.camera import CameraState

SMALL = 40


def _show_pose(window, qtbot):
    window.tabs.setCurrentWidget(window.pose_view)
    qtbot.waitUntil(lambda: "links" in window.pose_view.plotter.actors, timeout=10_000)
    view = window.pose_view.view
    view.plotter.render()
    return view


def _drag(qtbot, widget, start: QPoint, delta: QPoint, steps: int = 12) -> None:
    qtbot.mousePress(widget, Qt.MouseButton.LeftButton, pos=start)
    for k in range(1, steps + 1):
        qtbot.mouseMove(widget, start + QPoint(round(delta.x() * k / steps), round(delta.y() * k / steps)))
    qtbot.mouseRelease(widget, Qt.MouseButton.LeftButton, pos=start + delta)


def _camera_close(a: CameraState, b: CameraState, size: float) -> bool:
    # Restored cameras are the same doubles copied back: agreement to 1e-9 of the scene's size
    # leaves room only for the clipping-range recomputation, which does not move the camera.
    return all(np.allclose(getattr(a, f), getattr(b, f), atol=1e-9 * size, rtol=0)
               for f in ("position", "focal_point", "view_up"))


@pytest.mark.parametrize("device", ["inverse3_prototype", "fivebar_singh"])
def test_a_drag_turns_about_the_end_effector_and_keeps_it_in_view(make_window, qtbot, device):
    window = make_window(device, longest=SMALL)
    view = _show_pose(window, qtbot)
    renderer = view.plotter.renderer
    ee = window.pose_view.end_effector()
    before = camera.world_to_display(renderer, ee)
    cam_before = CameraState.of(renderer)
    centre = QPoint(view.width() // 2, view.height() // 2)
    _drag(qtbot, view, centre, QPoint(120, 0))
    _drag(qtbot, view, centre, QPoint(0, 120))
    after = camera.world_to_display(renderer, ee)
    w, h = view.plotter.ren_win.GetSize()
    assert 0 <= after[0] < w and 0 <= after[1] < h
    # A turn about the pivot leaves its camera coordinates, hence its pixel, unchanged; the
    # only error is the doubles' round trip through the view matrices (far below a pixel).
    assert np.allclose(after, before, atol=1e-3)
    assert not np.allclose(CameraState.of(renderer).position, cam_before.position)     # it did turn
    # ... and the rest of the device with it: every corner of every drawn mesh's box in the view
    # (a turn about the end-effector swung the Inverse3's base out; the view zooms out instead).
    boxes = camera.shown_bounds(view.plotter)
    corners = np.array([[b[i], b[2 + j], b[4 + k]] for b in boxes for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    px = np.array([camera.world_to_display(renderer, c) for c in corners])
    assert np.all(px >= 0) and np.all(px[:, 0] <= w) and np.all(px[:, 1] <= h), (px.min(axis=0), px.max(axis=0))

    # R frames the device again: the same camera as the view's own fit.
    view.setFocus()
    qtbot.keyClick(view, Qt.Key.Key_R)
    reset = CameraState.of(renderer)
    window.pose_view.fit_camera()
    size = float(np.linalg.norm(np.ptp(view.plotter.bounds, axis=0))) or 1.0
    assert _camera_close(reset, CameraState.of(renderer), size)
    # The fit shows the whole device: every corner of every drawn mesh's box inside the view.
    boxes = camera.shown_bounds(view.plotter)
    corners = np.array([[b[i], b[2 + j], b[4 + k]] for b in boxes for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    px = np.array([camera.world_to_display(renderer, c) for c in corners])
    assert np.all(px >= 0) and np.all(px[:, 0] <= w) and np.all(px[:, 1] <= h)
    # ... and so does the toolbar button.
    _drag(qtbot, view, centre, QPoint(90, 40))
    qtbot.mouseClick(view.reset_button, Qt.MouseButton.LeftButton)
    assert _camera_close(CameraState.of(renderer), reset, size)


def test_the_wheel_zooms_towards_the_cursor(make_window, qtbot):
    window = make_window("inverse3_prototype", longest=SMALL)
    view = _show_pose(window, qtbot)
    renderer = view.plotter.renderer
    at = QPointF(view.width() * 0.7, view.height() * 0.3)
    ratio = view.devicePixelRatioF()
    px = (at.x() * ratio, (view.height() - at.y() - 1) * ratio)
    anchor = camera.display_to_focal_plane(renderer, *px)
    distance = renderer.GetActiveCamera().GetDistance()
    event = QWheelEvent(at, view.mapToGlobal(at), QPoint(0, 0), QPoint(0, 240), Qt.MouseButton.NoButton,
                        Qt.KeyboardModifier.NoModifier, Qt.ScrollPhase.NoScrollPhase, False)
    QApplication.sendEvent(view, event)
    # Two notches in: the camera is 1.2^2 times nearer its focal point ...
    assert renderer.GetActiveCamera().GetDistance() == pytest.approx(distance / camera.ZOOM_PER_NOTCH ** 2,
                                                                      rel=1e-9)
    # ... and the point under the cursor kept its pixel (double round trip: far below 1e-3 px).
    assert np.allclose(camera.world_to_display(renderer, anchor), px, atol=1e-3)
    # Zoomed in (parts of the device out of view), a turn keeps the zoom: only a scene wholly
    # in view when the drag begins is kept in view by zooming out (review: the first pixel of a
    # drag threw the user's zoom away).
    QApplication.sendEvent(view, QWheelEvent(at, view.mapToGlobal(at), QPoint(0, 0), QPoint(0, 480),
                                             Qt.MouseButton.NoButton, Qt.KeyboardModifier.NoModifier,
                                             Qt.ScrollPhase.NoScrollPhase, False))
    assert not camera.all_in_view(renderer, camera.shown_bounds(view.plotter))
    zoomed = renderer.GetActiveCamera().GetDistance()
    _drag(qtbot, view, QPoint(view.width() // 2, view.height() // 2), QPoint(40, 0))
    assert renderer.GetActiveCamera().GetDistance() == pytest.approx(zoomed, rel=1e-9)


def test_each_device_and_tab_keeps_its_camera(make_window, qtbot, waits):
    window = make_window("inverse3_prototype", longest=SMALL)
    view = _show_pose(window, qtbot)
    centre = QPoint(view.width() // 2, view.height() // 2)
    _drag(qtbot, view, centre, QPoint(100, 30))
    left = CameraState.of(view.plotter.renderer)
    size = float(np.linalg.norm(np.ptp(view.plotter.bounds, axis=0)))

    window.tabs.setCurrentWidget(window.workspace_view)
    wview = window.workspace_view.view
    qtbot.waitUntil(lambda: "workspace" in wview.plotter.actors, timeout=20_000)
    wview.plotter.render()
    _drag(qtbot, wview, QPoint(wview.width() // 2, wview.height() // 2), QPoint(-80, 20))
    wleft = CameraState.of(wview.plotter.renderer)

    assert window.load_device("fivebar_singh")
    waits.full(window)
    window.tabs.setCurrentWidget(window.pose_view)
    qtbot.waitUntil(lambda: window.pose_view._camera_for[0] == "fivebar_singh", timeout=10_000)
    assert not _camera_close(CameraState.of(view.plotter.renderer), left, size)

    assert window.load_device("inverse3_prototype")
    waits.full(window)
    qtbot.waitUntil(lambda: window.pose_view._camera_for[0] == "inverse3_prototype", timeout=10_000)
    assert _camera_close(CameraState.of(view.plotter.renderer), left, size)
    window.tabs.setCurrentWidget(window.workspace_view)
    qtbot.waitUntil(lambda: window.workspace_view._camera_for == "inverse3_prototype", timeout=20_000)
    assert _camera_close(CameraState.of(wview.plotter.renderer), wleft, size)


def test_the_renderer_is_detected_and_software_keeps_the_cheap_settings(make_window, qtbot):
    window = make_window("fivebar_singh", longest=SMALL, wait=False)
    quality = window.pose_view.view.quality
    text = window.pose_view.plotter.ren_win.ReportCapabilities()
    # This machine renders with Mesa's llvmpipe (Xvfb): software settings.
    assert "llvmpipe" in gl_quality.renderer_string(text).lower()
    assert quality.software and quality.multisamples == 0 and not quality.depth_peeling
    assert window.pose_view.plotter.ren_win.GetMultiSamples() == 0
    assert not window.pose_view.plotter.renderer.GetUseDepthPeeling()


@pytest.mark.parametrize("renderer, software", [
    ("llvmpipe (LLVM 15.0.6, 256 bits)", True),
    ("softpipe", True),
    ("Google SwiftShader", True),
    ("Microsoft Basic Render Driver", True),
    ("", True),                                       # unknown: the settings that always work
    ("NVIDIA GeForce RTX 3080/PCIe/SSE2", False),
    ("AMD Radeon RX 6800 (radeonsi, navi21, LLVM 15.0.6, DRM 3.49, 6.1.0)", False),
    ("Mesa Intel(R) UHD Graphics 620 (KBL GT2)", False),
])
def test_quality_for_a_renderer_string(renderer, software):
    q = gl_quality.quality_for(renderer)
    assert q.software is software
    assert (q.multisamples > 0) is (not software) and q.depth_peeling is (not software)
    caps = f"OpenGL vendor string:  X\nOpenGL renderer string:  {renderer}\nOpenGL version string:  4.5\n"
    assert gl_quality.renderer_string(caps) == renderer


def test_hardware_settings_are_applied_to_a_plotter_and_software_ones_undo_them():
    import pyvista as pv

    plotter = pv.Plotter(off_screen=True, window_size=(64, 64))
    try:
        plotter.show(auto_close=False)
        gl_quality.apply(plotter, gl_quality.quality_for("NVIDIA GeForce RTX 3080/PCIe/SSE2"))
        assert plotter.renderer.GetUseDepthPeeling() and plotter.renderer.GetUseFXAA()
        assert plotter.ren_win.GetMultiSamples() == 4
        gl_quality.apply(plotter, gl_quality.quality_for("llvmpipe (LLVM 15.0.6, 256 bits)"))
        assert not plotter.renderer.GetUseDepthPeeling() and not plotter.renderer.GetUseFXAA()
        assert plotter.ren_win.GetMultiSamples() == 0
    finally:
        plotter.close()
