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
    and two top-level windows behind. Now each family's panel is kept, once, and shown again."""
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
    # The rows alive are one panel per family shown (kept to be shown again: a switch back builds
    # nothing), not one per switch.
    panel = window.param_panel
    assert len(panel.rows) and len(panel._bodies) == len(set(tour))      # three devices of three families
    alive = widget_census()[2]["ParameterRow"]
    assert alive == sum(len(body.rows) for body in panel._bodies.values()), alive


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


def _row_state(row) -> tuple:
    """What a row shows and how its slider moves: value, span, step, decimals and lower bound."""
    return (row.value(), row.lo, row.hi, row.step, row.slider.maximum(), row.slider.value(),
            row.spin.decimals(), row.spin.minimum())


def test_a_family_shown_before_reuses_its_rows_with_the_new_devices_values(make_window, waits):
    """The five-bar and the Haply 2DIY share a family: switching between them builds no row, and
    each reused row is what a row built for the new device's value shows (span, step, digits)."""
    from app.gui.widgets.parameter_panel import ParameterRow
    from resources import load_preset

    window = make_window("fivebar_singh", longest=SMALL)
    panel = window.param_panel
    first = dict(panel.rows)
    window.param_panel.rows[("proximal", -1)].spin.setValue(123.0)        # a changed design, left behind
    for key in ("haply_2diy", "fivebar_singh", "haply_2diy"):
        assert window.load_device(key)
        assert panel.rows == first                          # the same row objects, none built
        for info, value in load_preset(key).mechanism.parameter_table():
            if info.choices:
                assert panel.choices[info.name].currentText() == value
                continue
            for i, v in enumerate(value) if info.is_vector else [(-1, value)]:
                fresh = ParameterRow(v, info.unit, "", name=info.name)
                assert _row_state(panel.rows[(info.name, i)]) == _row_state(fresh), (key, info.name, i)
                fresh.deleteLater()
    waits.full(window)
    assert window.state.preset.key == "haply_2diy"


def test_a_new_familys_rows_are_built_out_of_sight_and_swapped_in_once(make_window, qtbot, monkeypatch):
    """A part of the build per turn of the event loop (here one parameter a part); meanwhile the
    last device's rows stay, greyed out, and the new ones are out of the layout until all built."""
    import app.gui.widgets.parameter_panel as parameter_panel
    window = make_window("fivebar_singh", longest=SMALL)
    panel = window.param_panel
    old = panel._shown
    monkeypatch.setattr(parameter_panel, "BUILD_SLICE_MS", 0.0)
    assert window.load_device("inoue_platform")
    new = panel._body
    assert new.pending and panel._shown is old and not old.widget.isEnabled()
    assert panel.layout().indexOf(new.widget) < 0 and not new.widget.isVisible()
    qtbot.waitUntil(lambda: not new.pending, timeout=10_000)
    assert panel._shown is new and new.widget.isVisible() and new.widget.isEnabled()
    assert panel.layout().indexOf(old.widget) < 0 and not old.widget.isVisible() and old.widget.isEnabled()
    # The glyphs were drawn for the new device a turn after the switch (``_defer_pose``).
    assert window._pose_for[1] == window.state.mechanism and window.state.pose_report is not None


def test_the_first_devices_rows_are_there_when_the_window_is_laid_out(make_window):
    """The first panel is built at once, before the window is shown: laid out around an empty
    panel, the design dock came out narrow and every slider was squeezed to its handle (~15 px)."""
    window = make_window("inverse3_prototype", longest=SMALL, size=(1280, 720))
    panel = window.param_panel
    assert not panel._body.pending and panel._shown is panel._body
    # A slider is dragged over its 100-odd steps: under 50 px it is a handle, not a slider.
    narrow = {key: row.slider.width() for key, row in panel.rows.items() if row.slider.width() < 50}
    assert not narrow, narrow
