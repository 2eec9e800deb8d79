"""Edit > Undo / Redo, the unsaved-changes prompt and sessions, in the real window under Xvfb.

A slider drag is one undo step from press to release; a device switch is undone with the
design it left; the menu names the step in display units. With ``ask_to_save`` (as
``run_app`` builds the window) a modified design is not dropped without asking on close or on
a device switch: the tests answer the patched ``QMessageBox.question``. A session saved,
everything changed, and the session opened again gives back the same state; ``isoforce figure
--session`` draws it.
"""
from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QApplication, QMessageBox

import app.gui.file_actions as file_actions
from app.cli import main as cli_main
from app.gui.views.camera import CameraState, orbit
from resources import load_preset

SMALL = 41          # points along the longer map axis: fast maps


def press(qtbot, window, key, modifier=Qt.KeyboardModifier.NoModifier) -> None:
    window.activateWindow()
    qtbot.waitUntil(window.isActiveWindow, timeout=5000)
    qtbot.keyClick(QApplication.focusWidget() or window, key, modifier)


def drag(row, steps) -> None:
    """A slider drag as the mouse makes it: pressed, moved through ``steps``, released."""
    row.slider.setSliderDown(True)          # sliderPressed
    for step in steps:
        row.slider.setValue(step)           # valueChanged while down: one edit per position
    row.slider.setSliderDown(False)         # sliderReleased


def gear_ratio(window, index: int = 0) -> float:
    return dict((info.name, v) for info, v in window.state.mechanism.parameter_table())["gear_ratios"][index]


def test_a_drag_is_one_undo_step_named_in_the_menu_and_undone_by_the_keys(waits, make_window, qtbot):
    window = make_window("inverse3_prototype", longest=SMALL)
    st = window.state
    start = st.mechanism
    assert not window.undo_action.isEnabled() and window.undo_action.text() == "&Undo"
    assert not window.isWindowModified() and "[*]" in window.windowTitle()
    row = window.param_panel.rows[("gear_ratios", 0)]
    first = row.slider.value()
    drag(row, range(first + 5, first + 60, 5))                 # 11 positions
    assert len(st.history.undo_steps) == 1
    moved = gear_ratio(window)
    assert moved > 6.875
    assert window.undo_action.isEnabled()
    text = window.undo_action.text()
    assert text.startswith("&Undo gear_ratios 6.875 -> ") and text.endswith(" (theta_0)"), text
    assert math.isclose(float(text.split(" -> ")[1].split()[0]), moved, rel_tol=1e-3)
    assert window.isWindowModified()
    # A typed value is one more step.
    window.param_panel.rows[("proximal_length", -1)].spin.setValue(150.0)
    assert len(st.history.undo_steps) == 2 and window.undo_action.text() == "&Undo proximal_length 140 -> 150 mm"

    press(qtbot, window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)            # Ctrl+Z
    assert window.param_panel.rows[("proximal_length", -1)].value() == 140.0
    press(qtbot, window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert st.mechanism == start and not window.isWindowModified()
    assert window.param_panel.rows[("gear_ratios", 0)].value() == 6.875
    assert not window.undo_action.isEnabled() and window.redo_action.text().startswith("&Redo gear_ratios 6.875 -> ")
    waits.full(window)                                         # the undone design's map, computed again
    assert st.current.mechanism == start
    press(qtbot, window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier)
    assert gear_ratio(window) == moved and window.isWindowModified()
    waits.full(window)


def test_a_device_switch_is_undone_with_the_design_it_left(waits, make_window, qtbot):
    window = make_window("fivebar_singh", longest=SMALL)
    st = window.state
    window.param_panel.rows[("gear_ratios", 1)].spin.setValue(12.0)
    edited = st.mechanism
    window.param_panel.presetChosen.emit("novint_falcon")      # the device list (no prompt: ask_to_save off)
    assert st.preset.key == "novint_falcon" and not window.isWindowModified()
    assert window.undo_action.text() == "&Undo device Five-bar (Singh et al.) -> Novint Falcon"
    waits.full(window)
    window.undo_action.trigger()
    assert st.preset.key == "fivebar_singh" and st.mechanism == edited
    assert window.param_panel.preset_box.currentData() == "fivebar_singh"
    assert window.param_panel.rows[("gear_ratios", 1)].value() == 12.0
    waits.full(window)
    assert st.current.mechanism == edited
    window.redo_action.trigger()
    assert st.preset.key == "novint_falcon"
    waits.full(window)


@pytest.fixture
def answer(monkeypatch):
    """``answer.next = QMessageBox.StandardButton.X``: what the patched prompt answers; ``answer.asked`` its texts."""
    class Answer:
        next = QMessageBox.StandardButton.Cancel
        asked: list[str] = []

        @classmethod
        def question(cls, parent, title, text, buttons, default):
            assert buttons & QMessageBox.StandardButton.Save and buttons & QMessageBox.StandardButton.Discard \
                and buttons & QMessageBox.StandardButton.Cancel
            cls.asked.append(text)
            return cls.next

    Answer.asked = []
    monkeypatch.setattr(file_actions.QMessageBox, "question", Answer.question)
    return Answer


def test_a_modified_design_is_not_dropped_without_asking(waits, make_window, qtbot, answer, monkeypatch, tmp_path):
    window = make_window("fivebar_singh", longest=SMALL)
    window.ask_to_save = True                                  # as run_app builds it
    st = window.state
    assert window.may_drop_design("closing") and answer.asked == []      # unmodified: nothing to ask
    window.param_panel.rows[("proximal", -1)].spin.setValue(110.0)
    assert window.isWindowModified()

    # Cancel: the window stays, the device stays (the list shows it).
    answer.next = QMessageBox.StandardButton.Cancel
    assert not window.close() and window.isVisible()
    assert "Five-bar (Singh et al.) has changed" in answer.asked[-1]
    window.param_panel.preset_box.setCurrentIndex(window.param_panel.preset_box.findData("novint_falcon"))
    window.param_panel.presetChosen.emit("novint_falcon")
    assert st.preset.key == "fivebar_singh" and window.param_panel.preset_box.currentData() == "fivebar_singh"
    assert len(answer.asked) == 2

    # Save: a file dialog, the design written, no longer modified; then the switch goes ahead.
    target = tmp_path / "mine.toml"
    monkeypatch.setattr(file_actions.QFileDialog, "getSaveFileName", lambda *a, **k: (str(target), ""))
    answer.next = QMessageBox.StandardButton.Save
    window.param_panel.presetChosen.emit("novint_falcon")
    assert target.exists() and st.preset.key == "novint_falcon"
    saved = load_preset(str(target))
    assert saved.mechanism == load_preset("fivebar_singh").mechanism.replace_display(proximal=110.0)

    # Discard on close: the window closes.
    window.undo_action.trigger()                               # back to the five-bar, modified (110 mm)
    assert window.isWindowModified()
    answer.next = QMessageBox.StandardButton.Discard
    asked = len(answer.asked)
    assert window.close() and len(answer.asked) == asked + 1
    window.ask_to_save = False                                 # (qtbot closes it again at teardown)


def test_a_session_round_trip_gives_back_the_state_and_figure_draws_it(waits, make_window, qtbot, tmp_path,
                                                                        capsys):
    window = make_window("fivebar_singh", longest=SMALL)
    st = window.state
    window.param_panel.rows[("gear_ratios", 0)].spin.setValue(13.0)
    window.pin_reference()
    window.param_panel.rows[("proximal", -1)].spin.setValue(115.0)
    window.on_quantity("condition_number")
    st.set_overlay("bands")
    st.set_glyph("force_ellipsoid", True)
    st.set_glyph("sphere", False)
    st.set_compare_mode("difference")
    st.set_pose((0.01, 0.16))
    st.set_desired_force((1.5, -0.5))
    waits.full(window)
    orbit(window.pose_view.plotter.renderer, np.array([0.0, 0.0, 0.0]), 60.0, -25.0)
    expected = dict(mechanism=st.mechanism, reference=st.reference_mechanism, quantity=st.quantity,
                    overlay=st.overlay, glyphs=st.glyphs, mode=st.compare_mode, pose=st.pose,
                    force=st.desired_force, camera=CameraState.of(window.pose_view.plotter.renderer))
    path = tmp_path / "s.toml"
    window.save_session(path)
    assert not window.isWindowModified()
    text = tomllib.loads(path.read_text())
    assert text["design"] == {"preset": "fivebar_singh", "values": {"proximal": 115.0, "gear_ratios": [13.0, 10.0]}}
    assert text["view"]["quantity"] == "condition_number" and "camera" in text

    # Change everything.
    window.load_device("inverse3_prototype")
    st.set_quantity("isotropic_force")
    waits.full(window)
    assert st.reference_mechanism is None and st.preset.key == "inverse3_prototype"

    assert window.open_session(path)
    waits.full(window)
    assert st.preset.key == "fivebar_singh" and st.mechanism == expected["mechanism"]
    assert st.reference_mechanism == expected["reference"] and st.reference_preset is None
    assert (st.quantity, st.overlay, st.glyphs, st.compare_mode) == (expected["quantity"], expected["overlay"],
                                                                     expected["glyphs"], expected["mode"])
    assert np.allclose(st.pose, expected["pose"], rtol=1e-12) and st.desired_force == expected["force"]
    assert window.quantity_box.currentData() == "condition_number" and window.overlay_actions["bands"].isChecked()
    camera = CameraState.of(window.pose_view.plotter.renderer)
    for a, b in zip(vars(camera).values(), vars(expected["camera"]).values()):
        assert np.allclose(a, b, rtol=1e-9, atol=1e-12)
    assert not window.isWindowModified()
    assert window.undo_action.text().startswith("&Undo device ")        # opening it is one undoable step

    out = tmp_path / "from_session.png"
    capsys.readouterr()
    assert cli_main(["figure", "--session", str(path), "--view", "map", "--resolution", "30", "--out", str(out)]) == 0
    assert out.stat().st_size > 0 and f"wrote {out}" in capsys.readouterr().out


def test_a_bad_session_gets_one_error_naming_file_and_key_and_changes_nothing(make_window, tmp_path):
    window = make_window("fivebar_singh", longest=SMALL)
    st = window.state
    before = (st.preset, st.mechanism, st.quantity)
    bad = tmp_path / "bad.toml"
    bad.write_text('version = 1\n[design]\npreset = "fivebar_singh"\n[view]\nquantity = "colour"\n')
    assert not window.open_session(bad)
    assert window.last_error.startswith("session 'bad.toml': key 'view.quantity': unknown map quantity 'colour'")
    assert (st.preset, st.mechanism, st.quantity) == before
    window.error_box.close()


def test_a_session_keeps_the_colour_range_of_a_box_maps_plane(waits, make_window, qtbot, tmp_path):
    """The Falcon's 3D box map shown on one plane coloured over the whole volume: saved, changed
    back to the plane's own range, opened again, the volume's range is back (file, control, bar)."""
    window = make_window("novint_falcon", longest=12)
    view = window.map_view
    assert view.colour_range == "plane"
    view.slice_controls.colours.setCurrentIndex(view.slice_controls.colours.findData("volume"))
    path = tmp_path / "falcon.toml"
    window.save_session(path)
    plane = tomllib.loads(path.read_text())["view"]["plane"]
    assert plane["colour_range"] == "volume" and plane["axis"] == window.state.slice_axis
    view.set_colour_range("plane")
    qtbot.waitUntil(lambda: "colours: this plane" in view.picture.bar.label, timeout=5000)
    assert window.open_session(path)
    waits.full(window)
    assert view.colour_range == "volume" and view.slice_controls.colours.currentText() == "whole volume"
    qtbot.waitUntil(lambda: "colours: whole volume" in view.picture.bar.label, timeout=5000)
    assert window.session().colour_range == "volume"


def test_a_session_keeps_a_fitted_map_range(waits, make_window, qtbot, tmp_path):
    """View > Fit map to workspace, saved in the session (``[view.map]``), comes back on open after
    a device switch dropped it; the maps are then computed over it."""
    window = make_window("inverse3_prototype", longest=SMALL)
    st = window.state
    own = st.preset.grid
    window.param_panel.rows[("proximal_length", -1)].spin.setValue(250.0)
    window.save_session(tmp_path / "own.toml")            # the preset's own range is not repeated
    assert "map" not in tomllib.loads((tmp_path / "own.toml").read_text())["view"]
    with qtbot.waitSignal(window.map_fitter.done, timeout=30_000):
        window.map_fitter.start()
    fitted = st.preset.grid
    assert fitted != own
    waits.full(window)
    path = tmp_path / "fitted.toml"
    window.save_session(path)
    table = tomllib.loads(path.read_text())["view"]["map"]
    assert table["axes"] == list(fitted.axes) and table["resolution"] == list(fitted.resolution)
    assert np.allclose(table["upper"], np.array(fitted.upper) * 1e3, rtol=1e-15)

    window.load_device("fivebar_singh")
    window.load_device("inverse3_prototype")
    waits.full(window)
    assert st.preset.grid == own                       # a device loaded anew has its preset's range
    assert window.open_session(path)
    waits.full(window)
    grid = st.preset.grid
    # m -> mm -> m: two roundings, each within eps/2 relative, so within eps together (2 eps bounds it).
    eps = np.finfo(float).eps
    assert grid.axes == fitted.axes and grid.resolution == fitted.resolution
    assert np.allclose(grid.lower, fitted.lower, rtol=2 * eps, atol=0)
    assert np.allclose(grid.upper, fitted.upper, rtol=2 * eps, atol=0)
    assert st.current.map.grid.lower == grid.lower and st.stale is None
    assert not window.isWindowModified()


def test_a_held_slider_keeps_undo_enabled_and_names_its_step_at_the_release(make_window):
    """While a design slider is held only the actions' enabled states follow each step; the
    release names the whole drag's step in the menu (``menus._follow_history``)."""
    window = make_window("inverse3_prototype", longest=SMALL)
    st = window.state
    assert not window.undo_action.isEnabled()
    window.on_parameter_edited("gear_ratios", (7.0, 5.957, 5.957), True)
    assert window.undo_action.isEnabled() and st.history.can_undo()
    window.on_parameter_edited("gear_ratios", (7.5, 5.957, 5.957), True)
    window.on_parameter_edited("gear_ratios", (7.5, 5.957, 5.957), False)       # released where it is
    assert st.interaction is None and len(st.history.undo_steps) == 1
    assert window.undo_action.text() == f"&Undo {st.history.undo_text()}"
    assert window.undo_action.text().startswith("&Undo gear_ratios 6.875 -> 7.5")
    assert window.undo_action.toolTip() == f"Undo {st.history.undo_text()}"
