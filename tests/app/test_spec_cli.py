"""``isoforce spec``: each row against an independent computation, missing data named, bad input refused."""
from __future__ import annotations

import json

import numpy as np
import pytest

from app.cli import main
from metrics.pose import analyse_pose
from resources import load_preset


def run(capsys, *argv):
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


def spec_json(capsys, *argv) -> dict:
    status, out, err = run(capsys, "spec", *argv, "--json")
    assert status == 0, err
    return json.loads(out, parse_constant=lambda c: pytest.fail(f"non-standard JSON constant {c}"))
def massless_omni(folder) -> str:
    """The PHANToM Omni preset with ``mass_model = "none"`` as a file ``phantom_omni.toml`` (key
    ``phantom_omni``): a device without a mass model, now that the shipped Omni has an estimated one."""
    from resources import preset_to_toml
    preset = load_preset("phantom_omni")
    path = folder / "phantom_omni.toml"
    path.write_text(preset_to_toml(preset.replace(mechanism=preset.mechanism.replace(mass_model="none"))),
                    encoding="utf-8")
    return str(path)



def test_prototype_rows_follow_from_its_mass_model_and_minimum_forces(capsys):
    # The mass rows come from the model's bodies (Lambda at the pose), not from eq. 28's table,
    # which docs/reproduction.md compares with it; the source is named.
    d = spec_json(capsys, "twin_pantograph_prototype")
    preset = load_preset("twin_pantograph_prototype")
    rows = {k: np.array(v["value"]) for k, v in d["rows"].items()}
    x0 = np.array(preset.pose)
    q0, _ = preset.mechanism.inverse(x0[None])
    mass = preset.mechanism.task_inertia(q0, x0[None])[0]
    assert d["effective_mass_source"].startswith("the model's bodies")
    assert rows["effective_mass"].tolist() == np.diag(mass).tolist()
    assert rows["apparent_mass"] == pytest.approx(1 / np.diag(np.linalg.inv(mass)), rel=1e-12)
    force = rows["continuous"].min(axis=1)         # no peak rating: the continuous force, and it says so
    assert "peak" in d["missing"] and "continuous" in d["rows"]["acceleration"]["units"]
    assert rows["acceleration"] == pytest.approx(force / np.diag(mass), rel=1e-15)
    assert rows["dynamic_range"] == pytest.approx(force / np.array(preset.spec.minimum_forces), rel=1e-15)
    # One 4000 cpt count through the Jacobian: the largest |J_iu| * 2 pi / 4000 over the active joints.
    mech, x = preset.mechanism, np.array(preset.pose)
    q, _ = mech.inverse(x[None])
    jac = mech.jacobian(q, x[None])[0]
    assert rows["resolution"] == pytest.approx(np.max(np.abs(jac), axis=1) * 2 * np.pi / 4000, rel=1e-12)


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
