"""Torque ratings and gravity through the quantity graph, maps and poses (``metrics.loading``).

References: the unloaded graph itself (the default must be bit-identical), the rated limits
scaled by hand, and for the gravity-shifted force set an independent construction with
scipy's qhull (``HalfspaceIntersection`` of the slabs, ``ConvexHull`` for the facets) with the
bias taken from central differences of the potential energy, not from ``gravity_torque``.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import ConvexHull, HalfspaceIntersection

from kinematics.fivebar import FiveBar
from kinematics.gravity import gravity_vector
from kinematics.inverse3 import Inverse3
from kinematics.serial_rrr import SerialRRR
from metrics.loading import DEFAULT_LOADING, Loading, LoadingError
from metrics.pose import analyse_pose
from metrics.quantities import MAP_QUANTITIES, QUANTITIES, available_quantities, closure, evaluate
from metrics.torque_box import sign_patterns
from metrics.workspace import compute_map
from resources import list_presets, load_preset

EPS = float(np.finfo(float).eps)
PHANTOM = SerialRRR()
FORCES = ("isotropic_force", "anisotropic_force", "bottleneck", "force_ellipsoid_min_radius")


def _phantom_points(k=300, seed=0):
    """Task points spread over the PHANToM's reach (some infeasible, which is part of the test)."""
    rng = np.random.default_rng(seed)
    return rng.uniform([-0.1, -0.25, -0.35], [0.38, 0.25, 0.35], size=(k, 3))


# -- the default is the unloaded graph, bit for bit ---------------------------------------------
@pytest.mark.parametrize("key", list_presets())
def test_default_loading_is_bit_identical(key):
    preset = load_preset(key)
    mech = preset.mechanism
    grid = preset.grid.with_resolution(9)
    names = available_quantities(mech)
    pts = grid.points(mech.task_names)
    plain = evaluate(mech, pts, names)
    for loading in (None, Loading(), DEFAULT_LOADING):
        ev = evaluate(mech, pts, names, loading=loading)
        assert ev.computed == plain.computed          # no torque_bias node without gravity
        for q in names:
            assert np.array_equal(ev.values[q], plain.values[q], equal_nan=True), (key, q)


def test_default_map_and_pose_are_bit_identical():
    preset = load_preset("phantom_premium_15")
    grid = preset.grid.with_resolution(21)
    a = compute_map(preset.mechanism, grid, ("isotropic_force", "anisotropic_force"))
    b = compute_map(preset.mechanism, grid, ("isotropic_force", "anisotropic_force"), loading=Loading())
    for q in a.values:
        assert np.array_equal(a.values[q], b.values[q], equal_nan=True)
    assert a.stats == b.stats and b.loading == DEFAULT_LOADING
    r1, r2 = analyse_pose(preset.mechanism, preset.pose), analyse_pose(preset.mechanism, preset.pose, loading=Loading())
    assert r1.isotropic_force == r2.isotropic_force and np.array_equal(r1.vertices, r2.vertices)
    assert np.array_equal(r2.torque_bias, np.zeros(3)) and np.array_equal(r2.force_centre, np.zeros(3))


# -- ratings -----------------------------------------------------------------------------------
def test_peak_rating_scales_the_forces_by_the_torque_ratio():
    """The PHANToM's peak/continuous ratio is 0.129 / 0.0286 on every motor, so every force scales by it.

    ``t_u / |J_u|`` and the vertex norms are homogeneous of degree 1 in t: scaling t by k
    changes each by the rounding of one more product, within 4 eps relative.
    """
    pts = _phantom_points()
    cont = evaluate(PHANTOM, pts, FORCES)
    peak = evaluate(PHANTOM, pts, FORCES, loading=Loading(rating="peak"))
    ratio = 0.129 / 0.0286
    assert np.array_equal(PHANTOM.peak_torque_limits(), np.asarray(PHANTOM.params.peak_motor_torques)
                          * np.asarray(PHANTOM.params.gear_ratios))
    ok = cont.feasible
    assert ok.sum() > 50
    for q in ("isotropic_force", "anisotropic_force", "force_ellipsoid_min_radius"):
        assert np.allclose(peak.values[q][ok], ratio * cont.values[q][ok], rtol=8 * EPS, atol=0), q
    assert np.array_equal(peak.values["bottleneck"], cont.values["bottleneck"])


def test_a_model_without_a_peak_rating_is_refused_by_name():
    for mech in (Inverse3(), FiveBar()):
        assert mech.peak_torque_limits() is None
        with pytest.raises(LoadingError, match=f"rating 'peak': {type(mech).__name__} has no peak") as err:
            evaluate(mech, np.zeros((1, mech.task_dim)), ["isotropic_force"], loading=Loading(rating="peak"))
        assert err.value.argument == "rating"


def test_gravity_without_a_mass_model_is_refused_by_name():
    with pytest.raises(LoadingError, match="gravity: Inverse3 has no mass model") as err:
        compute_map(Inverse3(), load_preset("inverse3_prototype").grid.with_resolution(5), ["isotropic_force"],
                    loading=Loading.mounted("upright"))
    assert err.value.argument == "gravity"
    with pytest.raises(LoadingError, match="device fivebar_singh has no mass model"):
        Loading.mounted("inverted").check(FiveBar(), device="device fivebar_singh")


def test_bad_loading_arguments_are_named():
    with pytest.raises(ValueError, match="rating must be one of continuous, peak, got 'max'"):
        Loading(rating="max")
    with pytest.raises(ValueError, match="mounting must be one of"):
        Loading(mounting="ceiling")
    with pytest.raises(ValueError, match="gravity must be 3 finite numbers"):
        Loading(gravity=(0.0, 0.0))


# -- gravity -------------------------------------------------------------------------------------
def test_gravity_adds_the_bias_node_only_where_the_set_moves():
    on = Loading.mounted("upright")
    assert closure(["condition_number"], PHANTOM, on) == closure(["condition_number"], PHANTOM)
    assert closure(["force_ellipsoid_min_radius"], PHANTOM, on) == ["jacobian", "force_ellipsoid_min_radius"]
    order = closure(["isotropic_force"], PHANTOM, on)
    assert order.index("torque_bias") < order.index("isotropic_force")
    assert "torque_bias" not in MAP_QUANTITIES and QUANTITIES["torque_bias"].unit == "N m"


def _numeric_bias(q, gravity, h=2e-5):
    """``dV/dq`` by central differences of the potential energy (not ``gravity_torque``)."""
    out = np.empty(3)
    for j in range(3):
        step = np.zeros(3)
        step[j] = h
        out[j] = (PHANTOM.potential_energy(q + step, gravity) - PHANTOM.potential_energy(q - step, gravity)) / (2 * h)
    return out


def _qhull_force_set(jac, t, bias):
    """Independent: the set ``{f : -t - b <= J^T f <= t - b}`` by qhull; its inscribed radius
    about 0 (smallest distance from 0 to a facet plane, 0 if 0 is outside) and farthest vertex."""
    lo, hi = -t - bias, t - bias
    # Halfspaces A f + c <= 0: J_u . f - hi_u <= 0 and -J_u . f + lo_u <= 0.
    halfspaces = np.vstack([np.hstack([jac.T, -hi[:, None]]), np.hstack([-jac.T, lo[:, None]])])
    centre = np.linalg.solve(jac.T, 0.5 * (lo + hi))
    verts = HalfspaceIntersection(halfspaces, centre).intersections
    hull = ConvexHull(verts)
    # equations: unit normal n and offset e with n . f + e <= 0 inside; distance from 0 = -e.
    radius = max(float(np.min(-hull.equations[:, -1])), 0.0)
    return radius, float(np.max(np.linalg.norm(verts, axis=1))), verts


@pytest.mark.parametrize("mounting", ["upright", "inverted", "x-up", "y-down"])
@pytest.mark.parametrize("rating", ["continuous", "peak"])
def test_gravity_shifted_forces_match_qhull(mounting, rating):
    loading = Loading.mounted(mounting, rating=rating)
    pts = _phantom_points(60, seed=1)
    ev = evaluate(PHANTOM, pts, ("isotropic_force", "anisotropic_force"), loading=loading)
    t = loading.torque_limits(PHANTOM)
    checked = 0
    for i, (q, ok) in enumerate(zip(ev.joints, ev.feasible)):
        if not ok:
            continue
        jac = PHANTOM.jacobian(q)
        bias = _numeric_bias(q, loading.gravity)
        radius, far, verts = _qhull_force_set(jac, t, bias)
        # Error budget: the numeric bias is within 1e-8 N m of dV/dq (test_gravity's central-
        # difference bound for h = 2e-5 is 4e-10 B, B < 10 J), which moves the set by at most
        # |J^-T| |db| <= sqrt(3) 1e-8 / sigma_min(J); qhull's vertices and planes are good to
        # a few hundred eps of the vertex scale (1e-10 leaves room).
        sigma_min = np.linalg.svd(jac, compute_uv=False)[-1]
        tol = np.sqrt(3) * 1e-8 / sigma_min + 1e-10 * far
        assert abs(ev.values["isotropic_force"][i] - radius) <= tol
        assert abs(ev.values["anisotropic_force"][i] - far) <= tol
        checked += 1
    assert checked > 15


def test_gravity_changes_the_forces_and_inverting_mirrors_them():
    """With symmetric limits, ``-b`` gives the mirror image ``-P`` of the set: same radius, same
    farthest vertex, bit for bit (``min(t - b, t + b)`` and the vertex set are symmetric in b)."""
    pts = _phantom_points(200, seed=2)
    plain = evaluate(PHANTOM, pts, FORCES)
    up = evaluate(PHANTOM, pts, FORCES, loading=Loading.mounted("upright"))
    down = evaluate(PHANTOM, pts, FORCES, loading=Loading.mounted("inverted"))
    ok = plain.feasible
    assert np.array_equal(up.values["isotropic_force"], down.values["isotropic_force"], equal_nan=True)
    assert np.allclose(up.values["anisotropic_force"][ok], down.values["anisotropic_force"][ok], rtol=8 * EPS)
    # Gravity only takes torque away from the ball about 0: the radius never grows ...
    assert np.all(up.values["isotropic_force"][ok] <= plain.values["isotropic_force"][ok])
    # ... and it does change it (the bias is reaching the force nodes).
    assert np.max(plain.values["isotropic_force"][ok] - up.values["isotropic_force"][ok]) > 1e-3
    # The force ellipsoid is the rating's, unbiased (the documented choice).
    assert np.array_equal(up.values["force_ellipsoid_min_radius"], plain.values["force_ellipsoid_min_radius"],
                          equal_nan=True)


def test_pose_and_map_agree_under_gravity():
    loading = Loading.mounted("x-down", rating="peak")
    preset = load_preset("phantom_premium_15")
    grid = preset.grid.with_resolution(15)
    wmap = compute_map(PHANTOM, grid, ("isotropic_force", "anisotropic_force", "bottleneck"), loading=loading)
    assert wmap.loading == loading
    pts = grid.points(PHANTOM.task_names).reshape(grid.resolution + (3,))
    feasible = np.argwhere(wmap.feasible)
    assert len(feasible) > 20
    for idx in map(tuple, feasible[::7]):
        r = analyse_pose(PHANTOM, pts[idx], loading=loading)
        assert r.loading == loading
        assert r.isotropic_force == wmap.values["isotropic_force"][idx]
        assert r.anisotropic_force == wmap.values["anisotropic_force"][idx]
        assert r.bottleneck == wmap.values["bottleneck"][idx]
        assert np.array_equal(r.torque_bias, PHANTOM.gravity_torque(r.joints, loading.gravity))
        # The vertices are the centre plus the signed half-edges (the reference forces).
        expected = r.force_centre + sign_patterns(3) @ r.reference_forces.T
        assert np.allclose(r.vertices, expected, rtol=0, atol=64 * EPS * np.abs(r.vertices).max())
        assert r.isotropic_force == max(float(np.min(r.facet_distances)), 0.0)


def test_phantom_home_pose_under_gravity_by_hand():
    """At q = 0 J is a signed permutation (each joint moves the tip along one axis: q1 along y
    by l1, q2 along z by l1, q3 along x by l2), so each slab is one axis: actuator u's facets
    are at ``(t_u - b_u) / l`` and ``-(t_u + b_u) / l``. The bias (-11.68, +1.29) mN m on q2,
    q3 (test_gravity's hand check) brings the q2 facet nearest: ``(t2 - |b2|) / l1``."""
    r = analyse_pose(PHANTOM, PHANTOM.home_pose(), loading=Loading.mounted("upright"))
    t = PHANTOM.torque_limits()
    b = PHANTOM.gravity_torque([0.0, 0.0, 0.0], gravity_vector("upright"))
    l1, l2 = PHANTOM.params.link1_length, PHANTOM.params.link2_length
    assert r.isotropic_force == pytest.approx((t[1] - abs(b[1])) / l1, rel=8 * EPS)
    assert r.joint_names[r.bottleneck] == "q2"
    # Centre: each axis moves by -b_u / l (f = J^-T (-b)).
    assert r.force_centre[2] == pytest.approx(-b[1] / l1, rel=8 * EPS)
    assert r.force_centre[0] == pytest.approx(-b[2] / l2, rel=8 * EPS)


def test_refined_minimum_under_gravity_bounds_the_grid():
    """``refine_global_minimum(..., loading=)``: certified, ``value - tol <= true min <= grid min``,
    and the value is attained (it is a loaded evaluation at some point)."""
    from metrics.refine import refine_global_minimum

    # Wall-mounted (x up): at the global minimum (arm stretched out) the base joint is the
    # bottleneck, and upright gravity puts no torque on it; with x up it does.
    loading = Loading.mounted("x-up")
    grid = load_preset("phantom_premium_15").grid
    r = refine_global_minimum(PHANTOM, grid, "isotropic_force", tol=1e-3, coarse_resolution=48, loading=loading)
    assert r.certified
    wmap = compute_map(PHANTOM, grid.with_resolution(121), ["isotropic_force"], keep=False, loading=loading)
    assert r.value - 1e-3 <= wmap.stats["isotropic_force"].min
    at = evaluate(PHANTOM, np.array([r.point]), ["isotropic_force"], loading=loading)
    assert at.values["isotropic_force"][0] == r.value
    unloaded = refine_global_minimum(PHANTOM, grid, "isotropic_force", tol=1e-3, coarse_resolution=48)
    assert unloaded.value != r.value
