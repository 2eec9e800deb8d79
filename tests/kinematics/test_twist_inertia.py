"""Lambda and the gravity wrench of the pens and platforms away from zero orientation (issue 22).

``J`` maps joint rates to the twist ``xi`` (``[v; omega]``; the 5-DOF Twin-Pantograph's
``[v; omega . a; omega . b]``), not to the rates of the pose coordinates (a rotation vector's
rate is the angular velocity only at zero orientation). ``task_inertia`` and
``kinematics.dynamics.task_gravity_force`` must be in the same twist coordinates at every
orientation. Independent reference, no Jacobian formed: along a random path ``x(t) = x + t d`` of
the pose coordinates,

- the bodies' kinetic energy differenced from ``body_poses`` (``kinematics.bodies.kinetic_energy``)
  plus the rotors' ``1/2 sum J_u N_u^2 qdot_u^2`` with ``qdot`` differenced from ``inverse``;
- the handle's twist measured from the platform's (pen's) own frame: ``v`` the task point's
  velocity, ``omega`` the axial vector of ``dR/dt R^T`` (both differenced);
- the power of gravity ``dV/dt``, ``V = -sum m_b g . c_b`` differenced along the path,

so ``1/2 xi^T Lambda xi`` must equal the energy and ``w . xi`` (``w`` the wrench the hand holds)
must equal ``dV/dt``, at orientations of up to 0.5 rad. The same energy read as
``1/2 d^T Lambda d`` (Lambda taken as per coordinate rate) misses by far more than the
tolerance: the test can tell the two apart.

Tolerance: as ``test_mass_model.py``'s energy test (central differences with ``dt = 1e-5`` on
poses with ``cond(J) < 20``, bound 1e-6 relative), for the energy and for the power.
"""
from __future__ import annotations

import numpy as np
import pytest

from kinematics import dynamics
from kinematics.bodies import body_arrays, centres, kinetic_energy
from resources import list_presets, load_preset

PRESETS = [key for key in list_presets()
           if load_preset(key).mechanism.has_mass_model and load_preset(key).mechanism.has_orientation]
DT = 1e-5
GRAVITY = np.array([0.0, 0.0, -9.80665])


def _turned_poses(key: str, count: int, seed: int) -> np.ndarray:
    """``count`` feasible poses of the preset's map box with every angle 0.15-0.5 rad (either sign)."""
    preset = load_preset(key)
    mech, grid = preset.mechanism, preset.grid
    rng = np.random.default_rng(seed)
    n = 80 * count
    names = list(mech.task_names)
    x = np.zeros((n, mech.task_dim))
    for name, value in grid.fixed:
        x[:, names.index(name)] = value
    for axis, lo, hi in zip(grid.axes, grid.lower, grid.upper):
        x[:, names.index(axis)] = rng.uniform(lo, hi, n)
    angles = [i for i, u in enumerate(mech.task_units) if u == "rad"]
    x[:, angles] += rng.choice([-1.0, 1.0], (n, len(angles))) * rng.uniform(0.15, 0.5, (n, len(angles)))
    q, ok = mech.inverse(x)
    ok &= mech.feasible(q, x) & np.all(np.isfinite(q), -1)
    # Well-conditioned in the coordinates' own sizes (m over LENGTH_SCALE, rad over 1), as test_mass_model.
    rows = np.array([1.0 if u == "rad" else dynamics.LENGTH_SCALE for u in mech.task_units])
    cols = np.array([1.0 if u == "rad" else dynamics.LENGTH_SCALE for u in mech.joint_units])
    with np.errstate(all="ignore"):
        fmap = mech.force_map(q[ok], x[ok])
        cond = np.linalg.cond(np.nan_to_num(fmap * rows[:, None] / cols, nan=np.inf))
    good = np.flatnonzero(ok)[np.isfinite(cond) & (cond < 20)]
    assert len(good) >= count, f"{key}: {len(good)} well-conditioned turned poses"
    return x[good[:count]]


def _axial(skew_like: np.ndarray) -> np.ndarray:
    return 0.5 * np.stack([skew_like[..., 2, 1] - skew_like[..., 1, 2], skew_like[..., 0, 2] - skew_like[..., 2, 0],
                           skew_like[..., 1, 0] - skew_like[..., 0, 1]], -1)


def _measured(mech, x: np.ndarray, d: np.ndarray):
    """Along ``x + t d``: the handle's twist ``xi`` (model coordinates), the joints' rates and ``dV/dt``."""
    def at(t):
        u = x + t * d
        q, _ = mech.inverse(u)
        rot, org = mech.body_poses(q, u)
        return u, q, rot, org

    _, q0, rot0, _ = at(0.0)
    u_up, q_up, rot_up, org_up = at(DT)
    u_dn, q_dn, rot_dn, org_dn = at(-DT)
    handle = rot0[..., -1, :, :]
    v = (u_up[..., :3] - u_dn[..., :3]) / (2 * DT)
    omega = _axial((rot_up[..., -1, :, :] - rot_dn[..., -1, :, :]) / (2 * DT) @ np.swapaxes(handle, -1, -2))
    if mech.task_dim == 6:
        xi = np.concatenate([v, omega], -1)
    else:              # the 5-DOF pen: omega across the pen, along a = R e_x and b = R e_z
        xi = np.concatenate([v, np.sum(omega * handle[..., :, 0], -1, keepdims=True),
                             np.sum(omega * handle[..., :, 2], -1, keepdims=True)], -1)
    qdot = (q_up - q_dn) / (2 * DT)
    masses, com, _ = body_arrays(mech.bodies())

    def potential(rot, org):
        return -np.einsum("k,...ki,i->...", masses, centres(rot, org, com), GRAVITY)

    power = (potential(rot_up, org_up) - potential(rot_dn, org_dn)) / (2 * DT)
    return xi, qdot, power


@pytest.mark.parametrize("key", PRESETS)
def test_lambda_is_the_kinetic_energy_per_twist_away_from_zero_orientation(key):
    mech = load_preset(key).mechanism
    x = _turned_poses(key, 30, seed=11)
    rng = np.random.default_rng(12)
    scales = np.array([1.0 if u == "rad" else dynamics.LENGTH_SCALE for u in mech.task_units])
    d = rng.standard_normal(x.shape) * scales
    q, _ = mech.inverse(x)
    masses, com, tensors = body_arrays(mech.bodies())
    links = kinetic_energy(masses, tensors, com, dynamics._placer(mech, True), x, d, DT)
    xi, qdot, power = _measured(mech, x, d)
    rotors = 0.5 * np.sum(mech.reflected_rotor_inertias() * qdot**2, -1)
    theirs = links + rotors
    lam = mech.task_inertia(q, x)
    ours = 0.5 * np.einsum("...a,...ab,...b->...", xi, lam, xi)
    assert np.all(np.abs(ours - theirs) <= 1e-6 * theirs), np.max(np.abs(ours / theirs - 1))
    # Read per coordinate rate, the same Lambda misses: the orientation matters at these poses.
    per_rate = 0.5 * np.einsum("...a,...ab,...b->...", d, lam, d)
    assert np.max(np.abs(per_rate / theirs - 1)) > 100 * 1e-6
    # The wrench gravity puts on the handle: its power along the twist is that of the bodies' weights.
    wrench = dynamics.task_gravity_force(mech, q, x, GRAVITY)
    ours_power = np.sum(wrench * xi, -1)
    size = np.sum(np.abs(wrench * xi), -1)
    assert np.all(np.abs(ours_power - power) <= 1e-6 * size)


@pytest.mark.parametrize("key", PRESETS)
def test_the_twist_and_coordinate_forms_agree_at_zero_orientation(key):
    """At zero orientation ``T = I``: the conversion leaves ``Lambda`` bit for bit (the maps' slices)."""
    from kinematics.dynamics import twist_columns
    mech = load_preset(key).mechanism
    x = np.array([load_preset(key).pose])
    columns = (np.arange(2.0 * mech.task_dim).reshape(2, mech.task_dim, 1),)
    assert twist_columns(mech, x, columns) is columns
    t = mech.coordinate_rates_to_twist(x + np.r_[np.zeros(3), 0.3 * np.ones(mech.task_dim - 3)])
    assert not np.allclose(t, np.eye(mech.task_dim))
