"""Asymmetric torque limits and a torque bias: the shifted force parallelepiped and zonotope.

The usable torque range is ``lo = t_min - b <= tau <= hi = t_max - b`` (pycapacity's
convention: the bias is torque the joints already spend). References:

- the largest ball about the origin inside ``{f : lo <= J^T f <= hi}`` as a linear programme
  (scipy.optimize.linprog, HiGHS): maximise ``r`` subject to ``r |a_i| <= b_i`` for the rows
  ``a_i . f <= b_i`` of the H-representation, with the ball's centre fixed at 0; infeasible
  (no ``r >= 0``) where the origin is outside the set. HiGHS solves to a feasibility
  tolerance of 1e-7 on entries of order 1, so LP values are compared with ``LP_RTOL = 1e-6``;
- the farthest vertex by enumeration: every choice of ``m`` of the ``2n`` constraints made
  active, solved with ``numpy.linalg.solve`` (LU, not the cofactor inverse the library uses),
  kept where feasible;
- the zonotope ``A [lo, hi]``: support values ``max nu . A tau`` over the box by linprog, and
  the facets of ``scipy.spatial.ConvexHull`` of its signed sums;
- pycapacity's ``force_polytope(J, t_max, t_min, t_bias)`` (vertices, and a ball about 0 from
  the H-representation ``H f <= d`` of ``find_halfplanes``), when pycapacity is installed.
  Its ``vertex_enumeration_vepoli2`` rounds the vertex torques to 7 decimals
  (``np.around(b_vertex, 7)``) before ``f = pinv(J^T) tau``, so its vertices are off by up
  to ``delta = 0.5e-7 sqrt(n) / sigma_min(J)``; its polytope is then within Hausdorff
  distance ``delta`` of the exact one, and so are its ball radius and largest vertex norm
  (support functions differ by at most ``delta``).

Floating-point comparisons: a backward-stable solve of a system with condition number
``kappa`` has a forward error below ``c n eps kappa`` relative to the solution (Higham,
*Accuracy and Stability*, 2nd ed., sec. 7.1, with a small constant ``c``); two such solutions
(the library's and the reference's) differ by at most twice that. We take ``c = 8`` and the
cases are drawn with ``kappa <= KAPPA_MAX``, so ``solve_rtol(n, kappa) = 16 n eps kappa``.
"""
from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.optimize import linprog
from scipy.spatial import ConvexHull

from metrics import (
    anisotropic_force,
    bottleneck_actuator,
    facet_distances,
    isotropic_force,
    polytope_vertices,
    polytopes,
)
from metrics.bottleneck import BOTTLENECK_TIE
from metrics.parallelepiped import polytope_centre, reference_forces
from metrics.torque_box import sign_patterns, torque_range
from metrics.zonotopes import zonotope, zonotope_vertices

EPS = float(np.finfo(float).eps)
LP_RTOL = 1e-6
KAPPA_MAX = 50.0


def solve_rtol(n: int, kappa: float) -> float:
    """Relative gap allowed between two backward-stable solves (module docstring)."""
    return 16 * n * EPS * kappa


def _case(rng, m, n, *, inside=True):
    """A random ``J`` (m, n) with condition number <= KAPPA_MAX and limits (t_max, t_min, bias)."""
    while True:
        jac = rng.normal(size=(m, n))
        kappa = np.linalg.cond(jac)
        if kappa <= KAPPA_MAX:
            break
    t_max = rng.uniform(0.5, 2.0, n)
    t_min = -rng.uniform(0.2, 2.0, n)
    bias = rng.uniform(-0.15, 0.15, n)          # inside (t_min, t_max): the origin is in the set
    if not inside:
        u = rng.integers(n)
        bias[u] = t_max[u] + rng.uniform(0.1, 0.5)     # actuator u already spends more than t_max
    return jac, kappa, t_max, t_min, bias


def _h_rep(jac, lo, hi):
    """Rows ``a_i . f <= b_i`` of ``{f : lo <= J^T f <= hi}``: (2n, m) and (2n,)."""
    return np.vstack([jac.T, -jac.T]), np.concatenate([hi, -lo])


def _lp_ball(a, b):
    """Largest ``r >= 0`` with the ball of radius r about 0 inside ``{a f <= b}``; 0 if infeasible."""
    norms = np.linalg.norm(a, axis=1)
    res = linprog(c=[-1.0], A_ub=norms[:, None], b_ub=b, bounds=[(0, None)], method="highs")
    if res.status == 2:                       # infeasible: the origin is outside the set
        return 0.0
    assert res.status == 0, res.message
    return float(res.x[0])


def _enumerated_vertices(a, b, m):
    """Vertices of ``{a f <= b}`` by making every m-subset of rows active (``numpy.linalg.solve``)."""
    scale = np.max(np.abs(b))
    out = []
    for rows in itertools.combinations(range(a.shape[0]), m):
        sub = a[list(rows)]
        if np.linalg.cond(sub) > 1e8:           # parallel rows (a slab's two sides): no vertex
            continue
        f = np.linalg.solve(sub, b[list(rows)])
        if np.all(a @ f <= b + 1e-9 * scale):
            out.append(f)
    return np.array(out)


# -- the symmetric case is the old one, bit for bit ----------------------------------------
@pytest.mark.parametrize("m", [2, 3])
def test_explicit_defaults_equal_the_symmetric_functions_exactly(m):
    rng = np.random.default_rng(10 + m)
    jac = rng.normal(size=(7, m, m))
    t = rng.uniform(0.5, 2.0, (7, m))
    sym = dict(torque_limits=t)
    explicit = dict(torque_limits=t, torque_min=-t, torque_bias=np.zeros(m))
    for fn in (facet_distances, isotropic_force, bottleneck_actuator, anisotropic_force, polytope_vertices,
               reference_forces):
        np.testing.assert_array_equal(fn(jac, **explicit), fn(jac, **sym), err_msg=fn.__name__)
    # A bias with t_min = -t_max + 2 b leaves the centred range [-(t - b), t - b]: the same numbers
    # as the symmetric functions with t - b (the fast path runs, bit for bit). Dyadic t and b, so
    # that (-t + 2 b) - b and -(t - b) are both exact.
    t = rng.integers(8, 33, (7, m)) / 16.0
    b = rng.integers(-3, 4, (7, m)) / 16.0
    shifted = dict(torque_limits=t, torque_min=-t + 2 * b, torque_bias=b)
    assert np.array_equal(torque_range(t, n=m, torque_min=-t + 2 * b, torque_bias=b)[0], -(t - b))
    for fn in (facet_distances, isotropic_force, anisotropic_force, polytope_vertices):
        np.testing.assert_array_equal(fn(jac, **shifted), fn(jac, torque_limits=t - b), err_msg=fn.__name__)


def test_explicit_defaults_zonotope_equals_symmetric_exactly():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(4, 3, 5))
    t = rng.uniform(0.5, 2.0, 5)
    z0 = zonotope(a, torque_limits=t)
    z1 = zonotope(a, torque_limits=t, torque_min=-t)
    k = z0.offsets.shape[-1]
    assert z1.offsets.shape[-1] == 2 * k              # +nu then -nu
    np.testing.assert_array_equal(z1.offsets[..., :k], z0.offsets)
    np.testing.assert_array_equal(z1.offsets[..., k:], z0.offsets)
    np.testing.assert_array_equal(z1.normals[..., :k, :], z0.normals)
    np.testing.assert_array_equal(z1.inscribed_radius, z0.inscribed_radius)
    np.testing.assert_array_equal(zonotope_vertices(a, torque_limits=t, torque_bias=np.zeros(5)),
                                  zonotope_vertices(a, torque_limits=t))


# -- against a linear programme and vertex enumeration ---------------------------------------
@pytest.mark.parametrize(("m", "n"), [(2, 2), (3, 3), (2, 3), (3, 5)])
def test_isotropic_force_equals_the_lp_ball(m, n):
    rng = np.random.default_rng(100 * m + n)
    for _ in range(10):
        jac, kappa, t_max, t_min, bias = _case(rng, m, n)
        lo, hi = t_min - bias, t_max - bias
        a, b = _h_rep(jac, lo, hi)
        r = float(isotropic_force(jac, torque_limits=t_max, torque_min=t_min, torque_bias=bias))
        assert r > 0
        assert r == pytest.approx(_lp_ball(a, b), rel=LP_RTOL)
        # The nearest facet's foot point is on the boundary: feasible, at distance r.
        d = facet_distances(jac, torque_limits=t_max, torque_min=t_min, torque_bias=bias)
        u = int(np.argmin(d))
        assert bottleneck_actuator(jac, torque_limits=t_max, torque_min=t_min, torque_bias=bias) == u
        normal = jac[:, u] / np.linalg.norm(jac[:, u])
        foot = r * normal if hi[u] <= -lo[u] else -r * normal
        assert np.all(a @ foot <= b + solve_rtol(m, kappa) * np.abs(b).max())


@pytest.mark.parametrize("m", [2, 3])
def test_anisotropic_force_and_vertices_by_enumeration(m):
    rng = np.random.default_rng(7 + m)
    for _ in range(10):
        jac, kappa, t_max, t_min, bias = _case(rng, m, m)
        lo, hi = t_min - bias, t_max - bias
        a, b = _h_rep(jac, lo, hi)
        ref = _enumerated_vertices(a, b, m)
        assert len(ref) == 2 ** m
        verts = polytope_vertices(jac, torque_limits=t_max, torque_min=t_min, torque_bias=bias)
        tol = solve_rtol(m, kappa) * np.abs(ref).max()
        # Row k belongs to sign pattern k: J^T v_k has hi where the sign is +1, lo where -1.
        want = np.where(sign_patterns(m) > 0, hi, lo)
        np.testing.assert_allclose(verts @ jac, want, rtol=0, atol=solve_rtol(m, kappa) * np.abs(want).max())
        for v in verts:
            assert np.min(np.linalg.norm(ref - v, axis=1)) <= tol
        far = float(anisotropic_force(jac, torque_limits=t_max, torque_min=t_min, torque_bias=bias))
        assert far == pytest.approx(np.linalg.norm(ref, axis=1).max(), rel=solve_rtol(m, kappa))
        # Vertices are centre + R s (the half-edges about the centre).
        centre = polytope_centre(jac, torque_limits=t_max, torque_min=t_min, torque_bias=bias)
        half = reference_forces(jac, torque_limits=t_max, torque_min=t_min, torque_bias=bias)
        np.testing.assert_allclose(centre + sign_patterns(m) @ half.T, verts, rtol=0, atol=tol)


@pytest.mark.parametrize(("m", "n"), [(2, 2), (3, 3), (3, 4)])
def test_origin_outside_gives_zero(m, n):
    rng = np.random.default_rng(40 + m + n)
    for _ in range(5):
        jac, _, t_max, t_min, bias = _case(rng, m, n, inside=False)
        kw = dict(torque_limits=t_max, torque_min=t_min, torque_bias=bias)
        assert _lp_ball(*_h_rep(jac, t_min - bias, t_max - bias)) == 0.0
        assert isotropic_force(jac, **kw) == 0.0
        d = facet_distances(jac, **kw)
        outside = np.flatnonzero(t_max - bias < 0)
        assert np.all(d[outside] < 0) and np.all(np.delete(d, outside) > 0)
        assert bottleneck_actuator(jac, **kw) == (outside[0] if len(outside) == 1 else BOTTLENECK_TIE)
    # Two actuators excluding the origin tie at 0.
    assert bottleneck_actuator(np.eye(3), torque_limits=[1.0, 1.0, 1.0], torque_bias=[2.0, -2.0, 0.0]) \
        == BOTTLENECK_TIE


def test_one_sided_ranges_and_negligible_columns():
    # A cable that only pulls: tau_0 in [0, 1]: the origin is on facet 0, the isotropic force 0.
    assert isotropic_force(np.eye(2), torque_limits=[1.0, 1.0], torque_min=[0.0, -1.0]) == 0.0
    # A zero column bounds nothing if its range holds 0, and empties the set if it does not.
    jac = np.array([[1.0, 0.0], [0.0, 0.0]])
    d = facet_distances(jac, torque_limits=[1.0, 1.0], torque_min=[-2.0, -1.0], torque_bias=[0.0, 0.5])
    assert d.tolist() == [1.0, np.inf]
    d = facet_distances(jac, torque_limits=[1.0, 1.0], torque_min=[-2.0, -1.0], torque_bias=[0.0, 1.5])
    assert d.tolist() == [1.0, -np.inf]
    assert isotropic_force(jac, torque_limits=[1.0, 1.0], torque_bias=[0.0, 1.5]) == 0.0


def test_batched_limits_equal_one_at_a_time():
    rng = np.random.default_rng(5)
    jac = rng.normal(size=(4, 6, 3, 3))
    t_max = rng.uniform(0.5, 2.0, (6, 3))              # broadcast over the first axis
    t_min = -rng.uniform(0.2, 2.0, (4, 6, 3))
    bias = rng.uniform(-0.15, 0.15, 3)
    kw = dict(torque_limits=t_max, torque_min=t_min, torque_bias=bias)
    batch = {fn: fn(jac, **kw) for fn in (isotropic_force, anisotropic_force, bottleneck_actuator,
                                          facet_distances, polytope_vertices)}
    assert batch[isotropic_force].shape == (4, 6) and batch[polytope_vertices].shape == (4, 6, 8, 3)
    for i, j in itertools.product(range(4), range(6)):
        one = dict(torque_limits=t_max[j], torque_min=t_min[i, j], torque_bias=bias)
        for fn, values in batch.items():
            np.testing.assert_array_equal(values[i, j], fn(jac[i, j], **one), err_msg=fn.__name__)


def test_singular_and_non_finite_jacobians():
    kw = dict(torque_limits=[1.0, 1.0], torque_min=[-0.5, -1.0])
    assert anisotropic_force(np.array([[1.0, 1.0], [1.0, 1.0]]), **kw) == np.inf
    assert np.isnan(anisotropic_force(np.array([[np.nan, 0.0], [0.0, 1.0]]), **kw))
    assert isotropic_force(np.array([[1.0, 1.0], [1.0, 1.0]]), **kw) == pytest.approx(0.5 / np.sqrt(2))


def test_validation_names_the_argument():
    with pytest.raises(ValueError, match="torque_min must be below torque_limits"):
        isotropic_force(np.eye(2), torque_limits=[1.0, 1.0], torque_min=[-1.0, 1.0])
    with pytest.raises(ValueError, match="torque_bias must be finite"):
        isotropic_force(np.eye(2), torque_limits=[1.0, 1.0], torque_bias=[np.nan, 0.0])
    with pytest.raises(ValueError, match=r"torque_min must have shape \(\.\.\., 2\)"):
        isotropic_force(np.eye(2), torque_limits=[1.0, 1.0], torque_min=[-1.0])
    with pytest.raises(ValueError, match="torque_limits must be positive"):
        isotropic_force(np.eye(2), torque_limits=[-1.0, 1.0], torque_bias=[0.0, 0.0])
    with pytest.raises(ValueError, match="pass jac and not ref"):
        anisotropic_force(np.eye(2), torque_limits=[1.0, 1.0], torque_bias=[0.1, 0.0], ref=np.eye(2))


# -- the redundant case: a shifted zonotope ---------------------------------------------------
@pytest.mark.parametrize(("m", "n"), [(2, 3), (2, 4), (3, 4), (3, 5)])
def test_shifted_zonotope_against_lp_and_hull(m, n):
    rng = np.random.default_rng(200 + 10 * m + n)
    for _ in range(4):
        a, kappa, t_max, t_min, bias = _case(rng, m, n)
        lo, hi = t_min - bias, t_max - bias
        z = zonotope(a, torque_limits=t_max, torque_min=t_min, torque_bias=bias)
        # Each offset is the support value max nu . A tau over the box lo <= tau <= hi.
        for nu, h in zip(z.normals, z.offsets):
            res = linprog(c=-(nu @ a), bounds=list(zip(lo, hi)), method="highs")
            assert res.status == 0
            assert h == pytest.approx(-res.fun, rel=LP_RTOL, abs=LP_RTOL)
        verts = zonotope_vertices(a, torque_limits=t_max, torque_min=t_min, torque_bias=bias)
        hull = ConvexHull(verts)                     # equations: unit n . x + c <= 0 inside
        ball = max(float(np.min(-hull.equations[:, -1])), 0.0)
        assert float(z.inscribed_radius) == pytest.approx(ball, rel=1e3 * solve_rtol(m, kappa))
        # The signed sums: A v with v_u = hi_u (s_u = +1) or lo_u.
        want = np.where(sign_patterns(n) > 0, hi, lo) @ a.T
        np.testing.assert_allclose(verts, want, rtol=0, atol=4 * n * EPS * np.abs(want).max())


def test_shifted_zonotope_origin_outside():
    a = np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]])
    z = zonotope(a, torque_limits=[1.0, 1.0, 1.0], torque_bias=[2.0, 2.0, 2.0])   # tau in [-3, -1]^3
    assert float(z.inscribed_radius) == 0.0
    assert np.min(z.offsets) < 0


# -- against pycapacity -------------------------------------------------------------------------
@pytest.mark.parametrize(("m", "n"), [(2, 2), (3, 3), (2, 3), (3, 4)])
@pytest.mark.parametrize("inside", [True, False])
def test_against_pycapacity(m, n, inside):
    robot = pytest.importorskip("pycapacity.robot")
    rng = np.random.default_rng(300 + 10 * m + n + inside)
    compared = []
    for _ in range(6):
        jac, kappa, t_max, t_min, bias = _case(rng, m, n, inside=inside)
        kw = dict(torque_limits=t_max, torque_min=t_min, torque_bias=bias)
        a, b = _h_rep(jac, t_min - bias, t_max - bias)
        if linprog(c=np.zeros(m), A_ub=a, b_ub=b, bounds=[(None, None)] * m, method="highs").status == 2:
            # n > m and the origin outside: the set can be empty, which pycapacity does not handle.
            assert isotropic_force(jac, **kw) == 0.0
            continue
        poly = robot.force_polytope(jac, t_max, t_min, bias)
        theirs = np.asarray(poly.vertices).T                     # (N, m)
        poly.find_halfplanes()
        h, d = np.asarray(poly.H), np.asarray(poly.d).ravel()     # H f <= d
        their_ball = max(float(np.min(d / np.linalg.norm(h, axis=1))), 0.0)
        compared.append(inside)
        # pycapacity's 7-decimal rounding (module docstring), plus the solve bound for the rest.
        scale = np.abs(theirs).max()
        delta = 0.5e-7 * np.sqrt(n) / np.linalg.svd(jac, compute_uv=False)[-1] + solve_rtol(m, kappa) * scale
        assert abs(float(isotropic_force(jac, **kw)) - their_ball) <= delta
        if m == n:
            ours = polytope_vertices(jac, **kw)
            assert len(theirs) == 2 ** m
            for v in ours:
                assert np.min(np.linalg.norm(theirs - v, axis=1)) <= delta
            assert abs(float(anisotropic_force(jac, **kw)) - np.linalg.norm(theirs, axis=1).max()) <= delta
        else:
            ref = _enumerated_vertices(a, b, m)
            assert abs(np.linalg.norm(theirs, axis=1).max() - np.linalg.norm(ref, axis=1).max()) <= delta
    assert len(compared) >= 2                       # the cases did reach pycapacity


def test_module_table_mentions_every_asymmetric_quantity():
    doc = polytopes.__doc__
    for word in ("torque_min", "torque_bias", "isotropic force", "anisotropic force", "zonotope facets",
                 "polytope_centre"):
        assert word in doc
