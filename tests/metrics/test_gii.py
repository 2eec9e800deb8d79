"""Global Isotropy Index (paper 001 eqs. 11-13) against per-matrix SVDs and hand derivations.

Headless, numpy only (plus the five-bar model); every random draw uses a fixed seed.
"""
from __future__ import annotations

import numpy as np
import pytest

from kinematics import FiveBar
from metrics import gii as G

RNG_SEED = 20240611


def _random_matrices(rng, count, m, n, cond_max=30.0):
    """U diag(s) V^T with log-uniform singular values, condition <= cond_max."""
    k = min(m, n)
    u = np.linalg.qr(rng.normal(size=(count, m, m)))[0]
    v = np.linalg.qr(rng.normal(size=(count, n, n)))[0]
    logs = rng.uniform(0.0, np.log(cond_max), size=(count, k))
    s = rng.uniform(0.02, 0.5, size=(count, 1)) * np.exp(logs - logs.max(axis=-1, keepdims=True))
    mid = np.zeros((count, m, n))
    mid[:, np.arange(k), np.arange(k)] = s
    return u @ mid @ np.swapaxes(v, -1, -2)


def _reference_sv(jac, s_j, s_t, kind):
    """One matrix at a time, numpy.linalg.svd of the explicitly formed diagonal products."""
    sj = np.diag(np.asarray(s_j, float) / s_j[0])
    st = np.diag(np.asarray(s_t, float) / s_t[0])
    out = []
    for mat in jac.reshape((-1,) + jac.shape[-2:]):
        scaled = st @ mat @ np.linalg.inv(sj) if kind == "jacobian" else np.linalg.inv(st) @ mat @ sj
        sv = np.linalg.svd(scaled, compute_uv=False)
        m = mat.shape[0]
        out.append(np.concatenate([sv, np.zeros(m - sv.size)]))
    return np.array(out).reshape(jac.shape[:-2] + (jac.shape[-2],))


def _two_link(q1, q2, l1, l2):
    """Planar 2R arm: columns are d(tip)/dq1, d(tip)/dq2, shape (..., 2, 2)."""
    q1, q2 = np.broadcast_arrays(np.asarray(q1, float), np.asarray(q2, float))
    c1, s1 = np.cos(q1), np.sin(q1)
    c12, s12 = np.cos(q1 + q2), np.sin(q1 + q2)
    col1 = np.stack([-l1 * s1 - l2 * s12, l1 * c1 + l2 * c12], -1)
    col2 = np.stack([-l2 * s12, l2 * c12], -1)
    return np.stack([col1, col2], -1)


def _sv_from_fro_det(fro2, det):
    """2 x 2 singular values by hand: (s1 +- s2)^2 = |A|_F^2 +- 2 |det A|."""
    plus, minus = np.sqrt(fro2 + 2 * np.abs(det)), np.sqrt(np.maximum(fro2 - 2 * np.abs(det), 0))
    return (plus + minus) / 2, (plus - minus) / 2


# -- against a per-matrix numpy reference -----------------------------------------------------
@pytest.mark.parametrize("kind", G.KINDS)
@pytest.mark.parametrize("m,n", [(2, 2), (3, 3), (6, 6), (2, 3), (5, 6), (3, 2)])
def test_scaled_singular_values_match_per_matrix_svd(kind, m, n):
    rng = np.random.default_rng(RNG_SEED + 10 * m + n)
    jac = _random_matrices(rng, 60, m, n).reshape(6, 10, m, n)
    s_j = rng.uniform(0.2, 5.0, n)
    s_t = rng.uniform(0.01, 2.0, m)
    got = G.scaled_singular_values(jac, s_j, s_t, kind=kind)
    ref = _reference_sv(jac, s_j, s_t, kind)
    assert got.shape == (6, 10, m)
    np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-14 * ref.max())
    # batch = one at a time, and local isotropy is the ratio of the extremes
    one = np.array([G.scaled_singular_values(j, s_j, s_t, kind=kind) for j in jac.reshape(-1, m, n)])
    np.testing.assert_allclose(one.reshape(got.shape), got, rtol=1e-12, atol=0)
    np.testing.assert_allclose(G.local_isotropy(jac, s_j, s_t, kind=kind), ref[..., -1] / ref[..., 0],
                               rtol=1e-9, atol=1e-15)


@pytest.mark.parametrize("kind", G.KINDS)
def test_gii_matches_brute_force_over_pairs(kind):
    """Eq. 11 literally: the minimum over all pairs (x0, x1) of sigma_min(x0) / sigma_max(x1)."""
    rng = np.random.default_rng(RNG_SEED)
    jac = _random_matrices(rng, 40, 3, 3).reshape(5, 8, 3, 3)
    s_j, s_t = rng.uniform(0.5, 2.0, 3), rng.uniform(0.5, 2.0, 3)
    ref = _reference_sv(jac, s_j, s_t, kind)
    pairs = ref[..., -1].reshape(-1, 1) / ref[..., 0].reshape(1, -1)
    res = G.gii(jac, s_j, s_t, kind=kind)
    assert res.value == pytest.approx(pairs.min(), rel=1e-9)
    assert res.count == 40 and res.kind == kind
    assert res.argmin == tuple(int(i) for i in np.unravel_index(np.argmin(ref[..., -1]), (5, 8)))
    assert res.argmax == tuple(int(i) for i in np.unravel_index(np.argmax(ref[..., 0]), (5, 8)))
    assert res.sigma_min == pytest.approx(ref[..., -1].min(), rel=1e-9)
    assert res.sigma_max == pytest.approx(ref[..., 0].max(), rel=1e-9)
    same = G.gii_from_extremes(ref[..., -1], ref[..., 0], kind=kind)
    assert same.value == pytest.approx(res.value, rel=1e-9)
    assert (same.argmin, same.argmax) == (res.argmin, res.argmax)


def test_fivebar_workspace_against_reference():
    """A real mechanism: the five-bar over a grid, infeasible points masked out."""
    mech = FiveBar(proximal=0.10, distal=0.15, half_base=0.03, motor_torques=(0.2, 0.1))
    xs, ys = np.meshgrid(np.linspace(-0.12, 0.12, 25), np.linspace(0.02, 0.21, 20), indexing="ij")
    pts = np.stack([xs, ys], -1)
    q, ok = mech.inverse(pts)
    ok = ok & mech.feasible(q)
    # (0, 40) mm is a node of this grid and the double inverse singularity (both legs folded),
    # where J = 0 and the GII is exactly 0; the comparison below is over the regular points.
    ok &= mech.singularity(np.where(ok[..., None], q, 0.0), pts) == 0
    assert 0 < ok.sum() < ok.size
    jac = np.where(ok[..., None, None], mech.jacobian(np.where(ok[..., None], q, 0.0), pts), np.nan)
    t = np.array([0.2, 0.1])
    res = G.gii(jac, t, [1.0, 1.0], feasible=ok)
    ref = _reference_sv(jac[ok], t, np.ones(2), "jacobian")
    assert res.count == ok.sum()
    assert res.value == pytest.approx(ref[:, -1].min() / ref[:, 0].max(), rel=1e-9)
    assert 0.0 < res.value < G.local_isotropy(jac[ok], t, [1, 1]).min() <= 1.0
    assert ok[res.argmin] and ok[res.argmax]


# -- hand-derived mechanisms ----------------------------------------------------------------
def test_two_link_arm_golden_ratio():
    """l1 = l2 = 1, q2 = 90 deg: J = [[-1, -1], [1, 0]], J^T J = [[2, 1], [1, 1]],
    eigenvalues (3 +- sqrt 5)/2, so sigma = phi and 1/phi (phi the golden ratio)."""
    phi = (1 + np.sqrt(5)) / 2
    jac = _two_link(0.0, np.pi / 2, 1.0, 1.0)
    np.testing.assert_allclose(jac, [[-1, -1], [1, 0]], atol=1e-15)
    sv = G.scaled_singular_values(jac, [1, 1], [1, 1])
    np.testing.assert_allclose(sv, [phi, 1 / phi], rtol=1e-14)
    assert G.local_isotropy(jac, [3, 3], [2, 2]) == pytest.approx(1 / phi ** 2, rel=1e-14)


def test_two_link_arm_isotropic_pose_and_scaled_torques():
    """Salisbury's isotropic arm: l1 = sqrt(2) l2, q2 = 135 deg gives |J|_F^2 = 2 l2^2 and
    det J = l1 l2 sin q2 = l2^2, so sigma1 = sigma2 = l2 for every q1. With a weaker second
    motor (t2 = t1 / c), S_J^-1 multiplies column 2 by c: |B|_F^2 = |c1|^2 + c^2 |c2|^2 and
    det B = c det J; the singular values follow from (s1 +- s2)^2 = |B|_F^2 +- 2 |det B|."""
    l2 = 0.1
    l1 = np.sqrt(2) * l2
    q1 = np.linspace(-1.0, 2.0, 7)
    jac = _two_link(q1, 3 * np.pi / 4, l1, l2)
    np.testing.assert_allclose(G.scaled_singular_values(jac, [1, 1], [1, 1]), l2, rtol=1e-12)
    np.testing.assert_allclose(G.local_isotropy(jac, [1, 1], [1, 1]), 1.0, rtol=1e-12)
    c = 2.5
    col1_sq = l1 ** 2 + l2 ** 2 + 2 * l1 * l2 * np.cos(3 * np.pi / 4)      # |c1|^2 = l2^2 here
    fro2 = col1_sq + c ** 2 * l2 ** 2
    det = c * l1 * l2 * np.sin(3 * np.pi / 4)
    s1, s2 = _sv_from_fro_det(fro2, det)
    np.testing.assert_allclose(G.scaled_singular_values(jac, [1.0, 1.0 / c], [1, 1]),
                               np.broadcast_to([s1, s2], (7, 2)), rtol=1e-12)


def test_two_link_arm_gii_over_elbow_range():
    """sigma depends on q2 only (J(q1) = Rot(q1) J(0)); over q2 in [60, 150] deg with
    l1 = l2 = 1: |J|_F^2 = 3 + 2 cos q2, det = sin q2; GII = min s2 / max s1."""
    q2 = np.radians(np.arange(60.0, 151.0, 5.0))
    q1 = np.linspace(0, 1, q2.size)[::-1]
    jac = _two_link(q1, q2, 1.0, 1.0)
    s1, s2 = _sv_from_fro_det(3 + 2 * np.cos(q2), np.sin(q2))
    res = G.gii(jac, [1, 1], [1, 1])
    assert res.value == pytest.approx(s2.min() / s1.max(), rel=1e-12)
    assert res.argmax == (int(np.argmax(s1)),) == (0,)          # most stretched pose: q2 = 60 deg
    np.testing.assert_allclose(G.local_isotropy(jac, [1, 1], [1, 1]), s2 / s1, rtol=1e-12)


@pytest.mark.parametrize("kind", G.KINDS)
def test_diagonal_matrix(kind):
    """J = diag(d): S_T J S_J^-1 = diag(s_k d_k / t_k) after normalising s by s_1 and t by t_1;
    the force map A = J^-T = diag(1/d) gives the reciprocals."""
    d = np.array([0.05, 0.2, 0.1])
    t = np.array([2.0, 1.0, 4.0])
    s = np.array([10.0, 15.0, 5.0])
    mat = np.diag(d) if kind == "jacobian" else np.diag(1 / d)
    expected = (s / 10.0) * d / (t / 2.0)                  # 0.05, 0.6, 0.025
    if kind == "force_map":
        expected = 1 / expected
    np.testing.assert_allclose(G.scaled_singular_values(mat, t, s, kind=kind), np.sort(expected)[::-1], rtol=1e-14)
    assert G.local_isotropy(mat, t, s, kind=kind) == pytest.approx(0.025 / 0.6, rel=1e-14)


def test_orthogonal_matrix_scaled_by_s():
    """J(x) = s(x) Q(x), Q orthogonal: all singular values are s(x), isotropy 1, and the
    GII is min s / max s, attained where s is smallest and largest."""
    rng = np.random.default_rng(RNG_SEED + 1)
    q = np.linalg.qr(rng.normal(size=(12, 3, 3)))[0]
    s = rng.uniform(0.1, 0.9, 12)
    jac = s[:, None, None] * q
    np.testing.assert_allclose(G.scaled_singular_values(jac, [1, 1, 1], [1, 1, 1]), np.repeat(s[:, None], 3, 1),
                               rtol=1e-12)
    np.testing.assert_allclose(G.local_isotropy(jac, [2, 2, 2], [3, 3, 3]), 1.0, rtol=1e-12)
    res = G.gii(jac, [1, 1, 1], [1, 1, 1])
    assert res.value == pytest.approx(s.min() / s.max(), rel=1e-12)
    assert res.argmin == (int(np.argmin(s)),) and res.argmax == (int(np.argmax(s)),)
    assert G.local_isotropy(jac, [1, 1, 1], [1, 1, 1]).min() == pytest.approx(1.0)   # GII < 1 = min LI


def test_redundant_force_map_by_hand():
    """Two task directions, three actuators: A = [[1, 0, 1], [0, 1, 1]] has A A^T = [[2, 1], [1, 2]],
    eigenvalues 3 and 1: sigma = sqrt 3, 1 and isotropy 1/sqrt 3."""
    a = np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]])
    np.testing.assert_allclose(G.scaled_singular_values(a, [1, 1, 1], [1, 1], kind="force_map"),
                               [np.sqrt(3), 1.0], rtol=1e-14)
    assert G.local_isotropy(a, [1, 1, 1], [1, 1], kind="force_map") == pytest.approx(1 / np.sqrt(3), rel=1e-14)


@pytest.mark.parametrize("kind", G.KINDS)
def test_fewer_actuators_than_task_directions_have_zero_isotropy(kind):
    """n < m: the m-th singular value is 0 (padded), so the isotropy and the GII are 0."""
    jac = np.array([[1.0, 0.0], [0.0, 2.0], [0.0, 0.0]])
    sv = G.scaled_singular_values(jac, [1, 1], [1, 1, 1], kind=kind)
    assert sv.shape == (3,) and sv[-1] == 0.0
    assert G.local_isotropy(jac, [1, 1], [1, 1, 1], kind=kind) == 0.0
    assert G.gii(jac[None], [1, 1], [1, 1, 1], kind=kind).value == 0.0


def test_human_hand_scaling_and_units():
    """Table I with our J = I: sigma = (1, 1, 1.5, 0.036, 0.005, 0.039) and isotropy 0.005/1.5.
    Changing the length unit to cm multiplies translational rows of J by 100 and the moment
    entries of S_T by 100 (3.6 cm): B_cm = 100 B_m, same GII. Table I's 3.6 with an SI
    Jacobian is the unit mistake: it changes the GII."""
    np.testing.assert_allclose(G.HUMAN_HAND_S_T, [1.0, 1.0, 1.5, 0.036, 0.005, 0.039])
    np.testing.assert_allclose(G.scaled_singular_values(np.eye(6), np.ones(6), G.HUMAN_HAND_S_T),
                               [1.5, 1.0, 1.0, 0.039, 0.036, 0.005], rtol=1e-15)
    assert G.local_isotropy(np.eye(6), np.ones(6), G.HUMAN_HAND_S_T) == pytest.approx(0.005 / 1.5, rel=1e-14)
    np.testing.assert_allclose(G.task_scale([20.0, 20.0, 30.0], [0.72, 0.1, 0.78]), G.HUMAN_HAND_S_T, rtol=1e-15)

    rng = np.random.default_rng(RNG_SEED + 2)
    jac_m = _random_matrices(rng, 30, 6, 6) * np.array([1, 1, 1, 10, 10, 10])[:, None]   # m/rad, rad/rad
    t = rng.uniform(0.1, 1.0, 6)
    si = G.gii(jac_m, t, G.HUMAN_HAND_S_T)
    to_cm = np.array([100.0, 100, 100, 1, 1, 1])[:, None]
    cm = G.gii(to_cm * jac_m, t * 100.0, [1.0, 1.0, 1.5, 3.6, 0.5, 3.9])       # torques in N cm
    assert cm.value == pytest.approx(si.value, rel=1e-12)
    assert (cm.argmin, cm.argmax) == (si.argmin, si.argmax)
    np.testing.assert_allclose(G.scaled_singular_values(to_cm * jac_m, t, [1.0, 1.0, 1.5, 3.6, 0.5, 3.9]),
                               100 * G.scaled_singular_values(jac_m, t, G.HUMAN_HAND_S_T), rtol=1e-9)
    wrong = G.gii(jac_m, t, [1.0, 1.0, 1.5, 3.6, 0.5, 3.9])
    assert abs(wrong.value - si.value) > 0.1 * si.value


# -- invariances, inequalities, reciprocity -------------------------------------------------
@pytest.mark.parametrize("kind", G.KINDS)
def test_scaling_all_torques_or_requirements_changes_nothing(kind):
    rng = np.random.default_rng(RNG_SEED + 3)
    jac = _random_matrices(rng, 50, 3, 4 if kind == "force_map" else 3)
    n = jac.shape[-1]
    t, s = rng.uniform(0.1, 3.0, n), rng.uniform(0.1, 3.0, 3)
    base = G.gii(jac, t, s, kind=kind)
    for c in (1e-3, 7.0, 1e4):
        # normalisation by tau_1 (eq. 12) and F_i (eq. 13): the scaled values are unchanged
        np.testing.assert_allclose(G.scaled_singular_values(jac, c * t, s, kind=kind),
                                   G.scaled_singular_values(jac, t, s, kind=kind), rtol=1e-12)
        for res in (G.gii(jac, c * t, s, kind=kind), G.gii(jac, t, c * s, kind=kind)):
            assert res.value == pytest.approx(base.value, rel=1e-12)
            assert (res.argmin, res.argmax) == (base.argmin, base.argmax)
    assert G.actuator_scale([0.4, 0.2, 0.8]).tolist() == [1.0, 0.5, 2.0]


def test_workspace_order_and_shape_do_not_matter():
    rng = np.random.default_rng(RNG_SEED + 4)
    jac = _random_matrices(rng, 48, 3, 3)
    t, s = [1.0, 0.7, 1.3], [1.0, 1.0, 1.5]
    flat = G.gii(jac, t, s)
    perm = rng.permutation(48)
    shuffled = G.gii(jac[perm], t, s)
    assert shuffled.value == pytest.approx(flat.value, rel=1e-15)
    assert perm[shuffled.argmin[0]] == flat.argmin[0] and perm[shuffled.argmax[0]] == flat.argmax[0]
    grid = G.gii(jac.reshape(4, 3, 4, 3, 3), t, s)
    assert grid.value == flat.value
    assert np.ravel_multi_index(grid.argmin, (4, 3, 4)) == flat.argmin[0]


def test_gii_is_at_most_the_smallest_local_isotropy():
    """For every x: min_x0 s_min(x0) <= s_min(x) and max_x1 s_max(x1) >= s_max(x), hence
    GII <= s_min(x) / s_max(x) for all x, i.e. GII <= min_x LI(x) <= 1. Equality when one
    sample holds both extremes, e.g. a one-sample workspace."""
    rng = np.random.default_rng(RNG_SEED + 5)
    for trial in range(20):
        m = int(rng.integers(2, 7))
        jac = _random_matrices(rng, int(rng.integers(2, 40)), m, m, cond_max=100.0)
        t, s = rng.uniform(0.1, 2, m), rng.uniform(0.1, 2, m)
        li = G.local_isotropy(jac, t, s)
        value = G.gii(jac, t, s).value
        assert 0.0 < value <= li.min() * (1 + 1e-12) <= 1.0 + 1e-12
        assert G.gii(jac[:1], t, s).value == pytest.approx(li[0], rel=1e-12)
    # strict in general: two isotropic samples of different size give LI = 1 but GII = 1/2
    two = np.stack([np.eye(2), 2 * np.eye(2)])
    assert G.gii(two, [1, 1], [1, 1]).value == 0.5
    np.testing.assert_array_equal(G.local_isotropy(two, [1, 1], [1, 1]), [1.0, 1.0])


def test_jacobian_and_force_map_give_the_same_gii():
    """(S_T^-1 J^-T S_J)^-T = S_T J S_J^-1: reciprocal singular values, equal GII; the
    extremes swap, and weakest/strongest name the same samples under both kinds."""
    rng = np.random.default_rng(RNG_SEED + 6)
    jac = _random_matrices(rng, 64, 3, 3, cond_max=50.0).reshape(8, 8, 3, 3)
    a = np.swapaxes(np.linalg.inv(jac), -1, -2)
    t, s = [0.3, 0.2, 0.5], list(G.HUMAN_HAND_FORCES)
    np.testing.assert_allclose(G.scaled_singular_values(jac, t, s),
                               1 / G.scaled_singular_values(a, t, s, kind="force_map")[..., ::-1], rtol=1e-10)
    np.testing.assert_allclose(G.local_isotropy(jac, t, s), G.local_isotropy(a, t, s, kind="force_map"), rtol=1e-10)
    rj, rf = G.gii(jac, t, s), G.gii(a, t, s, kind="force_map")
    assert rj.value == pytest.approx(rf.value, rel=1e-10)
    assert (rj.argmin, rj.argmax) == (rf.argmax, rf.argmin)
    assert (rj.weakest, rj.strongest) == (rf.weakest, rf.strongest) == (rf.argmin, rf.argmax)
    # scaling our J^T the paper's way (S_J J^T S_T^-1) is not the same index
    wrong = G.gii(np.swapaxes(jac, -1, -2), s, t)
    assert abs(wrong.value - rj.value) > 1e-3


# -- bad samples and misuse -----------------------------------------------------------------
def test_infeasible_samples_are_excluded_and_never_computed():
    rng = np.random.default_rng(RNG_SEED + 7)
    jac = _random_matrices(rng, 10, 2, 2)
    mask = np.ones(10, bool)
    mask[[2, 5]] = False
    poisoned = jac.copy()
    poisoned[2] = np.nan
    poisoned[5] = 1e9 * np.eye(2)
    res = G.gii(poisoned, [1, 2], [1, 1], feasible=mask)
    ref = G.gii(jac[mask], [1, 2], [1, 1])
    assert res.value == ref.value and res.count == 8
    kept = np.flatnonzero(mask)
    assert res.argmin == (int(kept[ref.argmin[0]]),) and res.argmax == (int(kept[ref.argmax[0]]),)
    none = G.gii(poisoned, [1, 2], [1, 1], feasible=np.zeros(10, bool))
    assert np.isnan(none.value) and none.count == 0 and none.argmin is None and none.weakest is None


@pytest.mark.parametrize("kind", G.KINDS)
def test_singular_samples_give_zero(kind):
    """A rank-deficient or non-finite feasible sample is singular: sigma_min = 0 or
    sigma_max = inf, so the GII is 0 and the local isotropy there is 0."""
    good = np.array([[1.0, 0.2], [0.1, 0.9]])
    rank1 = np.array([[1.0, 2.0], [0.5, 1.0]])
    infinite = np.array([[np.inf, 1.0], [0.0, 1.0]])
    for bad in (rank1, infinite, np.zeros((2, 2))):
        stack = np.stack([good, bad, good])
        assert G.gii(stack, [1, 1], [1, 1], kind=kind).value == 0.0
        li = G.local_isotropy(stack, [1, 1], [1, 1], kind=kind)
        assert li[1] == 0.0 and li[0] > 0.5
    res = G.gii(np.stack([good, infinite]), [1, 1], [1, 1], kind=kind)
    assert res.argmax == (1,) and res.sigma_max == np.inf


def test_fivebar_direct_singularity_gives_zero():
    """With a base 0.06 m wide and 0.10 m proximal links the elbows meet at
    B = (0, sqrt(0.1^2 - 0.03^2)); with C straight above, both distal links coincide: a direct
    singularity (det J_p = 0, paper 002), where our J blows up and the GII collapses."""
    mech = FiveBar(proximal=0.10, distal=0.15, half_base=0.03)
    h = np.sqrt(0.10 ** 2 - 0.03 ** 2)
    q = np.array([np.arctan2(h, 0.03), np.arctan2(h, -0.03)])
    x = np.array([0.0, h + 0.15])
    np.testing.assert_allclose(mech.elbows(q), [[0.0, h], [0.0, h]], atol=1e-15)
    assert mech.singularity(q, x) == 2
    stack = np.stack([mech.jacobian(q, x), np.array([[0.05, 0.01], [-0.02, 0.04]])])
    res = G.gii(stack, [0.1, 0.1], [1, 1])
    assert res.value < 1e-12 and res.weakest == (0,)
    exact = np.stack([np.array([[np.inf, np.inf], [0.0, -0.03]]), stack[1]])   # det J_p exactly 0
    assert G.gii(exact, [0.1, 0.1], [1, 1]).value == 0.0


def test_misuse_raises_naming_the_argument():
    jac = np.eye(3)
    with pytest.raises(ValueError, match="s_j must have shape"):
        G.gii(jac, [1, 1], [1, 1, 1])
    with pytest.raises(ValueError, match="s_t must be positive"):
        G.scaled_singular_values(jac, [1, 1, 1], [1, -1, 1])
    with pytest.raises(ValueError, match="kind must be one of"):
        G.local_isotropy(jac, [1, 1, 1], [1, 1, 1], kind="paper")
    with pytest.raises(ValueError, match="feasible must be a boolean array"):
        G.gii(np.stack([jac, jac]), [1, 1, 1], [1, 1, 1], feasible=[True])
    with pytest.raises(ValueError, match=r"s_t must have shape \(3,\)"):
        G.gii(jac, [1, 1, 1], [[1, 1, 1]])
    with pytest.raises(ValueError, match="jac must have shape"):
        G.scaled_matrix(np.ones(3), [1], [1])
    with pytest.raises(ValueError, match="sigma_min and sigma_max"):
        G.gii_from_extremes(np.ones(3), np.ones(4))


def test_rotate_task_rows_into_end_effector_frame():
    """blockdiag(R^T, R^T) J by hand; with S_T uniform within each block the singular
    values do not change, with Table I's (different per axis) they do."""
    rng = np.random.default_rng(RNG_SEED + 8)
    jac = _random_matrices(rng, 4, 6, 6)
    rot = np.linalg.qr(rng.normal(size=(4, 3, 3)))[0]
    rot *= np.sign(np.linalg.det(rot))[:, None, None]
    block = np.zeros((4, 6, 6))
    block[:, :3, :3] = block[:, 3:, 3:] = np.swapaxes(rot, -1, -2)
    got = G.rotate_task_rows(jac, rot)
    np.testing.assert_allclose(got, block @ jac, rtol=1e-13, atol=1e-16)
    uniform = [1, 1, 1, 0.04, 0.04, 0.04]
    np.testing.assert_allclose(G.scaled_singular_values(got, np.ones(6), uniform),
                               G.scaled_singular_values(jac, np.ones(6), uniform), rtol=1e-10)
    assert not np.allclose(G.scaled_singular_values(got, np.ones(6), G.HUMAN_HAND_S_T),
                           G.scaled_singular_values(jac, np.ones(6), G.HUMAN_HAND_S_T), rtol=1e-3)
    with pytest.raises(ValueError, match="multiple of 3"):
        G.rotate_task_rows(np.eye(2), np.eye(3))


def test_velocity_map_is_a_result_kind_not_a_scaling_kind():
    """``gii_from_extremes`` takes the sensor GII's kind (weakest = argmin, as a force map);
    ``scaled_matrix`` does not (its two branches are the force GII's)."""
    r = G.gii_from_extremes([2.0, 1.0], [3.0, 4.0], kind="velocity_map")
    assert (r.value, r.weakest, r.strongest) == (0.25, (1,), (1,))
    with pytest.raises(ValueError, match="kind"):
        G.scaled_matrix(np.eye(2), (1.0, 1.0), (1.0, 1.0), kind="velocity_map")
    with pytest.raises(ValueError, match="kind"):
        G.gii_from_extremes([1.0], [1.0], kind="velocity")
