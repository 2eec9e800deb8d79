"""The bottleneck actuator: whose facet is nearest the origin, so which actuator limits isotropy.

The isotropic force is the smallest facet distance ``t_u / |J[:, u]|``
(``metrics.isotropy``); the bottleneck is the ``u`` that attains it. Two facets equally near
within rounding (``tie_tolerance``) are a tie, which rounding must not pick between; a map of
the bottleneck explains *why* isotropy is low where it is.

Besides an actuator index ``0 <= u < n`` a bottleneck is one of the codes
``BOTTLENECK_INFEASIBLE``, ``BOTTLENECK_TIE`` and ``BOTTLENECK_SHARED``.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .columns import column_norms
from .isotropy import facet_distances
from .torque_box import TorqueSet, torque_set

#: Bottleneck codes besides an actuator index (``-1`` is an infeasible point, see ``evaluate``):
#: two or more actuators' facets are equally near the origin within rounding (a tie), or the
#: actuation is redundant and no single actuator caps the isotropic force (shared).
BOTTLENECK_INFEASIBLE = -1
BOTTLENECK_TIE = -2
BOTTLENECK_SHARED = -3


def tie_tolerance(n: int) -> float:
    """Relative gap ``(n + 4) eps`` within which two facet distances of an (n, n) J are a tie.

    Each facet distance ``t_u / |J[:, u]|`` is the quotient of a square root of a sum of ``n``
    squares: its relative rounding error is at most ``(n/2 + 1) u + u/2 + u <= (n/4 + 1) eps``
    (``u = eps/2``: ``n`` products and sums, the root halving theirs, the quotient), so two
    equal distances can come out ``(n/2 + 2) eps`` apart. The factor 2 allows as much again
    for the rounding in J's entries, which a mechanism computes in a few operations each.
    The Inverse3's p1 and p2 columns, equal in exact arithmetic over the whole slice, come
    out up to 2 eps apart, and no pair of its facets lies between 4 eps and 64 eps apart.

    Parameters
    ----------
    n : int
        Number of actuators (columns of J).

    Returns
    -------
    float
        Relative gap, dimensionless.

    Examples
    --------
    >>> tie_tolerance(3) == 7 * float(np.finfo(float).eps)
    True
    """
    return (n + 4) * float(np.finfo(float).eps)


def bottleneck_actuator(jac: ArrayLike | None = None, *, torque_limits: ArrayLike | TorqueSet,
                        norms: ArrayLike | None = None, torque_min: ArrayLike | None = None,
                        torque_bias: ArrayLike | None = None) -> np.ndarray:
    """Index of the actuator whose facet is nearest the origin (limits isotropy), shape (...), int.

    ``BOTTLENECK_TIE`` where a second facet is as near within rounding
    (``d_v <= d_min (1 + tie_tolerance(n))``): actuators that limit equally, which rounding
    must not pick between. That includes every facet at infinity (``J = 0``) or at 0.

    With ``torque_min`` or ``torque_bias``: the actuator of the nearest facet of the shifted
    set (``facet_distances``), with negative distances taken as 0, so where the origin is
    outside the set the one actuator whose range excludes 0, or a tie of several.

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
    ndarray of int, shape (...)
        Actuator index, or ``BOTTLENECK_TIE``.

    Examples
    --------
    >>> bottleneck_actuator([[3.0, 0.0], [4.0, 1.0]], torque_limits=[1.0, 2.0]).tolist()
    0
    >>> int(bottleneck_actuator(np.eye(2), torque_limits=[1.0, 1.0])) == BOTTLENECK_TIE
    True
    """
    norms = column_norms(jac) if norms is None else np.asarray(norms, float)
    box = torque_set(torque_limits, n=norms.shape[-1], torque_min=torque_min, torque_bias=torque_bias)
    dist = facet_distances(norms=norms, torque_limits=box)
    if box.shifted:
        dist = np.where(dist > 0, dist, 0.0)
    return bottleneck_of_distances(dist)


def tied_actuators(dist: ArrayLike) -> tuple[int, ...]:
    """The actuators a ``BOTTLENECK_TIE`` at one point is a tie of: those whose facets are
    nearest the origin within rounding (``bottleneck_of_distances``' rule, negative signed
    distances taken as 0 as ``bottleneck_actuator`` takes them).

    Parameters
    ----------
    dist : array_like, shape (n,)
        Distance from the origin to each actuator's facet pair at one point, N.

    Returns
    -------
    tuple of int
        Their indices, ascending: one actuator where none ties, () where a distance is nan.

    Examples
    --------
    >>> tied_actuators([2.0, 1.0, 1.0])
    (1, 2)
    """
    dist = np.asarray(dist, float)
    dist = np.where(dist > 0, dist, np.where(np.isnan(dist), np.nan, 0.0))
    with np.errstate(invalid="ignore"):
        return tuple(int(k) for k in np.flatnonzero(dist <= _tie_level(dist)))


def _tie_level(dist: np.ndarray) -> np.ndarray:
    """The distance (...) within which a facet of ``dist`` (..., n) ties the nearest one:
    ``d_min (1 + tie_tolerance(n))``, the one rule of ``bottleneck_of_distances`` and ``tied_actuators``."""
    with np.errstate(invalid="ignore", over="ignore"):
        return np.min(dist, axis=-1) * (1.0 + tie_tolerance(dist.shape[-1]))


def bottleneck_of_distances(dist: ArrayLike) -> np.ndarray:
    """``bottleneck_actuator`` from facet distances (..., n) already computed (e.g. of a force slice).

    Parameters
    ----------
    dist : array_like, shape (..., n)
        Distance from the origin to each actuator's facet pair, N.

    Returns
    -------
    ndarray of int, shape (...)
        The nearest facet's actuator, or ``BOTTLENECK_TIE``.

    Examples
    --------
    >>> bottleneck_of_distances([[0.2, 2.0], [1.0, 1.0]]).tolist()
    [0, -2]
    """
    dist = np.asarray(dist, float)
    n = dist.shape[-1]
    if n < 2:
        return np.argmin(dist, axis=-1)
    level = _tie_level(dist)
    with np.errstate(invalid="ignore"):
        # Count the facets within the level, and sum their indices: with exactly one, that sum
        # is the argmin. Elementwise over columns: faster than argmin along a short axis.
        close = dist[..., 0] <= level
        count = close.astype(np.int8)
        index = np.zeros(count.shape, np.intp)
        for k in range(1, n):
            close = dist[..., k] <= level
            count += close
            index += k * close
    return np.where(count > 1, BOTTLENECK_TIE, index)
