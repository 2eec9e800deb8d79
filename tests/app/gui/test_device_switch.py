"""A device switch (issue 21 sec. 0): the old parameter panel is freed, and a quantity the new
device cannot compute falls back to one it can, with a word in the status bar, not an error."""
from __future__ import annotations

import collections

from PySide6.QtWidgets import QApplication, QMessageBox

from metrics.quantities import QUANTITIES, available_quantities

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


def test_a_device_without_the_shown_quantity_falls_back_and_says_so(make_window, waits, qtbot):
    window = make_window("inverse3_prototype", longest=SMALL)
    box = window.quantity_box
    box.setCurrentIndex(box.findData("spatial_resolution"))
    waits.full(window)
    assert window.state.quantity == "spatial_resolution"
    assert window.load_device("woodenhaptics")          # joint sensors not modelled: no spatial resolution
    waits.full(window)
    qtbot.wait(50)
    st = window.state
    assert st.quantity == "isotropic_force" and "isotropic_force" in st.current.map.values
    assert window.last_error is None, window.last_error
    assert not [w for w in QApplication.topLevelWidgets() if isinstance(w, QMessageBox) and w.isVisible()]
    message = window.statusBar().currentMessage()
    assert message == "WoodenHaptics cannot compute spatial resolution: the map shows max. isotropic force", message
    # The list offers only what the device can compute, the fallback selected.
    listed = tuple(box.itemData(i) for i in range(box.count()))
    assert listed == available_quantities(st.mechanism) and "spatial_resolution" not in listed
    assert box.currentData() == "isotropic_force" and box.currentText() == QUANTITIES["isotropic_force"].label


def test_turning_the_sensors_off_takes_spatial_resolution_off_the_list(make_window, waits, qtbot):
    window = make_window("haply_2diy", longest=SMALL)
    box = window.quantity_box
    box.setCurrentIndex(box.findData("spatial_resolution"))
    waits.full(window)
    window.param_panel.choices["joint_sensors"].setCurrentText("none")
    waits.full(window)
    qtbot.wait(50)
    assert window.state.quantity == "isotropic_force" and window.last_error is None, window.last_error
    assert "spatial_resolution" not in [box.itemData(i) for i in range(box.count())]
    assert window.statusBar().currentMessage().startswith("this design cannot compute spatial resolution")
    window.param_panel.choices["joint_sensors"].setCurrentText("given")     # back on the list, not chosen
    qtbot.waitUntil(lambda: box.findData("spatial_resolution") >= 0, timeout=5_000)
    assert box.currentData() == "isotropic_force"
