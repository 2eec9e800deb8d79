"""View > Fit map to workspace (issue 26 sec. 6): the preset's map range is drawn around its own
link lengths, so a lengthened link's workspace ran past it; the fitted range holds every feasible
point of the new design and not much more.

Reference: the compute layer's own feasibility (``compute_map``) over a box three times the
fitted range's size at a finer spacing than the map's.
"""
from __future__ import annotations

import numpy as np
from conftest import wait_full_map

from app.logic.map_range import MARGIN_CELLS, SEARCH_POINTS, round_step
from kinematics.grid import GridSpec
from metrics.workspace import compute_map

LONGER_MM = 250.0


def _edge_hits(mask: np.ndarray) -> bool:
    return any(mask.take(i, axis=a).any() for a in range(mask.ndim) for i in (0, -1))


def _action(window, text: str):
    return next(a for menu in window.menuBar().actions() for a in menu.menu().actions()
                if a.text().replace("&", "") == text)


def test_fitting_after_a_longer_link_holds_the_whole_workspace(make_window, qtbot):
    window = make_window("inverse3_prototype", longest=80)
    st = window.state
    preset_grid = st.preset.grid
    row = window.param_panel.rows[("proximal_length", -1)]
    row.spin.setValue(LONGER_MM)
    qtbot.waitUntil(lambda: st.mechanism.parameter_table()[0][1] == LONGER_MM, timeout=5000)
    wait_full_map(qtbot, window)
    # The preset's range cuts the longer design's workspace: feasible points on its edge.
    assert _edge_hits(st.current.map.feasible)

    with qtbot.waitSignal(window.map_fitter.done, timeout=30_000):
        _action(window, "Fit map to workspace").trigger()
    wait_full_map(qtbot, window)
    grid = st.preset.grid
    assert grid != preset_grid and grid.resolution == preset_grid.resolution
    assert grid.axes == preset_grid.axes and grid.fixed == preset_grid.fixed
    wmap = st.current.map
    assert wmap.grid == grid and st.stale is None
    assert wmap.feasible.any() and not _edge_hits(wmap.feasible)      # nothing cut on the map

    # Every feasible point of a box three times as large, sampled finer than the map, lies in the range.
    lo, hi = np.array(grid.lower), np.array(grid.upper)
    span = hi - lo
    big = GridSpec(grid.axes, tuple(lo - span), tuple(hi + span), (301, 301), grid.fixed)
    reference = compute_map(st.mechanism, big, ["isotropic_force"], keep=True)
    pts = big.points(st.mechanism.task_names)[reference.feasible]
    ix = [st.mechanism.task_names.index(a) for a in grid.axes]
    xy = pts[:, ix]
    assert len(xy) and np.all(xy >= lo - 1e-12) and np.all(xy <= hi + 1e-12)
    # And the range is tight: each side within one search cell and one rounding step of the extent.
    for k in range(len(grid.axes)):
        slack = (MARGIN_CELLS + 1) * span[k] / (SEARCH_POINTS - 1) + round_step(span[k]) + 3 * span[k] / 300
        assert xy[:, k].min() - lo[k] <= slack and hi[k] - xy[:, k].max() <= slack, grid.axes[k]

    # A view change, not a design edit: undo still names the link's edit and takes it back.
    assert st.history.undo_text() == f"proximal_length 140 -> {LONGER_MM:g} mm"
    window.undo()
    qtbot.waitUntil(lambda: st.mechanism.parameter_table()[0][1] == 140.0, timeout=5000)
    assert st.preset.grid == grid and not st.modified
