"""Error against run time: how a map's global figures depend on its resolution.

Two tools, both headless (numpy/scipy only):

``convergence_study``
    Runs ``compute_map`` at a ladder of resolutions and records, for every rung, the wall
    time, the point counts, every global figure (min, max, mean, SD of each quantity) and its
    error, absolute and relative, against the finest run (the reference). Where an exact
    value exists it is used as well: the global min and max of each quantity are located by
    ``refine_global_minimum`` / ``refine_global_maximum`` to a tolerance far below the grid
    spacing, so ``exact_errors`` are true errors, not differences between two grids. A
    reciprocal (``RECIPROCALS``: 1 / condition number) studied beside its source has its
    extremes read off the source's (``reciprocal_refinement``), not searched for again.
    Only statistics are kept: each map is dropped before the next rung runs, so a
    2000 x 2000 ladder needs the memory of one map, not of the whole ladder. The reference
    runs first, and the exact searches, which need its figures, run beside the coarser rungs.

``refine_global_minimum`` / ``refine_global_maximum`` (``metrics.refine``)
    Branch and bound on a quadtree (octree in 3D) over the grid's box, to a tolerance far
    below the grid spacing; ``metrics.refine`` says what its "certified" means.

Ladder convention: a rung ``n`` puts ``n`` points on the grid's longest axis (the axis with
most points in the preset) and scales the others in proportion to the preset's own
resolution (at least 2), so the ladder keeps the preset's aspect: the Inverse3 slice
(1000 x 1000) gives ``n x n``, the five-bar half plane (521 x 261) about ``n x n/2``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from kinematics.validation import positive_finite

from .quantities import QUANTITIES, STATS_QUANTITIES

# Refinement and the refine_* functions are re-exported: callers find them beside the study.
from .refine import (  # noqa: F401
    Refinement,
    check_scalar_quantities,
    finite_or_none,
    ladder_resolution,
    refine_global_maximum,
    refine_global_minimum,
)
from .workspace import GridSpec, compute_map

#: Points on the longest axis of each rung of the default ladder.
DEFAULT_LADDER = (50, 100, 200, 500, 1000, 2000)
#: The global figures of every quantity, in table order.
FIGURES = ("min", "max", "mean", "sd", "median", "p05", "p95")


def resolution_label(resolution) -> str:
    """``"200 x 100"``: a grid's points per axis.

    Parameters
    ----------
    resolution : sequence of int
        Points per axis.

    Returns
    -------
    str

    Examples
    --------
    >>> resolution_label((200, 100))
    '200 x 100'
    """
    return " x ".join(str(int(r)) for r in resolution)


# -- the convergence study ------------------------------------------------------------------

@dataclass(frozen=True)
class ConvergenceRow:
    """One rung: its size, run time, global figures and their errors.

    ``figures[q][f]`` is figure ``f`` (min, max, mean, sd) of quantity ``q``;
    ``abs_errors``/``rel_errors`` compare it with the reference run (relative to
    ``|reference|``); ``exact_errors[q][f]`` is ``|figure - exact|`` for min and max where
    a usable exact value exists. Missing or non-finite errors are ``nan``.
    """

    resolution: tuple[int, ...]
    points: int
    feasible_points: int
    seconds: float
    figures: dict[str, dict[str, float]]
    abs_errors: dict[str, dict[str, float]]
    rel_errors: dict[str, dict[str, float]]
    exact_errors: dict[str, dict[str, float]]
    is_reference: bool = False

    def to_dict(self) -> dict:
        """A JSON-ready dict of the rung (non-finite figures and errors are None).

        Returns
        -------
        dict
            ``resolution``, point counts, ``seconds``, ``is_reference`` and, per quantity and
            figure, ``value``, ``abs_error``, ``rel_error`` and ``exact_error``.
        """
        q = {}
        for name, figs in self.figures.items():
            q[name] = {f: {"value": finite_or_none(figs[f]),
                           "abs_error": finite_or_none(self.abs_errors[name][f]),
                           "rel_error": finite_or_none(self.rel_errors[name][f]),
                           "exact_error": finite_or_none(self.exact_errors[name].get(f))}
                       for f in FIGURES}
        return {"resolution": list(self.resolution), "points": self.points,
                "feasible_points": self.feasible_points, "seconds": self.seconds,
                "is_reference": self.is_reference, "quantities": q}


@dataclass(frozen=True)
class ExactFigure:
    """A global min or max located beyond the grid, and whether it can serve as the truth.

    ``status``: ``"certified"`` (refinement reached its tolerance ``tol``), ``"attained"``
    (the reference grid already holds ``inf``, e.g. a node on a singularity), ``"not
    certified"`` (budget ran out; ``value`` is only the best found), ``"contradicted"`` (a
    grid rung found a value beyond ``value`` by more than ``tol``: the refinement's local
    slope estimate failed, typically next to a singularity where the quantity is unbounded).
    Only the first two are used for ``exact_errors``.
    """

    figure: str
    value: float
    status: str
    tol: float
    note: str
    refinement: Refinement | None

    @property
    def usable(self) -> bool:
        """Whether the value can serve as the truth (``"certified"`` or ``"attained"``).

        Returns
        -------
        bool
        """
        return self.status in ("certified", "attained")

    def to_dict(self) -> dict:
        """A JSON-ready dict (non-finite numbers are None; the refinement as its own dict).

        Returns
        -------
        dict
        """
        return {"figure": self.figure, "value": finite_or_none(self.value), "status": self.status,
                "tol": finite_or_none(self.tol), "note": self.note,
                "refinement": self.refinement.to_dict() if self.refinement is not None else None}


def _error(value: float, ref: float) -> tuple[float, float]:
    """|value - ref| and that over |ref|; nan where either is not finite (or ref is 0)."""
    if not (math.isfinite(value) and math.isfinite(ref)):
        return math.nan, math.nan
    err = abs(value - ref)
    return err, (err / abs(ref) if ref != 0.0 else math.nan)


@dataclass(frozen=True)
class ConvergenceStudy:
    """The ladder's rows (coarse to fine), the reference row, exact extremes and fitted rates.

    ``rates[q][f]`` is ``p`` in ``error ~ n^-p`` (``n`` points on the longest axis), a
    least-squares fit over the non-reference rows with a finite non-zero error against the
    reference; nan with fewer than two such rows. A ``p`` near 0 or below means the figure
    does not converge (or the reference is no better than the rungs). ``exact_rates`` is
    the same fit against the usable exact values, over every row including the reference.
    """

    grid: GridSpec
    quantities: tuple[str, ...]
    rows: tuple[ConvergenceRow, ...]
    reference: ConvergenceRow
    exact: dict[str, dict[str, ExactFigure]]
    rates: dict[str, dict[str, float]]
    exact_rates: dict[str, dict[str, float]]
    units: dict[str, str]

    def exact_value(self, quantity: str, figure: str) -> float | None:
        """The usable exact value of a figure, or None.

        Parameters
        ----------
        quantity : str
            A quantity of the study.
        figure : str
            ``"min"`` or ``"max"`` (the figures that have exact values).

        Returns
        -------
        float or None
            In the quantity's unit.
        """
        ex = self.exact.get(quantity, {}).get(figure)
        return ex.value if ex is not None and ex.usable else None

    def to_dict(self) -> dict:
        """A JSON-ready dict (``json.dumps(..., allow_nan=False)`` works; nan/inf are None).

        Returns
        -------
        dict
            The grid (m), ladder note, quantities, units, reference, rows, exact figures and rates.
        """
        g = self.grid
        return {
            "grid": {"axes": list(g.axes), "lower": list(g.lower), "upper": list(g.upper),
                     "resolution": list(g.resolution), "fixed": {k: v for k, v in g.fixed}, "unit": "m"},
            "ladder": "rung n puts n points on the grid's longest axis; other axes scale with the grid's resolution",
            "quantities": list(self.quantities),
            "units": dict(self.units),
            "reference": self.reference.to_dict(),
            "rows": [r.to_dict() for r in self.rows],
            "exact": {q: {f: e.to_dict() for f, e in figs.items()} for q, figs in self.exact.items()},
            "rates": {q: {f: finite_or_none(p) for f, p in figs.items()} for q, figs in self.rates.items()},
            "exact_rates": {q: {f: finite_or_none(p) for f, p in figs.items()}
                            for q, figs in self.exact_rates.items()},
        }


def _fit_rate(ns: list[float], errs: list[float]) -> float:
    pairs = [(n, e) for n, e in zip(ns, errs) if math.isfinite(e) and e > 0.0]
    if len(pairs) < 2 or len({p[0] for p in pairs}) < 2:
        return math.nan
    x = np.log([p[0] for p in pairs])
    y = np.log([p[1] for p in pairs])
    return float(-np.polyfit(x, y, 1)[0])


#: Quantities that are one over another at every point (``metrics.quantities``: ``1.0 / value``, in
#: the compiled kernels as in numpy): a reciprocal's global min is one over its source's max, and
#: its max one over the source's min, so a study of both refines the source's extremes only.
RECIPROCALS = {"inverse_condition_number": "condition_number"}


def reciprocal_refinement(source: Refinement, quantity: str, tol: float) -> Refinement | None:
    """The opposite extreme of ``quantity`` = 1 / ``source.quantity``, read off ``source``; None where
    it cannot stand for a refinement of ``quantity`` to ``tol``.

    ``1 / x`` is decreasing for ``x > 0``: the source's max at ``point`` is the reciprocal's min there,
    and the source's bracket ``[value, bound]`` is the reciprocal's ``[1 / bound, 1 / value]``. Its
    value is the reciprocal's own value at that point (it is computed as ``1.0 / source``). It is
    certified when the source is and that bracket is within ``tol``; a certified source whose
    bracket is wider than ``tol`` (``tol`` relative to a reciprocal much smaller than one) gives
    None: the reciprocal is then refined on its own. An uncertified source gives an uncertified
    reciprocal with the bracket the source reached (its search ran out of budget or float64).

    Parameters
    ----------
    source : Refinement
        A refinement of ``RECIPROCALS[quantity]``.
    quantity : str
        The reciprocal.
    tol : float
        The tolerance ``quantity``'s extreme is wanted to.

    Returns
    -------
    Refinement or None
        ``sense`` opposite to the source's; ``evaluations`` 0 and ``seconds`` 0.0 (none of its own),
        the source's levels, coarse grid and finest spacing; no history.

    Examples
    --------
    >>> r = Refinement("condition_number", "max", 4.0, (0.1, 0.2), 4.0000001, 4e-5, True, 1000, 0.01, 5,
    ...                (64, 64), (1e-4, 1e-4))
    >>> d = reciprocal_refinement(r, "inverse_condition_number", 2.5e-6)
    >>> d.sense, d.value, d.certified, d.point
    ('min', 0.25, True, (0.1, 0.2))
    """
    if RECIPROCALS.get(quantity) != source.quantity or not (source.value > 0.0 and source.bound > 0.0):
        return None                     # not its reciprocal, or nothing feasible (nan), or a sign change
    value, bound = 1.0 / source.value, 1.0 / source.bound
    certified = source.certified and abs(bound - value) <= tol
    if source.certified and not certified:
        return None
    return Refinement(quantity=quantity, sense="max" if source.sense == "min" else "min", value=value,
                      point=source.point, bound=bound, tol=tol, certified=certified, evaluations=0, seconds=0.0,
                      levels=source.levels, coarse_resolution=source.coarse_resolution,
                      finest_spacing=source.finest_spacing)


def _exact_figure(figure: str, r: Refinement, rungs: list[tuple[tuple[int, ...], dict]], q: str,
                  source: Refinement | None = None) -> ExactFigure:
    """Judge a refinement against every grid rung: no grid point may beat a true extreme.

    ``source``: the refinement ``r`` was read off (``reciprocal_refinement``), whose cost the note gives.
    """
    if source is not None:
        note = (f"(+-{r.tol:.2g}; 1 / {source.quantity}'s {source.sense}: {source.evaluations:,} evaluations, "
                f"{source.seconds:.3f} s, coarse {resolution_label(source.coarse_resolution)}, {source.levels} levels)")
    else:
        note = (f"(+-{r.tol:.2g}; {r.evaluations:,} evaluations, {r.seconds:.3f} s, "
                f"coarse {resolution_label(r.coarse_resolution)}, {r.levels} levels)")
    if math.isinf(r.value):
        return ExactFigure(figure, r.value, "attained", 0.0,
                           f"(the refinement reached a node where {q} is {r.value}: a singularity; "
                           f"{r.evaluations:,} evaluations)", r)
    for res, figs in rungs:
        grid_value = figs[q][figure]
        beyond = grid_value < r.value - r.tol if figure == "min" else grid_value > r.value + r.tol
        if beyond:
            return ExactFigure(figure, r.value, "contradicted", r.tol,
                               f"by the {resolution_label(res)} grid ({grid_value:.7g}) " + note, r)
    if not r.certified:
        return ExactFigure(figure, r.value, "not certified", r.tol,
                           f"best found; the true {figure} lies between {r.bound:.7g} and it " + note, r)
    return ExactFigure(figure, r.value, "certified", r.tol, note, r)


class _Searches:
    """The study's exact searches, started once the reference's figures are known, on worker threads.

    A search needs the reference's figure (its tolerance is ``exact_rtol`` times it) and nothing
    of the coarser rungs, which therefore run meanwhile on the caller's thread: the Inverse3's
    default study spent 0.3 s in its searches after its maps, whose compiled passes keep the two
    cores of the machine it was measured on about 70 % busy (1.4 times one core on two). The
    searches start in the order the study lists them, one worker per core (a search's node
    bookkeeping is one thread's numpy: the two that run out of their budget, a third of a second
    each, run side by side; in one process at load 4.5-5.5 the default study took 1.73-1.90 s
    with two workers against 1.90-2.11 s with one, medians of 8). Each is the computation it
    was on the caller's thread (a compiled pass's serial and ``prange`` builds give the same
    numbers, ``metrics.kernels.jit``): the same values, evaluations and levels. Only the seconds
    share the cores: a search's, and those of the rungs that ran beside it.

    A reciprocal's extreme (``RECIPROCALS``) whose source is searched is not submitted: ``judge``
    reads it off the source's result (``reciprocal_refinement``), or searches it there when it
    cannot, as the study did one search after another.
    """

    def __init__(self, mechanism, grid: GridSpec, names: tuple[str, ...], ref_figs: dict, exact_rtol: float,
                 budget: int, coarse_resolution) -> None:
        import os
        from concurrent.futures import ThreadPoolExecutor

        self._search_args = (mechanism, grid, coarse_resolution, budget)
        self._pool = ThreadPoolExecutor(max_workers=os.cpu_count() or 1, thread_name_prefix="isoforce-exact")
        #: (quantity, figure, value or tol, future, deferred) in the study's order.
        self.plan: list[tuple[str, str, float, object, bool]] = []
        may_search: set[tuple[str, str]] = set()
        # A reciprocal's extremes last: they are read off its source's refinements when the study has them.
        self.order = sorted(names, key=lambda n: RECIPROCALS.get(n) in names)
        for q in self.order:
            for f in ("min", "max"):
                value = ref_figs[q][f]
                if math.isinf(value):
                    self.plan.append((q, f, value, None, False))
                    continue
                if not math.isfinite(value):
                    continue   # nan: nothing feasible
                tol = exact_rtol * max(abs(value), np.finfo(float).tiny)
                deferred = (RECIPROCALS.get(q), "max" if f == "min" else "min") in may_search
                self.plan.append((q, f, tol, None if deferred else self._submit(q, f, tol), deferred))
                may_search.add((q, f))

    def _submit(self, q: str, f: str, tol: float):
        mechanism, grid, coarse_resolution, budget = self._search_args
        return self._pool.submit(_search, f, mechanism, grid, q, tol, coarse_resolution, budget)

    def judge(self, rungs: list[tuple[tuple[int, ...], dict]],
              progress: Callable[[str], None] | None) -> dict[str, dict[str, ExactFigure]]:
        """Every search's result judged against the ``rungs`` (coarse to fine, ``_exact_figure``), by quantity."""
        exact: dict[str, dict[str, ExactFigure]] = {q: {} for q in self.order}
        refined: dict[tuple[str, str], Refinement] = {}
        for q, f, tol, future, deferred in self.plan:
            figures = exact[q]
            if math.isinf(tol):
                figures[f] = ExactFigure(f, tol, "attained", 0.0,
                                         "(unbounded: the mechanism's singularity analysis puts a singularity "
                                         "in the feasible set's closure)", None)
                continue
            source = refined.get((RECIPROCALS.get(q), "max" if f == "min" else "min")) if deferred else None
            r = reciprocal_refinement(source, q, tol) if source is not None else None
            if r is None:
                source = None
                if progress is not None:
                    progress(f"refine {f} {q}")
                r = (future if future is not None else self._submit(q, f, tol)).result()
                refined[q, f] = r
            figures[f] = _exact_figure(f, r, rungs, q, source)
        return exact

    def close(self) -> None:
        """Cancel the searches not started and wait for those running (each bounded by its budget)."""
        self._pool.shutdown(wait=True, cancel_futures=True)


def _search(figure: str, mechanism, grid: GridSpec, q: str, tol: float, coarse_resolution, budget: int) -> Refinement:
    """``refine_global_minimum`` or ``_maximum`` (looked up when called: a test may wrap them)."""
    refine = refine_global_minimum if figure == "min" else refine_global_maximum
    return refine(mechanism, grid, q, tol=tol, coarse_resolution=coarse_resolution, max_evaluations=budget)


def convergence_study(mechanism, grid: GridSpec, quantities=STATS_QUANTITIES, resolutions=DEFAULT_LADDER, *,
                      reference_resolution: int | None = None, exact_rtol: float | None = 1e-5,
                      exact_budget: int = 600_000, coarse_resolution: int = 64,
                      progress: Callable[[str], None] | None = None,
                      map_progress: Callable[[float], None] | None = None) -> ConvergenceStudy:
    """Run ``grid``'s map at each rung of ``resolutions`` and compare every global figure.

    Memory: each map is reduced to its statistics and dropped before the next rung runs.
    Order: the reference runs first; the exact searches then run on worker threads beside the
    coarser rungs (``_Searches``), so those rungs' seconds and the searches' share the cores
    (the figures are the same whatever the order and the threads).

    Parameters
    ----------
    mechanism : Mechanism
        A kinematics model.
    grid : GridSpec
        The map; its box and fixed coordinates are kept, its resolution sets the aspect.
    quantities : sequence of str
        Scalar map quantities (default: condition number, anisotropic and isotropic force).
    resolutions : sequence of int
        Points on the longest axis of each rung (see the module notes); at least two unless
        ``reference_resolution`` is given.
    reference_resolution : int, optional
        Run the reference at this rung instead of the finest of ``resolutions``; it must be
        finer than every rung.
    exact_rtol : float or None
        Locate the global min and max of each quantity by ``refine_global_minimum`` /
        ``refine_global_maximum`` to ``exact_rtol * |reference figure|`` (None: skip). A
        figure already infinite on the reference grid is exact as it stands. A reciprocal's
        (``RECIPROCALS``) are its source's, when the study refines those (``reciprocal_refinement``).
    exact_budget : int
        ``max_evaluations`` of each of those refinements.
    coarse_resolution : int
        Their coarse grid (points on the longest axis).
    progress : callable, optional
        Called with a short message before each step (for a command line's stderr).
    map_progress : callable ``(float) -> None``, optional
        Called with the share of all the rungs' map points done, as the maps run.

    Returns
    -------
    ConvergenceStudy
        The rows coarse to fine, the reference row, the exact extremes and the fitted rates.
    """
    names = check_scalar_quantities(mechanism, quantities)
    if isinstance(resolutions, (int, np.integer)):
        resolutions = (resolutions,)
    try:
        ladder = sorted({int(n) for n in resolutions})
    except (TypeError, ValueError):
        raise ValueError(f"resolutions must be integers (points on the longest axis), got {resolutions!r}") from None
    if not ladder:
        raise ValueError("resolutions needs at least one rung, got none")
    if reference_resolution is None and len(ladder) < 2:
        raise ValueError(f"resolutions needs at least two rungs (the finest is the reference), got {ladder!r}")
    for n in ladder:
        ladder_resolution(grid, n)
    if reference_resolution is not None:
        ladder_resolution(grid, reference_resolution)
        if reference_resolution <= ladder[-1]:
            raise ValueError(f"reference_resolution must exceed every rung ({ladder[-1]}), got {reference_resolution}")
    if exact_rtol is not None:
        exact_rtol = positive_finite("exact_rtol", exact_rtol)

    maps = [ladder_resolution(grid, n)
            for n in ladder + ([int(reference_resolution)] if reference_resolution is not None else [])]
    raw: list = [None] * len(maps)
    total, done = sum(math.prod(r) for r in maps), 0
    searches = None
    try:
        # The reference first: the exact searches need its figures (their tolerances), and they run
        # on worker threads while the coarser rungs run here (see ``_Searches``).
        for i in [len(maps) - 1, *range(len(maps) - 1)]:
            res = maps[i]
            if progress is not None:
                progress(f"map {resolution_label(res)}")
            share = None if map_progress is None else (
                lambda f, done=done, n=math.prod(res): map_progress((done + f * n) / total))
            # Statistics only, streamed: memory does not grow with the rung's resolution.
            wmap = compute_map(mechanism, grid.with_resolution(res), names, keep=False, progress=share)
            done += math.prod(res)
            raw[i] = (res, math.prod(res), wmap.feasible_points, float(wmap.seconds),
                      {q: {f: getattr(wmap.stats[q], f) for f in FIGURES} for q in names})
            del wmap
            if i == len(maps) - 1 and exact_rtol is not None:
                searches = _Searches(mechanism, grid, names, raw[i][4], exact_rtol, exact_budget, coarse_resolution)
        ref_figs = raw[-1][4]
        exact: dict[str, dict[str, ExactFigure]] = {}
        if searches is not None:
            exact = searches.judge([(res, figs) for res, _, _, _, figs in raw], progress)
    finally:
        if searches is not None:
            searches.close()
    exact = {q: exact[q] for q in names if q in exact}           # the study's order

    rows = []
    for i, (res, points, feas, sec, figs) in enumerate(raw):
        abs_e: dict[str, dict[str, float]] = {}
        rel_e: dict[str, dict[str, float]] = {}
        ex_e: dict[str, dict[str, float]] = {}
        for q in names:
            abs_e[q], rel_e[q], ex_e[q] = {}, {}, {}
            for f in FIGURES:
                abs_e[q][f], rel_e[q][f] = _error(figs[q][f], ref_figs[q][f])
            for f, e in exact.get(q, {}).items():
                if e.usable:
                    ex_e[q][f] = 0.0 if figs[q][f] == e.value else _error(figs[q][f], e.value)[0]
        rows.append(ConvergenceRow(res, points, feas, sec, figs, abs_e, rel_e, ex_e, is_reference=i == len(raw) - 1))
    reference = rows[-1]
    if reference_resolution is not None:
        rows = rows[:-1]
    rungs_only = [r for r in rows if not r.is_reference]
    rates = {q: {f: _fit_rate([max(r.resolution) for r in rungs_only], [r.abs_errors[q][f] for r in rungs_only])
                 for f in FIGURES} for q in names}
    everything = list(rows) + ([reference] if reference_resolution is not None else [])
    exact_rates = {q: {f: _fit_rate([max(r.resolution) for r in everything],
                                    [r.exact_errors[q].get(f, math.nan) for r in everything])
                       for f, e in exact.get(q, {}).items() if e.usable} for q in names}
    units = {q: QUANTITIES[q].unit for q in names}
    return ConvergenceStudy(grid=grid, quantities=names, rows=tuple(rows), reference=reference, exact=exact,
                            rates=rates, exact_rates=exact_rates, units=units)


# -- refinement against the uniform grid ----------------------------------------------------

@dataclass(frozen=True)
class UniformMatch:
    """The coarsest rung from which every finer rung is within ``tol`` of ``exact``.

    ``lucky`` lists coarser rungs that are within ``tol`` too but are followed by a finer
    rung that is not (a node happened to fall near the extreme). When no rung qualifies,
    ``extrapolated`` is True and ``resolution``/``points``/``seconds`` are an estimate from
    the finest rung with ``error ~ n^-rate``: ``rate`` is fitted to the rows' errors against
    ``exact`` (clamped to [0.25, 2]; 1 when it cannot be fitted), time scales with points.
    """

    quantity: str
    figure: str
    tol: float
    exact: float
    resolution: tuple[int, ...] | None
    points: int | None
    seconds: float | None
    error: float | None
    extrapolated: bool
    lucky: tuple[tuple[int, ...], ...] = ()
    finest_error: float = math.nan
    rate: float = math.nan

    def to_dict(self) -> dict:
        """A JSON-ready dict (non-finite numbers are None, resolutions as lists).

        Returns
        -------
        dict
        """
        return {"quantity": self.quantity, "figure": self.figure, "tol": self.tol,
                "exact": finite_or_none(self.exact),
                "resolution": list(self.resolution) if self.resolution is not None else None,
                "points": self.points, "seconds": self.seconds, "error": finite_or_none(self.error),
                "extrapolated": self.extrapolated, "lucky": [list(r) for r in self.lucky],
                "finest_error": finite_or_none(self.finest_error), "rate": finite_or_none(self.rate)}


def uniform_grid_for(study: ConvergenceStudy, quantity: str, *, exact: float, tol: float,
                     figure: str = "min") -> UniformMatch:
    """The uniform rung of ``study`` that reaches ``|figure - exact| <= tol`` for good.

    Every rung counts, the reference included (rows sorted by points). The cost of a rung is
    its point count (``compute_map`` evaluates every grid point) and its ``seconds``.

    Parameters
    ----------
    study : ConvergenceStudy
        A finished study.
    quantity : str
        One of ``study.quantities``.
    exact : float
        The true figure, in the quantity's unit.
    tol : float
        The error to reach, same unit, > 0.
    figure : str
        One of ``FIGURES``.

    Returns
    -------
    UniformMatch
        The rung, or an extrapolated one when no rung qualifies.
    """
    tol = positive_finite("tol", tol)
    if quantity not in study.quantities:
        raise ValueError(f"quantity {quantity!r} is not in the study; it has {', '.join(study.quantities)}")
    if figure not in FIGURES:
        raise ValueError(f"figure must be one of {', '.join(FIGURES)}, got {figure!r}")
    rows = list(study.rows) + ([] if study.reference in study.rows else [study.reference])
    rows.sort(key=lambda r: r.points)
    errs = [abs(r.figures[quantity][figure] - exact) if math.isfinite(r.figures[quantity][figure]) else math.inf
            for r in rows]
    ok = [e <= tol for e in errs]
    first = None
    for i in range(len(rows) - 1, -1, -1):
        if not ok[i]:
            break
        first = i
    if first is not None:
        r = rows[first]
        lucky = tuple(rows[i].resolution for i in range(first) if ok[i])
        return UniformMatch(quantity, figure, tol, exact, r.resolution, r.points, r.seconds, errs[first], False,
                            lucky, finest_error=errs[-1])
    lucky = tuple(rows[i].resolution for i in range(len(rows)) if ok[i])
    finest = rows[-1]
    e = errs[-1]
    if not (math.isfinite(e) and e > 0.0):
        return UniformMatch(quantity, figure, tol, exact, None, None, None, None, True, lucky, finest_error=e)
    rate = _fit_rate([max(r.resolution) for r in rows], errs)
    rate = 1.0 if not math.isfinite(rate) else min(2.0, max(0.25, rate))
    factor = (e / tol) ** (1.0 / rate)
    res = tuple(max(2, int(math.ceil(n * factor))) for n in finest.resolution)
    points = int(math.prod(res))
    seconds = finest.seconds * points / finest.points
    return UniformMatch(quantity, figure, tol, exact, res, points, seconds, tol, True, lucky,
                        finest_error=e, rate=rate)
