"""Force and conditioning metrics against independent computations and textbook facts.

linalg (singular values, inverse transposes), conditioning, ellipsoids, polytopes
(isotropic / anisotropic force, bottleneck, clamp, faces) and zonotopes. Headless: numpy
and scipy only; every random draw uses a fixed seed.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import ConvexHull
from scipy.stats import special_ortho_group

from metrics import (
    anisotropy,
    bottleneck,
    columns,
    conditioning,
    ellipsoids,
    isotropy,
    linalg,
    parallelepiped,
    torque_box,
    zonotopes,
)


def _random_jacobians(rng, count, m, n, cond_max=20.0):
    """Random matrices U diag(s) V^T with log-uniform singular values and condition <= cond_max."""
    k = min(m, n)
    u = np.linalg.qr(rng.normal(size=(count, m, m)))[0]
    v = np.linalg.qr(rng.normal(size=(count, n, n)))[0]
    logs = rng.uniform(0.0, np.log(cond_max), size=(count, k))
    scale = rng.uniform(0.02, 0.5, size=(count, 1))           # m/rad, haptic-device sized
    s = scale * np.exp(logs - logs.max(axis=-1, keepdims=True))
    s_mat = np.zeros((count, m, n))
    idx = np.arange(k)
    s_mat[:, idx, idx] = s
    return u @ s_mat @ np.swapaxes(v, -1, -2)


def _random_torques(rng, count, n):
    return rng.uniform(0.1, 2.0, size=(count, n))


def _unit_directions(rng, count, m):
    d = rng.normal(size=(count, m))
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


# -- known values ---------------------------------------------------------------------------
@pytest.mark.parametrize("n", [2, 3])
def test_isotropic_jacobian_known_values(n):
    rng = np.random.default_rng(1)
    c, t = 0.07, 0.4
    q = special_ortho_group.rvs(n, random_state=2)
    jac = c * q
    tl = np.full(n, t)
    assert conditioning.condition_number(jac) == pytest.approx(1.0, abs=1e-12)
    assert conditioning.manipulability(jac) == pytest.approx(c ** n, rel=1e-12)
    np.testing.assert_allclose(linalg.singular_values(jac), c, rtol=1e-12)
    assert isotropy.isotropic_force(jac, torque_limits=tl) == pytest.approx(t / c, rel=1e-14)
    assert anisotropy.anisotropic_force(jac, torque_limits=tl) == pytest.approx(np.sqrt(n) * t / c, rel=1e-12)
    ell = ellipsoids.force_ellipsoid(jac, torque_limits=tl)
    np.testing.assert_allclose(ell.radii, t / c, rtol=1e-12)
    vel = ellipsoids.velocity_ellipsoid(jac, joint_speed_limits=np.full(n, 3.0))
    np.testing.assert_allclose(vel.radii, 3.0 * c, rtol=1e-12)
    # Reference forces are orthogonal, each of length t / c.
    ref = parallelepiped.reference_forces(jac, torque_limits=tl)
    np.testing.assert_allclose(ref.T @ ref, (t / c) ** 2 * np.eye(n), rtol=0, atol=1e-9)
    # A desired force beyond the isotropic radius is clamped onto it.
    f = rng.normal(size=n)
    f *= 3 * t / c / np.linalg.norm(f)
    np.testing.assert_allclose(np.linalg.norm(isotropy.clamp_force(f, t / c)), t / c, rtol=1e-14)


def test_diagonal_jacobian_known_values():
    """J = diag(a, b, c): facets at t_u / a_u, vertices (+-t1/a, +-t2/b, +-t3/c)."""
    jac = np.diag([0.1, 0.2, 0.05])
    t = np.array([0.5, 0.6, 0.1])
    assert isotropy.isotropic_force(jac, torque_limits=t) == pytest.approx(min(5.0, 3.0, 2.0))
    assert bottleneck.bottleneck_actuator(jac, torque_limits=t) == 2
    assert anisotropy.anisotropic_force(jac, torque_limits=t) == pytest.approx(np.sqrt(25 + 9 + 4), rel=1e-14)
    assert conditioning.condition_number(jac) == pytest.approx(4.0, rel=1e-14)
    assert conditioning.manipulability(jac) == pytest.approx(0.001, rel=1e-14)
    np.testing.assert_allclose(isotropy.facet_distances(jac, torque_limits=t), [5.0, 3.0, 2.0], rtol=1e-15)
    ell = ellipsoids.force_ellipsoid(jac, torque_limits=t)
    np.testing.assert_allclose(ell.radii, [5.0, 3.0, 2.0], rtol=1e-14)
    np.testing.assert_allclose(np.abs(ell.axes), np.eye(3), atol=1e-14)


# -- singular values, condition number, manipulability ---------------------------------------
@pytest.mark.parametrize("shape", [(2, 2), (3, 3), (3, 4), (6, 6), (4, 3)])
def test_singular_values_match_lapack(shape):
    rng = np.random.default_rng(10)
    m, n = shape
    # Plain Gaussian matrices (conditions spread over decades) and scaled, well-conditioned ones.
    batch = np.concatenate([rng.normal(size=(300, m, n)), _random_jacobians(rng, 300, m, n, 50.0)])
    sv = linalg.singular_values(batch)
    ref = np.linalg.svd(batch, compute_uv=False)
    assert sv.shape == (600, min(m, n))
    assert np.all(np.diff(sv, axis=-1) <= 0)
    kappa = ref[:, :1] / ref[:, -1:]
    # Closed forms lose up to ~10 eps kappa^2 relative below FAST_COND_LIMIT, LAPACK eps kappa.
    tol = 1e-13 * np.minimum(kappa, linalg.FAST_COND_LIMIT) ** 2 + 1e-13 * kappa
    err = np.abs(sv - ref) / (tol * ref[:, :1])
    assert err.max() <= 1.0, f"singular value error {err.max():.2f} x the tolerance"
    np.testing.assert_allclose(sv[:, 0], ref[:, 0], rtol=1e-12)
    # Nested batch shapes give the same values.
    nested = linalg.singular_values(batch.reshape(20, 30, m, n))
    assert nested.shape == (20, 30, min(m, n))
    np.testing.assert_array_equal(nested.reshape(600, -1), sv)


def test_singular_values_of_nonfinite_matrices_are_inf():
    jac = np.array([[[1.0, 0.0], [0.0, 2.0]], [[np.inf, 0.0], [0.0, 1.0]], [[np.nan, 1.0], [1.0, 1.0]]])
    sv = linalg.singular_values(jac)
    np.testing.assert_allclose(sv[0], [2.0, 1.0])
    assert np.all(np.isinf(sv[1:]))
    np.testing.assert_array_equal(conditioning.condition_number(jac), [2.0, np.inf, np.inf])


@pytest.mark.parametrize("shape", [(2, 2), (3, 3), (6, 6), (2, 3), (3, 4)])
def test_condition_number_and_manipulability(shape):
    rng = np.random.default_rng(11)
    m, n = shape
    jac = np.concatenate([_random_jacobians(rng, 200, m, n, 1e3), rng.normal(size=(200, m, n))])
    ref = np.linalg.svd(jac, compute_uv=False)
    cond = conditioning.condition_number(jac)
    np.testing.assert_allclose(cond, ref[:, 0] / ref[:, -1], rtol=1e-9)
    assert np.all(cond >= 1.0)
    manip = conditioning.manipulability(jac)
    np.testing.assert_allclose(manip, np.prod(ref, axis=-1), rtol=1e-9)
    expected = np.abs(np.linalg.det(jac)) if m == n else np.sqrt(np.linalg.det(jac @ np.swapaxes(jac, -1, -2)))
    np.testing.assert_allclose(manip, expected, rtol=1e-8)
    # Reusing singular values gives identical results.
    sv = linalg.singular_values(jac)
    np.testing.assert_array_equal(conditioning.condition_number(sv=sv), cond)
    np.testing.assert_array_equal(conditioning.manipulability(sv=sv), manip)


def test_condition_number_is_inf_at_singularities():
    zero = np.zeros((3, 3))
    rank2 = np.array([[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [1.0, 0.0, 1.0]])
    parallel = np.array([[0.1, 0.2], [0.05, 0.1]])
    assert conditioning.condition_number(zero) == np.inf
    assert conditioning.condition_number(rank2) == np.inf
    assert conditioning.condition_number(parallel) == np.inf
    assert conditioning.manipulability(parallel) == 0.0
    # Ill-conditioned but regular stays finite and correct.
    near = np.diag([1.0, 1e-6, 1e-8])
    assert conditioning.condition_number(near) == pytest.approx(1e8, rel=1e-12)


def test_scaling_invariance_of_condition_number():
    rng = np.random.default_rng(12)
    jac = _random_jacobians(rng, 100, 3, 3, 30.0)
    q = special_ortho_group.rvs(3, size=100, random_state=13)
    base = conditioning.condition_number(jac)
    np.testing.assert_allclose(conditioning.condition_number(1e3 * jac), base, rtol=1e-10)
    np.testing.assert_allclose(conditioning.condition_number(q @ jac), base, rtol=1e-10)


# -- inverse transpose ------------------------------------------------------------------------
@pytest.mark.parametrize("n", [2, 3, 4])
def test_inverse_transpose_matches_numpy(n):
    rng = np.random.default_rng(14)
    jac = np.concatenate([_random_jacobians(rng, 200, n, n, 10.0), _random_jacobians(rng, 200, n, n, 1e6)])
    inv_t, ok = linalg.inverse_transpose(jac)
    assert ok.all()
    ref = np.swapaxes(np.linalg.inv(jac), -1, -2)
    kappa = np.linalg.cond(jac)[:, None, None]
    scale = np.max(np.abs(ref), axis=(-2, -1), keepdims=True)
    err = np.abs(inv_t - ref) / (1e-13 * kappa * scale)
    assert err.max() <= 1.0, f"inverse error {err.max():.2f} x the tolerance"
    singular = np.zeros((2, n, n))
    singular[1, :, 0] = 1.0
    inv_s, ok_s = linalg.inverse_transpose(singular)
    assert not ok_s.any() and np.all(np.isnan(inv_s))
    with pytest.raises(ValueError, match=r"jac must be square"):
        linalg.inverse_transpose(np.zeros((n, n + 1)))


# -- ellipsoids -----------------------------------------------------------------------------
@pytest.mark.parametrize("shape", [(2, 2), (3, 3), (2, 3), (3, 4)])
def test_force_ellipsoid_boundary_maps_to_unit_torque(shape):
    rng = np.random.default_rng(20)
    m, n = shape
    jac = _random_jacobians(rng, 50, m, n, 30.0)
    t = _random_torques(rng, 50, n)
    ell = ellipsoids.force_ellipsoid(jac, torque_limits=t)
    assert ell.radii.shape == (50, m) and ell.axes.shape == (50, m, m)
    assert np.all(np.diff(ell.radii, axis=-1) <= 0)                         # largest first
    np.testing.assert_allclose(np.swapaxes(ell.axes, -1, -2) @ ell.axes, np.broadcast_to(np.eye(m), (50, m, m)),
                               atol=1e-12)
    b = np.swapaxes(jac, -1, -2) / t[..., :, None]                           # diag(1/t) J^T
    # Each semi-axis tip, and random points of the boundary, give |B f| = 1.
    tips = ell.axes * ell.radii[:, None, :]                                  # columns r_i a_i
    np.testing.assert_allclose(np.linalg.norm(b @ tips, axis=-2), 1.0, rtol=1e-10)
    c = _unit_directions(rng, 50 * 20, m).reshape(50, 20, m)
    boundary = np.einsum("kij,kpj->kpi", tips, c)
    np.testing.assert_allclose(np.linalg.norm(np.einsum("kui,kpi->kpu", b, boundary), axis=-1), 1.0, rtol=1e-10)
    # The smallest radius is the cheap one.
    np.testing.assert_allclose(ell.radii[:, -1], ellipsoids.force_ellipsoid_min_radius(jac, torque_limits=t),
                               rtol=1e-10)


def test_force_ellipsoid_of_a_tall_jacobian_has_an_infinite_radius():
    """m > n: a direction the structure holds without torque (J^T f = 0)."""
    jac = np.array([[1.0, 0.0], [0.0, 2.0], [0.0, 0.0]])
    ell = ellipsoids.force_ellipsoid(jac, torque_limits=[1.0, 1.0])
    assert ell.radii[0] == np.inf
    np.testing.assert_allclose(ell.radii[1:], [1.0, 0.5])
    np.testing.assert_allclose(np.abs(ell.axes[:, 0]), [0.0, 0.0, 1.0], atol=1e-15)


@pytest.mark.parametrize("shape", [(2, 2), (3, 3), (3, 4)])
def test_velocity_ellipsoid_boundary_needs_unit_scaled_joint_rates(shape):
    rng = np.random.default_rng(21)
    m, n = shape
    jac = _random_jacobians(rng, 40, m, n, 30.0)
    v = rng.uniform(1.0, 10.0, size=(40, n))
    ell = ellipsoids.velocity_ellipsoid(jac, joint_speed_limits=v)
    assert np.all(np.diff(ell.radii, axis=-1) <= 0)
    c = _unit_directions(rng, 40, m)
    x = np.einsum("kij,kj->ki", ell.axes * ell.radii[:, None, :], c)          # boundary points
    scaled = jac * v[:, None, :]                                             # J diag(qdot_max)
    w = np.einsum("kij,kj->ki", np.linalg.pinv(scaled), x)                   # least-norm scaled rates
    np.testing.assert_allclose(np.linalg.norm(w, axis=-1), 1.0, rtol=1e-9)
    np.testing.assert_allclose(np.einsum("kij,kj->ki", scaled, w), x, atol=1e-12)


def test_limits_are_validated_naming_the_argument():
    jac = np.eye(3)
    with pytest.raises(ValueError, match=r"torque_limits must have shape \(\.\.\., 3\)"):
        ellipsoids.force_ellipsoid(jac, torque_limits=[1.0, 1.0])
    with pytest.raises(ValueError, match="torque_limits must be positive"):
        isotropy.isotropic_force(jac, torque_limits=[1.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="joint_speed_limits must be positive"):
        ellipsoids.velocity_ellipsoid(jac, joint_speed_limits=[1.0, np.nan, 1.0])
    with pytest.raises(ValueError, match=r"jac must have shape \(\.\.\., m, n\)"):
        linalg.singular_values(np.ones(3))
    with pytest.raises(ValueError, match="generators needs at least as many columns"):
        zonotopes.zonotope(np.ones((3, 2)), torque_limits=[1.0, 1.0])


# -- isotropic force ---------------------------------------------------------------------------
def _eq8_reference(jac, t):
    """Paper 000 eq. 8, computed directly: R = inv(J).T diag(t), N_u = R_{u+1} x R_{u+2}."""
    ref = np.swapaxes(np.linalg.inv(jac), -1, -2) * t[..., None, :]
    out = []
    for u in range(3):
        ru, r1, r2 = ref[..., :, u], ref[..., :, (u + 1) % 3], ref[..., :, (u + 2) % 3]
        normal = np.cross(r1, r2)
        out.append(np.abs(np.sum(ru * normal, axis=-1)) / np.linalg.norm(normal, axis=-1))
    return np.min(np.stack(out, -1), axis=-1)


def test_isotropic_force_equals_paper_eq8():
    rng = np.random.default_rng(30)
    jac = _random_jacobians(rng, 500, 3, 3, 20.0)
    t = _random_torques(rng, 500, 3)
    iso = isotropy.isotropic_force(jac, torque_limits=t)
    assert iso.shape == (500,)
    np.testing.assert_allclose(iso, _eq8_reference(jac, t), rtol=1e-11)
    np.testing.assert_allclose(isotropy.isotropic_force_cross_product(jac, torque_limits=t), iso, rtol=1e-11)
    # 2 x 2: the distance from 0 to the line through R_u parallel to R_other.
    jac2 = _random_jacobians(rng, 300, 2, 2, 20.0)
    t2 = _random_torques(rng, 300, 2)
    ref2 = np.swapaxes(np.linalg.inv(jac2), -1, -2) * t2[:, None, :]
    dist = [np.abs(ref2[:, 0, u] * ref2[:, 1, 1 - u] - ref2[:, 1, u] * ref2[:, 0, 1 - u])
            / np.linalg.norm(ref2[:, :, 1 - u], axis=-1) for u in range(2)]
    np.testing.assert_allclose(isotropy.isotropic_force(jac2, torque_limits=t2), np.minimum(*dist), rtol=1e-11)


@pytest.mark.parametrize("m", [2, 3])
def test_isotropic_force_by_brute_force_over_directions(m):
    """min over unit d of the largest lambda with lambda d in P approaches the radius from above."""
    rng = np.random.default_rng(31 + m)
    jac = _random_jacobians(rng, 8, m, m, 10.0)
    t = _random_torques(rng, 8, m)
    d = _unit_directions(rng, 60000 if m == 3 else 4000, m)
    iso = isotropy.isotropic_force(jac, torque_limits=t)
    for k in range(8):
        reach = 1.0 / np.max(np.abs(d @ jac[k]) / t[k], axis=-1)            # lambda(d)
        assert reach.min() >= iso[k] * (1 - 1e-12)
        assert reach.min() <= iso[k] * (1 + 2e-3)
        # The bottleneck facet's normal attains the radius exactly.
        u = bottleneck.bottleneck_actuator(jac[k], torque_limits=t[k])
        normal = jac[k][:, u] / np.linalg.norm(jac[k][:, u])
        lam = 1.0 / np.max(np.abs(normal @ jac[k]) / t[k])
        assert lam == pytest.approx(iso[k], rel=1e-13)


def test_isotropic_force_stays_finite_at_a_singularity():
    jac = np.array([[0.1, 0.2, 0.0], [0.0, 0.0, 0.1], [0.05, 0.1, 0.0]])      # columns 0, 1 parallel
    t = np.array([0.5, 0.5, 0.5])
    iso = isotropy.isotropic_force(jac, torque_limits=t)
    assert iso == pytest.approx(min(0.5 / np.hypot(0.1, 0.05), 0.5 / np.hypot(0.2, 0.1), 5.0), rel=1e-14)
    assert anisotropy.anisotropic_force(jac, torque_limits=t) == np.inf
    bad = np.array([[np.inf, 0.0], [0.0, 1.0]])
    assert isotropy.isotropic_force(bad, torque_limits=[1.0, 1.0]) == 0.0
    assert np.isnan(anisotropy.anisotropic_force(bad, torque_limits=[1.0, 1.0]))
    # A zero column limits no direction.
    zero_col = np.array([[0.1, 0.0], [0.0, 0.0]])
    np.testing.assert_array_equal(isotropy.facet_distances(zero_col, torque_limits=[1.0, 1.0]), [10.0, np.inf])


def test_bottleneck_actuator_is_the_argmin_facet():
    rng = np.random.default_rng(32)
    jac = _random_jacobians(rng, 400, 3, 3, 20.0)
    t = _random_torques(rng, 400, 3)
    dist = t / np.linalg.norm(jac, axis=-2)
    # np.linalg.norm and column_norms may round differently (< 4 eps each); the argmins agree
    # in exact arithmetic, and in floats because these samples have no near-tie to flip.
    ordered = np.sort(dist, axis=-1)
    assert np.all(ordered[:, 1] > ordered[:, 0] * (1 + 1e-9))
    neck = bottleneck.bottleneck_actuator(jac, torque_limits=t)
    np.testing.assert_array_equal(neck, np.argmin(dist, axis=-1))
    assert set(np.unique(neck)) == {0, 1, 2}
    # Doubling the bottleneck's torque moves the bottleneck or raises the radius.
    k = np.arange(400)
    stronger = t.copy()
    stronger[k, neck] *= 2.0
    iso_before = isotropy.isotropic_force(jac, torque_limits=t)
    iso_after = isotropy.isotropic_force(jac, torque_limits=stronger)
    assert np.all(iso_after > iso_before)
    # Using precomputed norms gives the same answers.
    norms = columns.column_norms(jac)
    np.testing.assert_allclose(norms, np.linalg.norm(jac, axis=-2), rtol=1e-15)
    np.testing.assert_array_equal(bottleneck.bottleneck_actuator(norms=norms, torque_limits=t), neck)



def _mp_facet_distances(jac, t):
    """``t_u / |J[:, u]|`` at 50 digits from the float64 entries (an independent reference)."""
    import mpmath
    with mpmath.workdps(50):
        return [mpmath.mpf(float(t[u])) / mpmath.sqrt(mpmath.fsum(mpmath.mpf(float(x)) ** 2 for x in jac[:, u]))
                for u in range(jac.shape[1])]


@pytest.mark.parametrize("n", [2, 3])
def test_bottleneck_ties_within_rounding_are_reported_as_ties(n):
    """Columns equal in norm in exact arithmetic (one is a signed permutation of another, so
    the float sums of squares differ only in order) with equal torques: ``BOTTLENECK_TIE``,
    never a pick by rounding. Gaps well beyond ``tie_tolerance`` (1e-12 relative, by mpmath)
    give the nearer actuator."""
    import mpmath
    rng = np.random.default_rng(40 + n)
    count = 300
    jac = rng.normal(size=(count, n, n))
    perm = np.roll(np.arange(n), 1)
    jac[:, :, 1] = -jac[:, perm, 0]                         # |c1| = |c0| exactly
    if n == 3:                                                # c2 half as long: the nearest facets are c0's, c1's
        jac[:, :, 2] *= 0.5 * np.linalg.norm(jac[:, :, 0], axis=-1, keepdims=True) / np.linalg.norm(
            jac[:, :, 2], axis=-1, keepdims=True)
    t = np.ones(n)
    with mpmath.workdps(50):
        exact = [_mp_facet_distances(j, t) for j in jac]
        assert all(e[0] == e[1] and min(e) == e[0] for e in exact)   # ties in exact arithmetic
    neck = bottleneck.bottleneck_actuator(jac, torque_limits=t)
    assert np.all(neck == bottleneck.BOTTLENECK_TIE)
    d = isotropy.facet_distances(jac, torque_limits=t)
    assert np.all(np.abs(d[:, 0] - d[:, 1]) <= bottleneck.tie_tolerance(n) * d.min(axis=-1))
    # c1 = Q c0 with Q a rotation rounded to float64: |c1| and |c0| now differ by the rounding
    # of J's entries (a few eps, measured at 50 digits), as the Inverse3's p1/p2 columns do
    q = np.linalg.qr(rng.normal(size=(count, n, n)))[0]
    rotated = jac.copy()
    rotated[:, :, 1] = np.einsum("kij,kj->ki", q, jac[:, :, 0])
    # (observed up to 2.3 eps). Where the true gap leaves room for the norms' own rounding,
    # (n/2 + 2) eps (``tie_tolerance``'s derivation), the result must be a tie.
    eps = np.finfo(float).eps
    with mpmath.workdps(50):
        gaps = np.array([float(abs(e[0] - e[1]) / e[0]) for e in (_mp_facet_distances(j, t) for j in rotated)])
    room = gaps <= (n / 2 + 2) * eps
    assert room.mean() > 0.9 and gaps.max() > 0
    neck = bottleneck.bottleneck_actuator(rotated, torque_limits=t)
    assert np.all(neck[room] == bottleneck.BOTTLENECK_TIE)
    # separate the pair by 1e-12 relative (far beyond the tolerance): the nearer one limits
    apart = jac.copy()
    apart[:, :, 1] *= 1.0 + 1e-12
    neck = bottleneck.bottleneck_actuator(apart, torque_limits=t)
    with mpmath.workdps(50):
        expected = [int(np.argmin([float(v) for v in _mp_facet_distances(j, t)])) for j in apart]
    np.testing.assert_array_equal(neck, expected)
    assert np.all(neck == 1)


@pytest.mark.parametrize("n", [2, 3, 4])
def test_tied_actuators_are_the_ones_a_tie_is_of(n):
    """At every point: one index, the bottleneck, where it is an actuator; two or more where it
    is a tie, each within ``tie_tolerance`` of the nearest facet and every other beyond it
    (brute force over the indices). Signed (gravity) distances below 0 count as 0."""
    rng = np.random.default_rng(70 + n)
    dist = rng.uniform(0.5, 2.0, size=(2000, n))
    pair = rng.integers(0, n, size=(2000, 2))
    tied = rng.random(2000) < 0.5            # half the points: one facet copied onto another
    dist[tied, pair[tied, 1]] = dist[tied, pair[tied, 0]] * (1 + rng.integers(0, 3, tied.sum()) * np.finfo(float).eps)
    dist[rng.random(2000) < 0.1, 0] = -0.3   # the origin outside slab 0
    neck = bottleneck.bottleneck_of_distances(np.where(dist > 0, dist, 0.0))
    tol = bottleneck.tie_tolerance(n)
    for d, b in zip(dist, neck):
        got = bottleneck.tied_actuators(d)
        clipped = np.maximum(d, 0.0)
        assert got == tuple(k for k in range(n) if clipped[k] <= clipped.min() * (1 + tol))
        assert got == ((int(b),) if b >= 0 else got) and (len(got) >= 2) == (b == bottleneck.BOTTLENECK_TIE)
    assert np.count_nonzero(neck == bottleneck.BOTTLENECK_TIE) > 150      # ties are met (296 to 477 of 2000)
    assert bottleneck.tied_actuators([1.0, np.nan]) == ()


def test_bottleneck_tie_tolerance_and_degenerate_cases():
    """The tolerance is a few eps times n; all facets at infinity (J = 0) or at 0 (J
    unbounded) are equal: a tie. One actuator: no tie possible."""
    eps = np.finfo(float).eps
    assert 2 * eps <= bottleneck.tie_tolerance(2) <= 8 * eps
    assert bottleneck.tie_tolerance(3) > bottleneck.tie_tolerance(2)
    t = np.ones(2)
    assert bottleneck.bottleneck_actuator(np.zeros((2, 2)), torque_limits=t) == bottleneck.BOTTLENECK_TIE
    assert bottleneck.bottleneck_actuator(np.full((2, 2), np.inf), torque_limits=t) == bottleneck.BOTTLENECK_TIE
    assert bottleneck.bottleneck_actuator(np.array([[0.0, 1.0], [0.0, 0.0]]), torque_limits=t) == 1
    assert bottleneck.bottleneck_actuator(np.array([[2.0]]), torque_limits=[1.0]) == 0


def test_negligible_columns_are_zero_to_rounding():
    """A column at rounding level relative to J (``<= n eps max |J[:, v]|``) has its facet at
    infinity, like an exactly zero one; a column 1e-14 of the largest (beyond rounding) keeps
    its finite facet, 1e14 times farther. Unbounded columns make nothing negligible."""
    eps = np.finfo(float).eps
    t = np.ones(2)
    jac = np.array([[0.19, 1.0 * eps * 0.19], [0.0, 0.5 * eps * 0.19]])
    d = isotropy.facet_distances(jac, torque_limits=t)
    assert d[1] == np.inf and d[0] == pytest.approx(1 / 0.19, rel=4 * eps)
    jac[:, 1] = [1e-14 * 0.19, 0.0]
    d = isotropy.facet_distances(jac, torque_limits=t)
    assert d[1] == pytest.approx(1e14 / 0.19, rel=4 * eps)
    assert not columns.negligible_columns(np.array([np.inf, 1.0])).any()
    assert columns.negligible_columns(np.array([0.0, 0.0])).all()


def test_inverse3_p1_p2_tie_over_the_slice():
    """The coaxial five-bar's link columns ``0.5 (dP/dth3 +- dP/dh)`` have equal norms in
    exact arithmetic (the two derivatives are orthogonal) and p1, p2 have equal torques: over
    the slice the bottleneck is the base joint or the p1/p2 tie, never p1 or p2 alone
    (issue 7: 32,268 scattered "p2" pixels inside a "p1" region). Where it is the base joint,
    its facet is the nearest, to 50 digits."""
    import mpmath

    from kinematics import Inverse3
    from metrics.quantities import evaluate

    device = Inverse3()
    c = device.params.plane_offset
    x, z = np.meshgrid(np.linspace(-0.05, 0.35, 61), np.linspace(-0.15, 0.5, 61), indexing="ij")
    points = np.stack([x, np.full_like(x, c), z], -1).reshape(-1, 3)
    ev = evaluate(device, points, ("bottleneck", "jacobian"))
    neck = ev.values["bottleneck"][ev.feasible]
    assert set(np.unique(neck)) == {0, bottleneck.BOTTLENECK_TIE}
    t = device.torque_limits()
    with mpmath.workdps(50):
        for j, b in zip(ev.values["jacobian"][ev.feasible][::7], neck[::7], strict=True):
            d = _mp_facet_distances(j, t)
            assert abs(d[1] - d[2]) <= 4 * np.finfo(float).eps * d[1]     # equal but for J's rounding
            if b == 0:       # not a tie: farther apart than tol, more than the norms' rounding (3.5 eps)
                assert d[0] < min(d[1], d[2])


def test_redundant_bottleneck_is_shared():
    """Twin-Pantograph (redundant waist actuator): no single actuator caps the force, code shared."""
    from metrics.quantities import evaluate
    from resources import load_preset

    preset = load_preset("twin_pantograph")
    mech = preset.mechanism
    points = preset.grid.with_resolution(9).points(mech.task_names)
    ev = evaluate(mech, points, ("bottleneck",))
    assert ev.feasible.any()
    assert np.all(ev.values["bottleneck"][ev.feasible] == bottleneck.BOTTLENECK_SHARED)
    assert np.all(ev.values["bottleneck"][~ev.feasible] == bottleneck.BOTTLENECK_INFEASIBLE)


# -- anisotropic force and vertices --------------------------------------------------------------
@pytest.mark.parametrize("n", [2, 3])
def test_anisotropic_force_is_the_largest_vertex_norm(n):
    rng = np.random.default_rng(40 + n)
    jac = _random_jacobians(rng, 200, n, n, 20.0)
    t = _random_torques(rng, 200, n)
    verts = parallelepiped.polytope_vertices(jac, torque_limits=t)
    assert verts.shape == (200, 2 ** n, n)
    # Each vertex has every actuator at its limit, with the row's sign pattern.
    tau = np.einsum("kiu,kvi->kvu", jac, verts)                              # J^T v
    np.testing.assert_allclose(tau, torque_box.sign_patterns(n)[None] * t[:, None, :], rtol=1e-10, atol=1e-12)
    aniso = anisotropy.anisotropic_force(jac, torque_limits=t)
    np.testing.assert_allclose(aniso, np.linalg.norm(verts, axis=-1).max(axis=-1), rtol=1e-12)
    ref = parallelepiped.reference_forces(jac, torque_limits=t)
    np.testing.assert_array_equal(anisotropy.anisotropic_force(jac, ref=ref, torque_limits=t), aniso)
    # Every point of P is no longer than the anisotropic force, and boundary points come close.
    s = rng.uniform(-1.0, 1.0, size=(200, 500, n))
    inside = np.einsum("kij,kpj->kpi", ref, s)
    assert np.all(np.linalg.norm(inside, axis=-1) <= aniso[:, None] * (1 + 1e-12))
    d = _unit_directions(rng, 3000, n)
    reach = 1.0 / np.max(np.abs(np.einsum("pi,kiu->kpu", d, jac)) / t[:, None, :], axis=-1)
    assert np.all(reach <= aniso[:, None] * (1 + 1e-12))
    # Along the vertex directions the boundary is the vertex itself: the largest is aniso.
    vd = verts / np.linalg.norm(verts, axis=-1, keepdims=True)
    reach_v = 1.0 / np.max(np.abs(np.einsum("kpi,kiu->kpu", vd, jac)) / t[:, None, :], axis=-1)
    np.testing.assert_allclose(reach_v.max(axis=-1), aniso, rtol=1e-12)


def test_textbook_inequalities_between_ellipsoid_and_polytope():
    """With B = diag(1/t) J^T: E = {|Bf|_2 <= 1} in P = {|Bf|_inf <= 1} in sqrt(n) E."""
    rng = np.random.default_rng(45)
    for n in (2, 3):
        jac = np.concatenate([_random_jacobians(rng, 300, n, n, 10.0), _random_jacobians(rng, 300, n, n, 1e4)])
        t = np.exp(rng.uniform(-3, 3, size=(600, n)))                          # torques over decades
        r_min = ellipsoids.force_ellipsoid_min_radius(jac, torque_limits=t)
        iso = isotropy.isotropic_force(jac, torque_limits=t)
        aniso = anisotropy.anisotropic_force(jac, torque_limits=t)
        r_max = ellipsoids.force_ellipsoid(jac, torque_limits=t).radii[:, 0]
        assert np.all(r_min <= iso * (1 + 1e-12))
        assert np.all(iso <= np.sqrt(n) * r_min * (1 + 1e-12))
        # The same nesting bounds the longest vertex: r_max <= aniso <= sqrt(n) r_max.
        assert np.all(r_max <= aniso * (1 + 1e-9))
        assert np.all(aniso <= np.sqrt(n) * r_max * (1 + 1e-9))
        assert np.all(iso <= aniso)


# -- force clamp (eq. 9) --------------------------------------------------------------------------
def test_clamp_force_eq9():
    rng = np.random.default_rng(50)
    f = rng.normal(size=(1000, 3)) * rng.uniform(0.1, 10.0, size=(1000, 1))
    radius = rng.uniform(1.0, 5.0, size=1000)
    out = isotropy.clamp_force(f, radius)
    norm = np.linalg.norm(f, axis=-1)
    inside = norm < radius
    assert 100 < inside.sum() < 900
    np.testing.assert_array_equal(out[inside], f[inside])
    np.testing.assert_allclose(np.linalg.norm(out[~inside], axis=-1), radius[~inside], rtol=1e-14)
    cos = np.sum(out[~inside] * f[~inside], axis=-1) / (np.linalg.norm(out[~inside], axis=-1) * norm[~inside])
    np.testing.assert_allclose(cos, 1.0, rtol=1e-14)
    # A scalar radius broadcasts; a force exactly on the radius stays there.
    on = np.array([3.0, 4.0])
    np.testing.assert_allclose(isotropy.clamp_force(on, 5.0), on, rtol=1e-15)
    np.testing.assert_allclose(isotropy.clamp_force(np.array([[6.0, 8.0], [0.3, 0.4]]), 5.0),
                               [[3.0, 4.0], [0.3, 0.4]], rtol=1e-15)


# -- parallelepiped faces -----------------------------------------------------------------------
def test_parallelepiped_faces_are_planar_with_jacobian_column_normals():
    rng = np.random.default_rng(60)
    faces = parallelepiped.parallelepiped_faces(3)
    assert len(faces) == 6 and all(len(face) == 4 for face in faces)
    counts = np.bincount(np.concatenate(faces), minlength=8)
    np.testing.assert_array_equal(counts, 3)                          # each vertex on three faces
    for jac, t in zip(_random_jacobians(rng, 20, 3, 3, 20.0), _random_torques(rng, 20, 3)):
        verts = parallelepiped.polytope_vertices(jac, torque_limits=t)
        centre = verts.mean(axis=0)
        used = []
        for face in faces:
            v = verts[list(face)]
            normal = np.cross(v[1] - v[0], v[3] - v[0])
            normal /= np.linalg.norm(normal)
            scale = np.linalg.norm(v[2] - v[0])
            assert abs(np.dot(v[2] - v[0], normal)) < 1e-12 * scale          # coplanar
            # Ordered around the face: consecutive edge turns all have the same sense.
            turns = [np.dot(np.cross(v[(i + 1) % 4] - v[i], v[(i + 2) % 4] - v[(i + 1) % 4]), normal)
                     for i in range(4)]
            assert all(turn > 0 for turn in turns) or all(turn < 0 for turn in turns)
            # Outward normal is +- a column of J (a row of J^T), normalised.
            outward = normal if np.dot(v.mean(axis=0) - centre, normal) > 0 else -normal
            cols = jac / np.linalg.norm(jac, axis=0)
            match = np.abs(cols.T @ outward)
            u = int(np.argmax(match))
            assert match[u] == pytest.approx(1.0, abs=1e-12)
            # ... pointing the way the face's torque sign says.
            sign = np.sign(np.dot(jac[:, u], v[0]))
            np.testing.assert_allclose(outward, sign * cols[:, u], atol=1e-12)
            np.testing.assert_allclose(v @ jac[:, u], sign * t[u], rtol=1e-12)
            used.append(u)
        assert sorted(used) == [0, 0, 1, 1, 2, 2]


def test_parallelepiped_face_of_a_parallelogram():
    jac = np.array([[0.1, 0.03], [0.02, 0.08]])
    t = np.array([0.5, 0.7])
    (face,) = parallelepiped.parallelepiped_faces(2)
    v = parallelepiped.polytope_vertices(jac, torque_limits=t)[list(face)]
    edges = np.roll(v, -1, axis=0) - v
    cross = edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1] - edges[:, 1] * np.roll(edges, -1, axis=0)[:, 0]
    assert np.all(cross > 0) or np.all(cross < 0)                       # a convex cycle
    area = 0.5 * abs(np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1]))
    assert area == pytest.approx(4 * t[0] * t[1] / abs(np.linalg.det(jac)), rel=1e-12)
    with pytest.raises(ValueError, match="n = 2 or 3"):
        parallelepiped.parallelepiped_faces(4)


def test_sign_patterns():
    rows = torque_box.sign_patterns(3)
    assert rows.shape == (8, 3) and len({tuple(r) for r in rows}) == 8
    half = torque_box.sign_patterns(3, half=True)
    assert half.shape == (4, 3) and np.all(half[:, 0] == 1.0)


# -- zonotopes --------------------------------------------------------------------------------
@pytest.mark.parametrize("n", [2, 3])
def test_square_zonotope_inscribed_radius_is_the_isotropic_force(n):
    rng = np.random.default_rng(70 + n)
    jac = _random_jacobians(rng, 300, n, n, 20.0)
    t = _random_torques(rng, 300, n)
    gens = np.swapaxes(np.linalg.inv(jac), -1, -2)                        # A = J^-T: f = A tau
    zono = zonotopes.zonotope(gens, torque_limits=t)
    np.testing.assert_allclose(zono.inscribed_radius, isotropy.isotropic_force(jac, torque_limits=t), rtol=1e-10)
    verts = zonotopes.zonotope_vertices(gens, torque_limits=t)
    np.testing.assert_allclose(verts, parallelepiped.polytope_vertices(jac, torque_limits=t), rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("shape", [(2, 3), (3, 4), (3, 5)])
def test_redundant_zonotope_against_convex_hull(shape):
    rng = np.random.default_rng(80 + shape[1])
    m, n = shape
    for _ in range(15):
        gens = rng.normal(size=(m, n))
        t = rng.uniform(0.2, 2.0, size=n)
        zono = zonotopes.zonotope(gens, torque_limits=t)
        verts = zonotopes.zonotope_vertices(gens, torque_limits=t)
        assert verts.shape == (2 ** n, m)
        hull = ConvexHull(verts)
        hull_radius = np.min(-hull.equations[:, -1])
        assert zono.inscribed_radius == pytest.approx(hull_radius, rel=1e-10)
        # Every facet normal's offset is the support value of the vertex set in that direction.
        np.testing.assert_allclose(zono.offsets, np.max(zono.normals @ verts.T, axis=-1), rtol=1e-10)
        # ... and every hull facet is one of the zonotope's (up to sign).
        match = np.abs(hull.equations[:, :-1] @ zono.normals.T)
        np.testing.assert_allclose(match.max(axis=-1), 1.0, atol=1e-10)


def test_zonotope_batches_and_degenerate_generators():
    rng = np.random.default_rng(90)
    gens = rng.normal(size=(4, 5, 2, 3))
    t = np.array([0.5, 1.0, 1.5])
    zono = zonotopes.zonotope(gens, torque_limits=t)
    assert zono.inscribed_radius.shape == (4, 5)
    one = zonotopes.zonotope(gens[2, 3], torque_limits=t)
    np.testing.assert_allclose(zono.inscribed_radius[2, 3], one.inscribed_radius, rtol=1e-14)
    # Two parallel generators: their "facet" is no facet; the radius comes from the others.
    par = np.array([[1.0, 2.0, 0.0], [0.0, 0.0, 1.0]])
    z = zonotopes.zonotope(par, torque_limits=[1.0, 1.0, 1.0])
    hull = ConvexHull(zonotopes.zonotope_vertices(par, torque_limits=[1.0, 1.0, 1.0]))
    assert z.inscribed_radius == pytest.approx(np.min(-hull.equations[:, -1]), rel=1e-12)


# -- batches ----------------------------------------------------------------------------------
#: Built with einsum, whose summation order may differ between a batch and one matrix (1 ulp).
ULP_LEVEL = {"vertices"}


@pytest.mark.parametrize("n", [2, 3])
def test_batch_equals_one_at_a_time(n):
    """Every metric on a batch equals the same metric on each matrix alone, shapes unsqueezed."""
    rng = np.random.default_rng(100 + n)
    # Well and badly conditioned matrices, so both the closed forms and LAPACK paths run.
    jac = np.concatenate([_random_jacobians(rng, 12, n, n, 10.0), _random_jacobians(rng, 12, n, n, 1e7)])
    jac[3, :, 0] = 0.0                                                    # a singular one
    t = _random_torques(rng, 1, n)[0]
    funcs = {
        "singular_values": lambda j: linalg.singular_values(j),
        "inverse_transpose": lambda j: linalg.inverse_transpose(j)[0],
        "inverse_ok": lambda j: linalg.inverse_transpose(j)[1],
        "condition_number": lambda j: conditioning.condition_number(j),
        "manipulability": lambda j: conditioning.manipulability(j),
        "column_norms": lambda j: columns.column_norms(j),
        "isotropic_force": lambda j: isotropy.isotropic_force(j, torque_limits=t),
        "bottleneck": lambda j: bottleneck.bottleneck_actuator(j, torque_limits=t),
        "reference_forces": lambda j: parallelepiped.reference_forces(j, torque_limits=t),
        "anisotropic_force": lambda j: anisotropy.anisotropic_force(j, torque_limits=t),
        "vertices": lambda j: parallelepiped.polytope_vertices(j, torque_limits=t),
        "min_radius": lambda j: ellipsoids.force_ellipsoid_min_radius(j, torque_limits=t),
        "ellipsoid_radii": lambda j: ellipsoids.force_ellipsoid(j, torque_limits=t).radii,
        "velocity_radii": lambda j: ellipsoids.velocity_ellipsoid(j, joint_speed_limits=t).radii,
        "zonotope_radius": lambda j: zonotopes.zonotope(j, torque_limits=t).inscribed_radius,
    }
    for name, fn in funcs.items():
        batch = fn(jac)
        nested = fn(jac.reshape(4, 6, n, n))
        assert nested.shape == (4, 6) + batch.shape[1:], name
        np.testing.assert_array_equal(nested.reshape(batch.shape), batch, err_msg=name)
        for k in range(len(jac)):
            one = fn(jac[k])
            assert np.shape(one) == batch.shape[1:], name
            if name in ULP_LEVEL:
                scale = np.max(np.abs(batch[k]))
                np.testing.assert_allclose(one, batch[k], rtol=0, atol=2e-15 * scale, err_msg=f"{name}[{k}]")
            else:
                np.testing.assert_array_equal(one, batch[k], err_msg=f"{name}[{k}]")
