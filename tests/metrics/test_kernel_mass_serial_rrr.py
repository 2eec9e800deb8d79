"""``metrics.kernels.serial_rrr_mass`` gives ``kinetic_form``'s joint-space mass matrix, to rounding.

Reference: ``kinematics.dynamics.kinetic_form(mech, q, x, rotors=True)``, the numpy path. The two
evaluate ``M = sum_b m_b Jv_b^T Jv_b + (R_b^T Jw_b)^T I_b (R_b^T Jw_b) + diag(r)`` in different frames
(frame {0} there, the arm's turning frame here), so they agree to rounding, not bit for bit. The bound
(``_tolerance``), per path, with ``u = eps / 2`` and ``L_b = l1 + l3 + |c_b|_1`` for body ``b``:

- every entry of ``Jv_b`` (either frame) is a sum of at most four products of a length and at most
  two sines or cosines, whose absolute values add up to at most ``L_b``; with each sine or cosine
  within 2 ulp (relative ``2 eps``), each product within ``5 eps`` and at most three additions, an
  entry is off by at most ``6.5 eps L_b``, a column (3 entries, exact norm ``<= L_b``) by ``12 eps L_b``;
- ``m (Jv_a . Jv_b)`` is then off by ``2 * 12 eps m L_b^2`` from the columns plus ``4u m L_b^2`` from
  the dot product and the mass (Cauchy-Schwarz on ``|Jv|``): ``27 eps m L_b^2``;
- the body-axis angular velocities are unit vectors computed within ``5 eps`` per entry, so
  ``w_a^T I w_b`` is off by at most ``2 * 9 eps |I|_1 + 6u |I|_1 = 21 eps |I|_1`` (``|I|_1``: the
  sum of the tensor's nine absolute entries, which bounds its 2-norm);
- summing the ten body terms, the rotor and the symmetrisation adds ``12u`` of the sum of the
  terms' absolute values, at most ``S = sum_b (m_b L_b^2 + |I_b|_1) + max r``.

So each path is within ``34 eps S`` of the exact form, and the two within ``68 eps S`` of each other.
Measured: the largest difference is below ``3 eps max|M|``, hundreds of times inside the bound; a
wrong sign or a missing term moves an entry by at least one inertia product (``>= 1e-9 kg m^2``
here), millions of times outside it.
"""
from __future__ import annotations

import functools

import numpy as np
import pytest

from kinematics.dynamics import kinetic_form
from kinematics.registry import kind_of
from kinematics.serial_rrr import BODIES
from metrics.kernels.serial_rrr_mass import SIZE, inertia_points, pack_mass
from resources import list_presets, load_preset

EPS = np.finfo(float).eps
SAMPLES = 300
#: Grid points tried (a third or more of a shipped grid is feasible): enough for SAMPLES, and quick.
CANDIDATES = 5000


@functools.cache
def _keys() -> tuple[str, ...]:
    keys = []
    for key in list_presets():
        mech = load_preset(key).mechanism
        if kind_of(mech) == "serial_rrr" and mech.has_mass_model:
            keys.append(key)
    return tuple(keys)


@functools.cache
def _poses(key: str, turned: bool):
    """``SAMPLES`` feasible, regular poses ``(x, q, J)`` of the preset's grid, a fixed random subset.

    The shipped grids are the slice ``y = 0`` (``q1 = 0``); ``turned`` turns each point about the
    base axis by a random angle within q1's limits, so the numpy path's frame {0} rotation is used.
    """
    preset = load_preset(key)
    mech = preset.mechanism
    rng = np.random.default_rng(20261207)
    size = int(np.prod(preset.grid.resolution))
    pts = preset.grid.points(mech.task_names, np.sort(rng.choice(size, min(size, CANDIDATES), replace=False)))
    if turned:
        lo, hi = mech.params.lower_limits[0], mech.params.upper_limits[0]
        angle = rng.uniform(lo, hi, len(pts))
        c, s = np.cos(angle), np.sin(angle)
        pts = np.stack([c * pts[:, 0] - s * pts[:, 1], s * pts[:, 0] + c * pts[:, 1], pts[:, 2]], axis=-1)
    q, ok = mech.inverse(pts)
    ok &= mech.feasible(q) & (mech.singularity(q) == 0)
    take = rng.choice(np.flatnonzero(ok), SAMPLES, replace=False)
    x, q = pts[take], q[take]
    return x, q, mech.jacobian(q, x)


def _lengths(mech) -> np.ndarray:
    """``L_b = l1 + l3 + |c_b|_1`` per body (5,), m: bounds every ``Jv_b`` entry's terms and column norm."""
    p = mech.params
    return np.array([p.link1_length + p.crank_length + sum(abs(c) for c in body.com) for body in mech.bodies()])


def _tolerance(mech) -> float:
    """``68 eps S``: the two paths' rounding bound (module docstring)."""
    bodies = mech.bodies()
    masses = np.array([body.mass for body in bodies])
    # |I|_1: the diagonal (>= 0) once, each product of inertia twice.
    tensors = sum(sum(body.inertia[:3]) + 2 * sum(abs(v) for v in body.inertia[3:]) for body in bodies)
    scale = float(np.sum(masses * _lengths(mech) ** 2)) + tensors
    return 68 * EPS * (scale + float(np.max(mech.reflected_rotor_inertias())))


def _kernel(mech, x, q, jac):
    return inertia_points(x, q, jac, pack_mass(mech))


def test_serial_presets_have_mass_models():
    assert len(_keys()) >= 2


@pytest.mark.parametrize("turned", [False, True], ids=["grid", "turned"])
@pytest.mark.parametrize("key", _keys())
def test_matches_numpy_kinetic_form(key, turned):
    mech = load_preset(key).mechanism
    x, q, jac = _poses(key, turned)
    got = _kernel(mech, x, q, jac)
    ref = kinetic_form(mech, q, x, rotors=True)
    assert got.shape == (SAMPLES, 3, 3)
    assert np.array_equal(got, np.swapaxes(got, -1, -2))
    assert np.all(np.abs(got - ref) <= _tolerance(mech))


@pytest.mark.parametrize("power", [-40, 40])
@pytest.mark.parametrize("key", _keys())
def test_scales_exactly_with_the_masses(key, power):
    """Every term is linear in one mass, tensor entry or rotor: scaling all by ``2^k`` scales ``M`` by ``2^k``,
    bit for bit (a power of two commutes with every rounding while nothing under- or overflows)."""
    mech = load_preset(key).mechanism
    p, f = mech.params, 2.0**power
    scaled = mech.replace(link_masses=tuple(f * m for m in p.link_masses),
                          rotor_inertias=tuple(f * r for r in p.rotor_inertias),
                          **{f"inertia_{b}": tuple(f * v for v in getattr(p, f"inertia_{b}")) for b in BODIES})
    x, q, jac = _poses(key, True)
    assert np.array_equal(_kernel(scaled, x, q, jac), f * _kernel(mech, x, q, jac))


@pytest.mark.parametrize("key", _keys())
def test_rotors_alone_sit_on_the_diagonal(key):
    """Bodies of mass ``2^-1000`` and no tensor leave the rotors: ``diag(J_u N_u^2)``.

    The links' entries are at most ``sum_b m_b L_b^2`` (about ``1e-301``), far below half an ulp of
    each rotor, so the diagonal is ``reflected_rotor_inertias`` exactly and the rest within that size.
    """
    mech = load_preset(key).mechanism
    tiny = 2.0**-1000
    rotors_only = mech.replace(link_masses=(tiny,) * len(BODIES),
                               **{f"inertia_{b}": (0.0,) * 6 for b in BODIES})
    x, q, jac = _poses(key, True)
    got = _kernel(rotors_only, x, q, jac)
    rotors = mech.reflected_rotor_inertias()
    assert np.all(rotors > 0)
    assert np.array_equal(np.diagonal(got, axis1=-2, axis2=-1), np.broadcast_to(rotors, (SAMPLES, 3)))
    links = 2 * tiny * float(np.sum(_lengths(rotors_only) ** 2))      # |exact| <= sum m L^2; rounding < 2x
    assert np.all(np.abs(got - np.diag(rotors)) <= links)


@pytest.mark.parametrize("key", _keys())
def test_links_alone_match_numpy_without_rotors(key):
    mech = load_preset(key).mechanism
    bare = mech.replace(rotor_inertias=(0.0, 0.0, 0.0))
    x, q, jac = _poses(key, True)
    assert np.all(np.abs(_kernel(bare, x, q, jac) - kinetic_form(mech, q, x, rotors=False)) <= _tolerance(mech))


def test_pack_layout_and_refusal():
    mech = load_preset(_keys()[0]).mechanism
    mp = pack_mass(mech)
    assert mp.shape == (SIZE,) and mp.dtype == np.float64
    assert mp[2:SIZE - 3:10].tolist() == list(mech.params.link_masses)
    assert np.array_equal(mp[SIZE - 3:], mech.reflected_rotor_inertias())
    with pytest.raises(ValueError, match="no mass model"):
        pack_mass(mech.replace(mass_model="none"))
