"""The commented example device files (docs/examples, one per mechanism family) load and are current."""
from __future__ import annotations

from pathlib import Path

import pytest

from kinematics import MECHANISMS
from resources import PresetError, load_preset
from scripts import example_devices

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"


def test_every_family_has_an_example_and_the_files_are_what_the_script_writes():
    assert example_devices.main(["--check"]) == 0
    assert sorted(p.stem for p in EXAMPLES.glob("*.toml")) == sorted(MECHANISMS)


@pytest.mark.parametrize("kind", sorted(MECHANISMS))
def test_an_example_loads_as_its_family_with_the_presets_numbers(kind):
    preset = load_preset(str(EXAMPLES / f"{kind}.toml"))
    assert preset.kind == kind
    shipped = load_preset(example_devices.example_text(kind).split("preset '")[1].split("'")[0])
    assert preset.mechanism == shipped.mechanism and preset.grid == shipped.grid


def test_a_changed_example_with_a_bad_key_names_the_file_and_the_key(tmp_path):
    text = (EXAMPLES / "fivebar.toml").read_text(encoding="utf-8").replace("distal = ", "distel = ", 1)
    path = tmp_path / "my_device.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(PresetError, match=r"my_device\.toml.*distel"):
        load_preset(str(path))
