"""``isoforce map --help`` says which device families have a singularity map, as the models do."""
from __future__ import annotations

import re

import numpy as np
import pytest

from app.cli import main
from kinematics.registry import MECHANISMS
from metrics.quantities import available_quantities
from resources import list_presets, load_preset


def _quantity_help(capsys) -> str:
    assert main(["map", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())       # argparse wraps lines
    return text.rsplit("--quantity Q", 1)[1].split("--out FILE", 1)[0]     # the option, not the usage line


def test_the_help_names_every_family_whose_models_compute_singularity_and_no_other(capsys):
    scope = re.search(r"\(singularity: ([^)]*)\)", _quantity_help(capsys))
    assert scope, "the --quantity help says which devices have a singularity map"
    named = {kind for kind in MECHANISMS if re.search(rf"\b{kind}\b", scope.group(1))}
    expected = {kind for kind, cls in MECHANISMS.items() if "singularity" in available_quantities(cls())}
    assert named == expected and {"fivebar", "delta", "serial_rrr", "inoue"} <= expected


@pytest.mark.parametrize("key", [key for key in list_presets()
                                 if "singularity" in available_quantities(load_preset(key).mechanism)])
def test_a_singularity_map_is_made_for_every_preset_of_those_families(key, capsys, tmp_path):
    out = tmp_path / "s.npz"
    assert main(["map", key, "--quantity", "singularity", "--out", str(out), "--resolution", "6"]) == 0, \
        capsys.readouterr().err
    with np.load(out) as data:
        assert list(data["quantities"]) == ["singularity"]
