"""PyVista scene builders shared by the desktop app and the headless ``figure`` command.

Each ``draw_*`` function adds named actors to a plotter (``name=`` replaces an actor rather
than piling up a new one) from plain arrays, so the same code draws in the Qt window and in
an off-screen plotter. Planar mechanisms are drawn in the z = 0 plane.

A redraw is cheap when little changed (a slider step redraws the pose view many times a
second): an actor drawn here keeps its mapper and properties and gets only new geometry, or
nothing at all when the numbers it is made from are unchanged (``_show``); spheres, discs
and arrows are placed copies of unit meshes made once.

Forces are drawn at the end-effector with a fixed scale per device (``force_scale``, metres
per newton), so glyphs keep their size while the pose moves and a change of a gear ratio
shows as a change of size.
"""
from __future__ import annotations

import functools

import numpy as np
import pyvista as pv

from metrics import wrenches
from metrics.quantities import QUANTITIES

from .display_units import display_unit

#: Colours: links grey, polytope blue, isotropic sphere green, force ellipsoid orange,
#: velocity ellipsoid purple, reference arrows per actuator, desired red / clamped teal.
COLOURS = {
    "links": "#4d4d4d", "joints": "#202020", "polytope": "#4a90d9", "polytope_edges": "#1f4e80",
    "sphere": "#2ca02c", "force_ellipsoid": "#ff7f0e", "velocity_ellipsoid": "#9467bd",
    "desired": "#d62728", "clamped": "#17becf",
}
#: Joint balls and link tubes, as fractions of the drawn links' extent (``draw_links``).
BALL_FRACTION, TUBE_FRACTION = 0.025, 0.012
#: Per actuator: none of the glyphs' colours above (the legend tells each colour from the others).
ACTUATOR_COLOURS = ("#e7298a", "#a65628", "#808000", "#000080", "#e6ab02", "#f781bf")
GLYPH_ACTORS = {
    "links": ("links", "joints"),
    "polytope": ("polytope", "polytope_edges"),
    "sphere": ("sphere",),
    "force_ellipsoid": ("force_ellipsoid",),
    "velocity_ellipsoid": ("velocity_ellipsoid",),
    "reference_forces": tuple(f"reference_force_{u}" for u in range(6)),
    "desired_force": ("desired_force", "clamped_force"),
}


def to_3d(points: np.ndarray) -> np.ndarray:
    """Rows of 2 or 3 coordinates as rows of 3 (z = 0 for planar mechanisms), shape (N, 3)."""
    pts = np.atleast_2d(np.asarray(points, float))
    if pts.shape[-1] == 3:
        return pts
    out = np.zeros(pts.shape[:-1] + (3,))
    out[..., : pts.shape[-1]] = pts
    return out


def force_scale(mechanism) -> float:
    """Metres per newton for drawing forces: ``0.05 L / F`` with L the device's size.

    ``F`` is a typical force: ``t_max / L`` for joint torques (N m), ``t_max / 2`` for prismatic
    legs (N; a Stewart platform's isotropic force is of that order). A force ``F`` is then
    drawn 5 % of L long... times a factor that keeps the usual 2-10 N forces of a desktop
    device at a few centimetres.
    """
    size = device_size(mechanism)
    t_max = float(np.max(mechanism.torque_limits()))
    prismatic = "m" in tuple(getattr(mechanism, "joint_units", ()))
    return 0.05 * size / (0.5 * t_max if prismatic else t_max / size)


def velocity_scale(mechanism) -> float:
    """Metres per (m/s) for drawing the velocity ellipsoid of unit joint rates.

    Revolute joints at 1 rad/s move the end-effector at about the links' length per second:
    drawn 1:4. Prismatic legs at 1 m/s move it at about 1 m/s: drawn a quarter of the device.
    """
    if "m" in tuple(getattr(mechanism, "joint_units", ())):
        return 0.25 * device_size(mechanism)
    return 0.25


def device_size(mechanism) -> float:
    """A characteristic length (m): the longest reach of the links, or the drawn extent."""
    p = mechanism.params
    if hasattr(p, "proximal_length"):
        return p.proximal_length + p.distal_length
    if hasattr(p, "proximal"):
        return p.proximal + p.distal
    # Pen mechanisms: the extent of the drawing at the home pose.
    home = np.asarray(mechanism.home_pose(), float)
    q, _ = mechanism.inverse(home)
    pts = to_3d(mechanism.link_points(q))
    return float(np.max(np.ptp(pts, axis=0)))


def actor_named(plotter, name: str):
    """``plotter.actors.get(name)``, without rebuilding pyvista's collection of every actor.

    ``plotter.actors`` makes a dict of the renderer's props on each call (about 0.2 ms with a
    pose's dozen actors, and a pose looks a dozen names up per slider step). The dict is kept
    while the renderer's prop collection is unmodified (VTK stamps every addition and
    removal), so it is rebuilt only after an actor came or went.
    """
    stamp = plotter.renderer.GetViewProps().GetMTime()
    kept = plotter.__dict__.get("_isoforce_actors")
    if kept is None or kept[0] != stamp:
        kept = plotter.__dict__["_isoforce_actors"] = (stamp, plotter.actors)
    return kept[1].get(name)


def _remove(plotter, names) -> None:
    """Remove the actors ``names`` that are there (each removal by name searches every actor)."""
    for name in names:
        if actor_named(plotter, name) is not None:
            plotter.remove_actor(name, reset_camera=False, render=False)


def hide_glyph(plotter, glyph: str) -> None:
    """Remove every actor of ``glyph`` from the plotter."""
    _remove(plotter, GLYPH_ACTORS[glyph])


def _key(*values) -> bytes:
    """The numbers a mesh is made from, as one comparable value."""
    return b"|".join(np.ascontiguousarray(v, dtype=float).tobytes() for v in values)


def _show(plotter, name: str, make, inputs: bytes | None, *, placed=None, **look) -> None:
    """Draw the mesh ``make()`` as actor ``name`` with ``add_mesh`` options ``look``.

    ``add_mesh`` makes a new actor, mapper and property (milliseconds each, a dozen actors
    per pose). An actor made here with the same ``look`` is kept: with the same ``inputs``
    nothing is done, else only its geometry is replaced (``inputs=None``: always replaced).
    ``placed = (kind, detail, points)``: the mesh is a placed copy of that unit mesh
    (``_placed``); an actor showing one of the same kind and detail gets ``points()`` alone
    (its cells and normals are the unit mesh's already), not a copy of a whole new mesh.
    """
    actor = actor_named(plotter, name)
    tag = getattr(actor, "_isoforce_tag", None)
    unit = tuple(placed[:2]) if placed is not None else None
    if tag is not None and tag[0] == look:
        if inputs is None or tag[1] != inputs:
            if unit is not None and tag[2] == unit:
                actor.mapper.dataset.points = np.asarray(placed[2](), float)
            else:
                actor.mapper.dataset.copy_from(make())
            actor._isoforce_tag = (look, inputs, unit)
        return
    actor = plotter.add_mesh(make(), name=name, reset_camera=False, render=False, **look)
    actor._isoforce_tag = (look, inputs, unit)


@functools.lru_cache(maxsize=None)
def _unit_mesh(kind: str, detail: float) -> pv.PolyData:
    """Unit meshes placed by copies: sphere (resolution), circle (resolution), arrow along x (shaft)."""
    if kind == "sphere":
        return pv.Sphere(radius=1.0, theta_resolution=int(detail), phi_resolution=int(detail))
    if kind == "circle":
        return pv.Circle(radius=1.0, resolution=int(detail))
    return pv.Arrow(start=(0.0, 0.0, 0.0), direction=(1.0, 0.0, 0.0), scale=1.0, tip_length=0.2,
                    tip_radius=0.06, shaft_radius=detail)


def _placed(kind: str, detail: float, points) -> pv.PolyData:
    """A copy of a unit mesh (never sharing its arrays) with new points (the normals kept)."""
    mesh = _unit_mesh(kind, detail).copy(deep=True)
    mesh.points = np.asarray(points, float)
    return mesh


def _balls(points: np.ndarray, radius: float) -> pv.PolyData:
    """A sphere of ``radius`` (pv.Sphere's default 30 x 30) at each of ``points`` (k, 3)."""
    unit = _unit_mesh("sphere", 30)
    k, n = len(points), unit.n_points
    tri = unit.faces.reshape(-1, 4)             # all triangles: [3, a, b, c]
    faces = np.tile(tri, (k, 1))
    faces[:, 1:] += np.repeat(np.arange(k) * n, len(tri))[:, None]
    pts = (points[:, None, :] + radius * unit.points[None]).reshape(-1, 3)
    return pv.PolyData(pts, faces=faces.ravel())


def draw_links(plotter, link_points: np.ndarray) -> None:
    """The mechanism as a tube polyline through ``link_points`` (k, 2|3) with joint balls."""
    pts = to_3d(link_points)
    size = float(np.max(np.ptp(pts, axis=0))) or 1.0
    key = _key(pts)
    # The tube filter's normals, Phong-interpolated: what ``smooth_shading=True`` draws.
    _show(plotter, "links", lambda: pv.lines_from_points(pts).tube(radius=TUBE_FRACTION * size), key,
          color=COLOURS["links"], interpolation="phong")
    _show(plotter, "joints", lambda: _balls(pts, BALL_FRACTION * size), key, color=COLOURS["joints"])


def polytope_mesh(centre: np.ndarray, vertices: np.ndarray, faces, scale: float) -> pv.PolyData:
    """The force polytope as a surface at ``centre`` (m); ``vertices`` (2^n, m) in N."""
    pts = to_3d(centre)[0] + scale * to_3d(vertices)
    cells = np.concatenate([[len(f), *f] for f in faces])
    return pv.PolyData(pts, faces=cells)


def draw_polytope(plotter, centre, vertices, faces, scale: float) -> None:
    mesh = polytope_mesh(centre, vertices, faces, scale)
    key = _key(mesh.points, np.concatenate([[len(f), *f] for f in faces]))
    _show(plotter, "polytope", lambda: mesh, key, color=COLOURS["polytope"], opacity=0.25)
    _show(plotter, "polytope_edges", lambda: polytope_edges(mesh.points, faces), key,
          color=COLOURS["polytope_edges"], line_width=2)


def polytope_edges(points: np.ndarray, faces) -> pv.PolyData:
    """The polytope's edges as lines: each face's sides, an edge shared by two faces once.

    What ``extract_all_edges`` gives, from the face lists directly (VTK's filter took ~3 ms
    a slider step for a dozen faces). ``points`` (k, 3); ``faces`` lists of vertex indices.
    """
    sides = np.concatenate([np.column_stack([f, np.roll(f, -1)]) for f in faces]).astype(np.int64)
    sides = np.unique(np.sort(sides, axis=1), axis=0)
    lines = np.column_stack([np.full(len(sides), 2), sides]).ravel()
    return pv.PolyData(np.asarray(points, float), lines=lines)


def draw_sphere(plotter, centre, radius: float, scale: float, planar: bool) -> None:
    """The inscribed isotropic ball: a sphere, or a disc outline for planar mechanisms."""
    c = to_3d(centre)[0]
    r = radius * scale
    key = _key(c, r)
    kind, detail = ("circle", 96) if planar else ("sphere", 48)

    def points():
        return c + r * _unit_mesh(kind, detail).points

    if planar:
        _show(plotter, "sphere", lambda: _placed(kind, detail, points()), key, placed=(kind, detail, points),
              color=COLOURS["sphere"], opacity=0.35)
    else:
        # The unit sphere's own normals, Phong-interpolated: what ``smooth_shading=True`` draws.
        _show(plotter, "sphere", lambda: _placed(kind, detail, points()), key, placed=(kind, detail, points),
              color=COLOURS["sphere"], opacity=0.3, interpolation="phong")


def ellipsoid_mesh(centre, radii: np.ndarray, axes: np.ndarray, scale: float) -> pv.PolyData:
    """An ellipsoid with semi-axes ``radii`` (m,) along the columns of ``axes`` (m, m)."""
    radii = np.asarray(radii, float)
    axes = np.asarray(axes, float)
    m = radii.size
    base = _unit_mesh("circle", 96) if m == 2 else _unit_mesh("sphere", 48)
    transform = np.eye(4)
    transform[:m, :m] = axes * (radii * scale)
    transform[:3, 3] = to_3d(centre)[0]
    return base.transform(transform, inplace=False)


def draw_ellipsoid(plotter, name: str, centre, radii, axes, scale: float) -> None:
    if not np.all(np.isfinite(radii)):
        hide_glyph(plotter, name)
        return
    # ``transform`` carries the unit sphere's normals along (Phong: as ``smooth_shading=True``).
    _show(plotter, name, lambda: ellipsoid_mesh(centre, radii, axes, scale), _key(centre, radii, axes, scale),
          color=COLOURS[name], opacity=0.3, interpolation="phong")


def _arrow_points(start: np.ndarray, vector: np.ndarray, shaft: float) -> np.ndarray:
    """The unit arrow's points rotated onto ``vector``, scaled by its length, moved to ``start``."""
    length = float(np.linalg.norm(vector))
    d = np.asarray(vector, float) / length
    helper = np.array([0.0, 0.0, 1.0]) if abs(d[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(d, helper)
    u /= np.linalg.norm(u)
    rotation = np.column_stack([d, u, np.cross(d, u)])      # x -> d, a proper rotation
    return start + length * _unit_mesh("arrow", shaft).points @ rotation.T


def _arrow(start: np.ndarray, vector: np.ndarray, shaft: float) -> pv.PolyData | None:
    """``pv.Arrow(start, vector / |vector|, scale=|vector|, ...)``: the unit arrow rotated, scaled, moved."""
    length = float(np.linalg.norm(vector))
    if not np.isfinite(length) or length <= 0:
        return None
    return _placed("arrow", shaft, _arrow_points(start, vector, shaft))


def _draw_arrow(plotter, name: str, start: np.ndarray, vector: np.ndarray, shaft: float, colour: str) -> None:
    length = float(np.linalg.norm(vector))
    if not np.isfinite(length) or length <= 0:
        plotter.remove_actor(name, reset_camera=False, render=False)
    else:
        _show(plotter, name, lambda: _arrow(start, vector, shaft), _key(start, vector, shaft),
              placed=("arrow", shaft, lambda: _arrow_points(start, vector, shaft)), color=colour)


def draw_reference_forces(plotter, centre, reference_forces: np.ndarray, scale: float) -> None:
    """One arrow per actuator: column u of ``J^-T diag(t)`` (m, n) in N."""
    c = to_3d(centre)[0]
    ref = to_3d(np.asarray(reference_forces).T) * scale
    for u in range(6):
        name = f"reference_force_{u}"
        if u < len(ref):
            _draw_arrow(plotter, name, c, ref[u], 0.025, ACTUATOR_COLOURS[u])
        else:
            plotter.remove_actor(name, reset_camera=False, render=False)


def draw_desired_force(plotter, centre, desired, clamped, scale: float) -> None:
    c = to_3d(centre)[0]
    for name, vec, colour in (("desired_force", desired, COLOURS["desired"]),
                              ("clamped_force", clamped, COLOURS["clamped"])):
        _draw_arrow(plotter, name, c, to_3d(vec)[0] * scale, 0.03 if name == "desired_force" else 0.045, colour)


# -- workspace ---------------------------------------------------------------------------
#: The 3D workspace view draws at most this many map points per axis.
WORKSPACE_MAX_POINTS = 160


def workspace_volume(workspace_map, quantity: str, mechanism, *, max_points: int = WORKSPACE_MAX_POINTS,
                     angles: int = 72) -> pv.DataSet:
    """A 3D dataset of the workspace coloured by ``quantity``, infeasible cells removed.

    Inverse3: the (x, z) slice at theta_0 = 0 revolved over the base joint's range (every
    quantity is invariant under the base rotation, which only rotates J's rows). Planar
    mechanisms: the map itself as a flat surface. The slice is subsampled to at most
    ``max_points`` per axis: the 3D view shows the shape, the map view the detail.

    The workspace's edge is cut where feasibility, interpolated linearly between the samples,
    crosses one half (``clip_scalar``), so it is a smooth surface, not the staircase of whole
    cells; the values at infeasible samples next to it are their nearest feasible sample's, so
    the cut cells are coloured by feasible values only.
    """
    values = workspace_map.values[quantity] * display_unit(quantity)[1]     # µm, deg as on the map (display_units)
    feasible = workspace_map.feasible
    grid = workspace_map.grid
    step = [max(1, int(np.ceil(n / max_points))) for n in grid.resolution]
    sl = tuple(slice(None, None, s) for s in step)
    vals = np.where(feasible, values, np.nan)[sl].astype(float)
    ok = np.isfinite(vals)
    every, none = bool(ok.all()), not ok.any()
    vals = _edge_filled(vals)
    coords = [c[::s] for c, s in zip(grid.coordinates(), step)]
    if not (every or none):
        # Only cells with a feasible corner are kept (``clip_scalar`` below): the samples beyond
        # one step outside the feasible ones' box are left out before the grid is made (the
        # same cells, the revolved Inverse3 slice's ~10^6 points fewer by half).
        box = _index_box(ok)
        vals, ok = vals[box], ok[box]
        coords = [c[b] for c, b in zip(coords, box)]
    if len(grid.axes) == 2 and mechanism.task_dim == 3 and hasattr(mechanism.params, "plane_offset"):
        lo, hi = mechanism.params.lower_limits[0], mechanism.params.upper_limits[0]
        theta = np.linspace(lo, hi, angles)
        u = coords[grid.axes.index("x")]
        z = coords[grid.axes.index("z")]
        c = dict(grid.fixed).get("y", mechanism.params.plane_offset)
        # The points of meshgrid(u, z, theta, indexing="ij") in VTK's order (u fastest, theta
        # slowest), written once into one (N, 3) array: StructuredGrid(x, y, z) of the meshgrid
        # made the same points through five full-size temporaries.
        cos, sin = np.cos(theta)[:, None, None], np.sin(theta)[:, None, None]
        pts = np.empty((angles, len(z), len(u), 3))
        pts[..., 0] = u * cos - c * sin
        pts[..., 1] = u * sin + c * cos
        pts[..., 2] = z[:, None]
        mesh = pv.StructuredGrid()
        mesh.SetDimensions(len(u), len(z), angles)
        mesh.points = pts.reshape(-1, 3)
        ordered, inside = (vals, ok) if grid.axes.index("x") == 0 else (vals.T, ok.T)
        data = np.tile(ordered.ravel(order="F"), angles)
        inside = np.tile(inside.ravel(order="F"), angles)
    else:
        a, b = coords[0], coords[1]
        aa, bb = np.meshgrid(a, b, indexing="ij")
        pts = np.zeros(aa.shape + (3,))
        names = mechanism.task_names
        pts[..., names.index(grid.axes[0]) if grid.axes[0] in names else 0] = aa
        pts[..., names.index(grid.axes[1]) if grid.axes[1] in names else 1] = bb
        mesh = pv.StructuredGrid(pts[..., 0][..., None], pts[..., 1][..., None], pts[..., 2][..., None])
        data, inside = vals.ravel(order="F"), ok.ravel(order="F")
    mesh.point_data[quantity] = data
    if none:
        return mesh
    mesh.point_data["feasible"] = inside.astype(float)
    if every:
        return mesh.cast_to_unstructured_grid()
    return mesh.clip_scalar(scalars="feasible", value=0.5, invert=False)


def _index_box(ok: np.ndarray) -> tuple[slice, ...]:
    """Slices of the smallest box holding every True of ``ok`` (2D, not all False), one more each side."""
    box = []
    for axis in range(ok.ndim):
        hit = np.flatnonzero(ok.any(axis=1 - axis))
        box.append(slice(max(int(hit[0]) - 1, 0), int(hit[-1]) + 2))
    return tuple(box)


#: The workspace colour bar's place and labels (three: a narrow view has room for no more).
BAR_LOOK = {"position_x": 0.15, "position_y": 0.03, "width": 0.7, "n_labels": 3, "fmt": "%.3g"}
#: Iso-surfaces drawn of a 3D box map's quantity, at evenly spaced levels between these percentiles.
ISO_LEVELS = 4
ISO_PERCENTILES = (10.0, 90.0)
#: The actors of a 3D box map's scene (``draw_box_workspace``).
BOX_ACTORS = ("workspace", "box_hull", "box_plane", "box_levels")


def box_image(workspace_map, quantity: str) -> pv.ImageData:
    """A 3D box map as ``pyvista.ImageData`` (points at the grid's samples, m).

    Point arrays: ``quantity`` (``nan`` where infeasible or not finite: unbounded points are
    no level of any surface) and ``"feasible"`` (1.0 / 0.0, whose 0.5 contour is the
    workspace's boundary). The grid's axes are the task's x, y, z in some order; the image's
    axes are x, y, z, so the arrays are transposed to that order.
    """
    grid = workspace_map.grid
    order = [grid.axes.index(a) for a in ("x", "y", "z")]
    factor = display_unit(quantity)[1]           # µm, deg as on the map (display_units)
    values = np.where(workspace_map.feasible, workspace_map.values[quantity] * factor, np.nan).astype(float)
    values[~np.isfinite(values)] = np.nan
    feasible = np.transpose(workspace_map.feasible, order).astype(float)
    image = pv.ImageData(dimensions=tuple(grid.resolution[k] for k in order),
                         spacing=tuple(grid.spacing()[k] for k in order),
                         origin=tuple(grid.lower[k] for k in order))
    image.point_data[quantity] = np.transpose(values, order).ravel(order="F")
    image.point_data["feasible"] = feasible.ravel(order="F")
    return image


def iso_levels(values: np.ndarray, quantity: str, count: int = ISO_LEVELS) -> np.ndarray:
    """Levels of the iso-surfaces of a box map: ``count`` evenly spaced between the feasible values'
    10th and 90th percentiles (geometric spacing for the condition number, which spans decades).

    Returns an empty array when fewer than two distinct finite values exist.
    """
    finite = np.asarray(values, float)
    finite = finite[np.isfinite(finite)]
    if finite.size < 2 or finite.min() == finite.max():
        return np.empty(0)
    lo, hi = np.percentile(finite, ISO_PERCENTILES)
    if not hi > lo:
        return np.empty(0)
    if quantity == "condition_number" and lo > 0:
        return np.geomspace(lo, hi, count)
    return np.linspace(lo, hi, count)


def box_scene_parts(workspace_map, quantity: str, slice_axis: str, slice_value: float, *,
                    cache: dict | None = None) -> dict:
    """The meshes of a 3D box map's scene: boundary, iso-surfaces, the plane shown in the map view.

    Returns a dict with ``image`` (``box_image``), ``hull`` (the workspace boundary, the 0.5
    contour of feasibility), ``surfaces`` (iso-surfaces of ``quantity``, point array
    ``quantity``; None for classes), ``levels`` (their values), ``clim`` (the volume's colour
    range), ``plane`` (the grid plane along ``slice_axis`` nearest ``slice_value``, m,
    coloured by ``quantity``) and ``at`` (that plane's position, m).

    ``cache`` (a dict kept by the caller) holds the volume's meshes between calls for the same
    map and quantity: moving the plane then only cuts a new plane (about a millisecond).
    """
    if cache is not None and cache.get("map") is workspace_map and cache.get("quantity") == quantity:
        volume = cache["volume"]
    else:
        volume = _box_volume_parts(workspace_map, quantity)
        if cache is not None:
            cache.clear()
            cache.update(map=workspace_map, quantity=quantity, volume=volume)
    image = volume["image"]
    grid = workspace_map.grid
    k = grid.axes.index(slice_axis)
    coords = grid.coordinates()[k]
    at = float(coords[int(np.argmin(np.abs(coords - slice_value)))])
    origin = list(image.center)
    origin["xyz".index(slice_axis)] = at
    plane = image.slice(normal=slice_axis, origin=origin)
    return {**volume, "plane": plane, "at": at}


#: Taubin smoothing of a box map's contours: iterations and pass band (vtkWindowedSincPolyDataFilter).
#: The boundary is the 0.5 contour of a 0/1 field, a terrace of voxel steps; a few tens of
#: low-pass iterations take the steps out (points move well under a grid step) and keep the
#: shape; the scalars are carried along, so each surface still carries its level exactly.
SMOOTH_ITERATIONS, SMOOTH_PASS_BAND = 30, 0.05


def _nearest_filled(values: np.ndarray) -> np.ndarray:
    """``values`` (any shape) with each non-finite entry replaced by its nearest finite one's."""
    ok = np.isfinite(values)
    if not ok.any() or ok.all():
        return values
    from scipy import ndimage  # here: importing scipy.ndimage costs the CLI's start 1 s

    return values[tuple(ndimage.distance_transform_edt(~ok, return_distances=False, return_indices=True))]


#: The 8 neighbours (row, column offsets) of a sample, nearest first, and among equally near
#: ones in the order in which ``scipy.ndimage.distance_transform_edt`` picks its feature.
_NEIGHBOURS = ((0, -1), (-1, 0), (1, 0), (0, 1), (-1, -1), (1, -1), (-1, 1), (1, 1))


def _edge_filled(values: np.ndarray) -> np.ndarray:
    """``_nearest_filled`` where it can be seen in a clipped 2D slice, without scipy.

    Parameters
    ----------
    values : ndarray, shape (n0, n1)
        Samples of a quantity; non-finite ones are outside the workspace.

    Returns
    -------
    ndarray, shape (n0, n1)
        ``values`` with each non-finite sample next to a finite one (one of its 8 neighbours)
        given its nearest finite neighbour's value, ties broken as
        ``scipy.ndimage.distance_transform_edt`` breaks them, so equal to
        ``_nearest_filled(values)`` there; the other non-finite samples are nan.

    Notes
    -----
    ``workspace_volume`` keeps only the cells with a finite corner, clipped where the
    interpolated feasibility crosses one half: every corner of those cells is next to a
    finite sample, and no other sample reaches the picture. Importing ``scipy.ndimage``
    for the exact transform costs the ``figure`` command about 0.3 s of CPU.

    Examples
    --------
    >>> _edge_filled(np.array([[1.0, np.nan, np.nan, np.nan], [np.nan, 2.0, np.nan, np.nan]]))
    array([[ 1.,  1.,  2., nan],
           [ 1.,  2.,  2., nan]])
    """
    values = np.asarray(values, float)
    ok = np.isfinite(values)
    if ok.all() or not ok.any():
        return values
    n0, n1 = values.shape
    padded = np.full((n0 + 2, n1 + 2), np.nan)
    padded[1:-1, 1:-1] = np.where(ok, values, np.nan)
    out = padded[1:-1, 1:-1].copy()
    # The least preferred neighbour first: each later one overwrites it where it is finite.
    for di, dj in reversed(_NEIGHBOURS):
        near = padded[1 + di:1 + di + n0, 1 + dj:1 + dj + n1]
        take = ~ok & np.isfinite(near)
        out[take] = near[take]
    return out


def _iso_surfaces(image, quantity: str, levels: np.ndarray):
    """The iso-surfaces of ``quantity`` at ``levels`` inside the workspace, smoothed.

    Contoured from the values with each infeasible sample given its nearest feasible one's (a
    contour through a nan sample has nan vertices, and smoothing spreads them to every vertex),
    then cut where the interpolated feasibility crosses one half (the smooth boundary)."""
    dims = tuple(image.dimensions)
    work = pv.ImageData(dimensions=dims, spacing=image.spacing, origin=image.origin)
    values = np.asarray(image.point_data[quantity], float).reshape(dims, order="F")
    work.point_data[quantity] = _nearest_filled(values).ravel(order="F")
    work.point_data["feasible"] = image.point_data["feasible"]
    surfaces = work.contour(levels, scalars=quantity, method="contour")     # it carries "feasible" along
    if surfaces.n_points:
        surfaces = surfaces.clip_scalar(scalars="feasible", value=0.5, invert=False)
    if surfaces.n_points:
        # The filter writes its scalars in float32; each point lies on one level by construction,
        # so it gets that level's value exactly (the nearest level: float32 rounding is far
        # smaller than the levels' spacing).
        near = np.abs(np.asarray(surfaces.point_data[quantity], float)[:, None] - levels[None, :]).argmin(axis=1)
        surfaces.point_data[quantity] = np.asarray(levels, float)[near]
    return _smoothed(surfaces)


def _smoothed(mesh):
    """``mesh`` smoothed by Taubin's low-pass filter (no shrinking), or as it is when empty."""
    if mesh is None or mesh.n_points == 0:
        return mesh
    # Normalised coordinates: the filter is unstable (nan points) on a scene of 0.1 m across.
    return mesh.smooth_taubin(n_iter=SMOOTH_ITERATIONS, pass_band=SMOOTH_PASS_BAND, normalize_coordinates=True)


def _box_volume_parts(workspace_map, quantity: str) -> dict:
    """What ``box_scene_parts`` draws that does not depend on the plane: image, boundary, surfaces."""
    node = QUANTITIES[quantity]
    image = box_image(workspace_map, quantity)
    values = image.point_data[quantity]
    finite = values[np.isfinite(values)]
    hull = (_smoothed(image.contour([0.5], scalars="feasible", method="flying_edges"))
            if np.any(image.point_data["feasible"]) else None)
    levels = np.empty(0) if node.categorical else iso_levels(values, quantity)
    surfaces = _iso_surfaces(image, quantity, levels) if levels.size else None
    clim = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    return {"image": image, "hull": hull, "surfaces": surfaces, "levels": levels, "clim": clim}


def draw_box_workspace(plotter, workspace_map, quantity: str, mechanism, slice_axis: str, slice_value: float, *,
                       cache: dict | None = None) -> None:
    """A 3D box map: the workspace boundary, iso-surfaces of ``quantity`` and the plane the map view shows.

    One colour scale (the volume's) for the plane and the surfaces; the levels are written in
    the corner. Classes (the bottleneck) get no iso-surfaces: the plane shows them. With a
    ``cache`` (see ``box_scene_parts``) a moved plane replaces the plane's geometry and the
    caption only.
    """
    node = QUANTITIES[quantity]
    same_volume = cache is not None and cache.get("map") is workspace_map and cache.get("quantity") == quantity
    parts = box_scene_parts(workspace_map, quantity, slice_axis, slice_value, cache=cache)
    unit = f" {display_unit(quantity)[0]}" if node.unit else ""
    plane = plotter.actors.get("box_plane")
    if same_volume and plane is not None:
        plane.mapper.dataset.copy_from(parts["plane"])      # only the plane moved: new geometry, same look
    else:
        _draw_box_volume(plotter, parts, quantity)
    # Short lines: the caption shares the view's top edge with its "Reset view" button.
    if parts["levels"].size:
        levels = ", ".join(f"{v:.3g}" for v in parts["levels"])
        text = f"iso-surfaces of {node.label.lower()}\nat {levels}{unit}"
    elif node.categorical:
        text = f"{node.label}: classes have\nno iso-surfaces; the plane shows them"
    else:
        text = f"{node.label}: too few distinct\nvalues for iso-surfaces"
    text += f"\nplane {slice_axis} = {parts['at'] * 1e3:.1f} mm\ngrey: workspace boundary"
    corner = actor_named(plotter, "box_levels")
    if corner is not None and hasattr(corner, "set_text"):
        corner.set_text("upper_left", text)
    else:
        plotter.add_text(text, position="upper_left", font_size=9, color="black", name="box_levels", render=False)


def _draw_box_volume(plotter, parts: dict, quantity: str) -> None:
    """The boundary, iso-surface and plane actors of ``draw_box_workspace``, made anew."""
    node = QUANTITIES[quantity]
    title = node.label + (f" ({display_unit(quantity)[0]})" if node.unit else "")
    log = quantity == "condition_number" and parts["clim"][0] > 0
    look = dict(cmap="tab10" if node.categorical else "viridis", clim=parts["clim"], log_scale=log,
                reset_camera=False, render=False)
    if plotter.scalar_bars:
        plotter.remove_scalar_bar()
    if parts["hull"] is not None and parts["hull"].n_points:
        plotter.add_mesh(parts["hull"], color="#9a9a9a", opacity=0.12, name="box_hull", reset_camera=False,
                         render=False)
    else:
        plotter.remove_actor("box_hull", reset_camera=False, render=False)
    surfaces = parts["surfaces"]
    if surfaces is not None and surfaces.n_points:
        plotter.add_mesh(surfaces, scalars=quantity, opacity=0.5, smooth_shading=True, name="workspace",
                         show_scalar_bar=False, **look)
    else:
        plotter.remove_actor("workspace", reset_camera=False, render=False)
    plotter.add_mesh(parts["plane"], scalars=quantity, nan_opacity=0.0, name="box_plane",
                     scalar_bar_args={"title": title, **BAR_LOOK},
                     **look)


#: The inscribed sphere is drawn at least this many times the end-effector's joint ball's radius.
SPHERE_OVER_BALL = 1.5


def _round_up_125(value: float) -> float:
    """The smallest 1, 2 or 5 x 10^k at or above ``value`` (> 0)."""
    k = np.floor(np.log10(value))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * 10.0 ** k >= value * (1 - 1e-12):
            return float(m * 10.0 ** k)
    return float(10.0 ** (k + 1))


def pose_scale(mechanism, report) -> float:
    """Metres per newton for a pose's glyphs: ``force_scale``, or larger where the inscribed sphere
    would be drawn smaller than ``SPHERE_OVER_BALL`` joint balls (a high gear ratio's small
    isotropic force next to a big device), then rounded up to 1, 2 or 5 x 10^k m/N so that it
    changes in few steps while a slider moves. The caption prints the scale in use.
    """
    scale = force_scale(mechanism)
    iso = float(getattr(report, "isotropic_force", np.nan))
    if not (report.reachable and np.isfinite(iso) and iso > 0):
        return scale
    pts = to_3d(mechanism.link_points(report.joints))
    ball = BALL_FRACTION * (float(np.max(np.ptp(pts, axis=0))) or 1.0)
    needed = SPHERE_OVER_BALL * ball / iso
    return scale if scale >= needed else _round_up_125(needed)


#: Legend rows per glyph: (label, colour).
LEGEND = {
    "links": (("links", COLOURS["links"]),),
    "polytope": (("force polytope", COLOURS["polytope"]),),
    "sphere": (("inscribed sphere", COLOURS["sphere"]),),
    "force_ellipsoid": (("force ellipsoid", COLOURS["force_ellipsoid"]),),
    "velocity_ellipsoid": (("velocity ellipsoid", COLOURS["velocity_ellipsoid"]),),
    "reference_forces": tuple((f"actuator {u + 1}, full torque", c) for u, c in enumerate(ACTUATOR_COLOURS)),
    "desired_force": (("desired force", COLOURS["desired"]), ("clamped force", COLOURS["clamped"])),
}


def legend_rows(plotter, n_actuators: int) -> list[tuple[str, str]]:
    """(label, colour) of every glyph drawn in ``plotter`` now (its actors), in menu order."""
    rows = []
    for glyph, names in GLYPH_ACTORS.items():
        if glyph == "reference_forces":
            rows += [LEGEND[glyph][u] for u in range(min(n_actuators, 6)) if actor_named(plotter, names[u]) is not None]
        elif any(actor_named(plotter, n) is not None for n in names):
            rows += list(LEGEND[glyph])
    return rows


def force_values_text(desired, clamped) -> str:
    """The desired and clamped forces with their components and magnitudes in N."""
    def row(v):
        v = np.asarray(v, float)
        return "(" + ", ".join(f"{c:.3g}" for c in v) + f") N, |F| = {np.linalg.norm(v):.3g} N"
    return f"desired {row(desired)}; clamped {row(clamped)}"


def draw_pose_scene(plotter, mechanism, report, glyphs, desired_force, scale: float) -> None:
    """Draw every visible glyph of a ``metrics.pose.PoseReport`` and remove the hidden ones.

    Glyphs whose data the report does not hold (not computed because hidden, or the pose
    is unreachable) are removed too.
    """
    planar = mechanism.task_dim == 2
    ok = report.reachable
    # Force glyphs live in a 2D or 3D force space. A device with orientation freedoms holds
    # wrenches: it shows the forces it holds at zero moment (the report's vertices, faces,
    # isotropic force and ellipsoids are those of that 3D set), at its task point.
    wrench = wrenches.has_orientation(mechanism)
    forces = mechanism.task_dim <= 3 or wrench
    rows = list(wrenches.force_rows(mechanism)) if wrench else slice(None)
    x = report.x[rows]
    desired_force = np.asarray(desired_force, float)[rows]
    shown = set()
    if "links" in glyphs and ok:
        draw_links(plotter, mechanism.link_points(report.joints))
        shown.add("links")
    drawable = report.faces is not None and report.vertices is not None and np.all(np.isfinite(report.vertices))
    if "polytope" in glyphs and ok and forces and drawable:
        draw_polytope(plotter, x, report.vertices, report.faces, scale)
        shown.add("polytope")
    if "sphere" in glyphs and ok and forces and np.isfinite(report.isotropic_force):
        draw_sphere(plotter, x, report.isotropic_force, scale, planar)
        shown.add("sphere")
    for name in ("force_ellipsoid", "velocity_ellipsoid"):
        ell = getattr(report, name)
        if name in glyphs and ok and forces and ell is not None and np.all(np.isfinite(ell.radii)):
            # Velocities (m/s for unit joint rates) are drawn 1:4 so they sit beside the forces.
            draw_ellipsoid(plotter, name, x, ell.radii, ell.axes,
                           scale if name == "force_ellipsoid" else velocity_scale(mechanism))
            shown.add(name)
    # A wrench device's actuators each push with a force and a moment: no force arrows alone.
    if "reference_forces" in glyphs and ok and forces and not wrench and report.reference_forces is not None:
        draw_reference_forces(plotter, x, report.reference_forces, scale)
        shown.add("reference_forces")
    if "desired_force" in glyphs and ok and forces and np.any(np.asarray(desired_force) != 0):
        draw_desired_force(plotter, x, desired_force, report.clamp(np.asarray(desired_force, float)), scale)
        shown.add("desired_force")
    for glyph in GLYPH_ACTORS:
        if glyph not in shown:
            hide_glyph(plotter, glyph)


def frame_pose_camera(plotter, mechanism) -> None:
    """A camera that shows the whole device: top view for planar ones, oblique for spatial."""
    if mechanism.task_dim == 2:
        plotter.view_xy()
    else:
        plotter.view_isometric()
        plotter.camera.azimuth = plotter.camera.azimuth - 60
    plotter.reset_camera()


def pose_caption(report, scale: float, velocity_scale: float = 0.25) -> str:
    """The numbers under the pose view: forces, bottleneck, conditioning, the drawing scale."""
    if not report.reachable:
        return "pose unreachable"
    where = "" if report.feasible else " [outside the joint limits]"
    scaling = getattr(report, "condition_number_scaling", None)
    if scaling is not None:
        return (f"at zero moment: isotropic force {report.isotropic_force:.3g} N, anisotropic "
                f"{report.anisotropic_force:.3g} N; at zero force: isotropic moment "
                f"{report.isotropic_moment:.3g} N m, anisotropic {report.anisotropic_moment:.3g} N m{where}\n"
                f"condition {report.condition_number:.3g} (moments scaled by L = {scaling['length_m'] * 1e3:.3g} mm); "
                f"forces drawn at 10 N = {10 * scale * 1e3:.0f} mm; linear velocity ellipsoid at 1 m/s = "
                f"{velocity_scale * 1e3:.0f} mm")
    return (f"isotropic force {report.isotropic_force:.3g} N (bottleneck {report.bottleneck_name}), "
            f"anisotropic {report.anisotropic_force:.3g} N, condition {report.condition_number:.3g}{where}\n"
            f"forces drawn at 10 N = {10 * scale * 1e3:.0f} mm; velocity ellipsoid at 1 m/s = "
            f"{velocity_scale * 1e3:.0f} mm")


WORKSPACE_MODES = ("cut plane", "iso-surfaces")


def draw_workspace(plotter, workspace_map, quantity: str, mechanism, mode: str, *, interactive: bool) -> None:
    """Draw the workspace volume of ``quantity`` (shared by the app and ``isoforce figure``).

    A 3D box map is drawn by ``draw_box_workspace`` (iso-surfaces and its middle plane along z).
    """
    plotter.clear_plane_widgets() if interactive else None
    for name in BOX_ACTORS[1:]:
        plotter.remove_actor(name, reset_camera=False, render=False)
    if len(workspace_map.grid.axes) == 3:
        grid = workspace_map.grid
        k = grid.axes.index("z")
        draw_box_workspace(plotter, workspace_map, quantity, mechanism, "z", 0.5 * (grid.lower[k] + grid.upper[k]))
        return
    plotter.remove_actor("workspace", reset_camera=False, render=False)
    plotter.remove_scalar_bar() if plotter.scalar_bars else None
    node = QUANTITIES[quantity]
    volume = workspace_volume(workspace_map, quantity, mechanism)
    title = node.label + (f" ({display_unit(quantity)[0]})" if node.unit else "")
    bar = {"title": title, **BAR_LOOK}
    args = dict(scalars=quantity, cmap="tab10" if node.categorical else "viridis",
                log_scale=quantity == "condition_number", scalar_bar_args=bar,
                name="workspace", reset_camera=False, render=False)
    if volume.n_cells == 0:
        return
    if mode == "iso-surfaces" and mechanism.task_dim == 3 and not node.categorical:
        lo, hi = np.nanpercentile(volume.point_data[quantity], [10, 90])
        surfaces = volume.cell_data_to_point_data().contour(isosurfaces=np.linspace(lo, hi, 4), scalars=quantity)
        if surfaces.n_points:
            plotter.add_mesh(surfaces, opacity=0.55, smooth_shading=True, **args)
        else:
            plotter.add_mesh(volume.outline(), color="black", name="workspace", render=False)
    elif mechanism.task_dim == 3:
        if interactive:
            plotter.add_mesh_clip_plane(volume, normal="-y", origin=(0.0, 0.0, 0.0), **args)
        else:
            # Only the surface is seen: extracted once here (add_mesh would redo it on every
            # render of the volume's ~10^5 cells; the same picture, 0.4 s less per figure).
            plotter.add_mesh(volume.clip(normal="-y", origin=(0.0, 0.0, 0.0)).extract_surface(algorithm=None), **args)
    else:
        plotter.add_mesh(volume, **args)


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


def spread_labels(candidates, boxes, view, *, gap: float = ISO_LABEL_GAP) -> np.ndarray:
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
    for i in np.argsort(spread, kind="stable"):
        box = _label_boxes(px[i], boxes[i])
        inside = _inside(box, view, gap)
        clear = _separation(box, placed)
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


def display_points(renderer, points: np.ndarray) -> np.ndarray:
    """Display pixels of world points through the renderer's active camera.

    VTK's world-to-display transform for many points at once (``vtkCoordinate`` does one at a
    time, and ``GetComputedDisplayValue`` rounds its result down to whole pixels).

    Parameters
    ----------
    renderer : vtkRenderer
        Its size, origin in the window and active camera are used.
    points : array_like, shape (k, 3)
        World points, m.

    Returns
    -------
    ndarray, shape (k, 2)
        Pixels, x right and y up from the window's bottom-left corner; ``nan`` for a point
        behind the camera.
    """
    pts = np.asarray(points, float).reshape(-1, 3)
    w, h = renderer.GetSize()
    ox, oy = renderer.GetOrigin()
    m = renderer.GetActiveCamera().GetCompositeProjectionTransformMatrix(renderer.GetTiledAspectRatio(), -1, 1)
    mat = np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])
    hom = np.column_stack([pts, np.ones(len(pts))]) @ mat.T
    with np.errstate(divide="ignore", invalid="ignore"):
        ndc = np.where(hom[:, 3:4] > 0, hom[:, :2] / hom[:, 3:4], np.nan)
    return np.column_stack([ox + 0.5 * (ndc[:, 0] + 1) * w, oy + 0.5 * (ndc[:, 1] + 1) * h])


def iso_label_boxes(text_property, texts, margin: float, dpi: int) -> np.ndarray:
    """Each label's box as drawn, relative to its anchor.

    The text's extent as VTK's label mapper measures it (``vtkTextRenderer.GetBoundingBox``,
    as ``vtkFreeTypeLabelRenderStrategy.ComputeLabelBounds`` does, justification and line
    offset included), grown by the ``margin`` of the box ``vtkLabelPlacementMapper`` draws
    round it.

    Parameters
    ----------
    text_property : vtkTextProperty
        The labels' text property (font, size, justification).
    texts : sequence of str, length k
        The labels.
    margin : float
        The mapper's margin, px.
    dpi : int
        The render window's dpi (font sizes are points).

    Returns
    -------
    ndarray, shape (k, 4)
        (left, right, bottom, top) px from the anchor's display pixel.
    """
    from vtkmodules.vtkRenderingCore import vtkTextRenderer

    renderer = vtkTextRenderer.GetInstance()
    out = []
    for text in texts:
        bbox = [0, 0, 0, 0]
        renderer.GetBoundingBox(text_property, text, bbox, dpi)
        offset = text_property.GetLineOffset()
        out.append([bbox[0] - margin, bbox[1] + margin, bbox[2] - offset - margin, bbox[3] - offset + margin])
    return np.asarray(out, float).reshape(-1, 4)


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

    def __call__(self, renderer, _event=None) -> None:
        if not renderer.HasViewProp(self.actor):        # removed by other means than workspace_annotations
            return
        window = renderer.GetVTKWindow()
        dpi = int(window.GetDPI()) if window is not None else 72
        seen = (renderer.GetActiveCamera().GetMTime(), tuple(renderer.GetSize()), tuple(renderer.GetOrigin()), dpi)
        if seen == self.seen or min(renderer.GetSize()) <= 1:
            return
        self.seen = seen
        boxes = self._boxes.get(dpi)
        if boxes is None:
            boxes = self._boxes[dpi] = iso_label_boxes(self.text_property, self.texts, self.margin, dpi)
        (w, h), (ox, oy) = renderer.GetSize(), renderer.GetOrigin()
        view = np.array([ox, ox + w, oy, oy + h], float)
        if self.placed:
            # The test ``spread_labels`` places by: each box in the view and clear of the others.
            box = _label_boxes(display_points(renderer, np.asarray(self.data.points, float)), boxes)
            clear = [_separation(box[i:i + 1], np.delete(box, i, axis=0))[0] >= ISO_LABEL_GAP
                     for i in range(len(box))]
            if _inside(box, view, ISO_LABEL_GAP).all() and all(clear):
                return
        pick = spread_labels([display_points(renderer, c) for c in self.candidates], boxes, view)
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


def workspace_annotations(plotter, workspace_map, quantity: str, mechanism) -> None:
    """Axes in mm around the workspace scene and a label with its value on each iso-surface.

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
    candidates, levels = iso_label_candidates(_drawn_dataset(surfaces), quantity)
    if len(levels):
        unit = f" {display_unit(quantity)[0]}" if node.unit else ""
        texts = [f"{v:.3g}{unit}" for v in levels]
        same = before is not None and before[1] is surfaces and before[0].texts == texts
        at = np.asarray(before[0].data.points, float) if same else np.array([c[0] for c in candidates], float)
        data = pv.PolyData(at)
        data.point_data["iso_label"] = np.array(texts)
        label = plotter.add_point_labels(data, "iso_label", font_size=ISO_LABEL_FONT_SIZE, text_color="black",
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
        observer = plotter.renderer.AddObserver("StartEvent", placer)
        plotter.__dict__["_isoforce_iso_labels"] = (plotter.renderer, observer, placer, surfaces)
    plotter.remove_bounds_axes()
    shown = [plotter.actors[n] for n in ("workspace", "box_hull", "box_plane") if n in plotter.actors]
    if not shown:
        return
    b = np.array([a.GetBounds() for a in shown], float)
    bounds = np.column_stack([b[:, 0::2].min(axis=0), b[:, 1::2].max(axis=0)]).ravel()
    planar = mechanism.task_dim == 2
    # The scene is in metres; the axes' labels say millimetres (the same box, its numbers x 1000).
    # 2D labels: VTK's 3D label text shrinks with a narrow view until it is not drawn at all.
    plotter.show_bounds(bounds=bounds, axes_ranges=bounds * 1e3, xtitle="x (mm)", ytitle="y (mm)",
                        ztitle="z (mm)", show_zaxis=not planar, show_zlabels=not planar, color="black",
                        font_size=10, location="outer", fmt="%.0f", n_xlabels=3, n_ylabels=3, n_zlabels=3,
                        use_2d=True, render=False)
