"""Gravity for every device with a mass model (issue 22, sec. 3): the torque the joints spend
holding the bodies is the gradient of their potential energy, and the weight the hand holds is the
force that torque balances.

References: central differences of ``potential_energy`` along each actuated joint (the bodies
placed through ``forward``, independent of the differenced body Jacobians behind
``gravity_torque``), and a linear solve ``J^T f = tau_g`` for the weight.
"""
from __future__ import annotations

import numpy as np
import pytest

from kinematics.gravity import gravity_vector
from metrics.quantities import evaluate
from resources import list_presets, load_preset

PRESETS = [k for k in list_presets() if load_preset(k).mechanism.has_mass_model
           and not load_preset(k).mechanism.is_redundant]
#: A step of 1e-5 rad (m): central differences of a smooth V are exact to O(h^2) ~ 1e-10 of its
#: scale, and FK/IK rounding contributes ~eps |V| / h ~ 1e-11; 1e-7 relative is far outside both.
STEP, RTOL = 1e-5, 1e-7


def _poses(key: str, count: int = 8):
    preset = load_preset(key)
    mech = preset.mechanism
    rng = np.random.default_rng(3)
    pts = preset.grid.points(mech.task_names).reshape(-1, mech.task_dim)
    q, ok = mech.inverse(pts)
    good = ok & mech.feasible(q, pts) & np.all(np.isfinite(q), axis=-1)
    # Well away from singular poses, J scaled to the coordinates' sizes (m over 5 cm, rad over 1)
    # so that a pen's or platform's mixed rows give a unit-free condition number.
    rows = np.array([1.0 if u == "rad" else 0.05 for u in mech.task_units])
    cols = np.array([1.0 if u == "rad" else 0.05 for u in mech.joint_units])
    with np.errstate(all="ignore"):
        jac = mech.jacobian(np.where(good[:, None], q, 0), np.where(good[:, None], pts, 0))
        cond = np.linalg.cond(np.where(good[:, None, None], jac * cols / rows[:, None], np.eye(mech.task_dim)))
    good &= np.isfinite(cond) & (cond < 50)
    idx = rng.choice(np.flatnonzero(good), size=count, replace=False)
    return q[idx], pts[idx]


@pytest.mark.parametrize("key", PRESETS)
def test_the_gravity_torque_is_the_gradient_of_the_potential_energy(key):
    mech = load_preset(key).mechanism
    g = gravity_vector("x-up")           # sideways: every family's bodies feel it
    q, _ = _poses(key)
    tau = mech.gravity_torque(q, g)
    numeric = np.empty_like(tau)
    for j in range(mech.n_joints):
        dq = np.zeros(mech.n_joints)
        dq[j] = STEP
        numeric[:, j] = (mech.potential_energy(q + dq, g) - mech.potential_energy(q - dq, g)) / (2 * STEP)
    scale = np.abs(numeric).max()
    assert scale > 0
    assert np.all(np.abs(tau - numeric) <= RTOL * scale + 1e-6 * scale)


@pytest.mark.parametrize("key", PRESETS)
def test_the_weight_is_the_force_that_balances_the_gravity_torque(key):
    mech = load_preset(key).mechanism
    g = gravity_vector("upright")
    q, x = _poses(key)
    # With gravity off the weight is taken upright (the map quantity's definition); a loading
    # with gravity would bias the force set too, which devices with orientation freedoms refuse.
    weight = evaluate(mech, x, ["weight"]).values["weight"]
    f = np.linalg.solve(np.swapaxes(mech.jacobian(q, x), -1, -2), mech.gravity_torque(q, g)[..., None])[..., 0]
    rows = [i for i, u in enumerate(mech.task_units) if u == "m"]
    expected = np.linalg.norm(f[:, rows], axis=-1)
    assert np.allclose(weight, expected, rtol=1e-8, atol=1e-12)
