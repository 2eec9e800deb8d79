"""The 5-DOF Twin-Pantograph's compiled ``K`` and ``J`` (``metrics.kernels.twin_rows``) against the model's.

Reference: ``TwinPantograph.inverse_jacobian`` and ``jacobian`` (numpy), reached through the
quantity graph's node ``metrics.quantity_nodes.twin_rows``. Bounds (``u = eps / 2``):

- A row of ``K``: the pen frame and the U-joint centre (8 roundings), the waist (``atan2``,
  ``hypot``, its sine and cosine: 6), a leg's IK (``rho``, ``cos_e``, ``acos``, ``atan2``, their sum,
  the angle's cosine and sine: 10), the distal vector and ``l2 d . t`` (6), the gradient (2) and
  the row's entries (``g . b`` times the lever: 5); each path's angles are libm's or numpy's, an
  ulp apart: ``|theta| <= 2 pi``, ``4 pi u`` absolutely, about 13 roundings more. ``CHAIN = 50``,
  each relative ``u`` to its operand's size, normwise over the row. One step cancels, ``d . t``:
  relative ``u kappa``, ``kappa = |d| |t| / |d . t|``, and moving ``theta`` moves it ``kappa`` times
  too, so a shoulder's row is off by at most ``CHAIN u kappa |row|`` per path, a waist's by
  ``CHAIN u |row|`` (``n / w`` does not cancel). The two paths: ``CHAIN eps kappa |row|``.
- ``J = (K^T K)^-1 K^T``, both paths by the same Cholesky (``kinematics.rotations.spd_inverse``),
  which agrees with the exact inverse to ``k^2 eps kappa(K^T K)`` relative, ``k = 5``, and the
  product with ``K^T`` (5 terms): ``(2 (25 + 5) kappa(K)^2) eps |J|`` between the paths from their
  own rounding. Their ``K`` differ by ``delta |K|`` (above, ``delta = CHAIN eps max kappa``); the
  pseudo-inverse moves by at most ``sqrt(2) |K^+|^2 |delta K|`` (Wedin), ``sqrt(2) kappa(K) delta``
  relative. Norms are spectral; an entry is within the matrix's norm.
- The condition number (``quantity_nodes.scaled_condition``) from the same ``J``: both paths form
  the same Gram matrix ``G = M M^T`` (the same bits), then LAPACK's ``eigvalsh`` (backward stable,
  taken as ``2 m eps |G|``, ``m = 5``) or the Jacobi of ``kernels.twin_batch`` (``(GAMMA R + 1.5 D)
  eps tr(G)``, ``R + D <= MAX_ROTATIONS``). With ``|G| <= tr(G)``, each extreme eigenvalue is off by
  at most ``B = (GAMMA MAX_ROTATIONS + 1.5 MAX_ROTATIONS + 10) eps tr(G)`` between them, so
  ``kappa = sqrt(lambda_max / lambda_min)`` by ``B / (2 lambda_min) + B / (2 lambda_max)`` relative,
  plus the square root's and quotient's 3 eps.
"""
from __future__ import annotations

import numpy as np
import pytest

from metrics import quantity_nodes as nodes
from metrics import wrenches
from metrics.kernels import twin_batch, twin_rows
from metrics.quantities import summary_quantities
from metrics.workspace import compute_map
from resources import load_preset

EPS = np.finfo(float).eps
#: Roundings along a row's longest chain, the angles' ulps included (module docstring).
CHAIN = 50
SEED = 20261207


def _points(mech, grid, count=400, seed=SEED):
    """A fixed random subset of the grid's feasible points: ``x`` (k, 5), ``q`` (k, n)."""
    pts = grid.points(mech.task_names).reshape(-1, 5)
    q, ok = mech.inverse(pts)
    ok[ok] = mech.feasible(q[ok], pts[ok])
    at = np.sort(np.random.default_rng(seed).choice(np.flatnonzero(ok), count, replace=False))
    return pts[at], q[at]


def _kappa(mech, x):
    """Per row of all six joints' ``K`` (k, 6): 1 for a waist, ``|d| |t| / |d . t|`` for a shoulder."""
    cfg = mech._config(x)
    legs = [np.linalg.norm(u.distal, axis=-1) * np.linalg.norm(u.tangent, axis=-1)
            / np.abs(np.sum(u.distal * u.tangent, axis=-1)) for u in (cfg.a, cfg.b)]
    one = np.ones(len(x))
    return np.stack([one, legs[0][:, 0], legs[0][:, 1], one, legs[1][:, 0], legs[1][:, 1]], -1)


def _rows(mech, x, q):
    return nodes.twin_rows({"pose": x, "joints": q}, mech)


def _check_k(mech, x, q):
    k, _ = _rows(mech, x, q)
    ref = mech.inverse_jacobian(q, x)
    kappa = _kappa(mech, x)[:, list(mech.actuated)]
    bound = CHAIN * EPS * kappa * np.linalg.norm(ref, axis=-1)
    assert np.all(np.abs(k - ref) <= bound[..., None])


def _check_j(mech, x, q):
    k, jac = _rows(mech, x, q)
    ref_k = mech.inverse_jacobian(q, x)
    ref = mech.jacobian(q, x)
    sv = np.linalg.svd(ref_k, compute_uv=False)
    cond = sv[:, 0] / sv[:, -1]
    delta = CHAIN * EPS * np.max(_kappa(mech, x), axis=-1)
    size = np.linalg.norm(ref, 2, axis=(-2, -1))
    bound = (60 * cond ** 2 * EPS + np.sqrt(2) * cond * delta) * size
    assert np.all(np.abs(jac - ref) <= bound[:, None, None])


@pytest.fixture(scope="module", params=["twin_pantograph", "twin_pantograph_prototype"])
def twin(request):
    preset = load_preset(request.param)
    assert twin_rows.supports(preset.mechanism)
    return preset.mechanism, preset.grid


def test_k_and_j_match_the_model_on_the_presets_grid(twin):
    mech, grid = twin
    x, q = _points(mech, grid)
    _check_k(mech, x, q)
    _check_j(mech, x, q)


def test_k_and_j_match_the_model_at_tilted_poses(twin):
    mech, grid = twin
    x = _points(mech, grid, count=200)[0].copy()
    x[:, 3:] = np.random.default_rng(SEED).normal(scale=0.3, size=(len(x), 2))
    q, ok = mech.inverse(x)
    x, q = x[ok], q[ok]
    assert len(x) > 100
    _check_k(mech, x, q)
    _check_j(mech, x, q)


def test_task_point_along_the_pen_and_a_passive_waist(twin):
    """``reference_along`` moves the levers; a passive q4 leaves a 5 x 5 ``K`` and the model's ``J``."""
    mech, grid = twin
    x, _ = _points(mech, grid, count=60)
    moved = mech.replace(reference_along=0.5)
    q, ok = moved.inverse(x)
    _check_k(moved, x[ok], q[ok])
    _check_j(moved, x[ok], q[ok])
    passive = mech.replace(redundant_waist="passive")
    q, ok = passive.inverse(x)
    _check_k(passive, x[ok], q[ok])
    k, jac = _rows(passive, x[ok], q[ok])
    assert jac is None and k.shape == (np.count_nonzero(ok), 5, 5)


@pytest.mark.parametrize("back", [1e-3, 1e-6, 1e-9])
def test_k_and_j_near_the_reach_limit(twin, back):
    """Poses ``back`` m inside where a leg stops reaching: ``kappa`` about 7, 230 and 7000."""
    mech, grid = twin
    inside = _points(mech, grid, count=40)[0]
    lo, hi = inside.copy(), inside.copy()
    hi[:, 2] = 10.0                               # 10 m away along z: no leg reaches
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        ok = mech.inverse(mid)[1]
        lo[ok], hi[~ok] = mid[ok], mid[~ok]
    x = lo.copy()
    x[:, 2] -= back
    q, ok = mech.inverse(x)
    assert np.all(ok)
    _check_k(mech, x, q)
    _check_j(mech, x, q)


def test_a_handed_back_point_takes_the_models_jacobian(twin):
    """Where ``J``'s Cholesky pivot falls below the floor (a leg 1e-12 m from stretched), the node
    takes ``mech.jacobian``: its bits, ``inf`` or ``nan`` included."""
    mech, grid = twin
    inside = _points(mech, grid, count=40)[0]
    lo, hi = inside.copy(), inside.copy()
    hi[:, 2] = 10.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        ok = mech.inverse(mid)[1]
        lo[ok], hi[~ok] = mid[ok], mid[~ok]
    q, _ = mech.inverse(lo)
    k = np.empty((len(lo), 6, 5))
    jac = np.empty((len(lo), 5, 6))
    handed = np.zeros(len(lo), bool)
    twin_rows.jacobians(np.ascontiguousarray(lo), twin_rows.pack(mech), np.arange(6), k, jac, handed)
    assert handed.any()
    got = _rows(mech, lo, q)[1]
    assert np.array_equal(got[handed], mech.jacobian(q[handed], lo[handed]), equal_nan=True)


def test_unreached_and_nan_poses_are_nan(twin):
    mech, grid = twin
    x, q = _points(mech, grid, count=6)
    x[1] = np.nan
    x[2, 2] = 10.0
    k = np.empty((6, 6, 5))
    jac = np.empty((6, 5, 6))
    handed = np.zeros(6, bool)
    twin_rows.jacobians(np.ascontiguousarray(x), twin_rows.pack(mech), np.arange(6), k, jac, handed)
    ref = mech.inverse_jacobian(q, x)
    assert np.array_equal(np.isnan(k), np.isnan(ref)) and np.all(np.isnan(k[[1, 2]])) and np.all(np.isnan(jac[[1, 2]]))
    assert not handed.any()


def test_other_models_take_their_own_rows():
    """Any other model, a 6-DOF twin or one with an off-axis task point: no compiled rows."""
    preset = load_preset("twin_pantograph")
    mech = preset.mechanism
    for other in (mech.replace(roll_actuator="active", redundant_waist="passive"),
                  mech.replace(reference_offset=0.01), load_preset("inverse3_prototype").mechanism):
        assert not twin_rows.supports(other)
        assert nodes.twin_rows({}, other) is None


def test_map_is_the_same_with_threads_on_and_off(twin):
    """Every kernel runs on each chunk's thread: the whole map has the same bits either way."""
    mech, grid = twin
    small = grid.with_resolution((61, 71))
    names = summary_quantities(mech)
    on = compute_map(mech, small, names, threads=True)
    off = compute_map(mech, small, names, threads=False)
    for q in names:
        assert np.array_equal(on.values[q], off.values[q], equal_nan=True)
    assert repr(on.stats) == repr(off.stats)          # nan figures compare by their text


def test_condition_number_matches_the_numpy_path(twin):
    """``scaled_condition`` (Jacobi on the Gram matrix) against ``wrenches.scaled_condition_number``
    (``eigvalsh``) from the same ``J``, on the grid and at tilts (module docstring's bound); a point
    beyond ``FAST_COND_LIMIT`` (near the reach limit) takes the numpy path, its bits."""
    mech, grid = twin
    x, q = _points(mech, grid)
    tilted = x[:100].copy()
    tilted[:, 3:] = np.random.default_rng(SEED).normal(scale=0.3, size=(100, 2))
    qt, ok = mech.inverse(tilted)
    x, q = np.concatenate([x, tilted[ok]]), np.concatenate([q, qt[ok]])
    v = {"pose": x, "joints": q}
    v["jacobian"] = nodes.jacobian_at_pose(v, mech)
    got = nodes.scaled_condition(v, mech)
    scale = wrenches.task_row_scale(mech)
    ref = wrenches.scaled_condition_number(v["jacobian"], row_scale=scale)
    m = v["jacobian"] * scale[:, None]
    lam = np.linalg.eigvalsh(m @ np.swapaxes(m, -1, -2))
    rounds = twin_batch.MAX_ROTATIONS
    b = (twin_batch.GAMMA * rounds + 1.5 * rounds + 10) * EPS * np.sum(lam, axis=-1)
    bound = b / (2 * lam[:, 0]) + b / (2 * lam[:, -1]) + 3 * EPS
    assert np.all(np.abs(got - ref) <= bound * ref)


def test_a_condition_beyond_the_fast_limit_takes_the_numpy_path(twin):
    """1e-9 m inside the reach limit ``kappa`` passes ``FAST_COND_LIMIT``: those points get
    ``wrenches.scaled_condition_number``'s bits (LAPACK's SVD there)."""
    mech, grid = twin
    inside = _points(mech, grid, count=40)[0]
    lo, hi = inside.copy(), inside.copy()
    hi[:, 2] = 10.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        ok = mech.inverse(mid)[1]
        lo[ok], hi[~ok] = mid[ok], mid[~ok]
    x = lo.copy()
    x[:, 2] -= 1e-9
    q, _ = mech.inverse(x)
    v = {"pose": x, "joints": q}
    v["jacobian"] = nodes.jacobian_at_pose(v, mech)
    got = nodes.scaled_condition(v, mech)
    ref = wrenches.scaled_condition_number(v["jacobian"], row_scale=wrenches.task_row_scale(mech))
    beyond = ref > 200.0                  # beyond the limit with room for either path's rounding
    assert np.any(beyond)
    assert np.array_equal(got[beyond], ref[beyond])
