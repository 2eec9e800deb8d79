"""Search results and their ranking: what every search (culling, brute force, count) returns.

``ranking`` orders designs best first (value descending, then id ascending); ``TopK`` keeps
a search's K best and its culling threshold; ``merge_top_k`` combines searches over disjoint
design subsets into the global top K (exact; proof in ``metrics.design.culling``).
"""
from __future__ import annotations

import bisect
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

#: A per-sample value that rules its design out whatever the ``infeasible`` rule says (a
#: constraint such as ``max_apparent_mass``): the most negative finite float. In the min form
#: ``F = VETO`` then ranks after every design with a real value and before a design with no
#: feasible sample (``-inf``); the ratio form gives ``F = VETO`` whatever the denominator
#: (``metrics.design.culling``). A count is vetoed by ``inf`` instead (``metrics.design.count``).
VETO = -float(np.finfo(np.float64).max)


@dataclass(frozen=True, eq=False)
class SearchResult:
    """Outcome of a search. Unpacks as ``value, design, evaluations, seconds``.

    ``top_designs`` / ``top_values`` (K,) list the best designs, best first, with exact
    values (fewer than ``top_k`` when there are fewer designs, or when a ``floor`` culled
    them). ``evaluations`` counts (design, sample) pairs passed to the evaluator.
    ``exact_designs`` is how many designs were evaluated on the whole workspace; ``probes``
    are the sample ids culling used as probes (worst samples, in the order found): good
    ``initial_samples`` for a related run or another worker.
    """

    value: float
    design: int
    evaluations: int
    seconds: float
    top_designs: np.ndarray
    top_values: np.ndarray
    n_designs: int
    n_samples: int
    method: str
    exact_designs: int
    probes: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))

    def __iter__(self):
        return iter((self.value, self.design, self.evaluations, self.seconds))

    @property
    def pairs(self) -> int:
        """Number of (design, sample) pairs: what brute force evaluates.

        Returns
        -------
        int
        """
        return self.n_designs * self.n_samples

    @property
    def evaluation_fraction(self) -> float:
        """``evaluations / (n_designs * n_samples)``: 1 for brute force.

        Returns
        -------
        float
            0 for an empty problem.
        """
        return self.evaluations / self.pairs if self.pairs else 0.0

    @property
    def kth(self) -> tuple[float, int] | None:
        """``(value, design)`` of the last listed design: a ``floor`` for later chunks.

        Returns
        -------
        (float, int) or None
            None when no design is listed.
        """
        if len(self.top_designs) == 0:
            return None
        return float(self.top_values[-1]), int(self.top_designs[-1])


def ranking(values: ArrayLike, designs: ArrayLike) -> np.ndarray:
    """Indices that sort designs best first: ``values`` descending, then ``designs`` ascending.

    ``values`` must hold no ``nan`` (objectives never do).

    Parameters
    ----------
    values : array_like, shape (k,)
        Objective values (larger is better).
    designs : array_like of int, shape (k,)
        Design ids (tie-break: smaller first).

    Returns
    -------
    ndarray of int, shape (k,)
        Positions into ``values``, best first.

    Examples
    --------
    >>> ranking([1.0, 3.0, 3.0, 2.0], [0, 5, 2, 1]).tolist()
    [2, 1, 3, 0]
    """
    values = np.asarray(values, dtype=np.float64)
    designs = np.asarray(designs, dtype=np.int64)
    return np.lexsort((designs, -values))


class TopK:
    """The K best exactly evaluated designs of a search, and the threshold that culls the rest.

    Keys are ``(-value, id)`` in ascending order, so the first key is the best design (ties:
    the smaller id first, ``ranking``'s order). ``floor`` ``(value, id)``, e.g. the K-th best of
    chunks already searched (``SearchResult.kth``), culls from the start; once K designs
    are in, the threshold is the better-ranked of the K-th key and the floor, and a design
    is ``cullable`` when even its upper bound ranks after the threshold. Used by ``culling_search`` and
    ``metrics.design.count.count_search``.

    Parameters
    ----------
    k : int
        Designs to keep.
    floor : (float, int) or None
        ``(value, design)`` a listed design must beat, or None.

    Examples
    --------
    >>> top = TopK(2, None)
    >>> top.add(3.0, 5); top.add(1.0, 0)
    >>> top.keys
    [(-3.0, 5), (-1.0, 0)]
    >>> top.cullable(1.0, 0), top.cullable(1.0, 1)     # a tie goes to the smaller id
    (False, True)
    """

    def __init__(self, k: int, floor: tuple[float, int] | None) -> None:
        self.k = k
        self.keys: list[tuple[float, int]] = []
        self.floor = None if floor is None else (-float(floor[0]), int(floor[1]))
        self.threshold = self.floor

    def add(self, value: float, design: int) -> None:
        """List an exactly evaluated design, keep the K best and update the threshold.

        Parameters
        ----------
        value : float
            The design's exact objective.
        design : int
            Its id.

        Returns
        -------
        None
        """
        bisect.insort(self.keys, (-float(value), int(design)))
        del self.keys[self.k:]
        if len(self.keys) == self.k:
            kth = self.keys[-1]
            self.threshold = kth if self.floor is None else min(kth, self.floor)

    def cullable(self, bound: float, design: int) -> bool:
        """Whether a design with upper bound ``bound`` ranks after the threshold key.

        Parameters
        ----------
        bound : float
            An upper bound of the design's objective.
        design : int
            Its id.

        Returns
        -------
        bool
            False while there is no threshold.
        """
        return self.threshold is not None and (-bound, design) > self.threshold

    def cullable_array(self, bounds: np.ndarray, designs: np.ndarray) -> np.ndarray:
        """``cullable`` for many designs at once.

        Parameters
        ----------
        bounds : ndarray, shape (k,)
            Upper bounds of the designs' objectives.
        designs : ndarray of int, shape (k,)
            Their ids.

        Returns
        -------
        ndarray of bool, shape (k,)
        """
        if self.threshold is None:
            return np.zeros(bounds.shape, bool)
        neg, tid = self.threshold
        t = -neg
        return (bounds < t) | ((bounds == t) & (designs > tid))


def merge_top_k(results: Iterable[SearchResult], top_k: int | None = None) -> SearchResult:
    """Global top K from results over disjoint design subsets of one problem.

    Exact when each part holds its subset's top K exactly (what ``culling_search`` and
    ``brute_force`` return), or was culled against a ``floor`` taken from parts that are
    merged too; proof in the module docstring. ``top_k`` defaults to the longest list and
    must not exceed the K the parts were searched with.
    ``evaluations``, ``seconds`` (work, not wall time), ``n_designs`` and ``exact_designs``
    are summed; ``probes`` are the parts' probes in order, without repeats.

    Parameters
    ----------
    results : iterable of SearchResult
        Searches of one workspace over disjoint design subsets.
    top_k : int, optional
        Designs to list.

    Returns
    -------
    SearchResult
        ``method`` is ``"merged(...)"`` naming the parts' methods.
    """
    parts = list(results)
    if not parts:
        raise ValueError("results must hold at least one SearchResult, got none")
    if len({r.n_samples for r in parts}) != 1:
        raise ValueError(f"results must share one workspace, got n_samples {sorted({r.n_samples for r in parts})}")
    k = max(len(r.top_designs) for r in parts) if top_k is None else top_k
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
        raise ValueError(f"top_k must be a positive integer, got {top_k!r}")
    designs = np.concatenate([r.top_designs for r in parts]).astype(np.int64)
    values = np.concatenate([r.top_values for r in parts]).astype(np.float64)
    if np.unique(designs).size != designs.size:
        raise ValueError("results must come from disjoint design subsets; a design id appears twice")
    order = ranking(values, designs)[:k]
    top_designs, top_values = designs[order], values[order]
    probes = np.concatenate([r.probes for r in parts]).astype(np.int64)
    _, first = np.unique(probes, return_index=True)
    methods = sorted({r.method for r in parts})
    return SearchResult(
        value=float(top_values[0]) if order.size else float("nan"),
        design=int(top_designs[0]) if order.size else -1,
        evaluations=sum(r.evaluations for r in parts), seconds=sum(r.seconds for r in parts),
        top_designs=top_designs, top_values=top_values,
        n_designs=sum(r.n_designs for r in parts), n_samples=parts[0].n_samples,
        method="merged(" + ",".join(methods) + ")", exact_designs=sum(r.exact_designs for r in parts),
        probes=probes[np.sort(first)])
