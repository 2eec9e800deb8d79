"""The 3D workspace view: the map revolved into a volume, cut by a plane or as iso-surfaces."""
from __future__ import annotations

from PySide6.QtWidgets import QComboBox, QHBoxLayout, QLabel, QVBoxLayout, QWidget

from app.scenes import WORKSPACE_MODES as MODES  # noqa: F401 (re-exported)
from app.scenes import draw_workspace

from .plotter_widget import PlotterWidget


class WorkspaceView(QWidget):
    """Shows ``state.current`` as a 3D volume; redrawn only for full maps and while visible."""

    def __init__(self, state, parent=None) -> None:
        super().__init__(parent)
        self.state = state
        self.mode = QComboBox()
        self.mode.addItems(MODES)
        self.mode.setToolTip("Cut the revolved workspace with a draggable plane, or show iso-surfaces.")
        bar = QHBoxLayout()
        bar.addWidget(QLabel("Show:"))
        bar.addWidget(self.mode)
        bar.addStretch(1)
        # Off-screen VTK painted as an image (see ``plotter_widget``).
        self.view = PlotterWidget(self)
        self.plotter = self.view.plotter
        self.plotter.set_background("white")
        self.plotter.add_axes()
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addLayout(bar)
        layout.addWidget(self.view)
        self._drawn = None
        self.mode.currentTextChanged.connect(lambda _: self.redraw(force=True))
        state.mapChanged.connect(self.redraw)
        state.quantityChanged.connect(self.redraw)

    def showEvent(self, event) -> None:   # noqa: N802 (Qt name)
        super().showEvent(event)
        self.redraw()

    def redraw(self, force: bool = False) -> None:
        st = self.state
        slot = st.current
        # Leave out what is not seen: no volume while hidden, none for coarse drag maps.
        if slot is None or not self.isVisible() or slot.stage != "full" or st.quantity not in slot.map.values:
            return
        key = (slot.generation, st.quantity, self.mode.currentText())
        if key == self._drawn and not force:
            return
        draw_workspace(self.plotter, slot.map, st.quantity, st.mechanism, self.mode.currentText(), interactive=True)
        if self._drawn is None or self._drawn[0] is None:
            self.plotter.reset_camera()
        self._drawn = key
        self.view.request_render()

    def close_plotter(self) -> None:
        self.view.close_plotter()
