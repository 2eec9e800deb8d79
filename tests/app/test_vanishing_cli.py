"""A minimum that is 0 in truth reads "0 (singular)" in `stats` and `compare`, and is flagged in JSON."""
from __future__ import annotations

import json

from app.cli import main


def test_stats_and_compare_label_a_vanishing_minimum(capsys):
    assert main(["stats", "novint_falcon", "--resolution", "21"]) == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("isotropic_force "))
    assert "0 (singular)" in row and "isotropic_force: min 0:" in out
    assert main(["stats", "novint_falcon", "--resolution", "21", "--json"]) == 0
    entry = json.loads(capsys.readouterr().out)["quantities"]["isotropic_force"]
    assert entry["min"] == 0.0 and entry["vanishes"] is True and entry["vanishes_at"]
    # A box device and a slice device are compared each with its own kind (issue 21 sec. 2).
    assert main(["compare", "novint_falcon", "--resolution", "21"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "0 (singular)" in next(line for line in lines if line.startswith("novint_falcon"))
    assert main(["compare", "inverse3_prototype", "fivebar_singh", "--resolution", "21"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "0 (singular)" not in next(line for line in lines if line.startswith("inverse3_prototype"))
