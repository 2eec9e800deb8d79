"""The workspace scene: a workspace map's quantity drawn over the workspace in 3D.

A 2D map (``draw_workspace``, ``workspace_volume``) is the Inverse3's (x, z) slice revolved
over its base joint, cut open by a plane or drawn as iso-surfaces (``WORKSPACE_MODES``), or
a planar mechanism's map as a flat surface. A 3D box map (``draw_box_workspace``,
``box_scene_parts``) is its boundary, iso-surfaces of the quantity (``iso_levels``) and the
plane the map view shows, the contours smoothed (Taubin) so that they show no voxel
terraces. The values on the iso-surfaces and the axes in mm are ``app.scenes.iso_labels``.

A categorical quantity (the bottleneck actuator, the singularity class) is drawn as the map
view draws it: each sample's class over the cell around it, in the map's class colours, with a
key of the map's class names (``app.scenes.classes``), not a bar of codes. The slice's mesh,
revolved or flat, is ``app.scenes.slice_mesh``.
"""
from __future__ import annotations

import numpy as np
import pyvista as pv
from vtkmodules.vtkCommonDataModel import vtkPlane
from vtkmodules.vtkFiltersGeneral import vtkTableBasedClipDataSet

from app.logic.colour_limits import colour_limits, log_colours
from app.logic.display_units import display_unit
from app.scenes.classes import _class_bar, _class_cells, _class_image, class_key, class_lookup_table
from app.scenes.common import actor_named
from app.scenes.slice_mesh import _edge_field, _edge_filled, _index_box, _on_mesh, _slice_mesh, is_revolved
from metrics.quantities import QUANTITIES
from metrics.workspace import Cancelled

#: The 3D workspace view draws at most this many map points per axis.
WORKSPACE_MAX_POINTS = 160
#: ... and the app's revolved slice, whose cut plane can move, at most this many: the plane
#: widget keeps the whole revolved volume, a copy tagged with cell ids and the cut part alive (a
#: figure and a flat picture keep only a surface). At 160 the Inverse3's took 150 MB (415,000
#: cells drawn); at 100, 93 MB (208,000), and a 1000 px wide picture of it looks the same.
INTERACTIVE_MAX_POINTS = 100


def flat_axes(mechanism, grid) -> str:
    """The axes a workspace picture lies in: ``"xy"`` for a planar device, the slice's own
    (``"xz"``: the PHANToM family's y = 0 plane) for an unrevolved slice of a spatial one, and
    ``"xyz"`` for a revolved slice or a 3D box."""
    if mechanism.task_dim == 2:
        return "xy"
    if len(grid.axes) == 2 and not is_revolved(mechanism, grid):
        return "".join(a for a in "xyz" if a in grid.axes)
    return "xyz"


def frame_workspace_camera(plotter, mechanism, grid) -> None:
    """Look at a flat workspace picture square on (lit head on, its colours the key's), at a
    spatial one obliquely; then frame it (``reset_camera``)."""
    views = {"xy": plotter.view_xy, "xz": plotter.view_xz, "yz": plotter.view_yz}
    views.get(flat_axes(mechanism, grid), plotter.view_isometric)(render=False)
    plotter.reset_camera(render=False)


def workspace_volume(workspace_map, quantity: str, mechanism, *, max_points: int = WORKSPACE_MAX_POINTS,
                     angles: int = 72, key: dict | None = None, cut_open: bool = False) -> pv.DataSet:
    """A 3D dataset of the workspace coloured by ``quantity``, infeasible cells removed.

    Inverse3: the (x, z) slice at theta_0 = 0 revolved over the base joint's range (every
    quantity is invariant under the base rotation, which only rotates J's rows). Planar
    mechanisms: the map itself as a flat surface. The slice is subsampled to at most
    ``max_points`` per axis: the 3D view shows the shape, the map view the detail.

    A magnitude is point data at the samples. The workspace's edge is cut where a smoothed
    feasibility (``_edge_field``: every sample held on its own side), interpolated linearly
    between the samples, crosses one half (``clip_scalar``), so it is a smooth surface, neither
    the staircase of whole cells nor the 0/1 indicator's terrace of 45-degree steps; the values
    at infeasible samples next to it are their nearest feasible sample's, so the cut cells are
    coloured by feasible values only.

    A categorical quantity (``key``: its ``class_key``, made from the map if not given) is cell
    data, each cell the class index of its nearest sample, as the map view draws a class map; its
    edge is cut at the cell corners by the share of classed samples around each: see
    ``_class_cells``.

    ``cut_open``: the caller keeps only the side y >= 0 of a revolved slice (a figure's cut,
    ``workspace_parts``), so only the angle steps with a sample on that side are built
    (``_kept_steps``): a clip keeps or drops each cell by its own corners, so the steps left out
    held no cell the cut keeps, and the cut is the same. A magnitude's only (a class map's cells
    are built whole).
    """
    grid = workspace_map.grid
    if QUANTITIES[quantity].categorical:
        index = (class_key(workspace_map, quantity, mechanism) if key is None else key).to_data(
            workspace_map.values[quantity], workspace_map.feasible)
        values, feasible = np.ma.getdata(index).astype(float), ~np.ma.getmaskarray(index)
    else:
        values = workspace_map.values[quantity] * display_unit(quantity)[1]  # µm, deg as on the map (display_units)
        feasible = workspace_map.feasible
    step = [max(1, int(np.ceil(n / max_points))) for n in grid.resolution]
    sl = tuple(slice(None, None, s) for s in step)
    vals = np.where(feasible, values, np.nan)[sl].astype(float)
    ok = np.isfinite(vals)
    coords = [c[::s] for c, s in zip(grid.coordinates(), step)]
    if QUANTITIES[quantity].categorical:
        return _class_cells(vals, ok, coords, quantity, mechanism, grid, angles)
    every, none = bool(ok.all()), not ok.any()
    vals = _edge_filled(vals)
    if not (every or none):
        # Only cells with a feasible corner are kept (``clip_scalar`` below): the samples beyond
        # one step outside the feasible ones' box are left out before the grid is made (the
        # same cells, the revolved Inverse3 slice's ~10^6 points fewer by half).
        box = _index_box(ok)
        vals, ok = vals[box], ok[box]
        coords = [c[b] for c, b in zip(coords, box)]
    spans = _kept_spans(coords, mechanism, grid, angles) if cut_open and not none else [None]
    blocks = []
    for span in spans:
        mesh = _slice_mesh(coords, mechanism, grid, angles, span)
        count = angles if span is None else span[1] - span[0] + 1
        mesh.point_data[quantity] = _on_mesh(vals, mechanism, grid, count)
        if none:
            return mesh
        mesh.point_data["feasible"] = _on_mesh(_edge_field(ok), mechanism, grid, count)
        blocks.append(mesh.cast_to_unstructured_grid() if every else
                      mesh.clip_scalar(scalars="feasible", value=0.5, invert=False))
    return blocks[0] if len(blocks) == 1 else blocks[0].merge(blocks[1:], merge_points=False)


def _kept_spans(coords, mechanism, grid, angles: int) -> list:
    """The blocks of whole angle steps of a revolved slice (``_slice_mesh``'s ``span``: first and last
    angle) with a point at y >= 0, where ``workspace_parts`` cuts the figure's solid open; ``[None]``
    (every angle) for a flat slice, or when no step has one (the cut then leaves nothing either way).

    A step's points lie on its two angles' half-planes; along each, y = u sin t + c cos t is
    linear in u, so its largest y over the slice is at the smallest or the largest u.
    """
    if not is_revolved(mechanism, grid):
        return [None]
    lo, hi, offset = mechanism.revolution
    theta = np.linspace(lo, hi, angles)           # ``_slice_mesh``'s angles
    u = coords[grid.axes.index("x")]
    c = dict(grid.fixed).get("y", offset)
    reach = np.max(np.sin(theta)[:, None] * np.array([u.min(), u.max()]), axis=1) + c * np.cos(theta) >= 0.0
    step = reach[:-1] | reach[1:]                 # step k: between angles k and k + 1
    if not step.any():
        return [None]
    # Runs of kept steps: a run of steps k0..k1 is the block of angles k0..k1 + 1.
    edges = np.flatnonzero(np.diff(np.concatenate([[False], step, [False]]).astype(np.int8)))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2])]


#: The workspace colour bar's place (right of the axes triad's corner, 0 to 0.2 of the width), its
#: labels and fonts (px). Two labels, the ends: the title sits between them, where a middle
#: label was printed under it in a narrow view; fonts of fixed size, where VTK's own, fitted
#: to the bar's box, grew larger than any other text in the view.
BAR_LOOK = {"position_x": 0.22, "position_y": 0.03, "width": 0.72, "height": 0.1, "n_labels": 2, "fmt": "%.3g",
            "title_font_size": 12, "label_font_size": 11}
#: A categorical quantity's bar (``class_lookup_table``): a swatch per class with its name, no numbers.
CLASS_BAR_LOOK = {**BAR_LOOK, "n_labels": 0}
#: Share of a lit quantity's light that is ambient: a surface facing away from the key light
#: keeps this much of its colour (with none, the revolved Inverse3's shell read near black
#: against the colour bar's darkest colour), and the rest still shades the solid's shape.
SHADED_AMBIENT = 0.3
#: Share of a lit class picture's light that is ambient (the rest diffuse, no highlights): enough
#: shading to show a revolved solid's shape, little enough that each class keeps its hue and lightness.
CLASS_AMBIENT = 0.6
#: Iso-surfaces drawn of a 3D box map's quantity, at the feasible values' percentiles evenly spaced
#: between these (``iso_levels``).
ISO_LEVELS = 4
ISO_PERCENTILES = (10.0, 90.0)
#: Opacity of each iso-surface and the share of its light that is ambient: four nested surfaces at
#: 0.5, fully shaded (seen through up to eight sheets, each surface's front and back), blended into
#: one dark shape; lighter and half lit by ambient light, each keeps its colour and the inner ones
#: show through the outer ones.
ISO_OPACITY, ISO_AMBIENT = 0.3, 0.5
#: The actors of a 3D box map's scene (``draw_box_workspace``).
BOX_ACTORS = ("workspace", "box_hull", "box_plane", "box_levels")


def box_image(workspace_map, quantity: str) -> pv.ImageData:
    """A 3D box map as ``pyvista.ImageData`` (points at the grid's samples, m).

    Point arrays: ``quantity`` (``nan`` where infeasible or not finite: unbounded points are
    no level of any surface), ``"feasible"`` (1.0 / 0.0) and ``"edge"`` (``_edge_field`` of
    it: every sample on its own side of 0.5, the crossings where a blurred boundary's are),
    whose 0.5 contour is the workspace's boundary. The grid's axes are the task's x, y, z in
    some order; the image's axes are x, y, z, so the arrays are transposed to that order.
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
    image.point_data["edge"] = _edge_field(feasible > 0.5).ravel(order="F")
    return image


def iso_levels(values: np.ndarray, quantity: str, count: int = ISO_LEVELS) -> np.ndarray:
    """Levels of the iso-surfaces of a map: the finite values' percentiles evenly spaced from the
    10th to the 90th (``ISO_PERCENTILES``), so that the surfaces lie where the values are.

    Levels evenly spaced in value put the Falcon's four isotropic-force surfaces between 3.5
    and 7.2 N whatever the values between them: most of its workspace lies in 3 to 8 N, a
    few points reach 18.5 N. Quantiles split the workspace into equal shares of its samples
    (on a regular grid, of its volume) between the surfaces, on a linear or a log scale alike
    (a quantile does not depend on the scale). ``quantity`` is kept for the callers' sake.

    Returns the distinct levels, ascending; an empty array when fewer than two exist.

    Examples
    --------
    >>> iso_levels(np.r_[np.arange(1.0, 101.0), [1e6, np.nan]], "isotropic_force").round(2)
    array([11.  , 37.67, 64.33, 91.  ])
    """
    finite = np.asarray(values, float)
    finite = finite[np.isfinite(finite)]
    if finite.size < 2:
        return np.empty(0)
    levels = np.unique(np.percentile(finite, np.linspace(*ISO_PERCENTILES, count)))
    return levels if levels.size >= 2 else np.empty(0)


def box_scene_parts(workspace_map, quantity: str, slice_axis: str, slice_value: float, *,
                    cache: dict | None = None, mechanism=None, cancelled=None) -> dict:
    """The meshes of a 3D box map's scene: boundary, iso-surfaces, the plane shown in the map view.

    Returns a dict with ``image`` (``box_image``), ``hull`` (the workspace boundary, the 0.5
    contour of feasibility), ``surfaces`` (iso-surfaces of ``quantity``, point array
    ``quantity``; None for classes), ``levels`` (their values), ``clim``, ``log`` and ``capped``
    (``colour_range``: the map view's colour scale), ``plane`` (the grid plane along
    ``slice_axis`` nearest ``slice_value``, m, coloured by ``quantity``) and ``at`` (that
    plane's position, m). A categorical quantity's plane is cut from ``cells`` (one cell per
    sample, cell data its class index: ``class_key``, in ``key``, its classes named by
    ``mechanism``), so that each sample's class colours the cell around it, as on the map.

    ``cache`` (a dict kept by the caller) holds the volume's meshes between calls for the same
    map and quantity: moving the plane then only cuts a new plane (about a millisecond).
    ``cancelled()`` is asked between the volume's steps (``Cancelled`` raised).
    """
    if cache is not None and cache.get("map") is workspace_map and cache.get("quantity") == quantity:
        volume = cache["volume"]
    else:
        volume = _box_volume_parts(workspace_map, quantity, mechanism, cancelled)
        if cache is not None:
            cache.clear()
            cache.update(map=workspace_map, quantity=quantity, volume=volume)
    image = volume["image"]
    grid = workspace_map.grid
    k = grid.axes.index(slice_axis)
    coords = grid.coordinates()[k]
    index = int(np.argmin(np.abs(coords - slice_value)))
    at = float(coords[index])
    origin = list(image.center)
    origin["xyz".index(slice_axis)] = at
    if volume["cells"] is None:
        # The grid's own plane of samples (VTK's cutter returned nothing on the image's lowest
        # face), cut where the smoothed feasibility crosses one half, as the boundary and the
        # surfaces are (``_iso_surfaces``); its cells coloured by the feasible samples' values only.
        voi = [0, image.dimensions[0] - 1, 0, image.dimensions[1] - 1, 0, image.dimensions[2] - 1]
        voi[2 * "xyz".index(slice_axis)] = voi[2 * "xyz".index(slice_axis) + 1] = index
        whole = volume["filled"].extract_subset(voi)
        plane = whole.clip_scalar(scalars="edge", value=0.5, invert=False)
        if plane.n_points == 0:
            # No feasible sample in the plane: the whole plane, blank (nan is see-through), so that
            # it keeps an actor and the colour bar (an empty mesh cannot be drawn).
            whole.point_data[quantity] = np.full(whole.n_points, np.nan)
            plane = whole.cast_to_unstructured_grid()
    else:
        plane = volume["cells"].slice(normal=slice_axis, origin=origin)
    return {**volume, "plane": plane, "at": at}


#: Taubin smoothing of a box map's contours: iterations and pass band (vtkWindowedSincPolyDataFilter).
#: The boundary is the 0.5 contour of a 0/1 field, a terrace of voxel steps; a few tens of
#: low-pass iterations take the steps out (points move well under a grid step) and keep the
#: shape; the scalars are carried along, so each surface still carries its level exactly.
SMOOTH_ITERATIONS, SMOOTH_PASS_BAND = 30, 0.05
#: A surface's rim (where an iso-surface is cut at the workspace's edge) is smoothed too, but
#: VTK keeps fixed, as a corner, each rim point where the rim turns by more than this (degrees,
#: its ``EdgeAngle``; 15 by default): the rim of a coarse grid's cut turns by 17 degrees a point
#: on average, so most of its points stayed where the cut put them, a serrated edge.
SMOOTH_CORNER_ANGLE = 90.0


def _extrapolated(values: np.ndarray) -> np.ndarray:
    """``values`` (any shape) with each non-finite sample next to finite ones along an axis given
    the mean of their linear extrapolations (``2 v1 - v2`` from the two samples inward along
    that axis and direction, ``v1`` where only one is finite); other non-finite samples stay.

    Examples
    --------
    >>> _extrapolated(np.array([1.0, 2.0, np.nan, np.nan]))
    array([ 1.,  2.,  3., nan])
    """
    ok = np.isfinite(values)
    total, count = np.zeros(values.shape), np.zeros(values.shape)
    padded = np.pad(values.astype(float), 2, constant_values=np.nan)
    for axis in range(values.ndim):
        for step in (1, -1):
            def shifted(k: int) -> np.ndarray:      # the sample k steps inward, for every sample
                index = [slice(2, 2 + n) for n in values.shape]
                index[axis] = slice(2 - k * step, 2 - k * step + values.shape[axis])
                return padded[tuple(index)]
            v1, v2 = shifted(1), shifted(2)
            guess = np.where(np.isfinite(v2), 2.0 * v1 - v2, v1)
            use = ~ok & np.isfinite(v1)
            total[use] += guess[use]
            count[use] += 1
    out = values.astype(float)
    out[count > 0] = total[count > 0] / count[count > 0]
    return out


def _filled_image(image, quantity: str) -> pv.ImageData:
    """``image``'s grid with ``quantity`` filled outside the workspace, and its ``"edge"`` field.

    The samples next to the workspace get the values extrapolated linearly from inside
    (``_extrapolated``), the others their nearest filled sample's (a contour through a nan
    sample has nan vertices, and smoothing spreads them to every vertex; a cut cell would be
    coloured nan). With the nearest values only, a field flat across the boundary's cells cut
    the iso-surfaces' rims back to cell faces: a serrated rim."""
    dims = tuple(image.dimensions)
    work = pv.ImageData(dimensions=dims, spacing=image.spacing, origin=image.origin)
    values = np.asarray(image.point_data[quantity], float).reshape(dims, order="F")
    filled = _edge_filled(_extrapolated(values))
    far = ~np.isfinite(filled)
    if far.any() and not far.all():
        # Samples two or more steps from the workspace reach no kept cell (``_edge_filled``):
        # one finite value for them all, as the contour filter emits nan points where it meets nan.
        filled[far] = filled[~far].min()
    work.point_data[quantity] = filled.ravel(order="F")
    work.point_data["edge"] = image.point_data["edge"]
    return work


def _iso_surfaces(work, quantity: str, levels: np.ndarray):
    """The iso-surfaces of ``quantity`` at ``levels`` inside the workspace, smoothed.

    Contoured from ``_filled_image``'s values, then cut where the smoothed feasibility
    (``"edge"``) crosses one half, as the boundary is: the 0/1 indicator's crossings, at every
    edge's middle, cut the surfaces' rims into a staircase of voxel steps."""
    surfaces = work.contour(levels, scalars=quantity, method="contour")     # it carries "edge" along
    if surfaces.n_points:
        surfaces = surfaces.clip_scalar(scalars="edge", value=0.5, invert=False)
    if surfaces.n_points:
        # The filter writes its scalars in float32; each point lies on one level by construction,
        # so it gets that level's value exactly (the nearest level: float32 rounding is far
        # smaller than the levels' spacing).
        near = np.abs(np.asarray(surfaces.point_data[quantity], float)[:, None] - levels[None, :]).argmin(axis=1)
        surfaces.point_data[quantity] = np.asarray(levels, float)[near]
    return _smoothed(surfaces)


#: The static revolved scene's flat faces (the cut y = 0 and the end slices), drawn unlit beside
#: the lit "workspace" shell.
CUT_FACE_ACTOR = "workspace_cut"


def _revolved_planes(mechanism, grid) -> list[tuple[np.ndarray, float]]:
    """The planes of a revolved slice's flat faces, ``(unit normal, offset)`` with ``n . p = offset``:
    the cut y = 0 and the slice at each end of the base joint's range (``_slice_mesh``: the
    points ``u (cos t, sin t) + c (-sin t, cos t)``, on the plane of normal (-sin t, cos t, 0)
    at ``c`` from the axis)."""
    c = dict(grid.fixed).get("y", mechanism.params.plane_offset)
    ends = (mechanism.params.lower_limits[0], mechanism.params.upper_limits[0])
    return [(np.array([0.0, 1.0, 0.0]), 0.0)] + [(np.array([-np.sin(t), np.cos(t), 0.0]), float(c)) for t in ends]


def _flat_faces(surface, planes):
    """``surface`` (a clipped solid's surface) split into its cells on any of ``planes``
    (``(unit normal, offset)`` each; the flat faces, or None where it has none) and the others.

    A cell is on a plane when its centre is within a millionth of the surface's size of it: the
    solid lies on one side of each of its flat faces, so a centre that near one has all its
    points on it (up to rounding), while a cell of the revolved shell next to it reaches a step
    of the grid off it."""
    if surface.n_cells == 0:
        return None, surface
    tol = 1e-6 * max(float(np.ptp(np.asarray(surface.points, float), axis=0).max()), 1e-12)
    centres = np.asarray(surface.cell_centers().points, float)
    flat = np.zeros(surface.n_cells, bool)
    for normal, offset in planes:
        flat |= np.abs(centres @ normal - offset) <= tol
    if not flat.any():
        return None, surface
    return (surface.extract_cells(np.flatnonzero(flat)).extract_surface(algorithm=None),
            surface.extract_cells(np.flatnonzero(~flat)).extract_surface(algorithm=None))


def _with_normals(mesh):
    """``mesh`` with the point normals ``add_mesh(..., smooth_shading=True)`` would compute (it
    keeps a polygonal mesh's own): computed with the mesh, off the GUI thread in the app."""
    if mesh is None or mesh.n_points == 0 or mesh.n_verts + mesh.n_lines == mesh.n_cells:
        return mesh
    return mesh.compute_normals(cell_normals=False, split_vertices=False, feature_angle=30.0)


def _smoothed(mesh):
    """``mesh`` smoothed by Taubin's low-pass filter (no shrinking), or as it is when empty."""
    if mesh is None or mesh.n_points == 0:
        return mesh
    # Normalised coordinates: the filter is unstable (nan points) on a scene of 0.1 m across.
    return mesh.smooth_taubin(n_iter=SMOOTH_ITERATIONS, pass_band=SMOOTH_PASS_BAND, normalize_coordinates=True,
                              edge_angle=SMOOTH_CORNER_ANGLE)


def colour_range(workspace_map, quantity: str) -> tuple[tuple[float, float] | None, bool, bool]:
    """The map view's colour scale of ``quantity``, for the 3D views to colour by the same key.

    ``app.logic.colour_limits.colour_limits`` over the map's feasible finite values in display units (the
    map view's and the exported map's rule: a log scale for the condition number, the upper
    limit capped where a few points near a singularity would squeeze the rest into one colour).

    Returns
    -------
    clim : (float, float) or None
        The colour limits, display units (None for classes, whose colours are their own).
    log : bool
        Whether the scale is logarithmic.
    capped : bool
        Whether values above ``clim[1]`` exist (they take the top colour).
    """
    if QUANTITIES[quantity].categorical:
        return None, False, False
    values = np.asarray(workspace_map.values[quantity], float) * display_unit(quantity)[1]
    finite = values[workspace_map.feasible & np.isfinite(values)]
    log = log_colours(quantity)
    if log:
        finite = finite[finite > 0]
    lo, hi, capped = colour_limits(finite, log=log)
    return (lo, hi), log, capped


def bar_title(quantity: str, clim, capped: bool) -> str:
    """The 3D views' colour-bar title: the quantity, its unit, and the cap as the map view says it."""
    node = QUANTITIES[quantity]
    title = node.label + (f" ({display_unit(quantity)[0]})" if node.unit else "")
    # The cap on a line of its own, as on the map's bar: one line did not fit a narrow view's bar.
    return title + (f"\ncolours capped at {clim[1]:.3g}" if capped else "")


def _box_volume_parts(workspace_map, quantity: str, mechanism=None, cancelled=None) -> dict:
    """What ``box_scene_parts`` draws that does not depend on the plane: image, boundary, surfaces."""
    node = QUANTITIES[quantity]
    image = box_image(workspace_map, quantity)
    values = image.point_data[quantity]
    hull = (_smoothed(image.contour([0.5], scalars="edge", method="flying_edges"))
            if np.any(image.point_data["feasible"]) else None)
    _check(cancelled)
    levels = np.empty(0) if node.categorical else iso_levels(values, quantity)
    filled = None if node.categorical else _filled_image(image, quantity)
    _check(cancelled)
    surfaces = _with_normals(_iso_surfaces(filled, quantity, levels)) if levels.size else None
    _check(cancelled)
    clim, log, capped = colour_range(workspace_map, quantity)
    key = class_key(workspace_map, quantity, mechanism) if node.categorical else None
    cells = _class_image(workspace_map, quantity, key) if node.categorical else None
    return {"image": image, "filled": filled, "hull": hull, "surfaces": surfaces, "levels": levels, "clim": clim,
            "log": log, "capped": capped, "key": key, "cells": cells}


def draw_box_workspace(plotter, workspace_map, quantity: str, mechanism, slice_axis: str, slice_value: float, *,
                       cache: dict | None = None) -> None:
    """A 3D box map: the workspace boundary, iso-surfaces of ``quantity`` and the plane the map view shows.

    One colour scale (the volume's) for the plane and the surfaces; the levels are written in
    the corner. Classes (the bottleneck) get no iso-surfaces: the plane shows them. With a
    ``cache`` (see ``box_scene_parts``) a moved plane replaces the plane's geometry and the
    caption only. ``box_scene_parts`` then ``show_box_parts``: the app computes the first on a
    worker thread (``app.scenes.workspace_job``).
    """
    same_volume = cache is not None and cache.get("map") is workspace_map and cache.get("quantity") == quantity
    parts = box_scene_parts(workspace_map, quantity, slice_axis, slice_value, cache=cache, mechanism=mechanism)
    show_box_parts(plotter, parts, quantity, slice_axis, same_volume=same_volume)


def show_box_parts(plotter, parts: dict, quantity: str, slice_axis: str, *, same_volume: bool = False) -> None:
    """The actors of a 3D box map's scene from its ``box_scene_parts``: made anew, or with
    ``same_volume`` (the parts' volume is the one drawn) the plane's geometry and the caption only."""
    node = QUANTITIES[quantity]
    unit = f" {display_unit(quantity)[0]}" if node.unit else ""
    plane = plotter.actors.get("box_plane")
    if same_volume and plane is not None:
        plane._isoforce_dataset.copy_from(parts["plane"])   # only the plane moved: new geometry, same look
    else:
        _draw_box_volume(plotter, parts, quantity)
    # Short lines: the caption shares the view's top edge with its "Reset view" button.
    if parts["levels"].size:
        levels = ", ".join(f"{v:.3g}" for v in parts["levels"])
        first = f"iso-surfaces of {node.label.lower()}\nat {levels}{unit}"
        if parts["levels"].size == ISO_LEVELS:
            # Where they sit among the values: most of a workspace may lie low on a bar that spans
            # its whole range (the Falcon's isotropic force: 90 % of it under 8 N of 18.5 N).
            shares = ", ".join(f"{p:.0f}" for p in np.linspace(*ISO_PERCENTILES, ISO_LEVELS))
            first += f",\nthe {shares} % quantiles of its values"
    elif node.categorical:
        first = f"{node.label}: classes have\nno iso-surfaces; the plane shows them"
    else:
        first = f"{node.label}: too few distinct\nvalues for iso-surfaces"
    phrases = (first, f"plane {slice_axis} = {parts['at'] * 1e3:.1f} mm", "grey: workspace boundary")
    text = "\n".join(phrases)
    corner = actor_named(plotter, "box_levels")
    if corner is not None and hasattr(corner, "set_text"):
        corner.set_text("upper_left", text)
    else:
        corner = plotter.add_text(text, position="upper_left", font_size=9, color="black", name="box_levels",
                                  render=False)
    corner._isoforce_phrases = phrases      # the caption as phrases, for a figure's caption (``box_caption``)


def box_caption(plotter) -> str:
    """A box scene's corner text as one line of phrases, and the corner text removed (a figure
    prints it in its caption, at the figure's text size); "" for other scenes."""
    corner = actor_named(plotter, "box_levels")
    phrases = getattr(corner, "_isoforce_phrases", None)
    if phrases is None:
        return ""
    plotter.remove_actor("box_levels", reset_camera=False, render=False)
    return "; ".join(p.replace("\n", " ") for p in phrases)


def _draw_box_volume(plotter, parts: dict, quantity: str) -> None:
    """The boundary, iso-surface and plane actors of ``draw_box_workspace``, made anew."""
    node = QUANTITIES[quantity]
    title = bar_title(quantity, parts["clim"], parts["capped"])
    if node.categorical:
        # The map's class colours, unlit (shading would darken them), and a legend of their names.
        look = dict(cmap=class_lookup_table(parts["key"], nan_opacity=0.0), lighting=False, reset_camera=False,
                    render=False)
    else:
        look = dict(cmap="viridis", clim=parts["clim"], log_scale=parts["log"], reset_camera=False, render=False)
    if plotter.scalar_bars:
        plotter.remove_scalar_bar()
    if parts["hull"] is not None and parts["hull"].n_points:
        plotter.add_mesh(parts["hull"], color="#9a9a9a", opacity=0.12, name="box_hull", reset_camera=False,
                         render=False)
    else:
        plotter.remove_actor("box_hull", reset_camera=False, render=False)
    surfaces = parts["surfaces"]
    if surfaces is not None and surfaces.n_points:
        actor = plotter.add_mesh(surfaces, scalars=quantity, opacity=ISO_OPACITY, smooth_shading=True,
                                 ambient=ISO_AMBIENT, diffuse=1.0 - ISO_AMBIENT, name="workspace",
                                 show_scalar_bar=False, **look)
        actor._isoforce_iso_surfaces = True         # its values are levels: labelled (``label_iso_surfaces``)
    else:
        plotter.remove_actor("workspace", reset_camera=False, render=False)
    plane = plotter.add_mesh(parts["plane"], scalars=quantity, nan_opacity=0.0, name="box_plane",
                             scalar_bar_args={"title": title, **(CLASS_BAR_LOOK if node.categorical else BAR_LOOK)},
                             **look)
    # The dataset the plane's pipeline starts from, kept for a moved plane's new geometry: the
    # mapper's ``dataset`` says so only while pyvista's Python mapper object lives (the plotter
    # keeps the last mesh's only), else it is the pipeline's output, remade from the old input.
    plane._isoforce_dataset = plane.mapper.dataset
    if node.categorical:
        _class_bar(plotter, title)


WORKSPACE_MODES = ("cut plane", "iso-surfaces")


def clear_clip_plane(plotter) -> None:
    """Remove the revolved slice's cut plane (``draw_workspace(..., interactive=True)``) and what it cut.

    PyVista's ``clear_plane_widgets`` turns the widgets off but keeps every mesh that
    ``add_mesh_clip_plane`` cut in ``plane_clipped_meshes``, each holding its clipper and the
    volume it cut: 40-70 MB per redraw of a 1000 x 1000 Inverse3 map, never freed.
    """
    plotter.clear_plane_widgets()
    getattr(plotter, "widgets", plotter).plane_clipped_meshes.clear()   # (``Plotter.widgets`` from PyVista 0.48)


#: The revolved slice's cut in the app (``show_workspace_parts``): the plane's normal and a point on it.
CUT_NORMAL, CUT_ORIGIN = (0.0, -1.0, 0.0), (0.0, 0.0, 0.0)


def draw_workspace(plotter, workspace_map, quantity: str, mechanism, mode: str, *, interactive: bool) -> None:
    """Draw the workspace volume of ``quantity`` (shared by the app and ``isoforce figure``).

    A 3D box map is drawn by ``draw_box_workspace`` (iso-surfaces and its middle plane along z).
    Otherwise ``workspace_parts`` (the meshes; the app makes them on a worker thread,
    ``app.scenes.workspace_job``) then ``show_workspace_parts`` (the actors).
    """
    if len(workspace_map.grid.axes) == 3:
        clear_clip_plane(plotter) if interactive else None
        for name in BOX_ACTORS[1:]:
            plotter.remove_actor(name, reset_camera=False, render=False)
        grid = workspace_map.grid
        k = grid.axes.index("z")
        draw_box_workspace(plotter, workspace_map, quantity, mechanism, "z", 0.5 * (grid.lower[k] + grid.upper[k]))
        return
    show_workspace_parts(plotter, workspace_parts(workspace_map, quantity, mechanism, mode, interactive=interactive),
                         interactive=interactive)


def _check(cancelled) -> None:
    """Raise ``Cancelled`` when ``cancelled()`` says so (a newer scene was asked for)."""
    if cancelled is not None and cancelled():
        raise Cancelled()


def workspace_parts(workspace_map, quantity: str, mechanism, mode: str, *, interactive: bool,
                    cancelled=None) -> dict:
    """The meshes ``show_workspace_parts`` draws of a 2D map (no plotter: a worker thread may make them).

    Returns a dict: ``kind`` (``"empty"``: no feasible cell; ``"iso"``: iso-surfaces of a revolved
    slice in ``surfaces``, or ``"outline"`` of its ``volume`` where none exists; ``"cut"``: the
    app's revolved slice, its ``volume``, the part ``clipped`` on the side of ``CUT_NORMAL`` and
    that part's ``surface``; ``"static"``: a figure's revolved slice as its lit ``shell`` and
    unlit ``cut`` faces; ``"flat"``: a flat picture, ``volume``), the colour scale (``clim``,
    ``log``, ``capped``, ``bar``, ``colours``), the class ``key`` (categorical quantities) and
    ``quantity``. ``cancelled()`` is asked between the steps (``Cancelled`` raised).
    """
    node = QUANTITIES[quantity]
    key = class_key(workspace_map, quantity, mechanism) if node.categorical else None
    revolved = is_revolved(mechanism, workspace_map.grid)
    # Only the app's revolved slice keeps its whole volume (the cut plane's): a flat picture and
    # a figure keep a surface, drawn at WORKSPACE_MAX_POINTS.
    # A figure's revolved slice is cut open (``kind`` "static" below): only the part the cut keeps is built.
    cut_open = revolved and not interactive and mode != "iso-surfaces" and not node.categorical
    volume = workspace_volume(workspace_map, quantity, mechanism, key=key, cut_open=cut_open,
                              max_points=INTERACTIVE_MAX_POINTS if interactive and revolved else WORKSPACE_MAX_POINTS)
    _check(cancelled)
    clim, log, capped = colour_range(workspace_map, quantity)      # the map view's key
    bar = {"title": bar_title(quantity, clim, capped), **(CLASS_BAR_LOOK if node.categorical else BAR_LOOK)}
    # Classes: the map's class colours on cells (``workspace_volume``). Where the picture is 3D (the
    # revolved slice) they are lit mostly by ambient light: full shading would darken them into
    # colours of no class, none at all flattened the solid into two cut-outs.
    colours = (dict(cmap=class_lookup_table(key), ambient=CLASS_AMBIENT, diffuse=1.0 - CLASS_AMBIENT,
                    specular=0.0) if node.categorical else
               dict(cmap="viridis", clim=clim, log_scale=log, ambient=SHADED_AMBIENT, diffuse=1.0 - SHADED_AMBIENT))
    parts = {"quantity": quantity, "key": key, "clim": clim, "log": log, "capped": capped, "bar": bar,
             "colours": colours, "volume": volume}
    if volume.n_cells == 0:
        return {**parts, "kind": "empty"}
    # Iso-surfaces of a revolved slice; a flat picture has none (contoured, a flat slice gave
    # edge-on strips and specks), so it is drawn as it is in either mode.
    if mode == "iso-surfaces" and revolved and not node.categorical:
        levels = iso_levels(volume.point_data[quantity], quantity)
        surfaces = (volume.cell_data_to_point_data().contour(isosurfaces=levels, scalars=quantity) if levels.size
                    else pv.PolyData())
        if surfaces.n_points:
            return {**parts, "kind": "iso", "surfaces": _with_normals(surfaces)}
        return {**parts, "kind": "outline", "outline": volume.outline()}
    if revolved and interactive:
        # Cut open by the plane y = 0 (a clip of a flat slice in that plane would leave nothing),
        # here for the first picture; the plane's widget cuts again where the user moves it.
        clipped = _plane_clip(volume, CUT_NORMAL, CUT_ORIGIN)
        _check(cancelled)
        return {**parts, "kind": "cut", "clipped": clipped, "surface": clipped.extract_surface(algorithm=None)}
    if revolved:
        # Only the surface is seen: extracted once here (add_mesh would redo it on every
        # render of the volume's ~10^5 cells; the same picture, 0.4 s less per figure).
        surface = volume.clip(normal="-y", origin=(0.0, 0.0, 0.0)).extract_surface(algorithm=None)
        cut, shell = _flat_faces(surface, _revolved_planes(mechanism, workspace_map.grid))
        return {**parts, "kind": "static", "shell": shell, "cut": cut}
    return {**parts, "kind": "flat"}


def _plane_clip(volume, normal, origin):
    """The part of ``volume`` on the side ``normal`` points to from the plane through ``origin``:
    what PyVista's ``add_mesh_clip_plane`` keeps (a table-based clip, not inside out)."""
    plane = vtkPlane()
    plane.SetNormal(*normal)
    plane.SetOrigin(*origin)
    clipper = vtkTableBasedClipDataSet()
    clipper.SetInputData(volume)
    clipper.SetClipFunction(plane)
    clipper.SetInsideOut(False)
    clipper.Update()
    return pv.wrap(clipper.GetOutput())


def clear_workspace_scene(plotter) -> None:
    """Remove a drawn workspace scene, a box map's or a slice's: its actors, colour bar and cut
    plane (the semi-dextrous layer is its own; the caller draws the axes and labels again)."""
    clear_clip_plane(plotter)
    for name in ("workspace", CUT_FACE_ACTOR, *BOX_ACTORS[1:]):
        plotter.remove_actor(name, reset_camera=False, render=False)
    if plotter.scalar_bars:
        plotter.remove_scalar_bar()


def show_workspace_parts(plotter, parts: dict, *, interactive: bool) -> None:
    """The actors of a 2D map's ``workspace_parts``, replacing the workspace scene drawn before (a
    box map's actors, a cut plane's widget and what it cut)."""
    clear_clip_plane(plotter) if interactive else None
    for name in BOX_ACTORS[1:]:
        plotter.remove_actor(name, reset_camera=False, render=False)
    plotter.remove_actor("workspace", reset_camera=False, render=False)
    plotter.remove_scalar_bar() if plotter.scalar_bars else None
    quantity, kind = parts["quantity"], parts["kind"]
    args = dict(scalars=quantity, scalar_bar_args=parts["bar"], name="workspace", reset_camera=False, render=False,
                **parts["colours"])
    if kind == "empty":
        return
    lit = True
    if kind == "iso":
        actor = plotter.add_mesh(parts["surfaces"], opacity=0.55, smooth_shading=True, **args)
        actor._isoforce_iso_surfaces = True     # its values are levels: labelled (``label_iso_surfaces``)
    elif kind == "outline":
        plotter.add_mesh(parts["outline"], color="black", name="workspace", render=False)
    elif kind == "cut":
        _add_cut_volume(plotter, parts, args)
    elif kind == "static":
        plotter.add_mesh(parts["shell"], lighting=lit, **args)
        if parts["cut"] is not None:
            # The cut face and the end faces at the base joint's limits are slices of the map:
            # unlit, so their colours are the bar's exactly (lit, they faced away from the key
            # light and read near black against the bar).
            plotter.add_mesh(parts["cut"], lighting=False, **{**args, "name": CUT_FACE_ACTOR, "show_scalar_bar": False})
    else:
        # A flat picture (a planar device's map, an unrevolved slice) seen square on: unlit, so
        # its colours are the key's exactly (shading darkened the top colour to olive).
        plotter.add_mesh(parts["volume"], lighting=False, **args)
    if QUANTITIES[quantity].categorical:
        _class_bar(plotter, parts["bar"]["title"])


def _add_cut_volume(plotter, parts: dict, args: dict) -> None:
    """The app's revolved slice cut open by a plane the user can move: PyVista's
    ``add_mesh_clip_plane`` with its first cut made already (``workspace_parts``, on a worker
    thread: cutting ~2 x 10^5 cells and taking the surface the mapper would take at the first
    render were 70-100 ms of the GUI thread) and the actor drawing that surface, not the cut solid.

    As PyVista's: an invisible outline of the whole volume (the camera frames the solid, not the
    half shown), the cut solid kept in ``plane_clipped_meshes`` (``clear_clip_plane``), a plane
    widget round the volume cutting again where it is released (on the GUI thread: the user's
    own gesture); its right-drag zooms the view instead of resizing the widget's box (which the
    axes are drawn on: ``volume_axes``).
    """
    volume, clipped = parts["volume"], parts["clipped"]
    args = dict(args)
    args.setdefault("clim", volume.get_data_range(parts["quantity"]))      # the whole solid's, as PyVista's
    plotter.add_mesh(volume.outline(), name="workspace-outline", opacity=0.0, reset_camera=False, render=False)
    owner = getattr(plotter, "widgets", plotter)         # (``Plotter.widgets`` from PyVista 0.48)
    owner.plane_clipped_meshes.append(clipped)
    actor = plotter.add_mesh(parts["surface"], **args)
    actor._isoforce_dataset = actor.mapper.dataset
    actor._isoforce_cut_volume = volume         # what the plane cuts (held by its callback too)

    def cut_again(normal, origin) -> None:
        cut = _plane_clip(volume, normal, origin)
        clipped.shallow_copy(cut)
        actor._isoforce_dataset.copy_from(cut.extract_surface(algorithm=None))

    plotter.add_plane_widget(cut_again, normal=CUT_NORMAL, origin=CUT_ORIGIN, bounds=volume.bounds, factor=1.25,
                             test_callback=False, interaction_event="end")
    owner.plane_widgets[-1].SetScaleEnabled(False)
