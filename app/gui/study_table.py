"""The Optimize panel's ranking as text: column headers with units, shared ranks, enough digits.

Qt-free (the panel, ``app.gui.widgets.optimize_panel``, only puts these strings in its table), so
it is tested without a window. A rank is a claim about order, so:

- designs with equal objective values share a rank (competition ranking: ``1=``, ``1=``, ``3``);
  ``metrics.design.ranking`` lists tied designs by id, which is a listing order, not a rank;
- every column of numbers is printed with the fewest significant digits (at least
  ``MIN_DIGITS``) that tell its distinct values apart, the same digits for the whole column, so
  equal values read equal and unequal ones never do;
- a tie that runs past the end of the list is said (``RankingTable.note``), from the
  search's per-design records: designs evaluated exactly with the last listed value, and
  designs culled at a bound equal to it (they may equal it).

``ranking_table`` is the ranking with one column per parameter. The panel's dock is as narrow
as the statistics table (about 230 px), too narrow for a column per parameter, so the panel
shows ``stacked_ranking``: the same texts in three columns, rank, the objective and the design,
whose parameters are stacked as ``(name, value)`` (the unit under the header when all share one,
else with each value) and drawn under their ``labels``, the names as the Design dock writes them
(``shoulder separation``, not the study's key ``shoulder_separation``); a series' value heads the
block of its run instead of filling a column, and a tie past the end of a run's list is said in
a ``RunNote`` under it (the panel's summary keeps the note on shared ranks).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from itertools import groupby
from typing import Any

import numpy as np

#: Significant digits a value is printed with at least (what ``%g`` gives).
MIN_DIGITS = 6
#: Enough for any two distinct float64 values to print differently.
MAX_DIGITS = 17

#: Each objective's column label (its unit is added from ``Objective.unit``; κ is the condition number).
OBJECTIVE_LABELS = {
    "min_isotropic_force": "min isotropic force",
    "gii": "GII",
    "count_condition_above": "samples with κ\u00a0>\u00a0{threshold:g}",     # the comparison on one line
    "sensor_gii": "sensor GII",
}


def unit_suffix(unit: str) -> str:
    """The unit line of a header: ``(unit)``, ``(-)`` for a dimensionless quantity, on a line of its
    own (a header of two short lines keeps the narrow dock's columns narrow).

    Examples
    --------
    >>> unit_suffix("mm"), unit_suffix("")
    ('\\n(mm)', '\\n(-)')
    """
    return f"\n({unit})" if unit else "\n(-)"


def wrap_name(name: str, width: int = 12) -> str:
    """``name`` in lines of about ``width`` characters, broken after ``_`` or ``.`` or at a space,
    so a long parameter name does not widen its column of short numbers.

    Examples
    --------
    >>> wrap_name("shoulder_separation"), wrap_name("workspace.centre.z"), wrap_name("half_base")
    ('shoulder_\\nseparation', 'workspace.\\ncentre.z', 'half_base')
    >>> wrap_name("samples with κ > 5")
    'samples with\\nκ > 5'
    """
    pieces = re.findall(r"[^_. ]+[_.]?| ", name)
    lines, line = [], ""
    for piece in pieces:
        if line and len(line) + len(piece.rstrip()) > width:
            lines.append(line.rstrip())
            line = piece.lstrip()
        else:
            line += piece
    lines.append(line.rstrip())
    return "\n".join(x for x in lines if x)


def column_digits(values: Any, minimum: int = MIN_DIGITS) -> int:
    """The fewest significant digits (>= ``minimum``) that print the distinct finite ``values`` distinctly.

    Parameters
    ----------
    values : array_like, shape (k,)
        The column's numbers (non-finite ones are spelled out and do not count).
    minimum : int
        Digits to print at least.

    Returns
    -------
    int
        Between ``minimum`` and ``MAX_DIGITS``.

    Examples
    --------
    >>> column_digits([3.9140060089331765, 3.9140060089331765])
    6
    >>> column_digits([3.91400600893, 3.91400600894])
    12
    """
    finite = np.unique(np.asarray(values, dtype=np.float64))
    finite = finite[np.isfinite(finite)]
    for digits in range(minimum, MAX_DIGITS + 1):
        if len({f"{v:.{digits}g}" for v in finite.tolist()}) == finite.size:
            return digits
    return MAX_DIGITS


def column_texts(values: Any, digits: int) -> list[str]:
    """A column's cells: ``format_value``'s texts, then every finite one with as many decimals as
    the one with the most (11.785 above 11.800, not 11.8), more where that would print two
    distinct values alike; ``format_value``'s own texts when one needs an exponent.

    Parameters
    ----------
    values : array_like, shape (k,)
        The column's numbers.
    digits : int
        Significant digits (``column_digits``).

    Returns
    -------
    list of str, length k

    Examples
    --------
    >>> column_texts([11.785, 11.79, 11.8], 5)
    ['11.785', '11.790', '11.800']
    >>> column_texts([454.0, float("-inf"), 2.5], 6)
    ['454.0', 'infeasible', '2.5']
    """
    values = [float(v) + 0.0 for v in np.asarray(values, dtype=np.float64).ravel()]     # -0.0 reads as 0
    texts = [format_value(v, digits) for v in values]
    finite = [(v, t) for v, t in zip(values, texts) if math.isfinite(v)]
    if not finite or any("e" in t for _, t in finite):
        return texts
    decimals = max(len(t.partition(".")[2]) for _, t in finite)
    distinct = len({v for v, _ in finite})
    # Rounded again at more places, two values either side of a rounding edge could meet.
    while len({f"{v:.{decimals}f}" for v, _ in finite}) < distinct and decimals < 17:
        decimals += 1
    return [f"{v:.{decimals}f}" if math.isfinite(v) else t for v, t in zip(values, texts)]


def format_value(value: float, digits: int) -> str:
    """One cell: ``digits`` significant digits; ``infeasible`` for -inf, ``unbounded`` for inf, ``nan``.

    Examples
    --------
    >>> format_value(454.0, 6), format_value(float("-inf"), 6), format_value(0.0461818, 6)
    ('454', 'infeasible', '0.0461818')
    """
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "unbounded" if value > 0 else "infeasible"
    return f"{value:.{digits}g}"


def shared_ranks(values: Any, *, tied_after: bool = False) -> list[str]:
    """Competition ranks of values listed best first: equal values share the rank of the first,
    marked ``=``; the next distinct value's rank counts every design above it.

    Parameters
    ----------
    values : array_like, shape (k,)
        Objective values in ranking order (best first), compared exactly.
    tied_after : bool
        A design past the end of the list has exactly the last value: the last group is marked too.

    Returns
    -------
    list of str, length k

    Examples
    --------
    >>> shared_ranks([454.0, 456.0, 462.0, 468.0, 468.0, 478.0])
    ['1', '2', '3', '4=', '4=', '6']
    >>> shared_ranks([3.9, 3.9, 3.9])
    ['1=', '1=', '1=']
    >>> shared_ranks([1.0, 2.0], tied_after=True)
    ['1', '2=']
    """
    vals = np.asarray(values, dtype=np.float64).tolist()
    ranks = []
    for i, v in enumerate(vals):
        first = i
        while first > 0 and vals[first - 1] == v:
            first -= 1
        shared = (i > 0 and vals[i - 1] == v) or (i + 1 < len(vals) and vals[i + 1] == v) or (
            tied_after and v == vals[-1])
        ranks.append(f"{first + 1}{'=' if shared else ''}")
    return ranks


def ties_beyond(result) -> tuple[int, int]:
    """Designs outside ``result``'s list whose value may equal the last listed value.

    Parameters
    ----------
    result : metrics.design.StudyResult
        A finished run; its ``records`` hold every design's exact value or search bound
        (objective units; an upper bound for a maximised objective, a lower bound for a count).

    Returns
    -------
    exact : int
        Designs evaluated exactly with exactly the last listed value.
    bounded : int
        Designs culled at a bound equal to it (their value is that or worse).
    """
    if len(result.top_values) == 0:
        return 0, 0
    last = float(result.top_values[-1])
    rec = result.records
    outside = ~np.isin(rec["design"], result.top_designs)
    equal = outside & (rec["value"] == last)
    return int(np.count_nonzero(equal & rec["exact"])), int(np.count_nonzero(equal & ~rec["exact"]))


@dataclass(frozen=True)
class RankingTable:
    """What the panel shows: ``header`` and ``tooltips`` per column, ``rows`` of
    ``(result, design id, cells)`` and a ``note`` on ties (empty when there is none)."""

    header: list[str]
    tooltips: list[str]
    rows: list[tuple[Any, int, list[str]]]
    note: str


def objective_header(objective, width: int = 14) -> tuple[str, str]:
    """The value column's header (label and unit, in lines of about ``width`` characters) and its
    tooltip (the label and unit on one line, and what better means).

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> kappa = SimpleNamespace(kind="count_condition_above", threshold=5.0, unit="samples", direction="min")
    >>> objective_header(kappa)[0]
    'samples with\\nκ\\xa0>\\xa05\\n(samples)'
    >>> objective_header(kappa, width=9)[0]
    'samples\\nwith\\nκ\\xa0>\\xa05\\n(samples)'
    """
    label = OBJECTIVE_LABELS.get(objective.kind, objective.kind.replace("_", " "))
    label = label.format(threshold=objective.threshold if objective.threshold is not None else math.nan)
    better = "larger is better" if objective.direction == "max" else "smaller is better"
    meaning = " (κ: the condition number of the Jacobian)" if "κ" in label else ""
    unit = f"({objective.unit})" if objective.unit else "(-)"
    return (wrap_name(label, width) + unit_suffix(objective.unit),
            f"The design's objective, {label} {unit}{meaning}, {better}.")


def ranking_table(study, results) -> RankingTable:
    """The table of a finished study: one block of rows per run (series value), best first.

    Parameters
    ----------
    study : metrics.design.Study
        The study as started (its ``series``, if any, labels the blocks).
    results : list of metrics.design.StudyResult
        One per run, in series order.

    Returns
    -------
    RankingTable
    """
    run_study = results[0].study
    params = run_study.parameters
    infos = {info.name: info for info in run_study.mechanism.PARAM_INFO}
    series = study.series
    header, tooltips = [], []
    if series is not None:
        header.append(wrap_name(series.key) + unit_suffix(series.unit))
        tooltips.append("The series value this run was searched at.")
    header.append("rank")
    tooltips.append("Competition rank: equal values share a rank (marked =), the next rank counts every "
                    "design above it. Tied designs are listed by design id.")
    for p in params:
        header.append(wrap_name(p.name) + unit_suffix(p.unit))
        info = infos.get(p.targets[0].field)
        tooltips.append(info.description if info is not None else p.name)
    value_head, value_tip = objective_header(run_study.objective)
    header.append(value_head)
    tooltips.append(value_tip)

    param_digits = {p.name: column_digits(p.display) for p in params}
    value_digits = column_digits(np.concatenate([np.asarray(r.top_values, np.float64) for r in results]))
    series_digits = column_digits(series.values) if series is not None else MIN_DIGITS
    rows = []
    notes = []
    # Each column's numbers first: its texts share their decimals (``column_texts``).
    raw = []
    for res in results:
        display = res.study.design_display(res.top_designs)
        for i, design in enumerate(res.top_designs):
            raw.append([float(display[p.name][i]) for p in params] + [float(res.top_values[i])])
    digits = [param_digits[p.name] for p in params] + [value_digits]
    columns = [column_texts(column, d) for column, d in zip(zip(*raw), digits)] if raw else []
    texts = iter(list(zip(*columns)))
    for res in results:
        exact, bounded = ties_beyond(res)
        for i, (design, rank) in enumerate(zip(res.top_designs, shared_ranks(res.top_values, tied_after=exact > 0))):
            cells = [format_value(float(res.study.series_value), series_digits)] if series is not None else []
            cells.append(rank)
            cells += list(next(texts))
            rows.append((res, int(design), cells))
        if exact or bounded:
            where = f" at {series.key} = {format_value(float(res.study.series_value), series_digits)} " \
                    f"{series.unit}" if series is not None else ""
            notes.append(tie_note(exact, bounded, rows[-1][2][-1], where))
    rank_column = 1 if series is not None else 0
    if any(cells[rank_column].endswith("=") for _, _, cells in rows):
        notes.insert(0, SHARED_RANK_NOTE)
    return RankingTable(header, tooltips, rows, " ".join(notes))


#: What a rank marked ``=`` means (``RankingTable.note`` starts with it when a rank is shared).
SHARED_RANK_NOTE = "Equal values share a rank (marked =); tied designs are listed by design id."


def tie_note(exact: int, bounded: int, last: str, where: str = "") -> str:
    """The sentence on a tie past the end of a run's list (``ties_beyond``'s counts).

    Examples
    --------
    >>> tie_note(1, 240, "infeasible")
    'The last listed value, infeasible, is not the end of the tie: 1 more designs have it exactly; \
240 more were culled at a bound equal to it (their value is that or worse).'
    """
    parts = [f"{exact} more designs have it exactly"] if exact else []
    if bounded:
        parts.append(f"{bounded} more were culled at a bound equal to it (their value is that or worse)")
    return f"The last listed value{where}, {last}, is not the end of the tie: " + "; ".join(parts) + "."


#: Characters per line of the stacked ranking's objective header: the objective column is the
#: widest beside the design, and a line of 14 ("samples with") costs the design 20 px.
STACKED_LABEL_WIDTH = 9


@dataclass(frozen=True)
class RankedDesign:
    """One design of the stacked ranking: its run ``result``, ``design`` id, ``rank`` and objective
    ``value`` as ``ranking_table`` prints them, its ``parameters`` as ``(name, value)`` in the
    study's order (the value with its unit unless the column's header has the one unit of all),
    and ``full``: every parameter with its unit, one a line (the cell's tooltip)."""

    result: Any = field(repr=False)
    design: int
    rank: str
    value: str
    parameters: tuple[tuple[str, str], ...]
    full: str

    @property
    def text(self) -> str:
        """The parameters as shown, lines ``name = value``."""
        return "\n".join(f"{name} = {value}" for name, value in self.parameters)


@dataclass(frozen=True)
class RunHeading:
    """The line above one run's designs in a series: ``text`` is ``key = value unit``."""

    result: Any = field(repr=False)
    text: str


@dataclass(frozen=True)
class RunNote:
    """The line under a run's designs when its tie goes on past them (``tie_note``; the run's
    heading, if any, says which run)."""

    result: Any = field(repr=False)
    text: str


@dataclass(frozen=True)
class StackedRanking:
    """The ranking in three columns (rank, objective, design): ``header`` and ``tooltips`` per
    column, ``rows`` in table order (a ``RunHeading`` above each run of a series, then its
    ``RankedDesign`` rows, then a ``RunNote`` if its tie goes on past them), the ``note`` on
    shared ranks (``SHARED_RANK_NOTE`` or empty), the ``objective`` (label and unit, one line) and
    the parameters' ``labels`` to draw (``parameter_label``), in the study's order."""

    header: list[str]
    tooltips: list[str]
    rows: list[RankedDesign | RunHeading | RunNote]
    note: str
    objective: str
    labels: tuple[str, ...]


def parameter_label(name: str) -> str:
    """A study parameter's name as the Design dock writes it: words apart, a vector entry
    ``field.entry`` as ``field [entry]``, the entry kept on one line (a non-breaking space: a
    narrow design column wrapped it as "[theta" / "0]").

    Examples
    --------
    >>> parameter_label("shoulder_separation"), parameter_label("Q1")
    ('shoulder separation', 'Q1')
    >>> parameter_label("gear_ratios.theta_1")
    'gear ratios [theta\xa01]'
    """
    vector, dot, entry = name.partition(".")
    return f"{vector.replace('_', ' ')} [{entry.replace('_', chr(0xA0))}]" if dot else name.replace("_", " ")


def with_unit(text: str, unit: str) -> str:
    """A value and its unit, kept on one line; a dimensionless value alone.

    Examples
    --------
    >>> with_unit("90", "mm"), with_unit("1.6", "")
    ('90\\xa0mm', '1.6')
    """
    return f"{text}\u00a0{unit}" if unit else text


def shared_unit(units: list[str]) -> str | None:
    """The one unit of every parameter (``""``: all dimensionless), ``None`` when they differ.

    Examples
    --------
    >>> shared_unit(["mm", "mm", "mm"]), shared_unit([""]), shared_unit(["mm", "N m"])
    ('mm', '', None)
    """
    return units[0] if len(set(units)) == 1 else None


def stacked_ranking(study, results) -> StackedRanking:
    """``ranking_table``'s texts with the design's parameters stacked in one column.

    When every parameter has the same unit it goes under the design column's header, as under
    the others, and the lines are ``name = value``; otherwise each line has its unit. The panel
    draws each value under its ``labels`` entry (``parameter_label``), the name in full.

    Parameters
    ----------
    study : metrics.design.Study
        The study as started (its ``series``, if any, heads the blocks).
    results : list of metrics.design.StudyResult
        One per run, in series order.

    Returns
    -------
    StackedRanking
        Its ranks, values and parameter values are ``ranking_table``'s, character for character.
    """
    table = ranking_table(study, results)
    run_study = results[0].study
    params = run_study.parameters
    series = study.series
    rank_column = 1 if series is not None else 0
    unit = shared_unit([p.unit for p in params])
    value_head, value_tip = objective_header(run_study.objective, STACKED_LABEL_WIDTH)
    labels = tuple(parameter_label(p.name) for p in params)
    # A label that is not the study's key says the key too: the key is what a study file writes.
    described = [f"{label} ({p.name + ', ' if label != p.name else ''}{p.unit or '-'}): {tip}"
                 for p, label, tip in zip(params, labels, table.tooltips[rank_column + 1:-1])]
    design_head = "design" + (unit_suffix(unit) if unit is not None else "")
    design_tip = "The design's parameters, one a line:\n" + "\n".join(described)
    rows: list[RankedDesign | RunHeading | RunNote] = []
    for _, run in groupby(table.rows, key=lambda row: id(row[0])):
        run = list(run)
        res = run[0][0]
        if series is not None:
            rows.append(RunHeading(res, f"{series.key} = {with_unit(run[0][2][0], series.unit)}"))
        for _, design, cells in run:
            values = cells[rank_column + 1:-1]
            shown = tuple((p.name, v if unit is not None else with_unit(v, p.unit)) for p, v in zip(params, values))
            full = "\n".join(f"{p.name} = {with_unit(v, p.unit)}" for p, v in zip(params, values))
            rows.append(RankedDesign(res, design, cells[rank_column], cells[-1], shown, full))
        exact, bounded = ties_beyond(res)
        if exact or bounded:                # said under the run it belongs to, not in the panel's summary
            rows.append(RunNote(res, tie_note(exact, bounded, run[-1][2][-1])))
    note = SHARED_RANK_NOTE if table.note.startswith(SHARED_RANK_NOTE) else ""
    return StackedRanking(["rank", value_head, design_head], [table.tooltips[rank_column], value_tip, design_tip],
                          rows, note, table.header[-1].replace("\n", " "), labels)
