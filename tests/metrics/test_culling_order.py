"""Culling's sort helpers against the stable-argsort formulation they replace, bit for bit.

``_argsort_ties_by`` (an unstable sort whose runs of equal values are re-sorted), and
``_first_in_order`` (a partition, then a sort of the few candidates) must give exactly the
order ``np.argsort(kind="stable")`` gives, so that culling picks the same probes and takes
samples in the same order (same evaluation counts, on any CPU). ``_Problem.badness`` must give
the keys of its former two stable argsorts. Random keys drawn from a few values (many ties),
with nan, +-inf, -0.0 and 0.0, and infeasible samples under both rules. Headless, fixed seeds.
"""
from __future__ import annotations

import numpy as np
import pytest

from metrics.design import culling
from metrics.design.ranking import VETO


def tied_keys(rng, n):
    """``n`` floats from a small pool: ties everywhere, nan, +-inf, signed zeros, VETO."""
    pool = np.array([0.0, -0.0, 1.0, 2.5, -3.0, np.inf, -np.inf, np.nan, VETO, 1e-300, 7.0])
    pool = pool[rng.permutation(pool.size)[: rng.integers(1, pool.size + 1)]]
    x = pool[rng.integers(0, pool.size, n)]
    if rng.random() < 0.3:                          # some distinct values among the ties
        x = np.where(rng.random(n) < 0.5, rng.normal(size=n), x)
    return x


SIZES = [0, 1, 2, 3, 5, 17, 64, 1000, 20_000]


@pytest.mark.parametrize("n", SIZES)
def test_argsort_ties_by_index_is_the_stable_argsort(n):
    rng = np.random.default_rng(n)
    for _ in range(40 if n < 1000 else 5):
        x = tied_keys(rng, n)
        assert np.array_equal(culling._argsort_ties_by(x), np.argsort(x, kind="stable"))
        ints = rng.integers(-3, 4, n)
        assert np.array_equal(culling._argsort_ties_by(ints), np.argsort(ints, kind="stable"))
        # few ties among distinct values (below the stable-sort fallback's eighth)
        few = np.where(rng.random(n) < 0.04, x, rng.normal(size=n))
        assert np.array_equal(culling._argsort_ties_by(few), np.argsort(few, kind="stable"))


@pytest.mark.parametrize("n", SIZES)
def test_argsort_ties_by_tie_breaker(n):
    """Ties by ``tie``: the stable argsort of the keys taken in ``tie`` order."""
    rng = np.random.default_rng(100 + n)
    for _ in range(40 if n < 1000 else 5):
        x = tied_keys(rng, n)
        tie = rng.choice(3 * n + 1, n, replace=False).astype(np.int64)   # distinct, not 0..n-1
        by_tie = np.argsort(tie, kind="stable")
        expected = by_tie[np.argsort(x[by_tie], kind="stable")]
        assert np.array_equal(culling._argsort_ties_by(x, tie), expected)


@pytest.mark.parametrize("n", SIZES)
def test_first_in_order_is_the_stable_order_filtered(n):
    rng = np.random.default_rng(200 + n)
    for _ in range(40 if n < 1000 else 5):
        key = tied_keys(rng, n)
        mask = rng.random(n) < rng.choice([0.0, 0.1, 0.5, 1.0])
        order = np.argsort(key, kind="stable")
        for count in (1, 2, 3, 10, n + 5):
            expected = order[mask[order]][:count]
            assert np.array_equal(culling._first_in_order(key, mask, count), expected), (count, key, mask)


def old_badness(prob, a, b, infeas):
    """``_Problem.badness`` as it was: two stable argsorts for the ranks."""
    if b is None:
        key = a.copy()
    else:
        ra = np.empty(a.size)
        rb = np.empty(a.size)
        ra[np.argsort(np.where(infeas, np.inf, a), kind="stable")] = np.arange(a.size)
        rb[np.argsort(-np.where(infeas, 0.0, b), kind="stable")] = np.arange(a.size)
        key = np.minimum(ra, rb)
    key[infeas] = -np.inf if prob.fail else np.inf
    return key


@pytest.mark.parametrize("form", ["min", "ratio"])
@pytest.mark.parametrize("infeasible", ["fail", "skip"])
def test_badness_and_orders_as_before(form, infeasible):
    """Keys, the probe pick and the full sample order (``order_key``'s stable argsort) of the
    former formulation, on tied values with infeasible samples."""
    rng = np.random.default_rng(7 if form == "min" else 8)
    prob = culling._Problem(lambda d, s: None, 4, 1, form, infeasible, 1)
    for n in (1, 2, 9, 300, 5000):
        for _ in range(20 if n < 1000 else 4):
            levels = rng.integers(1, 6)
            a = rng.integers(0, levels, n) * 0.5
            a = np.where(rng.random(n) < 0.1, -0.0, a)
            a = np.where(rng.random(n) < 0.05, np.inf, a)
            if form == "min":
                a = np.where(rng.random(n) < 0.05, VETO, a)
            b = rng.integers(0, levels, n) * 0.25 if form == "ratio" else None
            infeas = rng.random(n) < rng.choice([0.0, 0.2, 0.9])
            a = np.where(infeas & (rng.random(n) < 0.5), np.nan, np.where(infeas, -np.inf, a))
            key = prob.badness(a, b, infeas)
            ref = old_badness(prob, a, b, infeas)
            assert np.array_equal(key, ref)
            # the probe pick: first `count` helpful samples in (key, place) order
            helps = rng.random(n) < 0.5
            order = np.argsort(ref, kind="stable")
            for count in (1, 2, 32):
                assert np.array_equal(culling._first_in_order(key, helps, count), order[helps[order]][:count])
            # the sample order after an exact design: its samples scattered among S positions
            S = n + rng.integers(0, 50)
            spos = rng.permutation(S)[:n]
            order_key = np.full(S, np.inf)
            order_key[spos] = ref
            assert np.array_equal(culling._argsort_ties_by(order_key), np.argsort(order_key, kind="stable"))


def test_ids_checks_still_name_the_repeat():
    with pytest.raises(ValueError, match="must not repeat an id, got 4 ids of which 3 distinct"):
        culling._ids("designs", np.array([3, 1, 3, 2]), "designs")
    r = culling._ids("samples", 5, "samples")
    assert np.array_equal(r, np.arange(5)) and not r.flags.writeable


def test_initial_samples_outside_a_range_of_samples():
    f = np.arange(12.0).reshape(3, 4)
    for bad in (4, -1):
        with pytest.raises(ValueError, match=f"initial_samples must be ids among samples, got {bad}"):
            culling.culling_search(lambda d, s: f[np.ix_(d, s)], 3, 4, initial_samples=[0, bad])
