"""Studies with the apparent mass: the ``max_apparent_mass`` bound and the
``min_force_per_apparent_mass`` objective, checked against ``metrics.quantities.evaluate``
design by design (brute force), and the searches' VETO against brute force on tables."""
from __future__ import annotations

import numpy as np
import pytest

from metrics.design import brute_force, build_study, culling_search, evaluator_for, run_study
from metrics.design.count import count_brute_force, count_search
from metrics.design.evaluator_adapters import table
from metrics.design.ranking import VETO
from metrics.quantities import evaluate
from resources.study_schema import StudyError, parse_study_text

INVERSE3 = """
name = "mass bound"
[mechanism]
preset = "inverse3_prototype"
[grid]
gear_ratios.theta_0 = {{ min = 4.0, max = 20.0, step = 1.0 }}
[workspace]
kind = "grid"
axes = ["x", "z"]
lower = [100.0, 100.0]
upper = [250.0, 300.0]
resolution = [7, 9]
fixed = {{ y = 22.3 }}
[objective]
kind = "{kind}"
infeasible = "fail"
{bound}
top_k = 3
"""

# Link lengths: not a rotor-only grid, so the mass comes from one model per design.
FIVEBAR = """
name = "five-bar mass bound"
[mechanism]
preset = "fivebar_singh"
[grid]
proximal = [60.0, 80.0, 100.0]
distal = [130.0, 150.0]
[workspace]
kind = "grid"
axes = ["x", "y"]
lower = [-30.0, 120.0]
upper = [30.0, 160.0]
resolution = [5, 4]
[objective]
kind = "{kind}"
infeasible = "skip"
{bound}
top_k = 2
"""


def study(text: str, kind: str = "min_isotropic_force", bound: float | None = None):
    line = "" if bound is None else f"max_apparent_mass = {bound!r}"
    return build_study(parse_study_text(text.format(kind=kind, bound=line), "t.toml", "t"))


def brute(study_, design: int):
    """``evaluate`` on one design's model over the search's samples: force, largest mass, feasible."""
    ev = evaluator_for(study_)
    x = study_.workspace.points[ev.samples]
    out = evaluate(study_.design_mechanism(design), x, ("isotropic_force", "apparent_mass_max"))
    return out.values["isotropic_force"], out.values["apparent_mass_max"], out.feasible


# Tolerance for the rotor-split path against evaluate: both sum the same finite-difference
# kinetic forms (the split adds the rotor pieces in another order), so they differ by rounding
# carried through an m x m inverse and its eigenvalues: about m * eps * kappa, kappa the mass
# condition number (max / min apparent mass, below 10 on these samples). 1e-12 is 100x that.
RTOL = 1e-12


@pytest.mark.parametrize("text", [INVERSE3, FIVEBAR], ids=["rotor-split", "per-design"])
def test_bound_removes_exactly_the_designs_over_it(text):
    probe = study(text, bound=1.0)
    largest = []
    for d in range(probe.n_designs):
        _, mass, feas = brute(probe, d)
        largest.append(mass[feas].max())
    largest = np.array(largest)
    ordered = np.sort(largest)                   # a bound between two designs: some over, some under
    bound = float(np.round(0.5 * (ordered[largest.size // 2 - 1] + ordered[largest.size // 2]), 9))
    assert np.min(np.abs(largest - bound)) > 1e6 * RTOL * bound     # no design on the edge
    s = study(text, bound=bound)
    want_over = largest > bound
    assert 0 < want_over.sum() < s.n_designs
    bf = run_study(s, method="brute_force", top_k=s.n_designs, with_report=False)
    np.testing.assert_array_equal(bf.records["over_bound"], want_over)
    assert bf.over_bound == int(want_over.sum())
    ranked = bf.top_designs
    assert set(ranked[np.isneginf(bf.top_values)]) >= set(np.flatnonzero(want_over))
    np.testing.assert_allclose(bf.top_masses, largest[ranked], rtol=RTOL)
    # culling: the same ranking; the designs it met over the bound are among the true ones
    cu = run_study(s, top_k=3, with_report=False)
    np.testing.assert_array_equal(cu.top_designs, bf.top_designs[:3])
    np.testing.assert_array_equal(cu.top_values, bf.top_values[:3])
    assert not np.any(cu.records["over_bound"] & ~want_over)
    # the feasible designs keep their plain objective value (the bound changes nothing else)
    plain = run_study(study(text), method="brute_force", top_k=s.n_designs, with_report=False)
    keep = ~want_over[plain.top_designs]
    np.testing.assert_array_equal(plain.top_designs[keep], ranked[: keep.sum()])
    np.testing.assert_array_equal(plain.top_values[keep], bf.top_values[: keep.sum()])


@pytest.mark.parametrize("text", [INVERSE3, FIVEBAR], ids=["rotor-split", "per-design"])
def test_force_per_mass_equals_brute_force(text):
    s = study(text, kind="min_force_per_apparent_mass")
    ev = evaluator_for(s)
    for d in (0, s.n_designs // 2, s.n_designs - 1):
        force, mass, feas = brute(s, d)
        want = np.min(force[feas] / mass[feas])
        got = ev(np.array([d]), np.arange(ev.n_samples))[0]
        assert np.all(np.isnan(got) == ~feas)
        # force: TorqueOnly's column norms or the batch kernel against evaluate's (rounding of
        # a norm and a quotient); mass: RTOL above.
        np.testing.assert_allclose(np.nanmin(got), want, rtol=RTOL)
    res = run_study(s, method="culling", with_report=False)
    best = max(range(s.n_designs), key=lambda d: (np.min((lambda f, m, k: f[k] / m[k])(*brute(s, d))), -d))
    assert res.design == best
    assert s.objective.unit == "N/kg"


def test_bound_and_force_per_mass_together():
    s = study(INVERSE3, kind="min_force_per_apparent_mass", bound=0.19)
    res = run_study(s, method="brute_force", top_k=s.n_designs, with_report=False)
    for d, v, m in zip(res.top_designs, res.top_values, res.top_masses):
        force, mass, feas = brute(s, d)
        assert (m > 0.19) == np.isneginf(v)
        if np.isfinite(v):
            np.testing.assert_allclose(v, np.min(force[feas] / mass[feas]), rtol=RTOL)


@pytest.mark.parametrize("form", ["min", "ratio"])
@pytest.mark.parametrize("infeasible", ["fail", "skip"])
def test_veto_in_culling_matches_brute_force(form, infeasible):
    rng = np.random.default_rng(7)
    for _ in range(40):
        D, S = int(rng.integers(3, 30)), int(rng.integers(2, 40))
        a = rng.integers(0, 5, (D, S)).astype(float)
        a[rng.random((D, S)) < 0.05] = np.nan
        a[rng.random((D, S)) < 0.03] = VETO
        b = rng.integers(1, 5, (D, S)).astype(float) if form == "ratio" else None
        ev = table(a, b)
        k = int(rng.integers(1, 4))
        want = brute_force(ev, D, S, form=form, infeasible=infeasible, top_k=k)
        got = culling_search(ev, D, S, form=form, infeasible=infeasible, top_k=k)
        np.testing.assert_array_equal(got.top_designs, want.top_designs)
        np.testing.assert_array_equal(got.top_values, want.top_values)
        vetoed = np.any(a == VETO, axis=1)         # (b is never nan: a's nan is the only infeasible)
        for d, v in zip(want.top_designs, want.top_values):
            dead = infeasible == "fail" and np.isnan(a[d]).any()
            assert v == (-np.inf if dead else VETO) if vetoed[d] else v == -np.inf if dead else v > VETO


def test_veto_in_count_matches_brute_force():
    rng = np.random.default_rng(3)
    for _ in range(40):
        D, S = int(rng.integers(3, 30)), int(rng.integers(2, 80))
        c = (rng.random((D, S)) < 0.3).astype(float)
        c[rng.random((D, S)) < 0.02] = np.inf
        want = count_brute_force(table(c), D, S, top_k=3)
        got = count_search(table(c), D, S, top_k=3, first_chunk=4)
        np.testing.assert_array_equal(got.top_designs, want.top_designs)
        np.testing.assert_array_equal(got.top_values, want.top_values)


@pytest.mark.parametrize("change, key, phrase", [
    ('[mechanism]\nkind = "fivebar"\n', "objective.max_apparent_mass", "the mechanism has no mass model"),
    ("max_apparent_mass = -0.1", "objective.max_apparent_mass", "positive"),
    ("max_apparent_mass = true", "objective.max_apparent_mass", "positive"),
])
def test_bad_bounds(change, key, phrase):
    text = FIVEBAR.format(kind="min_isotropic_force", bound="max_apparent_mass = 0.2")
    if change.startswith("[mechanism]"):
        text = text.replace('[mechanism]\npreset = "fivebar_singh"\n', change)
    else:
        text = text.replace("max_apparent_mass = 0.2", change)
    with pytest.raises(StudyError) as err:
        build_study(parse_study_text(text, "bad.toml"))
    msg = str(err.value)
    assert "bad.toml" in msg and f"'{key}'" in msg and phrase in msg and "\n" not in msg


def test_force_per_mass_needs_a_mass_model_and_fixed_points():
    text = FIVEBAR.format(kind="min_force_per_apparent_mass", bound="")
    with pytest.raises(StudyError, match=r"'objective.kind' .*no mass model"):
        build_study(parse_study_text(text.replace('preset = "fivebar_singh"', 'kind = "fivebar"'), "bad.toml"))
    sampling = text.replace('kind = "grid"\naxes = ["x", "y"]\nlower = [-30.0, 120.0]\nupper = [30.0, 160.0]\n'
                            'resolution = [5, 4]', 'kind = "sampling"\nname = "normalised_arcs"')
    with pytest.raises(StudyError, match=r"'objective.kind' .*sampling"):
        build_study(parse_study_text(sampling, "bad.toml"))


def test_shipped_example_study():
    from resources import load_study
    s = build_study(load_study("inverse3_gear_ratio_mass"))
    res = run_study(s)
    assert res.top()[0]["gear_ratios.theta_0"] == pytest.approx(9.36)
    assert res.top_masses[0] <= s.objective.max_apparent_mass < largest_mass_at(s, 9.37)
    assert res.over_bound == 1064


def largest_mass_at(s, g1: float) -> float:
    mech = s.values_mechanism({"gear_ratios.theta_0": g1})
    ev = evaluate(mech, s.workspace.points, ("apparent_mass_max",))
    return float(ev.values["apparent_mass_max"][ev.feasible].max())
