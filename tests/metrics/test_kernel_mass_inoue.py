"""The Inoue platform's compiled kinetic form (``metrics.kernels.inoue_mass``) against ``kinetic_form``.

Reference: ``kinematics.dynamics.kinetic_form(mech, q, x)`` (``InouePlatform.task_inertia``), from
the model's exact body velocities (``InouePlatform.body_velocities``). Both paths form the same
columns by the same formulas from the same configuration (the model's IK), in other orders of
summation, so they differ by rounding only, bounded as follows (``u = eps / 2``):

- A column's longest chain (``R a_k``, the tip's rate, the waist's ``psi' = n . T' / w``, a
  shoulder's ``theta' = d . T' / (l2 d . t)``, the elbow's rate, a link's frame in the plane and
  its spin ``e_y . (b' - a') / |b - a|``, the angular velocity, ``R c`` and the centre's velocity,
  ``R^T omega`` and the tensor's product) has at most ``N = 60`` roundings, each relative ``u`` to
  its operand's size. One step cancels: ``d . t`` (two products), off by ``u |d| |t|``, relative
  ``u kappa`` with ``kappa = |d| |t| / |d . t|`` (the five-bar's distance from its singularity), and so
  are ``theta'`` and every part linear in it (an elbow's rate, the links and counterweights it
  moves), of size at most ``kappa`` times the tip's rate. The plane's normal is perpendicular to a
  link in the plane, so ``|n x e_x| = 1`` divides nothing small; ``w`` is the tip's distance from
  the waist axis, a length of the device, and ``n . T'`` does not cancel normwise (``T'``'s position
  columns are the identity). So a column ``f`` is off by at most ``N u k^2 |f|``, normwise over the
  body's columns, ``k = 1 + max kappa`` over the six shoulders.
- An entry is ``sum_t w_t f_a . f_b`` over the 68 terms (31 bodies' translation and rotation, 6
  rotors): off by at most ``(2 N k^2 + 3 + 68) u T``, ``T = sum_t w_t |F_t|^2`` as in
  ``test_kernel_mass_stewart.py``.

Taken for each path, the two differ by at most ``(2 N k^2 + 72) eps T``; where an angle is not 0,
``|T^-1|^2`` times that plus ``12 eps |T^-1|^2 T`` (``test_kernel_mass_stewart.py``).
"""
from __future__ import annotations

import numpy as np
import pytest
from platform_mass_bound import SEED, entry_bound, feasible_points

from kinematics.dynamics import kinetic_form
from metrics import dynamics
from resources import load_preset


def _bound(mech, q, x):
    """The two paths' largest entry difference per point (k,) (module docstring)."""
    cfg = mech.kinetic_configuration(x)
    d, t = cfg["distal"], cfg["tangent"]
    kappa = np.linalg.norm(d, axis=-1) * np.linalg.norm(t, axis=-1) / np.abs(np.sum(d * t, axis=-1))
    k = 1.0 + np.max(kappa.reshape(len(x), -1), axis=-1)
    return entry_bound(mech, q, x, k, terms=72)


@pytest.fixture(scope="module")
def inoue():
    preset = load_preset("inoue_platform")
    return preset.mechanism, preset.grid


def test_compiled_form_matches_kinetic_form_on_the_presets_grid(inoue):
    mech, grid = inoue
    x, q = feasible_points(mech, grid)
    got = dynamics.task_inertia(mech, q, x)
    ref = kinetic_form(mech, q, x)
    assert np.all(np.abs(got - ref) <= _bound(mech, q, x)[:, None, None])
    assert np.array_equal(got, np.swapaxes(got, -1, -2))


def test_compiled_form_matches_kinetic_form_at_turned_poses(inoue):
    mech, grid = inoue
    x = feasible_points(mech, grid, count=200)[0].copy()
    x[:, 3:] = np.random.default_rng(SEED).normal(scale=0.1, size=(len(x), 3))
    q, ok = mech.inverse(x)
    x, q = x[ok], q[ok]
    assert len(x) > 100
    got = dynamics.task_inertia(mech, q, x)
    assert np.all(np.abs(got - kinetic_form(mech, q, x)) <= _bound(mech, q, x)[:, None, None])


def test_active_waists_add_their_rotors(inoue):
    """Nine actuators: the waists' rotors enter ``G^T diag(r) G`` too."""
    mech, grid = inoue
    active = mech.replace(waist_actuators="active")
    x, _ = feasible_points(mech, grid, count=50)
    q, ok = active.inverse(x)
    x, q = x[ok], q[ok]
    got = dynamics.task_inertia(active, q, x)
    assert np.all(np.abs(got - kinetic_form(active, q, x)) <= _bound(active, q, x)[:, None, None])
    assert not np.allclose(got, dynamics.task_inertia(mech, mech.inverse(x)[0], x))


def test_unreached_and_nan_poses_are_nan(inoue):
    mech, grid = inoue
    x, q = feasible_points(mech, grid, count=6)
    x[1] = np.nan
    x[2, 2] = 10.0                       # 10 m away: no leg reaches
    q, _ = mech.inverse(x)
    got = dynamics.task_inertia(mech, q, x)
    ref = kinetic_form(mech, q, x)
    assert np.array_equal(np.isnan(got), np.isnan(ref)) and np.all(np.isnan(got[[1, 2]]))


@pytest.mark.parametrize("k", [40, -40])
def test_scaled_masses_scale_the_form_exactly(inoue, k):
    """Every term is one mass, tensor entry or rotor inertia times velocities: a power of two passes through."""
    mech, grid = inoue
    p = mech.params
    scale = 2.0 ** k
    scaled = mech.replace(link_masses=tuple(m * scale for m in p.link_masses),
                          waist_inertia=tuple(i * scale for i in p.waist_inertia),
                          platform_inertia=tuple(i * scale for i in p.platform_inertia),
                          rotor_inertias=tuple(r * scale for r in p.rotor_inertias))
    x, q = feasible_points(mech, grid, count=50)
    assert np.array_equal(dynamics.task_inertia(scaled, q, x), dynamics.task_inertia(mech, q, x) * scale)
