"""Serial RRR with a parallelogram drive (PHANToM family): kinematics, limits, the sourced preset.

Tolerances follow from double rounding (``eps``) and the link lengths; see each test.
"""
from __future__ import annotations

import numpy as np
import pytest

from kinematics import SerialRRR, SerialRRRParams
from resources import load_preset

EPS = np.finfo(float).eps
DEG = np.pi / 180.0
MECH = SerialRRR()
L1, L2 = MECH.params.link1_length, MECH.params.link2_length


def feasible_joints(mech, count, seed, *, margin=1 * DEG):
    """Random joint vectors inside the limits and the coupling limits, ``margin`` away from each, (k, 3)."""
    rng = np.random.default_rng(seed)
    lo = np.array(mech.params.lower_limits) + margin
    hi = np.array(mech.params.upper_limits) - margin
    q = rng.uniform(lo, hi, (20 * count, 3))
    p = mech.params
    keep = mech.feasible(q)
    keep &= (q[:, 1] - q[:, 2] <= p.max_q2_minus_q3 - margin) & (q[:, 2] - q[:, 1] <= p.max_q3_minus_q2 - margin)
    q = q[keep][:count]
    assert len(q) == count
    return q


# -- derivatives ------------------------------------------------------------------------------
def test_jacobian_matches_central_differences():
    # Each coordinate of P is a sum of products of sines and cosines times l1 or l2, so along
    # any one joint |d^3 P / dq^3| <= l1 + l2 and |P| <= l1 + l2. A central difference with
    # step h then errs by at most h^2 / 6 (l1 + l2) (truncation) plus about 2 eps (l1 + l2) / h
    # (the rounding of two FK evaluations, each a few ulps of l1 + l2, divided by 2h);
    # h = eps^(1/3) balances them. Factor 4: the few ulps of each FK evaluation.
    q = feasible_joints(MECH, 500, seed=1)
    jac = MECH.jacobian(q)
    h = EPS ** (1 / 3)
    for j in range(3):
        dq = np.zeros(3)
        dq[j] = h
        xp, _ = MECH.forward(q + dq)
        xm, _ = MECH.forward(q - dq)
        numeric = (xp - xm) / (2 * h)
        tol = 4 * (h * h / 6 + 2 * EPS / h) * (L1 + L2)
        assert np.max(np.abs(numeric - jac[:, :, j])) <= tol


def test_determinant_is_l1_l2_r_cos_q2_minus_q3():
    q = feasible_joints(MECH, 200, seed=2)
    r = L1 * np.cos(q[:, 1]) + L2 * np.sin(q[:, 2])
    det = np.linalg.det(MECH.jacobian(q))
    # det of a 3 x 3 with entries up to l1 + l2: rounding ~ 6 terms of 3 products, (l1 + l2)^3 each.
    np.testing.assert_allclose(det, L1 * L2 * r * np.cos(q[:, 1] - q[:, 2]), rtol=0, atol=32 * EPS * (L1 + L2) ** 3)


# -- round trips ------------------------------------------------------------------------------
@pytest.mark.parametrize("branch", ["nearest", "front", "back"])
def test_forward_inverse_round_trip(branch):
    mech = MECH.replace(base_branch=branch)
    q = feasible_joints(mech, 500, seed=3)
    r = L1 * np.cos(q[:, 1]) + L2 * np.sin(q[:, 2])
    # Which points the branch reaches with the same q1: front where r > 0, back where r < 0,
    # nearest for both (|q1| < 90 deg - margin, so the tie at |q1| = 90 deg never arises).
    keep = {"nearest": np.ones(len(q), bool), "front": r > 0, "back": r < 0}[branch]
    keep &= np.abs(r) > 0.01 * (L1 + L2)          # away from the base axis (q1 undefined on it)
    q = q[keep]
    x, ok = mech.forward(q)
    assert ok.all()
    back, ok = mech.inverse(x)
    assert ok.all()
    # FK rounds to a few ulps of l1 + l2; IK turns a task error dx into |J^-1| dx. The coupling
    # limits keep the elbow angle in [35, 155] deg (acos well conditioned), so sigma_min(J)
    # bounds the amplification; 64 covers the ulps of both evaluations.
    sigma_min = np.linalg.svd(mech.jacobian(q), compute_uv=False)[:, -1]
    err = np.max(np.abs(back - q), axis=-1)
    assert np.all(err <= 64 * EPS * (L1 + L2) / sigma_min)
    again, _ = mech.forward(back)
    assert np.max(np.abs(again - x)) <= 64 * EPS * (L1 + L2)


def test_inverse_masks_unreachable_and_non_finite_points_without_warnings():
    pts = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [np.nan, 0.0, 0.0], [np.inf, np.inf, 0.0],
                    [0.0, 0.0, -(L1 - L2) / 2]])
    q, ok = MECH.inverse(pts)
    assert ok.tolist() == [False, False, False, False, False]
    assert np.all(np.isnan(q))


def test_inverse_branches_reach_a_point_two_ways():
    x = np.array([0.15, 0.05, -0.10])
    qf, okf = MECH.inverse(x, base_branch="front")
    qb, okb = MECH.inverse(x, base_branch="back")
    assert okf and okb
    assert qf[0] == pytest.approx(np.arctan2(0.05, 0.15), abs=4 * EPS)
    assert qb[0] == pytest.approx(np.arctan2(0.05, 0.15) - np.pi, abs=16 * EPS)
    for q in (qf, qb):
        np.testing.assert_allclose(MECH.forward(q)[0], x, rtol=0, atol=64 * EPS * (L1 + L2))
    assert MECH.feasible(qf) and not MECH.feasible(qb)      # q1 = -162 deg is past the -90 deg limit


# -- limits -----------------------------------------------------------------------------------
def test_joint_and_coupling_limits():
    p = MECH.params
    # The mask is PhantomModel.cpp validate_angles (lines 27-37), on random joints over a wide box.
    rng = np.random.default_rng(5)
    q = rng.uniform(-4.0, 4.0, (20000, 3))
    expect = np.all((q >= p.lower_limits) & (q <= p.upper_limits), axis=-1)
    expect &= (q[:, 1] - q[:, 2] <= p.max_q2_minus_q3) & (q[:, 2] - q[:, 1] <= p.max_q3_minus_q2)
    np.testing.assert_array_equal(MECH.feasible(q), expect)
    # Each bound that can be active, met and then passed by 1e-9 rad. The q2 lower limit (-124 deg)
    # and the q3 upper limit (214 deg) never are: q3 >= -29 deg and q3 - q2 <= 55 deg give
    # q2 >= -84 deg, and q2 <= 119 deg gives q3 <= 174 deg (docs/devices.md).
    d = 1e-9
    for q, i, sign in (([p.lower_limits[0], 0.2, 0.3], 0, -1), ([p.upper_limits[0], 0.2, 0.3], 0, 1),
                       ([0.0, p.upper_limits[1], p.upper_limits[1]], 1, 1),
                       ([0.0, 0.0, p.lower_limits[2]], 2, -1)):
        q = np.array(q)
        assert MECH.feasible(q), (i, q)
        q[i] += sign * d
        assert not MECH.feasible(q), (i, q)
    assert not MECH.feasible([0.0, -100 * DEG, -29 * DEG]) and not MECH.feasible([0.0, 119 * DEG, 180 * DEG])
    # Coupling: q2 - q3 <= 65 deg and q3 - q2 <= 55 deg.
    assert MECH.feasible([0.0, p.max_q2_minus_q3, 0.0])
    assert not MECH.feasible([0.0, p.max_q2_minus_q3 + d, 0.0])
    assert MECH.feasible([0.0, 0.0, p.max_q3_minus_q2])
    assert not MECH.feasible([0.0, 0.0, p.max_q3_minus_q2 + d])
    assert not MECH.feasible([[np.nan, 0.0, 0.0], [0.0, np.inf, 0.0]]).any()


def test_parameters_are_validated_with_their_names():
    with pytest.raises(ValueError, match="link1_length"):
        SerialRRRParams(link1_length=-0.1)
    with pytest.raises(ValueError, match="max_q3_minus_q2 must be below 90 deg"):
        SerialRRRParams(max_q3_minus_q2=np.pi / 2)
    with pytest.raises(ValueError, match=r"com_a\[y\]"):
        SerialRRRParams(com_a=(0.0, np.nan, 0.0))
    with pytest.raises(ValueError, match=r"lower_limits\[q2\] must be below"):
        SerialRRRParams(lower_limits=(-1.0, 2.5, -0.5))


# -- a pose checked by hand ---------------------------------------------------------------------
def test_nominal_pose_by_hand():
    # q = 0: link 1 horizontal (r = l1), link 2 straight down. P = (l1, 0, -l2);
    # dP/dq1 = r (0, 1, 0), dP/dq2 = l1 (-sin q2, 0, cos q2) = (0, 0, l1), dP/dq3 = l2 (cos q3, 0, sin q3) = (l2, 0, 0).
    x, ok = MECH.forward([0.0, 0.0, 0.0])
    assert ok
    np.testing.assert_allclose(x, [L1, 0.0, -L2], rtol=0, atol=2 * EPS * L1)
    np.testing.assert_allclose(MECH.jacobian([0.0, 0.0, 0.0]), [[0, 0, L2], [L1, 0, 0], [0, L1, 0]],
                               rtol=0, atol=2 * EPS * L1)
    # A pose off the axes: q = (30, 20, 60) deg. r = l1 cos 20 + l2 sin 60.
    q = np.array([30.0, 20.0, 60.0]) * DEG
    r = L1 * np.cos(20 * DEG) + L2 * np.sin(60 * DEG)
    expect = [r * np.cos(30 * DEG), r * np.sin(30 * DEG), L1 * np.sin(20 * DEG) - L2 * np.cos(60 * DEG)]
    np.testing.assert_allclose(MECH.forward(q)[0], expect, rtol=0, atol=8 * EPS * (L1 + L2))
    # Singular only on the base axis: q2 = 0, q3 = -asin(l1 / l2) is outside the limits, so put
    # the tip on the axis with q2 = 90 deg, q3 = 0 (r = 0): the q1 column vanishes.
    on_axis = np.array([0.0, np.pi / 2, 0.0])
    assert int(MECH.singularity(on_axis)) == 1 and MECH.singular_legs(on_axis).tolist() == [True, False, False]
    assert int(MECH.singularity(q)) == 0


def test_link_points_draw_a_parallelogram():
    q = feasible_joints(MECH, 20, seed=4)
    pts = MECH.link_points(q)
    tip, elbow, shoulder, crank, follower = np.moveaxis(pts, -2, 0)
    np.testing.assert_allclose(tip, MECH.forward(q)[0], rtol=0, atol=8 * EPS * (L1 + L2))
    np.testing.assert_allclose(shoulder, 0.0, atol=0)
    # Opposite sides equal as vectors: shoulder -> elbow == crank -> follower, shoulder -> crank == elbow -> follower.
    np.testing.assert_allclose(elbow - shoulder, follower - crank, rtol=0, atol=8 * EPS * (L1 + L2))
    np.testing.assert_allclose(crank - shoulder, follower - elbow, rtol=0, atol=8 * EPS * (L1 + L2))
    np.testing.assert_allclose(np.linalg.norm(crank, axis=-1), MECH.params.crank_length, rtol=4 * EPS)


# -- the preset against its source ------------------------------------------------------------------
def test_phantom_premium_15_preset_against_its_source():
    """Every number against mahilab/Phantom ff342f9 cpp/src/PhantomModel.hpp (line) and README.md,
    and the force the sales figures state, derived by hand at the source's nominal pose."""
    preset = load_preset("phantom_premium_15")
    mech = preset.mechanism
    p = mech.params
    # lines 33-35 (the preset's mm -> m rounds to within an ulp)
    np.testing.assert_allclose([p.link1_length, p.link2_length, p.crank_length], [0.209550, 0.169545, 0.031750],
                               rtol=EPS, atol=0)
    np.testing.assert_allclose(p.lower_limits, np.radians([-90, -124, -29]), rtol=1e-15)       # line 38
    np.testing.assert_allclose(p.upper_limits, np.radians([90, 119, 214]), rtol=1e-15)         # line 39
    assert p.max_q2_minus_q3 == pytest.approx(np.radians(65), rel=1e-15)                     # line 40
    assert p.max_q3_minus_q2 == pytest.approx(np.radians(55), rel=1e-15)                     # line 41
    assert p.gear_ratios == (13.3, 11.2, 11.2)                                                 # line 50, Eta
    assert p.motor_torques == (0.0286,) * 3 and p.peak_motor_torques == (0.129,) * 3   # hpp 53, 56; README 13, 15
    assert p.link_masses == (0.026220, 0.026146, 0.267840, 0.215420, 0.361590)                 # lines 12-16
    np.testing.assert_allclose([p.com_a, p.com_c, p.com_be, p.com_df, p.com_g],                 # lines 26-30
                               [[0.00002423, -0.05237892, 0], [0, 0.10477739, 0],
                                [-0.03518875, -0.0000628, 0.00232416], [-0.05153541, 0.00060903, 0.00402873],
                                [-0.01048563, 0.01396387, -0.05380827]], rtol=1e-15, atol=0)
    # Joint torques are the source's Tau_nom and Tau_max (lines 59, 62): Tau_mot * Eta.
    np.testing.assert_allclose(mech.torque_limits(), 0.0286 * np.array([13.3, 11.2, 11.2]), rtol=2 * EPS)
    np.testing.assert_allclose(mech.peak_torque_limits(), 0.129 * np.array([13.3, 11.2, 11.2]), rtol=2 * EPS)
    provenance = dict(preset.provenance)
    assert provenance["repository"] == "https://github.com/mahilab/Phantom"
    assert provenance["lines.link1_length"].startswith("cpp/src/PhantomModel.hpp:33")

    # The sales figure 8.5 N peak (issue 9's quote of SensAble's specification, "at the nominal
    # position"): at q = 0, tau = J^T f gives f_x = tau3 / l2, f_y = tau1 / l1, f_z = tau2 / l1.
    # The largest single-axis peak force is f_x = 0.129 * 11.2 / 0.169545 = 8.52 N, which rounds
    # to the quoted 8.5 N (two digits: +-0.05 N).
    q0 = np.zeros(3)
    jac = mech.jacobian(q0)
    peak_axis = np.abs(np.linalg.solve(jac.T, np.diag(mech.peak_torque_limits()))).max(axis=1)
    np.testing.assert_allclose(peak_axis, [0.129 * 11.2 / L2, 0.129 * 13.3 / L1, 0.129 * 11.2 / L1], rtol=8 * EPS)
    assert round(peak_axis.max(), 1) == 8.5
    # The continuous 1.4 N does NOT follow from the README's 28.6 mNm: the weakest axis there
    # (z, joint 2) gives 0.0286 * 11.2 / l1 = 1.53 N, 9 % more (docs/devices.md says so).
    cont_min = mech.torque_limits()[1] / L1
    assert cont_min == pytest.approx(1.5286, abs=1e-4) and cont_min > 1.4 * 1.05

    # The sales workspace 381 x 267 x 191 mm (W x H x D: y, z, x in frame {0}): placed at
    # (197.5, 0, 25) mm (the best centre of a 2.5 mm search), 99 % of a 21^3 grid in it is
    # feasible; the corners beyond the model's reach (370 mm) or below the shoulder are not.
    size = np.array([0.191, 0.381, 0.267])
    axes = [np.linspace(-s / 2, s / 2, 21) for s in size]
    box = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3) + [0.1975, 0.0, 0.025]
    qb, ok = mech.inverse(box)
    feas = np.zeros(len(box), bool)
    feas[ok] = mech.feasible(qb[ok])
    assert 0.98 <= feas.mean() < 1.0


def test_source_table_round_trips_and_names_a_bad_key():
    from resources import PresetError, parse_preset_text, preset_to_toml
    preset = load_preset("phantom_premium_15")
    again = parse_preset_text(preset_to_toml(preset), "phantom_premium_15.toml", "phantom_premium_15")
    assert again.provenance == preset.provenance and again.mechanism == preset.mechanism
    text = preset_to_toml(preset).replace('repository = "https://github.com/mahilab/Phantom"', "repository = true")
    with pytest.raises(PresetError, match=r"preset 'x.toml': key 'source.repository' must be a string"):
        parse_preset_text(text, "x.toml")


def test_phantom_omni_preset_against_its_sources():
    """Ubitrack component_haptic_calibration bf778bb (lengths, FK) and sawSensablePhantom 7ddd575
    models/urdf/omni.urdf (ranges; elbow = q3 - q2 by mtsSensableHD.cpp:419). Torques are estimates."""
    preset = load_preset("phantom_omni")
    mech = preset.mechanism
    p = mech.params
    # PhantomForwardKinematics.xml:50, 55 (0.13335 m; the preset's mm -> m within an ulp).
    np.testing.assert_allclose([p.link1_length, p.link2_length], [0.13335, 0.13335], rtol=EPS, atol=0)
    # omni.urdf:83 (waist +-0.98), :90 (shoulder 0..1.75), :98 (elbow -0.81..1.25 rad), written in
    # the preset as degrees to 6 decimals: within 1e-6 deg.
    tol = 1e-6 * DEG
    np.testing.assert_allclose([p.lower_limits[0], p.upper_limits[0]], [-0.98, 0.98], rtol=0, atol=tol)
    np.testing.assert_allclose([p.lower_limits[1], p.upper_limits[1]], [0.0, 1.75], rtol=0, atol=tol)
    np.testing.assert_allclose([p.max_q2_minus_q3, p.max_q3_minus_q2], [0.81, 1.25], rtol=0, atol=tol)
    assert dict(preset.provenance)["estimated"][:2] == ("motor_torques", "peak_motor_torques")
    # Ubitrack PhantomForwardKinematics.h:101-103 with no calibration (calx = caly = calz = 0) is
    # our FK in the OpenHaptics frame: (x, y, z)_OH = (-y, z + l2, x - l1).
    q = feasible_joints(mech, 50, seed=6)
    x, _ = mech.forward(q)
    r = p.link1_length * np.cos(q[:, 1]) + p.link2_length * np.sin(q[:, 2])
    ubitrack = np.stack([-r * np.sin(q[:, 0]),
                         p.link1_length * np.sin(q[:, 1]) - p.link2_length * np.cos(q[:, 2]) + p.link2_length,
                         -p.link1_length + r * np.cos(q[:, 0])], -1)
    np.testing.assert_allclose(np.stack([-x[:, 1], x[:, 2] + p.link2_length, x[:, 0] - p.link1_length], -1),
                               ubitrack, rtol=0, atol=16 * EPS * (p.link1_length + p.link2_length))
    # The sales workspace 160 W x 120 H x 70 D mm (y, z, x) fits wholly at (135, 0, -60) mm.
    size = np.array([0.070, 0.160, 0.120])
    axes = [np.linspace(-s / 2, s / 2, 21) for s in size]
    box = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3) + [0.135, 0.0, -0.060]
    qb, ok = mech.inverse(box)
    assert ok.all() and mech.feasible(qb).all()
    # The estimated torques give back the quoted forces at q = 0 (circular by construction: a
    # check of the arithmetic, not of the device): 0.44 / l1 = 3.3 N, 0.117 / l1 = 0.877 N.
    assert mech.peak_torque_limits()[1] / p.link1_length == pytest.approx(3.3, rel=1e-3)
    assert mech.torque_limits()[1] / p.link1_length == pytest.approx(0.88, abs=0.005)
