"""Revolute joint angles against their limits: an angle shifted by whole turns into a range.

A model's inverse kinematics finds an angle only up to whole turns; ``wrap_into`` shifts it
into a joint's limits where a shift fits, and says where none does.
"""
from __future__ import annotations

import numpy as np

from .arrays import BoolArray, FloatArray


def wrap_into(angle: FloatArray, lower: float, upper: float) -> tuple[FloatArray, BoolArray]:
    """Shift ``angle`` by a multiple of 2 pi into ``[lower, upper]`` where possible.

    Returns the shifted angle and whether it lies inside. Where no shift fits, the angle is
    shifted to just above ``lower`` and reported outside.

    Parameters
    ----------
    angle : ndarray, shape (...)
        Angles, rad.
    lower, upper : float
        The range, rad.

    Returns
    -------
    shifted : ndarray, shape (...)
        The shifted angles, rad.
    inside : ndarray of bool, shape (...)
        Whether each lies in ``[lower, upper]``.

    Examples
    --------
    >>> shifted, inside = wrap_into(np.array([3 * np.pi, 0.5]), 0.0, 2.0)
    >>> shifted.round(6).tolist(), inside.tolist()
    ([3.141593, 0.5], [False, True])
    """
    two_pi = 2.0 * np.pi
    # floor instead of np.mod: the same shift, several times faster on large batches.
    shifted = angle - two_pi * np.floor((angle - lower) / two_pi)
    return shifted, shifted <= upper
