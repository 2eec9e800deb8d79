"""The Stewart platform's compiled kinetic form (``metrics.kernels.stewart_mass``) against ``kinetic_form``.

Reference: ``kinematics.dynamics.kinetic_form(mech, q, x)`` (``StewartPlatform.task_inertia``), from
the model's exact body velocities (``StewartPlatform.body_velocities``). Both paths form the same
columns by the same formulas from the same ``x`` (each body's centre velocity and angular velocity
per pose-coordinate rate, and ``G = dq/dx``), in other orders of summation, so they differ by
rounding only, bounded as follows (``u = eps / 2``):

- A column's longest chain (``R p_i``, the leg, its length and unit ``e_x``, the joint's rate
  ``dleg``, ``e_x' = (dleg - e_x (e_x . dleg)) / |L|``, the side ``t_i x e_x``, its length ``w_i`` and
  ``e_y``, ``e_z``, the twist and spin, ``omega``, ``R c`` and the centre's velocity, ``R^T omega``
  and the tensor's product) has at most ``N = 60`` roundings, each relative ``u`` to its operand's
  size. One step amplifies: ``e_y = (t_i x e_x) / w_i``, whose cross product is off by a few ``u``
  absolutely while ``w_i = |t_i x e_x| <= 1``, so ``e_y``, the spin ``/ w_i`` and everything after
  them are off by ``k = 1 / w_i`` times more, relative. ``e_x'``'s projection does not cancel below
  the unit scale normwise (``I - e e^T`` keeps two singular values 1). So a column ``f`` is off by
  at most ``N u k^2 |f|``, normwise over the body's columns, ``k = 1 / min_i w_i``.
- An entry is ``sum_t w_t f_a . f_b`` over the 32 terms (13 bodies' translation and rotation, 6
  rotors; ``w`` a mass, a tensor's norm, a rotor inertia): off by at most ``(2 N k^2 + 3 + 32) u T``
  with ``T = sum_t w_t |F_t|^2`` (``|F_t|`` the Frobenius norm of the term's columns; the 3 a
  3-vector dot product, the 32 the sum), plus the symmetrisation's one rounding.

Taken for each path, the two differ by at most ``(2 N k^2 + 36) eps T``. Where an angle is not 0,
both take the result per twist with ``T^-1`` (the numpy path per column, the kernel on the form):
``|T^-1|^2`` times that, plus the two 6-term products' ``12 eps |T^-1|^2 T``.
"""
from __future__ import annotations

import numpy as np
import pytest
from platform_mass_bound import SEED, entry_bound, feasible_points

from kinematics.dynamics import kinetic_form
from metrics import dynamics
from resources import load_preset


def _turned(mech, x, seed=SEED):
    """``x`` with random orientations up to about 0.3 rad, and its legs."""
    x = x.copy()
    x[:, 3:] = np.random.default_rng(seed).normal(scale=0.15, size=(len(x), 3))
    return x, mech.inverse(x)[0]


def _bound(mech, q, x):
    """The two paths' largest entry difference per point (k,) (module docstring)."""
    _, _, legs = mech._legs(x)
    unit = legs / np.linalg.norm(legs, axis=-1, keepdims=True)
    tangent = np.cross([0.0, 0.0, 1.0], mech.base_joints())
    tangent /= np.linalg.norm(tangent, axis=-1, keepdims=True)
    k = 1.0 / np.min(np.linalg.norm(np.cross(tangent, unit), axis=-1), axis=-1)
    return entry_bound(mech, q, x, k, terms=36)


@pytest.fixture(scope="module")
def stewart():
    preset = load_preset("stewart_platform")
    return preset.mechanism, preset.grid


def test_compiled_form_matches_kinetic_form_on_the_presets_grid(stewart):
    mech, grid = stewart
    x, q = feasible_points(mech, grid)
    got = dynamics.task_inertia(mech, q, x)
    ref = kinetic_form(mech, q, x)
    assert np.all(np.abs(got - ref) <= _bound(mech, q, x)[:, None, None])
    assert np.array_equal(got, np.swapaxes(got, -1, -2))


def test_compiled_form_matches_kinetic_form_at_turned_poses(stewart):
    mech, grid = stewart
    x, q = _turned(mech, feasible_points(mech, grid, count=100)[0])
    got = dynamics.task_inertia(mech, q, x)
    ref = kinetic_form(mech, q, x)
    assert np.all(np.abs(got - ref) <= _bound(mech, q, x)[:, None, None])


def test_batch_axes_and_a_nan_pose(stewart):
    mech, grid = stewart
    x, q = feasible_points(mech, grid, count=12)
    x[3] = np.nan
    q[3] = np.nan
    got = dynamics.task_inertia(mech, q.reshape(3, 4, 6), x.reshape(3, 4, 6))
    assert got.shape == (3, 4, 6, 6)
    assert np.all(np.isnan(got[0, 3])) and np.all(np.isfinite(np.delete(got.reshape(12, 6, 6), 3, axis=0)))
    assert np.array_equal(got.reshape(12, 6, 6)[[0, 5]], dynamics.task_inertia(mech, q[[0, 5]], x[[0, 5]]))


def test_other_models_take_their_own_task_inertia(stewart):
    """Any other model, and a Stewart platform without a mass model (which refuses): ``mech.task_inertia``."""
    mech, grid = stewart
    x, q = feasible_points(mech, grid, count=20)
    with pytest.raises(ValueError, match="mass"):
        dynamics.task_inertia(mech.replace(mass_model="none"), q, x)
    other = load_preset("inverse3_prototype")
    pts = other.grid.points(other.mechanism.task_names).reshape(-1, 3)[::500]
    qo, ok = other.mechanism.inverse(pts)
    assert other.mechanism.has_mass_model and np.any(ok)
    assert np.array_equal(dynamics.task_inertia(other.mechanism, qo[ok], pts[ok]),
                          other.mechanism.task_inertia(qo[ok], pts[ok]), equal_nan=True)


@pytest.mark.parametrize("k", [40, -40])
def test_scaled_masses_scale_the_form_exactly(stewart, k):
    """Every term is one mass, tensor entry or rotor inertia times velocities: a power of two passes through."""
    mech, grid = stewart
    p = mech.params
    scale = 2.0 ** k
    scaled = mech.replace(link_masses=tuple(m * scale for m in p.link_masses), platform_mass=p.platform_mass * scale,
                          platform_inertia=tuple(i * scale for i in p.platform_inertia),
                          rotor_inertias=tuple(r * scale for r in p.rotor_inertias))
    x, q = feasible_points(mech, grid, count=50)
    assert np.array_equal(dynamics.task_inertia(scaled, q, x), dynamics.task_inertia(mech, q, x) * scale)
