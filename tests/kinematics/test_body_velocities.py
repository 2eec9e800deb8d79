"""Every family's exact body velocity Jacobians against central differences of its body poses.

``body_velocities`` (each model's closed form, from its chain Jacobians and loop closures) must
agree with ``kinematics.dynamics.differenced_velocities`` (central differences of ``body_poses``
through the closed-form inverse kinematics: the independent reference, and what the maps used
before) within that difference's own error, estimated at each pose and entry:

- truncation: a central difference ``D(h) = D + c h^2 + O(h^4)``, so ``D(2h) - D(h) = 3 c h^2``:
  ``|D(2h) - D(h)|`` is three times the leading truncation error of ``D(h)`` (the ``h^4`` terms
  are ``eps^(4/3)`` relative, far below the rounding);
- rounding: a body pose is evaluated to about ``ROUNDING`` relative of its size ``F`` (the
  largest centre or joint coordinate at that pose, 1 for a rotation's entries), a few tens of
  rounded operations through the inverse kinematics at the well-conditioned poses the mass-model
  tests draw (condition < 20); a central difference over ``2 h`` divides twice that by ``2 h``,
  and the estimate ``D(2h) - D(h)`` carries the rounding of both.

Plus: the kinetic form is the same on any batch shape as on its rows one by one.
Headless: numpy and the compute layer only. Fixed seeds.
"""
from __future__ import annotations

import numpy as np
import pytest

from kinematics import dynamics
from kinematics.bodies import FD_STEP
from resources import load_preset
from tests.kinematics.test_mass_model import PRESETS, _poses, _scales

EPS = np.finfo(float).eps
#: Relative error of one evaluated body pose: 64 rounded operations of eps/2 each, with margin.
ROUNDING = 64 * EPS


def _component_first_to_batch(values: np.ndarray) -> np.ndarray:
    return np.moveaxis(values, -1, 0)


@pytest.mark.parametrize("key", PRESETS)
def test_exact_body_velocities_match_differenced_poses_within_the_difference_error(key):
    mech = load_preset(key).mechanism
    q, x = _poses(key, 30, seed=11)
    by_task = mech.mass_coordinates == "task"
    u = x if by_task else q
    steps = FD_STEP * np.maximum(np.abs(u), _scales(mech, by_task))                    # (N, d)
    with np.errstate(all="ignore"):
        exact = mech.body_velocities(q, x)
    fine = dynamics.differenced_velocities(mech, q, x)
    coarse = dynamics.differenced_velocities(mech, q, x, step=2 * FD_STEP)
    centre_size = np.max(np.abs(mech.centres_of_mass(q)), axis=(-2, -1))               # (N,)
    joint_size = np.max(np.abs(q), axis=-1)
    sizes = {"jv": centre_size, "jw": np.ones(len(q)), "G": joint_size}
    for name, got, h1, h2 in zip(("jv", "jw", "rot", "G"), exact, fine, coarse):
        if name == "rot" or got is None:
            continue
        got = _component_first_to_batch(got)
        assert got.shape == h1.shape, name
        size = sizes[name][(slice(None),) + (None,) * (h1.ndim - 1)]
        rounding = ROUNDING * size / steps[(slice(None),) + (None,) * (h1.ndim - 2)]
        tolerance = np.abs(h2 - h1) + 3 * rounding
        err = np.abs(got - h1)
        worst = np.unravel_index(np.argmax(err - tolerance), err.shape)
        assert np.all(err <= tolerance), (f"{key} {name}: |exact - differenced| {err[worst]:.3g} > "
                                          f"{tolerance[worst]:.3g} at {worst}")


@pytest.mark.parametrize("key", PRESETS)
def test_the_kinetic_form_of_a_batch_is_that_of_its_rows(key):
    mech = load_preset(key).mechanism
    q, x = _poses(key, 6, seed=5)
    whole = dynamics.kinetic_form(mech, q.reshape(2, 3, -1), x.reshape(2, 3, -1))
    rows = np.stack([dynamics.kinetic_form(mech, qi, xi) for qi, xi in zip(q, x)])
    # The same arithmetic on each row: batch layout changes no operation's operands.
    assert whole.shape == (2, 3) + rows.shape[1:]
    np.testing.assert_array_equal(whole.reshape(rows.shape), rows)


@pytest.mark.parametrize("key", ["phantom_premium_15", "twin_pantograph"])
def test_the_kinetic_form_in_blocks_is_the_form_in_one(key, monkeypatch):
    mech = load_preset(key).mechanism
    q, x = _poses(key, 7, seed=2)
    whole = dynamics.kinetic_form(mech, q, x)
    monkeypatch.setattr(dynamics, "KINETIC_BLOCK", 3)
    np.testing.assert_array_equal(dynamics.kinetic_form(mech, q, x), whole)
