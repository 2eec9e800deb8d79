"""Free sets whose ``det G_O[:, F]`` is 0 exactly but computes as rounding noise (wrenches' slices).

A symmetric device has identical or opposite generators in the other rows ``O`` of a slice (the
Twin-Pantograph's two units on the rows (0, 2, 4) or (0, 4)); ``det G_O[:, F]`` of such a free set
is 0 in exact arithmetic but about 1e-22 as computed, and a solve with it divided noise by noise
(22687 N where the slice's largest force is 2.05 N). References here are exact: the floats of
``G`` are rationals (``fractions.Fraction``), and a vertex of the section
``Q = {s in [-1, 1]^n : G_O s = 0}`` is a basic solution: ``n - r`` coordinates at +-1 and the
``r`` others solving a nonsingular system, kept if in the box. Tolerances are derived below
from the kernel's operations (``_kernel_bounds``, ``_radius_bounds``); nothing is tuned.
"""
from __future__ import annotations

import itertools
import math
from fractions import Fraction

import numpy as np
import pytest

from metrics import linalg, wrench_facets, wrench_slices
from metrics.quantities import evaluate
from resources import load_preset

EPS = np.finfo(float).eps
U = EPS / 2                               # unit roundoff


def _gamma(k: int) -> float:
    """Higham's ``gamma_k = k u / (1 - k u)``: the bound of ``k`` roundings."""
    return k * U / (1 - k * U)


def _det(mat):
    """Exact determinant of a square list of Fractions (Laplace expansion)."""
    if len(mat) == 1:
        return mat[0][0]
    return sum((-1) ** j * mat[0][j] * _det([row[:j] + row[j + 1:] for row in mat[1:]]) for j in range(len(mat)))


def _rational(g):
    return [[Fraction(float(x)) for x in row] for row in np.asarray(g, float)]


def exact_max_norm2(g, rows, skip=()):
    """Largest squared norm of ``G_R s`` over the vertices of Q, exactly; ``None`` without a vertex.

    Free sets in ``skip`` are left out (to name the vertices a kernel cannot resolve).
    """
    m, n = np.shape(g)
    G = _rational(g)
    others = [i for i in range(m) if i not in rows]
    r = len(others)
    best = None
    for free in itertools.combinations(range(n), r):
        block = [[G[i][u] for u in free] for i in others]
        d = _det(block)
        if d == 0 or free in skip:
            continue
        fixed = [u for u in range(n) if u not in free]
        for signs in itertools.product((1, -1), repeat=len(fixed)):
            rhs = [-sum(G[i][u] * s for u, s in zip(fixed, signs)) for i in others]
            s = dict(zip(fixed, (Fraction(x) for x in signs)))
            for k, u in enumerate(free):          # Cramer's rule, exactly
                s[u] = _det([row[:k] + [rhs[a]] + row[k + 1:] for a, row in enumerate(block)]) / d
            if all(abs(s[u]) <= 1 for u in free):
                value = sum(sum(G[i][u] * s[u] for u in range(n)) ** 2 for i in rows)
                best = value if best is None else max(best, value)
    return best


def _kernel_bounds(g, rows):
    """Interval that must hold ``slice_max_norm(g, rows)``, from the exact value and a rounding analysis.

    The kernel scales the rows ``R`` by ``size = max |G_R|`` and equilibrates each row of ``G_O``
    (every entry rounded once). For a free set ``F`` (exactly nonsingular, ``d_F`` the exact
    determinant of the exactly scaled ``G_O[:, F]``), let ``c_u`` be the column sums of the
    scaled ``|G_O|``, ``alpha_u = max_i |G_R[i, u]| / size``, ``mu_F = min(1, min_F (c + alpha))``
    and ``E_F = gamma_M prod_F (c_u + alpha_u) sum_u (c_u + alpha_u) / mu_F``. Every quantity the
    kernel forms for ``F`` (``det_F``; ``det_F s_k`` and ``det_F (G_R s)_i``, sums over the ``b``
    fixed generators of r- and (r+1)-minors) is a signed sum of products of entries, each
    product through at most ``M = K_{r+1} + b + d + 3`` roundings (``K_k = k (k + 1) / 2 - 1 + k``,
    the Laplace expansion and the entries'; ``b - 1`` additions over the sign pattern; the norm,
    the division and the square root), and the sum of the products' sizes is at most the
    product of column sums above, so each is off by at most ``E_F`` (``lambda_F = E_F / |d_F|``).
    With ``lambda = max_F lambda_F`` and ``3 lambda <= VERTEX_TOL`` (checked): every true vertex
    passes the box test, an accepted candidate is in the box enlarged by ``VERTEX_TOL + 3 lambda``
    (so at most that much relatively above the true largest norm ``v``), no nonsingular free set
    is skipped, and each candidate's norm is computed within ``3 lambda`` relative plus
    ``2 sqrt(d) lambda`` absolute (scaled units). Hence, in units of ``size``::

        (1 - 3 lambda) v - 2 sqrt(d) lambda <= result <= (1 + VERTEX_TOL + 7 lambda) v + 2 sqrt(d) lambda

    A free set with ``0 < |d_F| <= T_F / 2`` (``T_F = K_r eps prod_F c_u``, the kernel's skip bound)
    is skipped whatever its rounding (``|det_F - d_F| <= gamma_{K_r} prod c_u < T_F / 2``): it is
    left out of ``lambda`` and of ``v``, and ``v_all``, the exact value with it, is returned too,
    for the check that skipping it lost no vertex. Returns ``(lo, hi, v, v_all)`` in ``G``'s units.
    """
    g = np.asarray(g, float)
    m, n = g.shape
    rows = list(rows)
    others = [i for i in range(m) if i not in rows]
    r, d, b = len(others), len(rows), n - len(others)
    size = float(np.max(np.abs(g[rows])))
    beta = np.max(np.abs(g[others]), axis=1)
    c = np.sum(np.abs(g[others]) / beta[:, None], axis=0)
    alpha = np.max(np.abs(g[rows]), axis=0) / size
    G = _rational(g)
    big_m = (r + 1) * (r + 2) // 2 - 1 + (r + 1) + b + d + 3
    lam = 0.0
    skipped = set()
    for free in itertools.combinations(range(n), r):
        det = _det([[G[i][u] for u in free] for i in others])
        if det == 0:
            continue
        d_f = abs(float(det / math.prod(Fraction(float(x)) for x in beta)))
        if d_f <= 0.5 * (r * (r + 1) // 2 - 1 + r) * EPS * math.prod(c[u] for u in free):
            skipped.add(free)
            continue
        mu = min(1.0, min(c[u] + alpha[u] for u in free))
        err = _gamma(big_m) * math.prod(c[u] + alpha[u] for u in free) * float(np.sum(c + alpha)) / mu
        lam = max(lam, err / d_f)
    assert 3 * lam <= wrench_slices.VERTEX_TOL, f"input too ill-conditioned for the bound: lambda = {lam:.1e}"
    v = math.sqrt(exact_max_norm2(g, rows, skip=skipped)) / size
    v_all = math.sqrt(exact_max_norm2(g, rows)) / size if skipped else v
    lo = (1 - 3 * lam) * v - 2 * math.sqrt(d) * lam
    hi = (1 + wrench_slices.VERTEX_TOL + 7 * lam) * v + 2 * math.sqrt(d) * lam
    return size * lo, size * hi, size * v, size * v_all


def _assert_within(g, rows, got):
    """The kernel's value within the derived bounds; the exact value with every free set too."""
    lo, hi, exact, exact_all = _kernel_bounds(g, rows)
    assert lo <= got <= hi, f"rows {rows}: got {got!r}, exact {exact!r}, bounds [{lo!r}, {hi!r}]"
    assert lo <= exact_all <= hi, f"rows {rows}: a skipped free set held a vertex: {exact_all!r} vs {exact!r}"


def _planted(rng, m, n, rows):
    """Generators whose other rows come in +- pairs, one pair 3 times another (Twin-Pantograph-like).

    The base entries have 20 significant bits, so the multiples and opposites are exact and the
    degenerate free sets have ``det = 0`` exactly; the kernel's row equilibration (by maxima that
    are not powers of two) turns them into rounding noise. The rows ``R`` are random.
    """
    others = [i for i in range(m) if i not in rows]
    g = rng.normal(size=(m, n))
    base = np.round(rng.normal(size=(len(others), (n + 1) // 2)) * 2.0 ** 20) / 2.0 ** 20
    base[:, -1] = 3.0 * base[:, -2]
    g[others] = np.stack([base[:, j // 2] * (1 if j % 2 == 0 else -1) for j in range(n)], axis=1)
    return g[:, rng.permutation(n)]


def _twin_generators(key, points, **changes):
    mech = load_preset(key).mechanism.replace(**changes)
    ev = evaluate(mech, np.asarray(points, float), ["reference_forces"])
    assert np.all(ev.feasible)
    return ev.values["reference_forces"]


# -- the reported pose ---------------------------------------------------------------------------
#: Twin-Pantograph pose (x, y, z, rx, rz) of the report: on the slice (0, 2, 4) the old kernel
#: gave 22687 (the exact largest norm is 2.0504...).
REPORTED_POSE = (-0.142, 0.0, 0.152, 0.0, 0.0)


def test_the_reported_twin_pantograph_pose_gives_the_exact_largest_norm():
    rows = (0, 2, 4)
    g = _twin_generators("twin_pantograph", [REPORTED_POSE], ujoint_lever=0.5)    # the report's reading
    got = float(wrench_slices.slice_max_norm(g, rows=rows)[0])
    _assert_within(g[0], rows, got)
    assert 2.0 < got < 2.1                            # was 22687 (noise / noise)


def test_the_reported_pose_has_free_sets_whose_determinant_is_noise_and_they_are_skipped():
    """The premise: ``det G_O[:, F]`` about 1e-18 relative (parallel generators of the two units, up
    to the force map's rounding), computed nonzero and wrong, within the rounding bound."""
    g = _twin_generators("twin_pantograph", [REPORTED_POSE])[0]
    others = [1, 3]
    beta = np.max(np.abs(g[others]), axis=1, keepdims=True)
    a = linalg.components((g[others] / beta)[None])
    det = linalg.minors(a, [(0, 1)])[0][:, 0]
    bound = wrench_slices._det_rounding_bound(a, 2)[:, 0]
    G = _rational(g)
    scale = math.prod(Fraction(float(x)) for x in beta[:, 0])
    noisy = []
    for k, free in enumerate(itertools.combinations(range(6), 2)):
        exact = _det([[G[i][u] for u in free] for i in others]) / scale
        if det[k] != 0 and abs(exact) <= Fraction(float(bound[k])) / 2:
            noisy.append(k)
            assert abs(Fraction(float(det[k])) - exact) > abs(exact) / 100     # no correct digit
    assert noisy
    assert all(abs(det[k]) <= bound[k] for k in noisy)


@pytest.mark.parametrize("key", ["twin_pantograph", "twin_pantograph_prototype"])
def test_twin_pantograph_grid_points_on_unusual_slices_give_the_exact_largest_norm(key):
    preset = load_preset(key)
    mech = preset.mechanism
    pts = preset.grid.points(mech.task_names)
    rng = np.random.default_rng(11)
    ev = evaluate(mech, pts[rng.choice(len(pts), 120, replace=False)], ["reference_forces"])
    gens = ev.values["reference_forces"][ev.feasible][:25]
    assert len(gens) == 25
    # Slices with r = 2 other rows: the (3, 4) and (0, 4) slices (r = 3) have free sets conditioned
    # beyond what the derived bound covers (lambda > VERTEX_TOL / 3).
    for rows in ((0, 2, 4), (0, 1, 2), (1, 2, 4)):
        got = wrench_slices.slice_max_norm(gens, rows=rows)
        for g, value in zip(gens, got):
            _assert_within(g, rows, float(value))


# -- planted exact degeneracies -------------------------------------------------------------------
@pytest.mark.parametrize("m, n, rows", [(5, 6, (0, 2, 4)), (5, 6, (0, 1, 2)), (4, 5, (0, 2)), (4, 6, (0, 1)),
                                        (6, 7, (0, 1, 2)), (6, 7, (0, 1, 2, 3)), (5, 7, (0, 2, 4))])
def test_planted_degenerate_free_sets_give_the_exact_largest_norm(m, n, rows):
    rng = np.random.default_rng(m * 100 + n * 10 + len(rows))
    gens = np.array([_planted(rng, m, n, rows) for _ in range(30)])
    got = wrench_slices.slice_max_norm(gens, rows=rows)
    for k, (g, value) in enumerate(zip(gens, got)):
        _assert_within(g, rows, float(value))
        if k < 10:
            # slice_vertices: the same candidates on unscaled G_R (the same minors up to the exact
            # factor size, so the same bounds up to that scaling's rounding, inside 2 sqrt(d) lambda).
            _assert_within(g, rows, float(np.max(np.linalg.norm(wrench_slices.slice_vertices(g, rows=rows), axis=1))))


def test_parallel_generators_and_generators_inside_the_slice_give_the_exact_largest_norm():
    """Small integers with a generator 3 (or -5) times another in ``G_O`` and one with ``G_O[:, u] = 0``."""
    rng = np.random.default_rng(5)
    for _ in range(40):
        m, n = 5, 7
        rows = (0, 2, 4)
        g = rng.integers(-6, 7, size=(m, n)).astype(float)
        g[[1, 3], 1] = 3.0 * g[[1, 3], 0]
        g[[1, 3], 2] = -5.0 * g[[1, 3], 0]
        g[[1, 3], 3] = 0.0
        if np.linalg.matrix_rank(g[[1, 3]]) < 2 or np.linalg.matrix_rank(g) < m:
            continue
        _assert_within(g, rows, float(wrench_slices.slice_max_norm(g, rows=rows)))


def test_the_rounding_bound_holds_for_the_computed_determinants():
    """``_det_rounding_bound`` against exact determinants of the exactly equilibrated ``G_O``."""
    rng = np.random.default_rng(7)
    for r, n in ((1, 6), (2, 6), (3, 7)):
        for _ in range(20):
            go = rng.normal(size=(r, n)) * 10.0 ** rng.uniform(-3, 3, size=(1, n))
            beta = np.max(np.abs(go), axis=1, keepdims=True)
            scaled = go / beta
            a = linalg.components(scaled[None])
            det = linalg.minors(a, [tuple(range(r))])[0][:, 0]
            bound = wrench_slices._det_rounding_bound(a, r)[:, 0]
            G = _rational(go)
            scale = math.prod(Fraction(float(x)) for x in beta[:, 0])
            for k, free in enumerate(itertools.combinations(range(n), r)):
                exact = _det([[G[i][u] for u in free] for i in range(r)]) / scale
                assert abs(Fraction(float(det[k])) - exact) <= Fraction(float(bound[k]))


# -- slice_vertices shares the enumeration ------------------------------------------------------
def test_slice_vertices_of_the_reported_pose_reach_the_exact_largest_norm_and_no_further():
    g = _twin_generators("twin_pantograph", [REPORTED_POSE])[0]
    rows = (0, 2, 4)
    verts = wrench_slices.slice_vertices(g, rows=rows)
    lo, hi, _, _ = _kernel_bounds(g, rows)
    # slice_vertices works on unscaled G_R (same minors up to the exact factor size): same bounds
    # up to the rounding of that scaling, inside 2 sqrt(d) lambda.
    assert lo <= float(np.max(np.linalg.norm(verts, axis=1))) <= hi


# -- the facet path divides no determinant: a noisy normal is still a valid slab -----------------
def _exact_radius(g, rows):
    """Exact squared inscribed radius of the slice and its facet: ``(h^2 / |nu_R|^2, nu, h)``."""
    m, n = np.shape(g)
    G = _rational(g)
    best = None
    for subset in itertools.combinations(range(n), m - 1):
        nu = [(-1) ** i * _det([[G[k][u] for u in subset] for k in range(m) if k != i]) for i in range(m)]
        den = sum(nu[i] ** 2 for i in rows)
        if den == 0:
            continue
        h = sum(abs(sum(nu[i] * G[i][u] for i in range(m))) for u in range(n))
        if best is None or h * h / den < best[0]:
            best = (h * h / den, nu, h, subset)
    return best


def _radius_bounds(g, rows):
    """Interval for ``slice_inscribed_radius(*facets(g), rows)`` from the exact radius ``rho``.

    Below: for any vector ``nu`` the slab ``|nu . w| <= h(nu) = sum_u |nu . g_u|`` contains ``W``,
    so ``h(nu) / |nu_R| >= rho`` for every computed normal, noisy or not; the computed ``h`` is
    within ``gamma_{m+n+6} |nu| sum_u |g_u|`` of ``h(nu)`` (unit columns, dot products, lengths,
    the sum) and ``h(nu) >= sigma_m(G) |nu|``, and ``|nu_R|`` and the quotient add
    ``gamma_{d+3}``: ``result >= rho (1 - delta_h - gamma_{d+3})``. Above: the exact minimising
    facet's normal is computed within ``eta = sqrt(m) gamma_K prod_S |g_u|_1`` (in the units of
    the exact cofactors; ``K = K_{m-1}`` plus the ``m + 3`` roundings of each unit-column entry),
    so ``result <= (h + eta sum_u |g_u|) (1 + delta_h) / ((|nu_R| - eta)(1 - gamma_{d+3}))``.
    """
    g = np.asarray(g, float)
    m, n = g.shape
    d = len(rows)
    value, nu, h, subset = _exact_radius(g, rows)
    rho = math.sqrt(value)
    col = float(np.sum(np.linalg.norm(g, axis=0)))
    delta_h = _gamma(m + n + 6) * col / float(np.linalg.svd(g, compute_uv=False)[-1])
    k = (m - 1) * m // 2 - 1 + (m - 1) * (m + 3)
    eta = math.sqrt(m) * _gamma(k) * math.prod(float(np.sum(np.abs(g[:, u]))) for u in subset)
    nu_r = math.sqrt(float(sum(nu[i] ** 2 for i in rows)))
    lo = rho * (1 - delta_h - _gamma(d + 3))
    hi = (float(h) + eta * col) * (1 + delta_h) / ((nu_r - eta) * (1 - _gamma(d + 3)))
    return lo, hi


@pytest.mark.parametrize("m, n, rows", [(5, 6, (0, 2, 4)), (4, 5, (0, 2)), (6, 7, (0, 1, 2))])
def test_inscribed_radius_of_planted_degenerate_generators_equals_the_exact_one(m, n, rows):
    rng = np.random.default_rng(m * 10 + n + 1)
    gens = np.array([_planted(rng, m, n, rows) for _ in range(12)])
    nu, h = wrench_facets.facets(gens)
    got = wrench_facets.slice_inscribed_radius(nu, h, rows=rows)
    for g, value in zip(gens, got):
        lo, hi = _radius_bounds(g, rows)
        assert lo <= float(value) <= hi


def test_inscribed_radius_of_the_reported_pose_equals_the_exact_one():
    g = _twin_generators("twin_pantograph", [REPORTED_POSE])
    nu, h = wrench_facets.facets(g)
    for rows in ((0, 2, 4), (0, 4), (0, 1, 2), (3, 4)):
        lo, hi = _radius_bounds(g[0], rows)
        assert lo <= float(wrench_facets.slice_inscribed_radius(nu, h, rows=rows)[0]) <= hi


def test_a_twin_pose_with_a_stretched_leg_is_unbounded_not_noise():
    """The adopted prototype's map has poses (x = -9, -2, 2, 9 mm at z = 45-46 mm) where both units'
    legs are stretched to machine precision: J is not finite (the condition number inf) or the
    force map's columns are ~1e17 rounding noise. The largest force and moment at zero moment/force are then
    unbounded (inf, as at the five-bar's inverse singularities), not 4e16 N; a regular pose
    beside it keeps its finite value, and the map's maximum is marked unbounded."""
    mech = load_preset("twin_pantograph_prototype").mechanism
    lost = np.array([0.009, 0.0, 0.046, 0.0, 0.0])        # J not finite
    noise = np.array([0.002, 0.0, 0.045, 0.0, 0.0])        # J finite, the force map's columns ~1e17
    regular = np.array([[0.0, 0.0, 0.2, 0.0, 0.0], [0.002, 0.0, 0.046, 0.0, 0.0]])   # the second 1 mm away
    names = ["anisotropic_force", "anisotropic_moment", "condition_number", "jacobian", "reference_forces"]
    ev = evaluate(mech, np.vstack([lost, noise, regular]), names)
    assert np.all(ev.feasible)
    assert not np.all(np.isfinite(ev.values["jacobian"][0])) and np.isposinf(ev.values["condition_number"][0])
    assert np.all(np.isfinite(ev.values["jacobian"][1])) and np.abs(ev.values["reference_forces"][1]).max() > 1e15
    for k in (0, 1):
        assert np.isposinf(ev.values["anisotropic_force"][k]) and np.isposinf(ev.values["anisotropic_moment"][k])
    for k in (2, 3):
        assert np.all(np.isfinite(ev.values["jacobian"][k]))
        for name in ("anisotropic_force", "anisotropic_moment"):
            assert 0 < ev.values[name][k] < 1e4, (name, k)
