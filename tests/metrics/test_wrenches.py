"""metrics.wrenches (and wrench_facets): forces at zero moment and moments at zero force, checked by linear programmes.

Reference: the support function of a slice, ``h(d) = max d . G_R s`` subject to
``G_O s = 0``, ``|s| <= 1`` (scipy.optimize.linprog, HiGHS). For the slice ``S`` on rows
``R``: a ball of radius ``r`` about 0 lies in ``S`` iff ``h(d) >= r`` for every unit ``d``,
with equality along the nearest facet's normal; the largest norm is ``max_d h(d)``,
attained along the farthest vertex. HiGHS solves to a feasibility tolerance of 1e-7
(relative to entries of order 1 here), so LP values are compared with rtol 1e-6.
"""
from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.optimize import linprog

from kinematics import FiveBar
from metrics import wrench_facets, wrench_slices, wrenches
from metrics.quantities import check_quantities, evaluate, summary_quantities
from resources import load_preset

STEWART = load_preset("stewart_platform").mechanism
TWIN = load_preset("twin_pantograph").mechanism                         # 5 x 6, redundant
TWIN_6 = TWIN.replace(redundant_waist="passive", roll_actuator="active")   # 6 x 6
TWIN_67 = TWIN.replace(roll_actuator="active")                             # 6 x 7, redundant
LP_RTOL = 1e-6


def _poses(mech, count, seed):
    """Feasible poses near the preset's pose (m, rad)."""
    rng = np.random.default_rng(seed)
    home = np.array(load_preset("stewart_platform").pose if mech is STEWART else mech.home_pose())
    spread = np.r_[np.full(3, 0.02), np.full(mech.task_dim - 3, 0.15)]
    x = home + rng.uniform(-1, 1, (4 * count, mech.task_dim)) * spread
    q, ok = mech.inverse(x)
    ok[ok] = mech.feasible(q[ok], x[ok])
    assert ok.sum() >= count
    return x[ok][:count], q[ok][:count]


def _generators(mech, count=3, seed=0):
    x, q = _poses(mech, count, seed)
    return mech.force_map(q, x) * mech.torque_limits(), x, q


def _support(g, rows, d):
    """LP: max d . G_R s subject to G_O s = 0, |s_u| <= 1."""
    others = [i for i in range(g.shape[0]) if i not in rows]
    res = linprog(-(d @ g[list(rows)]), A_eq=g[others], b_eq=np.zeros(len(others)),
                  bounds=[(-1.0, 1.0)] * g.shape[1], method="highs")
    assert res.status == 0
    return -res.fun


MECHS = [STEWART, TWIN, TWIN_6, TWIN_67]
IDS = ["stewart-6x6", "twin-5x6", "twin-6x6", "twin-6x7"]


@pytest.mark.parametrize("mech", MECHS, ids=IDS)
@pytest.mark.parametrize("part", ["force", "moment"])
def test_inscribed_radius_and_largest_norm_equal_linear_programmes(mech, part):
    rows = wrenches.force_rows(mech) if part == "force" else wrenches.moment_rows(mech)
    gens, _, _ = _generators(mech)
    nu, h = wrench_facets.facets(gens)
    radius = wrench_facets.slice_inscribed_radius(nu, h, rows=rows)
    largest = wrench_slices.slice_max_norm(gens, rows=rows)
    rng = np.random.default_rng(5)
    for g, r, big, normals, offsets in zip(gens, radius, largest, nu, h):
        assert 0 < r < big
        dirs = rng.normal(size=(60, len(rows)))
        for d in dirs / np.linalg.norm(dirs, axis=1, keepdims=True):
            value = _support(g, rows, d)
            assert value >= r * (1 - LP_RTOL)
            assert value <= big * (1 + LP_RTOL)
        # Equality along the nearest slab's normal and along the farthest vertex.
        part_nu = normals[:, list(rows)]
        k = np.argmin(offsets / np.linalg.norm(part_nu, axis=1))
        d = part_nu[k] / np.linalg.norm(part_nu[k])
        assert _support(g, rows, d) == pytest.approx(r, rel=LP_RTOL)
        vertices = wrench_slices.slice_vertices(g, rows=rows)
        far = vertices[np.argmax(np.linalg.norm(vertices, axis=1))]
        assert np.linalg.norm(far) == pytest.approx(big, rel=1e-12)
        assert _support(g, rows, far / np.linalg.norm(far)) == pytest.approx(big, rel=LP_RTOL)
        # Every vertex lies in the slice (an LP finds its torques) ...
        others = [i for i in range(g.shape[0]) if i not in rows]
        for v in vertices:
            res = linprog(np.zeros(g.shape[1]), A_eq=np.vstack([g[list(rows)], g[others]]),
                          b_eq=np.r_[v * (1 - LP_RTOL), np.zeros(len(others))],
                          bounds=[(-1.0, 1.0)] * g.shape[1], method="highs")
            assert res.status == 0
        # ... and the slice is their hull: its support values are the vertices' largest projection.
        for d in dirs[:20] / np.linalg.norm(dirs[:20], axis=1, keepdims=True):
            assert np.max(vertices @ d) == pytest.approx(_support(g, rows, d), rel=LP_RTOL)


@pytest.mark.parametrize("mech", [STEWART, TWIN_6], ids=["stewart", "twin-6x6"])
def test_square_formula_min_t_over_column_part_equals_the_facets(mech):
    """For square J (tau = J^T w) the slice on rows R is {y : |J[R, u] . y| <= t_u}."""
    gens, x, q = _generators(mech, count=5, seed=2)
    jac = mech.jacobian(q, x)
    t = mech.torque_limits()
    nu, h = wrench_facets.facets(gens)
    for rows in (wrenches.force_rows(mech), wrenches.moment_rows(mech)):
        square = np.min(wrench_facets.slice_facet_distances(jac, torque_limits=t, rows=rows), axis=-1)
        # Both equal in exact arithmetic; J = K^-1 of a K with condition < 1e3 here: 1e-9.
        np.testing.assert_allclose(square, wrench_facets.slice_inscribed_radius(nu, h, rows=rows), rtol=1e-9)


@pytest.mark.parametrize("mech", MECHS, ids=IDS)
def test_quantity_graph_reports_the_slices_in_their_own_units(mech):
    gens, x, _ = _generators(mech, count=4, seed=3)
    names = summary_quantities(mech) + ("force_ellipsoid_min_radius",)
    ev = evaluate(mech, x, names)
    assert ev.feasible.all()
    v = ev.values
    nu, h = wrench_facets.facets(gens)
    fr, mr = wrenches.force_rows(mech), wrenches.moment_rows(mech)
    np.testing.assert_allclose(v["isotropic_force"], wrench_facets.slice_inscribed_radius(nu, h, rows=fr), rtol=1e-9)
    np.testing.assert_allclose(v["isotropic_moment"], wrench_facets.slice_inscribed_radius(nu, h, rows=mr), rtol=1e-9)
    np.testing.assert_allclose(v["anisotropic_force"], wrench_slices.slice_max_norm(gens, rows=fr), rtol=1e-12)
    np.testing.assert_allclose(v["anisotropic_moment"], wrench_slices.slice_max_norm(gens, rows=mr), rtol=1e-12)
    assert np.all(v["anisotropic_force"] > v["isotropic_force"])
    assert np.all(v["anisotropic_moment"] > v["isotropic_moment"])
    # The zero-moment force ellipsoid lies in the force slice (least-norm torques within the box).
    assert np.all(v["force_ellipsoid_min_radius"] <= v["isotropic_force"] * (1 + 1e-9))


def test_stewart_home_isotropic_force_is_the_zero_moment_ball_not_the_mixed_one():
    """Regression: with six 10 N legs the mixed (N, N m) ball had radius 0.35; the force ball is 7.46 N."""
    x = np.array(load_preset("stewart_platform").pose)
    ev = evaluate(STEWART, x[None], ("isotropic_force", "isotropic_moment"))
    q, _ = STEWART.inverse(x[None])
    g = (STEWART.force_map(q, x[None]) * STEWART.torque_limits())[0]
    rng = np.random.default_rng(0)
    dirs = rng.normal(size=(400, 3))
    lp = min(_support(g, (0, 1, 2), d / np.linalg.norm(d)) for d in dirs)
    # The minimum over 400 directions is an upper bound, close to the radius.
    assert ev.values["isotropic_force"][0] <= lp * (1 + LP_RTOL)
    assert ev.values["isotropic_force"][0] > 0.9 * lp > 5.0


def test_scale_of_the_generators_carries_through_exactly():
    gens, _, _ = _generators(TWIN, count=3, seed=4)
    fr, mr = wrenches.force_rows(TWIN), wrenches.moment_rows(TWIN)
    nu, h = wrench_facets.facets(gens)
    base = [wrench_facets.slice_inscribed_radius(nu, h, rows=fr), wrench_slices.slice_max_norm(gens, rows=mr)]
    for c in (1e-300, 1e-150, 1e150, 1e300):
        scaled = gens * c
        nu_c, h_c = wrench_facets.facets(scaled)
        np.testing.assert_allclose(wrench_facets.slice_inscribed_radius(nu_c, h_c, rows=fr), base[0] * c, rtol=1e-12)
        np.testing.assert_allclose(wrench_slices.slice_max_norm(scaled, rows=mr), base[1] * c, rtol=1e-12)


def test_bad_generators_give_nan_without_warnings():
    gens, _, _ = _generators(TWIN, count=3, seed=6)
    gens[0, 2, 3] = np.nan
    gens[1, 0, 0] = np.inf
    gens[2] = 0.0
    fr = wrenches.force_rows(TWIN)
    nu, h = wrench_facets.facets(gens)
    assert np.all(np.isnan(wrench_facets.slice_inscribed_radius(nu, h, rows=fr)))
    assert np.all(np.isnan(wrench_slices.slice_max_norm(gens, rows=fr)))
    assert wrench_slices.slice_vertices(gens[0], rows=fr).shape == (0, 3)


def test_square_j_at_a_direct_singularity_holds_no_force_along_the_free_direction():
    """J = K^-1 infinite (K singular): as ``isotropy.facet_distances``, the radius is 0."""
    jac = np.full((1, 6, 6), np.inf)
    out = wrench_facets.slice_facet_distances(jac, torque_limits=np.ones(6), rows=(0, 1, 2))
    assert np.all(out == 0.0)


def test_slice_polytope_faces_are_planar_and_close_the_surface():
    gens, _, _ = _generators(TWIN, count=2, seed=7)
    for g in gens:
        v = wrench_slices.slice_vertices(g, rows=wrenches.force_rows(TWIN))
        faces = wrench_slices.hull_faces(v)
        edges = {tuple(sorted((f[i], f[(i + 1) % len(f)]))) for f in faces for i in range(len(f))}
        assert len(v) - len(edges) + len(faces) == 2                   # Euler: a closed convex surface
        used = sorted({i for f in faces for i in f})
        assert used == list(range(len(v)))                             # every vertex is on the hull
        for f in faces:
            pts = v[list(f)]
            normal = np.cross(pts[1] - pts[0], pts[2] - pts[0])
            normal /= np.linalg.norm(normal)
            assert np.all(np.abs((pts - pts[0]) @ normal) <= 1e-9 * np.max(np.abs(v)))


def test_condition_number_is_scaled_by_the_named_length_and_frame_free():
    gens, x, q = _generators(STEWART, count=3, seed=8)
    jac = STEWART.jacobian(q, x)
    L = wrenches.characteristic_length(STEWART)
    assert L == STEWART.params.platform_radius
    assert wrenches.condition_number_scaling(STEWART) == {"length_m": L}
    scale = wrenches.task_row_scale(STEWART)
    np.testing.assert_array_equal(scale, [1, 1, 1, L, L, L])
    kappa = wrenches.scaled_condition_number(jac, row_scale=scale)
    sv = np.linalg.svd(jac * scale[:, None], compute_uv=False)
    np.testing.assert_allclose(kappa, sv[:, 0] / sv[:, -1], rtol=1e-12)
    # One length for all rotational rows: rotating the base frame leaves it unchanged ...
    c, s = np.cos(0.7), np.sin(0.7)
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    block = np.kron(np.eye(2), rot)
    np.testing.assert_allclose(wrenches.scaled_condition_number(block @ jac, row_scale=scale), kappa, rtol=1e-9)
    # ... and so does the unit of length (J in mm with L in mm).
    # Task lengths and legs in mm: rows (mm, rad) per leg mm, L in mm.
    jac_mm = jac * np.array([1e3, 1e3, 1e3, 1, 1, 1])[:, None] / 1e3
    scale_mm = np.array([1, 1, 1, 1e3 * L, 1e3 * L, 1e3 * L])
    np.testing.assert_allclose(wrenches.scaled_condition_number(jac_mm, row_scale=scale_mm), kappa, rtol=1e-9)
    assert wrenches.condition_number_scaling(FiveBar()) is None


def test_moment_quantities_exist_only_for_devices_with_orientation_freedoms():
    assert STEWART.has_orientation and TWIN.has_orientation
    assert not FiveBar().has_orientation
    with pytest.raises(ValueError, match="unknown quantity 'isotropic_moment'"):
        check_quantities(FiveBar(), ("isotropic_moment",))
    assert wrenches.force_rows(TWIN) == (0, 1, 2) and wrenches.moment_rows(TWIN) == (3, 4)


def test_section_vertices_brute_force_small_case():
    """A random 5 x 6 set: the largest norm equals brute force over every vertex of Q."""
    rng = np.random.default_rng(11)
    g = rng.normal(size=(5, 6))
    rows, others = [0, 1, 2], [3, 4]
    best = 0.0
    # Vertices of Q: 4 coordinates at +-1, 2 solved exactly (numpy.linalg.solve).
    for free in itertools.combinations(range(6), 2):
        fixed = [u for u in range(6) if u not in free]
        for signs in itertools.product((1.0, -1.0), repeat=4):
            s = np.zeros(6)
            s[fixed] = signs
            s[list(free)] = np.linalg.solve(g[others][:, list(free)], -g[others][:, fixed] @ np.array(signs))
            if np.all(np.abs(s) <= 1 + 1e-12):
                best = max(best, float(np.linalg.norm(g[rows] @ s)))
    assert wrench_slices.slice_max_norm(g, rows=rows) == pytest.approx(best, rel=1e-12)


def test_bottleneck_of_a_wrench_device_is_the_nearest_facet_of_the_zero_moment_force_set():
    """Stewart: the leg whose facet of {f : (f, 0) in W} touches the isotropic ball (LP-checked radius
    elsewhere); the mixed-space facets of J named the wrong leg. Twin-Pantograph: shared."""
    mech = STEWART
    x, _ = _poses(mech, 200, 11)
    ev = evaluate(mech, x, ("bottleneck", "isotropic_force", "jacobian"))
    f = ev.feasible
    dist = wrench_facets.slice_facet_distances(ev.values["jacobian"][f], torque_limits=mech.torque_limits(),
                                          rows=wrenches.force_rows(mech))
    order = np.sort(dist, axis=-1)
    decided = order[:, 1] > order[:, 0] * (1 + 1e-9)       # no near-tie: argmin decided in exact arithmetic
    assert decided.sum() > 50
    np.testing.assert_array_equal(ev.values["bottleneck"][f][decided], np.argmin(dist[decided], axis=-1))
    np.testing.assert_allclose(order[:, 0], ev.values["isotropic_force"][f], rtol=1e-12)
    ev = evaluate(TWIN, _poses(TWIN, 20, 3)[0], ("bottleneck",))
    assert np.all(ev.values["bottleneck"][ev.feasible] == -3)
