"""The ``[spec]`` table's peak rating, control rate and physical damping (resources.spec_table).

Parsing, errors naming the file and the key, a save that keeps them, and the peak limits
against the continuous rating's own path (the mechanism's gear ratios and actuated joints).
"""
from __future__ import annotations

import numpy as np
import pytest

from resources import load_preset
from resources.schema import PresetError, parse_preset_text, preset_to_toml
from resources.spec_table import peak_torque_limits

BASE = """
name = "five-bar"
mechanism = "fivebar"
[parameters]
gear_ratios = [10.0, 12.0]
[map]
axes = ["x", "y"]
lower = [-100.0, 50.0]
upper = [100.0, 200.0]
resolution = [11, 11]
"""


def test_peak_rate_and_damping_parse_and_survive_a_save():
    p = parse_preset_text(BASE + "[spec]\npeak_motor_torques = [0.5, 0.25]\ncontrol_rate = 1000\n"
                                 "physical_damping = [0.1, 0.2]\n", "t.toml")
    assert p.spec.peak_motor_torques == (0.5, 0.25) and p.spec.control_rate == 1000.0
    assert p.spec.physical_damping == (0.1, 0.2)
    again = parse_preset_text(preset_to_toml(p), "again.toml")
    assert again.spec == p.spec


def test_peak_limits_take_the_gear_ratios_like_the_continuous_rating():
    p = parse_preset_text(BASE + "[spec]\npeak_motor_torques = [0.5, 0.25]\n", "t.toml")
    assert peak_torque_limits(p.spec, p.mechanism).tolist() == [5.0, 3.0]
    assert peak_torque_limits(None, p.mechanism) is None
    assert peak_torque_limits(parse_preset_text(BASE + "[spec]\nwhere = 'x'\n", "t.toml").spec, p.mechanism) is None


def test_peak_limits_of_the_prototype_are_its_actuated_joints():
    # Seven joint entries (as motor_torques); the passive roll q7 is dropped as torque_limits drops it.
    preset = load_preset("twin_pantograph_prototype")
    mech = preset.mechanism
    peak = peak_torque_limits(preset.spec, mech)
    assert mech.actuated == (0, 1, 2, 3, 4, 5)
    assert peak.tolist() == list(preset.spec.peak_motor_torques[:6])
    # Estimated stall torques k_m U / R from the datasheet constants in [source.lines].
    assert peak[0] == pytest.approx(30.2e-3 * 24 / 0.316, abs=0.005)        # RE 40 148877
    assert peak[1] == pytest.approx(0.0389 * 30 / 1.2, rel=1e-12)            # RE 35, RE_35.m
    assert np.all(peak > mech.torque_limits())
    prov = dict(preset.provenance)
    assert "peak_motor_torques" in prov["estimated"] and "stall" in prov["lines.peak_motor_torques"]
    assert preset.spec.control_rate == 1000.0 and "1KHz" in prov["lines.control_rate"]


def test_a_peak_rating_of_the_wrong_length_is_named_when_used():
    p = parse_preset_text(BASE + "[spec]\npeak_motor_torques = [0.5, 0.25, 0.1]\n", "t.toml")
    with pytest.raises(ValueError, match=r"\[spec\] peak_motor_torques must have 2 values"):
        peak_torque_limits(p.spec, p.mechanism)


@pytest.mark.parametrize("body, key", [
    ("peak_motor_torques = [0.5, -0.1]", "spec.peak_motor_torques"),
    ("peak_motor_torques = []", "spec.peak_motor_torques"),
    ("peak_motor_torques = 0.5", "spec.peak_motor_torques"),
    ("control_rate = 0", "spec.control_rate"),
    ("control_rate = 'fast'", "spec.control_rate"),
    ("control_rate = true", "spec.control_rate"),
    ("physical_damping = [0.1]", "spec.physical_damping"),
    ("physical_damping = [0.1, -0.2]", "spec.physical_damping"),
])
def test_bad_entries_name_the_file_and_key(body, key):
    with pytest.raises(PresetError, match=rf"preset 'bad.toml': key '{key}'"):
        parse_preset_text(BASE + "[spec]\n" + body + "\n", "bad.toml")
