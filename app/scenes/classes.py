"""Classes (the bottleneck actuator, the singularity class) in the workspace scene, as the map view draws them.

Each sample's class over the cell around it (nearest sample), never a colour between two
classes, in the map's class colours, with a key of the map's class names (``class_key``,
``class_lookup_table``, ``class_names``), not a bar of codes: ``_class_cells`` for a 2D map's
picture, ``_class_image`` for a 3D box map's plane.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pyvista as pv

from app.logic.colour_scale import colour_scale
from app.scenes.common import actor_named
from app.scenes.slice_mesh import _cell_edges, _edge_filled, _index_box, _on_mesh, _slice_mesh

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
    if cut.n_cells == 0:            # only lone classed samples: no corner reaches one half
        return mesh.extract_cells([])
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


def class_key(workspace_map, quantity: str, mechanism) -> dict:
    """The map view's key of a categorical quantity over ``workspace_map``: its classes, their
    colours and names (``app.logic.colour_scale.colour_scale`` of the map's values, as the map view and
    the exported map make it; the bottleneck's classes named by ``mechanism``'s joints).

    Returns
    -------
    dict
        A ``colour_scale``: ``to_data(values, feasible)`` gives each point's class index, masked
        where it has none; ``cmap`` the classes' colours by index; ``kind[2]`` their names.
    """
    # ``colour_scale`` names the classes from a preset's mechanism (``colour_scale.category_names``);
    # the scenes hold the mechanism itself.
    named = SimpleNamespace(mechanism=mechanism)
    return colour_scale(quantity, named, [(workspace_map.values[quantity], workspace_map.feasible)])


def class_lookup_table(key: dict, *, nan_opacity: float = 1.0) -> pv.LookupTable:
    """A VTK lookup table of ``class_key``'s classes: class index i (0, 1, ...) in class i's colour.

    The colours are the map's bytes (``cmap(i, bytes=True)``, as ``app.logic.map_picture`` colours
    the map). Each index is annotated with its class's name (the map's, without the map bar's
    counts of points) and the lookup is indexed: the scalar bar is a row of named swatches, and
    a value that is no index takes the nan colour (white, ``nan_opacity``). The scalar range,
    -0.5 to k - 0.5, centres each class's colour on its index in a bar drawn over it.
    """
    names = key.kind[2]          # ``colour_scale._categorical_scale``: the classes' names in index order
    k = len(names)
    lut = pv.LookupTable()
    lut.values = key.lut_bytes[:k]
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


def _class_image(workspace_map, quantity: str, key: dict) -> pv.ImageData:
    """A 3D box map's class indices (``class_key``) as cell data of ``pyvista.ImageData``: one cell
    centred at each sample (m; nan where the sample has no class), the axes x, y, z as ``box_image``."""
    grid = workspace_map.grid
    order = [grid.axes.index(a) for a in ("x", "y", "z")]
    index = key.to_data(workspace_map.values[quantity], workspace_map.feasible)
    values = np.ma.filled(index.astype(float), np.nan)
    spacing = tuple(grid.spacing()[k] for k in order)
    image = pv.ImageData(dimensions=tuple(grid.resolution[k] + 1 for k in order), spacing=spacing,
                         origin=tuple(grid.lower[k] - 0.5 * h for k, h in zip(order, spacing)))
    image.cell_data[quantity] = np.transpose(values, order).ravel(order="F")
    return image
