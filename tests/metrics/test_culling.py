"""Culling search = brute force, exactly: value, design, tie-breaking and the top-K list, on
hundreds of random problems (ties, infeasible samples under both semantics, all-infeasible
designs, D = 1, S = 1, the GII ratio form), on split design spaces merged, and on a real
five-bar. Also: every (design, sample) pair is evaluated at most once, and smooth problems
need a small fraction of brute force's evaluations. Headless, numpy only, fixed seeds.
"""
from __future__ import annotations

import numpy as np
import pytest

from kinematics import FiveBar
from metrics.design import culling
from metrics.design.culling import brute_force, culling_search, merge_top_k
from metrics.design.evaluator_adapters import elementwise, per_design, table
from metrics.quantities import evaluate


class Recorder:
    """Wraps an evaluator; records every (design, sample) pair and fails on a repeat."""

    def __init__(self, inner, designs=None):
        self.inner = inner
        self.pairs: set[tuple[int, int]] = set()
        self.allowed = None if designs is None else set(np.asarray(designs).tolist())

    def __call__(self, designs, samples):
        assert designs.dtype == np.int64 and samples.dtype == np.int64
        assert designs.ndim == samples.ndim == 1 and designs.size and samples.size
        for d in designs.tolist():
            if self.allowed is not None:
                assert d in self.allowed, f"design {d} outside this worker's subset"
            for s in samples.tolist():
                assert (d, s) not in self.pairs, f"pair ({d}, {s}) evaluated twice"
                self.pairs.add((d, s))
        return self.inner(designs, samples)


def random_problem(rng):
    """A random (D, S) table problem with the knobs the tests vary, and search options."""
    D = int(rng.choice([1, 2, 3, 4, 7, 12, 25, 60]))
    S = int(rng.choice([1, 2, 3, 5, 9, 17, 40]))
    form = str(rng.choice(culling.FORMS))
    infeasible = str(rng.choice(culling.INFEASIBLE))
    kind = str(rng.choice(["normal", "few", "smooth"]))
    if kind == "few":        # few distinct integer values: ties everywhere
        a = rng.integers(0, int(rng.choice([1, 2, 3])) + 1, (D, S)).astype(float)
        b = rng.integers(0, 3, (D, S)).astype(float)
    elif kind == "smooth":
        p = rng.uniform(0, 1, (D, 2))
        x = rng.uniform(0, 1, (S, 2))
        a = 1.5 + np.sin(3 * p[:, None, 0] + 2 * x[None, :, 0]) * np.cos(2 * p[:, None, 1] * x[None, :, 1])
        b = 1.0 + (p[:, None, 0] - x[None, :, 1]) ** 2
    else:
        a = rng.normal(size=(D, S))
        b = np.abs(rng.normal(size=(D, S)))
    if form == "ratio":
        a = np.abs(a)
        if rng.random() < 0.2:
            b[rng.random((D, S)) < 0.1] = np.inf         # singular poses: ratio 0
        if rng.random() < 0.2:
            a[rng.random((D, S)) < 0.1] = np.inf
    elif rng.random() < 0.2:
        a[rng.random((D, S)) < 0.1] = np.inf              # +inf is an ordinary value
    rate = float(rng.choice([0.0, 0.0, 0.05, 0.3]))
    holes = rng.random((D, S)) < rate
    marker = np.nan if rng.random() < 0.7 else -np.inf
    a[holes & (rng.random((D, S)) < 0.5)] = marker
    (b if form == "ratio" else a)[holes] = marker
    if rng.random() < 0.3:                               # whole designs infeasible everywhere
        a[rng.random(D) < 0.3] = np.nan
    ev = table(a, b) if form == "ratio" else table(a)
    options = dict(form=form, infeasible=infeasible,
                   top_k=int(rng.choice([1, 1, 2, 3, 5, D, D + 2])))
    extra = dict(n_initial=int(rng.integers(1, 5)), n_new=int(rng.integers(1, 4)),
                 first_chunk=int(rng.choice([1, 2, 4, 32])))
    if rng.random() < 0.3:
        extra["initial_samples"] = rng.choice(S, size=int(rng.integers(1, S + 1)), replace=False)
    return ev, D, S, options, extra


def assert_same(got, want):
    assert got.value == want.value or (np.isnan(got.value) and np.isnan(want.value))
    assert got.design == want.design
    np.testing.assert_array_equal(got.top_designs, want.top_designs)
    np.testing.assert_array_equal(got.top_values, want.top_values)   # bit-for-bit, -inf too


@pytest.mark.parametrize("block", range(8))
def test_culling_equals_brute_force_on_random_problems(block):
    rng = np.random.default_rng(1000 + block)
    for _ in range(60):                     # 8 x 60 = 480 problems
        ev, D, S, options, extra = random_problem(rng)
        want = brute_force(ev, D, S, **options)
        rec = Recorder(ev)
        got = culling_search(rec, D, S, **options, **extra)
        assert_same(got, want)
        assert got.evaluations == len(rec.pairs) <= want.evaluations == D * S
        assert len(got.top_designs) == min(options["top_k"], D)
        assert not np.isnan(got.top_values).any()


def test_brute_force_known_values_and_tie_rule():
    f = np.array([[3.0, 1.0, 2.0],      # F = 1
                  [2.0, 5.0, 2.0],      # F = 2
                  [4.0, 2.0, 9.0],      # F = 2 (ties with 1: larger id ranks after)
                  [0.0, 7.0, 7.0]])     # F = 0
    for method in (brute_force, culling_search):
        r = method(table(f), 4, 3, top_k=4)
        assert (r.value, r.design) == (2.0, 1)
        np.testing.assert_array_equal(r.top_designs, [1, 2, 0, 3])
        np.testing.assert_array_equal(r.top_values, [2.0, 2.0, 1.0, 0.0])
        value, design, evaluations, seconds = r
        assert (value, design) == (2.0, 1) and evaluations <= 12 and seconds >= 0.0
    assert brute_force(table(f), 4, 3).evaluations == 12
    flat = np.ones((6, 4))
    for method in (brute_force, culling_search):
        r = method(table(flat), 6, 4, top_k=3)
        np.testing.assert_array_equal(r.top_designs, [0, 1, 2])


def test_infeasible_semantics_by_hand():
    f = np.array([[5.0, np.nan, 4.0],    # fail: -inf; skip: 4
                  [3.0, 3.5, 6.0],       # 3 either way
                  [np.nan, -np.inf, np.nan]])   # infeasible everywhere: -inf either way
    for method in (brute_force, culling_search):
        fail = method(table(f), 3, 3, infeasible="fail", top_k=3)
        np.testing.assert_array_equal(fail.top_designs, [1, 0, 2])
        np.testing.assert_array_equal(fail.top_values, [3.0, -np.inf, -np.inf])
        skip = method(table(f), 3, 3, infeasible="skip", top_k=3)
        np.testing.assert_array_equal(skip.top_designs, [0, 1, 2])
        np.testing.assert_array_equal(skip.top_values, [4.0, 3.0, -np.inf])
        dead = method(table(np.full((4, 3), np.nan)), 4, 3, infeasible="skip", top_k=2)
        assert (dead.value, dead.design) == (-np.inf, 0)
        np.testing.assert_array_equal(dead.top_designs, [0, 1])


def test_ratio_form_by_hand_and_conventions():
    # F = min a / max b, numerator and denominator at different samples (paper 001 eq. 11)
    a = np.array([[2.0, 1.0, 3.0], [4.0, 4.0, 2.0], [1.0, 1.0, 1.0]])
    b = np.array([[2.0, 4.0, 1.0], [3.0, 8.0, 1.0], [1.0, 1.0, 1.0]])
    for method in (brute_force, culling_search):
        r = method(table(a, b), 3, 3, form="ratio", top_k=3)
        np.testing.assert_array_equal(r.top_designs, [2, 0, 1])
        np.testing.assert_array_equal(r.top_values, [1.0, 0.25, 0.25])
    # conventions: 0 / 0 = 0, A > 0 with B = 0 is inf, B = inf is 0
    a = np.array([[0.0, 0.0], [1.0, 2.0], [5.0, 5.0], [np.inf, np.inf]])
    b = np.array([[0.0, 0.0], [0.0, 0.0], [1.0, np.inf], [np.inf, 1.0]])
    for method in (brute_force, culling_search):
        r = method(table(a, b), 4, 2, form="ratio", top_k=4)
        np.testing.assert_array_equal(r.top_designs, [1, 0, 2, 3])
        np.testing.assert_array_equal(r.top_values, [np.inf, 0.0, 0.0, 0.0])


@pytest.mark.parametrize("form", culling.FORMS)
@pytest.mark.parametrize("infeasible", culling.INFEASIBLE)
def test_single_design_and_single_sample(form, infeasible):
    rng = np.random.default_rng(7)
    for D, S in ((1, 1), (1, 30), (30, 1)):
        for _ in range(10):
            a = np.abs(rng.normal(size=(D, S)))
            b = np.abs(rng.normal(size=(D, S)))
            a[rng.random((D, S)) < 0.2] = np.nan
            ev = table(a, b) if form == "ratio" else table(a)
            for k in (1, 3):
                want = brute_force(ev, D, S, form=form, infeasible=infeasible, top_k=k)
                got = culling_search(Recorder(ev), D, S, form=form, infeasible=infeasible, top_k=k)
                assert_same(got, want)


def smooth_grid_problem(n_design=30, n_sample=30):
    """Designs on a 2-D grid x samples on a 2-D grid; smooth f with an interior optimum."""
    g = np.linspace(0.0, 1.0, n_design)
    p = np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2)
    h = np.linspace(0.0, 1.0, n_sample)
    x = np.stack(np.meshgrid(h, h, indexing="ij"), -1).reshape(-1, 2)

    def f(d, s):
        pd, xs = p[d], x[s]
        return (1.0 + np.cos(2.0 * pd[..., 0] * xs[..., 0]) * (1.2 - pd[..., 1])
                - (pd[..., 0] - 0.6) ** 2 - 0.5 * (pd[..., 1] - 0.4) ** 2 * xs[..., 1])
    return elementwise(f), len(p), len(x)


@pytest.mark.parametrize("top_k", [1, 10])
def test_smooth_problem_needs_few_evaluations(top_k):
    ev, D, S = smooth_grid_problem()
    want = brute_force(ev, D, S, top_k=top_k)
    got = culling_search(ev, D, S, top_k=top_k)
    assert_same(got, want)
    assert want.evaluations == D * S == 900 * 900
    assert got.evaluations < 0.03 * want.evaluations, got.evaluation_fraction
    # the ratio form on the same grid: a = f shifted positive, b = a smooth positive field
    ev_b = elementwise(lambda d, s: 1.0 + 0.3 * np.sin(3.0 * d / D + 5.0 * s / S))

    def ratio(d, s):
        return ev(d, s) + 1.0, ev_b(d, s)
    want = brute_force(ratio, D, S, form="ratio", top_k=top_k)
    got = culling_search(ratio, D, S, form="ratio", top_k=top_k)
    assert_same(got, want)
    assert got.evaluations < 0.05 * want.evaluations, got.evaluation_fraction


def test_split_across_workers_merges_to_the_global_top_k():
    rng = np.random.default_rng(42)
    for _ in range(150):
        ev, D, S, options, extra = random_problem(rng)
        want = brute_force(ev, D, S, **options)
        parts = int(rng.integers(1, min(D, 5) + 1))
        labels = rng.integers(0, parts, D)               # random, non-contiguous subsets
        chunks = [np.flatnonzero(labels == w) for w in range(parts)]
        chunks = [c for c in chunks if c.size]
        results = [culling_search(Recorder(ev, c), c, S, **options, **extra) for c in chunks]
        merged = merge_top_k(results, options["top_k"])
        assert_same(merged, want)
        for c, r in zip(chunks, results):     # each part is its subset's exact top K
            assert_same(r, brute_force(ev, c, S, **options))
        # chunks run in turn, each culling against the merged K-th best so far
        done = []
        for c in chunks:
            floor = merge_top_k(done, options["top_k"]).kth if done else None
            if floor is not None and len(merge_top_k(done, options["top_k"]).top_designs) < options["top_k"]:
                floor = None                  # fewer than K in hand: no K-th best yet
            done.append(culling_search(Recorder(ev, c), c, S, floor=floor, **options, **extra))
        assert_same(merge_top_k(done, options["top_k"]), want)
        assert sum(r.evaluations for r in done) <= D * S


def test_probes_seed_a_related_run():
    ev, D, S = smooth_grid_problem(20, 20)
    first = culling_search(ev, D, S)
    assert first.probes.size >= 1
    again = culling_search(ev, D, S, initial_samples=first.probes)
    assert_same(again, brute_force(ev, D, S))


def test_adapters_agree():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(9, 11))
    b = np.abs(rng.normal(size=(9, 11)))
    d, s = np.array([4, 0, 7]), np.array([10, 2])
    np.testing.assert_array_equal(per_design(lambda i, ss: a[i, ss])(d, s), a[np.ix_(d, s)])
    np.testing.assert_array_equal(elementwise(lambda i, ss: a[i, ss])(d, s), a[np.ix_(d, s)])
    pa, pb = per_design(lambda i, ss: (np.abs(a[i, ss]), b[i, ss]))(d, s)
    np.testing.assert_array_equal(pa, np.abs(a[np.ix_(d, s)]))
    np.testing.assert_array_equal(pb, b[np.ix_(d, s)])
    got = culling_search(per_design(lambda i, ss: a[i, ss]), 9, 11, top_k=3)
    assert_same(got, brute_force(table(a), 9, 11, top_k=3))


def test_misuse_raises_naming_the_argument():
    ev = table(np.ones((3, 4)))
    with pytest.raises(ValueError, match="form"):
        brute_force(ev, 3, 4, form="max")
    with pytest.raises(ValueError, match="infeasible"):
        culling_search(ev, 3, 4, infeasible="drop")
    with pytest.raises(ValueError, match="top_k"):
        culling_search(ev, 3, 4, top_k=0)
    with pytest.raises(ValueError, match="designs"):
        culling_search(ev, np.array([1, 1]), 4)
    with pytest.raises(ValueError, match="samples"):
        brute_force(ev, 3, 0)
    with pytest.raises(ValueError, match="initial_samples"):
        culling_search(ev, 3, 4, initial_samples=[9])
    with pytest.raises(ValueError, match=r"shape \(1, 4\)"):
        culling_search(lambda d, s: np.ones(3), 3, 4)
    with pytest.raises(ValueError, match="pair"):
        culling_search(ev, 3, 4, form="ratio")
    with pytest.raises(ValueError, match="a = -1.0 < 0 for design 2, sample 1"):
        brute_force(table(np.array([[1.0, 1], [1, 1], [1, -1]]), np.ones((3, 2))), 3, 2, form="ratio")
    with pytest.raises(ValueError, match="floor"):
        culling_search(ev, 3, 4, floor=(np.nan, 0))
    with pytest.raises(ValueError, match="n_new"):
        culling_search(ev, 3, 4, n_new=0)
    with pytest.raises(ValueError, match="disjoint"):
        r = brute_force(ev, 3, 4)
        merge_top_k([r, r])


def fivebar_problem(ratio: bool):
    """27 five-bars (a1, a2, a3 on a 3^3 grid) x points of a disc: a small real study."""
    grid = [(a1, a2, a3) for a1 in (0.08, 0.10, 0.12) for a2 in (0.11, 0.13, 0.15)
            for a3 in (0.03, 0.04, 0.05)]
    mechs = [FiveBar(proximal=a1, distal=a2, half_base=a3) for a1, a2, a3 in grid]
    h = np.linspace(-0.05, 0.05, 9)
    pts = np.stack(np.meshgrid(h, h + 0.16, indexing="ij"), -1).reshape(-1, 2)
    pts = pts[np.hypot(pts[:, 0], pts[:, 1] - 0.16) <= 0.05]

    def f(d, s):
        if ratio:
            sv = evaluate(mechs[d], pts[s], ["singular_values"]).values["singular_values"]
            return sv[:, -1], sv[:, 0]
        return evaluate(mechs[d], pts[s], ["isotropic_force"]).values["isotropic_force"]
    return per_design(f), len(mechs), len(pts)


@pytest.mark.parametrize("ratio", [False, True])
@pytest.mark.parametrize("infeasible", culling.INFEASIBLE)
def test_real_fivebar_study(ratio, infeasible):
    ev, D, S = fivebar_problem(ratio)
    form = "ratio" if ratio else "min"
    want = brute_force(ev, D, S, form=form, infeasible=infeasible, top_k=5)
    got = culling_search(ev, D, S, form=form, infeasible=infeasible, top_k=5)
    assert_same(got, want)
    assert np.isfinite(want.value) and want.value > 0
    assert got.evaluations < want.evaluations


def test_probes_in_groups_cull_before_the_later_probes():
    """With a floor, probes go in groups of 1, 2, 4, ... and designs culled by the first groups
    are never evaluated on the later ones: fewer than D x (probes) evaluations in the probe
    phase, the same top K as brute force, and no pair twice."""
    rng = np.random.default_rng(21)
    D, S = 400, 60
    p = rng.uniform(0, 1, (D, 2))
    x = rng.uniform(0, 1, (S, 2))
    f = 1.5 + np.sin(3 * p[:, None, 0] + 2 * x[None, :, 0]) * np.cos(2 * p[:, None, 1] * x[None, :, 1])
    ref = brute_force(table(f), D, S, top_k=1)
    worst = np.argsort(f[ref.design])[:8]                  # the optimum's 8 worst samples as probes
    floor = (float(np.sort(f.min(axis=1))[-3]), 0)         # the 3rd best value: most designs rank after it
    rec = Recorder(table(f))
    res = culling_search(rec, D, S, top_k=1, initial_samples=worst, floor=floor)
    assert res.design == ref.design and res.value == ref.value
    probe_pairs = sum(1 for d, s in rec.pairs if s in set(worst.tolist()))
    assert probe_pairs < D * worst.size // 2               # all-at-once probing would evaluate D x 8
