"""Planar five-bar (paper 002): Jacobians, FK/IK round trips, batches, singularities, MIC.

Headless: numpy only. Every random draw uses a fixed seed.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from kinematics import FiveBar, FiveBarParams, Singularity

WORKING_MODES = ("+-", "++", "-+", "--")
ASSEMBLY_MODES = ("up", "down")


def _cross2(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _wrap(angle):
    """Angle difference wrapped into [-pi, pi)."""
    return np.mod(angle + np.pi, 2.0 * np.pi) - np.pi


def _well_posed(mech: FiveBar, q, x, margin=0.05):
    """Poses whose legs and distal links are at least ``margin`` (|sin|) away from singular.

    Computed here from the link directions, independently of ``FiveBar.singularity``.
    """
    p = mech.params
    bases = np.array([[-p.half_base, 0.0], [p.half_base, 0.0]])
    prox = np.stack([np.cos(q), np.sin(q)], axis=-1)                 # (..., 2, 2)
    elbows = bases + p.proximal * prox
    dist = (x[..., None, :] - elbows) / p.distal
    sin_leg = _cross2(prox, dist)
    sin_dist = _cross2(dist[..., 0, :], dist[..., 1, :])
    return np.all(np.abs(sin_leg) > margin, axis=-1) & (np.abs(sin_dist) > margin)


def _random_poses(mech: FiveBar, mode: str, count: int, seed: int):
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, size=(20 * count, 2))
    x, ok = mech.forward(q, mode)
    keep = ok & _well_posed(mech, q, x)
    assert np.count_nonzero(keep) >= count, "not enough well-posed random poses"
    return q[keep][:count], x[keep][:count]


def _random_points(count: int, seed: int):
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(-0.25, 0.25, count), rng.uniform(-0.25, 0.27, count)])


# -- Jacobian ---------------------------------------------------------------------------
@pytest.mark.parametrize("assembly", ASSEMBLY_MODES)
@pytest.mark.parametrize("geometry", [
    dict(),                                                    # defaults: a1 < a2
    dict(proximal=0.15, distal=0.10, half_base=0.02),          # a1 > a2
    dict(proximal=0.06, distal=0.08, half_base=0.05),
])
def test_jacobian_matches_central_differences(assembly, geometry):
    mech = FiveBar(assembly_mode=assembly, **geometry)
    q, _ = _random_poses(mech, assembly, 200, seed=11)
    jac = mech.jacobian(q)
    step = 1e-6
    numeric = np.empty_like(jac)
    for k in range(2):
        dq = np.zeros(2)
        dq[k] = step
        plus, ok_p = mech.forward(q + dq)
        minus, ok_m = mech.forward(q - dq)
        assert ok_p.all() and ok_m.all()
        numeric[..., :, k] = (plus - minus) / (2 * step)
    scale = np.max(np.abs(jac), axis=(-2, -1), keepdims=True)
    err = np.max(np.abs(numeric - jac) / scale)
    assert err < 1e-7, f"worst relative Jacobian error {err:.2e}"


def test_jacobian_uses_given_pose_for_assembly_mode():
    """``jacobian(q, x)`` with the other assembly's pose equals that assembly's Jacobian."""
    up = FiveBar(assembly_mode="up")
    down = up.replace(assembly_mode="down")
    q, _ = _random_poses(up, "up", 50, seed=12)
    x_down, ok = down.forward(q)
    assert ok.all()
    np.testing.assert_array_equal(up.jacobian(q, x_down), down.jacobian(q))
    assert not np.allclose(up.jacobian(q), down.jacobian(q))


def test_jacobian_gives_directional_derivatives():
    """xdot = J qdot along random joint-rate directions (forward differences, loose check)."""
    mech = FiveBar()
    q, _ = _random_poses(mech, "up", 20, seed=13)
    rng = np.random.default_rng(14)
    qdot = rng.normal(size=q.shape)
    jac = mech.jacobian(q)
    eps = 1e-7
    x0, _ = mech.forward(q)
    x1, _ = mech.forward(q + eps * qdot)
    np.testing.assert_allclose((x1 - x0) / eps, np.einsum("...ij,...j->...i", jac, qdot), rtol=0, atol=1e-5)


# -- FK / IK round trips -----------------------------------------------------------------
@pytest.mark.parametrize("working", WORKING_MODES)
def test_forward_of_inverse_round_trips_in_the_matching_assembly(working):
    mech = FiveBar()
    x = _random_points(4000, seed=21)
    q, ok = mech.inverse(x, working)
    assert ok.sum() > 1000
    q, x = q[ok], x[ok]
    assert np.all(np.isfinite(q))
    # The matching assembly mode is the side of B1 -> B2 that C lies on ("up" = left).
    elbows = mech.elbows(q)
    left = _cross2(elbows[:, 1] - elbows[:, 0], x - elbows[:, 0]) > 0
    x_up, ok_up = mech.forward(q, "up")
    x_down, ok_down = mech.forward(q, "down")
    assert ok_up.all() and ok_down.all()
    x_match = np.where(left[:, None], x_up, x_down)
    good = _well_posed(mech, q, x, margin=1e-2)
    assert good.sum() > 900
    err = np.linalg.norm(x_match - x, axis=-1)
    assert err[good].max() < 1e-12
    # Near a direct singularity FK is ill-conditioned, but one assembly still reproduces x.
    err_any = np.minimum(np.linalg.norm(x_up - x, axis=-1), np.linalg.norm(x_down - x, axis=-1))
    assert err_any.max() < 1e-9
    # The other assembly mode is a different point wherever the pose is well posed.
    x_other = np.where(left[:, None], x_down, x_up)
    assert np.linalg.norm(x_other - x, axis=-1)[good].min() > 1e-6


def test_usual_haptic_configuration_is_plus_minus_up():
    """Points in front of the base, elbows outwards ("+-"), assemble "up" (module docstring)."""
    mech = FiveBar()
    x = np.column_stack([np.linspace(-0.05, 0.05, 11), np.full(11, 0.15)])
    q, ok = mech.inverse(x, "+-")
    assert ok.all()
    elbows = mech.elbows(q)
    assert np.all(elbows[:, 0, 0] < -mech.params.half_base)   # leg 1 elbow outside, left
    assert np.all(elbows[:, 1, 0] > mech.params.half_base)    # leg 2 elbow outside, right
    x_back, _ = mech.forward(q, "up")
    np.testing.assert_allclose(x_back, x, rtol=0, atol=1e-13)


@pytest.mark.parametrize("assembly", ASSEMBLY_MODES)
def test_inverse_of_forward_returns_q_in_its_working_mode(assembly):
    mech = FiveBar()
    q, x = _random_poses(mech, assembly, 300, seed=31)
    # Working mode of each pose: the side of the line base_i -> C its proximal link lies on.
    bases = np.array([[-mech.params.half_base, 0.0], [mech.params.half_base, 0.0]])
    to_c = x[:, None, :] - bases
    prox = np.stack([np.cos(q), np.sin(q)], axis=-1)
    signs = np.where(_cross2(to_c, prox) > 0, "+", "-")
    modes = np.char.add(signs[:, 0], signs[:, 1])
    seen = set()
    for mode in WORKING_MODES:
        sel = modes == mode
        if not sel.any():
            continue
        seen.add(mode)
        q_back, ok = mech.inverse(x[sel], mode)
        assert ok.all()
        assert np.abs(_wrap(q_back - q[sel])).max() < 1e-10
        # Any other working mode gives different joints.
        for other in set(WORKING_MODES) - {mode}:
            q_other, _ = mech.inverse(x[sel], other)
            assert np.all(np.abs(_wrap(q_other - q[sel])).max(axis=-1) > 1e-6)
    assert len(seen) >= 3


def test_default_working_mode_comes_from_params():
    x = _random_points(200, seed=32)
    for mode in WORKING_MODES:
        mech = FiveBar(working_mode=mode)
        np.testing.assert_array_equal(mech.inverse(x)[0], FiveBar().inverse(x, mode)[0])


# -- unreachable points and non-assembling joints ----------------------------------------
def test_unreachable_points_give_nan_and_false():
    mech = FiveBar()
    a1, a2, a3 = mech.params.proximal, mech.params.distal, mech.params.half_base
    x = np.array([
        [0.0, a1 + a2 + 0.01],             # beyond both outer circles
        [-a3 + 0.5 * (a2 - a1), 0.0],      # in the hole of leg 1: |C - O1| < a2 - a1
        [-a3, 0.0],                         # on base 1: distance 0
        [0.5, 0.5],
        [0.0, 0.15],                        # reachable control point
    ])
    for mode in WORKING_MODES:
        q, ok = mech.inverse(x, mode)
        np.testing.assert_array_equal(ok, [False, False, False, False, True])
        assert np.all(np.isnan(q[:4]))
        assert np.all(np.isfinite(q[4]))


def test_boundary_points_are_reachable_with_rounding_slack():
    """Points on the outer circle of a leg (cosine = 1 up to rounding) are kept, not lost."""
    mech = FiveBar()
    a1, a2, a3 = mech.params.proximal, mech.params.distal, mech.params.half_base
    angles = np.linspace(0.6, 1.4, 50)
    x = np.column_stack([-a3 + (a1 + a2) * np.cos(angles), (a1 + a2) * np.sin(angles)])
    q, ok = mech.inverse(x, "+-")
    assert ok.all()
    np.testing.assert_allclose(q[:, 0], angles, rtol=0, atol=1e-7)   # leg 1 stretched
    _, ok_out = mech.inverse(np.column_stack([-a3 + (a1 + a2 + 1e-9) * np.cos(angles),
                                              (a1 + a2 + 1e-9) * np.sin(angles)]), "+-")
    assert not ok_out.any()


def test_forward_that_cannot_assemble_gives_nan_and_false():
    mech = FiveBar(distal=0.05)            # chord up to 0.26 m > 2 * 0.05 m
    q = np.array([[np.pi, 0.0], [np.pi / 2, np.pi / 2], [1.7, 1.4]])
    x, ok = mech.forward(q)
    np.testing.assert_array_equal(ok, [False, True, True])
    assert np.all(np.isnan(x[0]))
    assert np.all(np.isfinite(x[1:]))
    # The assembled poses really have distal links of length a2.
    elbows = mech.elbows(q[1:])
    np.testing.assert_allclose(np.linalg.norm(x[1:, None, :] - elbows, axis=-1), 0.05, rtol=1e-12)


# -- batches -----------------------------------------------------------------------------
def test_batch_equals_one_at_a_time():
    mech = FiveBar()
    x = _random_points(60, seed=41)
    rng = np.random.default_rng(42)
    q_rand = rng.uniform(-np.pi, np.pi, size=(60, 2))
    q_b, ok_b = mech.inverse(x)
    x_b, okf_b = mech.forward(q_rand)
    jac_b = mech.jacobian(q_rand)
    sing_b = mech.singularity(q_rand)
    feas_b = mech.feasible(q_b)
    links_b = mech.link_points(q_rand)
    elbows_b = mech.elbows(q_rand)
    assert ok_b.any() and not ok_b.all()
    assert okf_b.any()
    for i in range(60):
        q_i, ok_i = mech.inverse(x[i])
        assert q_i.shape == (2,) and ok_i.shape == ()
        np.testing.assert_array_equal(q_i, q_b[i])
        assert ok_i == ok_b[i]
        x_i, okf_i = mech.forward(q_rand[i])
        np.testing.assert_array_equal(x_i, x_b[i])
        assert okf_i == okf_b[i]
        jac_i = mech.jacobian(q_rand[i])
        assert jac_i.shape == (2, 2)
        np.testing.assert_array_equal(jac_i, jac_b[i])
        assert mech.singularity(q_rand[i]) == sing_b[i]
        assert mech.feasible(q_b[i]) == feas_b[i]
        np.testing.assert_array_equal(mech.link_points(q_rand[i]), links_b[i])
        np.testing.assert_array_equal(mech.elbows(q_rand[i]), elbows_b[i])


def test_nested_batch_shapes_equal_flat_batch():
    mech = FiveBar(joint_limits=((-1.0, 3.0), (-2.0, 2.5)))
    x = _random_points(4 * 5, seed=43)
    rng = np.random.default_rng(44)
    q = rng.uniform(-np.pi, np.pi, size=(4 * 5, 2))
    q_inv, ok = mech.inverse(x.reshape(4, 5, 2))
    assert q_inv.shape == (4, 5, 2) and ok.shape == (4, 5)
    flat_q, flat_ok = mech.inverse(x)
    np.testing.assert_array_equal(q_inv.reshape(-1, 2), flat_q)
    np.testing.assert_array_equal(ok.ravel(), flat_ok)
    x_fwd, okf = mech.forward(q.reshape(4, 5, 2))
    assert x_fwd.shape == (4, 5, 2) and okf.shape == (4, 5)
    np.testing.assert_array_equal(x_fwd.reshape(-1, 2), mech.forward(q)[0])
    jac = mech.jacobian(q.reshape(4, 5, 2))
    assert jac.shape == (4, 5, 2, 2)
    np.testing.assert_array_equal(jac.reshape(-1, 2, 2), mech.jacobian(q))
    sing = mech.singularity(q.reshape(4, 5, 2))
    assert sing.shape == (4, 5)
    feas = mech.feasible(q.reshape(4, 5, 2))
    assert feas.shape == (4, 5)
    np.testing.assert_array_equal(feas.ravel(), mech.feasible(q))
    assert mech.link_points(q.reshape(4, 5, 2)).shape == (4, 5, 5, 2)


def test_wrong_shapes_raise_naming_the_argument():
    mech = FiveBar()
    with pytest.raises(ValueError, match=r"x must have shape \(\.\.\., 2\)"):
        mech.inverse(np.zeros((4, 3)))
    with pytest.raises(ValueError, match=r"q must have shape \(\.\.\., 2\)"):
        mech.forward(np.zeros(3))
    with pytest.raises(ValueError, match=r"q must have shape"):
        mech.jacobian(1.0)
    with pytest.raises(ValueError, match="working_mode"):
        mech.inverse(np.zeros(2), "+x")
    with pytest.raises(ValueError, match="assembly_mode"):
        mech.forward(np.zeros(2), "sideways")


# -- feasibility with joint limits -------------------------------------------------------
def test_feasible_checks_joint_limits_and_nan():
    mech = FiveBar(joint_limits=((0.0, 2.0), (-1.0, 1.0)))
    q = np.array([[1.0, 0.0], [0.0, -1.0], [2.0, 1.0], [-1e-9, 0.0], [2.0 + 1e-9, 0.0],
                  [1.0, -1.0 - 1e-9], [1.0, 1.0 + 1e-9], [np.nan, 0.0]])
    np.testing.assert_array_equal(mech.feasible(q), [True, True, True, False, False, False, False, False])
    assert FiveBar().feasible(np.array([[10.0, -10.0]]))[0]
    assert not FiveBar().feasible(np.array([[np.inf, 0.0]]))[0]


# -- parameters: replace, validation, immutability ---------------------------------------
def test_replace_returns_new_validated_model():
    mech = FiveBar()
    longer = mech.replace(proximal=0.12, gear_ratios=(2.0, 3.0))
    assert isinstance(longer, FiveBar) and longer is not mech
    assert longer.params.proximal == 0.12 and longer.params.gear_ratios == (2.0, 3.0)
    assert mech.params.proximal == 0.10 and mech.params.gear_ratios == (1.0, 1.0)
    assert longer.params.distal == mech.params.distal
    np.testing.assert_allclose(longer.torque_limits(), [0.2, 0.3], rtol=1e-15)
    assert longer != mech and longer == FiveBar(dataclasses.replace(mech.params, proximal=0.12,
                                                                      gear_ratios=(2.0, 3.0)))
    assert hash(longer) == hash(mech.replace(proximal=0.12, gear_ratios=(2.0, 3.0)))
    # Geometry really changed: the outer reach grows with the proximal link.
    _, ok_old = mech.inverse(np.array([0.0, 0.265]))
    _, ok_new = longer.inverse(np.array([0.0, 0.265]))
    assert not ok_old and ok_new


@pytest.mark.parametrize("changes, pattern", [
    (dict(proximal=-0.1), r"proximal must be a positive finite number in m, got -0\.1"),
    (dict(distal=0.0), r"distal must be a positive"),
    (dict(half_base=float("nan")), r"half_base must be a positive"),
    (dict(proximal="long"), r"proximal must be a positive"),
    (dict(motor_torques=(0.1,)), r"motor_torques needs 2 values \(theta_1, theta_2\), got 1"),
    (dict(motor_torques=(0.1, 0.0)), r"motor_torques\[theta_2\] must be a positive"),
    (dict(gear_ratios=(1.0, 2.0, 3.0)), r"gear_ratios needs 2 values"),
    (dict(gear_ratios=5.0), r"gear_ratios needs 2 values"),
    (dict(working_mode="+0"), r"working_mode must be one of"),
    (dict(assembly_mode="left"), r"assembly_mode must be one of"),
    (dict(joint_limits=((1.0, 0.0), (0.0, 1.0))), r"joint_limits"),
    (dict(wheelbase=0.1), r"FiveBar has no parameter 'wheelbase'"),
])
def test_replace_validates_and_names_the_argument(changes, pattern):
    mech = FiveBar()
    with pytest.raises(ValueError, match=pattern):
        mech.replace(**changes)


def test_replace_display_converts_units():
    mech = FiveBar().replace_display(proximal=120, motor_torques=(0.2, 0.3))
    assert mech.params.proximal == pytest.approx(0.12, rel=1e-15)
    assert mech.params.motor_torques == (0.2, 0.3)
    table = dict((info.name, value) for info, value in mech.parameter_table())
    assert table["proximal"] == pytest.approx(120.0, rel=1e-15)
    with pytest.raises(ValueError, match="proximal must be a number"):
        FiveBar().replace_display(proximal="x")


def test_models_are_immutable():
    mech = FiveBar()
    with pytest.raises(AttributeError, match="immutable"):
        mech.params = FiveBarParams(proximal=0.2)
    with pytest.raises(AttributeError):
        mech.anything = 1
    with pytest.raises(dataclasses.FrozenInstanceError):
        mech.params.proximal = 0.2
    assert mech.params.proximal == 0.10


# -- singularity classes -----------------------------------------------------------------
def test_singularity_classes_on_constructed_poses():
    a1, a2, a3 = 0.10, 0.15, 0.03
    mech = FiveBar(proximal=a1, distal=a2, half_base=a3)
    # Leg 1 fully stretched towards angle 1.0: inverse (boundary) singularity.
    x = np.array([-a3 + (a1 + a2) * np.cos(1.0), (a1 + a2) * np.sin(1.0)])
    q, ok = mech.inverse(x, "+-")
    assert ok
    assert mech.singularity(q, x) == Singularity.INVERSE
    assert mech.singularity(q) == Singularity.INVERSE           # pose from FK
    # Leg 2 folded (|C - O2| = a2 - a1): also inverse.
    x = np.array([a3 + (a2 - a1) * np.cos(2.0), (a2 - a1) * np.sin(2.0)])
    q, ok = mech.inverse(x, "+-")
    assert ok
    assert mech.singularity(q, x) == Singularity.INVERSE
    # A generic interior pose: none.
    q, ok = mech.inverse(np.array([0.01, 0.16]), "+-")
    assert ok and mech.singularity(q) == Singularity.NONE

    # Distal links collinear (C between the elbows): direct singularity.
    short = FiveBar(proximal=a1, distal=0.12, half_base=a3)
    alpha = np.arccos((0.12 - a3) / a1)
    q = np.array([np.pi - alpha, alpha])
    c = np.array([0.0, a1 * np.sin(alpha)])
    elbows = short.elbows(q)
    np.testing.assert_allclose(np.linalg.norm(c - elbows, axis=-1), 0.12, rtol=1e-14)
    assert short.singularity(q, c) == Singularity.DIRECT
    # Its Jacobian is unbounded there, while a nearby regular pose has a finite one.
    assert np.max(np.abs(short.jacobian(q, c))) > 1e10
    assert np.max(np.abs(short.jacobian(q + [-0.05, 0.05]))) < 10.0

    # Both at once: leg 1 stretched along +x, leg 2 folded back onto it (a2 = a3).
    both = FiveBar(proximal=0.10, distal=0.05, half_base=0.05)
    q = np.array([0.0, 0.0])
    c = np.array([0.10, 0.0])
    np.testing.assert_allclose(np.linalg.norm(c - both.elbows(q), axis=-1), 0.05, rtol=1e-14)
    assert both.singularity(q, c) == Singularity.COMBINED


def test_singularity_tolerance_is_respected():
    """Just off the stretched pose: singular within the tolerance, regular beyond it."""
    a1, a2, a3 = 0.10, 0.15, 0.03
    x = np.array([-a3 + (a1 + a2) * np.cos(1.0), (a1 + a2) * np.sin(1.0)])
    q, _ = FiveBar().inverse(x, "+-")
    # Rotating the distal link by delta about the elbow gives |sin| = sin(delta).
    b1 = FiveBar().elbows(q)[0]
    for delta, tol, expected in [(1e-6, 1e-5, Singularity.INVERSE), (1e-6, 1e-7, Singularity.NONE)]:
        mech = FiveBar(singular_tol=tol)
        c = b1 + a2 * np.array([np.cos(q[0] + delta), np.sin(q[0] + delta)])
        # Leg 2 unchanged in angle: its |sin| is far from 0, direct too.
        assert mech.singularity(q, c) == expected


# -- maximum inscribed circle -------------------------------------------------------------
@pytest.mark.parametrize("a1, a2, a3", [(0.10, 0.15, 0.03), (0.15, 0.10, 0.02), (0.08, 0.09, 0.05)])
def test_max_inscribed_circle_is_tangent_to_both_annuli(a1, a2, a3):
    mech = FiveBar(proximal=a1, distal=a2, half_base=a3)
    y, r = mech.max_inscribed_circle()
    assert r > 0 and y > 0
    for base in ([-a3, 0.0], [a3, 0.0]):
        d = np.hypot(0.0 - base[0], y - base[1])
        assert d + r == pytest.approx(a1 + a2, rel=1e-14)       # tangent to the outer circle
        assert d - r == pytest.approx(abs(a1 - a2), abs=1e-14)  # tangent to the inner circle
    # Every point of the (slightly shrunk) circle is reachable in every working mode ...
    phi = np.linspace(0.0, 2.0 * np.pi, 721)
    ring = np.column_stack([r * (1 - 1e-9) * np.cos(phi), y + r * (1 - 1e-9) * np.sin(phi)])
    for mode in WORKING_MODES:
        assert mech.inverse(ring, mode)[1].all()
    # ... and the tangent points (towards and away from each base) are on the boundary:
    # a slightly larger circle leaves the workspace there, in both the outer and inner annulus.
    centre = np.array([0.0, y])
    for base in ([-a3, 0.0], [a3, 0.0]):
        away = (centre - base) / np.linalg.norm(centre - base)
        for direction in (away, -away):
            inside = centre + r * (1 - 1e-9) * direction
            outside = centre + r * (1 + 1e-6) * direction
            assert mech.inverse(inside)[1]
            assert not mech.inverse(outside)[1]
    # Moving the centre along the y axis loses points (it is the maximum).
    for shift in (-1e-5, 1e-5):
        moved = ring + [0.0, shift]
        assert not mech.inverse(moved)[1].all()


def test_max_inscribed_circle_nan_when_bases_too_far_apart():
    y, r = FiveBar(proximal=0.05, distal=0.06, half_base=0.07).max_inscribed_circle()
    assert np.isnan(y) and r == pytest.approx(0.05)


def test_link_points_are_bases_elbows_and_end_effector():
    mech = FiveBar()
    q, x = _random_poses(mech, "up", 5, seed=51)
    pts = mech.link_points(q)
    a3 = mech.params.half_base
    np.testing.assert_array_equal(pts[:, 0], np.broadcast_to([-a3, 0.0], (5, 2)))
    np.testing.assert_array_equal(pts[:, 4], np.broadcast_to([a3, 0.0], (5, 2)))
    np.testing.assert_allclose(pts[:, 2], x, rtol=0, atol=1e-15)
    seg = np.linalg.norm(np.diff(pts, axis=1), axis=-1)
    np.testing.assert_allclose(seg, np.tile([0.10, 0.15, 0.15, 0.10], (5, 1)), rtol=1e-12)


def test_all_mode_pairs_cover_the_same_reachable_set():
    """Every working mode reaches exactly the intersection of the two leg annuli."""
    mech = FiveBar()
    x = _random_points(3000, seed=61)
    a1, a2, a3 = mech.params.proximal, mech.params.distal, mech.params.half_base
    d1 = np.hypot(x[:, 0] + a3, x[:, 1])
    d2 = np.hypot(x[:, 0] - a3, x[:, 1])
    inside = (d1 <= a1 + a2) & (d1 >= a2 - a1) & (d2 <= a1 + a2) & (d2 >= a2 - a1)
    assert 500 < inside.sum() < 2900
    for mode in WORKING_MODES:
        np.testing.assert_array_equal(mech.inverse(x, mode)[1], inside)
