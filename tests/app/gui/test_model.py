"""``app.gui.model.AppModel`` without Qt: every change emits its event once, after the change.

A fresh interpreter checks that the model imports no Qt (``tests/app/test_jobs.py``).
"""
from __future__ import annotations

import pytest

from app.gui.model import AppModel, Event, MapSlot
from metrics.workspace import compute_map
from resources import load_preset


class Log:
    """Connected to every event of a model: remembers (name, args, what the model held then)."""

    def __init__(self, model: AppModel) -> None:
        self.seen: list[tuple[str, tuple]] = []
        self.model = model
        for name, event in model.events.all().items():
            event.connect(lambda *args, n=name: self.seen.append((n, args)))

    def names(self) -> list[str]:
        return [n for n, _ in self.seen]

    def clear(self) -> None:
        self.seen.clear()


@pytest.fixture(scope="module")
def presets():
    return load_preset("fivebar_singh"), load_preset("inverse3_prototype")


@pytest.fixture
def model(presets):
    return AppModel(presets[0])


def slot(mech, preset, quantities=("isotropic_force",), stage="full", generation=1) -> MapSlot:
    grid = preset.grid.with_resolution((9, 5))
    return MapSlot(compute_map(mech, grid, quantities), mech, stage, generation)


def test_an_event_calls_its_callbacks_in_order_and_can_be_disconnected():
    event, calls = Event("x"), []
    first = event.connect(lambda *a: calls.append(("first", a)))
    event.connect(lambda *a: calls.append(("second", a)))
    event.emit(1, "b")
    event.disconnect(first)
    event.emit(2)
    assert calls == [("first", (1, "b")), ("second", (1, "b")), ("second", (2,))]


def test_a_new_model_holds_the_presets_device_pose_and_no_map(model, presets):
    preset = presets[0]
    assert model.mechanism == preset.mechanism and model.pose == preset.pose
    assert model.desired_force == (0.0,) * preset.mechanism.task_dim
    assert model.current is None and model.reference is None and model.stale is None
    assert not model.busy and model.compare_mode == "side"


def test_setters_emit_once_after_the_change_and_not_at_all_for_no_change(model, presets):
    log = Log(model)
    mech = model.mechanism.replace_display(**{"distal": 120.0})
    seen_inside = []
    model.events.mechanism.connect(lambda: seen_inside.append(model.mechanism))
    model.set_mechanism(mech)
    model.set_mechanism(mech)                 # the same again: no event
    assert log.names() == ["mechanism", "history"] and seen_inside == [mech]     # (an undo step)
    log.clear()
    model.set_pose((0.01, 0.14))
    model.set_pose([0.01, 0.14])
    model.set_desired_force((1, 0))
    model.set_quantity("condition_number")
    model.set_quantity("condition_number")
    model.set_glyph("force_ellipsoid", True)
    model.set_glyph("force_ellipsoid", True)
    model.set_compare_mode("difference")
    model.set_busy(True)
    model.set_busy(True)
    model.set_progress(0.5)
    assert log.seen == [("pose", ()), ("pose", ()), ("quantity", ()), ("glyphs", ()), ("compare_mode", ()),
                        ("busy", (True,)), ("progress", (0.5,))]
    assert model.pose == (0.01, 0.14) and model.desired_force == (1.0, 0.0)
    assert "force_ellipsoid" in model.glyphs


def test_bad_glyph_and_compare_mode_raise_naming_the_choices(model):
    with pytest.raises(ValueError, match="unknown glyph 'halo'; known: links, polytope"):
        model.set_glyph("halo", True)
    with pytest.raises(ValueError, match="compare mode must be 'side' or 'difference', got 'overlay'"):
        model.set_compare_mode("overlay")


def test_stale_says_why_the_map_is_older_than_the_state_and_its_event_fires_on_change(model, presets):
    preset = presets[0]
    log = Log(model)
    model.set_current_map(slot(model.mechanism, preset))
    assert model.stale is None and log.names() == ["map"]
    log.clear()
    model.set_mechanism(model.mechanism.replace_display(**{"distal": 120.0}))
    assert model.stale == "parameters" and log.seen == [("mechanism", ()), ("stale", ("parameters",)),
                                                         ("history", ())]
    log.clear()
    model.set_current_map(slot(model.mechanism, preset, generation=2))
    assert model.stale is None and log.seen == [("map", ()), ("stale", (None,))]
    log.clear()
    model.set_quantity("condition_number")      # not in the map yet
    assert model.stale == "quantity" and log.seen == [("quantity", ()), ("stale", ("quantity",))]


def test_a_new_preset_resets_maps_and_emits_in_the_widgets_order(model, presets):
    fivebar, inverse3 = presets
    model.set_current_map(slot(model.mechanism, fivebar))
    model.pin_reference()
    assert model.reference is model.current and model.reference_mechanism == model.mechanism
    log = Log(model)
    model.set_preset(inverse3)
    assert log.names() == ["preset", "mechanism", "pose", "reference", "slice", "loading", "history"]
    assert model.mechanism == inverse3.mechanism and model.current is None and model.reference is None
    assert model.desired_force == (0.0, 0.0, 0.0)


def test_pinning_keeps_the_map_only_if_it_is_of_the_current_design(model, presets):
    preset = presets[0]
    model.set_current_map(slot(model.mechanism, preset))
    model.set_mechanism(model.mechanism.replace_display(**{"distal": 120.0}))
    model.pin_reference()
    assert model.reference_mechanism == model.mechanism and model.reference is None
    model.set_reference_map(slot(model.mechanism, preset, generation=3))
    assert model.reference.generation == 3
    model.clear_reference()
    assert model.reference is None and model.reference_mechanism is None


def test_the_gui_imports_no_command_line_module():
    """The two clients do not know each other: the whole window module loads no ``app.cli``."""
    import subprocess
    import sys
    from pathlib import Path

    code = ("import sys, app.gui.main_window; "
            "bad = sorted(m for m in sys.modules if m == 'app.launch' or m.split('.')[:2] == ['app', 'cli']); "
            "assert not bad, bad; print('ok')")
    result = subprocess.run([sys.executable, "-c", code], cwd=Path(__file__).resolve().parents[3],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0 and result.stdout.strip() == "ok", result.stderr


def test_a_device_that_cannot_compute_the_quantity_falls_back_and_says_so(presets):
    model = AppModel(presets[1], quantity="spatial_resolution")     # the Inverse3 has joint sensors
    log = Log(model)
    model.set_preset(load_preset("woodenhaptics"))                   # not modelled: no spatial resolution
    assert model.quantity == "isotropic_force"
    assert log.names() == ["preset", "quantity", "mechanism", "pose", "reference", "slice", "loading", "history",
                           "notice"]
    assert log.seen[-1] == ("notice", ("WoodenHaptics cannot compute spatial resolution: "
                                       "the map shows max. isotropic force",))
    log.clear()
    model.set_preset(presets[1])                                     # it has isotropic force: no notice
    assert model.quantity == "isotropic_force" and "notice" not in log.names()


def test_a_design_whose_sensors_are_turned_off_falls_back_from_spatial_resolution():
    model = AppModel(load_preset("haply_2diy"), quantity="spatial_resolution")
    log = Log(model)
    model.set_mechanism(model.mechanism.replace(joint_sensors="none"))
    assert model.quantity == "isotropic_force"
    assert log.names() == ["quantity", "mechanism", "history", "notice"]
    assert log.seen[-1][1][0].startswith("this design cannot compute spatial resolution")
