"""The Delta's singular loci, sampled: platform points next to each locus (``Delta.singular_loci``).

Three kinds, for ``metrics.suprema``: one leg's knee stretched or folded or its bars along the motor
axis, placed leg by leg from the arm angle, the bend and the bar angle (``_inverse_loci``); all three
knees at once, by Newton from a lattice of starts (``_all_inverse_loci``); and the bars coplanar, the
direct-singular surface, bisected on a lattice's edges (``_direct_loci``). Computed once per model
class and parameter set. Apart from ``kinematics.delta`` because they only call the model's public
kinematics (and ``_reach_terms``, ``_velocity_matrices``): the model's own module keeps its kinematics.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from .arrays import FloatArray

_EPS = np.finfo(np.float64).eps
#: How far (rad) ``singular_loci`` places a point inside a fold of the inverse kinematics: the IK
#: resolves angles there to about ``sqrt(16 eps kappa) ~ 1e-7`` (``Delta.singular_tolerances``), so
#: 1e-5 is on the reachable side, on libnifalcon's branch, by a hundred times rounding; the point
#: is then ``~ L EDGE^2 / 2 ~ 1e-11 m`` from the locus.
EDGE = 1e-5


def singular_loci(mech, samples: int) -> dict[str, FloatArray]:
    """``Delta.singular_loci`` of ``mech`` (a ``Delta``): its parameter set's points (k, 3), copied.

    Parameters
    ----------
    mech : Delta
        The model.
    samples : int
        Arm angles sampled (``Delta.singular_loci``).

    Returns
    -------
    dict of str to ndarray, shape (k, 3)
    """
    return {name: pts.copy() for name, pts in _loci(type(mech), mech.params, int(samples)).items()}


@lru_cache(maxsize=16)
def _loci(model: type, params, samples: int) -> dict[str, FloatArray]:
    """The loci of one model class and parameter set (cached: parameters are immutable)."""
    mech = model(params)
    return {"inverse": _inverse_loci(mech, samples), "all_inverse": _all_inverse_loci(mech),
            "direct": _direct_loci(mech, samples)}


def _place(mech, leg: int, q: FloatArray, bend: FloatArray, theta3: FloatArray) -> FloatArray:
    """Platform points (..., 3) of leg ``leg`` at arm angle ``q``, knee bend and bar angle (broadcast), m.

    The inverse of ``leg_angles``: ``x = K(q) + (D + b sin theta3) e(q + bend) + b cos theta3 v``,
    with ``K`` the effective knee of ``_knees`` and ``e(t) = cos t u + sin t w`` in the leg's plane.
    """
    p = mech.params
    u, v = mech.leg_frames()
    u, v, w = u[leg], v[leg], np.array([0.0, 0.0, 1.0])
    q, bend, theta3 = np.broadcast_arrays(*(np.asarray(t, float) for t in (q, bend, theta3)))
    root = (p.base_radius - p.platform_offset_u) * u + (p.base_offset_v - p.platform_offset_v) * v
    knee = root + p.upper_arm * (np.cos(q)[..., None] * u + np.sin(q)[..., None] * w)
    theta2 = q + bend
    reach = p.knee_offset + p.platform_joint_offset + p.parallelogram * np.sin(theta3)
    forearm = np.cos(theta2)[..., None] * u + np.sin(theta2)[..., None] * w
    return knee + reach[..., None] * forearm + (p.parallelogram * np.cos(theta3))[..., None] * v


def _inverse_loci(mech, samples: int) -> FloatArray:
    """Points (k, 3) just inside one leg's stretched, folded or bar-aligned locus (``singular_loci``)."""
    p = mech.params
    arm = np.linspace(p.arm_lower, p.arm_upper, max(2, samples))
    bar = np.linspace(np.pi / 2 - p.bar_limit, np.pi / 2 + p.bar_limit, max(2, samples // 2))
    bend = np.linspace(p.knee_min, p.knee_max, max(2, samples // 2))
    out = []
    for leg in range(3):
        qa, tb = np.meshgrid(arm, bar, indexing="ij")
        for edge in (EDGE, np.pi - EDGE):                  # knee stretched / folded
            out.append(_place(mech, leg, qa, edge, tb).reshape(-1, 3))
        qa, be = np.meshgrid(arm, bend, indexing="ij")
        for edge in (EDGE, np.pi - EDGE):                  # bars along the motor axis
            out.append(_place(mech, leg, qa, be, edge).reshape(-1, 3))
    return np.concatenate(out)


def _reach_box(mech) -> tuple[FloatArray, FloatArray]:
    """A box (lower, upper), m, that holds every reachable platform point."""
    p = mech.params
    side = mech.size()
    depth = p.upper_arm + p.knee_offset + p.platform_joint_offset + p.parallelogram
    return np.array([-side, -side, -depth]), np.array([side, side, depth])


def _all_inverse_loci(mech, starts: int = 4, steps: int = 40) -> FloatArray:
    """Points (k, 3) with every knee stretched or folded, just inside (``singular_loci``).

    Newton on ``k_i(x) = s_i (1 - EDGE^2 / 2)`` (``s`` one of the eight sign triples) from a
    ``starts^3`` lattice over the reach box, with the Jacobian of ``k`` by central differences
    (step ``eps^(1/3) S``: its ``eps^(2/3)`` error slows Newton only in the last digits). A root is
    kept where every residual is below ``1e3 eps`` (``k`` itself rounds to a few eps) and every leg
    reaches it. At ``k = +-(1 - EDGE^2 / 2)`` the arm is ``EDGE`` from the platform direction (or from
    opposite it) and the knee's bend ``rho / L`` times that from 0 (or pi), by the law of sines.
    """
    lower, upper = _reach_box(mech)
    axes = [np.linspace(lo, hi, starts + 2)[1:-1] for lo, hi in zip(lower, upper)]
    lattice = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    signs = np.array([[a, b, c] for a in (1.0, -1.0) for b in (1.0, -1.0) for c in (1.0, -1.0)])
    target = np.repeat(signs, len(lattice), axis=0) * (1.0 - 0.5 * EDGE * EDGE)
    x = np.tile(lattice, (len(signs), 1))
    h = _EPS ** (1 / 3) * mech.size()
    limit = 10 * mech.size()

    def residual(pts):
        with np.errstate(invalid="ignore", divide="ignore"):
            return mech._reach_terms(pts)[5] - target

    for _ in range(steps):
        res = residual(x)
        jac = np.stack([(residual(x + h * e) - residual(x - h * e)) / (2 * h) for e in np.eye(3)], -1)
        good = np.all(np.isfinite(jac), axis=(-2, -1)) & np.all(np.isfinite(res), -1)
        safe = np.where(good[:, None, None], jac, np.eye(3))
        good &= np.abs(np.linalg.det(safe)) > 0
        step = np.linalg.solve(safe, np.where(good[:, None], res, 0.0)[..., None])[..., 0]
        x = np.where(good[:, None], x - step, np.nan)
        x = np.where(np.all(np.abs(x) < limit, axis=-1, keepdims=True), x, np.nan)
        live = np.all(np.isfinite(x), axis=-1)                  # drop the runs that left the box
        moving = np.any(np.abs(step[live & good]) > _EPS * mech.size())
        x, target = x[live], target[live]
        if not moving:
            break
    res = residual(x)
    with np.errstate(invalid="ignore"):
        keep = np.all(np.abs(res) <= 1e3 * _EPS, axis=-1)
    x = x[keep]
    if len(x):
        _, ok = mech.inverse(x)
        x = x[ok]
    # Many starts find the same root: keep one per 1e-9 S cell.
    _, first = np.unique(np.round(x / (1e-9 * mech.size())), axis=0, return_index=True)
    return x[np.sort(first)].reshape(-1, 3)


def _direct_loci(mech, samples: int, steps: int = 60) -> FloatArray:
    """Points (k, 3) on the direct-singular surface inside the feasible set, found on a lattice (``singular_loci``)."""
    def feasible_det(pts):
        q, ok = mech.inverse(pts)
        feas = ok.copy()
        feas[ok] = mech.feasible(q[ok], pts[ok])
        det = np.full(len(pts), np.nan)
        if feas.any():
            a_mat, _ = mech._velocity_matrices(q[feas], pts[feas])
            det[feas] = np.linalg.det(a_mat)
        return feas, det

    lower, upper = _reach_box(mech)
    coarse = [np.linspace(lo, hi, 25) for lo, hi in zip(lower, upper)]
    pts = np.stack(np.meshgrid(*coarse, indexing="ij"), -1).reshape(-1, 3)
    feas, _ = feasible_det(pts)
    if not feas.any():
        return np.empty((0, 3))
    cell = (upper - lower) / 24
    lower = np.maximum(lower, pts[feas].min(axis=0) - cell)      # the feasible set's box, one cell out
    upper = np.minimum(upper, pts[feas].max(axis=0) + cell)
    n = max(2, samples)
    axes = [np.linspace(lo, hi, n) for lo, hi in zip(lower, upper)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1)
    feas, det = feasible_det(grid.reshape(-1, 3))
    feas, det = feas.reshape(grid.shape[:-1]), det.reshape(grid.shape[:-1])
    ends = []
    for axis in range(3):
        lo_idx = [slice(None)] * 3
        hi_idx = [slice(None)] * 3
        lo_idx[axis], hi_idx[axis] = slice(0, -1), slice(1, None)
        lo_idx, hi_idx = tuple(lo_idx), tuple(hi_idx)
        with np.errstate(invalid="ignore"):
            flip = feas[lo_idx] & feas[hi_idx] & (np.sign(det[lo_idx]) * np.sign(det[hi_idx]) < 0)
        ends.append((grid[lo_idx][flip], grid[hi_idx][flip]))
    a = np.concatenate([e[0] for e in ends])
    b = np.concatenate([e[1] for e in ends])
    if not len(a):
        return np.empty((0, 3))
    _, det_a = feasible_det(a)
    for _ in range(steps):                                   # bisection on the sign of det A along each edge
        mid = 0.5 * (a + b)
        _, det_m = feasible_det(mid)
        same = np.sign(det_m) == np.sign(det_a)
        a = np.where(same[:, None], mid, a)
        b = np.where(same[:, None], b, mid)
    return 0.5 * (a + b)
