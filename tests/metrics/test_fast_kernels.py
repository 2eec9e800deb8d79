"""The speed-ups of issue 11 give the numbers of the kernels they replace, to derived tolerances.

References: the previous implementations, kept verbatim in ``reference_kernels.py``; brute force
over every vertex of the section with ``numpy.linalg.solve``; ``numpy.linalg.svd``; mpmath at 40
digits for minors and singular values. Inputs: random matrices, the shipped wrench devices'
generators at random feasible poses, and near-singular ones (nearly parallel generators).
"""
from __future__ import annotations

import itertools
import math
import threading

import mpmath
import numpy as np
import pytest
import reference_kernels as ref

from metrics import linalg, wrench_facets, wrench_slices, wrenches
from metrics.quantities import evaluate
from resources import load_preset

EPS = np.finfo(float).eps
DPS = 40


def _device_generators(key, count, seed):
    """``A diag(t)`` (count, m, n) at random feasible grid points of preset ``key``."""
    preset = load_preset(key)
    mech = preset.mechanism
    pts = preset.grid.points(mech.task_names)
    rng = np.random.default_rng(seed)
    ev = evaluate(mech, pts[rng.choice(len(pts), min(len(pts), 10 * count), replace=False)], ["reference_forces"])
    gens = ev.values["reference_forces"][ev.feasible]
    assert len(gens) >= count
    return mech, gens[:count]


def _near_singular(rng, count, m, n, gap):
    """Random (count, m, n) generators whose columns 0 and 1 are parallel up to a relative ``gap``."""
    g = rng.normal(size=(count, m, n))
    g[:, :, 1] = 2.0 * g[:, :, 0] + gap * rng.normal(size=(count, m))
    return g


# -- minors ------------------------------------------------------------------------------------
@pytest.mark.parametrize("shape", [(1, 4), (3, 6), (5, 6), (6, 6), (6, 9)])
def test_minors_equal_mpmath_determinants(shape):
    m, n = shape
    rng = np.random.default_rng(m * 10 + n)
    mats = rng.normal(size=(3, m, n))
    mats[0] *= 1e-3                                   # scale must not matter
    size = m - 1 if m > 1 else 1
    row_sets = [tuple(r for r in range(m) if r != i) for i in range(m)] if m > 1 else [(0,)]
    got = linalg.minors(linalg.components(mats), row_sets)
    assert got.shape == (len(row_sets), math.comb(n, size), 3)
    with mpmath.workdps(DPS):
        for b, mat in enumerate(mats):
            for i, rows in enumerate(row_sets):
                for j, cols in enumerate(itertools.combinations(range(n), size)):
                    sub = mat[np.ix_(rows, cols)]
                    exact = float(mpmath.det(mpmath.matrix(sub.tolist())))
                    # Laplace expansion: s! products of s factors summed, each rounding at most
                    # gamma_(s + s!) relative of the sum of |products| <= prod of row 1-norms.
                    bound = (size + math.factorial(size)) * EPS * np.prod(np.sum(np.abs(sub), axis=1))
                    assert abs(got[i, j, b] - exact) <= bound


def test_minors_reject_unsorted_or_mixed_row_sets():
    a = linalg.components(np.ones((2, 4, 4)))
    with pytest.raises(ValueError, match="row_sets"):
        linalg.minors(a, [(1, 0)])
    with pytest.raises(ValueError, match="row_sets"):
        linalg.minors(a, [(0, 1), (2,)])



@pytest.mark.parametrize("shape, row_sets", [((5, 6), [(3, 4)]), ((5, 6), [(0, 3, 4), (1, 3, 4), (2, 3, 4)]),
                                             ((5, 6), [(0, 1, 2, 3), (0, 1, 2, 4)]), ((6, 9), [(0, 1, 2)]),
                                             ((2, 4), [(0, 1)]), ((1, 4), [(0,)])])
def test_minors_in_place_are_the_gathered_ones_bit_for_bit(shape, row_sets):
    """Minor by minor into buffers: the same products summed in the same order as the gathered
    kernel of the first speed-up (``reference_kernels.minors``), with any batch shape or none."""
    rng = np.random.default_rng(sum(shape))
    mats = rng.normal(size=(7, 3) + shape)
    mats[0, 0, 0] = np.nan
    mats[1, 1] *= 1e-200
    a = linalg.components(mats)
    np.testing.assert_array_equal(linalg.minors(a, row_sets), ref.minors(a, row_sets))
    np.testing.assert_array_equal(linalg.minors(a[..., 2, 1], row_sets), ref.minors(a[..., 2, 1], row_sets))

# -- slice_max_norm ----------------------------------------------------------------------------
#: Old and new both solve the same r x r systems by Cramer's rule on the same equilibrated G_O;
#: they differ in rounding only, by delta ~ 10 eps kappa relative per candidate (kappa the
#: condition of G_O[:, F], below 1e6 for every input here, so delta < 3e-9). A kept candidate
#: is in the box enlarged by VERTEX_TOL, and every true vertex is kept, so each result lies in
#: [true (1 - delta), true (1 + VERTEX_TOL)(1 + delta)]: they agree to VERTEX_TOL + 2 delta.
SLICE_RTOL = wrench_slices.VERTEX_TOL + 2 * 10 * EPS * 1e6


def _slice_cases():
    rng = np.random.default_rng(21)
    cases = []
    for m, n in ((5, 6), (6, 6), (6, 7), (6, 9), (4, 6), (3, 5)):
        cases.append((f"random-{m}x{n}", rng.normal(size=(200, m, n))))
        cases.append((f"near-singular-{m}x{n}", _near_singular(rng, 100, m, n, 1e-6)))
    return cases


@pytest.mark.parametrize("name, gens", _slice_cases(), ids=[c[0] for c in _slice_cases()])
def test_slice_max_norm_equals_the_previous_kernel(name, gens):
    m = gens.shape[-2]
    for d in range(max(1, m - 3), m):
        for rows in itertools.combinations(range(m), d):
            new = wrench_slices.slice_max_norm(gens, rows=rows)
            old = ref.slice_max_norm(gens, rows=rows)
            np.testing.assert_array_equal(np.isnan(new), np.isnan(old))
            ok = ~np.isnan(old)
            np.testing.assert_allclose(new[ok], old[ok], rtol=SLICE_RTOL, atol=0)


@pytest.mark.parametrize("key", ["twin_pantograph", "twin_pantograph_prototype", "stewart_platform",
                                 "inoue_platform"])
def test_slice_max_norm_of_the_shipped_devices_equals_the_previous_kernel(key):
    mech, gens = _device_generators(key, 300, seed=5)
    for rows in (wrenches.force_rows(mech), wrenches.moment_rows(mech)):
        new = wrench_slices.slice_max_norm(gens, rows=rows)
        np.testing.assert_allclose(new, ref.slice_max_norm(gens, rows=rows), rtol=SLICE_RTOL, atol=0)


def test_slice_max_norm_equals_brute_force_over_every_vertex_of_the_section():
    """Independent of both kernels: every vertex of Q by numpy.linalg.solve (LU), kept if in the box."""
    rng = np.random.default_rng(3)
    for m, n, rows in ((5, 6, (0, 1, 2)), (5, 6, (3, 4)), (6, 9, (0, 1, 2)), (6, 6, (3, 4, 5))):
        gens = np.concatenate([rng.normal(size=(6, m, n)), _near_singular(rng, 2, m, n, 1e-5)])
        others = [i for i in range(m) if i not in rows]
        r = len(others)
        got = wrench_slices.slice_max_norm(gens, rows=rows)
        for g, value in zip(gens, got):
            best = -1.0
            for free in itertools.combinations(range(n), r):
                fixed = [u for u in range(n) if u not in free]
                block = g[np.ix_(others, free)]
                if abs(np.linalg.det(block)) < 1e-14:
                    continue
                for signs in itertools.product((1.0, -1.0), repeat=n - r):
                    s = np.zeros(n)
                    s[fixed] = signs
                    s[list(free)] = np.linalg.solve(block, -g[np.ix_(others, fixed)] @ np.array(signs))
                    if np.all(np.abs(s) <= 1 + wrench_slices.VERTEX_TOL):
                        best = max(best, float(np.linalg.norm(g[list(rows)] @ s)))
            # The same candidate set, solved by LU instead of Cramer's rule: SLICE_RTOL as above.
            assert value == pytest.approx(best, rel=SLICE_RTOL)


def test_slice_max_norm_labels_bad_and_degenerate_generators_nan():
    rng = np.random.default_rng(8)
    gens = rng.normal(size=(5, 5, 6))
    gens[0, 1, 2] = np.nan
    gens[1, 0, 0] = np.inf
    gens[2, 3:] = 0.0                                  # G_O = 0: no vertex of the section
    gens[3, 4] = gens[3, 3]                            # G_O of rank 1 < r = 2
    out = wrench_slices.slice_max_norm(gens, rows=(0, 1, 2))
    assert np.all(np.isnan(out[:4])) and np.isfinite(out[4])
    old = ref.slice_max_norm(gens, rows=(0, 1, 2))
    np.testing.assert_array_equal(np.isnan(out), np.isnan(old))


def test_slice_max_norm_parts_and_batch_axes_do_not_change_the_result():
    rng = np.random.default_rng(9)
    gens = rng.normal(size=(1000, 5, 6))
    whole = wrench_slices.slice_max_norm(gens, rows=(0, 1, 2))
    parts = [wrench_slices.slice_max_norm(gens[i:i + 7], rows=(0, 1, 2)) for i in range(0, 1000, 7)]
    np.testing.assert_array_equal(np.concatenate(parts), whole)
    np.testing.assert_array_equal(wrench_slices.slice_max_norm(gens[:, None], rows=(0, 1, 2))[:, 0], whole)


def test_slice_vertices_reach_the_largest_norm_of_the_previous_kernel():
    rng = np.random.default_rng(10)
    for g in rng.normal(size=(5, 5, 6)):
        for rows in ((0, 1, 2), (3, 4)):
            v = wrench_slices.slice_vertices(g, rows=rows)
            old = float(ref.slice_max_norm(g, rows=rows))
            assert np.max(np.linalg.norm(v, axis=1)) == pytest.approx(old, rel=SLICE_RTOL)


# -- the second speed-up: free sets with det 0 skipped, one gather of a free set's coefficients ------
def _structured_cases():
    """Random, near-singular and Twin-Pantograph-like generators (exact zeros: some ``det G_O[:, F]``
    vanish at every point), with non-finite and all-zero members."""
    rng = np.random.default_rng(31)
    cases = []
    for m, n in ((5, 6), (6, 6), (6, 7), (4, 6), (3, 5), (2, 4)):
        gens = np.concatenate([rng.normal(size=(150, m, n)), _near_singular(rng, 50, m, n, 1e-7)])
        gens[::7, 0, 0] = 0.0
        gens[::5, -1, :2] = 0.0
        gens[3, 1, 2] = np.nan
        gens[4] = 0.0
        cases.append((f"{m}x{n}", gens))
    zeros = rng.normal(size=(200, 5, 6))
    zeros[:, 0, [0, 3]] = 0.0                      # the Twin-Pantograph's waist columns: no x force,
    zeros[:, 4, [0, 3]] = 0.0                      # no moment about the last axis
    cases.append(("waist-zeros-5x6", zeros))
    return cases


@pytest.mark.parametrize("name, gens", _structured_cases(), ids=[c[0] for c in _structured_cases()])
def test_slice_max_norm_is_the_shared_minors_kernel_bit_for_bit(name, gens):
    """The same operations in the same order on every free set not skipped, and a skipped one
    (``det G_O[:, F] = 0`` at every point of a block) has no candidate inside: the same numbers."""
    m = gens.shape[-2]
    for d in range(max(1, m - 3), m):
        for rows in itertools.combinations(range(m), d):
            with np.errstate(all="ignore"):
                old = ref.slice_max_norm_minors(gens, rows=rows)
            np.testing.assert_array_equal(wrench_slices.slice_max_norm(gens, rows=rows), old)


@pytest.mark.parametrize("key", ["twin_pantograph", "twin_pantograph_prototype", "stewart_platform",
                                 "inoue_platform"])
def test_slice_max_norm_of_the_shipped_devices_is_the_shared_minors_kernel_bit_for_bit(key):
    mech, gens = _device_generators(key, 400, seed=15)
    for rows in (wrenches.force_rows(mech), wrenches.moment_rows(mech)):
        np.testing.assert_array_equal(wrench_slices.slice_max_norm(gens, rows=rows),
                                      ref.slice_max_norm_minors(gens, rows=rows))


def test_slice_max_norm_of_a_batch_is_one_at_a_time():
    rng = np.random.default_rng(32)
    gens = _structured_cases()[-1][1][:40]
    gens[5] = _near_singular(rng, 1, 5, 6, 1e-9)[0]
    for rows in ((0, 1, 2), (3, 4)):
        batch = wrench_slices.slice_max_norm(gens, rows=rows)
        single = np.array([float(wrench_slices.slice_max_norm(g, rows=rows)) for g in gens])
        np.testing.assert_array_equal(batch, single)


# -- packed facets -----------------------------------------------------------------------------------
def _offset_bound(gens, normals):
    """Derived bound on |h_new - h_old|: the normals are the same numbers, each offset sums the same
    products ``|nu . a_u| |g_u|``, maybe in another order (einsum): at most ``gamma_m`` for each dot
    and ``gamma_n`` for the sum over ``u``, in both kernels, of ``sum_u sum_i |nu_i| |g_iu|``."""
    m, n = gens.shape[-2:]
    scale = np.einsum("...ki,...iu->...k", np.abs(normals), np.abs(gens))
    return 2 * (m + n + 2) * EPS * scale


def _facet_cases():
    rng = np.random.default_rng(33)
    cases = [(f"random-{m}x{n}", rng.normal(size=(60, m, n)))
             for m, n in ((5, 6), (6, 6), (6, 9), (3, 5), (2, 2), (1, 4))]
    cases += [(f"near-singular-{m}x{n}", _near_singular(rng, 60, m, n, 1e-9)) for m, n in ((5, 6), (6, 7))]
    scaled = rng.normal(size=(70, 5, 6)) * 10.0 ** rng.choice([-300.0, -100.0, 0.0, 100.0, 300.0], size=(70, 1, 6))
    scaled[0, 2, 3] = np.inf
    scaled[1, 0, 0] = np.nan
    scaled[2] = 0.0
    scaled[3, :, 4] = 0.0                               # a zero generator
    cases.append(("scales-and-bad-5x6", scaled))
    return cases


@pytest.mark.parametrize("name, gens", _facet_cases(), ids=[c[0] for c in _facet_cases()])
def test_packed_facets_equal_the_previous_kernel(name, gens):
    packed = wrench_facets.packed_facets(gens)
    with np.errstate(all="ignore"):
        nu, h = ref.facets(gens)
    np.testing.assert_array_equal(packed[..., :-1], nu)            # the same Laplace expansions
    np.testing.assert_array_equal(np.isnan(packed[..., -1]), np.isnan(h))
    ok = ~np.isnan(h)
    with np.errstate(all="ignore"):
        bound = _offset_bound(np.where(np.isfinite(gens), gens, 0.0), np.nan_to_num(nu))
    assert np.all(np.abs(packed[..., -1] - h)[ok] <= bound[ok])


@pytest.mark.parametrize("key", ["twin_pantograph", "twin_pantograph_prototype", "stewart_platform"])
def test_packed_facets_of_the_shipped_devices_equal_the_previous_kernel(key):
    _, gens = _device_generators(key, 300, seed=16)
    packed = wrench_facets.packed_facets(gens)
    nu, h = ref.facets(gens)
    np.testing.assert_array_equal(packed[..., :-1], nu)
    assert np.all(np.abs(packed[..., -1] - h) <= _offset_bound(gens, nu))


def test_packed_facets_of_a_batch_are_one_at_a_time_and_blocks_change_nothing(monkeypatch):
    gens = _facet_cases()[-1][1]
    whole = wrench_facets.packed_facets(gens)
    single = np.array([wrench_facets.packed_facets(g) for g in gens])
    np.testing.assert_array_equal(single, whole)
    np.testing.assert_array_equal(wrench_facets.packed_facets(gens.reshape(10, 7, 5, 6)).reshape(whole.shape), whole)
    monkeypatch.setattr(wrench_facets, "FACET_BLOCK", 3)        # the numpy reference's blocks
    with np.errstate(all="ignore"):
        np.testing.assert_array_equal(wrench_facets._packed_facets_reference(gens), whole)
    nu, h = wrench_facets.facets(gens)
    np.testing.assert_array_equal(nu, whole[..., :-1])
    np.testing.assert_array_equal(h, whole[..., -1])
    assert wrench_facets.facets(gens[0])[0].shape == (math.comb(6, 4), 5)


@pytest.mark.parametrize("name, gens", _facet_cases(), ids=[c[0] for c in _facet_cases()])
def test_packed_facets_compiled_are_the_numpy_reference_bit_for_bit(name, gens):
    """``kernels.facets`` runs ``_packed_facets_reference``'s operations in its order (no
    transcendental function, no reordered sum): equal, nan where G is not finite, at every scale."""
    with np.errstate(all="ignore"):
        want = wrench_facets._packed_facets_reference(gens)
    np.testing.assert_array_equal(wrench_facets.packed_facets(gens), want)


@pytest.mark.parametrize("key", ["twin_pantograph", "twin_pantograph_prototype", "stewart_platform"])
def test_packed_facets_and_radii_of_the_shipped_devices_are_the_numpy_reference(key):
    mech, gens = _device_generators(key, 300, seed=19)
    packed = wrench_facets.packed_facets(gens)
    np.testing.assert_array_equal(packed, wrench_facets._packed_facets_reference(gens))
    rng = np.random.default_rng(19)
    shifts = rng.normal(size=packed.shape[:-1]) * packed[..., -1]      # a biased set: some origins outside
    for rows in (wrenches.force_rows(mech), wrenches.moment_rows(mech)):
        for s in (None, shifts):
            got = wrench_facets.slice_inscribed_radius(packed[..., :-1], packed[..., -1], rows=rows, shifts=s)
            h = packed[..., -1] if s is None else packed[..., -1] - np.abs(s)
            np.testing.assert_array_equal(got, wrench_facets._inscribed_radius(packed[..., :-1], h, list(rows),
                                                                                s is not None))


def test_packed_facets_reject_fewer_columns_than_rows():
    with pytest.raises(ValueError, match="generators"):
        wrench_facets.packed_facets(np.ones((3, 4, 3)))


# -- singular values from the Gram matrix --------------------------------------------------------
def _gram_bound(mats, sv_ref):
    """Derived bound on |sigma_i - reference| (see ``linalg._sv_gram``) plus LAPACK's own error."""
    m, n = mats.shape[-2:]
    kappa = sv_ref[:, :1] / sv_ref[:, -1:]
    gram = (max(m, n) + 6) * EPS * np.minimum(kappa, linalg.FAST_COND_LIMIT) ** 2 / 2
    lapack = 4 * max(m, n) * EPS * kappa                 # gesdd: about eps sigma_1 absolute each
    return (gram + lapack) * sv_ref


@pytest.mark.parametrize("shape", [(5, 6), (6, 6), (6, 5), (4, 4), (7, 7), (2, 3), (1, 4)])
def test_gram_singular_values_equal_lapack_within_the_derived_bound(shape):
    rng = np.random.default_rng(sum(shape))
    mats = rng.normal(size=(3000, *shape))
    mats[::3] *= 1e-30                                   # far from unit scale, still inside SAFE_SCALE
    got = linalg.singular_values(mats)
    want = np.linalg.svd(mats, compute_uv=False)
    assert np.all(np.abs(got - want) <= _gram_bound(mats, want))


def test_gram_singular_values_hand_hard_matrices_to_lapack_bit_for_bit():
    rng = np.random.default_rng(4)
    mats = _near_singular(rng, 50, 6, 6, 1e-7)          # kappa ~ 1e7 > FAST_COND_LIMIT
    mats[0] = 0.0                                        # exactly singular
    mats[1] *= 1e200                                     # outside SAFE_SCALE
    got = linalg.singular_values(mats)
    np.testing.assert_array_equal(got, np.linalg.svd(mats, compute_uv=False))


def test_gram_singular_values_against_mpmath():
    rng = np.random.default_rng(6)
    mats = rng.normal(size=(6, 5, 6))
    got = linalg.singular_values(mats)
    with mpmath.workdps(DPS):
        exact = np.array([[float(v) for v in mpmath.svd_r(mpmath.matrix(a.tolist()), compute_uv=False)]
                          for a in mats])
    exact = -np.sort(-exact, axis=1)
    assert np.all(np.abs(got - exact) <= _gram_bound(mats, exact))


def test_singular_values_label_non_finite_matrices_inf():
    mats = np.ones((2, 6, 6))
    mats[0, 2, 2] = np.nan
    sv = linalg.singular_values(mats)
    assert np.all(np.isinf(sv[0])) and np.all(np.isfinite(sv[1]))


def test_scaled_condition_number_of_the_shipped_devices_equals_lapack():
    for key in ("twin_pantograph", "stewart_platform"):
        mech = load_preset(key).mechanism
        pts = load_preset(key).grid.points(mech.task_names)[::97]
        ev = evaluate(mech, pts, ["jacobian", "condition_number"])
        jac = ev.values["jacobian"][ev.feasible]
        scaled = jac * wrenches.task_row_scale(mech)[:, None]
        sv = np.linalg.svd(scaled, compute_uv=False)
        kappa = sv[:, 0] / sv[:, -1]
        rel = 2 * _gram_bound(scaled, sv)[:, -1] / sv[:, -1]        # both ends' relative errors
        got = ev.values["condition_number"][ev.feasible]
        assert np.all(np.abs(got - kappa) <= rel * kappa)


# -- the Twin-Pantograph's K, computed once for jacobian and force_map ------------------------------
def test_twin_pantograph_k_memo_returns_the_recomputed_numbers():
    mech = load_preset("twin_pantograph").mechanism
    rng = np.random.default_rng(2)
    x = mech.home_pose() + rng.uniform(-1, 1, (50, 5)) * np.array([0.02, 0.02, 0.02, 0.1, 0.1])
    q, ok = mech.inverse(x)
    x, q = x[ok], q[ok]
    first = mech.inverse_jacobian(q, x)
    first[0] = 123.0                                     # a caller writing into its result ...
    again = mech.inverse_jacobian(q, x)                  # ... does not change the next one
    other = mech.replace(pen_length=mech.params.pen_length * 1.01)
    fresh = other.inverse_jacobian(q, x)                 # other parameters: recomputed
    # A third model with the first's parameters, computed in another thread (its own memo).
    box = {}
    thread = threading.Thread(target=lambda: box.setdefault("k", mech.replace().inverse_jacobian(q, x)))
    thread.start()
    thread.join()
    np.testing.assert_array_equal(again, box["k"])
    assert not np.array_equal(fresh, again)
    np.testing.assert_array_equal(again[1:], first[1:])
    np.testing.assert_array_equal(mech.force_map(q, x), np.swapaxes(box["k"], -1, -2))


# -- inscribed radius of a slice -------------------------------------------------------------------
def test_slice_inscribed_radius_equals_the_previous_kernel_at_every_scale():
    mech, gens = _device_generators("twin_pantograph", 200, seed=12)
    nu, h = wrench_facets.facets(gens)
    rng = np.random.default_rng(12)
    nu = nu * 10.0 ** rng.choice([-300.0, -200.0, -100.0, 0.0, 100.0, 200.0, 300.0], size=nu.shape[:-1])[..., None]
    nu[0, 3] = 0.0                                     # a slab that bounds nothing
    nu[1, 2, 0] = np.inf                               # a direct singularity: bounded at 0
    nu[2, 5, 1] = np.nan
    h = np.abs(h)
    for rows in (wrenches.force_rows(mech), wrenches.moment_rows(mech)):
        new = wrench_facets.slice_inscribed_radius(nu, h, rows=rows)
        with np.errstate(over="ignore"):              # the old kernel squared the inf entry
            old = ref.slice_inscribed_radius(nu, h, rows=rows)
        np.testing.assert_array_equal(np.isnan(new), np.isnan(old))
        # Both are h / |nu[rows]|: sums of d squares (d + 1 roundings), a square root and a
        # division, the old one after an exact-up-to-rounding scaling: (2 (d + 2) + 1) eps apart.
        ok = ~np.isnan(old)
        np.testing.assert_allclose(new[ok], old[ok], rtol=(2 * (len(rows) + 2) + 1) * EPS, atol=0)


# -- inverse of the Twin-Pantograph's K^T K --------------------------------------------------------
def test_spd_inverse_equals_lapack_and_mpmath():
    from kinematics.rotations import batched_inverse, spd_inverse
    rng = np.random.default_rng(13)
    k = rng.normal(size=(2000, 6, 5)) * np.logspace(0, -2, 5)             # kappa(K^T K) up to ~1e5
    gram = np.swapaxes(k, -1, -2) @ k
    got, ok = spd_inverse(gram)
    want, ok_lapack = batched_inverse(gram)
    assert ok.all() and ok_lapack.all()
    kappa = np.linalg.cond(gram)[:, None, None]
    # Both backward stable: each within ~k^2 eps kappa |M^-1| of the truth (k = 5).
    scale = np.max(np.abs(want), axis=(-2, -1), keepdims=True)
    assert np.all(np.abs(got - want) <= 2 * 25 * EPS * kappa * scale)
    with mpmath.workdps(DPS):
        for m_, g_ in zip(gram[:5], got[:5]):
            exact = np.array((mpmath.matrix(m_.tolist()) ** -1).tolist(), dtype=float)
            assert np.all(np.abs(g_ - exact) <= 25 * EPS * np.linalg.cond(m_) * np.max(np.abs(exact)))


def test_spd_inverse_hands_singular_and_bad_matrices_to_batched_inverse():
    from kinematics.rotations import batched_inverse, spd_inverse
    rng = np.random.default_rng(14)
    k = rng.normal(size=(6, 6, 5))
    k[:, :, 1] = k[:, :, 0] * (1 + 1e-9)                                  # kappa(K^T K) ~ 1e19
    gram = np.swapaxes(k, -1, -2) @ k
    gram[0] = 0.0
    gram[1, 2, 2] = np.nan
    gram[2] = -np.eye(5)                                                  # not positive definite
    got, ok = spd_inverse(gram)
    want, ok_lapack = batched_inverse(gram)
    np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(ok, ok_lapack)


def test_slice_inscribed_radius_blocks_and_single_poses_change_nothing():
    """The compiled radius is numpy's ``_inscribed_radius`` bit for bit (the same operations; a point with
    a normal out of the plain sum's range handed to it), whole, in batch axes and one pose at a time,
    with the special normals (zero, inf, nan, far from unit scale) inside."""
    mech, gens = _device_generators("twin_pantograph", 120, seed=17)
    nu, h = wrench_facets.facets(gens)
    nu = nu * 10.0 ** np.random.default_rng(17).choice([-300.0, 0.0, 300.0], size=nu.shape[:-1])[..., None]
    nu[0, 3] = 0.0
    nu[1, 2, 0] = np.inf
    nu[2, 5, 1] = np.nan
    nu[3] = 0.0                                        # every normal zero: nan
    for rows in (wrenches.force_rows(mech), wrenches.moment_rows(mech)):
        whole = wrench_facets.slice_inscribed_radius(nu, h, rows=rows)
        with np.errstate(all="ignore"):
            np.testing.assert_array_equal(wrench_facets._inscribed_radius(nu, h, list(rows)), whole)
        np.testing.assert_array_equal(wrench_facets.slice_inscribed_radius(nu.reshape(12, 10, *nu.shape[1:]),
                                                                      h.reshape(12, 10, -1), rows=rows).ravel(), whole)
        single = [float(wrench_facets.slice_inscribed_radius(a, b, rows=rows)) for a, b in zip(nu, h)]
        np.testing.assert_array_equal(single, whole)
    assert np.isnan(whole[3])


def test_load_pieces_builds_every_facet_kernel_version_a_twin_map_uses():
    """``runtime.load_pieces`` loads the slab and radius kernels in the layouts a map passes them
    (a view of the packed slabs, a matmul's contiguous normals): the map's chunks then build nothing."""
    from metrics import runtime
    from metrics.kernels import facets
    from metrics.quantities import summary_quantities
    from metrics.workspace import compute_map

    runtime.load_pieces()
    preset = load_preset("twin_pantograph")
    mech = preset.mechanism
    builds = (len(facets.packed_facets_points.signatures), len(facets.inscribed_radius_points.signatures))
    compute_map(mech, preset.grid.with_resolution(9), summary_quantities(mech), keep=False)
    assert (len(facets.packed_facets_points.signatures), len(facets.inscribed_radius_points.signatures)) == builds
