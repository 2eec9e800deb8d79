"""Twin-Pantograph (paper 001, our reconstructed geometry): IK against an independent five-bar,
round trips, the inverse Jacobian against central differences along twists, statics by
virtual work, the redundant force map and its zonotope, the passive-waist singularity,
feasibility at constructed boundaries, batches, and parameter validation.

Headless: numpy only (plus metrics.polytopes for the zonotope). Fixed seeds.
"""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from kinematics import FiveBar, TwinPantograph, TwinPantographParams, pose_memo
from kinematics.rotations import rotation_matrix, rotation_vector, tilt_matrix, tilt_of_direction
from metrics.zonotopes import zonotope

DEG = np.pi / 180.0
MODES = list(itertools.product(("active", "passive"), ("active", "passive")))   # (waist q4, roll q7)
IDS = [f"waist-{w}-roll-{r}" for w, r in MODES]


def _mech(waist: str, roll: str, **kw) -> TwinPantograph:
    return TwinPantograph(redundant_waist=waist, roll_actuator=roll, **kw)


def _random_poses(mech: TwinPantograph, count: int, seed: int, *, tilt: float = 40 * DEG) -> np.ndarray:
    """Feasible poses in (and around) paper 001's workspace: +-8 x +-5 x 25+-5 cm, tilts up to ``tilt``."""
    rng = np.random.default_rng(seed)
    n = 6 * count
    centre = np.array([0.0, 0.0, 0.25]) + rng.uniform(-1, 1, (n, 3)) * [0.08, 0.05, 0.05]
    if mech.six_dof:
        axis = rng.normal(size=(n, 3))
        orient = axis / np.linalg.norm(axis, axis=1, keepdims=True) * rng.uniform(0, tilt, (n, 1))
    else:
        angle = rng.uniform(0, 2 * np.pi, n)
        orient = rng.uniform(0, tilt, (n, 1)) * np.stack([np.cos(angle), np.sin(angle)], -1)
    x = np.concatenate([centre, orient], -1)
    q, ok = mech.inverse(x)
    keep = ok & mech.feasible(q, x)
    assert np.count_nonzero(keep) >= count, "not enough feasible random poses"
    return x[keep][:count]


def _moved(mech: TwinPantograph, x: np.ndarray, xi: np.ndarray, t: float) -> np.ndarray:
    """The pose reached from ``x`` (..., m) after time ``t`` at constant twist ``xi`` (..., m)."""
    centre = x[..., :3] + t * xi[..., :3]
    if mech.six_dof:
        rot = rotation_matrix(t * xi[..., 3:]) @ rotation_matrix(x[..., 3:])
        return np.concatenate([centre, rotation_vector(rot)], -1)
    frame = tilt_matrix(x[..., 3:])
    omega = xi[..., 3:4] * frame[..., :, 0] + xi[..., 4:5] * frame[..., :, 2]     # across the pen
    pen = np.einsum("...ij,...j->...i", rotation_matrix(t * omega), frame[..., :, 1])
    return np.concatenate([centre, tilt_of_direction(pen)], -1)


def _twist_derivative(mech: TwinPantograph, x: np.ndarray, xi: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """Central difference of the IK joints along the twist ``xi``: (..., n)."""
    qp, okp = mech.inverse(_moved(mech, x, xi, h))
    qm, okm = mech.inverse(_moved(mech, x, xi, -h))
    assert okp.all() and okm.all()
    return (qp - qm) / (2 * h)


# -- parameters, names, the paper's values ------------------------------------------------
def test_defaults_are_paper_001_table_vii_optimum_with_redundant_waist():
    p = TwinPantograph().params
    assert (p.shoulder_separation, p.upper_arm, p.forearm, p.unit_separation, p.pen_length) == \
        (0.024, 0.170, 0.230, 0.080, 0.070)
    assert p.ujoint_limit == pytest.approx(85 * DEG)
    mech = TwinPantograph()
    assert mech.joint_names == ("q1", "q2", "q3", "q4", "q5", "q6")
    assert mech.task_names == ("x", "y", "z", "rx", "rz") and mech.task_units[3:] == ("rad", "rad")
    assert (mech.n_joints, mech.task_dim, mech.redundant) == (6, 5, True)
    t = mech.torque_limits()
    assert t[0] / t[1] == pytest.approx(1.6)                  # Table VII: Q1 = 1.6 (waist / shoulder)
    np.testing.assert_array_equal(t, [0.16, 0.1, 0.1, 0.16, 0.1, 0.1])


@pytest.mark.parametrize(("waist", "roll", "joints", "task"), [
    ("active", "passive", ("q1", "q2", "q3", "q4", "q5", "q6"), 5),
    ("passive", "active", ("q1", "q2", "q3", "q5", "q6", "q7"), 6),      # paper 001 Table III (6 x 6)
    ("passive", "passive", ("q1", "q2", "q3", "q5", "q6"), 5),
    ("active", "active", ("q1", "q2", "q3", "q4", "q5", "q6", "q7"), 6),
])
def test_actuation_modes_set_joints_and_task(waist, roll, joints, task):
    mech = _mech(waist, roll, gear_ratios=(1, 2, 3, 4, 5, 6, 7))
    assert mech.joint_names == joints and mech.n_joints == len(joints) and mech.task_dim == task
    assert mech.redundant == (len(joints) > task)
    idx = [int(j[1]) - 1 for j in joints]
    np.testing.assert_allclose(mech.torque_limits(), np.array(mech.params.motor_torques)[idx] * (np.array(idx) + 1))
    lo, hi = mech.joint_limits()
    assert lo.shape == hi.shape == (len(joints),)
    x = mech.home_pose(0.25)
    assert x.shape == (task,)
    q, ok = mech.inverse(x)
    assert q.shape == (len(joints),) and bool(ok) and bool(mech.feasible(q, x))
    assert mech.inverse_jacobian(q, x).shape == (len(joints), task)
    assert mech.force_map(q, x).shape == mech.jacobian(q, x).shape == (task, len(joints))


# -- inverse kinematics against an independent five-bar -----------------------------------
def test_home_pose_matches_hand_geometry_and_the_five_bar_model():
    mech = TwinPantograph()
    p = mech.params
    d = 0.25
    q, ok = mech.all_joints(mech.home_pose(d))
    assert ok
    offset = 0.5 * (p.unit_separation - p.pen_length)      # each tip's distance from its unit's plane at psi = 0
    assert q[0] == pytest.approx(-np.arctan2(offset, d), abs=1e-15)
    assert q[3] == pytest.approx(np.arctan2(offset, d), abs=1e-15)
    # The in-plane tip (u, w) = (0, hypot(offset, d)) solved by the paper-002 five-bar model:
    fivebar = FiveBar(proximal=p.upper_arm, distal=p.forearm, half_base=p.shoulder_separation / 2,
                      working_mode="+-")
    expected, fb_ok = fivebar.inverse(np.array([0.0, np.hypot(offset, d)]))
    assert fb_ok
    np.testing.assert_allclose(q[1:3], expected, rtol=0, atol=1e-14)
    np.testing.assert_allclose(q[4:6], expected, rtol=0, atol=1e-14)
    assert np.isnan(q[6])                                    # no roll in the 5-DOF task
    # Bend at home: the pen (along y) against the plane normal, tilted by the waist angle.
    np.testing.assert_allclose(mech.bend_angles(mech.home_pose(d)), [np.arctan2(offset, d)] * 2, atol=1e-15)


def test_tips_of_the_ik_lie_on_the_pen_at_the_link_lengths():
    mech = _mech("active", "active")
    x = _random_poses(mech, 200, seed=3)
    pts = mech.link_points(mech.inverse(x)[0], x)                         # (200, 16, 3)
    p = mech.params
    rot = rotation_matrix(x[:, 3:])
    np.testing.assert_allclose(pts[:, 3], x[:, :3] - p.pen_length / 2 * rot[:, :, 1], atol=1e-15)
    np.testing.assert_allclose(pts[:, 4], x[:, :3] + p.pen_length / 2 * rot[:, :, 1], atol=1e-15)
    dist = lambda i, j: np.linalg.norm(pts[:, i] - pts[:, j], axis=-1)    # noqa: E731
    for shoulder, elbow, tip in ((1, 2, 3), (6, 5, 4), (8, 9, 10), (13, 12, 11)):
        np.testing.assert_allclose(dist(shoulder, elbow), p.upper_arm, rtol=1e-13)
        np.testing.assert_allclose(dist(elbow, tip), p.forearm, rtol=1e-13)
    np.testing.assert_allclose(dist(0, 14), 0.0, atol=0)
    np.testing.assert_allclose(dist(14, 15), p.unit_separation, rtol=1e-15)
    np.testing.assert_allclose(dist(1, 13), p.shoulder_separation, rtol=1e-13)
    # Every point of unit A lies in its five-bar plane: normal (0, -cos psi, -sin psi) through (0, -l4/2, 0).
    q_all, _ = mech.all_joints(x)
    n = np.stack([np.zeros(200), -np.cos(q_all[:, 0]), -np.sin(q_all[:, 0])], -1)
    for i in (0, 1, 2, 3, 12, 13):
        rel = pts[:, i] - [0.0, -p.unit_separation / 2, 0.0]
        np.testing.assert_allclose(np.sum(rel * n, -1), 0.0, atol=1e-15)


# -- round trips ----------------------------------------------------------------------------
@pytest.mark.parametrize(("waist", "roll"), MODES, ids=IDS)
def test_forward_inverts_inverse(waist, roll):
    mech = _mech(waist, roll)
    x = _random_poses(mech, 300, seed=11)
    q, ok = mech.inverse(x)
    assert ok.all()
    back, ok2 = mech.forward(q)
    assert ok2.all()
    np.testing.assert_allclose(back, x, rtol=0, atol=1e-12)
    q2, _ = mech.inverse(back)
    np.testing.assert_allclose(q2, q, rtol=0, atol=1e-12)


def test_redundant_forward_rejects_inconsistent_joints():
    mech = TwinPantograph()
    q, _ = mech.inverse(mech.home_pose())
    x, ok = mech.forward(q)
    assert ok
    bad = q.copy()
    bad[3] += 1e-3                                    # turn the redundant waist alone: the pen would stretch
    x, ok = mech.forward(bad)
    assert not ok and np.isnan(x).all()


# -- Jacobians against central differences ------------------------------------------------
@pytest.mark.parametrize(("waist", "roll"), MODES, ids=IDS)
def test_inverse_jacobian_matches_central_differences_along_twists(waist, roll):
    mech = _mech(waist, roll)
    x = _random_poses(mech, 100, seed=21)
    q, _ = mech.inverse(x)
    k = mech.inverse_jacobian(q, x)                                  # (100, n, m)
    scale = np.abs(k).max(axis=(-2, -1), keepdims=True)
    for j in range(mech.task_dim):
        xi = np.zeros_like(x)
        xi[:, j] = 1.0
        fd = _twist_derivative(mech, x, xi)
        err = np.abs(fd - k[:, :, j]) / scale[:, :, 0]
        assert err.max() < 1e-8, (j, err.max())


@pytest.mark.parametrize(("waist", "roll"), MODES, ids=IDS)
def test_coordinate_rates_to_twist_chains_with_the_inverse_jacobian(waist, roll):
    """d q / d(coordinates) = K @ T(x): checks T (left Jacobian / tilt basis) by differences."""
    mech = _mech(waist, roll)
    x = _random_poses(mech, 40, seed=22)
    q, _ = mech.inverse(x)
    chain = mech.inverse_jacobian(q, x) @ mech.coordinate_rates_to_twist(x)
    h = 1e-6
    for j in range(mech.task_dim):
        step = np.zeros_like(x)
        step[:, j] = h
        fd = (mech.inverse(x + step)[0] - mech.inverse(x - step)[0]) / (2 * h)
        np.testing.assert_allclose(fd, chain[:, :, j], rtol=0, atol=1e-7 * np.abs(chain).max())


@pytest.mark.parametrize(("waist", "roll"), MODES, ids=IDS)
def test_jacobian_inverts_the_inverse_jacobian(waist, roll):
    mech = _mech(waist, roll)
    x = _random_poses(mech, 100, seed=31)
    q, _ = mech.inverse(x)
    k = mech.inverse_jacobian(q, x)
    jac = mech.jacobian(q, x)
    eye = np.eye(mech.task_dim)
    np.testing.assert_allclose(jac @ k, np.broadcast_to(eye, jac.shape[:-2] + eye.shape), atol=1e-11)
    # xi = J qdot recovers the twist from any consistent joint rates.
    rng = np.random.default_rng(32)
    xi = rng.normal(size=x.shape)
    np.testing.assert_allclose(np.einsum("...ij,...j->...i", jac, np.einsum("...ij,...j->...i", k, xi)), xi,
                               atol=1e-11)
    # Without x, the pose comes from forward(q): the same matrix.
    np.testing.assert_allclose(mech.jacobian(q[:5]), jac[:5], rtol=1e-10, atol=1e-12)


# -- statics: virtual work, the redundant force map --------------------------------------
@pytest.mark.parametrize(("waist", "roll"), MODES, ids=IDS)
def test_force_map_satisfies_virtual_work_for_consistent_motions(waist, roll):
    """For joint rates of a real motion (differences of the IK along a twist xi) and any
    torques tau, tau . qdot = w . xi with w = A tau: A is the force map, derived, not assumed."""
    mech = _mech(waist, roll)
    x = _random_poses(mech, 60, seed=41)
    q, _ = mech.inverse(x)
    a = mech.force_map(q, x)
    rng = np.random.default_rng(42)
    xi = rng.normal(size=x.shape) * np.r_[[0.1] * 3, [1.0] * (mech.task_dim - 3)]
    tau = rng.normal(size=q.shape)
    qdot = _twist_derivative(mech, x, xi)
    w = np.einsum("...ij,...j->...i", a, tau)
    power_joints = np.sum(tau * qdot, -1)
    power_task = np.sum(w * xi, -1)
    np.testing.assert_allclose(power_joints, power_task, rtol=0, atol=1e-7 * np.abs(power_task).max())
    # tau = J^T w reproduces w (least-norm torques when redundant: orthogonal to A's null space).
    least = np.einsum("...ji,...j->...i", mech.jacobian(q, x), w)
    np.testing.assert_allclose(np.einsum("...ij,...j->...i", a, least), w, atol=1e-10)
    if mech.redundant:
        null = np.linalg.svd(a)[2][:, -1, :]                       # (60, n): internal (antagonistic) torques
        np.testing.assert_allclose(np.sum(least * null, -1), 0.0, atol=1e-10)
        assert np.all(np.linalg.norm(least, axis=-1) <= np.linalg.norm(tau, axis=-1) + 1e-12)


def test_6dof_force_map_rows_are_pen_wrenches():
    """Column u of A (tau = e_u) is the wrench actuator u applies through its own unit: for unit A's
    actuators q1..q3 a force F at tip A, so the moment about the pen centre is (T_A - c) x F."""
    mech = _mech("passive", "active")
    x = _random_poses(mech, 20, seed=51)
    q, _ = mech.inverse(x)
    a = mech.force_map(q, x)
    # Actuator q1 acts on tip A only, through the tip force F: the wrench about the centre is
    # (F, (T_A - c) x F). So the moment column is (T_A - c) x (force column).
    rot = rotation_matrix(x[:, 3:])
    arm = -mech.params.pen_length / 2 * rot[:, :, 1]
    for col in range(3):                                            # q1, q2, q3 (unit A)
        f, m = a[:, :3, col], a[:, 3:, col]
        np.testing.assert_allclose(m, np.cross(arm, f), atol=1e-12 * np.abs(a).max())


def test_redundant_zonotope_contains_the_passive_waist_parallelepiped():
    """Actuating q4 adds one generator: A_passive is A_redundant without column q4, and the
    inscribed radius (metrics.zonotopes.zonotope) can only grow. The radius is also the
    minimum support value, checked against many random directions."""
    red, pas = _mech("active", "passive"), _mech("passive", "passive")
    x = _random_poses(red, 30, seed=61)
    q_red, _ = red.inverse(x)
    q_pas, _ = pas.inverse(x)
    a_red, a_pas = red.force_map(q_red, x), pas.force_map(q_pas, x)
    np.testing.assert_allclose(np.delete(a_red, 3, axis=-1), a_pas, rtol=1e-13, atol=1e-13)
    zono = zonotope(a_red, torque_limits=red.torque_limits())
    r_red = zono.inscribed_radius
    r_pas = zonotope(a_pas, torque_limits=pas.torque_limits()).inscribed_radius
    assert np.all(r_red >= r_pas * (1 - 1e-12)) and np.all(r_red > r_pas)
    # Support function h(d) = sum_u t_u |A_u . d| >= r for every unit d ...
    t = red.torque_limits()
    rng = np.random.default_rng(62)
    d = rng.normal(size=(20000, 5))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    support = np.abs(np.einsum("kn,bnu->bku", d, a_red)) @ t                     # (30, 20000)
    assert np.all(support.min(axis=1) >= r_red * (1 - 1e-12))
    # ... with equality at the nearest facet's normal, which is orthogonal to m - 1 = 4 generators.
    best = zono.normals[np.arange(30), np.argmin(zono.offsets, axis=-1)]          # (30, 5)
    along = np.einsum("bn,bnu->bu", best, a_red)
    np.testing.assert_allclose(np.abs(along) @ t, r_red, rtol=1e-12)
    scale = np.linalg.norm(a_red, axis=-2)
    assert np.all(np.sum(np.abs(along) < 1e-9 * scale, axis=-1) >= 4)


def test_passive_waist_singularity_when_the_pen_lies_in_unit_b_plane():
    """Paper 001 sec. V: with a passive waist, the device is singular when the pen lies in the
    five-bar's plane; the redundant waist actuator removes that singularity."""
    x = np.array([0.0, 0.0, 0.25, 0.0, -np.pi / 2])             # tilt about z by -90 deg: pen along +x
    pas, red = _mech("passive", "passive"), _mech("active", "passive")
    qp, ok = pas.inverse(x)
    assert ok
    sv = np.linalg.svd(pas.inverse_jacobian(qp, x), compute_uv=False)
    assert sv[-1] < 1e-12 * sv[0]
    assert not np.all(np.isfinite(pas.jacobian(qp, x))) or np.abs(pas.jacobian(qp, x)).max() > 1e10
    qr, _ = red.inverse(x)
    sv_red = np.linalg.svd(red.force_map(qr, x), compute_uv=False)
    assert sv_red[-1] > 1e-3 * sv_red[0]
    # There the bend is 90 deg, so the pose is outside the workspace anyway.
    np.testing.assert_allclose(pas.bend_angles(x), [np.pi / 2] * 2, atol=1e-12)
    assert not pas.feasible(qp, x)


# -- batches -----------------------------------------------------------------------------
@pytest.mark.parametrize(("waist", "roll"), MODES, ids=IDS)
def test_batch_equals_one_at_a_time(waist, roll):
    mech = _mech(waist, roll)
    x = _random_poses(mech, 12, seed=71).reshape(3, 4, mech.task_dim)
    x[0, 0, 2] = 2.0                                             # one unreachable pose in the batch
    q, ok = mech.inverse(x)
    assert not ok[0, 0] and np.isnan(q[0, 0]).all()
    fwd, fok = mech.forward(np.where(ok[..., None], q, 0.0))
    k = mech.inverse_jacobian(q, x)
    jac = mech.jacobian(q, x)
    feas = mech.feasible(q, x)
    pts = mech.link_points(q, x)
    for i, j in itertools.product(range(3), range(4)):
        q1, ok1 = mech.inverse(x[i, j])
        assert ok1 == ok[i, j]
        np.testing.assert_array_equal(q1, q[i, j])
        if not ok1:
            assert not feas[i, j]
            continue
        np.testing.assert_array_equal(mech.forward(q1)[0], fwd[i, j])
        np.testing.assert_array_equal(mech.inverse_jacobian(q1, x[i, j]), k[i, j])
        np.testing.assert_allclose(mech.jacobian(q1, x[i, j]), jac[i, j], rtol=1e-13, atol=1e-15)
        assert mech.feasible(q1, x[i, j]) == feas[i, j]
        np.testing.assert_array_equal(mech.link_points(q1, x[i, j]), pts[i, j])


# -- feasibility at constructed boundaries --------------------------------------------------
def test_reach_boundary_is_the_stretched_five_bar():
    """Pen along y at x = 0: each tip is at in-plane (0, w) with both legs at distance
    hypot(l1/2, w); the legs stretch when that equals l2 + l3."""
    mech = TwinPantograph()
    p = mech.params
    w = np.sqrt((p.upper_arm + p.forearm) ** 2 - (p.shoulder_separation / 2) ** 2)
    z = np.sqrt(w ** 2 - (0.5 * (p.unit_separation - p.pen_length)) ** 2)
    inside = np.array([[0, 0, z - 1e-9, 0, 0]])
    outside = np.array([[0, 0, z + 1e-9, 0, 0]])
    q, ok = mech.inverse(inside)
    assert ok.all() and mech.feasible(q, inside).all()
    q, ok = mech.inverse(outside)
    assert not ok.any() and not mech.feasible(q, outside).any()


def test_bend_limit_boundary():
    mech = TwinPantograph()
    x = np.array([0.02, -0.01, 0.26, 0.3, -0.5])
    bends = mech.bend_angles(x)
    worst = bends.max()
    assert 20 * DEG < worst < 60 * DEG
    q, ok = mech.inverse(x)
    assert ok
    assert mech.replace(ujoint_limit=worst + 1e-9).feasible(q, x)
    assert not mech.replace(ujoint_limit=worst - 1e-9).feasible(q, x)
    # The bend is the angle between the pen and the unit's plane normal (0, -cos psi, -sin psi).
    q_all, _ = mech.all_joints(x)
    pen = tilt_matrix(x[3:])[:, 1]
    for unit, psi in enumerate(q_all[[0, 3]]):
        normal = -np.array([0.0, -np.cos(psi), -np.sin(psi)])
        assert bends[unit] == pytest.approx(np.arccos(pen @ normal), abs=1e-12)


@pytest.mark.parametrize("joint", [1, 3])            # an actuated shoulder (q2) and the passive waist q4
def test_joint_limit_boundaries_apply_to_active_and_passive_joints(joint):
    mech = _mech("passive", "passive")
    x = np.array([0.03, 0.02, 0.24, 0.1, 0.2])
    q, ok = mech.inverse(x)
    q_all, _ = mech.all_joints(x)
    value = q_all[joint]
    upper = list(mech.params.upper_limits)
    lower = list(mech.params.lower_limits)
    upper[joint] = value + 1e-9
    assert mech.replace(upper_limits=tuple(upper)).feasible(q, x)
    upper[joint] = value - 1e-9
    lower[joint] = min(lower[joint], value - 1.0)
    assert not mech.replace(upper_limits=tuple(upper), lower_limits=tuple(lower)).feasible(q, x)


# -- validation ---------------------------------------------------------------------------
@pytest.mark.parametrize(("changes", "phrase"), [
    ({"forearm": -0.23}, "forearm"),
    ({"pen_length": 0.0}, "pen_length"),
    ({"shoulder_separation": float("nan")}, "shoulder_separation"),
    ({"upper_arm": "long"}, "upper_arm"),
    ({"ujoint_limit": 0.0}, "ujoint_limit"),
    ({"ujoint_limit": 100 * DEG}, "ujoint_limit"),
    ({"motor_torques": (0.1,) * 6}, "motor_torques"),
    ({"gear_ratios": (1, 1, 1, 0, 1, 1, 1)}, "gear_ratios[q4]"),
    ({"lower_limits": (0.0, 0.0, 0.0, 0.0, 5.0, 0.0, 0.0)}, "lower_limits[q5]"),
    ({"upper_limits": (1.0,) * 6 + (float("inf"),)}, "upper_limits[q7]"),
    ({"redundant_waist": "maybe"}, "redundant_waist"),
    ({"roll_actuator": True}, "roll_actuator"),
    ({"wheel_count": 4}, "wheel_count"),
])
def test_invalid_parameters_raise_naming_the_parameter(changes, phrase):
    with pytest.raises(ValueError, match=None) as info:
        TwinPantograph().replace(**changes)
    assert phrase in str(info.value)
    if "wheel_count" not in changes:
        with pytest.raises(ValueError):
            TwinPantographParams(**changes)


def test_replace_display_and_immutability():
    mech = TwinPantograph()
    other = mech.replace_display(forearm=250, ujoint_limit=80, redundant_waist="passive")
    assert other.params.forearm == 0.25 and other.params.ujoint_limit == pytest.approx(80 * DEG)
    assert other.n_joints == 5 and mech.n_joints == 6 and mech != other
    assert mech == TwinPantograph() and hash(mech) == hash(TwinPantograph())
    with pytest.raises(ValueError, match="forearm"):
        mech.replace_display(forearm=-5)
    with pytest.raises(AttributeError):
        mech.params = None                                            # type: ignore[misc]
    with pytest.raises(ValueError, match=r"x must have shape \(\.\.\., 5\)"):
        mech.inverse(np.zeros(6))
    with pytest.raises(ValueError, match=r"q must have shape \(\.\.\., 6\)"):
        mech.forward(np.zeros(5))


# -- the roll drive through the U-joint (6-DOF) ---------------------------------------------
def test_roll_drive_follows_the_cardan_joint_law():
    """Rolling the pen about its own axis moves only q7. With the U-joint straight the drive
    turns by exactly minus the roll (it turns about n_A = -pen); bent by beta, its speed ratio
    swings between cos(beta) and 1/cos(beta) over a turn, the law of a Cardan joint."""
    mech = _mech("passive", "active")
    p = mech.params
    straight = np.array([0.01, -p.unit_separation / 2 + p.pen_length / 2, 0.24])   # tip A on psi_A = 0
    rolls = np.array([0.0, 0.3, -1.0, 2.0])
    x = np.concatenate([np.broadcast_to(straight, (4, 3)), rolls[:, None] * [0.0, 1.0, 0.0]], -1)
    q, ok = mech.inverse(x)
    assert ok.all() and mech.bend_angles(x[0])[0] == pytest.approx(0.0, abs=1e-15)
    np.testing.assert_allclose(q[:, :5], np.broadcast_to(q[0, :5], (4, 5)), atol=1e-15)
    np.testing.assert_allclose(q[:, 5] - q[0, 5], -rolls, atol=1e-14)

    base = rotation_matrix([0.3, 0.0, -0.4])
    roll = np.linspace(0.0, 2 * np.pi, 20001)
    rot = rotation_matrix(roll[:, None] * base[:, 1]) @ base
    x = np.concatenate([np.broadcast_to([0.01, 0.0, 0.24], (roll.size, 3)), rotation_vector(rot)], -1)
    q, ok = mech.inverse(x)
    assert ok.all()
    np.testing.assert_allclose(q[:, :5], np.broadcast_to(q[0, :5], q[:, :5].shape), atol=1e-13)
    beta = mech.bend_angles(x[0])[0]
    assert 20 * DEG < beta < 40 * DEG
    drive = np.unwrap(q[:, 5])
    ratio = np.abs(np.gradient(drive, roll))
    assert ratio.max() == pytest.approx(1 / np.cos(beta), rel=1e-6)
    assert ratio.min() == pytest.approx(np.cos(beta), rel=1e-6)
    assert drive[-1] - drive[0] == pytest.approx(-2 * np.pi, abs=1e-12)


# -- robustness, presets ---------------------------------------------------------------------------
@pytest.mark.parametrize(("waist", "roll"), MODES, ids=IDS)
def test_bad_inputs_become_nan_and_masks_without_warnings(waist, roll):
    """pyproject turns warnings into errors, so no inf - inf or 0/0 may escape either."""
    mech = _mech(waist, roll)
    m = mech.task_dim
    x = np.array([[0.1, -0.005, 0.0] + [0.0] * (m - 3),          # tip A on its own waist axis
                  [0.0, 0.0, 2.0] + [0.0] * (m - 3),             # out of reach
                  [np.nan] * m, [np.inf] * m])
    q, ok = mech.inverse(x)
    np.testing.assert_array_equal(ok, [True, False, False, False])
    assert np.isnan(q[1:]).all()
    assert not mech.feasible(q, x).any()
    jac = mech.jacobian(q, x)
    assert not np.isfinite(jac[0]).all()                          # the waist rate is unbounded there
    assert np.isnan(jac[1:]).all() and np.isnan(mech.link_points(q, x)[1:]).all()
    assert np.isnan(mech.coordinate_rates_to_twist(x)[2:]).all()
    bad_q = np.array([[np.nan] * mech.n_joints, [-np.inf] * mech.n_joints, [1e3] * mech.n_joints])
    fx, fok = mech.forward(bad_q)
    assert not fok[:2].any() and np.isnan(fx[:2]).all()
    assert not mech.feasible(bad_q[:2]).any()


def test_shipped_preset_is_the_default_design_and_feasible():
    from resources import load_preset, parse_preset_text, preset_to_toml
    preset = load_preset("twin_pantograph")
    # The preset switches on the default (estimated) mass model and paper 001's adopted reading
    # (docs/reproduction.md: each U-joint l6 from the pen's centre).
    assert preset.kind == "twin_pantograph"
    assert preset.mechanism == TwinPantograph(mass_model="estimated", ujoint_lever=1.0)
    assert preset.grid.axes == ("x", "z") and dict(preset.grid.fixed) == {"y": 0.0, "rx": 0.0, "rz": 0.0}
    x = np.array(preset.pose)
    q, ok = preset.mechanism.inverse(x)
    assert ok and preset.mechanism.feasible(q, x)
    again = parse_preset_text(preset_to_toml(preset), "twin_pantograph.toml", "twin_pantograph")
    assert again.mechanism == preset.mechanism and again.grid == preset.grid and again.pose == preset.pose


def _stacked_reach(mech: TwinPantograph, x: np.ndarray):
    """The reach and limit test as the model computed it before its pen axis, tips and plane frames were
    kept by component (stacked (..., 3) arrays, ``vector_rows.angle_between(p, -n)``): ``(q, ok, bends)``."""
    from kinematics.angles import wrap_into
    from kinematics.rotations import finite_rows
    from kinematics.vector_rows import angle_between

    x, finite = finite_rows(x, mech.home_pose())
    rot = mech._rotation(x)
    p = rot[..., :, 1]
    tips = x[..., None, :3] + mech.tip_offsets(rot)
    l2, l3 = mech.params.upper_arm, mech.params.forearm
    joints, normals, ok = [], [], finite
    for k, y0 in enumerate(mech.unit_bases()[:, 1]):
        tip = tips[..., k, :]
        dy, dz = tip[..., 1] - y0, tip[..., 2]
        psi = np.arctan2(-dy, dz)
        w = np.hypot(dy, dz)
        zero = np.zeros_like(psi)
        normals.append(np.stack([zero, -np.cos(psi), -np.sin(psi)], -1))
        joints.append(psi)
        for (sx, sw), elbow in zip(mech._shoulders(), (1.0, -1.0)):
            du, dw = tip[..., 0] - sx, w - sw
            rho = np.hypot(du, dw)
            with np.errstate(divide="ignore", invalid="ignore"):
                cos_e = (l2 * l2 + rho * rho - l3 * l3) / (2.0 * l2 * rho)
            ok = ok & (np.abs(cos_e) <= 1.0 + 8 * np.finfo(float).eps)
            joints.append(np.arctan2(dw, du) + elbow * np.arccos(np.clip(cos_e, -1.0, 1.0)))
    lo, hi = mech.params.lower_limits, mech.params.upper_limits
    q = np.stack([wrap_into(joints[i], lo[i], hi[i])[0] for i in mech.actuated], -1)
    bends = np.stack([angle_between(p, -n) for n in normals], -1)
    return np.where(ok[..., None], q, np.nan), ok, bends


@pytest.mark.parametrize("changes", [{}, {"redundant_waist": "passive"},
                                     {"reference_along": 0.3, "reference_offset": 0.01, "ujoint_lever": 1.0}])
def test_reach_test_by_component_is_the_stacked_one_bit_for_bit(changes):
    """``inverse``, ``bend_angles`` and ``feasible`` (5-DOF) give the stacked computation's values exactly:
    the same operations on the same numbers, in a repeating orientation block (the dextrous region's
    batches, ``pose_memo.per_block``) and in free batches, with non-finite rows among them."""
    mech = TwinPantograph(**changes)
    rng = np.random.default_rng(7)
    centres = np.array([0.0, 0.0, 0.25]) + rng.uniform(-1, 1, (300, 3)) * [0.3, 0.3, 0.3]
    tilts = rng.uniform(-0.6, 0.6, (8, 2))
    # Grid positions, x fastest, each with the block of tilts: the waists are folded (computed once
    # per position (y, z) and tilt, pose_memo.fold_rows).
    axes = [np.linspace(-0.3, 0.3, 10), np.linspace(-0.3, 0.3, 5), np.linspace(-0.05, 0.55, 6)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).transpose(1, 2, 0, 3).reshape(-1, 3)
    block = np.concatenate([np.repeat(grid, 8, axis=0), np.tile(tilts, (len(grid), 1))], -1)
    assert pose_memo.fold_rows(block, slice(3, None), slice(0, 3), slice(1, 3)).groups == 30
    free = np.concatenate([centres, rng.uniform(-0.6, 0.6, (300, 2))], -1)
    free[3], free[5, 1] = np.nan, np.inf
    far = free.copy()                      # most out of reach: the angles are computed where a unit reaches
    far[:, :3] = np.array([0.0, 0.0, 0.25]) + rng.uniform(-0.6, 0.6, (300, 3))
    assert np.count_nonzero(mech.inverse(far)[1]) < 0.3 * len(far)
    for x in (block, free, far, free[0]):
        q, ok = mech.inverse(x)
        q_ref, ok_ref, bends_ref = _stacked_reach(mech, x)
        assert ok.any() and (~ok).any() if x.ndim == 2 else True          # both kinds of pose are tested
        np.testing.assert_array_equal(ok, ok_ref)
        assert q.tobytes() == q_ref.tobytes()                               # every bit, nan and signed zeros
        finite = np.all(np.isfinite(x), -1)
        bends = mech.bend_angles(x)
        assert bends[finite].tobytes() == bends_ref[finite].tobytes()
        lim = mech.params
        want = ok_ref & np.all([(q_ref[..., k] >= lim.lower_limits[i]) & (q_ref[..., k] <= lim.upper_limits[i])
                                for k, i in enumerate(mech.actuated)], axis=0)
        if mech.params.redundant_waist == "passive":                          # q4 comes from the pose
            q4 = mech.all_joints(x)[0][..., 3]
            want &= (q4 >= lim.lower_limits[3]) & (q4 <= lim.upper_limits[3])
        want &= np.all(bends_ref <= lim.ujoint_limit, -1)
        np.testing.assert_array_equal(mech.feasible(q, x), want)


@pytest.mark.parametrize("waist", ["active", "passive"])
def test_feasible_at_the_reached_rows_reads_the_inverse_configuration(waist):
    """``feasible`` at the reached rows of the poses ``inverse`` just saw (``metrics.quantities.evaluate``)
    takes those rows of its configuration: the same booleans bit for bit as a configuration built at
    those rows alone (an equal model, a different object: no memo of the first is read), and poses
    that are not exactly those rows (reordered, one bit changed) build their own."""
    mech = TwinPantograph(redundant_waist=waist)
    rng = np.random.default_rng(7)
    n = 4000
    # A grid-like batch: positions beyond the reach too (so some rows are not reached), tilts
    # repeating in blocks as a map's orientations do (the waists' fold).
    centre = np.array([0.0, 0.0, 0.25]) + rng.uniform(-1, 1, (n // 8, 3)) * [0.2, 0.1, 0.2]
    tilts = rng.uniform(-30, 30, (8, 2)) * DEG
    x = np.concatenate([np.repeat(centre, 8, axis=0), np.tile(tilts, (n // 8, 1))], -1)
    q, ok = mech.inverse(x)
    assert 0 < ok.sum() < n
    rows = mech._reached_rows(x[ok])
    assert rows is not None and np.array_equal(rows, ok)
    fast = mech.feasible(q[ok], x[ok])
    other = TwinPantograph(redundant_waist=waist)
    assert other is not mech
    reference = other.feasible(q[ok], x[ok])
    assert fast.dtype == bool and np.array_equal(fast, reference)
    assert fast.any() and not fast.all()
    mech.inverse(x)
    assert mech._reached_rows(x[ok][::-1]) is None
    moved = x[ok].copy()
    moved[0, 0] = np.nextafter(moved[0, 0], 1.0)
    assert mech._reached_rows(moved) is None
    assert other._reached_rows(x[ok]) is None          # the last inverse was mech's
