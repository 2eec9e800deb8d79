"""The compiled slab-slice enumeration (``metrics.kernels.wrench.slab_vertices``) against the numpy one.

``slab_slice_vertex_max_norm`` and ``slab_slice_vertices`` now run the compiled kernel; the numpy
code they ran before is kept in ``wrench_reference.py``. The kernel forms every candidate with the
same operations in the same order (cofactors, determinant, the dependence test, ``y``, the slab
products ``sum_j b_j (a_k . c_j / det)``, the slack), so its largest norm and its vertices are the
reference's bit for bit; what it skips (a candidate not above the best so far, the products of a
candidate already outside a slab beyond the widest slack) cannot change them.

``slab_slice_max_norm`` (square J at an inverse singularity) stays in numpy (LAPACK solves) and
gained the dependence test of the slab kernel: where no subset is near dependence it is the
previous code's value.
"""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from metrics import biased_sections, wrench_facets
from metrics.loading import Loading
from metrics.quantities import evaluate
from resources import load_preset
from tests.metrics import wrench_reference as ref

EPS = np.finfo(float).eps


def _slab_cases():
    """Slabs (N, k, m), bounds (N, k) and the slice's rows: random, planted degenerate, non-finite."""
    rng = np.random.default_rng(41)
    cases = []
    for d, m, k in ((2, 2, 4), (2, 3, 7), (3, 3, 6), (3, 5, 10), (3, 6, 15)):
        nu = rng.normal(size=(120, k, m))
        c = rng.normal(size=(120, k)) * 0.5                      # centres: the origin inside or not
        h = rng.uniform(0.2, 2.0, size=(120, k))
        nu[::6, 1] = -nu[::6, 0]                                  # antiparallel slabs
        nu[1::6, 2] = nu[1::6, 0] + nu[1::6, 1]                   # dependent within rounding
        nu[2::6, 1] = -nu[2::6, 0]
        nu[2::6, 1, 0] += 1e-18                                   # ... with a near-zero entry
        nu[3::6, 3 % k] = 0.0                                     # a zero normal
        nu[4, 0, 0] = np.nan
        h[5, 1] = np.inf
        rows = list(range(m - d, m))
        cases.append((f"random-d{d}-m{m}-k{k}", nu, c - h, c + h, rows))
    return cases


@pytest.mark.parametrize("name, nu, lo, hi, rows", _slab_cases(), ids=[c[0] for c in _slab_cases()])
def test_slab_vertex_max_norm_is_the_numpy_enumeration_bit_for_bit(name, nu, lo, hi, rows):
    with np.errstate(all="ignore"):
        old = ref.slab_slice_vertex_max_norm(nu, lo, hi, rows=rows)
        new = wrench_facets.slab_slice_vertex_max_norm(nu, lo, hi, rows=rows)     # inf bounds: inf / inf
    np.testing.assert_array_equal(new, old)
    assert np.any(np.isfinite(new) & (new > 0))                 # not only empty or unbounded slices


@pytest.mark.parametrize("name, nu, lo, hi, rows", _slab_cases(), ids=[c[0] for c in _slab_cases()])
def test_slab_slice_vertices_are_the_numpy_enumerations(name, nu, lo, hi, rows):
    for i in range(0, len(nu), 15):
        with np.errstate(all="ignore"):
            old = ref.slab_slice_vertices(nu[i], lo[i], hi[i], rows=rows)
            new = wrench_facets.slab_slice_vertices(nu[i], lo[i], hi[i], rows=rows)
        np.testing.assert_array_equal(new, old)


def _undecided(generators, bias, *, rows):
    """``biased_sections.biased_slice_max_norm`` deciding nothing."""
    shape = np.shape(generators)[:-2]
    return np.full(shape, np.nan), np.zeros(shape, bool)


def _biased_slabs(key, count, monkeypatch):
    """The slabs ``biased_slice_max`` hands ``slab_slice_vertex_max_norm`` for ``key`` under gravity.

    A redundant model's slices go to the section path (``metrics.biased_sections``) first; here
    it hands every point back, so the slab path sees all of them, as it would the undecided ones.
    """
    preset = load_preset(key)
    mech = preset.mechanism
    pts = preset.grid.points(mech.task_names).reshape(-1, mech.task_dim)
    pts = pts[np.random.default_rng(43).choice(len(pts), count, replace=False)]
    seen = []
    real = wrench_facets.slab_slice_vertex_max_norm

    def spy(nu, lo, hi, *, rows):
        seen.append((nu, lo, hi, list(rows)))
        return real(nu, lo, hi, rows=rows)
    with monkeypatch.context() as patch:
        patch.setattr(wrench_facets, "slab_slice_vertex_max_norm", spy)
        patch.setattr(biased_sections, "biased_slice_max_norm", _undecided)
        evaluate(mech, pts, ["anisotropic_force", "anisotropic_moment"],
                 loading=Loading(gravity=(0.0, 0.0, -9.80665), mounting="upright"))
    assert seen
    return seen


@pytest.mark.parametrize("key", ["twin_pantograph", "stewart_platform", "inoue_platform"])
def test_the_shipped_devices_biased_slices_are_the_numpy_enumeration_bit_for_bit(key, monkeypatch):
    for nu, lo, hi, rows in _biased_slabs(key, 300, monkeypatch):
        np.testing.assert_array_equal(wrench_facets.slab_slice_vertex_max_norm(nu, lo, hi, rows=rows),
                                      ref.slab_slice_vertex_max_norm(nu, lo, hi, rows=rows))


def test_slab_slice_max_norm_away_from_dependence_is_the_previous_code():
    """Where no subset of slabs is near dependence (kappa <= 1e6, far from the test's 1 / (64 eps)) the
    dependence test removes nothing: the previous code's value, to ``2 c kappa_max eps`` with
    ``c = 8 d`` (a margin for the solves, which are in fact the same LAPACK calls)."""
    rng = np.random.default_rng(44)
    checked = 0
    for d, n in ((2, 3), (3, 3), (3, 6), (2, 6)):
        for _ in range(60):
            jac = rng.normal(size=(6, n))
            jac[:, rng.integers(n)] = 0.0 if n > d else jac[:, 0]          # an actuator at a singularity
            t = rng.uniform(0.5, 2.0, size=n)
            rows = sorted(rng.choice(6, d, replace=False))
            normals = (jac[rows] / t).T
            kappa = max((np.linalg.cond(normals[list(s)]) for s in itertools.combinations(range(n), d)
                         if np.linalg.matrix_rank(normals[list(s)]) == d), default=np.inf)
            if not kappa <= 1e6:
                continue
            old = float(ref.slab_slice_max_norm(jac, torque_limits=t, rows=rows))
            new = float(wrench_facets.slab_slice_max_norm(jac, torque_limits=t, rows=rows))
            if np.isinf(old):
                assert np.isinf(new)
                continue
            assert new == pytest.approx(old, rel=2 * 8 * d * kappa * EPS, abs=0.0)
            checked += 1
    assert checked >= 100
