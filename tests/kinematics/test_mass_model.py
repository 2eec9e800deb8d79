"""Every preset with a mass model: its kinetic form against the bodies' own kinetic energy.

One parametrised file over the families (issue 22, sections 1 and 6). For each preset whose
mechanism has a mass model, random feasible poses are drawn from its ``[map]`` box (the fixed
coordinates at their values) through the closed-form inverse, and:

1. the kinetic form (``mass_matrix`` where the joints are independent, ``task_inertia`` for a
   redundantly actuated model) is symmetric positive definite;
2. ``1/2 udot^T K udot`` equals ``kinematics.bodies.kinetic_energy``, which differences the body
   poses along ``udot`` alone (no Jacobian is formed) -- independent of how ``K`` is assembled;
3. every body mass and inertia times ``k`` scales the link part of ``K`` by ``k``;
4. the rotors add exactly ``G^T diag(J_u N_u^2) G`` with ``G`` the analytic inverse Jacobian;
5. unphysical body input raises a ValueError naming the parameter.

Headless: numpy and the compute layer only. Fixed seeds.
"""
from __future__ import annotations

import numpy as np
import pytest

from kinematics import dynamics, kind_of
from kinematics.bodies import body_arrays, kinetic_energy
from kinematics.mass_params import MOMENTS
from resources import list_presets, load_preset

EPS = np.finfo(float).eps
PRESETS = [key for key in list_presets() if load_preset(key).mechanism.has_mass_model]


def _scales(mech, by_task: bool) -> np.ndarray:
    units = mech.task_units if by_task else mech.joint_units
    return np.array([1.0 if unit == "rad" else dynamics.LENGTH_SCALE for unit in units])


def _poses(key: str, count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``count`` random feasible ``(q, x)`` of the preset, from its map box through ``inverse``."""
    preset = load_preset(key)
    mech, grid = preset.mechanism, preset.grid
    rng = np.random.default_rng(seed)
    n = 40 * count
    x = np.empty((n, mech.task_dim))
    names = list(mech.task_names)
    for axis, lo, hi in zip(grid.axes, grid.lower, grid.upper):
        x[:, names.index(axis)] = rng.uniform(lo, hi, n)
    for name, value in grid.fixed:
        x[:, names.index(name)] = value
    q, ok = mech.inverse(x)
    keep = ok & mech.feasible(q, x) & np.all(np.isfinite(q), -1)
    # Well away from singular poses (see the energy test). J in the coordinates' own sizes (m over
    # LENGTH_SCALE, rad over 1): a unit-free condition. A redundant model's J stays regular where a
    # unit's leg is stretched (its joint rates K = dq/dx blow up instead): its force map K^T, in the
    # same sizes, is conditioned as well (paper 001's adopted pen meets such poses in its map box).
    rows, cols = _scales(mech, True), _scales(mech, False)
    cond = np.full(n, np.inf)
    with np.errstate(all="ignore"):     # only the kept rows: an unreachable pose's J is nan
        jac = mech.jacobian(q[keep], x[keep])
        c = np.linalg.cond(np.nan_to_num(jac * cols / rows[:, None], nan=np.inf))
        if mech.n_joints != mech.task_dim:
            fmap = mech.force_map(q[keep], x[keep])
            c = np.maximum(c, np.linalg.cond(np.nan_to_num(fmap * rows[:, None] / cols, nan=np.inf)))
        cond[keep] = c
        if kind_of(mech) == "twin_pantograph":
            # The redundant waist keeps J and K regular near a stretched leg; the legs' own angles
            # tell: |sin| of each forearm's angle to its upper arm (distal . tangent) above 0.1.
            cfg = mech._config(x[keep])
            sines = [np.abs(np.sum(unit.distal * unit.tangent, -1))
                     / (np.linalg.norm(unit.distal, axis=-1) * np.linalg.norm(unit.tangent, axis=-1))
                     for unit in (cfg.a, cfg.b)]
            cond[keep] = np.where(np.all(np.concatenate(sines, -1) > 0.1, -1), cond[keep], np.inf)
    keep &= np.isfinite(cond) & (cond < 20)
    q, x = q[keep][:count], x[keep][:count]
    assert len(q) == count, f"{key}: only {len(q)} feasible poses of {count} in its map box"
    return q, x


def _form(mech, q, x, rotors=True):
    """The kinetic form in the model's own coordinates (Lambda for task-placed, M for joint-placed)."""
    return dynamics.kinetic_form(mech, q, x, rotors=rotors)


def _mass_fields(mech) -> dict[str, object]:
    """Every body-mass parameter (unit kg) and body-inertia parameter (principal moments), not rotors."""
    out = {}
    for info in mech.PARAM_INFO:
        if info.unit == "kg" or (info.labels == MOMENTS and info.name != "rotor_inertias"):
            out[info.name] = getattr(mech.params, info.name)
    for name in getattr(mech.params, "__dataclass_fields__", {}):
        if name.startswith("inertia_"):            # serial_rrr's tensors, parameters outside PARAM_INFO
            out[name] = getattr(mech.params, name)
    return out


@pytest.mark.parametrize("key", PRESETS)
def test_the_kinetic_form_is_symmetric_positive_definite(key):
    mech = load_preset(key).mechanism
    q, x = _poses(key, 60, seed=1)
    square = mech.n_joints == mech.task_dim
    k = mech.mass_matrix(q, x) if square else mech.task_inertia(q, x)
    assert np.all(np.isfinite(k))
    # Lambda is symmetrised exactly; M = J^T Lambda J (base.mass_matrix) by an einsum whose two
    # triangles round differently: a few eps of |M|.
    assert np.all(np.abs(k - np.swapaxes(k, -1, -2)) <= 8 * EPS * np.abs(k).max(axis=(-1, -2), keepdims=True))
    assert np.all(np.linalg.eigvalsh(k)[..., 0] > 0)
    lam = mech.task_inertia(q, x)
    assert np.all(np.linalg.eigvalsh(lam)[..., 0] > 0)


@pytest.mark.parametrize("key", PRESETS)
def test_the_kinetic_energy_is_the_bodies_energy_from_differenced_poses(key):
    """``1/2 udot^T K udot`` against the bodies' energy differenced over ``+-dt udot``.

    Both are central differences of the same smooth pose functions. With ``udot`` of the
    coordinates' size (``LENGTH_SCALE`` m or 1 rad per unit time) and ``dt = 1e-5``, the energy's
    truncation error is relative ``~ (dt / L)^2 kappa`` (``L ~ 1`` in those units, ``kappa`` the
    poses' curvature over their slope) and its rounding ``~ eps / dt``; ``K``'s own differences are
    ``~ FD_STEP^2 kappa``. ``kappa`` grows like the inverse square of a leg's angle from its
    stretched or folded pose, faster than ``cond(J)``: at ``cond(J) = 60`` (a Haply leg 0.03 rad from
    stretched) ``K``'s step alone was off by 6e-4. With ``cond(J) < 20`` (``_poses``) ``kappa`` stays
    below ~1e3: ``1e3 (1e-10 + 2e-11 + 4e-11) ~ 2e-7``, bound 1e-6 of the energy (measured: at most
    8e-8 for the five-bars).
    """
    mech = load_preset(key).mechanism
    q, x = _poses(key, 40, seed=2)
    by_task = mech.mass_coordinates == "task"
    u = x if by_task else q
    rng = np.random.default_rng(3)
    udot = rng.standard_normal(u.shape) * _scales(mech, by_task)
    form = _form(mech, q, x, rotors=False)
    ours = 0.5 * np.einsum("...a,...ab,...b->...", udot, form, udot)
    masses, com, tensors = body_arrays(mech.bodies())
    dt = 1e-5
    theirs = kinetic_energy(masses, tensors, com, dynamics._placer(mech, by_task), u, udot, dt)
    assert np.all(theirs > 0)
    assert np.all(np.abs(ours - theirs) <= 1e-6 * theirs)


@pytest.mark.parametrize("k", [2.0**-30, 0.3, 7.0, 2.0**30])
@pytest.mark.parametrize("key", PRESETS)
def test_body_masses_and_inertias_times_k_scale_the_link_part_by_k(key, k):
    mech = load_preset(key).mechanism
    fields = _mass_fields(mech)
    assert "link_masses" in fields
    scaled = mech.replace(**{name: (tuple(k * v for v in value) if isinstance(value, tuple) else k * value)
                             for name, value in fields.items()})
    q, x = _poses(key, 10, seed=4)
    a, b = _form(mech, q, x, rotors=False), _form(scaled, q, x, rotors=False)
    # The differences place the bodies identically (steps depend on u only) and the form is a sum
    # of mass- and inertia-weighted products: a power of two scales exactly, another k within a
    # few roundings of each of the ~3 k terms of an entry (k bodies).
    tol = 0 if np.log2(k) == round(np.log2(k)) else 64 * EPS
    assert np.all(np.abs(b - k * a) <= tol * k * np.abs(a).max(axis=(-1, -2), keepdims=True))


@pytest.mark.parametrize("key", PRESETS)
def test_the_rotors_add_their_inertia_through_the_inverse_jacobian(key):
    """``K - K_links = G^T diag(J_u N_u^2) G``, ``G = J^-1`` (task-placed) or the identity (joint-placed).

    The model differences ``G = dq/dx`` with the bodies (relative ``~ FD_STEP^2 kappa``, 4e-8 with
    ``kappa`` up to 1e3); ``G`` here is the analytic ``inv(J)``. Bound: 1e-6 of ``|G^T R G|``.
    """
    mech = load_preset(key).mechanism
    q, x = _poses(key, 20, seed=5)
    diff = _form(mech, q, x) - _form(mech, q, x, rotors=False)
    reflected = np.asarray(mech.reflected_rotor_inertias())     # J_u N_u^2 of the actuated joints
    assert np.all(reflected > 0)
    if mech.mass_coordinates == "joint":
        expected = np.broadcast_to(np.diag(reflected), diff.shape)
        tol = 16 * EPS * np.abs(_form(mech, q, x)).max()
    elif mech.n_joints == mech.task_dim:
        g = np.linalg.inv(mech.jacobian(q, x))
        expected = np.einsum("...ua,u,...ub->...ab", g, reflected, g)
        tol = 1e-6 * np.abs(expected).max(axis=(-1, -2), keepdims=True)
    else:                                   # redundant: each actuator's rate from the inverse kinematics
        g = _inverse_jacobian(mech, x)
        expected = np.einsum("...ua,u,...ub->...ab", g, reflected, g)
        tol = 1e-6 * np.abs(expected).max(axis=(-1, -2), keepdims=True)
    assert np.all(np.abs(diff - expected) <= tol)


def _inverse_jacobian(mech, x):
    """``dq/dx`` (..., n, m) of a redundantly actuated model from its analytic per-leg Jacobian."""
    return mech.inverse_jacobian(mech.inverse(x)[0], x)


@pytest.mark.parametrize("key", PRESETS)
def test_rotor_inertias_scale_with_the_gear_ratio_squared(key):
    mech = load_preset(key).mechanism
    q, x = _poses(key, 5, seed=6)
    base = _form(mech, q, x) - _form(mech, q, x, rotors=False)
    geared = mech.replace(gear_ratios=tuple(2.0 * g for g in mech.params.gear_ratios))
    doubled = _form(geared, q, x) - _form(geared, q, x, rotors=False)
    scale = np.abs(_form(geared, q, x)).max()
    assert np.all(np.abs(doubled - 4.0 * base) <= 64 * EPS * scale)


@pytest.mark.parametrize("key", PRESETS)
def test_unphysical_body_input_names_its_parameter(key):
    mech = load_preset(key).mechanism
    masses = mech.params.link_masses
    for bad in (-0.01, 0.0, float("nan")):
        with pytest.raises(ValueError, match="link_masses"):
            mech.replace(link_masses=(bad, *masses[1:]))
    with pytest.raises(ValueError, match="rotor_inertias"):
        mech.replace(rotor_inertias=(-1e-7, *mech.params.rotor_inertias[1:]))
    for info in mech.PARAM_INFO:
        if info.labels == MOMENTS:
            with pytest.raises(ValueError, match=f"{info.name}.*triangle"):
                mech.replace(**{info.name: (1e-4, 1e-4, 3e-4)})
            with pytest.raises(ValueError, match=info.name):
                mech.replace(**{info.name: (-1e-4, 1e-4, 1e-4)})
        elif info.unit == "kg" and not info.is_vector:
            with pytest.raises(ValueError, match=info.name):
                mech.replace(**{info.name: -0.01})


@pytest.mark.parametrize("key", PRESETS)       # every family can switch its bodies off
def test_without_a_mass_model_the_dynamics_are_refused_with_the_reason(key):
    mech = load_preset(key).mechanism
    bare = mech.replace(mass_model="none")
    assert not bare.has_mass_model
    q, x = _poses(key, 2, seed=7)
    with pytest.raises(ValueError, match="no mass model"):
        bare.task_inertia(q, x)


def test_every_family_but_the_serial_arm_places_its_bodies_from_the_task_pose():
    kinds = {load_preset(key).kind: load_preset(key).mechanism.mass_coordinates for key in PRESETS}
    assert all(coords == ("joint" if kind == "serial_rrr" else "task") for kind, coords in kinds.items())
