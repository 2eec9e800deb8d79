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
``fold_rows`` goes one step further for the dextrous region's batches (positions, x varying
fastest, each with a block of orientations): a function of the orientation and of some of the
position's coordinates (the Twin-Pantograph's waist: the tip's y, z) is computed once per run of
positions that share them and per orientation, and spread back, again the same values bit for bit.
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
    rows = np.asarray(rows, dtype=np.float64)
    n = len(rows)
    if n < 2:
        return None
    # Column by column on int64 views of the (strided) columns: a comparison along the short last
    # axis, or a contiguous copy, would cost several times the compares themselves.
    cols = [rows[:, j].view(np.int64) for j in range(rows.shape[1])]
    if not cols:
        return 1
    period = None
    for stop in (min(n, 64), n):        # a block is short: look for the first row's repeat near the top first
        same = cols[0][1:stop] == cols[0][0]
        for col in cols[1:]:
            same &= col[1:stop] == col[0]
        first = int(np.argmax(same)) if len(same) else 0
        if len(same) and same[first]:
            period = first + 1
            break
    if period is None or n % period:
        return None
    for col in cols:
        if not np.all(col.reshape(n // period, period) == col[:period]):
            return None
    return period


def per_block(func: Callable[[np.ndarray], Any], rows: np.ndarray, period: int | None | bool = True) -> Any:
    """``func(rows)`` for ``rows`` (..., k), evaluated on one block where the rows repeat it (``repeat_period``).

    ``func`` maps rows (..., k) to an array (..., *shape) or a tuple of them, row by row (no row's
    result depends on another's): then the block's results, tiled, are the values ``func(rows)``
    gives, bit for bit. ``period``: the rows' ``repeat_period`` when the caller has it (``True``: find it).

    Examples
    --------
    >>> rows = np.array([[0.1], [0.2]] * 3)
    >>> bool(np.array_equal(per_block(np.sin, rows), np.sin(rows)))
    True
    """
    flat = rows.reshape(-1, rows.shape[-1])
    if period is True:
        period = repeat_period(flat)
    if period is None or period == len(flat):
        return func(rows)
    block = func(flat[:period])
    reps = len(flat) // period

    def tiled(a: np.ndarray) -> np.ndarray:
        return np.tile(a, (reps,) + (1,) * (a.ndim - 1)).reshape(rows.shape[:-1] + a.shape[1:])

    return tuple(tiled(a) for a in block) if isinstance(block, tuple) else tiled(block)


class Fold:
    """Rows laid out as ``P`` runs of a repeating block of ``B`` rows, consecutive runs grouped by their columns.

    ``fold_rows`` finds the layout. Row ``i * B + o`` is run ``i``'s ``o``-th row; group ``g`` is
    the ``counts[g]`` consecutive runs from run ``first[g]`` on, whose grouping columns hold the
    same bits. A function of the block columns and the grouping columns alone, row by row, takes
    the same value on every row of one group and block position: ``spread(f(table(a), block(b)))``
    is ``f(a, b)`` bit for bit, for ``a`` a function of the grouping columns and ``b`` of the
    block's, at ``U x B`` rows instead of ``P x B``.
    """

    def __init__(self, shape: tuple[int, ...], period: int, first: np.ndarray, counts: np.ndarray) -> None:
        self.shape, self.period, self.first, self.counts = shape, period, first, counts

    @property
    def groups(self) -> int:
        """``U``, the number of groups."""
        return len(self.first)

    def table(self, values: np.ndarray) -> np.ndarray:
        """``values`` (rows) at each group's first run, (U, B)."""
        return values.reshape(-1, self.period)[self.first]

    def block(self, values: np.ndarray) -> np.ndarray:
        """``values`` (rows) on the first block, (1, B): a function of the block columns alone."""
        return values.reshape(-1, self.period)[:1]

    def spread(self, table: np.ndarray) -> np.ndarray:
        """A (U, B) table back on the rows, shape ``shape``."""
        return np.repeat(table, self.counts, axis=0).reshape(self.shape)


def fold_rows(rows: np.ndarray, block_columns: slice, run_columns: slice, group_columns: slice,
              most: float = 0.5, period: int | None | bool = True) -> Fold | None:
    """The ``Fold`` of ``rows`` (..., k), or None where the rows are not laid out so, or grouping saves little.

    The layout: the ``block_columns`` repeat with a period ``B`` (``repeat_period``; ``B = 1``:
    one value throughout), the ``run_columns`` are constant over each run of ``B`` rows, and
    consecutive runs whose ``group_columns`` (a subset of the run columns) hold the same bits are
    a group (bits, as ``repeat_period`` compares). The dextrous region's poses fold: positions
    taken with x varying fastest, each with a block of orientations, grouped by their y, z. A
    map's do not (x varies slowest): that is seen on the first 64 runs.

    Parameters
    ----------
    rows : ndarray, shape (..., k)
    block_columns, run_columns, group_columns : slice
        Columns of the block, of the runs, and the run columns that group them.
    most : float
        Fold only where the groups are at most this share of the runs.
    period : int or None or True
        The block columns' ``repeat_period`` when the caller has it (``True``: find it).

    Returns
    -------
    Fold or None

    Examples
    --------
    >>> pos = np.array([[0.0, 1.0], [5.0, 1.0], [0.0, 2.0]])        # (x, y): runs grouped by y
    >>> rows = np.concatenate([np.repeat(pos, 2, axis=0), np.tile([[10.0], [20.0]], (3, 1))], -1)
    >>> fold = fold_rows(rows, slice(2, 3), slice(0, 2), slice(1, 2), most=1.0)
    >>> fold.groups, fold.table(rows[:, 1] + rows[:, 2]).tolist()
    (2, [[11.0, 21.0], [12.0, 22.0]])
    >>> bool(np.array_equal(fold.spread(fold.table(rows[:, 1] + rows[:, 2])), rows[:, 1] + rows[:, 2]))
    True
    """
    flat = np.asarray(rows, dtype=np.float64).reshape(-1, rows.shape[-1])
    if period is True:
        period = repeat_period(flat[:, block_columns])
    if period is None or period == len(flat):
        return None
    runs = len(flat) // period
    groups = [flat[::period, j].view(np.int64) for j in range(flat.shape[1])[group_columns]]
    for stop in (min(runs, 65), runs):  # a look at the first runs first: most batches that do not fold show it there
        new = np.zeros(stop - 1, bool)
        for col in groups:
            new |= col[1:stop] != col[:stop - 1]
        if np.count_nonzero(new) + 1 > most * stop:
            return None
    if period > 1:
        # Column by column on int64 views, as repeat_period compares.
        for j in range(flat.shape[1])[run_columns]:
            col = flat[:, j].view(np.int64).reshape(runs, period)
            if not np.all(col == col[:, :1]):
                return None
    first = np.flatnonzero(np.concatenate([[True], new]))
    return Fold(rows.shape[:-1], period, first, np.diff(np.append(first, runs)))
