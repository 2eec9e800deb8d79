"""Inoue platform (kinematics.inoue): Jacobians against central differences at tilted poses, IK/FK
round trips (passive and redundant waists), limits, force vs moment, by-hand figures at home.

The contract test (tests/kinematics/test_contract.py) covers the preset's map at zero orientation;
here poses are tilted, so coordinate rates are turned into twists with the left Jacobian.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import linprog

from kinematics import InouePlatform
from kinematics.inoue import ALL_JOINTS
from kinematics.rotations import left_jacobian
from metrics.pose import analyse_pose
from resources import load_preset

EPS = np.finfo(float).eps
DEG = math.pi / 180


def _poses(mech, count, seed, *, tilt=0.4, span=0.06):
    """Feasible poses around home: position +-span (m), rotation vector +-tilt (rad) per axis."""
    rng = np.random.default_rng(seed)
    x = mech.home_pose() + np.concatenate([rng.uniform(-span, span, (count, 3)),
                                           rng.uniform(-tilt, tilt, (count, 3))], -1)
    q, ok = mech.inverse(x)
    good = ok.copy()
    good[ok] = mech.feasible(q[ok], x[ok])
    return x[good]


def _twist_of_rates(x):
    """``T`` (k, 6, 6) with ``[v; omega] = T xdot``: blockdiag(I, J_l(r))."""
    t = np.zeros(x.shape[:-1] + (6, 6))
    t[..., :3, :3] = np.eye(3)
    t[..., 3:, 3:] = left_jacobian(x[..., 3:])
    return t


def _scales(mech):
    """Task scale (m for positions, 1 for angles) making J dimensionless: the device size."""
    size = mech.size()
    return np.array([size] * 3 + [1.0] * 3), size


def _scaled_cond(mech, q, x):
    task, _ = _scales(mech)
    jac = mech.jacobian(q, x) / task[:, None]
    sv = np.linalg.svd(jac, compute_uv=False)
    return sv[..., 0] / sv[..., -1]


# -- derivatives ------------------------------------------------------------------------------
# Central differences D(h) with h = eps^(1/3) S (m) or eps^(1/3) (rad). Their truncation error
# is h^2 f3 / 6 + O(h^4) (f3 the third derivative), so D(h) - D(2h) = 3 h^2 f3 / 6 + ...: a third
# of it estimates D(h)'s own truncation error (Richardson), and twice the difference bounds it
# with room. Rounding adds ~eps |f| / h: |q| <= 2 pi rad and |x| <= S make that <= 2 pi eps^(2/3)
# after the task scaling, below 10 eps^(2/3) times the largest scaled entry (>= 1 here). A 1e-4
# relative error in J's orientation part is far above both (checked by mutation when written).
def _differences(f, x, steps):
    """Central differences of ``f`` (k, a) -> (k, b) at ``x`` (k, a) with steps h and 2 h per
    coordinate: two arrays (k, b, a)."""
    out = []
    for factor in (1.0, 2.0):
        cols = []
        for i, h in enumerate(factor * steps):
            dx = np.zeros(x.shape[-1])
            dx[i] = h
            cols.append((f(x + dx) - f(x - dx)) / (2 * h))
        out.append(np.stack(cols, -1))
    return out


def _check(numeric, numeric_2h, analytic, rows, cols):
    """Scaled entries (rows (b,), cols (a,)): |D(h) - J| <= 2 |D(h) - D(2h)| + 10 eps^(2/3) max |J|."""
    scale = rows[:, None] * cols[None, :]
    err = np.abs(numeric - analytic) * scale
    bound = 2 * np.abs(numeric - numeric_2h) * scale + 10 * EPS ** (2 / 3) * np.max(np.abs(analytic * scale))
    assert np.all(err <= bound), np.max(err / bound)


@pytest.mark.parametrize("waists", ["passive", "active"])
def test_inverse_jacobian_matches_central_differences_of_the_ik_at_tilted_poses(waists):
    mech = InouePlatform(waist_actuators=waists)
    x = _poses(mech, 120, seed=1)
    assert len(x) >= 50
    task, _ = _scales(mech)

    def joints(xs):
        qs, ok = mech.all_joints(xs)
        assert ok.all()
        return qs[:, :mech.n_joints]

    d1, d2 = _differences(joints, x, EPS ** (1 / 3) * task)
    q, _ = mech.inverse(x)
    analytic = mech.inverse_jacobian(q, x) @ _twist_of_rates(x)          # dq / dxdot, (k, n, 6)
    _check(d1, d2, analytic, np.ones(mech.n_joints), task)


def test_jacobian_matches_central_differences_of_the_fk_at_tilted_poses():
    mech = InouePlatform()
    x = _poses(mech, 80, seed=2)
    assert len(x) >= 30
    q, _ = mech.inverse(x)
    task, _ = _scales(mech)

    def poses(qs):
        xs, ok = mech.forward(qs, guess=x)
        assert ok.all()
        return xs

    d1, d2 = _differences(poses, q, EPS ** (1 / 3) * np.ones(6))
    twist = _twist_of_rates(x)
    _check(twist @ d1, twist @ d2, mech.jacobian(q, x), 1.0 / task, np.ones(6))


# -- round trips ------------------------------------------------------------------------------
@pytest.mark.parametrize("waists", ["passive", "active"])
def test_forward_of_inverse_is_the_pose_and_batches_keep_their_shape(waists):
    mech = InouePlatform(waist_actuators=waists)
    x = _poses(mech, 300, seed=3, tilt=0.3, span=0.08)
    assert len(x) >= 250
    q, ok = mech.inverse(x)
    back, fok = mech.forward(q)
    assert ok.all() and fok.all()
    q_ok, _ = mech.inverse(x)
    cond = _scaled_cond(mech, q_ok, x)
    # IK and FK each round to a few ulps of the device size S; the inverse map amplifies by cond.
    task, _ = _scales(mech)
    err = np.max(np.abs(back - x) / task, axis=-1)
    assert np.all(err <= 1e3 * EPS * cond)
    grid = x[:12].reshape(3, 4, 6)
    qg, okg = mech.inverse(grid)
    assert qg.shape == (3, 4, mech.n_joints) and okg.shape == (3, 4)
    xg, _ = mech.forward(qg)
    assert xg.shape == (3, 4, 6)
    assert mech.jacobian(qg, grid).shape == (3, 4, 6, mech.n_joints)
    assert mech.link_points(qg).shape == (3, 4, 22, 3)


def test_redundant_waists_give_a_6_by_9_force_map_and_a_consistent_pseudo_inverse():
    mech = InouePlatform(waist_actuators="active")
    assert mech.n_joints == 9 and mech.is_redundant and mech.joint_names == ALL_JOINTS
    x = _poses(mech, 30, seed=4)
    q, _ = mech.inverse(x)
    k = mech.inverse_jacobian(q, x)
    jac = mech.jacobian(q, x)
    assert mech.force_map(q, x).shape == (len(x), 6, 9)
    np.testing.assert_allclose(jac @ k, np.broadcast_to(np.eye(6), (len(x), 6, 6)), atol=1e-9)
    # The waist rows are the passive waists' rates: the shoulders' rows are the 6-actuator K's.
    np.testing.assert_array_equal(k[:, :6], InouePlatform().inverse_jacobian(q[:, :6], x))
    # Inconsistent waists (one turned by 1 deg) do not assemble.
    bad = q.copy()
    bad[:, 7] += DEG
    assert not mech.forward(bad)[1].any()


def test_forward_rejects_the_flipped_twin_and_reports_non_finite_joints():
    mech = InouePlatform()
    x = mech.home_pose() + np.array([0.03, -0.02, 0.01, 0.1, -0.2, 0.1])
    q, _ = mech.inverse(x)
    back, ok = mech.forward(q)
    np.testing.assert_allclose(back, x, atol=1e-12)
    # The platform turned by pi about its long axis (y): attachments 2 and 3 swap sides. Its
    # U-joints bend past 90 deg, so it is not an assembly of the device.
    flipped = np.array([0.0, 0.0, 0.25, 0.0, np.pi, 0.0])
    assert np.all(mech.bend_angles(flipped)[1:] > np.pi / 2)
    x_nan, ok_nan = mech.forward(np.full((2, 6), np.nan))
    assert not ok_nan.any() and np.isnan(x_nan).all()


# -- limits -----------------------------------------------------------------------------------
def test_upright_bends_are_the_waist_angles_and_ujoint_limit_cuts_exactly():
    mech = InouePlatform()
    x = np.array([0.02, -0.01, 0.24, 0.0, 0.0, 0.0])
    full, _ = mech.all_joints(x)
    # At zero orientation the platform shaft is e_rad and n = cos psi e_rad - sin psi e_z.
    np.testing.assert_allclose(mech.bend_angles(x), np.abs(full[6:]), atol=1e-14)
    x = np.array([0.01, 0.02, 0.26, 0.3, -0.2, 0.25])
    q, _ = mech.inverse(x)
    bend = float(mech.bend_angles(x).max())
    assert 0 < bend < 85 * DEG
    assert mech.replace(ujoint_limit=bend + 1e-9).feasible(q, x)
    assert not mech.replace(ujoint_limit=bend - 1e-9).feasible(q, x)
    assert not mech.replace(ujoint_limit=bend - 1e-9).feasible(q)      # the pose from FK
    shown = mech.replace_display(ujoint_limit=60.0)
    assert shown.params.ujoint_limit == pytest.approx(math.radians(60.0), rel=1e-15)
    assert dict((i.name, v) for i, v in shown.parameter_table())["ujoint_limit"] == 60.0
    with pytest.raises(ValueError, match="ujoint_limit"):
        mech.replace(ujoint_limit=math.radians(95.0))


def test_passive_waist_limits_are_checked():
    mech = InouePlatform()
    x = np.array([0.05, 0.0, 0.22, 0.0, 0.0, 0.0])
    q, _ = mech.inverse(x)
    full, _ = mech.all_joints(x)
    w2 = full[7]
    assert mech.feasible(q, x)
    upper = list(mech.params.upper_limits)
    lower = list(mech.params.lower_limits)
    if w2 > 0:
        upper[7] = w2 - 1e-9
    else:
        lower[7] = w2 + 1e-9
    assert not mech.replace(upper_limits=tuple(upper), lower_limits=tuple(lower)).feasible(q, x)


def test_bad_parameters_name_the_parameter():
    with pytest.raises(ValueError, match="platform_pair_angle"):
        InouePlatform(platform_pair_angle=math.pi)            # attachments 2 and 3 would merge
    with pytest.raises(ValueError, match="upper_arm"):
        InouePlatform(upper_arm=-0.1)
    with pytest.raises(ValueError, match="motor_torques"):
        InouePlatform(motor_torques=(0.1,) * 6)
    with pytest.raises(ValueError, match="waist_actuators"):
        InouePlatform(waist_actuators="some")
    with pytest.raises(ValueError, match="q3 and q6"):
        InouePlatform(motor_torques=(0.1, 0.1, 0.2, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1)).actuator_scales()


def test_actuator_scales_are_table_v_q1_q2():
    assert InouePlatform().actuator_scales() == pytest.approx((0.75, 0.75), rel=1e-15)
    mech = InouePlatform(motor_torques=(0.2, 0.2, 0.1, 0.3, 0.3, 0.1, 0.2, 0.2, 0.2))
    assert mech.actuator_scales() == pytest.approx((0.5, 1.5), rel=1e-15)


# -- by hand at home ----------------------------------------------------------------------------
def test_home_joints_and_the_q1_row_by_hand():
    """Table V's optimum has l4 = l6, so leg 1 stands upright at home: its tip is at in-plane
    (u, w) = (0, z) with e_t = -x and e_r = +z, shoulders at u = -+l1/2."""
    mech = InouePlatform()
    l1, l2, l3, l6, z = 0.02, 0.16, 0.24, 0.02, 0.25
    rho = math.hypot(l1 / 2, z)
    elbow = math.acos((l2 * l2 + rho * rho - l3 * l3) / (2 * l2 * rho))
    q1 = math.atan2(z, l1 / 2) + elbow                     # shoulder at u = -l1/2, elbow outward
    q2 = math.atan2(z, -l1 / 2) - elbow
    q, ok = mech.inverse(mech.home_pose())
    assert ok and q[0] == pytest.approx(q1, abs=1e-13) and q[1] == pytest.approx(q2, abs=1e-13)
    assert math.degrees(q1) == pytest.approx(155.2397, abs=1e-4)
    # q1's row of K: g = D / (l2 d . t), D = d_u e_t + d_w e_r, row [g, a x g] with a = (0, l6, 0).
    eu, ew = -l1 / 2 + l2 * math.cos(q1), l2 * math.sin(q1)
    du, dw = 0.0 - eu, z - ew
    dt = du * -math.sin(q1) + dw * math.cos(q1)
    g = np.array([-du, 0.0, dw]) / (l2 * dt)
    row = np.concatenate([g, np.cross([0.0, l6, 0.0], g)])
    np.testing.assert_allclose(mech.inverse_jacobian(q, mech.home_pose())[0], row, rtol=1e-12, atol=1e-12)


def test_mirror_pairs_of_eq_18_at_poses_symmetric_about_the_jk_plane():
    """Mirror x -> -x maps q1 <-> q2, q3 <-> q6, q4 <-> q5 with the turning sense reversed: a
    column of A maps to minus the mirrored column, forces (-fx, fy, fz), moments (mx, -my, -mz)."""
    mech = InouePlatform()
    mirror = np.diag([-1.0, 1.0, 1.0, 1.0, -1.0, -1.0])
    for x in ([0.0, 0.0, 0.25, 0.0, 0.0, 0.0], [0.0, 0.03, 0.21, 0.2, 0.0, 0.0]):
        q, _ = mech.inverse(x)
        a = mech.force_map(q, x)
        for u, v in ((0, 1), (2, 5), (3, 4)):
            np.testing.assert_allclose(a[:, v], -mirror @ a[:, u], atol=1e-12 * np.abs(a).max())


# -- force and moment, separately ---------------------------------------------------------------
def _largest_along(a, t, direction, rows):
    """linprog: the largest s with A tau = s d on ``rows`` and 0 on the others, |tau| <= t."""
    n = a.shape[1]
    target = np.zeros(6)
    target[list(rows)] = direction
    a_eq = np.hstack([a, -target[:, None]])
    res = linprog(np.r_[np.zeros(n), -1.0], A_eq=a_eq, b_eq=np.zeros(6),
                  bounds=[(-ti, ti) for ti in t] + [(0, None)], method="highs")
    assert res.status == 0
    return res.x[-1]


def test_force_at_zero_moment_and_moment_at_zero_force_against_linprog():
    mech = load_preset("inoue_platform").mechanism
    x = np.array([0.02, -0.01, 0.24, 0.1, -0.15, 0.05])
    report = analyse_pose(mech, x, parts=())
    q, _ = mech.inverse(x)
    jac, a, t = mech.jacobian(q, x), mech.force_map(q, x), mech.torque_limits()
    # Square J, tau = J^T w: the slab of actuator u on the force slice is |J[:3, u] . f| <= t_u.
    for rows, value in ((range(3), report.isotropic_force), (range(3, 6), report.isotropic_moment)):
        part = jac[list(rows)]
        radii = t / np.linalg.norm(part, axis=0)
        assert value == pytest.approx(radii.min(), rel=1e-12)
        u = int(np.argmin(radii))
        # linprog's HiGHS solves to ~1e-9 relative feasibility
        assert _largest_along(a, t, part[:, u] / np.linalg.norm(part[:, u]), rows) == pytest.approx(value, rel=1e-7)
    # The two are different quantities in different units: N and N m (0.1 N m motors here).
    assert 0.1 < report.isotropic_force < 10 and 1e-4 < report.isotropic_moment < 0.1


def test_redundant_waists_never_shrink_the_force_at_zero_moment():
    """Extra actuators add generators to the wrench zonotope, so every slice can only grow."""
    x = np.array([0.01, 0.02, 0.25, 0.05, 0.1, -0.1])
    passive = analyse_pose(InouePlatform(), x, parts=())
    active = analyse_pose(InouePlatform(waist_actuators="active"), x, parts=())
    assert active.isotropic_force >= passive.isotropic_force * (1 - 1e-12)
    assert active.isotropic_moment >= passive.isotropic_moment * (1 - 1e-12)


# -- singularities ------------------------------------------------------------------------------
def test_all_six_shoulders_stretched_is_an_inverse_singularity():
    """An equilateral variant (radii 30 mm, 120 deg) has every tip above its waist centre at
    x = y = 0, zero orientation; at z = sqrt((l2 + l3)^2 - (l1/2)^2) every leg is stretched."""
    mech = InouePlatform(base_apex_radius=0.03, base_pair_radius=0.03, platform_apex_radius=0.03,
                         platform_pair_radius=0.03, platform_pair_angle=120 * DEG)
    z = math.sqrt(0.4 ** 2 - 0.01 ** 2)
    x = np.array([[0.0, 0.0, z, 0.0, 0.0, 0.0], [0.0, 0.0, z - 0.001, 0.0, 0.0, 0.0]])
    q, ok = mech.inverse(x)
    assert ok.all()
    legs = mech.singular_legs(q, x)
    assert legs[0].all() and not legs[1].any()
    assert mech.singularity(q, x).tolist() == [1, 0]
    assert mech.singularity_classes[1] == "inverse"
