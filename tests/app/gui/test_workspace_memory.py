"""The 3D workspace view holds one revolved volume, of bounded size, however often it is redrawn
(issue 21 sec. 0: RSS rose by 440 MB once the Workspace tab was shown on ``inverse3_scenario3``).

Every redraw of the cut-plane view added the mesh PyVista's ``add_mesh_clip_plane`` cut to the
plotter's ``plane_clipped_meshes``, which ``clear_plane_widgets`` keeps: each held its clipper
and the volume it cut, 40-70 MB per full map of the preset's 1000 x 1000 grid, never freed.
(The app's cut plane is its own now, ``app.scenes.workspace._add_cut_volume``, with the same
bookkeeping: the solid it cut in ``plane_clipped_meshes``, the volume it cuts on the actor.)
"""
from __future__ import annotations

from app.scenes.workspace import INTERACTIVE_MAX_POINTS, workspace_volume

LONGEST = 400       # points along the longer map axis: above the view's cap, so the cap applies


def held_datasets(plotter) -> list:
    """Every dataset the plotter keeps: its actors' inputs and the meshes its cut planes made."""
    owner = getattr(plotter, "widgets", plotter)
    shown = [actor.mapper.dataset for actor in plotter.actors.values()
             if getattr(getattr(actor, "mapper", None), "dataset", None) is not None]
    cut_from = [actor._isoforce_cut_volume for actor in plotter.actors.values()
                if getattr(actor, "_isoforce_cut_volume", None) is not None]
    return shown + cut_from + list(owner.plane_clipped_meshes)


def test_the_workspace_view_keeps_one_bounded_volume_over_redraws(make_window, waits, qtbot):
    window = make_window("inverse3_scenario3", longest=LONGEST)
    view = window.workspace_view
    window.tabs.setCurrentWidget(view)
    qtbot.waitUntil(lambda: view._drawn is not None, timeout=30_000)
    plotter = view.plotter
    row = next(iter(window.param_panel.rows.values()))
    sizes = []
    for k in range(4):                                  # four designs, each drawn when its full map arrives
        drawn = view._drawn
        row.spin.setValue(row.spin.value() * (1.01 if k % 2 == 0 else 1 / 1.01))
        waits.full(window)
        qtbot.waitUntil(lambda: view._drawn != drawn, timeout=30_000)
        owner = getattr(plotter, "widgets", plotter)
        assert len(owner.plane_clipped_meshes) == 1 and len(owner.plane_widgets) == 1
        sizes.append(sum(ds.actual_memory_size for ds in held_datasets(plotter)))
    # The same design twice (k = 0, 2 and 1, 3): the same memory, to the kilobyte.
    assert sizes[2] == sizes[0] and sizes[3] == sizes[1], sizes
    # What is cut is the slice revolved at INTERACTIVE_MAX_POINTS per axis, whatever the map's grid.
    st = window.state
    capped = workspace_volume(st.current.map, st.quantity, st.mechanism, max_points=INTERACTIVE_MAX_POINTS)
    assert max(st.current.map.grid.resolution) > INTERACTIVE_MAX_POINTS
    cut_from = plotter.actors["workspace"]._isoforce_cut_volume
    assert (cut_from.GetNumberOfPoints(), cut_from.GetNumberOfCells()) == (capped.n_points, capped.n_cells)
    assert 0 < owner.plane_clipped_meshes[0].n_points < capped.n_points
