"""Issue 9 sections 4-6 in the real window: a 3D box map (the Novint Falcon), joints in the pose
box, and another device as the comparison's reference.

Every value on screen is checked against the compute layer: the plane drawn against the
volume ``compute_map`` returns, sliced; the colour scale against ``colour_scale`` of
the whole volume; the iso-surfaces against their levels; the pose typed as joints against
the model's forward kinematics; the reference column against the reference device's map.
"""
from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt
from test_gui import expected_map, map_image, preset_text

from app.gui.volumes import COARSE_VOLUME_POINTS, workspace_size
from app.logic.colour_scale import colour_scale
from metrics.workspace import compute_map
from resources import load_preset

FALCON = 12        # points along the longest axis of the Falcon's box in these tests (12 x 12 x 11)


def plane_index(window):
    st = window.state
    grid = st.current.map.grid
    k = grid.axes.index(st.slice_axis)
    i = int(np.argmin(np.abs(grid.coordinates()[k] - st.slice_value)))
    return tuple(i if j == k else slice(None) for j in range(3))


def assert_plane_drawn(window) -> None:
    """The heat map holds exactly the current volume's plane: its feasible finite values, blank elsewhere."""
    st = window.state
    wmap = st.current.map
    index = plane_index(window)
    values, feasible = wmap.values[st.quantity][index], wmap.feasible[index]
    data, mask = map_image(window)
    shown = feasible & np.isfinite(values)
    np.testing.assert_array_equal(~mask, shown)
    np.testing.assert_array_equal(data[shown], values[shown])


def test_a_box_map_is_drawn_as_a_movable_plane_on_the_volumes_colour_scale(waits, make_window, qtbot):
    window = make_window("novint_falcon", longest=FALCON)
    st, view = window.state, window.map_view
    qtbot.wait(100)
    assert view.slice_controls.isVisible() and st.slice_axis == "z"
    assert st.current.map.grid.resolution == (12, 12, 11)
    from test_gui import assert_maps_equal
    assert_maps_equal(st.current.map, expected_map(window))
    assert_plane_drawn(window)
    wmap = st.current.map
    # The whole volume's colour range, chosen (the default is the plane's: test_plane_gui.py).
    view.slice_controls.colours.setCurrentIndex(view.slice_controls.colours.findData("volume"))
    scale = colour_scale(st.quantity, st.preset, [(wmap.values[st.quantity], wmap.feasible)])
    assert view.picture.panels[0].scale.limits == scale.limits
    title = view.picture.panels[0].title
    assert f"z = {st.slice_value * 1e3:g} mm" in title or "z = " in title
    # Move the plane with the slider, then along another axis: new plane, the same colour limits.
    clim = scale.limits
    controls = view.slice_controls
    for axis, step in (("z", 2), ("x", -3)):
        if controls.axis.currentText() != axis:
            controls.axis.setCurrentText(axis)
        controls.slider.setValue(controls.slider.value() + step)
        qtbot.wait(50)
        assert st.slice_axis == axis
        k = wmap.grid.axes.index(axis)
        assert st.slice_value == wmap.grid.coordinates()[k][controls.slider.value()]
        assert controls.spin.value() == pytest.approx(st.slice_value * 1e3, abs=5e-4)     # shown to 1 µm
        assert_plane_drawn(window)
        assert view.picture.panels[0].scale.limits == clim
        ax_names = (view.picture.panels[0].xlabel, view.picture.panels[0].ylabel)
        assert all(axis not in name for name in ax_names)
    # A typed position (mm) snaps to the nearest plane.
    controls.spin.setValue(-41.0)
    qtbot.wait(50)
    k = wmap.grid.axes.index("x")
    nearest = int(np.argmin(np.abs(wmap.grid.coordinates()[k] + 0.041)))
    assert st.slice_value == wmap.grid.coordinates()[k][nearest] and plane_index(window)[k] == nearest
    assert_plane_drawn(window)
    # Statistics over the volume, with its size in cm^3.
    header = window.stats_panel.header.text()
    _, size, _ = workspace_size(st.mechanism, wmap.grid, wmap.feasible_points)
    assert "over the volume" in header and f"workspace volume {size:.4g} cm^3" in header
    assert window.stats_panel.cell("isotropic_force", "mean") not in ("", "-")


def test_a_click_on_the_plane_moves_the_device_to_a_point_in_that_plane(waits, make_window, qtbot):
    window = make_window("novint_falcon", longest=FALCON)
    st, view = window.state, window.map_view
    qtbot.wait(100)
    px, py = view.data_to_widget(10.0, -20.0)
    qtbot.mouseClick(view.canvas, Qt.MouseButton.LeftButton, pos=view.canvas.rect().topLeft().__class__(px, py))
    qtbot.waitUntil(lambda: st.pose[2] == st.slice_value, timeout=5000)
    assert st.pose[0] == pytest.approx(0.010, abs=2e-3) and st.pose[1] == pytest.approx(-0.020, abs=2e-3)


def test_the_workspace_view_draws_iso_surfaces_at_their_labelled_levels_and_the_plane(waits, make_window, qtbot):
    window = make_window("novint_falcon", longest=FALCON)
    window.tabs.setCurrentWidget(window.workspace_view)
    st, plotter = window.state, window.workspace_view.plotter
    qtbot.waitUntil(lambda: "box_plane" in plotter.actors, timeout=10_000)
    q = st.quantity
    surfaces = plotter.actors["workspace"].mapper.dataset
    wmap = st.current.map
    finite = wmap.values[q][wmap.feasible & np.isfinite(wmap.values[q])]
    levels = np.percentile(finite, np.linspace(10.0, 90.0, 4))        # quantiles of the values (issue 26)
    # Every point of the iso-surfaces carries one of the levels (interpolated along an edge to
    # exactly the level, so to rounding of the level's magnitude).
    on = np.abs(np.asarray(surfaces.point_data[q])[:, None] - levels[None, :]).min(axis=1)
    assert surfaces.n_points > 0 and on.max() <= 1e-9 * levels.max()
    caption = plotter.actors["box_levels"].get_text(2)
    assert all(f"{v:.3g}" in caption for v in levels) and "N" in caption
    plane = plotter.actors["box_plane"].mapper.dataset
    np.testing.assert_allclose(plane.points[:, 2], st.slice_value, atol=1e-12)
    # Moving the plane moves the drawn plane (the surfaces are kept).
    window.map_view.slice_controls.slider.setValue(2)
    qtbot.waitUntil(lambda: np.allclose(plotter.actors["box_plane"].mapper.dataset.points[:, 2], st.slice_value),
                    timeout=5000)
    np.testing.assert_array_equal(plotter.actors["workspace"].mapper.dataset.points, surfaces.points)
    # Classes have no iso-surfaces: the caption says so and the plane shows them.
    window.quantity_box.setCurrentIndex(window.quantity_box.findData("bottleneck"))
    qtbot.waitUntil(lambda: "no iso-surfaces" in plotter.actors["box_levels"].get_text(2),
                    timeout=20_000)
    assert "workspace" not in plotter.actors


def test_a_drag_follows_with_a_coarse_volume_then_refines(waits, make_window, qtbot, monkeypatch):
    import app.gui.main_window as mw
    # The preset's box at 30^3, so that a coarse volume is smaller than the full one.
    original = mw.load_preset
    monkeypatch.setattr(mw, "load_preset", lambda key: (lambda p: p.replace(grid=p.grid.with_resolution(30)))(
        original(key)))
    window = make_window("novint_falcon")
    window.tabs.setCurrentWidget(window.workspace_view)
    st, view = window.state, window.workspace_view
    seen, drawn = [], []
    st.mapChanged.connect(lambda: seen.append((st.current.stage, st.current.map.grid.resolution,
                                               st.current.mechanism, st.current.generation)))
    # The scenes the view shows (built on its worker, swapped in on the GUI thread), by map generation.
    show = view._show
    monkeypatch.setattr(view, "_show", lambda request, parts: (drawn.append(request.view_key[0]),
                                                               show(request, parts)))
    window.on_parameter_edited("upper_arm", 62.0, True)
    # Hold the refinement back until the coarse volume is on screen: on a loaded machine the GUI
    # thread may be slower than the refine delay, and a newer request supersedes the coarse one.
    window.refine_timer.stop()

    def coarse() -> int | None:
        return next((g for s, _, m, g in seen if s == "coarse" and m == st.mechanism), None)
    qtbot.waitUntil(lambda: coarse() is not None and coarse() in drawn, timeout=30_000)
    window.refine_timer.start()
    waits.full(window)
    qtbot.waitUntil(lambda: drawn[-1] == st.current.generation, timeout=30_000)
    stages = [(s, r) for s, r, m, g in seen if m == st.mechanism and g in drawn]
    # The coarse volume reached the 3D view too (drawn), then the full one.
    assert ("coarse", (COARSE_VOLUME_POINTS,) * 3) in stages
    assert stages[-1] == ("full", (30, 30, 30))
    wmap = st.current.map
    assert np.array_equal(wmap.values["isotropic_force"], compute_map(
        st.mechanism, st.preset.grid, window.map_quantities()).values["isotropic_force"], equal_nan=True)


def test_the_pose_box_takes_joint_angles(waits, make_window, qtbot):
    window = make_window("novint_falcon", longest=FALCON)
    st = window.state
    box = window.pose_mode
    box.setCurrentIndex(box.findData("joints"))
    assert "q1 (deg)" in window.pose_edit.placeholderText()
    # The box shows the joints of the pose on screen.
    shown = [float(v) for v in window.pose_edit.text().split(",")]
    q, _ = st.mechanism.inverse(np.asarray(st.pose))
    np.testing.assert_allclose(shown, np.degrees(q), atol=0.005)        # printed to 2 decimals
    target = np.array([20.0, 35.0, 10.0])
    window.pose_edit.setText(", ".join(f"{v:g}" for v in target))
    qtbot.keyClick(window.pose_edit, Qt.Key.Key_Return)
    x, ok = st.mechanism.forward(np.radians(target))
    assert bool(ok)
    assert st.pose == tuple(float(v) for v in x)
    np.testing.assert_allclose(st.pose_report.joints, np.radians(target), atol=1e-9)
    # A wrong count, or joints that do not assemble, change nothing and say why.
    before = st.pose
    for text in ("1, 2", "180, 0, 0"):
        window.pose_edit.setText(text)
        qtbot.keyClick(window.pose_edit, Qt.Key.Key_Return)
        assert st.pose == before
    assert "does not assemble" in window.statusBar().currentMessage()
    box.setCurrentIndex(box.findData("position"))
    assert window.pose_edit.text() == ", ".join(f"{v * 1e3:.1f}" for v in st.pose)


def test_another_device_as_the_reference_on_one_colour_scale_and_a_refusal_when_maps_differ(
        waits, make_window, qtbot, tmp_path):
    window = make_window("novint_falcon", longest=FALCON)
    st = window.state
    other = tmp_path / "falcon_long_arm.toml"
    other.write_text(preset_text("novint_falcon").replace("upper_arm = 60.0", "upper_arm = 66.0")
                     .replace('name = "Novint Falcon"', 'name = "Falcon long arm"'), encoding="utf-8")
    assert window.set_reference_device(str(other))
    waits.reference(window)
    qtbot.wait(150)
    ref_preset = load_preset(str(other))
    assert st.reference.mechanism == ref_preset.mechanism and st.reference.map.grid == st.reference_preset.grid
    view = window.map_view
    view.slice_controls.colours.setCurrentIndex(view.slice_controls.colours.findData("volume"))   # both volumes
    panels = view.picture.panels
    assert [p.title.split("\n")[1].split(":")[0] for p in panels] == ["reference Falcon long arm",
                                                                      "current Novint Falcon"]
    q = st.quantity
    layers = [(m.values[q], m.feasible) for m in (st.reference.map, st.current.map)]
    assert panels[0].scale.limits == panels[1].scale.limits == colour_scale(q, st.preset, layers).limits
    assert not view.note.isVisible()
    # The statistics side by side: the reference device's figures in their column.
    ref = compute_map(ref_preset.mechanism, st.reference_preset.grid, window.map_quantities())
    from app.logic.figure_digits import format_with_error
    from metrics.workspace import resolution_error
    assert window.stats_panel.cell("isotropic_force", "mean", 3) == format_with_error(
        ref.stats[q].mean, resolution_error(ref)[q]["mean"])[0]
    assert "Reference: Falcon long arm" in window.stats_panel.header.text()
    # A device whose map is a 2D (x, z) slice: not drawn beside the box, and the panel says why.
    assert window.set_reference_device("inverse3_prototype")
    waits.reference(window, timeout=120_000)
    qtbot.wait(150)
    assert view.note.isVisible() and "different coordinates" in view.note.text()
    assert len(view.picture.panels) == 1
    assert window.stats_panel.cell("isotropic_force", "mean", 3) == ""
    assert "not compared" in window.stats_panel.header.text()
    # A broken file: an error, and the reference stays.
    bad = tmp_path / "bad.toml"
    bad.write_text("mechanism = 'delta'\n[parameters]\nupper_arm = -1\n", encoding="utf-8")
    assert not window.set_reference_device(str(bad))
    assert window.last_error and st.reference_preset.key == "inverse3_prototype"


def test_another_devices_scene_is_taken_away_while_a_slice_waits_for_its_full_map(waits, make_window, qtbot):
    """From the Falcon's box to the Twin-Pantograph's slice: a slice's coarse map draws no 3D
    scene, and the Falcon's iso-surfaces, caption and colour bar stayed meanwhile (seen in a
    screenshot beside the pen's semi-dextrous region)."""
    window = make_window("novint_falcon", longest=FALCON)
    window.tabs.setCurrentWidget(window.workspace_view)
    st, view = window.state, window.workspace_view
    plotter = view.plotter
    qtbot.waitUntil(lambda: "box_levels" in plotter.actors and len(plotter.scalar_bars) > 0, timeout=10_000)
    seen = []

    def after_the_view() -> None:        # connected after the view's redraw: runs once it has
        if st.current.stage != "full" and st.preset.key == "twin_pantograph":
            seen.append((sorted(n for n in ("workspace", "box_levels", "box_hull", "box_plane") if n in plotter.actors),
                         len(plotter.scalar_bars), view.view.caption))
    st.mapChanged.connect(after_the_view)
    assert window.load_device("twin_pantograph")
    waits.full(window)
    assert seen, "the switch showed a coarse map first"
    names, bars, caption = seen[0]
    assert names == [] and bars == 0 and "Twin-Pantograph" in caption and "full map" in caption
