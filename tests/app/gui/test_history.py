"""The undo history and the modified mark, in the Qt-free model (no display, no Qt)."""
from __future__ import annotations

import subprocess
import sys

from app.gui.history import Design, History, edit_label
from app.gui.model import AppModel
from resources import load_preset


def test_the_history_and_session_files_import_no_qt():
    # In a fresh interpreter: a GUI test in this one may have imported Qt already.
    code = ("import sys, app.gui.history, app.gui.model, app.files.session; "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('PySide6', 'pyvista', 'vtk', 'matplotlib')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_a_slider_drag_is_one_step_named_in_display_units():
    model = AppModel(load_preset("inverse3_prototype"))
    start = model.mechanism
    model.set_interaction("design")                       # pressed
    for ratio in (7.0, 9.5, 12.0, 13.75):                 # moved: one design per pixel
        model.set_mechanism(model.mechanism.replace_display(gear_ratios=(ratio, 5.957, 5.957)))
    model.set_interaction(None)                           # released
    assert len(model.history.undo_steps) == 1
    assert model.history.undo_text() == "gear_ratios 6.875 -> 13.75 (theta_0)"
    assert model.modified
    assert model.undo()
    assert model.mechanism == start and not model.modified
    assert model.history.redo_text() == "gear_ratios 6.875 -> 13.75 (theta_0)"
    assert model.redo()
    assert model.mechanism.parameter_table()[6][1] == (13.75, 5.957, 5.957)


def test_edits_are_steps_and_a_new_edit_drops_the_redo():
    model = AppModel(load_preset("fivebar_singh"))
    a = model.mechanism
    b = a.replace_display(proximal=110.0)
    c = b.replace_display(distal=170.0)
    model.set_mechanism(b)
    model.set_mechanism(c)
    assert [s.label for s in model.history.undo_steps] == ["proximal 100 -> 110 mm", "distal 150 -> 170 mm"]
    model.undo()
    assert model.mechanism == b and model.history.can_redo()
    model.set_mechanism(b.replace_display(half_base=40.0))
    assert not model.history.can_redo()
    model.undo()
    model.undo()
    assert model.mechanism == a and not model.history.can_undo() and not model.undo()


def test_a_device_switch_is_undone_with_its_design():
    five = load_preset("fivebar_singh")
    model = AppModel(five)
    edited = five.mechanism.replace_display(gear_ratios=(12.0, 10.0))
    model.set_mechanism(edited)
    falcon = load_preset("novint_falcon")
    model.set_preset(falcon)
    assert not model.modified                             # a device just loaded is on disk
    assert model.history.undo_text() == "device Five-bar (Singh et al.) -> Novint Falcon"
    model.undo()
    assert model.preset is five and model.mechanism == edited
    assert model.modified                                 # (the design last loaded is the Falcon)
    model.redo()
    assert model.preset is falcon and model.mechanism == falcon.mechanism


def test_a_drag_back_to_its_start_leaves_no_step():
    history = History()
    p = load_preset("fivebar_singh")
    a, b = Design(p, p.mechanism), Design(p, p.mechanism.replace_display(proximal=120.0))
    history.record(a, b, merge=True)
    history.record(b, a, merge=True)
    history.close()
    assert not history.can_undo()
    assert edit_label(a, b) == "proximal 100 -> 120 mm"
