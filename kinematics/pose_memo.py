"""The last value a model computed from a batch of poses, kept per thread and keyed on the exact bits.

A map's evaluation asks one model for several things at the same poses (the inverse kinematics
and the limits, the Jacobian, the force map, the singularity classes, the mass matrix), and a
closed-chain model rebuilds its whole configuration (every leg's inverse kinematics) for each.
``PoseMemo`` keeps the last one: a call on the same model with bit-for-bit the same poses
gets the value back instead of a recomputation, so a hit returns exactly what a recomputation
would. One entry per thread: map chunks evaluated on a thread pool do not evict each other.

``per_block`` saves the same kind of work within one batch: a map holds the orientation fixed
over its grid, and the dextrous region tests a block of orientations at every position
(``metrics.dextrous``, position-major), so a function of the orientation alone (the platform's
rotation, its rotated attachments, ``J_l``) is computed once per row of the repeating block.
"""
from __future__ import annotations

import threading
from typing import Any, Callable

import numpy as np


class PoseMemo:
    """One ``(key, poses, value)`` entry per thread.

    ``key`` is the object the value belongs to (the model), compared by identity: a subclass may
    place its joints from more than its parameters (``scripts/stewart_reconstruction.py``), so
    equal parameters do not make equal models; the entry holds a reference, so the identity is
    never reused while it is stored. ``poses`` is compared bit for bit (so ``-0.0`` is not ``0.0``,
    whose results may differ in a sign) against a copy taken when the value was stored, so a
    caller that later writes into its array causes no false hit. The value is returned as stored:
    the models treat it as read-only.

    Examples
    --------
    >>> memo = PoseMemo()
    >>> x = np.zeros((2, 3))
    >>> memo.get("p", x) is None
    True
    >>> memo.put("p", x, 42)
    42
    >>> memo.get("p", x.copy()), memo.get("q", x), memo.get("p", x + 1.0), memo.get("p", -x)
    (42, None, None, None)
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
        if stored_key is not key or stored.shape != np.shape(poses):
            return None
        bits = np.ascontiguousarray(poses, dtype=np.float64).view(np.int64)
        return value if np.array_equal(stored, bits) else None

    def put(self, key: Any, poses: np.ndarray, value: Any) -> Any:
        """Store ``value`` as this thread's entry for ``key`` at ``poses`` (copied) and return it."""
        self._local.entry = (key, np.array(poses, dtype=np.float64).view(np.int64), value)
        return value

    def clear(self) -> None:
        """Forget this thread's entry."""
        self._local.entry = None


def repeat_period(rows: np.ndarray) -> int | None:
    """The smallest ``p`` such that ``rows`` (N, k) is its first ``p`` rows repeated bit for bit, or None.

    Bits, not values: ``-0.0`` and ``0.0`` (or two nans) may give results that differ in a sign,
    so only identical bit patterns count as a repeat. Only the first row's repeats are candidates
    (a block that holds its first row twice is not found: the rows are then taken one by one).

    Examples
    --------
    >>> repeat_period(np.array([[1.0, 2.0], [3.0, 4.0]] * 3)), repeat_period(np.zeros((4, 2)))
    (2, 1)
    >>> repeat_period(np.array([[1.0], [2.0], [1.0]])) is None
    True
    """
    n = len(rows)
    if n < 2:
        return None
    bits = np.ascontiguousarray(rows, dtype=np.float64).view(np.int64)
    repeats = np.flatnonzero(np.all(bits == bits[0], axis=-1)[1:])
    if not len(repeats):
        return None
    period = int(repeats[0]) + 1
    if n % period or not np.array_equal(bits.reshape(n // period, period, -1), np.broadcast_to(
            bits[:period], (n // period,) + bits[:period].shape)):
        return None
    return period


def per_block(func: Callable[[np.ndarray], Any], rows: np.ndarray) -> Any:
    """``func(rows)`` for ``rows`` (..., k), evaluated on one block where the rows repeat it (``repeat_period``).

    ``func`` maps rows (..., k) to an array (..., *shape) or a tuple of them, row by row (no row's
    result depends on another's): then the block's results, tiled, are the values ``func(rows)``
    gives, bit for bit.

    Examples
    --------
    >>> rows = np.array([[0.1], [0.2]] * 3)
    >>> bool(np.array_equal(per_block(np.sin, rows), np.sin(rows)))
    True
    """
    flat = rows.reshape(-1, rows.shape[-1])
    period = repeat_period(flat)
    if period is None or period == len(flat):
        return func(rows)
    block = func(flat[:period])
    reps = len(flat) // period

    def tiled(a: np.ndarray) -> np.ndarray:
        return np.tile(a, (reps,) + (1,) * (a.ndim - 1)).reshape(rows.shape[:-1] + a.shape[1:])

    return tuple(tiled(a) for a in block) if isinstance(block, tuple) else tiled(block)
