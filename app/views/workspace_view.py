"""The 3D workspace view: the map revolved into a volume, cut by a plane or as iso-surfaces."""
from __future__ import annotations

import numpy as np
from PySide6.QtWidgets import QComboBox, QHBoxLayout, QLabel, QVBoxLayout, QWidget
from pyvistaqt import QtInteractor

from metrics.quantities import QUANTITIES

from .. import scenes

MODES = ("cut plane", "iso-surfaces")


def draw_workspace(plotter, workspace_map, quantity: str, mechanism, mode: str, *, interactive: bool) -> None:
    """Draw the workspace volume of ``quantity`` (shared by the app and ``isoforce figure``)."""
    plotter.clear_plane_widgets() if interactive else None
    plotter.remove_actor("workspace", reset_camera=False, render=False)
    plotter.remove_scalar_bar() if plotter.scalar_bars else None
    node = QUANTITIES[quantity]
    volume = scenes.workspace_volume(workspace_map, quantity, mechanism)
    title = node.label + (f" ({node.unit})" if node.unit else "")
    bar = {"title": title, "position_x": 0.15, "position_y": 0.03, "width": 0.7}
    args = dict(scalars=quantity, cmap="tab10" if node.categorical else "viridis",
                log_scale=quantity == "condition_number", scalar_bar_args=bar,
                name="workspace", reset_camera=False, render=False)
    if volume.n_cells == 0:
        return
    if mode == "iso-surfaces" and mechanism.task_dim == 3 and not node.categorical:
        lo, hi = np.nanpercentile(volume.point_data[quantity], [10, 90])
        surfaces = volume.cell_data_to_point_data().contour(isosurfaces=np.linspace(lo, hi, 4), scalars=quantity)
        if surfaces.n_points:
            plotter.add_mesh(surfaces, opacity=0.55, smooth_shading=True, **args)
        else:
            plotter.add_mesh(volume.outline(), color="black", name="workspace", render=False)
    elif mechanism.task_dim == 3:
        if interactive:
            plotter.add_mesh_clip_plane(volume, normal="-y", origin=(0.0, 0.0, 0.0), **args)
        else:
            plotter.add_mesh(volume.clip(normal="-y", origin=(0.0, 0.0, 0.0)), **args)
    else:
        plotter.add_mesh(volume, **args)


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
        self.plotter = QtInteractor(self)
        self.plotter.set_background("white")
        self.plotter.add_axes()
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addLayout(bar)
        layout.addWidget(self.plotter)
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
        self.plotter.render()

    def close_plotter(self) -> None:
        self.plotter.close()
