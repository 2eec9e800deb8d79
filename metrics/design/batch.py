"""Design-vectorised planar five-bar: IK, Jacobian and force metrics for many designs at once.

``metrics.quantities.evaluate`` takes one mechanism and many points. A design study asks for
many designs on the same points (the culling search's probes: every design on a few
samples), and building a ``FiveBar`` per design costs more than evaluating it. Here the link
lengths ``a1, a2, a3`` (and the torque limits) are arrays that broadcast against the points,
so a ``(k, 1)`` column of designs and a ``(1, m)`` row of points give ``(k, m)`` results in one
pass of numpy ufuncs.

The formulas are ``kinematics.fivebar.FiveBar``'s, written out on entry arrays in the same
order of operations (IK: ``arctan2`` and ``arccos`` of the law of cosines; ``J = J_p^-1
J_theta`` by the adjugate; ``metrics.columns``' column norms), so the results equal
``evaluate(FiveBar(...), points, ...)`` to rounding; ``tests/metrics/test_studies.py`` checks
1e-12 relative on random designs (in practice they agree to the last bit: numpy's
transcendental ufuncs give the same bits whatever the array layout).

With ``J[:, u] = adj(J_p)[:, u] * jtheta_u / det(J_p)`` and the adjugate's column ``u`` being
the other leg's distal vector turned by 90 deg, ``|J[:, u]| = a2 |jtheta_u| / |det J_p|`` up to
rounding; we keep the literal entries so that direct singularities (``det = 0``: ``inf``
entries, isotropic force 0) and inverse ones (``jtheta_u = 0``: a zero column, facet at
infinity) behave exactly as in ``metrics.columns`` and ``metrics.isotropy``.

================================  ==========================================================
function                          returns
================================  ==========================================================
``fivebar_batch``                 ``FiveBarBatch``: feasible mask and the requested
                                  quantities (``isotropic_force``, ``condition_number``,
                                  ``column_norms``), broadcast shape
================================  ==========================================================
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from kinematics import mechanism_class
from kinematics.arrays import BoolArray, FloatArray

from ..conditioning import condition_number

#: The five-bar's working modes (IK branches), as its ``working_mode`` parameter takes them.
WORKING_MODES = next(info.choices for info in mechanism_class("fivebar").PARAM_INFO if info.name == "working_mode")
#: Quantities ``fivebar_batch`` can return.
BATCH_QUANTITIES = ("isotropic_force", "condition_number", "column_norms")
_SLACK = 8 * np.finfo(float).eps      # as FiveBar.inverse: cosines a few ulps beyond 1 are clipped


@dataclass(frozen=True)
class FiveBarBatch:
    """Result of ``fivebar_batch``: ``feasible`` (...) and each quantity (...) (``column_norms``
    (..., 2)); ``nan`` at infeasible points, as ``metrics.quantities.evaluate`` gives."""

    feasible: BoolArray
    values: dict[str, FloatArray] = field(default_factory=dict)


def _lengths(name: str, value: ArrayLike) -> FloatArray:
    arr = np.asarray(value, dtype=np.float64)
    if not np.all(np.isfinite(arr) & (arr > 0.0)):
        bad = arr[~(np.isfinite(arr) & (arr > 0.0))].ravel()[:1]
        raise ValueError(f"{name} must be positive finite lengths in m, got {bad.tolist()[0] if bad.size else arr!r}")
    return arr


def fivebar_batch(proximal: ArrayLike, distal: ArrayLike, half_base: ArrayLike, points: ArrayLike, *,
                  quantities=("isotropic_force",), torque_limits: ArrayLike | None = None,
                  working_mode: str = "+-") -> FiveBarBatch:
    """Five-bar quantities for designs and points that broadcast together.

    Parameters
    ----------
    proximal, distal, half_base : array_like, shape broadcastable to the batch shape
        ``a1``, ``a2``, ``a3`` in m (e.g. ``(k, 1)`` for ``k`` designs).
    points : array_like, shape (..., 2)
        End-effector points in m; ``points[..., 0]`` broadcasts with the lengths
        (e.g. ``(1, m, 2)`` for ``m`` points shared by every design).
    quantities : sequence of str
        Names from ``BATCH_QUANTITIES``.
    torque_limits : array_like, shape (..., 2), optional
        Joint-side torque limits ``t_u = motor_torque_u * gear_ratio_u`` (N m); needed for
        ``isotropic_force``; leading axes broadcast with the batch (``(k, 1, 2)``).
    working_mode : str
        IK branch, as ``FiveBar`` (``"+-"``: both elbows out).

    Returns
    -------
    FiveBarBatch
        ``feasible`` (batch shape): the IK reaches the point in ``working_mode`` (the five-bar
        has no joint limits in its presets); each quantity with ``nan`` where infeasible.

    Examples
    --------
    >>> r = fivebar_batch(np.full((3, 1), 0.1), 0.1, 0.05, np.zeros((1, 4, 2)) + [0.0, 0.12],
    ...                   torque_limits=[1.0, 1.0])
    >>> r.feasible.shape, r.values["isotropic_force"].shape
    ((3, 4), (3, 4))
    """
    names = tuple(quantities)
    for q in names:
        if q not in BATCH_QUANTITIES:
            raise ValueError(f"quantities must be among {', '.join(BATCH_QUANTITIES)}, got {q!r}")
    if working_mode not in WORKING_MODES:
        raise ValueError(f"working_mode must be one of {', '.join(map(repr, WORKING_MODES))}, got {working_mode!r}")
    a1 = _lengths("proximal", proximal)
    a2 = _lengths("distal", distal)
    a3 = _lengths("half_base", half_base)
    x = np.asarray(points, dtype=np.float64)
    if x.ndim == 0 or x.shape[-1] != 2:
        raise ValueError(f"points must have shape (..., 2), got {x.shape}")
    t = None
    if "isotropic_force" in names:
        if torque_limits is None:
            raise ValueError("torque_limits (..., 2) in N m are needed for isotropic_force")
        t = np.asarray(torque_limits, dtype=np.float64)
        if t.ndim == 0 or t.shape[-1] != 2 or not np.all(np.isfinite(t) & (t > 0.0)):
            raise ValueError(f"torque_limits must be positive finite, shape (..., 2), got {t.shape}")
    ok, entries = _kernel(a1, a2, a3, x[..., 0], x[..., 1], working_mode, bool(names))
    values: dict[str, FloatArray] = {}
    if not names:
        return FiveBarBatch(ok, values)

    j00, j10, j01, j11 = entries
    batch = ok.shape
    if "isotropic_force" in names or "column_norms" in names:
        n0, n1 = _norms(j00, j10, j01, j11)
        if "column_norms" in names:
            values["column_norms"] = np.where(ok[..., None], np.stack([n0, n1], -1), np.nan)
        if "isotropic_force" in names:
            values["isotropic_force"] = isotropic_from_norms(ok, n0, n1, t[..., 0], t[..., 1])
    if "condition_number" in names:
        jac = np.stack([np.stack([j00, j01], -1), np.stack([j10, j11], -1)], -2)
        jac = np.broadcast_to(jac, batch + (2, 2))
        cond = np.full(batch, np.nan)
        cond[ok] = condition_number(jac[ok])
        values["condition_number"] = cond
    return FiveBarBatch(ok, values)


def _kernel(a1, a2, a3, px, py, working_mode: str, jacobian: bool):
    """IK (``FiveBar.inverse``) and, if ``jacobian``, J's entries (``FiveBar.jacobian`` at the
    pose): ``ok``, ``(J00, J10, J01, J11)``. No validation: the hot path of a study."""
    s0 = 1.0 if working_mode[0] == "+" else -1.0
    s1 = 1.0 if working_mode[1] == "+" else -1.0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # leg 0 based at (-a3, 0), leg 1 at (a3, 0); d = x - base
        d0x, d1x = px - (-a3), px - a3
        dy = py - 0.0
        rho0, rho1 = np.hypot(d0x, dy), np.hypot(d1x, dy)
        a1sq, a2sq, a1x2 = a1 * a1, a2 * a2, 2.0 * a1
        c0 = (a1sq + rho0 * rho0 - a2sq) / (a1x2 * rho0)
        c1 = (a1sq + rho1 * rho1 - a2sq) / (a1x2 * rho1)
        ok = (np.abs(c0) <= 1.0 + _SLACK) & (np.abs(c1) <= 1.0 + _SLACK)
        q0 = np.arctan2(dy, d0x) + s0 * np.arccos(np.clip(c0, -1.0, 1.0))
        q1 = np.arctan2(dy, d1x) + s1 * np.arccos(np.clip(c1, -1.0, 1.0))
        ok &= np.isfinite(q0) & np.isfinite(q1)          # FiveBar.feasible: finite joints
        if not jacobian:
            return ok, None
        cq0, sq0, cq1, sq1 = np.cos(q0), np.sin(q0), np.cos(q1), np.sin(q1)
        p00 = px - (-a3 + a1 * cq0)          # distal vector of leg 0: C - B0
        p01 = py - (0.0 + a1 * sq0)
        p10 = px - (a3 + a1 * cq1)
        p11 = py - (0.0 + a1 * sq1)
        jt0 = a1 * (p00 * -sq0 + p01 * cq0)  # J_theta
        jt1 = a1 * (p10 * -sq1 + p11 * cq1)
        det = p00 * p11 - p01 * p10          # det J_p
        return ok, (p11 * jt0 / det, -p10 * jt0 / det, -p01 * jt1 / det, p00 * jt1 / det)


def _norms(j00, j10, j01, j11):
    """Column norms as ``metrics.columns.column_norms`` (``nan`` -> ``inf``)."""
    with np.errstate(invalid="ignore", over="ignore"):
        n0 = np.sqrt(j00 * j00 + j10 * j10)
        n1 = np.sqrt(j01 * j01 + j11 * j11)
    return np.where(np.isnan(n0), np.inf, n0), np.where(np.isnan(n1), np.inf, n1)


def isotropic_from_norms(ok, n0, n1, t0, t1) -> FloatArray:
    """``min_u t_u / |J[:, u]|`` (paper 000 eq. 8 as ``metrics.isotropy``), ``nan`` where not ``ok``.

    Parameters
    ----------
    ok : ndarray of bool, shape (...)
        Feasible points.
    n0, n1 : ndarray, shape (...)
        Norms of J's two columns, m/rad (``inf`` at a direct singularity).
    t0, t1 : float or ndarray, broadcastable to (...)
        The two joints' torque limits, N m.

    Returns
    -------
    ndarray, shape (...)
        Isotropic force, N.

    Examples
    --------
    >>> isotropic_from_norms(np.array([True, False]), np.array([2.0, 1.0]), np.array([4.0, 1.0]), 1.0, 1.0).tolist()
    [0.25, nan]
    """
    with np.errstate(divide="ignore"):
        iso = np.minimum(t0 / n0, t1 / n1)
    return np.where(ok, iso, np.nan)


def isotropic_force_fast(a1, a2, a3, px, py, t0, t1, working_mode: str = "+-") -> FloatArray:
    """``fivebar_batch(...).values["isotropic_force"]`` without validation: the study hot path.

    Every argument is a float array (or float) broadcasting to the batch shape; ``t0``, ``t1``
    the two joints' torque limits. Same numbers as ``fivebar_batch``.

    Parameters
    ----------
    a1, a2, a3 : float or ndarray, broadcastable to (...)
        Proximal, distal and half-base lengths, m.
    px, py : float or ndarray, broadcastable to (...)
        End-effector coordinates, m.
    t0, t1 : float or ndarray, broadcastable to (...)
        Joint-side torque limits, N m.
    working_mode : str
        IK branch, as ``FiveBar``.

    Returns
    -------
    ndarray, shape (...)
        Isotropic force, N; ``nan`` where the IK does not reach the point.
    """
    ok, (j00, j10, j01, j11) = _kernel(a1, a2, a3, px, py, working_mode, True)
    n0, n1 = _norms(j00, j10, j01, j11)
    return isotropic_from_norms(ok, n0, n1, t0, t1)
