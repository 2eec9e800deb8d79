"""``--set`` errors name the bad parameter, in the unit the person typed, and only its value."""
from __future__ import annotations

import pytest

from app.cli import main
from resources import load_preset


def _error(capsys, *argv: str) -> str:
    assert main(list(argv)) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.strip().splitlines()) == 1, err
    return err


def _typed(preset_key: str, name: str) -> str:
    """The preset's own value of scalar parameter ``name`` in its display unit, as a person would type it."""
    mech = load_preset(preset_key).mechanism
    return next(f"{value:g}" for info, value in mech.parameter_table() if info.name == name)


@pytest.mark.parametrize("key, bad, unit, good", [
    ("novint_falcon", "knee_min=0", "deg", ("upper_arm", "knee_max")),
    ("novint_falcon", "upper_arm=-5", "mm", ("knee_min", "parallelogram")),
    ("fivebar_singh", "proximal=-5", "mm", ("distal",)),
    ("inverse3_prototype", "min_link_spread=-3", "deg", ("proximal_length",)),
])
def test_the_error_names_the_bad_value_in_its_typed_unit_and_no_other_value(capsys, key, bad, unit, good):
    name, value = bad.split("=")
    others = [f"{g}={_typed(key, g)}" for g in good]
    for sets in ([bad], [*others[:1], bad, *others[1:]]):
        err = _error(capsys, "pose", key, "--set", *sets)
        assert f"{name} = {value} {unit}" in err, err
        # The model's SI unit ("(given in rad)", "in m") is not what was typed.
        assert "given in" not in err and " rad" not in err.replace(name, ""), err
        for g in good:
            assert f"{g} =" not in err, err
