"""The pose scene: a device's links and the glyphs of its forces at one pose.

``draw_pose_scene`` draws what a ``metrics.pose.PoseReport`` holds: the links and joints,
the force polytope and its edges, the inscribed (isotropic) sphere, the force, velocity and
inertia ellipsoids, one reference force per actuator and a desired force with its clamped part.
Planar mechanisms are drawn in the z = 0 plane. ``legend_rows`` and ``pose_caption`` say
what is drawn; ``frame_pose_camera`` frames the device.

Closed glyphs (polytope, sphere, ellipsoids) overlap at the end-effector: only the first shown
(``app.logic.glyphs.outlined_glyphs``) is a translucent surface, drawn behind every other glyph,
the others are outlines (their principal sections, ``principal_sections``), and the arrows are
drawn over everything (``DEPTH_LAYERS``), so none is lost inside another and each legend swatch
is the colour its glyph shows on screen (``drawn_colour``).

Forces are drawn at the end-effector with a fixed scale per device (``force_scale``, metres
per newton), so glyphs keep their size while the pose moves and a change of a gear ratio
shows as a change of size (``pose_scale`` enlarges it only where the inscribed sphere would
be drawn too small beside its joint ball or its links). Masses (the inertia ellipsoid)
likewise, ``inertia_scale`` metres per kg.
"""
from __future__ import annotations

import functools

import numpy as np
import pyvista as pv

from app.logic.glyphs import outlined_glyphs
from app.scenes.common import _key, _placed, _remove, _show, _unit_mesh, _unit_points, actor_named, to_3d
from metrics import wrenches

#: Colours: links grey, polytope blue, isotropic sphere green, force ellipsoid orange,
#: velocity ellipsoid purple, inertia ellipsoid dark cyan (teal: a hue between the sphere's green
#: and the polytope's blue, darker than the clamped arrow's cyan), reference arrows per actuator,
#: desired red / clamped cyan (text naming them asks ``colour_name``).
COLOURS = {
    "links": "#4d4d4d", "joints": "#202020", "polytope": "#4a90d9", "polytope_edges": "#1f4e80",
    "sphere": "#2ca02c", "force_ellipsoid": "#ff7f0e", "velocity_ellipsoid": "#9467bd",
    "inertia_ellipsoid": "#008c8c", "desired": "#d62728", "clamped": "#17becf",
}


#: Joint balls and link tubes, as fractions of the drawn links' extent (``draw_links``).
BALL_FRACTION, TUBE_FRACTION = 0.025, 0.012
#: Facets of a joint ball and of the inscribed sphere (``pv.Sphere``'s theta and phi resolution).
#: Shaded smoothly (their exact normals, Phong), a sphere of 16 x 16 is round to the eye; its outline
#: is a polygon of 16 sides whose flats sit r (1 - cos(pi / 16)) = 0.019 r inside the circle, under a
#: pixel for a ball under 50 px across. Each triangle costs a software renderer (llvmpipe) on every
#: frame of a slider step: seven balls of 30 x 30 were 11,760 of the pose view's 16,455.
BALL_RESOLUTION, SPHERE_RESOLUTION = 16, 32
#: Per actuator: none of the glyphs' colours above (the legend tells each colour from the others).
ACTUATOR_COLOURS = ("#e7298a", "#a65628", "#808000", "#000080", "#e6ab02", "#f781bf")
GLYPH_ACTORS = {
    "links": ("links", "joints"),
    "polytope": ("polytope", "polytope_edges"),
    "sphere": ("sphere",),
    "force_ellipsoid": ("force_ellipsoid",),
    "velocity_ellipsoid": ("velocity_ellipsoid",),
    "inertia_ellipsoid": ("inertia_ellipsoid", "inertia_ellipsoid_edge"),
    "reference_forces": tuple(f"reference_force_{u}" for u in range(6)),
    "desired_force": ("desired_force", "clamped_force"),
}


def force_scale(mechanism) -> float:
    """Metres per newton for drawing forces: ``0.05 L / F`` with L the device's size.

    ``F`` is a typical force: ``t_max / L`` for joint torques (N m), ``t_max / 2`` for prismatic
    legs (N; a Stewart platform's isotropic force is of that order). A force ``F`` is then
    drawn 5 % of L long... times a factor that keeps the usual 2-10 N forces of a desktop
    device at a few centimetres.
    """
    size = device_size(mechanism)
    t_max = float(np.max(mechanism.torque_limits()))
    prismatic = "m" in mechanism.joint_units
    return 0.05 * size / (0.5 * t_max if prismatic else t_max / size)


def velocity_scale(mechanism) -> float:
    """Metres per (m/s) for drawing the velocity ellipsoid of unit joint rates.

    Revolute joints at 1 rad/s move the end-effector at about the links' length per second:
    drawn 1:4. Prismatic legs at 1 m/s move it at about 1 m/s: drawn a quarter of the device.
    """
    if "m" in mechanism.joint_units:
        return 0.25 * device_size(mechanism)
    return 0.25


#: Metres per kg of the inertia ellipsoid: 0.1 kg is drawn 25 mm long (``inertia_scale``).
INERTIA_SCALE = 0.25


def inertia_scale(mechanism) -> float:
    """Metres per kg for drawing the inertia ellipsoid (apparent masses): ``INERTIA_SCALE`` for
    every device.

    The presets' hands feel 0.008 to 0.34 kg at their default poses (``isoforce pose --json``'s
    ``apparent_mass_range``) on devices 160 to 320 mm across: at 0.25 m/kg the heaviest axis is
    drawn 7 mm (Haply) to 84 mm (WoodenHaptics) long, beside the joint ball and inside the
    device. One scale for all, neither the device's size nor its masses, so two devices'
    ellipsoids compare by eye and a heavier design (a higher gear ratio's rotors) draws larger.
    """
    return INERTIA_SCALE


def device_size(mechanism) -> float:
    """A characteristic length (m): the longest reach of the links, or the drawn extent.

    Kept per design (a pen mechanism's is its drawing at the home pose: its inverse kinematics,
    2-10 ms, at every slider step of another parameter)."""
    try:
        return _device_size(mechanism)
    except TypeError:                   # a design that cannot be a dict key: not kept
        return _device_size.__wrapped__(mechanism)


@functools.lru_cache(maxsize=16)
def _device_size(mechanism) -> float:
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


_LAST_LINKS: tuple = (None, b"", None)      # (mechanism, joints, their link points): ``_link_points``


def _link_points(mechanism, joints) -> np.ndarray:
    """``mechanism.link_points(joints)``, kept for the last pose asked (``pose_scale`` and
    ``draw_pose_scene`` draw one pose: a Stewart platform's takes its forward kinematics, 3 ms)."""
    global _LAST_LINKS
    key = np.asarray(joints, float).tobytes()
    kept, kept_key, points = _LAST_LINKS
    if kept is not mechanism or kept_key != key:
        points = np.asarray(mechanism.link_points(joints))
        _LAST_LINKS = (mechanism, key, points)
    return points


def hide_glyph(plotter, glyph: str) -> None:
    """Remove every actor of ``glyph`` from the plotter."""
    _remove(plotter, GLYPH_ACTORS[glyph])


def glyph_drawn(plotter, glyph: str) -> bool:
    """Whether the plotter shows ``glyph`` now (an actor of it): asked for and drawable here."""
    return any(actor_named(plotter, name) is not None for name in GLYPH_ACTORS[glyph])


def _balls(points: np.ndarray, radius: float) -> pv.PolyData:
    """A sphere of ``radius`` (``BALL_RESOLUTION``, smooth normals) at each of ``points`` (k, 3)."""
    unit = _unit_mesh("sphere", BALL_RESOLUTION)
    k, n = len(points), unit.n_points
    tri = unit.faces.reshape(-1, 4)             # all triangles: [3, a, b, c]
    faces = np.tile(tri, (k, 1))
    faces[:, 1:] += np.repeat(np.arange(k) * n, len(tri))[:, None]
    pts = (points[:, None, :] + radius * unit.points[None]).reshape(-1, 3)
    balls = pv.PolyData(pts, faces=faces.ravel())
    balls.point_data.active_normals = np.tile(unit.points, (k, 1))     # a unit sphere's normal is its point
    return balls


def draw_links(plotter, link_points: np.ndarray) -> None:
    """The mechanism as a tube polyline through ``link_points`` (k, 2|3) with joint balls."""
    pts = to_3d(link_points)
    size = float(np.max(np.ptp(pts, axis=0))) or 1.0
    key = _key(pts)
    # The tube filter's normals, Phong-interpolated: what ``smooth_shading=True`` draws.
    _show(plotter, "links", lambda: pv.lines_from_points(pts).tube(radius=TUBE_FRACTION * size), key,
          color=COLOURS["links"], interpolation="phong")
    _show(plotter, "joints", lambda: _balls(pts, BALL_FRACTION * size), key, color=COLOURS["joints"],
          interpolation="phong")


def polytope_mesh(centre: np.ndarray, vertices: np.ndarray, faces, scale: float) -> pv.PolyData:
    """The force polytope as a surface at ``centre`` (m); ``vertices`` (2^n, m) in N."""
    pts = to_3d(centre)[0] + scale * to_3d(vertices)
    cells = np.concatenate([[len(f), *f] for f in faces])
    return pv.PolyData(pts, faces=cells)


#: The first closed glyph shown is a translucent surface, lit so that its face towards the camera
#: shows its colour blended with the background and nothing darker: the colour its legend swatch
#: has (``drawn_colour``). Spatial: the polytope's faces and the sphere's or an ellipsoid's surface
#: (opacity of one sheet; the front and back sheets together cover 64 %), shaded by the camera's
#: light kit with ``SURFACE_AMBIENT`` ambient light added: pyvista's light kit lights a face
#: towards the camera at 0.76 of its colour (measured), so 0.25 more brings it to its colour and
#: the rim, turned away, keeps a quarter (the shape still reads). Planar: one flat sheet, unlit.
#: Drawn behind the other glyphs, it hides none of them whatever its opacity: these keep its
#: swatch (and the app's legend text, drawn in the swatch's colour) a mid tone, not a pale one.
POLYTOPE_OPACITY, SURFACE_OPACITY, FLAT_OPACITY = 0.4, 0.4, 0.5
SURFACE_AMBIENT = 0.25


def _surface_look(planar: bool, opacity: float) -> dict:
    """``add_mesh`` options of a translucent glyph surface (see ``SURFACE_AMBIENT``)."""
    if planar:
        return {"opacity": FLAT_OPACITY, "lighting": False}
    return {"opacity": opacity, "ambient": SURFACE_AMBIENT, "interpolation": "phong"}

#: Outlines (the closed glyphs after the first): line width (px), unlit, so that they show their
#: colour exactly, as the legend's swatch does.
OUTLINE_LOOK = {"line_width": 2.5, "lighting": False}


def draw_polytope(plotter, centre, vertices, faces, scale: float, outline: bool = False) -> None:
    """The force polytope: translucent faces and their edges, or (``outline``) its edges alone.

    A slider step changes the vertices, rarely the faces: actors showing a polytope of the same
    faces get the new points alone (``_show``'s ``placed``), not a new mesh and edge list.
    """
    points = to_3d(centre)[0] + scale * to_3d(vertices)
    cells = np.concatenate([[len(f), *f] for f in faces])
    key = _key(points, cells)
    # The faces (and the number of vertices) fix both meshes' cells: what an actor may keep.
    topology = _key(len(points), cells)

    def mesh():
        return pv.PolyData(points, faces=cells)

    if outline:
        _remove(plotter, ["polytope"])
    else:
        planar = np.shape(vertices)[-1] == 2            # a polygon: a planar device's force set
        _show(plotter, "polytope", mesh, key, placed=("polytope", topology, lambda: points),
              color=COLOURS["polytope"], **_surface_look(planar, POLYTOPE_OPACITY))
        draw_in_layer(actor_named(plotter, "polytope"), "back")
    _show(plotter, "polytope_edges", lambda: polytope_edges(points, faces), key,
          placed=("polytope_edges", topology, lambda: points), color=COLOURS["polytope_edges"], line_width=2)


def polytope_edges(points: np.ndarray, faces) -> pv.PolyData:
    """The polytope's edges as lines: each face's sides, an edge shared by two faces once.

    What ``extract_all_edges`` gives, from the face lists directly (VTK's filter took ~3 ms
    a slider step for a dozen faces). ``points`` (k, 3); ``faces`` lists of vertex indices.
    """
    sides = np.concatenate([np.column_stack([f, np.roll(f, -1)]) for f in faces]).astype(np.int64)
    sides = np.unique(np.sort(sides, axis=1), axis=0)
    lines = np.column_stack([np.full(len(sides), 2), sides]).ravel()
    return pv.PolyData(np.asarray(points, float), lines=lines)


def draw_sphere(plotter, centre, radius: float, scale: float, planar: bool, outline: bool = False) -> None:
    """The inscribed isotropic ball: a sphere, or a disc for planar mechanisms; with ``outline``
    its great circles (``principal_sections``), a circle for planar ones."""
    c = to_3d(centre)[0]
    r = radius * scale
    key = _key(c, r)
    if outline:
        m = 2 if planar else 3
        radii, axes = np.full(m, r), np.eye(m)
        _show(plotter, "sphere", lambda: principal_sections(c, radii, axes, 1.0, SECTION_POINTS), key,
              placed=("sections", (m, SECTION_POINTS), lambda: section_points(c, radii, axes, 1.0, SECTION_POINTS)),
              color=COLOURS["sphere"], **OUTLINE_LOOK)
        return
    kind, detail = ("circle", 96) if planar else ("sphere", SPHERE_RESOLUTION)

    def points():
        return c + r * _unit_points(kind, detail)

    if planar:
        _show(plotter, "sphere", lambda: _placed(kind, detail, points()), key, placed=(kind, detail, points),
              color=COLOURS["sphere"], **_surface_look(True, FLAT_OPACITY))
        draw_in_layer(actor_named(plotter, "sphere"), "back")
    else:
        # The unit sphere's own normals, Phong-interpolated: what ``smooth_shading=True`` draws.
        _show(plotter, "sphere", lambda: _placed(kind, detail, points()), key, placed=(kind, detail, points),
              color=COLOURS["sphere"], **_surface_look(False, SURFACE_OPACITY))
        draw_in_layer(actor_named(plotter, "sphere"), "back")


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


def principal_sections(centre, radii: np.ndarray, axes: np.ndarray, scale: float, points: int = 97) -> pv.PolyData:
    """An ellipsoid's outline: its principal sections as closed polylines (three great ellipses,
    each in the plane of two principal axes; a planar ellipse's boundary, in z = 0).

    Parameters
    ----------
    centre : array_like, shape (m,) or (3,)
        The centre, m.
    radii : array_like, shape (m,)
        Semi-axes (any unit), along the columns of ``axes`` (m, m); ``scale`` turns them into m.
    points : int
        Points per ellipse, the first repeated at the end.

    Returns
    -------
    pyvista.PolyData
        Lines only (no faces), every point on the ellipsoid's surface (``section_points``).

    Examples
    --------
    >>> sections = principal_sections(np.zeros(3), np.array([1.0, 2.0, 3.0]), np.eye(3), 1.0, points=5)
    >>> sections.n_lines, sections.faces.size, np.abs(sections.points).max(axis=0).tolist()
    (3, 0, [1.0, 2.0, 3.0])
    """
    pts = section_points(centre, radii, axes, scale, points)
    sections = len(pts) // points
    lines = np.concatenate([[points, *range(k * points, (k + 1) * points)] for k in range(sections)])
    return pv.PolyData(pts, lines=lines)


def section_points(centre, radii: np.ndarray, axes: np.ndarray, scale: float, points: int = 97) -> np.ndarray:
    """The points of ``principal_sections`` (its lines are fixed by ``len(radii)`` and ``points``),
    shape (points, 3) for a planar ellipse, (3 * points, 3) for an ellipsoid: a slider step moves
    an outline's points alone (``_show``'s ``placed``), not a new mesh (a new ``PolyData`` of
    lines cost ~1 ms of pyvista's checks)."""
    radii, axes = np.asarray(radii, float), np.asarray(axes, float)
    m = radii.size
    semi = axes * (radii * scale)                    # columns: the semi-axes as vectors
    angle = np.linspace(0.0, 2.0 * np.pi, points)
    pairs = [(0, 1)] if m == 2 else [(0, 1), (1, 2), (2, 0)]
    c = to_3d(centre)[0]
    return np.concatenate([c + to_3d(np.outer(np.cos(angle), semi[:, i]) + np.outer(np.sin(angle), semi[:, j]))
                           for i, j in pairs])


#: Points per principal section of an outline (``principal_sections``).
SECTION_POINTS = 97


def draw_ellipsoid(plotter, name: str, centre, radii, axes, scale: float, outline: bool = False) -> None:
    """An ellipsoid (a planar ellipse) translucent, or (``outline``) its principal sections."""
    if not np.all(np.isfinite(radii)):
        hide_glyph(plotter, name)
        return
    if outline:
        m = np.size(radii)
        _show(plotter, name, lambda: principal_sections(centre, radii, axes, scale, SECTION_POINTS),
              _key(centre, radii, axes, scale),
              placed=("sections", (m, SECTION_POINTS),
                      lambda: section_points(centre, radii, axes, scale, SECTION_POINTS)),
              color=COLOURS[name], **OUTLINE_LOOK)
        return
    # ``transform`` carries the unit sphere's normals along (Phong: as ``smooth_shading=True``).
    _show(plotter, name, lambda: ellipsoid_mesh(centre, radii, axes, scale), _key(centre, radii, axes, scale),
          color=COLOURS[name], **_surface_look(np.size(radii) == 2, SURFACE_OPACITY))
    draw_in_layer(actor_named(plotter, name), "back")


def ellipse_edge(centre, radii: np.ndarray, axes: np.ndarray, scale: float, points: int = 97) -> pv.PolyData:
    """The boundary of a 2D ellipse (semi-axes ``radii`` (2,) along the columns of ``axes``) as a
    closed polyline in the z = 0 plane."""
    angle = np.linspace(0.0, 2.0 * np.pi, points)
    circle = np.column_stack([np.cos(angle), np.sin(angle)])
    pts = to_3d(centre)[0] + to_3d(circle @ (np.asarray(axes, float) * (np.asarray(radii, float) * scale)).T)
    return pv.lines_from_points(pts)


def draw_ellipse_edge(plotter, name: str, centre, radii, axes, scale: float, colour: str, planar: bool) -> None:
    """A planar ellipse's outline (``ellipse_edge``); removed for a spatial one. A translucent disc
    lying over the inscribed disc of a similar size (the five-bar's inertia ellipse and its
    isotropic force) blends with it into one colour: the outline keeps it apart."""
    if not planar:
        _remove(plotter, [name])
        return
    _show(plotter, name, lambda: ellipse_edge(centre, radii, axes, scale), _key(centre, radii, axes, scale),
          color=colour, line_width=2)


def _arrow_points(start: np.ndarray, vector: np.ndarray, shaft: float) -> np.ndarray:
    """The unit arrow's points rotated onto ``vector``, scaled by its length, moved to ``start``."""
    length = float(np.linalg.norm(vector))
    d = np.asarray(vector, float) / length
    helper = np.array([0.0, 0.0, 1.0]) if abs(d[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = _cross(d, helper)
    u /= np.linalg.norm(u)
    rotation = np.column_stack([d, u, _cross(d, u)])      # x -> d, a proper rotation
    return start + length * _unit_points("arrow", shaft) @ rotation.T


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross(a, b)`` of two 3-vectors, the same products and differences (so the same bits),
    without its axis handling (~70 us a call: a slider step made six)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _arrow(start: np.ndarray, vector: np.ndarray, shaft: float) -> pv.PolyData | None:
    """``pv.Arrow(start, vector / |vector|, scale=|vector|, ...)``: the unit arrow rotated, scaled, moved."""
    length = float(np.linalg.norm(vector))
    if not np.isfinite(length) or length <= 0:
        return None
    return _placed("arrow", shaft, _arrow_points(start, vector, shaft))


#: Depth layers (``draw_in_layer``): an actor's fragments are written at a share ``DEPTH_SHARE`` of
#: their depth (``gl_FragDepth``; the others' fill 0 to 1 between the camera's clipping planes) at
#: the front of that range ("front": the arrows), just behind it ("over": the desired force, under
#: its clamp) or at its back ("back": the translucent surface), in order among themselves. An
#: arrow under a link, inside a surface or along a five-bar's distal link (an actuator's force at
#: full torque lies along the other arm's distal link) is drawn over it; the translucent surface
#: is drawn behind every other glyph, so it tints none of them (a planar device's outlines lie in
#: its plane, and showed the polygon's blue over their colours).
DEPTH_SHARE = 1e-3
DEPTH_LAYERS = {"front": f"{DEPTH_SHARE:g} * gl_FragCoord.z", "over": f"{DEPTH_SHARE:g} * (1.0 + gl_FragCoord.z)",
                "back": f"{1 - DEPTH_SHARE:g} + {DEPTH_SHARE:g} * gl_FragCoord.z"}


def draw_in_layer(actor, layer: str | None) -> None:
    """Draw ``actor`` in front of (``"front"``, ``"over"``) or behind (``"back"``) every other actor
    of its renderer, or (None) where its depth puts it (``DEPTH_LAYERS``)."""
    if getattr(actor, "_isoforce_layer", None) == layer:
        return
    shaders = actor.GetShaderProperty()
    shaders.ClearAllFragmentShaderReplacements()
    if layer is not None:
        shaders.AddFragmentShaderReplacement("//VTK::Depth::Impl", True,
                                             f"//VTK::Depth::Impl\n  gl_FragDepth = {DEPTH_LAYERS[layer]};\n", False)
    actor._isoforce_layer = layer


def depth_layer(actor) -> str | None:
    """The depth layer ``actor`` is drawn in (``draw_in_layer``): a key of ``DEPTH_LAYERS`` or None."""
    layer = getattr(actor, "_isoforce_layer", None)
    return layer if layer is not None and actor.GetShaderProperty().GetNumberOfShaderReplacements() else None


def _draw_arrow(plotter, name: str, start: np.ndarray, vector: np.ndarray, shaft: float, colour: str,
                layer: str = "front") -> None:
    length = float(np.linalg.norm(vector))
    if not np.isfinite(length) or length <= 0:
        plotter.remove_actor(name, reset_camera=False, render=False)
    else:
        _show(plotter, name, lambda: _arrow(start, vector, shaft), _key(start, vector, shaft),
              placed=("arrow", shaft, lambda: _arrow_points(start, vector, shaft)), color=colour)
        draw_in_layer(actor_named(plotter, name), layer)


def draw_reference_forces(plotter, centre, reference_forces: np.ndarray, scale: float) -> None:
    """One arrow per actuator: column u of ``J^-T diag(t)`` (m, n) in N."""
    c = to_3d(centre)[0]
    ref = to_3d(np.asarray(reference_forces).T) * scale
    for u in range(6):
        name = f"reference_force_{u}"
        if u < len(ref):
            _draw_arrow(plotter, name, c, ref[u], 0.025, ACTUATOR_COLOURS[u])
        else:
            _remove(plotter, [name])        # a lookup, not pyvista's search of every actor by name


def draw_desired_force(plotter, centre, desired, clamped, scale: float) -> None:
    """The desired force's arrow and its clamp's. The clamped force lies along the desired one,
    shorter and (its shaft a share of its length) thinner, inside it: the desired arrow is drawn
    in the ``"over"`` layer, under the other arrows, so the clamped one shows over it in its own
    colour (drawn see-through instead, the desired arrow tinted the clamped one grey). A desired
    force the device holds in every direction is not clamped: its clamp would cover it exactly,
    so only the desired arrow is drawn (and the legend lists only it)."""
    c = to_3d(centre)[0]
    _draw_arrow(plotter, "desired_force", c, to_3d(desired)[0] * scale, 0.03, COLOURS["desired"], layer="over")
    if np.allclose(clamped, desired, rtol=1e-12, atol=0.0):
        _remove(plotter, ["clamped_force"])
    else:
        _draw_arrow(plotter, "clamped_force", c, to_3d(clamped)[0] * scale, 0.045, COLOURS["clamped"])


#: The inscribed sphere is drawn at least this many times the end-effector's joint ball's radius,
#: and its radius at least this share of the drawn links' extent: the PHANToM Premium's 1.5 N on
#: 210 mm of links was drawn 9 mm across, a speck under its links (0.042 of them).
SPHERE_OVER_BALL, SPHERE_OVER_SIZE = 1.5, 0.08
#: ... unless the anisotropic force would then be drawn longer than this share of the extent.
POLYTOPE_OVER_SIZE = 0.5


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
    isotropic force next to a big device) or its radius smaller than ``SPHERE_OVER_SIZE`` of the
    links' extent (a small force on long links: the PHANToM Premium), then rounded up to 1, 2 or
    5 x 10^k m/N so that it changes in few steps while a slider moves. The second rule gives way
    where it would draw the anisotropic force longer than ``POLYTOPE_OVER_SIZE`` of the extent (a
    long thin polytope: the Stewart platform's reaches 0.58 of it at its own scale). The caption
    prints the scale in use.
    """
    scale = force_scale(mechanism)
    iso = float(getattr(report, "isotropic_force", np.nan))
    if not (report.reachable and np.isfinite(iso) and iso > 0):
        return scale
    pts = to_3d(_link_points(mechanism, report.joints))
    extent = float(np.max(np.ptp(pts, axis=0))) or 1.0
    needed = SPHERE_OVER_BALL * BALL_FRACTION * extent / iso
    sized = max(needed, SPHERE_OVER_SIZE * extent / iso)
    aniso = float(getattr(report, "anisotropic_force", np.nan))
    if np.isfinite(aniso) and aniso * _round_up_125(sized) <= POLYTOPE_OVER_SIZE * extent:
        needed = sized
    return scale if scale >= needed else _round_up_125(needed)


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
    wrench = mechanism.has_orientation
    forces = mechanism.task_dim <= 3 or wrench
    rows = list(wrenches.force_rows(mechanism)) if wrench else slice(None)
    x = report.x[rows]
    desired_force = np.asarray(desired_force, float)[rows]
    # Which closed glyphs will be drawn: all but the first are outlines (``outlined_glyphs``).
    drawable = report.faces is not None and report.vertices is not None and np.all(np.isfinite(report.vertices))
    closed = {"polytope": drawable, "sphere": np.isfinite(report.isotropic_force)}
    closed.update({name: getattr(report, name) is not None and np.all(np.isfinite(getattr(report, name).radii))
                   for name in ("force_ellipsoid", "velocity_ellipsoid", "inertia_ellipsoid")})
    outline = outlined_glyphs({g for g, can in closed.items() if can and g in glyphs and ok and forces})
    shown = set()
    if "links" in glyphs and ok:
        draw_links(plotter, _link_points(mechanism, report.joints))
        shown.add("links")
    if "polytope" in glyphs and ok and forces and drawable:
        draw_polytope(plotter, x, report.vertices, report.faces, scale, "polytope" in outline)
        shown.add("polytope")
    if "sphere" in glyphs and ok and forces and np.isfinite(report.isotropic_force):
        draw_sphere(plotter, x, report.isotropic_force, scale, planar, "sphere" in outline)
        shown.add("sphere")
    for name in ("force_ellipsoid", "velocity_ellipsoid"):
        ell = getattr(report, name)
        if name in glyphs and ok and forces and ell is not None and np.all(np.isfinite(ell.radii)):
            # Velocities (m/s for unit joint rates) are drawn 1:4 so they sit beside the forces.
            draw_ellipsoid(plotter, name, x, ell.radii, ell.axes,
                           scale if name == "force_ellipsoid" else velocity_scale(mechanism), name in outline)
            shown.add(name)
    # Masses of a pure force (the force rows), at the handle: only where every axis is finite
    # (an infinite one is said in the caption, ``inertia_text``).
    ell = report.inertia_ellipsoid
    if "inertia_ellipsoid" in glyphs and ok and forces and ell is not None and np.all(np.isfinite(ell.radii)):
        outlined = "inertia_ellipsoid" in outline
        draw_ellipsoid(plotter, "inertia_ellipsoid", x, ell.radii, ell.axes, inertia_scale(mechanism), outlined)
        draw_ellipse_edge(plotter, "inertia_ellipsoid_edge", x, ell.radii, ell.axes, inertia_scale(mechanism),
                          COLOURS["inertia_ellipsoid"], planar and not outlined)
        shown.add("inertia_ellipsoid")
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
    # (Not rendered here: whoever shows the scene renders it once.)
    if mechanism.task_dim == 2:
        plotter.view_xy(render=False)
    else:
        plotter.view_isometric(render=False)
        plotter.camera.azimuth = plotter.camera.azimuth - 60
    plotter.reset_camera(render=False)


