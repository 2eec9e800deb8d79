"""The Twin-Pantograph graph's compiled steps (``kernels.twin_nodes``, ``kernels.facets.acceleration_radius_points``)
against the numpy formulas they replace, kept here as the reference.

Bounds (``gamma_k = k eps / (1 - k eps)``, the error of a k-term dot product in any order, relative
to the sum of its terms' magnitudes):

- The scaled Gram matrix: ``M = diag(s) J`` is formed by the same products in both paths (the same
  bits), so its ``good`` flags are the same; an entry ``sum_u M_iu M_ju`` in two orders differs by at
  most ``2 gamma_n sum_u |M_iu M_ju|``, ``n = 6``.
- The acceleration radius ``min_k h_k / |v_k|``, ``v_k = (nu_k^T Lambda)[rows]``: each entry of
  ``v_k`` in two orders differs by at most ``2 gamma_m S_kj``, ``S_kj = sum_i |nu_ki Lambda_ij|``;
  ``|v_k|`` then by at most ``2 gamma_m |S_k|`` (triangle inequality) plus each path's own
  rounding of the norm (``d`` squares, ``d - 1`` sums, the root: ``(d + 2) eps |v_k|`` each), and
  ``h_k / |v_k|`` by one more rounding a path. Relative to the ratio, to first order:
  ``2 gamma_m |S_k| / |v_k| + 2 (d + 3) eps``, the minimum inherits the largest; doubled for the
  second-order terms.
- The residual test is exact where it decides: it leaves a residual within ``MARGIN`` of its bound
  to numpy (derived at ``twin_nodes.MARGIN``), so its decided points must agree with numpy's.
"""
from __future__ import annotations

import numpy as np
import pytest

from metrics import dynamics, wrench_facets
from metrics import quantity_nodes as nodes
from metrics.kernels import facets, twin_nodes
from metrics.linalg import SAFE_SCALE, outside_safe_scale
from metrics.loading import DEFAULT_LOADING
from metrics.quantities import QUANTITIES, closure, summary_quantities
from metrics.workspace import compute_map
from resources import load_preset

EPS = np.finfo(float).eps
SEED = 20261207


def gamma(k: int) -> float:
    return k * EPS / (1 - k * EPS)


@pytest.fixture(scope="module")
def twin():
    return load_preset("twin_pantograph").mechanism


def _graph(mech, count=300, names=("jacobian", "reference_forces", "wrench_facets", "mass_matrices"), seed=SEED):
    """The numpy graph's values at a random subset of the preset's feasible grid points."""
    grid = load_preset("twin_pantograph").grid
    pts = grid.points(mech.task_names).reshape(-1, 5)
    q, ok = mech.inverse(pts)
    ok[ok] = mech.feasible(q[ok], pts[ok])
    at = np.sort(np.random.default_rng(seed).choice(np.flatnonzero(ok), count, replace=False))
    v = {"pose": pts[at], "joints": q[at], "loading": DEFAULT_LOADING, "torques": DEFAULT_LOADING.torque_set(mech)}
    for name in closure(names, mech, DEFAULT_LOADING):
        v[name] = QUANTITIES[name].run(v, mech)
    return v


def _random_jacobians(rng, count):
    """5 x 6 matrices: random, near rank 4 (a row nearly a combination of two others), scaled 1e-300 .. 1e300,
    some with an inf or nan entry."""
    jac = rng.standard_normal((count, 5, 6))
    near = slice(0, count // 4)
    jac[near, 4] = jac[near, 0] - 2.0 * jac[near, 1] + 1e-13 * rng.standard_normal((count // 4, 6))
    jac *= 10.0 ** rng.uniform(-300, 300, (count, 1, 1))
    jac[-3, 1, 2], jac[-2, 0, 0], jac[-1, 4, 5] = np.inf, np.nan, -np.inf
    return jac


def _numpy_gram(jac, scale):
    """``quantity_nodes.scaled_condition``'s numpy Gram matrices and flags (before ``twin_nodes``)."""
    with np.errstate(invalid="ignore", over="ignore"):
        scaled = jac * scale[:, None]
    finite = np.all(np.isfinite(scaled), axis=(-2, -1))
    far = outside_safe_scale(np.max(np.abs(scaled), axis=(-2, -1)))
    safe = np.where((finite & ~far)[:, None, None], scaled, 0.0)
    return np.ascontiguousarray(safe @ np.swapaxes(safe, -1, -2)), finite & ~far, safe


@pytest.mark.parametrize("source", ["random", "twin"])
def test_scaled_gram_matches_numpy(twin, source):
    rng = np.random.default_rng(SEED)
    jac = _random_jacobians(rng, 400) if source == "random" else _graph(twin)["jacobian"]
    scale = np.array([1.0, 1.0, 1.0, 0.07, 0.07])
    ref, ref_good, safe = _numpy_gram(jac, scale)
    gram, good = np.empty_like(ref), np.empty(len(jac), bool)
    twin_nodes.scaled_gram(np.ascontiguousarray(jac), scale, *SAFE_SCALE, gram, good)
    np.testing.assert_array_equal(good, ref_good)
    terms = np.abs(safe) @ np.swapaxes(np.abs(safe), -1, -2)            # sum_u |M_iu M_ju|
    assert np.all(np.abs(gram - ref) <= 2 * gamma(6) * terms)
    assert np.all(gram[~good] == 0.0)
    np.testing.assert_array_equal(gram, np.swapaxes(gram, -1, -2))


def _numpy_lost(jac, gen, t):
    return np.isinf(nodes.unbounded_where_lost(np.zeros(len(jac)), jac, gen / t))


def test_lost_points_agree_with_numpy_where_they_decide(twin):
    rng = np.random.default_rng(SEED)
    count = 600
    k = rng.standard_normal((count, 6, 5)) * 10.0 ** rng.uniform(-150, 150, (count, 1, 1))
    t = np.array([0.3, 0.2, 0.2, 0.3, 0.2, 0.2])
    with np.errstate(all="ignore"):
        jac = np.linalg.pinv(k)                                         # a consistent pair: J A^T = I
        gen = np.swapaxes(k, -1, -2) * t
        # Residuals spread across the bound: J moved by a multiple of 64 n eps |J| (some far beyond,
        # some within the margin), a few pairs inconsistent outright, a few not finite.
        spread = 10.0 ** rng.uniform(-3, 3, (count, 1, 1)) * 64 * 6 * EPS
        jac = jac * (1.0 + spread * rng.standard_normal(jac.shape))
    jac[:20] = rng.standard_normal((20, 5, 6))
    jac[-2, 0, 0], gen[-1, 3, 3] = np.nan, np.inf
    lost, undecided = np.empty(count, bool), np.empty(count, bool)
    twin_nodes.lost_points(np.ascontiguousarray(jac), np.ascontiguousarray(gen), t, lost, undecided)
    ref = _numpy_lost(jac, gen, t)
    decided = ~undecided
    np.testing.assert_array_equal(lost[decided], ref[decided])
    assert undecided[-2] and undecided[-1]
    assert lost[decided].any() and not lost[decided].all()              # both answers were exercised


def test_lost_poses_node_matches_numpy(twin):
    v = _graph(twin)
    t = nodes.rated_limits(v, twin)
    np.testing.assert_array_equal(nodes.lost_poses(v, twin), _numpy_lost(v["jacobian"], v["reference_forces"], t))


def _numpy_acceleration(packed, lam, rows):
    """``acceleration_slabs`` with gravity off, in numpy: ``facets.acceleration_radius_points``' reference."""
    with np.errstate(invalid="ignore"):
        normals = dynamics.acceleration_facets(packed[..., :-1], lam)
        return wrench_facets.slice_inscribed_radius(normals, packed[..., -1], rows=rows)


def _acceleration_bound(packed, lam, rows, ref):
    """The module doc's bound on ``|r - r_numpy|`` per point."""
    nu = packed[..., :-1]
    with np.errstate(all="ignore"):
        terms = (np.abs(nu) @ np.abs(lam))[..., rows]                  # S_kj
        v = (nu @ lam)[..., rows]
        rel = 2 * gamma(nu.shape[-1]) * np.linalg.norm(terms, axis=-1) / np.linalg.norm(v, axis=-1)
    d = len(rows)
    return 2 * (np.max(rel, axis=-1) + 2 * (d + 3) * EPS) * np.abs(ref)


def test_acceleration_radius_matches_numpy_on_the_preset(twin):
    v = _graph(twin)
    rows = [0, 1, 2]
    lam = v["mass_matrices"][:, 0]
    ref = _numpy_acceleration(v["wrench_facets"], lam, rows)
    out = nodes.acceleration_slabs(v, twin, v["wrench_facets"])
    assert np.all(np.abs(out - ref) <= _acceleration_bound(v["wrench_facets"], lam, rows, ref))


def test_acceleration_radius_random_extreme_and_singular_inputs():
    rng = np.random.default_rng(SEED)
    count = 400
    gen = rng.standard_normal((count, 5, 6)) * 10.0 ** rng.uniform(-100, 100, (count, 1, 1))
    packed = wrench_facets.packed_facets(gen)
    root = rng.standard_normal((count, 5, 5))
    lam = root @ np.swapaxes(root, -1, -2) * 10.0 ** rng.uniform(-150, 150, (count, 1, 1))
    lam[:10, 1, 1] = lam[:10, 0, 0] * 1e-17                             # nearly singular force block
    lam[-4] = np.inf                                                    # a singular pose's marked mass
    lam[-3, 2, 2] = np.nan
    packed[-2] = np.nan                                                 # generators not finite
    packed[-1, :, :-1] = 0.0                                            # no slab: the degenerate set
    for rows in ([0, 1, 2], [3, 4], [1]):
        ref = _numpy_acceleration(packed, lam, rows)
        out, redo = np.empty(count), np.empty(count, bool)
        facets.acceleration_radius_points(packed[..., :-1], np.ascontiguousarray(packed[..., -1]), lam,
                                          np.array(rows, np.int64), out, redo)
        assert redo[-4] and redo[-3] and redo[-2] and redo[-1]
        kept = ~redo
        assert np.all(np.abs(out[kept] - ref[kept]) <= _acceleration_bound(packed, lam, rows, ref)[kept])


def test_stats_are_the_same_with_threads_on_and_off(twin):
    grid = load_preset("twin_pantograph").grid.with_resolution(41)
    names = summary_quantities(twin)
    one = compute_map(twin, grid, names, keep=False, threads=False)
    many = compute_map(twin, grid, names, keep=False, threads=True)
    for name in names:
        assert one.stats[name] == many.stats[name], name


def test_load_pieces_builds_the_versions_a_map_uses(twin):
    """``runtime.load_pieces`` loads these steps in the array layouts a map passes them: its chunks build nothing."""
    from metrics import runtime

    def builds():
        return tuple(len(f.signatures) for f in (twin_nodes.scaled_gram, twin_nodes.lost_points,
                                                  facets.acceleration_radius_points))

    runtime.load_pieces()
    before = builds()
    compute_map(twin, load_preset("twin_pantograph").grid.with_resolution(9), summary_quantities(twin), keep=False)
    assert builds() == before and min(before) >= 1
