"""metrics.pose: one pose's report is consistent with itself and with the map (its JSON: tests/app/test_pose_report.py).

The heavy checks of each metric (against mpmath, central differences) live with the
metrics; here: the report's pieces agree with each other and with ``evaluate``.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from kinematics import FiveBar, Inverse3
from metrics.bottleneck import BOTTLENECK_TIE
from metrics.pose import PoseReport, analyse_pose
from metrics.quantities import evaluate
from metrics.torque_box import sign_patterns
from resources import load_preset

INVERSE3 = load_preset("inverse3_prototype").mechanism
FIVEBAR = load_preset("fivebar_singh").mechanism
# A few feasible points of each device (m), spread over the workspace.
POINTS = [
    (INVERSE3, (0.170, 0.0223, 0.230)),
    (INVERSE3, (0.250, 0.0223, 0.100)),
    (INVERSE3, (0.120, 0.0900, 0.300)),     # off the theta_0 = 0 slice
    (FIVEBAR, (0.0, 0.150)),
    (FIVEBAR, (-0.080, 0.120)),
    (FIVEBAR, (0.150, 0.060)),
]
IDS = ["i3-centre", "i3-low", "i3-turned", "fb-centre", "fb-left", "fb-right"]


@pytest.fixture(params=range(len(POINTS)), ids=IDS)
def case(request) -> tuple[object, np.ndarray, PoseReport]:
    mech, x = POINTS[request.param]
    return mech, np.array(x), analyse_pose(mech, x)


def test_feasible_points_have_finite_numbers_of_the_right_shapes(case):
    mech, x, r = case
    m = n = mech.task_dim
    assert r.reachable and r.feasible
    assert r.joints.shape == (n,) and r.jacobian.shape == (m, n)
    assert r.vertices.shape == (2 ** n, m) and r.reference_forces.shape == (m, n)
    assert r.force_ellipsoid.radii.shape == (m,) and r.force_ellipsoid.axes.shape == (m, m)
    assert len(r.faces) == (6 if n == 3 else 1)
    for value in (r.condition_number, r.isotropic_force, r.anisotropic_force, r.manipulability):
        assert math.isfinite(value)
    np.testing.assert_allclose(mech.forward(r.joints)[0], x, atol=1e-12)


def test_report_equals_the_quantity_graph_at_the_same_point(case):
    mech, x, r = case
    names = ["condition_number", "isotropic_force", "anisotropic_force", "bottleneck", "manipulability",
             "jacobian"] + (["singularity"] if isinstance(mech, FiveBar) else [])
    ev = evaluate(mech, x[None], names)
    assert bool(ev.feasible[0])
    np.testing.assert_allclose(r.joints, ev.joints[0], rtol=0, atol=0)
    np.testing.assert_allclose(r.jacobian, ev.values["jacobian"][0], rtol=1e-15)
    for name in ("condition_number", "isotropic_force", "anisotropic_force", "manipulability"):
        assert getattr(r, name) == pytest.approx(float(ev.values[name][0]), rel=1e-14), name
    assert r.bottleneck == int(ev.values["bottleneck"][0])
    if isinstance(mech, FiveBar):
        assert r.singularity == int(ev.values["singularity"][0]) == 0
        assert r.singularity_name == "none"
    else:
        assert r.singularity is None and r.singularity_name is None


def test_every_vertex_lies_on_one_facet_of_each_actuator(case):
    _, _, r = case
    # tau = J^T f at a vertex is (+-t_1, ..., +-t_n) with the vertex's own sign pattern.
    torques = r.vertices @ r.jacobian
    np.testing.assert_allclose(torques, sign_patterns(len(r.joints)) * r.torque_limits, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(r.jacobian.T @ r.reference_forces, np.diag(r.torque_limits), atol=1e-12)


def test_isotropic_ball_is_inside_the_polytope_and_touches_the_bottleneck_facet(case):
    _, _, r = case
    rng = np.random.default_rng(1)
    directions = rng.normal(size=(2000, len(r.x)))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    inside = (r.isotropic_force * (1 - 1e-12)) * directions
    assert np.all(np.abs(inside @ r.jacobian) <= r.torque_limits)
    # Just beyond the radius along a nearest facet's normal, that actuator saturates. Which facet
    # argmin picks when two tie (fb-centre on the symmetry axis, i3-turned: p1 and p2 equally
    # near) is rounding; every nearest facet touches the ball, so any of them will do here.
    d = r.facet_distances
    b = int(np.argmin(d))
    normal = r.jacobian[:, b] / np.linalg.norm(r.jacobian[:, b])
    outside = r.isotropic_force * (1 + 1e-9) * normal
    assert abs(outside @ r.jacobian[:, b]) > r.torque_limits[b]
    assert r.isotropic_force == pytest.approx(d.min(), rel=1e-15)
    # The reported bottleneck is a nearest facet (t_u / |J[:, u]|: a 2-norm of <= 3 terms and a
    # division, relative error < 4 eps each, so 8 eps apart may be equal in exact arithmetic), or
    # the tie code when several are.
    near = np.flatnonzero(d <= d.min() * (1 + 8 * np.finfo(float).eps))
    assert r.bottleneck in near or (r.bottleneck == BOTTLENECK_TIE and near.size > 1)
    if r.bottleneck >= 0:
        assert r.bottleneck_name == r.joint_names[r.bottleneck]


def test_textbook_inequalities_between_ball_polytope_and_ellipsoid(case):
    _, _, r = case
    n = len(r.joints)
    # E inside P inside sqrt(n) E, with E the force ellipsoid (DESIGN.md).
    smallest = r.force_ellipsoid.radii.min()
    assert smallest * (1 - 1e-12) <= r.isotropic_force <= math.sqrt(n) * smallest * (1 + 1e-12)
    assert r.isotropic_force <= r.anisotropic_force
    assert r.anisotropic_force == pytest.approx(np.linalg.norm(r.vertices, axis=1).max(), rel=1e-12)
    assert r.condition_number == pytest.approx(r.singular_values[0] / r.singular_values[-1], rel=1e-14)


def test_velocity_ellipsoid_scales_with_joint_speeds(case):
    mech, x, r = case
    np.testing.assert_allclose(r.velocity_ellipsoid.radii, r.singular_values, rtol=1e-12)
    faster = analyse_pose(mech, x, joint_speeds=np.full(len(r.joints), 2.0))
    np.testing.assert_allclose(faster.velocity_ellipsoid.radii, 2.0 * r.velocity_ellipsoid.radii, rtol=1e-12)
    # Axes are unit and orthogonal.
    axes = r.velocity_ellipsoid.axes
    np.testing.assert_allclose(axes.T @ axes, np.eye(len(x)), atol=1e-12)


def test_clamp_keeps_small_forces_and_scales_large_ones_to_the_radius(case):
    _, x, r = case
    small = np.full(len(x), 0.1 * r.isotropic_force / math.sqrt(len(x)))
    np.testing.assert_array_equal(r.clamp(small), small)
    big = np.zeros(len(x))
    big[-1] = -50.0 * r.isotropic_force
    clamped = r.clamp(big)
    assert np.linalg.norm(clamped) == pytest.approx(r.isotropic_force, rel=1e-14)
    assert clamped[-1] < 0 and np.allclose(clamped[:-1], 0)


def test_unreachable_point_gives_nan_and_a_mask_not_an_exception():
    r = analyse_pose(INVERSE3, (2.0, 0.0, 0.2))
    assert not r.reachable and not r.feasible
    assert np.all(np.isnan(r.joints)) and np.all(np.isnan(r.vertices))
    assert math.isnan(r.isotropic_force) and r.bottleneck == -1 and r.bottleneck_name is None
    fb = analyse_pose(FIVEBAR, (0.0, 0.5))
    assert not fb.reachable and fb.singularity_name is None


def test_reachable_point_outside_the_body_constraint_is_analysed_but_not_feasible():
    # x = 50 mm < 65 mm and z = 100 mm < 180 mm: inside the device's body.
    r = analyse_pose(INVERSE3, (0.050, 0.0223, 0.100))
    assert r.reachable and not r.feasible
    # Analysed: a bottleneck is named, an actuator or a tie (p1 and p2 are always equally near
    # on the Inverse3, by the five-bar's symmetry, so which one wins is rounding).
    assert math.isfinite(r.isotropic_force) and (r.bottleneck >= 0 or r.bottleneck == BOTTLENECK_TIE)


def test_boundary_pose_has_unbounded_numbers():
    # Leg 2 fully stretched (|C - base2| = a1 + a2): an inverse singularity on the boundary.
    p = FIVEBAR.params
    angle = np.radians(120.0)
    x = np.array([p.half_base, 0.0]) + (p.proximal + p.distal) * np.array([np.cos(angle), np.sin(angle)])
    r = analyse_pose(FIVEBAR, x)
    assert r.reachable
    assert r.condition_number > 1e6


def test_report_is_immutable():
    r = analyse_pose(INVERSE3, (0.170, 0.0223, 0.230))
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.isotropic_force = 0.0  # type: ignore[misc]
    with pytest.raises(ValueError):
        r.jacobian[0, 0] = 1.0
    with pytest.raises(ValueError):
        r.force_ellipsoid.radii[0] = 1.0


@pytest.mark.parametrize("bad", [(0.1, 0.2), (0.1, 0.2, 0.3, 0.4), [[0.1, 0.0, 0.2]]])
def test_wrong_point_shape_raises_naming_x(bad):
    with pytest.raises(ValueError, match=r"\bx\b"):
        analyse_pose(Inverse3(), bad)


def test_bad_joint_speeds_raise_naming_them():
    with pytest.raises(ValueError, match="joint_speeds"):
        analyse_pose(Inverse3(), (0.170, 0.0223, 0.230), joint_speeds=[1.0, 0.0, 1.0])


def test_parts_not_requested_are_not_computed_and_the_scalars_do_not_change():
    x = (0.170, 0.0223, 0.230)
    full = analyse_pose(INVERSE3, x)
    bare = analyse_pose(INVERSE3, x, parts=())
    for name in ("vertices", "faces", "reference_forces", "force_ellipsoid", "velocity_ellipsoid"):
        assert getattr(bare, name) is None, name
    for name in ("condition_number", "isotropic_force", "anisotropic_force", "bottleneck", "manipulability"):
        assert getattr(bare, name) == getattr(full, name), name
    some = analyse_pose(INVERSE3, x, parts={"vertices", "force_ellipsoid"})
    np.testing.assert_array_equal(some.vertices, full.vertices)
    assert some.faces == full.faces and some.velocity_ellipsoid is None
    assert analyse_pose(INVERSE3, (2.0, 0.0, 0.0), parts=["vertices"]).force_ellipsoid is None


@pytest.mark.parametrize("parts", [["polytope"], "vertices"])
def test_unknown_parts_raise_naming_parts(parts):
    with pytest.raises(ValueError, match="parts"):
        analyse_pose(INVERSE3, (0.170, 0.0223, 0.230), parts=parts)


def test_bottleneck_phrase_names_the_actuator_or_the_actuators_that_tie():
    """On the five-bar's axis of symmetry both legs' facets are equally near (a tie of theta_1
    and theta_2); off it one leg limits; the phrase says which, as the captions print it."""
    mech = load_preset("fivebar_singh").mechanism
    on_axis = analyse_pose(mech, np.array([0.0, 0.15]))
    assert on_axis.bottleneck == BOTTLENECK_TIE
    assert on_axis.bottleneck_phrase == "theta_1 and theta_2 limit equally"
    off_axis = analyse_pose(mech, np.array([0.04, 0.17]))
    assert off_axis.bottleneck_phrase == f"{off_axis.bottleneck_name} limits" and off_axis.bottleneck >= 0
    unreachable = analyse_pose(mech, np.array([1.0, 1.0]))
    assert not unreachable.reachable and unreachable.bottleneck_phrase is None


@pytest.mark.parametrize("device, gravity", [("inverse3_prototype", None), ("woodenhaptics", None),
                                             ("fivebar_singh", None), ("phantom_premium_15", (0.0, 0.0, -9.81)),
                                             ("phantom_premium_15", (0.0, -9.81, 0.0)),
                                             ("novint_falcon", None), ("stewart_platform", None)])
def test_force_along_a_direction_is_where_the_ray_leaves_the_force_polytope(device, gravity):
    """Against a linear programme over the polytope's vertices (their convex hull, as
    ``torque_box`` makes them: J^-T of the torque box's corners, shifted by gravity): max s with
    s d a convex combination of the vertices. A different route from the slabs the method
    intersects. The clamp (paper 000 eq. 9) never exceeds it."""
    from scipy.optimize import linprog

    from metrics.loading import Loading

    preset = load_preset(device)
    loading = Loading(gravity=gravity) if gravity is not None else None
    rng = np.random.default_rng(5)
    report = analyse_pose(preset.mechanism, np.asarray(preset.pose), parts=("vertices",), loading=loading)
    assert report.feasible
    vertices = np.asarray(report.vertices, float)            # (2^n, m): the force set at zero moment
    m = vertices.shape[1]
    scale = np.abs(vertices).max()
    for _ in range(12):
        d = rng.normal(size=m)
        d /= np.linalg.norm(d)
        # variables (s, lambda_1..K): maximise s, s d = V^T lambda, sum lambda = 1, lambda >= 0
        k = len(vertices)
        a_eq = np.vstack([np.column_stack([d, -vertices.T]), np.concatenate([[0.0], np.ones(k)])])
        b_eq = np.concatenate([np.zeros(m), [1.0]])
        lp = linprog(np.concatenate([[-1.0], np.zeros(k)]), A_eq=a_eq, b_eq=b_eq,
                     bounds=[(0, None)] * (k + 1), method="highs")
        assert lp.status == 0
        # The LP's feasibility tolerance (1e-7 of the vertices' size) bounds the agreement.
        assert report.force_along(d) == pytest.approx(lp.x[0], rel=1e-6, abs=1e-6 * scale)
        assert report.force_along(d) >= np.linalg.norm(report.clamp(100.0 * scale * d)) * (1 - 1e-12)
    assert math.isnan(report.force_along(np.zeros(m)))


def test_force_along_is_not_claimed_for_redundant_actuation_or_an_unreachable_point():
    twin = load_preset("twin_pantograph")
    report = analyse_pose(twin.mechanism, np.asarray(twin.pose))
    assert report.reachable and math.isnan(report.force_along(np.ones(3)))
    assert math.isnan(analyse_pose(INVERSE3, (2.0, 0.0, 0.2)).force_along([1.0, 0.0, 0.0]))


def test_force_along_with_the_origin_outside_the_set_is_where_the_ray_crosses_it():
    """Gravity beyond a rating (a bias past its limit) leaves the origin outside slab u: a ray may
    still cross the set further out (its far end is the answer) or miss it (nan). Against a linear
    programme over the slabs, for directions all round."""
    from scipy.optimize import linprog

    mech = load_preset("fivebar_singh").mechanism
    report = analyse_pose(mech, np.array([0.04, 0.17]))
    t = np.asarray(report.torque_limits, float)
    biased = dataclasses.replace(report, torque_bias=np.array([1.5 * t[0], 0.0]))   # slab 0 misses 0
    c_all = np.asarray(biased.jacobian, float)
    lo, hi = -t - biased.torque_bias, t - biased.torque_bias
    outcomes = set()
    for angle in np.linspace(0.0, 2 * np.pi, 73)[:-1]:
        d = np.array([np.cos(angle), np.sin(angle)])
        c = c_all.T @ d
        lp = linprog([-1.0], A_ub=np.concatenate([c, -c])[:, None], b_ub=np.concatenate([hi, -lo]),
                     bounds=[(0, None)], method="highs")
        got = biased.force_along(d)
        if lp.status == 2:                         # infeasible: the ray misses the set
            assert math.isnan(got)
            outcomes.add("miss")
        else:
            assert lp.status == 0 and got == pytest.approx(lp.x[0], rel=1e-9)
            outcomes.add("cross")
    assert outcomes == {"miss", "cross"}
