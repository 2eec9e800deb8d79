"""Exact discrete max-min design search: the culling algorithm, and brute force to check it.

Paper 001 (Stocco, Salcudean, Sassani) picks a haptic pen's design with "the culling
algorithm" of its ref. [24]: a discrete optimizer for minimax problems that "guarantees the
same result as a global search but [is] orders of magnitude faster". The paper gives no more
than that; this module is our own exact algorithm in that spirit, written for any objective
of the two forms below.

The problem
-----------
Designs ``p`` are integer ids in a finite set ``P`` (``0 .. D-1``, or any subset of ids, see
"Splitting" below); workspace samples ``x`` are ids in a finite set ``W`` (``0 .. S-1``).

``form="min"``
    ``F(p) = min_x f(p, x)``: e.g. the global minimum isotropic force over the workspace.
``form="ratio"``
    ``F(p) = min_x a(p, x) / max_x b(p, x)`` with ``a, b >= 0``: the Global Isotropy Index of
    paper 001 eq. 11 (``a = sigma_min``, ``b = sigma_max`` of the scaled Jacobian). The
    numerator and denominator may be attained at different samples, as eq. 11 says.

and the search returns ``p* = argmax_p F(p)`` (paper 001 eq. 10) with ``F(p*)``, plus the
``top_k`` best designs with their exact values.

The evaluator
-------------
``evaluate(design_ids, sample_ids)`` takes two 1-D int64 arrays, ``(k,)`` and ``(m,)``, and
returns the ``(k, m)`` block of ``f`` values (``form="min"``) or a pair ``(a, b)`` of such
blocks (``form="ratio"``). The search calls it with ``k = 1`` and many samples (one
design's rows, what a mechanism model computes efficiently: one model, many points) and with
many designs on a few samples (the probes). Adapters (``metrics.design.evaluator_adapters``):
``per_design`` (a function of one design and a sample array, looped over the block),
``elementwise`` (a numpy-broadcasting function of index arrays), ``table`` (precomputed arrays,
for tests).

Requirement: ``f(p, x)`` must not depend on which other pairs share the call. Both methods
then see bit-identical values, and since ``min``/``max`` are exact in floating point however
the samples are grouped, culling reproduces brute force's values to the last bit.

Infeasible samples and values
-----------------------------
``nan`` or ``-inf`` (in ``f``, or in ``a`` or ``b``) marks an infeasible sample (unreachable,
outside the joint limits). ``+inf`` is an ordinary value. ``infeasible`` chooses what it does:

``"fail"`` (default)
    one infeasible sample makes the design infeasible: ``F(p) = -inf``. A design must cover
    the whole workspace.
``"skip"``
    infeasible samples are left out of the min and the max; a design with no feasible sample
    at all gets ``F(p) = -inf``.

In the ratio form ``a`` and ``b`` must otherwise be ``>= 0`` (a ``ValueError`` says which
design and sample broke this), and the quotient ``A / B`` of ``A = min a``, ``B = max b``
follows fixed conventions: ``0`` if ``A == 0`` or ``B == inf`` (a singular pose), ``inf`` if
``A > 0`` and ``B == 0``, else ``A / B``. This quotient never decreases when ``A`` grows or
``B`` shrinks, which is what the bounds below need.

A constraint outside the objective (``max_apparent_mass``) marks a (design, sample) pair with
``ranking.VETO``, the most negative finite float, in ``f`` or ``a``. It is an ordinary value
under both rules: in the min form ``F = VETO`` ranks after every real value; in the ratio form
``a = VETO`` is allowed and the quotient is ``VETO`` whatever ``B`` (still monotone: it is the
least value ``A`` can take).

Ranking and ties
----------------
Designs are ranked by ``F`` descending, equal values by design id ascending: ``p`` ranks
before ``q`` iff ``F(p) > F(q)``, or ``F(p) == F(q)`` and ``p < q``. This is a total order
(``F`` is never ``nan``), so the best design and the top-K list are unique. Brute force and
culling both use it; with every design infeasible the optimum is ``-inf`` at the smallest id.

The culling algorithm
---------------------
Bounds. After a design has been evaluated on a subset ``X`` of the samples, ``min_X a >=
min_W a`` and ``max_X b <= max_W b``, so ``U(p) = min_X a / max_X b`` (``min_X f`` in the min
form; ``-inf`` once an infeasible sample is seen under ``"fail"``; ``+inf`` while no feasible
sample is seen under ``"skip"``) is an upper bound: ``U(p) >= F(p)``. Division is correctly
rounded, hence monotone, so the bound also holds in floating point.

Culling rule. Let ``(T, t)`` be the value and id of the K-th best design evaluated exactly so
far (``K = top_k``). A design ``p`` with ``U(p) < T``, or ``U(p) == T`` and ``p > t``, ranks
after ``t`` whatever its exact value, and is culled: never evaluated again.

Loop.

1. *Probes.* Either the caller's ``initial_samples`` (e.g. the worst samples of an earlier
   run, or of another worker), or: evaluate the middle design exactly on the whole
   workspace and take its ``n_initial`` worst samples. Every design is evaluated on the
   probes (one block call per batch of designs), which gives its first bound: the probes in
   groups of 1, 2, 4, ..., and once a K-th best (or a floor) is known, the designs it culls
   are dropped between groups (a design has then seen a prefix of the probes; step 2 brings
   the rest before it becomes a candidate).
2. Take the live design with the highest bound (ties: smallest id). If it cannot beat
   ``(T, t)``, stop: neither can any other. If the probes added since its last visit have not
   been evaluated for it, evaluate them now (one call), tighten its bound, and go back to 2
   (a lazy priority queue: designs whose stale bound is already too low are never touched
   again).
3. Otherwise its bound is current and the highest: evaluate it on the rest of the workspace,
   worst-first in the order of the last exactly evaluated design's samples, in chunks of
   doubling size, and stop early if its bound falls below ``(T, t)`` (culled). If it
   completes, its value is exact and enters the top-K list, which may raise ``(T, t)``.
4. Up to ``n_new`` of the samples evaluated in step 3 join the probes: the worst for this
   candidate (its minimum of ``f`` or ``a``, its maximum of ``b``) among those that lower
   the bound its probes gave it. The samples attaining a design's minimum tend to be the
   worst for neighbouring designs too. Go to 2.

Every (design, sample) pair is evaluated at most once (a live design has seen exactly the
probes, and step 3 evaluates only the others), so culling never costs more evaluations than
brute force, ``D * S``; on smooth problems it costs a small fraction.

Exactness. (i) A culled design ``p`` ranks after the key ``(T_c, t_c)`` in force when it was
culled: ``F(p) <= U(p)`` and the rule. (ii) Keys only improve: the K-th best of a growing set
of exactly evaluated designs can only move up the ranking. So ``p`` ranks after the final
K-th best exact design, i.e. at least K exactly evaluated designs rank before it, and ``p`` is
not in the top K. Hence the global top K are all evaluated exactly, and the top K of the
exact designs, sorted by the ranking, is the global top K, values, ids and order. Stopping in
step 2 culls the rest by the same rule (the highest bound with the smallest id fails it, so
every lower bound, or equal bound with a larger id, fails too). The loop ends: each pass
either removes a design or advances one design through a probe list that grows only when a
design is removed.

Splitting across workers
------------------------
``culling_search(evaluate, designs=ids_of_this_worker, ...)`` works on any subset of design
ids (the evaluator sees the global ids; ties use them too) and returns that subset's top K
exactly. ``merge_top_k`` takes the K best of the union of the workers' lists. Exact: if
``p`` is in the global top K, fewer than K designs of ``P`` rank before it, so fewer than K of
its own worker's subset do, and ``p`` is in that worker's list; the merged list therefore
contains the whole global top K, every listed value is exact, and sorting by the same total
order puts it in the same order (``top_k`` of the merge must not exceed the K each part was
searched with). A worker may also start from a ``floor``: the K-th best ``(value, id)`` of
results already in hand, once they list K designs (e.g. ``merge_top_k(finished).kth``,
shared by workers that run chunks in turn). Designs ranking after it cannot be in the global top K
(K designs in hand rank before them), so culling against it keeps the merge exact, as long as
the results that gave the floor are merged too; the worker's own list may then hold fewer
than K designs, or none (``design == -1``, ``value == nan``).

``brute_force`` has the same signature and result type, evaluates every pair, and is what
the tests compare against.
"""
from __future__ import annotations

import functools
import heapq
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .ranking import VETO, SearchResult, TopK, merge_top_k, ranking  # noqa: F401  (merge_top_k: search API)

FORMS = ("min", "ratio")
INFEASIBLE = ("fail", "skip")

#: Largest block (designs x samples) brute force and the probe phase ask for at once.
BLOCK_PAIRS = 1 << 20

Evaluator = Callable[[np.ndarray, np.ndarray], Any]


# ------------------------------------------------------------------------------------------
# Problem: validation, evaluator calls, accumulated min / max per design
# ------------------------------------------------------------------------------------------


def _ids(name: str, value: Any, what: str) -> np.ndarray:
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        if value < 1:
            raise ValueError(f"{name} must be a positive count of {what} or an array of ids, got {value}")
        return _range(int(value))
    arr = np.asarray(value)
    if arr.ndim != 1 or arr.size == 0 or not np.issubdtype(arr.dtype, np.integer):
        raise ValueError(f"{name} must be a positive count of {what} or a non-empty 1-D array of "
                         f"integer ids, got {arr.dtype} array of shape {arr.shape}")
    arr = arr.astype(np.int64)
    # A sort, not np.unique: the chunks' ids come sorted, which a sort passes through in O(n)
    # where np.unique hashed every id (7.9 s over the 337 chunks of Table VII).
    ordered = np.sort(arr)
    repeats = int(np.count_nonzero(ordered[1:] == ordered[:-1]))
    if repeats:
        raise ValueError(f"{name} must not repeat an id, got {arr.size} ids of which "
                         f"{arr.size - repeats} distinct")
    return arr


@functools.lru_cache(maxsize=4)
def _range(n: int) -> np.ndarray:
    """``arange(n)``, read-only and shared by the searches of one size: every chunk of a study
    needs its samples' ids ``0 .. S-1`` (19 MB for Table VII's 2.4 M samples), and allocating
    them afresh cost 7.8 s over its 337 chunks."""
    arr = np.arange(n, dtype=np.int64)
    arr.flags.writeable = False
    return arr


def _argsort_ties_by(x: np.ndarray, tie: np.ndarray | None = None) -> np.ndarray:
    """Indices sorting ``x`` ascending, equal values ordered by ``tie`` ascending.

    With ``tie=None`` (ties by index) this is ``np.argsort(x, kind="stable")``, bit for bit:
    ``nan`` sorts last, ``-0.0 == 0.0`` is a tie. It is an unstable sort (3 times faster on
    float64 here; numpy may dispatch it to a SIMD sort whose order among equal values depends
    on the CPU) whose runs of equal values are then re-sorted by ``tie``, so no tie is ever
    left to the unstable sort; with more than an eighth of the values tied (and ties by index)
    the stable sort itself is the cheaper fix.

    Parameters
    ----------
    x : ndarray, shape (n,)
        Keys.
    tie : ndarray of int, shape (n,), optional
        Distinct non-negative tie-breakers (default ``arange(n)``).

    Returns
    -------
    ndarray of int64, shape (n,)
    """
    perm = np.argsort(x, kind="quicksort")
    n = perm.size
    if n < 2:
        return perm
    v = x[perm]
    eq = v[1:] == v[:-1]
    if v.dtype.kind in "fc":
        nan = np.isnan(v)                   # all at the end
        eq |= nan[1:] & nan[:-1]
    if not eq.any():
        return perm
    in_run = np.zeros(n, bool)
    in_run[1:] = eq
    in_run[:-1] |= eq
    pos = np.flatnonzero(in_run)            # sorted positions inside runs of equal values
    if tie is None and pos.size > n // 8:
        # Mostly ties (e.g. many infeasible samples): re-sorting them costs more than the
        # stable sort itself, which gives the same order.
        return np.argsort(x, kind="stable")
    # which run each is in, ascending: a run starts where the value before differs
    starts = np.ones(pos.size, bool)
    inner = pos > 0
    starts[inner] = ~eq[pos[inner] - 1]
    run = np.cumsum(starts)
    members = perm[pos]
    t = members if tie is None else np.asarray(tie, np.int64)[members]
    span = int(t.max()) + 1
    if (int(run[-1]) + 1) * span < 1 << 62:
        # Runs sit in ascending order, so one sort of (run, tie) fixes them all; the keys are
        # distinct, hence any sort gives the same order.
        within = np.argsort(run * span + t, kind="quicksort")
    else:
        within = np.lexsort((t, run))
    perm[pos] = members[within]
    return perm


def _first_in_order(key: np.ndarray, mask: np.ndarray, count: int) -> np.ndarray:
    """The first ``count`` indices ``i`` with ``mask[i]``, in order of ``(key[i], i)``.

    ``np.argsort(key, kind="stable")`` filtered by ``mask`` and cut to ``count``, bit for bit,
    without sorting everything: a partition finds the ``count``-th smallest key ``v``, and only
    the keys ``<= v`` (every tie at the boundary included) are sorted.

    Parameters
    ----------
    key : ndarray of float, shape (n,)
    mask : ndarray of bool, shape (n,)
    count : int

    Returns
    -------
    ndarray of int64, shape (min(count, mask.sum()),)
    """
    idx = np.flatnonzero(mask)
    k = key[idx]
    if idx.size > count:
        v = np.partition(k, count - 1)[count - 1]
        if not np.isnan(v):                 # nan: the count-th is among the nans, keep all
            near = np.flatnonzero(k <= v)
            idx, k = idx[near], k[near]
    return idx[_argsort_ties_by(k)[:count]]


def _ratio(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    """``num / den`` with 0 where ``num == 0`` or ``den == inf``, ``inf`` where only ``den == 0``,
    ``VETO`` where ``num == VETO``."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = num / den
    return np.where(num == VETO, VETO, np.where((num == 0.0) | (den == np.inf), 0.0, r))


class _Problem:
    """Validated ids, counted evaluator calls, and per-design running min / max."""

    def __init__(self, evaluate: Evaluator, designs: Any, samples: Any, form: str,
                 infeasible: str, top_k: int) -> None:
        if not callable(evaluate):
            raise ValueError(f"evaluate must be callable (design_ids, sample_ids) -> values, got {evaluate!r}")
        if form not in FORMS:
            raise ValueError(f"form must be one of {FORMS}, got {form!r}")
        if infeasible not in INFEASIBLE:
            raise ValueError(f"infeasible must be one of {INFEASIBLE}, got {infeasible!r}")
        if isinstance(top_k, bool) or not isinstance(top_k, (int, np.integer)) or top_k < 1:
            raise ValueError(f"top_k must be a positive integer, got {top_k!r}")
        self.evaluate = evaluate
        self.ratio = form == "ratio"
        self.fail = infeasible == "fail"
        self.top_k = int(top_k)
        self.design_ids = np.sort(_ids("designs", designs, "designs"))
        self.sample_ids = _ids("samples", samples, "workspace samples")
        self.D, self.S = self.design_ids.size, self.sample_ids.size
        self.evaluations = 0
        # running state per design (local positions 0..D-1, ascending id)
        self.A = np.full(self.D, np.inf)          # min of a (or f) over feasible samples seen
        self.B = np.zeros(self.D)                 # max of b over feasible samples seen (ratio)
        self.seen = np.zeros(self.D, bool)        # a feasible sample seen
        self.bad = np.zeros(self.D, bool)         # an infeasible sample seen

    # -- evaluator ----------------------------------------------------------------------
    def block(self, dpos: np.ndarray, spos: np.ndarray) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        """Evaluate designs ``dpos`` x samples ``spos`` (local positions): ``(a, b, infeasible)``."""
        k, m = dpos.size, spos.size
        dids, sids = self.design_ids[dpos], self.sample_ids[spos]
        out = self.evaluate(dids, sids)
        self.evaluations += k * m
        if self.ratio:
            if not (isinstance(out, (tuple, list)) and len(out) == 2):
                raise ValueError(f"evaluate must return a pair (a, b) of ({k}, {m}) arrays in the ratio "
                                 f"form, got {type(out).__name__}")
            a, b = (self._check(v, k, m, name) for v, name in zip(out, ("a", "b")))
            infeas = np.isnan(a) | (a == -np.inf) | np.isnan(b) | (b == -np.inf)
            for v, name in ((a, "a"), (b, "b")):
                neg = ~infeas & (v < 0.0) & ((v != VETO) if name == "a" else True)
                if neg.any():
                    i, j = np.argwhere(neg)[0]
                    raise ValueError(f"evaluate returned {name} = {float(v[i, j])!r} < 0 for design {dids[i]}, "
                                     f"sample {sids[j]}; the ratio form needs a, b >= 0 (nan or -inf: infeasible)")
            return a, b, infeas
        a = self._check(out, k, m, "f")
        return a, None, np.isnan(a) | (a == -np.inf)

    @staticmethod
    def _check(v: Any, k: int, m: int, name: str) -> np.ndarray:
        arr = np.asarray(v, dtype=np.float64)
        if arr.shape != (k, m):
            raise ValueError(f"evaluate must return {name} of shape ({k}, {m}) for {k} designs x {m} samples, "
                             f"got shape {arr.shape}")
        return arr

    # -- accumulated state --------------------------------------------------------------
    def absorb(self, dpos: np.ndarray, a: np.ndarray, b: np.ndarray | None, infeas: np.ndarray) -> None:
        """Fold an evaluated block into the running min / max of designs ``dpos`` (distinct)."""
        self.A[dpos] = np.minimum(self.A[dpos], np.where(infeas, np.inf, a).min(axis=1, initial=np.inf))
        if b is not None:
            self.B[dpos] = np.maximum(self.B[dpos], np.where(infeas, 0.0, b).max(axis=1, initial=0.0))
        self.seen[dpos] |= ~infeas.all(axis=1)      # False for an empty block
        self.bad[dpos] |= infeas.any(axis=1)

    def _objective(self, A: np.ndarray, B: np.ndarray) -> np.ndarray:
        return _ratio(A, B) if self.ratio else A.copy()

    def state(self, p: int) -> tuple[float, float, bool, bool]:
        """What design ``p`` has seen so far: ``(A, B, seen, bad)``."""
        return float(self.A[p]), float(self.B[p]), bool(self.seen[p]), bool(self.bad[p])

    def _bound(self, A, B, seen, bad) -> np.ndarray:
        u = self._objective(np.asarray(A, float), np.asarray(B, float))
        u = np.where(seen, u, np.inf)
        return np.where(bad, -np.inf, u) if self.fail else u

    def bound(self, dpos: np.ndarray) -> np.ndarray:
        """Upper bound ``U >= F`` from the samples seen so far."""
        return self._bound(self.A[dpos], self.B[dpos], self.seen[dpos], self.bad[dpos])

    def exact(self, dpos: np.ndarray) -> np.ndarray:
        """``F`` of designs that have seen every sample."""
        u = self._objective(self.A[dpos], self.B[dpos])
        dead = ~self.seen[dpos]
        if self.fail:
            dead |= self.bad[dpos]
        u[dead] = -np.inf
        return u

    def bound_if_added(self, state, a: np.ndarray, b: np.ndarray | None, infeas: np.ndarray) -> np.ndarray:
        """Bound from ``state`` (see ``state``) plus each sample alone, (m,)."""
        A0, B0, seen0, bad0 = state
        A = np.where(infeas, A0, np.minimum(A0, a))
        B = np.where(infeas, B0, np.maximum(B0, b)) if b is not None else np.zeros(a.shape)
        return self._bound(A, B, seen0 | ~infeas, bad0 | infeas)

    def badness(self, a: np.ndarray, b: np.ndarray | None, infeas: np.ndarray) -> np.ndarray:
        """Sort key of one design's samples, worst (lowest) first.

        Min form: the value. Ratio form: the better of the sample's rank by ``a`` ascending and
        by ``b`` descending, so the worst numerator and worst denominator samples come first.
        Infeasible samples come first under ``"fail"`` and last under ``"skip"``.
        """
        if b is None:
            key = a.copy()
        else:
            # Not _range: a candidate's sample count varies, and caching each would evict the
            # study's 0 .. S-1, which sample_positions recognises by identity.
            ranks = np.arange(a.size, dtype=np.float64)
            ra = np.empty(a.size)
            rb = np.empty(a.size)
            ra[_argsort_ties_by(np.where(infeas, np.inf, a))] = ranks
            rb[_argsort_ties_by(-np.where(infeas, 0.0, b))] = ranks
            key = np.minimum(ra, rb)
        key[infeas] = -np.inf if self.fail else np.inf
        return key

    def result(self, method: str, seconds: float, top: list[tuple[float, int]], exact_designs: int,
               probes: Sequence[int]) -> SearchResult:
        top_values = np.array([-neg for neg, _ in top], dtype=np.float64)
        top_designs = np.array([d for _, d in top], dtype=np.int64)
        value, design = (float(top_values[0]), int(top_designs[0])) if top else (float("nan"), -1)
        return SearchResult(value=value, design=design, evaluations=self.evaluations, seconds=seconds,
                            top_designs=top_designs, top_values=top_values, n_designs=self.D,
                            n_samples=self.S, method=method, exact_designs=exact_designs,
                            probes=self.sample_ids[np.asarray(probes, dtype=np.int64)])


# ------------------------------------------------------------------------------------------
# Searches
# ------------------------------------------------------------------------------------------


def brute_force(evaluate: Evaluator, designs: Any, samples: Any, *, form: str = "min",
                infeasible: str = "fail", top_k: int = 1) -> SearchResult:
    """Evaluate every design on every sample and rank them: the reference for ``culling_search``.

    Parameters
    ----------
    evaluate : callable ``(design_ids (k,), sample_ids (m,)) -> (k, m)`` values, or ``(a, b)``
        in the ratio form (see the module docstring).
    designs : int or array_like of int, shape (D,)
        ``D`` (ids ``0..D-1``) or the design ids.
    samples : int or array_like of int, shape (S,)
        ``S`` (ids ``0..S-1``) or the sample ids.
    form : {"min", "ratio"}
        ``"min"`` (``F = min f``) or ``"ratio"`` (``F = min a / max b``, paper 001 eq. 11).
    infeasible : {"fail", "skip"}
        ``"fail"`` (an infeasible sample makes ``F = -inf``) or ``"skip"``.
    top_k : int
        How many best designs to list.

    Returns
    -------
    SearchResult
        The ``top_k`` best designs with exact values; ``evaluations`` is ``D * S``.

    Examples
    --------
    >>> from metrics.design.evaluator_adapters import table
    >>> f = np.array([[3.0, 1.0, 2.0], [2.0, 2.0, 5.0], [0.0, 4.0, 4.0], [2.0, 3.0, 2.0]])
    >>> r = brute_force(table(f), 4, 3, top_k=2)
    >>> r.top_designs.tolist(), r.top_values.tolist(), r.evaluations
    ([1, 3], [2.0, 2.0], 12)
    """
    t0 = time.perf_counter()
    prob = _Problem(evaluate, designs, samples, form, infeasible, top_k)
    allsamples = _range(prob.S)
    rows = max(1, BLOCK_PAIRS // prob.S)
    for start in range(0, prob.D, rows):
        dpos = np.arange(start, min(start + rows, prob.D))
        prob.absorb(dpos, *prob.block(dpos, allsamples))
    values = prob.exact(np.arange(prob.D))
    order = ranking(values, prob.design_ids)[: prob.top_k]
    top = [(-float(values[i]), int(prob.design_ids[i])) for i in order]
    return prob.result("brute_force", time.perf_counter() - t0, top, prob.D, [])


def culling_search(evaluate: Evaluator, designs: Any, samples: Any, *, form: str = "min",
                   infeasible: str = "fail", top_k: int = 1, initial_samples: ArrayLike | None = None,
                   n_initial: int = 2, n_new: int = 2, first_chunk: int = 32,
                   floor: tuple[float, int] | None = None) -> SearchResult:
    """Exact max-min search by culling; same answer as ``brute_force``, far fewer evaluations.

    The algorithm, its exactness argument and the tie rule are in the module docstring.

    Parameters
    ----------
    evaluate, designs, samples, form, infeasible, top_k
        As for ``brute_force``.
    initial_samples : array_like of int, shape (p,), optional
        First probes (e.g. ``probes`` of an earlier result). Default: the ``n_initial`` worst
        samples of the middle design, which is evaluated exactly first.
    n_initial : int
        Probes taken from the middle design when ``initial_samples`` is not given.
    n_new : int
        Probes added after each exactly (or partly) evaluated candidate.
    first_chunk : int
        Samples in the first chunk of a candidate's evaluation; chunks double.
    floor : (float, int), optional
        ``(value, design id)``: the K-th best of K results already in hand for the same problem
        (see "Splitting" in the module docstring); designs ranking after it are culled from the
        start (the middle design of step 1 is still evaluated when ``initial_samples`` is not given).

    Returns
    -------
    SearchResult
        The same designs and values as ``brute_force``; ``probes`` for a related run.

    Examples
    --------
    >>> f = np.array([[3.0, 1.0, 2.0], [2.0, 2.0, 5.0], [0.0, 4.0, 4.0], [2.0, 3.0, 2.0]])
    >>> from metrics.design.evaluator_adapters import table
    >>> r = culling_search(table(f), 4, 3, top_k=2)
    >>> r.top_designs.tolist(), r.top_values.tolist()
    ([1, 3], [2.0, 2.0])
    """
    t0 = time.perf_counter()
    prob = _Problem(evaluate, designs, samples, form, infeasible, top_k)
    for name, v in (("n_initial", n_initial), ("n_new", n_new), ("first_chunk", first_chunk)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
            raise ValueError(f"{name} must be a positive integer, got {v!r}")
    search = _Culling(prob, TopK(prob.top_k, _checked_floor(floor)), first_chunk)
    if initial_samples is None:
        search.add_probes(search.evaluate_middle_design(n_initial))
    else:
        search.add_probes(search.sample_positions(initial_samples))
    heap = search.probe_designs()
    search.best_first(heap, n_new)
    return prob.result("culling", time.perf_counter() - t0, search.top.keys, search.exact_designs, search.probes)


def _checked_floor(floor) -> tuple[float, int] | None:
    """``floor`` as a ``(value, design id)`` pair, or a ValueError naming it."""
    if floor is None:
        return None
    try:
        floor = (float(floor[0]), int(floor[1]))
    except (TypeError, ValueError, IndexError):
        raise ValueError(f"floor must be a (value, design id) pair, got {floor!r}") from None
    if np.isnan(floor[0]):
        raise ValueError(f"floor value must not be nan, got {floor!r}")
    return floor


class _Culling:
    """The state of one ``culling_search`` and its steps (the module docstring's 1 to 4).

    ``probes`` are sample positions every live design is evaluated on, in the order they were
    chosen; ``seen_probes[p]`` how many of them design ``p`` has seen; ``order`` the samples,
    worst first for the last design evaluated exactly (the order the rest is taken in).
    """

    def __init__(self, prob: _Problem, top: TopK, first_chunk: int) -> None:
        self.prob, self.top, self.first_chunk = prob, top, first_chunk
        self.ids = prob.design_ids
        self.probes: list[int] = []
        self.in_probe = np.zeros(prob.S, bool)
        self.seen_probes = np.zeros(prob.D, np.int64)
        self.alive = np.ones(prob.D, bool)
        self.order = _range(prob.S)                   # samples by priority (ties by position)
        self.exact_designs = 0

    # -- probes ------------------------------------------------------------------------
    def add_probes(self, spos: np.ndarray) -> None:
        self.probes.extend(spos.tolist())
        self.in_probe[spos] = True

    def pick_probes(self, state, spos: np.ndarray, a, b, infeas, count: int,
                    key: np.ndarray | None = None) -> np.ndarray:
        """Up to ``count`` of ``spos`` that would lower the bound of ``state``, worst first (by
        ``key``, default ``badness``; ties by place in ``spos``)."""
        prob = self.prob
        if key is None:
            key = prob.badness(a, b, infeas)
        helps = prob.bound_if_added(state, a, b, infeas) < prob._bound(*state)
        return spos[_first_in_order(key, helps, count)]

    def sample_positions(self, initial_samples) -> np.ndarray:
        """Positions in ``samples`` of the ids ``initial_samples``, or a ValueError naming them."""
        prob = self.prob
        init = _ids("initial_samples", np.asarray(initial_samples), "samples")
        if prob.sample_ids is _range(prob.S):       # samples 0 .. S-1: an id is its position
            bad = (init < 0) | (init >= prob.S)
            if bad.any():
                raise ValueError(f"initial_samples must be ids among samples, got {init[bad][0]}")
            return init
        lookup = np.argsort(prob.sample_ids)
        where = np.minimum(np.searchsorted(prob.sample_ids, init, sorter=lookup), prob.S - 1)
        found = prob.sample_ids[lookup[where]] == init
        if not found.all():
            raise ValueError(f"initial_samples must be ids among samples, got {init[~found][0]}")
        return lookup[where]

    def evaluate_middle_design(self, n_initial: int) -> np.ndarray:
        """Step 1: the middle design evaluated exactly; its ``n_initial`` worst samples, the first probes."""
        prob, p = self.prob, self.prob.D // 2
        a, b, infeas = prob.block(np.array([p]), _range(prob.S))
        b0 = None if b is None else b[0]
        key = prob.badness(a[0], b0, infeas[0])
        new = self.pick_probes(prob.state(p), _range(prob.S), a[0], b0, infeas[0], n_initial, key)
        prob.absorb(np.array([p]), a, b, infeas)
        self.top.add(prob.exact(np.array([p]))[0], self.ids[p])
        self.order = _argsort_ties_by(key)
        self.alive[p] = False
        self.exact_designs += 1
        return new

    def probe_designs(self) -> list[tuple[float, int]]:
        """Step 2: every live design on the probes; the heap ``(-bound, position)`` of those left.

        The probes go in groups of doubling size (1, 2, 4, ...), and the designs whose bound
        has fallen below the K-th best are culled between groups: with a floor from earlier
        chunks most designs fail on the first probe or two and never see the rest. A bound from
        a prefix of the probes is an upper bound like any other, and ``seen_probes`` records
        the prefix, so ``best_first`` evaluates a design's remaining probes before it is a
        candidate. Without a K-th best yet nothing can be culled: all probes in one call
        (fewer, larger calls; and evaluators whose last bit depends on the call's size, like
        the zonotope's, keep agreeing with brute force where they did).
        """
        prob, top, ids = self.prob, self.top, self.ids
        live = np.flatnonzero(self.alive & ~top.cullable_array(prob.bound(np.arange(prob.D)), ids))
        done_p, group = 0, (1 if top.threshold is not None else max(1, len(self.probes)))
        while done_p < len(self.probes) and live.size:
            spos = np.asarray(self.probes[done_p:done_p + group], np.int64)
            rows = max(1, BLOCK_PAIRS // spos.size)
            for start in range(0, live.size, rows):
                dpos = live[start:start + rows]
                prob.absorb(dpos, *prob.block(dpos, spos))
            done_p += spos.size
            self.seen_probes[live] = done_p
            group *= 2
            if top.threshold is not None and done_p < len(self.probes):
                live = live[~top.cullable_array(prob.bound(live), ids[live])]
        bounds = prob.bound(live)
        keep = ~top.cullable_array(bounds, ids[live])
        heap = list(zip((-bounds[keep]).tolist(), live[keep].tolist()))
        heapq.heapify(heap)
        return heap

    # -- candidates --------------------------------------------------------------------
    def next_rest(self, at: int, size: int) -> tuple[np.ndarray, int]:
        """The next ``size`` non-probe samples of ``order`` from position ``at``, and the position
        after them. A window of ``size + len(probes)`` positions holds at least ``size`` of them
        (or reaches the end of ``order``)."""
        window = self.order[at:at + size + len(self.probes)]
        free = ~self.in_probe[window]
        cum = np.cumsum(free)
        used = int(np.searchsorted(cum, size)) + 1 if cum.size and cum[-1] >= size else window.size
        return window[:used][free[:used]], at + used

    def best_first(self, heap: list[tuple[float, int]], n_new: int) -> None:
        """Steps 2 to 4: the design with the highest bound first, until no bound can enter the top K.

        A bound older than the newest probes is brought up to date first; a current one makes
        the design a candidate (``evaluate_candidate``), whose samples that lowered its bound
        become new probes.
        """
        prob, top, ids = self.prob, self.top, self.ids
        while heap:
            negu, p = heap[0]
            if top.cullable(-negu, int(ids[p])):
                break                               # the highest bound cannot enter: nor can the rest
            heapq.heappop(heap)
            one = np.array([p])
            if self.seen_probes[p] < len(self.probes):        # stale bound: the newer probes first
                spos = np.asarray(self.probes[self.seen_probes[p]:], np.int64)
                prob.absorb(one, *prob.block(one, spos))
                self.seen_probes[p] = len(self.probes)
                u = prob.bound(one)[0]
                if not top.cullable(u, int(ids[p])):
                    heapq.heappush(heap, (-u, p))
                continue
            before = prob.state(p)                  # what the probes alone said
            spos, a, b, infeas, key = self.evaluate_candidate(p)
            # probes: what lowered this candidate's bound below what the probes said
            self.add_probes(self.pick_probes(before, spos, a, b, infeas, n_new, key) if spos.size else spos)

    def evaluate_candidate(self, p: int):
        """Step 3: the rest of the workspace for design position ``p``, worst first, in doubling
        chunks, stopping once it cannot enter the top K; exact designs enter it (step 4).

        The rest is ``order`` without the probes, taken a chunk at a time (``next_rest``): most
        candidates are culled on their first chunk, and filtering and sorting all S samples for
        each of thousands of candidates cost more than evaluating them. Returns the samples
        evaluated, their values and, for an exact design, their ``badness`` (else None)
        ``(spos, a, b, infeas, key)``.
        """
        prob, top, ids = self.prob, self.top, self.ids
        one = np.array([p])
        parts: list[tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray]] = []
        n_rest = prob.S - len(self.probes)
        done, chunk, culled, at = 0, self.first_chunk, False, 0
        while done < n_rest:
            size = chunk if top.threshold is not None else n_rest - done
            spos, at = self.next_rest(at, size)
            a, b, infeas = prob.block(one, spos)
            parts.append((spos, a[0], None if b is None else b[0], infeas[0]))
            done += spos.size
            chunk *= 2
            prob.absorb(one, a, b, infeas)
            if done < n_rest and top.cullable(prob.bound(one)[0], int(ids[p])):
                culled = True                   # early exit: cannot enter the top K
                break
        spos = np.concatenate([q[0] for q in parts]) if parts else np.zeros(0, np.int64)
        a = np.concatenate([q[1] for q in parts]) if parts else np.zeros(0)
        b = (np.concatenate([q[2] for q in parts]) if parts else np.zeros(0)) if prob.ratio else None
        infeas = np.concatenate([q[3] for q in parts]) if parts else np.zeros(0, bool)
        key = None
        if not culled:
            top.add(prob.exact(one)[0], int(ids[p]))
            self.exact_designs += 1
            if spos.size:
                key = prob.badness(a, b, infeas)
                order_key = np.full(prob.S, np.inf)
                order_key[spos] = key
                self.order = _argsort_ties_by(order_key)
        return spos, a, b, infeas, key
