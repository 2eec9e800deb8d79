"""app.logic.pose_report: a pose report in display units as strict JSON (``isoforce pose --json``)."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from app.logic.pose_report import json_safe, to_dict
from kinematics import FiveBar
from metrics.pose import analyse_pose
from resources import load_preset

INVERSE3 = load_preset("inverse3_prototype").mechanism
FIVEBAR = load_preset("fivebar_singh").mechanism
POINTS = [(INVERSE3, (0.170, 0.0223, 0.230)), (INVERSE3, (0.120, 0.0900, 0.300)), (FIVEBAR, (0.0, 0.150)),
          (FIVEBAR, (0.150, 0.060))]


@pytest.fixture(params=range(len(POINTS)), ids=[f"{type(m).__name__}-{i}" for i, (m, _) in enumerate(POINTS)])
def case(request):
    mech, x = POINTS[request.param]
    x = np.array(x)
    return mech, x, analyse_pose(mech, x)


def test_to_dict_converts_units_and_is_strict_json(case):
    mech, x, r = case
    d = json.loads(json.dumps(to_dict(r), allow_nan=False))
    np.testing.assert_allclose(d["x"], x * 1e3)
    np.testing.assert_allclose(d["joints"], np.degrees(r.joints))
    np.testing.assert_allclose(d["jacobian"], r.jacobian * 1e3)
    np.testing.assert_allclose(d["vertices"], r.vertices)
    # Per-actuator and per-axis vectors are listed one per entry (columns of the matrices).
    np.testing.assert_allclose(d["reference_forces"], r.reference_forces.T)
    np.testing.assert_allclose(d["force_ellipsoid"]["axes"], r.force_ellipsoid.axes.T)
    np.testing.assert_allclose(d["velocity_ellipsoid"]["radii"], r.velocity_ellipsoid.radii * 1e3)
    assert d["isotropic_force"] == r.isotropic_force and d["bottleneck_actuator"] == r.bottleneck_name
    assert d["units"]["x"] == "mm" and d["units"]["isotropic_force"] == "N"
    si = to_dict(r, mm=False)
    np.testing.assert_allclose(si["x"], x)
    assert ("singularity" in d) == isinstance(mech, FiveBar)


def test_json_safe_spells_non_finite_values():
    value = {"a": np.array([1.0, np.nan, np.inf, -np.inf]), "b": np.int64(3), "c": np.bool_(True),
             4: (np.float32(0.5),)}
    assert json_safe(value) == {"a": [1.0, None, "inf", "-inf"], "b": 3, "c": True, "4": [0.5]}
    json.dumps(json_safe(value), allow_nan=False)
    assert float(json_safe(np.inf)) == math.inf        # a Python reader gets the number back


def test_unreachable_and_singular_poses_give_strict_json():
    # Unreachable: every number nan (null); leg 2 fully stretched: unbounded numbers ("inf").
    p = FIVEBAR.params
    angle = np.radians(120.0)
    stretched = np.array([p.half_base, 0.0]) + (p.proximal + p.distal) * np.array([np.cos(angle), np.sin(angle)])
    for report in (analyse_pose(FIVEBAR, (0.0, 0.5)), analyse_pose(INVERSE3, (2.0, 0.0, 0.2)),
                   analyse_pose(FIVEBAR, stretched)):
        text = json.dumps(to_dict(report), allow_nan=False)
        assert "NaN" not in text and "Infinity" not in text


def test_parts_not_computed_are_null():
    d = to_dict(analyse_pose(INVERSE3, (0.170, 0.0223, 0.230), parts=()))
    assert d["vertices"] is None and d["force_ellipsoid"] is None
    json.dumps(d, allow_nan=False)


def _pose_json(capsys, *argv):
    from app.cli import main

    capsys.readouterr()
    status = main(["pose", *argv, "--json"])
    out, err = capsys.readouterr()
    assert status == 0, err
    return json.loads(out, parse_constant=lambda c: pytest.fail(f"non-standard JSON constant {c}"))


def test_pose_json_gives_the_velocity_polytope_from_the_motors_speeds(capsys):
    from metrics.velocity import isotropic_velocity, joint_speed_limits, velocity_polytope_vertices

    preset = load_preset("phantom_premium_15")
    mech = preset.mechanism
    d = _pose_json(capsys, "phantom_premium_15", "--at", "150,40,-120")
    x = np.array([0.150, 0.040, -0.120])
    q, _ = mech.inverse(x)
    jac = mech.jacobian(q, x)
    speeds = joint_speed_limits(preset.motor_speeds, gear_ratios=mech.params.gear_ratios)
    # Independent of the CLI's path: the same functions on the model's own J at the typed point
    # (mm in, m out: the point differs from the typed one by the parse's rounding, < 1e-15 relative).
    assert d["isotropic_velocity"] == pytest.approx(float(isotropic_velocity(jac, joint_speed_limits=speeds)),
                                                    rel=1e-12)
    corners = velocity_polytope_vertices(jac, joint_speed_limits=speeds)
    np.testing.assert_allclose(d["velocity_polytope"]["vertices"], corners, rtol=1e-12, atol=0)
    assert d["velocity_polytope"]["signs"][0] == [1, 1, 1]
    np.testing.assert_allclose(d["joint_speed_limits"], speeds, rtol=1e-15)
    assert d["velocity_units"]["isotropic_velocity"] == "m/s" and "README.md:10" in d["velocity_units"]["source"]
    ell = d["acceleration_ellipsoid"]
    assert len(ell["radii"]) == 3 and d["dynamics_units"]["acceleration_ellipsoid.radii"] == "m/s^2"
    # The ellipsoid {A u : |u| <= 1} lies in the polytope {A u : |u|_inf <= 1}, which lies in sqrt(n)
    # times it: the isotropic acceleration is between its smallest radius and sqrt(3) times that.
    assert d["loading"]["gravity"] == "off"
    low, iso = ell["radii"][-1], d["isotropic_acceleration"]
    assert low * (1 - 1e-12) <= iso <= np.sqrt(3) * low * (1 + 1e-12)


def test_pose_json_refuses_the_velocity_polytope_with_the_reason_and_gives_the_omnis_masses(capsys):
    d = _pose_json(capsys, "phantom_omni")
    assert "velocity_polytope" not in d and "isotropic_velocity" not in d
    assert d["velocity"].startswith("not computed: ") and "max_speeds" in d["velocity"]
    # The Omni's estimated body model: every mass key, no refusal.
    assert "dynamics" not in d
    for key in ("effective_mass", "apparent_mass", "apparent_mass_range", "isotropic_acceleration",
                "peak_acceleration", "weight", "acceleration_ellipsoid"):
        assert d[key] is not None and not isinstance(d[key], str), key
    assert 0 < d["apparent_mass_range"][0] <= d["apparent_mass_range"][1]
