"""Reproduce the papers: paper 000 Table 3 (Inverse3) and paper 002 Table 1 (five-bar sweep).

Every figure of Table 3 is checked to 0.1 %; the one that does not reproduce is listed in
``EXPECTED_MISMATCHES`` with the reason, and the test asserts that it really misses, by how
much, and that the printed value is not attainable at all under the model that reproduces
the other 35. The Table 1 sweep's counts are checked against an independent brute-force
loop (paper 002's own Jacobian, circle-intersection inverse kinematics, numpy.linalg.cond),
against plain geometry and against facts that follow from symmetry and scale invariance;
whether the paper's winner comes out under each sampling is recorded, not assumed.
docs/reproduction.md reports the same numbers (``python scripts/reproduce_papers.py``); the
printed tables are in ``scripts/paper_data.py``, the papers cited in ``docs/references.md``.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from kinematics import FiveBar
from kinematics.angles import wrap_into
from metrics import sweeps as S
from metrics.quantities import evaluate
from resources import load_preset
from scripts import paper_data as P

DEG = math.pi / 180.0

# ------------------------------------------------------------------------------------------
# Paper 000, Table 3
# ------------------------------------------------------------------------------------------

#: (quantity, statistic, scenario index) -> (paper, ours at 1000 x 1000, relative error, reason)
EXPECTED_MISMATCHES = {
    ("isotropic_force", "max", 2): (
        11.974, 11.6743, -0.02503,
        "not attainable: the base-joint facet caps the isotropic force at 11.705 N (supremum over the slice, "
        "at the p1-limit / spread-limit corner); the paper's figure is most likely 11.674 with one digit "
        "mistyped or misread",
    ),
}


def _scenarios():
    return [(p.mechanism, p.grid) for p in map(load_preset, P.TABLE3_SCENARIOS)]


@pytest.fixture(scope="module")
def maps():
    return S.scenario_maps(_scenarios())


@pytest.fixture(scope="module")
def comparison(maps):
    return {(r.quantity, r.statistic, r.scenario): r for r in P.compare_table3([m.stats for m in maps])}


def test_table3_has_36_figures(comparison):
    assert len(comparison) == 36
    assert {k[0] for k in comparison} == {"condition_number", "anisotropic_force", "isotropic_force"}


@pytest.mark.parametrize("key", [(q, s, k) for (q, s) in P.TABLE3_PAPER for k in range(3)],
                         ids=lambda key: f"{key[0]}-{key[1]}-scenario{key[2] + 1}")
def test_table3_figure(comparison, key):
    row = comparison[key]
    if key in EXPECTED_MISMATCHES:
        paper, ours, rel, _reason = EXPECTED_MISMATCHES[key]
        assert row.paper == paper
        assert not row.matches, "an expected mismatch now matches: remove it from the lists"
        assert row.ours == pytest.approx(ours, abs=5e-4)
        assert row.rel_error == pytest.approx(rel, abs=1e-4)
    else:
        assert abs(row.rel_error) <= 1e-3, f"{key}: paper {row.paper}, ours {row.ours:.5f}"


def test_expected_mismatches_are_the_modules_list():
    """The report (scripts.paper_data.TABLE3_MISMATCHES) names exactly the figures this test expects to miss."""
    assert set(P.TABLE3_MISMATCHES) == set(EXPECTED_MISMATCHES)


def test_condition_number_does_not_depend_on_gear_ratios(maps):
    base = maps[0].values["condition_number"]
    for m in maps[1:]:
        assert np.array_equal(m.feasible, maps[0].feasible)
        assert np.array_equal(m.values["condition_number"], base, equal_nan=True)


def test_forces_never_drop_when_a_gear_ratio_rises(maps):
    """Raising t_u enlarges the torque box, so the force polytope (and its ball, its longest vertex) can only grow."""
    feasible = maps[0].feasible
    for name in ("isotropic_force", "anisotropic_force"):
        base = maps[0].values[name][feasible]
        for m in maps[1:]:
            assert np.all(m.values[name][feasible] >= base * (1.0 - 1e-12))


def test_scenarios_share_the_extremes_the_paper_says_they_share(maps):
    iso = [m.stats["isotropic_force"] for m in maps]
    # Scenario 3 changes only the five-bar ratios; the minimum is base-limited in both.
    assert iso[2].min == iso[0].min
    # (bit for bit: t_0 / |J[:, 0]| is the same division in both, and the other facets only
    # move away). Where: the minimum is shared by grid points at the same radius (the base facet
    # is t_0 / r), so compare values at the reported minimiser rather than its tie order.
    mech0 = _scenarios()[0][0]
    at = evaluate(mech0, np.array(iso[2].argmin)[None], ("isotropic_force",)).values["isotropic_force"][0]
    assert at == pytest.approx(iso[0].min, rel=1e-12)
    # Scenario 2 changes only the base ratio; the maximum is five-bar-limited in both.
    assert iso[1].max == iso[0].max


def test_scenario3_maximum_sits_at_the_joint_limit_corner(maps):
    mech = load_preset("inverse3_scenario3").mechanism
    stats = maps[2].stats["isotropic_force"]
    at = evaluate(mech, np.array(stats.argmax), ("isotropic_force", "bottleneck"))
    assert at.values["bottleneck"] == 0          # the base joint limits the best point
    sup = S.inverse3_isotropic_sup(mech)
    # The maximiser: theta_p1 at its upper limit, |theta_p1 - theta_p2| at its maximum.
    assert sup.h_at_sup == pytest.approx(100 * DEG, abs=1e-12)
    assert sup.corner == pytest.approx([0.0, 225 * DEG, 25 * DEG], abs=1e-12)
    assert bool(mech.feasible(sup.corner))
    assert sup.corner_point * 1000 == pytest.approx([54.336, 22.3, 224.496], abs=1e-3)
    assert sup.corner_value == pytest.approx(sup.sup, rel=1e-12)
    assert sup.sup == pytest.approx(11.7054, abs=1e-4)
    # The grid approaches the corner from inside: below it, within the cell size's effect.
    assert stats.max <= sup.sup
    assert stats.max == pytest.approx(sup.sup, rel=5e-3)


def test_paper_scenario3_maximum_is_not_attainable():
    """No feasible point of the slice holds 11.974 N (paper Table 3, Scenario 3, isotropic max).

    isotropic = min(base facet, five-bar facets), base facet = t0 / sqrt(x^2 + c^2) on the slice.
    1. Five-bar facet >= V needs h >= h_V (the facet grows with h).
    2. theta_3 in [0, th3_hi(h)] with th3_hi = 135 deg - h for those h: x >= a3 cos(th3_hi) = x_min(h),
       and min(five-bar, base(x_min)) < V for every such h.
    3. theta_3 < 0 puts the point below the five-bar centre: the body constraint then needs
       x > 65 mm (base facet < V) or z > 180 mm, i.e. x >= sqrt(a3^2 - 6.45 mm^2) (base facet < V).
    """
    value = 11.974
    mech = load_preset("inverse3_scenario3").mechanism
    p, t = mech.params, mech.torque_limits()
    c = p.plane_offset
    sup = S.inverse3_isotropic_sup(mech)
    assert np.all(np.diff(sup.five_bar_facet) > 0)                                   # 1.
    enough = sup.five_bar_facet >= value
    h_v = sup.h[enough][0]
    assert 82 * DEG < h_v < 83 * DEG
    assert np.all(np.isfinite(sup.x_min[enough]))                                    # th3_hi in [0, 90 deg]
    assert np.all(135 * DEG - sup.h[enough] == pytest.approx(
        np.minimum(p.upper_limits[1], p.upper_limits[2] + 2 * sup.h[enough]) - sup.h[enough] - 90 * DEG))
    assert np.max(sup.bound[enough]) < value                                         # 2.
    assert t[0] / math.hypot(p.body_radius, c) < value                               # 3., x > 65 mm
    a3_min = sup.x_min[-1] / math.cos(135 * DEG - sup.h[-1])                          # a3 at h = 100 deg
    drop = p.base_height - p.body_height
    assert t[0] / math.hypot(math.sqrt(a3_min ** 2 - drop ** 2), c) < value           # 3., z > 180 mm
    # The gap is not a rounding matter: the supremum is 2.2 % below the printed figure.
    assert sup.sup < value / 1.02
    # And 11.674 (ours at 1000 x 1000) is the printed figure with one digit changed.
    assert f"{11.6743:.3f}".replace("6", "9", 1) == "11.974"


def test_dense_joint_space_sampling_never_beats_the_supremum():
    """Brute force over the feasible set, independent of the grid: (h, theta_3) on a dense grid."""
    mech = load_preset("inverse3_scenario3").mechanism
    p = mech.params
    sup = S.inverse3_isotropic_sup(mech)
    h, th3 = np.meshgrid(np.linspace(10 * DEG, 100 * DEG, 721), np.linspace(-180 * DEG, 180 * DEG, 1441),
                         indexing="ij")
    p1, _ = wrap_into(th3 + h + 90 * DEG, p.lower_limits[1], p.upper_limits[1])
    q = np.stack([np.zeros_like(h), p1, p1 - 2 * h], axis=-1)
    x, _ = mech.forward(q)
    ok = mech.feasible(q, x)
    ok &= (x[..., 0] >= -0.05) & (x[..., 0] <= 0.35) & (x[..., 2] >= -0.15) & (x[..., 2] <= 0.5)
    jac = mech.jacobian(q[ok])
    iso = np.min(mech.torque_limits() / np.linalg.norm(jac, axis=-2), axis=-1)
    assert ok.sum() > 100_000
    assert iso.max() <= sup.sup * (1 + 1e-12)
    assert iso.max() == pytest.approx(sup.sup, rel=1e-12)     # the sampled grid contains the corner


#: claim text prefix -> (holds, value recomputed from our figures)
EXPECTED_CLAIMS = {
    "increasing the gear ratio increased the global maximum isotropic force by 71.8 %": (True, 71.69),
    "the mean maximum isotropic force by 11.3 %": (True, 11.28),
    "and reduced standard deviation by 29.4 %": (True, 29.48),
    "[the g1 change would increase] the global maximum isotropic force by 42 %": (False, 71.69),
    "the minimum force in the two cases [Scenarios 1 and 3] is identical": (True, 1.0),
}


def test_table3_derived_claims(maps):
    claims = {c.text: c for c in P.table3_claims([m.stats for m in maps])}
    assert set(claims) == set(EXPECTED_CLAIMS)
    for text, (holds, ours) in EXPECTED_CLAIMS.items():
        assert claims[text].holds is holds, text
        assert claims[text].from_ours == pytest.approx(ours, abs=0.006), text
    assert claims["and reduced standard deviation by 29.4 %"].from_paper == pytest.approx(29.453, abs=1e-3)


def test_section42_base_gear_ratio_claims(maps):
    mech, grid = _scenarios()[0]
    study = S.isotropic_force_by_gear_ratio(mech, grid, P.SECTION42_G1)
    s1 = maps[0].stats["isotropic_force"]
    s2 = maps[1].stats["isotropic_force"]
    by_g1 = {round(c.g1, 6): c.isotropic for c in study}
    plus60 = by_g1[round(6.875 * 1.6, 6)]
    # While the base joint limits the minimum, the minimum scales with g1 exactly. Its location
    # does not, bit for bit: the base facet t_0 / r depends only on the radius r = x, so the
    # minimum is shared by a column of grid points and which one wins is rounding (seen: exact
    # ties). So: plus60's minimiser is a minimiser of scenario 1 too.
    at = evaluate(mech, np.array(plus60.argmin)[None], ("isotropic_force",)).values["isotropic_force"][0]
    assert at == pytest.approx(s1.min, rel=1e-12)
    assert plus60.min == pytest.approx(1.6 * s1.min, rel=1e-12)
    assert plus60.min == pytest.approx(3.6475, abs=1e-4)
    verdicts = [(c.where, c.claimed, c.holds) for c in P.section42_claims(study, s2)]
    assert verdicts == [
        ("Discussion 4.2", 3.9, False),      # +60 % g1: global 3.65 N, not 3.9 N
        ("Discussion 4.2", 4.5, True),       # ... mean 4.466 N
        ("Conclusions", 3.914, True),        # +71.8 % g1 reaches Scenario 2's 3.914 N
        ("Discussion 4.1", 0.0, True),       # g1 beyond 13.75 changes nothing
    ]
    # Beyond Scenario 2's g1 nothing changes at all: every point is five-bar-limited.
    big = by_g1[100.0]
    assert (big.min, big.max) == (s2.min, s2.max)


# ------------------------------------------------------------------------------------------
# Paper 002, Table 1
# ------------------------------------------------------------------------------------------

CM = 0.01
OPT, TIE = P.PAPER_OPTIMUM, P.PAPER_TIE

#: What the sweep gives (working mode "+-"): winners, and the counts of the paper's pair.
RECORDED = {
    "grid": {"winners": [(9, 13, 3)], "optimum": 548, "tie": 486},
    "arcs": {"winners": [(9, 14, 3)], "optimum": 414, "tie": 376},
    "normalised": {"winners": [(9, 15, 5)], "optimum": 648, "tie": 630},
    "normalised_arcs": {"winners": [(10, 15, 3)], "optimum": 454, "tie": 456},
}
#: Is the paper's winner (a1, a2, a3) = (10, 15, 3) cm the (or a) minimum under the sampling?
PAPER_WINNER_REPRODUCED = {"grid": False, "arcs": False, "normalised": False, "normalised_arcs": True}
#: Kendall tau-b between the samplings' counts over the 60 designs.
RECORDED_TAU = {("grid", "arcs"): 0.902, ("grid", "normalised"): 0.822, ("arcs", "normalised_arcs"): 0.888,
                ("normalised", "normalised_arcs"): 0.889}


@pytest.fixture(scope="module")
def sweeps():
    return {name: P.table1_sweep(name) for name in S.SAMPLINGS}


def _cm(design):
    return tuple(round(v / CM) for v in design)


def test_table1_parameter_space():
    d = P.table1_designs()
    assert d.shape == (60, 3)
    assert {_cm(row) for row in d} == {(a1, a2, a3) for a1 in range(9, 13) for a2 in range(11, 16)
                                       for a3 in range(3, 6)}


@pytest.mark.parametrize("name", list(S.SAMPLINGS))
def test_table1_winner_under_each_sampling(sweeps, name):
    result = sweeps[name]
    assert [_cm(w) for w in result.winners()] == RECORDED[name]["winners"]
    assert result.count(OPT) == RECORDED[name]["optimum"]
    assert result.count(TIE) == RECORDED[name]["tie"]
    assert (OPT in [tuple(w) for w in result.winners()]) is PAPER_WINNER_REPRODUCED[name]
    assert result.rank(result.winners()[0]) == 1


def test_normalised_arcs_reproduce_the_papers_near_tie(sweeps):
    """The paper's pair comes first and second, 2 samples apart in 27,000 (the paper: a tie)."""
    result = sweeps["normalised_arcs"]
    assert [_cm(d) for d, _ in result.top(2)] == [(10, 15, 3), (9, 14, 3)]
    assert abs(result.count(OPT) - result.count(TIE)) <= 2


def test_kendall_tau_between_samplings(sweeps):
    for (a, b), tau in RECORDED_TAU.items():
        assert S.kendall_tau(sweeps[a], sweeps[b]) == pytest.approx(tau, abs=5e-4)
    assert S.kendall_tau(sweeps["grid"], sweeps["grid"]) == pytest.approx(1.0)


def _brute_force_count(design, points, threshold=5.0):
    """Independent count: circle-intersection IK for elbows out, paper 002's J = J_theta^-1 J_p, LAPACK cond."""
    a1, a2, a3 = design
    ill = reachable = 0
    for x, y in points:
        angles = []
        for bx, side in ((-a3, 1.0), (a3, -1.0)):          # leg 1 elbow to the left of O1->C, leg 2 right
            dx, dy = x - bx, y
            d = math.hypot(dx, dy)
            along = (a1 * a1 - a2 * a2 + d * d) / (2.0 * d)
            h_sq = a1 * a1 - along * along
            if h_sq < 0.0:
                break
            h = math.sqrt(h_sq)
            ex, ey = bx + along * dx / d - side * h * dy / d, along * dy / d + side * h * dx / d
            angles.append(math.atan2(ey, ex - bx))
        else:
            reachable += 1
            t1, t2 = angles
            j_p = np.array([[x - a1 * math.cos(t1) + a3, y - a1 * math.sin(t1)],
                            [x - a1 * math.cos(t2) - a3, y - a1 * math.sin(t2)]])
            j_t = a1 * np.diag([y * math.cos(t1) - (x + a3) * math.sin(t1),
                                y * math.cos(t2) + (a3 - x) * math.sin(t2)])
            try:
                k = np.linalg.cond(np.linalg.solve(j_t, j_p))
            except np.linalg.LinAlgError:
                k = math.inf
            ill += bool(k > threshold)
    return reachable, ill


def test_count_equals_brute_force_loop(sweeps):
    """One design, point by point: the count is what a plain loop with numpy.linalg.cond gives."""
    sampling = S.SAMPLINGS["grid"]
    reachable, ill = _brute_force_count(OPT, sampling.points(OPT))
    row = sweeps["grid"].details[sweeps["grid"].index(OPT)]
    assert (row.reachable, row.ill) == (reachable, ill) == (19106, 548)


def _independent_counts(design, points, threshold=5.0):
    """The same independent computation as ``_brute_force_count``, vectorised over the points.

    A sample within rounding of a boundary circle (|h^2| <= 1e-12 a1^2, the elbow offset
    vanishing) is on the workspace boundary: reachable, with J_theta singular (K = inf).
    """
    a1, a2, a3 = design
    x, y = points[:, 0], points[:, 1]
    ok = np.ones(len(x), bool)
    j_p = np.empty((len(x), 2, 2))
    j_t = np.empty((len(x), 2))
    for i, (bx, side) in enumerate(((-a3, 1.0), (a3, -1.0))):
        dx, dy = x - bx, y
        d = np.hypot(dx, dy)
        along = (a1 * a1 - a2 * a2 + d * d) / (2.0 * d)
        h_sq = a1 * a1 - along * along
        ok &= h_sq >= -1e-12 * a1 * a1
        h = np.sqrt(np.maximum(h_sq, 0.0))
        t = np.arctan2(along * dy / d + side * h * dx / d, along * dx / d - side * h * dy / d)
        j_p[:, i] = np.stack([x - a1 * np.cos(t) - bx, y - a1 * np.sin(t)], axis=-1)
        j_t[:, i] = a1 * (y * np.cos(t) - (x - bx) * np.sin(t)) * (h_sq > 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        jac = j_p[ok] / j_t[ok][:, :, None]                  # J_theta^-1 J_p, J_theta diagonal
    finite = np.all(np.isfinite(jac), axis=(1, 2))
    k = np.full(len(jac), np.inf)
    k[finite] = np.linalg.cond(jac[finite])
    return int(ok.sum()), int(np.count_nonzero(k > threshold))


@pytest.mark.parametrize("name", list(S.SAMPLINGS))
def test_every_count_equals_the_independent_computation(sweeps, name):
    sampling = S.SAMPLINGS[name]
    for row in sweeps[name].details:
        s = sampling.scale(row.design)
        expected = _independent_counts([v / s for v in row.design], sampling.points(row.design))
        assert (row.reachable, row.ill) == expected, row.design


def test_reachable_samples_are_the_two_annuli(sweeps):
    """Reachable = inside both annuli |a1 - a2| <= |C - O_i| <= a1 + a2, whatever the working mode."""
    result = sweeps["grid"]
    pts = S.SAMPLINGS["grid"].points(OPT)
    for row, (a1, a2, a3) in zip(result.details, result.designs):
        inside = np.ones(len(pts), bool)
        for bx in (-a3, a3):
            d = np.hypot(pts[:, 0] - bx, pts[:, 1])
            inside &= (d >= abs(a1 - a2)) & (d <= a1 + a2)
        assert row.reachable == inside.sum()


def test_count_is_even_by_mirror_symmetry(sweeps):
    """Elbows out is symmetric about the y axis and so is each sampling: K(x, y) = K(-x, y)."""
    for result in sweeps.values():
        assert np.all(result.counts % 2 == 0)
    for name in ("grid", "normalised_arcs"):
        sampling = S.SAMPLINGS[name]
        pts = sampling.points(OPT)
        mech = sampling.mechanism(OPT)
        k = evaluate(mech, pts, ("condition_number",)).values["condition_number"]
        k_mirror = evaluate(mech, pts * [-1.0, 1.0], ("condition_number",)).values["condition_number"]
        np.testing.assert_allclose(k, k_mirror, rtol=1e-9)


def test_mirror_working_modes_give_the_same_counts():
    """"++" is the mirror image of "--" (swap the legs, reflect x): pointwise equal condition numbers."""
    for name in ("grid", "arcs"):
        sampling = S.SAMPLINGS[name]
        for design in (OPT, TIE, (0.12, 0.11, 0.05)):
            pts = sampling.points(design)
            mech = sampling.mechanism(design)
            k_pp = evaluate(mech.replace(working_mode="++"), pts, ("condition_number",)).values["condition_number"]
            k_mm = evaluate(mech.replace(working_mode="--"), pts * [-1.0, 1.0],
                            ("condition_number",)).values["condition_number"]
            np.testing.assert_allclose(k_pp, k_mm, rtol=1e-9)
            assert (S.count_ill_conditioned(design, sampling, working_mode="++").ill
                    == S.count_ill_conditioned(design, sampling, working_mode="--").ill)


def test_counts_are_scale_invariant_where_the_sampling_scales(sweeps):
    """The condition number is scale-free: doubling a design (exact in binary) and its sampling changes nothing."""
    for design in (OPT, TIE):
        double = tuple(2.0 * v for v in design)
        for name in ("normalised", "normalised_arcs"):
            assert S.count_ill_conditioned(double, S.SAMPLINGS[name]).ill == sweeps[name].count(design)
        grid = S.SAMPLINGS["grid"]
        big = S.Sampling("grid2", "grid", "physical", 2 * grid.step, box=((-0.64, 0.64), (0.0, 0.54)))
        assert S.count_ill_conditioned(double, big).ill == sweeps["grid"].count(design)


def test_counts_fall_as_the_threshold_rises(sweeps):
    k5 = sweeps["normalised_arcs"]
    k10 = P.table1_sweep("normalised_arcs", threshold=10.0)
    assert np.all(k10.counts <= k5.counts)
    assert np.all(k5.counts <= k5.reachable)
    assert np.all(k5.counts > 0)        # the boundary singularities cannot be removed (paper sec. 5)


def test_max_inscribed_circle_of_the_tied_pair():
    """r_MIC = min(a1, a2): 9 cm for (9, 14, 3), 10 cm for (10, 15, 3), so the paper keeps the latter."""
    radii = {}
    for design in (TIE, OPT):
        a1, a2, a3 = design
        mech = FiveBar(proximal=a1, distal=a2, half_base=a3)
        y_mic, r_mic = mech.max_inscribed_circle()
        assert r_mic == pytest.approx(min(a1, a2), rel=1e-12)
        assert y_mic == pytest.approx(math.sqrt(max(a1, a2) ** 2 - a3 ** 2), rel=1e-12)
        phi = np.linspace(0, 2 * np.pi, 721)
        ring = np.stack([np.cos(phi), np.sin(phi)], -1)
        _, inside = mech.inverse(np.array([0.0, y_mic]) + 0.999 * r_mic * ring)
        assert inside.all()                               # inscribed ...
        away = np.array([a3, y_mic]) / math.hypot(a3, y_mic)
        _, beyond = mech.inverse(np.array([0.0, y_mic]) + 1.001 * r_mic * away)
        assert not beyond.any()                           # ... and tangent to the outer boundary
        radii[_cm(design)] = r_mic
    assert radii[(10, 15, 3)] > radii[(9, 14, 3)]
