"""The iso-surface labels of the 3D workspace scene (``scenes.workspace_annotations``) stay apart
on screen, each on its own surface, for every preset whose workspace scene has iso-surfaces.

The Novint Falcon's four labels sat at their surfaces' highest points, which lie within a few
pixels of each other on screen: VTK's label mapper drew two of them overlapping and dropped the
rest (and annotated before any render, the smoothed surfaces were still empty: no labels at
all). Headless (EGL): the scene is built as the app's workspace tab builds it.

A label's box on screen is derived, not tuned: VTK's label mapper puts the text's bounding box
(``vtkTextRenderer.GetBoundingBox`` of the label's own text property at the window's dpi, the
measure ``vtkFreeTypeLabelRenderStrategy.ComputeLabelBounds`` takes) at the anchor's display
pixel (``vtkCoordinate``, rounded down as ``GetComputedDisplayValue`` does) and draws its box
``margin`` pixels round it. The rendered pixels check that model: a label drawn or hidden
changes only pixels inside its box, and some inside each box.
"""
from __future__ import annotations

import functools

import numpy as np
import pytest

from app import scenes
from app.gui.views import camera
from app.logic.display_units import display_unit
from app.render.views import _plotter
from metrics.quantities import QUANTITIES
from metrics.workspace import compute_map
from resources import list_presets, load_preset

QUANTITY = "isotropic_force"
#: The app's workspace tab as the GUI tests size it (a 1400 x 900 window: the tab is narrow),
#: a mid-sized tab and a large one (the ``figure`` command's default size).
SIZES = ((210, 768), (900, 700), (1600, 1200))
#: The share of the view the app leaves round the framed scene (``workspace_view.AXES_MARGIN``).
AXES_MARGIN = 0.14


def _has_iso_surfaces(key: str) -> bool:
    """The workspace scene draws iso-surfaces: a 3D box map, or a revolved slice in iso-surface mode."""
    preset = load_preset(key)
    return ((len(preset.grid.axes) == 3 or scenes.is_revolved(preset.mechanism, preset.grid))
            and not QUANTITIES[QUANTITY].categorical)


PRESETS = [key for key in list_presets() if _has_iso_surfaces(key)]


@functools.lru_cache(maxsize=None)
def _map(key: str):
    """The preset's map; a slice at ``WORKSPACE_MAX_POINTS`` along its longer axis (the scene
    draws no more of a finer one: ``workspace_volume`` subsamples it to that)."""
    preset = load_preset(key)
    grid = preset.grid
    top = max(grid.resolution)
    if len(grid.axes) == 2 and top > scenes.WORKSPACE_MAX_POINTS:
        grid = grid.with_resolution(tuple(max(3, round(n * scenes.WORKSPACE_MAX_POINTS / top))
                                          for n in grid.resolution))
    return preset.mechanism, compute_map(preset.mechanism, grid, [QUANTITY])


def _draw(plotter, key: str) -> None:
    """The workspace scene as the app's workspace tab draws it (``WorkspaceView.redraw``)."""
    mech, wmap = _map(key)
    if len(wmap.grid.axes) == 3:
        grid = wmap.grid
        k = grid.axes.index("z")
        scenes.draw_box_workspace(plotter, wmap, QUANTITY, mech, "z", 0.5 * (grid.lower[k] + grid.upper[k]))
    else:
        scenes.draw_workspace(plotter, wmap, QUANTITY, mech, "iso-surfaces", interactive=False)


def _frame(plotter, key: str) -> None:
    """The app's framing of the workspace (``WorkspaceView.fit_camera``): a flat slice square on
    (the PHANToM family's), a volume obliquely."""
    mech, wmap = _map(key)
    scenes.frame_workspace_camera(plotter, mech, wmap.grid)
    camera.fit_bounds(plotter.renderer, camera.shown_bounds(plotter), margin=scenes.axes_margin(plotter, AXES_MARGIN))


def _kept_plotter(held: dict, key: str, size, draw):
    """The plotter ``held`` keeps for preset ``key`` (drawing a scene is most of a case's time),
    made at ``size`` and drawn by ``draw(plotter)`` when the preset changes."""
    if held.get("key") != key:
        if "plotter" in held:
            held.pop("plotter").close()
        held["plotter"] = _plotter(size)
        held["key"] = key
        draw(held["plotter"])
    return held["plotter"]


@pytest.fixture(scope="module")
def scene():
    """``scene(key, size, order)``: an off-screen plotter with the scene drawn, annotated, framed
    and rendered at ``size``.

    ``order``: ``"app"`` annotates before the camera is framed (the app's order: on a device's
    first map also before any render); ``"framed"`` frames and renders first, then annotates
    (the labels then belong to the camera they are drawn for); ``"turned"`` is the app's
    order, then the user turns the scene a quarter round and tilts it; ``"tilted"``: the app's
    order, then the camera raised by 40 degrees. The drawn scene is kept
    for the next case of the same preset (drawing it is most of a case's time); the labels are
    made anew each time, as the app's redraw makes them.
    """
    held: dict = {}

    def make(key: str, size, order: str):
        mech, wmap = _map(key)
        plotter = _kept_plotter(held, key, size, lambda p: _draw(p, key))
        plotter.window_size = list(size)
        if order == "framed":
            _frame(plotter, key)
            plotter.ren_win.Render()
        scenes.workspace_annotations(plotter, QUANTITY)
        if order != "framed":
            _frame(plotter, key)
        plotter.ren_win.Render()
        if order == "turned":
            camera.orbit(plotter.renderer, plotter.camera.focal_point, 180.0, 40.0)
            plotter.ren_win.Render()
        if order == "tilted":
            cam = plotter.renderer.GetActiveCamera()
            cam.Elevation(40.0)
            cam.OrthogonalizeViewUp()
            plotter.renderer.ResetCameraClippingRange()
            plotter.ren_win.Render()
        return plotter

    yield make
    if "plotter" in held:
        held["plotter"].close()


def _pixels(plotter) -> np.ndarray:
    """The rendered frame, (h, w, 3) uint8, row 0 at the bottom (VTK's display y)."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkUnsignedCharArray

    plotter.ren_win.Render()
    w, h = plotter.ren_win.GetSize()
    data = vtkUnsignedCharArray()
    plotter.ren_win.GetRGBACharPixelData(0, 0, w - 1, h - 1, 0, data)
    return vtk_to_numpy(data).reshape(h, w, 4)[..., :3].copy()


def _label_boxes(plotter) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """The labels' anchors (k, 3) m, their boxes on screen (k, 4) (left, right, bottom, top) px, texts."""
    from vtkmodules.vtkRenderingCore import vtkCoordinate, vtkTextRenderer

    actor = plotter.actors[scenes.ISO_LABEL_ACTOR]
    mapper = actor.GetMapper()
    hierarchy = mapper.GetInputAlgorithm()
    data = hierarchy.GetInputDataObject(0, 0)
    texts = [data.GetPointData().GetAbstractArray(hierarchy.GetLabelArrayName()).GetValue(i)
             for i in range(data.GetNumberOfPoints())]
    anchors = np.array([data.GetPoint(i) for i in range(data.GetNumberOfPoints())], float)
    tprop = hierarchy.GetTextProperty()
    dpi = plotter.ren_win.GetDPI()
    margin = mapper.GetMargin()
    coordinate = vtkCoordinate()
    coordinate.SetCoordinateSystemToWorld()
    boxes = []
    for p, text in zip(anchors, texts):
        coordinate.SetValue(*p)
        x, y = coordinate.GetComputedDisplayValue(plotter.renderer)
        bbox = [0, 0, 0, 0]
        vtkTextRenderer.GetInstance().GetBoundingBox(tprop, text, bbox, dpi)
        off = tprop.GetLineOffset()
        boxes.append([x + bbox[0] - margin, x + bbox[1] + margin,
                      y + bbox[2] - off - margin, y + bbox[3] - off + margin])
    return anchors, np.asarray(boxes, float), texts


CASES = ([(key, size, "app") for key in PRESETS for size in SIZES]
         + [(key, SIZES[1], order) for key in PRESETS for order in ("framed", "turned")]
         # Tilted 40 degrees in the narrow tab: the Falcon's "3.53 N" met an axis' label there.
         + [(key, SIZES[0], "tilted") for key in ("novint_falcon", "inverse3_prototype")])


@pytest.mark.parametrize("key, size, order", CASES)
def test_iso_labels_do_not_overlap_and_each_sits_on_its_own_surface(scene, key, size, order):
    plotter = scene(key, size, order)
    mesh = plotter.actors["workspace"].mapper.dataset
    _, levels = scenes.iso_label_points(mesh, QUANTITY)
    # Every shipped preset with iso-surfaces draws a few levels, each labelled.
    assert len(levels) >= 2
    assert scenes.ISO_LABEL_ACTOR in plotter.actors
    anchors, boxes, texts = _label_boxes(plotter)
    assert texts == [f"{v:.3g} {display_unit(QUANTITY)[0]}" for v in levels]

    # Each anchor is a point of the drawn surfaces, and the value there is its own level: a
    # contour's points carry the level up to the rounding of its interpolation, which
    # ``iso_label_points`` takes as one level within 1e-9 of the largest magnitude; and the
    # nearest level is its own, not a neighbour surface's.
    points = np.asarray(mesh.points, float)
    values = np.asarray(mesh.point_data[QUANTITY], float)
    tol = 1e-9 * np.max(np.abs(levels))
    for i, (p, level) in enumerate(zip(anchors, levels)):
        at = np.flatnonzero(np.all(points == p, axis=1))
        assert at.size, (key, level)
        assert np.all(np.abs(values[at] - level) <= tol), (key, level, values[at])
        assert np.all(np.argmin(np.abs(values[at, None] - np.asarray(levels)[None, :]), axis=1) == i)

    # No two labels' boxes meet, and each is inside the view, unless no point of its surface
    # could hold it there (a contour along the edge of a narrow view: the PHANToM family's flat
    # slice, square on, in the 210 px tab).
    w, h = plotter.renderer.GetSize()
    candidates, _ = scenes.iso_label_candidates(mesh, QUANTITY)
    gap = scenes.ISO_LABEL_GAP
    for i, box in enumerate(boxes):
        if box[0] >= 0 and box[1] <= w - 1 and box[2] >= 0 and box[3] <= h - 1:
            continue
        px = scenes.display_points(plotter.renderer, candidates[i])
        anchor = scenes.display_points(plotter.renderer, anchors[i:i + 1])[0]
        rel = box - np.repeat(anchor, 2)                          # the box about its anchor
        fits = ((px[:, 0] + rel[0] >= gap) & (px[:, 0] + rel[1] <= w - gap)
                & (px[:, 1] + rel[2] >= gap) & (px[:, 1] + rel[3] <= h - gap))
        assert not np.any(fits), f"{key}: label {texts[i]!r} {box} outside the {w} x {h} view, but it fits"
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            a, b = boxes[i], boxes[j]
            apart = a[1] < b[0] or b[1] < a[0] or a[3] < b[2] or b[3] < a[2]
            assert apart, f"{key}: labels {texts[i]!r} {a} and {texts[j]!r} {b} overlap"

    # The box model against the pixels: the labels change only pixels inside their boxes
    # (1 px more for the rounded box's antialiased edge), and some inside each one.
    shown = _pixels(plotter)
    plotter.actors[scenes.ISO_LABEL_ACTOR].SetVisibility(False)
    hidden = _pixels(plotter)
    changed = np.any(shown != hidden, axis=2)
    inside = np.zeros_like(changed)
    for x0, x1, y0, y1 in boxes:
        box = (slice(max(int(y0) - 1, 0), int(y1) + 2), slice(max(int(x0) - 1, 0), int(x1) + 2))
        assert changed[box].any(), f"{key}: a label was not drawn"
        inside[box] = True
    assert not np.any(changed & ~inside), f"{key}: label pixels outside the derived boxes"

    # Clear of the axes' titles and labels (drawn with the labels hidden, and then without
    # them): "3.53 N" was printed over the x label "-50".
    parts = plotter.actors[scenes.VOLUME_AXES].GetParts()
    texts = [parts.GetItemAsObject(i) for i in range(parts.GetNumberOfItems())]
    texts = [t for t in texts if t.IsA("vtkTextActor") and t.GetVisibility()]
    try:
        with_axes = _pixels(plotter)
        for t in texts:
            t.SetVisibility(False)
        axes_text = np.any(with_axes != _pixels(plotter), axis=2)
    finally:
        for t in texts:
            t.SetVisibility(True)
        plotter.actors[scenes.ISO_LABEL_ACTOR].SetVisibility(True)
    assert axes_text.any()
    for (x0, x1, y0, y1), text in zip(boxes, _label_boxes(plotter)[2]):
        box = (slice(max(int(y0), 0), int(y1) + 1), slice(max(int(x0), 0), int(x1) + 1))
        assert not axes_text[box].any(), f"{key} {size} {order}: label {text!r} over an axis' text"


def test_the_labelled_presets_include_the_box_map_and_the_revolved_maps():
    # The cases above are not vacuous: the Falcon (3D box map) and the Inverse3 (revolved slice).
    assert {"novint_falcon", "inverse3_prototype"} <= set(PRESETS)


def test_spread_labels_moves_a_label_off_a_taken_spot_and_keeps_the_view():
    # Three 40 x 16 px labels whose preferred (highest) anchors coincide at the view's top.
    top = np.array([[100.0, 170.0]])
    others = np.array([[100.0, 20.0], [20.0, 100.0], [150.0, 100.0], [195.0, 100.0]])
    candidates = [np.vstack([top, others])] * 3
    boxes = np.array([[0.0, 40.0, 0.0, 16.0]] * 3)
    view = np.array([0.0, 200.0, 0.0, 200.0])
    pick = scenes.spread_labels(candidates, boxes, view, gap=4.0)
    at = np.array([candidates[i][k] for i, k in enumerate(pick)])
    placed = at[:, [0, 0, 1, 1]] + boxes
    assert len(set(map(tuple, at))) == 3
    for i in range(3):
        # In the view by the gap (the anchor at x = 195 would put the box past the right edge).
        assert placed[i, 0] >= 4 and placed[i, 1] <= 196 and placed[i, 2] >= 4 and placed[i, 3] <= 196
        for j in range(i + 1, 3):
            a, b = placed[i], placed[j]
            assert max(b[0] - a[1], a[0] - b[1], b[2] - a[3], a[2] - b[3]) >= 4.0


def test_labels_keep_their_places_while_they_stay_apart():
    # A small turn of the scene, and a box map's plane moved (its surfaces' actor kept), leave
    # the labels where they were: they move only when they would meet or leave the view.
    mech, wmap = _map("novint_falcon")
    z = wmap.grid.coordinates()[wmap.grid.axes.index("z")]
    cache: dict = {}
    plotter = _plotter(SIZES[1])
    try:
        scenes.draw_box_workspace(plotter, wmap, QUANTITY, mech, "z", z[len(z) // 3], cache=cache)
        scenes.workspace_annotations(plotter, QUANTITY)
        _frame(plotter, "novint_falcon")
        plotter.ren_win.Render()
        placed = _label_boxes(plotter)[0]
        # Placed for this camera: not all at the surfaces' highest points (where they met).
        assert not np.array_equal(placed, scenes.iso_label_points(plotter.actors["workspace"].mapper.dataset,
                                                                  QUANTITY)[0])
        camera.orbit(plotter.renderer, plotter.camera.focal_point, 4.0, 0.0)      # 2 degrees
        plotter.ren_win.Render()
        np.testing.assert_array_equal(_label_boxes(plotter)[0], placed)
        surfaces = plotter.actors["workspace"]
        scenes.draw_box_workspace(plotter, wmap, QUANTITY, mech, "z", z[2 * len(z) // 3], cache=cache)
        scenes.workspace_annotations(plotter, QUANTITY)
        plotter.ren_win.Render()
        assert plotter.actors["workspace"] is surfaces
        np.testing.assert_array_equal(_label_boxes(plotter)[0], placed)
    finally:
        plotter.close()
