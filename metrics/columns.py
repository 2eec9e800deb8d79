"""Jacobian columns: their Euclidean norms, safe from over- and underflow, and which are negligible.

Column ``u`` of J is the end-effector velocity of actuator ``u`` at unit joint rate; its norm
``|J[:, u]|`` is the denominator of the distance ``t_u / |J[:, u]|`` from the origin to that
actuator's facet pair of the force parallelepiped (``metrics.isotropy``). Computing it needs
no inverse, so it stays finite at every singularity, and a column at rounding level relative
to J (``negligible_columns``) is an actuator that moves nothing.

``SAFE_SUM_SQ`` is the range of sums of squares that need no rescaling; ``metrics.anisotropy``
uses the same bounds for the trace of the reference forces' Gram matrix.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

from .linalg import as_jacobian, components, pow2_exponents

#: Sums of squares strictly between these are formed as given: no square overflowed, and the
#: squares that underflowed (below 2^-1022 each) are below 2^-120 of the sum.
SAFE_SUM_SQ = (2.0 ** -900, 2.0 ** 1000)


def _sum_squares(a: FloatArray) -> FloatArray:
    """``sum_k a[k]^2`` over the first axis of entry arrays (m, ...)."""
    acc = a[0] * a[0]
    for k in range(1, a.shape[0]):
        acc += a[k] * a[k]
    return acc


def column_norms(jac: ArrayLike) -> FloatArray:
    """Euclidean norm of each Jacobian column, shape (..., n); ``inf`` for a non-finite column.

    The sum of squares is formed as given where it cannot have over- or underflowed (nearly
    always); other columns are scaled by a power of two first (exact) and scaled back, so
    ``column_norms(c * J) = |c| column_norms(J)`` for any representable result.

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
        Jacobians.

    Returns
    -------
    ndarray, shape (..., n)
        In the unit of ``J`` (m/rad).

    Examples
    --------
    >>> column_norms([[3.0, 0.0], [4.0, 1.0]]).tolist()
    [5.0, 1.0]
    """
    a = components(as_jacobian(jac))
    with np.errstate(over="ignore", invalid="ignore"):
        acc = _sum_squares(a)
    lo, hi = SAFE_SUM_SQ
    with np.errstate(invalid="ignore"):
        norms = np.sqrt(acc)
        redo = ~((acc > lo) & (acc < hi))
    if np.any(redo):
        cols = a[:, redo]                              # (m, k): the columns to redo
        e = pow2_exponents(cols, axis=0)
        with np.errstate(over="ignore", invalid="ignore"):
            norms[redo] = np.ldexp(np.sqrt(_sum_squares(np.ldexp(cols, -e))), e)
    norms = np.moveaxis(norms, 0, -1)
    return np.where(np.isnan(norms), np.inf, norms)


def negligible_columns(norms: ArrayLike) -> np.ndarray:
    """Columns (..., n) whose norm is at rounding level, ``<= n eps max_v |J[:, v]|``: zero to rounding.

    A Jacobian computed in floating point carries absolute errors of order eps times its
    scale in every entry; a column no larger than ``n`` such errors cannot be told from an
    exactly zero one (the actuator moves nothing). The largest column norm is within
    ``sqrt(n)`` of ``sigma_max``, so such a column also makes ``sigma_min <= n eps sigma_max``,
    the level at which ``condition_number`` and ``inverse_transpose`` call J singular.
    Where a column is unbounded (``inf``) nothing is negligible.

    Parameters
    ----------
    norms : array_like, shape (..., n)
        Column norms (``column_norms``).

    Returns
    -------
    ndarray of bool, shape (..., n)

    Examples
    --------
    >>> negligible_columns([1.0, 1e-17, 0.5]).tolist()
    [False, True, False]
    """
    norms = np.asarray(norms, float)
    n = norms.shape[-1]
    scale = norms[..., 0]
    for k in range(1, n):          # elementwise over columns: faster than a reduction along a short axis
        scale = np.maximum(scale, norms[..., k])
    with np.errstate(invalid="ignore", over="ignore"):
        level = (n * np.finfo(float).eps) * scale[..., None]
        negligible = norms <= level
    if negligible.any():
        negligible &= np.isfinite(level)
    return negligible
