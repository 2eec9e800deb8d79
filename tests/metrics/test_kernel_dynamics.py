"""The compiled mass quantities (``metrics.kernels.dynamics``) give the numpy path's numbers.

References: ``metrics.quantities.evaluate`` on the numpy path (``kernels.use_compiled(False)``), the
reference of every formula. Here the compiled tail gets numpy's own kinetic form ``K``
(``kinematics.dynamics.kinetic_form``) and ``J`` (the model's ``jacobian``), so what is compared is
the tail alone; ``test_kernel_mass_*`` compare each family's compiled ``K`` with numpy's, and the
end-to-end test at the bottom both together.

Tolerances, per point. Task-placed models: the mobility ``K^-1`` is the same adjugate formula in
both paths, bit for bit; the eigenvalues then differ only by the last bits of ``acos``/``cos``
(libm against numpy's loops): a 1-ulp change moves each eigenvalue by at most ``2 pi eps p <= 2 pi
eps w_1``, so the smallest apparent mass ``1 / w_1`` by ``2 pi eps`` relative and the largest,
``1 / w_m``, by ``2 pi eps kappa(W)``. Joint-placed models form ``W = J M^-1 J^T`` by matrix
products whose summation order may differ from numpy's: each entry within ``6 eps`` of
``(|J| |M^-1| |J|^T)_ij``, so every eigenvalue within ``6 eps |J|_F^2 |M^-1|_F`` (Weyl), and
``Lambda = W^-1`` within ``kappa(W)`` times that relative. The isotropic acceleration is a column
norm of ``Lambda J``: relative error at most the error of ``Lambda`` times ``|J|_F / min_u
|(Lambda J)[:, u]| * |Lambda|_F``, plus ``3 eps`` for the products and the square root. The bounds
below take each term with a factor of 8 for the few roundings not itemised.
"""
from __future__ import annotations

import numba
import numpy as np
import pytest

from kinematics.dynamics import kinetic_form
from metrics import kernels
from metrics.kernels import dynamics as tail
from metrics.loading import DEFAULT_LOADING
from metrics.quantities import evaluate
from resources import list_presets, load_preset

EPS = np.finfo(float).eps
MASS = ("apparent_mass_min", "apparent_mass_max", "isotropic_acceleration")
SQUARE = [k for k in list_presets() if load_preset(k).mechanism.has_mass_model
          and not load_preset(k).mechanism.is_redundant and load_preset(k).mechanism.task_dim in (2, 3)
          and load_preset(k).mechanism.n_joints == load_preset(k).mechanism.task_dim
          and not load_preset(k).mechanism.has_orientation]


@numba.njit(cache=False)
def _tail3(form, jac, t, joint_placed, out, back):
    for i in range(form.shape[0]):
        k, a = form[i], jac[i]
        back[i] = tail.dynamics3(k[0, 0], k[0, 1], k[0, 2], k[1, 1], k[1, 2], k[2, 2], a[0, 0], a[0, 1], a[0, 2],
                                 a[1, 0], a[1, 1], a[1, 2], a[2, 0], a[2, 1], a[2, 2], joint_placed, t, out, i,
                                 True, True)


@numba.njit(cache=False)
def _tail2(form, jac, t, out, back):
    for i in range(form.shape[0]):
        k, a = form[i], jac[i]
        back[i] = tail.dynamics2(k[0, 0], k[0, 1], k[1, 1], a[0, 0], a[0, 1], a[1, 0], a[1, 1], t, out, i, True, True)


def _feasible_points(preset, count, seed=0):
    """``count`` feasible points of the preset's own grid (a fixed random subset), with their joints."""
    mech = preset.mechanism
    grid = preset.grid
    rng = np.random.default_rng(seed)
    total = int(np.prod(grid.resolution))
    pick = np.sort(rng.choice(total, size=min(total, 40 * count), replace=False))
    pts = grid.points(mech.task_names, pick)
    with kernels.use_compiled(False):
        ref = evaluate(mech, pts, MASS + ("condition_number",))
    keep = np.flatnonzero(ref.feasible)[:count]
    return pts[keep], ref.joints[keep], {n: ref.values[n][keep] for n in MASS}


def _bounds(mech, form, jac):
    """Per-point relative tolerances (module docstring) for the two masses and the acceleration."""
    joint_placed = mech.mass_coordinates == "joint"
    if joint_placed:
        minv = np.linalg.inv(form)
        mob = jac @ minv @ np.swapaxes(jac, -1, -2)
        spread = (np.linalg.norm(jac, axis=(-2, -1)) ** 2 * np.linalg.norm(minv, axis=(-2, -1))
                  / np.linalg.norm(mob, 2, axis=(-2, -1)))
    else:
        mob = np.linalg.inv(form)
        spread = np.ones(len(form))
    kappa = np.linalg.cond(mob)
    lam = np.linalg.inv(mob)
    acc = lam @ jac
    lam_rel = 8 * 6 * EPS * spread * kappa if joint_placed else np.zeros(len(form))
    acc_rel = (lam_rel * np.linalg.norm(lam, axis=(-2, -1)) * np.linalg.norm(jac, axis=(-2, -1))
               / np.min(np.linalg.norm(acc, axis=-2), axis=-1)) + 8 * 3 * EPS
    mass_rel = 8 * (2 * np.pi * EPS + 6 * EPS * spread) * kappa
    return {"apparent_mass_min": mass_rel, "apparent_mass_max": mass_rel, "isotropic_acceleration": acc_rel}


@pytest.mark.parametrize("key", SQUARE)
def test_the_compiled_tail_gives_numpys_masses_and_acceleration(key):
    preset = load_preset(key)
    mech = preset.mechanism
    x, q, ref = _feasible_points(preset, 300)
    form = kinetic_form(mech, q, x)
    jac = mech.jacobian(q, x)
    t = np.ascontiguousarray(DEFAULT_LOADING.torque_limits(mech), float)
    out = np.full((9, len(x)), np.nan)
    back = np.zeros(len(x), bool)
    if mech.task_dim == 3:
        _tail3(np.ascontiguousarray(form), np.ascontiguousarray(jac), t, mech.mass_coordinates == "joint", out, back)
    else:
        assert mech.mass_coordinates == "task"
        _tail2(np.ascontiguousarray(form), np.ascontiguousarray(jac), t, out, back)
    done = ~back
    assert done.sum() >= 0.5 * len(x), f"{key}: the tail handed back {back.sum()} of {len(x)} points"
    bounds = _bounds(mech, form[done], jac[done])
    for row, name in enumerate(MASS):
        got, want = out[6 + row, done], ref[name][done]
        assert np.all(np.isfinite(got)), name
        err = np.abs(got - want) / np.abs(want)
        assert np.all(err <= bounds[name]), (key, name, float(np.max(err / bounds[name])))


def test_a_singular_jacobian_or_mass_is_handed_back():
    out = np.full((9, 1), np.nan)
    t = np.ones(3)
    eye = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    # J with a zero column (an inverse singularity), a rank-deficient kinetic form, and a huge scale.
    assert _one((1.0, 0.0, 0.0, 1.0, 0.0, 1.0), (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0), t, out)
    assert _one((1.0, 1.0, 0.0, 1.0, 0.0, 1.0), eye, t, out)
    assert _one((1e300, 0.0, 0.0, 1e300, 0.0, 1e300), eye, t, out)
    # A regular one is not: unit masses, unit J, unit torques give 1 kg and 1 m/s^2.
    assert not _one((1.0, 0.0, 0.0, 1.0, 0.0, 1.0), eye, t, out)
    assert np.all(out[6:, 0] == 1.0)


def _one(k, a, t, out):
    return _tail3_one(np.array(k), np.array(a), t, out)


@numba.njit(cache=False)
def _tail3_one(k, a, t, out):
    return tail.dynamics3(k[0], k[1], k[2], k[3], k[4], k[5], a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8],
                          False, t, out, 0, True, True)
