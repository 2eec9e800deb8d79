"""Fixtures for the GUI tests: the real ``MainWindow`` on a virtual X server.

pytest-xvfb starts Xvfb for the session (the Qt ``offscreen`` platform cannot host the VTK
render window, DESIGN.md "Tests"); pytest-qt's ``qtbot`` drives the window. Every window
keeps its settings in ``tmp_path`` and is closed at teardown, which shuts its scheduler and
its VTK plotters down before Qt deletes the widgets.

The windows measure no map rates (``MainWindow.measure_rates``): a slider step always previews
a coarse map and refines it, however fast this machine computed the maps (tests never depend
on timings); ``test_map_schedule.py`` sets the rates the path is chosen from.

Most tests shrink the preset's map grid (``make_window(..., longest=N)``) so a full map takes
milliseconds; the tests that check paper figures or the coarse-then-full refinement use the
preset's own grid.
"""
from __future__ import annotations

from types import SimpleNamespace

import pytest

#: How long a full map may take to reach the screen in a test (1000 x 1000 Inverse3 maps
#: take about a second on two cores; this is a hang guard, not a timing assertion).
FULL_MAP_TIMEOUT_MS = 60_000


def shrink_grid(grid, longest: int):
    """``grid`` with at most ``longest`` points along its longer axis, aspect kept."""
    top = max(grid.resolution)
    if top <= longest:
        return grid
    return grid.with_resolution(tuple(max(3, round(n * longest / top)) for n in grid.resolution))


def widget_rgb(widget):
    """A widget as painted (``grab``), ndarray (height, width, 3) of uint8."""
    import numpy as np
    from PySide6.QtGui import QImage
    image = widget.grab().toImage().convertToFormat(QImage.Format.Format_RGB888)
    w, h = image.width(), image.height()
    rows = np.frombuffer(bytes(image.constBits()), np.uint8).reshape(h, image.bytesPerLine())
    return rows[:, :3 * w].reshape(h, w, 3)


def map_ready(window) -> bool:
    """The full map of the window's current design is on screen and nothing is being computed."""
    st = window.state
    return (st.current is not None and st.current.stage == "full" and not st.busy
            and st.current.mechanism == st.mechanism)


def wait_full_map(qtbot, window, timeout: int = FULL_MAP_TIMEOUT_MS) -> None:
    qtbot.waitUntil(lambda: map_ready(window), timeout=timeout)


def wait_reference_map(qtbot, window, timeout: int = FULL_MAP_TIMEOUT_MS) -> None:
    st = window.state
    qtbot.waitUntil(lambda: st.reference is not None and st.reference.stage == "full"
                    and st.reference.mechanism == st.reference_mechanism, timeout=timeout)


@pytest.fixture
def waits(qtbot):
    """``waits.ready(window)``, ``waits.full(window)``, ``waits.reference(window)`` for the tests."""
    return SimpleNamespace(ready=map_ready,
                           full=lambda window, timeout=FULL_MAP_TIMEOUT_MS: wait_full_map(qtbot, window, timeout),
                           reference=lambda window, timeout=FULL_MAP_TIMEOUT_MS: wait_reference_map(
                               qtbot, window, timeout))


@pytest.fixture
def make_window(qtbot, tmp_path, monkeypatch):
    """Factory: ``make_window(device, longest=None, settings_file=None, wait=True)``.

    ``longest`` shrinks every preset the window loads (``load_preset`` inside
    ``app.gui.main_window`` and ``app.gui.file_actions``) to that many points along the longer
    map axis. The window is shown, exposed and, with ``wait``, has its full map. Settings default to ``tmp_path``.
    """
    import app.gui.file_actions as file_actions
    import app.gui.main_window as mw
    from resources import load_preset

    # Nothing may reach the real settings of whoever runs the tests.
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "xdg-config"))
    monkeypatch.setenv("ISOFORCE_SETTINGS", str(tmp_path / "env-settings.ini"))

    def make(device: str | None = "fivebar_singh", *, longest: int | None = None, settings_file=None,
             wait: bool = True, size: tuple[int, int] | None = (1400, 900)):
        if longest is not None:
            def shrunk(key):
                preset = load_preset(key)
                return preset.replace(grid=shrink_grid(preset.grid, longest))
            # The window's first device (main_window) and the devices loaded later (file_actions).
            for module in (mw, file_actions):
                monkeypatch.setattr(module, "load_preset", shrunk)
        window = mw.MainWindow(device=device, settings_file=settings_file or tmp_path / "settings.ini")
        # No map rates measured: every slider step previews coarse, then refines (``MainWindow.rates``),
        # whatever this machine's speed; tests of the measured path set ``window.rates`` themselves.
        window.measure_rates = False
        # qtbot closes (closeEvent: scheduler and plotters shut down) and deletes it at teardown.
        qtbot.addWidget(window)
        if size is not None:
            window.resize(*size)
        window.show()
        qtbot.waitExposed(window)
        if wait:
            wait_full_map(qtbot, window)
        return window

    return make
