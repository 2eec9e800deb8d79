"""The statistics panel says which figures its grid does not resolve, and which grid would (issue 26
sec. 5): the same note as ``isoforce stats`` (``figure_digits.unresolved_note``), on the error cell
(red, tooltip) and in a line under the table; no error reads "0.000"."""
from __future__ import annotations

import re

from conftest import wait_full_map
from PySide6.QtCore import Qt

from app.gui.widgets.stats_panel import UNRESOLVED_COLOUR
from app.logic.display_units import display_unit, scaled_errors, scaled_stats
from app.logic.figure_digits import shown_error, unresolved_note


def test_unresolved_figures_name_the_grid_that_would_resolve_them(make_window, qtbot):
    # The PHANToM Premium on a 10 x 16 slice: its heaviest direction's mean and p95 are not resolved.
    window = make_window("phantom_premium_15", longest=16)
    wait_full_map(qtbot, window)
    panel, wmap = window.stats_panel, window.state.current.map
    resolution = tuple(wmap.grid.resolution)
    notes = []
    for (q, fig), row in panel.rows.items():
        if q == "gci":
            continue
        _, factor = display_unit(q)
        stats = scaled_stats(wmap.stats[q], factor)
        error = scaled_errors(wmap.errors[q], factor)[fig]
        value = getattr(stats, fig)
        expected = ("" if fig == "max" and stats.unbounded else
                    unresolved_note(value, shown_error(value, error), wmap.error_orders[q][fig], resolution))
        item = panel.table.item(row, 2)
        assert not re.fullmatch(r"0(\.0*)?(e[+-]\d+)?", item.text()), (q, fig, item.text())
        if expected:
            notes.append(expected)
            assert item.toolTip().lower().startswith(expected[:20].lower()), (q, fig, item.toolTip())
            assert expected.split("; ")[1] in item.toolTip()
            assert item.foreground().color().name() == UNRESOLVED_COLOUR
        else:
            assert item.toolTip() == "" and item.foreground().style() == Qt.BrushStyle.NoBrush, (q, fig)
    assert any("points" in n and "would resolve it" in n for n in notes), notes
    assert panel.unresolved_label.isVisible()
    label = panel.unresolved_label.text()
    for n in notes:                     # each remedy, for one figure ("it") or several ("them")
        assert n.split("; ")[1].rsplit(" resolve ", 1)[0] in label
