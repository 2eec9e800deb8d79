"""The inlined ``hypot`` (``metrics.kernels.hypot``) against libm's (``np.hypot``) and mpmath.

References: ``np.hypot`` (the platform's libm, which the numpy model calls), bit for bit where
``matches_libm`` says the platform's libm is glibc's arithmetic; mpmath's exact ``sqrt(x^2 + y^2)``
in 40 digits for the accuracy, on any platform: glibc's algorithm is within 1 ulp (Borges 2019: a
correctly rounded ``sqrt`` of ``ax^2 + ay^2`` (3 roundings, at most 1.5 ulp together), then one
correction from the residual, which leaves at most the correction's own rounding and its
second-order term). And the Inverse3 pass gives the same outputs with libm's call as with the
inlined form.
"""
from __future__ import annotations

import math

import mpmath
import numba
import numpy as np
import pytest

from metrics import kernels
from metrics.kernels import hypot
from metrics.kernels import inverse3 as inverse3_kernel
from metrics.loading import DEFAULT_LOADING
from metrics.quantities import CORE_QUANTITIES
from resources import load_preset


def _pairs(rng, n):
    """``n`` pairs over every ratio ``2^-k`` (k < 90) and magnitudes ``2^-300..2^300``, both signs."""
    x = rng.uniform(1.0, 2.0, n) * np.ldexp(1.0, rng.integers(-300, 300, n)) * rng.choice([-1.0, 1.0], n)
    y = x * rng.uniform(0.5, 2.0, n) * np.ldexp(1.0, -rng.integers(0, 90, n)) * rng.choice([-1.0, 1.0], n)
    return x, y


@pytest.mark.skipif(not hypot.matches_libm(), reason="this platform's libm hypot is not glibc's arithmetic")
def test_hypot_fast_is_libms_hypot_bit_for_bit():
    x, y = _pairs(np.random.default_rng(7), 20000)
    got = np.array([hypot.hypot_fast(a, b) for a, b in zip(x.tolist(), y.tolist())])
    assert all(hypot.hypot_covers(a, b) for a, b in zip(x.tolist(), y.tolist()))
    np.testing.assert_array_equal(got, np.hypot(x, y))
    # And the compiled call the pass made before (numba's ``math.hypot``: libm's; Python's own is CPython's).
    libm = numba.njit(lambda a, b: math.hypot(a, b))
    np.testing.assert_array_equal(got, [libm(a, b) for a, b in zip(x.tolist(), y.tolist())])


def test_hypot_fast_is_within_an_ulp_of_mpmath():
    x, y = _pairs(np.random.default_rng(8), 3000)
    with mpmath.workdps(40):
        for a, b in zip(x.tolist(), y.tolist()):
            exact = mpmath.sqrt(mpmath.mpf(a) ** 2 + mpmath.mpf(b) ** 2)
            got = hypot.hypot_fast(a, b)
            assert abs(got - exact) <= math.ulp(got), (a, b)


def test_hypot_covers_only_the_unscaled_range():
    for a, b in ((0.0, 1.0), (1.0, 0.0), (2.0 ** -401, 1.0), (2.0 ** 401, 1.0), (math.inf, 1.0), (math.nan, 1.0),
                 (1.0, -math.inf), (5e-324, 5e-324)):
        assert not hypot.hypot_covers(a, b)
    assert hypot.hypot_covers(2.0 ** -400, -(2.0 ** 400))


def test_the_inverse3_pass_is_the_same_with_libms_hypot():
    """The 1000 x 1000 map's points, every request's outputs: the pass with ``pack``'s hypot flag off (libm's
    call) and as packed (inlined where the platform's libm is glibc's)."""
    preset = load_preset("inverse3_prototype")
    mech = preset.mechanism
    pts = preset.grid.with_resolution(1000).points(mech.task_names).reshape(-1, 3)
    kernel = kernels.find(mech, CORE_QUANTITIES, DEFAULT_LOADING)
    runs = []
    for flag in (kernel.params[15], 0.0):
        kernel.params[15] = flag
        runs.append(kernel.run(pts, threads=False, fill=True))
    kernel.params[15] = runs and inverse3_kernel.pack(mech)[15]
    (f0, j0, v0, c0, b0), (f1, j1, v1, c1, b1) = runs
    np.testing.assert_array_equal(f0, f1)
    np.testing.assert_array_equal(j0, j1)
    np.testing.assert_array_equal(v0, v1)
    np.testing.assert_array_equal(b0, b1)
    for name in c0:
        np.testing.assert_array_equal(c0[name], c1[name])
