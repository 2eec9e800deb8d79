"""Extreme but valid numbers (issue 7, section 5): results do not depend on the overall scale.

A Jacobian ``c J`` and torques ``s t`` give condition number ``kappa(J)``, singular values
``|c| sigma(J)``, isotropic and anisotropic force ``(s / |c|) f(J, t)`` wherever those are
representable, for ``c`` and ``s`` over 1e-300 .. 1e300. The closed forms square and cube
entries, so without scaling ``1e-300 * I`` looked singular and ``1e300 * I`` held no force.

Every reference is computed in mpmath at 50 digits from the float64 inputs actually passed
(scaled matrices are formed in mpmath from the unscaled float64 matrix and the float64
factor, so the reference is the exact value of what the code was given up to the one
rounding of ``c * J`` itself, which is at most eps/2 relative per entry and covered by the
bounds below). Bounds (eps = 2.2e-16, kappa the reference condition number):

===========================  =====================  =========================================
quantity                     bound                  why
===========================  =====================  =========================================
singular values              (C + 1) eps kappa      the unscaled paths' bounds (test_stiff:
                                                    C eps kappa, 3 x 3 closed form C eps
                                                    kappa^2 below kappa 100) plus the entry
                                                    rounding of ``c * J``, amplified by kappa
column norms, isotropic      C_NORM eps             a sum of squares, a root and a quotient
anisotropic force            C_SMALL eps kappa      a solve with J^T
===========================  =====================  =========================================
"""
from __future__ import annotations

import itertools
import warnings

import mpmath
import numpy as np
import pytest

from kinematics import Inverse3
from metrics import anisotropy, columns, conditioning, isotropy, linalg
from metrics.quantities import evaluate

DPS = 50
EPS = float(np.finfo(float).eps)
C_SMALL = 10.0
C_CLOSED = 10.0
C_NORM = 4.0
SCALES = tuple(10.0 ** k for k in range(-300, 301, 25))


def mp_scaled(jac: np.ndarray, c: float) -> mpmath.matrix:
    """``c * jac`` at 50 digits from the float64 ``jac`` and ``c``."""
    with mpmath.workdps(DPS):
        return mpmath.matrix([[mpmath.mpf(float(v)) * mpmath.mpf(c) for v in row] for row in jac])


def mp_sv(mat: mpmath.matrix) -> list:
    with mpmath.workdps(DPS):
        s = mpmath.svd_r(mat, compute_uv=False)
        return sorted((s[i] for i in range(len(s))), reverse=True)


def mp_isotropic(mat: mpmath.matrix, t) -> mpmath.mpf:
    with mpmath.workdps(DPS):
        return min(mpmath.mpf(float(t[u])) / mpmath.sqrt(mpmath.fsum(mat[i, u] ** 2 for i in range(mat.rows)))
                   for u in range(mat.cols))


def mp_anisotropic(mat: mpmath.matrix, t) -> mpmath.mpf:
    n = mat.cols
    with mpmath.workdps(DPS):
        best = mpmath.mpf(0)
        for signs in itertools.product((1, -1), repeat=n):
            rhs = mpmath.matrix([mpmath.mpf(float(t[u])) * signs[u] for u in range(n)])
            best = max(best, mpmath.norm(mpmath.lu_solve(mat.T, rhs)))
        return best


def rel(computed, exact) -> float:
    with mpmath.workdps(DPS):
        return float(abs((mpmath.mpf(float(computed)) - exact) / exact))


def base_jacobians(n: int, rng: np.random.Generator) -> np.ndarray:
    """Unit-scale matrices: the identity, a rotation-like one, and random ones of condition 1..1e4."""
    out = [np.eye(n), np.linalg.qr(rng.standard_normal((n, n)))[0]]
    for log_kappa in (0.5, 2.0, 4.0):
        u = np.linalg.qr(rng.standard_normal((n, n)))[0]
        v = np.linalg.qr(rng.standard_normal((n, n)))[0]
        s = 10.0 ** -np.linspace(0.0, log_kappa, n)
        out.append(u @ np.diag(s) @ v.T)
    return np.array(out)


@pytest.mark.parametrize("n", [2, 3])
def test_issue_examples(n):
    """The three numbers the issue quotes: cond(1e-300 I) = 1 (was inf); isotropic force of
    1e300 I with unit torques 1e-300 (was 0) and anisotropic ``sqrt(n) 1e-300`` (was 0)."""
    eye = np.eye(n)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert conditioning.condition_number(1e-300 * eye) == pytest.approx(1.0, rel=4 * EPS)
        assert conditioning.condition_number(1e300 * eye) == pytest.approx(1.0, rel=4 * EPS)
        iso = isotropy.isotropic_force(1e300 * eye, torque_limits=np.ones(n))
        aniso = anisotropy.anisotropic_force(1e300 * eye, torque_limits=np.ones(n))
    assert iso == pytest.approx(1e-300, rel=C_NORM * EPS)
    assert aniso == pytest.approx(np.sqrt(n) * 1e-300, rel=C_SMALL * EPS)


@pytest.mark.parametrize("n", [2, 3])
def test_singular_values_and_condition_number_over_600_decades(n):
    """``c J`` for c = 1e-300 .. 1e300 against mpmath, batched together (mixed scales in one batch)."""
    rng = np.random.default_rng([7, n])
    jacs = base_jacobians(n, rng)
    batch = np.array([c * j for c in SCALES for j in jacs])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sv = linalg.singular_values(batch)
        cond = conditioning.condition_number(sv=sv)
    k = 0
    for c in SCALES:
        for j in jacs:
            exact = mp_sv(mp_scaled(j, c))
            kappa = float(exact[0] / exact[-1])
            bound = (C_SMALL + 1) * EPS * kappa + (C_CLOSED * EPS * kappa ** 2 if n == 3 and kappa <= 100.5 else 0)
            for computed, s in zip(sv[k], exact, strict=True):
                assert rel(computed, s) <= bound, (c, kappa)
            assert rel(cond[k], exact[0] / exact[-1]) <= 2 * bound
            k += 1


@pytest.mark.parametrize("n", [2, 3])
def test_forces_over_600_decades_of_jacobian_and_torque_scale(n):
    """Isotropic and anisotropic force and column norms of ``c J`` with torques ``s t``, every
    pair with ``s / c`` representable (1e-290 .. 1e290), against mpmath; the anisotropic force
    is never below the isotropic one (it is at least sqrt(n) times it, see
    ``test_anisotropic_force_is_at_least_sqrt_n_times_the_isotropic``)."""
    rng = np.random.default_rng([8, n])
    jacs = base_jacobians(n, rng)
    base_t = np.array([0.3, 0.7, 1.1][:n])
    cases = [(c, s) for c in SCALES[::2] for s in SCALES[::3] if 1e-290 <= s / c <= 1e290]
    for c, s in cases:
        batch = c * jacs
        t = s * base_t
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            norms = columns.column_norms(batch)
            iso = isotropy.isotropic_force(batch, torque_limits=t)
            aniso = anisotropy.anisotropic_force(batch, torque_limits=t)
        for k, j in enumerate(jacs):
            mat = mp_scaled(j, c)
            exact_sv = mp_sv(mat)
            kappa = float(exact_sv[0] / exact_sv[-1])
            with mpmath.workdps(DPS):
                for u in range(n):
                    exact_norm = mpmath.sqrt(mpmath.fsum(mat[i, u] ** 2 for i in range(n)))
                    assert rel(norms[k, u], exact_norm) <= C_NORM * EPS
            assert rel(iso[k], mp_isotropic(mat, t)) <= C_NORM * EPS, (c, s)
            assert rel(aniso[k], mp_anisotropic(mat, t)) <= C_SMALL * EPS * kappa, (c, s)
            assert aniso[k] >= iso[k]


@pytest.mark.parametrize("n", [2, 3])
def test_anisotropic_force_is_at_least_sqrt_n_times_the_isotropic(n):
    """Property: ``max_s |R s|^2 >= mean_s |R s|^2 = sum_u |R_u|^2 >= n min_u d_u^2`` (cross
    terms cancel over the sign vectors, and a reference force is at least as long as its
    facet's distance), so ``aniso >= sqrt(n) iso``; asserted with the two computed values'
    error bounds (test_stiff's: the anisotropic force to C_SMALL eps kappa also with torques
    eight decades apart), over random J of condition 1..1e8 at scales 1e-300..1e300, torques
    at a common scale 1e-150..1e150 spread over eight decades across actuators."""
    rng = np.random.default_rng([9, n])
    count = 400
    u = np.linalg.qr(rng.standard_normal((count, n, n)))[0]
    v = np.linalg.qr(rng.standard_normal((count, n, n)))[0]
    logs = -rng.uniform(0.0, 8.0, size=(count, n))
    logs[:, 0] = 0.0
    jacs = u @ (10.0 ** logs[:, :, None] * np.swapaxes(v, -1, -2))
    jacs *= 10.0 ** rng.uniform(-300, 300, size=(count, 1, 1))
    t = 10.0 ** (rng.uniform(-150, 150, size=(count, 1)) + rng.uniform(-4, 4, size=(count, n)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        iso = isotropy.isotropic_force(jacs, torque_limits=t)
        aniso = anisotropy.anisotropic_force(jacs, torque_limits=t)
        cond = conditioning.condition_number(jacs)
    representable = (iso > 1e-290) & (aniso < 1e290)
    assert representable.sum() > count // 2
    bound = C_SMALL * EPS * cond + C_NORM * EPS
    assert np.all(bound[representable] < 1e-6)
    assert np.all(aniso[representable] >= np.sqrt(n) * iso[representable] * (1.0 - bound[representable]))
    assert np.all(aniso[representable] >= iso[representable])


def test_inverse3_with_gear_ratios_of_1e_minus_300():
    """``--set gear_ratios=1e-300,1e-300,1e-300``: the anisotropic force was 0, below the
    isotropic force. Now both are 1e-300 times those at gear 1 (to C_NORM eps: the torque
    enters linearly) and agree with mpmath."""
    base = Inverse3()
    gear = 1e-300
    device = base.replace(gear_ratios=tuple(gear * g for g in base.params.gear_ratios))
    c = base.params.plane_offset
    points = np.array([[0.15, c, 0.25], [0.2, c, 0.1], [0.25, c, 0.3], [0.3, c, 0.2]])
    names = ("condition_number", "isotropic_force", "anisotropic_force")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ev = evaluate(device, points, names + ("jacobian",))
        ev_1 = evaluate(base, points, names)
    assert ev.feasible.all()
    t = device.torque_limits()
    for k, j in enumerate(ev.values["jacobian"]):
        mat = mp_scaled(j, 1.0)
        kappa = float(mp_sv(mat)[0] / mp_sv(mat)[-1])
        assert rel(ev.values["isotropic_force"][k], mp_isotropic(mat, t)) <= C_NORM * EPS
        assert rel(ev.values["anisotropic_force"][k], mp_anisotropic(mat, t)) <= C_SMALL * EPS * kappa
    assert np.all(ev.values["anisotropic_force"] > ev.values["isotropic_force"])
    for name in ("isotropic_force", "anisotropic_force"):
        np.testing.assert_allclose(ev.values[name], gear * ev_1.values[name], rtol=2 * C_NORM * EPS, atol=0)


def test_in_range_results_are_those_of_the_plain_formulas():
    """Matrices inside ``SAFE_SCALE`` never see the scaling: a batch mixing them with extreme
    ones gives them exactly what a batch of them alone gives (batch = one at a time, and the
    fast path's speed is untouched)."""
    rng = np.random.default_rng(10)
    for n in (2, 3):
        jacs = base_jacobians(n, rng)
        mixed = np.concatenate([jacs, 1e-300 * jacs, 1e300 * jacs])
        t = np.array([0.3, 0.7, 1.1][:n])
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            for f in (linalg.singular_values, lambda a: linalg.inverse_transpose(a)[0], columns.column_norms,
                      lambda a: anisotropy.anisotropic_force(a, torque_limits=t)):
                np.testing.assert_array_equal(f(mixed)[: len(jacs)], f(jacs))


def test_scale_helpers():
    """``pow2_exponents`` puts the largest entry in [0.5, 1) exactly; 0 for a zero or non-finite one."""
    a = np.array([[3.0, -5.0], [1e-310, 0.0]])
    e = linalg.pow2_exponents(a, axis=(-2, -1))
    assert 0.5 <= np.max(np.abs(np.ldexp(a, -e))) < 1.0
    assert linalg.pow2_exponents(np.zeros((2, 2)), axis=(-2, -1)) == 0
    assert linalg.pow2_exponents(np.array([[np.inf, 1.0]]), axis=(-2, -1)) == 0
    assert np.all(linalg.outside_safe_scale(np.array([0.0, 1e-300, np.nan, np.inf, 1e300])))
    assert not linalg.outside_safe_scale(1.0)
