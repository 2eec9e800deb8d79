"""The compiled conditioning near a repeated singular value (``metrics.kernels.svd3``) against LAPACK.

Reference: ``numpy.linalg.svd`` (LAPACK's ``gesdd``), which the numpy path calls at these matrices. Both
are backward stable: one-sided Jacobi's values are those of a matrix within ``6 R eps |J|_F`` of J
(``R`` rotations, each within ``6 eps`` of ``|J|_F``: its cosine and sine within 3 ulps of an exactly
orthogonal pair, then the update's two products and sum), plus ``3 eps`` relative for the final norms;
LAPACK's within ``p(n) eps |J|_F``, taken as ``3 n = 9`` ulps for n = 3. By Weyl's theorem each
singular value of either is within that much of the exact one, so the two differ by at most the sum.
"""
from __future__ import annotations

import numpy as np
import pytest

from metrics import kernels
from metrics.kernels import svd3
from metrics.kernels.square3 import singular_values3
from metrics.linalg import FAST_COND_LIMIT, components, gram, symmetric_eigenvalues_3x3
from metrics.loading import DEFAULT_LOADING
from metrics.quantities import evaluate
from resources import load_preset

EPS = np.finfo(float).eps


def _near_repeated(rng, n, scale_exponents=(-3, 3)):
    """Matrices ``U diag(s) V^T`` with two singular values ``1`` and ``1 + d`` (``d`` 1e-16..1e-4, where the
    Gram matrix's ``arccos`` loses digits), the third ``10^-2..10^2`` (``kappa <= 100``), scaled."""
    u = np.linalg.qr(rng.normal(size=(n, 3, 3)))[0]
    v = np.linalg.qr(rng.normal(size=(n, 3, 3)))[0]
    s = np.stack([np.ones(n), 1.0 + 10.0 ** rng.uniform(-16, -4, n), 10.0 ** rng.uniform(-1.99, 1.99, n)], axis=-1)
    s *= 10.0 ** rng.uniform(*scale_exponents, n)[:, None]
    rng.shuffle(s, axis=1)
    return u @ (s[..., None] * v)


def _bound(mats, rotations):
    fro = np.linalg.norm(mats, axis=(-2, -1))
    return (6 * rotations + 9) * EPS * fro + 3 * EPS * np.linalg.svd(mats, compute_uv=False)[:, 0]


def test_hestenes_gives_lapacks_singular_values_near_a_repeated_one():
    rng = np.random.default_rng(3)
    mats = _near_repeated(rng, 4000)
    ok, got, rotations = svd3.hestenes_points(mats)
    assert ok.all()
    assert rotations.max() <= 3 * svd3.SWEEPS
    want = np.linalg.svd(mats, compute_uv=False)
    err = np.abs(got - want)
    assert np.all(err <= _bound(mats, rotations)[:, None]), float(np.max(err / _bound(mats, rotations)[:, None]))
    assert np.all(got[:, :-1] >= got[:, 1:])             # descending


def test_hestenes_on_general_matrices_and_exact_cases():
    rng = np.random.default_rng(4)
    mats = rng.normal(size=(4000, 3, 3))
    ok, got, rotations = svd3.hestenes_points(mats)
    assert ok.all()
    want = np.linalg.svd(mats, compute_uv=False)
    assert np.all(np.abs(got - want) <= _bound(mats, rotations)[:, None])
    # Orthogonal columns need no rotation: their norms, exactly as the formula forms them.
    ok, got, rotations = svd3.hestenes_points(np.diag([3.0, -5.0, 4.0])[None])
    assert ok[0] and rotations[0] == 0 and got[0].tolist() == [5.0, 4.0, 3.0]


def test_the_closed_form_hands_these_matrices_over_and_the_kernel_keeps_them():
    """``singular_values3`` alone calls them hard (``|r| > 1 - 1e-3``); ``singular_values_any3`` computes them,
    within the bound above of LAPACK's, and hands back only what is truly hard."""
    rng = np.random.default_rng(5)
    mats = _near_repeated(rng, 500)
    flat = [m.reshape(-1).tolist() for m in mats]
    assert all(singular_values3(*f)[3] for f in flat)
    got = np.array([svd3.singular_values_any3(*f) for f in flat])
    assert not got[:, 3].any()
    rotations = svd3.hestenes_points(mats)[2]
    assert np.all(np.abs(got[:, :3] - np.linalg.svd(mats, compute_uv=False)) <= _bound(mats, rotations)[:, None])
    # kappa beyond FAST_COND_LIMIT, or far from unit scale: handed back (LAPACK and rescaling in numpy).
    ill = np.diag([1.0, 1.0 + 1e-12, 0.5 / FAST_COND_LIMIT])
    far = np.diag([1.0, 1.0 + 1e-12, 0.5]) * 1e200
    for m in (ill, far):
        assert svd3.singular_values_any3(*m.reshape(-1).tolist())[3]


@pytest.mark.parametrize("key", ["inverse3_prototype", "phantom_premium_15"])
def test_map_points_near_a_repeated_value_are_computed_and_match_numpy(key):
    """On the preset's map the points numpy sends to LAPACK for a near-repeated value are the kernel's now
    (not handed back), and their condition numbers are numpy's within the bound above through ``kappa``
    (``s1 / s3``: twice the relative error of ``s3``), plus J's own difference (``test_kernels``' tolerances)."""
    preset = load_preset(key)
    mech = preset.mechanism
    pts = preset.grid.with_resolution(301).points(mech.task_names).reshape(-1, 3)
    with kernels.use_compiled(False):
        ref = evaluate(mech, pts, ("jacobian", "condition_number"))
    at = np.flatnonzero(ref.feasible & np.isfinite(ref.values["condition_number"]))
    jac = ref.values["jacobian"][at]
    r = symmetric_eigenvalues_3x3(gram(components(jac)))[3]         # numpy's own test for LAPACK
    near = (np.abs(r) > 1.0 - 1e-3) & (np.linalg.cond(jac) <= FAST_COND_LIMIT / 2)
    assert near.sum() > 10
    kernel = kernels.find(mech, ("condition_number",), DEFAULT_LOADING)
    feasible, _, values, _, back = kernel.run(pts[at[near]], threads=False)
    assert feasible.all() and not back.any()
    kappa = ref.values["condition_number"][at[near]]
    rotations = svd3.hestenes_points(jac[near])[2]
    s = np.linalg.svd(jac[near], compute_uv=False)
    sv_rel = _bound(jac[near], rotations) / s[:, 2]
    # J's own difference between the paths, relative to |J|_F (test_kernels' module docstring): DJ, and for
    # the Inverse3's ratios sqrt(2) (16 pi eps + 8 eps / |sin h|).
    dj = 16 * EPS
    if key.startswith("inverse3"):
        q = ref.joints[at[near]]
        dj = dj + np.sqrt(2) * (16 * np.pi * EPS + 8 * EPS / np.abs(np.sin(0.5 * (q[:, 1] - q[:, 2]))))
    tol = 2 * sv_rel + (np.pi * kappa ** 2 + kappa) * dj
    got = values[0]
    assert np.all(np.abs(got - kappa) <= tol * kappa), float(np.max(np.abs(got - kappa) / (tol * kappa)))


def test_third_cosines_are_within_three_eps_of_mpmath():
    """``square3.third_cosines3`` (a cube root by Halley's steps, no libm) against ``cos(acos(r) / 3)`` and
    ``cos(acos(r) / 3 + 2 pi / 3)`` in 40 digits: within 3 eps (its docstring's bound), at the ends
    ``r = +-1`` and just inside them (where ``arccos`` is ill conditioned and the cube root is not), at
    ``r = 0`` and over random ``r``; clamped outside [-1, 1]."""
    import mpmath

    from metrics.kernels.square3 import third_cosines3

    rng = np.random.default_rng(5)
    r = np.concatenate([[-1.0, 1.0, 0.0, -1.0 + EPS, 1.0 - EPS / 2, -0.999, 0.999],
                        -1.0 + 10.0 ** rng.uniform(-16, 0, 300), 1.0 - 10.0 ** rng.uniform(-16, 0, 300),
                        rng.uniform(-1.0, 1.0, 1000)])
    with mpmath.workdps(40):
        for x in r.tolist():
            phi = mpmath.acos(mpmath.mpf(x)) / 3
            first, third = third_cosines3(x)
            assert abs(first - mpmath.cos(phi)) <= 3 * EPS, x
            assert abs(third - mpmath.cos(phi + 2 * mpmath.pi / 3)) <= 3 * EPS, x
    assert third_cosines3(1.5) == third_cosines3(1.0) and third_cosines3(-1.5) == third_cosines3(-1.0)
