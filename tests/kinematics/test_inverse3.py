"""Inverse3 prototype (paper 000, conventions of DESIGN.md): FK hand formula, Jacobian,
IK branches and round trips, batches, Table 2 limits and the body constraint.

Headless: numpy only. Every random draw uses a fixed seed.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from kinematics import Inverse3, Inverse3Params

DEG = np.pi / 180.0
DELTA = 1e-7            # rad: "just inside / just outside" a limit
BRANCHES = ("nearest", "front", "back")


def _wrap(angle):
    """Angle (difference) wrapped into [-pi, pi)."""
    return np.mod(angle + np.pi, 2.0 * np.pi) - np.pi


def _random_feasible(mech: Inverse3, count: int, seed: int):
    rng = np.random.default_rng(seed)
    p = mech.params
    q = rng.uniform(p.lower_limits, p.upper_limits, size=(20 * count, 3))
    keep = mech.feasible(q)
    assert np.count_nonzero(keep) >= count, "not enough feasible random poses"
    return q[keep][:count]


def _radial(q, x):
    """In-plane distance from the base axis, ``u``, of pose ``x`` at base angle ``q[..., 0]``."""
    return x[..., 0] * np.cos(q[..., 0]) + x[..., 1] * np.sin(q[..., 0])


# -- forward kinematics against DESIGN.md ------------------------------------------------
def test_default_parameters_are_paper_000_tables_1_and_2():
    p = Inverse3().params
    assert (p.proximal_length, p.distal_length) == (0.140, 0.165)
    assert p.base_height == 0.18645
    assert p.plane_offset == pytest.approx(0.0223, abs=1e-15)          # -41.93 + 64.23 mm
    np.testing.assert_allclose(np.array(p.lower_limits) / DEG, [-205, 5, -85], rtol=1e-14)
    np.testing.assert_allclose(np.array(p.upper_limits) / DEG, [45, 225, 114], rtol=1e-14)
    assert p.gear_ratios == (6.875, 5.957, 5.957)
    np.testing.assert_allclose(Inverse3().torque_limits(), [0.6875, 0.5957, 0.5957], rtol=1e-15)
    assert p.min_link_spread == pytest.approx(20 * DEG) and p.max_link_spread == pytest.approx(200 * DEG)
    assert (p.body_radius, p.body_height) == (0.065, 0.180)


def _hand_forward_theta0_zero(p1, p2):
    """DESIGN.md: P = (a3 cos th3, 22.3 mm, 186.45 mm + a3 sin th3), in metres."""
    l1, l2 = 0.140, 0.165
    phi1, phi2 = p1 - np.pi / 2, p2 - np.pi / 2
    th3, h = (phi1 + phi2) / 2, (phi1 - phi2) / 2
    a3 = l1 * np.cos(h) + np.sqrt(l2 ** 2 - l1 ** 2 * np.sin(h) ** 2)
    return np.stack([a3 * np.cos(th3), np.full_like(th3, 0.0223), 0.18645 + a3 * np.sin(th3)], -1)


def _circle_intersection_theta0_zero(p1, p2):
    """The same point from elbows and distal links: the far intersection of two circles."""
    l1, l2 = 0.140, 0.165
    e1 = l1 * np.stack([np.sin(p1), -np.cos(p1)], -1)    # motor 0 points down (-z), + towards +x
    e2 = l1 * np.stack([np.sin(p2), -np.cos(p2)], -1)
    mid = 0.5 * (e1 + e2)
    half = 0.5 * np.linalg.norm(e2 - e1, axis=-1, keepdims=True)
    along = np.sqrt(l2 ** 2 - half ** 2)
    direction = np.where(np.linalg.norm(mid, axis=-1, keepdims=True) > 0, mid, [[1.0, 0.0]])
    direction = direction / np.linalg.norm(direction, axis=-1, keepdims=True)
    # Distance from the midpoint along the bisector; the chord is perpendicular to it.
    plane = mid + along * direction
    return np.stack([plane[:, 0], np.full(len(p1), 0.0223), 0.18645 + plane[:, 1]], -1)


def test_forward_matches_hand_formula_and_circle_intersection():
    rng = np.random.default_rng(1)
    p1 = rng.uniform(5, 225, 500) * DEG
    p2 = p1 - rng.uniform(20, 170, 500) * DEG                  # p1 drives the upper link
    q = np.stack([np.zeros(500), p1, p2], -1)
    x, ok = Inverse3().forward(q)
    assert ok.all()
    np.testing.assert_allclose(x, _hand_forward_theta0_zero(p1, p2), rtol=0, atol=1e-15)
    np.testing.assert_allclose(x, _circle_intersection_theta0_zero(p1, p2), rtol=0, atol=1e-14)
    # Both distal links have length l2.
    elbows = Inverse3().link_points(q)[:, [3, 5]]
    np.testing.assert_allclose(np.linalg.norm(x[:, None, :] - elbows, axis=-1), 0.165, rtol=1e-13)


def test_forward_known_pose():
    """Both links horizontal, forwards (p = 90 deg): P = (l1 + l2, 22.3 mm, 186.45 mm) is the
    stretched limit; with p1 = 100, p2 = 80 deg the numbers follow by hand."""
    x, ok = Inverse3().forward(np.array([0.0, 100 * DEG, 80 * DEG]))
    h = 10 * DEG
    a3 = 0.140 * np.cos(h) + np.sqrt(0.165 ** 2 - (0.140 * np.sin(h)) ** 2)
    assert ok
    np.testing.assert_allclose(x, [a3, 0.0223, 0.18645], rtol=0, atol=1e-15)
    x, _ = Inverse3().forward(np.array([0.0, 90 * DEG, 90 * DEG]))
    np.testing.assert_allclose(x, [0.305, 0.0223, 0.18645], rtol=0, atol=1e-15)


def test_base_joint_rotates_the_slice_about_z():
    rng = np.random.default_rng(2)
    q = _random_feasible(Inverse3(), 200, seed=3)
    th0 = rng.uniform(-np.pi, np.pi, 200)
    q0 = q.copy()
    q0[:, 0] = 0.0
    q[:, 0] = th0
    x0, _ = Inverse3().forward(q0)
    x, _ = Inverse3().forward(q)
    c, s = np.cos(th0), np.sin(th0)
    rotated = np.stack([c * x0[:, 0] - s * x0[:, 1], s * x0[:, 0] + c * x0[:, 1], x0[:, 2]], -1)
    np.testing.assert_allclose(x, rotated, rtol=0, atol=1e-15)


def test_motor_zero_points_down_and_positive_towards_x():
    """Motor angle = link angle + 90 deg: elbow = (l1 sin p, 22.3 mm, 186.45 mm - l1 cos p) at theta_0 = 0."""
    q = np.array([[0.0, 0.0, -30 * DEG], [0.0, 90 * DEG, 45 * DEG], [0.0, 200 * DEG, 20 * DEG]])
    pts = Inverse3().link_points(q)
    assert pts.shape == (3, 7, 3)
    for k, index in ((1, 3), (2, 5)):
        expected = np.stack([0.140 * np.sin(q[:, k]), np.full(3, 0.0223), 0.18645 - 0.140 * np.cos(q[:, k])], -1)
        np.testing.assert_allclose(pts[:, index], expected, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(pts[:, 0], 0.0)
    np.testing.assert_allclose(pts[:, 2], [[0.0, 0.0223, 0.18645]] * 3, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(pts[:, 4], Inverse3().forward(q)[0])


def test_swapping_motors_mirrors_to_the_same_point():
    """The five-bar is symmetric: (p1, p2) and (p2, p1) reach the same point."""
    q = _random_feasible(Inverse3(), 100, seed=4)
    x, _ = Inverse3().forward(q)
    xs, _ = Inverse3().forward(q[:, [0, 2, 1]])
    np.testing.assert_allclose(xs, x, rtol=0, atol=1e-15)


# -- Jacobian ---------------------------------------------------------------------------
@pytest.mark.parametrize("params", [dict(), dict(proximal_length=0.1, distal_length=0.3, tool_offset=0.2)])
def test_jacobian_matches_central_differences(params):
    mech = Inverse3(**params)
    rng = np.random.default_rng(5)
    feasible = _random_feasible(Inverse3(), 200, seed=6)
    anywhere = rng.uniform(-np.pi, np.pi, size=(200, 3))
    q = np.concatenate([feasible, anywhere])
    jac = mech.jacobian(q)
    step = 1e-6
    numeric = np.empty_like(jac)
    for k in range(3):
        dq = np.zeros(3)
        dq[k] = step
        plus, ok_p = mech.forward(q + dq)
        minus, ok_m = mech.forward(q - dq)
        assert ok_p.all() and ok_m.all()
        numeric[..., :, k] = (plus - minus) / (2 * step)
    scale = np.max(np.abs(jac), axis=(-2, -1), keepdims=True)
    err = np.max(np.abs(numeric - jac) / scale)
    assert err < 1e-7, f"worst relative Jacobian error {err:.2e}"
    # The base joint never moves the end-effector vertically.
    np.testing.assert_array_equal(jac[:, 2, 0], 0.0)


# -- inverse kinematics -------------------------------------------------------------------
@pytest.mark.parametrize("branch", BRANCHES)
def test_forward_of_inverse_round_trips(branch):
    mech = Inverse3(base_branch=branch)
    rng = np.random.default_rng(7)
    x = np.column_stack([rng.uniform(-0.35, 0.35, 5000), rng.uniform(-0.35, 0.35, 5000),
                         rng.uniform(-0.15, 0.5, 5000)])
    q, ok = mech.inverse(x)
    assert 1000 < ok.sum() < 5000
    assert np.all(np.isnan(q[~ok])) and np.all(np.isfinite(q[ok]))
    x_back, ok_back = mech.forward(q[ok])
    assert ok_back.all()
    err = np.linalg.norm(x_back - x[ok], axis=-1)
    assert err.max() < 1e-12
    # p1 drives the upper link (h >= 0) and is shifted into its limits where it can be.
    assert np.all(q[ok, 1] >= q[ok, 2])
    lo = mech.params.lower_limits[1]
    assert np.all((q[ok, 1] >= lo) & (q[ok, 1] < lo + 2 * np.pi))
    u = _radial(q[ok], x[ok])
    if branch == "front":
        assert np.all(u >= -1e-15)
    elif branch == "back":
        assert np.all(u <= 1e-15)


def test_nearest_branch_takes_the_smaller_base_turn():
    rng = np.random.default_rng(8)
    x = np.column_stack([rng.uniform(-0.3, 0.3, 3000), rng.uniform(-0.3, 0.3, 3000),
                         rng.uniform(-0.1, 0.45, 3000)])
    mech = Inverse3()
    q_near, ok = mech.inverse(x, "nearest")
    q_front, _ = mech.inverse(x, "front")
    q_back, _ = mech.inverse(x, "back")
    use_back = np.abs(_wrap(q_back[:, 0])) < np.abs(_wrap(q_front[:, 0]))
    expected = np.where(use_back[:, None], q_back, q_front)
    np.testing.assert_array_equal(q_near[ok], expected[ok])
    assert 0 < np.count_nonzero(use_back & ok) < np.count_nonzero(ok)
    # The theta_0 = 0 slice of DESIGN.md is swept without turning the base.
    c = mech.params.plane_offset
    xs = np.column_stack([np.linspace(-0.05, 0.30, 36), np.full(36, c), np.full(36, 0.25)])
    q_s, ok_s = mech.inverse(xs)
    assert ok_s.sum() > 30
    np.testing.assert_allclose(q_s[ok_s, 0], 0.0, rtol=0, atol=1e-12)


@pytest.mark.parametrize("branch", ("front", "back", "nearest"))
def test_inverse_of_forward_returns_q_mod_2pi(branch):
    """Generic joint vectors with p1 above p2 (0 < p1 - p2 < 2 pi) come back mod 2 pi."""
    mech = Inverse3()
    rng = np.random.default_rng(9)
    p2 = rng.uniform(-np.pi, np.pi, 2000)
    q = np.stack([rng.uniform(-np.pi, np.pi, 2000), p2 + rng.uniform(0.2, 2 * np.pi - 0.2, 2000), p2], -1)
    x, _ = mech.forward(q)
    u = _radial(q, x)
    q_back, ok = mech.inverse(x, branch)
    assert ok.all()
    if branch == "front":
        sel = u > 0
    elif branch == "back":
        sel = u < 0
    else:
        # Nearest reproduces q where q's own base turn is the smaller of the two.
        q_front, _ = mech.inverse(x, "front")
        q_rear, _ = mech.inverse(x, "back")
        own = np.where((u > 0)[:, None], q_front, q_rear)
        other = np.where((u > 0)[:, None], q_rear, q_front)
        sel = np.abs(_wrap(own[:, 0])) < np.abs(_wrap(other[:, 0]))
    assert 300 < sel.sum() < 1700
    np.testing.assert_allclose(_wrap(q_back[sel] - q[sel]), 0.0, rtol=0, atol=1e-9)
    # The other branch reaches the same point with a different base angle.
    assert np.all(np.abs(_wrap(q_back[~sel, 0] - q[~sel, 0])) > 1e-6)


def test_inverse_of_forward_returns_feasible_q_unshifted():
    """Feasible q lie within the ranges IK shifts into, so they come back as they were."""
    mech = Inverse3()
    q = _random_feasible(mech, 400, seed=10)
    q = q[q[:, 1] > q[:, 2]]
    x, _ = mech.forward(q)
    assert np.all(_radial(q, x) > 0)                 # feasible poses here are all in front
    q_back, ok = mech.inverse(x, "front")
    assert ok.all() and len(q) > 100
    np.testing.assert_allclose(q_back, q, rtol=0, atol=1e-10)
    assert mech.feasible(q_back).all()


def test_inverse_swaps_motors_when_p1_is_below_p2():
    mech = Inverse3()
    q = _random_feasible(mech, 400, seed=14)
    q = q[q[:, 1] < q[:, 2]]
    assert len(q) > 10
    x, _ = mech.forward(q)
    q_back, ok = mech.inverse(x, "front")
    sel = _radial(q, x) > 0
    assert ok.all() and sel.sum() > 5
    np.testing.assert_allclose(_wrap(q_back[sel] - q[sel][:, [0, 2, 1]]), 0.0, rtol=0, atol=1e-10)


def test_unreachable_points_give_nan_and_false():
    mech = Inverse3()
    c, height = mech.params.plane_offset, mech.params.base_height
    x = np.array([
        [0.0, 0.0, 0.2],              # inside the cylinder of radius c about the base axis
        [0.5, 0.0, 0.2],              # beyond l1 + l2
        [0.0, c, height],             # the plane's centre (a3 = 0)
        [0.01, c, height],            # a3 = 10 mm < l2 - l1 = 25 mm
        [0.2, c, 0.2],                # reachable
        [0.0, c, height + 0.3],       # reachable straight up (a3 = 300 mm)
    ])
    for branch in BRANCHES:
        q, ok = mech.inverse(x, branch)
        np.testing.assert_array_equal(ok, [False, False, False, False, True, True])
        assert np.all(np.isnan(q[:4])) and np.all(np.isfinite(q[4:]))
    # The boundary of the outer sphere (a3 = l1 + l2) survives rounding.
    edge = np.array([0.305 * np.cos(0.3), c, height + 0.305 * np.sin(0.3)])
    q, ok = mech.inverse(edge)
    assert ok and abs(q[1] - q[2]) < 1e-6


# -- batches ----------------------------------------------------------------------------
def test_batch_equals_one_at_a_time():
    mech = Inverse3()
    rng = np.random.default_rng(11)
    x = np.column_stack([rng.uniform(-0.3, 0.3, 60), rng.uniform(-0.3, 0.3, 60), rng.uniform(-0.1, 0.45, 60)])
    q_rand = rng.uniform(-np.pi, np.pi, size=(60, 3))
    q_b, ok_b = mech.inverse(x)
    x_b, _ = mech.forward(q_rand)
    jac_b = mech.jacobian(q_rand)
    feas_b = mech.feasible(q_b)
    links_b = mech.link_points(q_rand)
    assert ok_b.any() and not ok_b.all() and feas_b.any()
    for i in range(60):
        q_i, ok_i = mech.inverse(x[i])
        assert q_i.shape == (3,) and ok_i.shape == ()
        np.testing.assert_array_equal(q_i, q_b[i])
        assert ok_i == ok_b[i]
        np.testing.assert_array_equal(mech.forward(q_rand[i])[0], x_b[i])
        jac_i = mech.jacobian(q_rand[i])
        assert jac_i.shape == (3, 3)
        np.testing.assert_array_equal(jac_i, jac_b[i])
        assert mech.feasible(q_b[i]) == feas_b[i]
        np.testing.assert_array_equal(mech.link_points(q_rand[i]), links_b[i])


def test_nested_batch_shapes_equal_flat_batch():
    mech = Inverse3()
    rng = np.random.default_rng(12)
    x = np.column_stack([rng.uniform(-0.3, 0.3, 30), rng.uniform(-0.3, 0.3, 30), rng.uniform(-0.1, 0.45, 30)])
    q = rng.uniform(-np.pi, np.pi, size=(30, 3))
    q3, ok3 = mech.inverse(x.reshape(2, 3, 5, 3))
    assert q3.shape == (2, 3, 5, 3) and ok3.shape == (2, 3, 5)
    q1, ok1 = mech.inverse(x)
    np.testing.assert_array_equal(q3.reshape(-1, 3), q1)
    np.testing.assert_array_equal(ok3.ravel(), ok1)
    np.testing.assert_array_equal(mech.forward(q.reshape(5, 6, 3))[0].reshape(-1, 3), mech.forward(q)[0])
    jac = mech.jacobian(q.reshape(5, 6, 3))
    assert jac.shape == (5, 6, 3, 3)
    np.testing.assert_array_equal(jac.reshape(-1, 3, 3), mech.jacobian(q))
    feas = mech.feasible(q1.reshape(6, 5, 3))
    assert feas.shape == (6, 5)
    np.testing.assert_array_equal(feas.ravel(), mech.feasible(q1))
    assert mech.link_points(q.reshape(5, 6, 3)).shape == (5, 6, 7, 3)


def test_wrong_shapes_raise_naming_the_argument():
    mech = Inverse3()
    with pytest.raises(ValueError, match=r"x must have shape \(\.\.\., 3\)"):
        mech.inverse(np.zeros((4, 2)))
    with pytest.raises(ValueError, match=r"q must have shape \(\.\.\., 3\)"):
        mech.forward(np.zeros(2))
    with pytest.raises(ValueError, match=r"q must have shape"):
        mech.jacobian(np.zeros((3, 4)))
    with pytest.raises(ValueError, match="base_branch"):
        mech.inverse(np.zeros(3), "sideways")


# -- feasibility: Table 2 limits, link spread, body constraint ---------------------------
BASE = np.array([0.0, 120.0, 40.0]) * DEG          # a comfortable feasible pose


def _pose(th0_deg, p1_deg, p2_deg, *, d0=0.0, d1=0.0, d2=0.0):
    return np.array([th0_deg * DEG + d0, p1_deg * DEG + d1, p2_deg * DEG + d2])


@pytest.mark.parametrize("inside, outside, what", [
    (_pose(45, 120, 40, d0=-DELTA), _pose(45, 120, 40, d0=DELTA), "theta_0 upper 45 deg"),
    (_pose(-205, 120, 40, d0=DELTA), _pose(-205, 120, 40, d0=-DELTA), "theta_0 lower -205 deg"),
    (_pose(0, 225, 100, d1=-DELTA), _pose(0, 225, 100, d1=DELTA), "p1 upper 225 deg"),
    (_pose(0, 5, 100, d1=DELTA), _pose(0, 5, 100, d1=-DELTA), "p1 lower 5 deg"),
    (_pose(0, 60, 114, d2=-DELTA), _pose(0, 60, 114, d2=DELTA), "p2 upper 114 deg"),
    (_pose(0, 110, 90, d2=-DELTA), _pose(0, 110, 90, d2=DELTA), "spread >= 20 deg (p1 > p2)"),
    (_pose(0, 90, 110, d2=DELTA), _pose(0, 90, 110, d2=-DELTA), "spread >= 20 deg (p1 < p2)"),
    (_pose(0, 205, 5, d2=DELTA), _pose(0, 205, 5, d2=-DELTA), "spread <= 200 deg"),
])
def test_feasible_limits_just_inside_and_outside(inside, outside, what):
    mech = Inverse3()
    assert mech.feasible(BASE)
    assert mech.feasible(inside), what
    assert not mech.feasible(outside), what
    # Only the named limit moved: the pose is the same to 1e-7 rad, so the body constraint
    # holds with margin at both.
    x_in, _ = mech.forward(inside)
    x_out, _ = mech.forward(outside)
    for x, q in ((x_in, inside), (x_out, outside)):
        assert _radial(q, x) > 0.065 + 1e-4 or x[2] > 0.180 + 1e-4


def test_p2_lower_limit_with_the_body_constraint_relaxed():
    """p2 = -85 deg points the lower link backwards; every such pose of the default model is
    inside the body, so the limit is checked with a body of (almost) zero size."""
    relaxed = Inverse3().replace(body_radius=1e-9, body_height=1e-9)
    inside, outside = _pose(0, 60, -85, d2=DELTA), _pose(0, 60, -85, d2=-DELTA)
    assert relaxed.feasible(inside)
    assert not relaxed.feasible(outside)
    assert not Inverse3().feasible(inside)              # the body constraint rules it out
    assert Inverse3().forward(inside)[0][2] < 0.180


def test_body_constraint_radial():
    mech = Inverse3()
    c = mech.params.plane_offset
    # At theta_0 = 0 the radial coordinate is P_x; z = 100 mm < 180 mm.
    q_in, ok_in = mech.inverse(np.array([0.065 + 1e-7, c, 0.1]))
    q_out, ok_out = mech.inverse(np.array([0.065 - 1e-7, c, 0.1]))
    assert ok_in and ok_out
    np.testing.assert_allclose([q_in[0], q_out[0]], 0.0, atol=1e-12)
    assert mech.feasible(q_in)
    assert not mech.feasible(q_out)
    # The constraint is about the distance from the base axis: turning the base keeps it.
    for th0 in (-150 * DEG, -90 * DEG, 30 * DEG):
        assert mech.feasible(q_in + [th0, 0, 0])
        assert not mech.feasible(q_out + [th0, 0, 0])
    # Passing the pose explicitly gives the same answer as letting feasible compute it.
    x_in, _ = mech.forward(q_in)
    assert mech.feasible(q_in, x_in)
    assert not mech.feasible(q_in, x_in - [2e-7, 0, 0])


def test_body_constraint_height():
    """z > 180 mm rescues a pose close to the axis; checked with the joint limits opened
    (in the default model no pose with radial < 65 mm and z near 180 mm is within them)."""
    wide = Inverse3().replace(lower_limits=(-4.0, -1.0, -8.0), upper_limits=(4.0, 6.0, 8.0),
                              min_link_spread=1e-6, max_link_spread=6.2)
    c = wide.params.plane_offset
    q_in, ok_in = wide.inverse(np.array([0.03, c, 0.180 + 1e-7]))
    q_out, ok_out = wide.inverse(np.array([0.03, c, 0.180 - 1e-7]))
    assert ok_in and ok_out
    assert wide.feasible(q_in)
    assert not wide.feasible(q_out)
    # A far-out pose below 180 mm is fine: either condition suffices.
    q_far, _ = wide.inverse(np.array([0.2, c, 0.05]))
    assert wide.feasible(q_far)


def test_feasible_matches_an_independent_mask():
    """Random joint vectors over and beyond the ranges, against the constraints written out."""
    mech = Inverse3()
    rng = np.random.default_rng(13)
    q = rng.uniform([-230 * DEG, -20 * DEG, -110 * DEG], [70 * DEG, 250 * DEG, 140 * DEG], size=(20000, 3))
    x, _ = mech.forward(q)
    d = q / DEG
    limits = ((d[:, 0] >= -205) & (d[:, 0] <= 45) & (d[:, 1] >= 5) & (d[:, 1] <= 225)
              & (d[:, 2] >= -85) & (d[:, 2] <= 114))
    spread = np.abs(d[:, 1] - d[:, 2])
    body = (_radial(q, x) > 0.065) | (x[:, 2] > 0.180)
    expected = limits & (spread >= 20) & (spread <= 200) & body
    got = mech.feasible(q)
    assert 1000 < expected.sum() < 19000
    np.testing.assert_array_equal(got, expected)
    nan_q = q[:3].copy()
    nan_q[:, 1] = np.nan
    assert not mech.feasible(nan_q).any()


# -- parameters: replace, validation, immutability ---------------------------------------
def test_replace_returns_new_validated_model():
    mech = Inverse3()
    doubled = mech.replace(gear_ratios=(13.75, 5.957, 5.957))
    assert doubled is not mech and isinstance(doubled, Inverse3)
    assert mech.params.gear_ratios == (6.875, 5.957, 5.957)
    np.testing.assert_allclose(doubled.torque_limits(), [1.375, 0.5957, 0.5957], rtol=1e-15)
    longer = mech.replace(distal_length=0.2)
    x, _ = longer.forward(np.array([0.0, 90 * DEG, 90 * DEG]))
    np.testing.assert_allclose(x[0], 0.34, rtol=1e-15)
    assert longer.replace(distal_length=0.165) == mech
    assert Inverse3(base_branch="back") == mech.replace(base_branch="back")


@pytest.mark.parametrize("changes, pattern", [
    (dict(proximal_length=-0.14), r"proximal_length must be a positive finite number in m, got -0\.14"),
    (dict(distal_length=0), r"distal_length must be a positive"),
    (dict(base_height=float("inf")), r"base_height must be a positive"),
    (dict(gear_ratios=(6.875, 5.957)), r"gear_ratios needs 3 values \(theta_0, p1, p2\), got 2"),
    (dict(motor_torques=(0.1, 0.0, 0.1)), r"motor_torques\[p1\] must be a positive"),
    (dict(motor_torques=(0.1, 0.1, -1.0)), r"motor_torques\[p2\] must be a positive"),
    (dict(lower_limits=(0.0, 0.0)), r"lower_limits needs 3 values"),
    (dict(upper_limits=(1.0, float("nan"), 1.0)), r"upper_limits\[p1\] must be a finite angle"),
    (dict(lower_limits=(1.0, 0.0, 0.0), upper_limits=(0.5, 1.0, 1.0)), r"lower_limits\[theta_0\] must be below"),
    (dict(min_link_spread=4.0), r"min_link_spread must be below max_link_spread"),
    (dict(body_radius=-1.0), r"body_radius must be a positive"),
    (dict(base_branch="left"), r"base_branch must be one of"),
    (dict(link_count=3), r"Inverse3 has no parameter 'link_count'"),
])
def test_replace_validates_and_names_the_argument(changes, pattern):
    with pytest.raises(ValueError, match=pattern):
        Inverse3().replace(**changes)


def test_replace_display_uses_millimetres_and_degrees():
    mech = Inverse3().replace_display(proximal_length=150, upper_limits=(40, 220, 110))
    assert mech.params.proximal_length == pytest.approx(0.150, rel=1e-15)
    np.testing.assert_allclose(mech.params.upper_limits, np.array([40, 220, 110]) * DEG, rtol=1e-15)
    with pytest.raises(ValueError, match="upper_limits needs 3 values"):
        Inverse3().replace_display(upper_limits=5)
    with pytest.raises(ValueError, match="Inverse3 has no parameter 'colour'"):
        Inverse3().replace_display(colour="red")


def test_models_are_immutable():
    mech = Inverse3()
    with pytest.raises(AttributeError, match="immutable"):
        mech.params = Inverse3Params(proximal_length=0.2)
    with pytest.raises(AttributeError):
        mech.forward = None
    with pytest.raises(dataclasses.FrozenInstanceError):
        mech.params.distal_length = 0.2
    assert mech.params.proximal_length == 0.140 and mech.params.distal_length == 0.165
