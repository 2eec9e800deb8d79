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

Near a repeated eigenvalue the kernel takes Jacobi's method and numpy LAPACK's ``eigvalsh``: each is
backward stable, its eigenvalues within a few ``eps w_1`` of the exact ones (Weyl), inside the same
``8 * 2 pi eps w_1`` (``test_jacobi_gives_lapacks_eigenvalues_near_a_repeated_one``).
"""
from __future__ import annotations

import numba
import numpy as np
import pytest

from kinematics.dynamics import kinetic_form
from kinematics.registry import kind_of
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


@numba.njit(cache=False)
def _eigenvalues(mats, out):
    for i in range(mats.shape[0]):
        m = mats[i]
        hard, out[i, 0], out[i, 1], out[i, 2] = tail._eigenvalues_sym3(m[0, 0], m[0, 1], m[0, 2], m[1, 1], m[1, 2],
                                                                       m[2, 2])
        if hard:
            out[i, :] = np.nan


def test_jacobi_gives_lapacks_eigenvalues_near_a_repeated_one():
    """Symmetric positive definite matrices with two eigenvalues 1 and 1 + d (d from 1e-16 to 1e-2, where
    ``arccos`` would lose digits), the third from 1e-8 to 100, at scales 1e-30 to 1e30: the kernel's
    eigenvalues against ``numpy.linalg.eigvalsh`` within ``8 * 2 pi eps w_1`` (module docstring)."""
    rng = np.random.default_rng(5)
    n = 4000
    q = np.linalg.qr(rng.normal(size=(n, 3, 3)))[0]
    w = np.stack([np.ones(n), 1.0 + 10.0 ** rng.uniform(-16, -2, n), 10.0 ** rng.uniform(-8, 2, n)], axis=-1)
    w *= 10.0 ** rng.uniform(-30, 30, n)[:, None]
    mats = q @ (w[..., None] * np.swapaxes(q, -1, -2))
    mats = 0.5 * (mats + np.swapaxes(mats, -1, -2))
    got = np.empty((n, 3))
    _eigenvalues(mats, got)
    want = np.linalg.eigvalsh(mats)[:, ::-1]
    assert np.all(np.isfinite(got))                 # none handed back
    err = np.abs(got - want) / want[:, :1]
    assert np.all(err <= 8 * 2 * np.pi * EPS), float(np.max(err) / EPS)


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


def _kernel_presets():
    return [k for k in SQUARE if kind_of(load_preset(k).mechanism) in kernels.FAMILIES]


@pytest.mark.parametrize("key", _kernel_presets())
def test_the_compiled_pass_gives_numpys_masses_and_acceleration(key):
    """End to end: IK, J, the family's compiled kinetic form and the tail against the numpy path.

    Beyond the tail's own bounds (above), the compiled ``K`` differs from numpy's by the last bits
    of the transcendental functions in J (``DJ = 16 eps`` of ``|J|_F``, ``test_kernels``) and by
    its own roundings: the body velocities go through ``G = J^-1`` (relative error ``kappa_F(J) DJ``)
    and enter ``K`` twice, plus at most ``64 eps`` for the sums over bodies. So ``K`` and ``W = K^-1``
    (or ``J M^-1 J^T``) carry ``rel_K = 2 kappa_F(J) DJ + 64 eps``, the eigenvalues ``kappa(W) rel_K``
    and a column of ``Lambda J`` that times ``|Lambda|_F |J|_F / |(Lambda J)[:, u]|``; a factor 8 for
    the roundings not itemised, as above.
    """
    preset = load_preset(key)
    mech = preset.mechanism
    total = int(np.prod(preset.grid.resolution))
    pick = np.sort(np.random.default_rng(1).choice(total, size=min(total, 4000), replace=False))
    pts = preset.grid.points(mech.task_names, pick)
    names = MASS + ("condition_number",)
    with kernels.use_compiled(True):
        fast = evaluate(mech, pts, names)
    with kernels.use_compiled(False):
        ref = evaluate(mech, pts, names)
    assert np.array_equal(fast.feasible, ref.feasible)
    ok = ref.feasible & np.isfinite(ref.values["apparent_mass_max"]) & (ref.values["isotropic_acceleration"] > 0)
    assert ok.sum() > 100
    q, x = ref.joints[ok], pts[ok]
    jac = mech.jacobian(q, x)
    packed = _inertias(mech, q, x, jac)
    lam, mob = packed[:, 0], packed[:, 1]
    kappa_w = np.linalg.cond(mob)
    kappa_j = np.linalg.norm(jac, axis=(-2, -1)) * np.linalg.norm(np.linalg.inv(jac), axis=(-2, -1))
    rel_k = 2 * kappa_j * 16 * EPS + 64 * EPS
    mass_rel = 8 * (kappa_w * rel_k + 2 * np.pi * EPS * kappa_w)
    acc = lam @ jac
    spread = (np.linalg.norm(lam, axis=(-2, -1)) * np.linalg.norm(jac, axis=(-2, -1))
              / np.min(np.linalg.norm(acc, axis=-2), axis=-1))
    acc_rel = 8 * (kappa_w * rel_k + 16 * EPS) * spread
    for name, bound in (("apparent_mass_min", mass_rel), ("apparent_mass_max", mass_rel),
                        ("isotropic_acceleration", acc_rel)):
        got, want = fast.values[name][ok], ref.values[name][ok]
        err = np.abs(got - want) / np.abs(want)
        assert np.all(err <= bound), (key, name, float(np.max(err / bound)))
    # Where numpy says singular or unbounded, the kernel handed the point back: the same value, bit for bit.
    rest = ref.feasible & ~ok
    for name in MASS:
        assert np.array_equal(fast.values[name][rest], ref.values[name][rest], equal_nan=True), name


def _inertias(mech, q, x, jac):
    from metrics.quantity_nodes import inertias
    return inertias({"joints": q, "pose": x, "jacobian": jac}, mech)


def test_the_mass_quantities_cost_nothing_when_not_asked():
    mech = load_preset("inverse3_prototype").mechanism
    kernel = kernels.find(mech, ("isotropic_force",), DEFAULT_LOADING)
    assert kernel is not None and not kernel.want_mass and not kernel.want_acceleration
    assert kernel.mass.shape == (1,)            # no body data packed either


def test_a_model_without_a_mass_model_gets_no_kernel_for_them():
    from kinematics import Inverse3
    mech = Inverse3()
    assert not mech.has_mass_model
    assert kernels.find(mech, ("apparent_mass_min",), DEFAULT_LOADING) is None
    assert kernels.find(mech, ("isotropic_force",), DEFAULT_LOADING) is not None
def test_every_kernel_family_declares_the_mass_quantities():
    for kind, (_, names) in kernels.FAMILIES.items():
        assert set(MASS) <= set(names), kind
    assert all(kind_of(load_preset(k).mechanism) for k in SQUARE)


@pytest.mark.parametrize("key", [k for k in _kernel_presets()
                                 if load_preset(k).mechanism.joint_speed_limits() is not None])
def test_the_compiled_isotropic_velocity_is_numpys(key):
    """The velocity zonotope's inscribed radius, compiled, against the numpy path.

    Each facet offset is ``s_u |det J| / |J[:, v] x J[:, w]|`` in exact arithmetic, which moves by at
    most ``2 kappa_F(J)`` times J's relative perturbation (``DJ = 16 eps``, ``test_kernels``); numpy's
    normals come from LAPACK determinants of 2 x 2 minors and its offsets sum three terms of which
    two vanish in exact arithmetic, each within a few ``eps kappa_F(J)`` of the offset: 8 of them
    bound it, and the factor 8 of the other bounds covers the rest.
    """
    mech = load_preset(key).mechanism
    grid = load_preset(key).grid
    total = int(np.prod(grid.resolution))
    pts = grid.points(mech.task_names, np.sort(np.random.default_rng(2).choice(total, min(total, 4000), False)))
    with kernels.use_compiled(True):
        fast = evaluate(mech, pts, ("isotropic_velocity",))
    with kernels.use_compiled(False):
        ref = evaluate(mech, pts, ("isotropic_velocity",))
    ok = ref.feasible & (ref.values["isotropic_velocity"] > 0)
    jac = mech.jacobian(ref.joints[ok], pts[ok])
    kappa_j = np.linalg.norm(jac, axis=(-2, -1)) * np.linalg.norm(np.linalg.inv(jac), axis=(-2, -1))
    bound = 8 * (2 * kappa_j * 16 * EPS + 8 * EPS * kappa_j)
    got, want = fast.values["isotropic_velocity"][ok], ref.values["isotropic_velocity"][ok]
    err = np.abs(got - want) / want
    assert np.all(err <= bound), float(np.max(err / bound))
    rest = ref.feasible & ~ok
    assert np.array_equal(fast.values["isotropic_velocity"][rest], ref.values["isotropic_velocity"][rest])
