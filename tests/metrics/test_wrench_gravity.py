"""Gravity on a device with orientation freedoms: the biased wrench set against linear programmes.

With gravity the joints spend ``b`` holding the links, so the wrenches the hand can be given
are ``{w = A tau' : -t - b <= tau' <= t - b}`` (``A`` the force map; square ``A = J^-T``, the
Stewart platform and the Inoue platform; redundant, the Twin-Pantograph's 6 actuators on 5 task
coordinates). The isotropic force is the radius of the largest ball of forces about 0 held at
zero moment. Independent reference (scipy.optimize.linprog, HiGHS): the slice's support
function ``h(d) = max {d . w[forces] : w in the set, w[moments] = 0}`` in direction ``d``. A ball
of radius ``r`` about 0 lies in the slice iff ``r <= h(d)`` for every unit ``d``, with equality
in the direction of the nearest face. So at random poses:

1. ``r <= h(d)`` for 40 random unit directions;
2. ``r = h(d*)`` in the direction ``d*`` of the face the model's slabs say is nearest (the LP
   evaluates the set there, independently of the slabs);
3. likewise for the isotropic moment at zero force;
4. the largest force held at zero moment (``anisotropic_force``) is ``max_d h(d)``: no random
   direction's support exceeds it, and the LP reaches it along the vertex it reports;
5. the torque bias the graph uses (``J^T grad_x V`` from the pose) equals
   ``Mechanism.gravity_torque`` (through the forward kinematics and the centres' Jacobian).

Tolerances: HiGHS is run with feasibility tolerances of 1e-10 (absolute, on the torque bounds
and equality rows, which are of order ``t`` and ``|A| t``); an objective ``d . w`` then moves by at
most ``1e-10 (|A^T d|_1 + 1)``: the ``LP_TOL`` term below, with a factor 10 for the scaling HiGHS applies.
Headless: numpy, scipy and the compute layer only. Fixed seeds.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

from metrics import wrench_facets, wrenches
from metrics.loading import Loading
from metrics.quantities import evaluate
from resources import load_preset
from tests.kinematics.test_mass_model import _poses

PRESETS = ["stewart_platform", "inoue_platform", "twin_pantograph"]
LP_OPTIONS = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}
EPS = np.finfo(float).eps
#: Sideways as well as down, so no task axis is spared the bias.
GRAVITY = (3.0, -4.0, -8.5)


def _support(a: np.ndarray, lo: np.ndarray, hi: np.ndarray, rows, others, d: np.ndarray) -> tuple[float, float]:
    """``max d . (A tau)[rows]`` over ``lo <= tau <= hi`` with ``(A tau)[others] = 0``, and its tolerance."""
    objective = -(a[rows].T @ d)
    res = linprog(objective, A_eq=a[others], b_eq=np.zeros(len(others)), bounds=list(zip(lo, hi)),
                  method="highs", options=LP_OPTIONS)
    assert res.status == 0, res.message
    tol = 10 * 1e-10 * (np.sum(np.abs(objective)) + np.sum(np.abs(a[others])) + 1.0)
    return -res.fun, tol


def _setting(key: str, count: int):
    preset = load_preset(key)
    mech = preset.mechanism
    q, x = _poses(key, count, seed=23)
    loading = Loading(gravity=GRAVITY)
    loading.check(mech)
    names = ["isotropic_force", "isotropic_moment", "anisotropic_force", "torque_bias", "wrench_facets"]
    ev = evaluate(mech, x, names, loading=loading)
    assert np.all(ev.feasible)
    return mech, q, x, loading, ev


@pytest.mark.parametrize("key", PRESETS)
def test_the_biased_isotropic_force_and_moment_are_the_linear_programmes_inscribed_balls(key):
    mech, q, x, loading, ev = _setting(key, 6)
    t = loading.torque_limits(mech)
    b = ev.values["torque_bias"]
    assert np.any(ev.values["isotropic_force"] > 0), f"{key}: no pose holds its links: nothing tested"
    rng = np.random.default_rng(3)
    for rows, name in ((list(wrenches.force_rows(mech)), "isotropic_force"),
                       (list(wrenches.moment_rows(mech)), "isotropic_moment")):
        others = [i for i in range(mech.task_dim) if i not in rows]
        for k in range(len(q)):
            a = mech.force_map(q[k], x[k])
            lo, hi = -t - b[k], t - b[k]
            r = float(ev.values[name][k])
            if r == 0.0:
                # The joints cannot hold the links here (|b_u| > t_u for some u, or the slice
                # misses the origin): then no torques within the limits give w = 0 at all.
                res = linprog(np.zeros(len(t)), A_eq=a, b_eq=np.zeros(mech.task_dim), bounds=list(zip(lo, hi)),
                              method="highs", options=LP_OPTIONS)
                assert res.status == 2, f"{key} {name} pose {k}: radius 0 but the origin is in the set"
                continue
            for _ in range(40):
                d = rng.normal(size=len(rows))
                d /= np.linalg.norm(d)
                h, tol = _support(a, lo, hi, rows, others, d)
                assert r <= h + tol, f"{key} {name} pose {k}: radius {r} > support {h} along {d}"
            # The nearest face, from the model's slabs and their shifts nu . c, c = -A b.
            packed = ev.values["wrench_facets"][k]
            nu, off = packed[:, :-1], packed[:, -1]
            shift = wrench_facets.slab_shifts(nu, -a @ b[k])
            norms = np.linalg.norm(nu[:, rows], axis=-1)
            with np.errstate(divide="ignore"):
                ratio = np.where(norms > 0, (off - np.abs(shift)) / norms, np.inf)
            near = int(np.argmin(ratio))
            d_star = -np.sign(shift[near] or 1.0) * nu[near, rows] / norms[near]
            h, tol = _support(a, lo, hi, rows, others, d_star)
            assert abs(h - r) <= tol + 64 * EPS * r, f"{key} {name} pose {k}: support {h} at the nearest face, r {r}"


@pytest.mark.parametrize("key", PRESETS)
def test_the_biased_largest_force_at_zero_moment_is_the_supports_maximum(key):
    mech, q, x, loading, ev = _setting(key, 4)
    t = loading.torque_limits(mech)
    b = ev.values["torque_bias"]
    rows = list(wrenches.force_rows(mech))
    others = [i for i in range(mech.task_dim) if i not in rows]
    rng = np.random.default_rng(8)
    for k in range(len(q)):
        a = mech.force_map(q[k], x[k])
        lo, hi = -t - b[k], t - b[k]
        big = float(ev.values["anisotropic_force"][k])
        best = 0.0
        for _ in range(60):
            d = rng.normal(size=3)
            d /= np.linalg.norm(d)
            h, tol = _support(a, lo, hi, rows, others, d)
            assert h <= big + tol, f"{key} pose {k}: support {h} beyond the largest norm {big}"
            best = max(best, h)
        # 60 directions come within a few per cent of the largest vertex norm, never beyond it.
        assert best >= 0.7 * big


@pytest.mark.parametrize("key", PRESETS)
def test_the_graphs_torque_bias_is_the_mechanisms_gravity_torque(key):
    mech, q, x, loading, ev = _setting(key, 6)
    ref = mech.gravity_torque(q, loading.gravity)
    got = ev.values["torque_bias"]
    # Two orders of the same products (J^T grad V against (dc/dx J)^T g): rounding of a few
    # hundred operations on values of size |J| |grad V|.
    scale = np.max(np.abs(ref), axis=-1, keepdims=True)
    assert np.all(np.abs(got - ref) <= 1e3 * EPS * scale)


@pytest.mark.parametrize("key", ["stewart_platform", "twin_pantograph"])
def test_the_pose_reports_the_biased_slice(key):
    """``analyse_pose`` with gravity: the force slice's vertices are those of the shifted set (each
    one's support along itself reached by the LP, none beyond the largest norm), its largest
    norm is ``anisotropic_force`` and a square device's nearest facet is ``isotropic_force``."""
    from metrics.pose import analyse_pose

    mech, q, x, loading, ev = _setting(key, 3)
    t = loading.torque_limits(mech)
    rows = list(wrenches.force_rows(mech))
    others = [i for i in range(mech.task_dim) if i not in rows]
    for k in range(len(q)):
        report = analyse_pose(mech, x[k], loading=loading)
        verts = report.vertices
        assert len(verts) >= 4
        norms = np.linalg.norm(verts, axis=-1)
        assert np.isclose(norms.max(), report.anisotropic_force, rtol=1e-12, atol=0)
        if not mech.is_redundant:
            assert np.isclose(report.facet_distances.min(), report.isotropic_force, rtol=1e-12, atol=0)
        a = mech.force_map(q[k], x[k])
        b = report.torque_bias
        for v in verts[:8]:
            d = v / np.linalg.norm(v)
            h, tol = _support(a, -t - b, t - b, rows, others, d)
            # A vertex lies in the set (support >= its projection) and no farther than the support.
            assert d @ v <= h + tol + 64 * EPS * np.linalg.norm(v)


def test_a_slice_with_parallel_slabs_keeps_its_largest_force_between_the_lps_bounds():
    """The Twin-Pantograph upright at its own map's grid point (110, 0, 60) mm: two of its slabs are
    antiparallel and a zero entry of a third comes out 1e-18, so one subset's determinant is rounding
    noise; the "vertex" it gave, 1.2e18 away, made the largest force 2^61 N (its neighbours: 6 N).
    Independent bounds from the LPs: at least the support in 60 random directions, at most the
    corner of the box the six axis supports span."""
    preset = load_preset("twin_pantograph")
    mech, grid = preset.mechanism, preset.grid
    pts = grid.points(mech.task_names).reshape(-1, mech.task_dim)
    x = pts[np.argmin(np.sum((pts - [0.11, 0.0, 0.06, 0.0, 0.0]) ** 2, axis=-1))][None]
    loading = Loading(gravity=(0.0, 0.0, -9.80665), mounting="upright")
    ev = evaluate(mech, x, ["anisotropic_force", "torque_bias"], loading=loading)
    q = ev.joints[0]
    t = loading.torque_limits(mech)
    lo, hi = -t - ev.values["torque_bias"][0], t - ev.values["torque_bias"][0]
    a = mech.force_map(q, x[0])
    rows = list(wrenches.force_rows(mech))
    others = [i for i in range(mech.task_dim) if i not in rows]
    big = float(ev.values["anisotropic_force"][0])
    corner, slack = 0.0, 0.0
    for axis in np.eye(3):
        ends = [_support(a, lo, hi, rows, others, s * axis) for s in (1.0, -1.0)]
        corner += max(h for h, _ in ends) ** 2
        slack += max(tol for _, tol in ends)
    assert big <= np.sqrt(corner) + slack, (big, np.sqrt(corner))
    rng = np.random.default_rng(9)
    for _ in range(60):
        d = rng.normal(size=3)
        h, tol = _support(a, lo, hi, rows, others, d / np.linalg.norm(d))
        assert h <= big + tol
