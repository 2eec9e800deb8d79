"""The zero-moment slice of a wrench set where an actuator is at an inverse singularity.

There ``J`` has an exactly zero column (``kinematics.base.singular_limit``), ``J^-T`` does not
exist, and the slice is bounded by the other actuators' slabs: ``wrench_facets.slab_slice_max_norm``
takes its largest norm from those slabs. Checked against the generator method
(``wrench_slices.slice_max_norm``) at regular poses, and at a singular Inoue pose against the limit the
regular poses approach.
"""
from __future__ import annotations

import numpy as np
import pytest

from metrics import wrench_facets, wrench_slices, wrenches
from metrics.pose import analyse_pose
from resources import list_presets, load_preset

EPS = np.finfo(float).eps
SQUARE_WRENCH = [k for k in list_presets()
                 if load_preset(k).mechanism.has_orientation and not load_preset(k).mechanism.is_redundant]


@pytest.mark.parametrize("key", SQUARE_WRENCH)
def test_slabs_and_generators_give_the_same_largest_slice_norm_at_regular_poses(key):
    preset = load_preset(key)
    mech = preset.mechanism
    home = preset.pose if preset.pose is not None else mech.home_pose()
    rng = np.random.default_rng(1)
    x = home + rng.normal(scale=0.01, size=(40, mech.task_dim))
    q, ok = mech.inverse(x)
    q, x = q[ok], x[ok]
    jac = mech.jacobian(q, x)
    t = mech.torque_limits()
    gens = mech.force_map(q, x) * t
    cond = np.linalg.cond(jac)
    for rows in (wrenches.force_rows(mech), wrenches.moment_rows(mech)):
        slabs = wrench_facets.slab_slice_max_norm(jac, torque_limits=t, rows=rows)
        verts = wrench_slices.slice_max_norm(gens, rows=rows)
        # Two roundings of the same vertices, each a few eps times the condition number.
        np.testing.assert_array_less(np.abs(slabs - verts), 1e3 * EPS * cond * verts)


def test_the_singular_inoue_pose_gets_the_limit_of_the_regular_poses_beside_it():
    mech = load_preset("inoue_platform").mechanism
    up = np.eye(6)[2]
    # Straight up from home until the IK folds (a stretched leg): bisected to adjacent doubles.
    lo, hi = 0.0, 1.0
    home = mech.home_pose()
    while (mid := 0.5 * (lo + hi)) not in (lo, hi):
        lo, hi = (mid, hi) if mech.inverse(home + mid * up)[1] else (lo, mid)
    edge = home + lo * up
    at = analyse_pose(mech, edge)
    assert at.singular_legs and at.singularity_name == "inverse"
    for name in ("anisotropic_force", "anisotropic_moment"):
        limit = getattr(at, name)
        assert np.isfinite(limit), name
        # A fold: values approach the limit like sqrt(distance), so each step 100 times closer
        # comes about 10 times closer to it.
        gaps = [abs(getattr(analyse_pose(mech, edge - dz * up), name) - limit) for dz in (1e-6, 1e-8, 1e-10)]
        assert gaps[0] > gaps[1] > gaps[2] and gaps[2] < 1e-4 * limit, (name, gaps)
