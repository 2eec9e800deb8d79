"""Maximum isotropic force (paper 000 eq. 7-9): the distance from the origin to each facet, their minimum, the clamp.

The force parallelepiped ``P = {f : |J[:, u] . f| <= t_u}`` is an intersection of slabs, one
per actuator; the distance from the origin to the facet pair of actuator ``u`` is
``t_u / |J[:, u]|`` (``metrics.columns.column_norms``). The largest ball about 0 inside P has
the smallest of them as radius: the same value as eq. 7-8 of paper 000, but with no inverse
and no cross products of nearly parallel reference forces, so finite at singularities.

=========================  ============================================  ======================
quantity                   how we compute it                             paper 000
=========================  ============================================  ======================
facet distances            t_u / |J[:, u]|; signed min(hi_u, -lo_u) /    --
                           |J[:, u]| with a range [lo, hi]
isotropic force            min_u of the same, 0 where the origin is      eq. 7-8 (same value,
                           outside the (shifted) set                     no cross products)
eq. 7-8 as printed         min_u |R_u . N_u| / |N_u|, for comparison     eq. 7-8
force clamp                F_d scaled down to the isotropic radius       eq. 9
=========================  ============================================  ======================

The actuator that attains the minimum is ``metrics.bottleneck``.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

from .columns import column_norms, negligible_columns
from .parallelepiped import reference_forces
from .torque_box import TorqueSet, torque_set


def facet_distances(jac: ArrayLike | None = None, *, torque_limits: ArrayLike | TorqueSet,
                    norms: ArrayLike | None = None, torque_min: ArrayLike | None = None,
                    torque_bias: ArrayLike | None = None) -> FloatArray:
    """Distance ``t_u / |J[:, u]|`` from the origin to each facet pair of P, shape (..., n), in N.

    A zero column (the actuator's joint cannot move the end-effector), or one at rounding
    level relative to J (``negligible_columns``), gives ``inf``: that actuator limits no
    direction. An unbounded column (a direct singularity) gives 0.

    With ``torque_min`` or ``torque_bias`` (usable range ``[lo, hi]``, ``torque_range``) the
    slab of actuator u is ``lo_u <= J[:, u] . f <= hi_u`` and its entry is the signed distance
    ``min(hi_u, -lo_u) / |J[:, u]|`` to the nearer of its two facets: negative where the
    origin is outside the slab (0 is not in ``[lo_u, hi_u]``). A negligible column gives
    ``inf`` if 0 is in the range, else ``-inf`` (no force gives that actuator a usable torque).

    Parameters
    ----------
    jac : array_like, shape (..., m, n), optional
        Jacobians; not needed with ``norms``.
    torque_limits : array_like, shape (..., n), or TorqueSet
        Joint torque limits ``t`` (the upper limit with ``torque_min``), N m; a ``TorqueSet`` is
        taken as it is (``metrics.torque_box``).
    norms : array_like, shape (..., n), optional
        ``column_norms(jac)`` already computed.
    torque_min : array_like, shape (..., n), optional
        Lower joint torque limits, N m; default ``-torque_limits``.
    torque_bias : array_like, shape (..., n), optional
        Torque the joints already spend, N m; default 0.

    Returns
    -------
    ndarray, shape (..., n)
        N.

    Examples
    --------
    >>> facet_distances([[3.0, 0.0], [4.0, 1.0]], torque_limits=[1.0, 2.0]).tolist()
    [0.2, 2.0]
    >>> facet_distances(np.eye(2), torque_limits=[1.0, 2.0], torque_min=[-3.0, 0.5]).tolist()
    [1.0, -0.5]
    """
    norms = column_norms(jac) if norms is None else np.asarray(norms, float)
    box = torque_set(torque_limits, n=norms.shape[-1], torque_min=torque_min, torque_bias=torque_bias)
    t = box.centred_limits
    if t is None:
        lo, hi = box.lower, box.upper
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            dist = np.minimum(hi, -lo) / norms
        negligible = negligible_columns(norms)
        if negligible.any():
            inside = (lo <= 0) & (hi >= 0)
            dist = np.where(negligible, np.where(inside, np.inf, -np.inf), dist)
        return dist
    with np.errstate(divide="ignore", over="ignore"):
        dist = t / norms
    negligible = negligible_columns(norms)
    return np.where(negligible, np.inf, dist) if negligible.any() else dist


def isotropic_force(jac: ArrayLike | None = None, *, torque_limits: ArrayLike | TorqueSet,
                    norms: ArrayLike | None = None, torque_min: ArrayLike | None = None,
                    torque_bias: ArrayLike | None = None) -> FloatArray:
    """Maximum isotropic force (paper 000 eq. 8): radius of the largest ball about 0 in P, shape (...).

    ``min_u t_u / |J[:, u]|``, equal to eq. 8's ``min_u |R_u . N_u| / |N_u|`` but with no
    inverse: finite at singularities, zero where J is unbounded (a direct singularity).

    With ``torque_min`` or ``torque_bias`` the set ``{f : lo <= J^T f <= hi}`` is a shifted
    parallelepiped (any m x n J: an intersection of slabs) and this is the distance from the
    origin to its nearest facet, ``max(0, min_u min(hi_u, -lo_u) / |J[:, u]|)``: 0 where the
    origin is outside the set.

    Parameters
    ----------
    jac : array_like, shape (..., m, n), optional
        Jacobians; not needed with ``norms``.
    torque_limits : array_like, shape (..., n), or TorqueSet
        Joint torque limits ``t`` (the upper limit with ``torque_min``), N m; a ``TorqueSet`` is
        taken as it is (``metrics.torque_box``).
    norms : array_like, shape (..., n), optional
        ``column_norms(jac)`` already computed.
    torque_min : array_like, shape (..., n), optional
        Lower joint torque limits, N m; default ``-torque_limits``.
    torque_bias : array_like, shape (..., n), optional
        Torque the joints already spend (preload, gravity compensation), N m; default 0.

    Returns
    -------
    ndarray, shape (...)
        N.

    References
    ----------
    Łącki, Rossa and Gallacher (paper 000), eq. 7-8.

    Examples
    --------
    >>> isotropic_force([[3.0, 0.0], [4.0, 1.0]], torque_limits=[1.0, 2.0]).tolist()
    0.2
    >>> isotropic_force(np.tile(np.eye(3), (5, 1, 1)), torque_limits=[1.0, 2.0, 3.0]).tolist()
    [1.0, 1.0, 1.0, 1.0, 1.0]
    >>> isotropic_force(np.eye(2), torque_limits=[1.0, 2.0], torque_bias=[0.25, 0.0]).tolist()
    0.75
    >>> isotropic_force(np.eye(2), torque_limits=[1.0, 2.0], torque_bias=[1.5, 0.0]).tolist()
    0.0
    """
    norms = column_norms(jac) if norms is None else np.asarray(norms, float)
    box = torque_set(torque_limits, n=norms.shape[-1], torque_min=torque_min, torque_bias=torque_bias)
    radius = np.min(facet_distances(norms=norms, torque_limits=box), axis=-1)
    if box.shifted and np.any(radius <= 0):
        radius = np.where(radius > 0, radius, 0.0)        # outside the set (or -0.0): 0
    return radius


def isotropic_force_cross_product(jac: ArrayLike, *, torque_limits: ArrayLike) -> FloatArray:
    """Paper 000 eq. 7-8 as printed, for comparison only (3 x 3): ``min |R_u . N_u| / |N_u|``.

    ``N_1 = R_2 x R_3`` etc. loses accuracy when reference forces are nearly parallel; use
    ``isotropic_force`` instead.

    Parameters
    ----------
    jac : array_like, shape (..., 3, 3)
        Jacobians.
    torque_limits : array_like, shape (..., 3)
        Joint torque limits ``t``, N m.

    Returns
    -------
    ndarray, shape (...)
        N.

    Raises
    ------
    ValueError
        For Jacobians that are not 3 x 3.

    References
    ----------
    Łącki, Rossa and Gallacher (paper 000), eq. 7-8.

    Examples
    --------
    >>> isotropic_force_cross_product(np.eye(3), torque_limits=[1.0, 2.0, 3.0]).tolist()
    1.0
    """
    ref = reference_forces(jac, torque_limits=torque_limits)
    if ref.shape[-2:] != (3, 3):
        raise ValueError(f"the cross-product formula needs 3 x 3 Jacobians, got {ref.shape[-2:]}")
    r = [ref[..., :, u] for u in range(3)]
    dists = []
    for u in range(3):
        normal = np.cross(r[(u + 1) % 3], r[(u + 2) % 3])
        with np.errstate(divide="ignore", invalid="ignore"):
            dists.append(np.abs(np.einsum("...i,...i->...", r[u], normal)) / np.linalg.norm(normal, axis=-1))
    return np.min(np.stack(dists, -1), axis=-1)


def clamp_force(desired: ArrayLike, radius: ArrayLike) -> FloatArray:
    """Paper 000 eq. 9: ``F_d`` if ``|F_d| < r``, else ``F_d / |F_d| * r``, shape (..., m).

    Parameters
    ----------
    desired : array_like, shape (..., m)
        Desired forces ``F_d``, N.
    radius : array_like, shape (...)
        Isotropic force radius ``r``, N.

    Returns
    -------
    ndarray, shape (..., m)
        N.

    References
    ----------
    Łącki, Rossa and Gallacher (paper 000), eq. 9.

    Examples
    --------
    >>> clamp_force([[3.0, 4.0], [0.3, 0.4]], 1.0).tolist()
    [[0.6, 0.8], [0.3, 0.4]]
    """
    f = np.asarray(desired, float)
    r = np.asarray(radius, float)[..., None]
    norm = np.linalg.norm(f, axis=-1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        scaled = f / norm * r
    return np.where(norm < r, f, scaled)
