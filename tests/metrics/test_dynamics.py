"""Task-space inertia, apparent masses and acceleration capability (metrics.dynamics).

References: pycapacity's ``acceleration_ellipsoid`` and ``acceleration_polytope`` with the same
``J`` and ``M``; the definition ``Lambda = (J M^-1 J^T)^-1`` by a plain inverse; the inscribed
ball of the acceleration polytope from pycapacity's half-planes; exact scaling laws.
"""
from __future__ import annotations

import numpy as np
import pytest

from metrics import dynamics

EPS = np.finfo(float).eps

#: pycapacity rounds the vertices and half-planes it returns to 7 decimals.
PYCAPACITY_ROUNDING = 0.5e-7


def _case(rng, m):
    """A well-conditioned J (m x m), an SPD M and limits, entries of order 1."""
    jac = np.eye(m) + 0.3 * rng.standard_normal((m, m))
    a = rng.standard_normal((m, m))
    mass = a @ a.T + m * np.eye(m)
    t = rng.uniform(0.5, 2.0, m)
    return jac, mass, t


def test_task_space_inertia_is_the_inverse_of_j_m_inv_jt():
    rng = np.random.default_rng(1)
    for m in (2, 3):
        jac, mass, _ = _case(rng, m)
        lam = dynamics.task_space_inertia(jac, mass)
        ref = np.linalg.inv(jac @ np.linalg.inv(mass) @ jac.T)
        # Two inversions of a matrix of condition < 1e3: well inside 1e-10 relative.
        assert np.allclose(lam, ref, rtol=1e-10, atol=1e-10 * np.abs(ref).max())


def test_a_singular_jacobian_gives_an_infinite_largest_apparent_mass_and_no_isotropic_acceleration():
    jac = np.array([[1.0, 0.0], [0.0, 0.0]])           # the device cannot move along y
    mob = dynamics.mobility(jac, np.eye(2))
    low, high = dynamics.apparent_mass_range(mob)
    assert low == 1.0 and high == np.inf
    assert dynamics.mass_condition_number(mob) == np.inf
    lam = dynamics.inverse_spd(mob)
    assert float(dynamics.isotropic_acceleration(jac, lam, torque_limits=[1.0, 1.0])) == 0.0


@pytest.mark.parametrize("m", [2, 3])
def test_acceleration_ellipsoid_and_polytope_against_pycapacity(m):
    robot = pytest.importorskip("pycapacity.robot")
    rng = np.random.default_rng(10 + m)
    for _ in range(5):
        jac, mass, t = _case(rng, m)
        ours = dynamics.acceleration_ellipsoid(jac, mass, torque_limits=t)
        theirs = robot.acceleration_ellipsoid(jac, mass, t)
        assert np.allclose(np.sort(ours.radii), np.sort(theirs.radii), rtol=1e-12, atol=0)
        poly = robot.acceleration_polytope(jac, mass, t, -t)
        verts = np.asarray(poly.vertices).T                                   # (2^m, m)
        mine = dynamics.acceleration_polytope_vertices(jac, mass, torque_max=t)
        for v in mine:
            assert np.min(np.linalg.norm(verts - v, axis=1)) <= 4 * PYCAPACITY_ROUNDING
        # The inscribed ball from pycapacity's half-planes H a <= d equals ours through Lambda J.
        poly.find_halfplanes()
        h, d = np.asarray(poly.H), np.asarray(poly.d).ravel()
        ball = float(np.min(d / np.linalg.norm(h, axis=1)))
        lam = dynamics.task_space_inertia(jac, mass)
        iso = float(dynamics.isotropic_acceleration(jac, lam, torque_limits=t))
        assert abs(iso - ball) <= 8 * PYCAPACITY_ROUNDING * max(1.0, ball)


@pytest.mark.parametrize("k", [2.0**-30, 3.0, 2.0**30])
def test_masses_times_k_scale_masses_by_k_and_accelerations_by_one_over_k(k):
    rng = np.random.default_rng(5)
    jac, mass, t = _case(rng, 3)
    mob, mob_k = dynamics.mobility(jac, mass), dynamics.mobility(jac, k * mass)
    r, r_k = dynamics.apparent_mass_range(mob), dynamics.apparent_mass_range(mob_k)
    # Linear algebra on a matrix scaled by k: exact for a power of two, within a few
    # backward errors (m eps kappa, kappa < 1e3 here) otherwise.
    tol = 1e-12
    assert np.allclose(r_k, k * r, rtol=tol, atol=0)
    lam, lam_k = dynamics.inverse_spd(mob), dynamics.inverse_spd(mob_k)
    a = dynamics.isotropic_acceleration(jac, lam, torque_limits=t)
    a_k = dynamics.isotropic_acceleration(jac, lam_k, torque_limits=t)
    assert np.isclose(a_k, a / k, rtol=tol, atol=0)


def test_apparent_mass_along_an_axis_lies_between_the_extremes_and_below_the_effective_mass():
    # 1 / (Lambda^-1)_ii <= Lambda_ii (Cauchy-Schwarz on an SPD matrix) and within the eigenvalues.
    rng = np.random.default_rng(7)
    for _ in range(20):
        jac, mass, _ = _case(rng, 3)
        mob = dynamics.mobility(jac, mass)
        lam = dynamics.inverse_spd(mob)
        app, eff = dynamics.apparent_masses(mob), dynamics.effective_masses(lam)
        low, high = dynamics.apparent_mass_range(mob)
        slack = 1e-12 * high
        assert np.all(app <= eff + slack)
        assert np.all((low - slack <= app) & (app <= high + slack))
        assert np.all((low - slack <= eff) & (eff <= high + slack))


@pytest.mark.parametrize("k", [1e-300, 1e300])
def test_the_phantoms_masses_accelerations_and_weight_scale_over_the_whole_float_range(k):
    """Every body mass, inertia and rotor times k: masses times k, accelerations over k, weight times k,
    with no warning (the suite turns warnings into errors), as the force figures scale with torque."""
    from metrics.pose_dynamics import analyse_dynamics
    from resources import load_preset

    mech = load_preset("phantom_premium_15").mechanism
    x = np.array(load_preset("phantom_premium_15").pose)
    p = mech.params
    scaled = mech.replace(link_masses=tuple(k * v for v in p.link_masses),
                          rotor_inertias=tuple(k * v for v in p.rotor_inertias),
                          **{f"inertia_{b}": tuple(k * v for v in getattr(p, f"inertia_{b}"))
                             for b in ("a", "c", "be", "df", "g")})
    a, b = analyse_dynamics(mech, x), analyse_dynamics(scaled, x)
    # Each figure goes through a few solves and an eigen-decomposition of a matrix of condition
    # < 10: well inside 1e-12 relative; k itself is applied once, not compounded.
    rtol = 1e-12
    assert np.allclose(np.array(b.apparent_mass_range) / k, a.apparent_mass_range, rtol=rtol, atol=0)
    assert np.allclose(b.effective_mass / k, a.effective_mass, rtol=rtol, atol=0)
    assert np.isclose(b.isotropic_acceleration * k, a.isotropic_acceleration, rtol=rtol, atol=0)
    assert np.isclose(b.weight / k, a.weight, rtol=rtol, atol=0)


@pytest.mark.parametrize("key", ["fivebar_singh", "haply_2diy"])
def test_a_feasible_singular_pose_has_an_unbounded_heaviest_mass_and_no_isotropic_acceleration(key):
    """Where the model classes a map point singular (a leg stretched or folded), the device cannot
    move along a direction: the heaviest apparent mass and the mass condition are inf and the
    acceleration set is flat, as the force quantities take their singular limits; regular points
    keep finite values."""
    from metrics.quantities import evaluate
    from resources import load_preset

    preset = load_preset(key)
    mech = preset.mechanism
    pts = preset.grid.points(mech.task_names).reshape(-1, mech.task_dim)
    names = ["singularity", "apparent_mass_max", "mass_condition_number", "isotropic_acceleration"]
    ev = evaluate(mech, pts, names)
    code = ev.values["singularity"]
    singular, regular = ev.feasible & (code > 0), ev.feasible & (code == 0)
    assert singular.sum() > 0
    assert np.all(ev.values["apparent_mass_max"][singular] == np.inf)
    assert np.all(ev.values["mass_condition_number"][singular] == np.inf)
    assert np.all(ev.values["isotropic_acceleration"][singular] == 0.0)
    for name in names[1:]:
        assert np.all(np.isfinite(ev.values[name][regular]))


@pytest.mark.parametrize("key", ["phantom_premium_15", "phantom_omni", "inverse3_prototype", "fivebar_singh"])
def test_the_pose_acceleration_ellipsoid_against_pycapacity_at_random_poses(key):
    """``analyse_dynamics``'s acceleration ellipsoid is pycapacity's ``acceleration_ellipsoid(J, M, t)``
    with the model's own J and M: a serial arm's ``M(q)`` from its bodies, a closed chain's
    ``M = J^T Lambda J`` from its task-space inertia; t the loading's torque limits."""
    robot = pytest.importorskip("pycapacity.robot")
    from kinematics.dynamics import kinetic_form
    from metrics.loading import Loading
    from metrics.pose_dynamics import analyse_dynamics
    from resources import load_preset

    mech = load_preset(key).mechanism
    pts = load_preset(key).grid.points(mech.task_names).reshape(-1, mech.task_dim)
    q, ok = mech.inverse(pts)
    ok &= mech.feasible(q, pts)
    if mech.singularity_classes:
        ok &= mech.singularity(q, pts) == 0
    rng = np.random.default_rng(3)
    for k in rng.choice(np.flatnonzero(ok), 8, replace=False):
        x, qk = pts[k], q[k]
        jac = mech.jacobian(qk[None], x[None])[0]
        form = kinetic_form(mech, qk[None], x[None])[0]
        mass = form if mech.mass_coordinates == "joint" else jac.T @ form @ jac
        for loading in (Loading(), Loading(rating="peak")) if mech.peak_torque_limits() is not None else (Loading(),):
            t = loading.torque_limits(mech)
            ours = analyse_dynamics(mech, x, loading=loading).acceleration_ellipsoid
            theirs = robot.acceleration_ellipsoid(jac, mass, t)
            # Compare the ellipsoids' matrices U diag(r^2) U^T (unique where radii repeat): two
            # solves (ours, pycapacity's pinv) of M, each with a backward error of a few n eps,
            # amplified by cond(M) (cond(J)^2 cond(Lambda) for a closed chain's J^T Lambda J).
            def shape(radii, axes):
                return (axes * np.asarray(radii) ** 2) @ axes.T
            a, b = shape(ours.radii, ours.axes), shape(theirs.radii, theirs.rotation)
            tol = 16 * mass.shape[0] * np.finfo(float).eps * np.linalg.cond(mass) * float(np.max(ours.radii)) ** 2
            assert np.max(np.abs(a - b)) <= tol
            assert np.all(np.diff(ours.radii) <= 0)                      # largest first


def test_a_batch_of_large_matrices_is_inverted_by_cholesky_where_surely_regular_and_by_eigenvalues_elsewhere():
    """``inverse_spd`` for m > 3: the same figures as the eigen-decomposition within ``m eps kappa``.

    Both are backward stable inversions of the same matrix, each within about ``m eps kappa |A^-1|``
    of the exact inverse; 8 m eps kappa bounds their difference. Null and non-finite matrices take
    the eigen-decomposition in both (``inf`` along the null direction, ``nan`` for non-finite).
    """
    rng = np.random.default_rng(12)
    m = 6
    a = rng.normal(size=(400, m, m))
    mats = a @ np.swapaxes(a, -1, -2) + np.logspace(-12, 0, 400)[:, None, None] * np.eye(m)
    mats[0] = np.diag([1.0, 1.0, 1.0, 1.0, 1.0, 0.0])            # a null direction
    mats[1, 0, 0] = np.nan
    mats[2] *= 1e300                                              # traces out of the safe range
    got = dynamics.inverse_spd(mats)
    ref = dynamics._inverse_spd_eigh(mats)
    assert np.array_equal(np.isinf(got), np.isinf(ref)) and np.array_equal(np.isnan(got), np.isnan(ref))
    ok = np.all(np.isfinite(ref), axis=(-2, -1))
    kappa = np.linalg.cond(mats[ok])
    scale = np.max(np.abs(ref[ok]), axis=(-2, -1))
    assert np.all(np.max(np.abs(got[ok] - ref[ok]), axis=(-2, -1)) <= 8 * m * EPS * kappa * scale)
    assert np.any(got[ok] != ref[ok])           # the Cholesky path was taken (the eigenvalues' would be identical)


@pytest.mark.parametrize("m", [4, 5, 6])
def test_the_compiled_cholesky_takes_only_surely_regular_matrices(m):
    """``kernels.spd.sure_inverses``: the inverse where ``det > SURE_REGULAR m eps tr^m`` (and finite, in
    scale), within ``8 m eps kappa`` of LAPACK's (both backward stable); nothing elsewhere."""
    from metrics.kernels import spd

    rng = np.random.default_rng(m)
    a = rng.normal(size=(200, m, m))
    mats = a @ np.swapaxes(a, -1, -2) + np.logspace(-9, 0, 200)[:, None, None] * np.eye(m)
    mats[0] = np.diag([1.0] * (m - 1) + [0.0])                    # null
    mats[1] = np.diag([1.0] * (m - 1) + [-1.0])                   # indefinite
    mats[2, 0, 1] = mats[2, 1, 0] = np.inf
    mats[3] *= 2.0 ** 160                                          # trace beyond SAFE_SCALE
    mats[4] = np.diag([1.0] * (m - 1) + [1e-15])                  # regular, but not surely
    out = np.full_like(mats, -7.0)
    sure = np.zeros(len(mats), bool)
    spd.sure_inverses(mats, out, sure, np.zeros((m, m)), np.zeros((m, m)))
    assert not sure[:5].any() and np.all(out[:5] == -7.0)
    det = np.linalg.det(mats[5:])
    tr = np.trace(mats[5:], axis1=-2, axis2=-1)
    # Away from the threshold (a factor 2 either side: the determinants' rounding is far smaller).
    clear = np.abs(np.log(det / (dynamics.SURE_REGULAR * m * EPS * tr ** m))) > np.log(2.0)
    assert np.array_equal(sure[5:][clear], (det > dynamics.SURE_REGULAR * m * EPS * tr ** m)[clear])
    ref = np.linalg.inv(mats[sure])
    kappa = np.linalg.cond(mats[sure])
    scale = np.max(np.abs(ref), axis=(-2, -1))
    assert np.all(np.max(np.abs(out[sure] - ref), axis=(-2, -1)) <= 8 * m * EPS * kappa * scale)
    assert np.array_equal(out[sure], np.swapaxes(out[sure], -1, -2))
