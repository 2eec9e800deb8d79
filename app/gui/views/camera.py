"""Camera moves of the 3D views, done by hand (the views are off-screen VTK painted as images).

No Qt here: each function takes a ``pyvista.Renderer`` (its camera is changed in place) and
display pixels in VTK's convention (origin bottom-left, device pixels).

- ``orbit``: turn the camera about a pivot (the end-effector in the pose view). The pivot's
  place in camera coordinates is unchanged, so its pixel stays where it was, whatever the drag.
- ``keep_in_view``: after an orbit, zoom out about the pivot until the whole scene is in view.
- ``zoom_at``: a homothety of the camera about the point under the cursor (on the focal
  plane): that point keeps its pixel, in perspective and in parallel projection.
- ``pan``: move the camera parallel to the view plane by the drag, in focal-plane metres.
- ``CameraState``: a camera's numbers, to keep one per device and restore it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Degrees of turn per pixel of drag (a 360 px drag turns the scene half round).
DEG_PER_PX = 0.5
#: Zoom factor per wheel notch (120 units of ``angleDelta``).
ZOOM_PER_NOTCH = 1.2


@dataclass(frozen=True)
class CameraState:
    """Position, focal point, view-up (m), view angle (deg), parallel scale (m), projection."""

    position: tuple
    focal_point: tuple
    view_up: tuple
    view_angle: float
    parallel_scale: float
    parallel: bool

    @classmethod
    def of(cls, renderer) -> CameraState:
        cam = renderer.GetActiveCamera()
        return cls(tuple(cam.GetPosition()), tuple(cam.GetFocalPoint()), tuple(cam.GetViewUp()),
                   float(cam.GetViewAngle()), float(cam.GetParallelScale()), bool(cam.GetParallelProjection()))

    def apply(self, renderer) -> None:
        cam = renderer.GetActiveCamera()
        cam.SetPosition(*self.position)
        cam.SetFocalPoint(*self.focal_point)
        cam.SetViewUp(*self.view_up)
        cam.SetViewAngle(self.view_angle)
        cam.SetParallelScale(self.parallel_scale)
        cam.SetParallelProjection(self.parallel)
        renderer.ResetCameraClippingRange()


def _rotation(axis: np.ndarray, degrees: float) -> np.ndarray:
    """Rodrigues' rotation matrix (3, 3) about unit ``axis`` by ``degrees``."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    t = np.radians(degrees)
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + np.sin(t) * k + (1.0 - np.cos(t)) * (k @ k)


def orbit(renderer, pivot, dx_px: float, dy_px: float, deg_per_px: float = DEG_PER_PX) -> None:
    """Turn the camera about ``pivot`` (3,) m: a drag of ``dx_px`` right turns the scene right
    (about the view-up axis), ``dy_px`` up tilts it up (about the camera's right axis)."""
    cam = renderer.GetActiveCamera()
    pos, focal = np.array(cam.GetPosition()), np.array(cam.GetFocalPoint())
    up = np.array(cam.GetViewUp())
    forward = focal - pos
    right = np.cross(forward, up)
    if np.linalg.norm(right) == 0:
        return
    # The scene turns with the drag, so the camera turns the other way.
    r = _rotation(up, -dx_px * deg_per_px) @ _rotation(right, dy_px * deg_per_px)
    p = np.asarray(pivot, float)
    cam.SetPosition(*(p + r @ (pos - p)))
    cam.SetFocalPoint(*(p + r @ (focal - p)))
    cam.SetViewUp(*(r @ up))
    cam.OrthogonalizeViewUp()
    renderer.ResetCameraClippingRange()


def display_to_focal_plane(renderer, x_px: float, y_px: float) -> np.ndarray:
    """The world point (3,) m on the camera's focal plane seen at display pixel (x, y)."""
    cam = renderer.GetActiveCamera()
    renderer.SetWorldPoint(*cam.GetFocalPoint(), 1.0)
    renderer.WorldToDisplay()
    depth = renderer.GetDisplayPoint()[2]
    renderer.SetDisplayPoint(float(x_px), float(y_px), depth)
    renderer.DisplayToWorld()
    w = np.array(renderer.GetWorldPoint(), float)
    return w[:3] / w[3]


def world_to_display(renderer, point) -> np.ndarray:
    """Display pixel (x, y) (2,) of world ``point`` (3,) m, VTK's origin at the bottom left."""
    renderer.SetWorldPoint(*np.asarray(point, float), 1.0)
    renderer.WorldToDisplay()
    return np.array(renderer.GetDisplayPoint()[:2], float)


def zoom_at(renderer, x_px: float, y_px: float, factor: float) -> None:
    """Magnify by ``factor`` (> 1 in) keeping the focal-plane point under pixel (x, y) in place.

    The camera's position and focal point are scaled about that point by 1 / factor (and the
    parallel scale with them): a homothety about a point leaves that point's image unchanged.
    """
    cam = renderer.GetActiveCamera()
    anchor = display_to_focal_plane(renderer, x_px, y_px)
    s = 1.0 / float(factor)
    pos, focal = np.array(cam.GetPosition()), np.array(cam.GetFocalPoint())
    cam.SetPosition(*(anchor + s * (pos - anchor)))
    cam.SetFocalPoint(*(anchor + s * (focal - anchor)))
    cam.SetParallelScale(cam.GetParallelScale() * s)
    renderer.ResetCameraClippingRange()


def pan(renderer, x0: float, y0: float, x1: float, y1: float) -> None:
    """Move the camera so the focal-plane point under (x0, y0) comes under (x1, y1)."""
    cam = renderer.GetActiveCamera()
    shift = display_to_focal_plane(renderer, x0, y0) - display_to_focal_plane(renderer, x1, y1)
    cam.SetPosition(*(np.array(cam.GetPosition()) + shift))
    cam.SetFocalPoint(*(np.array(cam.GetFocalPoint()) + shift))
    renderer.ResetCameraClippingRange()


def _project(renderer, points: np.ndarray) -> np.ndarray:
    """Display pixels (k, 2) of world points (k, 3) m through the active camera."""
    w, h = renderer.GetSize()
    m = renderer.GetActiveCamera().GetCompositeProjectionTransformMatrix(w / max(h, 1), -1, 1)
    mat = np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])
    hom = np.column_stack([points, np.ones(len(points))]) @ mat.T
    ndc = hom[:, :2] / hom[:, 3:4]
    return np.column_stack([(ndc[:, 0] + 1) * 0.5 * w, (ndc[:, 1] + 1) * 0.5 * h])


def fit_bounds(renderer, bounds: np.ndarray, margin: float = 0.06, iterations: int = 4, top: float = 0.0,
               bottom: float = 0.0) -> None:
    """Pan and zoom so the boxes ``bounds`` (k, 6) m fill the view, ``margin`` of it left free
    on the tighter side. VTK's ``ResetCamera`` fits a bounding sphere to the view's height, which
    in a narrow view leaves parts outside at the sides; this fits the boxes' projected corners.
    In perspective a zoom changes the corners' projection a little, so it is repeated. ``top``:
    the share of the view's height kept free at the top (a legend sits there), ``bottom`` at the
    bottom (a caption)."""
    if not (top >= 0 and bottom >= 0 and top + bottom < 1):
        raise ValueError(f"top and bottom must be shares of the view's height that leave part of it free, "
                         f"got top={top!r}, bottom={bottom!r}")
    corners = _corners(bounds)
    w, h = renderer.GetSize()
    if not len(corners) or w <= 1 or h <= 1:
        return
    free_h = (1.0 - top - bottom) * h
    middle = bottom * h + 0.5 * free_h             # display y goes up from the view's bottom
    for _ in range(iterations):
        px = _project(renderer, corners)
        lo, hi = px.min(axis=0), px.max(axis=0)
        centre = 0.5 * (lo + hi)
        pan(renderer, centre[0], centre[1], 0.5 * w, middle)
        extent = np.maximum(hi - lo, 1e-9)
        zoom_at(renderer, 0.5 * w, middle, float(min((1 - 2 * margin) * w / extent[0],
                                                             (1 - 2 * margin) * free_h / extent[1])))


def _corners(bounds: np.ndarray) -> np.ndarray:
    """The corners (8 k, 3) of the boxes ``bounds`` (k, 6)."""
    b = np.atleast_2d(np.asarray(bounds, float))
    return np.array([[bb[i], bb[2 + j], bb[4 + k]] for bb in b for i in (0, 1) for j in (0, 1) for k in (0, 1)])


def all_in_view(renderer, bounds: np.ndarray) -> bool:
    """Whether every corner of the boxes ``bounds`` (k, 6) m projects into the view."""
    corners = _corners(bounds)
    w, h = renderer.GetSize()
    if not len(corners):
        return True
    px = _project(renderer, corners)
    return bool(np.all(px >= 0) and np.all(px[:, 0] <= w) and np.all(px[:, 1] <= h))


def keep_in_view(renderer, pivot, bounds: np.ndarray, margin: float = 0.02, iterations: int = 4) -> None:
    """Zoom out about ``pivot``'s pixel until every corner of the boxes ``bounds`` (k, 6) m is in
    the view, ``margin`` of it free at each edge; never in. After ``orbit``: the device turns
    about its end-effector (which keeps its pixel: a homothety about a point of its ray) and no
    part of it swings out of the view (a 120 px drag took the Inverse3's base off the left edge).
    For a scene in view when the drag began (``all_in_view``): a view zoomed in stays so.
    In perspective a zoom changes the corners' projection a little, so it is repeated."""
    corners = _corners(bounds)
    w, h = renderer.GetSize()
    if not len(corners) or w <= 1 or h <= 1:
        return
    lo, hi = margin * np.array([w, h]), (1.0 - margin) * np.array([w, h])
    for _ in range(iterations):
        c = world_to_display(renderer, pivot)
        if np.any(c <= lo) or np.any(c >= hi):
            return                       # the pivot itself is out of the free box: no zoom about it helps
        d = _project(renderer, corners) - c
        room = np.where(d > 0, hi - c, c - lo)
        need = float(np.max(np.abs(d) / room))
        if need <= 1.0:
            return
        zoom_at(renderer, c[0], c[1], 1.0 / need)


def shown_bounds(plotter) -> np.ndarray:
    """The bounds (k, 6) m of the plotter's visible mesh actors (not its text or axes)."""
    out = []
    for actor in plotter.renderer.GetActors():
        if actor.GetVisibility() and actor.GetMapper() is not None and actor.GetMapper().GetInput() is not None:
            b = np.asarray(actor.GetBounds(), float)
            if np.all(np.isfinite(b)) and b[1] >= b[0]:
                out.append(b)
    return np.asarray(out).reshape(-1, 6)
