"""The Twin-Pantograph's compiled kinetic form (``metrics.kernels.twin_mass``) against ``kinetic_form``.

Reference: ``kinematics.dynamics.kinetic_form(mech, q, x)`` (``TwinPantograph.task_inertia``), from
the model's exact body velocities (``TwinPantograph.body_velocities``). Both paths form the same
columns by the same formulas, in other orders of summation, so they differ by rounding only,
bounded as follows (``u = eps / 2``):

- A column's longest chain (the pen frame, the tip's rate ``v + omega x r``, the waist's ``psi' =
  n . T' / w``, a shoulder's ``theta' = d . T' / (l2 d . t)``, the elbow's rate, a link's frame in
  the plane and its spin ``e_y . (b' - a') / |b - a|``, the angular velocity, ``R c`` and the
  centre's velocity, ``R^T omega`` and the tensor's product) has at most 60 roundings, each
  relative ``u`` to its operand's size. One step cancels: ``d . t`` (two products), off by ``u |d|
  |t|``, relative ``u kappa`` with ``kappa = |d| |t| / |d . t|`` (the five-bar's distance from its
  singularity), and so are ``theta'`` and every part linear in it. The plane's normal is
  perpendicular to a link in the plane, so ``|n x e_x| = 1`` divides nothing small; ``w`` is the
  tip's distance from the waist axis, a length of the device, and ``n . T'`` does not cancel
  normwise.
- Each path also solves the IK itself, with the same operations, but its angles ``psi``, ``theta``
  and their sines and cosines come from libm here and from numpy's loops there: an ulp apart at
  most, ``|theta| <= 2 pi``, so at most ``4 pi u`` absolutely. Moving ``theta`` by ``delta`` moves
  ``d . t`` by at most ``(l2 + l3) delta``, relative ``kappa (1 + l2 / l3) delta``: with ``l2 < l3``
  and a margin, 30 roundings more on the chain, ``N = 90`` in all, each amplified by ``kappa``.
  So a column ``f`` is off by at most ``N u k^2 |f|``, normwise over the body's columns, ``k = 1 +
  max kappa`` over the four shoulders (``k^2`` as in ``test_kernel_mass_inoue.py``: a column may
  carry ``kappa`` twice, an elbow's rate through a forearm's spin).
- An entry is ``sum_t w_t f_a . f_b`` over the 48 terms (21 bodies' translation and rotation, 6
  rotors): off by at most ``(2 N k^2 + 3 + 48) u T``, ``T = sum_t w_t |F_t|^2`` as in
  ``test_kernel_mass_stewart.py``.

Taken for each path, the two differ by at most ``(2 N k^2 + 52) eps T``. Where the pen is tilted
the numpy path forms the columns per rate of ``(rx, rz)`` and takes them to the twist with ``T^-1``
(``kinetic_form``'s ``twist_columns``), the kernel per twist directly: ``|T^-1|^2`` times that, plus
the 5-term products' ``10 eps |T^-1|^2 T``.
"""
from __future__ import annotations

import numpy as np
import pytest

from kinematics.bodies import body_arrays
from kinematics.dynamics import kinetic_form
from kinematics.rotations import batched_inverse
from metrics import dynamics
from metrics.kernels import twin_mass
from metrics.quantities import summary_quantities
from metrics.workspace import compute_map
from resources import load_preset

EPS = np.finfo(float).eps
#: Roundings along a column's longest chain, the angles' ulps included (see the module's docstring).
CHAIN = 90
POINTS = 300
SEED = 20261207


def _feasible_points(mech, grid, count=POINTS, seed=SEED):
    """A fixed random subset of the grid's feasible points: ``x`` (k, 5), ``q`` (k, n)."""
    pts = grid.points(mech.task_names).reshape(-1, 5)
    q, ok = mech.inverse(pts)
    ok[ok] = mech.feasible(q[ok], pts[ok])
    at = np.sort(np.random.default_rng(seed).choice(np.flatnonzero(ok), count, replace=False))
    return pts[at], q[at]


def _bound(mech, q, x):
    """The two paths' largest entry difference per point (k,) (module docstring)."""
    masses, _, tensors = body_arrays(mech.bodies())
    jv, jw, _, g = mech.body_velocities(q, x)
    total = np.einsum("u,uan->n", mech.reflected_rotor_inertias(), g ** 2)
    for b, mass in enumerate(masses):
        total += mass * np.sum(jv[b] ** 2, axis=(0, 1))
        total += np.linalg.norm(tensors[b], 2) * np.sum(jw[b] ** 2, axis=(0, 1))
    cfg = mech._config(x)
    kappa = [np.linalg.norm(unit.distal, axis=-1) * np.linalg.norm(unit.tangent, axis=-1)
             / np.abs(np.sum(unit.distal * unit.tangent, axis=-1)) for unit in (cfg.a, cfg.b)]
    k = 1.0 + np.max(np.concatenate(kappa, axis=-1), axis=-1)
    bound = (2 * CHAIN * k ** 2 + 52) * EPS * total
    turned = np.any(x[:, 3:] != 0, axis=-1)
    if np.any(turned):
        inv, _ = batched_inverse(mech.coordinate_rates_to_twist(x[turned]))
        size = np.linalg.norm(inv, 2, axis=(-2, -1)) ** 2
        bound[turned] = bound[turned] * size + 10 * EPS * size * total[turned]
    return bound


@pytest.fixture(scope="module", params=["twin_pantograph", "twin_pantograph_prototype"])
def twin(request):
    preset = load_preset(request.param)
    assert twin_mass.supports(preset.mechanism)
    return preset.mechanism, preset.grid


def _check(mech, q, x):
    got = dynamics.task_inertia(mech, q, x)
    ref = kinetic_form(mech, q, x)
    assert np.all(np.isfinite(got))
    assert np.all(np.abs(got - ref) <= _bound(mech, q, x)[:, None, None])
    assert np.array_equal(got, np.swapaxes(got, -1, -2))
    return got


def test_compiled_form_matches_kinetic_form_on_the_presets_grid(twin):
    mech, grid = twin
    x, q = _feasible_points(mech, grid)
    _check(mech, q, x)


def test_compiled_form_matches_kinetic_form_at_tilted_poses(twin):
    mech, grid = twin
    x = _feasible_points(mech, grid, count=200)[0].copy()
    x[:, 3:] = np.random.default_rng(SEED).normal(scale=0.3, size=(len(x), 2))
    q, ok = mech.inverse(x)
    x, q = x[ok], q[ok]
    assert len(x) > 100
    _check(mech, q, x)


@pytest.mark.parametrize("back", [1e-3, 1e-6, 1e-9])
def test_compiled_form_near_the_reach_limit(twin, back):
    """Poses ``back`` m inside where a leg stops reaching (bisected along z): ``kappa`` about 7, 230
    and 7000 there, and the bound grows with it (about 3e-12, 3e-9 and 3e-6 of the largest entry)."""
    mech, grid = twin
    inside = _feasible_points(mech, grid, count=40)[0]
    outside = inside.copy()
    outside[:, 2] = 10.0                          # 10 m away along z: no leg reaches
    lo, hi = inside.copy(), outside
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        ok = mech.inverse(mid)[1]
        lo[ok], hi[~ok] = mid[ok], mid[~ok]
    assert np.all(hi[:, 2] - lo[:, 2] < 1e-12)
    x = lo.copy()
    x[:, 2] -= back
    q, ok = mech.inverse(x)
    assert np.all(ok)
    _check(mech, q, x)


def test_passive_waist_drops_its_rotor(twin):
    """q4 passive: no rotor and no row of ``G`` for it."""
    mech, grid = twin
    passive = mech.replace(redundant_waist="passive")
    assert twin_mass.supports(passive)
    x, _ = _feasible_points(mech, grid, count=50)
    q, ok = passive.inverse(x)
    got = _check(passive, q[ok], x[ok])
    assert not np.allclose(got, dynamics.task_inertia(mech, mech.inverse(x[ok])[0], x[ok]))


def test_task_point_along_the_pen(twin):
    """``reference_along`` moves the U-joints' levers (``tip_offsets``); the kernel reads them."""
    mech, grid = twin
    moved = mech.replace(reference_along=0.5)
    x, _ = _feasible_points(mech, grid, count=60)
    q, ok = moved.inverse(x)
    _check(moved, q[ok], x[ok])


def test_unreached_and_nan_poses_are_nan(twin):
    mech, grid = twin
    x, q = _feasible_points(mech, grid, count=6)
    x[1] = np.nan
    x[2, 2] = 10.0                       # 10 m away: no leg reaches
    q, _ = mech.inverse(x)
    got = dynamics.task_inertia(mech, q, x)
    ref = kinetic_form(mech, q, x)
    assert np.array_equal(np.isnan(got), np.isnan(ref)) and np.all(np.isnan(got[[1, 2]]))
    assert got.shape == (6, 5, 5)
    assert np.array_equal(dynamics.task_inertia(mech, q.reshape(2, 3, -1), x.reshape(2, 3, 5)).reshape(6, 5, 5),
                          got, equal_nan=True)


def test_other_twins_take_the_numpy_path(twin):
    """6-DOF (roll driven) or a task point off the pen's axis: ``mech.task_inertia``."""
    mech, grid = twin
    x, _ = _feasible_points(mech, grid, count=20)
    for other in (mech.replace(roll_actuator="active", redundant_waist="passive"),
                  mech.replace(reference_offset=0.01)):
        assert not twin_mass.supports(other)
        pts = np.concatenate([x, np.zeros((len(x), 1))], axis=-1) if other.six_dof else x
        q, ok = other.inverse(pts)
        assert np.array_equal(dynamics.task_inertia(other, q[ok], pts[ok]), other.task_inertia(q[ok], pts[ok]))


@pytest.mark.parametrize("k", [40, -40])
def test_scaled_masses_scale_the_form_exactly(twin, k):
    """Every term is one mass, tensor entry or rotor inertia times velocities: a power of two passes through."""
    mech, grid = twin
    p = mech.params
    scale = 2.0 ** k
    scaled = mech.replace(link_masses=tuple(m * scale for m in p.link_masses),
                          waist_inertia=tuple(i * scale for i in p.waist_inertia),
                          rotor_inertias=tuple(r * scale for r in p.rotor_inertias))
    x, q = _feasible_points(mech, grid, count=50)
    assert np.array_equal(dynamics.task_inertia(scaled, q, x), dynamics.task_inertia(mech, q, x) * scale)


def test_map_is_the_same_with_threads_on_and_off(twin):
    """The kernel runs on each chunk's thread: the apparent masses' map has the same bits either way."""
    mech, grid = twin
    small = grid.with_resolution((61, 71))
    names = [q for q in summary_quantities(mech) if q.startswith("apparent_mass")]
    on = compute_map(mech, small, names, threads=True)
    off = compute_map(mech, small, names, threads=False)
    for q in names:
        assert np.array_equal(on.values[q], off.values[q], equal_nan=True)


def test_a_point_gets_the_same_bits_in_any_block(twin):
    """The points run ``BLOCK`` at a time, each step over the block's lanes: a point's value is its
    own, whether alone, at any lane of a block or in a short last block, next to nan and unreached
    poses (which get nan and disturb nothing)."""
    mech, grid = twin
    count = 2 * twin_mass.BLOCK + 5                 # two full blocks and a short one
    x = _feasible_points(mech, grid, count=count)[0]
    x[3] = np.nan
    x[count - 2, 2] = 10.0                          # 10 m away: no leg reaches
    pm = twin_mass.pack_mass(mech)
    whole = np.empty((count, 5, 5))
    twin_mass.inertia_points(x, *pm, whole)
    assert np.all(np.isnan(whole[[3, count - 2]]))
    assert np.all(np.isfinite(np.delete(whole, [3, count - 2], axis=0)))
    for start in (0, 1, twin_mass.BLOCK - 1):       # every point at another lane
        part = np.empty((count - start, 5, 5))
        twin_mass.inertia_points(np.ascontiguousarray(x[start:]), *pm, part)
        assert part.tobytes() == whole[start:].tobytes()
    for i in range(0, count, 7):
        alone = np.empty((1, 5, 5))
        twin_mass.inertia_points(x[i:i + 1], *pm, alone)
        assert alone.tobytes() == whole[i:i + 1].tobytes()
