"""The optimization panel drives a real study in the background and loads its designs."""
from __future__ import annotations

import re

from app.gui.studies import load_study
from app.gui.study_table import column_digits, column_texts, ranking_table
from metrics.design import run_study


def table_texts(panel) -> tuple[list[str], list[list[str]]]:
    """The panel's header labels and cell texts, as shown."""
    t = panel.table
    header = [t.horizontalHeaderItem(c).text() for c in range(t.columnCount())]
    return header, [[t.item(r, c).text() for c in range(t.columnCount())] for r in range(t.rowCount())]


def test_the_panel_runs_a_study_ranks_it_like_run_study_and_loads_the_best_design(make_window, waits, qtbot):
    window = make_window("fivebar_singh", longest=80)
    panel = window.optimize_panel
    panel.study_box.setCurrentText("fivebar_table1")
    with qtbot.waitSignal(window.study_runner.finished, timeout=60000):
        panel.run_button.click()
    assert panel.run_button.isEnabled() and not panel.cancel_button.isEnabled()

    study = load_study("fivebar_table1")
    expected = run_study(study, workers=1, top_k=study.objective.top_k)      # the study's own top_k = 5
    shown = [row.design for row in panel._rows]
    assert shown == [int(d) for d in expected.top_designs]
    header, cells = table_texts(panel)
    # One rank column (no row numbers beside it), a unit under every other header: the design's
    # parameters (stacked in one column, the dock is narrow) share the millimetre.
    assert not panel.table.verticalHeader().isVisible() and header.count("rank") == 1
    assert header == ["rank", "samples\nwith\nκ\u00a0>\u00a05\n(samples)", "design\n(mm)"]
    assert "samples with κ\u00a0>\u00a05 (samples)" in panel.table.horizontalHeaderItem(1).toolTip()
    # The values as run_study has them, with the column's digits; 468 samples twice: a shared rank 4.
    digits = column_digits(expected.top_values)
    assert [row[1] for row in cells] == column_texts(expected.top_values, digits)
    assert study.objective.top_k == 5 and len(cells) == 5
    assert "Best: fewest samples with κ\u00a0&gt;\u00a05." in panel.summary.text()          # (rich text)
    assert [row[0] for row in cells] == ["1", "2", "3", "4=", "4="]
    # ranking_table's texts, character for character: rank, objective, each parameter by name.
    names, flat = ["proximal", "distal", "half_base"], [c for _, _, c in ranking_table(study, [expected]).rows]
    assert cells == [[c[0], c[-1], "\n".join(f"{n} = {v}" for n, v in zip(names, c[1:-1]))] for c in flat]
    # The cell's tooltip: each parameter with its unit (the names in full where the column elides them).
    assert panel.table.item(0, 2).toolTip() == "\n".join(f"{n} = {v}\u00a0mm" for n, v in zip(names, flat[0][1:-1]))
    assert panel.progress.value() == 100 and panel.progress.text() == "done: 100 %"
    assert "done (100 %)" in panel.summary.text() and "share a rank" in panel.summary.text()

    panel.table.selectRow(1)
    panel.load_button.click()
    waits.full(window)
    assert window.state.mechanism == study.design_mechanism(int(expected.top_designs[1]))
    assert window.state.current.mechanism == window.state.mechanism


def test_a_new_study_clears_the_old_ranking_and_cancel_says_where_it_stopped(make_window, qtbot):
    window = make_window("fivebar_singh", longest=80)
    panel = window.optimize_panel
    panel.study_box.setCurrentText("fivebar_table1")
    with qtbot.waitSignal(window.study_runner.finished, timeout=60000):
        panel.run_button.click()
    assert panel.table.rowCount() == 5 and panel.load_button.isEnabled()     # the study's top_k
    panel.study_box.setCurrentText("twin_pantograph_distance")     # the slow one: six runs
    with qtbot.waitSignal(window.study_runner.cancelled, timeout=60000):
        panel.run_button.click()
        # At once, before any result: the old ranking is gone and nothing can be loaded from it.
        assert panel.table.rowCount() == 0 and panel.table.columnCount() == 0 and not panel.load_button.isEnabled()
        assert panel.progress.value() == 0 and panel.progress.text() == "run 1 of 6: 0 %"
        assert panel.summary.text().endswith(": run 1 of 6, 0 % done.")
        qtbot.wait(200)
        panel.cancel_button.click()
    percent = panel.progress.value()
    assert panel.progress.text() == f"cancelled at {percent} %" and panel.run_button.isEnabled()
    assert re.fullmatch(rf"Cancelled at {percent} % \(run [1-6] of 6\); no ranking\.", panel.summary.text())
    assert panel.table.rowCount() == 0


def test_the_progress_bar_and_the_summary_show_the_same_fraction_and_phase(make_window, qtbot):
    window = make_window("fivebar_singh", longest=80)
    panel = window.optimize_panel
    panel.study_box.setCurrentText("twin_pantograph_sensor")       # seven runs, one chunk each
    seen = []
    # Connected after the panel's own slot, so it sees what the panel shows for each report.
    window.study_runner.progressed.connect(
        lambda f: seen.append((f, panel.progress.value(), panel.progress.text(), panel.summary.text())))
    with qtbot.waitSignal(window.study_runner.finished, timeout=60000):
        panel.run_button.click()
    n = len(load_study("twin_pantograph_sensor").runs())
    assert [f for f, *_ in seen] == [(k + 1) / n for k in range(n)]
    for k, (f, value, bar, summary) in enumerate(seen):
        # After run k + 1 of n the next one starts; the last report is the end of the last run.
        phase = f"run {min(k + 2, n)} of {n}"
        assert value == round(100 * f) and bar == f"{phase}: {value} %"
        assert summary.endswith(f": {phase}, {value} % done.")
    assert panel.progress.value() == 100 and panel.progress.text() == "done: 100 %"
    assert "done (100 %) over 7 runs" in panel.summary.text()


def test_a_bad_study_says_why_in_the_panel_and_in_an_error_dialog(make_window, tmp_path):
    window = make_window("fivebar_singh", longest=80)
    panel = window.optimize_panel
    bad = tmp_path / "bad_study.toml"
    bad.write_text("[grid]\nproximal = [100.0]\n", encoding="utf-8")
    panel.study_box.addItem(str(bad))
    panel.study_box.setCurrentText(str(bad))
    panel.run_button.click()
    assert panel.run_button.isEnabled() and not panel.cancel_button.isEnabled()     # nothing started
    assert panel.summary.text().startswith("<b>Cannot run:</b> study '") and "bad_study.toml" in panel.summary.text()
    assert window.last_error.startswith("The study cannot be run: study '") and "bad_study.toml" in window.last_error
    assert "STUDY:" not in window.last_error and window.error_box.isVisible()
