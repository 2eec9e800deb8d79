"""The count search: exact culling of a *sum* objective, with partial counts as bounds.

The first two are max-min problems and run on ``metrics.design.culling.culling_search`` (forms
``"min"`` and ``"ratio"``). The count is a *sum* over the workspace, which the min-form bounds
do not cover; ``count_search`` is the same algorithm with the bound that fits a sum of
non-negative integers: a partial count over some samples is a lower bound of the final count,
so ``-partial`` is an upper bound of ``F = -count`` that only falls as samples are added.
Counts are sums of 0/1 in float64, exact in any order, so its result equals brute force
bit for bit (tested). A constraint vetoes a design with a sample worth ``inf`` (``max_apparent_mass``):
its count is ``inf``, its bound ``-inf`` from that sample on, and it ranks last.
"""
from __future__ import annotations

import heapq
import time

import numpy as np

from .culling import BLOCK_PAIRS
from .ranking import SearchResult, TopK, ranking


def _sum_result(method, t0, D, S, evaluations, keys, exact, probes) -> SearchResult:
    top_values = np.array([-n for n, _ in keys], dtype=np.float64)
    top_designs = np.array([d for _, d in keys], dtype=np.int64)
    value, design = (float(top_values[0]), int(top_designs[0])) if keys else (float("nan"), -1)
    return SearchResult(value=value, design=design, evaluations=evaluations, seconds=time.perf_counter() - t0,
                        top_designs=top_designs, top_values=top_values, n_designs=D, n_samples=S, method=method,
                        exact_designs=exact, probes=np.asarray(probes, np.int64))


def _sum_ids(designs, samples):
    d = np.arange(designs) if isinstance(designs, (int, np.integer)) else np.sort(np.asarray(designs, np.int64))
    s = np.arange(samples) if isinstance(samples, (int, np.integer)) else np.asarray(samples, np.int64)
    if d.size == 0 or s.size == 0:
        raise ValueError(f"designs and samples must be non-empty, got {d.size} and {s.size}")
    return d, s


def _check_counts(block: np.ndarray, k: int, m: int) -> np.ndarray:
    arr = np.asarray(block, dtype=np.float64)
    if arr.shape != (k, m):
        raise ValueError(f"evaluate must return shape ({k}, {m}), got {arr.shape}")
    if not np.all((arr == 0.0) | (arr == 1.0) | (arr == np.inf)):
        raise ValueError("a count evaluator must return 0 or 1 per (design, sample) (inf: the design is vetoed)")
    return arr


def count_brute_force(evaluate, designs, samples, *, top_k: int = 1) -> SearchResult:
    """Every design on every sample: ``F = -(number of samples with value 1)``, ranked as in
    ``metrics.design.culling`` (``F`` descending = count ascending, then id ascending).

    Parameters
    ----------
    evaluate : callable ``(design_ids (k,), sample_ids (s,)) -> (k, s)``
        0/1 per (design, sample), float.
    designs : int or array_like of int, shape (D,)
        Design ids, or their count (ids ``0 .. D - 1``).
    samples : int or array_like of int, shape (S,)
        Sample ids, or their count.
    top_k : int
        How many best designs to keep.

    Returns
    -------
    SearchResult
        ``value`` is ``-count`` of the best design; ``evaluations`` is ``D * S``.

    Examples
    --------
    >>> def ev(d, s):              # design d counts its samples s <= d % 5
    ...     return (s[None, :] <= d[:, None] % 5).astype(float)
    >>> r = count_brute_force(ev, 10, 8, top_k=2)
    >>> r.value, r.top_designs.tolist(), r.evaluations
    (-1.0, [0, 5], 80)
    """
    t0 = time.perf_counter()
    ids, sids = _sum_ids(designs, samples)
    rows = max(1, BLOCK_PAIRS // sids.size)
    counts = np.zeros(ids.size)
    for start in range(0, ids.size, rows):
        d = ids[start:start + rows]
        counts[start:start + d.size] = _check_counts(evaluate(d, sids), d.size, sids.size).sum(axis=1)
    values = -counts
    order = ranking(values, ids)[:top_k]
    keys = [(-float(values[i]), int(ids[i])) for i in order]
    return _sum_result("brute_force", t0, ids.size, sids.size, ids.size * sids.size, keys, ids.size, [])


def count_search(evaluate, designs, samples, *, top_k: int = 1, initial_samples=None, first_chunk: int = 64,
                 floor: tuple[float, int] | None = None) -> SearchResult:
    """Exact search for the ``top_k`` designs with the smallest count (``F = -count`` largest).

    ``evaluate(design_ids, sample_ids)`` returns 0/1 blocks (1: the sample counts, e.g. its
    condition number exceeds the threshold). The bound: a design evaluated on a prefix of the
    sample order has ``count >= partial``, so ``F <= -partial``; a design whose bound ranks
    after the K-th best exact design (``metrics.design.culling``'s rule and tie order, and its
    ``floor`` for split runs) is culled. Sample order: ``initial_samples`` (a permutation, e.g.
    ``probes`` of an earlier chunk), else the middle design is evaluated exactly and its
    counted samples go first (they tend to count for its neighbours too). Every design is
    then evaluated on the first ``first_chunk`` samples; best-first, the live design with the
    highest bound evaluates its next chunk (doubling) until it is exact or culled.
    Same result as ``count_brute_force``, exactly (integer sums), with ``probes`` = the order.

    Parameters
    ----------
    evaluate : callable ``(design_ids (k,), sample_ids (s,)) -> (k, s)``
        0/1 per (design, sample), float.
    designs : int or array_like of int, shape (D,)
        Design ids, or their count (ids ``0 .. D - 1``).
    samples : int or array_like of int, shape (S,)
        Sample ids, or their count.
    top_k : int
        How many best designs to find.
    initial_samples : array_like of int, optional
        Sample ids to evaluate first (the rest follow in order).
    first_chunk : int
        Samples every design is evaluated on first.
    floor : (float, int), optional
        ``(F, design id)`` a design must beat (an earlier chunk's K-th best), for split runs.

    Returns
    -------
    SearchResult
        As ``count_brute_force``'s, with fewer ``evaluations``.

    Examples
    --------
    >>> def ev(d, s):
    ...     return (s[None, :] <= d[:, None] % 5).astype(float)
    >>> count_search(ev, 10, 8, top_k=2).top_designs.tolist()
    [0, 5]
    """
    t0 = time.perf_counter()
    ids, sids = _sum_ids(designs, samples)
    D, S = ids.size, sids.size
    top = TopK(int(top_k), floor)      # the culling search's own K-best list and threshold
    evaluations = 0
    counts = np.zeros(D)
    pos = np.zeros(D, np.int64)
    exact = 0

    def block(dpos, spos):
        nonlocal evaluations
        evaluations += dpos.size * spos.size
        return _check_counts(evaluate(ids[dpos], sids[spos]), dpos.size, spos.size)

    if initial_samples is not None:
        init = np.asarray(initial_samples, np.int64)
        lookup = {int(s): i for i, s in enumerate(sids.tolist())}
        first = [lookup[int(s)] for s in init.tolist() if int(s) in lookup]
        seen = np.zeros(S, bool)
        seen[first] = True
        order = np.concatenate([np.asarray(first, np.int64), np.flatnonzero(~seen)])
        skip = -1
    else:
        skip = D // 2
        row = block(np.array([skip]), np.arange(S))[0]
        order = np.argsort(-row, kind="stable")
        counts[skip], pos[skip] = row.sum(), S
        top.add(-counts[skip], ids[skip])
        exact += 1
    n0 = min(first_chunk, S)
    live = np.flatnonzero(np.arange(D) != skip)
    rows = max(1, BLOCK_PAIRS // n0)
    for start in range(0, live.size, rows):
        dpos = live[start:start + rows]
        counts[dpos] = block(dpos, order[:n0]).sum(axis=1)
        pos[dpos] = n0
    for p in live[pos[live] == S]:
        top.add(-counts[p], ids[p])
        exact += 1
    live = live[pos[live] < S]
    keep = ~top.cullable_array(-counts[live], ids[live])
    heap = list(zip(counts[live[keep]].tolist(), ids[live[keep]].tolist(), live[keep].tolist()))
    heapq.heapify(heap)
    while heap:
        c, d, p = heap[0]
        if top.cullable(-c, d):
            break
        heapq.heappop(heap)
        size = max(first_chunk, int(pos[p]))
        spos = order[pos[p]:pos[p] + size]
        counts[p] += block(np.array([p]), spos)[0].sum()
        pos[p] += spos.size
        if pos[p] == S:
            top.add(-counts[p], d)
            exact += 1
        elif not top.cullable(-counts[p], d):
            heapq.heappush(heap, (float(counts[p]), d, p))
    return _sum_result("culling", t0, D, S, evaluations, top.keys, exact, sids[order])
