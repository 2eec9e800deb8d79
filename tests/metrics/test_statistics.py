"""Streamed statistics, singular points, unbounded suprema and the GCI (issue 7, sections 3 and 6).

References are independent: sorting for order statistics, numpy two-pass mean/SD on the
whole array, brute-force masks from the mechanism's own singularity classes.
"""
from __future__ import annotations

import math
import tracemalloc

import numpy as np
import pytest

from kinematics.fivebar import Singularity
from kinematics.grid import GridSpec
from metrics.quantities import STATS_QUANTITIES
from metrics.statistics import QUANTILE_REL_ERROR, QUANTILES, StatsAccumulator, chunk_partial, quantile_rank
from metrics.workspace import compute_map
from resources import load_preset

EPS = np.finfo(float).eps


def _order_statistic(values: np.ndarray, q) -> float:
    """The inverted-CDF quantile by sorting, with the exact rational rank."""
    return float(np.sort(values)[quantile_rank(q, values.size) - 1])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_accumulator_equals_whole_array_figures_in_any_chunk_order(seed):
    rng = np.random.default_rng(seed)
    n = 50_001
    v = rng.lognormal(0.0, 2.0, n) * np.where(rng.random(n) < 0.3, -1.0, 1.0)
    regular = rng.random(n) < 0.9
    singular = ~regular & (rng.random(n) < 0.5)
    index = np.arange(n)
    chunks = np.array_split(rng.permutation(n), 9)
    acc = StatsAccumulator()
    for c in chunks:
        acc.merge(chunk_partial(v[c], regular[c], singular[c], index[c], histogram=True))
    ref = v[regular]
    assert acc.count == ref.size
    assert acc.singular == int(singular.sum())
    assert acc.min == ref.min() and acc.max == ref.max()          # exact: extremes are selections
    assert v[acc.argmin] == ref.min() and v[acc.argmax] == ref.max()
    # Pairwise mean/M2 merging: error a few eps per merge times the spread; 1e3 eps is ample.
    spread = float(np.max(np.abs(ref)))
    assert abs(acc.mean - ref.mean()) <= 1e3 * EPS * spread
    assert abs(acc.sd - ref.std(ddof=1)) <= 1e3 * EPS * spread
    quants = acc.quantiles()
    for name, q in QUANTILES.items():
        exact = _order_statistic(ref, q)
        assert abs(quants[name] - exact) <= QUANTILE_REL_ERROR * abs(exact), name


def test_quantile_histogram_is_exact_where_values_are_few():
    # Integers below 2^16 are bin edges: every bin holds one value, so the quantile is that value.
    v = np.arange(1.0, 101.0)
    acc = StatsAccumulator()
    acc.merge(chunk_partial(v, np.ones(100, bool), np.zeros(100, bool), np.arange(100), histogram=True))
    q = acc.quantiles()
    assert q == {"p05": 5.0, "median": 50.0, "p95": 95.0}


def _fivebar():
    return load_preset("fivebar_singh")


def test_fivebar_double_singularity_is_counted_not_averaged_and_the_max_is_unbounded():
    preset = _fivebar()
    mech = preset.mechanism
    wmap = compute_map(mech, preset.grid, STATS_QUANTITIES)
    # Independent: the mechanism's own classes at the feasible points.
    classes = wmap.values.get("singularity")
    assert classes is None                               # not requested, not returned
    q = wmap.values["isotropic_force"]
    singular = wmap.singular
    assert singular.sum() == wmap.singular_points > 0
    assert not np.any(singular & ~wmap.feasible)
    # (0, 40) mm, both legs folded, is a grid node: it is singular, and out of every figure.
    node = np.unravel_index(np.argmin(np.hypot(*(wmap.points - [0.0, 0.040]).transpose(2, 0, 1))), q.shape)
    assert singular[node]
    regular = wmap.feasible & ~singular
    iso = wmap.stats["isotropic_force"]
    assert iso.count == int(np.count_nonzero(regular & np.isfinite(q)))
    assert iso.mean == pytest.approx(np.mean(q[regular]), rel=1e-12)
    assert iso.mean < 11.0                               # was 11,290 N with the rounding-noise node
    # Unbounded: the five-bar reaches its folded-folded point; the stats say so and where.
    assert iso.unbounded and math.isinf(iso.max)
    assert any(np.allclose(p, (0.0, 0.040), atol=1e-6) or np.allclose(p, (0.0, 0.2482), atol=1e-4)
               for p in iso.unbounded_at)
    assert wmap.stats["condition_number"].unbounded
    assert wmap.stats["anisotropic_force"].unbounded
    assert not wmap.stats["inverse_condition_number"].unbounded
    assert wmap.errors["isotropic_force"]["max"] != wmap.errors["isotropic_force"]["max"]   # nan: no estimate


def test_inverse3_has_no_unbounded_figure_and_table3_maxima_stay():
    preset = load_preset("inverse3_prototype")
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution(200), STATS_QUANTITIES)
    for name, s in wmap.stats.items():
        assert not s.unbounded, name
        assert math.isfinite(s.max), name
    assert wmap.singular_points == 0


def test_gci_is_the_mean_of_inverse_condition_over_feasible_points_and_bounded():
    for key in ("fivebar_singh", "inverse3_prototype"):
        preset = load_preset(key)
        wmap = compute_map(preset.mechanism, preset.grid.with_resolution(150), STATS_QUANTITIES)
        kappa = wmap.values["condition_number"][wmap.feasible]
        inv = np.where(np.isinf(kappa) | wmap.singular[wmap.feasible], 0.0, 1.0 / kappa)
        assert wmap.gci == pytest.approx(np.mean(inv), rel=1e-12)
        assert 0.0 <= wmap.gci <= 1.0


def test_streamed_statistics_equal_the_kept_map_and_hold_no_map():
    preset = _fivebar()
    grid = preset.grid.with_resolution(301)
    kept = compute_map(preset.mechanism, grid, STATS_QUANTITIES)
    streamed = compute_map(preset.mechanism, grid, STATS_QUANTITIES, keep=False)
    assert streamed.values == {} and streamed.feasible is None
    assert streamed.feasible_points == kept.feasible_points
    for name, s in kept.stats.items():
        t = streamed.stats[name]
        assert (t.count, t.singular_points, t.unbounded) == (s.count, s.singular_points, s.unbounded)
        assert (t.min, t.max, t.argmin, t.argmax) == (s.min, s.max, s.argmin, s.argmax)
        assert t.mean == pytest.approx(s.mean, rel=1e-12)
        for f in QUANTILES:
            assert abs(getattr(t, f) - getattr(s, f)) <= QUANTILE_REL_ERROR * abs(getattr(s, f)), (name, f)
    assert streamed.gci == pytest.approx(kept.gci, rel=1e-12)


def _peak_bytes(preset, resolution: int) -> int:
    tracemalloc.start()
    try:
        compute_map(preset.mechanism, preset.grid.with_resolution(resolution), STATS_QUANTITIES, keep=False)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_streamed_statistics_do_not_hold_the_map():
    # A kept map of this grid holds four float64 arrays and two masks; streamed statistics hold
    # a few chunks and histograms bounded by the binades the values span (metrics.statistics).
    preset = load_preset("inverse3_prototype")
    n = 2000
    kept_bytes = n * n * (len(STATS_QUANTITIES) * 8 + 2)
    assert _peak_bytes(preset, n) < 0.5 * kept_bytes


def test_fivebar_mean_and_median_are_grid_stable_between_1000_and_1001():
    preset = _fivebar()
    a = compute_map(preset.mechanism, preset.grid.with_resolution(1000), STATS_QUANTITIES, keep=False)
    b = compute_map(preset.mechanism, preset.grid.with_resolution(1001), STATS_QUANTITIES, keep=False)
    for name in ("isotropic_force", "condition_number"):
        for fig in ("mean", "median"):
            change = abs(getattr(a.stats[name], fig) - getattr(b.stats[name], fig))
            assert change < max(a.errors[name][fig], b.errors[name][fig]), (name, fig)


def test_singular_classes_at_the_located_points_are_singular():
    preset = _fivebar()
    mech = preset.mechanism
    wmap = compute_map(mech, preset.grid, ("isotropic_force",), keep=False)
    s = wmap.stats["isotropic_force"]
    pts = np.array(s.singular_at)
    q, ok = mech.inverse(pts)
    assert ok.all()
    assert np.all(mech.singularity(q, pts) != Singularity.NONE)


@pytest.mark.parametrize("magnitude", [1e-300, 1e-150, 1.0, 1e150, 1e300])
def test_mean_and_sd_hold_over_the_whole_float_range(magnitude):
    # Squares of 1e-300 underflow and of 1e300 overflow: the accumulator works in a power-of-two
    # scale of the spread, so SD = magnitude * SD(unit values) up to rounding.
    rng = np.random.default_rng(3)
    unit = 1.0 + rng.random(10_001)
    v = unit * magnitude
    acc = StatsAccumulator()
    for c in np.array_split(np.arange(v.size), 5):
        acc.merge(chunk_partial(v[c], np.ones(c.size, bool), np.zeros(c.size, bool), c, histogram=False))
    assert acc.sd == pytest.approx(unit.std(ddof=1) * magnitude, rel=1e-12)
    assert acc.mean == pytest.approx(unit.mean() * magnitude, rel=1e-12)


def test_a_minimum_reached_at_a_stretched_leg_is_the_value_there():
    """The five-bar's isotropic force is finite at an inverse singularity (a leg stretched: one
    column of J is left) and tends to its value there with the square root of the distance.
    Its infimum is the value at the singular node (-220, 0) mm, 5.263 N; the regular nodes
    alone gave 5.60 +- 0.24 N, which does not hold it. Reference: the quantity on a line of
    points approaching the node from inside, 1 um apart, evaluated independently of the map."""
    preset = _fivebar()
    mech = preset.mechanism
    wmap = compute_map(mech, preset.grid, ["isotropic_force"])
    iso = wmap.stats["isotropic_force"]
    x = np.linspace(-0.220, -0.21999, 11)
    line = compute_map(mech, GridSpec(("x", "y"), (x[0], 0.0), (x[-1], 1e-9), (11, 2)), ["isotropic_force"])
    approach = line.values["isotropic_force"][:, 0]
    assert line.singular[0, 0] and not line.singular[1:, 0].any()
    assert np.all(np.diff(approach) > 0)                                  # falls towards the node
    assert approach[0] == iso.min and np.allclose(iso.argmin, (-0.220, 0.0), atol=1e-12)
    assert approach[1] - approach[0] < 0.05 * (iso.min - 0.0)               # within 5 % 1 um inside: no jump
    # The singular nodes stay out of the mean: it is the regular nodes' mean.
    regular = wmap.feasible & ~wmap.singular
    assert iso.mean == pytest.approx(np.mean(wmap.values["isotropic_force"][regular]), rel=1e-12)


def test_a_grid_node_classed_inverse_makes_the_condition_number_unbounded():
    """The Inoue platform has no singular loci of its own; its default grid meets an inverse
    singularity (condition number 1e8 at a node). The condition number's supremum is then
    infinite, not the regular nodes' largest value (34 +- 4 before), and 1 / kappa's infimum 0."""
    preset = load_preset("inoue_platform")
    wmap = compute_map(preset.mechanism, preset.grid, ["condition_number", "inverse_condition_number", "singularity"])
    classes = wmap.values["singularity"]
    inverse = wmap.feasible & (classes == preset.mechanism.singularity_classes.index("inverse"))
    assert inverse.any()
    assert np.all(wmap.values["condition_number"][inverse] > 1e7)
    cond = wmap.stats["condition_number"]
    assert cond.unbounded and math.isinf(cond.max)
    assert any(np.allclose(p, q) for p in cond.unbounded_at for q in wmap.points[inverse])
    assert wmap.stats["inverse_condition_number"].vanishes and wmap.stats["inverse_condition_number"].min == 0.0


def test_the_inoue_platforms_anisotropic_force_stays_bounded_at_an_inverse_node():
    """A device with orientation freedoms reports the anisotropic force at zero moment, a slice
    of its wrench set that stays bounded next to an inverse singularity (the unbounded direction
    has a moment part). Reference: the quantity at 0.1 um, 0.5 mm and 1 mm from the inverse
    node along x, finite, the nearest within 0.1 % of the node's own value; the map's maximum
    is then a grid figure, not "unbounded" (as the grid node classed inverse made it)."""
    preset = load_preset("inoue_platform")
    mech = preset.mechanism
    wmap = compute_map(mech, preset.grid, ["anisotropic_force", "singularity"])
    inverse = wmap.feasible & (wmap.values["singularity"] == mech.singularity_classes.index("inverse"))
    node = wmap.points[inverse][0]
    aniso = wmap.stats["anisotropic_force"]
    assert not aniso.unbounded and math.isfinite(aniso.max)
    ix, iz = (wmap.task_names.index(a) for a in preset.grid.axes)           # the map's axes: x and z
    x = [node[ix] + d for d in (1e-3, 1e-7)]
    line = compute_map(mech, GridSpec(preset.grid.axes, (min(x), node[iz]), (max(x), node[iz] + 1e-12), (3, 2),
                                      preset.grid.fixed), ["anisotropic_force"])
    approach = line.values["anisotropic_force"][:, 0]
    value = wmap.values["anisotropic_force"][inverse][0]
    assert np.all(np.isfinite(approach)) and abs(approach[0] - value) < 1e-3 * value
    assert value <= aniso.max


@pytest.mark.parametrize("span", [50, 1 << 40])
def test_merged_histogram_tables_sum_counts_and_keep_extremes_per_key(span):
    """``_merged`` against a dictionary built entry by entry: keys from a narrow span (the dense path)
    and from a span far wider than the entries (the sorted path), tables of any length, empty ones too."""
    from metrics.statistics import _merged

    rng = np.random.default_rng(3)
    tables, want = [], {}
    for size in (0, 1, 7, 40, 3, 25):
        keys = np.unique(rng.integers(0, span, size).astype(np.uint64))
        counts = rng.integers(1, 9, keys.size).astype(np.int64)
        lows = rng.normal(size=keys.size)
        highs = lows + rng.random(keys.size)
        tables.append((keys, counts, lows, highs))
        for k, c, lo, hi in zip(keys.tolist(), counts.tolist(), lows.tolist(), highs.tolist()):
            n, a, b = want.get(k, (0, math.inf, -math.inf))
            want[k] = (n + c, min(a, lo), max(b, hi))
    keys, counts, lows, highs = _merged(tables)
    assert keys.dtype == np.uint64 and counts.dtype == np.int64
    assert keys.tolist() == sorted(want)
    assert [(n, a, b) for n, a, b in zip(counts.tolist(), lows.tolist(), highs.tolist())] == [want[k] for k in
                                                                                               sorted(want)]
