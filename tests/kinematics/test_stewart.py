"""Stewart platform and the shared rotation helpers: joint layout, IK by hand, the Jacobian
against central differences, statics as a sum of leg forces, Newton FK round trips,
feasibility at constructed boundaries, batches, validation. Rotations against SciPy.

Headless: numpy (and scipy.spatial.transform as an independent reference). Fixed seeds.
"""
from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from kinematics import StewartParams, StewartPlatform
from kinematics.rotations import (
    batched_inverse,
    left_jacobian,
    rotation_matrix,
    rotation_vector,
    tilt_direction,
    tilt_matrix,
    tilt_of_direction,
)
from kinematics.stewart import FK_RTOL

DEG = np.pi / 180.0


def _random_poses(mech: StewartPlatform, count: int, seed: int, *, angle: float = 30 * DEG) -> np.ndarray:
    """Feasible poses around home: +-4 cm, rotations up to ``angle`` about random axes."""
    rng = np.random.default_rng(seed)
    n = 5 * count
    axis = rng.normal(size=(n, 3))
    rot = axis / np.linalg.norm(axis, axis=1, keepdims=True) * rng.uniform(0, angle, (n, 1))
    x = mech.home_pose() + np.concatenate([rng.uniform(-0.04, 0.04, (n, 3)), rot], -1)
    q, _ = mech.inverse(x)
    keep = mech.feasible(q, x)
    assert np.count_nonzero(keep) >= count, "not enough feasible random poses"
    return x[keep][:count]


def _moved(x: np.ndarray, xi: np.ndarray, t: float) -> np.ndarray:
    rot = rotation_matrix(t * xi[..., 3:]) @ rotation_matrix(x[..., 3:])
    return np.concatenate([x[..., :3] + t * xi[..., :3], rotation_vector(rot)], -1)


# -- rotations ---------------------------------------------------------------------------
def test_rotation_helpers_match_scipy_and_invert_each_other():
    rng = np.random.default_rng(1)
    axis = rng.normal(size=(5000, 3))
    r = axis / np.linalg.norm(axis, axis=1, keepdims=True) * rng.uniform(0, np.pi, (5000, 1))
    r[:4] = [[0, 0, 0], [1e-9, 0, 0], [0, 3e-5, 2e-5], [0, 0, np.pi - 1e-7]]   # tiny and near-pi angles
    np.testing.assert_allclose(rotation_matrix(r), Rotation.from_rotvec(r).as_matrix(), atol=2e-15)
    np.testing.assert_allclose(rotation_vector(rotation_matrix(r)), r, atol=2e-15)
    np.testing.assert_allclose(rotation_vector(Rotation.from_rotvec(r).as_matrix()), r, atol=3e-15)


def test_left_jacobian_maps_rotation_vector_rates_to_spatial_angular_velocity():
    rng = np.random.default_rng(2)
    r = rng.normal(size=(200, 3))
    r = r / np.linalg.norm(r, axis=1, keepdims=True) * rng.uniform(0, 3.0, (200, 1))
    r[0] = [1e-7, -2e-7, 0.0]
    rdot = rng.normal(size=(200, 3))
    h = 1e-6
    dr = (rotation_matrix(r + h * rdot) - rotation_matrix(r - h * rdot)) / (2 * h)
    w = dr @ np.swapaxes(rotation_matrix(r), -1, -2)                    # [omega]x
    omega = np.stack([w[:, 2, 1], w[:, 0, 2], w[:, 1, 0]], -1)
    np.testing.assert_allclose(np.einsum("...ij,...j->...i", left_jacobian(r), rdot), omega, atol=1e-9)


def test_tilts_are_rotations_about_axes_across_the_pen():
    rng = np.random.default_rng(3)
    t = rng.uniform(-2, 2, (500, 2))
    t[0] = [0.0, 0.0]
    t[1] = [1e-9, -3e-9]
    pen = tilt_direction(t)
    np.testing.assert_allclose(pen, tilt_matrix(t)[:, :, 1], atol=1e-15)
    np.testing.assert_allclose(tilt_of_direction(pen), t, atol=1e-13)
    # The tip angle (paper 001's theta_1) is |tilt|: the angle between the pen and y.
    np.testing.assert_allclose(np.arccos(np.clip(pen[:, 1], -1, 1)), np.hypot(t[:, 0], t[:, 1]), atol=2e-8)


def test_batched_inverse_marks_singular_and_non_finite_matrices():
    m = np.stack([np.diag([2.0, 4.0]), np.zeros((2, 2)), np.full((2, 2), np.nan)])
    inv, ok = batched_inverse(m)
    np.testing.assert_array_equal(ok, [True, False, False])
    np.testing.assert_allclose(inv[0], np.diag([0.5, 0.25]))
    assert np.isinf(inv[1]).all() and np.isnan(inv[2]).all()


# -- geometry ------------------------------------------------------------------------------
def test_joint_layout_radii_pairs_and_mirror_symmetry():
    mech = StewartPlatform(base_half_angle=12 * DEG, platform_half_angle=20 * DEG)
    b, p = mech.base_joints(), mech.platform_joints()
    np.testing.assert_allclose(np.hypot(b[:, 0], b[:, 1]), 0.06, rtol=1e-15)
    np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 1]), 0.03, rtol=1e-15)
    np.testing.assert_allclose(b[:, 2], 0.0)
    np.testing.assert_allclose(p[:, 2], -0.10)
    az_b = np.degrees(np.arctan2(b[:, 1], b[:, 0])) % 360
    az_p = np.degrees(np.arctan2(p[:, 1], p[:, 0])) % 360
    np.testing.assert_allclose(az_b, [78, 102, 198, 222, 318, 342], atol=1e-12)
    np.testing.assert_allclose(az_p, [50, 130, 170, 250, 290, 10], atol=1e-12)    # pairs at 30 +- 20 deg etc.
    # Paper 001 eq. 18 pairs: legs (1, 2), (3, 6), (4, 5) are mirror images in the yz plane.
    mirror = np.array([-1.0, 1.0, 1.0])
    for i, j in ((0, 1), (2, 5), (3, 4)):
        np.testing.assert_allclose(b[i] * mirror, b[j], atol=1e-15)
        np.testing.assert_allclose(p[i] * mirror, p[j], atol=1e-15)


def test_home_pose_by_hand():
    mech = StewartPlatform()
    x = mech.home_pose()
    q, ok = mech.inverse(x)
    assert ok
    np.testing.assert_allclose(q, 0.135, rtol=1e-15)                     # mid-stroke of 90..180 mm
    # Each leg spans 30 deg of azimuth between radii 60 and 30 mm.
    horizontal = np.sqrt(0.06 ** 2 + 0.03 ** 2 - 2 * 0.06 * 0.03 * np.cos(30 * DEG))
    assert x[2] == pytest.approx(np.sqrt(0.135 ** 2 - horizontal ** 2) + 0.10, rel=1e-15)
    np.testing.assert_allclose(mech.bend_angles(x), np.arcsin(horizontal / 0.135), rtol=1e-13)
    assert mech.feasible(q, x)


# -- Jacobian --------------------------------------------------------------------------------
def test_inverse_jacobian_matches_central_differences_along_twists():
    mech = StewartPlatform()
    x = _random_poses(mech, 300, seed=11)
    k = mech.inverse_jacobian(x=x)
    h = 1e-6
    for j in range(6):
        xi = np.zeros_like(x)
        xi[:, j] = 1.0
        fd = (mech.inverse(_moved(x, xi, h))[0] - mech.inverse(_moved(x, xi, -h))[0]) / (2 * h)
        np.testing.assert_allclose(fd, k[:, :, j], rtol=0, atol=1e-9)
    # and against coordinates: dq/dx = K blockdiag(I, J_l(r))
    chain = k.copy()
    chain[:, :, 3:] = k[:, :, 3:] @ left_jacobian(x[:, 3:])
    for j in range(6):
        step = np.zeros_like(x)
        step[:, j] = h
        fd = (mech.inverse(x + step)[0] - mech.inverse(x - step)[0]) / (2 * h)
        np.testing.assert_allclose(fd, chain[:, :, j], rtol=0, atol=1e-9)


def test_jacobian_is_the_inverse_and_statics_is_the_sum_of_leg_forces():
    mech = StewartPlatform()
    x = _random_poses(mech, 200, seed=21)
    q, _ = mech.inverse(x)
    k = mech.inverse_jacobian(q, x)
    jac = mech.jacobian(q, x)
    np.testing.assert_allclose(jac @ k, np.broadcast_to(np.eye(6), k.shape), atol=1e-10)
    rng = np.random.default_rng(22)
    tau = rng.normal(size=(200, 6)) * 10.0
    # Independent statics: legs push along u_i at the platform joints R p_i (relative to the task point).
    rot = rotation_matrix(x[:, 3:])
    arm = np.einsum("bij,kj->bki", rot, mech.platform_joints())
    legs = x[:, None, :3] + arm - mech.base_joints()
    u = legs / np.linalg.norm(legs, axis=-1, keepdims=True)
    force = np.sum(tau[:, :, None] * u, 1)
    moment = np.sum(np.cross(arm, tau[:, :, None] * u), 1)
    w = np.concatenate([force, moment], -1)
    np.testing.assert_allclose(np.einsum("bij,bj->bi", mech.force_map(q, x), tau), w, atol=1e-12)
    np.testing.assert_allclose(np.einsum("bji,bj->bi", jac, w), tau, rtol=0, atol=1e-9)     # tau = J^T w
    # Virtual work with leg rates of a real motion.
    xi = rng.normal(size=(200, 6)) * np.r_[0.1, 0.1, 0.1, 1.0, 1.0, 1.0]
    h = 1e-6
    qdot = (mech.inverse(_moved(x, xi, h))[0] - mech.inverse(_moved(x, xi, -h))[0]) / (2 * h)
    np.testing.assert_allclose(np.sum(tau * qdot, -1), np.sum(w * xi, -1), atol=1e-7)
    # Without x the pose comes from the Newton FK: the same Jacobian.
    np.testing.assert_allclose(mech.jacobian(q[:10]), jac[:10], rtol=1e-8, atol=1e-10)


def test_parallel_legs_are_singular():
    """Equal radii and eta_p = 60 deg - eta_b put each platform joint above its base joint: at zero
    rotation all legs are vertical and parallel, so no horizontal force can be held (K has rank 3
    up to rounding) and J blows up, without an exception, next to a regular pose in the batch."""
    mech = StewartPlatform(base_radius=0.05, platform_radius=0.05, base_half_angle=25 * DEG,
                           platform_half_angle=35 * DEG, tool_offset=0.0)
    x = np.array([0.0, 0.0, 0.12, 0.0, 0.0, 0.0])
    k = mech.inverse_jacobian(x=x)
    np.testing.assert_allclose(k[:, :3], np.broadcast_to([0.0, 0.0, 1.0], (6, 3)), atol=1e-15)
    sv = np.linalg.svd(k, compute_uv=False)
    assert sv[-1] < 1e-14 * sv[0]
    np.testing.assert_allclose(mech.bend_angles(x), 0.0, atol=1e-15)
    regular = StewartPlatform()
    both = np.stack([regular.inverse_jacobian(x=regular.home_pose()), k])
    inv, _ = batched_inverse(both)
    assert np.isfinite(inv[0]).all() and np.allclose(inv[0] @ both[0], np.eye(6), atol=1e-12)
    assert not np.all(np.isfinite(inv[1])) or np.abs(inv[1]).max() > 1e12


# -- forward kinematics ------------------------------------------------------------------------
def test_newton_forward_inverts_inverse():
    mech = StewartPlatform()
    x = _random_poses(mech, 500, seed=31)
    q, _ = mech.inverse(x)
    back, ok = mech.forward(q)
    assert ok.all()
    np.testing.assert_allclose(back, x, rtol=0, atol=1e-10)
    np.testing.assert_allclose(mech.inverse(back)[0], q, rtol=0, atol=1e-13)


#: Bound on |q(FK(q)) - q| / scale (longest leg + plate radii) for a converged FK, checked
#: through ``inverse``: the solver's own residual (FK_RTOL = 16 eps) plus the reported pose's
#: rotation-vector round trip R -> r -> R (each way within 2e-15 per entry, ~9 eps,
#: test_rotation_helpers_match_scipy...;
#: at most 3 x 9 eps each in spectral norm, acting on |p_i| < scale): 16 + 54 < 72 eps.
_FK_CHECK = 72 * np.finfo(float).eps


def _fk_check(mech: StewartPlatform, q: np.ndarray, x: np.ndarray, ok: np.ndarray) -> None:
    """Where FK converged its pose realises ``q`` to ``_FK_CHECK`` relative; elsewhere ``nan``."""
    assert np.isnan(x[~ok]).all() and np.isfinite(x[ok]).all()
    err = np.abs(mech.inverse(x[ok])[0] - q[ok]).max(-1, initial=0.0)
    radii = np.linalg.norm(mech.platform_joints(), axis=-1).max() + np.linalg.norm(mech.base_joints(), axis=-1).max()
    scale = q[ok].max(-1, initial=0.0) + radii                    # longest leg + plate radii, m
    np.testing.assert_allclose(mech.residual_scale(q[ok]), scale, rtol=4 * np.finfo(float).eps)
    assert np.all(err <= _FK_CHECK * scale)


@pytest.mark.parametrize("scale", [1e-4, 1.0, 1e4])
def test_forward_tolerance_is_relative_to_the_device_size(scale):
    """The same device at 0.1 mm, 1 m and 10 km: FK converges everywhere and to the same relative
    accuracy. An absolute tolerance (1e-13 m) is unreachable at 10 km (one rounding of a leg is
    2e-13 m) and meaningless at 0.1 mm (1e-9 of the device)."""
    base = StewartPlatform()
    x0 = _random_poses(base, 200, seed=37)
    p = base.params
    mech = base.replace(base_radius=p.base_radius * scale, platform_radius=p.platform_radius * scale,
                        tool_offset=p.tool_offset * scale, min_leg=p.min_leg * scale, max_leg=p.max_leg * scale)
    x = np.concatenate([x0[:, :3] * scale, x0[:, 3:]], -1)
    q, _ = mech.inverse(x)
    back, ok = mech.forward(q)
    assert ok.all()
    _fk_check(mech, q, back, ok)


def test_forward_of_very_long_legs_is_right_or_masked():
    """1e9 m legs on 6 cm plates: a pose exists (centred, unrotated, 1e9 m up), but the legs are
    parallel to 1e-10 rad, so K is nearly singular and whether Newton reaches the rounding floor
    depends on last bits. Either outcome is allowed; a wrong pose is not."""
    mech = StewartPlatform()
    q = np.array([[1e9] * 6, [1e9 * (1 + 1e-12)] * 6, [2e6] * 6])
    x, ok = mech.forward(q)
    _fk_check(mech, q, x, ok)


def test_forward_marks_impossible_leg_lengths():
    mech = StewartPlatform()
    q = np.stack([np.full(6, 0.135), np.full(6, 1e-4), [0.09, 0.18, 0.09, 0.18, 0.09, 0.18]])
    x, ok = mech.forward(q)
    assert ok[0] and not ok[1]
    assert np.isnan(x[1]).all()
    if ok[2]:
        np.testing.assert_allclose(mech.inverse(x[2])[0], q[2], atol=1e-12)


# -- feasibility at constructed boundaries -------------------------------------------------------
def test_leg_length_boundary_on_the_vertical_axis():
    mech = StewartPlatform()
    b, p = mech.base_joints(), mech.platform_joints()
    horizontal = np.hypot(*(p[0, :2] - b[0, :2]))
    top = np.sqrt(0.18 ** 2 - horizontal ** 2) + 0.10                   # every leg at max_leg
    for dz, expected in ((-1e-9, True), (1e-9, False)):
        x = np.array([0.0, 0.0, top + dz, 0.0, 0.0, 0.0])
        q, _ = mech.inverse(x)
        assert bool(mech.feasible(q, x)) is expected
    bottom = np.sqrt(0.09 ** 2 - horizontal ** 2) + 0.10                # every leg at min_leg
    for dz, expected in ((1e-9, True), (-1e-9, False)):
        x = np.array([0.0, 0.0, bottom + dz, 0.0, 0.0, 0.0])
        q, _ = mech.inverse(x)
        assert bool(mech.feasible(q, x)) is expected


@pytest.mark.parametrize(("column", "name"), [(0, "base_joint_limit"), (1, "platform_joint_limit")])
def test_joint_bend_boundaries(column, name):
    mech = StewartPlatform()
    x = np.array([0.02, -0.015, 0.22, 0.2, -0.1, 0.3])
    q, _ = mech.inverse(x)
    worst = mech.bend_angles(x)[:, column].max()
    assert mech.feasible(q, x)
    assert mech.replace(**{name: worst + 1e-9}).feasible(q, x)
    assert not mech.replace(**{name: worst - 1e-9}).feasible(q, x)


# -- batches and validation -----------------------------------------------------------------------
def test_batch_equals_one_at_a_time():
    mech = StewartPlatform()
    x = _random_poses(mech, 12, seed=41).reshape(3, 4, 6)
    x[1, 2, 2] = 0.5                                                      # legs too long: infeasible
    q, ok = mech.inverse(x)
    fwd, fok = mech.forward(q)
    k = mech.inverse_jacobian(q, x)
    jac = mech.jacobian(q, x)
    feas = mech.feasible(q, x)
    pts = mech.link_points(q, x)
    assert pts.shape == (3, 4, 26, 3) and not feas[1, 2]
    # Tolerances, not bit equality: a batch and a single pose may take different einsum / LAPACK
    # loops. Lengths are within 4 eps * scale of exact (FK_RTOL's derivation), unit vectors and
    # K's entries within ~8 eps, so two evaluations differ by at most twice that (16 eps). Two
    # converged Newton runs each leave residuals <= FK_RTOL * scale, so their poses differ by at
    # most |J| (2 sqrt(6) FK_RTOL scale), plus the rotation-vector extraction (2e-15 rad).
    # J = K^-1 moves by at most |J|^2 |dK| (dK < 6 * 16 eps in the 2-norm) plus LAPACK's own
    # backward error (< 6 * 8 eps |K| |J|^2) each time.
    eps = np.finfo(float).eps
    scale = mech.residual_scale(q)
    jnorm = np.linalg.norm(jac, 2, axis=(-2, -1))
    knorm = np.linalg.norm(k, 2, axis=(-2, -1))
    for i, j in itertools.product(range(3), range(4)):
        np.testing.assert_allclose(mech.inverse(x[i, j])[0], q[i, j], rtol=0, atol=16 * eps * scale[i, j])
        f1, ok1 = mech.forward(q[i, j])
        assert ok1 == fok[i, j]                          # every pose here converges with margin 16
        atol_x = jnorm[i, j] * 2 * np.sqrt(6) * FK_RTOL * scale[i, j] + 2e-15
        np.testing.assert_allclose(f1, fwd[i, j], rtol=0, atol=atol_x)
        np.testing.assert_allclose(mech.inverse_jacobian(q[i, j], x[i, j]), k[i, j], rtol=0, atol=16 * eps)
        atol_j = jnorm[i, j] ** 2 * (6 * 16 * eps + 2 * 6 * 8 * eps * knorm[i, j])
        np.testing.assert_allclose(mech.jacobian(q[i, j], x[i, j]), jac[i, j], rtol=0, atol=atol_j)
        assert mech.feasible(q[i, j], x[i, j]) == feas[i, j]    # random poses: no limit within rounding
        np.testing.assert_allclose(mech.link_points(q[i, j], x[i, j]), pts[i, j], rtol=0,
                                   atol=16 * eps * scale[i, j])


def test_link_points_trace_legs_of_the_right_length():
    mech = StewartPlatform()
    x = _random_poses(mech, 5, seed=51)
    q, _ = mech.inverse(x)
    pts = mech.link_points(q, x)
    for leg, (i, j) in enumerate([(6, 7), (8, 9), (11, 10), (12, 13), (15, 14), (16, 17)]):
        np.testing.assert_allclose(np.linalg.norm(pts[:, i] - pts[:, j], axis=-1), q[:, leg], rtol=1e-13)
    np.testing.assert_allclose(pts[:, -1], x[:, :3])
    np.testing.assert_allclose(np.linalg.norm(pts[:, -1] - pts[:, -2], axis=-1), 0.10, rtol=1e-13)


@pytest.mark.parametrize(("changes", "phrase"), [
    ({"base_radius": -0.06}, "base_radius"),
    ({"platform_radius": 0.0}, "platform_radius"),
    ({"base_half_angle": 60 * DEG}, "base_half_angle"),
    ({"platform_half_angle": -1 * DEG}, "platform_half_angle"),
    ({"tool_offset": float("inf")}, "tool_offset"),
    ({"min_leg": 0.2}, "min_leg"),
    ({"max_leg": "long"}, "max_leg"),
    ({"base_joint_limit": 0.0}, "base_joint_limit"),
    ({"platform_joint_limit": 4.0}, "platform_joint_limit"),
    ({"motor_forces": (10.0,) * 5}, "motor_forces"),
    ({"gear_ratios": (1, 1, 1, 1, 1, -1)}, "gear_ratios[L6]"),
])
def test_invalid_parameters_raise_naming_the_parameter(changes, phrase):
    with pytest.raises(ValueError) as info:
        StewartPlatform().replace(**changes)
    assert phrase in str(info.value)
    with pytest.raises(ValueError):
        StewartParams(**changes)


def test_replace_display_units_and_shapes():
    mech = StewartPlatform().replace_display(base_radius=70, base_half_angle=10, motor_forces=[20] * 6)
    assert mech.params.base_radius == 0.07 and mech.params.base_half_angle == pytest.approx(10 * DEG)
    np.testing.assert_array_equal(mech.torque_limits(), np.full(6, 20.0))
    lo, hi = mech.joint_limits()
    np.testing.assert_array_equal(lo, 0.09) and np.testing.assert_array_equal(hi, 0.18)
    assert [row[0].name for row in mech.parameter_table()] == [info.name for info in StewartPlatform.PARAM_INFO]
    with pytest.raises(ValueError, match=r"x must have shape \(\.\.\., 6\)"):
        mech.inverse(np.zeros(5))
    with pytest.raises(ValueError, match="tool_offset"):
        mech.replace_display(tool_offset="up")


def test_bad_inputs_become_nan_and_masks_without_warnings():
    mech = StewartPlatform()
    x = np.array([mech.home_pose(), [np.nan] * 6, [np.inf] * 6, [0.0, 0.0, 0.5, 0.0, 0.0, 0.0]])
    q, ok = mech.inverse(x)
    np.testing.assert_array_equal(ok, [True, False, False, True])
    np.testing.assert_array_equal(mech.feasible(q, x), [True, False, False, False])
    assert np.isnan(mech.jacobian(q, x)[1:3]).all() and np.isnan(mech.link_points(q, x)[1:3]).all()
    assert np.isnan(mech.bend_angles(x)[1:3]).all()
    # Non-finite legs, and legs no pose can realise, decided in exact arithmetic by the triangle
    # inequality |q_i - q_j| <= |b_i - b_j| + |p_i - p_j| (< 0.2 m here): legs 5 and 6 cannot differ
    # by 1e9 m, so some residual stays above 4e8 m, far above any rounding (4 eps * 1e9 m).
    fx, fok = mech.forward(np.array([[np.nan] * 6, [np.inf] * 6, [1e9] * 5 + [0.135]]))
    assert not fok.any() and np.isnan(fx).all()


def test_shipped_preset_loads_and_its_pose_is_feasible():
    from resources import load_preset, parse_preset_text, preset_to_toml
    preset = load_preset("stewart_platform")
    assert preset.kind == "stewart" and preset.mechanism == StewartPlatform()
    assert dict(preset.grid.fixed) == {"y": 0.0, "rx": 0.0, "ry": 0.0, "rz": 0.0}
    x = np.array(preset.pose)
    q, ok = preset.mechanism.inverse(x)
    assert ok and preset.mechanism.feasible(q, x)
    again = parse_preset_text(preset_to_toml(preset), "stewart_platform.toml", "stewart_platform")
    assert again.mechanism == preset.mechanism and again.grid == preset.grid and again.pose == preset.pose
