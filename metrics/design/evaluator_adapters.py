"""Evaluators from plain functions and tables, for ``culling_search`` and ``brute_force``.

An evaluator is any ``(design_ids (k,), sample_ids (m,)) -> (k, m)`` callable (or a pair of
such arrays for the ratio form). These build one from a per-design function, a broadcasting
function, or a precomputed ``(D, S)`` table: the shapes tests, benchmarks and worked examples
have; the mechanism studies use ``metrics.design.evaluators``.
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np
from numpy.typing import ArrayLike

from .culling import Evaluator


def per_design(func: Callable[[int, np.ndarray], Any]) -> Evaluator:
    """Evaluator from ``func(design_id, sample_ids (m,)) -> (m,)`` values (or ``(a, b)``).

    One call per design in a block: the shape a mechanism model evaluates efficiently
    (one model, many points).

    Parameters
    ----------
    func : callable ``(int, ndarray (m,)) -> ndarray (m,)`` or a pair of them
        One design's values on the given samples.

    Returns
    -------
    callable ``(design_ids (k,), sample_ids (m,)) -> (k, m)``
        An evaluator for ``culling_search`` and ``brute_force``.

    Examples
    --------
    >>> ev = per_design(lambda d, s: 10.0 * d + s)
    >>> ev(np.array([1, 3]), np.array([0, 2])).tolist()
    [[10.0, 12.0], [30.0, 32.0]]
    """
    def evaluate(designs: np.ndarray, samples: np.ndarray):
        rows = [func(int(d), samples) for d in designs]
        if rows and isinstance(rows[0], (tuple, list)):
            return (np.array([np.asarray(r[0], float) for r in rows]).reshape(len(rows), samples.size),
                    np.array([np.asarray(r[1], float) for r in rows]).reshape(len(rows), samples.size))
        return np.array([np.asarray(r, float) for r in rows]).reshape(len(rows), samples.size)
    return evaluate


def elementwise(func: Callable[[np.ndarray, np.ndarray], Any]) -> Evaluator:
    """Evaluator from a numpy-broadcasting ``func(design_ids, sample_ids)``, called with
    ``(k, 1)`` and ``(1, m)`` index arrays.

    Parameters
    ----------
    func : callable ``(ndarray (k, 1), ndarray (1, m)) -> array_like`` broadcasting to (k, m)
        Values (or a pair ``(a, b)``) for every design and sample.

    Returns
    -------
    callable ``(design_ids (k,), sample_ids (m,)) -> (k, m)``

    Examples
    --------
    >>> ev = elementwise(lambda d, s: 10.0 * d + s)
    >>> ev(np.array([1, 3]), np.array([0, 2])).tolist()
    [[10.0, 12.0], [30.0, 32.0]]
    """
    def evaluate(designs: np.ndarray, samples: np.ndarray):
        out = func(designs[:, None], samples[None, :])
        if isinstance(out, (tuple, list)):
            return tuple(np.broadcast_to(np.asarray(v, float), (designs.size, samples.size)) for v in out)
        return np.broadcast_to(np.asarray(out, float), (designs.size, samples.size))
    return evaluate


def table(values: ArrayLike, denominators: ArrayLike | None = None) -> Evaluator:
    """Evaluator reading a precomputed ``(D, S)`` array (and ``b``, for the ratio form).

    Parameters
    ----------
    values : array_like, shape (D, S)
        ``f`` (or ``a`` of the ratio form) of every design and sample.
    denominators : array_like, shape (D, S), optional
        ``b`` of the ratio form.

    Returns
    -------
    callable ``(design_ids (k,), sample_ids (m,)) -> (k, m)`` or a pair of such arrays

    Examples
    --------
    >>> table(np.arange(6.0).reshape(2, 3))(np.array([1]), np.array([0, 2])).tolist()
    [[3.0, 5.0]]
    """
    f = np.asarray(values, dtype=np.float64)
    g = None if denominators is None else np.asarray(denominators, dtype=np.float64)
    if f.ndim != 2 or (g is not None and g.shape != f.shape):
        raise ValueError(f"table needs (D, S) arrays of one shape, got {f.shape}"
                         + ("" if g is None else f" and {g.shape}"))

    def evaluate(designs: np.ndarray, samples: np.ndarray):
        ix = np.ix_(designs, samples)
        return f[ix] if g is None else (f[ix], g[ix])
    return evaluate
