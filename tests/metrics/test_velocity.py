"""Velocity polytope and isotropic velocity under joint speed limits (metrics.velocity).

References: pycapacity's ``velocity_polytope`` (hyperplane shifting: unit normals from an SVD,
vertices by qhull's halfspace intersection) with the same ``J`` and limits, on random matrices
and on the PHANToM Premium at random feasible poses with its motors' no-load speeds; exact
scaling laws; the flat set of a rank-deficient ``J``.
"""
from __future__ import annotations

import numpy as np
import pytest

from metrics import velocity

EPS = np.finfo(float).eps
#: qhull's halfspace intersection (pycapacity's vertices) works in a dual space of reciprocal
#: distances from the Chebyshev centre; its vertices carry qhull's rounding (about 1e-13 of the
#: largest coordinate times the dual's condition), far inside this bound, which a wrong vertex
#: (a wrong corner, a missing facet) exceeds by orders of magnitude.
QHULL = 1e-9


def _case(rng, m, n):
    """A well-conditioned J (m x n) with entries of order 1 and an asymmetric speed box about 0."""
    jac = np.eye(m, n) + 0.3 * rng.standard_normal((m, n))
    return jac, rng.uniform(0.5, 2.0, n), -rng.uniform(0.5, 2.0, n)


def _hull_vertices(points):
    from scipy.spatial import ConvexHull
    return points[ConvexHull(points).vertices]


@pytest.mark.parametrize(("m", "n"), [(2, 2), (3, 3), (2, 3), (3, 4), (3, 5)])
def test_polytope_and_isotropic_velocity_against_pycapacity(m, n):
    robot = pytest.importorskip("pycapacity.robot")
    rng = np.random.default_rng(100 * m + n)
    for _ in range(10):
        jac, hi, lo = _case(rng, m, n)
        for lower in (None, lo):
            poly = robot.velocity_polytope(jac, hi, -hi if lower is None else lower)
            theirs = np.asarray(poly.vertices).T                                   # (k, m)
            corners = velocity.velocity_polytope_vertices(jac, joint_speed_limits=hi, joint_speed_min=lower)
            ours = _hull_vertices(corners)
            scale = np.abs(corners).max()
            # The same vertex set, both ways.
            assert len(ours) == len(theirs)
            for a, b in ((ours, theirs), (theirs, ours)):
                gaps = [np.min(np.linalg.norm(b - v, axis=1)) for v in a]
                assert max(gaps) <= QHULL * scale
            # The inscribed ball from pycapacity's half-spaces H v <= d (unit normals from an SVD)
            # against ours (cofactor normals): each normal carries a backward error of a few
            # m eps |J|, amplified by J's condition number, on an offset of size `scale`.
            h, d = np.asarray(poly.H), np.asarray(poly.d).ravel()
            ball = float(np.min(d / np.linalg.norm(h, axis=1)))
            iso = float(velocity.isotropic_velocity(jac, joint_speed_limits=hi, joint_speed_min=lower))
            assert abs(iso - ball) <= 8 * m * EPS * np.linalg.cond(jac) * scale


def test_the_phantoms_velocity_polytope_at_random_poses_against_pycapacity():
    """Its motors' no-load speed (mahilab/Phantom README.md:10, 4860 rpm) over the capstan ratios."""
    robot = pytest.importorskip("pycapacity.robot")
    from resources import load_preset

    preset = load_preset("phantom_premium_15")
    mech = preset.mechanism
    # The preset's six digits of 4860 pi / 30 rad/s.
    assert preset.motor_speeds == pytest.approx([4860 * np.pi / 30] * 3, rel=1e-6)
    speeds = velocity.joint_speed_limits(preset.motor_speeds, gear_ratios=mech.params.gear_ratios)
    np.testing.assert_array_equal(speeds, np.asarray(preset.motor_speeds) / np.asarray(mech.params.gear_ratios))
    p = mech.params
    q = np.random.default_rng(11).uniform(p.lower_limits, p.upper_limits, (400, 3))
    x, _ = mech.forward(q)
    keep = mech.feasible(q, x)
    q, x = q[keep][:40], x[keep][:40]
    assert len(q) == 40
    jac = mech.jacobian(q, x)
    batch = velocity.isotropic_velocity(jac, joint_speed_limits=speeds)
    for k in range(len(q)):
        poly = robot.velocity_polytope(jac[k], speeds, -speeds)
        h, d = np.asarray(poly.H), np.asarray(poly.d).ravel()
        ball = float(np.min(d / np.linalg.norm(h, axis=1)))
        scale = float(np.abs(jac[k]).max() * speeds.max() * 3)
        assert abs(batch[k] - ball) <= 8 * 3 * EPS * np.linalg.cond(jac[k]) * scale
        one = velocity.analyse_velocity(jac[k], motor_speeds=preset.motor_speeds, gear_ratios=mech.params.gear_ratios)
        assert one.isotropic_velocity == batch[k]                 # batch = one at a time
        theirs = np.asarray(poly.vertices).T
        assert len(one.vertices) == len(theirs) == 8
        gaps = [np.min(np.linalg.norm(theirs - v, axis=1)) for v in one.vertices]
        assert max(gaps) <= QHULL * scale


def test_at_q_zero_the_phantoms_isotropic_velocity_is_its_slowest_joint_times_its_lever():
    # q = 0: J's columns are l1 (base yaw, along y), l1 (shoulder, along z) and l2 (q3, along x),
    # orthogonal, so the polytope is a box and its inscribed radius the smallest half-edge.
    from resources import load_preset

    preset = load_preset("phantom_premium_15")
    p = preset.mechanism.params
    jac = preset.mechanism.jacobian(np.zeros(3))
    speeds = velocity.joint_speed_limits(preset.motor_speeds, gear_ratios=p.gear_ratios)
    edges = np.array([p.link1_length * speeds[0], p.link1_length * speeds[1], p.link2_length * speeds[2]])
    iso = float(velocity.isotropic_velocity(jac, joint_speed_limits=speeds))
    assert iso == pytest.approx(edges.min(), rel=8 * EPS)


def test_a_rank_deficient_jacobian_gives_a_flat_set_and_a_non_finite_one_nan():
    flat = np.array([[1.0, 2.0, 0.0], [2.0, 4.0, 0.0], [0.0, 0.0, 0.0]])     # rank 1
    line = np.array([[1.0, 1.0], [1.0, 1.0]])
    zero = np.zeros((2, 2))
    out = velocity.isotropic_velocity(np.stack([np.eye(2), line, zero]), joint_speed_limits=[1.0, 1.0])
    assert out.tolist() == [1.0, 0.0, 0.0]
    assert float(velocity.isotropic_velocity(flat, joint_speed_limits=[1.0, 1.0, 1.0])) == 0.0
    assert np.isnan(velocity.isotropic_velocity([[np.nan, 0.0], [0.0, 1.0]], joint_speed_limits=[1.0, 1.0]))


@pytest.mark.parametrize("k", [2.0**-40, 2.0**40])
def test_speeds_times_k_scale_the_polytope_by_k(k):
    rng = np.random.default_rng(9)
    jac, hi, lo = _case(rng, 3, 4)
    a = velocity.isotropic_velocity(jac, joint_speed_limits=hi, joint_speed_min=lo)
    b = velocity.isotropic_velocity(jac, joint_speed_limits=k * hi, joint_speed_min=k * lo)
    assert b == k * a                                            # a power of two: exact
    np.testing.assert_array_equal(velocity.velocity_polytope_vertices(jac, joint_speed_limits=k * hi),
                                  k * velocity.velocity_polytope_vertices(jac, joint_speed_limits=hi))


def test_bad_limits_are_refused_naming_the_argument():
    with pytest.raises(ValueError, match="joint_speed_limits"):
        velocity.isotropic_velocity(np.eye(2), joint_speed_limits=[1.0, -1.0])
    with pytest.raises(ValueError, match="joint_speed_min"):
        velocity.isotropic_velocity(np.eye(2), joint_speed_limits=[1.0, 1.0], joint_speed_min=[2.0, 0.0])
    with pytest.raises(ValueError, match="motor_speeds"):
        velocity.joint_speed_limits([1.0, 0.0], gear_ratios=[1.0, 1.0])


def test_rows_keep_the_linear_part_of_a_wrench_devices_polytope():
    """``analyse_velocity(rows=...)``: the projection onto the length rows, a zonotope of n
    generators in 3D, against pycapacity's polytope of the same rows."""
    robot = pytest.importorskip("pycapacity.robot")
    rng = np.random.default_rng(21)
    jac = np.eye(6) + 0.3 * rng.standard_normal((6, 6))
    motors, ratios = rng.uniform(100.0, 500.0, 6), rng.uniform(5.0, 15.0, 6)
    v = velocity.analyse_velocity(jac, motor_speeds=motors, gear_ratios=ratios, rows=(0, 1, 2))
    speeds = motors / ratios
    poly = robot.velocity_polytope(jac[:3], speeds, -speeds)
    theirs = np.asarray(poly.vertices).T
    scale = np.abs(velocity.velocity_polytope_vertices(jac[:3], joint_speed_limits=speeds)).max()
    assert v.rows == (0, 1, 2) and len(v.vertices) == len(theirs)
    assert max(np.min(np.linalg.norm(theirs - p, axis=1)) for p in v.vertices) <= QHULL * scale
    h, d = np.asarray(poly.H), np.asarray(poly.d).ravel()
    assert abs(v.isotropic_velocity - np.min(d / np.linalg.norm(h, axis=1))) <= \
        8 * 3 * EPS * np.linalg.cond(jac[:3]) * scale


def test_a_presets_motors_table_is_read_checked_and_written_back():
    from resources import PresetError, load_preset, parse_preset_text, preset_to_toml

    text = preset_to_toml(load_preset("phantom_premium_15"))
    again = parse_preset_text(text, "x.toml")
    assert again.motor_speeds == load_preset("phantom_premium_15").motor_speeds
    assert "README.md:10" in again.motor_speeds_source
    start = text.index("[motors]")
    for table, key in (("[motors]\nmax_speeds = [1.0, 2.0]\nsource = \"s\"\n", "motors.max_speeds"),
                       ("[motors]\nmax_speeds = [1.0, -2.0, 3.0]\nsource = \"s\"\n", "motors.max_speeds"),
                       ("[motors]\nmax_speeds = [1.0, 2.0, 3.0]\n", "motors.source"),
                       ("[motors]\nmax_speeds = [1.0, 2.0, 3.0]\nsource = \"s\"\nrpm = 3\n", "motors.rpm")):
        with pytest.raises(PresetError, match=key.replace(".", r"\.")):
            parse_preset_text(text[:start] + table, "bad.toml")
