"""The optimisation panel drives a real study in the background and loads its designs."""
from __future__ import annotations

from app.optimize_cli import load_study
from metrics.studies import run_study


def test_the_panel_runs_a_study_ranks_it_like_run_study_and_loads_the_best_design(make_window, waits, qtbot):
    window = make_window("fivebar_singh", longest=80)
    panel = window.optimise_panel
    panel.study_box.setCurrentText("fivebar_table1")
    with qtbot.waitSignal(window.study_runner.finished, timeout=60000):
        panel.run_button.click()
    assert panel.run_button.isEnabled() and not panel.cancel_button.isEnabled()

    study = load_study("fivebar_table1")
    expected = run_study(study, workers=1, top_k=10)
    shown = [int(design) for _, design, _ in panel._rows]
    assert shown == [int(d) for d in expected.top_designs]
    assert panel.table.item(0, panel.table.columnCount() - 1).text() == f"{expected.top_values[0]:.6g}"

    panel.table.selectRow(1)
    panel.load_button.click()
    waits.full(window)
    assert window.state.mechanism == study.design_mechanism(int(expected.top_designs[1]))
    assert window.state.current.mechanism == window.state.mechanism


def test_cancel_stops_a_running_study_and_the_panel_says_so(make_window, qtbot):
    window = make_window("fivebar_singh", longest=80)
    panel = window.optimise_panel
    panel.study_box.setCurrentText("twin_pantograph_distance")     # the slow one: ~30 s in full
    with qtbot.waitSignal(window.study_runner.cancelled, timeout=60000):
        panel.run_button.click()
        qtbot.wait(200)
        panel.cancel_button.click()
    assert panel.summary.text() == "Cancelled." and panel.run_button.isEnabled()
