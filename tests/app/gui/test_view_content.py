"""What the 3D views show (issue 11 sec. 3): the inscribed sphere outside the end-effector's joint
ball, the legend and force values, the planar workspace from above with a smooth edge, axes
in mm and labelled iso-surfaces."""
from __future__ import annotations

import numpy as np
from conftest import widget_rgb
from PySide6.QtGui import QFontMetrics
from PySide6.QtWidgets import QApplication

from app import scenes
from app.gui.views import camera

SMALL = 40
#: The most of a 3D view's height a caption painted over it may cover, however small the view.
CAPTION_BOUND = 1 / 3


def _pixel_radius(renderer, centre, radius) -> float:
    """On-screen radius (px) of a ball of ``radius`` (m) at ``centre``: its centre and a point
    ``radius`` along the camera's right axis, projected."""
    cam = renderer.GetActiveCamera()
    right = np.cross(np.array(cam.GetDirectionOfProjection()), np.array(cam.GetViewUp()))
    right /= np.linalg.norm(right)
    return float(np.linalg.norm(camera.world_to_display(renderer, centre + radius * right)
                                - camera.world_to_display(renderer, centre)))


def test_the_inscribed_sphere_is_drawn_outside_the_joint_ball_at_gear_ratio_27_5(make_window, qtbot):
    window = make_window("inverse3_prototype", longest=SMALL)
    window.tabs.setCurrentWidget(window.pose_view)
    st, plotter = window.state, window.pose_view.plotter
    mech = st.mechanism.replace(gear_ratios=(27.5, 5.957, 5.957))
    st.set_mechanism(mech)
    qtbot.waitUntil(lambda: st.pose_report is not None and st.mechanism == mech and "sphere" in plotter.actors
                    and window.pose_view.scale is not None, timeout=20_000)
    QApplication.processEvents()
    report = st.pose_report
    x = scenes.to_3d(report.x)[0]
    pts = scenes.to_3d(mech.link_points(report.joints))
    ball = scenes.BALL_FRACTION * float(np.max(np.ptp(pts, axis=0)))
    # The case is real: at the device's fixed scale the sphere would sit inside the ball.
    assert report.isotropic_force * scenes.force_scale(mech) < ball
    sphere = np.asarray(plotter.actors["sphere"].mapper.dataset.points)
    r_sphere = float(np.mean(np.linalg.norm(sphere - x, axis=1)))
    joints = np.asarray(plotter.actors["joints"].mapper.dataset.points)
    r_ball = float(np.min(np.linalg.norm(joints - x, axis=1)))     # the end-effector's ball is nearest
    assert abs(r_ball - ball) <= 1e-9 * ball * 1e3
    renderer = plotter.renderer
    assert _pixel_radius(renderer, x, r_sphere) > _pixel_radius(renderer, x, r_ball)
    assert r_sphere >= scenes.SPHERE_OVER_BALL * r_ball * (1 - 1e-9)
    # The caption prints the scale actually drawn.
    caption = window.pose_view.view.caption
    assert f"forces drawn at 10 N = {10 * window.pose_view.scale * 1e3:.0f} mm" in caption


def test_the_legend_and_the_desired_and_clamped_forces(make_window, qtbot):
    window = make_window("fivebar_singh", longest=SMALL)
    window.tabs.setCurrentWidget(window.pose_view)
    st, plotter = window.state, window.pose_view.plotter
    st.set_desired_force((30.0, -5.0))
    qtbot.waitUntil(lambda: "desired_force" in plotter.actors, timeout=10_000)
    labels = [row[0] for row in window.pose_view._legend_rows]
    assert {"links", "force polytope", "inscribed sphere", "desired force", "clamped force"} <= set(labels)
    assert {"theta_1 at full torque", "theta_2 at full torque"} <= set(labels)      # named as the caption names them
    colours = [row[1] for row in window.pose_view._legend_rows]
    assert len(set(colours)) == len(colours)          # one colour per glyph: the legend is unambiguous
    clamped = st.pose_report.clamp(np.array([30.0, -5.0]))
    caption = window.pose_view.view.caption
    along = st.pose_report.force_along(np.array([30.0, -5.0]))
    assert scenes.force_values_text([30.0, -5.0], clamped, along) in caption
    assert f"{np.linalg.norm(clamped):.3g} N" in caption and "(30, -5) N" in caption
    # Far beyond what the device can render, the clamped force is a short arrow inside the
    # desired one (its shaft a share of its length): it is seen through it, not hidden.
    st.set_desired_force((300.0, -50.0))

    def length(name: str) -> float:
        return float(np.linalg.norm(np.ptp(np.asarray(plotter.actors[name].mapper.dataset.points), axis=0)))
    qtbot.waitUntil(lambda: length("desired_force") > 5 * length("clamped_force"), timeout=10_000)

    def frame() -> np.ndarray:
        # The view as painted: its frame is read from the back buffer (the hidden render window
        # is not swapped, so pyvista's screenshot, which reads the front one, is not it).
        view = window.pose_view.view
        view.request_render()
        view.repaint()
        return widget_rgb(view)
    shown = frame()
    plotter.actors["clamped_force"].SetVisibility(False)
    try:
        hidden = frame()
    finally:
        plotter.actors["clamped_force"].SetVisibility(True)
    assert np.count_nonzero(np.any(shown != hidden, axis=2)) >= 20


def _boundary_segments(mesh) -> np.ndarray:
    edges = mesh.extract_surface(algorithm=None).extract_feature_edges(boundary_edges=True, feature_edges=False,
                                                                       manifold_edges=False, non_manifold_edges=False)
    lines = edges.lines.reshape(-1, 3)[:, 1:]
    a, b = np.asarray(edges.points)[lines[:, 0]], np.asarray(edges.points)[lines[:, 1]]
    return b - a, 0.5 * (a + b)


def test_a_planar_workspace_is_a_flat_map_seen_from_above_with_a_smooth_edge_and_mm_axes(make_window, qtbot):
    window = make_window("fivebar_singh", longest=80)
    window.tabs.setCurrentWidget(window.workspace_view)
    plotter = window.workspace_view.plotter
    qtbot.waitUntil(lambda: "workspace" in plotter.actors, timeout=20_000)
    QApplication.processEvents()
    mesh = plotter.actors["workspace"].mapper.dataset
    assert np.all(np.asarray(mesh.points)[:, 2] == 0.0)
    direction = np.array(plotter.renderer.GetActiveCamera().GetDirectionOfProjection())
    assert np.allclose(direction, (0.0, 0.0, -1.0), atol=1e-12)
    # The whole map is in view.
    b = np.asarray(mesh.bounds)
    w, h = plotter.renderer.GetSize()
    for corner in ((b[0], b[2], 0.0), (b[1], b[3], 0.0)):
        px = camera.world_to_display(plotter.renderer, corner)
        assert 0 <= px[0] <= w and 0 <= px[1] <= h
    # A smooth edge: a staircase of whole cells has only axis-parallel boundary edges; a cut at
    # interpolated feasibility has mostly slanted ones round the semicircle.
    seg, mid = _boundary_segments(mesh)
    # The straight base (y at its lowest) is axis-parallel by nature: the curved rest is measured.
    seg = seg[mid[:, 1] > b[2] + 1e-9 * (b[3] - b[2])]
    slanted = np.all(np.abs(seg[:, :2]) > 1e-12 * np.abs(seg[:, :2]).max(), axis=1)
    assert slanted.mean() > 0.5
    # Its axes in mm: on the map's own box, x and y titled (its flat z has no edge to draw).
    axes = plotter.actors[scenes.VOLUME_AXES]
    np.testing.assert_array_equal(axes._isoforce_box, b)
    plotter.ren_win.Render()
    parts = axes.GetParts()
    titles = sorted(p.GetInput() for p in (parts.GetItemAsObject(i) for i in range(parts.GetNumberOfItems()))
                    if p.IsA("vtkTextActor") and p.GetVisibility() and "(mm)" in p.GetInput())
    assert titles == ["x (mm)", "y (mm)"]


def test_revolved_iso_surfaces_are_labelled_with_their_levels(make_window, qtbot):
    window = make_window("inverse3_prototype", longest=SMALL)
    view = window.workspace_view
    window.tabs.setCurrentWidget(view)
    view.mode.setCurrentText("iso-surfaces")
    qtbot.waitUntil(lambda: view._drawn is not None and view._drawn[-1] == "iso-surfaces"
                    and scenes.ISO_LABEL_ACTOR in view.plotter.actors, timeout=20_000)
    st = window.state
    mesh = view.plotter.actors["workspace"].mapper.dataset
    points, levels = scenes.iso_label_points(mesh, st.quantity)
    drawn = np.unique(np.asarray(mesh.point_data[st.quantity]))
    assert len(levels) == len(drawn) >= 2
    np.testing.assert_array_equal(levels, drawn)
    # Each label sits on its own surface.
    for p, v in zip(points, levels):
        on = np.asarray(mesh.points)[np.asarray(mesh.point_data[st.quantity]) == v]
        assert np.min(np.linalg.norm(on - p, axis=1)) == 0.0


def test_the_pose_caption_is_readable_and_the_device_framed_clear_of_it(make_window, qtbot):
    """The caption is Qt text at the widget's font size (VTK's corner text shrank a long line to
    5-6 px to fit the view), inside the view, and "Reset view" frames the device above it."""
    window = make_window("inverse3_prototype", longest=SMALL, size=(1600, 950))
    window.tabs.setCurrentWidget(window.pose_view)
    view = window.pose_view.view
    qtbot.waitUntil(lambda: bool(view.caption), timeout=10_000)
    rect = view.caption_rect()
    assert view.rect().contains(rect)
    # The text is painted at a readable size: the first line's glyphs (it has ascenders and
    # descenders: "f", "k", "p", "(") span most of the widget font's ascent in pixels; VTK's
    # shrunk corner text was 5-6 px tall.
    rgb = widget_rgb(view)[rect.top(): rect.bottom() + 1, rect.left(): rect.right() + 1]
    dark = (rgb.max(axis=2) < 100).any(axis=1)
    first = np.flatnonzero(dark)[0]
    line = np.argmin(dark[first:]) if not dark[first:].all() else dark.size - first    # its dark rows
    assert line >= 0.7 * QFontMetrics(QApplication.font()).ascent(), line
    view.reset_camera()
    assert_framed_between_legend_and_caption(window.pose_view)
    # A desired force adds two legend rows and a caption line: a view still framed by Reset view
    # is framed again for them (the legend covered the Inverse3's top joint).
    rows = len(window.pose_view._legend_rows)
    window.state.set_desired_force((12.0, 0.0, 4.0))
    qtbot.waitUntil(lambda: len(window.pose_view._legend_rows) == rows + 2, timeout=10_000)
    assert_framed_between_legend_and_caption(window.pose_view)


def assert_framed_between_legend_and_caption(pose_view) -> None:
    """The shown meshes' bounding boxes project below the legend and above the caption."""
    view, renderer = pose_view.view, pose_view.plotter.renderer
    corners = np.array([camera.world_to_display(renderer, [b[i], b[2 + j], b[4 + k]])
                        for b in camera.shown_bounds(pose_view.plotter)
                        for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    h = renderer.GetSize()[1]
    ratio = h / view.height()                                  # render-window pixels per widget pixel
    lowest, highest = corners[:, 1].min() / ratio, corners[:, 1].max() / ratio     # y up from the bottom
    assert lowest >= view.height() - view.caption_rect().top() - 1, lowest
    legend = pose_view._legend_height(len(pose_view._legend_rows))
    assert highest <= (1 - legend) * view.height() + 1, (highest, legend)


def test_a_tiny_pose_view_keeps_its_caption_to_a_third_and_the_device_in_view(make_window, qtbot):
    """A pose view dragged to 150 x 120 px: the caption, wrapped to 108 px, was 130 px tall,
    taller than the view, and covered the device. It keeps to a third of the view's height,
    cut short with its whole text in the tooltip, and the device is framed clear of it."""
    window = make_window("inverse3_prototype", longest=SMALL, size=(1600, 950))
    window.tabs.setCurrentWidget(window.pose_view)
    view = window.pose_view.view
    qtbot.waitUntil(lambda: bool(view.caption) and view.fitted, timeout=10_000)
    caption = view.caption
    view.setMaximumSize(150, 120)             # as a dragged splitter leaves it: the layout shrinks it
    qtbot.waitUntil(lambda: (view.width(), view.height()) == (150, 120), timeout=10_000)
    QApplication.processEvents()
    assert view.fitted                        # a fitted view is framed again for its new size
    # The caption as painted: the pixels it changes (its box and text over the same frame).
    shown = widget_rgb(view)
    view.set_caption("")
    bare = widget_rgb(view)
    view.set_caption(caption)
    painted = np.any(shown != bare, axis=2)
    rows, cols = np.nonzero(painted)
    assert rows.size, "no caption is painted"
    height = rows.max() - rows.min() + 1
    assert height <= CAPTION_BOUND * view.height(), (height, view.height())
    box = view.caption_box()
    assert box.height() <= CAPTION_BOUND * view.height() and view.rect().contains(box)
    assert box.top() <= rows.min() and rows.max() <= box.bottom() and box.left() <= cols.min() \
        and cols.max() <= box.right()
    # Shortened, not lost: the lines shown are the caption's first ones, cut with "...", and
    # the whole caption is the tooltip.
    text, whole = view.caption_layout()
    assert not whole and view.toolTip() == caption
    rows = text.replace("\u00a0", " ").replace("\u2060", "").split("\n")      # (its kept phrases)
    for row, line in zip(rows, caption.split("\n")):
        assert row == line or (row.endswith("\u2026") and line.startswith(row[:-1]))
    # The device: every point of its links and joints projects into the view, none under the
    # caption or the "Reset view" button, and it is drawn large enough to see (a sixth of the
    # view's height: the glyphs round its end-effector are framed with it).
    renderer = window.pose_view.plotter.renderer
    ratio = renderer.GetSize()[1] / view.height()
    points = np.vstack([np.asarray(window.pose_view.plotter.actors[name].mapper.dataset.points)
                        for name in scenes.GLYPH_ACTORS["links"]])
    px = np.array([camera.world_to_display(renderer, p) for p in points]) / ratio
    x, y = px[:, 0], view.height() - px[:, 1]                  # widget pixels, y down
    assert np.all((x >= 0) & (x <= view.width()) & (y >= 0) & (y <= view.height()))
    for cover in (box, view.reset_button.geometry()):
        assert not np.any((x >= cover.left()) & (x <= cover.right() + 1) & (y >= cover.top())
                          & (y <= cover.bottom() + 1)), cover
    assert max(np.ptp(x), np.ptp(y)) >= view.height() / 6, (np.ptp(x), np.ptp(y))
    assert_framed_between_legend_and_caption(window.pose_view)


def test_the_cut_open_volume_has_three_axes_in_mm_on_its_one_box(make_window, qtbot):
    """The revolved Inverse3 in the app: its cut plane's widget draws a box round the scene, and
    the axes are on that box (no second box inside it), all three titles shown."""
    window = make_window("inverse3_prototype", longest=SMALL)
    view = window.workspace_view
    window.tabs.setCurrentWidget(view)
    plotter = view.plotter
    qtbot.waitUntil(lambda: scenes.VOLUME_AXES in plotter.actors, timeout=20_000)
    box = scenes.widget_box(plotter)
    assert box is not None and scenes.VOLUME_BOX not in plotter.actors
    # A right-drag over the plane cannot resize that box away from the axes: it zooms the view.
    widgets = getattr(plotter, "widgets", plotter).plane_widgets
    assert [w.GetScaleEnabled() for w in widgets] == [0]
    plotter.ren_win.Render()
    parts = plotter.actors[scenes.VOLUME_AXES].GetParts()
    shown = [parts.GetItemAsObject(i) for i in range(parts.GetNumberOfItems())]
    titles = sorted(p.GetInput() for p in shown if p.IsA("vtkTextActor") and p.GetVisibility()
                    and "(mm)" in p.GetInput())
    assert titles == ["x (mm)", "y (mm)", "z (mm)"]
    # The box is the scene's grown by the widget's place factor: it holds the drawn workspace.
    drawn = np.asarray(plotter.actors["workspace"].GetBounds()).reshape(3, 2)
    b = box.reshape(3, 2)
    assert np.all(b[:, 0] <= drawn[:, 0]) and np.all(b[:, 1] >= drawn[:, 1])


def test_a_flat_picture_has_no_mode_to_choose_and_is_drawn_flat_in_either(make_window, qtbot):
    """The PHANToM Premium's x-z slice is drawn flat (it is not revolved): "iso-surfaces" of a
    flat slice were edge-on strips and specks, and for the five-bar the choice changed nothing.
    The mode is offered for the revolved Inverse3 only."""
    window = make_window("phantom_premium_15", longest=SMALL)
    view = window.workspace_view
    window.tabs.setCurrentWidget(view)
    qtbot.waitUntil(lambda: "workspace" in view.plotter.actors, timeout=20_000)
    assert not view.mode.isVisible()
    flat = view.plotter.actors["workspace"].mapper.dataset
    view.mode.setCurrentText("iso-surfaces")
    qtbot.waitUntil(lambda: view._drawn is not None and view._drawn[-1] == "iso-surfaces", timeout=20_000)
    drawn = view.plotter.actors["workspace"].mapper.dataset
    assert not getattr(view.plotter.actors["workspace"], "_isoforce_iso_surfaces", False)
    np.testing.assert_array_equal(np.asarray(drawn.points), np.asarray(flat.points))
    assert window.load_device("inverse3_prototype")
    qtbot.waitUntil(lambda: view.mode.isVisible(), timeout=20_000)
