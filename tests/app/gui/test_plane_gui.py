"""Issue 21 section 1 in the real window: a 3D box map (the Novint Falcon) on one plane.

The exports (File > Export > Map image, File > Export report) draw the plane on screen; the
plane spin box shows the grid plane the map is on; the pose marker is drawn on its own plane
only. Every value is checked against the volume the compute layer returns, indexed by hand.
"""
from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtGui import QAction

import app.plots.figures as figures

FALCON = 12        # points along the longest axis of the Falcon's box in these tests (12 x 12 x 11)


def plane_k(window) -> int:
    st = window.state
    grid = st.current.map.grid
    k = grid.axes.index(st.slice_axis)
    return int(np.argmin(np.abs(grid.coordinates()[k] - st.slice_value)))


def test_the_map_export_and_the_report_draw_the_plane_on_screen(make_window, qtbot, tmp_path, monkeypatch):
    window = make_window("novint_falcon", longest=FALCON)
    st = window.state
    grid = st.current.map.grid
    st.set_slice("x", float(grid.coordinates()[0][4]))
    drawn = []
    original = figures.map_figure

    def spy(wmap, quantity, preset, **kwargs):
        drawn.append(wmap)
        return original(wmap, quantity, preset, **kwargs)

    monkeypatch.setattr(figures, "map_figure", spy)
    path = window.export("map", tmp_path / "map.png")
    assert path.stat().st_size > 1000
    (plane,) = drawn
    volume = st.current.map
    assert plane.grid.axes == ("y", "z") and dict(plane.grid.fixed)["x"] == grid.coordinates()[0][4]
    np.testing.assert_array_equal(plane.feasible, volume.feasible[4])
    ok = volume.feasible[4]
    np.testing.assert_array_equal(plane.values[st.quantity][ok], volume.values[st.quantity][4][ok])
    # The report: its map figures on that plane too, its data the whole volume.
    drawn.clear()
    written = window.export_report(tmp_path)
    assert {p.name for p in written} >= {"map_isotropic_force.png", "map.npz", "workspace.png"}
    assert drawn and all(m.grid.fixed == plane.grid.fixed for m in drawn)
    assert np.load(tmp_path / "map.npz")["isotropic_force"].shape == volume.grid.resolution


def test_the_plane_spin_box_shows_the_grid_plane_the_map_is_on(make_window, qtbot):
    """Typed 170 mm on the Falcon's own grid (z planes 4.444 mm apart from 30 mm): the map is on
    the plane z = 172.222 mm, and the spin box, the model and the title all say so."""
    window = make_window("novint_falcon")
    st, controls = window.state, window.map_view.slice_controls
    z = st.preset.grid.coordinates()[2]
    nearest = float(z[np.argmin(np.abs(z - 0.170))])
    assert abs(nearest * 1e3 - 172.222) < 1e-3        # (30 + 32 * 160 / 36 mm)
    controls.spin.setValue(170.0)
    qtbot.waitUntil(lambda: st.slice_value == nearest, timeout=5000)
    qtbot.waitUntil(lambda: "z = 172.222 mm" in window.map_view.picture.panels[0].title, timeout=5000)
    assert controls.spin.text() == "172.222 mm"
    assert controls.slider.value() == int(np.argmin(np.abs(z - 0.170)))
    # The arrows step one grid plane: the next plane up, shown as the title shows it.
    controls.spin.stepUp()
    qtbot.waitUntil(lambda: st.slice_value == float(z[33]), timeout=5000)
    assert controls.spin.text() == f"{z[33] * 1e3:.3f} mm"
    assert f"z = {z[33] * 1e3:g} mm" in window.map_view.picture.panels[0].title


def red_pixels(window, centre, radius: int = 10) -> int:
    """Pure-red pixels (the pose cross; no viridis colour) within ``radius`` of ``centre`` (widget px)."""
    from conftest import widget_rgb
    rgb = widget_rgb(window.map_view.canvas).astype(int)
    x, y = centre
    patch = rgb[max(0, y - radius):y + radius + 1, max(0, x - radius):x + radius + 1]
    return int(np.count_nonzero((patch[..., 0] > 200) & (patch[..., 1] < 60) & (patch[..., 2] < 60)))


def test_the_pose_cross_is_drawn_on_its_own_plane_only(make_window, qtbot):
    window = make_window("novint_falcon", longest=FALCON)
    st, view = window.state, window.map_view
    grid = st.current.map.grid
    z = grid.coordinates()[2]
    k_pose = int(np.argmin(np.abs(z - st.pose[2])))
    st.set_slice("z", float(z[k_pose]))
    qtbot.wait(50)
    assert view.canvas.pose_mm == (st.pose[0] * 1e3, st.pose[1] * 1e3) and view.canvas.pose_note is None
    where = view.data_to_widget(*view.canvas.pose_mm)
    assert red_pixels(window, where) > 10
    # Another plane: no cross where the pose's (x, y) are, and a note saying where the pose is.
    st.set_slice("z", float(z[k_pose + 3]))
    qtbot.waitUntil(lambda: view.canvas.pose_mm is None, timeout=5000)
    assert view.canvas.pose_note == f"pose at z = {st.pose[2] * 1e3:g} mm" == "pose at z = 110 mm"
    view.canvas.repaint()
    assert red_pixels(window, where) == 0
    # The note is painted in the panel's top left corner (dark red text on white).
    axes = view.canvas.layouts[-1].axes
    from conftest import widget_rgb
    corner = widget_rgb(view.canvas).astype(int)[int(axes.top()) + 4:int(axes.top()) + 24,
                                                  int(axes.left()) + 4:int(axes.left()) + 120]
    assert np.count_nonzero((corner[..., 0] > 150) & (corner[..., 1] < 80) & (corner[..., 2] < 80)) > 20
    # A plane along another axis through the pose: the cross is back.
    st.set_slice("x", float(grid.coordinates()[0][int(np.argmin(np.abs(grid.coordinates()[0] - st.pose[0])))]))
    qtbot.waitUntil(lambda: view.canvas.pose_mm is not None, timeout=5000)
    assert view.canvas.pose_note is None and view.canvas.pose_mm == (st.pose[1] * 1e3, st.pose[2] * 1e3)


def test_a_plane_is_coloured_over_its_own_range_by_default_or_the_volumes(make_window, qtbot, tmp_path,
                                                                            monkeypatch):
    """The Falcon's z = 110 mm plane spans 2.1-6.9 N of the volume's 0.013-18.5 N: drawn on its own
    range by default, on the volume's when chosen; the colour bar and the exported figure say which."""
    window = make_window("novint_falcon")
    st, view = window.state, window.map_view
    volume = st.current.map
    k = plane_k(window)
    assert st.slice_axis == "z" and volume.grid.coordinates()[2][k] == pytest.approx(0.110)
    q = st.quantity
    plane, ok = volume.values[q][:, :, k], volume.feasible[:, :, k]
    everywhere = volume.values[q][volume.feasible & np.isfinite(volume.values[q])]
    assert view.slice_controls.colours.currentData() == "plane" == view.colour_range
    figs = []
    original = figures.map_figure
    monkeypatch.setattr(figures, "map_figure", lambda *a, **kw: figs.append(original(*a, **kw)) or figs[-1])
    for choice, values, note in (("plane", plane[ok & np.isfinite(plane)], "colours: this plane"),
                                 ("volume", everywhere, "colours: whole volume")):
        view.slice_controls.colours.setCurrentIndex(view.slice_controls.colours.findData(choice))
        qtbot.waitUntil(lambda: note in view.picture.bar.label, timeout=5000)
        lo, hi = view.picture.panels[0].scale.limits
        # The lower limit is the range's minimum; the upper is its maximum unless capped (a percentile).
        assert lo == values.min() and hi <= values.max()
        assert hi > 0.5 * values.max()
        window.export("map", tmp_path / f"map_{choice}.png")
        image = figs[-1].axes[0].images[0]
        assert image.get_clim() == (lo, hi)
        assert note in figs[-1].axes[1].get_ylabel()
    # The plane's range is the narrower: 2.1-6.9 N against the volume's 0.013-18.5 N (issue 21).
    assert plane[ok].min() > 2.0 and plane[ok].max() < 7.0 and everywhere.min() < 0.1 and everywhere.max() > 18


@pytest.mark.parametrize("size", [(1600, 950), (1920, 1080)])
def test_two_devices_side_by_side_are_drawn_at_one_length_scale(make_window, qtbot, waits, size):
    """Compare > Reference device: the PHANToM Premium 1.5's slice (three times the Omni's area) is
    drawn three times the Omni's area on screen, both panels at one millimetre per pixel."""
    window = make_window("phantom_omni", longest=60, size=size)
    assert window.set_reference_device("phantom_premium_15")
    waits.reference(window)
    view = window.map_view
    qtbot.waitUntil(lambda: len(view.picture.panels) == 2, timeout=10_000)
    canvas = view.canvas
    scales = []
    for lay, panel in zip(canvas.layouts, view.picture.panels):
        x0, x1, y0, y1 = panel.limits
        scales.append((lay.axes.width() / (x1 - x0), lay.axes.height() / (y1 - y0)))
    (rx, ry), (cx, cy) = scales
    assert rx == pytest.approx(cx, rel=1e-9) and ry == pytest.approx(cy, rel=1e-9) and rx == pytest.approx(ry)
    ref, cur = view.picture.panels
    area = [(p.limits[1] - p.limits[0]) * (p.limits[3] - p.limits[2]) for p in (ref, cur)]
    drawn = [lay.axes.width() * lay.axes.height() for lay in canvas.layouts]
    assert area[0] > 2.5 * area[1] and drawn[0] / drawn[1] == pytest.approx(area[0] / area[1], rel=1e-9)
    # Inside the canvas, and a click still lands on the map point under it.
    for lay in canvas.layouts:
        assert canvas.rect().toRectF().contains(lay.axes)
    px, py = view.data_to_widget(100.0, 0.0, panel=0)
    hit = canvas.to_data(px + 0.5, py + 0.5)
    assert hit[0] == 0 and abs(hit[1] - 100.0) < 2 / rx and abs(hit[2]) < 2 / ry


def test_difference_of_two_devices_on_different_grids_is_disabled_with_the_reason(make_window, qtbot, waits):
    window = make_window("phantom_omni", longest=40)
    st, view = window.state, window.map_view
    difference = next(a for a in window.findChildren(QAction) if a.text().startswith("Difference"))
    assert difference.isEnabled()
    st.set_compare_mode("difference")          # chosen before the reference device
    assert window.set_reference_device("phantom_premium_15")
    waits.reference(window)
    qtbot.waitUntil(lambda: len(view.picture.panels) == 2, timeout=10_000)
    assert st.reference_grid != st.preset.grid
    assert not difference.isEnabled() and st.compare_mode == "side"
    assert "different grids" in difference.toolTip() and "PHANToM Premium 1.5" in difference.toolTip()
    assert view.difference_note.isVisible() and "different grids" in view.difference_note.text()
    st.set_compare_mode("difference")          # e.g. the shortcut: refused the same way
    assert st.compare_mode == "side" and len(view.picture.panels) == 2
    # The same device pinned: one grid, the difference is back and drawn.
    st.clear_reference()
    window.pin_reference()
    qtbot.waitUntil(lambda: st.reference is not None, timeout=10_000)
    assert difference.isEnabled() and not view.difference_note.isVisible()
    difference.trigger()
    qtbot.waitUntil(lambda: len(view.picture.panels) == 1, timeout=10_000)
    assert st.compare_mode == "difference"


def test_the_background_report_of_a_box_map_is_written_on_the_plane_on_screen(make_window, qtbot, tmp_path,
                                                                                monkeypatch):
    """File > Export report (the background exporter) with the Falcon: every file written, the map
    figures of the plane on screen (it failed on "wmap must be a 2D slice" before)."""
    import app.render.views
    from app.gui.export_job import exporter_of
    monkeypatch.setattr(app.render.views, "DEFAULT_SIZE", (400, 300))
    window = make_window("novint_falcon", longest=FALCON)
    st = window.state
    st.set_slice("y", float(st.current.map.grid.coordinates()[1][3]))
    drawn = []
    original = figures.map_figure
    monkeypatch.setattr(figures, "map_figure", lambda w, *a, **kw: drawn.append(w) or original(w, *a, **kw))
    done = []
    exporter = exporter_of(window)
    exporter.finished.connect(done.append)
    request = exporter.start(tmp_path / "report", window._export_inputs())
    qtbot.waitUntil(lambda: bool(done), timeout=120_000)
    assert sorted(p.name for p in (tmp_path / "report").iterdir()) == sorted(name for _, name in request.files)
    assert len(drawn) == 3 and all(dict(m.grid.fixed) == {"y": st.slice_value} for m in drawn)   # PNG, SVG, PDF
