"""A device switch (issue 21 sec. 0): the old parameter panel is freed."""
from __future__ import annotations

import collections

from PySide6.QtWidgets import QApplication

SMALL = 41      # points along the longer map axis


def widget_census() -> tuple[int, int, collections.Counter]:
    """(all widgets, top-level widgets, count by class) of the application."""
    widgets = QApplication.allWidgets()
    return len(widgets), len(QApplication.topLevelWidgets()), collections.Counter(type(w).__name__ for w in widgets)


def test_switching_devices_leaves_no_old_parameter_panel_alive(make_window, qtbot):
    """Counted after each switch while Qt is driven by ``processEvents`` (as a script or a soak
    drives it): the old panel was left to ``deleteLater``, which waits for an event loop to return
    to the level it was called from, and each switch to the Inverse3 left 135 widgets (24 rows)
    and two top-level windows behind."""
    window = make_window("inverse3_prototype", longest=SMALL)
    tour = ["fivebar_singh", "inverse3_prototype", "woodenhaptics"] * 4
    seen: dict[str, list] = collections.defaultdict(list)
    for key in tour:
        assert window.load_device(key), key
        for _ in range(5):
            QApplication.processEvents()
        seen[key].append(widget_census())
    # Flat from the second visit of each device on (the first may build a popup or a cache once).
    for key, visits in seen.items():
        totals = [(total, top) for total, top, _ in visits[1:]]
        grown = visits[-1][2] - visits[1][2]
        assert len(set(totals)) == 1, (key, totals, dict(grown))
    rows = window.param_panel.rows
    alive = widget_census()[2]["ParameterRow"]
    assert alive == len(rows), (alive, len(rows))
