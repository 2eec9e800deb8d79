"""The preset ``[spec]`` table (resources.spec_table): parsing, errors naming file and key, saving."""
from __future__ import annotations

import pytest

from resources.schema import PresetError, parse_preset_text, preset_to_toml

BASE = """
name = "five-bar"
mechanism = "fivebar"
[map]
axes = ["x", "y"]
lower = [-100.0, 50.0]
upper = [100.0, 200.0]
resolution = [11, 11]
"""


def test_spec_table_parses_and_survives_a_save():
    p = parse_preset_text(BASE + '[spec]\nmass_matrix = [[0.2, 0.01], [0.01, 0.3]]\nminimum_forces = [0.02, 0.03]\n'
                                 'where = "measured"\n', "t.toml")
    assert p.spec.mass_matrix == ((0.2, 0.01), (0.01, 0.3))
    assert p.spec.minimum_forces == (0.02, 0.03) and p.spec.where == "measured"
    again = parse_preset_text(preset_to_toml(p), "again.toml")
    assert again.spec == p.spec


def test_a_preset_without_spec_has_none():
    assert parse_preset_text(BASE, "t.toml").spec is None


@pytest.mark.parametrize("body, key", [
    ("speed = 1", "spec.speed"),
    ("mass_matrix = [[1.0, 0.0]]", "spec.mass_matrix"),
    ("mass_matrix = [[1.0, 2.0], [2.0, 1.0]]", "spec.mass_matrix"),          # not positive definite
    ("mass_matrix = [[1.0, 0.1], [0.0, 1.0]]", "spec.mass_matrix"),          # not symmetric
    ("minimum_forces = [0.1, -0.1]", "spec.minimum_forces"),
    ("minimum_forces = [0.1]", "spec.minimum_forces"),
    ("where = 3", "spec.where"),
])
def test_bad_spec_entries_name_the_file_and_key(body, key):
    with pytest.raises(PresetError, match=rf"preset 'bad.toml': key '{key}'"):
        parse_preset_text(BASE + "[spec]\n" + body + "\n", "bad.toml")
