"""The 3D pose view: the mechanism at the selected pose with its force glyphs (PyVista).

The camera turns about the end-effector (a drag keeps it in view), zooms towards the
cursor, and ``R`` or "Reset view" frames the device again (``plotter_widget``). Each device
keeps its own camera: switching back to it restores the view it was left at. A legend names
each glyph's colour; the caption prints the forces, the desired and clamped forces' values
and the drawing scale (``scenes.pose_scale``: the inscribed sphere is never drawn inside the
end-effector's joint ball). In a view dragged small each takes at most a third of its height
(the caption cut short, ``PlotterWidget.caption_layout``; the legend left out once its text
would shrink past reading) and the device is framed in the rest.
"""
from __future__ import annotations

import numpy as np
from PySide6.QtWidgets import QVBoxLayout, QWidget
from pyvista.plotting.renderer import map_loc_to_pos

from app import scenes
from app.gui.views import camera
from app.gui.views.camera import CameraState, shown_bounds
from app.gui.views.plotter_widget import CAPTION_MARGIN_PX, PlotterWidget
from metrics import wrenches

#: The legend's size in pixels: width, height per row (its text is fitted to its box). Qt paints
#: it over the frame (``PlotterWidget.set_legend``), not VTK.
LEGEND_WIDTH_PX, LEGEND_ROW_PX = 180, 16
#: The legend takes at most 90 % of the view's width and this share of its height (its text
#: shrinks to fit), as the caption takes at most ``plotter_widget.CAPTION_HEIGHT_SHARE``: the
#: device keeps a third of a view dragged small. Shrunk below ``LEGEND_MIN_SCALE`` of its size
#: its text is unreadable, and the legend is left out.
LEGEND_HEIGHT_SHARE, LEGEND_MIN_SCALE = 1 / 3, 0.5
#: Where the legend sits (pyvista's ``loc``).
LEGEND_LOC = "upper left"
#: The least share of the view's height the framed device keeps, whatever is painted over it.
DEVICE_SHARE = 1 / 3


class PoseView(QWidget):
    """Draws ``state.pose_report`` with the glyphs in ``state.glyphs``."""

    def __init__(self, state, parent=None) -> None:
        super().__init__(parent)
        self.state = state
        # Off-screen VTK painted as an image, rendered on demand (see ``plotter_widget``).
        self.view = PlotterWidget(self)
        self.plotter = self.view.plotter
        self.plotter.set_background("white")
        self.plotter.add_axes()
        self.view.pivot = self.end_effector
        self.view.fit = self.fit_camera
        self.view.resized = self._resized
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.view)
        self._camera_for = None
        self._cameras: dict = {}          # (preset, task_dim) -> CameraState the user left it at
        self._legend_rows = None
        self._caption_height = 0          # the caption's height (px) when the camera was framed
        self.scale = None                 # the drawing scale in use, m/N
        self._unbuilt = False             # a redraw was left out while hidden (``_skipped``)
        state.poseReportChanged.connect(self.redraw)
        # While a design slider moves the view renders a draft (half the pixels).
        state.interactionChanged.connect(self._on_interaction)

    def end_effector(self):
        """The end-effector's position (3,) m, or None (no reachable pose): the camera's pivot."""
        report = self.state.pose_report
        if report is None or not report.reachable:
            return None
        mech = self.state.mechanism
        rows = list(wrenches.force_rows(mech)) if mech.has_orientation else slice(None)
        return scenes.to_3d(np.asarray(report.x, float)[rows][: 3])[0]

    def fit_camera(self) -> None:
        """Frame the whole device (top view of planar ones, oblique of spatial ones)."""
        scenes.frame_pose_camera(self.plotter, self.state.mechanism)
        rows = len(scenes.legend_rows(self.plotter, self.state.mechanism.joint_names))
        # The legend's rows and the "Reset view" button at the top and the caption's box at the
        # bottom (with a margin) stay clear of the device, which keeps at least DEVICE_SHARE of
        # the view's height (in a view a few rows high they give way in proportion).
        height = max(1, self.view.height())
        box = self.view.caption_box()
        caption = 0 if box.isEmpty() else height - box.top() + CAPTION_MARGIN_PX
        button = self.view.reset_button.geometry().bottom() + 1 + CAPTION_MARGIN_PX
        top, bottom = max(self._legend_height(rows), button / height), caption / height
        shrink = min(1.0, (1 - DEVICE_SHARE) / max(top + bottom, 1e-9))
        camera.fit_bounds(self.plotter.renderer, shown_bounds(self.plotter), top=top * shrink, bottom=bottom * shrink)

    def _on_interaction(self) -> None:
        self.view.set_draft(self.state.interaction == "design")
        if self._unbuilt and not self._skipped():
            self.redraw()           # the slider released behind another tab: its last design, once

    def _skipped(self) -> bool:
        """Whether a redraw is left out: a design slider moves while another tab hides this view
        in a shown window (the scene took 6-10 ms of the GUI thread a step, for nobody). It is
        built once the slider is released or the view shown, whichever comes first."""
        return self.state.interaction == "design" and self.window().isVisible() and not self.isVisible()

    def showEvent(self, event) -> None:   # noqa: N802 (Qt name)
        super().showEvent(event)
        if self._unbuilt:
            self.redraw()

    def redraw(self) -> None:
        if getattr(self.plotter, "_closed", False):
            return              # the window closed with a redraw still queued
        self._unbuilt = self._skipped()
        if self._unbuilt:
            return
        with self.view.quiet():
            self._build_scene()
        self.view.request_render()        # one render at the next paint, however many redraws

    def _build_scene(self) -> None:
        st = self.state
        report = st.pose_report
        if report is None:
            for glyph in scenes.GLYPH_ACTORS:
                scenes.hide_glyph(self.plotter, glyph)
            self.view.set_caption("")
            self._show_legend()
            return
        scale = self.scale = scenes.pose_scale(st.mechanism, report)
        scenes.draw_pose_scene(self.plotter, st.mechanism, report, st.glyphs, st.desired_force, scale)
        shown = scenes.glyph_drawn(self.plotter, "velocity_ellipsoid")
        caption = scenes.pose_caption(report, scale, scenes.velocity_scale(st.mechanism) if shown else None,
                                      scenes.inertia_text(self.plotter, st.mechanism, report, st.glyphs))
        forces = scenes.drawn_forces_text(self.plotter, st.mechanism, report, st.desired_force)
        if forces:
            caption += "\n" + forces
        caption += f"\n{report.loading.describe()}"      # the rating and gravity these glyphs are of
        self.view.set_caption(caption)
        height = self.view.caption_rect().height()
        legend_changed = self._show_legend()
        key = (st.preset.key, st.mechanism.task_dim)
        if key == self._camera_for and self.view.fitted and (legend_changed or height != self._caption_height):
            # Framed for the old legend and caption, which the new ones would cover: frame again
            # (a camera the user moved stays where it is).
            self.view.reset_camera()
        self._caption_height = height
        if key != self._camera_for:
            # Each device keeps its camera: the one it was left at, else a framing of it.
            if self._camera_for is not None:
                self._cameras[self._camera_for] = CameraState.of(self.plotter.renderer)
            kept = self._cameras.get(key)
            if kept is None:
                self.view.reset_camera()
            else:
                kept.apply(self.plotter.renderer)
                self.view.fitted = False
            self._camera_for = key

    def _legend_size(self, rows: int) -> tuple[float, float] | None:
        """The legend's width and height, shares of the view's; None: left out (too small to read)."""
        if not rows:
            return None
        w, h = (max(1.0, v) for v in self._full_size())
        want = np.array([LEGEND_WIDTH_PX, LEGEND_ROW_PX * rows], float)
        size = np.minimum(want, [0.9 * w, LEGEND_HEIGHT_SHARE * h])
        if np.min(size / want) < LEGEND_MIN_SCALE:
            return None
        return float(size[0] / w), float(size[1] / h)

    def _legend_height(self, rows: int) -> float:
        """The legend's height, a share of the view's (0: no legend)."""
        size = self._legend_size(rows)
        return 0.0 if size is None else size[1]

    def _full_size(self) -> tuple[float, float]:
        """The view's render pixels at full size: the legend keeps its size through a draft
        (whose renderer has half the pixels, where the same pixel sizes doubled its share)."""
        ratio = self.view.devicePixelRatioF()
        return self.view.width() * ratio, self.view.height() * ratio

    def _resized(self) -> None:
        """A new view size: the legend keeps its size in pixels (or is left out of a view too
        small for it); the caption was laid out for the size already (``PlotterWidget``).

        (A device switch resizes the view two or three times as the docks fit their new contents.)"""
        if self._legend_rows is not None:
            self._place_legend(self._legend_rows)
        self._caption_height = self.view.caption_rect().height()

    def _show_legend(self) -> bool:
        """The legend of the glyphs drawn now, laid out anew only when that set changes; whether it did."""
        rows = scenes.legend_rows(self.plotter, self.state.mechanism.joint_names)
        if rows == self._legend_rows:
            return False
        self._legend_rows = rows
        self._place_legend(rows)
        return True

    def _place_legend(self, rows) -> None:
        """The legend of ``rows`` at ``LEGEND_LOC``, ``_legend_size`` (none in a view too small for it),
        painted by the view over its frame (pyvista's ``add_legend(..., loc=LEGEND_LOC, border=0.05)``
        box)."""
        size = self._legend_size(len(rows))
        if size is None:
            self.view.set_legend((), None)
            return
        x, y, _ = map_loc_to_pos(LEGEND_LOC, size, border=0.05)
        self.view.set_legend(rows, (x, y, *size))

    def close_plotter(self) -> None:
        self.view.close_plotter()
