"""Presets: every shipped one loads, round-trips through TOML, and bad files say where they are bad."""
from __future__ import annotations

import re
from importlib import resources as importlib_resources

import numpy as np
import pytest

from resources import (
    MECHANISMS,
    PresetError,
    list_presets,
    load_preset,
    parse_preset_text,
    preset_to_toml,
    read_preset_file,
)

SHIPPED = ("fivebar_singh", "inverse3_prototype", "inverse3_scenario2", "inverse3_scenario3")


def shipped_text(key: str) -> str:
    return importlib_resources.files("resources").joinpath("presets", f"{key}.toml").read_text(encoding="utf-8")


def test_the_issue_presets_are_shipped():
    assert set(SHIPPED) <= set(list_presets())


@pytest.mark.parametrize("key", list_presets())
def test_every_shipped_preset_loads_with_a_map_and_a_feasible_pose(key):
    preset = load_preset(key)
    assert preset.key == key and preset.name and preset.description
    mech = preset.mechanism
    assert isinstance(mech, tuple(MECHANISMS.values()))
    assert len(preset.grid.axes) in (2, 3) and min(preset.grid.resolution) >= 2
    assert preset.pose is not None
    q, ok = mech.inverse(np.array(preset.pose))
    assert bool(ok) and bool(mech.feasible(q, np.array(preset.pose)))


def test_paper_values_reach_the_models():
    i3 = load_preset("inverse3_prototype")
    assert i3.mechanism.params.gear_ratios == (6.875, 5.957, 5.957)
    assert i3.mechanism.params.proximal_length == 0.140 and i3.mechanism.params.distal_length == 0.165
    # The paper's slice: theta_0 = 0 plane y = 22.3 mm, x in [-50, 350], z in [-150, 500], 1000 x 1000.
    assert i3.grid.axes == ("x", "z") and i3.grid.resolution == (1000, 1000)
    assert i3.grid.lower == (-0.050, -0.150) and i3.grid.upper == (0.350, 0.500)
    assert dict(i3.grid.fixed) == {"y": pytest.approx(0.0223, abs=1e-15)}
    assert load_preset("inverse3_scenario2").mechanism.params.gear_ratios == (13.75, 5.957, 5.957)
    assert load_preset("inverse3_scenario3").mechanism.params.gear_ratios == (6.875, 11.914, 11.914)
    fb = load_preset("fivebar_singh").mechanism.params
    assert (fb.proximal, fb.distal, fb.half_base) == (0.10, 0.15, 0.03)


@pytest.mark.parametrize("key", list_presets())
def test_round_trip_through_toml_is_exact(key):
    preset = load_preset(key)
    again = parse_preset_text(preset_to_toml(preset), f"{key}.toml", key)
    assert again.mechanism == preset.mechanism          # params compared field by field, exactly
    assert again.grid == preset.grid
    assert again.pose == preset.pose
    assert (again.name, again.description, again.kind) == (preset.name, preset.description, preset.kind)


def test_round_trip_keeps_overridden_parameters(tmp_path):
    preset = load_preset("inverse3_prototype")
    changed = preset.replace(mechanism=preset.mechanism.replace_display(gear_ratios=(13.75, 5.957, 5.957),
                                                                          proximal_length=141.5))
    path = tmp_path / "mine.toml"
    path.write_text(preset_to_toml(changed), encoding="utf-8")
    loaded = read_preset_file(path)
    assert loaded.mechanism == changed.mechanism
    assert load_preset(str(path)).mechanism == changed.mechanism     # by path, as the CLI does


# -- malformed files: each names the file and the key ------------------------------------------
BASE = "inverse3_prototype"


def edited(pattern: str, replacement: str) -> str:
    """The shipped Inverse3 preset with one line changed (the pattern must match exactly once)."""
    text, count = re.subn(pattern, replacement, shipped_text(BASE), flags=re.MULTILINE)
    assert count == 1, f"pattern {pattern!r} matched {count} times"
    return text


MALFORMED = {
    # case: (TOML text, key the message must name, a phrase it must contain)
    "unknown top-level key": ("colour = 'blue'\n" + shipped_text(BASE), "colour", "not a preset key"),
    "unknown parameter": (edited(r"^body_height = 180.0$", "body_height = 180.0\nwheel_count = 4"),
                          "parameters.wheel_count", "not a parameter"),
    "vector too short": (edited(r"^gear_ratios = .*$", "gear_ratios = [13.75, 5.957]"),
                         "parameters.gear_ratios", "3"),
    "vector of strings": (edited(r"^gear_ratios = .*$", 'gear_ratios = ["a", "b", "c"]'),
                          "parameters.gear_ratios", "numbers"),
    "negative length": (edited(r"^proximal_length = .*$", "proximal_length = -140.0"),
                        "parameters.proximal_length", "in mm, got -140.0"),   # the value as typed
    "zero torque": (edited(r"^motor_torques = .*$", "motor_torques = [0.1, 0.0, 0.1]"),
                    "parameters.motor_torques", "positive"),
    "length as text": (edited(r"^distal_length = .*$", 'distal_length = "long"'),
                       "parameters.distal_length", "number"),
    "unknown map axis": (edited(r"^axes = .*$", 'axes = ["x", "w"]'), "map.axes", "'w'"),
    "repeated map axis": (edited(r"^axes = .*$", 'axes = ["x", "x"]'), "map.axes", "distinct"),
    "resolution 1": (edited(r"^resolution = .*$", "resolution = [1000, 1]"), "map.resolution", "got 1"),
    "resolution not integer": (edited(r"^resolution = .*$", "resolution = [1000, 10.5]"), "map.resolution",
                               "integers"),
    "empty range": (edited(r"^upper = .*$", "upper = [350.0, -150.0]"), "map.upper", "exceed"),
    "missing fixed coordinate": (edited(r"^fixed = .*$", ""), "map.fixed", "y"),
    "pose of wrong length": (edited(r"^at = .*$", "at = [170.0, 230.0]"), "pose.at", "3"),
    "unknown mechanism": (edited(r'^mechanism = .*$', 'mechanism = "no_such_kind"'), "mechanism", "'no_such_kind'"),
    "missing map": (shipped_text(BASE).split("[map]")[0], "map", "table"),
    "bad base branch": (edited(r"^body_height = 180.0$", 'body_height = 180.0\nbase_branch = "sideways"'),
                        "parameters.base_branch", "sideways"),
}


@pytest.mark.parametrize("case", MALFORMED, ids=list(MALFORMED))
def test_malformed_preset_names_file_and_key(tmp_path, case):
    text, key, phrase = MALFORMED[case]
    path = tmp_path / "broken_device.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(PresetError) as info:
        read_preset_file(path)
    message = str(info.value)
    assert f"preset '{path}'" in message
    assert f"key '{key}'" in message
    assert phrase in message
    assert "\n" not in message                  # one line, ready for the command line


def test_bad_toml_names_the_file_and_the_line(tmp_path):
    path = tmp_path / "syntax.toml"
    path.write_text(shipped_text(BASE).replace("proximal_length = 140.0", "proximal_length = 140.0 mm"),
                    encoding="utf-8")
    with pytest.raises(PresetError, match=r"preset '.*syntax\.toml': is not valid TOML: .*line \d+"):
        read_preset_file(path)


def test_missing_file_and_unknown_key_are_preset_errors(tmp_path):
    with pytest.raises(PresetError, match="nowhere.toml"):
        load_preset(str(tmp_path / "nowhere.toml"))
    with pytest.raises(PresetError, match=r"unknown device 'inverse4'.*inverse3_prototype"):
        load_preset("inverse4")


def test_a_preset_that_is_not_utf8_names_its_file(tmp_path):
    """Before: a bare "'utf-8' codec can't decode byte 0xf6" with no file name."""
    from resources import read_preset_file
    path = tmp_path / "latin1.toml"
    path.write_bytes(shipped_text("fivebar_singh").replace('name = "', 'name = "K\u00f6rper ').encode("latin-1"))
    with pytest.raises(PresetError, match=r"latin1\.toml.*not UTF-8.*0xf6"):
        read_preset_file(path)


def test_an_edited_design_says_which_values_left_its_sources(tmp_path):
    """A file saved from an edited design (the app's Save device as, ``show --set``) keeps its sources
    and says which values they no longer describe; a second edit keeps the source's first value."""
    from resources.schema import parse_preset_text, preset_to_toml, with_changes

    preset = load_preset("inverse3_prototype")
    edited = with_changes(preset, preset.mechanism.replace_display(proximal_length=160.0))
    again = parse_preset_text(preset_to_toml(edited), "saved.toml", "saved")
    changed = {k: v for k, v in again.provenance if k.startswith("changed.")}
    assert changed == {"changed.proximal_length": "140 mm in the source above; now 160 mm"}
    assert {k: v for k, v in again.provenance if not k.startswith("changed.")} == dict(preset.provenance)
    twice = with_changes(again, again.mechanism.replace_display(proximal_length=170.0))
    assert dict(twice.provenance)["changed.proximal_length"] == "140 mm in the source above; now 170 mm"
    assert not any(k.startswith("changed.") for k, _ in with_changes(preset, preset.mechanism).provenance)
