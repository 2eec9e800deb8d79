"""The 2D map view: a heat map of the chosen quantity on the slice, with a colour bar.

Matplotlib on a Qt canvas. The image artist is kept and only its data and norm change on an
update, so a new map costs one canvas draw, not a rebuilt figure. A click on the map moves
the device there (``poseRequested``). With a pinned reference the view shows the reference
and the current map side by side, or their difference.
"""
from __future__ import annotations

import numpy as np
from matplotlib import colors
from matplotlib.backends.backend_qtagg import FigureCanvasQTAgg
from matplotlib.figure import Figure
from PySide6.QtCore import Signal
from PySide6.QtWidgets import QVBoxLayout, QWidget

from metrics.quantities import QUANTITIES

from ..figures import draw_map


class MapView(QWidget):
    """Shows ``state.current`` (and ``state.reference``) for ``state.quantity``."""

    #: Emitted with a task-space point (m) when the user clicks inside the map.
    poseRequested = Signal(object)
    #: What this view needs computed, beyond its quantity.
    NEEDS: tuple[str, ...] = ()

    def __init__(self, state, parent=None) -> None:
        super().__init__(parent)
        self.state = state
        self.figure = Figure(figsize=(6, 5), layout="compressed")
        self.canvas = FigureCanvasQTAgg(self.figure)
        self.canvas.setToolTip("Click a point to move the device there.")
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.canvas)
        self._axes: list = []
        self._artists: list = []
        self._layout_key = None
        self._pose_marker = None
        self.canvas.mpl_connect("button_press_event", self._on_click)
        for signal in (state.mapChanged, state.quantityChanged, state.referenceChanged, state.compareModeChanged):
            signal.connect(self.redraw)
        state.poseChanged.connect(self._draw_pose_marker)

    def needs(self) -> set[str]:
        return {self.state.quantity}

    # -- drawing ---------------------------------------------------------------------------
    def panels(self) -> list[tuple[str, object, np.ndarray | None]]:
        """What to draw: (title, map, values override) per axes."""
        st = self.state
        current = st.current.map if st.current is not None else None
        reference = st.reference.map if st.reference is not None else None
        q = st.quantity
        if reference is None or current is None or q not in reference.values:
            return [("", current, None)] if current is not None else []
        if st.compare_mode == "difference" and reference.grid == current.grid and not QUANTITIES[q].categorical:
            diff = np.where(current.feasible & reference.feasible, current.values[q] - reference.values[q], np.nan)
            return [("current - reference", current, diff)]
        return [("reference", reference, None), ("current", current, None)]

    def redraw(self) -> None:
        panels = self.panels()
        q = self.state.quantity
        key = (q, tuple(title for title, _, _ in panels), tuple(m.grid for _, m, _ in panels))
        if key != self._layout_key:
            self.figure.clear()
            # Two panels stack when the view is taller than wide, else sit side by side.
            tall = self.canvas.height() >= self.canvas.width()
            rows, cols = (len(panels), 1) if tall else (1, len(panels))
            self._axes = [self.figure.add_subplot(rows, cols, i + 1) for i in range(len(panels))]
            self._artists = [None] * len(panels)
            self._pose_marker = None
            self._layout_key = key
        for i, (title, wmap, override) in enumerate(panels):
            self._artists[i] = draw_map(self.figure, self._axes[i], wmap, q, self.state.preset,
                                        values=override, title=title, artists=self._artists[i])
        self._draw_pose_marker()

    def _draw_pose_marker(self) -> None:
        pose = self.state.pose
        plots = self._axes
        if pose is None or not plots or self.state.current is None:
            self.canvas.draw_idle()
            return
        grid = self.state.current.map.grid
        names = self.state.mechanism.task_names
        px, py = (pose[names.index(a)] * 1e3 for a in grid.axes[:2])
        if self._pose_marker is not None:
            for line in self._pose_marker:
                line.set_data([px], [py])
        else:
            self._pose_marker = [ax.plot([px], [py], "+", color="red", markersize=16, mew=2.5,
                                         label="_pose")[0] for ax in plots]
        self.canvas.draw_idle()

    # -- interaction -----------------------------------------------------------------------
    def _on_click(self, event) -> None:
        if event.inaxes is None or event.xdata is None or self.state.current is None:
            return
        if event.inaxes not in self._axes:
            return
        self.poseRequested.emit(self.point_at(event.xdata, event.ydata))

    def point_at(self, x_mm: float, y_mm: float) -> tuple[float, ...]:
        """The task point (m) under map coordinates (mm), fixed coordinates filled in."""
        grid = self.state.current.map.grid
        names = self.state.mechanism.task_names
        fixed = dict(grid.fixed)
        point = []
        for name in names:
            if name == grid.axes[0]:
                point.append(x_mm / 1e3)
            elif name == grid.axes[1]:
                point.append(y_mm / 1e3)
            else:
                point.append(fixed[name])
        return tuple(point)

    def data_to_widget(self, x_mm: float, y_mm: float, panel: int = -1) -> tuple[int, int]:
        """Widget pixel (for tests and scripts) of a map point in the given panel."""
        ax = self._axes[panel]
        self.canvas.draw()
        px, py = ax.transData.transform((x_mm, y_mm))
        ratio = self.canvas.device_pixel_ratio or 1.0
        return int(round(px / ratio)), int(round(self.canvas.height() - py / ratio))
