"""The main window's layout: its place on the screen, the statistics dock's width, and the
map's width while two maps are compared (a mixin of ``MainWindow``).

Qt only in what it calls on the window; the decisions about the screen are ``screen_fit``'s.
"""
from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QApplication

from app.gui.screen_fit import DEFAULT_SIZE, fitted_rect, narrow_screen
from app.gui.views.map_view import SIDE_BY_SIDE_PX

#: Width the map view takes (from the 3D views beside it) while two maps are compared side by side.
COMPARE_MAP_PX = 720
#: Width the 3D views keep while two maps are compared (their tab bar and a usable view).
MIN_3D_PX = 280
#: How much wider than its columns need the statistics dock may stay before it is narrowed to
#: them, px: a few pixels more or less per new map must not move the map view at every slider step.
STATS_DOCK_SLACK_PX = 24


class WindowLayout:
    """``MainWindow``'s layout methods; the window holds ``param_dock``, ``stats_dock``,
    ``optimize_dock``, ``stats_panel``, ``splitter``, ``settings`` and ``state``."""

    def _restore_layout(self) -> None:
        screen = (self.screen() or QApplication.primaryScreen()).availableGeometry()
        available = (screen.x(), screen.y(), screen.width(), screen.height())
        geometry = self.settings.value("geometry")
        if geometry is not None:
            self.restoreGeometry(geometry)
            frame = self.frameGeometry()
            wanted, at = (frame.width(), frame.height()), (frame.x(), frame.y())
        else:
            wanted, at = DEFAULT_SIZE, None
        # The frame inside the screen: its decorations taken from the size the contents get.
        x, y, width, height = fitted_rect(available, wanted, at)
        extra = self.frameGeometry().size() - self.geometry().size()
        self.resize(width - extra.width(), height - extra.height())
        self.move(x, y)
        layout = self.settings.value("window_state")
        if layout is not None:
            self.restoreState(layout)
        left = Qt.DockWidgetArea.LeftDockWidgetArea
        if narrow_screen(screen.width()) and self.dockWidgetArea(self.stats_dock) != left:
            # Three columns of docks leave the map and 3D views too little room: one column of tabs.
            for dock in (self.stats_dock, self.optimize_dock):
                self.addDockWidget(left, dock)
                self.tabifyDockWidget(self.param_dock, dock)
            self.param_dock.raise_()
        sizes = self.settings.value("splitter")
        if sizes is not None:
            self.splitter.restoreState(sizes)

    def _fit_stats_dock(self, width: int) -> None:
        """The statistics dock sized to its columns (``width``, ``StatsPanel.widthNeeded``).

        It grows with them anyway (the panel's minimum). It is narrowed to them when they
        shrink by more than ``STATS_DOCK_SLACK_PX`` (the reference columns hidden, another
        device), unless the user has resized the dock by hand since its last fit. The first
        fit of a session overrides a saved layout's width (the columns decide); a floating
        dock is left alone. No narrower than the docks tabbed with it allow (Optimize).
        """
        dock = self.stats_dock
        if dock.isFloating():
            return
        fitted, now = self._stats_dock_fit, dock.width()
        if fitted is not None and (abs(now - fitted) > 1 and now > width       # resized by hand
                                   or 0 <= now - width <= STATS_DOCK_SLACK_PX):
            return
        # The panel's new minimum through the dock to the window's layout first: resizeDocks
        # clamps to the minimum it knows, which a pending layout request may still hold wider.
        for layout in (self.stats_panel.layout(), dock.layout(), self.layout()):
            layout.activate()
        self.resizeDocks([dock], [width], Qt.Orientation.Horizontal)
        # The width it gets: the tab group's widest minimum may keep it wider.
        self._stats_dock_fit = max([width] + [d.minimumSizeHint().width() for d in self.tabifiedDockWidgets(dock)])

    def _fit_comparison(self) -> None:
        """Side by side needs width: while comparing, the map view takes it from the 3D views.

        The splitter's sizes before are restored when the comparison ends (reference cleared,
        difference mode); the user can drag the splitter at any time.
        """
        st = self.state
        comparing = st.reference_mechanism is not None and st.compare_mode == "side"
        sizes = self.splitter.sizes()
        total = sum(sizes)
        # The 3D views keep room for their tabs; where the rest cannot hold two panels side by
        # side the maps stack, and taking the views' width would buy nothing.
        wide = min(total - MIN_3D_PX, COMPARE_MAP_PX)
        if comparing and self._sizes_before_compare is None and sizes[0] < wide and wide >= SIDE_BY_SIDE_PX:
            self._sizes_before_compare = sizes
            self.splitter.setSizes([wide, total - wide])
            self.statusBar().showMessage("Comparing side by side: the maps take width from the 3D views; "
                                         "drag the splitter to bring it back.", 8000)
        elif not comparing and self._sizes_before_compare is not None:
            self.splitter.setSizes(self._sizes_before_compare)
            self._sizes_before_compare = None
