"""Streamed statistics of a workspace map: one pass over chunks, memory independent of resolution.

A map's global figures are taken over its *regular* feasible points: feasible, not singular
(the mechanism's own singularity analysis, or an infinite value where a mechanism has none),
and with a finite value. Singular feasible points are counted and located, never averaged:
at a singularity a Jacobian is rounding noise and one such point moved the five-bar's mean
isotropic force from 10.4 N to 11,290 N.

===============  ===========================================  ================================
figure           how it is accumulated                        exact?
===============  ===========================================  ================================
min, max         per-chunk extreme and its flat grid index     exact
mean, SD         per-chunk two-pass mean and squared           to rounding (Chan et al. 1979)
                 deviations, merged pairwise (ddof = 1)
median, p05,     a histogram over the leading bits of each     within ``QUANTILE_REL_ERROR``
p95              value's IEEE-754 pattern (sign, exponent,     relative (half a bin), of the
                 ``QUANTILE_BITS`` mantissa bits)              ``inverted_cdf`` order statistic
count            regular points                                exact
singular_points  feasible points the mechanism calls singular  exact; the first
                                                               ``SINGULAR_LOCATIONS`` located
===============  ===========================================  ================================

The histogram has at most ``2^QUANTILE_BITS`` bins per binade the values span, however many
points there are, so ``isoforce stats`` at 8000 x 8000 needs no more memory than at 200 x 200.

References
----------
Chan, Golub and LeVeque, "Updating formulae and a pairwise algorithm for computing sample
variances", Stanford CS report 79-773 (1979).
"""
from __future__ import annotations

import math
import struct
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

#: Mantissa bits kept by the quantile histogram: bins of relative width 2^-12 (quantiles within 1.2e-4).
QUANTILE_BITS = 12
#: Largest relative error of a reported quantile against the exact order statistic (half a bin).
QUANTILE_REL_ERROR = 2.0 ** -(QUANTILE_BITS + 1)
#: How many singular points a statistics record locates (all of them are counted).
SINGULAR_LOCATIONS = 10
#: Quantiles every record carries, by name; exact rationals, so that the rank ``ceil(q n)`` is exact.
QUANTILES = {"p05": Fraction(1, 20), "median": Fraction(1, 2), "p95": Fraction(19, 20)}

_SHIFT = np.uint64(52 - QUANTILE_BITS)
_SIGN = np.uint64(1 << 63)


def _keys(values: np.ndarray) -> np.ndarray:
    """Monotone integer keys of finite floats (..., ): order of keys = order of values, truncated to bins.

    The IEEE-754 pattern of a non-negative float orders like the float; flipping every bit of
    a negative one and setting the sign bit of a positive one makes one unsigned order for all.
    """
    bits = np.ascontiguousarray(values, dtype=np.float64).view(np.uint64)
    negative = (bits & _SIGN) != 0
    ordered = np.where(negative, ~bits, bits | _SIGN)
    return ordered >> _SHIFT


def _bin_value(key: int, lo: float, hi: float) -> float:
    """The midpoint of histogram bin ``key``, clipped to the observed range ``[lo, hi]``.

    In Python integers (``_keys`` undone: a set sign bit marks a positive float, else every bit was
    flipped), the bits read as a float by ``struct``: the same numbers as numpy's uint64 view, without
    its scalar overhead (2.6 us a call against 11 us).
    """
    shift, sign = int(_SHIFT), int(_SIGN)
    first = int(key) << shift
    last = first | ((1 << shift) - 1)
    ends = []
    for ordered in (first, last):
        bits = ordered & ~sign if ordered & sign else ~ordered & 0xFFFFFFFFFFFFFFFF
        ends.append(struct.unpack("<d", struct.pack("<Q", bits))[0])
    a, b = min(ends), max(ends)
    mid = a + 0.5 * (b - a)
    return float(min(max(mid, lo), hi))


def quantile_rank(q: Fraction, count: int) -> int:
    """1-based rank of the ``inverted_cdf`` q-quantile of ``count`` values: ``max(1, ceil(q count))``.

    Parameters
    ----------
    q : Fraction
        The quantile, in [0, 1].
    count : int
        Number of values.

    Returns
    -------
    int

    Examples
    --------
    >>> quantile_rank(Fraction(1, 2), 10), quantile_rank(Fraction(1, 20), 10)
    (5, 1)
    """
    return max(1, math.ceil(q * count))


def exact_quantiles(values: np.ndarray) -> dict[str, float]:
    """``QUANTILES`` of finite ``values`` (k,) as exact order statistics (``inverted_cdf``).

    Parameters
    ----------
    values : ndarray, shape (k,)
        Finite values.

    Returns
    -------
    dict of str to float
        One entry per name of ``QUANTILES``; ``nan`` for no values.

    Examples
    --------
    >>> exact_quantiles(np.arange(1.0, 21.0))
    {'p05': 1.0, 'median': 10.0, 'p95': 19.0}
    """
    if values.size == 0:
        return dict.fromkeys(QUANTILES, math.nan)
    ranks = {name: quantile_rank(q, values.size) - 1 for name, q in QUANTILES.items()}
    part = np.partition(values, sorted(set(ranks.values())))
    return {name: float(part[r]) for name, r in ranks.items()}


@dataclass
class Partial:
    """The statistics of one chunk of one quantity, made where the chunk was computed (a worker)."""

    count: int
    mean: float
    m2: float                    # sum of squared deviations, in units of scale^2
    scale: float                 # a power of two >= the largest |deviation|, so squares neither
                                 # underflow (values near 1e-300) nor overflow (near 1e300)
    min: float
    max: float
    argmin: int
    argmax: int
    singular: int
    singular_index: np.ndarray
    keys: np.ndarray | None      # histogram bins (sorted keys), their counts and the values at their ends
    counts: np.ndarray | None
    lows: np.ndarray | None = None
    highs: np.ndarray | None = None


def chunk_partial(values: np.ndarray, regular: np.ndarray, singular: np.ndarray, index: np.ndarray, *,
                  histogram: bool, bounded: np.ndarray | None = None) -> Partial:
    """Statistics of one chunk, to be merged by ``StatsAccumulator.merge``.

    Parameters
    ----------
    values : ndarray, shape (k,)
        The quantity at the chunk's points (any value where not regular).
    regular, singular : ndarray of bool, shape (k,)
        Points that enter the figures, and feasible singular points (counted, located).
    index : ndarray of int, shape (k,)
        Flat grid index of each point (C order), to locate extremes and singular points.
    histogram : bool
        Also bin the values for streamed quantiles (not needed when the map is kept whole).
    bounded : ndarray of bool, shape (k,), optional
        Singular points whose finite values enter the extremes (not the count, mean, SD or
        quantiles): where the quantity has a finite limit at the singularity, the workspace's
        infimum or supremum may be attained there (the five-bar's isotropic force at a stretched
        leg, 5.26 N, against 5.60 N, the smallest at its regular nodes).

    Returns
    -------
    Partial
        Count, mean, scaled squared deviations, extremes with their grid indices, the singular
        points, and (with ``histogram``) the bins. Without regular points, ``count`` is 0 and the
        extremes are those of the ``bounded`` points, if any.

    Examples
    --------
    >>> part = chunk_partial(np.array([2.0, 5.0, np.nan]), np.array([True, True, True]),
    ...                      np.array([False, False, False]), np.array([7, 8, 9]), histogram=False)
    >>> part.count, part.mean, part.argmax
    (2, 3.5, 8)
    """
    sing = index[singular][:SINGULAR_LOCATIONS]
    n_sing = int(np.count_nonzero(singular))
    finite = np.isfinite(values)
    keep = regular & finite
    ends = keep if bounded is None else (regular | (bounded & singular)) & finite
    extremes = (math.inf, -math.inf, -1, -1)
    if ends.any():
        e, where = values[ends], index[ends]
        i, j = int(np.argmin(e)), int(np.argmax(e))
        extremes = (float(e[i]), float(e[j]), int(where[i]), int(where[j]))
    v = values[keep]
    if v.size == 0:
        return Partial(0, 0.0, 0.0, 0.0, *extremes, n_sing, sing, None, None)
    mean = float(np.mean(v))
    dev = v - mean
    spread = float(np.max(np.abs(dev)))
    scale = math.ldexp(1.0, math.frexp(spread)[1]) if spread > 0.0 else 0.0    # 0: no spread at all
    m2 = float(np.sum((dev / scale) ** 2)) if scale > 0.0 else 0.0
    table: tuple = (None, None, None, None)
    if histogram:
        table = _histogram(np.sort(v))
    return Partial(int(v.size), mean, m2, scale, *extremes, n_sing, sing, *table)


def _histogram(ordered: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Bins of sorted finite values (k,): keys, counts, and the smallest and largest value in each."""
    keys = _keys(ordered)
    starts = np.flatnonzero(np.concatenate([[True], keys[1:] != keys[:-1]]))
    ends = np.append(starts[1:], keys.size)
    return keys[starts], ends - starts, ordered[starts], ordered[ends - 1]


#: Histogram entries held beyond twice the last compacted table before the tables are compacted again.
_COMPACT_SLACK = 1 << 16


def _merged(tables: list) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One table of histogram tables ``(keys, counts, lows, highs)``, each sorted by key: per key, the
    counts summed and the extreme values kept.

    The keys of a map's tables usually span a few thousand bins: then each table's entries are
    added into a dense array indexed by key (``ufunc.at``), 2-3x faster than sorting every entry
    (40 tables of the 1000 x 1000 Inverse3 statistics: 10-15 ms against 29 ms), the same table.
    A span wider than ``2 entries + _COMPACT_SLACK`` (values spread over many binades) is sorted.
    """
    keys, counts, lows, highs = (np.concatenate(parts) for parts in zip(*tables))
    filled = [t[0] for t in tables if t[0].size]
    if filled:
        first, last = min(int(k[0]) for k in filled), max(int(k[-1]) for k in filled)
        span = last - first + 1
        if span <= 2 * keys.size + _COMPACT_SLACK:
            at = (keys - np.uint64(first)).astype(np.intp)
            total = np.zeros(span, counts.dtype)
            np.add.at(total, at, counts)
            low, high = np.full(span, np.inf), np.full(span, -np.inf)
            np.minimum.at(low, at, lows)
            np.maximum.at(high, at, highs)
            used = np.flatnonzero(total)
            return used.astype(np.uint64) + np.uint64(first), total[used], low[used], high[used]
    order = np.argsort(keys, kind="stable")
    keys = keys[order]
    starts = np.flatnonzero(np.concatenate([[True], keys[1:] != keys[:-1]]))
    return (keys[starts], np.add.reduceat(counts[order], starts), np.minimum.reduceat(lows[order], starts),
            np.maximum.reduceat(highs[order], starts))


@dataclass
class StatsAccumulator:
    """Running statistics of one quantity over the regular points of a map, merged chunk by chunk.

    ``merge`` takes the ``Partial`` of each chunk in any order. Nothing grows with the number
    of points except the histogram, whose size is bounded by the binades the values span
    (module docstring).
    """

    count: int = 0
    mean: float = 0.0
    m2: float = 0.0              # in units of scale^2, as in ``Partial``
    scale: float = 0.0
    min: float = math.inf
    max: float = -math.inf
    argmin: int = -1
    argmax: int = -1
    singular: int = 0
    singular_index: list[int] = field(default_factory=list)
    _tables: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = field(default_factory=list)
    _held: int = 0
    _compacted: int = 0

    def merge(self, part: Partial) -> None:
        """Add one chunk's statistics (Chan et al.'s pairwise update for mean and squared deviations).

        Parameters
        ----------
        part : Partial
            One chunk's statistics (``chunk_partial``).

        Returns
        -------
        None

        Examples
        --------
        >>> acc = StatsAccumulator()
        >>> for start in (0, 3):
        ...     values = np.arange(start, start + 3, dtype=float)
        ...     ok = np.ones(3, bool)
        ...     acc.merge(chunk_partial(values, ok, ~ok, np.arange(start, start + 3), histogram=True))
        >>> acc.count, acc.mean, acc.min, acc.argmax
        (6, 2.5, 0.0, 5)
        """
        self.singular += part.singular
        room = SINGULAR_LOCATIONS - len(self.singular_index)
        if room > 0:
            self.singular_index.extend(int(i) for i in part.singular_index[:room])
        # Ties between chunks keep the smaller grid index, so the result does not depend on
        # the order chunks arrive in. A chunk without regular points may still hold extremes
        # (its ``bounded`` singular points).
        if part.argmin >= 0 and (part.min < self.min or (part.min == self.min and part.argmin < self.argmin)):
            self.min, self.argmin = part.min, part.argmin
        if part.argmax >= 0 and (part.max > self.max or (part.max == self.max and part.argmax < self.argmax)):
            self.max, self.argmax = part.max, part.argmax
        if part.count == 0:
            return
        n = self.count + part.count
        delta = part.mean - self.mean
        self.mean += delta * (part.count / n)
        # One power-of-two scale for both parts and the shift of the means: exact rescaling.
        new_scale = max(self.scale, part.scale, math.ldexp(1.0, math.frexp(abs(delta))[1]) if delta else 0.0)
        if new_scale > 0.0:
            self.m2 = (self.m2 * (self.scale / new_scale) ** 2 + part.m2 * (part.scale / new_scale) ** 2
                       + (delta / new_scale) ** 2 * (self.count * part.count / n))
            self.scale = new_scale
        self.count = n
        if part.keys is not None:
            self._tables.append((part.keys, part.counts, part.lows, part.highs))
            self._held += part.keys.size
            if self._held > 2 * self._compacted + _COMPACT_SLACK:
                self._compact()

    def _compact(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        if len(self._tables) != 1:
            self._tables = [_merged(self._tables)]
        self._held = self._compacted = self._tables[0][0].size
        return self._tables[0]

    def quantiles(self) -> dict[str, float]:
        """``QUANTILES`` from the histogram: within ``QUANTILE_REL_ERROR`` of the exact order statistics.

        Returns
        -------
        dict of str to float
            One entry per name of ``QUANTILES``; ``nan`` without regular points or histogram.
        """
        if self.count == 0 or not self._tables:
            return dict.fromkeys(QUANTILES, math.nan)
        keys, counts, lows, highs = self._compact()
        cumulative = np.cumsum(counts)
        out = {}
        for name, q in QUANTILES.items():
            k = int(np.searchsorted(cumulative, quantile_rank(q, self.count)))
            # The bin's midpoint, within the values the bin actually holds: exact where it holds one.
            out[name] = _bin_value(int(keys[k]), float(lows[k]), float(highs[k]))
        return out

    @property
    def sd(self) -> float:
        """Sample standard deviation (ddof = 1); ``nan`` for fewer than two points.

        Returns
        -------
        float
            In the unit of the quantity.
        """
        return self.scale * math.sqrt(self.m2 / (self.count - 1)) if self.count > 1 else math.nan
