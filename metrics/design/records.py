"""How results are recorded and reported: per-design records, the study result, the [report] answers.

The [report] table
------------------
``reference``: one design's exact value; ``target`` = that value within ``tolerance``
(relative). ``smallest``: the smallest value of the named grid parameter at which a design
reaches the target (``first_reaching``: exact, no monotonicity assumed). ``checks``: designs
(on the grid or not) evaluated exactly and compared with the reference.

What the results hold
---------------------
Every design gets a record: ``exact`` designs were evaluated on the whole workspace and
carry their value; culled designs carry the bound the search had when it dropped them
(``min_isotropic_force``, ``gii``: an *upper* bound of the value; count: a *lower* bound of
the count), with the number of samples it came from. ``over_bound`` marks the designs in
which the search met a sample over the study's ``max_apparent_mass`` (a ``VETO``): every such
design under ``brute_force``; under culling, those of them it looked at closely enough (a
design the objective culls first is not looked at further).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .evaluators import Evaluator, evaluator_for
from .ranking import VETO
from .study import Study


def _ratio(num, den):
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = num / den
    return np.where(num == VETO, VETO, np.where((num == 0.0) | (den == np.inf), 0.0, r))


class Recorder:
    """Wraps an evaluator and keeps, per design of a chunk, the running min (max) and the number
    of samples seen, with ``metrics.design.culling``'s conventions for infeasible samples. After the
    search, ``records()`` gives each design's exact value (all samples seen) or bound."""

    def __init__(self, evaluate, design_ids: np.ndarray, n_samples: int, form: str, infeasible: str) -> None:
        self.evaluate = evaluate
        self.ids = np.asarray(design_ids, np.int64)
        self.S = n_samples
        self.form = form
        self.fail = infeasible == "fail"
        n = self.ids.size
        self.A = np.full(n, np.inf)
        self.B = np.zeros(n)
        self.sum = np.zeros(n)
        self.seen = np.zeros(n, np.int64)
        self.feasible_seen = np.zeros(n, bool)
        self.bad = np.zeros(n, bool)
        self.over = np.zeros(n, bool)

    def __call__(self, design_ids, sample_ids):
        out = self.evaluate(design_ids, sample_ids)
        loc = np.searchsorted(self.ids, design_ids)
        self.seen[loc] += len(sample_ids)
        if self.form == "sum":
            counts = np.asarray(out, float)
            self.sum[loc] += counts.sum(axis=1)
            self.over[loc] |= (counts == np.inf).any(axis=1)
            return out
        if self.form == "ratio":
            a, b = (np.asarray(v, float) for v in out)
            infeas = np.isnan(a) | (a == -np.inf) | np.isnan(b) | (b == -np.inf)
            self.B[loc] = np.maximum(self.B[loc], np.where(infeas, 0.0, b).max(axis=1, initial=0.0))
        else:
            a = np.asarray(out, float)
            infeas = np.isnan(a) | (a == -np.inf)
        self.A[loc] = np.minimum(self.A[loc], np.where(infeas, np.inf, a).min(axis=1, initial=np.inf))
        self.over[loc] |= (~infeas & (a == VETO)).any(axis=1)
        self.feasible_seen[loc] |= ~infeas.all(axis=1)
        self.bad[loc] |= infeas.any(axis=1)
        return out

    def records(self) -> dict[str, np.ndarray]:
        """``design``, ``exact`` (bool), ``value`` (a count for the sum form; exact, or the bound
        where not exact; ``VETO`` or an ``inf`` count when vetoed), ``samples`` (evaluated),
        ``over_bound`` (bool: a vetoed sample seen).

        Returns
        -------
        dict of str to ndarray, each of shape (k,)
            One entry per design of the chunk, in ``design`` order.

        Examples
        --------
        >>> rec = Recorder(lambda d, s: s[None, :] + d[:, None] + 0.0, np.array([0, 1]), 4, "min", "fail")
        >>> _ = rec(np.array([0, 1]), np.array([1, 2]))
        >>> _ = rec(np.array([1]), np.array([0, 3]))
        >>> r = rec.records()
        >>> r["exact"].tolist(), r["value"].tolist(), r["samples"].tolist()
        ([False, True], [1.0, 1.0], [2, 4])
        """
        exact = self.seen == self.S
        if self.form == "sum":
            value = self.sum.copy()
        else:
            u = _ratio(self.A, self.B) if self.form == "ratio" else self.A.copy()
            u = np.where(self.feasible_seen, u, np.where(exact, -np.inf, np.inf))
            if self.fail:
                u = np.where(self.bad, -np.inf, u)
            value = u
        return {"design": self.ids.copy(), "exact": exact, "value": value, "samples": self.seen.copy(),
                "over_bound": self.over.copy()}


@dataclass(frozen=True)
class ReportResult:
    """Answers to the study's [report] table. Values in objective units (counts positive)."""

    reference: dict[str, float] | None
    reference_value: float | None
    tolerance: float
    target: float | None                   # the value a design must reach (reference within tolerance)
    smallest: str | None
    smallest_design: dict[str, float] | None
    smallest_value: float | None
    checks: list[dict[str, Any]]
    evaluations: int


@dataclass(frozen=True)
class StudyResult:
    """Outcome of ``run_study`` for one study (one series value)."""

    study: Study
    method: str
    top_designs: np.ndarray                # (K,) ids, best first
    top_values: np.ndarray                 # (K,) objective units (counts positive)
    n_designs: int
    n_samples: int                         # samples the search used (see Evaluator)
    evaluations: int
    exact_designs: int
    wall_seconds: float
    work_seconds: float
    chunks: int
    workers: int
    engine: str
    records: dict[str, np.ndarray]         # per design (sorted ids): exact, value, samples
    evaluator_note: str = ""
    report: ReportResult | None = None
    #: (K,) each listed design's largest apparent mass over the samples, kg (studies using the mass).
    top_masses: np.ndarray | None = None

    @property
    def over_bound(self) -> int:
        """Designs the ``max_apparent_mass`` bound removed: those in which the search met a sample
        over it (all of them under ``brute_force``; see the module docstring for culling).

        Returns
        -------
        int
        """
        return int(self.records["over_bound"].sum()) if "over_bound" in self.records else 0

    @property
    def brute_force_evaluations(self) -> int:
        """``D * S``: what brute force evaluates (computed, not run).

        Returns
        -------
        int
        """
        return self.n_designs * self.n_samples

    @property
    def ratio(self) -> float:
        """Evaluations over brute force's ``D * S``.

        Returns
        -------
        float
            1 for brute force.
        """
        return self.evaluations / self.brute_force_evaluations

    @property
    def value(self) -> float:
        """The best design's value, in objective units (a count is positive).

        Returns
        -------
        float
        """
        return float(self.top_values[0])

    @property
    def design(self) -> int:
        """The best design's id.

        Returns
        -------
        int
        """
        return int(self.top_designs[0])

    def top(self) -> list[dict[str, Any]]:
        """The ranking: ``rank``, ``design`` id, each parameter's display value, ``value``
        (and ``max_apparent_mass``, kg, for a study that uses the mass).

        Returns
        -------
        list of dict
            One per listed design, best first.
        """
        disp = self.study.design_display(self.top_designs)
        rows = [{"rank": i + 1, "design": int(d), **{k: float(v[i]) for k, v in disp.items()},
                 "value": float(self.top_values[i])} for i, d in enumerate(self.top_designs)]
        if self.top_masses is not None:
            for row, m in zip(rows, self.top_masses):
                row["max_apparent_mass"] = float(m)
        return rows


def to_objective(study: Study, internal: np.ndarray) -> np.ndarray:
    """Search values (maximised) -> objective units (a count is positive).

    Parameters
    ----------
    study : Study
        Its objective's form says whether to negate.
    internal : ndarray, shape (k,)
        Values as the searches maximise them.

    Returns
    -------
    ndarray, shape (k,)
        A vetoed design (``VETO``) as ``-inf``: infeasible.
    """
    if study.objective.form == "sum":
        return -internal
    return np.where(np.asarray(internal) == VETO, -np.inf, internal)


def _worst_samples(form: str, out, fail: bool) -> list[int]:
    """Positions (within a block of one design) of the samples that lower its bound most:
    the counted ones (sum), the smallest value (min; an infeasible one first under "fail"),
    the smallest numerator and the largest denominator (ratio)."""
    if form == "sum":
        return [int(np.argmax(np.asarray(out)[0]))]
    a = np.asarray(out[0] if form == "ratio" else out, float)[0]
    bad = np.isnan(a) | (a == -np.inf)
    picks = [int(np.argmin(np.where(bad, -np.inf if fail else np.inf, a)))]
    if form == "ratio":
        b = np.asarray(out[1], float)[0]
        bad |= np.isnan(b) | (b == -np.inf)
        picks.append(int(np.argmax(np.where(bad, -np.inf, b))))
    return picks


def first_reaching(study: Study, ev: Evaluator, parameter: str, target: float, *,
                   first_chunk: int = 32, max_probes: int = 8) -> tuple[tuple[int, float] | None, int]:
    """The best design at the smallest value of ``parameter`` whose search value reaches
    ``target`` (``F >= target``, ``F`` maximised as in the searches), and the evaluations spent.

    Exact without assuming ``F`` monotone in the parameter: designs are visited in ascending
    parameter value (then id); each is evaluated on the probes (the samples that dropped
    earlier designs) and then on the rest in doubling chunks, and dropped as soon as its
    upper bound (``Recorder``) falls below ``target``. The first parameter value with a
    design that completes at ``F >= target`` is the answer; the other designs at that value
    are finished too, and the best of them (ranking order) is returned.

    Parameters
    ----------
    study : Study
        The study (its designs' display values).
    ev : Evaluator
        Its evaluator (``evaluator_for``).
    parameter : str
        A grid parameter's name.
    target : float
        The search value to reach (maximised form: a count negated).
    first_chunk : int
        Samples in a design's first chunk after the probes; chunks double.
    max_probes : int
        Probes kept (samples that dropped earlier designs).

    Returns
    -------
    ((int, float) or None, int)
        ``(design id, search value)`` of the answer, or None when no design reaches
        ``target``; and the (design, sample) evaluations spent.
    """
    D, S = study.n_designs, ev.n_samples
    col = study.design_display(np.arange(D))[parameter]
    sign = -1.0 if ev.form == "sum" else 1.0
    fail = study.objective.infeasible == "fail"
    probes: list[int] = []
    evaluations = 0
    found: list[tuple[float, int]] = []
    stop_at = None
    for d in np.lexsort((np.arange(D), col)).tolist():
        if stop_at is not None and col[d] != stop_at:
            break
        rec = Recorder(ev, np.array([d]), S, ev.form, study.objective.infeasible)
        todo = np.ones(S, bool)
        first = np.asarray(probes, np.int64)
        chunk = first_chunk
        reached = True
        while todo.any():
            if first.size:
                spos, first = first, first[:0]
            else:
                spos = np.flatnonzero(todo)[:chunk]
                chunk *= 2
            out = rec(np.array([d]), spos)
            evaluations += spos.size
            todo[spos] = False
            if sign * rec.records()["value"][0] < target:
                reached = False
                for w in _worst_samples(ev.form, out, fail):
                    if int(spos[w]) not in probes:
                        probes.insert(0, int(spos[w]))
                del probes[max_probes:]
                break
        if reached:
            found.append((float(sign * rec.records()["value"][0]), d))
            stop_at = col[d]
    if not found:
        return None, evaluations
    value, d = min(found, key=lambda vd: (-vd[0], vd[1]))
    return (d, value), evaluations


def study_report(study: Study, result: StudyResult) -> ReportResult:
    """The [report] table's answers, all by exact evaluation (no monotonicity assumed).

    ``smallest``: ``first_reaching`` (the smallest value of the named parameter at which some
    design reaches ``target``, the reference's value within the relative tolerance).

    Parameters
    ----------
    study : Study
        A study with a [report] table.
    result : StudyResult
        Its search result.

    Returns
    -------
    ReportResult
        Values in objective units.
    """
    rep = study.report
    ev = evaluator_for(study)
    S = ev.n_samples
    evaluations = 0
    sign = -1.0 if study.objective.form == "sum" else 1.0    # search maximises sign * value

    def value_at(values: dict[str, float]) -> float:
        nonlocal evaluations
        out = ev.at(values)
        evaluations += S
        if ev.form == "sum":
            return float(np.asarray(out).sum())
        if ev.form == "ratio":
            rec = Recorder(lambda d, s: out, np.array([0]), S, "ratio", study.objective.infeasible)
        else:
            rec = Recorder(lambda d, s: out, np.array([0]), S, "min", study.objective.infeasible)
        rec(np.array([0]), np.arange(S))
        return float(to_objective(study, rec.records()["value"][:1])[0])

    ref_value = target = None
    smallest_design = smallest_value = None
    if rep.reference is not None:
        ref_value = value_at(rep.reference)
        target = ref_value - rep.tolerance * abs(ref_value) if sign > 0 else ref_value + rep.tolerance * abs(ref_value)
    if rep.smallest is not None and target is not None and np.isfinite(target):
        found, count = first_reaching(study, ev, rep.smallest, sign * target)
        evaluations += count
        if found is not None:
            d, internal = found
            smallest_design = {k: float(v[0]) for k, v in study.design_display([d]).items()}
            smallest_value = float(sign * internal)
    checks = []
    for c in rep.checks:
        v = value_at(c.values)
        entry: dict[str, Any] = {"label": c.label, **c.values, "value": v}
        if ref_value is not None:
            entry["vs_reference"] = v / ref_value - 1.0 if ref_value else float("nan")
            entry["reaches"] = bool(v >= target) if sign > 0 else bool(v <= target)
        checks.append(entry)
    return ReportResult(rep.reference, ref_value, rep.tolerance, target, rep.smallest, smallest_design,
                        smallest_value, checks, evaluations)
