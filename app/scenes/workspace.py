"""The workspace scene: a workspace map's quantity drawn over the workspace in 3D.

A 2D map (``draw_workspace``, ``workspace_volume``) is the Inverse3's (x, z) slice revolved
over its base joint, cut open by a plane or drawn as iso-surfaces (``WORKSPACE_MODES``), or
a planar mechanism's map as a flat surface. A 3D box map (``draw_box_workspace``,
``box_scene_parts``) is its boundary, iso-surfaces of the quantity (``iso_levels``) and the
plane the map view shows, the contours smoothed (Taubin) so that they show no voxel
terraces. The values on the iso-surfaces and the axes in mm are ``app.scenes.iso_labels``.

A categorical quantity (the bottleneck actuator, the singularity class) is drawn as the map
view draws it: each sample's class over the cell around it, in the map's class colours, with a
key of the map's class names (``class_key``, ``class_lookup_table``), not a bar of codes.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pyvista as pv

from metrics.quantities import QUANTITIES

from ..display_units import display_unit
from ..figures import colour_limits, colour_scale, log_colours
from .common import actor_named

#: The 3D workspace view draws at most this many map points per axis.
WORKSPACE_MAX_POINTS = 160


def is_revolved(mechanism, grid) -> bool:
    """Whether the workspace view revolves the map: the Inverse3's (x, z) slice over its base joint.

    Other spatial devices mapped on a slice (the PHANToM family's y = 0 plane) are drawn as
    the flat slice they are: their quantities are not claimed invariant under the base joint
    (a side mounting's gravity is not).
    """
    return len(grid.axes) == 2 and mechanism.task_dim == 3 and hasattr(mechanism.params, "plane_offset")


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
                     angles: int = 72, key: dict | None = None) -> pv.DataSet:
    """A 3D dataset of the workspace coloured by ``quantity``, infeasible cells removed.

    Inverse3: the (x, z) slice at theta_0 = 0 revolved over the base joint's range (every
    quantity is invariant under the base rotation, which only rotates J's rows). Planar
    mechanisms: the map itself as a flat surface. The slice is subsampled to at most
    ``max_points`` per axis: the 3D view shows the shape, the map view the detail.

    A magnitude is point data at the samples. The workspace's edge is cut where feasibility,
    interpolated linearly between the samples, crosses one half (``clip_scalar``), so it is a
    smooth surface, not the staircase of whole cells; the values at infeasible samples next to
    it are their nearest feasible sample's, so the cut cells are coloured by feasible values only.

    A categorical quantity (``key``: its ``class_key``, made from the map if not given) is cut
    the same way but is cell data, each cell the class index of its nearest sample, as the map
    view draws a class map: see ``_class_cells``.
    """
    grid = workspace_map.grid
    if QUANTITIES[quantity].categorical:
        index = (class_key(workspace_map, quantity, mechanism) if key is None else key)["to_data"](
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
    mesh = _slice_mesh(coords, mechanism, grid, angles)
    mesh.point_data[quantity] = _on_mesh(vals, mechanism, grid, angles)
    if none:
        return mesh
    mesh.point_data["feasible"] = _on_mesh(ok.astype(float), mechanism, grid, angles)
    if every:
        return mesh.cast_to_unstructured_grid()
    return mesh.clip_scalar(scalars="feasible", value=0.5, invert=False)


def _slice_mesh(coords, mechanism, grid, angles: int) -> pv.StructuredGrid:
    """The structured grid whose points are ``coords`` (two 1D arrays, m, along the map's axes):
    revolved over the base joint's range in ``angles`` steps (``is_revolved``), else flat in
    the map's plane. Points in VTK's order: the map's first axis fastest (for a revolved
    slice: x, then z, then the angle)."""
    if is_revolved(mechanism, grid):
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
        return mesh
    a, b = coords[0], coords[1]
    aa, bb = np.meshgrid(a, b, indexing="ij")
    pts = np.zeros(aa.shape + (3,))
    names = mechanism.task_names
    pts[..., names.index(grid.axes[0]) if grid.axes[0] in names else 0] = aa
    pts[..., names.index(grid.axes[1]) if grid.axes[1] in names else 1] = bb
    return pv.StructuredGrid(pts[..., 0][..., None], pts[..., 1][..., None], pts[..., 2][..., None])


#: How near (sample steps, along each axis) the centre of a class cell's piece is to its nearest
#: sample when the piece stands for that sample: its whole cell is centred on it (0), a piece
#: at the grid's edge a sixth of a step off; the triangles that cut a step of the workspace's
#: edge diagonally are a third of a step off their sample. A quarter tells them apart.
HOLE_CENTRE = 0.25


def _class_cells(vals, ok, coords, quantity: str, mechanism, grid, angles: int) -> pv.UnstructuredGrid:
    """``workspace_volume`` of a categorical quantity: the map view's cells, one centred on each
    sample, cut along a smooth edge; cell data ``quantity`` the class index (float) of the sample
    nearest each cell's centre.

    A class is drawn as the map view draws it, each sample's own colour over the cell around it
    (nearest sample), never a colour between two classes: point data would be interpolated
    across each cell (a texture lookup of the interpolated index passes through every class
    between the two indices; ``interpolate_before_map=False`` blends the two colours). The edge
    is cut where the share of classed samples among a cell corner's four neighbours, interpolated
    along the cell edges, crosses one half: along a straight run of cells that is their outer
    edge, as in the map view; at a step it is a diagonal, not a staircase. A cut cell takes the
    class of the sample nearest its centre, or, when that sample has no class, of the nearest
    sample with one (``_edge_filled``). Centres are found in sample indices: index fields carried
    as point data through the cut (linear along each edge, as the indices are) and averaged
    over each cell's points.
    """
    if ok.any() and not ok.all():
        box = _index_box(ok)
        vals, ok = vals[box], ok[box]
        coords = [c[b] for c, b in zip(coords, box)]
    mesh = _slice_mesh([_cell_edges(c) for c in coords], mechanism, grid, angles)
    corners = np.meshgrid(*(np.arange(n + 1) - 0.5 for n in vals.shape), indexing="ij")
    for k, along in enumerate(corners):
        mesh.point_data[f"index{k}"] = _on_mesh(along, mechanism, grid, angles)
    if not ok.any():
        return mesh.extract_cells([])
    around = np.pad(ok.astype(float), 1, mode="edge")         # beyond the box: as its border
    share = 0.25 * (around[:-1, :-1] + around[1:, :-1] + around[:-1, 1:] + around[1:, 1:])
    mesh.point_data["feasible"] = _on_mesh(share, mechanism, grid, angles)
    cut = mesh.clip_scalar(scalars="feasible", value=0.5, invert=False)
    centres = cut.point_data_to_cell_data(pass_point_data=False).cell_data
    at = [centres[f"index{k}"] for k in range(vals.ndim)]
    nearest = tuple(np.clip(np.rint(c).astype(np.intp), 0, n - 1) for c, n in zip(at, vals.shape))
    classes = _edge_filled(np.where(ok, vals, np.nan))[nearest]
    # A sample without a class inside the workspace (a hole, a crack one sample wide, a notch)
    # keeps every corner of its cell at a share of one half or more: its cell, centred on it, is
    # left out, as the map view leaves it blank; the diagonal cuts of the edge's steps stay.
    centred = np.max([np.abs(c - n) for c, n in zip(at, nearest)], axis=0) < HOLE_CENTRE
    classes[centred & ~ok[nearest]] = np.nan
    cut.clear_data()
    cut.cell_data[quantity] = classes
    return cut.extract_cells(np.flatnonzero(np.isfinite(classes)), pass_cell_ids=False, pass_point_ids=False)


def _cell_edges(c: np.ndarray) -> np.ndarray:
    """The edges (n + 1,) of the cells centred at the evenly spaced samples ``c`` (n,), n >= 2:
    midway between neighbours, half a step beyond the outer ones (``figures.grid_extent``).

    >>> _cell_edges(np.array([0.0, 1.0, 2.0]))
    array([-0.5,  0.5,  1.5,  2.5])
    """
    half = 0.5 * (c[1] - c[0])
    return np.concatenate([[c[0] - half], 0.5 * (c[:-1] + c[1:]), [c[-1] + half]])


def _on_mesh(values: np.ndarray, mechanism, grid, angles: int) -> np.ndarray:
    """``values`` (n0, n1) at the points of ``_slice_mesh`` of n0 x n1 coordinates, shape (N,)."""
    if is_revolved(mechanism, grid):
        ordered = values if grid.axes.index("x") == 0 else values.T
        return np.tile(ordered.ravel(order="F"), angles)
    return values.ravel(order="F")


def class_key(workspace_map, quantity: str, mechanism) -> dict:
    """The map view's key of a categorical quantity over ``workspace_map``: its classes, their
    colours and names (``app.figures.colour_scale`` of the map's values, as the map view and
    the exported map make it; the bottleneck's classes named by ``mechanism``'s joints).

    Returns
    -------
    dict
        A ``colour_scale``: ``to_data(values, feasible)`` gives each point's class index, masked
        where it has none; ``cmap`` the classes' colours by index; ``kind[2]`` their names.
    """
    # ``colour_scale`` names the classes from a preset's mechanism (``figures._category_names``);
    # the scenes hold the mechanism itself.
    named = SimpleNamespace(mechanism=mechanism)
    return colour_scale(quantity, named, [(workspace_map.values[quantity], workspace_map.feasible)])


def class_lookup_table(key: dict, *, nan_opacity: float = 1.0) -> pv.LookupTable:
    """A VTK lookup table of ``class_key``'s classes: class index i (0, 1, ...) in class i's colour.

    The colours are the map's bytes (``cmap(i, bytes=True)``, as ``app.map_picture`` colours
    the map). Each index is annotated with its class's name (the map's, without the map bar's
    counts of points) and the lookup is indexed: the scalar bar is a row of named swatches, and
    a value that is no index takes the nan colour (white, ``nan_opacity``). The scalar range,
    -0.5 to k - 0.5, centres each class's colour on its index in a bar drawn over it.
    """
    names = key["kind"][2]          # ``figures._categorical_scale``: the classes' names in index order
    k = len(names)
    lut = pv.LookupTable()
    lut.values = key["cmap"](np.arange(k), bytes=True)
    lut.scalar_range = (-0.5, k - 0.5)
    lut.annotations = {float(i): name for i, name in enumerate(names)}
    lut.SetIndexedLookup(True)
    lut.SetNanColor(1.0, 1.0, 1.0, nan_opacity)
    return lut


def class_names(plotter, name: str) -> tuple[str, ...] | None:
    """The class names of actor ``name``'s key in index order (``class_lookup_table``), or None
    when it is not coloured by classes."""
    actor = actor_named(plotter, name)
    lut = getattr(getattr(actor, "mapper", None), "lookup_table", None)
    if lut is None or not lut.GetIndexedLookup():
        return None
    # VTK's own accessors: pyvista's ``annotations`` reads past the end of the array on VTK 9.7.
    values = [lut.GetAnnotatedValue(i).ToFloat() for i in range(lut.GetNumberOfAnnotatedValues())]
    names = [lut.GetAnnotation(i) for i in range(lut.GetNumberOfAnnotatedValues())]
    return tuple(name for _, name in sorted(zip(values, names)))


def _class_bar(plotter, title: str) -> None:
    """The scalar bar ``title`` of a class key (``class_lookup_table``) with its names above the
    swatches and its title under them: VTK puts annotations on the far side from the title, and
    under a bar at the view's foot they fell outside the view."""
    bar = plotter.scalar_bars[title]
    bar.SetTextPositionToPrecedeScalarBar()


def _index_box(ok: np.ndarray) -> tuple[slice, ...]:
    """Slices of the smallest box holding every True of ``ok`` (2D, not all False), one more each side."""
    box = []
    for axis in range(ok.ndim):
        hit = np.flatnonzero(ok.any(axis=1 - axis))
        box.append(slice(max(int(hit[0]) - 1, 0), int(hit[-1]) + 2))
    return tuple(box)


#: The workspace colour bar's place (right of the axes triad's corner, 0 to 0.2 of the width) and labels
#: (three: a narrow view has room for no more).
BAR_LOOK = {"position_x": 0.22, "position_y": 0.03, "width": 0.72, "n_labels": 3, "fmt": "%.3g"}
#: A categorical quantity's bar (``class_lookup_table``): a swatch per class with its name, no numbers.
CLASS_BAR_LOOK = {**BAR_LOOK, "n_labels": 0}
#: Share of a lit class picture's light that is ambient (the rest diffuse, no highlights): enough
#: shading to show a revolved solid's shape, little enough that each class keeps its hue and lightness.
CLASS_AMBIENT = 0.6
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
    if log_colours(quantity) and lo > 0:
        return np.geomspace(lo, hi, count)
    return np.linspace(lo, hi, count)


def box_scene_parts(workspace_map, quantity: str, slice_axis: str, slice_value: float, *,
                    cache: dict | None = None, mechanism=None) -> dict:
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
    """
    if cache is not None and cache.get("map") is workspace_map and cache.get("quantity") == quantity:
        volume = cache["volume"]
    else:
        volume = _box_volume_parts(workspace_map, quantity, mechanism)
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
    plane = (image if volume["cells"] is None else volume["cells"]).slice(normal=slice_axis, origin=origin)
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


def colour_range(workspace_map, quantity: str) -> tuple[tuple[float, float] | None, bool, bool]:
    """The map view's colour scale of ``quantity``, for the 3D views to colour by the same key.

    ``app.figures.colour_limits`` over the map's feasible finite values in display units (the
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


def _class_image(workspace_map, quantity: str, key: dict) -> pv.ImageData:
    """A 3D box map's class indices (``class_key``) as cell data of ``pyvista.ImageData``: one cell
    centred at each sample (m; nan where the sample has no class), the axes x, y, z as ``box_image``."""
    grid = workspace_map.grid
    order = [grid.axes.index(a) for a in ("x", "y", "z")]
    index = key["to_data"](workspace_map.values[quantity], workspace_map.feasible)
    values = np.ma.filled(index.astype(float), np.nan)
    spacing = tuple(grid.spacing()[k] for k in order)
    image = pv.ImageData(dimensions=tuple(grid.resolution[k] + 1 for k in order), spacing=spacing,
                         origin=tuple(grid.lower[k] - 0.5 * h for k, h in zip(order, spacing)))
    image.cell_data[quantity] = np.transpose(values, order).ravel(order="F")
    return image


def _box_volume_parts(workspace_map, quantity: str, mechanism=None) -> dict:
    """What ``box_scene_parts`` draws that does not depend on the plane: image, boundary, surfaces."""
    node = QUANTITIES[quantity]
    image = box_image(workspace_map, quantity)
    values = image.point_data[quantity]
    hull = (_smoothed(image.contour([0.5], scalars="feasible", method="flying_edges"))
            if np.any(image.point_data["feasible"]) else None)
    levels = np.empty(0) if node.categorical else iso_levels(values, quantity)
    surfaces = _iso_surfaces(image, quantity, levels) if levels.size else None
    clim, log, capped = colour_range(workspace_map, quantity)
    key = class_key(workspace_map, quantity, mechanism) if node.categorical else None
    cells = _class_image(workspace_map, quantity, key) if node.categorical else None
    return {"image": image, "hull": hull, "surfaces": surfaces, "levels": levels, "clim": clim, "log": log,
            "capped": capped, "key": key, "cells": cells}


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
    parts = box_scene_parts(workspace_map, quantity, slice_axis, slice_value, cache=cache, mechanism=mechanism)
    unit = f" {display_unit(quantity)[0]}" if node.unit else ""
    plane = plotter.actors.get("box_plane")
    if same_volume and plane is not None:
        plane.mapper.dataset.copy_from(parts["plane"])      # only the plane moved: new geometry, same look
    else:
        _draw_box_volume(plotter, parts, quantity)
    # Short lines: the caption shares the view's top edge with its "Reset view" button.
    if parts["levels"].size:
        levels = ", ".join(f"{v:.3g}" for v in parts["levels"])
        first = f"iso-surfaces of {node.label.lower()}\nat {levels}{unit}"
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
        actor = plotter.add_mesh(surfaces, scalars=quantity, opacity=0.5, smooth_shading=True, name="workspace",
                                 show_scalar_bar=False, **look)
        actor._isoforce_iso_surfaces = True         # its values are levels: labelled (``label_iso_surfaces``)
    else:
        plotter.remove_actor("workspace", reset_camera=False, render=False)
    plotter.add_mesh(parts["plane"], scalars=quantity, nan_opacity=0.0, name="box_plane",
                     scalar_bar_args={"title": title, **(CLASS_BAR_LOOK if node.categorical else BAR_LOOK)},
                     **look)
    if node.categorical:
        _class_bar(plotter, title)


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
    key = class_key(workspace_map, quantity, mechanism) if node.categorical else None
    volume = workspace_volume(workspace_map, quantity, mechanism, key=key)
    clim, log, capped = colour_range(workspace_map, quantity)      # the map view's key
    bar = {"title": bar_title(quantity, clim, capped), **(CLASS_BAR_LOOK if node.categorical else BAR_LOOK)}
    # Classes: the map's class colours on cells (``workspace_volume``). Where the picture is 3D (the
    # revolved slice) they are lit mostly by ambient light: full shading would darken them into
    # colours of no class, none at all flattened the solid into two cut-outs.
    colours = (dict(cmap=class_lookup_table(key), ambient=CLASS_AMBIENT, diffuse=1.0 - CLASS_AMBIENT,
                    specular=0.0) if node.categorical else dict(cmap="viridis", clim=clim, log_scale=log))
    lit = True
    args = dict(scalars=quantity, scalar_bar_args=bar, name="workspace", reset_camera=False, render=False,
                **colours)
    if volume.n_cells == 0:
        return
    if mode == "iso-surfaces" and mechanism.task_dim == 3 and not node.categorical:
        lo, hi = np.nanpercentile(volume.point_data[quantity], [10, 90])
        surfaces = volume.cell_data_to_point_data().contour(isosurfaces=np.linspace(lo, hi, 4), scalars=quantity)
        if surfaces.n_points:
            actor = plotter.add_mesh(surfaces, opacity=0.55, smooth_shading=True, **args)
            actor._isoforce_iso_surfaces = True     # its values are levels: labelled (``label_iso_surfaces``)
        else:
            plotter.add_mesh(volume.outline(), color="black", name="workspace", render=False)
    elif is_revolved(mechanism, workspace_map.grid):
        # Cut open by the plane y = 0 (a clip of a flat slice in that plane would leave nothing).
        if interactive:
            plotter.add_mesh_clip_plane(volume, normal="-y", origin=(0.0, 0.0, 0.0), lighting=lit, **args)
        else:
            # Only the surface is seen: extracted once here (add_mesh would redo it on every
            # render of the volume's ~10^5 cells; the same picture, 0.4 s less per figure).
            plotter.add_mesh(volume.clip(normal="-y", origin=(0.0, 0.0, 0.0)).extract_surface(algorithm=None),
                             lighting=lit, **args)
    else:
        # A flat picture (a planar device's map, an unrevolved slice) seen square on: unlit, so
        # its colours are the key's exactly (shading darkened the top colour to olive).
        plotter.add_mesh(volume, lighting=False, **args)
    if node.categorical:
        _class_bar(plotter, bar["title"])
