"""The iso-surface labels of a workspace scene, kept apart on screen, and its axes in mm.

``workspace_annotations`` writes each iso-surface's value at a point of that surface and
draws the scene's bounds as axes in millimetres on the outer edges of its box
(``volume_axes``: a volume's three, a flat picture's two). The points are chosen for the camera of a
render (``_IsoLabelPlacer``, a renderer observer): each surface's candidate points
(``iso_label_candidates``) are projected to the screen (``display_points``) and
``spread_labels`` picks one per label so that the labels' boxes (``iso_label_boxes``) stay
apart and inside the view.
"""
from __future__ import annotations

import numpy as np
import pyvista as pv
from vtkmodules.vtkCommonCore import vtkStringArray

from app.logic.display_units import display_unit
from app.scenes.screen import display_points, iso_label_boxes, new_view
from app.scenes.volume_axes import axes_texts, remove_volume_axes, volume_axes
from app.scenes.workspace import ISO_LEVELS
from metrics.quantities import QUANTITIES

#: The iso-surface labels in a workspace scene (``workspace_annotations``): the name given to
#: ``add_point_labels`` and the name its actor is kept under (pyvista appends "-labels").
ISO_LABELS = "iso_labels"
ISO_LABEL_ACTOR = ISO_LABELS + "-labels"
#: The labels' font size (points; VTK draws 72 points per inch, so pixels at its default 72 dpi)
#: and the margin (px) of the white box drawn round each text.
ISO_LABEL_FONT_SIZE, ISO_LABEL_MARGIN = 11, 3
#: Pixels kept free between two labels' boxes (with their margins), and inside the view's edge:
#: a clear white line between two boxes after VTK rounds each anchor down to a whole pixel.
ISO_LABEL_GAP = 4
#: At most this many points of an iso-surface are tried as its label's anchor (evenly strided
#: through the surface's points): enough to reach every side of it, and a few ms to project.
ISO_LABEL_CANDIDATES = 2000


def _iso_surface_masks(mesh, quantity: str, max_levels: int) -> tuple[np.ndarray, list[np.ndarray], list[float]]:
    """The points (N, 3) m of ``mesh``, one mask (N,) per level of the points on it, and the levels (k,)."""
    if mesh is None or not mesh.n_points or quantity not in mesh.point_data:
        return np.empty((0, 3)), [], []
    values = np.asarray(mesh.point_data[quantity], float)
    finite = np.unique(values[np.isfinite(values)])
    if not finite.size:
        return np.empty((0, 3)), [], []
    # A surface cut at the workspace's edge interpolates between two samples of its level: the
    # same level to rounding. Values within 1e-9 of the largest magnitude are one level.
    tol = 1e-9 * float(np.max(np.abs(finite)))
    levels = finite[np.concatenate([[True], np.diff(finite) > tol])]
    if not levels.size <= max_levels:
        return np.empty((0, 3)), [], []
    return np.asarray(mesh.points, float), [np.abs(values - v) <= tol for v in levels], [float(v) for v in levels]


def iso_label_points(mesh, quantity: str, max_levels: int = 2 * ISO_LEVELS) -> tuple[np.ndarray, list[float]]:
    """One point per iso-surface of ``mesh``, its highest, and the surfaces' levels.

    Parameters
    ----------
    mesh : pyvista.DataSet or None
        Iso-surfaces (or contour lines) carrying point array ``quantity``: each point its
        surface's level exactly, as a contour's points do.
    quantity : str
        The point array's name.
    max_levels : int
        More distinct values than this is a continuous field, not iso-surfaces: no points.

    Returns
    -------
    points : ndarray, shape (k, 3)
        The highest point (largest z, m) of each surface, a point of ``mesh``.
    levels : list of float, length k
        The levels, ascending.

    See Also
    --------
    iso_label_candidates : every point that may hold a surface's label, for placing the labels
        apart on screen (``workspace_annotations`` does).

    Examples
    --------
    >>> mesh = pv.PolyData(np.array([[0.0, 0, 0], [0, 0, 1], [1, 0, 0], [1, 0, 2]]))
    >>> mesh.point_data["f"] = [2.0, 2.0, 5.0, 5.0]
    >>> points, levels = iso_label_points(mesh, "f")
    >>> points, levels
    (array([[0., 0., 1.],
           [1., 0., 2.]]), [2.0, 5.0])
    """
    pts, masks, levels = _iso_surface_masks(mesh, quantity, max_levels)
    at = [pts[on][np.argmax(pts[on, 2])] for on in masks]
    return (np.asarray(at) if at else np.empty((0, 3))), levels


def iso_label_candidates(mesh, quantity: str, max_levels: int = 2 * ISO_LEVELS,
                         count: int = ISO_LABEL_CANDIDATES) -> tuple[list[np.ndarray], list[float]]:
    """The points of each iso-surface of ``mesh`` that may hold its label, and the levels.

    Parameters
    ----------
    mesh, quantity, max_levels
        As for ``iso_label_points``.
    count : int
        At most about this many candidates per surface: its points, evenly strided.

    Returns
    -------
    candidates : list of ndarray, each shape (n_i, 3)
        Points of the i-th surface (m), its highest point (``iso_label_points``) first.
    levels : list of float, length k
        The levels, ascending.

    Examples
    --------
    >>> mesh = pv.PolyData(np.array([[0.0, 0, 0], [0, 0, 1], [1, 0, 0], [1, 0, 2]]))
    >>> mesh.point_data["f"] = [2.0, 2.0, 5.0, 5.0]
    >>> candidates, levels = iso_label_candidates(mesh, "f")
    >>> candidates[1], levels
    (array([[1., 0., 2.],
           [1., 0., 0.],
           [1., 0., 2.]]), [2.0, 5.0])
    """
    pts, masks, levels = _iso_surface_masks(mesh, quantity, max_levels)
    out = []
    for on in masks:
        own = pts[on]
        step = max(1, -(-len(own) // count))
        out.append(np.vstack([own[np.argmax(own[:, 2])], own[::step]]))
    return out, levels


def _label_boxes(anchors: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """Boxes (n, 4) on screen, (left, right, bottom, top) px, of labels with boxes ``boxes``
    ((4,) or (n, 4), relative to the anchor) at anchors (n, 2) px."""
    return np.column_stack([anchors[:, 0] + boxes[..., 0], anchors[:, 0] + boxes[..., 1],
                            anchors[:, 1] + boxes[..., 2], anchors[:, 1] + boxes[..., 3]])


def _inside(boxes: np.ndarray, view: np.ndarray, gap: float) -> np.ndarray:
    """Whether each box (n, 4) lies ``gap`` px inside ``view`` (4,), shape (n,); False for nan."""
    return ((boxes[:, 0] >= view[0] + gap) & (boxes[:, 1] <= view[1] - gap)
            & (boxes[:, 2] >= view[2] + gap) & (boxes[:, 3] <= view[3] - gap))


def _separation(boxes: np.ndarray, placed: np.ndarray) -> np.ndarray:
    """The clearance (px) of each box (n, 4) from the nearest of ``placed`` (m, 4), shape (n,).

    Boxes are (left, right, bottom, top). Two boxes are apart by the larger of their horizontal
    and vertical gaps; a negative clearance is an overlap. ``inf`` with nothing placed.
    """
    if not len(placed):
        return np.full(len(boxes), np.inf)
    b, q = boxes[:, None, :], placed[None, :, :]
    dx = np.maximum(q[..., 0] - b[..., 1], b[..., 0] - q[..., 1])
    dy = np.maximum(q[..., 2] - b[..., 3], b[..., 2] - q[..., 3])
    return np.maximum(dx, dy).min(axis=1)


def spread_labels(candidates, boxes, view, *, gap: float = ISO_LABEL_GAP, taken=None) -> np.ndarray:
    """Choose one anchor per label so that no two labels' boxes come within ``gap`` pixels.

    Parameters
    ----------
    candidates : sequence of k ndarrays, each shape (n_i, 2)
        Each label's possible anchors on screen (px, x right, y up; ``nan``: not on screen).
    boxes : array_like, shape (k, 4)
        Each label's box as drawn (text and margin), relative to its anchor: (left, right,
        bottom, top) px.
    view : array_like, shape (4,)
        The screen area (left, right, bottom, top) px every box should stay ``gap`` inside.
    gap : float
        The least clearance (px) between two boxes, and between a box and the view's edge.
    taken : array_like, shape (m, 4), optional
        Boxes of other texts on screen (the axes' labels), (left, right, bottom, top) px: the
        labels keep ``gap`` clear of them too.

    Returns
    -------
    ndarray of int, shape (k,)
        For each label, the index of its chosen anchor among its ``candidates``.

    Notes
    -----
    Greedy, the label with the narrowest spread of anchors on screen (an inner surface) first.
    The first label takes its highest anchor (where it is seen over the rest). Each later one
    takes, among the anchors whose box is inside the view and clear of the boxes already
    placed, the one farthest from them (centre to centre): the labels spread over the
    surfaces' outlines instead of crowding one side. When no anchor is clear (a view too small
    for the labels) it takes the one that overlaps the others least.

    Examples
    --------
    Two labels 20 x 10 px whose highest anchors coincide: the second moves to its other anchor.

    >>> candidates = [np.array([[50.0, 80.0], [50.0, 20.0]]), np.array([[50.0, 80.0], [10.0, 40.0]])]
    >>> spread_labels(candidates, [[0, 20, 0, 10]] * 2, [0, 100, 0, 100])
    array([0, 1])
    """
    boxes = np.asarray(boxes, float).reshape(-1, 4)
    view = np.asarray(view, float)
    px = [np.asarray(c, float).reshape(-1, 2) for c in candidates]
    chosen = np.zeros(len(px), int)
    spread = [float(np.prod(np.ptp(p[np.all(np.isfinite(p), axis=1)], axis=0)))
              if np.isfinite(p).all(axis=1).any() else np.inf for p in px]
    placed = np.empty((0, 4))
    fixed = np.empty((0, 4)) if taken is None else np.asarray(taken, float).reshape(-1, 4)
    for i in np.argsort(spread, kind="stable"):
        box = _label_boxes(px[i], boxes[i])
        inside = _inside(box, view, gap)
        clear = _separation(box, np.vstack([fixed, placed]))
        ok = inside & (clear >= gap)
        if not ok.any():
            # Nothing fits: the least overlap, on screen if anything is (nan compares False).
            score = np.where(inside, clear, -np.inf) if inside.any() else np.nan_to_num(clear, nan=-np.inf)
        elif not len(placed):
            score = np.where(ok, box[:, 3], -np.inf)
        else:
            centre = np.column_stack([box[:, 0] + box[:, 1], box[:, 2] + box[:, 3]]) / 2
            others = np.column_stack([placed[:, 0] + placed[:, 1], placed[:, 2] + placed[:, 3]]) / 2
            far = np.linalg.norm(centre[:, None, :] - others[None, :, :], axis=2).min(axis=1)
            score = np.where(ok, far, -np.inf)
        chosen[i] = int(np.argmax(score))
        placed = np.vstack([placed, box[chosen[i]]])
    return chosen


class _IsoLabelPlacer:
    """Moves the iso-surface labels apart for the camera of each render (a renderer ``StartEvent`` observer).

    The labels' anchors are the points of ``data`` (its point array holds the texts). On a
    render whose camera, view size or dpi changed since the last, the labels are kept where
    they are while they stay clear of each other and inside the view (so they do not jump as
    the user turns the scene), and placed anew by ``spread_labels`` when they do not.
    """

    def __init__(self, actor, data, candidates, texts, text_property, margin: float) -> None:
        self.actor, self.data, self.candidates, self.texts = actor, data, candidates, list(texts)
        self.text_property, self.margin = text_property, margin
        self.seen = None            # (camera stamp, size, origin, dpi) of the last render checked
        self.placed = False         # anchors chosen for some camera yet (else the highest points)
        self._boxes: dict = {}      # dpi -> boxes (k, 4)
        #: Boxes (m, 4) px of other texts to keep clear of, for this render (the axes' labels), or None.
        self.avoid = None

    def __call__(self, renderer, _event=None) -> None:
        if not renderer.HasViewProp(self.actor):        # removed by other means than workspace_annotations
            return
        seen = new_view(renderer, self.seen)
        if seen is None:
            return
        self.seen, dpi = seen, seen[-1]
        boxes = self._boxes.get(dpi)
        if boxes is None:
            boxes = self._boxes[dpi] = iso_label_boxes(self.text_property, self.texts, self.margin, dpi)
        (w, h), (ox, oy) = renderer.GetSize(), renderer.GetOrigin()
        view = np.array([ox, ox + w, oy, oy + h], float)
        taken = np.empty((0, 4)) if self.avoid is None else np.asarray(self.avoid(), float).reshape(-1, 4)
        if self.placed:
            # The test ``spread_labels`` places by: each box in the view and clear of the others.
            box = _label_boxes(display_points(renderer, np.asarray(self.data.points, float)), boxes)
            clear = [_separation(box[i:i + 1], np.delete(box, i, axis=0))[0] >= ISO_LABEL_GAP
                     for i in range(len(box))]
            # The axes' texts move with every turn: a label is kept until it would touch one
            # (placed, it keeps the gap), so that it does not jump at each small turn.
            off_axes = _separation(box, taken) >= 0.0
            if _inside(box, view, ISO_LABEL_GAP).all() and all(clear) and off_axes.all():
                return
        pick = spread_labels([display_points(renderer, c) for c in self.candidates], boxes, view, taken=taken)
        self.data.points = np.array([c[i] for c, i in zip(self.candidates, pick)], float)
        self.placed = True


def _remove_iso_labels(plotter):
    """Remove the iso-surface labels' actor and the observer that places them; return that
    observer's ``(placer, surfaces' actor)``, or None."""
    plotter.remove_actor(ISO_LABEL_ACTOR, reset_camera=False, render=False)
    kept = plotter.__dict__.pop("_isoforce_iso_labels", None)
    if kept is None:
        return None
    renderer, observer, placer, surfaces = kept
    renderer.RemoveObserver(observer)
    return placer, surfaces


def _drawn_dataset(actor):
    """The dataset an actor shows, its pipeline run (smooth shading draws a normals filter's
    output, which is empty until the first render runs the filter)."""
    if actor is None:
        return None
    algorithm = actor.GetMapper().GetInputAlgorithm()
    if algorithm is not None:
        algorithm.Update()
    return actor.mapper.dataset


def workspace_annotations(plotter, quantity: str, also=()) -> None:
    """Axes in mm around the workspace scene and a label with its value on each iso-surface
    (``label_iso_surfaces``): the app's 3D workspace view. The axes' box holds the scene's
    actors and those named in ``also`` (the semi-dextrous region's)."""
    plotter.remove_bounds_axes()
    remove_volume_axes(plotter)
    names = ("workspace", "box_hull", "box_plane", *also)
    shown = [plotter.actors[n] for n in names if plotter.actors.get(n) is not None]
    avoid = None
    if shown:
        b = np.array([a.GetBounds() for a in shown], float)
        bounds = np.column_stack([b[:, 0::2].min(axis=0), b[:, 1::2].max(axis=0)]).ravel()
        # The scene is in metres; the axes' labels say millimetres, each at its own value's point.
        # Drawn first: their placer runs before the iso-surface labels' at each render, and
        # those keep clear of the axes' texts ("3.53 N" was printed over the x label "-50").
        avoid = axes_texts(volume_axes(plotter, bounds))
    label_iso_surfaces(plotter, quantity, avoid=avoid)


def label_iso_surfaces(plotter, quantity: str, font_size: int = ISO_LABEL_FONT_SIZE, *, avoid=None) -> None:
    """A label with its value on each iso-surface of the plotter's ``"workspace"`` actor (the
    app's view and the exported workspace figure), when that actor is iso-surfaces (drawn by
    ``draw_box_workspace`` or the "iso-surfaces" mode, which mark it so); none on a map's
    surface, however few distinct values it has (classes, a coarse grid). ``font_size`` in
    points (a figure's labels grow with its pixels).

    Each label is anchored at a point of its own surface. Where on the surface is chosen at
    render time for the camera of that render (``spread_labels``): at the first render after
    this call (the framed view, in the app and in a figure alike) and again whenever a turn,
    zoom or resize of the view makes two labels touch or one leave the view; otherwise they
    stay where they are while the user turns the scene. Before any render they are at the
    surfaces' highest points (``iso_label_points``). Labels of the same surfaces drawn again
    (a box map's plane moved: its surfaces' actor is kept) keep their places.
    """
    node = QUANTITIES[quantity]
    before = _remove_iso_labels(plotter)
    surfaces = plotter.actors.get("workspace")
    if not getattr(surfaces, "_isoforce_iso_surfaces", False):
        return
    candidates, levels = iso_label_candidates(_drawn_dataset(surfaces), quantity)
    if len(levels):
        unit = f" {display_unit(quantity)[0]}" if node.unit else ""
        texts = [f"{v:.3g}{unit}" for v in levels]
        same = before is not None and before[1] is surfaces and before[0].texts == texts
        at = np.asarray(before[0].data.points, float) if same else np.array([c[0] for c in candidates], float)
        data = pv.PolyData(at)
        # A VTK string array made here: pyvista's conversion refuses non-ASCII text ("µm").
        strings = vtkStringArray()
        strings.SetName("iso_label")
        for text in texts:
            strings.InsertNextValue(text)
        data.GetPointData().AddArray(strings)
        label = plotter.add_point_labels(data, "iso_label", font_size=font_size, text_color="black",
                                         shape_color="white", shape_opacity=0.75, margin=ISO_LABEL_MARGIN,
                                         show_points=False, name=ISO_LABELS, always_visible=True,
                                         reset_camera=False, render=False)
        mapper = label.GetMapper()
        # The placer keeps the labels apart; VTK's own collision test (text boxes without their
        # margins) would only ever drop a label that the placer could not fit (a tiny view).
        mapper.SetPlaceAllLabels(True)
        placer = _IsoLabelPlacer(label, data, candidates, texts, mapper.GetInputAlgorithm().GetTextProperty(),
                                 ISO_LABEL_MARGIN)
        placer.placed = same and before[0].placed
        placer.avoid = avoid
        # After the axes' placer (priority 0; VTK calls the higher first): their texts' places
        # for this camera are known when the labels are placed clear of them.
        observer = plotter.renderer.AddObserver("StartEvent", placer, -1.0)
        plotter.__dict__["_isoforce_iso_labels"] = (plotter.renderer, observer, placer, surfaces)
