"""Force zonotopes: the force set of redundant actuation, ``f = A tau`` with ``A`` (m, n), n > m.

The set ``A [lo, hi]^n`` (``lo = -t``, ``hi = t`` without asymmetry or bias) is bounded by
facet pairs whose normals are orthogonal to ``m - 1`` generators (generalised cross products);
its inscribed radius is the smallest facet offset, and its vertices are among the ``2^n``
signed sums. The square case is ``metrics.parallelepiped`` (the map: ``metrics.polytopes``).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

from .linalg import as_jacobian
from .parallelepiped import matvecs
from .torque_box import TorqueSet, sign_patterns, torque_set


@dataclass(frozen=True)
class Zonotope:
    """Force zonotope ``A [-t, t]^n``: facet unit normals (..., k, m), support values (..., k)."""

    normals: FloatArray
    offsets: FloatArray

    @property
    def inscribed_radius(self) -> FloatArray:
        """Radius of the largest ball about 0 inside, shape (...): the smallest facet offset.

        0 where the origin is outside (a negative offset: a shifted zonotope).

        Returns
        -------
        ndarray, shape (...)
            N.
        """
        radius = np.min(self.offsets, axis=-1)
        if np.any(radius < 0):
            radius = np.where(radius > 0, radius, 0.0)
        return radius


def zonotope(generators: ArrayLike, *, torque_limits: ArrayLike | TorqueSet, torque_min: ArrayLike | None = None,
             torque_bias: ArrayLike | None = None) -> Zonotope:
    """Facets of the force set ``{A tau : |tau_u| <= t_u}`` with ``A`` (..., m, n), n >= m.

    Every facet normal is orthogonal to m - 1 generators; for each (m-1)-subset the normal is
    the generalised cross product (cofactors), and its support value is
    ``sum_u t_u |A[:, u] . nu|``. Degenerate subsets (parallel generators) give no facet.

    With ``torque_min`` or ``torque_bias`` the set is ``{A tau : lo <= tau <= hi}``, centred at
    ``c = A (hi + lo) / 2``: each normal appears twice, ``+nu`` then ``-nu`` (2k facets), with
    offsets ``H +- nu . c``, ``H = sum_u (hi_u - lo_u) / 2 |A[:, u] . nu|``; a negative offset
    means the origin is outside.

    Parameters
    ----------
    generators : array_like, shape (..., m, n)
        The force map ``A`` (``n >= m``).
    torque_limits : array_like, shape (..., n), or TorqueSet
        Actuator limits ``t`` (the upper limit with ``torque_min``), N m; a ``TorqueSet`` is
        taken as it is (``metrics.torque_box``).
    torque_min : array_like, shape (..., n), optional
        Lower actuator limits, N m; default ``-torque_limits``.
    torque_bias : array_like, shape (..., n), optional
        Torque the actuators already spend, N m; default 0.

    Returns
    -------
    Zonotope
        ``normals`` (..., k, m) and ``offsets`` (..., k), ``k = C(n, m - 1)`` (``2 C(n, m - 1)``
        with ``torque_min`` or ``torque_bias``), N.

    Raises
    ------
    ValueError
        If ``n < m``.

    Examples
    --------
    >>> z = zonotope([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]], torque_limits=[1.0, 1.0, 1.0])
    >>> z.normals.shape, round(float(z.inscribed_radius), 6)
    ((3, 2), 1.414214)
    """
    a = as_jacobian(generators, "generators")
    m, n = a.shape[-2:]
    if n < m:
        raise ValueError(f"generators needs at least as many columns as rows (..., {m}, >= {m}), got {a.shape}")
    box = torque_set(torque_limits, n=n, torque_min=torque_min, torque_bias=torque_bias)
    shifted = box.shifted
    t = box.half_width if shifted else box.limits
    scaled = a * t[..., None, :]
    normals = []
    for subset in itertools.combinations(range(n), m - 1):
        sub = a[..., :, list(subset)]
        # Generalised cross product: component i = (-1)^i det(sub without row i).
        comps = []
        for i in range(m):
            minor = np.delete(sub, i, axis=-2)
            comps.append((-1) ** i * (np.linalg.det(minor) if m > 1 else np.ones(minor.shape[:-2])))
        normals.append(np.stack(comps, axis=-1))
    nu = np.stack(normals, axis=-2)                                   # (..., k, m)
    length = np.linalg.norm(nu, axis=-1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        unit = nu / length
    offsets = np.sum(np.abs(np.einsum("...km,...mn->...kn", unit, scaled)), axis=-1)
    if shifted:
        with np.errstate(invalid="ignore", over="ignore"):
            centre = np.einsum("...mn,...n->...m", a, 0.5 * box.lower + 0.5 * box.upper)
            shift = np.einsum("...km,...m->...k", unit, centre)
            offsets = np.concatenate([offsets + shift, offsets - shift], axis=-1)
        unit = np.concatenate([unit, -unit], axis=-2)
        length = np.concatenate([length, length], axis=-2)
    offsets = np.where(length[..., 0] > 0, offsets, np.inf)         # degenerate: no facet
    return Zonotope(normals=unit, offsets=offsets)


def zonotope_vertices(generators: ArrayLike, *, torque_limits: ArrayLike | TorqueSet,
                      torque_min: ArrayLike | None = None, torque_bias: ArrayLike | None = None) -> FloatArray:
    """The ``2^n`` signed sums ``A diag(t) s`` (..., 2^n, m): a superset of the zonotope's vertices.

    With ``torque_min`` or ``torque_bias``: ``A v``, ``v_u = hi_u`` for ``s_u = +1``, else ``lo_u``.

    Parameters
    ----------
    generators : array_like, shape (..., m, n)
        The force map ``A``.
    torque_limits : array_like, shape (..., n), or TorqueSet
        Actuator limits ``t`` (the upper limit with ``torque_min``), N m; a ``TorqueSet`` is
        taken as it is (``metrics.torque_box``).
    torque_min : array_like, shape (..., n), optional
        Lower actuator limits, N m; default ``-torque_limits``.
    torque_bias : array_like, shape (..., n), optional
        Torque the actuators already spend, N m; default 0.

    Returns
    -------
    ndarray, shape (..., 2^n, m)
        N; row k for ``sign_patterns(n)[k]``.

    Examples
    --------
    >>> zonotope_vertices([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]], torque_limits=[1.0, 1.0, 1.0]).shape
    (8, 2)
    """
    a = as_jacobian(generators, "generators")
    box = torque_set(torque_limits, n=a.shape[-1], torque_min=torque_min, torque_bias=torque_bias)
    t = box.centred_limits
    if t is None:
        v = np.where(sign_patterns(a.shape[-1]) > 0, box.upper[..., None, :], box.lower[..., None, :])
        return matvecs(a, v)
    return np.einsum("...ij,kj->...ki", a * t[..., None, :], sign_patterns(a.shape[-1]))
