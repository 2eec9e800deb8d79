"""The compiled Inverse3 kinetic form (``metrics.kernels.inverse3_mass``) against ``kinetic_form``.

Points: a fixed random subset of each shipped Inverse3 preset's own grid (the ``theta_0 = 0``
slice) and the same points turned about the base axis (so that ``theta_0`` varies), kept where
feasible and ``cond(J) <= FAST_COND_LIMIT`` (the kernel's domain: the caller hands the rest to numpy).
"""
from __future__ import annotations

import numpy as np
import pytest

from kinematics.bodies import Body, body_arrays
from kinematics.dynamics import kinetic_form
from kinematics.inverse3 import Inverse3
from kinematics.registry import kind_of
from metrics.kernels import inverse3_mass as km
from metrics.linalg import FAST_COND_LIMIT
from resources import list_presets, load_preset

EPS = np.finfo(float).eps
PRESETS = [key for key, mech in ((key, load_preset(key).mechanism) for key in list_presets())
           if kind_of(mech) == "inverse3" and mech.has_mass_model]
#: Roundings along the longest chain from the shared G and sin/cos to one velocity component
#: (products with lengths, the link's direction and 1/|P - elbow|, sums of at most 4 terms).
VELOCITY_DEPTH = 8
#: Roundings of the sums that make one entry from products of two components (3 components or
#: 3 x 3 tensor terms, 5 bodies, the handle and the rotors: a summation depth of at most 10).
SUM_DEPTH = 10


def _points(mech, grid, count, seed):
    """``count`` feasible, regular points of ``grid`` and ``count`` turned about z: x (k, 3), q, J."""
    pts = grid.points(mech.task_names).reshape(-1, 3)
    rng = np.random.default_rng(seed)
    x = pts[rng.choice(len(pts), 20 * count, replace=False)]
    turn = rng.uniform(mech.params.lower_limits[0], mech.params.upper_limits[0], len(x))
    c, s = np.cos(turn), np.sin(turn)
    turned = np.stack([c * x[:, 0] - s * x[:, 1], s * x[:, 0] + c * x[:, 1], x[:, 2]], axis=-1)
    out = []
    for cloud in (x, turned):
        q, ok = mech.inverse(cloud)
        ok &= mech.feasible(q, cloud)
        cloud, q = cloud[ok], q[ok]
        jac = mech.jacobian(q)
        regular = np.linalg.cond(jac) <= FAST_COND_LIMIT
        assert regular.sum() >= count
        out.append((cloud[regular][:count], q[regular][:count], jac[regular][:count]))
    return tuple(np.concatenate(parts) for parts in zip(*out))


def _rates_bound(mech, q, x, jac):
    """``s`` (k, 3): per task rate ``a``, a bound whose products ``s_a s_b`` bound the magnitudes of the
    terms either implementation sums into ``Lambda[a, b]``.

    Every body velocity per task rate is, in exact arithmetic, its joint-rate Jacobian times a
    column of ``G``: ``C G e_a`` with ``C = (dc_b/dx) J`` (``centre_jacobians``), ``(dw_b/dx) J``.
    Either implementation forms each component as a sum of geometric factors times entries of
    ``G`` (or, for the handle's own rate, ``J G = I``), whose absolute values add up to at most
    ``(|C| |G|)[i, a]``. Taken to the body's axes (a rotation), a component's bound grows by at most
    ``sqrt(3)`` times the 2-norm of these. So ``s_a^2 = sum_b m_b |v_a|^2 + ||I_b||_F |w_a|^2 +
    sum_u r_u G_ua^2`` with ``v_a``, ``w_a`` those columns, and every term of ``Lambda[a, b]`` is at
    most ``3 s_a s_b`` in magnitude (Cauchy-Schwarz).
    """
    jv, jw, _, g = mech.body_velocities(q, x)
    masses, _, tensors = body_arrays(mech.bodies())
    spread = np.abs(np.moveaxis(g, -1, 0))                                           # |G| (k, 3, 3)
    total = np.einsum("u,kua->ka", mech.reflected_rotor_inertias(), spread ** 2)
    for mass, tensor, v, w in zip(masses, tensors, jv, jw):
        v = np.abs(np.moveaxis(v, -1, 0) @ jac) @ spread
        w = np.abs(np.moveaxis(w, -1, 0) @ jac) @ spread
        total += mass * (v ** 2).sum(axis=1) + np.linalg.norm(tensor) * (w ** 2).sum(axis=1)
    return np.sqrt(total)


def _tolerance(mech, q, x, jac):
    """The bound (k, 3, 3) on ``|inertia - kinetic_form|`` at the points, in kg.

    Each implementation forms a velocity component within ``VELOCITY_DEPTH`` roundings of its
    absolute-term bound, times the distal link's direction's cancellation: ``e_x = (P - elbow) /
    |P - elbow|`` is a difference of points up to ``|P - O| + l1 <= 2 l1 + l2`` from the motors'
    centre, ``l2`` apart, so its error is ``(2 l1 + l2) / l2`` times a relative one. A product of two
    components is then within ``2 VELOCITY_DEPTH reach + 1`` roundings of the product of bounds, the
    entry's sums ``SUM_DEPTH`` more, over terms of at most ``3 s_a s_b`` (``_rates_bound``). Their
    difference: twice that. sin/cos within 1 ulp between libm and numpy count among the roundings;
    G is the same in both (the same adjugate, the same J).

    The kernel takes another route to the same sums: each body's components per unit joint rate
    (no G in them: at most ``VELOCITY_DEPTH - 2`` roundings, the J entries of P's velocity counted
    with the sin/cos), the joint-space form from them (``SUM_DEPTH``), then ``G^T M G`` (two sums of
    three products: 6 more roundings, over terms whose absolute values add up to the same
    ``3 s_a s_b``, as ``|G|^T |M| |G|`` is the bound above taken before the sums). Its error is then
    within ``2 (VELOCITY_DEPTH - 2) reach + 1 + SUM_DEPTH + 6`` roundings and numpy's within
    ``2 VELOCITY_DEPTH reach + 1 + SUM_DEPTH``: together at most twice the latter while ``4 reach >= 6``,
    and ``reach >= 1 + 2 l1 / l2`` is 2.7 on every preset.
    """
    p = mech.params
    reach = (2 * p.proximal_length + p.distal_length) / p.distal_length
    s = _rates_bound(mech, q, x, jac)
    return 2 * 3 * (2 * VELOCITY_DEPTH * reach + 1 + SUM_DEPTH) * EPS * s[:, :, None] * s[:, None, :]


def _assert_matches_numpy(mech, x, q, jac):
    got = km.inertia_points(x, q, np.ascontiguousarray(jac), km.pack_mass(mech))
    want = kinetic_form(mech, q, x)
    tol = _tolerance(mech, q, x, jac)
    assert np.all(np.abs(got - want) <= tol), np.max(np.abs(got - want) / tol)
    assert np.array_equal(got, np.swapaxes(got, 1, 2))


@pytest.mark.parametrize("key", PRESETS)
def test_kinetic_form_matches_numpy_on_preset_grid(key):
    preset = load_preset(key)
    mech = preset.mechanism
    _assert_matches_numpy(mech, *_points(mech, preset.grid, 300, seed=11))


class _Offset(Inverse3):
    """Inverse3 whose bodies have centres off their frames' axes and full (rotated) inertia tensors:
    every term ``inertia`` reads from ``pack_mass`` is nonzero (the presets' are mostly 0)."""

    def bodies(self):
        rng = np.random.default_rng(5)
        out = []
        for body in super().bodies():
            turn, _ = np.linalg.qr(rng.normal(size=(3, 3)))
            tensor = turn @ np.diag(rng.uniform(2e-5, 4e-5, 3)) @ turn.T    # moments obey the triangle rule
            com = np.add(body.com, rng.uniform(-0.02, 0.02, 3))
            inertia = (*np.diag(tensor), tensor[0, 1], tensor[0, 2], tensor[1, 2])
            out.append(Body(body.name, body.mass, tuple(map(float, com)), tuple(map(float, inertia))))
        return tuple(out)


def test_general_centres_and_tensors_match_numpy():
    preset = load_preset(PRESETS[0])
    mech = _Offset(preset.mechanism.params)
    _assert_matches_numpy(mech, *_points(mech, preset.grid, 200, seed=12))


@pytest.mark.parametrize("k", [40, -40])
def test_scaled_masses_scale_the_form_exactly(k):
    preset = load_preset(PRESETS[0])
    mech = preset.mechanism
    x, q, jac = _points(mech, preset.grid, 100, seed=13)
    p, f = mech.params, 2.0 ** k
    scaled = mech.replace(link_masses=tuple(f * m for m in p.link_masses),
                          turret_inertia=tuple(f * i for i in p.turret_inertia), handle_mass=f * p.handle_mass,
                          rotor_inertias=tuple(f * r for r in p.rotor_inertias))
    jac = np.ascontiguousarray(jac)
    got = km.inertia_points(x, q, jac, km.pack_mass(scaled))
    assert np.array_equal(got, f * km.inertia_points(x, q, jac, km.pack_mass(mech)))


def test_rotor_term_alone_is_g_transpose_r_g():
    preset = load_preset(PRESETS[0])
    mech = preset.mechanism
    x, q, jac = _points(mech, preset.grid, 200, seed=14)
    mp = km.pack_mass(mech)
    mp[km.BODY0:] = 0.0                                # no bodies: masses, centres, tensors 0
    got = km.inertia_points(x, q, np.ascontiguousarray(jac), mp)
    g = np.moveaxis(mech.body_velocities(q, x)[3], -1, 0)        # the numpy model's G = J^-1, (k, 3, 3)
    r = mech.reflected_rotor_inertias()
    want = np.einsum("kua,u,kub->kab", g, r, g)
    # G is bit for bit the model's (the same adjugate); each side rounds (G_ua r_u) G_ub twice and
    # sums three such terms (two more): within 4 eps of sum_u |G_ua| r_u |G_ub| each.
    bound = np.einsum("kua,u,kub->kab", np.abs(g), r, np.abs(g))
    assert np.all(np.abs(got - want) <= 2 * 4 * EPS * bound)
    # And the links alone: the kernel without rotors is kinetic_form(rotors=False).
    mp = km.pack_mass(mech)
    mp[km.ROTORS:km.BODY0] = 0.0
    links = km.inertia_points(x, q, np.ascontiguousarray(jac), mp)
    assert np.all(np.abs(links - kinetic_form(mech, q, x, rotors=False)) <= _tolerance(mech, q, x, jac))


def test_pack_mass_layout():
    mech = load_preset(PRESETS[0]).mechanism
    mp = km.pack_mass(mech)
    assert mp.shape == (km.SIZE,)
    assert np.array_equal(mp[km.ROTORS:km.BODY0], mech.reflected_rotor_inertias())
    for b, body in enumerate(mech.bodies()):
        k = km.BODY0 + km.BODY_SIZE * b
        assert mp[k] == body.mass and tuple(mp[k + 1:k + 4]) == body.com and tuple(mp[k + 4:k + 10]) == body.inertia
