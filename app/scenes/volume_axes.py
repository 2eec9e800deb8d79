"""A workspace scene's axes in mm, on the outer edges of its box as the camera sees it.

VTK's cube axes draw 2D text for two axes only (their 2D mode has no z axis), and their 3D
text shrinks with a narrow view until it is not drawn at all. These axes are drawn as 2D
text at a fixed size, re-placed at every render whose camera or view size changed
(``_Placer``, a renderer ``StartEvent`` observer):

- each axis is drawn on one of its box's four parallel edges that lies on the box's outline
  as the camera sees it (a silhouette edge: one face at it seen from the front, the other
  from behind); of those, an edge level on screen takes the lower, an upright one the one
  further left;
- its labels are round millimetre values inside the edge, clear of both ends (where two axes
  meet), each beside a short tick at its value's own point and offset away from the box;
- its title is beyond its labels, at the edge's middle, upright beside an upright edge.

A flat picture's box (no depth along one axis) is drawn the same way: the axis it has no
extent along has no edge to draw on.
"""
from __future__ import annotations

import numpy as np
import pyvista as pv
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
from vtkmodules.vtkRenderingCore import (
    vtkActor2D,
    vtkPolyDataMapper2D,
    vtkPropAssembly,
    vtkTextActor,
    vtkTextProperty,
)

from app.scenes.screen import display_points, iso_label_boxes, new_view

#: The actor names of a volume's axes: the box's outline, and its labels, titles and ticks.
VOLUME_AXES, VOLUME_BOX = "volume_axes", "volume_axes_box"
#: Label and title font sizes (px), and pixels: a tick's length and the gaps between tick,
#: labels and title.
LABEL_SIZE, TITLE_SIZE, TICK, GAP = 10, 11, 4, 3
#: An axis' labels keep this share of its length clear at each end (where axes meet), and
#: there are at most ``MOST_LABELS`` of them.
END_CLEAR, MOST_LABELS = 0.12, 3


def axis_ticks(lo: float, hi: float, most: int = MOST_LABELS) -> tuple[np.ndarray, int]:
    """Round values strictly inside ``[lo, hi]`` for an axis' labels, and their decimals.

    The values are the multiples of one step, 1, 2 or 5 times a power of ten, inside the
    range less ``END_CLEAR`` of it at each end: of the steps that put 2 to ``most`` values
    there, the one whose values spread widest (the larger step on a tie); one value where
    no step puts two (the largest step that puts one).

    Parameters
    ----------
    lo, hi : float
        The axis' range (mm), ``lo < hi``.
    most : int
        At most this many values.

    Returns
    -------
    values : ndarray, shape (k,)
        1 <= k <= ``most``, increasing; an exact 0 where 0 is one (never -0).
    decimals : int
        The decimals that write the step (0 for a step of 1 mm or more).

    Examples
    --------
    >>> axis_ticks(-259.0, 259.0)
    (array([-100.,    0.,  100.]), 0)
    >>> axis_ticks(10.0, 11.0)
    (array([10.5]), 1)
    >>> axis_ticks(-110.4, 410.2)
    (array([  0., 200.]), 0)
    >>> axis_ticks(0.0, 0.8)
    (array([0.2, 0.4, 0.6]), 1)
    """
    span = hi - lo
    if not np.isfinite(span) or span <= 0:
        raise ValueError(f"the axis' range must be finite and increasing, got {lo!r} to {hi!r}")
    inner_lo, inner_hi = lo + END_CLEAR * span, hi - END_CLEAR * span
    power = 10.0 ** np.floor(np.log10(span / (most + 1)))
    best, single = None, None                      # (spread, step, multiples); a step with one
    for step in power * np.array([1.0, 2.0, 5.0, 10.0, 20.0, 50.0]):
        k = np.arange(np.ceil(inner_lo / step), np.floor(inner_hi / step) + 1)
        if 2 <= k.size <= most and (best is None or (k[-1] - k[0]) * step >= best[0]):
            best = ((k[-1] - k[0]) * step, step, k)
        elif k.size == 1:
            single = (0.0, step, k)
    # A narrow range (no step puts two values in it): the roundest value inside it.
    best = best or single
    _, step, k = best
    return k * step + 0.0, max(0, int(-np.floor(np.log10(step) + 1e-9)))


def _faces_seen(renderer, b: np.ndarray) -> np.ndarray:
    """Whether each face (axis, side) of box ``b`` (3, 2) faces the camera: (3, 2) bool."""
    cam = renderer.GetActiveCamera()
    centre = b.mean(axis=1)
    seen = np.zeros((3, 2), bool)
    for axis in range(3):
        for side in range(2):
            normal = np.zeros(3)
            normal[axis] = 1.0 if side else -1.0
            if cam.GetParallelProjection():
                towards = -np.asarray(cam.GetDirectionOfProjection(), float)
            else:
                face = centre.copy()
                face[axis] = b[axis, side]
                towards = np.asarray(cam.GetPosition(), float) - face
            seen[axis, side] = float(normal @ towards) > 0.0
    return seen


def outer_edges(renderer, bounds) -> dict[int, np.ndarray]:
    """The edge each axis is drawn on: its two ends (2, 3) m, by axis (0, 1, 2).

    An axis seen end-on (all four of its edges off the outline) is left out.

    Parameters
    ----------
    renderer : vtkRenderer
        Its active camera and size.
    bounds : array_like, shape (6,)
        The box (xmin, xmax, ymin, ymax, zmin, zmax), m.
    """
    b = np.asarray(bounds, float).reshape(3, 2)
    seen = _faces_seen(renderer, b)
    out = {}
    centre = b.mean(axis=1)
    for axis in range(3):
        u, v = (a for a in range(3) if a != axis)
        # One rule for all of the axis' edges (in perspective they slant differently): an axis
        # level on screen (through the box's centre) is drawn below the box, an upright one left.
        through = np.array([centre, centre])
        through[:, axis] = b[axis]
        dx, dy = np.diff(display_points(renderer, through), axis=0)[0]
        level = abs(dx) >= abs(dy)
        best = None
        for su in range(2):
            for sv in range(2):
                if seen[u, su] == seen[v, sv]:
                    continue                        # not on the outline
                ends = np.empty((2, 3))
                ends[:, axis] = b[axis]
                ends[:, u], ends[:, v] = b[u, su], b[v, sv]
                shown = display_points(renderer, ends)
                if not np.all(np.isfinite(shown)):
                    continue
                mid = shown.mean(axis=0)
                key = mid[1] if level else mid[0]        # the lower, or the further left, the better
                if best is None or key < best[0]:
                    best = (key, ends)
        if best is not None:
            out[axis] = best[1]
    return out


def _text_actor(size: int) -> vtkTextActor:
    actor = vtkTextActor()
    prop = actor.GetTextProperty()
    prop.SetFontSize(size)
    prop.SetColor(0.0, 0.0, 0.0)
    prop.SetFontFamilyToArial()
    return actor


def _sizes(text_property, texts, dpi: int) -> np.ndarray:
    """Each text's size (w, h) px as VTK draws it at ``dpi``: (k, 2)."""
    boxes = iso_label_boxes(text_property, texts, 0.0, dpi)
    return np.column_stack([boxes[:, 1] - boxes[:, 0], boxes[:, 3] - boxes[:, 2]])


def _level(text_property) -> vtkTextProperty:
    """A copy of ``text_property`` turned level (a title measured as it reads, not as drawn)."""
    level = vtkTextProperty()
    level.ShallowCopy(text_property)
    level.SetOrientation(0.0)
    return level


def _justify(prop, direction: np.ndarray) -> None:
    """Justify a text so that it lies on the ``direction`` (2,) side of its anchor."""
    dx, dy = direction
    if dx > 0.5:
        prop.SetJustificationToLeft()
    elif dx < -0.5:
        prop.SetJustificationToRight()
    else:
        prop.SetJustificationToCentered()
    if dy > 0.5:
        prop.SetVerticalJustificationToBottom()
    elif dy < -0.5:
        prop.SetVerticalJustificationToTop()
    else:
        prop.SetVerticalJustificationToCentered()


def _text_box(anchor: np.ndarray, size: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """The box (left, right, bottom, top) px of a text of ``size`` (w, h) px justified by
    ``_justify(prop, direction)`` at ``anchor`` (2,)."""
    (w, h), (dx, dy) = size, direction
    x0 = anchor[0] - (0.0 if dx > 0.5 else w if dx < -0.5 else 0.5 * w)
    y0 = anchor[1] - (0.0 if dy > 0.5 else h if dy < -0.5 else 0.5 * h)
    return np.array([x0, x0 + w, y0, y0 + h])


def _into(box: np.ndarray, view: np.ndarray) -> np.ndarray:
    """The shift (2,) px that brings ``box`` (left, right, bottom, top) inside ``view`` (the
    same), ``GAP`` px from its edges; zero for a box inside already.

    Examples
    --------
    >>> _into(np.array([-5.0, 20.0, 10.0, 20.0]), np.array([0.0, 100.0, 0.0, 100.0]))
    array([8., 0.])
    """
    lo = view[[0, 2]] + GAP - box[[0, 2]]
    hi = view[[1, 3]] - GAP - box[[1, 3]]
    return np.where(lo > 0, lo, np.where(hi < 0, hi, 0.0))


def _clear(box: np.ndarray, taken: list[np.ndarray]) -> bool:
    """``box`` is at least ``GAP`` px from each of the boxes ``taken``."""
    return all(box[0] >= t[1] + GAP or t[0] >= box[1] + GAP or box[2] >= t[3] + GAP or t[2] >= box[3] + GAP
               for t in taken)


class _Placer:
    """Places the axes' ticks, labels and titles for the camera of each render (a renderer
    ``StartEvent`` observer); does nothing while its assembly is not in the renderer.

    An axis' texts are laid out beside its edge; then the titles are kept, and the labels
    from each edge's middle outwards, each only where it is clear of those kept before it
    (a foreshortened edge, or two edges meeting at a corner, keeps fewer).
    """

    def __init__(self, assembly, bounds: np.ndarray, titles, labels, values, ticks: vtkPolyData) -> None:
        self.assembly, self.bounds, self.ticks = assembly, bounds, ticks
        # By axis: its title actor; its label actors and their values (mm).
        self.titles, self.labels, self.values = titles, labels, values
        self.seen = None                 # (camera stamp, size, origin, dpi) of the last placing
        self.observer = None             # its tag as the renderer's observer
        #: The boxes (left, right, bottom, top) px of the texts drawn for the last camera.
        self.shown: list = []
        self._sizes: dict = {}           # dpi -> by axis, (title's (w, h), labels' (k, 2)) px

    def sizes(self, dpi: int) -> list:
        """By axis, its title's size (w, h) px and its labels' (k, 2), drawn at ``dpi``."""
        if dpi not in self._sizes:
            self._sizes[dpi] = [(_sizes(_level(title.GetTextProperty()), [title.GetInput()], dpi)[0],
                                 _sizes(row[0].GetTextProperty(), [a.GetInput() for a in row], dpi)
                                 if row else np.empty((0, 2)))
                                for title, row in zip(self.titles, self.labels)]
        return self._sizes[dpi]

    def __call__(self, renderer, _event=None) -> None:
        if not renderer.HasViewProp(self.assembly):       # removed by other means (``plotter.clear()``)
            if self.observer is not None:
                renderer.RemoveObserver(self.observer)
                self.observer = None
            return
        seen = new_view(renderer, self.seen)
        if seen is None:
            return
        self.seen, dpi = seen, seen[-1]
        all_sizes = self.sizes(dpi)
        for actor in [*self.titles, *(a for row in self.labels for a in row)]:
            actor.SetVisibility(False)
        b = self.bounds.reshape(3, 2)
        origin = np.asarray(renderer.GetOrigin(), float)
        centre = display_points(renderer, b.mean(axis=1)[None])[0]
        edges = outer_edges(renderer, self.bounds)
        titles, labels = [], []        # (box, actor), and (priority, box, actor, tick's two ends)
        (vw, vh), (ox, oy) = renderer.GetSize(), renderer.GetOrigin()
        view = np.array([ox, ox + vw, oy, oy + vh], float)
        for axis, edge in edges.items():
            ends = display_points(renderer, edge)
            along = ends[1] - ends[0]
            length = float(np.hypot(*along))
            if not length > 1.0:                    # an edge seen end-on: a point on screen
                continue
            along /= length
            out = np.array([-along[1], along[0]])
            middle = 0.5 * (ends[0] + ends[1])
            if out @ (middle - centre) < 0:
                out = -out
            # The labels' extent away from the edge (widest along ``out``), for the title's place.
            sizes = all_sizes[axis][1]
            reach = float(np.max(np.abs(out) @ sizes.T)) if len(sizes) else 0.0
            lo, hi = b[axis] * 1e3
            # Each value's own point on the edge, projected: in perspective the screen's
            # shares of the edge are not the edge's own.
            shares = (np.asarray(self.values[axis], float) - lo) / (hi - lo)
            spots = display_points(renderer, edge[0] + np.outer(shares, edge[1] - edge[0]))
            for label, share, at, size in zip(self.labels[axis], shares, spots, sizes):
                _justify(label.GetTextProperty(), out)
                anchor = at + (TICK + GAP) * out
                label.SetPosition(*(anchor - origin))
                labels.append((abs(share - 0.5), _text_box(anchor, size, out), label, (at, at + TICK * out)))
            title = self.titles[axis]
            upright = abs(along[1]) > 0.8
            prop = title.GetTextProperty()
            prop.SetOrientation(90.0 if upright else 0.0)
            anchor = middle + (TICK + 3 * GAP + reach) * out     # a gap clear of the widest label
            tw, th = all_sizes[axis][0]                          # the title's size, read level
            if upright:
                # Turned a quarter left, the text's top faces left: anchored at its bottom, it
                # lies left of the anchor; at its top, right of it.
                prop.SetJustificationToCentered()
                if out[0] < 0:
                    prop.SetVerticalJustificationToBottom()
                else:
                    prop.SetVerticalJustificationToTop()
                box = _text_box(anchor, np.array([th, tw]), np.array([np.sign(out[0]), 0.0]))
            else:
                _justify(prop, out)
                box = _text_box(anchor, np.array([tw, th]), out)
            # A title past the view's edge (the camera turned, the box outgrew the margin) is
            # moved in, if its edge's middle is in view (else it would stand by no part of its
            # axis): an axis without its title is a row of bare numbers.
            shift = _into(box, view)
            beside = view[0] <= middle[0] <= view[1] and view[2] <= middle[1] <= view[3]
            if np.any(shift) and not beside:
                continue
            title.SetPosition(*(anchor + shift - origin))
            titles.append((box + np.repeat(shift, 2), title))
        taken = []
        for box, title in titles:
            if _clear(box, taken):              # two titles moved into one corner: the first only
                title.SetVisibility(True)
                taken.append(box)
        self.shown = taken                       # the texts' boxes, filled in as they are kept
        points, lines = vtkPoints(), vtkCellArray()
        for _, box, label, tick in sorted(labels, key=lambda item: item[0]):
            if _clear(box, taken) and not np.any(_into(box, view)):          # whole, in view, apart
                label.SetVisibility(True)
                taken.append(box)
                ids = [points.InsertNextPoint(*(p - origin), 0.0) for p in tick]
                lines.InsertNextCell(2, ids)
        self.ticks.SetPoints(points)
        self.ticks.SetLines(lines)
        self.ticks.Modified()


def axes_margin(plotter, share: float) -> float:
    """The share of the view's width to keep free at each side when framing the scene
    (``camera.fit_bounds``): ``share``, or more where the volume's axes need more pixels
    beside the box than that leaves (a narrow tab): a tick, a label, a title and their gaps.

    Parameters
    ----------
    plotter : pyvista.Plotter
        Its renderer's size, and its volume axes if it has them (``volume_axes``).
    share : float
        The share to keep at least.
    """
    kept = plotter.__dict__.get("_isoforce_volume_axes")
    width = plotter.renderer.GetSize()[0]
    if kept is None or width <= 1 or not plotter.renderer.HasViewProp(kept[2].assembly):
        return share
    placer = kept[2]
    window = plotter.renderer.GetVTKWindow()
    sizes = placer.sizes(int(window.GetDPI()) if window is not None else 72)
    widest = max((float(labels[:, 0].max()) for _, labels in sizes if len(labels)), default=0.0)
    title = max(float(min(size)) for size, _ in sizes)       # an upright title's width is its height
    room = TICK + 3 * GAP + widest + title + GAP
    return min(0.45, max(share, room / width))


def axes_texts(assembly):
    """A callable giving the boxes (m, 4) px of the texts ``volume_axes``'s ``assembly`` draws
    for the camera of the render under way (its placer runs first), for other texts to avoid."""
    placer = assembly._isoforce_placer
    return lambda: np.asarray(placer.shown, float).reshape(-1, 4)


def remove_volume_axes(plotter) -> None:
    """Remove a volume's axes (``volume_axes``) from the plotter, if it has them."""
    plotter.remove_actor([VOLUME_AXES, VOLUME_BOX], reset_camera=False, render=False)
    kept = plotter.__dict__.pop("_isoforce_volume_axes", None)
    if kept is not None:
        renderer, observer, _ = kept
        renderer.RemoveObserver(observer)


def widget_box(plotter) -> np.ndarray | None:
    """The box (6,) m a cut plane's widget draws round the scene (``add_mesh_clip_plane``:
    the scene's box grown by a quarter), or None without one."""
    # ``Plotter.widgets`` from PyVista 0.48 (its ``plane_widgets`` warns there), the plotter before.
    owner = getattr(plotter, "widgets", plotter)
    for widget in getattr(owner, "plane_widgets", []):
        if not widget.IsA("vtkImplicitPlaneWidget"):
            continue
        outline = widget.GetOutlineProperty()
        actors = plotter.renderer.GetActors()
        for i in range(actors.GetNumberOfItems()):
            actor = actors.GetItemAsObject(i)
            if actor.GetProperty() is outline and actor.GetVisibility():
                return np.asarray(actor.GetBounds(), float)
    return None


def box_outline(bounds) -> pv.PolyData:
    """The 12 edges of the box ``bounds`` (6,) m as lines: ``pv.Box(bounds).outline()``, made
    directly (VTK's two filters took 20-30 ms of the GUI thread on a loaded machine).

    Examples
    --------
    >>> edges = box_outline([0.0, 1.0, 0.0, 2.0, 0.0, 3.0])
    >>> edges.n_points, edges.n_lines, edges.bounds == pv.Box([0.0, 1.0, 0.0, 2.0, 0.0, 3.0]).outline().bounds
    (8, 12, True)
    """
    b = np.asarray(bounds, float).reshape(3, 2)
    corners = np.array([[b[0, i], b[1, j], b[2, k]] for k in (0, 1) for j in (0, 1) for i in (0, 1)])
    # Corner index = i + 2 j + 4 k: an edge joins two corners that differ in one of i, j, k.
    edges = [(c, c | bit) for bit in (1, 2, 4) for c in range(8) if not c & bit]
    return pv.PolyData(corners, lines=np.array([[2, a, z] for a, z in edges]).ravel())


def volume_axes(plotter, bounds) -> vtkPropAssembly:
    """Draw the box ``bounds`` (6,) m with its three axes in mm on its outer edges.

    Replaces the axes drawn before (``remove_volume_axes``). The box's outline is the actor
    ``VOLUME_BOX``; the labels, titles and ticks are the assembly ``VOLUME_AXES``, placed
    for the camera at each render. Where a cut plane's widget draws a box round the scene
    (``widget_box``), the axes are on that box and no second box is drawn.

    Returns
    -------
    vtkPropAssembly
        The labels, titles and ticks: the text actors first (three titles, then each axis'
        labels), the ticks' 2D actor last.
    """
    remove_volume_axes(plotter)
    b = widget_box(plotter)
    if b is None:
        b = np.asarray(bounds, float).reshape(6)
        plotter.add_mesh(box_outline(b), color="black", line_width=1, name=VOLUME_BOX, pickable=False,
                         reset_camera=False, render=False)
    titles = [_text_actor(TITLE_SIZE) for _ in range(3)]
    labels, values = [], []
    for axis, title in enumerate(titles):
        title.SetInput(f"{'xyz'[axis]} (mm)")
        lo, hi = b[2 * axis: 2 * axis + 2] * 1e3
        ticks, decimals = axis_ticks(lo, hi) if hi > lo else (np.empty(0), 0)
        strings = [f"{v:.{decimals}f}" for v in ticks]
        row = [_text_actor(LABEL_SIZE) for _ in strings]
        for actor, text in zip(row, strings):
            actor.SetInput(text)
        labels.append(row)
        values.append(ticks)
    tick_data = vtkPolyData()
    tick_mapper = vtkPolyDataMapper2D()
    tick_mapper.SetInputData(tick_data)
    tick_actor = vtkActor2D()
    tick_actor.SetMapper(tick_mapper)
    tick_actor.GetProperty().SetColor(0.0, 0.0, 0.0)
    assembly = vtkPropAssembly()
    for actor in [*titles, *(a for row in labels for a in row), tick_actor]:
        assembly.AddPart(actor)
    plotter.add_actor(assembly, name=VOLUME_AXES, reset_camera=False, render=False, pickable=False)
    assembly._isoforce_box = b          # the box (6,) m the axes are drawn on
    placer = _Placer(assembly, b, titles, labels, values, tick_data)
    observer = placer.observer = plotter.renderer.AddObserver("StartEvent", placer)
    assembly._isoforce_placer = placer
    plotter.__dict__["_isoforce_volume_axes"] = (plotter.renderer, observer, placer)
    return assembly
