"""View > Fit map to workspace: the map's range fitted to the design's workspace, off the GUI thread.

``app.logic.map_range.fit_grid`` takes 10-250 ms (a 3D box searches ~10^4 points a round), so
it runs on a thread of its own; its result comes back through a queued signal and is applied
only if the design is still the one it was fitted for. Applying it replaces the preset's grid
(``AppModel.set_map_grid``) and asks for the maps anew.
"""
from __future__ import annotations

import threading

import shiboken6
from PySide6.QtCore import QObject, Signal

from app.logic.map_range import NoWorkspace, fit_grid


def range_text(grid, mechanism) -> str:
    """``"x 35 to 305 mm, z -110 to 410 mm"``: the fitted axes (lengths) in mm."""
    units = dict(zip(mechanism.task_names, mechanism.task_units))
    return ", ".join(f"{a} {lo * 1e3:g} to {hi * 1e3:g} mm"
                     for a, lo, hi in zip(grid.axes, grid.lower, grid.upper) if units.get(a) == "m")


class MapFitter(QObject):
    """Fits the window's map range to its design's workspace (``start``), then recomputes the maps."""

    #: (the design fitted, the grid or the ``NoWorkspace`` error), from the worker thread.
    fitted = Signal(object, object)
    #: The range was applied (or found to fit already): for tests and scripts.
    done = Signal()

    def __init__(self, window) -> None:
        super().__init__(window)
        self.window = window
        self.running = False
        self.fitted.connect(self._apply)

    def start(self) -> None:
        """Fit the map to the workspace of the design on screen (nothing if a fit is running)."""
        if self.running:
            return
        st = self.window.state
        self.running = True
        self.window.statusBar().showMessage("Fitting the map to the workspace...")
        threading.Thread(target=self._run, args=(st.mechanism, st.preset.grid), daemon=True,
                         name="isoforce-map-fit").start()

    def _run(self, mechanism, grid) -> None:
        try:
            result = fit_grid(mechanism, grid)
        except NoWorkspace as exc:
            result = exc
        if shiboken6.isValid(self):          # the window may have closed meanwhile
            self.fitted.emit(mechanism, result)

    def _apply(self, mechanism, result) -> None:
        self.running = False
        window, st = self.window, self.window.state
        bar = window.statusBar()
        if mechanism != st.mechanism:
            bar.showMessage("Not fitted: the design changed while its workspace was searched (fit again)", 8000)
        elif isinstance(result, Exception):
            bar.showMessage(f"Not fitted: {result}", 8000)
        elif result == st.preset.grid:
            bar.showMessage(f"The map already fits the workspace: {range_text(result, mechanism)}", 8000)
        else:
            st.set_map_grid(result)
            window.scheduler.cancel("current")
            window.request_map("coarse")
            window.request_map("full")
            if st.reference_mechanism is not None and st.reference_preset is None:
                window.request_map("full", tag="reference")      # a pinned design of this device
            bar.showMessage(f"Map fitted to the workspace: {range_text(result, mechanism)}", 8000)
        self.done.emit()
