"""The Stewart platform's fused kernel (``metrics.kernels.stewart``) against the numpy path.

Reference: the numpy path (``kernels.use_compiled(False)``), whose formulas the kernel follows. Where
the two take the same operations on the same numbers they must agree bit for bit: the legs ``q``
(``(o + p_i) - b_i`` and ``vector_rows.dot``'s order at zero orientation, where ``R = I`` exactly),
the feasible set (a bend within ``BEND_MARGIN`` of its limit is handed back), ``K`` and the generators
``G = K^T diag(t)``, so the anisotropic force and moment (``section.section_point`` is
``section_max_norm``'s body). Handed-back points (non-finite, turned, ill-conditioned, singular) are
the numpy path's own values: identical. The rest differ by rounding, bounded as follows (``eps``
the unit roundoff's double):

- ``J = K^-1``: LU with partial pivoting here, LAPACK's (also partial pivoting) there. Each is
  backward stable with a growth factor at most ``2^(n - 1) = 32`` for ``n = 6``, so its relative
  normwise error is at most ``2 n 32 eps kappa = 384 eps kappa`` (Higham, "Accuracy and Stability of
  Numerical Algorithms", 2nd ed., thm. 9.5 and sec. 14.3). Partial pivoting picks the same pivots
  for ``K D`` as for ``K`` (``D`` diagonal, a column scaling), so the bound holds for the scaled
  ``J_s = S J = (K S^-1)^-1`` with ``S = diag(1, 1, 1, L, L, L)`` and the scaled condition
  ``kappa_s``, the reported condition number. Both paths: ``DJ = 768 eps kappa_s |J_s|_2``.
- condition number: numpy takes the singular values of ``J_s`` from its Gram matrix, the kernel
  from ``K_s = K S^-1``'s; each Gram route is off by ``(n + 6) eps kappa^2 / 2`` relative in a
  singular value (``linalg._sv_gram``), twice for the ratio and twice for the two paths
  (``24 eps kappa^2``), and ``J_s``'s error ``DJ`` moves ``sigma_min(J_s)`` by ``DJ``, relative
  ``768 eps kappa_s^2``: ``1024 eps kappa^2`` in all.
- isotropic force and moment ``min_u t_u / |J[rows, u]|``: each column norm moves by at most ``DJ``
  (a row scaling by ``L`` on the moment rows changes no ratio), plus the norm's own ``4 eps``.
- isotropic acceleration ``min_u t_u / |(Lambda J[:, u])[rows]|``: ``Lambda`` is the same compiled
  ``stewart_mass`` code on the same pose in both paths; ``Lambda J = (Lambda S^-1) J_s`` moves by
  ``|(Lambda S^-1)[rows]|_2 DJ``, and each six-term sum rounds by ``6 eps sum |Lambda| |J|``, per path.
- apparent masses (eigenvalues of the force block of ``Lambda^-1``): both invert ``Lambda`` by LU,
  so (the same column-scaling argument, ``D = diag(1, 1, 1, 1/L, 1/L, 1/L)``) the force block moves by
  at most ``768 eps kappa(Lambda D) |D^-1 Lambda^-1|_2``, each eigenvalue by as much (Weyl), plus the
  trigonometric eigenvalue form's ``(2 pi + 8) eps lambda_1`` per path (``test_kernels``' docstring):
  ``32 eps lambda_1`` for both.
"""
from __future__ import annotations

import numba
import numpy as np
import pytest

from metrics import dynamics, kernels
from metrics.kernels import stewart as stewart_kernel
from metrics.loading import DEFAULT_LOADING
from metrics.quantities import evaluate, summary_quantities
from resources import load_preset

EPS = np.finfo(float).eps
NAMES = ("condition_number", "inverse_condition_number", "isotropic_force", "anisotropic_force",
         "isotropic_moment", "anisotropic_moment", "apparent_mass_min", "apparent_mass_max",
         "isotropic_acceleration")
EXACT = ("anisotropic_force", "anisotropic_moment")


def _grid_points(mech, every=1):
    from app.cli._args import device_grid

    grid = device_grid(load_preset("stewart_platform"), None)
    return grid.points(mech.task_names).reshape(-1, 6)[::every]


def _both(mech, pts, names=NAMES):
    with kernels.use_compiled(True):
        fast = evaluate(mech, pts, names)
    with kernels.use_compiled(False):
        ref = evaluate(mech, pts, names)
    return fast, ref


def _bounds(mech, x, q, ref, names=NAMES):
    """Per point, the relative tolerance of each inexact quantity (the module's derivation), dict of (k,)."""
    scale = np.array([1.0, 1.0, 1.0, *(3 * [mech.characteristic_length])])
    jac = mech.jacobian(q, x)
    js = jac * scale[:, None]
    kappa = ref["condition_number"]
    dj = 768 * EPS * kappa * np.linalg.norm(js, 2, axis=(-2, -1))
    force = np.linalg.norm(js[:, :3], axis=-2)
    moment = np.linalg.norm(js[:, 3:], axis=-2)
    out = {"condition_number": 1024 * EPS * kappa ** 2,
           "isotropic_force": np.max(dj[:, None] / force, axis=-1) + 4 * EPS,
           "isotropic_moment": np.max(dj[:, None] / moment, axis=-1) + 4 * EPS}
    out["inverse_condition_number"] = out["condition_number"]
    if "isotropic_acceleration" not in names:
        return out
    lam = dynamics.task_inertia(mech, q, x)
    lam_s = lam / scale[None, :]
    normals = np.einsum("kma,kmu->kua", lam, jac)[..., :3]                 # (Lambda J[:, u])[rows]
    sums = np.einsum("kma,kmu->kua", np.abs(lam), np.abs(jac))[..., :3]
    move = (np.linalg.norm(lam_s[:, :3], 2, axis=(-2, -1)) * dj)[:, None] + 12 * EPS * np.linalg.norm(sums, axis=-1)
    out["isotropic_acceleration"] = np.max(move / np.linalg.norm(normals, axis=-1), axis=-1) + 4 * EPS
    d = 1.0 / scale
    mob = np.linalg.inv(lam)
    block = np.linalg.eigvalsh(mob[:, :3, :3])                             # ascending
    shift = (768 * EPS * np.linalg.cond(lam * d[None, None, :]) * np.linalg.norm(mob / d[None, :, None], 2,
                                                                                 axis=(-2, -1))
             + 32 * EPS * block[:, -1])
    out["apparent_mass_min"] = shift / block[:, -1]
    out["apparent_mass_max"] = shift / block[:, 0]
    return out


def _check(mech, pts, names=NAMES):
    """The kernel's evaluation of ``pts`` against the numpy path's, with the module's bounds."""
    fast, ref = _both(mech, pts, names)
    np.testing.assert_array_equal(fast.feasible, ref.feasible)
    np.testing.assert_array_equal(fast.joints, ref.joints)
    at = ref.feasible
    for name in EXACT:
        np.testing.assert_array_equal(fast.values[name], ref.values[name], err_msg=name)
    if not at.any():
        return fast, ref
    x, q = pts[at], ref.joints[at]
    bounds = _bounds(mech, x, q, {n: ref.values[n][at] for n in names}, names)
    for name, tol in bounds.items():
        a, b = fast.values[name][at], ref.values[name][at]
        same = (a == b) | (np.isnan(a) & np.isnan(b))
        err = np.abs(a - b) / np.abs(b)
        bad = ~same & ~(err <= tol)
        assert not bad.any(), f"{name}: {np.flatnonzero(bad)[:5]} err {err[bad][:5]} tol {tol[bad][:5]}"
    return fast, ref


def test_the_preset_map_is_the_kernels():
    mech = load_preset("stewart_platform").mechanism
    kernel = kernels.find(mech, summary_quantities(mech), DEFAULT_LOADING)
    assert kernel is not None and kernel.module is stewart_kernel


def test_preset_map_against_numpy():
    mech = load_preset("stewart_platform").mechanism
    pts = _grid_points(mech)
    fast, ref = _check(mech, pts)
    assert ref.feasible.sum() > 10000
    # Most feasible points are the kernel's own (not handed back): a kernel that handed everything
    # back would pass the comparisons above trivially.
    kernel = kernels.find(mech, NAMES, DEFAULT_LOADING)
    feasible, _, _, _, back = kernel.run(pts)
    assert np.count_nonzero(back & ref.feasible) < 0.02 * np.count_nonzero(ref.feasible)


def _scaled(scale, massed):
    """The preset's model with every length scaled (the platform's moments of inertia by its square, or by
    the scale where the square overflows); ``massed`` False: no mass model."""
    base = load_preset("stewart_platform").mechanism
    p = base.params
    inertia = tuple(v * scale * scale if np.isfinite(v * scale * scale) else v * scale for v in p.platform_inertia)
    return base.replace(base_radius=p.base_radius * scale, platform_radius=p.platform_radius * scale,
                        tool_offset=p.tool_offset * scale, min_leg=p.min_leg * scale, max_leg=p.max_leg * scale,
                        platform_inertia=inertia if massed else p.platform_inertia,
                        mass_model=p.mass_model if massed else "none")


@pytest.mark.parametrize("scale", [1e-300, 1e-150, 1e-100, 1e-5, 1e5, 1e100, 1e150, 1e300])
def test_extreme_scales(scale):
    """The same map scaled: the geometric quantities at every scale, the masses where the model has them.

    At 1e+-300 no leg length is representable (its square under- or overflows): nothing is feasible in
    either path. At 1e+-150 ``J``'s moment rows leave ``wrench_facets``' plain-norm range and every point
    goes back to numpy. Between, the kernel computes them. The masses go back off unit scale: ``Lambda``
    mixes kg with kg m^2, and ``inverse_spd``'s "sure regular" test fails there (numpy then takes
    eigenvalues). Beyond 1e150 m the model's bodies overflow (a rod's ``m L^2``): no mass model.
    """
    geometric = NAMES[:6]
    mech = _scaled(scale, massed=False)
    pts = _grid_points(mech, every=7) * np.array([scale] * 3 + [1.0] * 3)
    with np.errstate(all="ignore"):
        _, ref = _check(mech, pts, geometric)
        back = kernels.find(mech, geometric, DEFAULT_LOADING).run(pts)[4]
    if 1e-100 <= scale <= 1e100:
        assert np.count_nonzero(ref.feasible & ~back) > 0.9 * np.count_nonzero(ref.feasible)
    if scale <= 1e150:
        with np.errstate(all="ignore"):
            _check(_scaled(scale, massed=True), pts)


def test_singular_and_handed_back_points_are_numpys():
    """Equal plates with matching joints: every leg vertical at zero orientation, K of rank 3 (singular).
    Turned, non-finite and near-limit points go back too: their values are numpy's, bit for bit."""
    base = load_preset("stewart_platform").mechanism
    mech = base.replace(platform_radius=base.params.base_radius, platform_half_angle=np.pi / 3
                        - base.params.base_half_angle)
    z = np.linspace(0.09, 0.3, 9) + mech.params.tool_offset
    pts = np.zeros((len(z), 6))
    pts[:, 2] = z
    fast, ref = _both(mech, pts)
    assert ref.feasible.any()
    np.testing.assert_array_equal(fast.feasible, ref.feasible)
    for name in NAMES:
        np.testing.assert_array_equal(fast.values[name], ref.values[name], err_msg=name)
    kernel = kernels.find(mech, NAMES, DEFAULT_LOADING)
    assert kernel.run(pts)[4][ref.feasible].all()
    odd = np.array([[0.0, 0.0, 0.23, 0.1, 0.0, 0.0], [np.nan, 0.0, 0.23, 0.0, 0.0, 0.0],
                    [0.0, np.inf, 0.23, 0.0, 0.0, 0.0], [0.0, 0.0, 0.23, 0.0, 0.0, -0.2]])
    mech = load_preset("stewart_platform").mechanism
    fast, ref = _both(mech, odd)
    assert kernels.find(mech, NAMES, DEFAULT_LOADING).run(odd)[4].all()
    np.testing.assert_array_equal(fast.feasible, ref.feasible)
    for name in NAMES:
        np.testing.assert_array_equal(fast.values[name], ref.values[name], err_msg=name)


def test_bends_at_their_limit_go_back():
    """A point whose leg bends by its limit to within ``BEND_MARGIN`` is handed back (its label is numpy's)."""
    mech = load_preset("stewart_platform").mechanism
    limit = np.deg2rad(30.0)
    mech = mech.replace(base_joint_limit=limit, platform_joint_limit=limit)
    # Leg 0 at exactly the limit: o + p_0 - b_0 at angle `limit` from e_z, with q inside the range.
    b, p = mech.base_joints()[0], mech.platform_joints()[0]
    q = 0.5 * (mech.params.min_leg + mech.params.max_leg)
    pts = []
    for h in np.linspace(0.0, 2 * np.pi, 16, endpoint=False):
        d = np.array([np.sin(limit) * np.cos(h), np.sin(limit) * np.sin(h), np.cos(limit)])
        pts.append([*(b + q * d - p), 0.0, 0.0, 0.0])
    pts = np.array(pts)
    kernel = kernels.find(mech, NAMES, DEFAULT_LOADING)
    bends = mech.bend_angles(pts)
    legs, _ = mech.inverse(pts)
    near = np.abs(bends[:, 0, 0] - limit) <= stewart_kernel.BEND_MARGIN
    # The other legs inside their range and clear of the limit: only leg 0 decides.
    others = (np.all((legs >= mech.params.min_leg) & (legs <= mech.params.max_leg), axis=-1)
              & np.all(bends[:, 1:] < limit - stewart_kernel.BEND_MARGIN, axis=(-2, -1)))
    assert (near & others).any()
    back = kernel.run(pts)[4]
    assert back[near & others].all()
    fast, ref = _both(mech, pts)
    np.testing.assert_array_equal(fast.feasible, ref.feasible)


def test_threads_on_and_off_agree_bit_for_bit():
    mech = load_preset("stewart_platform").mechanism
    pts = _grid_points(mech)
    kernel = kernels.find(mech, NAMES, DEFAULT_LOADING)
    serial = kernel.run(pts, threads=False)
    before = numba.get_num_threads()
    try:
        results = []
        for n in sorted({1, numba.config.NUMBA_NUM_THREADS}):
            numba.set_num_threads(n)
            results.append(kernel.run(pts, threads=True))
    finally:
        numba.set_num_threads(before)
    for other in results:
        for a, b in zip(serial[:3] + (serial[4],), other[:3] + (other[4],)):
            np.testing.assert_array_equal(a, b)


def test_a_quantity_not_asked_for_is_not_computed():
    """Only the requested columns are written (the others keep the blank ``nan``)."""
    mech = load_preset("stewart_platform").mechanism
    pts = _grid_points(mech, every=11)
    kernel = kernels.find(mech, ("condition_number",), DEFAULT_LOADING)
    feasible, _, values, _, back = kernel.run(pts)
    keep = feasible & ~back
    assert keep.any()
    assert np.all(np.isfinite(values[kernels.COLUMNS.index("condition_number"), keep]))
    for name in NAMES[2:]:
        assert np.all(np.isnan(values[kernels.COLUMNS.index(name), keep])), name


def test_a_turned_map_takes_the_numpy_path():
    """A grid with an orientation axis or a fixed turn would hand every point back: no kernel for it."""
    from kinematics.grid import GridSpec
    from metrics.map_chunks import ChunkWork

    mech = load_preset("stewart_platform").mechanism
    level = (("y", 0.0), ("rx", 0.0), ("ry", 0.0), ("rz", 0.0))
    flat = GridSpec(("x", "z"), (-0.1, 0.15), (0.1, 0.3), (5, 5), level)
    tilted = GridSpec(("x", "z"), (-0.1, 0.15), (0.1, 0.3), (5, 5), (("y", 0.0), ("rx", 0.1), ("ry", 0.0),
                                                                      ("rz", 0.0)))
    swept = GridSpec(("x", "rz"), (-0.1, -0.3), (0.1, 0.3), (5, 5), (("y", 0.0), ("z", 0.23), ("rx", 0.0),
                                                                      ("ry", 0.0)))
    plans = [ChunkWork.plan(mech, g, NAMES, keep=False) for g in (flat, tilted, swept)]
    assert plans[0].kernel is not None and plans[1].kernel is None and plans[2].kernel is None
