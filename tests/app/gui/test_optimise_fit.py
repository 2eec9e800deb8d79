"""The Optimise panel's ranking fits the dock it shares with the statistics: no horizontal
scroll bar at the default 1600 x 950 and at 1920 x 1080, the dock as narrow as the statistics
table makes it; rank and objective whole, every parameter's value and unit whole, and (for
these studies' short names) every parameter's name whole beside it."""
from __future__ import annotations

import pytest
from conftest import wait_full_map
from PySide6.QtWidgets import QStyleOptionViewItem

from app.gui.main_window import STATS_DOCK_SLACK_PX

SIZES = [(1600, 950), (1920, 1080)]
#: Fast studies with the widest fixed columns: the longest objective header (fivebar_table1:
#: 'samples with κ > 5', 3 lengths), and a series with its run headings and a vertical scroll
#: bar eating into the width (twin_pantograph_sensor, 7 runs).
STUDIES = ["fivebar_table1", "twin_pantograph_sensor"]


def ranked(qtbot, window, size, study: str) -> None:
    """The window at ``size``, the statistics dock fitted, the Optimise tab up with ``study``'s ranking."""
    window.resize(*size)
    qtbot.waitUntil(lambda: window.width() == size[0] and window.height() == size[1], timeout=5000)
    wait_full_map(qtbot, window)
    stats = window.stats_panel
    qtbot.waitUntil(lambda: not stats._width_timer.isActive() and stats.table.rowCount() > 0, timeout=5000)
    window.optimise_dock.raise_()
    panel = window.optimise_panel
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
    table = window.optimise_panel.table
    # The dock as narrow as the statistics make it (not widened by the ranking).
    floor = max(window.stats_panel.content_width(), window.optimise_dock.minimumSizeHint().width())
    assert window.optimise_dock.width() <= floor + STATS_DOCK_SLACK_PX
    bar = table.horizontalScrollBar()
    assert bar.maximum() == 0 and not bar.isVisible(), (window.optimise_dock.width(), table.viewport().width(),
                                                        table.horizontalHeader().length())
    header, viewport = table.horizontalHeader(), table.viewport().width()
    for c in range(table.columnCount()):
        assert header.sectionViewportPosition(c) >= 0
        assert header.sectionViewportPosition(c) + header.sectionSize(c) <= viewport, c
        assert header.sectionSize(c) >= header.sectionSizeHint(c), c          # the header's text, whole
    assert_cells_whole(window.optimise_panel)


def assert_cells_whole(panel) -> None:
    """Rank, objective and run headings unelided; each design line's value, unit and name drawn whole."""
    from app.gui.study_table import RankedDesign
    from app.gui.widgets.optimise_panel import LINES_ROLE, fitted_lines, text_rect

    table = panel.table
    metrics = table.fontMetrics()
    for r, row in enumerate(panel._rows):
        if not isinstance(row, RankedDesign):       # a run's heading, across the row
            assert metrics.horizontalAdvance(row.text) <= text_rect(cell_option(table, r, 0)).width(), row.text
            continue
        for c, text in ((0, row.rank), (1, row.value)):
            assert metrics.horizontalAdvance(text) <= text_rect(cell_option(table, r, c)).width(), text
        lines = table.item(r, 2).data(LINES_ROLE)
        assert [tuple(line) for line in lines] == list(row.parameters)
        width = text_rect(cell_option(table, r, 2)).width()
        assert fitted_lines(lines, width, metrics) == list(lines), (width, lines)
        # The row is as tall as its lines.
        assert table.rowHeight(r) >= len(lines) * metrics.lineSpacing()
