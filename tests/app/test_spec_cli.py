"""``isoforce spec``: each row against an independent computation, missing data named, bad input refused."""
from __future__ import annotations

import contextlib
import io
import itertools
import json
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import linprog

from app.cli import main
from metrics.pose import analyse_pose
from resources import load_preset, presets
from tests.preset_files import massless_omni


def run(capsys, *argv):
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


def spec_json(capsys, *argv) -> dict:
    status, out, err = run(capsys, "spec", *argv, "--json")
    assert status == 0, err
    return json.loads(out, parse_constant=lambda c: pytest.fail(f"non-standard JSON constant {c}"))

PROTO_TOML = Path(presets.__file__).parent / "twin_pantograph_prototype.toml"


def _json_of(*argv) -> dict:
    """``spec ARGV --json`` run once, outside capsys (for module fixtures)."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["spec", *argv, "--json"]) == 0
    return json.loads(out.getvalue())


@pytest.fixture(scope="module")
def proto():
    """The prototype's sheet, the held box on a 3-point grid (its corners decide it: tests/metrics/test_spec_box.py)."""
    return _json_of("twin_pantograph_prototype", "--box-points", "3", "--gravity", "off")


def test_prototype_rows_follow_from_its_mass_model_and_minimum_forces(proto):
    # The mass rows come from the model's bodies (Lambda at the pose), not from eq. 28's table,
    # which docs/reproduction.md compares with it; the source is named.
    d = proto
    preset = load_preset("twin_pantograph_prototype")
    rows = {k: np.array(v["value"]) for k, v in d["rows"].items()}
    x0 = np.array(preset.pose)
    q0, _ = preset.mechanism.inverse(x0[None])
    mass = preset.mechanism.task_inertia(q0, x0[None])[0]
    assert d["effective_mass_source"].startswith("the model's bodies")
    assert rows["effective_mass"].tolist() == np.diag(mass).tolist()
    assert rows["apparent_mass"] == pytest.approx(1 / np.diag(np.linalg.inv(mass)), rel=1e-12)
    # Table X's definitions: peak force (the smaller direction) over D_ii and over the minimum force.
    force = rows["peak"].min(axis=1)
    assert "peak" not in d["missing"] and "peak" in d["rows"]["acceleration"]["units"]
    assert rows["acceleration"] == pytest.approx(force / np.diag(mass), rel=1e-15)
    assert rows["dynamic_range"] == pytest.approx(force / np.array(preset.spec.minimum_forces), rel=1e-15)
    assert rows["minimum_force"].tolist() == list(preset.spec.minimum_forces)
    # One 4000 cpt count through the Jacobian: the largest |J_iu| * 2 pi / 4000 over the active joints.
    mech, x = preset.mechanism, np.array(preset.pose)
    q, _ = mech.inverse(x[None])
    jac = mech.jacobian(q, x[None])[0]
    res = np.max(np.abs(jac), axis=1) * 2 * np.pi / 4000
    assert rows["resolution"] == pytest.approx(res, rel=1e-12)
    # The bounds by hand: 2 f_c / D, and Colgate and Schenkel's b > K T / 2 at T = 1 ms (1 kHz, [spec]).
    k = 2 * np.array(preset.spec.minimum_forces) / res
    assert d["control_rate"] == 1000.0
    assert rows["stiffness_bound_quantisation"] == pytest.approx(k, rel=1e-12)
    assert rows["damping_needed_quantisation"] == pytest.approx(k * 1e-3 / 2, rel=1e-12)
    assert "physical_damping" in d["missing"]["stiffness_bound_sampling"]
    assert set(d["not_modelled"]) == {"minimum_force", "max_stiffness", "max_damping"}


def test_prototype_peak_forces_against_a_linear_programme(proto):
    # max t: A tau = t e_i, |tau_u| <= the [spec] peak torques of the actuated joints (HiGHS).
    preset = load_preset("twin_pantograph_prototype")
    mech, x = preset.mechanism, np.array(preset.pose)
    peak = np.array(preset.spec.peak_motor_torques)[list(mech.actuated)]
    assert proto["peak_limits"]["value"] == peak.tolist()
    assert "[spec] peak_motor_torques" in proto["peak_limits"]["source"]
    assert "RE 40" in proto["peak_limits"]["source"] and "RE 35" in proto["peak_limits"]["source"]
    q, _ = mech.inverse(x[None])
    a = mech.force_map(q, x[None])[0]
    m, n = a.shape
    got = np.array(proto["rows"]["peak"]["value"])
    for i, (side, sign) in itertools.product(range(m), enumerate((1.0, -1.0))):
        e = np.zeros(m)
        e[i] = sign
        res = linprog(np.r_[np.zeros(n), -1.0], A_eq=np.c_[a, -e], b_eq=np.zeros(m),
                      bounds=[(-p, p) for p in peak] + [(0, None)], method="highs")
        assert res.status == 0
        # HiGHS's feasibility tolerance is 1e-7 on torques of O(1) N m.
        assert got[i, side] == pytest.approx(-res.fun, rel=1e-6)


def test_peak_forces_scale_exactly_with_the_peak_rating(proto, tmp_path):
    # Twice the [spec] peak torques: every peak force, acceleration and dynamic range exactly doubles
    # (x 2 is exact in binary floating point), the continuous rows do not move.
    text = PROTO_TOML.read_text(encoding="utf-8")
    old = "peak_motor_torques = [2.29, 0.9725, 0.9725, 2.29, 0.9725, 0.9725, 0.003]"
    assert old in text
    doubled = tmp_path / "doubled.toml"
    doubled.write_text(text.replace(old, "peak_motor_torques = [4.58, 1.945, 1.945, 4.58, 1.945, 1.945, 0.006]"),
                       encoding="utf-8")
    d = _json_of(str(doubled), "--no-box", "--gravity", "off")
    for key in ("peak", "acceleration", "dynamic_range"):
        assert np.array(d["rows"][key]["value"]).tolist() == (2 * np.array(proto["rows"][key]["value"])).tolist()
    assert d["rows"]["continuous"]["value"] == proto["rows"]["continuous"]["value"]
    # The peak rating in the continuous rating's place (--set motor_torques) gives the same forces exactly.
    as_continuous = _json_of("twin_pantograph_prototype", "--no-box", "--gravity", "off", "--set",
                             "motor_torques=2.29,0.9725,0.9725,2.29,0.9725,0.9725,0.003")
    assert as_continuous["rows"]["continuous"]["value"] == proto["rows"]["peak"]["value"]


def test_prototype_box_row_is_the_metrics_search(proto, capsys):
    from metrics.spec_box import TABLE_X_HALF_WIDTHS, largest_held_box

    preset = load_preset("twin_pantograph_prototype")
    box = largest_held_box(preset.mechanism, np.array(preset.pose)[:3], TABLE_X_HALF_WIDTHS, points=3)
    got = proto["held_box"]
    assert got["half_widths"] == box.half_widths.tolist() and got["failed_scale"] == box.failed_scale
    assert got["orientations"] == 95 and got["points_per_axis"] == 3 and got["angle"] == pytest.approx(np.pi / 4)
    assert 1.70 < got["scale"] < 1.71                 # +-102.3 x +-63.9 x +-63.9 mm: 1.705 x Table X's box
    # The text names the definition, the sampling and the bisection's resolution beside the reach.
    status, out, err = run(capsys, "spec", "twin_pantograph_prototype", "--box-points", "2", "--gravity", "off")
    assert status == 0, err
    lines = out.splitlines()
    assert lines[2].startswith("box held at +-45 deg") and lines[3].startswith("reach through the pose")
    for phrase in ("Table X's shape, +-60 x +-37.5 x +-37.5 mm", "bisection on the scale to 0.001",
                   "2 x 2 x 2 grid points", "95 distinct orientations", "estimate from above",
                   "max stiffness: not modelled", "max damping: not modelled", "minimum force: not modelled",
                   "Colgate & Schenkel", "T = 1 / 1000 Hz = 1 ms", "peak force", "dynamic range (peak)"):
        assert phrase in out, phrase


def test_physical_damping_gives_the_sampling_bounds(tmp_path):
    text = PROTO_TOML.read_text(encoding="utf-8").replace(
        "control_rate = 1000.0", "control_rate = 2000.0\nphysical_damping = [0.5, 0.6, 0.7, 0.001, 0.002]")
    path = tmp_path / "damped.toml"
    path.write_text(text, encoding="utf-8")
    d = _json_of(str(path), "--no-box", "--gravity", "off")
    rows = d["rows"]
    # K < 2 (b - |B|) / T at B = 0, T = 0.5 ms; |B| < b at K = 0.
    assert rows["stiffness_bound_sampling"]["value"] == pytest.approx([2000.0, 2400.0, 2800.0, 4.0, 8.0], rel=1e-15)
    assert rows["damping_bound_sampling"]["value"] == [0.5, 0.6, 0.7, 0.001, 0.002]
    assert "stiffness_bound_sampling" not in d["missing"]


def test_wrong_peak_length_is_one_line_naming_the_key(tmp_path, capsys):
    text = PROTO_TOML.read_text(encoding="utf-8").replace(
        "peak_motor_torques = [2.29, 0.9725, 0.9725, 2.29, 0.9725, 0.9725, 0.003]", "peak_motor_torques = [1.0, 1.0]")
    path = tmp_path / "short.toml"
    path.write_text(text, encoding="utf-8")
    status, out, err = run(capsys, "spec", str(path), "--no-box")
    assert status == 2 and out == "" and "[spec] peak_motor_torques must have 7 values" in err


@pytest.mark.parametrize("key", ["fivebar_singh", "inverse3_prototype", "phantom_premium_15"])
def test_axis_forces_lie_between_the_isotropic_and_anisotropic_force(capsys, key):
    # The ball of the isotropic force is inside the force set, which is inside the ball of its farthest vertex.
    d = spec_json(capsys, key)
    preset = load_preset(key)
    report = analyse_pose(preset.mechanism, np.array(preset.pose))
    forces = np.array(d["rows"]["continuous"]["value"])
    slack = 1 + 64 * np.finfo(float).eps
    assert np.all(forces >= report.isotropic_force / slack)
    assert np.all(forces <= report.anisotropic_force * slack)


def test_reach_matches_dense_sampling_of_the_five_bar(capsys):
    d = spec_json(capsys, "fivebar_singh")
    preset = load_preset("fivebar_singh")
    mech, x = preset.mechanism, np.array(preset.pose)
    extents = np.array(d["rows"]["workspace"]["value"])
    span = d["spans"][0]
    for i in range(2):
        t = np.linspace(-span, span, 200_001)
        pts = np.repeat(x[None], t.size, axis=0)
        pts[:, i] += t
        q, ok = mech.inverse(pts)
        good = ok & mech.feasible(q, pts)
        centre = t.size // 2
        lo = centre - np.argmin(good[centre::-1]) + 1        # first infeasible sample below the pose, + 1
        hi = centre + np.argmin(good[centre:]) - 1
        step = t[1] - t[0]
        # The bisected ends are exact to 2^-48 of a coarse step; the dense samples bracket them to one fine step.
        assert t[lo] - step <= extents[i, 0] <= t[lo] + 1e-12
        assert t[hi] - 1e-12 <= extents[i, 1] <= t[hi] + step


def test_text_names_every_missing_row(capsys):
    status, out, err = run(capsys, "spec", "fivebar_singh")
    assert status == 0, err
    for phrase in ("reach through the pose", "continuous force", "peak: not given", "resolution: not given",
                   "dynamic range: not given"):
        assert phrase in out
    # The five-bar has a mass model: its masses and accelerations come from it, never "not given".
    assert "effective mass (D_ii)" in out and "from the model's bodies" in out
    assert "effective mass: not given" not in out and "weight: not given" not in out


@pytest.mark.parametrize("argv, phrase", [
    (["fivebar_singh", "--at", "0,500"], "--at"),
    (["fivebar_singh", "--at", "1,2,3"], "--at"),
    (["no_such_device"], "DEVICE"),
    (["twin_pantograph_prototype", "--box-shape", "60,0,30"], "--box-shape"),
    (["twin_pantograph_prototype", "--box-shape", "60,30"], "--box-shape"),
    (["twin_pantograph_prototype", "--box-angle", "95"], "--box-angle"),
])
def test_bad_input_is_one_line_and_exit_2(capsys, argv, phrase):
    status, out, err = run(capsys, "spec", *argv)
    assert status == 2 and out == ""
    assert err.count("\n") == 1 and phrase in err and "Traceback" not in err


def test_weight_row_is_the_force_balancing_central_differences_of_the_potential(capsys):
    # The hand holds f with J^T f = dV/dq: V's gradient by central differences, then solve for f at every
    # feasible point of the same grid; the extremes must agree with the CLI's.
    d = spec_json(capsys, "phantom_premium_15")
    preset = load_preset("phantom_premium_15")
    mech = preset.mechanism
    grid = preset.grid.with_resolution(tuple(d["weight"]["grid"]))
    pts = grid.points(mech.task_names).reshape(-1, 3)
    q, ok = mech.inverse(pts)
    good = ok & mech.feasible(q, pts)
    q, pts = q[good], pts[good]
    g = np.array([0.0, 0.0, -9.80665])
    h = 1e-6
    grad = np.stack([(mech.potential_energy(q + h * e, g) - mech.potential_energy(q - h * e, g)) / (2 * h)
                     for e in np.eye(3)], axis=-1)
    jac = mech.jacobian(q, pts)
    f = np.linalg.solve(np.swapaxes(jac, -1, -2), grad[..., None])[..., 0]
    weight = np.linalg.norm(f, axis=-1)
    weight = weight[np.isfinite(weight)]
    assert d["weight"]["points"] == weight.size
    # Central differences of V (|V| < 1 J) err by ~|V'''| h^2 + eps |V| / h ~ 1e-10 N m; through J^-T
    # (|J^-T| <= 1250 / m at these points, measured) that is < 1e-6 N.
    assert d["weight"]["min"] == pytest.approx(weight.min(), abs=1e-6)
    assert d["weight"]["max"] == pytest.approx(weight.max(), abs=1e-6)


def test_weight_is_missing_without_a_mass_model(capsys, tmp_path):
    d = spec_json(capsys, massless_omni(tmp_path))
    assert "weight" not in d and "mass model" in d["missing"]["weight"]


def test_a_planar_device_says_gravity_is_carried_by_its_structure(capsys):
    """The five-bar's joints turn about z: a weight along -z gives no joint torque, so the hand
    holds exactly nothing, and the sheet says why instead of printing a bare 0 N."""
    assert main(["spec", "fivebar_singh"]) == 0
    out = capsys.readouterr().out
    assert "0 to 0 N" in out and "none along the task coordinates x, y" in out
    assert main(["spec", "phantom_premium_15"]) == 0
    assert "none along the task coordinates" not in capsys.readouterr().out
