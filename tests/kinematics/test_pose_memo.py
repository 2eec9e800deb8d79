"""``kinematics.pose_memo``: a hit is only ever the value computed from the same parameters and poses.

The models keep their last configuration (and the Inoue platform its singularity classes) so that
the calls of one evaluation at the same poses build it once; a stale or shared entry would give
one batch another batch's answer, which these tests would see.
"""
from __future__ import annotations

import threading

import numpy as np
import pytest

from kinematics import inoue, stewart, twin_pantograph
from kinematics.pose_memo import PoseMemo
from resources import load_preset


def test_a_hit_needs_the_same_key_and_the_same_values():
    memo = PoseMemo()
    x = np.array([[0.0, np.nan], [1.0, 2.0]])
    value = object()
    assert memo.put("a", x, value) is value
    assert memo.get("a", x.copy()) is value                   # equal values (nan equal to nan), other array
    assert memo.get("b", x) is None                           # other parameters
    assert memo.get("a", x[:1]) is None                       # other shape
    assert memo.get("a", np.nextafter(x, 3.0)) is None        # one ulp away
    zeros = np.zeros(2)
    memo.put("a", zeros, value)
    assert memo.get("a", -zeros) is None                      # -0.0: equal value, other bits
    memo.put("a", x, value)
    x[1, 1] = 5.0                                             # the caller writes into its array after storing
    assert memo.get("a", x) is None
    memo.clear()
    assert memo.get("a", np.array([[0.0, np.nan], [1.0, 2.0]])) is None


def test_each_thread_has_its_own_entry():
    memo = PoseMemo()
    x = np.zeros(3)
    memo.put("k", x, "main")
    seen = []
    worker = threading.Thread(target=lambda: seen.append(memo.get("k", x)))
    worker.start()
    worker.join()
    assert seen == [None] and memo.get("k", x) == "main"


def _poses(mech, n, seed):
    rng = np.random.default_rng(seed)
    home = mech.home_pose()
    spread = np.array([0.05, 0.05, 0.05] + [0.3] * (mech.task_dim - 3))
    return home + rng.uniform(-1.0, 1.0, (n, mech.task_dim)) * spread


@pytest.mark.parametrize("key, module", [("twin_pantograph", twin_pantograph), ("inoue_platform", inoue),
                                         ("stewart_platform", stewart)])
def test_remembered_results_are_those_of_a_fresh_computation(key, module):
    mech = load_preset(key).mechanism
    x = _poses(mech, 64, seed=3)
    other = _poses(mech, 64, seed=4)

    def results():
        with np.errstate(all="ignore"):
            q, ok = mech.inverse(x)
            out = [q, ok, mech.feasible(q, x), mech.jacobian(q, x), mech.force_map(q, x)]
            if mech.singularity_classes:
                out.append(mech.singularity(q, x))
        return out

    def forget():
        for memo in vars(module).values():
            if isinstance(memo, PoseMemo):
                memo.clear()

    forget()
    fresh = results()
    mech.inverse(other)                               # another batch in between: its entry replaces the first
    again = results()                                 # then every call but the first of each kind is a hit
    for a, b in zip(fresh, again):
        np.testing.assert_array_equal(a, b)
    # A model with other parameters at the same poses is not served the first model's configuration.
    name = "base_radius" if key == "stewart_platform" else "forearm"
    longer = mech.replace(**{name: getattr(mech.params, name) * 1.1})
    forget()
    with np.errstate(all="ignore"):
        expected = longer.inverse(x)
        mech.inverse(x)
        got = longer.inverse(x)
    np.testing.assert_array_equal(got[0], expected[0])
    assert not np.array_equal(got[0], mech.inverse(x)[0], equal_nan=True)
