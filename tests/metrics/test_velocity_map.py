"""The velocity polytope as a map quantity: ``isotropic_velocity`` and ``peak_velocity`` of every family.

Every preset's model is given motor speeds (random, one per gear ratio) and evaluated at random
feasible poses of its map box (a pen or platform also turned up to 0.3 rad). References,
independent of how the graph computes (``metrics.quantity_nodes.velocity_radius``: the zonotope
``J box`` for a square model without orientation freedoms, the joint-rate slabs of the force map
otherwise):

- a linear programme (scipy's HiGHS) over the joint rates themselves: the slice of the velocity
  set on the length rows is ``{v : J qdot = [v; 0], |qdot| <= qdot_max}`` (a redundantly actuated
  model: ``qdot = K [v; 0]``, its joints tied by the loop closures). Its support function
  ``h(d) = max d . v`` is at least the inscribed radius in every direction ``d`` and equals it
  along the nearest facet's normal; the peak velocity along axis i is ``max t`` with
  ``J qdot = t e_i``;
- pycapacity's ``velocity_polytope`` (its half-spaces ``H v <= d``) with the same ``J`` and speed
  limits for the square models without orientation freedoms;
- exact scaling: speeds times ``2^k`` scale every velocity by ``2^k``, a gear ratio times 2 halves
  its joint's speed limit.

Tolerances: HiGHS runs with feasibility tolerances of 1e-10 (absolute, on each equality and each
joint-rate bound), so its optimum may exceed the true one by at most ``1e-10`` times the equality
rows' weight ``(1 + sum |J|)`` per unit of speed, the ``LP`` term (with a factor 10 for HiGHS's
scaling).
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

from metrics.quantities import evaluate
from metrics.wrenches import force_rows
from resources import list_presets, load_preset

EPS = np.finfo(float).eps
LP_OPTIONS = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}
PRESETS = list_presets()


def _with_speeds(key: str, seed: int):
    """The preset's model with random motor speeds (rad/s or m/s at the motor, one per gear ratio)."""
    mech = load_preset(key).mechanism
    rng = np.random.default_rng(seed)
    count = len(mech.params.gear_ratios)
    speeds = rng.uniform(50.0, 500.0, count) if "m" not in mech.joint_units else rng.uniform(0.05, 0.5, count)
    return mech.replace(motor_speeds=tuple(speeds))


def _poses(mech, key: str, count: int, seed: int) -> np.ndarray:
    """``count`` random feasible task points from the preset's map box (angles turned +-0.3 rad)."""
    grid = load_preset(key).grid
    rng = np.random.default_rng(seed)
    n = 60 * count
    names = list(mech.task_names)
    x = np.zeros((n, mech.task_dim))
    for i, unit in enumerate(mech.task_units):
        if unit == "rad":
            x[:, i] = rng.uniform(-0.3, 0.3, n)
    for name, value in grid.fixed:
        x[:, names.index(name)] += value
    for axis, lo, hi in zip(grid.axes, grid.lower, grid.upper):
        x[:, names.index(axis)] = rng.uniform(lo, hi, n)
    q, ok = mech.inverse(x)
    ok &= mech.feasible(q, x) & np.all(np.isfinite(q), -1)
    with np.errstate(all="ignore"):
        jac = mech.jacobian(q[ok], x[ok])
        fmap = mech.force_map(q[ok], x[ok])
    keep = np.all(np.isfinite(jac), (-2, -1)) & np.all(np.isfinite(fmap), (-2, -1))
    x = x[ok][keep][:count]
    assert len(x) == count, f"{key}: only {len(x)} feasible poses"
    return x


def _slice_lp(mech, q, x, speeds, rows, objective_v):
    """``max objective . v`` over the velocity set's slice on ``rows`` (other task rates 0), with its tolerance.

    Variables ``(v, qdot)``. Non-redundant: ``J qdot - [v; 0] = 0`` (J from ``jacobian``).
    Redundant: ``K [v; 0] - qdot = 0`` (K the force map transposed).
    """
    m, n, d = mech.task_dim, mech.n_joints, len(rows)
    embed = np.zeros((m, d))
    embed[list(rows), np.arange(d)] = 1.0
    if mech.is_redundant:
        k = np.swapaxes(mech.force_map(q[None], x[None])[0], -1, -2)         # (n, m)
        a_eq = np.concatenate([k @ embed, -np.eye(n)], axis=1)
        b_eq = np.zeros(n)
    else:
        jac = mech.jacobian(q[None], x[None])[0]
        a_eq = np.concatenate([-embed, jac], axis=1)
        b_eq = np.zeros(m)
    cost = np.concatenate([-np.asarray(objective_v, float), np.zeros(n)])
    bounds = [(None, None)] * d + list(zip(-speeds, speeds))
    res = linprog(cost, A_eq=a_eq, b_eq=b_eq, bounds=bounds, method="highs", options=LP_OPTIONS)
    assert res.status == 0, res.message
    tol = 10 * 1e-10 * (1.0 + np.sum(np.abs(a_eq))) * (1.0 + np.max(speeds))
    return -res.fun, tol


@pytest.mark.parametrize("key", PRESETS)
def test_isotropic_and_peak_velocity_against_a_linear_programme(key):
    mech = _with_speeds(key, seed=len(key))
    x = _poses(mech, key, 6, seed=3)
    ev = evaluate(mech, x, ("isotropic_velocity", "peak_velocity"))
    assert np.all(ev.feasible)
    speeds = mech.joint_speed_limits()
    rows = force_rows(mech)
    rng = np.random.default_rng(5)
    for k in range(len(x)):
        q = ev.joints[k]
        r = float(ev.values["isotropic_velocity"][k])
        assert np.isfinite(r) and r > 0
        # Every direction's support is at least r ...
        for d in rng.standard_normal((8, len(rows))):
            d /= np.linalg.norm(d)
            h, tol = _slice_lp(mech, q, x[k], speeds, rows, d)
            assert r <= h + tol, f"{key} pose {k}: radius {r} > support {h} along {d}"
        # ... and along the nearest slab's normal (a row of K = dq/dx, restricted to the rows) it is r.
        kk = np.swapaxes(mech.force_map(q[None], x[k][None])[0], -1, -2)[:, list(rows)]
        u = int(np.argmin(speeds / np.linalg.norm(kk, axis=1)))
        h, tol = _slice_lp(mech, q, x[k], speeds, rows, kk[u] / np.linalg.norm(kk[u]))
        assert abs(h - r) <= tol + 64 * EPS * r, f"{key} pose {k}: support {h} at the nearest face, r {r}"
        # The peak velocity along each task axis: the fastest motion along it alone.
        peaks = ev.values["peak_velocity"][k]
        for i in range(mech.task_dim):
            t, tol = _slice_lp(mech, q, x[k], speeds, [i], [1.0])
            assert abs(t - peaks[i]) <= tol + 64 * EPS * peaks[i], f"{key} pose {k} axis {i}: {peaks[i]} vs LP {t}"


@pytest.mark.parametrize("key", [k for k in PRESETS if not load_preset(k).mechanism.has_orientation
                                 and not load_preset(k).mechanism.is_redundant])
def test_isotropic_velocity_against_pycapacity(key):
    robot = pytest.importorskip("pycapacity.robot")
    mech = _with_speeds(key, seed=2 * len(key))
    x = _poses(mech, key, 10, seed=4)
    ev = evaluate(mech, x, ("isotropic_velocity",))
    speeds = mech.joint_speed_limits()
    jac = mech.jacobian(ev.joints, x)
    for k in range(len(x)):
        poly = robot.velocity_polytope(jac[k], speeds, -speeds)
        h, d = np.asarray(poly.H), np.asarray(poly.d).ravel()
        ball = float(np.min(d / np.linalg.norm(h, axis=1)))
        scale = float(np.max(np.abs(jac[k]) @ speeds))
        # pycapacity's unit normals (an SVD) and ours (cofactors) each carry a backward error of a few
        # m eps |J| amplified by J's condition number, on offsets of size `scale` (test_velocity.py).
        m = mech.task_dim
        assert abs(ev.values["isotropic_velocity"][k] - ball) <= 8 * m * EPS * np.linalg.cond(jac[k]) * scale


@pytest.mark.parametrize("key", ["phantom_premium_15", "fivebar_singh", "stewart_platform", "twin_pantograph"])
def test_velocities_scale_with_the_speeds_and_inversely_with_the_gear_ratios(key):
    mech = _with_speeds(key, seed=7)
    x = _poses(mech, key, 5, seed=8)
    names = ("isotropic_velocity", "peak_velocity")
    base = evaluate(mech, x, names).values
    faster = mech.replace(motor_speeds=tuple(2.0**5 * np.asarray(mech.params.motor_speeds)))
    for name in names:
        np.testing.assert_array_equal(evaluate(faster, x, names).values[name], 2.0**5 * base[name])
    # Every gear ratio doubled: each joint's speed limit halves (its torque limit doubles).
    geared = mech.replace(gear_ratios=tuple(2.0 * np.asarray(mech.params.gear_ratios)))
    np.testing.assert_array_equal(geared.joint_speed_limits(), mech.joint_speed_limits() / 2.0)
    for name in names:
        np.testing.assert_array_equal(evaluate(geared, x, names).values[name], base[name] / 2.0)


def test_a_model_without_motor_speeds_refuses_the_velocity_with_the_reason():
    mech = load_preset("fivebar_singh").mechanism
    assert mech.joint_speed_limits() is None
    for name in ("isotropic_velocity", "peak_velocity"):
        with pytest.raises(ValueError, match=r"needs the motors' speeds: FiveBar has no motor speeds \(a preset's "
                                             r"\[motors\] max_speeds"):
            evaluate(mech, np.array([[0.0, 0.2]]), [name])
    with pytest.raises(ValueError, match=r"motor_speeds\[theta_2\] must be a positive"):
        mech.replace(motor_speeds=(10.0, -1.0))
    with pytest.raises(ValueError, match=r"motor_speeds\[theta_1\] / gear_ratios\[theta_1\] .* overflows"):
        mech.replace(motor_speeds=(1e308, 1.0), gear_ratios=(1e-10, 1.0))


def test_the_phantoms_preset_speeds_reach_its_model_and_the_stats():
    from metrics.quantities import summary_quantities
    preset = load_preset("phantom_premium_15")
    mech = preset.mechanism
    np.testing.assert_array_equal(mech.joint_speed_limits(),
                                  np.asarray(preset.motor_speeds) / np.asarray(mech.params.gear_ratios))
    assert "isotropic_velocity" in summary_quantities(mech)
    assert "isotropic_velocity" not in summary_quantities(load_preset("fivebar_singh").mechanism)
    # At q = 0 link 2 hangs straight down: a pure x motion is q3 alone (l2 q3dot), y is q1 (l1 q1dot),
    # z is q2 (l1 q2dot); the isotropic velocity is the smallest of the three (the set is a box).
    p = mech.params
    ev = evaluate(mech, np.array([preset.pose]), ("isotropic_velocity", "peak_velocity"))
    lim = mech.joint_speed_limits()
    expected = [p.link2_length * lim[2], p.link1_length * lim[0], p.link1_length * lim[1]]
    np.testing.assert_allclose(ev.values["peak_velocity"][0], expected, rtol=8 * EPS)
    assert ev.values["isotropic_velocity"][0] == pytest.approx(min(expected), rel=8 * EPS)


@pytest.mark.parametrize("key", ["phantom_premium_15", "fivebar_singh", "stewart_platform", "twin_pantograph",
                                 "inoue_platform"])
def test_the_pose_polytopes_vertices_span_the_velocity_set(key):
    """``analyse_pose_velocity``'s vertices against the linear programme: the support function of
    their hull equals the set's in random directions (so they are its vertices, all of them), each
    lies in the set, and the pose's isotropic and peak velocities are the map's at that point."""
    from metrics.pose_velocity import analyse_pose_velocity
    mech = _with_speeds(key, seed=9)
    x = _poses(mech, key, 3, seed=10)
    ev = evaluate(mech, x, ("isotropic_velocity", "peak_velocity"))
    speeds = mech.joint_speed_limits()
    rows = force_rows(mech)
    rng = np.random.default_rng(11)
    for k in range(len(x)):
        pose = analyse_pose_velocity(mech, x[k])
        assert pose.isotropic_velocity == ev.values["isotropic_velocity"][k]
        np.testing.assert_array_equal(pose.peak_velocity, ev.values["peak_velocity"][k])
        verts = pose.vertices
        assert verts.shape[1] == len(rows) and len(verts) > len(rows)
        # In the set: the joint rates K [v; 0] within their limits (to rounding).
        kk = np.swapaxes(mech.force_map(ev.joints[k][None], x[k][None])[0], -1, -2)[:, list(rows)]
        assert np.all(np.abs(verts @ kk.T) <= speeds * (1 + 1e-9))
        for d in rng.standard_normal((6, len(rows))):
            d /= np.linalg.norm(d)
            h, tol = _slice_lp(mech, ev.joints[k], x[k], speeds, rows, d)
            assert abs(np.max(verts @ d) - h) <= tol + 64 * EPS * h, f"{key} pose {k}: hull {np.max(verts @ d)} vs {h}"
