"""The real main window under Xvfb, driven with pytest-qt, checked against the compute layer.

Issue 3's GUI bar: move a slider and the map data and statistics change and equal
``compute_map`` at the new parameter; click the map and the pose glyphs equal
``isoforce pose`` there; a hidden glyph's part is not computed; every export format reads
back; a malformed preset gets an error dialog while the app keeps working. Also: the first
screen, coarse-then-full refinement, stale results never shown, settings redirected to
``tmp_path``, keyboard shortcuts, tooltips, and paper 000's Scenario 2 vs 1 comparison.

Values come from the compute layer (``compute_map``, ``analyse_pose``, ``isoforce pose
--json``), never from the widgets' own arithmetic; the one hard-coded figure is paper 000's.
"""
from __future__ import annotations

import csv
import importlib.resources
import json
import math
import re
import threading
import xml.etree.ElementTree as ET

import matplotlib.image
import numpy as np
import pytest
from conftest import widget_rgb
from PySide6.QtCore import QPoint, Qt
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import QApplication, QFileDialog, QInputDialog, QMessageBox

import app.render.views
import metrics.ellipsoids
import metrics.pose
from app import scenes
from app.cli import main as cli_main
from app.files.export import map_columns
from app.gui.main_window import COARSE_POINTS, REFINE_DELAY_MS, coarse_grid
from app.gui.widgets.stats_panel import FIGURES, figure_texts, relative_change
from app.logic.figure_digits import format_with_error
from app.logic.glyphs import GLYPHS
from app.plots.figures import matplotlib_norm
from metrics.pose import analyse_pose
from metrics.quantities import CORE_QUANTITIES, QUANTITIES, available_quantities
from metrics.workspace import compute_map, resolution_error
from resources import load_preset

SMALL = 121          # points along the longer map axis for most tests (fast maps)


# -- helpers -----------------------------------------------------------------------------------
def expected_map(window, mechanism=None, grid=None):
    """The compute layer's map of what the window should be showing."""
    st = window.state
    return compute_map(mechanism if mechanism is not None else st.mechanism,
                       grid if grid is not None else st.preset.grid, window.map_quantities())


def assert_maps_equal(actual, expected) -> None:
    assert actual.grid == expected.grid
    np.testing.assert_array_equal(actual.feasible, expected.feasible)
    assert set(expected.values) <= set(actual.values)
    for q in expected.values:
        np.testing.assert_array_equal(actual.values[q], expected.values[q], err_msg=q)


def map_image(window):
    """The array the map view's heat map draws, indexed like the map (x first)."""
    data = window.map_view.picture.panels[0].data
    return np.ma.getdata(data), np.ma.getmaskarray(data)


def assert_view_draws(window, wmap, quantity: str) -> None:
    """The heat map on screen holds exactly ``wmap``'s feasible finite values, blank elsewhere."""
    data, mask = map_image(window)
    values = wmap.values[quantity]
    shown = wmap.feasible & np.isfinite(values)
    np.testing.assert_array_equal(~mask, shown)
    np.testing.assert_array_equal(data[shown], values[shown])


def assert_stats_panel_shows(window, wmap, reference=None) -> None:
    panel = window.stats_panel
    # Digits from each map's own resolution-error estimate (stats_panel.format_with_error).
    errors = resolution_error(wmap)
    ref_errors = resolution_error(reference) if reference is not None else {}
    for q in CORE_QUANTITIES:
        for fig in FIGURES:
            value = getattr(wmap.stats[q], fig)
            assert panel.cell(q, fig, 1) == figure_texts(wmap.stats[q], fig, errors.get(q, {}).get(fig))[0], (q, fig)
            if reference is not None:
                old = getattr(reference.stats[q], fig)
                old_text = figure_texts(reference.stats[q], fig, ref_errors.get(q, {}).get(fig))[0]
                assert panel.cell(q, fig, 3) == old_text, (q, fig)
                assert panel.cell(q, fig, 4) == relative_change(value, old), (q, fig)


def pose_json(capsys, device: str, pose_m) -> dict:
    """``isoforce pose DEVICE --at ... --json`` at a pose given in metres."""
    at = ",".join(repr(float(v) * 1e3) for v in pose_m)
    capsys.readouterr()
    status = cli_main(["pose", device, f"--at={at}", "--json"])
    out, err = capsys.readouterr()
    assert status == 0, err
    return json.loads(out)


def actor_points(window, name: str) -> np.ndarray:
    return np.asarray(window.pose_view.plotter.actors[name].mapper.dataset.points, float)


def drawn_glyph_actors(window) -> set[str]:
    names = set(window.pose_view.plotter.actors)
    return {glyph for glyph, actors in scenes.GLYPH_ACTORS.items() if names & set(actors)}


def preset_text(key: str) -> str:
    """The shipped TOML of a preset (to make good and broken copies of it)."""
    return importlib.resources.files("resources").joinpath("presets", f"{key}.toml").read_text(encoding="utf-8")


def set_spin(qtbot, row, value: float) -> None:
    """Type a value into a parameter's spin box and press Enter, as a user does."""
    row.spin.setFocus()
    row.spin.selectAll()
    qtbot.keyClicks(row.spin, f"{value:g}")
    qtbot.keyClick(row.spin, Qt.Key.Key_Return)
    assert row.spin.value() == pytest.approx(value)


def press(qtbot, window, key, modifier=Qt.KeyboardModifier.NoModifier) -> None:
    window.activateWindow()
    qtbot.waitUntil(window.isActiveWindow, timeout=5000)
    qtbot.keyClick(QApplication.focusWidget() or window, key, modifier)


# -- first screen ----------------------------------------------------------------------------
def test_first_screen_is_the_inverse3_isotropic_force_map_with_a_central_pose(make_window):
    window = make_window(device=None)          # empty settings: the default device
    st = window.state
    preset = load_preset("inverse3_prototype")
    assert st.preset.key == "inverse3_prototype" and st.mechanism == preset.mechanism
    assert st.quantity == "isotropic_force" and window.quantity_box.currentData() == "isotropic_force"
    assert st.current.map.grid == preset.grid == st.preset.grid       # the paper's 1000 x 1000 slice
    assert_view_draws(window, st.current.map, "isotropic_force")
    # The pose sits inside the workspace, near the middle of the slice's feasible region.
    report = st.pose_report
    assert report.feasible
    feasible_pts = st.current.map.points[st.current.map.feasible]
    centre = feasible_pts.mean(axis=0)
    spread = feasible_pts.std(axis=0)
    assert np.all(np.abs(np.asarray(st.pose) - centre) <= spread + 1e-12)
    assert report.isotropic_force == analyse_pose(preset.mechanism, np.asarray(st.pose)).isotropic_force
    assert window.last_error is None and window.error_box is None


# -- slider -> map and statistics ---------------------------------------------------------------
def test_slider_move_updates_map_statistics_and_glyphs_to_the_compute_layers(waits, make_window, qtbot):
    window = make_window("fivebar_singh", longest=SMALL)
    st = window.state
    before_map = st.current.map
    before_stats = {q: window.stats_panel.cell(q, "mean") for q in CORE_QUANTITIES}
    before_facets = st.pose_report.facet_distances
    row = window.param_panel.rows[("gear_ratios", 0)]
    steps_before = row.slider.value()

    for _ in range(5):                                   # five page steps with the keyboard
        qtbot.keyClick(row.slider, Qt.Key.Key_PageUp)
    assert row.slider.value() == steps_before + 5 * row.slider.pageStep()
    # The spin box shows the slider's value in the parameter's unit, rounded to its decimals.
    slider_value = row.lo + (row.hi - row.lo) * row.slider.value() / row.slider.maximum()
    assert row.spin.value() == pytest.approx(slider_value, abs=0.5 * 10 ** -row.spin.decimals())

    new_mech = load_preset("fivebar_singh").mechanism.replace_display(gear_ratios=(row.spin.value(), 10.0))
    qtbot.waitUntil(lambda: waits.ready(window) and st.mechanism == new_mech, timeout=30_000)

    expected = expected_map(window, new_mech)
    assert_maps_equal(st.current.map, expected)
    assert not np.array_equal(st.current.map.values["isotropic_force"], before_map.values["isotropic_force"],
                              equal_nan=True)
    assert_view_draws(window, expected, "isotropic_force")
    assert_stats_panel_shows(window, expected)
    assert window.stats_panel.cell("isotropic_force", "mean") != before_stats["isotropic_force"]
    # Gear ratios scale forces, not conditioning (paper 000 sec. 4.2): that row stays put.
    assert window.stats_panel.cell("condition_number", "mean") == before_stats["condition_number"]
    # The glyphs follow too: the pose report is the compute layer's at the new design.
    report = analyse_pose(new_mech, np.asarray(st.pose))
    np.testing.assert_array_equal(st.pose_report.facet_distances, report.facet_distances)
    assert st.pose_report.facet_distances[0] > before_facets[0]       # a larger g1: a farther facet
    assert st.pose_report.isotropic_force == report.isotropic_force
    assert window.progress.value() == 100


def test_a_drag_shows_a_coarse_map_then_refines_to_full_resolution(waits, make_window, qtbot):
    window = make_window("fivebar_singh")                 # the preset's 521 x 261 grid
    st = window.state
    full_grid = st.preset.grid
    small_grid = coarse_grid(full_grid)
    assert max(small_grid.resolution) == COARSE_POINTS < max(full_grid.resolution)
    shown: list = []
    st.mapChanged.connect(lambda: shown.append((st.current, st.mechanism)))

    row = window.param_panel.rows[("proximal", -1)]
    row.slider.setSliderDown(True)                       # the hand holds the slider...
    for step in (5, 10, 15):
        row.slider.setValue(row.slider.value() + step)
        qtbot.wait(20)
    held_mech = st.mechanism
    qtbot.waitUntil(lambda: any(s.stage == "coarse" and s.mechanism == held_mech for s, _ in shown), timeout=30_000)
    row.slider.setSliderDown(False)                      # ...and lets go
    qtbot.waitUntil(lambda: waits.ready(window), timeout=30_000)

    assert st.mechanism == held_mech
    assert all(slot.mechanism == mech for slot, mech in shown)          # never a stale design
    stages = [(s.stage, s.map.grid) for s, _ in shown if s.mechanism == held_mech]
    first_coarse = stages.index(("coarse", small_grid))
    assert stages[-1] == ("full", full_grid) and first_coarse < len(stages) - 1
    coarse_slot = next(s for s, _ in shown if s.mechanism == held_mech and s.stage == "coarse")
    # While held, the coarse map is what the map view draws (the statistics' follow at rest).
    assert_maps_equal(coarse_slot.map, compute_map(held_mech, small_grid, tuple(sorted(window.map_view.needs()))))
    assert_maps_equal(st.current.map, expected_map(window, held_mech, full_grid))
    assert_stats_panel_shows(window, st.current.map)


def test_results_for_stale_parameters_are_never_shown(waits, make_window, qtbot):
    window = make_window("fivebar_singh", longest=SMALL)
    st = window.state
    shown: list = []
    st.mapChanged.connect(lambda: shown.append((st.current, st.mechanism)))
    row = window.param_panel.rows[("distal", -1)]
    for k in range(12):                                   # a burst of edits, faster than any map
        set_spin(qtbot, row, 150.0 + 2.0 * (k + 1))
    waits.full(window)
    assert shown and all(slot.mechanism == mech for slot, mech in shown)
    last = load_preset("fivebar_singh").mechanism.replace_display(distal=174.0)
    assert st.mechanism == last
    assert_maps_equal(st.current.map, expected_map(window, last))

    # A result whose request is no longer the newest is dropped on the GUI thread too.
    slot_before = st.current
    old = window.request_map("full")
    window.request_map("full")
    window.scheduler.resultReady.emit(old, slot_before.map)
    assert st.current is slot_before
    waits.full(window)

    # So is the newest request's result if the design changed without a new request.
    request = window.request_map("full")
    other = st.mechanism.replace_display(distal=140.0)
    st.set_mechanism(other)
    assert window.scheduler.core.wait_idle(30.0)
    qtbot.wait(50)                                        # let the queued result signal arrive
    assert st.current.generation != request.generation
    assert st.current.mechanism != other


# -- clicking the map -> pose glyphs ------------------------------------------------------------
def test_clicking_the_map_moves_the_device_and_the_glyphs_match_isoforce_pose(make_window, qtbot, capsys):
    window = make_window("fivebar_singh", longest=SMALL)
    st = window.state
    target_mm = (40.0, 170.0)
    px, py = window.map_view.data_to_widget(*target_mm)
    qx, _ = window.map_view.data_to_widget(target_mm[0] + 10.0, target_mm[1])
    mm_per_px = 10.0 / abs(qx - px)
    with qtbot.waitSignal(st.poseReportChanged, timeout=5000):
        qtbot.mouseClick(window.map_view.canvas, Qt.MouseButton.LeftButton, pos=QPoint(px, py))
    pose = np.asarray(st.pose)
    assert np.all(np.abs(pose * 1e3 - target_mm) <= 1.5 * mm_per_px), (pose * 1e3, target_mm)
    assert window.pose_edit.text() == ", ".join(f"{v * 1e3:.1f}" for v in pose)

    d = pose_json(capsys, "fivebar_singh", pose)
    assert st.mechanism == load_preset("fivebar_singh").mechanism
    report = st.pose_report
    assert report.feasible and d["feasible"]
    np.testing.assert_allclose(report.x * 1e3, d["x"], rtol=1e-12)
    np.testing.assert_allclose(np.degrees(report.joints), d["joints"], rtol=1e-9)
    assert report.isotropic_force == pytest.approx(d["isotropic_force"], rel=1e-9)
    assert report.anisotropic_force == pytest.approx(d["anisotropic_force"], rel=1e-9)
    assert report.condition_number == pytest.approx(d["condition_number"], rel=1e-9)
    assert report.bottleneck_name == d["bottleneck_actuator"]

    # The glyphs on screen are those numbers, drawn at the device's force scale.
    scale = scenes.force_scale(st.mechanism)
    centre = np.array([*d["x"], 0.0]) / 1e3              # planar: drawn in z = 0
    assert drawn_glyph_actors(window) == {"links", "polytope", "sphere", "reference_forces"}
    vertices = np.c_[np.asarray(d["vertices"]), np.zeros(len(d["vertices"]))]
    np.testing.assert_allclose(actor_points(window, "polytope"), centre + scale * vertices, rtol=1e-9, atol=1e-12)
    radii = np.linalg.norm(actor_points(window, "sphere") - centre, axis=1)
    np.testing.assert_allclose(radii, d["isotropic_force"] * scale, rtol=1e-6)
    for u, force in enumerate(d["reference_forces"]):
        tip = np.r_[force, 0.0] * scale
        pts = actor_points(window, f"reference_force_{u}") - centre
        far = pts[np.argmax(np.linalg.norm(pts, axis=1))]
        np.testing.assert_allclose(far, tip, rtol=1e-5, atol=1e-9 * np.linalg.norm(tip))
    assert f"isotropic {d['isotropic_force']:.3g} N ({d['bottleneck_actuator']} limits)" in window.pose_label.text()

    # A desired force typed in the toolbar, drawn with its clamped version (paper 000 eq. 9).
    desired = np.array([5.0, 30.0])
    window.force_edit.setText("5, 30")
    qtbot.keyClick(window.force_edit, Qt.Key.Key_Return)
    assert st.desired_force == (5.0, 30.0)
    clamped = desired * min(1.0, d["isotropic_force"] / np.linalg.norm(desired))
    for name, vector in (("desired_force", desired), ("clamped_force", clamped)):
        pts = actor_points(window, name) - centre
        far = pts[np.argmax(np.linalg.norm(pts, axis=1))]
        np.testing.assert_allclose(far, np.r_[vector, 0.0] * scale, rtol=1e-5)


def test_a_typed_pose_moves_the_device_and_a_bad_one_is_refused(make_window, qtbot, capsys):
    window = make_window("fivebar_singh", longest=SMALL)
    st = window.state
    window.pose_edit.setText("-60, 120")
    qtbot.keyClick(window.pose_edit, Qt.Key.Key_Return)
    assert st.pose == (-0.06, 0.12)
    d = pose_json(capsys, "fivebar_singh", st.pose)
    assert st.pose_report.isotropic_force == pytest.approx(d["isotropic_force"], rel=1e-12)
    assert st.pose_report.bottleneck_name == d["bottleneck_actuator"]
    window.pose_edit.setText("1, 2, 3")
    qtbot.keyClick(window.pose_edit, Qt.Key.Key_Return)
    assert st.pose == (-0.06, 0.12)
    assert "needs 2 comma-separated numbers" in window.statusBar().currentMessage()


# -- hidden glyphs are neither computed nor drawn -----------------------------------------------
def test_a_hidden_glyph_is_neither_computed_nor_drawn(make_window, qtbot, monkeypatch):
    window = make_window("fivebar_singh", longest=SMALL)
    st = window.state
    full = analyse_pose(st.mechanism, np.array([0.04, 0.17]))          # every part, before counting
    calls = {"_parallelepiped_vertices": 0, "force_ellipsoid": 0}

    def counted(module, name):
        original = getattr(module, name)

        def wrapper(*args, **kwargs):
            if threading.current_thread() is threading.main_thread():     # the GUI thread's pose work
                calls[name] += 1
            return original(*args, **kwargs)
        monkeypatch.setattr(module, name, wrapper)

    # (The pose analysis makes the polytope's vertices from its reference forces: ``metrics.pose``.)
    counted(metrics.pose, "_parallelepiped_vertices")
    counted(metrics.ellipsoids, "force_ellipsoid")

    # Shown by default: the polytope is computed and drawn for every pose.
    assert st.pose != (-0.06, 0.12)
    st.set_pose((-0.06, 0.12))
    assert calls["_parallelepiped_vertices"] == 1 and st.pose_report.vertices is not None
    assert "polytope" in drawn_glyph_actors(window)
    # The force ellipsoid is hidden by default: not computed, not drawn.
    assert calls["force_ellipsoid"] == 0 and st.pose_report.force_ellipsoid is None
    assert "force_ellipsoid" not in drawn_glyph_actors(window)

    window.glyph_actions["polytope"].trigger()            # View > Polytope off
    assert "polytope" not in st.glyphs
    st.set_pose((0.04, 0.17))
    assert calls["_parallelepiped_vertices"] == 1                # not computed again
    assert st.pose_report.vertices is None and st.pose_report.faces is None
    assert "polytope" not in drawn_glyph_actors(window)
    assert not {"polytope", "polytope_edges"} & set(window.pose_view.plotter.actors)
    # What is still shown still matches the compute layer.
    assert st.pose_report.isotropic_force == full.isotropic_force
    np.testing.assert_array_equal(st.pose_report.reference_forces, full.reference_forces)

    window.glyph_actions["force_ellipsoid"].trigger()     # View > Force ellipsoid on
    assert calls["force_ellipsoid"] == 1
    np.testing.assert_allclose(st.pose_report.force_ellipsoid.radii, full.force_ellipsoid.radii, rtol=1e-12)
    assert "force_ellipsoid" in drawn_glyph_actors(window)
    window.glyph_actions["force_ellipsoid"].trigger()
    st.set_pose((0.0, 0.15))
    assert calls["force_ellipsoid"] == 1                  # hidden again: not computed again
    assert st.pose_report.force_ellipsoid is None and "force_ellipsoid" not in drawn_glyph_actors(window)


# -- export ---------------------------------------------------------------------------------
def read_png(path):
    return matplotlib.image.imread(path)


def assert_vector_file(path) -> None:
    data = path.read_bytes()
    if path.suffix == ".pdf":
        assert data.startswith(b"%PDF-") and b"%%EOF" in data[-64:]
    else:
        root = ET.fromstring(data)
        assert root.tag.endswith("svg")


def test_every_export_format_is_written_and_reads_back(waits, make_window, qtbot, tmp_path, monkeypatch):
    # 3D figures at 400 x 300 by default here: VTK's SVG/PDF export takes seconds at 1600 x 1200.
    monkeypatch.setattr(app.render.views, "DEFAULT_SIZE", (400, 300))
    window = make_window("fivebar_singh", longest=SMALL)
    st = window.state
    window.pin_reference()
    set_spin(qtbot, window.param_panel.rows[("gear_ratios", 1)], 14.0)
    qtbot.waitUntil(lambda: waits.ready(window) and st.mechanism != st.reference_mechanism, timeout=30_000)
    waits.reference(window)
    expected = expected_map(window)
    assert_maps_equal(st.current.map, expected)

    # "Export report": every figure as PNG, SVG and PDF, the map data and the statistics.
    report_dir = tmp_path / "report"
    report_dir.mkdir()
    written = window.export_report(report_dir)
    assert len(written) == len(set(written)) == 14
    assert sorted(p.name for p in report_dir.iterdir()) == sorted(p.name for p in written)   # no temp files
    by_name = {p.name: p for p in written}
    for view in ("map_isotropic_force", "pose", "compare_isotropic_force"):
        for suffix in (".png", ".svg", ".pdf"):
            assert f"{view}{suffix}" in by_name
    for path in written:
        if path.suffix == ".png":
            image = read_png(path)
            assert image.ndim == 3 and np.ptp(image[..., :3]) > 0.1, path.name     # not a blank canvas
        elif path.suffix in (".svg", ".pdf"):
            assert_vector_file(path)
    h, w = read_png(by_name["pose.png"]).shape[:2]          # the 3D views' default size, cropped to content
    assert h <= 300 and w <= 400 and max(h / 300, w / 400) > 0.95, (h, w)
    # The pose figure's caption (text in the SVG) carries the compute layer's numbers there.
    caption = " ".join(t.text or "" for t in ET.parse(by_name["pose.svg"]).iter() if t.tag.endswith("text"))
    report = analyse_pose(st.mechanism, np.asarray(st.pose))
    assert f"isotropic force {report.isotropic_force:.3g} N" in caption

    # Map data: every column equals the compute layer's map.
    names, columns = map_columns(expected)
    lines = by_name["map.csv"].read_text().splitlines()     # '#' comments, names, a row per feasible point
    skip = next(i for i, line in enumerate(lines) if not line.startswith("#")) + 1
    table = np.loadtxt(by_name["map.csv"], delimiter=",", skiprows=skip)
    assert lines[skip - 1].split(",") == names
    for k, column in enumerate(columns):
        np.testing.assert_array_equal(table[:, k], column, err_msg=names[k])
    with np.load(by_name["map.npz"]) as npz:
        np.testing.assert_array_equal(npz["feasible"], expected.feasible)
        for q in expected.values:
            np.testing.assert_array_equal(npz[q], expected.values[q])
    # Statistics: JSON and CSV hold the compute layer's figures exactly.
    summary = json.loads(by_name["statistics.json"].read_text())
    with open(by_name["statistics.csv"], newline="") as fh:
        rows = {r["quantity"]: r for r in csv.DictReader(fh)}
    for q in CORE_QUANTITIES:
        for fig in FIGURES:
            value = getattr(expected.stats[q], fig)
            written = summary["quantities"][q][fig]      # JSON: "inf" for an unbounded figure, null for nan
            assert (float(written) if written is not None else math.nan) == value or \
                (written is None and math.isnan(value))
            assert float(rows[q][fig]) == value or math.isnan(value)

    # One view at a time (File > Export): PNG at a chosen size, and what the report leaves out.
    out = tmp_path / "out"
    out.mkdir()
    for what in ("map", "pose", "workspace", "compare"):
        image = read_png(window.export(what, out / f"{what}.png", size=(320, 240)))
        if what in ("pose", "workspace"):       # 3D views: cropped to their content within the size
            assert image.shape[0] <= 240 and image.shape[1] <= 320 and max(
                image.shape[0] / 240, image.shape[1] / 320) > 0.95, (what, image.shape)
        else:
            assert image.shape[:2] == (240, 320), what
    for suffix in (".svg", ".pdf"):
        assert_vector_file(window.export("workspace", out / f"workspace{suffix}"))
    for name in ("map.csv", "map.npz", "stats.csv", "stats.json"):
        what = "data" if name.startswith("map") else "stats"
        assert window.export(what, out / name).read_bytes()[:4] == by_name[
            name.replace("stats", "statistics")].read_bytes()[:4]
    with np.load(out / "map.npz") as npz:
        np.testing.assert_array_equal(npz["isotropic_force"], expected.values["isotropic_force"])


def test_a_failed_export_shows_an_error_and_leaves_no_file(make_window, qtbot, tmp_path, monkeypatch):
    window = make_window("fivebar_singh", longest=SMALL)
    missing = tmp_path / "missing" / "map.png"
    with pytest.raises(ValueError, match="does not exist"):
        window.export("map", missing)
    with pytest.raises(ValueError, match="must end in"):
        window.export("map", tmp_path / "map.jpg")
    assert not (tmp_path / "map.jpg").exists() and not missing.parent.exists()

    # Through the menu's dialogs: a good path writes the file at the typed size...
    good = tmp_path / "map.png"
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (str(good), "PNG (*.png)"))
    monkeypatch.setattr(QInputDialog, "getText", lambda *a, **k: ("400x300", True))
    window.export_dialog("map")
    assert read_png(good).shape[:2] == (300, 400)
    assert window.error_box is None
    # ...and a bad one gets an error dialog, nothing on disk, and the app carries on.
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (str(missing), "PNG (*.png)"))
    window.export_dialog("map")
    assert window.error_box is not None and window.error_box.isVisible()
    assert "nothing was written" in window.error_box.text()
    assert not missing.parent.exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


# -- malformed presets ----------------------------------------------------------------------
def test_a_malformed_preset_gets_an_error_dialog_and_the_app_keeps_working(waits, make_window, qtbot, tmp_path,
                                                                         monkeypatch):
    window = make_window("fivebar_singh", longest=SMALL)
    st = window.state
    before = (st.preset, st.mechanism, st.current)
    good_toml = preset_text("fivebar_singh")
    broken = tmp_path / "broken.toml"
    broken.write_text('name = "unterminated\nmechanism = ', encoding="utf-8")
    wrong = tmp_path / "wrong.toml"
    assert "gear_ratios = [10.0, 10.0]" in good_toml
    wrong.write_text(good_toml.replace("gear_ratios = [10.0, 10.0]", "gear_ratios = [10.0]"), encoding="utf-8")

    assert window.load_device(str(broken)) is False
    box = window.error_box
    assert isinstance(box, QMessageBox) and box.isVisible() and not box.isModal()
    assert box.icon() == QMessageBox.Icon.Critical
    assert str(broken) in box.text() and "not valid TOML" in box.text()
    assert QApplication.activeModalWidget() is None        # the window still takes input
    assert (st.preset, st.mechanism, st.current) == before
    assert window.param_panel.preset_box.currentData() == "fivebar_singh"

    # Through File > Open: the message names the file and the key.
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (str(wrong), "Device presets (*.toml)"))
    window.open_device_dialog()
    assert window.error_box is box and window.error_box.isVisible()     # one dialog at a time, new text
    assert str(wrong) in window.last_error and "parameters.gear_ratios" in window.last_error
    assert (st.preset, st.mechanism, st.current) == before

    # The app keeps working: an edit still reaches the compute layer's map and statistics.
    set_spin(qtbot, window.param_panel.rows[("half_base", -1)], 40.0)
    new_mech = load_preset("fivebar_singh").mechanism.replace_display(half_base=40.0)
    qtbot.waitUntil(lambda: waits.ready(window) and st.mechanism == new_mech, timeout=30_000)
    expected = expected_map(window)
    assert_maps_equal(st.current.map, expected)
    assert_stats_panel_shows(window, expected)
    # And a good file loads.
    good = tmp_path / "good.toml"
    assert "proximal = 100.0" in good_toml
    good.write_text(good_toml.replace("proximal = 100.0", "proximal = 110.0"), encoding="utf-8")
    assert window.load_device(str(good)) is True
    waits.full(window)
    assert st.mechanism == load_preset("fivebar_singh").mechanism.replace_display(proximal=110.0)


def test_an_unknown_last_device_falls_back_to_the_default_and_says_so(make_window, tmp_path):
    settings = tmp_path / "stale.ini"
    settings.write_text("[General]\nlast_device=no_such_device\n", encoding="utf-8")
    window = make_window(None, longest=SMALL, settings_file=settings)
    assert window.state.preset.key == "inverse3_prototype"
    assert "no_such_device" in window.last_error


# -- settings -------------------------------------------------------------------------------
def test_layout_and_last_device_are_remembered_in_the_redirected_settings_file(waits, make_window, qtbot, tmp_path):
    settings = tmp_path / "isoforce.ini"
    first = make_window("fivebar_singh", longest=SMALL, settings_file=settings, size=(1500, 880))
    assert (first.width(), first.height()) == (1500, 880)
    first.stats_dock.hide()
    first.splitter.setSizes([700, 400])
    sizes = first.splitter.sizes()
    first.close()
    assert settings.is_file()
    text = settings.read_text()
    assert "last_device=fivebar_singh" in text and "geometry" in text

    second = make_window(None, longest=SMALL, settings_file=settings, size=None)
    assert second.state.preset.key == "fivebar_singh"
    assert (second.width(), second.height()) == (1500, 880)
    assert not second.stats_dock.isVisible() and second.param_dock.isVisible()
    # The splitter keeps its proportions (the hidden dock gave the central area more room).
    (a, b), (c, d) = sizes, second.splitter.sizes()
    assert a / b > 1.5 and c / d == pytest.approx(a / b, rel=0.02)

    # A device opened from a file is remembered by its path.
    own = tmp_path / "my_device.toml"
    second.on_parameter_edited("proximal", 120.0, False)
    second.save_device(own)
    assert second.load_device(str(own))
    waits.full(second)
    second.close()
    third = make_window(None, longest=SMALL, settings_file=settings)
    assert third.state.preset.source == str(own)
    assert third.state.mechanism == load_preset("fivebar_singh").mechanism.replace_display(proximal=120.0)
    # Nothing went to the default locations (the fixture points them into tmp_path).
    assert not (tmp_path / "env-settings.ini").exists() and not (tmp_path / "xdg-config").exists()


def test_closing_with_a_refinement_pending_is_safe(make_window, qtbot):
    window = make_window("fivebar_singh", longest=SMALL)
    set_spin(qtbot, window.param_panel.rows[("distal", -1)], 160.0)
    assert window.refine_timer.isActive()
    window.close()
    qtbot.wait(REFINE_DELAY_MS + 150)      # the refine timer must not fire into a closed window
    assert not window.refine_timer.isActive()


# -- keyboard and tooltips --------------------------------------------------------------------
def test_keyboard_shortcuts_exist_are_unique_and_work(waits, make_window, qtbot):
    window = make_window("fivebar_singh", longest=SMALL)
    st = window.state
    actions = [a for a in window.findChildren(QAction) if not a.shortcut().isEmpty()]
    keys = [a.shortcut().toString() for a in actions]
    assert len(keys) == len(set(keys)), keys
    by_text = {a.text().replace("&", ""): a.shortcut() for a in actions}
    assert by_text["Open device..."] == QKeySequence(QKeySequence.StandardKey.Open)
    for text in ("Save device as...", "Export report...", "Recompute map", "Pin current design as reference",
                 "Quantities", "Quit"):
        assert not by_text[text].isEmpty(), text
    for name, action in window.glyph_actions.items():
        assert not action.shortcut().isEmpty(), name

    press(qtbot, window, Qt.Key.Key_4, Qt.KeyboardModifier.AltModifier)     # Alt+4: force ellipsoid
    assert "force_ellipsoid" in st.glyphs and st.pose_report.force_ellipsoid is not None
    assert window.glyph_actions["force_ellipsoid"].isChecked()
    press(qtbot, window, Qt.Key.Key_P, Qt.KeyboardModifier.ControlModifier)  # Ctrl+P: pin reference
    assert st.reference_mechanism == st.mechanism and st.reference is st.current
    generation = window.pending["current"].generation
    press(qtbot, window, Qt.Key.Key_F5)                                       # F5: recompute
    assert window.pending["current"].generation > generation
    waits.full(window)
    press(qtbot, window, Qt.Key.Key_BracketRight, Qt.KeyboardModifier.ControlModifier)
    assert st.compare_mode == "difference"


def one_sentence(text: str) -> bool:
    """One sentence: ends with a full stop, none inside (parenthesised references aside)."""
    while re.search(r"\([^()]*\)", text):
        text = re.sub(r"\([^()]*\)", "", text)
    return text.strip().endswith(".") and ". " not in text.strip()[:-1]


def test_tooltips_define_quantities_parameters_glyphs_and_statistics(make_window):
    window = make_window("fivebar_singh", longest=SMALL)
    box = window.quantity_box
    names = [box.itemData(i) for i in range(box.count())]
    assert names == list(available_quantities(window.state.mechanism))
    for i, name in enumerate(names):
        tip = box.itemData(i, Qt.ItemDataRole.ToolTipRole)
        assert tip == QUANTITIES[name].description and one_sentence(tip), name
        assert box.itemText(i) == QUANTITIES[name].label
    for info, _ in window.state.mechanism.parameter_table():
        if info.choices:
            widgets = [window.param_panel.choices[info.name]]
        else:
            widgets = [w for (n, _), row in window.param_panel.rows.items() if n == info.name
                       for w in (row.slider, row.spin)]
        assert widgets, info.name
        for w in widgets:
            assert info.description in w.toolTip() and (info.unit in w.toolTip()), info.name
    for name, action in window.glyph_actions.items():
        assert action.toolTip() == GLYPHS[name] and one_sentence(action.toolTip()), name
    for q in CORE_QUANTITIES:
        item = window.stats_panel.table.item(window.stats_panel.rows[(q, "min")], 0)
        assert item.toolTip() == QUANTITIES[q].description
    for w in (window.pose_edit, window.force_edit, window.map_view.canvas, window.stats_panel.table,
              window.param_panel.preset_box, window.workspace_view.mode):
        assert w.toolTip(), w


# -- quantity, workspace view -------------------------------------------------------------------
def test_choosing_a_quantity_maps_it_and_the_workspace_view_draws_it(waits, make_window, qtbot):
    window = make_window("fivebar_singh", longest=SMALL)
    st = window.state
    window.tabs.setCurrentWidget(window.workspace_view)
    qtbot.waitUntil(lambda: "workspace" in window.workspace_view.plotter.actors, timeout=10_000)

    box = window.quantity_box
    box.setCurrentIndex(box.findData("manipulability"))
    assert st.quantity == "manipulability"
    qtbot.waitUntil(lambda: waits.ready(window) and "manipulability" in st.current.map.values, timeout=30_000)
    expected = expected_map(window)
    assert "manipulability" in window.map_quantities()
    assert_maps_equal(st.current.map, expected)
    assert_view_draws(window, expected, "manipulability")
    title = window.map_view.picture.panels[0].title
    assert "yoshikawa manipulability" in title and f"{expected.feasible_points} feasible points" in title

    # The 3D view holds the same values (the planar map as a flat surface, cut smoothly at the
    # workspace's edge): its grid samples carry the map's values, the edge's cut points values between them.
    qtbot.waitUntil(lambda: window.workspace_view._drawn is not None
                    and window.workspace_view._drawn[1] == "manipulability", timeout=10_000)
    mesh = window.workspace_view.plotter.actors["workspace"].mapper.dataset
    drawn = np.asarray(mesh.point_data["manipulability"])
    values = expected.values["manipulability"][expected.feasible]
    sample = np.asarray(mesh.point_data["feasible"]) == 1.0
    assert sample.sum() > 0.5 * values.size      # a flat picture: every sample (only a revolved slice is capped)
    assert np.all(np.isin(drawn[sample], values))
    assert np.all((drawn[~sample] >= values.min()) & (drawn[~sample] <= values.max()))

    box.setCurrentIndex(box.findData("condition_number"))     # already in the map: no new map
    generation = st.current.generation
    assert st.quantity == "condition_number" and st.current.generation == generation
    assert_view_draws(window, expected, "condition_number")


# -- compare -----------------------------------------------------------------------------------
def test_pinned_reference_and_a_gear_ratio_change_give_paper_000s_scenario_2_comparison(waits, make_window, qtbot):
    """Paper 000: raising g1 to 13.75 raises the global isotropic force 2.2797 -> 3.9140 N (+71.7 %)."""
    window = make_window("inverse3_prototype")           # the paper's 1000 x 1000 slice
    st = window.state
    scenario1 = load_preset("inverse3_prototype")
    scenario2 = load_preset("inverse3_scenario2")
    window.pin_reference()
    assert st.reference is st.current and st.reference_mechanism == scenario1.mechanism

    set_spin(qtbot, window.param_panel.rows[("gear_ratios", 0)], 13.75)
    qtbot.waitUntil(lambda: waits.ready(window) and st.mechanism == scenario2.mechanism, timeout=60_000)
    waits.reference(window)
    current, reference = st.current.map, st.reference.map
    assert current.grid == reference.grid == scenario1.grid

    # The paper's figure, at its resolution.
    new, old = current.stats["isotropic_force"].min, reference.stats["isotropic_force"].min
    assert new == pytest.approx(3.9140, abs=5e-5) and old == pytest.approx(2.2797, abs=5e-5)
    assert 100.0 * (new - old) / old == pytest.approx(71.7, abs=0.05)
    panel = window.stats_panel
    # The paper's figures as the panel prints them, to the last digit shown (its digits: the error's).
    for column, paper in ((1, 3.9140), (3, 2.2797)):
        text = panel.cell("isotropic_force", "min", column)
        last = 10.0 ** -len(text.partition(".")[2])
        assert float(text) == pytest.approx(paper, abs=max(5e-5, last / 2)), text
    assert panel.cell("isotropic_force", "min", 4) == "+71.7 %"
    # Every other cell: the compute layer's maps of the two scenario presets.
    expected_new = expected_map(window, scenario2.mechanism)
    expected_old = expected_map(window, scenario1.mechanism)
    assert_maps_equal(current, expected_new)
    assert_maps_equal(reference, expected_old)
    assert_stats_panel_shows(window, expected_new, expected_old)
    # The global maximum isotropic force and where it occurs, as the compute layer finds it.
    iso = expected_new.stats["isotropic_force"]
    where = ", ".join(f"{v * 1e3:.1f} mm" for v in iso.argmin)
    shown = format_with_error(iso.min, resolution_error(expected_new)["isotropic_force"]["min"])
    assert f"{shown[0]} N</b> (± {shown[1]} N)" in panel.global_label.text()
    assert f"({where})" in panel.global_label.text()

    # The map view: reference beside current, or their difference.
    titles = [t for t, _, _ in window.map_view.panels()]
    assert titles == ["reference", "current"]
    assert len(window.map_view.picture.panels) == 2
    window.state.set_compare_mode("difference")
    (title, _, diff), = window.map_view.panels()
    both = expected_new.feasible & expected_old.feasible
    q = "isotropic_force"
    np.testing.assert_array_equal(diff[both], expected_new.values[q][both] - expected_old.values[q][both])
    assert np.all(np.isnan(diff[~both]))


def test_the_comparison_follows_a_newly_chosen_quantity(waits, make_window, qtbot):
    window = make_window("fivebar_singh", longest=SMALL)
    st = window.state
    window.pin_reference()
    set_spin(qtbot, window.param_panel.rows[("proximal", -1)], 110.0)
    qtbot.waitUntil(lambda: waits.ready(window) and st.mechanism != st.reference_mechanism, timeout=30_000)
    box = window.quantity_box
    box.setCurrentIndex(box.findData("manipulability"))
    qtbot.waitUntil(lambda: waits.ready(window) and "manipulability" in st.current.map.values, timeout=30_000)
    qtbot.waitUntil(lambda: st.reference is not None and "manipulability" in st.reference.map.values,
                    timeout=30_000)
    assert [t for t, _, _ in window.map_view.panels()] == ["reference", "current"]
    assert_maps_equal(st.reference.map, expected_map(window, st.reference_mechanism))
    assert_maps_equal(st.current.map, expected_map(window))
    assert not st.busy

    # A reference map alone (nothing else to compute) does not leave the window "busy".
    request = window.request_map("full", tag="reference")
    qtbot.waitUntil(lambda: st.reference.generation == request.generation, timeout=30_000)
    assert not st.busy and window.progress.value() == 100


# -- a stale picture is marked, another device's figures never shown ---------------------------
def gate_maps(window):
    """Hold every map job until ``release()``: a slow device, as the user's machine may have.

    The job still honours cancellation while it waits, as ``compute_map`` does between chunks.
    """
    from metrics.workspace import Cancelled
    core = window.scheduler.core
    job = core._job
    gate = threading.Event()

    def slow(request, progress, cancelled):
        while not gate.wait(0.005):
            if cancelled():
                raise Cancelled()
        return job(request, progress, cancelled)

    core._job = slow
    return gate.set


def stale_red_pixels(window, panel: int = -1) -> int:
    """Pixels of the stale veil's colour on the border of the current map's axes, as painted.

    The veil draws a 3 px frame of its colour there; red markers (singular points, the pose)
    near the frame cover a few of its pixels at most.
    """
    from matplotlib.colors import to_rgb

    from app.gui.views.map_canvas import STALE_COLOUR
    rgb = widget_rgb(window.map_view.canvas).astype(float)
    axes = window.map_view.canvas.layouts[panel].axes
    x0, x1, y0, y1 = (int(round(v)) for v in (axes.left(), axes.right(), axes.top(), axes.bottom()))
    ring = np.zeros(rgb.shape[:2], bool)
    ring[y0 - 1:y1 + 2, x0 - 1:x1 + 2] = True
    ring[y0 + 2:y1 - 1, x0 + 2:x1 - 1] = False
    target = 255.0 * np.asarray(to_rgb(STALE_COLOUR))
    return int(np.count_nonzero(ring & (np.linalg.norm(rgb - target, axis=-1) < 40.0)))


def stale_marks_visible(window) -> bool:
    return window.map_view.canvas.stale is not None


def test_a_map_older_than_the_parameters_is_marked_stale_until_the_current_one_arrives(waits, make_window, qtbot):
    from app.gui.widgets.stats_panel import STALE_NOTE
    window = make_window("fivebar_singh", longest=SMALL)
    st, view, panel = window.state, window.map_view, window.stats_panel
    qtbot.wait(100)                                       # the first map's deferred groups drawn
    assert view.stale() is None and not stale_marks_visible(window) and stale_red_pixels(window) == 0
    assert not panel.stale_label.isVisible() and panel.table.isEnabled()
    release = gate_maps(window)

    row = window.param_panel.rows[("distal", -1)]
    set_spin(qtbot, row, 170.0)                            # the map of 150 mm is still on screen
    new_mech = load_preset("fivebar_singh").mechanism.replace_display(distal=170.0)
    assert st.mechanism == new_mech != st.current.mechanism
    assert view.stale() == "parameters"
    # Veiled once it has stayed stale for a moment (a slider's coarse maps replace each other sooner).
    qtbot.waitUntil(lambda: stale_marks_visible(window), timeout=2000)
    qtbot.waitUntil(lambda: stale_red_pixels(window) > 200, timeout=5000)       # drawn, not only flagged
    assert "STALE" in view.canvas.stale
    assert panel.stale_label.isVisible() and panel.stale_label.text() == STALE_NOTE
    assert not panel.table.isEnabled()
    # A drag that outruns the computation: still stale after each step, however long it takes.
    row.slider.setSliderDown(True)
    for step in (4, 8, 12):
        row.slider.setValue(row.slider.value() + step)
        qtbot.wait(150)
        assert view.stale() == "parameters" and stale_marks_visible(window) and stale_red_pixels(window) > 200
    row.slider.setSliderDown(False)
    held = st.mechanism

    release()
    qtbot.waitUntil(lambda: waits.ready(window), timeout=30_000)
    qtbot.waitUntil(lambda: stale_red_pixels(window) == 0, timeout=5000)
    assert st.current.mechanism == held
    assert view.stale() is None and not stale_marks_visible(window)
    assert not panel.stale_label.isVisible() and panel.table.isEnabled()
    expected = expected_map(window)
    assert_maps_equal(st.current.map, expected)
    assert_view_draws(window, expected, "isotropic_force")
    assert panel.cell("isotropic_force", "mean") == format_with_error(
        expected.stats["isotropic_force"].mean, resolution_error(expected)["isotropic_force"]["mean"])[0]


def test_only_the_current_panel_of_a_comparison_is_veiled_while_stale(waits, make_window, qtbot):
    window = make_window("fivebar_singh", longest=SMALL, size=(1920, 1080))
    window.pin_reference()
    waits.reference(window)
    release = gate_maps(window)
    set_spin(qtbot, window.param_panel.rows[("distal", -1)], 170.0)
    qtbot.waitUntil(lambda: stale_marks_visible(window), timeout=2000)
    panels = window.map_view.picture.panels
    assert [p.reference for p in panels] == [True, False]
    qtbot.waitUntil(lambda: stale_red_pixels(window, 1) > 200, timeout=5000)
    assert stale_red_pixels(window, 0) < 50          # the pinned design is what it was: no veil
    release()
    qtbot.waitUntil(lambda: waits.ready(window), timeout=30_000)


def test_a_newly_chosen_quantity_marks_the_old_picture_until_its_map_arrives(waits, make_window, qtbot):
    window = make_window("fivebar_singh", longest=SMALL)
    release = gate_maps(window)
    box = window.quantity_box
    box.setCurrentIndex(box.findData("manipulability"))
    assert window.map_view.stale() == "quantity"
    qtbot.waitUntil(lambda: stale_marks_visible(window), timeout=2000)
    assert "quantity" in window.map_view.canvas.stale
    release()
    qtbot.waitUntil(lambda: waits.ready(window) and "manipulability" in window.state.current.map.values,
                    timeout=30_000)
    assert window.map_view.stale() is None and not stale_marks_visible(window)
    assert_view_draws(window, window.state.current.map, "manipulability")


def test_switching_device_clears_the_old_devices_statistics_and_map_at_once(waits, make_window, qtbot):
    window = make_window("fivebar_singh", longest=SMALL)
    st, panel = window.state, window.stats_panel
    assert panel.table.rowCount() > 0 and "Five-bar" in panel.header.text()
    release = gate_maps(window)                           # the new device's map takes its time
    assert window.load_device("twin_pantograph")
    # At once, before any map of the new device exists: nothing of the five-bar stays.
    assert st.current is None
    assert panel.table.rowCount() == 0 and panel.rows == {} and panel.global_label.text() == ""
    assert st.preset.name in panel.header.text() and "Five-bar" not in panel.header.text()
    assert not window.map_view.picture.panels
    assert st.preset.name in window.map_view.picture.message
    qtbot.wait(300)                                       # still nothing while the map computes
    assert panel.table.rowCount() == 0 and not window.map_view.picture.panels

    release()
    waits.full(window)
    assert st.preset.key == "twin_pantograph" and st.current.mechanism == st.mechanism
    assert panel.table.rowCount() > 0 and st.preset.name in panel.header.text()
    assert not panel.stale_label.isVisible() and window.map_view.stale() is None
    expected = expected_map(window)
    assert_maps_equal(st.current.map, expected)
    assert panel.cell("isotropic_force", "mean") == format_with_error(
        expected.stats["isotropic_force"].mean, resolution_error(expected)["isotropic_force"]["mean"])[0]


@pytest.mark.parametrize("size", [(1600, 950), (1920, 1080)])
def test_compare_shows_reference_and_current_side_by_side_on_one_colour_scale(waits, make_window, qtbot, size):
    from app.gui.views.map_view import SIDE_BY_SIDE_PX
    window = make_window("inverse3_prototype", longest=SMALL, size=size)
    st = window.state
    sizes_before = window.splitter.sizes()
    window.pin_reference()
    set_spin(qtbot, window.param_panel.rows[("gear_ratios", 0)], 13.75)
    qtbot.waitUntil(lambda: waits.ready(window) and st.mechanism == load_preset("inverse3_scenario2").mechanism,
                    timeout=30_000)
    waits.reference(window)
    qtbot.wait(200)
    assert window.map_view.canvas.width() >= SIDE_BY_SIDE_PX
    picture = window.map_view.picture
    panels = picture.panels
    assert [p.title.split("\n")[1].split(":")[0] for p in panels] == ["reference", "current"]
    # Side by side: the same rows of the screen, reference on the left.
    a, b = (lay.axes for lay in window.map_view.canvas.layouts)
    assert a.right() <= b.left() and a.top() < b.bottom() and b.top() < a.bottom()
    # One colour scale: the same limits, spanning both designs, and a single colour bar.
    assert panels[0].scale is panels[1].scale and picture.bar is not None
    q = "isotropic_force"
    ref, cur = st.reference.map, st.current.map
    lo, hi = panels[0].scale.limits
    assert lo == min(ref.stats[q].min, cur.stats[q].min)
    assert hi <= max(ref.stats[q].max, cur.stats[q].max)
    # Scenario 2 is better everywhere (paper 000): brighter where it is better, never darker.
    both = ref.feasible & cur.feasible
    r, c = ref.values[q][both], cur.values[q][both]
    assert np.all(c >= r)
    from app.logic.map_picture import colour_samples
    scale = panels[0].scale
    light = [colour_samples(scale, np.ma.masked_array(v))[:, :3].astype(float).sum(axis=1) for v in (r, c)]
    assert np.all(light[1] >= light[0] - 1e-12) and np.any(light[1] > light[0])
    # The exported compare figure says the same.
    exported = app.render.views.compare_figure(ref, cur, q, st.preset)
    ex_images = [ax.images[0] for ax in exported.axes if ax.images]
    assert [im.get_clim() for im in ex_images] == [scale.limits] * 2 and len(exported.axes) == 3

    window.state.clear_reference()                        # the 3D views get their width back
    qtbot.wait(100)
    # In the proportion they had: the statistics dock narrows without the reference columns, and
    # the splitter shares the width it gains as before (to a pixel of rounding).
    after = window.splitter.sizes()
    assert abs(after[0] / sum(after) - sizes_before[0] / sum(sizes_before)) <= 2.0 / sum(sizes_before)


def test_the_bottleneck_map_of_every_shipped_device_is_drawn_with_its_classes(waits, make_window, qtbot):
    from resources import list_presets, load_preset
    window = make_window("fivebar_singh", longest=41)
    box = window.quantity_box
    box.setCurrentIndex(box.findData("bottleneck"))
    waits.full(window)
    for key in list_presets():
        if len(load_preset(key).grid.axes) == 3:
            continue        # a 3D box map (the delta's): its planes are checked in test_volume_gui.py
        assert window.load_device(key), key
        qtbot.waitUntil(lambda: waits.ready(window) and "bottleneck" in window.state.current.map.values,
                        timeout=30_000)
        qtbot.wait(50)
        assert window.last_error is None, window.last_error
        wmap, mech = window.state.current.map, window.state.mechanism
        values, feasible = wmap.values["bottleneck"], wmap.feasible
        panel = window.map_view.picture.panels[0]
        data, mask = map_image(window)
        # Blank off the workspace and where no class applies (-1); elsewhere a class named on the bar.
        classes = list(mech.joint_names) + [name for code, name in ((-2, "tie"), (-3, "shared (redundant)"))
                                            if np.any(feasible & (values == code))]
        np.testing.assert_array_equal(~mask, feasible & (values != -1))
        labels = [text.rsplit(" (", 1)[0] for _, text in window.map_view.picture.bar.ticks]
        assert labels == classes, key
        drawn = np.array(classes, object)[data[~mask]]
        want = [mech.joint_names[v] if v >= 0 else {-2: "tie", -3: "shared (redundant)"}[v] for v in values[~mask]]
        assert list(drawn) == want, key
        assert len(matplotlib_norm(panel.scale).boundaries) - 1 == len(panel.scale.lut) == len(classes)


def test_a_global_minimum_on_the_maps_edge_says_so(make_window):
    """The five-bar's minimum (-220, 0) mm sits where its grid stops at y = 0 and its workspace
    goes on: the statistics panel says so, as the map's legend does; the Inverse3's lies inside."""
    window = make_window("fivebar_singh", longest=105)
    assert "on the map's edge" in window.stats_panel.global_label.text()
    window = make_window("inverse3_prototype", longest=101)
    assert "Global maximum isotropic force" in window.stats_panel.global_label.text()
    assert "on the map's edge" not in window.stats_panel.global_label.text()
