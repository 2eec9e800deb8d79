"""The five-bar's compiled kinetic form (``metrics.kernels.fivebar_mass``) against ``kinetic_form``.

Reference: ``kinematics.dynamics.kinetic_form(mech, q, x)`` (the model's exact body velocities),
at feasible, non-singular points of every shipped five-bar preset with a mass model.

Tolerance (``_bound``). Both sides compute the same exact ``Lambda(q, x)`` from the same ``q`` and
``x``, by different roundings (libm's sines and cosines here, numpy's there, each within a few
ulps; reciprocals here, quotients and 3 x 3 frames there). First order in eps, every factor a
term is built from carries an error within ``30 eps kappa`` of its magnitude ("shadow", the same
expression with every sum of absolute values):

- ``p_i = C - B_i``: within ``6 eps P_i`` (two sums and ``a1 cos q_i`` to 4 ulps), ``P_i`` its
  shadow ``(|x| + a3 + a1, |y| + a1)``;
- ``jt_i = a1 p_i . t_i``: within ``13 eps a1 (P_i0 + P_i1)``, relative ``13 eps (kappa_i - 1)``,
  ``kappa_i = 1 + a1 (P_i0 + P_i1) / |jt_i| + (a3 + a1) / a1`` (the last term: numpy's proximal
  frame normalises ``(O_i + a1 (c, s)) - O_i``, a1's length to ``eps (a3 + a1)``);
- then ``g_i = p_i / jt_i``, the distal unit vectors, spins and centre velocities, a few roundings
  more each (``kappa >= 1`` and ``kappa_i >= (P_i0 + P_i1) / a2``, the unit vectors' amplification).

A term is a product of two factors (``m v_j . v_k``, ``I s_j s_k``, ``J g_ij g_ik``), within
``60 eps kappa`` of its shadow, and the sums over the five bodies and the symmetrisation add a
few eps of the shadow: each side within ``64 eps kappa K_abs`` of the exact form, the two within
``128 eps kappa K_abs`` of each other. ``K_abs`` is the shadow form (``_bound``), ``kappa`` the
larger ``kappa_i``. The bound is checked to have teeth (far below the entries' size).
"""
from __future__ import annotations

import numpy as np
import pytest

from kinematics.bodies import Body
from kinematics.dynamics import kinetic_form
from kinematics.fivebar import FiveBar
from kinematics.registry import kind_of
from metrics.kernels import fivebar_mass
from metrics.kernels.fivebar_mass import BODIES, BODY_SIZE, SIZE, inertia_points, pack_mass
from resources import list_presets, load_preset

EPS = np.finfo(float).eps
#: Points per preset: a random subset (fixed seed) of the preset grid's feasible, regular points.
SAMPLES = 300
#: Two sides, each within 64 eps kappa K_abs of the exact form (module docstring).
C_BOUND = 128.0


def _presets() -> list[str]:
    keys = []
    for key in list_presets():
        mech = load_preset(key).mechanism
        if kind_of(mech) == "fivebar" and mech.has_mass_model:
            keys.append(key)
    return keys


PRESETS = _presets()


def _points(preset, seed: int = 20261207):
    """``SAMPLES`` feasible, non-singular grid points of ``preset``: ``x`` (k, 2), ``q`` (k, 2), ``J`` (k, 2, 2)."""
    mech = preset.mechanism
    x = preset.grid.points(mech.task_names).reshape(-1, 2)
    q, ok = mech.inverse(x)
    ok &= mech.feasible(q, x)
    ok[ok] = mech.singularity(q[ok], x[ok]) == 0      # the caller hands singular poses to numpy
    at = np.random.default_rng(seed).choice(np.flatnonzero(ok), SAMPLES, replace=False)
    x, q = np.ascontiguousarray(x[at]), np.ascontiguousarray(q[at])
    return x, q, np.ascontiguousarray(mech.jacobian(q, x))


def _bound(q: np.ndarray, x: np.ndarray, mp: np.ndarray) -> np.ndarray:
    """``C_BOUND eps kappa K_abs`` per entry, (k, 2, 2) (module docstring)."""
    a1, a3 = mp[0], mp[2]
    bodies = mp[3:3 + BODY_SIZE * len(BODIES)].reshape(len(BODIES), BODY_SIZE)
    mass, cxy, izz = bodies[:, 0], np.hypot(bodies[:, 1], bodies[:, 2]), bodies[:, 6]
    rotors = mp[3 + BODY_SIZE * len(BODIES):]
    c, s = np.cos(q), np.sin(q)
    shadow = np.zeros((len(q), 2, 2))
    shadow[:, 0, 0] = shadow[:, 1, 1] = mass[4]                                        # handle
    kappa = np.ones(len(q))
    for i, base in enumerate((-a3, a3)):
        p = np.stack([x[:, 0] - (base + a1 * c[:, i]), x[:, 1] - a1 * s[:, i]], -1)
        big = np.stack([np.abs(x[:, 0]) + a3 + a1, np.abs(x[:, 1]) + a1], -1)          # P_i
        jt = np.abs(a1 * (-p[:, 0] * s[:, i] + p[:, 1] * c[:, i]))
        kappa = np.maximum(kappa, 1.0 + a1 * big.sum(-1) / jt + (a3 + a1) / a1)
        g = big / jt[:, None]                                                            # |g_i|'s shadow
        joint = izz[i] + mass[i] * cxy[i] ** 2 + rotors[i]
        spin = (1.0 + a1 * g) / np.hypot(p[:, 0], p[:, 1])[:, None]
        v = a1 * g + spin * cxy[2 + i]
        shadow += joint * _outer(g) + mass[2 + i] * _outer(v) + izz[2 + i] * _outer(spin)
    return C_BOUND * EPS * kappa[:, None, None] * shadow


def _outer(u: np.ndarray) -> np.ndarray:
    """``u u^T`` per row, (k, 2) -> (k, 2, 2)."""
    return u[:, :, None] * u[:, None, :]


@pytest.mark.parametrize("key", PRESETS)
def test_matches_kinetic_form(key):
    preset = load_preset(key)
    mech = preset.mechanism
    x, q, jac = _points(preset)
    mp = pack_mass(mech)
    got = inertia_points(x, q, jac, mp)
    ref = kinetic_form(mech, q, x)
    bound = _bound(q, x, mp)
    assert np.all(np.abs(got - ref) <= bound)
    assert np.all(got == np.swapaxes(got, 1, 2))
    # Teeth: the bound is a small multiple of eps of the entries, not of their size.
    assert np.median(bound / np.abs(ref).max(axis=(1, 2))[:, None, None]) < 1e-11


@pytest.mark.parametrize("k", [40, -40])
def test_scales_with_the_masses_exactly(k):
    """Every mass, tensor and rotor times 2**k: the form times 2**k, bit for bit (every term is linear
    in one of them and a power-of-two factor commutes with rounding, far from over- and underflow)."""
    preset = load_preset(PRESETS[0])
    mech = preset.mechanism
    p = mech.params
    scale = 2.0 ** k
    heavy = mech.replace(link_masses=tuple(m * scale for m in p.link_masses), handle_mass=p.handle_mass * scale,
                         rotor_inertias=tuple(r * scale for r in p.rotor_inertias))
    x, q, jac = _points(preset)
    mp, mp_heavy = pack_mass(mech), pack_mass(heavy)
    assert np.array_equal(mp_heavy[3:], mp[3:] * np.where(_mass_entries(), scale, 1.0)[3:])
    assert np.array_equal(inertia_points(x, q, jac, mp_heavy), scale * inertia_points(x, q, jac, mp))


def _mass_entries() -> np.ndarray:
    """Which entries of ``pack_mass``' array are masses, tensors or rotors (not lengths or centres)."""
    mask = np.zeros(SIZE, bool)
    for b in range(len(BODIES)):
        at = 3 + BODY_SIZE * b
        mask[at] = True
        mask[at + 4:at + 10] = True
    mask[3 + BODY_SIZE * len(BODIES):] = True
    return mask


@pytest.mark.parametrize("key", PRESETS)
def test_rotors_alone(key):
    """Bodies zeroed in the packed array (the model refuses massless links): ``G^T diag(r) G``, ``G = dq/dx``
    the model's (``body_velocities``); and the rotors are the form's whole difference to ``rotors=False``."""
    preset = load_preset(key)
    mech = preset.mechanism
    x, q, jac = _points(preset)
    mp = pack_mass(mech)
    rotors_only = np.where(_mass_entries(), 0.0, mp)
    rotors_only[3 + BODY_SIZE * len(BODIES):] = mech.reflected_rotor_inertias()
    got = inertia_points(x, q, jac, rotors_only)
    g = np.moveaxis(mech.body_velocities(q, x)[3], -1, 0)                              # (k, 2, 2)
    ref = np.einsum("kua,u,kub->kab", g, mech.reflected_rotor_inertias(), g)
    assert np.all(np.abs(got - ref) <= _bound(q, x, rotors_only))
    bare = pack_mass(mech, rotors=False)
    links = inertia_points(x, q, jac, bare)
    assert np.all(np.abs(links - kinetic_form(mech, q, x, rotors=False)) <= _bound(q, x, bare))


class _OffAxis(FiveBar):
    """A five-bar whose bodies have centres off their axes and full tensors (the presets' rods have neither)."""

    def bodies(self):
        out = []
        for b, body in enumerate(super().bodies()):
            m, length = body.mass, max(body.com[0], 0.05) * 2.0
            sign = 1.0 if b % 2 else -1.0
            tensor = tuple(m * length**2 * f for f in (0.02, 0.08, 0.09, 0.01, 0.005, 0.003))
            out.append(Body(body.name, m, (body.com[0], sign * 0.3 * length, 0.2 * length), tensor))
        return tuple(out)


@pytest.mark.parametrize("key", PRESETS)
def test_off_axis_centres_and_full_tensors(key):
    """Centres off the link (c_y != 0, c_z != 0) and every tensor entry set, the handle's too: only c_x, c_y and
    I_zz of the links move ``Lambda``, as in the numpy path (module docstring of ``fivebar_mass``)."""
    preset = load_preset(key)
    mech = _OffAxis(preset.mechanism.params)
    x, q, jac = _points(preset)
    mp = pack_mass(mech)
    ref = kinetic_form(mech, q, x)
    bound = _bound(q, x, mp)
    assert np.all(np.abs(inertia_points(x, q, jac, mp) - ref) <= bound)
    # Not the rods' form: at every point some entry moved by far more than the bound.
    moved = np.abs(ref - kinetic_form(preset.mechanism, q, x)) - bound
    assert np.all(moved.max(axis=(1, 2)) > 0.0)


def test_pack_layout():
    mech = load_preset(PRESETS[0]).mechanism
    mp = pack_mass(mech)
    assert mp.shape == (SIZE,) and mp.dtype == np.float64
    for b, body in enumerate(mech.bodies()):
        at = 3 + BODY_SIZE * b
        assert (mp[at], tuple(mp[at + 1:at + 4]), tuple(mp[at + 4:at + 10])) == (body.mass, body.com, body.inertia)
    assert np.array_equal(mp[-2:], mech.reflected_rotor_inertias())
    assert fivebar_mass.BODIES == tuple(b.name for b in mech.bodies())
