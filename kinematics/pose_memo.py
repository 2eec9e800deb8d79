"""The last value a model computed from a batch of poses, kept per thread and keyed on the exact values.

A map's evaluation asks one model for several things at the same poses (the inverse kinematics
and the limits, the Jacobian, the force map, the singularity classes, the mass matrix), and a
closed-chain model rebuilds its whole configuration (every leg's inverse kinematics) for each.
``PoseMemo`` keeps the last one: a call with the same parameters and bit-for-bit the same poses
gets the value back instead of a recomputation, so a hit returns exactly what a recomputation
would. One entry per thread: map chunks evaluated on a thread pool do not evict each other.
"""
from __future__ import annotations

import threading
from typing import Any

import numpy as np


class PoseMemo:
    """One ``(key, poses, value)`` entry per thread.

    ``key`` is the object the value belongs to (the model), compared by identity: a subclass may
    place its joints from more than its parameters (``scripts/stewart_reconstruction.py``), so
    equal parameters do not make equal models; the entry holds a reference, so the identity is
    never reused while it is stored. ``poses`` is compared entry by entry (``nan`` equal to
    ``nan``) against a copy taken when the value was stored, so a caller that later writes into
    its array causes no false hit. The value is returned as stored: the models treat it as read-only.

    Examples
    --------
    >>> memo = PoseMemo()
    >>> x = np.zeros((2, 3))
    >>> memo.get("p", x) is None
    True
    >>> memo.put("p", x, 42)
    42
    >>> memo.get("p", x.copy()), memo.get("q", x), memo.get("p", x + 1.0)
    (42, None, None)
    """

    def __init__(self) -> None:
        self._local = threading.local()

    def get(self, key: Any, poses: np.ndarray) -> Any | None:
        """The stored value for ``key`` at exactly ``poses``, or ``None``.

        Parameters
        ----------
        key : object
            The model (compared by identity).
        poses : ndarray
            The poses (any shape).

        Returns
        -------
        object or None
        """
        entry = getattr(self._local, "entry", None)
        if entry is None:
            return None
        stored_key, stored, value = entry
        if (stored.shape == poses.shape and stored_key is key
                and np.array_equal(stored, poses, equal_nan=True)):
            return value
        return None

    def put(self, key: Any, poses: np.ndarray, value: Any) -> Any:
        """Store ``value`` as this thread's entry for ``key`` at ``poses`` (copied) and return it."""
        self._local.entry = (key, np.array(poses, dtype=float), value)
        return value

    def clear(self) -> None:
        """Forget this thread's entry."""
        self._local.entry = None
