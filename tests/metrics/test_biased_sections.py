"""The biased slices' section path (``metrics.biased_sections``) against an exact enumeration and the slab path.

Reference: the exact largest norm of the slice, by the same theorem but in rational arithmetic
(``fractions``, every float taken exactly): every free set ``F`` with ``det G_O[:, F] != 0``, every
sign pattern of the others, kept where ``|s_F| <= 1`` exactly. No rounding, no tolerance.

What is asserted, and why (``biased_sections``' module doc): a decided value is the largest
norm of a candidate whose free coordinates exceed the box by at most ``VERTEX_TOL`` (and none
below it is dropped), so it lies between the exact maximum at the ratings ``t`` and at
``(1 + VERTEX_TOL) t`` with the same gravity torque (``G (1 + tau)``, ``beta / (1 + tau)``), up to the
rounding of the winning image, ``_image_rounding``. Where the section path hands a point back,
the quantity node gives the slab path's value, as before.
"""
from __future__ import annotations

import itertools
import math
from fractions import Fraction

import numpy as np
import pytest

from metrics import biased_sections, wrench_facets
from metrics.loading import Loading
from metrics.quantities import summary_quantities
from metrics.workspace import compute_map
from metrics.wrench_slices import VERTEX_TOL
from resources import load_preset

EPS = np.finfo(float).eps


def _det(rows: list[list[Fraction]]) -> Fraction:
    if len(rows) == 1:
        return rows[0][0]
    return sum(((-1) ** j) * rows[0][j] * _det([r[:j] + r[j + 1:] for r in rows[1:]]) for j in range(len(rows)))


def _exact_max2(g: np.ndarray, beta: np.ndarray, rows, scale: Fraction = Fraction(1)) -> Fraction | None:
    """Exact ``max |G_R (s - beta)|^2`` over the section, ratings times ``scale`` (None: empty slice)."""
    m, n = g.shape
    others = [i for i in range(m) if i not in rows]
    r = len(others)
    gq = [[Fraction(float(x)) * scale for x in row] for row in g]
    bq = [Fraction(float(x)) / scale for x in beta]
    best = None
    for free in itertools.combinations(range(n), r):
        fixed = [u for u in range(n) if u not in free]
        block = [[gq[i][u] for u in free] for i in others]
        det = _det(block)
        if det == 0:
            continue
        for signs in itertools.product((-1, 1), repeat=len(fixed)):
            sigma = {u: e - bq[u] for u, e in zip(fixed, signs)}
            rhs = [-sum(gq[i][u] * sigma[u] for u in fixed) for i in others]
            for c, u in enumerate(free):          # Cramer's rule
                swapped = [row[:c] + [rhs[k]] + row[c + 1:] for k, row in enumerate(block)]
                sigma[u] = _det(swapped) / det
            if any(abs(sigma[u] + bq[u]) > 1 for u in free):
                continue
            norm2 = sum(sum(gq[i][u] * sigma[u] for u in range(n)) ** 2 for i in rows)
            best = norm2 if best is None or norm2 > best else best
    return best


def _root(x: Fraction) -> float:
    """``sqrt(x)`` of an exact square norm at any scale (1e-600 and 1e600 leave the float range)."""
    e = (x.numerator.bit_length() - x.denominator.bit_length()) // 2
    return math.ldexp(math.sqrt(float(x / Fraction(4) ** e)), e)


def _image_rounding(g: np.ndarray, beta: np.ndarray, rows) -> float:
    """Bound on the rounding of a decided value's image, in the unit of ``G``'s rows ``rows``.

    The kernel works on ``G`` with the slice rows over their largest entry (``size``) and the rows
    ``O`` equilibrated; ``c_u`` is column ``u``'s sum of ``|.|`` over the rows ``O`` and ``c'_u`` over
    all rows. For a free set ``F`` an image coordinate is ``v / det``: ``v`` sums the ``b``
    (r+1)-minors ``z_j`` of the columns ``F + j`` with weights at most ``1 + |beta_j|``; each is at
    most ``P_j = prod_{u in F + j} c'_u`` and rounded by at most ``K_{r+1} eps P_j`` (Laplace,
    ``wrench_slices._det_rounding_bound``'s derivation), and the ``2 b + 2`` operations forming
    ``v`` add ``(2 b + 2) u`` of the magnitudes (``(2 b + 4) eps`` with room): ``|v| <= V`` and
    ``|v - v_hat| <= (K_{r+1} + 2 b + 4) eps V`` with ``V = sum_j (1 + |beta_j|) P_j``. ``det`` is off
    by at most ``bnd = K_r eps prod_F c_u``, so ``v / det`` by ``(E_v + V bnd / L) / L`` plus one
    rounding, ``L = |det| - bnd``. The winning free set is unknown: the largest over the sets the
    kernel uses. The norm adds a factor ``sqrt(d)`` over a coordinate's and ``d u`` relative.
    """
    m, n = g.shape
    rows = list(rows)
    others = [i for i in range(m) if i not in rows]
    r, d, b = len(others), len(rows), n - len(others)
    size = np.max(np.abs(g[rows]))
    go = g[others] / np.max(np.abs(g[others]), axis=1, keepdims=True)
    c = np.sum(np.abs(go), axis=0)
    c_all = c + np.sum(np.abs(g[rows] / size), axis=0)
    k_r = r * (r + 1) // 2 - 1 + r
    k_w = (r + 1) * (r + 2) // 2 - 1 + (r + 1)
    worst = 0.0
    for free in itertools.combinations(range(n), r):
        det = abs(np.linalg.det(go[:, list(free)]))
        bnd = k_r * EPS * math.prod(c[list(free)])
        if not det > 2 * bnd:          # numpy's det is not the kernel's: a factor 2 for its rounding
            continue
        low = det - 2 * bnd
        fixed = [u for u in range(n) if u not in free]
        big_v = math.prod(c_all[list(free)]) * sum((1.0 + abs(beta[j])) * c_all[j] for j in fixed)
        f = big_v / low
        coordinate = ((k_w + 2 * b + 4) * EPS * big_v + big_v * 2 * bnd / low) / low + EPS * f
        worst = max(worst, math.sqrt(d) * coordinate + d * EPS * math.sqrt(d) * f)
    return float(size * worst)


def _check_sandwich(g, beta, rows):
    value, decided = biased_sections.biased_slice_max_norm(g, beta, rows=rows)
    assert decided, "a generic case was handed back"
    low = _exact_max2(g, beta, rows)
    high = _exact_max2(g, beta, rows, Fraction(1) + Fraction(VERTEX_TOL))
    assert low is not None
    rho = _image_rounding(g, beta, rows)
    assert _root(low) - rho <= float(value) <= _root(high) + rho


SHAPES = [((3, 5), [0, 1]), ((5, 6), [0, 1, 2]), ((5, 6), [3, 4]), ((6, 8), [0, 1, 2]), ((4, 7), [1, 2, 3])]


@pytest.mark.parametrize("shape, rows", SHAPES)
def test_random_biased_slices_are_between_the_exact_maxima_at_t_and_t_plus_tol(shape, rows):
    rng = np.random.default_rng(61 + len(rows) + shape[1])
    for _ in range(6):
        g = rng.normal(size=shape)
        beta = rng.uniform(-0.7, 0.7, size=shape[1])
        _check_sandwich(g, beta, rows)


def test_parallel_actuators_and_a_zero_column_are_decided_exactly():
    """Mirrored units (identical or opposite columns of ``G_O``, free sets singular exactly), a dead actuator."""
    rng = np.random.default_rng(62)
    for _ in range(5):
        half = rng.normal(size=(5, 3))
        g = np.concatenate([half, half * np.array([1, -1, 1, 1, -1])[:, None]], axis=1)   # the Twin's mirror
        beta = rng.uniform(-0.5, 0.5, size=6)
        _check_sandwich(g, beta, [0, 1, 2])
        g2 = g.copy()
        g2[:, 4] = 0.0
        _check_sandwich(g2, beta, [0, 1, 2])


def test_undecidable_points_are_handed_back():
    rng = np.random.default_rng(63)
    g = rng.normal(size=(5, 6))
    rank_deficient = g.copy()
    rank_deficient[4] = 2.0 * rank_deficient[3]            # G_O of rank 1 < r = 2
    empty = np.abs(g)                                      # G_O > 0 and s - beta < 0: no zero moment
    nan = g.copy()
    nan[0, 0] = np.nan
    gens = np.stack([rank_deficient, empty, nan, g])
    beta = np.stack([np.full(6, 0.1), np.full(6, 1.5), np.zeros(6), np.full(6, 0.2)])
    beta_nan = beta.copy()
    beta_nan[3, 2] = np.inf
    _, decided = biased_sections.biased_slice_max_norm(gens, beta, rows=[0, 1, 2])
    assert decided.tolist() == [False, False, False, True]
    _, decided = biased_sections.biased_slice_max_norm(gens, beta_nan, rows=[0, 1, 2])
    assert decided.tolist() == [False, False, False, False]
    assert _exact_max2(empty, beta[1], [0, 1, 2]) is None


@pytest.mark.parametrize("exponent", [-990, -400, 0, 400, 990])
def test_power_of_two_scales_give_the_same_bits(exponent):
    """The kernel divides the slice rows by their largest entry and equilibrates the others: exact for 2^k."""
    rng = np.random.default_rng(64)
    g = rng.normal(size=(20, 5, 6))
    beta = rng.uniform(-0.6, 0.6, size=(20, 6))
    for rows in ([0, 1, 2], [3, 4]):
        base, ok = biased_sections.biased_slice_max_norm(g, beta, rows=rows)
        scaled, ok2 = biased_sections.biased_slice_max_norm(np.ldexp(g, exponent), beta, rows=rows)
        assert ok.all() and ok2.all()
        np.testing.assert_array_equal(scaled, np.ldexp(base, exponent))


@pytest.mark.parametrize("factor", [1e-300, 1e300])
def test_extreme_decimal_scales_against_the_exact_maximum(factor):
    rng = np.random.default_rng(65)
    for _ in range(3):
        g = rng.normal(size=(5, 6)) * factor
        _check_sandwich(g, rng.uniform(-0.6, 0.6, size=6), [0, 1, 2])


def _slab_path(monkeypatch):
    """Make ``quantity_nodes.biased_slice_max`` hand every redundant point to the slab path (the old code)."""
    def nothing(generators, bias, *, rows):
        shape = np.shape(generators)[:-2]
        return np.full(shape, np.nan), np.zeros(shape, bool)
    monkeypatch.setattr(biased_sections, "biased_slice_max_norm", nothing)


def _twin_map(threads: bool, resolution: int = 24):
    preset = load_preset("twin_pantograph")
    mech = preset.mechanism
    loading = Loading(gravity=(0.0, 0.0, -9.80665), mounting="upright")
    return compute_map(mech, preset.grid.with_resolution(resolution), ["anisotropic_force", "anisotropic_moment"],
                       threads=threads, loading=loading)


def test_the_twin_gravity_map_is_the_slab_paths_and_the_same_with_threads(monkeypatch):
    """The Twin-Pantograph's default map under gravity: the slab path's values within ``VERTEX_TOL``.

    Relative ``VERTEX_TOL``: the section's values are those at ratings up to ``1 + VERTEX_TOL``
    times ``t`` (module doc); the slab path's slabs are exact to ``64 eps`` of their widths. A
    looser comparison than the exact one above, which is run on a sample of these poses below.
    """
    new = _twin_map(threads=False)
    again = _twin_map(threads=True)
    with monkeypatch.context() as patch:
        _slab_path(patch)
        old = _twin_map(threads=False)
    for name in ("anisotropic_force", "anisotropic_moment"):
        a, b = np.asarray(new.values[name]), np.asarray(old.values[name])
        np.testing.assert_array_equal(a, np.asarray(again.values[name]))
        assert np.array_equal(np.isfinite(a), np.isfinite(b)) and np.array_equal(np.isnan(a), np.isnan(b))
        both = np.isfinite(a)
        assert np.count_nonzero(both) > 100
        np.testing.assert_allclose(a[both], b[both], rtol=VERTEX_TOL, atol=0.0)


def test_twin_poses_against_the_exact_maximum():
    preset = load_preset("twin_pantograph")
    mech = preset.mechanism
    from metrics.quantities import evaluate
    pts = preset.grid.points(mech.task_names).reshape(-1, mech.task_dim)
    pts = pts[np.random.default_rng(66).choice(len(pts), 60, replace=False)]
    loading = Loading(gravity=(0.0, 0.0, -9.80665), mounting="upright")
    ev = evaluate(mech, pts, ["reference_forces", "torque_bias"], loading=loading)
    t = loading.torque_limits(mech)
    checked = 0
    for g, b in zip(ev.values["reference_forces"][ev.feasible], ev.values["torque_bias"][ev.feasible]):
        if not np.all(np.isfinite(g)):
            continue
        for rows in ([0, 1, 2], [3, 4]):
            _check_sandwich(g, b / t, rows)
        checked += 1
    assert checked >= 20


def test_the_summary_map_under_gravity_calls_no_slab_path_for_the_twin(monkeypatch):
    """Every Twin pose of a small default map is decided by the section path (the speed this is for)."""
    calls = []
    real = wrench_facets.slab_slice_vertex_max_norm
    monkeypatch.setattr(wrench_facets, "slab_slice_vertex_max_norm",
                        lambda *a, **k: calls.append(1) or real(*a, **k))
    preset = load_preset("twin_pantograph")
    mech = preset.mechanism
    compute_map(mech, preset.grid.with_resolution(16), summary_quantities(mech), threads=False,
                loading=Loading(gravity=(0.0, 0.0, -9.80665), mounting="upright"))
    assert not calls


def test_points_handed_back_get_the_slab_paths_values_and_the_rest_keep_theirs(monkeypatch):
    """A map where every other pose is handed back: those are the slab path's, the others the section's."""
    new = _twin_map(threads=False, resolution=16)
    real = biased_sections.biased_slice_max_norm

    def half(generators, bias, *, rows):
        out, decided = real(generators, bias, rows=rows)
        decided[::2] = False
        return out, decided
    with monkeypatch.context() as patch:
        _slab_path(patch)
        old = _twin_map(threads=False, resolution=16)
    monkeypatch.setattr(biased_sections, "biased_slice_max_norm", half)
    mixed = _twin_map(threads=False, resolution=16)
    for name in ("anisotropic_force", "anisotropic_moment"):
        a, b, c = (np.asarray(x.values[name]).ravel() for x in (new, old, mixed))
        from_new = np.isclose(c, a, rtol=0.0, atol=0.0) | (np.isnan(c) & np.isnan(a))
        from_old = np.isclose(c, b, rtol=0.0, atol=0.0) | (np.isnan(c) & np.isnan(b))
        assert np.all(from_new | from_old)
        assert np.any(from_old & ~from_new)


def test_a_weak_actuator_whose_determinants_square_below_the_float_range_is_still_exact():
    """One column 2^-600 of the others: ``det^2`` of its free sets underflows; the image is formed per coordinate."""
    rng = np.random.default_rng(67)
    for _ in range(4):
        g = rng.normal(size=(5, 6))
        g[:, 2] *= 2.0 ** -600
        _check_sandwich(g, rng.uniform(-0.6, 0.6, size=6), [0, 1, 2])


# -- the slab path (points handed back, the pose report's vertices) with parallel actuators ---------
#: A repeated column (actuators 3 and 4 in parallel, slice on the forces, 2 other rows): the slab
#: path gave 4.012 against the exact 4.448. Its largest vertex is where slabs 0, 7 and 11 of
#: ``packed_facets`` meet (condition 620 on the slice's rows); the Cramer products ``a_k . c_j / det``
#: of slab 7 with its own vertex came out 80 eps off its face against a fixed slack of 64 eps, so
#: the vertex was dropped (slab 8, the same slab from the parallel actuator, likewise).
PARALLEL_DROPPED = (
    [[-0.250909689886589, 0.5736104270965086, -0.7837235119093278, -0.922937659714148, -0.922937659714148,
      0.5695038082281503],
     [0.37476565216467417, -0.3664373169105649, 0.9367417536378219, -0.62744358681017, -0.62744358681017,
      -0.6941938225481445],
     [-2.0940803838257245, 0.1642509844687974, 0.6945195944129824, 2.661205947199466, 2.661205947199466,
      -0.35181544406498944],
     [-1.2897778309108172, 1.7877017834463647, 1.5659489314854476, -0.058973969630420287, -0.058973969630420287,
      -0.48986640228500844],
     [0.5411390095865136, -0.3368725502133775, 0.7700532474283642, 1.983027453146224, 1.983027453146224,
      -0.4123833713914764]],
    [-0.21159056769370638, 0.31642536888232264, 0.41349588175556506, 0.19177259960577409, -0.2859895938852482,
     -0.0151522185888614],
    [0, 1, 2])
#: The other side: a slack that bounds the products' rounding by ``|c_j|`` summed term by term for
#: the determinant's share as well (``delta / det`` times ``|rhs| sum |c_j|`` instead of ``|a_k . c_j|``)
#: let a vertex of slabs 4, 8, 17 through 1.73 outside slab 12: 13.89 against the exact 5.82.
PARALLEL_ADMITTED = (
    [[-1.5919587278877214, 0.214076606949003, 0.8331859412499848, 0.027106600969339305, 0.027106600969339305,
      2.1968172574653537],
     [-0.5090338929459353, -0.13681444280103053, -0.6610105549620744, 1.2120516975137086, 1.2120516975137086,
      -0.9033633073905117],
     [-0.4639155734313754, 0.30967922018023436, 0.34024083555369106, 0.9874232339741723, 0.9874232339741723,
      -0.7421562267788668],
     [-0.06890545653121055, -0.8775032043777127, -0.5418280318746636, -0.4849769927296599, -0.4849769927296599,
      0.8289187469078719]],
    [-0.1452605360880871, 0.0012600239525875079, 0.35198960613056884, -0.01714050253064625, 0.4700248797525005,
     0.43740396643769797],
    [1, 2, 3])


def _slab_paths(g, beta, rows):
    """The slab path's largest norm and the largest of its vertex list (the pose report's), as the graph builds them."""
    packed = wrench_facets.packed_facets(g)
    nu, h = packed[..., :-1], packed[..., -1]
    s = wrench_facets.slab_shifts(nu, -np.asarray(g) @ np.asarray(beta))
    value = float(wrench_facets.slab_slice_vertex_max_norm(nu, s - h, s + h, rows=rows))
    vertices = wrench_facets.slab_slice_vertices(nu, s - h, s + h, rows=rows)
    return value, float(np.max(np.linalg.norm(vertices, axis=1)))


def _parallel_cases():
    rng = np.random.default_rng(68)
    cases = [PARALLEL_DROPPED, PARALLEL_ADMITTED]
    for shape, rows in (((5, 6), [0, 1, 2]), ((4, 6), [1, 2, 3]), ((5, 6), [3, 4]), ((3, 5), [0, 1])):
        for factor in (1.0, -1.0, 2.0):                 # identical, opposite, a stronger parallel actuator
            g = rng.normal(size=shape)
            i, j = rng.choice(shape[1], 2, replace=False)
            g[:, j] = factor * g[:, i]
            cases.append((g.tolist(), rng.uniform(-0.6, 0.6, size=shape[1]).tolist(), rows))
    return cases


@pytest.mark.parametrize("g, beta, rows", _parallel_cases())
def test_the_slab_path_and_its_vertices_with_parallel_actuators_against_the_exact_maximum(g, beta, rows):
    """Both slab-path answers lie in the section path's sandwich, widened by ``VERTEX_TOL``.

    Tolerance: the slab path keeps every vertex of its slabs whose products' rounding it bounds
    (``kernels.wrench``) and a candidate within that bound plus ``64 eps`` of the slab widths; its
    slabs are the zonotope's to the rounding of ``packed_facets``' minors. Both are relative
    errors of order ``kappa eps`` (``kappa`` the conditioning of the slabs meeting at the vertex,
    620 in the planted case): far below ``VERTEX_TOL`` here, and far below the 10 % and 140 %
    the two planted cases were off. The same comparison, at ``VERTEX_TOL``, as the Twin map's above.
    """
    g, beta = np.array(g), np.array(beta)
    low = _exact_max2(g, beta, rows)
    high = _exact_max2(g, beta, rows, Fraction(1) + Fraction(VERTEX_TOL))
    lo, hi = _root(low) * (1 - VERTEX_TOL), _root(high) * (1 + VERTEX_TOL)
    value, listed = _slab_paths(g, beta, rows)
    assert lo <= value <= hi
    assert lo <= listed <= hi
    section, decided = biased_sections.biased_slice_max_norm(g, beta, rows=rows)
    assert decided
    np.testing.assert_allclose(value, float(section), rtol=VERTEX_TOL, atol=0.0)


def _exact_corner_max(a: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> Fraction:
    """``max |y|^2`` over the 8 corners ``a y = b`` (``b_j`` in ``{lo_j, hi_j}``) of three slabs, in rationals."""
    aq = [[Fraction(float(x)) for x in row] for row in a]
    det = _det(aq)
    best = Fraction(0)
    for b in itertools.product(*[(Fraction(float(lo[j])), Fraction(float(hi[j]))) for j in range(3)]):
        y = [_det([row[:c] + [b[r]] + row[c + 1:] for r, row in enumerate(aq)]) / det for c in range(3)]
        best = max(best, sum(v * v for v in y))
    return best


def test_an_ill_conditioned_parallelepiped_keeps_every_corner():
    """Three slabs (a square J under gravity), condition 1e2 to 1e6: every corner is a vertex of the slice.

    Before the products' rounding entered the slack, such corners failed their own slabs (0.7 %
    of random square cases, median condition 600; some lost all eight: an "empty" slice). With
    ``max(|lo|, |hi|) = 1`` and no power-of-two scale the kernel's inputs are these exactly, so the
    exact corners compare with its value up to the rounding of Cramer's rule (kernel module doc,
    ``u = eps / 2``): ``|y - y*| <= sum_j |b_j| ((d + 2) u |C_j| + |c_j| (delta / (|det| - delta) + 2 u)) / |det|``
    with ``delta = (d + 2) u sum_i |a_0i| C_0i``; twice that below, and ``d u |y|`` for the norm.
    """
    rng = np.random.default_rng(69)
    for _ in range(40):
        q1, _r = np.linalg.qr(rng.normal(size=(3, 3)))
        q2, _r = np.linalg.qr(rng.normal(size=(3, 3)))
        kappa = 10.0 ** rng.uniform(2, 6)
        a = q1 @ np.diag([0.9, 0.9 / np.sqrt(kappa), 0.9 / kappa]) @ q2      # entries below 1: no rescale
        hi = np.ones(3)
        lo = -rng.uniform(0.1, 1.0, size=3)
        flip = rng.random(3) < 0.5
        lo, hi = np.where(flip, -hi, lo), np.where(flip, -lo, hi)
        value = float(wrench_facets.slab_slice_vertex_max_norm(a, lo, hi, rows=[0, 1, 2]))
        listed = float(np.max(np.linalg.norm(wrench_facets.slab_slice_vertices(a, lo, hi, rows=[0, 1, 2]), axis=1)))
        exact = _root(_exact_corner_max(a, lo, hi))
        cof = np.array([np.cross(a[(j + 1) % 3], a[(j + 2) % 3]) for j in range(3)])
        c_abs = np.array([[abs(a[(j + 1) % 3, (i + 1) % 3] * a[(j + 2) % 3, (i + 2) % 3])
                           + abs(a[(j + 1) % 3, (i + 2) % 3] * a[(j + 2) % 3, (i + 1) % 3]) for i in range(3)]
                          for j in range(3)])
        det = abs(np.linalg.det(a))
        u = EPS / 2
        delta = 5 * u * np.sum(np.abs(a[0]) * c_abs[0])
        b = np.maximum(np.abs(lo), np.abs(hi))
        err = np.sum(b * (5 * u * np.linalg.norm(c_abs, axis=1)
                          + np.linalg.norm(cof, axis=1) * (delta / (det - delta) + 2 * u))) / det
        tol = 2 * err + 3 * u * exact
        assert abs(value - exact) <= tol
        assert abs(listed - exact) <= tol
