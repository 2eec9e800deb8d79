"""``kinematics.vector_rows`` returns numpy's values bit for bit (signed zeros, nan and inf included).

The models use these in place of ``np.sum(a * b, -1)``, ``np.cross`` and
``rotations.angle_between``; a different order of the terms, or a sum started from the first term
instead of ``0.0``, would change last bits or the sign of a zero, which these comparisons see.
"""
from __future__ import annotations

import numpy as np

from kinematics import vector_rows
from kinematics.rotations import angle_between


def _vectors(seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    a, b = rng.normal(size=(2, 4000, 3, 3)) * 10.0 ** rng.integers(-200, 200, size=(2, 4000, 3, 1))
    a[:100], b[100:200] = 0.0, -0.0                            # zero vectors of either sign
    a[200:300, ..., 1], b[300:400, ..., 2] = -0.0, 0.0          # signed zero components
    a[400:410, ..., 0], b[410:420, ..., 1] = np.nan, np.inf
    a[420:430], b[420:430] = 1e300, 1e300                       # products overflow to inf
    return a, b


def _same_bits(got, want) -> bool:
    got, want = np.asarray(got), np.asarray(want)
    return got.shape == want.shape and np.array_equal(got.view(np.int64), want.view(np.int64))


def test_dot_cross_and_angle_are_numpys_bits():
    a, b = _vectors(1)
    with np.errstate(all="ignore"):
        assert _same_bits(vector_rows.dot(a, b), np.sum(a * b, -1))
        assert _same_bits(np.stack(vector_rows.cross(a, b), -1), np.cross(a, b))
        assert _same_bits(vector_rows.angle_between(a, b), angle_between(a, b))
        assert _same_bits(np.sqrt(vector_rows.dot(a, a)), np.linalg.norm(a, axis=-1))
        # Broadcast against one vector per leg, as the models use them.
        legs = b[0]
        assert _same_bits(vector_rows.dot(a, legs), np.sum(a * legs, -1))
