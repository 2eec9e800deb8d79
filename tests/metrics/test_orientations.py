"""Axis-angle orientation sampling (paper 001 eqs. 14-16) and its workspace tables II and VI.

Headless; scipy's Rotation is the independent reference for the matrices.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from metrics import orientations as O

DEG45, DEG30 = math.radians(45.0), math.radians(30.0)


def _nearest_angles(directions):
    """Great-circle distance from each unit vector to its nearest other one, shape (K,)."""
    cos = np.clip(directions @ directions.T, -1.0, 1.0)
    np.fill_diagonal(cos, -2.0)
    return np.arccos(np.clip(cos.max(axis=1), -1.0, 1.0))


# -- counts: eq. 16 ---------------------------------------------------------------------------
def test_counts_by_hand_at_45_degrees():
    """theta1_bar = pi/4, so 2 pi N / theta1_bar = 8 N.
    N = 1: 1 + floor(8 sin 45) = 1 + floor(5.657) = 6.
    N = 2: 1 + floor(16 sin 22.5) + floor(16 sin 45) = 1 + floor(6.12) + floor(11.31) = 18.
    N = 3: 1 + floor(24 sin 15) + floor(24 sin 30) + floor(24 sin 45) = 1 + 6 + 12 + 16 = 35
           in exact arithmetic; 24 sin 30 evaluates to 11.999999999999998 in double: 34.
    N = 4: 1 + floor(6.24) + floor(12.25) + floor(17.78) + floor(22.63) = 58."""
    assert [O.rotation_count(DEG45, n) for n in range(1, 5)] == [6, 18, 35, 58]
    assert [O.rotation_count(DEG45, n, rule="float") for n in range(1, 5)] == [6, 18, 34, 58]
    assert O.ring_counts(DEG45, 3).tolist() == [1, 6, 12, 16]
    assert O.ring_counts(DEG45, 3, rule="float").tolist() == [1, 6, 11, 16]
    assert O.ring_terms(DEG45, 3)[1] < 12.0          # the floating-point floor effect itself
    # The paper's text lists {6, 8, 34, 58}: 6, 34 and 58 are the float rule; "8" is a
    # damaged 18 (no rule gives 8: the two rings alone hold 6 + 11 samples).
    paper = [6, 8, 34, 58]
    flt = [O.rotation_count(DEG45, n, rule="float") for n in range(1, 5)]
    assert [p == f for p, f in zip(paper, flt)] == [True, False, True, True]


def test_count_tables_for_45_and_30_degrees():
    """The tables the script prints (N = 1..15)."""
    assert [O.rotation_count(DEG45, n) for n in range(1, 16)] == \
        [6, 18, 35, 58, 88, 123, 163, 211, 264, 322, 387, 458, 534, 617, 708]
    assert [O.rotation_count(DEG45, n, rule="float") for n in range(1, 16)] == \
        [6, 18, 34, 58, 88, 122, 163, 211, 263, 322, 387, 457, 534, 617, 707]
    assert [O.rotation_count(DEG30, n) for n in range(1, 16)] == \
        [7, 19, 37, 61, 91, 127, 169, 217, 271, 334, 401, 475, 554, 639, 730]
    assert [O.rotation_count(DEG30, n, rule="float") for n in range(1, 16)] == \
        [6, 18, 36, 60, 91, 126, 168, 216, 271, 334, 400, 474, 554, 638, 729]


def test_rules_differ_only_on_exact_integer_terms():
    """Niven: sin of a rational number of degrees is rational only at 0, 1/2, 1, so the terms
    are integers only where n theta1_bar / N is 30 deg (or 90 or 150). At 45 deg that is
    n = 2N/3 (N a multiple of 3), term 4N; at 30 deg the outer ring n = N, term 6N. Every
    other term stays far from an integer, which justifies the 1e-9 tolerance of the exact rule."""
    for bound_deg, tb in ((45, DEG45), (30, DEG30)):
        closest = np.inf
        for big_n in range(1, 61):
            x = O.ring_terms(tb, big_n)
            n = np.arange(1, big_n + 1)
            on_30 = (n * bound_deg) == 30 * big_n
            np.testing.assert_allclose(x[on_30], 360 * big_n / bound_deg * 0.5, rtol=1e-14)
            exact, flt = O.ring_counts(tb, big_n)[1:], O.ring_counts(tb, big_n, rule="float")[1:]
            assert np.all(exact[~on_30] == flt[~on_30])
            assert np.all(exact[on_30] == np.rint(x[on_30]))
            assert np.all(flt[on_30] >= exact[on_30] - 1)
            if np.any(~on_30):
                closest = min(closest, np.min(np.abs(x[~on_30] - np.rint(x[~on_30]))))
        assert closest > 1e-6


def test_geometry_of_a_ring_count():
    """Ring n holds c_n samples with arc spacing >= dtheta_1 and no room for one more:
    2 pi sin(theta_n) / c_n >= dtheta_1 > 2 pi sin(theta_n) / (c_n + 1)."""
    for tb in (DEG30, DEG45, math.radians(80)):
        for big_n in (1, 4, 9, 14):
            d1 = tb / big_n
            counts = O.ring_counts(tb, big_n)
            for n in range(1, big_n + 1):
                circumference = 2 * math.pi * math.sin(n * d1)
                assert circumference / counts[n] >= d1 * (1 - 1e-12)
                assert circumference / (counts[n] + 1) < d1


# -- eq. 15 and the paper's tables ------------------------------------------------------------
def test_balanced_count_and_choice_of_n():
    assert O.balanced_rotation_count((17, 11, 11), 2) == pytest.approx(2057 ** (2 / 3))
    assert O.balanced_rotation_count((10, 10, 10), 3) == pytest.approx(1000.0)
    assert O.balanced_rotation_count((4, 4), 1) == pytest.approx(4.0)
    # closest K_r; on a tie the smaller N: K_r(45 deg) = 6, 18 -> target 12 ties
    assert O.choose_ring_count(DEG45, 12.0) == 1
    assert O.choose_ring_count(DEG45, 12.5) == 2
    assert O.choose_ring_count(DEG45, 1e9, max_rings=20) == 20


def test_table_ii_counts_and_total():
    """Table II: positions 17 x 11 x 11 (1 cm), tip bound 30 deg -> 168, roll 13 (5 deg).
    Eq. 15 on the positions (d_r = 2): k_r = 2057^(2/3) = 161.7 -> N = 7 -> K_r = 168 with
    the literal floor (169 in exact arithmetic); total 2057 x 168 x 13 = 4,492,488."""
    target = O.balanced_rotation_count((17, 11, 11), 2)
    assert target == pytest.approx(161.7, abs=0.05)
    assert O.choose_ring_count(DEG30, target, rule="float") == 7
    assert O.choose_ring_count(DEG30, target) == 7
    assert O.rotation_count(DEG30, 7, rule="float") == 168
    assert O.rotation_count(DEG30, 7) == 169
    rolls = O.roll_angles(DEG30, 13)
    np.testing.assert_allclose(np.diff(rolls), math.radians(5.0), rtol=1e-12)
    assert 17 * 11 * 11 * 168 * rolls.size == 4_492_488
    samples = O.orientation_samples(DEG30, 7, roll=rolls, rule="float", tool_axis=(0, 1, 0))
    assert 17 * 11 * 11 * samples.count == 4_492_488


def test_table_ii_half_workspace_total_does_not_reproduce():
    """The text's 2,653,020 for i >= 0 is no product of the table's counts: i = 0..8 cm is 9
    samples, 9 x 11 x 11 x 168 x 13 = 2,378,376; and 2,653,020 = 2^2 3^3 5 17^3 has no factor
    7, 11 or 13, so no grid with 11 samples on j or k, 168 tips or 13 rolls gives it."""
    assert 9 * 11 * 11 * 168 * 13 == 2_378_376
    assert 2_653_020 == 2 ** 2 * 3 ** 3 * 5 * 17 ** 3
    assert all(2_653_020 % p for p in (7, 11, 13))


def test_table_vi_counts_and_total():
    """Table VI: a quarter of the positions, 17 x 11 x 21 (0.5 cm), tip bound 45 deg -> 617.
    Eq. 15 on the full grid 33 x 21 x 21 gives k_r = 596.1 -> N = 14 -> K_r = 617 (both
    rules); on the quarter it would give N = 9 (263). Total 3927 x 617 = 2,422,959."""
    full = O.balanced_rotation_count((33, 21, 21), 2)
    assert O.choose_ring_count(DEG45, full) == O.choose_ring_count(DEG45, full, rule="float") == 14
    assert O.rotation_count(DEG45, 14) == O.rotation_count(DEG45, 14, rule="float") == 617
    assert O.choose_ring_count(DEG45, O.balanced_rotation_count((17, 11, 21), 2), rule="float") == 9
    assert 17 * 11 * 21 * O.orientation_samples(DEG45, 14).count == 2_422_959


# -- the samples --------------------------------------------------------------------------------
@pytest.mark.parametrize("axis", [(0, 0, 1), (0, 1, 0), (1, 0, 0), (1, 2, -2)])
def test_samples_are_rotations_within_the_bound(axis):
    rolls = O.roll_angles(DEG30, 5)
    s = O.orientation_samples(DEG45, 6, roll=rolls, tool_axis=axis)
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    assert s.count == O.rotation_count(DEG45, 6) * 5 == s.tip_count * 5
    assert s.rotations.shape == (s.count, 3, 3) and s.axis_angle.shape == (s.count, 3)
    r = s.rotations
    np.testing.assert_allclose(np.swapaxes(r, -1, -2) @ r, np.broadcast_to(np.eye(3), r.shape), atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(r), 1.0, atol=1e-14)
    tip = O.tip_angle(r, tool_axis=axis)
    assert np.all(tip <= DEG45 + 1e-14) and np.all(s.axis_angle[:, 1] <= DEG45)
    np.testing.assert_allclose(tip, s.axis_angle[:, 1], atol=1e-14)
    np.testing.assert_allclose(s.directions, r @ a, atol=1e-15)
    # each tip direction once per roll angle, roll fastest; the tip direction ignores roll
    np.testing.assert_array_equal(s.axis_angle[:, 0], np.tile(rolls, s.tip_count))
    dirs = s.directions.reshape(s.tip_count, 5, 3)
    np.testing.assert_allclose(dirs, np.repeat(dirs[:, :1], 5, axis=1), atol=1e-14)
    assert s.ring.max() == 6 and np.bincount(s.ring).tolist() == (5 * s.ring_counts).tolist()


def test_matrices_against_scipy_and_the_frame_convention():
    """R = Rot(u, theta_1) Rot(a, theta_0) with u = -sin(theta_2) e1 + cos(theta_2) e2, built
    independently with scipy from rotation vectors; the tip points at azimuth theta_2 from e1.
    Paper 001's pen axis j = y has the frame (e1, e2) = (z, x)."""
    rng = np.random.default_rng(7)
    t0, t1, t2 = rng.uniform(-1, 1, 50), rng.uniform(0, 1.2, 50), rng.uniform(0, 2 * np.pi, 50)
    for a, e1, e2 in (((0, 0, 1), (1, 0, 0), (0, 1, 0)), ((0, 1, 0), (0, 0, 1), (1, 0, 0))):
        a, e1, e2 = (np.array(v, float) for v in (a, e1, e2))
        u = -np.sin(t2)[:, None] * e1 + np.cos(t2)[:, None] * e2
        ref = (Rotation.from_rotvec(u * t1[:, None]) * Rotation.from_rotvec(a * t0[:, None])).as_matrix()
        got = O.axis_angle_matrix(t0, t1, t2, tool_axis=a)
        np.testing.assert_allclose(got, ref, atol=1e-14)
        tipped = got @ a
        expect = np.sin(t1)[:, None] * (np.cos(t2)[:, None] * e1 + np.sin(t2)[:, None] * e2) + np.cos(t1)[:, None] * a
        np.testing.assert_allclose(tipped, expect, atol=1e-15)
        # one at a time equals the batch
        np.testing.assert_allclose(O.axis_angle_matrix(t0[3], t1[3], t2[3], tool_axis=a), got[3], atol=0)


def test_tilt_vectors_are_the_rotation_vectors_without_roll():
    s = O.orientation_samples(DEG45, 5, tool_axis=(0, 1, 0))
    ref = Rotation.from_matrix(s.rotations).as_rotvec()
    np.testing.assert_allclose(s.tilt_vectors, ref, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(s.tilt_vectors, axis=-1), s.axis_angle[:, 1], atol=1e-15)
    np.testing.assert_allclose(s.tilt_vectors[:, 1], 0.0, atol=1e-15)        # perpendicular to the pen axis
    rolled = O.orientation_samples(DEG45, 5, roll=[0.3], tool_axis=(0, 1, 0))
    np.testing.assert_allclose(rolled.tilt_vectors, s.tilt_vectors, atol=0)


def test_azimuths_within_a_ring():
    s = O.orientation_samples(DEG45, 3)
    # ring 2 (theta_1 = 30 deg) holds 12 samples 30 deg apart in the exact rule, 11 in the float rule
    for rule, count in (("exact", 12), ("float", 11)):
        samples = O.orientation_samples(DEG45, 3, rule=rule)
        t2 = samples.axis_angle[samples.ring == 2, 2]
        np.testing.assert_allclose(t2, 2 * np.pi * np.arange(count) / count, rtol=1e-15)
        np.testing.assert_allclose(samples.axis_angle[samples.ring == 2, 1], math.radians(30), rtol=1e-15)
    assert s.axis_angle[0].tolist() == [0.0, 0.0, 0.0]          # the pole first


def test_spacing_is_nearly_uniform_unlike_uniform_azimuth():
    """Eq. 14: samples on different rings are >= dtheta_1 apart (polar angles differ by it),
    ring neighbours a little under dtheta_1 (chord of the small circle). Nearest-neighbour
    distances stay within a few % of dtheta_1. Uniform theta_2 with the same number of
    samples per ring (same total) crowds them near the pole."""
    for tb, big_n in ((DEG45, 8), (DEG45, 14), (DEG30, 7)):
        d1 = tb / big_n
        s = O.orientation_samples(tb, big_n)
        nn = _nearest_angles(s.directions) / d1
        assert 0.98 < nn.min() and nn.max() < 1.07
        assert nn.std() / nn.mean() < 0.03
        ring = s.ring
        cos = np.clip(s.directions @ s.directions.T, -1, 1)
        other = ring[:, None] != ring[None, :]
        assert np.arccos(cos[other]).min() >= d1 * (1 - 1e-9)
        per_ring = round((s.tip_count - 1) / big_n)
        n = np.repeat(np.arange(1, big_n + 1), per_ring)
        k = np.tile(np.arange(per_ring), big_n)
        naive = O.axis_angle_matrix(0.0, n * d1, 2 * np.pi * k / per_ring) @ np.array([0, 0, 1.0])
        naive = np.vstack([[0, 0, 1.0], naive])
        nn_naive = _nearest_angles(naive) / d1
        assert nn_naive.std() / nn_naive.mean() > 8 * nn.std() / nn.mean()
        assert nn_naive.min() < 0.6


def test_misuse_raises_naming_the_argument():
    with pytest.raises(ValueError, match="theta1_bar"):
        O.rotation_count(0.0, 3)
    with pytest.raises(ValueError, match="theta1_bar"):
        O.ring_counts(4.0, 3)
    with pytest.raises(ValueError, match="n_rings"):
        O.ring_counts(DEG45, 0)
    with pytest.raises(ValueError, match="n_rings"):
        O.orientation_samples(DEG45, 2.5)
    with pytest.raises(ValueError, match="rule"):
        O.ring_counts(DEG45, 2, rule="round")
    with pytest.raises(ValueError, match="tool_axis"):
        O.axis_angle_matrix(0, 0, 0, tool_axis=(0, 0, 0))
    with pytest.raises(ValueError, match="roll"):
        O.orientation_samples(DEG45, 2, roll=[np.nan])
    with pytest.raises(ValueError, match="target"):
        O.choose_ring_count(DEG45, -1.0)
    with pytest.raises(ValueError, match="rotational_axes"):
        O.balanced_rotation_count((3, 3, 3), 0)
    with pytest.raises(ValueError, match="rotations"):
        O.tip_angle(np.eye(2))
