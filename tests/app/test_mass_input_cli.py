"""Bad body input through the command line and presets (issue 22, sec. 6): one line naming the key,
exit code 2, nothing else printed."""
from __future__ import annotations

from pathlib import Path

import pytest

from app.cli import main

PRESETS = Path(__file__).resolve().parents[2] / "resources" / "presets"


def _run(capsys, *argv):
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


@pytest.mark.parametrize("argv, key", [
    (["pose", "fivebar_singh", "--set", "link_masses=-0.01,0.01,0.01,0.01"], "link_masses[proximal_1]"),
    (["pose", "phantom_premium_15", "--set", "link_masses=0,1,1,1,1"], "link_masses[a]"),
    (["pose", "fivebar_singh", "--set", "rotor_inertias=-1,70"], "rotor_inertias"),
])
def test_a_bad_mass_on_the_command_line_is_one_line_naming_it(capsys, argv, key):
    status, out, err = _run(capsys, *argv)
    assert status == 2 and out == ""
    assert err.count("\n") == 1 and key in err and "Traceback" not in err


@pytest.mark.parametrize("line, key", [
    ("link_masses = [0.013, 0.013, -0.02, 0.02]", "parameters.link_masses"),
    ("inertia_be = [100.0, 100.0, 300.0, 0.0, 0.0, 0.0]", "triangle inequality"),
    ("link_mass = [0.013, 0.013, 0.02, 0.02]", "link_mass"),
])
def test_a_bad_body_in_a_preset_is_one_line_naming_the_file_and_key(capsys, tmp_path, line, key):
    source = "phantom_premium_15.toml" if line.startswith("inertia_") else "fivebar_singh.toml"
    text = (PRESETS / source).read_text(encoding="utf-8").replace("[parameters]\n", f"[parameters]\n{line}\n", 1)
    if line.startswith("link_masses"):
        text = "\n".join(row for row in text.splitlines() if not row.startswith("link_masses = [0.0135"))
    path = tmp_path / "bad.toml"
    path.write_text(text, encoding="utf-8")
    status, out, err = _run(capsys, "pose", str(path))
    assert status == 2 and out == ""
    assert err.count("\n") == 1 and key in err and "bad.toml" in err
