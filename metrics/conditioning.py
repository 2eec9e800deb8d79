"""Kinematic conditioning: condition number and Yoshikawa manipulability.

=====================  ==============================  ==========================================
quantity               formula                         reference
=====================  ==============================  ==========================================
condition number       sigma_max / sigma_min           Salisbury & Craig 1982; paper 002 sec. 4.1
manipulability         sqrt(det(J J^T)) = prod sigma   Yoshikawa 1985
=====================  ==============================  ==========================================
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

from .linalg import singular_values


def condition_number(jac: ArrayLike | None = None, *, sv: ArrayLike | None = None) -> FloatArray:
    """``sigma_max / sigma_min`` of each ``(..., m, n)`` Jacobian, shape ``(...)``; ``inf`` at a singularity.

    Pass ``sv`` (..., k), descending singular values, to reuse ones already computed.

    Parameters
    ----------
    jac : array_like, shape (..., m, n), optional
        Jacobians; not needed with ``sv``.
    sv : array_like, shape (..., k), optional
        Their singular values, descending.

    Returns
    -------
    ndarray, shape (...)
        Dimensionless, at least 1; ``inf`` where singular (``sigma_min <= k eps sigma_max``).

    References
    ----------
    Salisbury and Craig (1982); paper 002 sec. 4.1.

    Examples
    --------
    >>> condition_number([[3.0, 0.0], [0.0, 2.0]]).tolist()
    1.5
    >>> condition_number(sv=[[2.0, 2.0], [1.0, 0.0]]).tolist()
    [1.0, inf]
    """
    s = singular_values(jac) if sv is None else np.asarray(sv, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        cond = s[..., 0] / s[..., -1]
    # 0/0 (a zero matrix) and inf/inf (non-finite J) are both singular: report inf. So is a
    # sigma_min at rounding level (k eps sigma_max): SVD gets an exactly singular matrix's
    # sigma_min only to about eps sigma_max, rarely as an exact 0.
    k = s.shape[-1]
    with np.errstate(invalid="ignore"):
        singular = np.isnan(cond) | ~(s[..., -1] > k * np.finfo(float).eps * s[..., 0])
    return np.where(singular, np.inf, cond)


def manipulability(jac: ArrayLike | None = None, *, sv: ArrayLike | None = None) -> FloatArray:
    """Yoshikawa's ``sqrt(det(J J^T))``, the product of singular values, shape ``(...)``.

    Parameters
    ----------
    jac : array_like, shape (..., m, n), optional
        Jacobians; not needed with ``sv``.
    sv : array_like, shape (..., k), optional
        Their singular values.

    Returns
    -------
    ndarray, shape (...)
        In the SI units of ``J`` to the power ``k``.

    References
    ----------
    Yoshikawa (1985).

    Examples
    --------
    >>> manipulability([[3.0, 0.0], [0.0, 2.0]]).tolist()
    6.0
    """
    s = singular_values(jac) if sv is None else np.asarray(sv, float)
    return np.prod(s, axis=-1)
