"""The 3D pose view: the mechanism at the selected pose with its force glyphs (PyVista)."""
from __future__ import annotations

from PySide6.QtWidgets import QVBoxLayout, QWidget
from pyvistaqt import QtInteractor

from .. import scenes


class PoseView(QWidget):
    """Draws ``state.pose_report`` with the glyphs in ``state.glyphs``."""

    def __init__(self, state, parent=None) -> None:
        super().__init__(parent)
        self.state = state
        self.plotter = QtInteractor(self)
        self.plotter.set_background("white")
        self.plotter.add_axes()
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.plotter)
        self._camera_for = None
        state.poseReportChanged.connect(self.redraw)

    def redraw(self) -> None:
        st = self.state
        report = st.pose_report
        if report is None:
            for glyph in scenes.GLYPH_ACTORS:
                scenes.hide_glyph(self.plotter, glyph)
            self.plotter.render()
            return
        scale = scenes.force_scale(st.mechanism)
        scenes.draw_pose_scene(self.plotter, st.mechanism, report, st.glyphs, st.desired_force, scale)
        self.plotter.add_text(scenes.pose_caption(report, scale), position="lower_right", font_size=8,
                              color="black", name="pose_caption")
        key = (st.preset.key, st.mechanism.task_dim)
        if key != self._camera_for:
            # Frame the device once per preset; later redraws keep the user's camera.
            scenes.frame_pose_camera(self.plotter, st.mechanism)
            self._camera_for = key
        self.plotter.render()

    def close_plotter(self) -> None:
        self.plotter.close()
