"""A modified design outlives the app: autosaved as a session beside the settings file (in the
test's ``tmp_path``: ``make_window`` points ``ISOFORCE_SETTINGS``, ``XDG_CONFIG_HOME`` and the
window's settings file there) and restored at the next start, as an undoable edit marked unsaved,
with a status-bar note. A design saved, undone back to the one loaded, or discarded at the close
prompt leaves no autosave; an unreadable one is moved aside and said."""
from __future__ import annotations

import re

from PySide6.QtWidgets import QMessageBox

import app.gui.file_actions as file_actions
from app.files.session import read_session
from app.gui.main_window import settings_path
from resources import load_preset

SMALL = 41          # points along the longer map axis: fast maps
WRITTEN_MS = 5000   # the autosave is written once the design rests (AUTOSAVE_DELAY_MS): a hang guard


def test_an_unsaved_design_is_restored_at_the_next_start_and_undone_to_its_preset(make_window, qtbot, tmp_path):
    window = make_window("fivebar_singh", longest=SMALL)
    autosave = window.autosave_path()
    # Beside the settings (the test's: ISOFORCE_SETTINGS is tmp_path's too, as settings_path() says).
    assert autosave == tmp_path / "settings.autosave.toml" and settings_path().parent == tmp_path
    assert not autosave.exists()
    window.param_panel.rows[("gear_ratios", 1)].spin.setValue(12.0)
    window.on_quantity("condition_number")
    edited = window.state.mechanism
    qtbot.waitUntil(autosave.exists, timeout=WRITTEN_MS)
    assert read_session(autosave).mechanism == edited
    # Undone back to the design loaded: nothing to restore; redone: autosaved again.
    window.undo_action.trigger()
    qtbot.waitUntil(lambda: not autosave.exists(), timeout=WRITTEN_MS)
    window.redo_action.trigger()
    qtbot.waitUntil(autosave.exists, timeout=WRITTEN_MS)
    window.close()              # no prompt (ask_to_save off): what a crash or a kill leaves too
    assert autosave.exists()

    again = make_window(None, longest=SMALL)          # the next start: no device asked for
    st = again.state
    assert st.preset.key == "fivebar_singh" and st.mechanism == edited and st.quantity == "condition_number"
    assert again.isWindowModified() and again.windowTitle().startswith("Five-bar (Singh et al.)")
    assert re.match(r"Restored the unsaved design of Five-bar \(Singh et al\.\) from \d{4}-\d\d-\d\d \d\d:\d\d "
                    r"\(gear_ratios 10 -> 12 \(theta_2\)\): Edit > Undo goes back to the preset", again.notice)
    assert again.statusBar().currentMessage() == again.notice
    assert again.param_panel.rows[("gear_ratios", 1)].value() == 12.0
    assert again.undo_action.text() == "&Undo gear_ratios 10 -> 12 (theta_2)"
    again.undo_action.trigger()
    assert st.mechanism == st.preset.mechanism and not again.isWindowModified()
    qtbot.waitUntil(lambda: not autosave.exists(), timeout=WRITTEN_MS)


def test_a_design_saved_or_discarded_at_the_prompt_is_not_restored(make_window, qtbot, tmp_path, monkeypatch):
    window = make_window("fivebar_singh", longest=SMALL)
    autosave = window.autosave_path()
    window.param_panel.rows[("proximal", -1)].spin.setValue(110.0)
    qtbot.waitUntil(autosave.exists, timeout=WRITTEN_MS)
    window.save_session(tmp_path / "mine.toml")          # saved: no longer modified
    qtbot.waitUntil(lambda: not autosave.exists(), timeout=WRITTEN_MS)
    window.param_panel.rows[("proximal", -1)].spin.setValue(115.0)
    qtbot.waitUntil(autosave.exists, timeout=WRITTEN_MS)
    window.ask_to_save = True                             # as run_app builds it
    monkeypatch.setattr(file_actions.QMessageBox, "question", lambda *a: QMessageBox.StandardButton.Discard)
    assert window.close() and not autosave.exists()       # the user said so: not offered again
    window.ask_to_save = False                            # (qtbot closes it again at teardown)

    again = make_window(None, longest=SMALL)
    assert again.state.preset.key == "fivebar_singh" and not again.isWindowModified()
    assert again.state.mechanism == load_preset("fivebar_singh").mechanism and again.notice is None


def test_an_unreadable_autosave_is_moved_aside_and_said(make_window, tmp_path):
    autosave = tmp_path / "settings.autosave.toml"
    autosave.write_text('version = 1\n[design]\npreset = "no_such_device"\n')
    window = make_window(None, longest=SMALL)
    assert not window.isWindowModified() and not autosave.exists()
    aside = tmp_path / "settings.autosave.unreadable.toml"
    assert aside.exists()
    assert window.notice.startswith(f"The unsaved design autosaved in {aside} could not be restored: "
                                    "session 'settings.autosave.toml': key 'design.preset': ")
