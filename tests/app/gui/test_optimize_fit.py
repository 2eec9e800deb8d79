"""The Optimize panel's ranking fits the dock it shares with the statistics: no horizontal
scroll bar at the default 1600 x 950 and at 1920 x 1080, the dock as narrow as the statistics
table makes it; rank and objective whole, every parameter's value and unit whole, and every
parameter's name drawn in full (on lines of its own where it does not fit beside its value),
as the delegate paints it; the summary above the table a few lines tall, every fact kept."""
from __future__ import annotations

import re

import pytest
from conftest import wait_full_map
from PySide6.QtCore import QRect, Qt
from PySide6.QtGui import QFontMetrics, QImage, QPainter
from PySide6.QtWidgets import QApplication, QStyleOptionViewItem

from app.gui.studies import load_study
from app.gui.study_table import (
    SHARED_RANK_NOTE,
    RankedDesign,
    RunHeading,
    RunNote,
    ranking_table,
    stacked_ranking,
    tie_note,
    ties_beyond,
)
from app.gui.widgets.optimize_panel import design_lines, text_rect
from app.gui.window_layout import STATS_DOCK_SLACK_PX
from app.jobs.requests import StudyRequest, run_study_job

SIZES = [(1600, 950), (1920, 1080)]
#: Fast studies with the widest fixed columns: the longest objective header (fivebar_table1:
#: 'samples with κ > 5', 3 lengths), and a series with its run headings and a vertical scroll
#: bar eating into the width (twin_pantograph_sensor, 7 runs).
STUDIES = ["fivebar_table1", "twin_pantograph_sensor"]


def ranked(qtbot, window, size, study: str) -> None:
    """The window at ``size``, the statistics dock fitted, the Optimize tab up with ``study``'s ranking."""
    window.resize(*size)
    qtbot.waitUntil(lambda: window.width() == size[0] and window.height() == size[1], timeout=5000)
    wait_full_map(qtbot, window)
    stats = window.stats_panel
    qtbot.waitUntil(lambda: not stats._width_timer.isActive() and stats.table.rowCount() > 0, timeout=5000)
    window.optimize_dock.raise_()
    panel = window.optimize_panel
    panel.study_box.setCurrentText(study)
    with qtbot.waitSignal(window.study_runner.finished, timeout=60_000):
        panel.run_button.click()
    qtbot.waitUntil(lambda: panel.table.rowCount() > 0 and panel.table.isVisible(), timeout=5000)
    qtbot.wait(50)                  # the table lays its rows and columns out


def cell_option(table, row: int, column: int) -> QStyleOptionViewItem:
    opt = QStyleOptionViewItem()
    opt.initFrom(table)
    opt.widget = table
    opt.rect = table.visualRect(table.model().index(row, column))
    return opt


@pytest.mark.parametrize("size", SIZES)
@pytest.mark.parametrize("study", STUDIES)
def test_the_ranking_fits_the_narrow_dock_without_a_horizontal_scroll_bar(make_window, qtbot, study, size):
    window = make_window("fivebar_singh", longest=60, size=size)
    ranked(qtbot, window, size, study)
    table = window.optimize_panel.table
    # The dock as narrow as the statistics make it (not widened by the ranking).
    floor = max(window.stats_panel.content_width(), window.optimize_dock.minimumSizeHint().width())
    assert window.optimize_dock.width() <= floor + STATS_DOCK_SLACK_PX
    bar = table.horizontalScrollBar()
    assert bar.maximum() == 0 and not bar.isVisible(), (window.optimize_dock.width(), table.viewport().width(),
                                                        table.horizontalHeader().length())
    header, viewport = table.horizontalHeader(), table.viewport().width()
    for c in range(table.columnCount()):
        assert header.sectionViewportPosition(c) >= 0
        assert header.sectionViewportPosition(c) + header.sectionSize(c) <= viewport, c
        assert header.sectionSize(c) >= header.sectionSizeHint(c), c          # the header's text, whole
    assert_cells_whole(window.optimize_panel)


class RecordingPainter(QPainter):
    """A painter that keeps every ``drawText(rect, flags, text)`` made through it from Python."""

    def __init__(self, device) -> None:
        super().__init__(device)
        self.texts: list[tuple[QRect, Qt.AlignmentFlag, str]] = []

    def drawText(self, *args) -> None:  # noqa: N802 (Qt's name)
        if len(args) == 3 and isinstance(args[0], QRect):
            self.texts.append((QRect(args[0]), args[1], args[2]))
        super().drawText(*args)


def painted_texts(table, row: int, column: int) -> list[tuple[QRect, Qt.AlignmentFlag, str]]:
    """What the cell's delegate draws in it from Python: ``(rect, alignment flags, text)``, empty
    texts left out (none for a cell the style draws)."""
    image = QImage(table.viewport().size(), QImage.Format.Format_ARGB32)
    painter = RecordingPainter(image)
    try:
        index = table.model().index(row, column)
        table.itemDelegateForIndex(index).paint(painter, cell_option(table, row, column), index)
    finally:
        painter.end()
    return [(rect, flags, text) for rect, flags, text in painter.texts if text]


def squashed(text: str) -> str:
    """``text`` without the characters a name may be written or broken with (spaces, ``_``, ``.``, brackets)."""
    return re.sub(r"[\s_.\[\]]", "", text)


def assert_cells_whole(panel) -> None:
    """Rank, objective and run headings unelided; each design's values (with units) drawn whole at
    the right, its parameters' names drawn in full (not elided, in order), every drawn line
    inside its cell's text width and inside its row."""
    table = panel.table
    metrics = table.fontMetrics()
    names = [p.name for p in panel.results[0].study.parameters]
    for r, row in enumerate(panel._rows):
        if not isinstance(row, RankedDesign):       # a run's heading, across the row
            drawn = painted_texts(table, r, 0)
            if not drawn:                           # the style's: one line, elided if too long
                assert metrics.horizontalAdvance(row.text) <= text_rect(cell_option(table, r, 0)).width(), row.text
                continue
            assert_lines_inside(drawn, cell_option(table, r, 0), metrics)
            assert " ".join(text for _, _, text in drawn) == row.text
            continue
        for c, text in ((0, row.rank), (1, row.value)):
            assert metrics.horizontalAdvance(text) <= text_rect(cell_option(table, r, c)).width(), text
        option = cell_option(table, r, 2)
        drawn = painted_texts(table, r, 2)
        right = [text for _, flags, text in drawn if flags & Qt.AlignmentFlag.AlignRight]
        left = [text for _, flags, text in drawn if flags & Qt.AlignmentFlag.AlignLeft]
        assert right == [value for _, value in row.parameters], (r, drawn)       # every value whole
        assert not any("\u2026" in text for text in left), left                  # no name elided
        assert squashed("".join(left)) == squashed("".join(names)), left
        assert_lines_inside(drawn, option, metrics)


def assert_lines_inside(drawn, option: QStyleOptionViewItem, metrics) -> None:
    """Each line drawn in a cell (what shares its rectangle: a name and its value) fits the cell's
    text width, and the row is tall enough for every line."""
    area, cell = text_rect(option), QRect(option.rect)
    for rect, _, text in drawn:
        beside = sum(metrics.horizontalAdvance(t) for q, _, t in drawn if q == rect)
        assert area.left() <= rect.left() and rect.right() <= area.right(), (rect, area)
        assert beside <= rect.width(), (text, rect.width())
        assert cell.top() <= rect.top() and rect.bottom() <= cell.bottom(), (text, rect, cell)


@pytest.mark.parametrize("size", SIZES)
def test_the_twin_pantograph_distance_study_reads_in_the_narrow_dock(make_window, qtbot, size):
    """Its five parameters (``shoulder_separation`` ... ``Q1``, mm and N m) were drawn as ``sho…``,
    ``up…``, ``for…``, ``pe…`` beside their values, and the summary took seven lines of the dock."""
    window = make_window("twin_pantograph", size=size)      # its own grid: the dock as wide as the app makes it
    ranked(qtbot, window, size, "twin_pantograph_distance")
    panel = window.optimize_panel
    bar = panel.table.horizontalScrollBar()
    assert bar.maximum() == 0 and not bar.isVisible()
    assert_cells_whole(panel)
    # The summary: the study's name on one line, what the run did on three at most.
    summary = panel.summary
    lines = summary.height() / summary.fontMetrics().lineSpacing()
    assert lines <= 4, (lines, summary.width(), summary.text())
    study, results = panel.study, panel.results
    evaluations = sum(res.evaluations for res in results)
    brute = sum(res.brute_force_evaluations for res in results)
    seconds = sum(res.wall_seconds for res in results)
    text = summary.text()
    for fact in ("done (100 %) over 6 runs", f"{seconds:.2f} s", f"{evaluations:,} evaluations",
                 f"{100 * evaluations / brute:.2f} %", f"brute force's {brute:,}", "largest GII"):
        assert fact in text, (fact, text)
    head = re.match(r"<b>(.*?)</b>", text).group(1)
    assert study.name.startswith(head.removesuffix("\u2026")) and len(head) > 10, head
    assert study.name in summary.toolTip() and summary.toolTip().endswith(text[text.index("<br>"):])


def test_a_name_is_wrapped_at_its_spaces_or_broken_never_elided(qtbot):
    """``design_lines`` at every width from a letter's to the whole line's: each label is drawn in
    full, on lines no wider than the cell (but a letter), and each value whole at the right."""
    metrics = QFontMetrics(QApplication.font())
    lines = [("shoulder separation", "24 mm"), ("upper arm", "125 mm"), ("Q1", "0.16 N m")]
    widest = ["36 mm", "300 mm", "0.16 N m"]
    seen = set()
    for width in range(metrics.horizontalAdvance("W"), 260):
        drawn = design_lines(lines, width, metrics, widest)
        assert [value for _, value in drawn if value] == [value for _, value in lines]
        assert " ".join(label for label, _ in drawn if label).replace(" ", "") == "".join(
            label for label, _ in lines).replace(" ", "")
        for label, value in drawn:
            if label and value:                 # beside each other: the widest value fits too
                wide = max(metrics.horizontalAdvance(w) for (n, _), w in zip(lines, widest) if n == label)
                assert metrics.horizontalAdvance(label + "  ") + wide <= width
            elif label and len(label) > 1:
                assert metrics.horizontalAdvance(label) <= width, (width, label)
        seen.add(len(drawn))
    assert min(seen) == 3 and max(seen) > 9          # one line each when wide, many when narrow


def test_a_tie_past_a_runs_list_is_said_under_that_run_and_the_summary_keeps_the_shared_rank_note():
    """twin_pantograph_sensor at 100 mm: every design is infeasible, so the tie runs past the ten
    listed. The stacked ranking says it in a ``RunNote`` right under that run's designs, with
    ``ranking_table``'s counts; its ``note`` (the panel's summary) is the one on shared ranks."""
    study = load_study("twin_pantograph_sensor")
    results = run_study_job(StudyRequest(study, top_k=10), lambda f: None, lambda: False)
    flat, stacked = ranking_table(study, results), stacked_ranking(study, results)
    tied = [res for res in results if sum(ties_beyond(res)) > 0]
    assert tied                                          # the 100 mm run at least
    assert stacked.note == SHARED_RANK_NOTE and flat.note.startswith(SHARED_RANK_NOTE)
    notes = [i for i, row in enumerate(stacked.rows) if isinstance(row, RunNote)]
    assert [stacked.rows[i].result for i in notes] == tied
    for i in notes:
        row, above = stacked.rows[i], stacked.rows[i - 1]
        assert isinstance(above, RankedDesign) and above.result is row.result        # under its run's last design
        assert i + 1 == len(stacked.rows) or isinstance(stacked.rows[i + 1], RunHeading)
        assert row.text == tie_note(*ties_beyond(row.result), above.value)
        # ranking_table's sentence for that run, but for the "at key = value unit" its heading says
        heading = [h for h in stacked.rows[:i] if isinstance(h, RunHeading)][-1]
        assert heading.result is row.result
        where = " at " + heading.text.replace("\u00a0", " ")
        assert row.text.replace("The last listed value,", f"The last listed value{where},") in flat.note
