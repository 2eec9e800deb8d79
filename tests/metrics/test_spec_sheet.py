"""The spec-sheet rows (metrics.spec_sheet, metrics.resolution) against paper 001's Table X and eq. 28,
a linear programme, and central differences.

Table X's derived rows follow from eq. 28's mass matrix D and Table X's own peak and minimum
forces; every printed number is rounded, so each check is an interval: the inputs vary over
their printed rounding (half a unit in the last digit) and the result, rounded as printed,
must be reachable. No tolerance is chosen.
"""
from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.optimize import linprog

from metrics import resolution as R
from metrics import spec_sheet as S
from scripts import paper_data as P

# Paper 001 eq. 28 (SI) and Table X as printed (scripts/paper_data.py).
D_SI = P.EQ28_D_SI
PEAK = np.array(P.TABLEX_PEAK)
MINIMUM = np.array(P.TABLEX_MINIMUM)
EFF_MASS = list(P.TABLEX_EFFECTIVE_MASS)                # g, g cm^2
PEAK_ACCEL = list(P.TABLEX_PEAK_ACCEL)                  # G, G, G, s^-2, s^-2
DYN_RANGE = list(P.TABLEX_DYNAMIC_RANGE)


def _half_unit(printed: float, sig: int | None = None, decimals: int | None = None) -> float:
    """Half a unit in the last printed digit."""
    if decimals is not None:
        return 0.5 * 10.0 ** -decimals
    return 0.5 * 10.0 ** (np.floor(np.log10(abs(printed))) - sig + 1)


def test_effective_mass_is_the_diagonal_of_d_as_table_x_prints():
    diagonal, apparent = S.effective_masses(D_SI)
    grams = diagonal * np.array([1e3, 1e3, 1e3, 1e7, 1e7])       # kg -> g; kg m^2 -> g cm^2
    assert grams.tolist() == pytest.approx(EFF_MASS, rel=1e-12)
    # The apparent mass 1 / (D^-1)_ii is what a free-moving other axis would give: y and the
    # x rotation are coupled (D_24 = -346e-5), so it is well below Table X's figure there.
    apparent_g = apparent * np.array([1e3, 1e3, 1e3, 1e7, 1e7])
    assert apparent_g[1] < 220 < EFF_MASS[1] and apparent_g[3] < 9900 < EFF_MASS[3]


def test_table_x_peak_accelerations_follow_from_peak_force_over_diagonal_mass():
    diagonal, apparent = S.effective_masses(D_SI)
    decimals = [1, 1, 1, 0, 0]
    sig_d = [3, 3, 3, 3, 3]
    for i in range(5):
        to_out = 1.0 / S.STANDARD_GRAVITY if i < 3 else 0.01       # G; N cm / (kg m^2) -> s^-2
        hp = _half_unit(PEAK[i], sig=2 if PEAK[i] < 100 else 3)
        hd = _half_unit(EFF_MASS[i], sig=sig_d[i]) / EFF_MASS[i] * diagonal[i]
        lo = (PEAK[i] - hp) / (diagonal[i] + hd) * to_out
        hi = (PEAK[i] + hp) / (diagonal[i] - hd) * to_out
        h = _half_unit(PEAK_ACCEL[i], decimals=decimals[i])
        assert lo - h <= PEAK_ACCEL[i] <= hi + h, (i, lo, hi)
        # The nominal value agrees with the print to within the inputs' rounding.
        nominal = S.peak_accelerations(PEAK[i:i + 1], diagonal[i:i + 1])[0] * to_out
        assert lo <= nominal <= hi
    # With the apparent mass the y acceleration would be 9.98 G: no rounding of the inputs reaches 9.5.
    y = (PEAK[1] - 0.5) / apparent[1] / S.STANDARD_GRAVITY
    assert y > PEAK_ACCEL[1] + 0.05


def test_table_x_dynamic_ranges_are_peak_over_minimum():
    got = S.dynamic_ranges(PEAK, MINIMUM)
    for g, p, mn, printed in zip(got, PEAK, MINIMUM, DYN_RANGE):
        hp, hm = _half_unit(p, sig=2 if p < 100 else 3), _half_unit(mn, sig=2)
        lo, hi = (p - hp) / (mn + hm), (p + hp) / (mn - hm)
        assert lo <= g <= hi
        assert lo - _half_unit(printed, sig=2) <= printed <= hi + _half_unit(printed, sig=2)


@pytest.mark.parametrize("m, n, biased", [(2, 2, False), (3, 3, True), (3, 4, False), (5, 6, True), (2, 3, True)])
def test_axis_capabilities_match_a_linear_programme(m, n, biased):
    rng = np.random.default_rng(100 * m + n + biased)
    for _ in range(5):
        a = rng.normal(size=(m, n))
        hi = rng.uniform(0.5, 2.0, n)
        lo = -rng.uniform(0.5, 2.0, n) if biased else -hi
        bias = rng.uniform(-0.3, 0.3, n) if biased else None
        got = S.axis_capabilities(a, torque_limits=hi, torque_min=lo if biased else None, torque_bias=bias)
        b = np.zeros(n) if bias is None else bias
        for i, (side, sign) in itertools.product(range(m), enumerate((1.0, -1.0))):
            # Variables (tau, t): maximise t, A tau - t (sign e_i) = 0, lo - b <= tau <= hi - b, t >= 0.
            e = np.zeros(m)
            e[i] = sign
            res = linprog(np.r_[np.zeros(n), -1.0], A_eq=np.c_[a, -e], b_eq=np.zeros(m),
                          bounds=[(lo_u - b_u, hi_u - b_u) for lo_u, hi_u, b_u in zip(lo, hi, b)] + [(0, None)],
                          method="highs")
            assert res.status == 0
            # HiGHS's feasibility tolerance is 1e-7 (absolute, on the O(1) torques here).
            assert got[i, side] == pytest.approx(-res.fun, rel=1e-6, abs=1e-6)


def test_axis_capabilities_of_a_square_map_in_closed_form():
    # For square A, t e_i = A tau gives tau = t A^-1 e_i: t^+ = min_u t_u / |(A^-1)_ui|.
    a = np.array([[0.3, -0.1, 0.0], [0.2, 0.4, 0.1], [0.0, 0.1, 0.5]])
    t = np.array([1.0, 2.0, 3.0])
    inv = np.linalg.inv(a)
    want = np.min(t[:, None] / np.abs(inv), axis=0)
    got = S.axis_capabilities(a, torque_limits=t)
    assert got[:, 0] == pytest.approx(want, rel=8 * np.finfo(float).eps * 10)
    assert got[:, 1] == pytest.approx(want, rel=8 * np.finfo(float).eps * 10)


def test_axis_capabilities_unbounded_and_unholdable():
    assert np.isinf(S.axis_capabilities([[np.inf, 0.0], [0.0, 1.0]], torque_limits=[1.0, 1.0])).all()
    # A bias beyond the limit: the origin is outside the set, nothing can be held along any axis.
    got = S.axis_capabilities(np.eye(2), torque_limits=[1.0, 1.0], torque_bias=[1.5, 0.0])
    assert got.tolist() == [[0.0, 0.0], [0.0, 0.0]]


def test_effective_masses_reject_bad_matrices():
    with pytest.raises(ValueError, match="square"):
        S.effective_masses(np.ones((2, 3)))
    with pytest.raises(ValueError, match="symmetric"):
        S.effective_masses([[1.0, 0.5], [0.0, 1.0]])
    with pytest.raises(ValueError, match="positive definite"):
        S.effective_masses([[1.0, 2.0], [2.0, 1.0]])


def test_resolution_is_one_step_through_the_jacobian_against_central_differences():
    # A planar RR arm: x = l1 (cos a, sin a) + l2 (cos(a + b), sin(a + b)).
    l1, l2 = 0.2, 0.15

    def fk(q):
        return np.array([l1 * np.cos(q[0]) + l2 * np.cos(q[0] + q[1]), l1 * np.sin(q[0]) + l2 * np.sin(q[0] + q[1])])

    q = np.array([0.4, 1.1])
    steps = R.joint_steps([4000.0, 2000.0], [10.0, 5.0])
    assert steps.tolist() == pytest.approx([2 * np.pi / 40000, 2 * np.pi / 10000], rel=1e-15)
    h = 1e-6
    jac = np.stack([(fk(q + h * e) - fk(q - h * e)) / (2 * h) for e in np.eye(2)], axis=-1)
    moves = [fk(q + steps[u] * np.eye(2)[u]) - fk(q) for u in range(2)]
    # One real step moves the tip by J delta to second order: |error| <= |J''| delta^2 / 2 <= (l1 + l2) delta^2.
    second = (l1 + l2) * float(np.max(steps)) ** 2
    want_axis = np.max(np.abs(np.stack(moves, -1)), axis=-1)
    assert R.axis_resolution(jac, steps) == pytest.approx(want_axis, abs=second + 1e-12)
    assert float(R.spatial_resolution(jac, steps)) == pytest.approx(max(np.linalg.norm(mv) for mv in moves),
                                                                     abs=second + 1e-12)


def test_resolution_rejects_bad_steps():
    with pytest.raises(ValueError, match="encoder counts"):
        R.joint_steps([0.0, 100.0])
    with pytest.raises(ValueError, match="gear_ratios"):
        R.joint_steps([100.0, 100.0], [1.0])
    with pytest.raises(ValueError, match="one entry per joint"):
        R.axis_resolution(np.eye(2), [1.0, 2.0, 3.0])


# -- the bounds for a passive wall, by hand --------------------------------------------------------
def test_quantisation_bound_is_twice_the_friction_over_one_count():
    # Table X's own figures: x 0.022 N over 142 um; rx 0.19 N cm over 0.122 deg.
    got = S.quantisation_stiffness_bounds([0.022, 0.0019], [142e-6, np.radians(0.122)])
    assert got[0] == pytest.approx(2 * 0.022 / 142e-6, rel=1e-15)             # 309.86 N/m = 3.1 N/cm
    assert got[1] == pytest.approx(2 * 0.0019 / (0.122 * np.pi / 180), rel=1e-15)
    assert 309.8 < got[0] < 309.9


def test_colgate_schenkel_bound_both_ways():
    # b > K T / 2 + |B|: Table X's x stiffness 16 N/cm and damping 0.44 N s/cm at 1 kHz need
    # b > 1600 x 0.001 / 2 + 44 = 44.8 N s/m of physical damping.
    assert float(S.sampling_damping_needed(1600.0, 1000.0, 44.0)) == pytest.approx(44.8, rel=1e-15)
    assert float(S.sampling_damping_needed(1600.0, 1000.0, -44.0)) == pytest.approx(44.8, rel=1e-15)
    # Solved for K: K < 2 (b - |B|) / T; none where |B| >= b.
    b = np.array([0.5, 0.5, 0.5])
    got = S.sampling_stiffness_bounds(b, 1000.0, [0.0, -0.2, 0.7])
    assert got.tolist() == pytest.approx([1000.0, 600.0, 0.0], rel=1e-15)
    # The two directions agree: at K = 2 (b - |B|) / T the needed damping is exactly b.
    assert S.sampling_damping_needed(got[:2], 1000.0, [0.0, 0.2]) == pytest.approx(b[:2], rel=1e-15)


def test_spec_rows_give_the_bounds_only_with_their_inputs():
    from resources import load_preset

    preset = load_preset("twin_pantograph_prototype")
    mech, x = preset.mechanism, np.array(preset.pose)
    steps = R.mechanism_steps(mech)
    spans = np.full(5, 0.01)
    rows = S.spec_rows(mech, x, spans=spans, steps=steps, minimum_forces=preset.spec.minimum_forces,
                       control_rate=1000.0)
    k = 2 * np.array(preset.spec.minimum_forces) / rows["resolution"]
    assert rows["stiffness_bound_quantisation"] == pytest.approx(k, rel=1e-15)
    assert rows["damping_needed_quantisation"] == pytest.approx(k * 0.001 / 2, rel=1e-15)
    assert rows["minimum_force"].tolist() == list(preset.spec.minimum_forces)
    assert "stiffness_bound_sampling" not in rows                  # no physical damping given
    rows = S.spec_rows(mech, x, spans=spans, steps=steps, minimum_forces=preset.spec.minimum_forces,
                       control_rate=2000.0, physical_damping=[1.0, 2.0, 3.0, 0.01, 0.02])
    assert rows["stiffness_bound_sampling"] == pytest.approx([4000.0, 8000.0, 12000.0, 40.0, 80.0], rel=1e-15)
    assert rows["damping_bound_sampling"].tolist() == [1.0, 2.0, 3.0, 0.01, 0.02]
    bare = S.spec_rows(mech, x, spans=spans)
    assert not any(key.startswith(("stiffness", "damping", "minimum")) for key in bare)
