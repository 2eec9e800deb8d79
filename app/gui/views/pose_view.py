"""The 3D pose view: the mechanism at the selected pose with its force glyphs (PyVista)."""
from __future__ import annotations

from PySide6.QtWidgets import QVBoxLayout, QWidget

from app import scenes

from .plotter_widget import PlotterWidget


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
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.view)
        self._camera_for = None
        state.poseReportChanged.connect(self.redraw)

    def redraw(self) -> None:
        if getattr(self.plotter, "_closed", False):
            return              # the window closed with a redraw still queued
        self._build_scene()
        self.view.request_render()        # one render at the next paint, however many redraws

    def _build_scene(self) -> None:
        st = self.state
        report = st.pose_report
        if report is None:
            for glyph in scenes.GLYPH_ACTORS:
                scenes.hide_glyph(self.plotter, glyph)
            return
        scale = scenes.force_scale(st.mechanism)
        scenes.draw_pose_scene(self.plotter, st.mechanism, report, st.glyphs, st.desired_force, scale)
        caption = scenes.pose_caption(report, scale, scenes.velocity_scale(st.mechanism))
        caption += f"\n{report.loading.describe()}"      # the rating and gravity these glyphs are of
        corner = self.plotter.actors.get("pose_caption")
        if corner is not None and hasattr(corner, "set_text"):
            corner.set_text("lower_right", caption)     # in place: a new text actor renders 2x slower
        else:
            self.plotter.add_text(caption, position="lower_right", font_size=8, color="black",
                                  name="pose_caption", render=False)
        key = (st.preset.key, st.mechanism.task_dim)
        if key != self._camera_for:
            # Frame the device once per preset; later redraws keep the user's camera.
            scenes.frame_pose_camera(self.plotter, st.mechanism)
            self._camera_for = key

    def close_plotter(self) -> None:
        self.view.close_plotter()
