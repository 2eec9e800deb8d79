"""The compiled Twin-Pantograph pass (``metrics.kernels.twin_batch``): its eigenvalue routine against
mpmath, lanes and threads that change no bit, and the compiled pass against the numpy reference.

Tolerance of the eigenvalue routine (the kernel module's doc): every computed extreme eigenvalue of
a symmetric positive semidefinite 5 x 5 ``G`` is within ``(GAMMA R + 1.5 D) eps tr G`` of the exact
one, ``R`` the rotations it applied and ``D`` the nonzero entries it dropped (both returned per
matrix; the Frobenius norm of ``G`` is at most its trace). The reference is mpmath's ``eigsy`` at 40 digits on the same
floating-point matrix, so its own error (1e-40 relative) does not count.
"""
from __future__ import annotations

import mpmath
import numba
import numpy as np
import pytest

from metrics import kernels
from metrics.design.twin_batch import force_gii_values
from metrics.kernels import twin_batch as comp

EPS = np.finfo(float).eps


def _psd(rng, eigenvalues: np.ndarray) -> np.ndarray:
    """``Q diag(w) Q^T`` (N, 5, 5) with random orthogonal ``Q``, symmetrised exactly."""
    q = np.linalg.qr(rng.normal(size=(eigenvalues.shape[0], 5, 5)))[0]
    g = q @ (eigenvalues[..., None] * np.swapaxes(q, -1, -2))
    return 0.5 * (g + np.swapaxes(g, -1, -2))


def _hard_matrices(n: int = 240) -> np.ndarray:
    """Positive semidefinite 5 x 5 at scales 1e-150 .. 1e150: condition numbers to 1e16, singular
    ones (two zero eigenvalues), near-repeated eigenvalues (1 and 1 + 1e-16 .. 1e-2, twice)."""
    rng = np.random.default_rng(11)
    third = n // 3
    spread = 10.0 ** rng.uniform(-16, 0, (third, 5))
    singular = np.concatenate([10.0 ** rng.uniform(-3, 0, (third, 3)), np.zeros((third, 2))], -1)
    close = 1.0 + 10.0 ** rng.uniform(-16, -2, (n - 2 * third, 2))
    repeated = np.concatenate([np.ones((n - 2 * third, 1)), close, close[:, :1] * (1.0 + 1e-15),
                               10.0 ** rng.uniform(-8, 2, (n - 2 * third, 1))], -1)
    w = np.concatenate([spread, singular, repeated])
    return _psd(rng, w) * 10.0 ** rng.uniform(-150, 150, n)[:, None, None]


def _mp_extremes(g: np.ndarray) -> tuple[float, float]:
    with mpmath.workdps(40):
        ev = mpmath.eigsy(mpmath.matrix(g.tolist()), eigvals_only=True)
        values = sorted(ev[i] for i in range(5))
        return values[0], values[-1]


def test_extreme_eigenvalues_within_the_derived_bound():
    mats = _hard_matrices()
    out = np.empty((len(mats), 2))
    rotations, drops = np.empty(len(mats), np.int64), np.empty(len(mats), np.int64)
    comp.extremes(mats, out, rotations, drops, comp.lane_buffer()[0])
    # every matrix converged: a sweep without a rotation before the cap
    assert np.all(rotations + drops <= comp.MAX_ROTATIONS - 10), int((rotations + drops).max())
    worst = 0.0
    for g, (lo, hi), r, d in zip(mats, out, rotations, drops):
        ref_lo, ref_hi = _mp_extremes(g)
        tr = float(np.trace(g))
        bound = (comp.GAMMA * r + 1.5 * d) * EPS * tr
        err = max(abs(mpmath.mpf(lo) - ref_lo), abs(mpmath.mpf(hi) - ref_hi))
        assert err <= bound, (float(err / (EPS * tr)), int(r))
        worst = max(worst, float(err / (EPS * tr)))
    assert worst > 0.0                       # the comparison sees rounding: the reference is not the kernel's


def test_extreme_eigenvalues_against_lapack():
    """Many more matrices against ``numpy.linalg.eigvalsh``: both within their bound of the exact
    values, so within the sum (LAPACK's ``dsyevd``: a backward stable reduction and QR, taken as
    ``GAMMA 5 eps tr``, a round of the sweep's worth: it is below that by far)."""
    rng = np.random.default_rng(3)
    n = 20000
    w = 10.0 ** rng.uniform(-16, 0, (n, 5))
    w[: n // 4, 1] = w[: n // 4, 0] * (1.0 + 10.0 ** rng.uniform(-16, -1, n // 4))    # near-repeated
    mats = _psd(rng, w) * 10.0 ** rng.uniform(-150, 150, n)[:, None, None]
    out = np.empty((n, 2))
    rotations, drops = np.empty(n, np.int64), np.empty(n, np.int64)
    comp.extremes(mats, out, rotations, drops, comp.lane_buffer()[0])
    ref = np.linalg.eigvalsh(mats)
    tr = np.trace(mats, axis1=1, axis2=2)
    bound = (comp.GAMMA * (rotations + 5) + 1.5 * drops) * EPS * tr
    assert np.all(np.abs(out[:, 0] - ref[:, 0]) <= bound)
    assert np.all(np.abs(out[:, 1] - ref[:, -1]) <= bound)


def test_a_lane_does_not_depend_on_its_neighbours():
    """The same matrices in other lanes, beside other matrices (hard and trivial ones), give the same bits."""
    mats = _hard_matrices(64)
    out = np.empty((64, 2))
    rot, drops = np.empty(64, np.int64), np.empty(64, np.int64)
    comp.extremes(mats, out, rot, drops, comp.lane_buffer()[0])
    rng = np.random.default_rng(2)
    order = rng.permutation(64)
    mixed = np.concatenate([np.eye(5)[None] * 3.0, mats[order], np.zeros((3, 5, 5))])
    out2 = np.empty((len(mixed), 2))
    rot2, drops2 = np.empty(len(mixed), np.int64), np.empty(len(mixed), np.int64)
    comp.extremes(mixed, out2, rot2, drops2, comp.lane_buffer()[0])
    np.testing.assert_array_equal(out2[1:65], out[order])
    np.testing.assert_array_equal(rot2[1:65], rot[order])
    np.testing.assert_array_equal(drops2[1:65], drops[order])
    assert out2[0].tolist() == [3.0, 3.0] and out2[65:].tolist() == [[0.0, 0.0]] * 3


def test_a_matrix_that_meets_the_sweeps_cap_gets_no_value():
    """One sweep: the hard matrices still rotate in it (no bound holds, ``nan``); diagonal ones do
    not (converged at once, their exact diagonal); the default cap converges them all."""
    hard = _hard_matrices(40)
    diagonal = np.array([np.diag(w) for w in np.random.default_rng(4).uniform(0.5, 2.0, (9, 5))])
    mats = np.concatenate([hard[:20], diagonal, hard[20:]])
    out = np.empty((len(mats), 2))
    rotations, drops = np.empty(len(mats), np.int64), np.empty(len(mats), np.int64)
    comp.extremes(mats, out, rotations, drops, comp.lane_buffer(sweeps=1)[0])
    is_diagonal = np.zeros(len(mats), bool)
    is_diagonal[20:29] = True
    assert np.all(np.isnan(out[~is_diagonal]))
    np.testing.assert_array_equal(out[is_diagonal], np.stack([diagonal.diagonal(axis1=1, axis2=2).min(1),
                                                              diagonal.diagonal(axis1=1, axis2=2).max(1)], -1))
    comp.extremes(mats, out, rotations, drops, comp.lane_buffer()[0])
    assert np.all(np.isfinite(out))
    with pytest.raises(ValueError, match="sweeps"):
        comp.lane_buffer(sweeps=0)


def test_pairs_that_meet_the_sweeps_cap_are_recomputed_by_lapack(monkeypatch):
    """With a cap of one sweep most pairs have no kernel value (``HANDED_BACK``): the pass hands
    them to the numpy reference, so the result is the reference's within ``tolerance`` and no pair
    keeps the sentinel."""
    from test_twin_batch import tolerance

    from metrics.design import twin_batch as design

    study, fields, points = _table7_like()
    kw = {"s_t": study.objective.s_t, "frame": "end_effector"}
    handed = []
    reference = design._numpy_values

    def counted(x, *args):
        handed.append(len(x))
        return reference(x, *args)

    monkeypatch.setattr(comp, "SWEEPS", 1)
    monkeypatch.setattr(design, "_numpy_values", counted)
    a, b = force_gii_values(study.mechanism, fields, points[::5], **kw)
    monkeypatch.undo()
    with kernels.use_compiled(False):
        a0, b0 = force_gii_values(study.mechanism, fields, points[::5], **kw)
    ok = np.isfinite(a0)
    assert sum(handed) > ok.sum() // 2, (sum(handed), int(ok.sum()))
    assert not np.any(a == comp.HANDED_BACK) and not np.any(b == comp.HANDED_BACK)
    np.testing.assert_array_equal(np.isnan(a), np.isnan(a0))
    np.testing.assert_array_equal(np.isinf(a), np.isinf(a0))
    ta, tb = tolerance(a0[ok], b0[ok])
    assert np.all(np.abs(a[ok] - a0[ok]) <= 2 * ta)
    assert np.all(np.abs(b[ok] - b0[ok]) <= 2 * tb)


def _table7_like():
    from test_twin_batch import reduced  # the reduced Table VII study

    study = reduced("end_effector", 1.0)
    rng = np.random.default_rng(5)
    k = 60
    fields = {"shoulder_separation": rng.uniform(0.024, 0.070, k), "upper_arm": rng.uniform(0.10, 0.30, k),
              "forearm": rng.uniform(0.15, 0.35, k), "pen_length": np.repeat(rng.uniform(0.07, 0.11, k // 3), 3)}
    for name in ("shoulder_separation", "upper_arm", "forearm"):
        fields[name] = np.repeat(fields[name][::3], 3)          # runs of three designs share a geometry
    motor = np.tile(np.asarray(study.mechanism.params.motor_torques), (k, 1))
    motor[:, [0, 3]] = rng.uniform(0.05, 0.30, k)[:, None]
    fields["motor_torques"] = motor
    points = np.repeat(study.workspace.points, 20, axis=0)      # enough items for the parallel build
    return study, fields, points


def test_one_and_two_threads_give_the_same_bits():
    study, fields, points = _table7_like()
    kw = {"s_t": study.objective.s_t, "frame": "end_effector"}
    serial = force_gii_values(study.mechanism, fields, points, threads=False, **kw)
    before = numba.get_num_threads()
    try:
        for threads in (1, 2):
            numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
            par = force_gii_values(study.mechanism, fields, points, threads=True, **kw)
            for x, y in zip(par, serial):
                np.testing.assert_array_equal(x, y)
    finally:
        numba.set_num_threads(before)
    assert np.isnan(serial[0]).any() and np.isfinite(serial[0]).any()
    # designs one at a time and in another order (other runs, other lanes): the same bits per pair
    order = np.random.default_rng(1).permutation(len(fields["motor_torques"]))[:7]
    for d in order:
        one = force_gii_values(study.mechanism, {n: v[d:d + 1] for n, v in fields.items()}, points[::37],
                               threads=False, **kw)
        np.testing.assert_array_equal(one[0][0], serial[0][d, ::37])
        np.testing.assert_array_equal(one[1][0], serial[1][d, ::37])


@pytest.mark.parametrize("frame", ["end_effector", "base"])
def test_the_compiled_pass_equals_the_numpy_reference(frame):
    """Same feasibility and singular samples; values within ``tolerance`` of test_twin_batch (the
    Gram matrix's rounding and both eigensolvers' bounds, against one another)."""
    from test_twin_batch import tolerance

    study, fields, points = _table7_like()
    kw = {"s_t": study.objective.s_t, "frame": frame}
    a, b = force_gii_values(study.mechanism, fields, points[::5], **kw)
    with kernels.use_compiled(False):
        a0, b0 = force_gii_values(study.mechanism, fields, points[::5], **kw)
    np.testing.assert_array_equal(np.isnan(a), np.isnan(a0))
    np.testing.assert_array_equal(np.isinf(a), np.isinf(a0))
    ok = np.isfinite(a0)
    ta, tb = tolerance(a0[ok], b0[ok])
    assert np.all(np.abs(a[ok] - a0[ok]) <= 2 * ta)
    assert np.all(np.abs(b[ok] - b0[ok]) <= 2 * tb)
