"""Products of 3-vectors stored along a last axis of 3, (..., 3), term by term: numpy's bits, fewer passes.

``np.sum(a * b, -1)``, ``np.cross`` and ``np.linalg.norm(..., axis=-1)`` reduce over a short
strided axis, which costs several times the arithmetic on whole (...) arrays. The functions here
form the same terms in the same order (a sum of three is ``0.0 + p0 + p1 + p2``, as numpy's
reduction adds them, signed zeros included), so they return the same values bit for bit
(``tests/kinematics/test_vector_rows.py``) at a third to a half of the cost. The component-first
products of ``kinematics.bodies`` (``dot3``, ``cross3``) are the same idea for arrays whose
components lead.
"""
from __future__ import annotations

import numpy as np

from .arrays import FloatArray


def dot(a: FloatArray, b: FloatArray) -> FloatArray:
    """``np.sum(a * b, -1)`` of (..., 3) arrays (broadcast), shape (...).

    Examples
    --------
    >>> float(dot(np.array([1.0, 2.0, 3.0]), np.array([4.0, 5.0, 6.0])))
    32.0
    """
    out = 0.0 + a[..., 0] * b[..., 0]
    out += a[..., 1] * b[..., 1]
    out += a[..., 2] * b[..., 2]
    return out


def cross(a: FloatArray, b: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The components of ``np.cross(a, b)`` (each (...)) of (..., 3) arrays: ``a1 b2 - a2 b1``, ...

    Examples
    --------
    >>> [float(c) for c in cross(np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))]
    [0.0, 0.0, 1.0]
    """
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


def angle_between(a: FloatArray, b: FloatArray) -> FloatArray:
    """``kinematics.rotations.angle_between(a, b)`` of (..., 3) float arrays: ``atan2(|a x b|, a . b)``, (...).

    Examples
    --------
    >>> round(float(angle_between(np.array([1.0, 0.0, 0.0]), np.array([0.0, 2.0, 0.0]))), 6)
    1.570796
    """
    c0, c1, c2 = cross(a, b)
    square = 0.0 + c0 * c0
    square += c1 * c1
    square += c2 * c2
    return np.arctan2(np.sqrt(square), dot(a, b))
