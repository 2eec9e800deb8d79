"""The delta family's compiled kinetic form (``metrics.kernels.delta_mass``) against ``kinetic_form``.

Reference: ``kinematics.dynamics.kinetic_form(mech, q, x)``, from the model's exact body velocities
(``Delta.body_velocities``). Both paths form the same columns (each body's centre velocity and
body-axis angular velocity per task direction, and ``G = dq/dx``) from the same ``x`` and ``q``: the
model by its equations, the kernel by their closed forms (identities of orthonormal frames, exact
in exact arithmetic; ``delta_mass``'s docstring). So they differ by rounding only, bounded as
follows (``u = eps / 2``):

- A column's longest chain in the model (knee, bar ``n_i``, ``B_ii = n_i . dK_i``, ``G``'s row, the
  knee's rate, the radial rate, the bar's end rates, its frame's rate, the centre's velocity) has
  at most ``N = 40`` roundings, each relative ``u`` to its own operand (the trigonometric values of
  ``q`` within an ulp: libm here, numpy's loops there); the kernel's closed forms are shorter. The
  model's frames are orthonormal to a few ``u``, so the identities the kernel uses hold there to
  the same order, one more rounding per use, inside ``N``.
- The one cancelling step is ``B_ii``, a sum of products of size ``|n_i| |dK_i|``: it is off by a
  few ``u`` of that, relative ``u kappa_i`` to itself with ``kappa_i = |n_i| |dK_i| / |B_ii|``, and so
  are ``G``'s row i and every part linear in it. Those parts are the knee's velocity, of size
  ``|dK_i| |G_i| = kappa_i``, against the platform's unit velocity: an operand is at most
  ``1 + kappa_i`` times the size of the column it ends in (the bar's columns are linear in
  ``dqv = (I - dK_i G_i) e_d``, a map with two singular values at least 1: no cancellation below
  the unit scale across the body's three columns). So a column ``f`` is off by at most
  ``N u k^2 |f|`` with ``k = 1 + max_i kappa_i``, normwise over the body's three columns.
- An entry is ``sum_t w_t f_a . f_b`` over the 17 terms (7 bodies' translation and rotation, 3
  rotors; ``w`` a mass, a tensor's norm, a rotor inertia): off by at most
  ``(2 N k^2 + 3 + 17) u T`` with ``T = sum_t w_t |F_t|^2``, ``|F_t|`` the Frobenius norm of the
  term's columns (each ``|f_a| |f_b| <= |F|^2``; the 3 is a 3-vector dot product, the 17 the sum).

Taken for each path, the two differ by at most ``(2 N k^2 + 20) eps T``. The points are regular
(the compiled pass hands singular ones to numpy), where ``k`` stays below about 10 on the presets.
"""
from __future__ import annotations

import numpy as np
import pytest

from kinematics.bodies import Body, body_arrays
from kinematics.delta import Delta
from kinematics.dynamics import kinetic_form
from kinematics.registry import kind_of
from metrics.kernels import delta_mass
from resources import list_presets, load_preset

EPS = np.finfo(float).eps
#: Roundings along a column's longest chain (see the module's docstring).
CHAIN = 40
POINTS = 300
SEED = 20261207
PRESETS = [key for key, mech in ((key, load_preset(key).mechanism) for key in list_presets())
           if kind_of(mech) == "delta" and mech.has_mass_model]


def _regular_points(mech, grid, count=POINTS, seed=SEED):
    """A fixed random subset of the grid's feasible, regular points: ``x``, ``q`` (k, 3) and ``J`` (k, 3, 3)."""
    pts = grid.points(mech.task_names).reshape(-1, 3)
    q, ok = mech.inverse(pts)
    ok[ok] = mech.feasible(q[ok], pts[ok])
    ok[ok] = mech.singularity(q[ok], pts[ok]) == 0
    at = np.flatnonzero(ok)
    at = np.sort(np.random.default_rng(seed).choice(at, min(count, len(at)), replace=False))
    x, q = pts[at], q[at]
    return x, q, mech.jacobian(q, x)


def _bound(mech, q, x, *, rotors=True):
    """``(2 N k^2 + 20) eps T`` per point (k,): the two paths' largest entry difference (module docstring)."""
    masses, _, tensors = body_arrays(mech.bodies())
    jv, jw, _, g = mech.body_velocities(q, x)
    total = np.zeros(len(x))
    for b, mass in enumerate(masses):
        total += mass * np.sum(jv[b] ** 2, axis=(0, 1))
        total += np.linalg.norm(tensors[b], 2) * np.sum(jw[b] ** 2, axis=(0, 1))
    if rotors:
        total += np.einsum("u,uan->n", mech.reflected_rotor_inertias(), g ** 2)
    a_mat, b_diag = mech._velocity_matrices(q, x)
    _, dknee = mech._knees(q)
    kappa = np.max(np.linalg.norm(a_mat, axis=-1) * np.linalg.norm(dknee, axis=-1) / np.abs(b_diag), axis=-1)
    return (2 * CHAIN * (1 + kappa) ** 2 + 20) * EPS * total


def _compiled(mech, x, q, jac, mp=None):
    return delta_mass.inertia_points(x, q, jac, delta_mass.pack_mass(mech) if mp is None else mp)


def _body_entries(mp, body):
    """Slice of ``mp`` holding body ``body``'s 11 entries (``pack_mass``'s layout)."""
    start = delta_mass.BODIES + body * delta_mass.BODY_SIZE
    return slice(start, start + delta_mass.BODY_SIZE)


def test_a_delta_preset_has_a_mass_model():
    assert PRESETS, "no shipped delta preset with a mass model: the comparisons below test nothing"


@pytest.mark.parametrize("key", PRESETS)
def test_compiled_form_matches_kinetic_form_on_the_presets_grid(key):
    preset = load_preset(key)
    mech = preset.mechanism
    x, q, jac = _regular_points(mech, preset.grid)
    assert len(x) == POINTS
    got = _compiled(mech, x, q, jac)
    ref = kinetic_form(mech, q, x)
    assert np.all(np.abs(got - ref) <= _bound(mech, q, x)[:, None, None])
    assert np.array_equal(got, np.swapaxes(got, 1, 2))


class _GeneralBodies(Delta):
    """The Falcon with bodies whose centres leave the links' axes and whose tensors have products of inertia."""

    def bodies(self):
        tensor = (2e-6, 3e-6, 4e-6, 0.5e-6, -0.3e-6, 0.2e-6)
        return tuple(Body(b.name, b.mass, (0.03, 0.004, -0.002), tensor) for b in super().bodies())


def test_compiled_form_takes_any_centre_and_tensor():
    preset = load_preset("novint_falcon")
    mech = _GeneralBodies(preset.mechanism.params)
    x, q, jac = _regular_points(mech, preset.grid, count=100)
    got = _compiled(mech, x, q, jac)
    assert np.all(np.abs(got - kinetic_form(mech, q, x)) <= _bound(mech, q, x)[:, None, None])


def test_links_alone_match_kinetic_form_without_rotors():
    preset = load_preset("novint_falcon")
    mech = preset.mechanism
    x, q, jac = _regular_points(mech, preset.grid, count=100)
    mp = delta_mass.pack_mass(mech)
    mp[delta_mass.ROTORS:] = 0.0
    got = _compiled(mech, x, q, jac, mp)
    ref = kinetic_form(mech, q, x, rotors=False)
    assert np.all(np.abs(got - ref) <= _bound(mech, q, x, rotors=False)[:, None, None])


def test_rotors_alone_are_g_transposed_r_g():
    """Massless links (set in ``mp``: the model wants positive masses) leave ``G^T diag(r) G``.

    ``G`` here is ``inv(J)`` (LAPACK, from the model's ``J = A^-1 B``), not the kernel's bars: off by
    ``~ n u (cond(A) + cond(J))`` relative, each of ``A^-1`` and ``inv(J)`` backward stable, plus the
    bars' ``u kappa`` (module docstring). An entry ``sum_u r_u G_ua G_ub`` is then off by at most twice
    that times ``T = sum_u r_u |G_u|^2``, plus its own 3-term sum; 16 covers ``n = 3`` and the factor
    2 with room for each path's few roundings of ``A``, ``B`` and ``n_i``.
    """
    preset = load_preset("novint_falcon")
    mech = preset.mechanism
    x, q, jac = _regular_points(mech, preset.grid, count=100)
    mp = delta_mass.pack_mass(mech)
    mp[delta_mass.BODIES:delta_mass.ROTORS] = 0.0          # every body's entries and the arms' axis moments
    got = _compiled(mech, x, q, jac, mp)
    g = np.linalg.inv(jac)
    r = mech.reflected_rotor_inertias()
    ref = np.einsum("nua,u,nub->nab", g, r, g)
    a_mat, b_diag = mech._velocity_matrices(q, x)
    _, dknee = mech._knees(q)
    kappa = np.max(np.linalg.norm(a_mat, axis=-1) * np.linalg.norm(dknee, axis=-1) / np.abs(b_diag), axis=-1)
    conds = np.linalg.cond(a_mat) + np.linalg.cond(jac) + kappa
    bound = (16 * conds + 3) * EPS * np.einsum("u,nua->n", r, g ** 2)
    assert np.all(np.abs(got - ref) <= bound[:, None, None])


def test_body_entries_are_where_the_layout_says():
    mech = load_preset("novint_falcon").mechanism
    mp = delta_mass.pack_mass(mech)
    for b, body in enumerate(mech.bodies()):
        entries = mp[_body_entries(mp, b)]
        assert entries[0] == body.mass and tuple(entries[1:4]) == body.com and tuple(entries[4:10]) == body.inertia
    assert np.array_equal(mp[delta_mass.ROTORS:], mech.reflected_rotor_inertias())


@pytest.mark.parametrize("k", [40, -40])
def test_scaled_masses_scale_the_form_exactly(k):
    """Every term is one mass, tensor entry or rotor inertia times velocities: a power of two passes through."""
    preset = load_preset("novint_falcon")
    mech = preset.mechanism
    p = mech.params
    scale = 2.0 ** k
    scaled = mech.replace(link_masses=tuple(m * scale for m in p.link_masses), platform_mass=p.platform_mass * scale,
                          rotor_inertias=tuple(r * scale for r in p.rotor_inertias))
    x, q, jac = _regular_points(mech, preset.grid, count=100)
    for body, big in zip(mech.bodies(), scaled.bodies()):       # the rods' tensors scale with their masses
        assert np.array_equal(np.array(big.inertia), np.array(body.inertia) * scale)
    assert np.array_equal(_compiled(scaled, x, q, jac), _compiled(mech, x, q, jac) * scale)
