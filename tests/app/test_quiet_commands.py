"""No command prints a numpy or VTK warning: every subcommand, on hostile input, headless.

The suite's ``filterwarnings = error`` catches warnings raised in the tests' own process; a
command run by a person is another process, where a RuntimeWarning or a VTK log line lands on
the terminal. Each case runs ``python -m app`` in a subprocess with ``DISPLAY`` unset (the
headless case: VTK once probed X before EGL and logged ``bad X server connection``) and Python
warnings shown every time (``-W always``), and asserts that stderr holds only the program's
own lines: ``wrote FILE`` notes and, for bad input, one line of error naming the command.
Small resolutions keep the whole file well under a minute.
"""
from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
# Torque scales far from 1 N m: products of several torques (determinants, squared norms)
# underflow or overflow unless the code works at a normalised scale.
TINY, HUGE = "1e-300", "1e300"
TWIN_TORQUES = (0.16, 0.1, 0.1, 0.16, 0.1, 0.1, 0.003)      # twin_pantograph preset, N m


def _scaled(values, factor: str) -> str:
    return ",".join(f"{v * float(factor):.17g}" for v in values)


def _set(name: str, value: str, count: int) -> list[str]:
    return ["--set", f"{name}={','.join([value] * count)}"]


TWIN_TINY = ["--set", f"motor_torques={_scaled(TWIN_TORQUES, TINY)}"]
TWIN_HUGE = ["--set", f"motor_torques={_scaled(TWIN_TORQUES, HUGE)}"]
STEWART_GEARS = _set("gear_ratios", HUGE, 6)
FIVEBAR_GEARS = _set("gear_ratios", "1e307", 2)      # forces near the top of the float range
FIVEBAR_HUGE = _set("gear_ratios", HUGE, 2)

#: (argv after ``isoforce``, whether it is bad input: exit 2 with one error line).
CASES = [
    (["devices"], False),
    (["show", "twin_pantograph", *TWIN_TINY], False),
    (["pose", "twin_pantograph", *TWIN_TINY], False),
    (["pose", "twin_pantograph", *TWIN_HUGE, "--json"], False),
    (["pose", "stewart_platform", *STEWART_GEARS], False),
    (["pose", "inoue_platform", *_set("gear_ratios", HUGE, 9)], False),
    (["pose", "fivebar_singh", *FIVEBAR_GEARS], False),
    # All three knees of the Falcon stretched (J = 0): classed singular, and outside its knee limits.
    (["pose", "novint_falcon", "--at", "0,0,183.2064149244076"], True),
    (["pose", "fivebar_singh", "--set", "motor_torques=1e308,1e308"], True),
    (["pose", "novint_falcon", "--set", "knee_min=0", "upper_arm=60"], True),
    (["spec", "twin_pantograph", *TWIN_TINY], False),
    (["spec", "stewart_platform", *STEWART_GEARS], False),
    (["stats", "twin_pantograph", *TWIN_TINY, "--resolution", "5"], False),
    (["stats", "stewart_platform", *STEWART_GEARS, "--resolution", "4"], False),
    (["map", "fivebar_singh", *FIVEBAR_HUGE, "--quantity", "anisotropic_force", "--resolution", "24",
      "--out", "{tmp}/m.png"], False),
    (["map", "twin_pantograph", *TWIN_HUGE, "--quantity", "isotropic_force,anisotropic_moment",
      "--resolution", "5", "--out", "{tmp}/m.npz"], False),
    (["compare", "fivebar_singh", "haply_2diy", "--resolution", "12"], False),
    (["convergence", "fivebar_singh", "--resolutions", "8,16", "--quantity", "isotropic_force"], False),
    (["figure", "twin_pantograph", *TWIN_TINY, "--view", "pose", "--size", "320x240",
      "--out", "{tmp}/p.png"], False),
    (["figure", "fivebar_singh", *FIVEBAR_HUGE, "--view", "map", "--resolution", "16", "--size", "320x240",
      "--out", "{tmp}/f.png"], False),
    (["dextrous", "twin_pantograph", "--resolution", "5", "--rings", "2", "--rolls", "2", "--size", "320x240",
      "--out", "{tmp}/d.png"], False),
    (["optimize", "--list"], False),
    # pycapacity's numpy.matlib import warns under -W always; its own import, silenced there.
    (["bench", "--repeats", "1", "--points", "5"], False),
]


def test_the_cases_run_every_subcommand():
    from app.cli import COMMANDS
    assert {argv[0] for argv, _ in CASES} == set(COMMANDS)


def _ids():
    return ["-".join(a for a in argv[:2]) + f"-{k}" for k, (argv, _) in enumerate(CASES)]


@pytest.mark.parametrize("argv, bad_input", CASES, ids=_ids())
def test_a_command_prints_only_its_own_lines_on_stderr(argv, bad_input, tmp_path):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    # A guard against a hang, not a speed check: ``bench`` compiles the kernels from an empty cache
    # (``compile.cold_seconds``), 89 s at load 11 on a 2-core machine.
    proc = subprocess.run([sys.executable, "-W", "always", "-m", "app", *argv], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=600)
    lines = proc.stderr.splitlines()
    command = argv[0]
    if bad_input:
        assert proc.returncode == 2 and len(lines) == 1, proc.stderr
        assert lines[0].startswith(f"isoforce {command}: error: "), proc.stderr
        return
    assert proc.returncode == 0, proc.stderr
    # The program's own notes: "wrote FILE" and one-line "isoforce CMD: ..." messages; nothing
    # else (no "RuntimeWarning", no colour-coded VTK log line, no traceback).
    foreign = [line for line in lines
               if not re.match(r"(wrote \S|isoforce \w+: )", line) or "\x1b" in line or "Warning" in line]
    assert not foreign, proc.stderr


def test_bench_refuses_a_repeat_count_below_one_naming_it():
    # It once ran no timing and printed statistics' internal 'no median for empty data'.
    proc = subprocess.run([sys.executable, "-m", "app", "bench", "--repeats", "0"], cwd=ROOT,
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1 and "--repeats" in proc.stderr, proc.stderr
