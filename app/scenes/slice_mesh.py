"""A 2D map's samples as the workspace scene's mesh, and the values it shows at its edge.

``_slice_mesh`` puts a map's (two axes') coordinates in 3D: the Inverse3's (x, z) slice revolved
over its base joint (``is_revolved``), else flat in the map's plane; ``_on_mesh`` lays samples
out as its point data. ``_index_box`` crops a map to its feasible samples' box, ``_cell_edges``
gives the cells centred on samples, and ``_edge_filled`` gives the samples just outside the
workspace their nearest feasible neighbour's value (where a clipped slice or volume shows
them), so that a cut cell is coloured by feasible values only.

The underscored helpers are for this package's scene modules, not for callers outside it.
"""
from __future__ import annotations

import itertools

import numpy as np
import pyvista as pv


def is_revolved(mechanism, grid) -> bool:
    """Whether the workspace view revolves the map: an (x, z) slice of a model with a ``revolution``
    (the Inverse3's, over its base joint).

    Other spatial devices mapped on a slice (the PHANToM family's y = 0 plane) are drawn as
    the flat slice they are: their quantities are not claimed invariant under the base joint
    (a side mounting's gravity is not).
    """
    return set(grid.axes) == {"x", "z"} and mechanism.revolution is not None


def _slice_mesh(coords, mechanism, grid, angles: int, span: tuple[int, int] | None = None) -> pv.StructuredGrid:
    """The structured grid whose points are ``coords`` (two 1D arrays, m, along the map's axes):
    revolved over the base joint's range in ``angles`` steps (``is_revolved``), else flat in
    the map's plane. Points in VTK's order: the map's first axis fastest (for a revolved
    slice: x, then z, then the angle). ``span`` ``(first, last)``: a revolved slice's angles
    ``first`` to ``last`` of the ``angles`` only, the same points as those of the whole."""
    if is_revolved(mechanism, grid):
        lo, hi, offset = mechanism.revolution
        theta = np.linspace(lo, hi, angles)
        u = coords[grid.axes.index("x")]
        z = coords[grid.axes.index("z")]
        c = dict(grid.fixed).get("y", offset)
        # The points of meshgrid(u, z, theta, indexing="ij") in VTK's order (u fastest, theta
        # slowest), written once into one (N, 3) array: StructuredGrid(x, y, z) of the meshgrid
        # made the same points through five full-size temporaries. A span's sines and cosines
        # are taken from the whole range's (a vectorised cosine may round a shorter array otherwise).
        cos, sin = np.cos(theta)[:, None, None], np.sin(theta)[:, None, None]
        if span is not None:
            cos, sin = cos[span[0]:span[1] + 1], sin[span[0]:span[1] + 1]
            angles = span[1] - span[0] + 1
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


def _cell_edges(c: np.ndarray) -> np.ndarray:
    """The edges (n + 1,) of the cells centred at the evenly spaced samples ``c`` (n,), n >= 2:
    midway between neighbours, half a step beyond the outer ones (``map_marks.grid_extent``).

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


def _index_box(ok: np.ndarray) -> tuple[slice, ...]:
    """Slices of the smallest box holding every True of ``ok`` (2D, not all False), one more each side."""
    box = []
    for axis in range(ok.ndim):
        hit = np.flatnonzero(ok.any(axis=1 - axis))
        box.append(slice(max(int(hit[0]) - 1, 0), int(hit[-1]) + 2))
    return tuple(box)


#: Passes of the binomial filter [1, 4, 6, 4, 1] / 16 along each axis that smooth the feasibility
#: indicator whose one-half crossing is the workspace's edge (``_edge_field``): each pass adds a
#: variance of one sample step squared, so two give a blur of about 1.4 steps, wide enough that
#: a stair of samples along a slanted edge crosses one half on a straight line.
EDGE_SMOOTHING_PASSES = 2
#: How far from one half ``_edge_field`` keeps every sample on its own side (0 < margin < 0.5).
EDGE_MARGIN = 0.05


def _edge_field(ok: np.ndarray) -> np.ndarray:
    """The field whose one-half crossing, interpolated linearly, is a 2D slice's workspace edge.

    Parameters
    ----------
    ok : ndarray of bool, shape (n0, n1)
        The feasible samples.

    Returns
    -------
    ndarray, shape (n0, n1)
        The indicator of ``ok`` smoothed (``EDGE_SMOOTHING_PASSES``, the grid's border
        replicated), then held at least ``EDGE_MARGIN`` above one half at every feasible sample
        and as far below at every other.

    Notes
    -----
    The 0/1 indicator itself crosses one half at the middle of every edge between a feasible
    and an infeasible sample: a slanted edge becomes a terrace of flat and 45-degree steps,
    which the revolved Inverse3 slice turns into rings of light and shade. The smoothed field
    places each crossing where a blurred edge would, and the margin keeps the crossing on the
    same edges as before: every sample stays on its own side (a one-sample hole or spur is
    kept as the samples say), and only cells with a feasible corner are ever drawn.

    Examples
    --------
    >>> ok = np.array([[True, True, False], [True, False, False]])
    >>> field = _edge_field(ok)
    >>> bool(np.all((field > 0.5) == ok))
    True
    """
    field = ok.astype(float)
    weights = np.array([1.0, 4.0, 6.0, 4.0, 1.0]) / 16.0
    for _ in range(EDGE_SMOOTHING_PASSES):
        for axis in range(field.ndim):
            padded = np.moveaxis(np.pad(np.moveaxis(field, axis, 0), [(2, 2)] + [(0, 0)] * (field.ndim - 1),
                                        mode="edge"), 0, axis)
            n = field.shape[axis]
            field = sum(w * np.take(padded, np.arange(k, k + n), axis=axis) for k, w in enumerate(weights))
    return np.where(ok, np.maximum(field, 0.5 + EDGE_MARGIN), np.minimum(field, 0.5 - EDGE_MARGIN))


def _neighbours(ndim: int) -> list[tuple[int, ...]]:
    """The 3**ndim - 1 neighbours (index offsets) of a sample, nearest first, and among equally
    near ones in the order in which ``scipy.ndimage.distance_transform_edt`` picks its feature
    (the offsets read last axis first, ascending; found by placing two features, for 2 and 3 axes)."""
    offsets = [o for o in itertools.product((-1, 0, 1), repeat=ndim) if any(o)]
    return sorted(offsets, key=lambda o: (sum(k * k for k in o), o[::-1]))


def _edge_filled(values: np.ndarray) -> np.ndarray:
    """``values`` with each non-finite sample next to a finite one given its nearest finite
    sample's value, as ``scipy.ndimage.distance_transform_edt`` would pick it, without scipy.

    Parameters
    ----------
    values : ndarray, shape (n0, n1) or (n0, n1, n2)
        Samples of a quantity; non-finite ones are outside the workspace.

    Returns
    -------
    ndarray, the shape of ``values``
        ``values`` with each non-finite sample that has a finite one among its 3**ndim - 1
        neighbours given the nearest one's value, ties broken as ``distance_transform_edt``
        breaks them (with 2 or 3 axes the nearest finite sample of such a sample is one of its
        neighbours: any other is at least 2 samples away, a neighbour at most sqrt(3)). The
        other non-finite samples are nan.

    Notes
    -----
    The workspace scenes keep only the cells with a finite corner, clipped where the
    interpolated feasibility crosses one half: every corner of those cells is a neighbour of a
    finite sample, and no other sample reaches the picture. Importing ``scipy.ndimage`` for
    the exact transform would cost the ``figure`` command about 0.15 s of its 1 s.

    Examples
    --------
    >>> _edge_filled(np.array([[1.0, np.nan, np.nan, np.nan], [np.nan, 2.0, np.nan, np.nan]]))
    array([[ 1.,  1.,  2., nan],
           [ 1.,  2.,  2., nan]])
    """
    values = np.asarray(values, float)
    if values.ndim not in (2, 3):
        raise ValueError(f"values: 2 or 3 axes expected, got shape {values.shape}")
    ok = np.isfinite(values)
    if ok.all() or not ok.any():
        return values
    padded = np.pad(np.where(ok, values, np.nan), 1, constant_values=np.nan)
    inner = tuple(slice(1, 1 + n) for n in values.shape)
    out = padded[inner].copy()
    # The least preferred neighbour first: each later one overwrites it where it is finite.
    for offset in reversed(_neighbours(values.ndim)):
        near = padded[tuple(slice(1 + k, 1 + k + n) for k, n in zip(offset, values.shape))]
        take = ~ok & np.isfinite(near)
        out[take] = near[take]
    return out
