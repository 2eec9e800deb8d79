"""The compiled chunk statistics (``kernels.chunk_partials``) are ``statistics.chunk_partial``'s, bit for bit.

References, both independent of the kernels:

- ``statistics.chunk_partial`` (numpy) on each sub-grid's points, picked by ``np.unravel_index``:
  counts, extremes and their places, the singular points and the histogram are exact figures, so
  they must be equal bit for bit;
- the mean and the scaled squared deviations are sums, whose last bits depend on the order and the
  method: ``chunk_partial`` sums pairwise (``np.mean``), the kernels with Neumaier's compensation in
  chunk order (``metrics.kernels.partials``). Those are checked bit for bit against that method
  written out in Python floats (``_neumaier``), and within ``chunk_partial``'s rounding bound in
  ``test_kernels.test_compiled_partials_equal_chunk_partial``.

The chunks mix everything a map hands over: NaN and infinite values, signed zeros, singular points
with and without a finite limit (``bounded``), values over more binades than the dense histogram
holds, and points in grid order or not.
"""
from __future__ import annotations

import math
import threading

import numpy as np
import pytest

from metrics import kernels, statistics
from metrics.kernels import partials

GRIDS = ((1, 0), (2, 0), (2, 1), (4, 0), (4, 2))


def _neumaier(values) -> float:
    """Neumaier's compensated sum of ``values`` in order, in Python floats (IEEE-754 double)."""
    total = comp = 0.0
    for v in values:
        t = total + v
        comp += (total - t) + v if abs(total) >= abs(v) else (v - t) + total
        total = t
    return total + comp


def _sums(values: np.ndarray) -> tuple[float, float, float]:
    """``(mean, m2, scale)`` of the regular finite ``values`` (in chunk order) by the kernels' method."""
    x = [float(v) for v in values]
    if not x:
        return 0.0, 0.0, 0.0
    mean = _neumaier(x) / len(x)
    spread = max(max(x) - mean, mean - min(x))
    scale = math.ldexp(1.0, math.frexp(spread)[1]) if spread > 0.0 else 0.0
    if scale == 0.0:
        return mean, 0.0, 0.0
    return mean, _neumaier(((v - mean) / scale) * ((v - mean) / scale) for v in x), scale


def _taking_turns(work, takers: set[int]):
    """``work``, noting the threads that call it; the first to call waits until a second thread calls too.

    Either thread may come first: the helper may take every item before the caller takes one.
    """
    second = threading.Event()

    def wrapped(*args):
        takers.add(threading.get_ident())
        if len(takers) == 1:
            second.wait(60)
        else:
            second.set()
        return work(*args)
    return wrapped


def _bits(x) -> bytes:
    return np.asarray(x, np.float64).tobytes()


def _chunk(rng, shape, k, *, magnitude, sort):
    """A random chunk: ``(values, regular, singular, bounded, index)``, with every kind of point."""
    index = rng.choice(math.prod(shape), k, replace=False)
    index = np.sort(index) if sort else index
    regular = rng.random(k) < 0.85
    singular = ~regular & (rng.random(k) < 0.6)
    bounded = singular & (rng.random(k) < 0.5)
    narrow = magnitude * (1.0 + rng.random(k))
    # ~90 binades: wider than the dense histogram's 16, so binned by sorting instead.
    wide = magnitude * np.exp(rng.normal(0.0, 30.0 if magnitude == 1.0 else 0.5, k)) * rng.choice([-1.0, 1.0], k)
    signed = magnitude * rng.normal(0.0, 1.0, k)
    signed[rng.random(k) < 0.05] = 0.0
    signed[rng.random(k) < 0.05] = -0.0
    for v in (narrow, wide, signed):
        v[rng.random(k) < 0.03] = np.nan
        v[rng.random(k) < 0.03] = np.inf
        v[rng.random(k) < 0.02] = -np.inf
    # A quantity with equal values (no spread: scale 0) and one with ties at its extremes.
    flat = np.full(k, magnitude)
    ties = magnitude * rng.integers(0, 3, k).astype(float)
    ties[(ties == 0.0) & (rng.random(k) < 0.3)] = -0.0      # zeros of both signs at the minimum
    return [narrow, wide, signed, flat, ties], regular, singular, bounded, index


@pytest.mark.parametrize("magnitude", [1e-300, 1.0, 1e300])
@pytest.mark.parametrize("shape, sort", [((37, 41), True), ((13, 11, 9), True), ((29, 31), False)])
@pytest.mark.parametrize("threads", [False, True])
def test_chunk_partials_are_chunk_partial_bit_for_bit(magnitude, shape, sort, threads, monkeypatch):
    rng = np.random.default_rng(int(magnitude > 1) + 2 * len(shape) + 7 * sort)
    k = min(1000, math.prod(shape) - 1)
    values, regular, singular, bounded, index = _chunk(rng, shape, k, magnitude=magnitude, sort=sort)
    ends = [q % 2 == 0 for q in range(len(values))]
    takers: set[int] = set()
    if threads:         # this small chunk shared all the same, the helper made to take a quantity
        monkeypatch.setattr(partials, "SHARED_MIN", 0)
        monkeypatch.setattr(partials, "quantity", _taking_turns(partials.quantity, takers))
    parts = kernels.chunk_partials(values, regular, singular, bounded, index, shape, (True,) * 4, ends,
                                   histogram=True, threads=threads)
    if threads:
        assert len(takers) == 2
    ijk = np.unravel_index(index, shape)
    for q, v in enumerate(values):
        assert len(parts[q]) == len(GRIDS)
        for (stride, start), part in zip(GRIDS, parts[q]):
            member = np.logical_and.reduce([c % stride == start for c in ijk])
            sub_shape = tuple((n - start + stride - 1) // stride for n in shape)
            at = np.ravel_multi_index(tuple((c[member] - start) // stride for c in ijk), sub_shape)
            ref = statistics.chunk_partial(v[member], regular[member], singular[member], at, histogram=True,
                                           bounded=bounded[member] if ends[q] else None)
            # Ties at an extreme go to the smallest grid index: np.argmin's choice in grid order.
            order = np.argsort(at)
            ordered = statistics.chunk_partial(v[member][order], regular[member][order], singular[member][order],
                                               at[order], histogram=False,
                                               bounded=bounded[member][order] if ends[q] else None)
            assert (part.count, part.argmin, part.argmax, part.singular) == (
                ref.count, ordered.argmin, ordered.argmax, ref.singular)
            assert _bits([part.min, part.max]) == _bits([ordered.min, ordered.max])
            np.testing.assert_array_equal(part.singular_index, ref.singular_index)
            for mine, theirs in zip((part.keys, part.counts, part.lows, part.highs),
                                    (ref.keys, ref.counts, ref.lows, ref.highs)):
                if theirs is None:
                    assert mine is None
                else:
                    assert mine.dtype == theirs.dtype and mine.tobytes() == theirs.tobytes()
            keep = v[member][regular[member] & np.isfinite(v[member])]
            assert _bits([part.mean, part.m2, part.scale]) == _bits(_sums(keep))


def test_missing_sub_grids_and_empty_chunks():
    rng = np.random.default_rng(5)
    shape = (20, 30)
    values, regular, singular, bounded, index = _chunk(rng, shape, 300, magnitude=1.0, sort=True)
    parts = kernels.chunk_partials(values, regular, singular, bounded, index, shape, (True, False, True), [False] * 5,
                                   histogram=False)
    for row in parts:
        assert [p is None for p in row] == [False, False, True, False]
        assert all(p.keys is None for p in row if p is not None)
    empty = np.zeros(0, bool)
    parts = kernels.chunk_partials([np.zeros(0)], empty, empty, empty, np.zeros(0, np.int64), shape, (True,) * 4,
                                   [True], histogram=True)
    for part in parts[0]:
        assert (part.count, part.min, part.max, part.argmin, part.argmax, part.singular) == (
            0, math.inf, -math.inf, -1, -1, 0)
        assert part.keys is None and part.singular_index.size == 0


def test_shared_work_keeps_the_order_uses_both_threads_and_raises():
    takers: set[int] = set()
    assert partials.shared(12, _taking_turns(lambda i: i * i, takers), helper=True) == [i * i for i in range(12)]
    assert len(takers) == 2

    def failing(i):
        if i == 3:
            raise ValueError("item 3")
        return i

    with pytest.raises(ValueError, match="item 3"):
        partials.shared(8, failing, helper=True)
    assert partials.shared(3, failing, helper=False) == [0, 1, 2]


def _grid_values(rng, shape, magnitude):
    """Values over a grid of ``shape`` with what a kept map holds: NaN, infinities, signed zeros, ties, both signs."""
    n = math.prod(shape)
    v = rng.standard_normal(n) * magnitude
    v[rng.random(n) < 0.05] = np.nan
    v[rng.random(n) < 0.02] = np.inf
    v[rng.random(n) < 0.02] = -np.inf
    v[rng.random(n) < 0.03] = 0.0
    v[rng.random(n) < 0.03] = -0.0
    v[rng.random(n) < 0.05] = magnitude      # many equal values: one bucket holds them
    return v.reshape(shape)


@pytest.mark.parametrize("magnitude", [1e-300, 1.0, 1e300])
@pytest.mark.parametrize("shape", [(37, 41), (9, 10, 11), (1, 50), (3, 3)])
@pytest.mark.parametrize("hint", ["extremes", "narrow", "none"])
def test_grid_quantiles_are_exact_quantiles(magnitude, shape, hint):
    """Every grid's quantiles are ``exact_quantiles`` of its regular finite values (picked by slicing), equal in value.

    The buckets' range is only a hint: the map's extremes, a range inside the values (the keys
    outside it fall into the end buckets), or a single value (one bucket holds everything).
    """
    rng = np.random.default_rng(len(shape) * 1000 + int(math.log10(magnitude)))
    v = _grid_values(rng, shape, magnitude)
    regular = rng.random(shape) < 0.8
    finite = v[regular & np.isfinite(v)]
    lo, hi = {"extremes": (finite.min(), finite.max()), "narrow": (-0.1 * magnitude, 0.2 * magnitude),
              "none": (0.0, 0.0)}[hint]
    grids = [all(n > start for n in shape) for _, start in GRIDS]
    got = partials.exact_grid_quantiles(v, regular, grids, lo, hi)
    for (stride, start), take, quants in zip(GRIDS, grids, got):
        if not take:
            assert quants is None
            continue
        sub = tuple(slice(start, None, stride) for _ in shape)
        ref = statistics.exact_quantiles(v[sub][regular[sub] & np.isfinite(v[sub])])
        assert quants.keys() == ref.keys()
        for name in ref:
            same = quants[name] == ref[name] or (math.isnan(quants[name]) and math.isnan(ref[name]))
            assert same, (stride, start, name)


def test_grid_quantiles_without_values():
    v = np.full((4, 6), np.nan)
    got = partials.exact_grid_quantiles(v, np.ones((4, 6), bool), [True, True, False], 0.0, 1.0)
    assert all(math.isnan(x) for x in got[0].values()) and all(math.isnan(x) for x in got[1].values())
    assert got[2] is None
