"""``app.logic.tail_percentiles.percentiles``: ``np.percentile`` bit for bit, whatever the array.

The reference is ``np.percentile`` itself (method ``"linear"``) on the same array: equal bits, not
a tolerance, since the order statistics are selected exactly and interpolated with numpy's own
operations. Arrays that make the tails' sample miss (a period of the sample's stride), zeros at the
ranks, ties, constants and sizes about the partition-everything limit take the fallback or not: the
result must be the same either way.
"""
from __future__ import annotations

import numpy as np
import pytest

from app.logic import tail_percentiles as tp
from app.logic.tail_percentiles import percentiles


def _arrays():
    rng = np.random.default_rng(38)
    n = 76_631
    yield "normal", rng.normal(size=n)
    yield "lognormal", rng.lognormal(sigma=3.0, size=n)
    yield "uniform", rng.random(n)
    yield "ties", np.round(rng.normal(size=n), 1)
    yield "constant", np.full(n, 2.5)
    yield "negative", -rng.lognormal(size=n)
    yield "sorted", np.sort(rng.normal(size=n))
    yield "reversed", np.sort(rng.normal(size=n))[::-1].copy()
    yield "period of the stride", np.tile(np.arange(tp.STRIDE, dtype=float), n // tp.STRIDE)
    yield "zeros at the ranks", np.concatenate([np.zeros(n // 20), rng.random(n)])
    yield "signed zeros", np.concatenate([np.zeros(n // 20), -np.zeros(n // 20), rng.random(n) - 0.5])
    yield "spikes", np.concatenate([rng.random(n), [1e300, -1e300, 1e-300, 5e-324]])
    for size in (tp.SMALL - 1, tp.SMALL, tp.SMALL + 1, 10 ** 6):
        yield f"size {size}", rng.standard_cauchy(size)


@pytest.mark.parametrize("name, data", list(_arrays()), ids=lambda v: v if isinstance(v, str) else "")
@pytest.mark.parametrize("percents", [[1.0, 99.0], [0.0, 100.0], [50.0], [0.1, 99.9], [5.0, 1.0, 95.0, 99.0]])
def test_percentiles_are_numpy_s_bit_for_bit(name, data, percents):
    expected = np.percentile(data, percents)
    got = percentiles(data, percents)
    assert got.dtype == expected.dtype and got.shape == expected.shape
    assert got.tobytes() == expected.tobytes(), (name, percents, got, expected)


def test_the_array_is_left_as_it_was():
    data = np.random.default_rng(1).normal(size=50_000)
    before = data.copy()
    percentiles(data, [1.0, 99.0])
    assert data.tobytes() == before.tobytes()
