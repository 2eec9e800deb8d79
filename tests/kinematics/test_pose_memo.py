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
from kinematics.pose_memo import PoseMemo, fold_rows, repeat_period
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


def _period_by_rows(rows: np.ndarray):
    """``repeat_period`` the plain way: whole rows' bits, the first repeat of row 0, then every block."""
    bits = np.ascontiguousarray(rows, dtype=np.float64).view(np.int64).reshape(len(rows), -1)
    if len(bits) < 2:
        return None
    for p in range(1, len(bits)):
        if np.array_equal(bits[p], bits[0]):
            break
    else:
        return None
    if len(bits) % p:
        return None
    return p if all(np.array_equal(bits[i:i + p], bits[:p]) for i in range(0, len(bits), p)) else None


def test_repeat_period_is_the_plain_one_on_every_layout():
    """Column views, a first look near the top: the same period as comparing whole rows one by one, on
    blocks of every length (past the first look's 64 rows too), signed zeros and nans, broken repeats,
    ragged tails, strided and Fortran-ordered rows, and no columns."""
    rng = np.random.default_rng(11)
    seen = set()
    for t in range(1500):
        k, p, reps = int(rng.integers(0, 4)), int(rng.integers(1, 90)), int(rng.integers(1, 5))
        block = rng.choice([0.0, -0.0, 1.0, np.nan], size=(p, k)) if t % 2 else rng.random((p, k))
        rows = np.tile(block, (reps, 1))
        if t % 3 == 0 and len(rows) > 1:
            rows[rng.integers(len(rows))] = rng.random(k)
        if t % 7 == 0:
            rows = rows[:-1]
        if t % 11 == 0:
            rows = np.asfortranarray(rows)
        if t % 13 == 0:
            rows = np.repeat(rows, 2, axis=1)[:, ::2]
        got = repeat_period(rows)
        assert got == _period_by_rows(rows), t
        seen.add(got if got is None else min(got, 65))
    assert None in seen and 1 in seen and 65 in seen          # no repeat, constant, and past the first look


def test_fold_spreads_a_row_function_back_bit_for_bit():
    """A function of the grouping and block columns, computed on the fold's table and spread, is the
    function computed row by row; layouts that do not fold give None."""
    axes = [np.array([-0.0, 0.0, 0.1, 0.2]), np.linspace(-1, 1, 4), np.array([0.0, -0.0, 0.5])]
    # x fastest: each (y, z) line is consecutive runs; the first line comes back at the end, apart.
    pos = np.stack(np.meshgrid(*axes, indexing="ij"), -1).transpose(1, 2, 0, 3).reshape(-1, 3)
    pos = np.concatenate([pos, pos[:2]])
    block = np.array([[0.0, 1.0], [-0.0, 1.0], [0.3, -2.0]])

    def f(y, z, a, b):
        return np.arctan2(y + a, z - b) + np.copysign(1.0, y * z)       # sees signed zeros

    for b in (block, block[:1]):                                        # a block of 3, one orientation
        rows = np.concatenate([np.repeat(pos, len(b), axis=0), np.tile(b, (len(pos), 1))], -1)
        fold = fold_rows(rows, slice(3, 5), slice(0, 3), slice(1, 3))
        assert fold is not None and fold.groups == 13 and fold.period == len(b)
        table = f(fold.table(rows[:, 1]), fold.table(rows[:, 2]), fold.block(rows[:, 3]), fold.block(rows[:, 4]))
        assert fold.spread(table).tobytes() == f(rows[:, 1], rows[:, 2], rows[:, 3], rows[:, 4]).tobytes()
        shaped = fold_rows(rows.reshape(len(pos), len(b), 5), slice(3, 5), slice(0, 3), slice(1, 3))
        assert shaped.spread(table).shape == (len(pos), len(b))
    rows = np.concatenate([np.repeat(pos, 3, axis=0), np.tile(block, (len(pos), 1))], -1)
    broken = rows.copy()
    broken[4, 0] = 9.0                                                   # a run whose position changes
    assert fold_rows(broken, slice(3, 5), slice(0, 3), slice(1, 3)) is None
    assert fold_rows(rows[:3], slice(3, 5), slice(0, 3), slice(1, 3)) is None          # one run: nothing to fold
    assert fold_rows(rows, slice(3, 5), slice(0, 3), slice(0, 3)) is None               # all distinct: no saving
    x_slowest = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)         # a map's order
    assert fold_rows(np.concatenate([x_slowest, np.zeros((len(x_slowest), 2))], -1),
                     slice(3, 5), slice(0, 3), slice(1, 3)) is None
