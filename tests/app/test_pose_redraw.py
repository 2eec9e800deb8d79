"""A slider step redraws the pose scene in place (``scenes.common._show``: an actor keeps its
mapper and gets new points, or a new mesh): what it shows is what a scene drawn afresh for the
new design shows, mesh for mesh, bit for bit (the exported figure draws afresh; the app redraws)."""
from __future__ import annotations

import numpy as np
import pytest
from vtkmodules.util.numpy_support import vtk_to_numpy

from app.logic.glyphs import DEFAULT_GLYPHS, pose_parts
from app.render.views import _plotter
from app.scenes import pose as pose_scene
from metrics.pose import analyse_pose
from resources import load_preset

ALL_GLYPHS = ("links", "polytope", "sphere", "force_ellipsoid", "velocity_ellipsoid", "inertia_ellipsoid",
              "reference_forces", "desired_force")
NO_POLYTOPE = ("links", "sphere", "force_ellipsoid", "velocity_ellipsoid", "inertia_ellipsoid", "reference_forces")


def _draw(plotter, mechanism, pose, glyphs, desired):
    report = analyse_pose(mechanism, np.asarray(pose, float), parts=pose_parts(glyphs))
    pose_scene.draw_pose_scene(plotter, mechanism, report, glyphs, desired, pose_scene.pose_scale(mechanism, report))


def _meshes(plotter) -> dict:
    """Per named actor: its mesh's points, cells (lines, polygons, strips) and normals, and its look."""
    out = {}
    for name, actor in plotter.actors.items():
        mapper = getattr(actor, "mapper", None)
        if mapper is None or not isinstance(name, str) or actor.GetClassName() != "vtkOpenGLActor":
            continue
        mesh = actor.GetMapper().GetInput()
        normals = mesh.GetPointData().GetNormals()
        prop = actor.GetProperty()
        out[name] = (vtk_to_numpy(mesh.GetPoints().GetData()).copy(),
                     [vtk_to_numpy(a).copy() for c in (mesh.GetLines(), mesh.GetPolys(), mesh.GetStrips())
                      for a in (c.GetOffsetsArray(), c.GetConnectivityArray())],
                     None if normals is None else vtk_to_numpy(normals).copy(),
                     (prop.GetColor(), prop.GetOpacity(), prop.GetLineWidth(), bool(actor.GetVisibility()),
                      pose_scene.depth_layer(actor)))
    return out


@pytest.mark.parametrize("key", ["inverse3_prototype", "fivebar_singh", "stewart_platform"])
@pytest.mark.parametrize("glyphs", [DEFAULT_GLYPHS, ALL_GLYPHS, NO_POLYTOPE], ids=["default", "all", "no_polytope"])
def test_a_redrawn_scene_holds_the_meshes_of_one_drawn_afresh(key, glyphs):
    preset = load_preset(key)
    mech = preset.mechanism
    gears = getattr(mech.params, "gear_ratios", None)
    name, before = ("gear_ratios", tuple(gears)) if gears is not None else (None, None)
    # Two designs of different glyphs (a gear ratio scales the forces), drawn with a desired force
    # the device cannot hold in every direction (its clamp is drawn too).
    other = mech.replace(**{name: tuple(1.3 * np.asarray(before))}) if name else mech
    desired = np.zeros(mech.task_dim)
    desired[0] = 50.0
    pose = np.asarray(preset.pose, float)
    redrawn, fresh = _plotter((300, 400)), _plotter((300, 400))
    try:
        _draw(redrawn, mech, pose, glyphs, desired)
        _draw(redrawn, other, pose, glyphs, desired)
        _draw(fresh, other, pose, glyphs, desired)
        a, b = _meshes(redrawn), _meshes(fresh)
        assert a.keys() == b.keys() and a
        for actor in a:
            (pa, ca, na, la), (pb, cb, nb, lb) = a[actor], b[actor]
            np.testing.assert_array_equal(pa, pb, err_msg=actor)
            for x, y in zip(ca, cb):
                np.testing.assert_array_equal(x, y, err_msg=actor)
            assert (na is None) == (nb is None), actor
            if na is not None:
                np.testing.assert_array_equal(na, nb, err_msg=actor)
            assert la == lb, actor
    finally:
        redrawn.close()
        fresh.close()
