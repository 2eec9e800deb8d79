"""A joint-side limit ``rating * gear_ratio`` that leaves the floats is refused, naming both parameters."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from kinematics.registry import MECHANISMS

ROOT = Path(__file__).resolve().parents[2]
BIG, TINY = np.finfo(float).max, np.finfo(float).tiny


def _rating(cls) -> str:
    return next(info.name for info in cls.PARAM_INFO if info.name in ("motor_torques", "motor_forces"))


@pytest.mark.parametrize("kind", sorted(MECHANISMS))
@pytest.mark.parametrize("scale, how", [(np.sqrt(BIG) * 4, "overflows"), (np.sqrt(TINY) / 4, "underflows")])
def test_a_product_outside_the_floats_is_a_value_error_naming_both_factors(kind, scale, how):
    mech = MECHANISMS[kind]()
    name = _rating(type(mech))
    # Each factor alone is a finite positive float; the product of the two is past max (or below tiny).
    rating = tuple(v * 0 + scale for v in getattr(mech.params, name))
    gears = tuple(v * 0 + scale for v in mech.params.gear_ratios)
    with pytest.raises(ValueError, match=rf"{name}\[.*\] x gear_ratios\[.*\] = .* {how}"):
        mech.replace(**{name: rating, "gear_ratios": gears})


def test_the_command_says_it_in_one_line_naming_set_and_the_product():
    proc = subprocess.run([sys.executable, "-m", "app", "pose", "fivebar_singh",
                           "--set", "motor_torques=1e308,1e308"],
                          cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr            # no RuntimeWarning before the error
    assert re.search(r"--set: motor_torques\[theta_1\] x gear_ratios\[theta_1\] = 1e\+308 N m x \S+ overflows",
                     lines[0]), lines[0]
