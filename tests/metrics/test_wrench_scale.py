"""The zero-moment force set of a wrench device is the same shape at any torque scale.

The set ``{f : (f, 0) in A diag(t) Q}`` is linear in ``t``: scaling every torque by ``c``
scales its vertices by ``c`` and leaves its faces (which vertices, in which order around
each face) as they are. At 1e-300 N m and 1e300 N m products of several torques underflow
or overflow unless the computation is done at a normalised scale.
"""
from __future__ import annotations

import numpy as np
import pytest

from metrics.pose import analyse_pose
from metrics.wrench_slices import hull_faces
from resources import list_presets, load_preset

WRENCH_PRESETS = [key for key in list_presets() if load_preset(key).mechanism.has_orientation]
EPS = np.finfo(float).eps


def _rating(mech) -> str:
    return "motor_forces" if hasattr(mech.params, "motor_forces") else "motor_torques"


def _scaled(mech, c):
    name = _rating(mech)
    return mech.replace(**{name: tuple(v * c for v in getattr(mech.params, name))})


def _cycles(faces, relabel):
    """Faces as cycles starting at their smallest (relabelled) index: the same set iff the same
    faces with the same winding (a reversed cycle starts the same but runs the other way)."""
    out = set()
    for face in faces:
        f = [int(relabel[i]) for i in face]
        k = f.index(min(f))
        out.add(tuple(f[k:] + f[:k]))
    return out


@pytest.mark.parametrize("key", WRENCH_PRESETS)
@pytest.mark.parametrize("c", [1e-300, 1e300, 2.0 ** -990])
def test_faces_and_vertices_scale_with_the_torques(key, c):
    preset = load_preset(key)
    mech = preset.mechanism
    x = preset.pose if preset.pose is not None else mech.home_pose()
    base = analyse_pose(mech, x)
    scaled = analyse_pose(_scaled(mech, c), x)
    assert base.faces and len(scaled.vertices) == len(base.vertices)
    size = np.max(np.abs(base.vertices))
    # Each torque c t_u is rounded once (relative eps / 2); the vertices are sums of a few
    # generators over determinants, so they move by a few ulps of the set's size.
    gap = np.max(np.abs(scaled.vertices[:, None, :] / c - base.vertices[None]), axis=-1)   # (k, k)
    relabel = np.argmin(gap, axis=1)
    assert sorted(relabel.tolist()) == list(range(len(base.vertices)))
    assert np.max(np.min(gap, axis=1)) <= 64 * EPS * size
    assert _cycles(scaled.faces, relabel) == _cycles(base.faces, range(len(base.vertices)))
    # And what ``isoforce pose --json`` prints is the same: vertices in the same order, faces the
    # same list (rounding noise at another scale reorders neither).
    assert relabel.tolist() == list(range(len(base.vertices))) and scaled.faces == base.faces
    for name in ("isotropic_force", "anisotropic_force", "isotropic_moment", "anisotropic_moment"):
        assert getattr(scaled, name) / c == pytest.approx(getattr(base, name), rel=64 * EPS)


def test_hull_faces_of_a_cube_are_the_same_cycles_at_any_scale_wound_outwards():
    cube = np.array([[x, y, z] for x in (1, -1) for y in (1, -1) for z in (1, -1)], float)
    faces = hull_faces(cube)
    assert len(faces) == 6 and all(len(f) == 4 for f in faces)
    for face in faces:
        p = cube[list(face)]
        # Counter-clockwise seen from outside: the polygon's area vector points away from 0.
        area = sum(np.cross(p[k], p[(k + 1) % 4]) for k in range(4))
        assert np.dot(area, p.mean(axis=0)) > 0
    for c in (1e-300, 1e300, 3.0):
        assert hull_faces(cube * c) == faces


def test_power_of_two_scale_is_exact():
    from metrics.wrench_slices import power_of_two_scale

    for v in (3.0, 1e-300, 1e300, 0.5, 1.0):
        s = power_of_two_scale([v, -v / 3])
        assert 0.5 <= v / s < 1.0 and np.frexp(s)[0] == 0.5
