"""The Optimize panel's ranking text (app.gui.study_table), without a window.

Ranks are checked against brute force (every design evaluated exactly, so the true competition
rank of each listed design is counted, not inferred), digits against exact float comparison.
"""
from __future__ import annotations

import numpy as np
import pytest

from app.gui.studies import load_study
from app.gui.study_table import (
    RankedDesign,
    RunHeading,
    column_digits,
    column_texts,
    format_value,
    ranking_table,
    shared_ranks,
    stacked_ranking,
    ties_beyond,
)
from app.jobs.requests import StudyRequest, run_study_job
from metrics.design import run_study


@pytest.fixture(scope="module")
def table1():
    study = load_study("fivebar_table1")
    truth = run_study(study, method="brute_force", top_k=study.n_designs)     # every design, exactly
    return study, truth


def true_ranks(values_all: np.ndarray, value: float, direction: str) -> tuple[int, int]:
    """(1 + designs strictly better, designs with exactly this value) over every design."""
    better = values_all < value if direction == "min" else values_all > value
    return 1 + int(np.count_nonzero(better)), int(np.count_nonzero(values_all == value))


@pytest.mark.parametrize("top_k", [4, 5, 10])
def test_ranks_are_the_competition_ranks_brute_force_counts(table1, top_k):
    study, truth = table1
    assert truth.records["exact"].all()
    values_all = truth.records["value"]
    result = run_study(study, top_k=top_k)           # culling, as the panel runs it
    table = ranking_table(study, [result])
    exact_after, bounded_after = ties_beyond(result)
    for (_, design, cells), value in zip(table.rows, result.top_values):
        rank, tied = true_ranks(values_all, float(value), study.objective.direction)
        assert cells[0].rstrip("=") == str(rank), (design, cells)
        if cells[0].endswith("="):
            assert tied > 1                          # never a tie that is not one
        elif tied > 1:
            # A tie the list cannot prove: the rest of it was culled at a bound equal to the value.
            assert value == result.top_values[-1] and bounded_after >= tied - 1, (design, cells)
    # top_k = 4 cuts the 468-sample tie (designs 12 and 42) after its first design.
    if top_k == 4:
        assert result.top_values[-1] == 468.0 and (exact_after, bounded_after) != (0, 0)
        assert "is not the end of the tie" in table.note


def test_headers_carry_units_and_one_rank_column(table1):
    study, _ = table1
    table = ranking_table(study, [run_study(study, top_k=5)])
    assert table.header == ["rank", "proximal\n(mm)", "distal\n(mm)", "half_base\n(mm)",
                            "samples with\nκ\u00a0>\u00a05\n(samples)"]
    assert "smaller is better" in table.tooltips[-1] and "condition number" in table.tooltips[-1]


def test_a_series_labels_its_runs_with_the_series_unit_and_ranks_each_run():
    study = load_study("twin_pantograph_sensor")
    results = run_study_job(StudyRequest(study, top_k=3), lambda f: None, lambda: False)
    table = ranking_table(study, results)
    assert table.header[:2] == ["workspace.\ncentre.z\n(mm)", "rank"]
    assert table.header[2] == "Q1\n(-)" and table.header[-1] == "sensor GII\n(-)"
    assert [cells[0] for _, _, cells in table.rows] == [f"{v:g}" for v in study.series.values for _ in range(3)]
    for res in results:
        rows = [cells for r, _, cells in table.rows if r is res]
        assert [c[1] for c in rows] == shared_ranks(res.top_values, tied_after=ties_beyond(res)[0] > 0)


def test_the_study_job_reports_one_fraction_for_the_whole_series():
    study = load_study("twin_pantograph_sensor")          # 7 runs of one chunk each
    fractions = []
    run_study_job(StudyRequest(study, top_k=3), fractions.append, lambda: False)
    n = len(study.runs())
    assert fractions == [(k + 1) / n for k in range(n)]   # runs done over runs, never reset per run


def test_equal_values_print_equal_and_distinct_values_print_distinct():
    rng = np.random.default_rng(7)
    base = rng.uniform(0.1, 10.0, 20)
    # Exact repeats, neighbours one ulp apart, values equal to 6 and to 12 digits, a count.
    values = np.concatenate([base, base[:5], np.nextafter(base[5:10], np.inf), base[10:15] * (1 + 1e-9),
                             [454.0, 454.0, 456.0]])
    digits = column_digits(values)
    texts = [format_value(float(v), digits) for v in values]
    for i in range(values.size):
        for j in range(values.size):
            assert (texts[i] == texts[j]) == (values[i] == values[j]), (values[i], values[j], texts[i], texts[j])
    assert digits == 17                                    # one-ulp neighbours need every digit
    assert column_digits([454.0, 456.0]) == 6 and format_value(454.0, 6) == "454"
    assert format_value(float("-inf"), 6) == "infeasible" and format_value(float("inf"), 6) == "unbounded"


def test_the_gear_ratio_plateau_is_one_shared_rank_with_the_tie_said():
    study = load_study("inverse3_gear_ratio")
    result = run_study(study, top_k=10)
    assert np.all(result.top_values == result.top_values[0])          # ten designs on the plateau
    table = ranking_table(study, [result])
    assert [cells[0] for _, _, cells in table.rows] == ["1="] * 10
    assert len({cells[-1] for _, _, cells in table.rows}) == 1
    assert table.note.startswith("Equal values share a rank")
    exact, bounded = ties_beyond(result)
    assert exact + bounded > 0 and f"{bounded} more were culled at a bound equal to it" in table.note


MIXED_UNITS = """
name = "mixed units"
description = "a link length in mm and a gear ratio without unit"
[mechanism]
kind = "fivebar"
parameters = { working_mode = "+-" }
[grid]
proximal = [90.0, 100.0]
"gear_ratios.theta_1" = [8.0, 10.0]
[workspace]
kind = "sampling"
name = "normalised_arcs"
[objective]
kind = "count_condition_above"
threshold = 5.0
direction = "min"
"""


def test_the_stacked_ranking_has_ranking_tables_texts_with_the_unit_once_or_on_every_line(table1, tmp_path):
    # One unit for all (five-bar lengths): under the design's header, lines 'name = value'.
    study, _ = table1
    result = run_study(study, top_k=5)
    flat, stacked = ranking_table(study, [result]), stacked_ranking(study, [result])
    assert stacked.header == ["rank", "samples\nwith\nκ\u00a0>\u00a05\n(samples)", "design\n(mm)"]
    assert "samples with κ\u00a0>\u00a05 (samples)" in stacked.tooltips[1]
    assert stacked.objective == "samples with κ\u00a0>\u00a05 (samples)" and stacked.note == flat.note
    names = ["proximal", "distal", "half_base"]
    for (res, design, cells), row in zip(flat.rows, stacked.rows, strict=True):
        assert (row.result, row.design, row.rank, row.value) == (res, design, cells[0], cells[-1])
        assert row.parameters == tuple(zip(names, cells[1:-1]))
        assert row.full == "\n".join(f"{n} = {v}\u00a0mm" for n, v in zip(names, cells[1:-1]))
    # Units that differ: none under the header, each line has its own (a ratio has none).
    path = tmp_path / "mixed.toml"
    path.write_text(MIXED_UNITS, encoding="utf-8")
    mixed = load_study(str(path))
    stacked = stacked_ranking(mixed, [run_study(mixed, top_k=4)])
    assert stacked.header[2] == "design"
    assert [row.parameters[0][1] for row in stacked.rows] == ["100\u00a0mm", "100\u00a0mm", "90\u00a0mm", "90\u00a0mm"]
    assert [row.parameters[1] for row in stacked.rows] == [("gear_ratios.theta_1", v) for v in ["8", "10", "8", "10"]]


def test_a_series_heads_each_run_of_the_stacked_ranking_with_its_value_and_unit():
    study = load_study("twin_pantograph_sensor")
    results = run_study_job(StudyRequest(study, top_k=3), lambda f: None, lambda: False)
    flat, stacked = ranking_table(study, results), stacked_ranking(study, results)
    headings = [row for row in stacked.rows if isinstance(row, RunHeading)]
    assert [h.text for h in headings] == [f"workspace.centre.z = {v:g}\u00a0mm" for v in study.series.values]
    assert [h.result for h in headings] == results
    designs = [row for row in stacked.rows if isinstance(row, RankedDesign)]
    assert [(r.result, r.design, r.rank, r.value) for r in designs] == [
        (res, design, cells[1], cells[-1]) for res, design, cells in flat.rows]
    # Each heading is followed by its own run's designs.
    for i, row in enumerate(stacked.rows):
        if isinstance(row, RankedDesign):
            assert [h for h in stacked.rows[:i] if isinstance(h, RunHeading)][-1].result is row.result
    assert stacked.header[2] == "design\n(-)" and designs[0].parameters[0][0] == "Q1"


def test_a_column_shares_its_decimals_and_keeps_distinct_values_distinct():
    """11.785 above 11.800, not 11.8 (the inverse3_gear_ratio study's 0.005 grid); and values
    either side of a rounding edge stay apart when padded to more places."""
    assert column_texts([11.785, 11.79, 11.8, 11.805], 5) == ["11.785", "11.790", "11.800", "11.805"]
    rng = np.random.default_rng(3)
    for _ in range(200):
        values = np.array([round(v, int(d)) for v, d in zip(rng.uniform(1.0, 20.0, 12), rng.integers(0, 4, 12))])
        values = np.concatenate([values, values[:3], np.nextafter(values[3:5], np.inf)])
        texts = column_texts(values, column_digits(values))
        assert len({t.partition(".")[2].__len__() for t in texts}) == 1, texts      # one number of decimals
        for i in range(values.size):
            for j in range(values.size):
                assert (texts[i] == texts[j]) == (values[i] == values[j]), (values[i], values[j], texts[i])
        # Each text is its value rounded (to half its last place, plus the reading of the text as a float).
        assert all(abs(float(t) - v) <= 0.5 * 10.0 ** -len(t.partition(".")[2]) + 4 * np.finfo(float).eps * v
                   for t, v in zip(texts, values))
