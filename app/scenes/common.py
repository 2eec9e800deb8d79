"""What the scenes draw with: actors found by name and redrawn cheaply, points lifted to 3D.

Scenes add named actors to a plotter (``name=`` replaces an actor rather than piling up a
new one on every redraw) and look them up by name (``actor_named``). A redraw is cheap when
little changed (a slider step redraws the pose view many times a second): an actor drawn
through ``_show`` keeps its mapper and properties and gets only new geometry, or nothing at
all when the numbers it is made from are unchanged (``_key``); spheres, discs and arrows are
placed copies of unit meshes made once (``_unit_mesh``, ``_placed``).

The underscored helpers are for this package's scene modules, not for callers outside it.
"""
from __future__ import annotations

import functools

import numpy as np
import pyvista as pv
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import VTK_DOUBLE


def to_3d(points: np.ndarray) -> np.ndarray:
    """Rows of 2 or 3 coordinates as rows of 3 (z = 0 for planar mechanisms), shape (N, 3)."""
    pts = np.atleast_2d(np.asarray(points, float))
    if pts.shape[-1] == 3:
        return pts
    out = np.zeros(pts.shape[:-1] + (3,))
    out[..., : pts.shape[-1]] = pts
    return out


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


def _key(*values) -> bytes:
    """The numbers a mesh is made from, as one comparable value."""
    return b"|".join(np.ascontiguousarray(v, dtype=float).tobytes() for v in values)


def _show(plotter, name: str, make, inputs: bytes | None, *, placed=None, **look) -> None:
    """Draw the mesh ``make()`` as actor ``name`` with ``add_mesh`` options ``look``.

    ``add_mesh`` makes a new actor, mapper and property (milliseconds each, a dozen actors
    per pose). An actor made here with the same ``look`` is kept: with the same ``inputs``
    nothing is done, else only its geometry is replaced (``inputs=None``: always replaced).
    ``placed = (kind, detail, points)``: the mesh is a placed copy of that unit mesh
    (``_placed``), or any mesh whose cells (and normals, if any) ``kind`` and ``detail`` fix (a
    polytope of the same faces); an actor showing one of the same kind and detail gets
    ``points()`` alone (its cells are those already), not a copy of a whole new mesh.
    """
    actor = actor_named(plotter, name)
    tag = getattr(actor, "_isoforce_tag", None)
    unit = tuple(placed[:2]) if placed is not None else None
    if tag is not None and tag[0] == look:
        if inputs is None or tag[1] != inputs:
            if unit is not None and tag[2] == unit:
                _set_points(actor._isoforce_dataset, placed[2]())
            else:
                actor._isoforce_dataset.copy_from(make())
            actor._isoforce_tag = (look, inputs, unit)
        return
    actor = plotter.add_mesh(make(), name=name, reset_camera=False, render=False, **look)
    actor._isoforce_tag = (look, inputs, unit)
    # The mesh the actor's pipeline starts from, for new geometry: ``actor.mapper.dataset``
    # says so only while pyvista's Python mapper object lives (the plotter keeps the last
    # mesh's only), else it is the end of a scalars pipeline, remade from the old mesh.
    actor._isoforce_dataset = actor.mapper.dataset


@functools.lru_cache(maxsize=None)
def _unit_mesh(kind: str, detail: float) -> pv.PolyData:
    """Unit meshes placed by copies: sphere (resolution), circle (resolution), arrow along x (shaft)."""
    if kind == "sphere":
        return pv.Sphere(radius=1.0, theta_resolution=int(detail), phi_resolution=int(detail))
    if kind == "circle":
        return pv.Circle(radius=1.0, resolution=int(detail))
    return pv.Arrow(start=(0.0, 0.0, 0.0), direction=(1.0, 0.0, 0.0), scale=1.0, tip_length=0.2,
                    tip_radius=0.06, shaft_radius=detail)


@functools.lru_cache(maxsize=None)
def _unit_points(kind: str, detail: float) -> np.ndarray:
    """``_unit_mesh(kind, detail).points`` as a plain read-only array of the same dtype, made once
    (pyvista's ``points`` wraps the VTK array anew on each call: a slider step placed a dozen)."""
    points = np.array(_unit_mesh(kind, detail).points)
    points.flags.writeable = False
    return points


def _set_points(mesh: pv.PolyData, points) -> None:
    """``mesh.points = points`` (as float64): written into the mesh's own float64 array of as many
    points when it has one (pyvista's setter makes a new VTK array each time), else set."""
    points = np.asarray(points, float)
    vtk_points = mesh.GetPoints()
    if (vtk_points is not None and vtk_points.GetDataType() == VTK_DOUBLE
            and vtk_points.GetNumberOfPoints() == len(points) and points.ndim == 2 and points.shape[1] == 3):
        vtk_to_numpy(vtk_points.GetData())[...] = points
        vtk_points.GetData().Modified()
        vtk_points.Modified()
    else:
        mesh.points = points


def _placed(kind: str, detail: float, points) -> pv.PolyData:
    """A copy of a unit mesh (never sharing its arrays) with new points (the normals kept)."""
    mesh = _unit_mesh(kind, detail).copy(deep=True)
    mesh.points = np.asarray(points, float)
    return mesh
