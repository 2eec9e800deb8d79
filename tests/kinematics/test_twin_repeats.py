"""The Twin-Pantograph's pen frames of a repeated orientation block are those computed pose by pose.

``TwinPantograph._rotation`` computes one frame per orientation where the poses repeat a block of
orientations bit for bit (a map's fixed orientation, the dextrous region's blocks); a wrong period
or a repeat judged by value (``-0.0 == 0.0``) would hand a pose another pose's frame.
"""
from __future__ import annotations

import numpy as np
import pytest

from kinematics import twin_pantograph as tp
from kinematics.rotations import rotation_matrix, tilt_matrix
from resources import load_preset


def _frames_one_by_one(mech, x):
    frame = rotation_matrix if mech.six_dof else tilt_matrix
    return np.stack([frame(row[3:]) for row in x])


@pytest.mark.parametrize("roll", ["passive", "active"])
@pytest.mark.parametrize("layout", ["block", "constant", "no_repeat", "block_twice_first", "signed_zero"])
def test_frames_of_repeated_orientations_are_the_frames_pose_by_pose(roll, layout):
    mech = load_preset("twin_pantograph").mechanism.replace(roll_actuator=roll)
    k = mech.task_dim - 3
    rng = np.random.default_rng(7)
    block = rng.uniform(-0.7, 0.7, (5, k))
    if layout == "constant":
        block = block[:1]
    if layout == "block_twice_first":
        block[3] = block[0]                 # the first orientation twice: no period is taken
    orient = np.tile(block, (40, 1))
    if layout == "no_repeat":
        orient = rng.uniform(-0.7, 0.7, orient.shape)
    if layout == "signed_zero":             # 0.0 and -0.0 alternate: equal values, other bits
        orient = np.zeros((200, k))
        orient[1::2] = -0.0
    x = np.concatenate([rng.uniform(-0.05, 0.05, (len(orient), 3)), orient], 1)
    got = mech._rotation(x)
    want = _frames_one_by_one(mech, x)
    np.testing.assert_array_equal(got, want)
    assert np.array_equal(np.signbit(got), np.signbit(want))
    expected = {"block": 5, "constant": 1, "no_repeat": None, "block_twice_first": None, "signed_zero": 2}[layout]
    assert tp._repeat_period(np.ascontiguousarray(orient)) == expected
