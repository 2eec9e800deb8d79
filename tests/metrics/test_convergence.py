"""Convergence studies and adaptive refinement of a global extreme. Headless: numpy/scipy only.

The Inverse3 slice has an exact global minimum isotropic force: on the theta_0 = 0 slice
(y = plane offset c) the base actuator is the bottleneck near the outer reach, its facet
distance is ``t_0 / hypot(c, x)`` (the base column of J is ``(-c, x, 0)``), so the minimum
sits at the largest feasible x, where the link spread reaches its lower limit:
``x_max = l1 cos h + sqrt(l2^2 - l1^2 sin^2 h)`` with ``h = min_link_spread / 2``, at the
five-bar centre height. Paper 000 reports 2.278 N.
"""
from __future__ import annotations

import gc
import json
import math
import subprocess
import sys
import weakref

import numpy as np
import pytest

from app.logic.convergence_text import format_table
from metrics import convergence
from metrics.convergence import (
    FIGURES,
    convergence_study,
    ladder_resolution,
    refine_global_maximum,
    refine_global_minimum,
    uniform_grid_for,
)
from metrics.quantities import evaluate
from metrics.statistics import QUANTILE_REL_ERROR, QUANTILES
from metrics.workspace import GridSpec, compute_map
from resources import load_preset

INV3 = load_preset("inverse3_prototype")
FIVEBAR = load_preset("fivebar_singh")


def inverse3_exact_minimum(mech) -> tuple[float, np.ndarray]:
    """The analytic global minimum isotropic force of the slice and where it is (m)."""
    p = mech.params
    h = p.min_link_spread / 2.0
    l1, l2 = p.proximal_length, p.distal_length
    x_max = l1 * math.cos(h) + math.sqrt(l2 * l2 - (l1 * math.sin(h)) ** 2)
    t0 = mech.torque_limits()[0]
    return t0 / math.hypot(p.plane_offset, x_max), np.array([x_max, p.plane_offset, p.base_height])


INV3_MIN, INV3_ARGMIN = inverse3_exact_minimum(INV3.mechanism)


# -- the analytic reference itself ----------------------------------------------------------
def test_analytic_inverse3_minimum_matches_evaluate_and_the_paper():
    inside = INV3_ARGMIN - np.array([1e-12, 0.0, 0.0])
    outside = INV3_ARGMIN + np.array([1e-9, 0.0, 0.0])
    ev = evaluate(INV3.mechanism, np.stack([inside, outside]), ("isotropic_force", "bottleneck"))
    assert ev.feasible.tolist() == [True, False]          # x_max is the edge of the feasible set
    assert ev.values["bottleneck"][0] == 0                  # theta_0 limits isotropy there
    assert ev.values["isotropic_force"][0] == pytest.approx(INV3_MIN, rel=1e-10)
    # Paper 000 (Table 3) reports 2.278 N from a 1000 x 1000 grid; a grid minimum can only
    # lie above the true one, here by 0.7 mN.
    assert 0.0 < 2.278 - INV3_MIN < 1e-3


# -- ladder ---------------------------------------------------------------------------------
def test_ladder_keeps_the_presets_aspect():
    assert ladder_resolution(INV3.grid, 50) == (50, 50)             # preset 1000 x 1000
    assert ladder_resolution(FIVEBAR.grid, 100) == (100, 50)        # preset 521 x 261
    assert ladder_resolution(FIVEBAR.grid, 2) == (2, 2)             # never below 2
    with pytest.raises(ValueError, match=r"integer number of points >= 2, got 1"):
        ladder_resolution(INV3.grid, 1)


# -- the study ------------------------------------------------------------------------------
LADDER = (25, 50, 100, 200, 400, 800)


@pytest.fixture(scope="module")
def inv3_study():
    return convergence_study(INV3.mechanism, INV3.grid, resolutions=LADDER, exact_rtol=1e-4, exact_budget=200_000)


def test_rows_are_the_ladder_with_the_finest_as_reference(inv3_study):
    st = inv3_study
    assert [r.resolution for r in st.rows] == [(n, n) for n in LADDER]
    assert st.reference is st.rows[-1] and st.reference.is_reference
    assert [r.is_reference for r in st.rows].count(True) == 1
    for r in st.rows:
        assert r.points == r.resolution[0] * r.resolution[1]
        assert 0 < r.feasible_points < r.points
        assert r.seconds > 0


def test_figures_are_the_maps_statistics():
    res = ladder_resolution(INV3.grid, 50)
    st = convergence_study(INV3.mechanism, INV3.grid, resolutions=(50, 60), exact_rtol=None)
    # The study streams its statistics (keep=False): the same accumulators as a kept map, so
    # min, max, mean and SD are the same numbers; quantiles come from the histogram, within
    # its bin of the kept map's exact order statistics.
    wmap = compute_map(INV3.mechanism, INV3.grid.with_resolution(res), st.quantities)
    row = st.rows[0]
    assert row.feasible_points == wmap.feasible_points
    for q in st.quantities:
        s = wmap.stats[q]
        assert {f: row.figures[q][f] for f in ("min", "max", "mean", "sd")} == \
            {"min": s.min, "max": s.max, "mean": s.mean, "sd": s.sd}
        for f in QUANTILES:
            assert abs(row.figures[q][f] - getattr(s, f)) <= QUANTILE_REL_ERROR * abs(getattr(s, f))


def test_errors_are_exactly_the_difference_from_the_reference_figure(inv3_study):
    ref = inv3_study.reference.figures
    for r in inv3_study.rows:
        for q in inv3_study.quantities:
            for f in FIGURES:
                diff = abs(r.figures[q][f] - ref[q][f])
                assert r.abs_errors[q][f] == diff
                assert r.rel_errors[q][f] == diff / abs(ref[q][f])
                if r.is_reference:
                    assert diff == 0.0


def test_exact_errors_are_the_difference_from_the_refined_extremes(inv3_study):
    st = inv3_study
    ex = st.exact["isotropic_force"]["min"]
    assert ex.status == "certified" and ex.usable
    assert abs(ex.value - INV3_MIN) <= ex.tol                     # the analytic truth
    for r in st.rows:
        assert r.exact_errors["isotropic_force"]["min"] == abs(r.figures["isotropic_force"]["min"] - ex.value)
        # a grid point lies in the domain: no rung may beat the true minimum
        assert r.figures["isotropic_force"]["min"] >= INV3_MIN
    # not usable -> no exact error reported
    for q, figs in st.exact.items():
        for f, e in figs.items():
            if not e.usable:
                assert all(f not in r.exact_errors[q] for r in st.rows)


def test_errors_decrease_overall_but_extremes_are_not_monotone(inv3_study):
    st = inv3_study
    rungs = [r for r in st.rows if not r.is_reference]
    for q in st.quantities:
        for f in FIGURES:
            errs = [r.abs_errors[q][f] for r in rungs]
            # Overall: the finest rung beats the coarsest, and the log-log fit falls.
            assert errs[-1] < errs[0], (q, f, errs)
            assert st.rates[q][f] > 0.3, (q, f, st.rates[q][f])
    # What is also true: the minimum isotropic force is not monotone in the resolution. It
    # is attained on the feasible boundary (the link-spread limit), so its error is how close
    # some node happens to fall to that point; 50 x 50 is luckier than 100 x 100.
    errs = [r.exact_errors["isotropic_force"]["min"] for r in st.rows]
    assert any(b > a for a, b in zip(errs, errs[1:]))
    # It is bounded by slope x spacing: |df/dx| <= t0 / x^2 at the minimum, plus the
    # boundary's curvature over half a z step (R = x_max).
    t0, x_max = INV3.mechanism.torque_limits()[0], INV3_ARGMIN[0]
    for r in st.rows:
        hx, hz = INV3.grid.with_resolution(r.resolution).spacing()
        assert r.exact_errors["isotropic_force"]["min"] <= t0 / x_max ** 2 * (hx + hz ** 2 / (8 * x_max)) * 1.05


def test_json_round_trip_is_strict(inv3_study):
    d = inv3_study.to_dict()
    text = json.dumps(d, allow_nan=False)
    assert json.loads(text) == d
    assert d["reference"]["resolution"] == [800, 800]
    assert [r["resolution"] for r in d["rows"]] == [[n, n] for n in LADDER]
    row = d["rows"][0]["quantities"]["isotropic_force"]["min"]
    assert set(row) == {"value", "abs_error", "rel_error", "exact_error"}


def test_non_finite_figures_become_null_in_json():
    # The five-bar's condition number is infinite on its reach boundary: a fine enough
    # ladder on its 1 mm grid lands nodes on it; the refinement reaches it too.
    st = convergence_study(FIVEBAR.mechanism, FIVEBAR.grid, ("condition_number",), (27, 521),
                           exact_rtol=1e-3, exact_budget=50_000)
    assert math.isinf(st.reference.figures["condition_number"]["max"])
    assert st.exact["condition_number"]["max"].status == "attained"
    d = st.to_dict()
    json.dumps(d, allow_nan=False)
    assert d["reference"]["quantities"]["condition_number"]["max"]["value"] is None
    assert d["exact"]["condition_number"]["max"]["value"] is None


def test_format_table_lists_every_rung_and_quantity(inv3_study):
    text = format_table(inv3_study)
    for n in LADDER:
        assert f"{n} x {n}" in text
    for q in inv3_study.quantities:
        assert q in text
    assert "(ref)" in text and "min-exact" in text and "rate p" in text


def test_separate_reference_resolution():
    st = convergence_study(INV3.mechanism, INV3.grid, ("isotropic_force",), (20, 40), reference_resolution=80,
                           exact_rtol=None)
    assert [r.resolution for r in st.rows] == [(20, 20), (40, 40)]
    assert st.reference.resolution == (80, 80) and not any(r.is_reference for r in st.rows)
    with pytest.raises(ValueError, match="reference_resolution must exceed every rung"):
        convergence_study(INV3.mechanism, INV3.grid, resolutions=(20, 40), reference_resolution=40)


def test_the_study_keeps_one_map_alive_at_a_time(monkeypatch):
    alive: list[weakref.ref] = []
    real = convergence.compute_map

    def tracked(*args, **kwargs):
        gc.collect()
        assert all(ref() is None for ref in alive), "a previous rung's map is still alive"
        wmap = real(*args, **kwargs)
        alive.append(weakref.ref(wmap))
        return wmap

    monkeypatch.setattr(convergence, "compute_map", tracked)
    convergence_study(INV3.mechanism, INV3.grid, resolutions=(20, 40, 80), exact_rtol=None)
    gc.collect()
    assert len(alive) == 3 and all(ref() is None for ref in alive)



def test_the_reference_runs_first_and_the_searches_beside_the_rungs_are_the_searches_run_alone(monkeypatch):
    """The exact searches run on worker threads beside the coarser rungs (``_Searches``): each is
    the very search run alone on this thread with the same tolerance, budget and coarse grid (value,
    point, bound, evaluations, levels, history), and the reference map ran before any rung."""
    sizes = []
    real = convergence.compute_map

    def recorded(mech, grid, *args, **kwargs):
        sizes.append(tuple(grid.resolution))
        return real(mech, grid, *args, **kwargs)

    monkeypatch.setattr(convergence, "compute_map", recorded)
    quantities = ("condition_number", "isotropic_force", "inverse_condition_number")
    st = convergence_study(INV3.mechanism, INV3.grid, quantities, (20, 40, 80), exact_rtol=1e-4,
                           exact_budget=40_000, coarse_resolution=16)
    assert sizes == [(80, 80), (20, 20), (40, 40)]
    assert [r.resolution for r in st.rows] == [(20, 20), (40, 40), (80, 80)] and st.rows[-1].is_reference
    searched = 0
    for q in quantities:
        for f, e in st.exact[q].items():
            r = e.refinement
            if r is None or r.evaluations == 0:       # attained, or read off its source
                continue
            refine = refine_global_minimum if f == "min" else refine_global_maximum
            alone = refine(INV3.mechanism, INV3.grid, q, tol=r.tol, coarse_resolution=16, max_evaluations=40_000)
            for name in ("value", "point", "bound", "tol", "certified", "evaluations", "levels", "coarse_resolution",
                         "finest_spacing"):
                assert getattr(alone, name) == getattr(r, name), (q, f, name)
            assert [h[:3] for h in alone.history] == [h[:3] for h in r.history]
            searched += 1
    assert searched == 4          # the condition number's and the isotropic force's min and max

@pytest.mark.parametrize("kwargs, pattern", [
    (dict(quantities=("bottleneck",)), r"quantity 'bottleneck' has no global min/max/mean/SD"),
    (dict(quantities=("nonsense",)), r"unknown quantity 'nonsense'"),
    (dict(resolutions=(50,)), r"at least two rungs"),
    (dict(resolutions=(50, 1)), r"integer number of points >= 2, got 1"),
    (dict(exact_rtol=-1.0), r"exact_rtol must be a positive finite number, got -1.0"),
])
def test_study_validation_names_the_argument(kwargs, pattern):
    args = dict(quantities=("isotropic_force",), resolutions=(20, 40), exact_rtol=None)
    args.update(kwargs)
    with pytest.raises(ValueError, match=pattern):
        convergence_study(INV3.mechanism, INV3.grid, **args)


# -- refinement -----------------------------------------------------------------------------
@pytest.mark.parametrize("tol", [1e-2, 1e-3, 1e-4, 1e-5])
def test_refined_inverse3_minimum_is_within_tol_of_the_exact_value(tol):
    r = refine_global_minimum(INV3.mechanism, INV3.grid, tol=tol)
    assert r.certified and r.sense == "min" and r.quantity == "isotropic_force"
    assert INV3_MIN <= r.value <= INV3_MIN + tol
    assert r.bound <= INV3_MIN
    # the value is attained where it says
    ev = evaluate(INV3.mechanism, np.array([r.point]), ("isotropic_force",))
    assert ev.feasible[0] and ev.values["isotropic_force"][0] == r.value
    assert np.linalg.norm(np.array(r.point) - INV3_ARGMIN) < 0.01


def test_refinement_beats_the_uniform_grid_that_meets_the_same_tol():
    tol = 3e-3
    st = convergence_study(INV3.mechanism, INV3.grid, ("isotropic_force",), (100, 200, 500, 1000), exact_rtol=None)
    u = uniform_grid_for(st, "isotropic_force", exact=INV3_MIN, tol=tol)
    assert not u.extrapolated and u.resolution == (1000, 1000) and u.points == 1_000_000
    # the rung before it misses the tolerance: it is really the first that meets it for good
    assert abs(st.rows[-2].figures["isotropic_force"]["min"] - INV3_MIN) > tol
    r = refine_global_minimum(INV3.mechanism, INV3.grid, tol=tol)
    assert r.certified and r.value - INV3_MIN <= tol
    assert r.evaluations * 20 < u.points


def test_uniform_grid_for_reports_lucky_rungs_and_extrapolates():
    st = convergence_study(INV3.mechanism, INV3.grid, ("isotropic_force",), (50, 100, 200), exact_rtol=None)
    errs = [abs(r.figures["isotropic_force"]["min"] - INV3_MIN) for r in st.rows]
    tol = 1e-3
    assert errs[0] <= tol < min(errs[1:])           # 50 x 50 happens to hit near the minimum
    u = uniform_grid_for(st, "isotropic_force", exact=INV3_MIN, tol=tol)
    assert u.extrapolated and u.lucky == ((50, 50),)
    assert u.points > 200 * 200 and u.finest_error == errs[-1]
    assert 0.25 <= u.rate <= 2.0


def _brute_force_fivebar_minimum() -> float:
    """Isotropic force minimum by brute force: the preset's 1 mm grid (which holds the two
    corners where the reach circles meet y = 0) and 0.5 um grids around those corners."""
    mech = FIVEBAR.mechanism
    best = compute_map(mech, FIVEBAR.grid, ("isotropic_force",)).stats["isotropic_force"].min
    for sign in (-1.0, 1.0):
        xs = sign * np.linspace(0.2195, 0.22, 1001)
        ys = np.linspace(0.0, 0.0005, 1001)
        pts = np.stack(np.meshgrid(xs, ys, indexing="ij"), axis=-1)
        ev = evaluate(mech, pts, ("isotropic_force",))
        best = min(best, float(np.min(ev.values["isotropic_force"][ev.feasible])))
    return best


def test_refined_fivebar_minimum_agrees_with_brute_force():
    # The five-bar's isotropic force goes like sqrt(distance) into its reach boundary (an
    # inverse singularity): unbounded slope, the case the Hoelder bound of boundary cells is for.
    brute = _brute_force_fivebar_minimum()
    assert brute == pytest.approx(1 / 0.19, rel=1e-12)   # leg fully stretched at (+-220, 0) mm
    tol = 1e-2
    r = refine_global_minimum(FIVEBAR.mechanism, FIVEBAR.grid, tol=tol)
    assert r.certified
    assert r.bound <= brute <= r.value + 1e-12 + tol and r.value <= brute + tol
    assert r.value >= brute - 1e-9          # brute force reaches the true minimum here
    # fewer evaluations than a uniform rung that still misses the tolerance by far
    res = ladder_resolution(FIVEBAR.grid, 1000)
    wmap_min = compute_map(FIVEBAR.mechanism, FIVEBAR.grid.with_resolution(res),
                           ("isotropic_force",)).stats["isotropic_force"].min
    assert wmap_min - brute > 5 * tol
    assert r.evaluations < res[0] * res[1]


def test_refined_maximum_and_3d_volume():
    # A small 3D box around the slice: the refined maximum is at least every grid value and
    # within tol of the best of a denser grid; the refined minimum at most every grid value.
    c = INV3.mechanism.params.plane_offset
    box = GridSpec(("x", "y", "z"), (0.10, c - 0.05, 0.10), (0.25, c + 0.05, 0.30), (9, 9, 9))
    tol = 1e-3
    hi = refine_global_maximum(INV3.mechanism, box, "isotropic_force", tol=tol, coarse_resolution=9)
    lo = refine_global_minimum(INV3.mechanism, box, "isotropic_force", tol=tol, coarse_resolution=9)
    dense = compute_map(INV3.mechanism, box.with_resolution(41), ("isotropic_force",)).stats["isotropic_force"]
    assert hi.sense == "max" and hi.certified and lo.certified
    assert dense.max <= hi.value + tol and hi.bound >= dense.max
    assert dense.min >= lo.value - tol and lo.bound <= dense.min
    assert len(hi.point) == 3


def test_the_inverse_condition_number_is_one_over_the_condition_number_at_every_point():
    # What reading its extremes off the condition number's rests on (``convergence.RECIPROCALS``):
    # 1.0 / cn exactly, compiled and numpy, feasible points and singular ones alike.
    from metrics.kernels import use_compiled
    for key in ("inverse3_prototype", "fivebar_singh"):
        preset = load_preset(key)
        pts = preset.grid.with_resolution(tuple(min(n, 60) for n in preset.grid.resolution)).points(
            preset.mechanism.task_names).reshape(-1, preset.mechanism.task_dim)
        for compiled in (True, False):
            with use_compiled(compiled):
                ev = evaluate(preset.mechanism, pts, ("condition_number", "inverse_condition_number"))
            cn, icn = ev.values["condition_number"], ev.values["inverse_condition_number"]
            assert ev.feasible.any()
            np.testing.assert_array_equal(icn, 1.0 / cn)
    for q, source in convergence.RECIPROCALS.items():
        assert source in convergence.QUANTITIES[q].needs


def test_reciprocal_extremes_are_read_off_the_source_and_agree_with_their_own_refinement(monkeypatch):
    searched = []
    for name in ("refine_global_minimum", "refine_global_maximum"):
        real = getattr(convergence, name)
        monkeypatch.setattr(convergence, name,
                            lambda *a, real=real, name=name, **k: searched.append((a[2], name)) or real(*a, **k))
    rtol = 1e-4
    # The reciprocal first: its extremes wait for the source's all the same.
    st = convergence_study(INV3.mechanism, INV3.grid, ("inverse_condition_number", "condition_number"), (40, 80),
                           exact_rtol=rtol, exact_budget=200_000)
    assert sorted(searched) == [("condition_number", "refine_global_maximum"),
                                ("condition_number", "refine_global_minimum")]
    assert list(st.exact) == ["inverse_condition_number", "condition_number"]
    for f, g in (("min", "max"), ("max", "min")):
        derived, source = st.exact["inverse_condition_number"][f], st.exact["condition_number"][g]
        r = derived.refinement
        assert r.sense == f and r.quantity == "inverse_condition_number" and r.evaluations == 0
        assert r.value == 1.0 / source.value and r.point == source.refinement.point
        assert r.tol == rtol * abs(st.reference.figures["inverse_condition_number"][f])
        assert "1 / condition_number's " + g in derived.note
        if source.status == "certified":
            assert derived.status == "certified" and abs(r.bound - r.value) <= r.tol
    # Where the condition number's min is certified, the reciprocal's max found on its own agrees
    # within the two tolerances (each is within its tol of the one true maximum).
    derived = st.exact["inverse_condition_number"]["max"]
    assert derived.status == "certified"
    own = refine_global_maximum(INV3.mechanism, INV3.grid, "inverse_condition_number", tol=derived.tol,
                                coarse_resolution=64, max_evaluations=200_000)
    assert own.certified
    assert abs(own.value - derived.value) <= own.tol + derived.tol


def test_a_reciprocal_is_refined_on_its_own_without_its_source_or_a_tight_enough_one():
    src = convergence.Refinement("condition_number", "min", 2.0, (0.1, 0.2), 1.9, 0.1, True, 100, 0.0, 3,
                                 (64, 64), (1e-3, 1e-3))
    # [1/2, 1/1.9] is 0.026 wide: certified for a tol of 0.03, not for 0.01 (then None: refine it).
    assert convergence.reciprocal_refinement(src, "inverse_condition_number", 0.03).certified
    assert convergence.reciprocal_refinement(src, "inverse_condition_number", 0.01) is None
    assert convergence.reciprocal_refinement(src, "isotropic_force", 0.03) is None
    loose = convergence.Refinement("condition_number", "min", 2.0, (0.1, 0.2), 1.0, 0.1, False, 100, 0.0, 3,
                                   (64, 64), (1e-3, 1e-3))
    d = convergence.reciprocal_refinement(loose, "inverse_condition_number", 0.01)
    assert not d.certified and (d.value, d.bound, d.sense) == (0.5, 1.0, "max")
    st = convergence_study(INV3.mechanism, INV3.grid, ("inverse_condition_number",), (40, 80), exact_rtol=1e-3,
                           exact_budget=50_000)
    assert all(e.refinement.evaluations > 0 for e in st.exact["inverse_condition_number"].values())


def test_refinement_budget_gives_an_honest_uncertified_answer():
    r = refine_global_minimum(INV3.mechanism, INV3.grid, tol=1e-9, max_evaluations=6000)
    assert not r.certified and r.evaluations <= 6000
    assert r.bound <= INV3_MIN <= r.value


@pytest.mark.parametrize("kwargs, pattern", [
    (dict(tol=0.0), r"tol must be a positive finite number, got 0.0"),
    (dict(tol=float("nan")), r"tol must be a positive finite number"),
    (dict(tol=1e-3, quantity="bottleneck"), r"'bottleneck' has no global"),
    (dict(tol=1e-3, max_evaluations=0), r"max_evaluations must be a positive integer"),
    (dict(tol=1e-3, coarse_resolution=1), r"integer number of points >= 2"),
])
def test_refinement_validation(kwargs, pattern):
    with pytest.raises(ValueError, match=pattern):
        refine_global_minimum(INV3.mechanism, INV3.grid, **kwargs)


def test_refinement_json_is_strict():
    r = refine_global_minimum(INV3.mechanism, INV3.grid, tol=1e-2)
    d = r.to_dict()
    assert json.loads(json.dumps(d, allow_nan=False)) == d
    assert d["evaluations"] == r.evaluations and d["history"][0]["level"] == 0


def test_convergence_module_imports_no_gui_or_plotting():
    code = ("import sys, metrics.convergence; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('matplotlib', 'PySide6', 'pyvista', 'vtk')]; "
            "print(bad); sys.exit(1 if bad else 0)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr


@pytest.mark.parametrize("shape", [(63, 63), (1, 5), (5, 1), (1, 1), (7, 9, 11), (2, 2, 2)])
def test_the_block_maximum_is_the_largest_value_of_each_3_by_3_neighbourhood(shape):
    """The coarse cells' slope estimates: each entry's largest neighbour within one step per axis
    (edges clipped, as scipy's mode="nearest" repeats them), against a loop over every entry."""
    from metrics.refine import _block_max

    rng = np.random.default_rng(7)
    a = rng.random(shape)
    a[a < 0.3] = 0.0                   # ties, as slopes of 0 where a block has no feasible pair
    expected = np.empty_like(a)
    for at in np.ndindex(*shape):
        block = tuple(slice(max(i - 1, 0), i + 2) for i in at)
        expected[at] = a[block].max()
    assert np.array_equal(_block_max(a), expected)


@pytest.mark.parametrize("sizes", [(9, 7), (5, 6, 4), (3 * 2 ** 40, 5), (2 ** 40, 2 ** 23)])
def test_the_refinement_s_unique_nodes_are_numpy_s_unique_rows(sizes):
    """The dedup of a level's new nodes: numpy's own ``unique(axis=0)`` rows (sorted) and an
    inverse that rebuilds every node, with repeats and runs of ascending keys as blocks give."""
    from metrics.refine import _unique_rows

    rng = np.random.default_rng(3)
    rows = np.stack([rng.integers(0, min(n, 6), 400) for n in sizes], axis=1)
    rows[100:200] = np.sort(rows[100:200], axis=0)          # an ascending run
    uniq, inverse = _unique_rows(rows, list(sizes))
    expected = np.unique(rows, axis=0)
    assert np.array_equal(uniq, expected)
    assert np.array_equal(uniq[inverse], rows)


@pytest.mark.parametrize("d, top", [(2, 63 * 2 ** 15 + 1), (3, 11 * 2 ** 12 + 1), (2, 2 ** 40)])
def test_the_refinement_s_new_nodes_are_the_unique_rows_of_the_nodes_made(d, top):
    """A level's new nodes from their cells' keys (``_new_nodes``): the very ``_unique_rows`` of the
    nodes ``2 lo + offset`` made one by one (sorted rows, the inverse laid out cell by offset), in 2D
    and 3D, neighbouring cells sharing nodes, and past the one-key range (2^40 per axis in 2D)."""
    from metrics.refine import _Blocks, _new_nodes, _unique_rows

    rng = np.random.default_rng(11)
    sizes = [top] * d
    new = _Blocks(d).new
    corner = rng.integers(0, (top - 1) // 2 - 8, d)
    lo = corner + rng.integers(0, 6, (300, d))             # a cluster: many cells share edges and faces
    lo = np.concatenate([lo, lo[:40]])                     # and repeated cells
    uniq, inverse = _new_nodes(lo, new, sizes)
    made = (2 * lo[:, None, :] + new[None, :, :]).reshape(-1, d)
    want_uniq, want_inverse = _unique_rows(made, sizes)
    assert np.array_equal(uniq, want_uniq)
    assert np.array_equal(inverse, want_inverse.reshape(len(lo), len(new)))
    assert np.array_equal(uniq[inverse].reshape(-1, d), made)
    # The budget's early look (``_Blocks.fewest_new``) never counts more nodes than the distinct ones.
    blocks = _Blocks(d)
    assert blocks.fewest_new(len(np.unique(lo, axis=0))) <= len(uniq)


@pytest.mark.parametrize("d", [2, 3])
def test_the_fewest_new_nodes_bound_the_distinct_new_nodes_and_meet_them_on_a_large_block(d):
    """``_Blocks.fewest_new``: at most the distinct new nodes of any set of distinct cells, brute force
    (a single cell, a line of cells, a random scatter), and their count to within the block's surface
    on an m^d block of cells (each node inside shared by all the cells around it)."""
    from metrics.refine import _Blocks

    blocks = _Blocks(d)
    rng = np.random.default_rng(5)
    line = np.zeros((7, d), np.int64)
    line[:, 0] = np.arange(7)
    m = 12
    block = np.stack(np.meshgrid(*[np.arange(m)] * d, indexing="ij"), axis=-1).reshape(-1, d)
    for cells in (np.zeros((1, d), np.int64), line, np.unique(rng.integers(0, 9, (60, d)), axis=0), block):
        made = (2 * cells[:, None, :] + blocks.new[None, :, :]).reshape(-1, d)
        distinct = len(np.unique(made, axis=0))
        assert blocks.fewest_new(len(cells)) <= distinct
    # The block: (2m + 1)^d nodes at the finer level less its (m + 1)^d corner nodes, against the bound.
    assert distinct == (2 * m + 1) ** d - (m + 1) ** d
    assert blocks.fewest_new(len(block)) >= distinct - d * 2 * (2 * m + 1) ** (d - 1)


def test_the_refinement_s_task_points_are_its_coordinates_placed_by_task_points():
    """Lattice nodes to task points in place: bit for bit ``task_points`` of ``coords`` (the
    plain formula), fixed coordinate and clipping at the box's upper corner included."""
    from metrics.refine import _Lattice, task_points

    grid = INV3.grid
    lat = _Lattice(INV3.mechanism, grid, "isotropic_force", 1.0, grid.with_resolution((64, 64)))
    rng = np.random.default_rng(5)
    for level in (0, 3, 17):
        top = (lat.n0 - 1) * 2 ** level
        idx = np.concatenate([rng.integers(0, top + 1, (500, 2)), top[None, :]])   # the upper corner too
        expected = task_points(grid, tuple(INV3.mechanism.task_names), lat.coords(idx, level))
        assert np.array_equal(lat.task_points(idx, level), expected)
