"""The first window fits the screen it opens on: 1280 x 720 and 1920 x 1080.

Xvfb's screen is 1920 x 1080 here; a smaller screen is stood in for by its available area
(``QScreen.availableGeometry``, what the window sizes itself by). On each, the window, its
docks, the status bar with its progress bar and the map's canvas lie on the screen, and the
3D views' tab titles are whole (no scroll arrows, no "Workspace (").
"""
from __future__ import annotations

import pytest
from PySide6.QtCore import QRect
from PySide6.QtGui import QScreen

from app.gui.screen_fit import DEFAULT_SIZE, NARROW_SCREEN_PX


def global_rect(widget) -> QRect:
    return QRect(widget.mapToGlobal(widget.rect().topLeft()), widget.size())


@pytest.mark.parametrize("screen", [(1280, 720), (1366, 768), (1920, 1080)])
def test_the_first_window_and_everything_in_it_fit_the_screen(make_window, monkeypatch, screen):
    area = QRect(0, 0, *screen)
    monkeypatch.setattr(QScreen, "availableGeometry", lambda self: QRect(area))
    window = make_window("inverse3_prototype", longest=60, size=None)
    frame = window.frameGeometry()
    assert area.contains(frame), (frame, area)
    assert (frame.width(), frame.height()) == (min(DEFAULT_SIZE[0], screen[0]), min(DEFAULT_SIZE[1], screen[1]))
    shown = [window.param_dock, window.map_view.canvas, window.tabs, window.statusBar(), window.progress]
    visible_docks = [d for d in (window.stats_dock, window.optimize_dock) if not d.visibleRegion().isEmpty()]
    for widget in shown + visible_docks:
        assert widget.isVisible() and area.contains(global_rect(widget)), (widget, global_rect(widget), area)
    # The statistics stay one click away: a tab of the left column on a narrow screen, a dock beside it else.
    narrow = screen[0] < NARROW_SCREEN_PX
    assert (window.stats_dock in window.tabifiedDockWidgets(window.param_dock)) == narrow
    bar = window.tabs.tabBar()
    assert bar.sizeHint().width() <= window.tabs.width()
    assert all(bar.tabRect(i).width() >= bar.fontMetrics().horizontalAdvance(bar.tabText(i))
               for i in range(bar.count()))


def test_a_saved_geometry_larger_than_the_screen_shrinks_to_it(make_window, monkeypatch, tmp_path):
    settings = tmp_path / "big.ini"
    first = make_window("inverse3_prototype", longest=40, settings_file=settings, size=(1900, 1060))
    first.close()                         # saves its geometry
    area = QRect(0, 0, 1280, 720)
    monkeypatch.setattr(QScreen, "availableGeometry", lambda self: QRect(area))
    second = make_window("inverse3_prototype", longest=40, settings_file=settings, size=None)
    assert area.contains(second.frameGeometry())
