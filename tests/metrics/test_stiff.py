"""Stiff and extreme cases: the numbers stay right where they are hard (DESIGN.md, "Tests").

Near-singular Jacobians (condition 1e2 to 1e14), exactly singular and non-finite ones,
torques and gear ratios over eight decades, millimetre against kilometre scale, points on
the workspace boundary, and a batch through ``evaluate`` that mixes good and bad points.

Every reference value is computed in mpmath at 50 digits *from the float64 matrix actually
passed* (its entries are exact binary numbers), so a reported error is the error of our code
on that input, not the rounding that made the input.

Bounds asserted (relative errors; eps = 2.2e-16; kappa = the reference condition number of
the float64 matrix), and the worst seen with the fixed seeds here:

=============================  ===========================  ================  ====================
quantity                       bound asserted               worst observed    why this bound
=============================  ===========================  ================  ====================
sigma_min, 2 x 2 closed form   C_SMALL eps kappa            0.07 eps kappa    |det| / sigma_max;
                               (C_SMALL = 10)                                 det is off by
                                                                              ~eps sigma_max^2
sigma_min, LAPACK (3 x 3       C_SMALL eps kappa            0.74 eps kappa    backward-stable SVD:
above FAST_COND_LIMIT,                                                        |d sigma| <= p(n)
3 x 4, 4 x 4)                                                                 eps sigma_max
sigma_min, 3 x 3 closed form   C_CLOSED eps kappa^2         2.5 eps at        metrics/linalg.py's
(kappa <= FAST_COND_LIMIT)     (C_CLOSED = 10)              kappa = 1, 0.54   own table
                                                            eps kappa^2 above
sigma_max, every path          C_MAX eps (C_MAX = 10)       2.0 eps           well conditioned
condition number               the sum of the two above     0.74 eps kappa    ratio of the two
isotropic force                C_NORM eps (C_NORM = 4)      0.97 eps          column norms and a
                                                                              division, no inverse
anisotropic force              C_SMALL eps kappa            0.89 eps kappa    a solve with J^T
force linearity in torque      C_NORM eps                   2.0 eps           one product each
length scale k (1e-3..1e4)     1e-12                        1.0e-14           IK and J at k x
paper's cross-product formula  *at least* eps kappa for     9.5 eps kappa at  cancellation between
                               kappa >= 1e6; > 1e-2 for     1e6; 1.0 (100 %)  nearly parallel
                               kappa >= 1e12                at 1e12           reference forces
=============================  ===========================  ================  ====================
"""
from __future__ import annotations

import contextlib
import itertools
import warnings

import mpmath
import numpy as np
import pytest

from kinematics import FiveBar, Inverse3, Singularity
from metrics import anisotropy, bottleneck, conditioning, ellipsoids, isotropy, linalg, parallelepiped
from metrics.linalg import FAST_COND_LIMIT
from metrics.quantities import evaluate

DPS = 50
EPS = float(np.finfo(float).eps)
SEED = 20240611
KAPPAS = (1e2, 1e4, 1e6, 1e8, 1e10, 1e12, 1e14)
DECADES = tuple(10.0 ** k for k in range(-4, 5))      # eight decades, 1e-4 .. 1e4

C_SMALL = 10.0      # sigma_min and anything that solves with J: C eps kappa
C_CLOSED = 10.0     # 3 x 3 closed form: C eps kappa^2 (metrics/linalg.py docstring)
C_MAX = 10.0        # sigma_max: "a few eps"
C_NORM = 4.0        # column norms and a division

TABLE = ("condition_number", "isotropic_force", "anisotropic_force")


# -- helpers ---------------------------------------------------------------------------------
@contextlib.contextmanager
def strict():
    """Every numpy warning is an error (pyproject says so too; this holds outside pytest)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


def mp_matrix(a: np.ndarray) -> mpmath.matrix:
    """The float64 matrix as an mpmath matrix, entry for entry (float64 values are exact)."""
    return mpmath.matrix(np.asarray(a, float).tolist())


def mp_orthogonal(n: int, rng: np.random.Generator) -> mpmath.matrix:
    """A random orthogonal matrix, orthogonal to 50 digits (QR of a Gaussian matrix)."""
    with mpmath.workdps(DPS):
        q, _ = mpmath.qr(mp_matrix(rng.standard_normal((n, n))))
    return q


def jacobian_with_singular_values(shape: tuple[int, int], sv, rng: np.random.Generator) -> np.ndarray:
    """``U diag(sv) V^T`` built at 50 digits, then rounded to float64."""
    m, n = shape
    with mpmath.workdps(DPS):
        u, v = mp_orthogonal(m, rng), mp_orthogonal(n, rng)
        d = mpmath.zeros(m, n)
        for i, s in enumerate(sv):
            d[i, i] = mpmath.mpf(s)
        j = u * d * v.T
        return np.array([[float(j[i, k]) for k in range(n)] for i in range(m)])


def spectrum(kind: str, k: int, kappa: float) -> list:
    """``k`` singular values from 1 down to 1/kappa (mpmath numbers, exact at 50 digits)."""
    with mpmath.workdps(DPS):
        one, low = mpmath.mpf(1), 1 / mpmath.mpf(kappa)
        if kind == "geometric":
            return [mpmath.mpf(kappa) ** (-mpmath.mpf(i) / (k - 1)) for i in range(k)]
        if kind == "repeated small":
            return [one] + [low] * (k - 1)
        if kind == "mid":                    # well apart: the 3 x 3 closed form's home ground
            return [one] + [(one + low) / 2] * (k - 2) + [low]
        if kind == "repeated large":
            return [one] * (k - 1) + [low]
        if kind == "near-repeated small":
            return [one] + [low * (1 + mpmath.mpf("1e-6"))] * (k - 2) + [low]
        if kind == "near-repeated large":
            return [one] + [one * (1 - mpmath.mpf("1e-6"))] * (k - 2) + [low]
    raise AssertionError(kind)


def mp_singular_values(a: np.ndarray) -> list:
    """Singular values of the float64 matrix ``a`` at 50 digits, descending."""
    with mpmath.workdps(DPS):
        s = mpmath.svd_r(mp_matrix(a), compute_uv=False)
        return sorted((s[i] for i in range(len(s))), reverse=True)


def mp_isotropic(jac: np.ndarray, t) -> mpmath.mpf:
    """``min_u t_u / |J[:, u]|`` at 50 digits (``inf`` facet for a zero column)."""
    with mpmath.workdps(DPS):
        best = mpmath.inf
        for u in range(jac.shape[1]):
            norm = mpmath.sqrt(mpmath.fsum(mpmath.mpf(float(x)) ** 2 for x in jac[:, u]))
            if norm > 0:
                best = min(best, mpmath.mpf(float(t[u])) / norm)
        return best


def mp_anisotropic(jac: np.ndarray, t) -> mpmath.mpf:
    """Largest vertex norm of P: ``max_s |J^-T diag(t) s|`` over all 2^n sign vectors, 50 digits."""
    n = jac.shape[1]
    with mpmath.workdps(DPS):
        jt = mp_matrix(jac.T)
        best = mpmath.mpf(0)
        for signs in itertools.product((1, -1), repeat=n):
            rhs = mpmath.matrix([mpmath.mpf(float(t[u])) * signs[u] for u in range(n)])
            best = max(best, mpmath.norm(mpmath.lu_solve(jt, rhs)))
        return best


def rel_err(computed, exact) -> float:
    """``|computed - exact| / |exact|`` evaluated at 50 digits."""
    with mpmath.workdps(DPS):
        return float(abs((mpmath.mpf(float(computed)) - exact) / exact))


def random_jacobians(shape, kappa, count, rng, kinds=("geometric", "repeated large", "repeated small")):
    """``count`` matrices of each spectrum kind, scaled by a random factor in [1e-2, 1e2]."""
    k = min(shape)
    out = []
    for kind in kinds if k > 2 else ("geometric",):
        for _ in range(count):
            scale = 10.0 ** rng.uniform(-2, 2)
            out.append(jacobian_with_singular_values(shape, [scale * s for s in spectrum(kind, k, kappa)], rng))
    return np.array(out)


def sigma_min_bound(shape, kappa_ref: float) -> float:
    """Bound on the relative error of sigma_min for this shape and conditioning (see the table)."""
    fast = kappa_ref <= FAST_COND_LIMIT * (1 + 1e-6)
    if tuple(shape) == (3, 3) and fast:
        return max(C_CLOSED * EPS * kappa_ref ** 2, C_SMALL * EPS * kappa_ref)
    if min(shape) > 2 and max(shape) <= linalg.GRAM_MAX_SIZE and fast:
        # The Gram matrix's eigenvalues (metrics.linalg's table): (max(m, n) + 6) eps kappa^2 / 2.
        return max((max(shape) + 6) * EPS * kappa_ref ** 2 / 2, C_SMALL * EPS * kappa_ref)
    return C_SMALL * EPS * kappa_ref


# -- near-singular Jacobians: singular values and condition numbers ----------------------------
@pytest.mark.parametrize("kappa", KAPPAS)
@pytest.mark.parametrize("shape", [(2, 2), (3, 3), (3, 4), (4, 4)])
def test_singular_values_and_condition_number_against_mpmath(shape, kappa):
    """sigma_min within C eps kappa (3 x 3 closed form: 10 eps kappa^2), sigma_max within a few eps.

    2 x 2 and 3 x 3 take the closed forms of ``metrics.linalg``, 3 x 4 and 4 x 4 the Gram
    matrix's eigenvalues; above ``FAST_COND_LIMIT`` all but 2 x 2 defer to LAPACK. The whole
    set goes through in one batch, as in a map.
    """
    rng = np.random.default_rng([SEED, shape[0], shape[1], int(np.log10(kappa))])
    jacs = random_jacobians(shape, kappa, 4, rng)
    with strict():
        sv = linalg.singular_values(jacs)
        cond = conditioning.condition_number(jacs)
    assert sv.shape == (len(jacs), min(shape))
    for j, s, c in zip(jacs, sv, cond, strict=True):
        ref = mp_singular_values(j)
        kappa_ref = float(ref[0] / ref[-1])
        assert kappa / 2 < kappa_ref < kappa * 2          # rounding J moved kappa by ~eps kappa
        small = sigma_min_bound(shape, kappa_ref)
        assert rel_err(s[-1], ref[-1]) <= small
        assert rel_err(s[0], ref[0]) <= C_MAX * EPS
        assert np.all(np.diff(s) <= 0.0)                  # descending
        assert np.isfinite(c)
        with mpmath.workdps(DPS):
            assert rel_err(c, ref[0] / ref[-1]) <= small + C_MAX * EPS


@pytest.mark.parametrize("kappa", [1.0, 2.0, 10.0, 50.0, 99.0])
@pytest.mark.parametrize("kind", ["mid", "geometric", "repeated small", "repeated large",
                                  "near-repeated small", "near-repeated large"])
def test_3x3_closed_form_region_keeps_the_documented_bound(kind, kappa):
    """kappa <= FAST_COND_LIMIT: sigma_min within 10 eps kappa^2, sigma_max within a few eps.

    Repeated and nearly repeated singular values are where the trigonometric eigenvalue
    formula is weakest (arccos near +-1 loses half the digits of the split); metrics/linalg.py
    hands those to LAPACK, and this test holds it to the bound there too.
    """
    rng = np.random.default_rng([SEED, 33, int(kappa), len(kind)])
    jacs = random_jacobians((3, 3), kappa, 6, rng, kinds=(kind,))
    with strict():
        sv = linalg.singular_values(jacs)
        cond = conditioning.condition_number(jacs)
    for j, s, c in zip(jacs, sv, cond, strict=True):
        ref = mp_singular_values(j)
        kappa_ref = float(ref[0] / ref[-1])
        bound = C_CLOSED * EPS * max(kappa_ref, 1.0) ** 2
        assert rel_err(s[-1], ref[-1]) <= bound
        assert rel_err(s[0], ref[0]) <= C_MAX * EPS
        with mpmath.workdps(DPS):
            assert rel_err(c, ref[0] / ref[-1]) <= bound + C_MAX * EPS


@pytest.mark.parametrize("kappa", [2.0, 10.0, 50.0, 99.0])
def test_3x3_closed_form_is_what_runs_below_the_limit(kappa, monkeypatch):
    """Well-separated spectra with kappa < FAST_COND_LIMIT never reach LAPACK.

    Without this the bound test above could be passing on LAPACK's numbers alone.
    """
    rng = np.random.default_rng([SEED, 34, int(kappa)])
    jacs = random_jacobians((3, 3), kappa, 8, rng, kinds=("mid",))
    calls = []
    lapack = np.linalg.svd

    def counting_svd(a, *args, **kwargs):
        calls.append(np.shape(a))
        return lapack(a, *args, **kwargs)

    monkeypatch.setattr(np.linalg, "svd", counting_svd)
    with strict():
        sv = linalg.singular_values(jacs)
    assert calls == []
    for j, s in zip(jacs, sv, strict=True):
        ref = mp_singular_values(j)
        assert rel_err(s[-1], ref[-1]) <= C_CLOSED * EPS * float(ref[0] / ref[-1]) ** 2


# -- exactly singular and non-finite Jacobians ---------------------------------------------------
SINGULAR = {
    "2x2 rank 1": [[1.0, 2.0], [2.0, 4.0]],
    "2x2 rank 1, scaled": [[0.1, 0.3], [0.2, 0.6]],
    "2x2 zero column": [[0.0, 0.3], [0.0, 0.4]],
    "2x2 zero": [[0.0, 0.0], [0.0, 0.0]],
    "3x3 rank 2 (c2 = c0 + c1)": [[1.0, 2.0, 3.0], [4.0, 5.0, 9.0], [7.0, 8.0, 15.0]],
    "3x3 rank 1": [[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [3.0, 6.0, 9.0]],
    "3x3 zero column": [[1.0, 0.0, 3.0], [4.0, 0.0, 9.0], [7.0, 0.0, 15.0]],
    "3x3 two equal columns": [[0.3, 0.7, 0.7], [0.1, -0.2, -0.2], [1.1, 0.5, 0.5]],
    "3x3 zero row": [[0.3, 0.7, 0.2], [0.0, 0.0, 0.0], [1.1, 0.5, -0.4]],
    "3x3 zero": [[0.0] * 3] * 3,
}


@pytest.mark.parametrize("batched", [True, False], ids=["batch", "single"])
@pytest.mark.parametrize("name", list(SINGULAR))
def test_exactly_singular_jacobians(name, batched):
    """cond = inf, anisotropic = inf, reference forces nan; isotropic finite and exact.

    The isotropic radius is ``min_u t_u / |J[:, u]|`` (a zero column's facet is at infinity,
    so the all-zero matrix gives ``inf``: P is all of R^n). Batched, the singular matrix sits
    between two regular ones, which must come out untouched.
    """
    jac = np.array(SINGULAR[name])
    n = jac.shape[-1]
    t = np.array([0.3, 0.7, 1.1][:n])
    regular = np.eye(n) * 2.0 + 0.25
    arg = np.stack([regular, jac, regular]) if batched else jac
    with strict():
        cond = conditioning.condition_number(arg)
        iso = isotropy.isotropic_force(arg, torque_limits=t)
        facets = isotropy.facet_distances(arg, torque_limits=t)
        aniso = anisotropy.anisotropic_force(arg, torque_limits=t)
        ref = parallelepiped.reference_forces(arg, torque_limits=t)
        _, exists = linalg.inverse_transpose(arg)
    if batched:
        assert np.all(np.isfinite(cond[[0, 2]])) and np.all(exists[[0, 2]])
        assert np.all(np.isfinite(aniso[[0, 2]]))
        cond, iso, facets, aniso, ref, exists = cond[1], iso[1], facets[1], aniso[1], ref[1], exists[1]
    assert cond == np.inf
    assert aniso == np.inf
    assert np.all(np.isnan(ref))
    assert not exists
    expected = mp_isotropic(jac, t)
    if expected == mpmath.inf:
        assert iso == np.inf
    else:
        assert np.isfinite(iso) and rel_err(iso, expected) <= C_NORM * EPS
    zero_columns = np.all(jac == 0.0, axis=0)
    assert np.all(facets[zero_columns] == np.inf)
    assert np.all(np.isfinite(facets[~zero_columns]))


@pytest.mark.parametrize("batched", [True, False], ids=["batch", "single"])
@pytest.mark.parametrize("bad", [np.inf, -np.inf, np.nan], ids=["inf", "-inf", "nan"])
@pytest.mark.parametrize("n", [2, 3])
def test_non_finite_jacobians(n, bad, batched):
    """A direct singularity's unbounded J: cond = inf, isotropic = 0, anisotropic = nan.

    The column with the non-finite entry has an infinite norm, so its facet passes through
    the origin (isotropic force exactly 0, and that actuator is the bottleneck); the
    reference forces cannot be formed, so the anisotropic force is unknown (nan).
    """
    jac = np.arange(1.0, n * n + 1.0).reshape(n, n) + np.eye(n)
    jac[0, 1] = bad
    t = np.array([0.3, 0.7, 1.1][:n])
    regular = np.eye(n) * 2.0 + 0.25
    arg = np.stack([regular, jac]) if batched else jac
    with strict():
        cond = conditioning.condition_number(arg)
        iso = isotropy.isotropic_force(arg, torque_limits=t)
        neck = bottleneck.bottleneck_actuator(arg, torque_limits=t)
        aniso = anisotropy.anisotropic_force(arg, torque_limits=t)
        ref = parallelepiped.reference_forces(arg, torque_limits=t)
        sv = linalg.singular_values(arg)
    if batched:
        assert np.isfinite(cond[0]) and np.isfinite(aniso[0]) and iso[0] > 0.0
        cond, iso, neck, aniso, ref, sv = cond[1], iso[1], neck[1], aniso[1], ref[1], sv[1]
    assert cond == np.inf
    assert iso == 0.0
    assert neck == 1
    assert np.isnan(aniso)
    assert np.all(np.isnan(ref))
    assert np.all(np.isinf(sv))


# -- torques and gear ratios over eight decades ----------------------------------------------------
@pytest.mark.parametrize("scale", DECADES)
@pytest.mark.parametrize("n", [2, 3])
def test_torque_scale_over_eight_decades(n, scale):
    """Isotropic and anisotropic force against mpmath, for t = scale * base and for torques
    that span the eight decades across actuators; both scale linearly with the torque.

    Bounds: isotropic C_NORM eps (column norms only), anisotropic C_SMALL eps kappa (a
    solve with J^T), linearity a few eps.
    """
    rng = np.random.default_rng([SEED, 8, n, int(np.log10(scale)) + 4])
    jacs = np.concatenate([random_jacobians((n, n), kappa, 2, rng, kinds=("geometric",))
                           for kappa in (10.0, 1e4, 1e8)])
    base = np.array([0.3, 0.7, 1.1][:n])
    spread = np.array([1e-4, 1.0, 1e4][:n]) if n == 3 else np.array([1e-4, 1e4])
    for t in (scale * base, scale * spread):
        with strict():
            iso = isotropy.isotropic_force(jacs, torque_limits=t)
            aniso = anisotropy.anisotropic_force(jacs, torque_limits=t)
            iso_1 = isotropy.isotropic_force(jacs, torque_limits=t / scale)
            aniso_1 = anisotropy.anisotropic_force(jacs, torque_limits=t / scale)
        for j, fi, fa in zip(jacs, iso, aniso, strict=True):
            ref = mp_singular_values(j)
            kappa_ref = float(ref[0] / ref[-1])
            assert rel_err(fi, mp_isotropic(j, t)) <= C_NORM * EPS
            assert rel_err(fa, mp_anisotropic(j, t)) <= C_SMALL * EPS * kappa_ref
        np.testing.assert_allclose(iso, scale * iso_1, rtol=C_NORM * EPS, atol=0)
        np.testing.assert_allclose(aniso, scale * aniso_1, rtol=C_NORM * EPS, atol=0)


@pytest.mark.parametrize("gear", DECADES)
def test_gear_ratios_over_eight_decades_through_evaluate(gear):
    """Inverse3 with every gear ratio times ``gear``: J does not change, forces scale with it."""
    base = Inverse3()
    device = base.replace(gear_ratios=tuple(gear * g for g in base.params.gear_ratios))
    c = base.params.plane_offset
    points = np.array([[0.15, c, 0.25], [0.2, c, 0.1], [0.25, c, 0.3], [0.3, c, 0.2]])
    # Both through the same path: a request with "jacobian" runs in numpy whole (no kernel outputs J),
    # while the compiled kernel forms J from the point's ratios and differs from numpy's by the IK's
    # rounding (tests/metrics/test_kernels.py), so a mixed pair would compare two paths, not two gears.
    with strict():
        ev = evaluate(device, points, TABLE + ("jacobian",))
        ev_1 = evaluate(base, points, TABLE + ("jacobian",))
    assert ev.feasible.all()
    np.testing.assert_array_equal(ev.values["jacobian"], ev_1.values["jacobian"])
    np.testing.assert_array_equal(ev.values["condition_number"], ev_1.values["condition_number"])
    for name in ("isotropic_force", "anisotropic_force"):
        np.testing.assert_allclose(ev.values[name], gear * ev_1.values[name], rtol=C_NORM * EPS, atol=0)
    t = device.torque_limits()
    v = ev.values
    for j, fi, fa in zip(v["jacobian"], v["isotropic_force"], v["anisotropic_force"], strict=True):
        ref = mp_singular_values(j)
        assert rel_err(fi, mp_isotropic(j, t)) <= C_NORM * EPS
        assert rel_err(fa, mp_anisotropic(j, t)) <= C_SMALL * EPS * float(ref[0] / ref[-1])


# -- millimetre against kilometre ------------------------------------------------------------------
SCALES = (1e-3, 1e-2, 1e-1, 1e1, 1e2, 1e3, 1e4)     # 0.1 mm links .. 1 km links
INVERSE3_LENGTHS = ("proximal_length", "distal_length", "base_height", "shoulder_offset",
                    "tool_offset", "body_radius", "body_height")


def fivebar_interior_points() -> np.ndarray:
    """Reachable five-bar points at moderate conditioning (so 1e-12 is a fair tolerance)."""
    x, y = np.meshgrid(np.linspace(-0.12, 0.12, 7), np.linspace(0.06, 0.22, 5), indexing="ij")
    points = np.stack([x, y], -1).reshape(-1, 2)
    ev = evaluate(FiveBar(), points, ("condition_number",))
    keep = ev.feasible & (ev.values["condition_number"] < 50.0)
    assert keep.sum() >= 10
    return points[keep]


def inverse3_points() -> np.ndarray:
    """Inverse3 points inside the workspace, on three planes of the base joint (deg -80, 0, 40)."""
    c = Inverse3().params.plane_offset
    plane = np.array([[0.15, c, 0.25], [0.2, c, 0.1], [0.25, c, 0.3], [0.1, c, 0.35], [0.3, c, 0.2]])
    out = []
    for deg in (-80.0, 0.0, 40.0):
        a = np.deg2rad(deg)
        rot = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
        out.append(plane @ rot.T)
    return np.concatenate(out)


@pytest.mark.parametrize("k", SCALES)
@pytest.mark.parametrize("device", ["fivebar", "inverse3"])
def test_length_scale_invariance(device, k):
    """All lengths times k: J scales by k (all joints revolute), so the condition number is
    unchanged and both forces scale as 1/k, to 1e-12 relative."""
    if device == "fivebar":
        base = FiveBar()
        scaled = FiveBar(proximal=0.10 * k, distal=0.15 * k, half_base=0.03 * k)
        points = fivebar_interior_points()
    else:
        base = Inverse3()
        p = base.params
        scaled = base.replace(**{name: k * getattr(p, name) for name in INVERSE3_LENGTHS})
        points = inverse3_points()
    with strict():
        ev_1 = evaluate(base, points, TABLE)
        ev_k = evaluate(scaled, k * points, TABLE)
    assert ev_1.feasible.all() and ev_k.feasible.all()
    np.testing.assert_allclose(ev_k.values["condition_number"], ev_1.values["condition_number"], rtol=1e-12)
    np.testing.assert_allclose(k * ev_k.values["isotropic_force"], ev_1.values["isotropic_force"], rtol=1e-12)
    np.testing.assert_allclose(k * ev_k.values["anisotropic_force"], ev_1.values["anisotropic_force"], rtol=1e-12)


# -- the paper's cross-product formula against the stable one --------------------------------------
@pytest.mark.parametrize("kappa", KAPPAS)
def test_cross_product_formula_loses_what_the_stable_one_keeps(kappa):
    """Ill-conditioned J: the reference forces (columns of J^-T diag(t)) are nearly parallel.

    ``isotropic_force`` (column norms only) stays within C_NORM eps of mpmath at every kappa.
    The paper's eq. 7-8 as printed (``isotropic_force_cross_product``) crosses nearly parallel
    reference forces; observed, its error grows like (3..12)e-3 eps kappa^1.5 (1e-6 at kappa
    1e8, 100 % at 1e12). Asserted: at least eps kappa for kappa >= 1e6 (worst of the batch),
    and over 1e-2 (one digit or none left) for kappa >= 1e12, where the stable formula is
    still right to a few eps.
    """
    rng = np.random.default_rng([SEED, 7, int(np.log10(kappa))])
    jacs = random_jacobians((3, 3), kappa, 8, rng, kinds=("geometric",))
    t = np.array([0.3, 0.7, 1.1])
    with strict():
        stable = isotropy.isotropic_force(jacs, torque_limits=t)
        cross = isotropy.isotropic_force_cross_product(jacs, torque_limits=t)
        ref_forces = parallelepiped.reference_forces(jacs, torque_limits=t)
    worst_cross = 0.0
    for j, fs, fc, r in zip(jacs, stable, cross, ref_forces, strict=True):
        exact = mp_isotropic(j, t)
        assert rel_err(fs, exact) <= C_NORM * EPS
        worst_cross = max(worst_cross, rel_err(fc, exact))
        # the reference forces really are nearly parallel: for a geometric spectrum |sin| of
        # the angle between the closest two is ~ sigma_3 / sigma_2 = 1 / sqrt(kappa)
        unit = r / np.linalg.norm(r, axis=0)
        sines = [np.linalg.norm(np.cross(unit[:, u], unit[:, (u + 1) % 3])) for u in range(3)]
        assert min(sines) < 100.0 / np.sqrt(kappa)
    if kappa >= 1e6:
        assert worst_cross >= EPS * kappa
    if kappa >= 1e12:
        assert worst_cross > 1e-2


# -- points on the workspace boundary ----------------------------------------------------------------
def fivebar_circle(radius: float, lo_deg: float, hi_deg: float, count: int = 2001) -> np.ndarray:
    """Points at ``radius`` from the default five-bar's base joint 1, ``(-a3, 0)``, in float64."""
    a3 = FiveBar().params.half_base
    t = np.deg2rad(np.linspace(lo_deg, hi_deg, count))
    return np.stack([-a3 + radius * np.cos(t), radius * np.sin(t)], axis=-1)


# Outer circle (a1 + a2) and inner circle |a1 - a2| of leg 1; the angle ranges keep the
# point inside leg 2's annulus so that only leg 1 is at its boundary.
BOUNDARIES = {"outer": (lambda p: p.proximal + p.distal, -80.0, 80.0, 1.0 + 1e-6),
              "inner": (lambda p: abs(p.proximal - p.distal), 60.0, 300.0, 1.0 - 1e-6)}


@pytest.mark.parametrize("which", list(BOUNDARIES))
def test_fivebar_boundary_points_are_reachable_and_singular(which):
    """Leg 1 fully stretched (outer) or folded (inner).

    Rounding puts many of these points a few ulps outside the annulus (the IK cosine
    overshoots 1); inverse() clips that, so every one is reachable with finite joints, and
    is classified INVERSE. The tolerance must exceed the ~sqrt(eps) angle a point within an
    ulp of the circle can show (arccos(1 - eps) = 2e-8), so ``singular_tol = 1e-6``; a point a
    relative 1e-6 inside is then not singular. A relative 1e-6 outside is unreachable: nan
    joints, masked, nan quantities.
    """
    device = FiveBar(singular_tol=1e-6)
    p = device.params
    radius_of, lo, hi, outside = BOUNDARIES[which]
    radius = radius_of(p)
    points = fivebar_circle(radius, lo, hi)
    # the test must exercise the clip: some cosines overshoot 1 in magnitude by rounding
    rho = np.hypot(points[:, 0] + p.half_base, points[:, 1])
    cosine = (p.proximal ** 2 + rho ** 2 - p.distal ** 2) / (2 * p.proximal * rho)
    assert np.count_nonzero(np.abs(cosine) > 1.0) > 100
    with strict():
        q, reachable = device.inverse(points)
        classes = device.singularity(q, points)
        ev = evaluate(device, points, TABLE + ("singularity", "bottleneck", "jacobian"))
    assert reachable.all() and np.all(np.isfinite(q))
    assert np.all(classes == Singularity.INVERSE)
    assert ev.feasible.all()
    # FK of the IK lands back on the point, in one of the two assemblies
    back = np.stack([device.forward(q, assembly_mode=mode)[0] for mode in ("up", "down")])
    assert np.min(np.max(np.abs(back - points), axis=-1), axis=0).max() < 1e-9 * radius
    # leg 1 limits no direction here: actuator 2 is the bottleneck, the isotropic force is
    # its facet distance (finite), the polytope is (nearly) unbounded along leg 1
    v = ev.values
    t = device.torque_limits()
    assert np.all(v["bottleneck"] == 1)
    assert np.all(v["condition_number"] > 1e6)
    facets = isotropy.facet_distances(v["jacobian"], torque_limits=t)
    assert np.all(np.isfinite(v["isotropic_force"])) and np.all(v["isotropic_force"] > 0)
    assert np.all(v["anisotropic_force"] >= facets.max(axis=-1) * (1 - C_NORM * EPS))
    assert np.all(facets[:, 0] > 1e6 * facets[:, 1])      # leg 1's facet is (nearly) at infinity
    # where the computed J is singular to rounding, cond and anisotropic force are inf together
    np.testing.assert_array_equal(np.isinf(v["condition_number"]), np.isinf(v["anisotropic_force"]))
    for j, fi in zip(v["jacobian"][::50], v["isotropic_force"][::50], strict=True):
        assert rel_err(fi, mp_isotropic(j, t)) <= C_NORM * EPS
    # a relative 1e-6 inside the annulus: reachable and no longer singular
    inside = fivebar_circle(radius * (2.0 - outside), lo, hi)
    with strict():
        q_in, ok_in = device.inverse(inside)
        classes_in = device.singularity(q_in, inside)
    assert ok_in.all() and np.all(classes_in == Singularity.NONE)
    # a relative 1e-6 outside: unreachable and masked
    beyond = fivebar_circle(radius * outside, lo, hi)
    with strict():
        q_out, ok_out = device.inverse(beyond)
        ev_out = evaluate(device, beyond, TABLE + ("singularity", "bottleneck"))
    assert not ok_out.any() and np.all(np.isnan(q_out))
    assert not ev_out.feasible.any() and np.all(np.isnan(ev_out.joints))
    for name in TABLE:
        assert np.all(np.isnan(ev_out.values[name]))
    assert np.all(ev_out.values["singularity"] == -1) and np.all(ev_out.values["bottleneck"] == -1)


@pytest.mark.parametrize("which", ["stretched", "folded"])
def test_inverse3_reach_boundary(which):
    """The coaxial five-bar at a3 = l1 + l2 (h = 0) and a3 = l2 - l1 (h = pi).

    inverse() clips the ulps-level overshoot of cos h, so every point is reachable with
    finite joints; the link spread |p1 - p2| = 2h is then 0 or 2 pi, outside Table 2's
    20..200 deg, so ``feasible`` is False and ``evaluate`` masks the points. Stretched, J has
    (nearly) equal p1 and p2 columns: cond > 1e6 (inf where the clip made them equal),
    anisotropic inf with it, isotropic finite and exact. A relative 1e-6 beyond is
    unreachable with nan joints.
    """
    device = Inverse3()
    p = device.params
    l1, l2, c = p.proximal_length, p.distal_length, p.plane_offset
    a3 = l1 + l2 if which == "stretched" else l2 - l1
    th3, th0 = np.meshgrid(np.deg2rad(np.linspace(-80, 80, 41)), np.deg2rad(np.linspace(-200, 40, 9)),
                           indexing="ij")

    def at(reach):
        u, w = reach * np.cos(th3), reach * np.sin(th3)
        return np.stack([u * np.cos(th0) - c * np.sin(th0), u * np.sin(th0) + c * np.cos(th0),
                         p.base_height + w], -1).reshape(-1, 3)

    points = at(a3)
    t = device.torque_limits()
    with strict():
        q, reachable = device.inverse(points)
        feasible = device.feasible(q, points)
        jac = device.jacobian(q)
        cond = conditioning.condition_number(jac)
        iso = isotropy.isotropic_force(jac, torque_limits=t)
        aniso = anisotropy.anisotropic_force(jac, torque_limits=t)
        ev = evaluate(device, points, TABLE)
    assert reachable.all() and np.all(np.isfinite(q))
    spread = np.abs(q[:, 1] - q[:, 2])
    expected_spread = 0.0 if which == "stretched" else 2 * np.pi
    np.testing.assert_allclose(spread, expected_spread, atol=1e-7)
    assert not feasible.any() and not ev.feasible.any()
    assert all(np.all(np.isnan(ev.values[name])) for name in TABLE)
    assert np.all(cond > 1e6)
    np.testing.assert_array_equal(np.isinf(cond), np.isinf(aniso))
    assert np.all(np.isfinite(iso)) and np.all(iso > 0)
    if which == "stretched":
        exact = spread == 0.0
        assert exact.sum() > 100                       # the clip happened, many times
        assert np.all(np.isinf(cond[exact])) and np.all(aniso[exact] == np.inf)
    for j, fi in zip(jac[::20], iso[::20], strict=True):
        assert rel_err(fi, mp_isotropic(j, t)) <= C_NORM * EPS
    factor = 1 + 1e-6 if which == "stretched" else 1 - 1e-6
    with strict():
        q_out, ok_out = device.inverse(at(a3 * factor))
    assert not ok_out.any() and np.all(np.isnan(q_out))


# -- evaluate on a batch mixing feasible, unreachable and singular points ------------------------
def test_evaluate_fivebar_mixed_batch():
    """Finite where the truth is finite, inf/nan and the mask exactly where it is not."""
    device = FiveBar(singular_tol=1e-6)
    p = device.params
    r_out = p.proximal + p.distal
    interior = np.array([[0.0, 0.15], [0.05, 0.12], [-0.06, 0.2], [0.1, 0.05], [0.02, -0.1]])
    boundary = np.array([[-p.half_base + r_out * np.cos(a), r_out * np.sin(a)] for a in (0.3, 0.7, 1.1)])
    unreachable = np.array([[0.0, 0.3],          # beyond both outer circles
                            [0.0, 0.01],         # inside the inner circles
                            [1e3, 1e3],          # far away
                            [np.nan, 0.1],       # not a number
                            [np.inf, 0.0]])
    points = np.concatenate([interior[:2], unreachable[:2], boundary, interior[2:], unreachable[2:]])
    kind = ["in"] * 2 + ["out"] * 2 + ["edge"] * 3 + ["in"] * 3 + ["out"] * 3
    kind = np.array(kind)
    names = TABLE + ("singularity", "bottleneck", "jacobian")
    with strict():
        ev = evaluate(device, points.reshape(13, 1, 2), names)     # a batch shape is kept
    assert ev.feasible.shape == (13, 1)
    feasible = ev.feasible[:, 0]
    v = {name: ev.values[name][:, 0] for name in names}
    np.testing.assert_array_equal(feasible, kind != "out")
    t = device.torque_limits()
    for i in np.flatnonzero(kind == "in"):
        jac = v["jacobian"][i]
        ref = mp_singular_values(jac)
        kappa_ref = float(ref[0] / ref[-1])
        with mpmath.workdps(DPS):
            assert rel_err(v["condition_number"][i], ref[0] / ref[-1]) <= 2 * C_SMALL * EPS * kappa_ref
        assert rel_err(v["isotropic_force"][i], mp_isotropic(jac, t)) <= C_NORM * EPS
        assert rel_err(v["anisotropic_force"][i], mp_anisotropic(jac, t)) <= C_SMALL * EPS * kappa_ref
        assert v["singularity"][i] == Singularity.NONE
    edge = kind == "edge"
    assert np.all(v["singularity"][edge] == Singularity.INVERSE)
    assert np.all(v["condition_number"][edge] > 1e6)
    assert np.all(np.isfinite(v["isotropic_force"][edge])) and np.all(v["bottleneck"][edge] == 1)
    assert np.all(v["anisotropic_force"][edge] > 1e5)
    out = kind == "out"
    assert np.all(np.isnan(ev.joints[out]))
    for name in TABLE:
        assert np.all(np.isnan(v[name][out]))
        assert np.all(np.isfinite(v[name][kind == "in"]))
    assert np.all(np.isnan(v["jacobian"][out]))
    assert np.all(v["singularity"][out] == -1) and np.all(v["bottleneck"][out] == -1)
    # batch = one at a time
    for i, x in enumerate(points):
        with strict():
            one = evaluate(device, x, TABLE)
        for name in TABLE:
            np.testing.assert_array_equal(one.values[name], v[name][i])


def test_evaluate_inverse3_mixed_batch():
    """Feasible, unreachable (beyond reach, within the plane offset of the axis) and
    reachable-but-infeasible (body constraint, link spread) points in one batch."""
    device = Inverse3()
    p = device.params
    c = p.plane_offset
    points = np.array([[0.15, c, 0.25],                                    # feasible
                       [0.5, c, 0.2],                                      # beyond l1 + l2
                       [0.2, c, 0.1],                                      # feasible
                       [0.0, 0.0, 0.3],                                    # on the base axis
                       [0.03, c, 0.1],                                     # inside the body
                       [p.proximal_length + p.distal_length, c, p.base_height],  # stretched
                       [0.3, c, 0.2]])                                     # feasible
    expected_reachable = np.array([True, False, True, False, True, True, True])
    expected_feasible = np.array([True, False, True, False, False, False, True])
    with strict():
        _, reachable = device.inverse(points)
        ev = evaluate(device, points, TABLE + ("jacobian",))
    np.testing.assert_array_equal(reachable, expected_reachable)
    np.testing.assert_array_equal(ev.feasible, expected_feasible)
    t = device.torque_limits()
    for i in np.flatnonzero(expected_feasible):
        j = ev.values["jacobian"][i]
        ref = mp_singular_values(j)
        kappa_ref = float(ref[0] / ref[-1])
        with mpmath.workdps(DPS):
            assert rel_err(ev.values["condition_number"][i], ref[0] / ref[-1]) <= C_CLOSED * EPS * kappa_ref ** 2
        assert rel_err(ev.values["isotropic_force"][i], mp_isotropic(j, t)) <= C_NORM * EPS
        assert rel_err(ev.values["anisotropic_force"][i], mp_anisotropic(j, t)) <= C_SMALL * EPS * kappa_ref
    for name in TABLE:
        assert np.all(np.isnan(ev.values[name][~expected_feasible]))
    assert np.all(np.isnan(ev.joints[~expected_feasible]))


def test_evaluate_uses_the_jacobian_of_the_pose_reached():
    """Below the base line the five-bar's working mode ``+-`` reaches points in the *other*
    assembly than the configured ``up``; the Jacobian must be the one at the point, not at
    ``forward(q)``. Independent check: J^-1 = d inverse(x) / dx by central differences."""
    device = FiveBar()
    points = np.array([[-0.02, -0.05], [0.0, -0.05], [0.02, -0.05], [0.0, 0.15]])
    q, _ = device.inverse(points)
    up, _ = device.forward(q)
    assert np.all(np.max(np.abs(up[:3] - points[:3]), axis=-1) > 0.1)   # really the other assembly
    with strict():
        ev = evaluate(device, points, ("jacobian", "condition_number"))
    h = 1e-7
    for x, jac in zip(points, ev.values["jacobian"], strict=True):
        dq = np.stack([(device.inverse(x + h * e)[0] - device.inverse(x - h * e)[0]) / (2 * h)
                       for e in np.eye(2)], axis=-1)
        np.testing.assert_allclose(jac @ dq, np.eye(2), atol=1e-6)


# -- singular points are reported as singular (issue 7, section 2) ------------------------------------
def mp_circle_offsets(point, base_x: float, radii) -> list:
    """``| |C - O| - r |`` at 50 digits for each radius: how far the float point is from each circle."""
    with mpmath.workdps(DPS):
        x, y = (mpmath.mpf(float(c)) for c in point)
        rho = mpmath.sqrt((x - mpmath.mpf(base_x)) ** 2 + y ** 2)
        return [abs(rho - mpmath.mpf(r)) for r in radii]


def double_inverse_points(device: FiveBar) -> np.ndarray:
    """Points where a circle of leg 1 (|C - O_1| = a1 +- a2) meets one of leg 2: both legs singular.

    Where the circles meet, ``x = (r1^2 - r2^2) / (4 a3)``; the float point lies within rounding
    (a few eps of the link scale, checked at 50 digits by the caller) of both circles.
    """
    p = device.params
    a1, a2, a3 = p.proximal, p.distal, p.half_base
    radii = [a1 + a2, abs(a2 - a1)]
    out = []
    for r1 in radii:
        for r2 in radii:
            x = (r1 * r1 - r2 * r2) / (4.0 * a3)
            y_sq = r1 * r1 - (x + a3) ** 2
            if y_sq > 0:
                out += [[x, np.sqrt(y_sq)], [x, -np.sqrt(y_sq)]]
    return np.array(out)


SINGH = dict(proximal=0.10, distal=0.15, half_base=0.03)


@pytest.mark.parametrize("k", [1e-3, 1.0, 1e3])
def test_fivebar_double_inverse_singularity_takes_the_singular_values(k):
    """Both legs folded (issue 7: ``pose fivebar_singh --at 0,40`` said ``none``, cond 1.333,
    8.6e8 N): class INVERSE with both legs singular, J = 0, and every quantity its limit:
    condition number, isotropic and anisotropic force, facet distances and force-ellipsoid
    radii ``inf``; the bottleneck is a tie. Map (``evaluate``) and pose agree. At every
    length scale k: the tolerance is relative to the links, not absolute.

    Reference: the point's distance from both circles at 50 digits is at rounding level
    (<= 8 eps of the link scale), so the true pose is (within rounding) the double singularity,
    where J = J_p^-1 diag(a1 a2 sin(elbow angles)) = 0 exactly.
    """
    from app.logic.pose_report import to_dict
    from metrics.pose import analyse_pose

    device = FiveBar(**{name: k * v for name, v in SINGH.items()})
    p = device.params
    scale = p.proximal + p.distal + p.half_base
    points = np.concatenate([[[0.0, 0.04 * k]], double_inverse_points(device)])
    radii = [p.proximal + p.distal, abs(p.distal - p.proximal)]
    for x in points:
        assert min(mp_circle_offsets(x, -p.half_base, radii)) <= 8 * EPS * scale
        assert min(mp_circle_offsets(x, p.half_base, radii)) <= 8 * EPS * scale
    names = TABLE + ("singularity", "bottleneck", "jacobian", "force_ellipsoid_min_radius")
    with strict():
        ev = evaluate(device, points, names)
        q, _ = device.inverse(points)
        legs = device.singular_legs(q, points)
    assert ev.feasible.all()
    v = ev.values
    assert np.all(legs)
    assert np.all(v["singularity"] == Singularity.INVERSE)
    assert np.all(v["jacobian"] == 0.0)
    for name in TABLE + ("force_ellipsoid_min_radius",):
        assert np.all(v[name] == np.inf), name
    assert np.all(v["bottleneck"] == bottleneck.BOTTLENECK_TIE)
    with strict():
        report = analyse_pose(device, points[0])
    assert report.singularity == Singularity.INVERSE
    assert report.condition_number == np.inf and report.isotropic_force == np.inf
    assert report.anisotropic_force == np.inf
    assert np.all(report.facet_distances == np.inf)
    assert np.all(report.force_ellipsoid.radii == np.inf)
    assert report.bottleneck_name == "tie" and report.bottleneck_phrase == "no actuator limits it"
    assert report.singular_legs == ("theta_1", "theta_2")      # a double inverse singularity
    d = to_dict(report)
    assert d["condition_number"] == d["isotropic_force"] == d["anisotropic_force"] == "inf"
    assert d["singularity"] == "inverse" and d["singular_legs"] == ["theta_1", "theta_2"]
    # 1e-7 of the link scale into both annuli (metrics.suprema's probe points): regular again,
    # with finite values that grow as the point nears the singularity.
    corners = device.singular_loci()["all_inverse"]
    with strict():
        near = evaluate(device, corners, names)
    ok = near.feasible
    assert ok.any()
    assert np.all(near.values["singularity"][ok] == Singularity.NONE)
    assert np.all(np.isfinite(near.values["isotropic_force"][ok]))
    assert np.all(near.values["isotropic_force"][ok] > 1e2 * evaluate(device, [[0.0, 0.15 * k]],
                                                                           ("isotropic_force",)).values[
        "isotropic_force"][0])


@pytest.mark.parametrize("seed", range(4))
def test_fivebar_singular_tolerance_is_relative_to_the_links(seed):
    """Points on the stretched and folded circles of random geometries over six decades of
    length scale: every one is INVERSE with the default, derived tolerance (the old absolute
    ``1e-9`` missed them: IK's arccos near 1 leaves ``|sin| ~ sqrt(eps)``), and a relative
    ``1e-9`` inside the annulus (``|sin| ~ 1e-4``) none is.

    Reference: the true ``|sin|`` at a point a relative ``delta`` inside the circle of radius
    ``r`` is ``sqrt(2 delta) r / sqrt(a1 a2)`` to first order, >= 1e-5 here, 50 times the
    tolerance; on the circle it is 0.
    """
    rng = np.random.default_rng([SEED, 70, seed])
    tested = 0
    for _ in range(6):
        a1, a2, a3 = rng.uniform(0.05, 0.3, 3) * 10.0 ** rng.uniform(-3, 3)
        device = FiveBar(proximal=a1, distal=a2, half_base=a3)
        assert device.singular_tolerance < 1e-6
        angle = rng.uniform(0.0, 2.0 * np.pi, 500)
        ring = np.stack([np.cos(angle), np.sin(angle)], -1)
        for r in (a1 + a2, abs(a1 - a2)):
            for base in (-a3, a3):
                for factor, expect_singular in ((1.0, True), (1.0 - 1e-9 if r == a1 + a2 else 1.0 + 1e-9, False)):
                    points = np.array([base, 0.0]) + factor * r * ring
                    with strict():
                        q, ok = device.inverse(points)
                        legs = device.singular_legs(q[ok], points[ok])
                    leg = 0 if base < 0 else 1
                    if expect_singular:
                        assert np.all(legs[:, leg])
                        tested += int(ok.sum())
                    else:
                        assert not np.any(legs[:, leg])
    assert tested >= 1000          # the other leg reaches enough of the circles to test


def test_fivebar_singular_tolerance_override_is_validated():
    """``singular_tol`` overrides the derived tolerance; a non-positive one is refused by name."""
    assert FiveBar(singular_tol=1e-6).singular_tolerance == 1e-6
    derived = FiveBar(**SINGH).singular_tolerance
    assert 1e-7 < derived < 3e-7                       # sqrt(16 eps S), S = 10.6 for 100/150/30 mm
    assert FiveBar(**{k: 1e3 * v for k, v in SINGH.items()}).singular_tolerance == pytest.approx(derived, rel=1e-12)
    for bad in (0.0, -1e-9, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="singular_tol"):
            FiveBar(singular_tol=bad)


def test_fivebar_direct_singularity_gives_an_unbounded_jacobian():
    """Distal links aligned (C between the elbows): class DIRECT, J = inf, isotropic force 0
    (the platform gains a freedom: it holds no force in one direction), condition number inf.
    From the pose and from FK alike (FK's height sqrt(a2^2 - half^2) is off by ~sqrt(eps))."""
    a1, a3, a2 = 0.10, 0.03, 0.12
    device = FiveBar(proximal=a1, distal=a2, half_base=a3)
    alpha = np.arccos((a2 - a3) / a1)
    q = np.array([np.pi - alpha, alpha])
    c = np.array([0.0, a1 * np.sin(alpha)])
    with strict():
        for x in (c, None):
            assert device.singularity(q, x) == Singularity.DIRECT
            jac = device.jacobian(q, x)
            assert np.all(jac == np.inf)
            t = device.torque_limits()
            assert isotropy.isotropic_force(jac, torque_limits=t) == 0.0
            assert conditioning.condition_number(jac) == np.inf
        # a regular pose nearby keeps its finite J
        assert device.singularity(q + [-0.05, 0.05]) == Singularity.NONE
        assert np.all(np.isfinite(device.jacobian(q + [-0.05, 0.05])))


def test_single_inverse_singularity_prints_inf_not_1e16():
    """``pose fivebar_singh --at -220,0``: leg 2 stretched. Its facet is at infinity (was
    2.56e16 N), the force ellipsoid's radius along leg 2 is ``inf`` (was 4.9e16 N) and the
    velocity radius 0; the other facet is finite and right to C_NORM eps (mpmath)."""
    from app.logic.pose_report import to_dict
    from metrics.pose import analyse_pose

    device = FiveBar(**SINGH, motor_torques=(0.1, 0.1), gear_ratios=(10.0, 10.0))
    with strict():
        r = analyse_pose(device, (-0.22, 0.0))
    assert r.singularity == Singularity.INVERSE
    assert r.facet_distances[1] == np.inf and np.isfinite(r.facet_distances[0])
    assert rel_err(r.facet_distances[0], mp_isotropic(r.jacobian[:, :1], r.torque_limits[:1])) <= C_NORM * EPS
    assert r.condition_number == np.inf and r.anisotropic_force == np.inf
    assert r.force_ellipsoid.radii[0] == np.inf and np.isfinite(r.force_ellipsoid.radii[1])
    assert r.velocity_ellipsoid.radii[-1] == 0.0
    assert r.isotropic_force == r.facet_distances[0] and r.bottleneck == 0
    assert r.singular_legs == ("theta_2",)
    assert to_dict(r)["facet_distances"][1] == "inf"


@pytest.mark.parametrize("name", list(SINGULAR))
def test_exactly_singular_jacobians_have_infinite_ellipsoid_radii(name):
    """Rank-deficient J (rank from mpmath's singular values: zero to 50 digits): the force
    ellipsoid has ``n - rank`` infinite radii (was 1.15e16 N for [[1, 2], [2, 4]]) and the
    velocity ellipsoid as many zero radii; the others are right to C_SMALL eps kappa."""
    jac = np.array(SINGULAR[name])
    n = jac.shape[-1]
    t = np.array([0.3, 0.7, 1.1][:n])
    with mpmath.workdps(DPS):
        # J diag(1/t) formed at 50 digits from the exact float64 J and t (in float64 the
        # quotient's rounding would make it regular by 1e-17)
        scaled = mp_matrix(jac)
        for i in range(n):
            for u in range(n):
                scaled[i, u] /= mpmath.mpf(float(t[u]))
        s = mpmath.svd_r(scaled, compute_uv=False)
        exact = sorted((s[i] for i in range(n)), reverse=True)
        rank = sum(1 for s in exact if s > mpmath.mpf(10) ** -40)
    with strict():
        force = ellipsoids.force_ellipsoid(jac, torque_limits=t)
        vel = ellipsoids.velocity_ellipsoid(jac, joint_speed_limits=1.0 / t)
        small = ellipsoids.force_ellipsoid_min_radius(jac, torque_limits=t)
    assert np.count_nonzero(force.radii == np.inf) == n - rank
    assert np.count_nonzero(vel.radii == 0.0) == n - rank
    if rank:
        kappa = float(exact[0] / exact[rank - 1])
        finite = np.sort(force.radii[np.isfinite(force.radii)])
        for radius, s in zip(finite, exact[:rank], strict=True):
            with mpmath.workdps(DPS):
                assert rel_err(radius, 1 / s) <= C_SMALL * EPS * kappa
        assert rel_err(small, 1 / exact[0]) <= C_MAX * EPS
    else:
        assert small == np.inf
