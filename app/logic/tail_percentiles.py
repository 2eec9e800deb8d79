"""``np.percentile`` (its default ``"linear"`` method) of percentiles near 0 or 100, from the tails alone.

``np.percentile`` partitions the whole array around the order statistics it interpolates between
(and its first and last): ~0.55 ms for the 76,000 feasible values of the five-bar's 521 x 261 map,
the largest part of its colour limits (``colour_limits``), which a dragged slider's map waits
for. The p1 and p99 of the colour limits lie in the tails: each tail's values are those at or past
a threshold read from a sample of the array (every ``STRIDE``-th value), and only they are
partitioned. The order statistics are then the whole array's exactly (the values at or below a
threshold t are the smallest ones, as a multiset; its order statistics below their count are the
whole array's), and the interpolation is numpy's own arithmetic, so the result is
``np.percentile``'s bit for bit (``tests/app/test_tail_percentiles.py`` compares them). A sample
that misses (too few values past its threshold), a zero at a selected order statistic (-0.0 and
0.0 are equal, either may be selected) or a small array takes ``np.percentile`` itself.
"""
from __future__ import annotations

import math

import numpy as np

#: One value in ``STRIDE`` makes the sample the thresholds are read from.
STRIDE = 16
#: Below this many values the whole array is partitioned (``np.percentile``).
SMALL = 8 * STRIDE * STRIDE


def percentiles(data: np.ndarray, percents) -> np.ndarray:
    """``np.percentile(data, percents)``, bit for bit, from the tails of ``data`` when it is large.

    Parameters
    ----------
    data : ndarray, shape (n,)
        Finite values (no ``nan``), float64.
    percents : sequence of float
        Percentiles in [0, 100]; the fewer values lie below the lowest or above the highest,
        the less is partitioned.

    Returns
    -------
    ndarray of float64, shape (len(percents),)

    Examples
    --------
    >>> x = np.random.default_rng(1).normal(size=10 ** 5)
    >>> bool(np.array_equal(percentiles(x, [1.0, 99.0]), np.percentile(x, [1.0, 99.0])))
    True
    """
    data = np.asarray(data)
    n = data.size
    if n < SMALL or data.ndim != 1 or data.dtype != np.float64:
        return np.percentile(data, percents)
    # np.percentile's indices and weights (``_quantile``, ``_get_indexes``, ``_get_gamma``), as it forms them.
    q = np.true_divide(np.asarray(percents, dtype=np.float64), 100)
    virtual = (n - 1) * q
    previous = np.floor(virtual)
    following = previous + 1
    above, below = virtual >= n - 1, virtual < 0
    previous[above], following[above] = -1, -1
    previous[below], following[below] = 0, 0
    previous, following = previous.astype(np.intp), following.astype(np.intp)
    gamma = np.asanyarray(virtual - previous, dtype=virtual.dtype)
    ranks = sorted({int(r) % n for r in (*previous, *following)})
    found = _order_statistics(data, ranks)
    if found is None:
        return np.percentile(data, percents)
    a = np.array([found[int(r) % n] for r in previous])
    b = np.array([found[int(r) % n] for r in following])
    # ``_lerp``: a + (b - a) t, and b - (b - a) (1 - t) where t >= 0.5.
    diff = b - a
    out = np.add(a, diff * gamma)
    np.subtract(b, diff * (1 - gamma), out=out, where=gamma >= 0.5)
    return out


def _order_statistics(data: np.ndarray, ranks: list[int]) -> dict[int, float] | None:
    """The values of the given ranks (0: the smallest) of ``data`` (n,), each found in its tail; None
    where a tail's threshold missed or a value is zero (the caller then partitions everything)."""
    n = data.size
    low = [r for r in ranks if r < n // 2]
    high = [r for r in ranks if r >= n // 2]
    sample = data[::STRIDE]
    m = sample.size
    # A sample's value of rank j has about j * STRIDE values of the array below it: half as many
    # again, and a few, so that the tail holds the ranks asked for on any but a contrived array.
    picks = {}
    if low:
        picks["low"] = min(m - 1, math.ceil(1.5 * (max(low) + 1) / STRIDE) + 8)
    if high:
        picks["high"] = max(0, m - 1 - (math.ceil(1.5 * (n - min(high)) / STRIDE) + 8))
    kth = sorted(set(picks.values()))
    cut = np.partition(sample, kth)
    found: dict[int, float] = {}
    if low:
        tail = data[data <= cut[picks["low"]]]
        if tail.size <= max(low):
            return None
        part = np.partition(tail, low)
        found.update((r, part[r]) for r in low)
    if high:
        tail = data[data >= cut[picks["high"]]]
        skip = n - tail.size                # the values below the tail
        if skip > min(high):
            return None
        at = [r - skip for r in high]
        part = np.partition(tail, at)
        found.update((r, part[r - skip]) for r in high)
    if any(v == 0.0 for v in found.values()):
        return None
    return found
