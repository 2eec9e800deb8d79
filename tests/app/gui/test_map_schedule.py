"""A slider step's maps, planned from this session's measured rates (``MainWindow.rates``).

The windows of these tests get rates set by hand (``conftest``: nothing is measured), so the
path each test checks is chosen the same way on any machine: a full map predicted within a
frame is asked for at once; a slower one is previewed coarse (while dragged, with the map
view's quantities alone, sized to the rate), its statistics follow when the slider rests, and
the full map once it has rested ``REFINE_DELAY_MS``. Run under Xvfb (``conftest``).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from app import scenes
from app.gui.main_window import PREVIEW_S, coarse_grid
from app.gui.map_rate import FRAME_S, MapRates, rate_key
from app.gui.widgets.stats_panel import figure_texts
from metrics.workspace import compute_map, resolution_error

SMALL = 121          # points along the longer map axis (fast maps)


def recorded_requests(window) -> list:
    """Every request the window submits from now on, numbered, in order."""
    sent = []
    submit = window.scheduler.submit

    def record(request):
        numbered = submit(request)
        sent.append(numbered)
        return numbered
    window.scheduler.submit = record
    return sent


def proximal_mm(window, factor: float) -> float:
    """The five-bar's proximal link, in mm, ``factor`` times the current one."""
    return round(window.state.mechanism.params.proximal * 1e3 * factor, 3)


def test_a_full_map_measured_within_a_frame_is_asked_for_at_once(waits, make_window, qtbot):
    window = make_window("fivebar_singh", longest=SMALL)
    st = window.state
    full = st.preset.grid
    shown = tuple(sorted(window.map_view.needs()))
    assert set(shown) < set(window.map_quantities())
    # Both kinds within a frame: the dragged slider's (the map view's quantities) and the statistics'.
    window.rates = MapRates()
    for quantities in (shown, window.map_quantities()):
        window.rates.add(rate_key(st.mechanism, quantities), math.prod(full.resolution), FRAME_S / 2)
    sent = recorded_requests(window)

    # Dragged: the full map at once, with the map view's quantities alone; the statistics' at rest.
    value = proximal_mm(window, 1.03)
    window.on_parameter_edited("proximal", value, True)
    assert [(r.stage, r.grid, r.mechanism, r.quantities) for r in sent] == [("full", full, st.mechanism, shown)]
    assert sent[0].figures == "extremes"        # its legend's figures alone: the map at rest takes them all
    assert window.refine_timer.isActive() and not window.figures_timer.isActive()
    qtbot.waitUntil(lambda: st.current.mechanism == st.mechanism, timeout=30_000)
    assert st.current.stage == "full" and st.current.map.grid == full and st.busy       # (its statistics to come)
    assert st.progress == 0.0           # the bar fills for the statistics' map at rest, not the drag's
    np.testing.assert_array_equal(st.current.map.values["isotropic_force"],
                                  compute_map(st.mechanism, full, shown).values["isotropic_force"])
    # Its mean, SD and quantiles are not computed (``nan``): no export writes them.
    assert st.current.map.figures == "extremes"
    with pytest.raises(ValueError, match="still being computed"):
        window._export_inputs()
    # Released where it was: the full map with the statistics' quantities, once.
    window.on_parameter_edited("proximal", value, False)
    waits.full(window)
    assert [(r.stage, set(r.quantities), r.figures) for r in sent[1:]] == \
        [("full", set(window.map_quantities()), "all")]
    qtbot.wait(50)
    assert len(sent) == 2 and not window.refine_timer.isActive()
    assert window.stats_panel.holds_figures(st.current) and not window.stats_panel.stale()
    assert st.current.map.figures == "all" and window._export_inputs()["workspace_map"] is st.current.map

    # A click (no drag): the full map with every quantity at once, and nothing after it.
    window.on_parameter_edited("proximal", proximal_mm(window, 1.03), False)
    assert [(r.stage, r.grid, set(r.quantities)) for r in sent[2:]] == [("full", full, set(window.map_quantities()))]
    assert not window.refine_timer.isActive() and not window.figures_timer.isActive()
    waits.full(window)
    qtbot.wait(50)
    assert len(sent) == 3
    np.testing.assert_array_equal(st.current.map.values["isotropic_force"],
                                  compute_map(st.mechanism, full, window.map_quantities()).values["isotropic_force"])


def test_a_slow_map_is_previewed_with_its_own_quantities_and_its_figures_follow_at_rest(waits, make_window, qtbot):
    window = make_window("fivebar_singh")                  # the preset's 521 x 261 grid
    st = window.state
    full = st.preset.grid
    shown = tuple(sorted(window.map_view.needs()))
    assert set(shown) < set(window.map_quantities())
    # The full map measured at a second; the map's own quantity at 1e5 points a second.
    window.rates = MapRates()
    window.rates.add(rate_key(st.mechanism, window.map_quantities()), math.prod(full.resolution), 1.0)
    window.rates.add(rate_key(st.mechanism, shown, threads=False), 1000, 0.01)     # (previews: on one core)
    panel = window.stats_panel
    before = panel.cell("isotropic_force", "mean")
    sent = recorded_requests(window)

    value = proximal_mm(window, 1.03)
    window.on_parameter_edited("proximal", value, True)
    (preview,) = sent
    assert (preview.stage, preview.quantities) == ("coarse", shown)
    assert preview.grid == coarse_grid(full, 1e5 * PREVIEW_S)
    assert max(preview.grid.resolution) < max(coarse_grid(full).resolution)       # smaller than the default
    qtbot.waitUntil(lambda: st.current.mechanism == st.mechanism, timeout=30_000)
    # The preview is drawn; the statistics of the design before stay, marked stale.
    assert st.current.map.grid == preview.grid
    data = window.map_view.picture.panels[0].data
    expected = compute_map(st.mechanism, preview.grid, shown).values["isotropic_force"]
    on_map = ~np.ma.getmaskarray(data)
    np.testing.assert_array_equal(np.ma.getdata(data)[on_map], expected[on_map])
    assert panel.cell("isotropic_force", "mean") == before and panel.stale()

    # The slider rests: the preview of all quantities, then (REFINE_DELAY_MS) the full map.
    waits.full(window)
    assert [(r.stage, set(r.quantities)) for r in sent[1:]] == [("coarse", set(window.map_quantities())),
                                                              ("full", set(window.map_quantities()))]
    wmap = st.current.map
    stats, error = wmap.stats["isotropic_force"], resolution_error(wmap).get("isotropic_force", {}).get("mean")
    assert panel.cell("isotropic_force", "mean") == figure_texts(stats, "mean", error)[0]
    assert not panel.stale()


def test_the_pose_scene_waits_while_a_slider_moves_behind_the_workspace_tab(waits, make_window, qtbot):
    window = make_window("fivebar_singh", longest=SMALL)
    st, view = window.state, window.pose_view

    def edges():
        return np.asarray(view.plotter.actors["polytope_edges"].mapper.dataset.points, float)

    def edges_of_report():
        report = st.pose_report
        return scenes.to_3d(report.x)[0] + view.scale * scenes.to_3d(report.vertices)

    np.testing.assert_allclose(edges(), edges_of_report(), rtol=0, atol=1e-15)
    before = edges()
    window.tabs.setCurrentWidget(window.workspace_view)
    value = proximal_mm(window, 1.05)
    window.on_parameter_edited("proximal", value, True)
    # Analysed (the status bar's figures), not drawn: the view is behind the other tab.
    assert st.pose_report is not None and st.pose_report.reachable
    np.testing.assert_array_equal(edges(), before)
    assert not np.allclose(edges_of_report(), before, rtol=0, atol=1e-9)
    window.on_parameter_edited("proximal", value, False)        # released: drawn once, still hidden
    np.testing.assert_allclose(edges(), edges_of_report(), rtol=0, atol=1e-15)
    # Shown again after a drag that ended unseen, it shows that design too.
    window.tabs.setCurrentWidget(window.workspace_view)
    window.on_parameter_edited("proximal", proximal_mm(window, 1.02), True)
    window.tabs.setCurrentWidget(view)
    np.testing.assert_allclose(edges(), edges_of_report(), rtol=0, atol=1e-15)
    waits.full(window)


def test_closing_with_a_preview_s_statistics_pending_is_safe(make_window, qtbot):
    window = make_window("fivebar_singh", longest=SMALL)
    window.on_parameter_edited("proximal", proximal_mm(window, 1.03), True)
    assert window.figures_timer.isActive()
    window.close()
    qtbot.wait(window.figures_timer.interval() + 150)     # it must not fire into the shut scheduler
    assert not window.figures_timer.isActive()


def test_a_dragged_slider_s_full_map_is_timed_once_while_the_design_rests(waits, make_window, qtbot):
    """``MainWindow._probe_drag_rate``: after a full map at rest, the full map of the map view's
    quantities alone (what a drag would ask for) is computed unseen, once a rest until it was timed
    ``KEPT`` times, as a map over the cores; a map asked for meanwhile cancels it."""
    from app.gui.map_rate import KEPT
    from app.jobs.requests import PROBE_TAG

    window = make_window("fivebar_singh", longest=SMALL)
    st = window.state
    full = st.preset.grid
    shown = tuple(sorted(window.map_view.needs()))
    window.rates, window.measure_rates = MapRates(), True
    sent = recorded_requests(window)
    # A click (no drag): the full map at rest, then its probe.
    window.on_parameter_edited("proximal", proximal_mm(window, 1.03), False)
    waits.full(window)
    qtbot.waitUntil(lambda: window.rates.measured(rate_key(st.mechanism, shown), math.prod(full.resolution)),
                    timeout=30_000)
    probes = [r for r in sent if r.tag == PROBE_TAG]
    assert [(r.stage, r.grid, r.quantities, r.mechanism, r.drag, r.figures) for r in probes] == \
        [("full", full, shown, st.mechanism, True, "extremes")]         # the job a drag asks for
    assert st.current.generation != probes[0].generation            # never shown
    assert not window.rates.measured(rate_key(st.mechanism, shown, threads=False), math.prod(full.resolution))
    # One more a rest until timed KEPT times; then none.
    for k in range(2, KEPT + 2):
        window.on_parameter_edited("proximal", proximal_mm(window, 1.03), False)
        waits.full(window)
        qtbot.waitUntil(lambda: window.rates.measured(rate_key(st.mechanism, shown), math.prod(full.resolution))
                        == min(k, KEPT), timeout=30_000)
        qtbot.wait(50)
        assert len([r for r in sent if r.tag == PROBE_TAG]) == min(k, KEPT)
    assert window.rates.measured(rate_key(st.mechanism, shown), math.prod(full.resolution)) == KEPT
    # Unmeasured again (a new session's rates), a map asked for cancels the probe in flight.
    window.rates = MapRates()
    window._probe_drag_rate()
    probe = sent[-1]
    assert probe.tag == PROBE_TAG and window.scheduler.is_current(probe)
    window.request_map("full")
    assert not window.scheduler.is_current(probe)
    waits.full(window)


def test_a_drag_s_full_map_superseded_unfinished_is_recorded_as_a_bound_and_timed_again_at_rest(
        waits, make_window, qtbot):
    """``MainWindow._superseded``: a step's full map still computing at the next step took longer
    than predicted; its time so far is recorded (a lower bound), and the next rests time it again
    while a bound is among the kept times."""
    from app.gui.map_rate import KEPT
    from app.jobs.requests import PROBE_TAG

    window = make_window("fivebar_singh", longest=SMALL)
    st = window.state
    full = st.preset.grid
    shown = tuple(sorted(window.map_view.needs()))
    key, points = rate_key(st.mechanism, shown), math.prod(full.resolution)
    window.rates, window.measure_rates = MapRates(), True
    for _ in range(3):
        window.rates.add(key, points, 1e-9)         # predicted far within a frame
    sent = recorded_requests(window)
    window.on_parameter_edited("proximal", proximal_mm(window, 1.03), True)
    (first,) = sent
    assert (first.stage, first.drag) == ("full", True)
    # The next step before the GUI thread took the first one's result: superseded, unfinished.
    window.on_parameter_edited("proximal", proximal_mm(window, 1.03), True)
    assert window.rates.bounded(key, points) and window.rates.seconds(key, points) == 1e-9     # (median of 3)
    assert not window.scheduler.is_current(first)
    # The second step's map, shown, is a whole time, but the bound is still among the kept times.
    qtbot.waitUntil(lambda: st.current is not None and st.current.mechanism == st.mechanism, timeout=30_000)
    assert window.rates.bounded(key, points)
    # At rest, the kind is timed again, a probe a rest, until no kept time is a bound (``KEPT`` rests
    # at most: each probe's whole time pushes one kept time out).
    record, timed = window.rates.add, []
    window.rates.add = lambda k, n, seconds, **kw: (timed.append((k, n, kw)), record(k, n, seconds, **kw))
    for step in range(KEPT):
        window.on_parameter_edited("proximal", proximal_mm(window, 1.01 if step % 2 == 0 else 0.99), False)
        waits.full(window)
        qtbot.waitUntil(lambda n=step + 1: timed.count((key, points, {})) == n, timeout=30_000)
        if not window.rates.bounded(key, points):
            break
    assert not window.rates.bounded(key, points)
    probes = [r for r in sent if r.tag == PROBE_TAG]
    assert 1 <= len(probes) <= KEPT and {r.quantities for r in probes} == {shown}
