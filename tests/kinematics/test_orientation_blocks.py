"""A platform's results at poses that repeat a block of orientations are those computed pose by pose.

The Twin-Pantograph, Stewart and Inoue models compute what depends on the orientation alone (the
frame, the rotated attachments, ``J_l``) once per row of a repeating block
(``kinematics.pose_memo.per_block``: a map's fixed orientation, the dextrous region's blocks). A
wrong period, or a repeat judged by value (``-0.0 == 0.0``), would hand a pose another pose's
values; these tests compare with the same calls with the repeat detection turned off.
"""
from __future__ import annotations

import numpy as np
import pytest

from kinematics import inoue, pose_memo, stewart, twin_pantograph
from kinematics.pose_memo import PoseMemo, repeat_period
from resources import load_preset

PLATFORMS = ["twin_pantograph", "stewart_platform", "inoue_platform"]
LAYOUTS = ["block", "constant", "no_repeat", "block_twice_first", "signed_zero"]


def _orientations(k: int, layout: str, rng) -> np.ndarray:
    block = rng.uniform(-0.3, 0.3, (5, k))
    if layout == "constant":
        block = block[:1]
    if layout == "block_twice_first":
        block[3] = block[0]                 # the first orientation twice: no period is taken
    orient = np.tile(block, (40, 1))
    if layout == "no_repeat":
        orient = rng.uniform(-0.3, 0.3, orient.shape)
    if layout == "signed_zero":             # 0.0 and -0.0 alternate: equal values, other bits
        orient = np.zeros((200, k))
        orient[1::2] = -0.0
    return orient


def _results(mech, x):
    with np.errstate(all="ignore"):
        q, ok = mech.inverse(x)
        out = [q, ok, mech.feasible(q, x), mech.jacobian(q, x), mech.force_map(q, x)]
        if mech.has_mass_model:
            out.append(mech.task_inertia(q, x))
    return out


@pytest.mark.parametrize("key", PLATFORMS)
@pytest.mark.parametrize("layout", LAYOUTS)
def test_results_at_repeated_orientations_are_those_without_the_repeats(key, layout, monkeypatch):
    mech = load_preset(key).mechanism
    k = mech.task_dim - 3
    rng = np.random.default_rng(7)
    orient = _orientations(k, layout, rng)
    x = np.concatenate([mech.home_pose()[:3] + rng.uniform(-0.02, 0.02, (len(orient), 3)), orient], 1)
    got = _results(mech, x)
    monkeypatch.setattr(pose_memo, "repeat_period", lambda rows: None)
    for module in (twin_pantograph, stewart, inoue):          # nothing remembered from the first pass
        for memo in vars(module).values():
            if isinstance(memo, PoseMemo):
                memo.clear()
    want = _results(mech, x)
    for a, b in zip(got, want):
        np.testing.assert_array_equal(a, b)
        assert np.array_equal(np.signbit(a), np.signbit(b))


@pytest.mark.parametrize("layout, period", [("block", 5), ("constant", 1), ("no_repeat", None),
                                            ("block_twice_first", None), ("signed_zero", 2)])
def test_the_repeat_period_is_the_block_length_by_bits(layout, period):
    orient = _orientations(2, layout, np.random.default_rng(3))
    assert repeat_period(orient) == period
