"""The 5-DOF Twin-Pantograph's IK, ``K`` and ``J`` point by point, compiled (``metrics.quantity_nodes``).

``unit_pose`` is one unit's IK at one pose with ``TwinPantograph._unit_inverse``'s operations (the
waist, front branch; the five-bar, elbows outward) and what the rows read from it; ``rows`` turns a
gradient ``g`` of the tip's velocity into the row of ``K`` per task twist ``xi = [v; omega . a;
omega . b]``: ``[g, lever g . b, -lever g . a]`` (the tip moves at ``v + omega x lever p``, and ``(p x
g) . a = g . b``, ``(p x g) . b = -g . a`` in the frame ``(a, p, b)``). ``TwinPantograph._twist_rows``
forms ``[g, -lever g x p]`` and the task basis ``E`` takes it to the same row in exact arithmetic.
The waist's gradient is ``n / w``, a shoulder's ``(d_u e_x + d_w e_r) / (l2 d . t)``.

``jacobians`` fills ``K`` (n, 5) and, for the redundant device (q1..q6 actuated, 6 x 5 ``K``),
``J = K^+ = (K^T K)^-1 K^T`` with ``kinematics.rotations.spd_inverse``'s Cholesky in its order: a
pivot below ``SPD_PIVOT_FLOOR`` times its diagonal entry hands the point back (``handed``), and the
caller takes the model's ``jacobian`` there, which inverts such a Gram matrix by LAPACK.

Covered: the roll passive (5-DOF), the task point on the pen's axis (``reference_offset`` 0), any
``reference_along`` (``supports``); a pose with a non-finite coordinate or that a leg does not reach
gets ``nan`` as the model's ``inverse_jacobian`` does. Sines and cosines are libm's here and numpy's
loops there, an ulp apart: the paths differ by rounding (``tests/metrics/test_kernel_twin_rows.py``).
"""
from __future__ import annotations

import math

import numpy as np

from .jit import jit
from .twin_batch import _pen_frame

EPS = 2.220446049250313e-16
_SLACK = 8.0 * EPS                 # TwinPantograph's: cosines a few ulps beyond 1 are clipped
#: ``params`` layout (``pack``): half the unit separation, l1, l2, l3, the U-joints' levers (A, B)
#: from the task point along the pen, the counterweight's offset behind the shoulder.
HALF, L1, L2, L3, LEVER_A, LEVER_B, BACK = 0, 1, 2, 3, 4, 5, 6
#: Task twist columns (5-DOF).
M = 5
#: ``kinematics.rotations.SPD_PIVOT_FLOOR``: a Cholesky pivot below this fraction of its diagonal
#: entry hands the point back.
PIVOT_FLOOR = 1e-8


def supports(mechanism, *, mass: bool = False) -> bool:
    """Whether these kernels cover ``mechanism``: a Twin-Pantograph, the roll passive (5-DOF), the
    task point on the pen's axis; with ``mass``, with a mass model too.

    Parameters
    ----------
    mechanism : Mechanism
    mass : bool

    Returns
    -------
    bool
    """
    from . import registered_kind

    return (registered_kind(mechanism) == "twin_pantograph" and not mechanism.six_dof
            and mechanism.params.reference_offset == 0.0 and (mechanism.has_mass_model or not mass))


def pack(mechanism) -> np.ndarray:
    """The model's geometry, ``params`` layout above.

    Parameters
    ----------
    mechanism : TwinPantograph

    Returns
    -------
    ndarray, shape (7,)
    """
    p = mechanism.params
    h, along = mechanism.half_span, p.reference_along
    # TwinPantograph.tip_offsets' coefficients: (s - along) h, or s h when along is 0.
    levers = [((s - along) * h) if along else (s * h) for s in (-1.0, 1.0)]
    return np.array([0.5 * p.unit_separation, p.shoulder_separation, p.upper_arm, p.forearm, *levers,
                     p.counterweight_offset], np.float64)


@jit(inline=True)
def _leg(u, w, sx, branch, l2, l3):
    """A shoulder's five-bar IK (elbow ``branch``): ``(reach, (sx, cos theta, sin theta, d_u, d_w, l2 d . t))``."""
    du = u - sx
    rho = math.hypot(du, w)
    cos_e = (l2 * l2 + rho * rho - l3 * l3) / (2.0 * l2 * rho)
    reach = abs(cos_e) <= 1.0 + _SLACK
    theta = math.atan2(w, du) + branch * math.acos(min(max(cos_e, -1.0), 1.0))
    ct, st = math.cos(theta), math.sin(theta)
    d0, d1 = u - (sx + l2 * ct), w - l2 * st
    return reach, (sx, ct, st, d0, d1, l2 * (d0 * -st + d1 * ct))


@jit(inline=True)
def unit_pose(x0, x1, x2, p, lever, y0, l1, l2, l3):
    """One unit's IK at the pose ``(x0, x1, x2)`` with pen axis ``p``: ``TwinPantograph._unit_inverse``.

    Returns ``(ok, (t0, t1, t2), w, sin psi, cos psi, leg0, leg1)``: whether both legs reach, the
    U-joint centre, the tip's distance from the waist axis, the waist's sine and cosine, and per
    leg ``(sx, cos theta, sin theta, d_u, d_w, l2 d . t)``: its shoulder's ``x``, the shoulder
    angle's cosine and sine, the distal vector tip - elbow in the plane and the shoulder row's
    denominator (leg 0 at ``x = -l1 / 2``, elbow towards ``-x``; leg 1 at ``+l1 / 2``).
    """
    t0, t1, t2 = x0 + lever * p[0], x1 + lever * p[1], x2 + lever * p[2]
    dy, dz = t1 - y0, t2
    psi = math.atan2(-dy, dz)
    w = math.hypot(dy, dz)
    reach0, leg0 = _leg(t0, w, -0.5 * l1, 1.0, l2, l3)
    reach1, leg1 = _leg(t0, w, 0.5 * l1, -1.0, l2, l3)
    return reach0 and reach1, (t0, t1, t2), w, math.sin(psi), math.cos(psi), leg0, leg1


@jit(inline=True)
def row(g0, g1, g2, a, b, lever):
    """The row of ``K`` (5 entries) of the tip-velocity gradient ``g``: ``[g, lever g . b, -lever g . a]``."""
    return (g0, g1, g2, lever * (g0 * b[0] + g1 * b[1] + g2 * b[2]), -lever * (g0 * a[0] + g1 * a[1] + g2 * a[2]))


@jit(inline=True)
def unit_rows(sn, cs, w, leg0, leg1, a, b, lever):
    """The unit's three rows of ``K``: its waist's, then its shoulders' (``unit_pose``'s legs)."""
    er1, er2 = -sn, cs
    n1, n2 = -cs, -sn
    waist = row(0.0, n1 / w, n2 / w, a, b, lever)
    _, _, _, d0, d1, denom = leg0
    first = row(d0 / denom, d1 * er1 / denom, d1 * er2 / denom, a, b, lever)
    _, _, _, d0, d1, denom = leg1
    second = row(d0 / denom, d1 * er1 / denom, d1 * er2 / denom, a, b, lever)
    return waist, first, second


@jit(allocates=True)
def jacobians(x, params, actuated, k_out, j_out, handed):
    """``K`` (N, n, 5) and, with six actuators, ``J = K^+`` (N, 5, 6) at poses ``x`` (N, 5).

    Parameters
    ----------
    x : ndarray, shape (N, 5)
        Poses ``(x, y, z, rx, rz)`` (m, rad).
    params : ndarray, shape (7,)
        ``pack``.
    actuated : ndarray of int, shape (n,)
        The actuated joints among q1..q6 (indices 0..5), in order.
    k_out : ndarray, shape (N, n, 5)
        ``qdot = K xi``; ``nan`` where the pose is not finite or a leg does not reach.
    j_out : ndarray, shape (N, 5, n)
        Filled when ``n`` is 6 (else not touched); ``nan`` with ``K``, and at a handed-back point.
    handed : ndarray of bool, shape (N,)
        True where ``J``'s Cholesky pivot fell below ``PIVOT_FLOOR`` (or ``K`` is not finite at a
        reached pose): the caller's to take from the model.
    """
    half, l1, l2, l3 = params[HALF], params[L1], params[L2], params[L3]
    n = actuated.shape[0]
    rows6 = np.empty((6, M))
    gram = np.empty((M, M))
    low = np.zeros((M, M))
    inv_l = np.zeros((M, M))
    ginv = np.empty((M, M))
    for pt in range(x.shape[0]):
        handed[pt] = False
        finite = True
        for c in range(5):
            if not np.isfinite(x[pt, c]):
                finite = False
        ok = finite
        if finite:
            a, p, b = _pen_frame(x[pt, 3], x[pt, 4])
            for k in range(2):
                lever = params[LEVER_A + k]
                reach, _, w, sn, cs, leg0, leg1 = unit_pose(x[pt, 0], x[pt, 1], x[pt, 2], p, lever,
                                                            -half if k == 0 else half, l1, l2, l3)
                ok = ok and reach
                r0, r1, r2 = unit_rows(sn, cs, w, leg0, leg1, a, b, lever)
                for c in range(M):
                    rows6[3 * k, c] = r0[c]
                    rows6[3 * k + 1, c] = r1[c]
                    rows6[3 * k + 2, c] = r2[c]
        if not ok:
            k_out[pt] = np.nan
            if n == 6:
                j_out[pt] = np.nan
            continue
        for u in range(n):
            for c in range(M):
                k_out[pt, u, c] = rows6[actuated[u], c]
        if n != 6:
            continue
        # G = K^T K (lower triangle), its Cholesky L L^T and G^-1 = L^-T L^-1 (spd_inverse's order).
        good = True
        for r in range(M):
            for c in range(r + 1):
                acc = 0.0
                for u in range(n):
                    acc += k_out[pt, u, r] * k_out[pt, u, c]
                gram[r, c] = acc
        for j in range(M):
            d = gram[j, j]
            for i in range(j):
                d -= low[j, i] * low[j, i]
            if not d > PIVOT_FLOOR * gram[j, j]:          # False for nan, inf, d <= 0
                good = False
                break
            root = math.sqrt(d)
            low[j, j] = root
            for r in range(j + 1, M):
                acc = gram[r, j]
                for i in range(j):
                    acc -= low[r, i] * low[j, i]
                low[r, j] = acc / root
        if not good:
            handed[pt] = True
            j_out[pt] = np.nan
            continue
        for j in range(M):
            inv_l[j, j] = 1.0 / low[j, j]
            for r in range(j + 1, M):
                acc = 0.0
                for i in range(j, r):
                    acc += low[r, i] * inv_l[i, j]
                inv_l[r, j] = -acc / low[r, r]
        for r in range(M):
            for c in range(r + 1):
                acc = inv_l[r, r] * inv_l[r, c]
                for i in range(r + 1, M):
                    acc += inv_l[i, r] * inv_l[i, c]
                ginv[r, c] = acc
                ginv[c, r] = acc
        for r in range(M):
            for u in range(n):
                acc = 0.0
                for c in range(M):
                    acc += ginv[r, c] * k_out[pt, u, c]
                j_out[pt, r, u] = acc
