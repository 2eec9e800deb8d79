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

from kinematics.base import FloatArray

from .linalg import singular_values


def condition_number(jac: ArrayLike | None = None, *, sv: ArrayLike | None = None) -> FloatArray:
    """``sigma_max / sigma_min`` of each ``(..., m, n)`` Jacobian, shape ``(...)``; ``inf`` at a singularity.

    Pass ``sv`` (..., k), descending singular values, to reuse ones already computed.
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
    """Yoshikawa's ``sqrt(det(J J^T))``, the product of singular values, shape ``(...)``."""
    s = singular_values(jac) if sv is None else np.asarray(sv, float)
    return np.prod(s, axis=-1)
