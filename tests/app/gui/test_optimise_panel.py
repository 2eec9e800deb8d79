"""The optimisation panel drives a real study in the background and loads its designs."""
from __future__ import annotations

from app.gui.studies import load_study
from metrics.design import run_study


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


def test_a_bad_study_says_why_in_the_panel_and_in_an_error_dialog(make_window, tmp_path):
    window = make_window("fivebar_singh", longest=80)
    panel = window.optimise_panel
    bad = tmp_path / "bad_study.toml"
    bad.write_text("[grid]\nproximal = [100.0]\n", encoding="utf-8")
    panel.study_box.addItem(str(bad))
    panel.study_box.setCurrentText(str(bad))
    panel.run_button.click()
    assert panel.run_button.isEnabled() and not panel.cancel_button.isEnabled()     # nothing started
    assert panel.summary.text().startswith("<b>Cannot run:</b> study '") and "bad_study.toml" in panel.summary.text()
    assert window.last_error.startswith("The study cannot be run: study '") and "bad_study.toml" in window.last_error
    assert "STUDY:" not in window.last_error and window.error_box.isVisible()
