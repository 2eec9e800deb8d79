"""Branch and bound for a global extreme of a map quantity, to a tolerance far below a grid's spacing.

``refine_global_minimum`` (and ``refine_global_maximum``): Branch and bound on a quadtree
(octree in 3D) over the grid's box: start from a coarse
grid, give every cell a lower bound from its corner values and local slope estimates,
discard cells whose bound cannot beat the best value found by more than
``tol``, and split the rest in ``2^d`` until none is left. It works on the same
continuous domain the dense grid samples (grid box intersected with the feasible set),
including its boundary, where the minimum isotropic force of the Inverse3 lies.

What the refinement's "certified" means. A cell of widths ``w_i`` whose corners are all
feasible gets the lower bound ``min(corner values) - sum_i L_i w_i / 2`` (every point is
within ``w_i / 2`` of its nearest corner along each axis: a Lipschitz bound). A cell with
some infeasible corners holds the feasible set's boundary, where a quantity can have an
unbounded slope (the five-bar's isotropic force grows like ``sqrt(distance)`` away from its
reach boundary, an inverse singularity), so it gets a Hoelder-1/2 bound over its whole width,
``min(feasible corner values) - sum_i H_i sqrt(w_i)``; for a smooth quantity that costs
about as much as the Lipschitz bound. ``L_i`` and ``H_i`` are estimated, not proven:
``safety`` (2) times the largest ``|difference| / h`` and ``|difference| / sqrt(h)`` between
neighbouring feasible nodes of the parent's 3^d block of nodes, or of the neighbouring
coarse cells, and of the parent's own estimate (one level of memory: local enough to shrink
near a smooth minimum, wide enough to see a kink). An axis with no feasible pair in the block
keeps the parent's value (a boundary cell cannot see the slope normal to the boundary).
A cell with no feasible corner is kept for one more split if its parent had feasible corners
(a convex boundary can bulge between two infeasible corners by about ``w^2 / (8 rho)`` for a
boundary of radius ``rho``), else dropped; a feasible region thinner than the coarse spacing
with no feasible coarse node near it is not seen, as a dense grid would not see it below its
own spacing. So ``true min >= value - tol`` holds when those estimates bound the quantity's
local variation; it fails where the quantity is unbounded (a cell next to a singularity
where it tends to infinity can be pruned too early: the five-bar's isotropic force *maximum*
is such a case). ``metrics.convergence.convergence_study`` therefore checks every refined extreme against every
grid rung and marks it "contradicted" when a grid point beats it. The tests check the
minimum against an analytic value (Inverse3) and brute-force fine grids (five-bar).
"""
from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from kinematics.grid import GridSpec
from kinematics.validation import positive_finite

from .quantities import CORE_QUANTITIES, QUANTITIES, check_quantities, evaluate

#: Points per evaluate() call in the refinement (bounds the temporary memory).
EVAL_CHUNK = 65536


# -- shared with metrics.convergence --------------------------------------------------------

def ladder_resolution(grid: GridSpec, n: int) -> tuple[int, ...]:
    """Per-axis resolution of a rung with ``n`` points on the grid's longest axis.

    The others scale with the grid's own resolution, rounded, at least 2: the rung keeps the
    preset's aspect. ``n`` must be an integer >= 2.

    Parameters
    ----------
    grid : GridSpec
        The preset's grid; its resolution sets the aspect.
    n : int
        Points on the longest axis, >= 2.

    Returns
    -------
    tuple of int, length d
        Points per axis of the rung.

    Examples
    --------
    >>> g = GridSpec(("x", "z"), (0.0, 0.0), (0.2, 0.1), (521, 261), (("y", 0.05),))
    >>> ladder_resolution(g, 100)
    (100, 50)
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 2:
        raise ValueError(f"a ladder rung needs an integer number of points >= 2, got {n!r}")
    top = max(grid.resolution)
    return tuple(max(2, int(round(r * int(n) / top))) for r in grid.resolution)


def check_scalar_quantities(mechanism, quantities) -> tuple[str, ...]:
    """The names of ``quantities`` (one str or several), each a per-point scalar with global
    figures, no repeats; a ValueError naming the quantity otherwise.

    Parameters
    ----------
    mechanism : Mechanism
        The model the quantities must be available for.
    quantities : str or iterable of str
        Quantity names (``metrics.quantities.QUANTITIES``).

    Returns
    -------
    tuple of str
        The names, in the given order.
    """
    if isinstance(quantities, str):
        quantities = (quantities,)
    names = check_quantities(mechanism, quantities)
    if not names:
        raise ValueError("quantities must name at least one quantity, got none")
    for name in names:
        node = QUANTITIES[name]
        if not node.scalar or node.categorical:
            raise ValueError(f"quantity {name!r} has no global min/max/mean/SD (it is "
                             f"{'categorical' if node.categorical else 'not a per-point scalar'}); "
                             f"choose a scalar quantity such as {', '.join(CORE_QUANTITIES)}")
    if len(set(names)) != len(names):
        raise ValueError(f"quantities must not repeat a name, got {list(names)}")
    return names


def finite_or_none(value: Any) -> float | None:
    """A float for JSON, or None where it is not finite (JSON has no nan/inf).

    Parameters
    ----------
    value : float-like or None
        Anything ``float`` accepts.

    Returns
    -------
    float or None

    Examples
    --------
    >>> finite_or_none(2.5), finite_or_none(float("nan")), finite_or_none(None)
    (2.5, None, None)
    """
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def task_points(grid: GridSpec, task_names: tuple[str, ...], coords: np.ndarray) -> np.ndarray:
    """Task-space points (N, m) from coordinates along the grid's axes (N, d).

    Parameters
    ----------
    grid : GridSpec
        Names the axes and the fixed coordinates.
    task_names : tuple of str, length m
        The mechanism's task coordinates, in order.
    coords : ndarray, shape (N, d)
        Coordinates along ``grid.axes``, m.

    Returns
    -------
    ndarray, shape (N, m)
        Task-space points, m.

    Examples
    --------
    >>> g = GridSpec(("x", "z"), (0.0, 0.0), (0.2, 0.1), (3, 3), (("y", 0.05),))
    >>> task_points(g, ("x", "y", "z"), np.array([[0.1, 0.02]])).tolist()
    [[0.1, 0.05, 0.02]]
    """
    fixed = dict(grid.fixed)
    out = np.empty((coords.shape[0], len(task_names)))
    for j, name in enumerate(task_names):
        if name in grid.axes:
            out[:, j] = coords[:, grid.axes.index(name)]
        elif name in fixed:
            out[:, j] = fixed[name]
        else:
            raise ValueError(f"grid has no value for task coordinate {name!r}: add it to axes or fixed")
    return out


def _resolution_label(resolution) -> str:
    return " x ".join(str(int(r)) for r in resolution)


# -- the result ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Refinement:
    """A global extreme of one quantity over the grid box intersected with the feasible set.

    ``value`` is attained at ``point`` (task space, m). The true extreme lies between
    ``bound`` and ``value`` (min: ``bound <= true <= value``; max: ``value <= true <=
    bound``), and ``value`` is within ``tol`` of it, when ``certified`` (see the module
    notes for the assumption). ``evaluations`` counts the points passed to
    ``metrics.quantities.evaluate``, coarse grid included.
    """

    quantity: str
    sense: str
    value: float
    point: tuple[float, ...]
    bound: float
    tol: float
    certified: bool
    evaluations: int
    seconds: float
    levels: int
    coarse_resolution: tuple[int, ...]
    finest_spacing: tuple[float, ...]
    history: tuple[tuple[int, int, int, float], ...] = field(default=(), repr=False)

    def to_dict(self) -> dict:
        """Plain JSON values (points in m); non-finite numbers become None.

        Returns
        -------
        dict
            The fields by name, ``history`` as a list of dicts.
        """
        return {
            "quantity": self.quantity, "sense": self.sense, "value": finite_or_none(self.value),
            "point": [float(c) for c in self.point], "bound": finite_or_none(self.bound),
            "tol": self.tol, "certified": self.certified, "evaluations": self.evaluations,
            "seconds": self.seconds, "levels": self.levels,
            "coarse_resolution": list(self.coarse_resolution),
            "finest_spacing": list(self.finest_spacing),
            "history": [{"level": lv, "cells": c, "evaluations": e, "best": finite_or_none(b)}
                        for lv, c, e, b in self.history],
        }


# -- lattice geometry ------------------------------------------------------------------------

_CORNERS = {d: np.array(list(itertools.product((0, 1), repeat=d)), dtype=np.int64) for d in (2, 3)}
_BLOCK = {d: np.array(list(itertools.product((0, 1, 2), repeat=d)), dtype=np.int64) for d in (2, 3)}


def _block_index(offsets: np.ndarray) -> np.ndarray:
    """Index into the 3^d block of child nodes of offsets in {0, 1, 2}^d (row-major)."""
    d = offsets.shape[-1]
    return np.sum(offsets * (3 ** np.arange(d - 1, -1, -1)), axis=-1)


def _neighbour_pairs(nodes: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """For each axis, index pairs (a, b) of ``nodes`` (k, d) with nodes[b] = nodes[a] + e_axis."""
    d = nodes.shape[1]
    where = {tuple(row): i for i, row in enumerate(nodes.tolist())}
    out = []
    for axis in range(d):
        step = np.eye(d, dtype=np.int64)[axis]
        pairs = [(i, where[tuple((row + step).tolist())]) for i, row in enumerate(nodes)
                 if tuple((row + step).tolist()) in where]
        out.append((np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])))
    return out


def _across(ufunc, a: np.ndarray) -> np.ndarray:
    """``ufunc.reduce(a, axis=1)`` of an (N, k) array of a few columns, one column at a time, shape (N,).

    The same values: a minimum, maximum, "or", "and" or a count is exact in any order. numpy's
    reduction along a short last axis took eight times as long as k - 1 passes over whole columns.
    Booleans are counted (``np.add``) in int64.
    """
    out = np.array(a[:, 0], dtype=np.int64 if ufunc is np.add and a.dtype == bool else a.dtype)
    for j in range(1, a.shape[1]):
        ufunc(out, a[:, j], out=out)
    return out


def _slopes(values: np.ndarray, pairs, spacing: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-axis largest |difference| / h and / sqrt(h) over node pairs with both values finite.

    ``values`` (N, k) are node values of N groups, ``pairs`` from ``_neighbour_pairs``;
    returns two (N, d) arrays (0 where an axis has no finite pair) and that mask, (N, d).
    """
    d = spacing.size
    lip = np.zeros((values.shape[0], d))
    hol = np.zeros((values.shape[0], d))
    seen = np.zeros((values.shape[0], d), bool)
    for axis, (a, b) in enumerate(pairs):
        with np.errstate(invalid="ignore"):
            diff = np.abs(np.take(values, b, axis=1) - np.take(values, a, axis=1))
        finite = np.isfinite(diff)
        diff = _across(np.maximum, np.where(finite, diff, 0.0))
        lip[:, axis] = diff / spacing[axis]
        hol[:, axis] = diff / math.sqrt(spacing[axis])
        seen[:, axis] = _across(np.logical_or, finite)
    return lip, hol, seen


def _unique_keys(key: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The sorted unique values of int64 ``key`` (N,) and the inverse index (N,) that rebuilds ``key``."""
    # np.unique's stable sort for the first indices cost four times this: any row of a key is the row.
    # Stable (timsort) nonetheless: a block's nodes come in runs of ascending keys, which it merges,
    # and it took 0.6-0.85 of the default sort's time over a refinement's levels (same order of keys).
    order = np.argsort(key, kind="stable")
    ordered = key[order]
    new = np.empty(key.size, bool)
    new[:1] = True
    np.not_equal(ordered[1:], ordered[:-1], out=new[1:])
    inverse = np.empty(key.size, np.int64)
    inverse[order] = np.cumsum(new) - 1
    return ordered[new], inverse


def _unique_rows(rows: np.ndarray, sizes: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """Unique integer rows (sorted by their row-major key) and the inverse index; one int64 key where it fits.

    ``rows[:, a]`` must lie in ``[0, sizes[a])``.
    """
    if math.prod(sizes) < 2 ** 62:
        key = rows[:, 0].astype(np.int64)
        for axis in range(1, len(sizes)):
            key *= sizes[axis]
            key += rows[:, axis]
        uniq, inverse = _unique_keys(key)
        return _key_rows(uniq, sizes), inverse
    uniq, inverse = np.unique(rows, axis=0, return_inverse=True)
    return uniq, inverse.reshape(-1)


def _key_rows(key: np.ndarray, sizes: list[int]) -> np.ndarray:
    """The rows (N, d) of row-major keys (N,) in a lattice of ``sizes`` points per axis (their inverse)."""
    rows = np.empty((key.size, len(sizes)), np.int64)
    rest = key.copy()
    for axis in range(len(sizes) - 1, 0, -1):
        np.remainder(rest, sizes[axis], out=rows[:, axis])
        rest //= sizes[axis]
    rows[:, 0] = rest
    return rows


def _new_nodes(lo: np.ndarray, offsets: np.ndarray, sizes: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """``_unique_rows`` of the nodes ``2 lo + offsets`` of every cell, without making them.

    A row-major key is linear in the row, so a node's key is its cell's ``key(2 lo)`` plus its
    offset's ``key(offsets)``: one (K, n) sum of int64 instead of the (K, n, d) nodes and their keys,
    the same keys (exact integers), hence the same sorted unique nodes and inverse. The cells' keys
    are sorted first (K of them), and the n * K node keys laid out offset by offset: n ascending
    runs, which the stable sort (timsort) merges, where the cell by cell layout was a sort of
    n * K keys in short runs. That halved the function's time over a refinement's levels.

    Parameters
    ----------
    lo : ndarray of int64, shape (K, d)
        The cells' lower corner nodes at the coarser level.
    offsets : ndarray of int64, shape (n, d)
        The new nodes' offsets in the cell's 3^d block (``_Blocks.new``).
    sizes : list of int, length d
        Nodes per axis at the finer level.

    Returns
    -------
    uniq : ndarray of int64, shape (U, d)
        The distinct nodes, sorted by their row-major key.
    inverse : ndarray of int64, shape (K, n)
        ``uniq[inverse[k, j]]`` is ``2 lo[k] + offsets[j]``.
    """
    k, n = lo.shape[0], offsets.shape[0]
    if math.prod(sizes) >= 2 ** 62:
        uniq, inverse = _unique_rows((2 * lo[:, None, :] + offsets[None, :, :]).reshape(-1, len(sizes)), sizes)
        return uniq, inverse.reshape(k, n)
    strides = [math.prod(sizes[a + 1:]) for a in range(len(sizes))]
    base = lo[:, 0] * (2 * strides[0])
    for axis in range(1, len(sizes)):
        base += lo[:, axis] * (2 * strides[axis])
    off = np.array([sum(int(o) * st for o, st in zip(row, strides)) for row in offsets], np.int64)
    by_key = np.argsort(base, kind="stable")
    uniq, inverse = _unique_keys((off[:, None] + base[by_key][None, :]).reshape(-1))       # (n, K) layout
    out = np.empty((k, n), np.int64)
    out[by_key] = inverse.reshape(n, k).T
    return _key_rows(uniq, sizes), out


def refine_global_minimum(mechanism, grid: GridSpec, quantity: str = "isotropic_force", *, tol: float,
                          coarse_resolution: int | tuple[int, ...] = 64, safety: float = 2.0,
                          max_evaluations: int = 2_000_000, loading=None) -> Refinement:
    """Global minimum of ``quantity`` over ``grid``'s box and the feasible set, to within ``tol``.

    Parameters
    ----------
    mechanism : Mechanism
        A kinematics model.
    grid : GridSpec
        The box (its ``resolution`` only sets the aspect of the coarse grid).
    quantity : str
        A scalar map quantity; the default is paper 000's "global maximum isotropic force"
        (the smallest maximum isotropic force over the workspace).
    tol : float
        Absolute tolerance in the quantity's unit: when ``certified``, ``value - tol <=
        true minimum <= value``.
    coarse_resolution : int or tuple
        Starting grid: an int is the point count on the longest axis (aspect kept, like a
        ladder rung), a tuple gives every axis.
    safety : float
        Factor on the finite-difference slope estimates used as local bounds.
    max_evaluations : int
        Budget of points passed to ``evaluate``; when the next split would exceed it (or
        would need cells finer than float64 can place) the search stops and returns
        ``certified=False`` with the bound reached.
    loading : metrics.loading.Loading, optional
        Torque rating and gravity (``evaluate``'s ``loading``); default continuous, gravity off.

    Returns
    -------
    Refinement
    """
    return _refine(mechanism, grid, quantity, +1.0, tol, coarse_resolution, safety, max_evaluations, loading)


def refine_global_maximum(mechanism, grid: GridSpec, quantity: str = "isotropic_force", *, tol: float,
                          coarse_resolution: int | tuple[int, ...] = 64, safety: float = 2.0,
                          max_evaluations: int = 2_000_000, loading=None) -> Refinement:
    """Global maximum of ``quantity`` (the minimum of its negative); see ``refine_global_minimum``.

    Parameters
    ----------
    mechanism : Mechanism
        A kinematics model.
    grid : GridSpec
        The box (its ``resolution`` only sets the aspect of the coarse grid).
    quantity : str
        A scalar map quantity.
    tol : float
        Absolute tolerance in the quantity's unit: when ``certified``, ``value <= true
        maximum <= value + tol``.
    coarse_resolution : int or tuple of int
        Starting grid, as in ``refine_global_minimum``.
    safety : float
        Factor on the finite-difference slope estimates used as local bounds.
    max_evaluations : int
        Budget of points passed to ``evaluate`` (``certified=False`` when it runs out).
    loading : metrics.loading.Loading, optional
        Torque rating and gravity; default continuous, gravity off.

    Returns
    -------
    Refinement
        ``sense`` is ``"max"``.
    """
    return _refine(mechanism, grid, quantity, -1.0, tol, coarse_resolution, safety, max_evaluations, loading)


# -- the search, step by step ---------------------------------------------------------------

def _coarse_resolution(grid: GridSpec, coarse_resolution) -> tuple[int, ...]:
    """The starting grid's points per axis: an int is a ladder rung, a tuple one count per axis."""
    if isinstance(coarse_resolution, (int, np.integer)) and not isinstance(coarse_resolution, bool):
        return ladder_resolution(grid, int(coarse_resolution))
    try:
        return tuple(int(r) for r in coarse_resolution)
    except TypeError:
        raise ValueError(f"coarse_resolution must be an int or one int per axis {grid.axes!r}, "
                         f"got {coarse_resolution!r}") from None


class _Lattice:
    """Nodes of the refinement's nested lattices: level ``l`` has spacing ``h0 / 2^l`` from the
    box's lower corner. Evaluates ``sign * quantity`` at nodes and counts the points."""

    def __init__(self, mechanism, grid: GridSpec, quantity: str, sign: float, coarse: GridSpec,
                 loading=None) -> None:
        self.mechanism, self.grid, self.quantity, self.sign = mechanism, grid, quantity, sign
        self.loading = loading
        self.lower, self.upper = np.array(grid.lower), np.array(grid.upper)
        self.h0 = np.array(coarse.spacing())
        self.n0 = np.array(coarse.resolution, dtype=np.int64)
        self.task_names = tuple(mechanism.task_names)
        self.evaluations = 0

    def coords(self, idx: np.ndarray, level: int) -> np.ndarray:
        return np.minimum(self.lower + idx * (self.h0 / 2.0 ** level), self.upper)

    def task_points(self, idx: np.ndarray, level: int) -> np.ndarray:
        """``task_points`` of ``coords``, each axis's column written in place: the same numbers, fewer passes."""
        step = self.h0 / 2.0 ** level
        fixed = dict(self.grid.fixed)
        out = np.empty((idx.shape[0], len(self.task_names)))
        for j, name in enumerate(self.task_names):
            if name in self.grid.axes:
                a = self.grid.axes.index(name)
                col = out[:, j]
                np.multiply(idx[:, a], step[a], out=col)
                np.add(col, self.lower[a], out=col)
                np.minimum(col, self.upper[a], out=col)
            elif name in fixed:
                out[:, j] = fixed[name]
            else:
                raise ValueError(f"grid has no value for task coordinate {name!r}: add it to axes or fixed")
        return out

    def values(self, idx: np.ndarray, level: int) -> np.ndarray:
        """sign * quantity at lattice nodes ``idx`` (N, d) of ``level``, shape (N,); nan where infeasible."""
        pts = self.task_points(idx, level)
        out = np.empty(pts.shape[0])
        for s in range(0, pts.shape[0], EVAL_CHUNK):
            ev = evaluate(self.mechanism, pts[s:s + EVAL_CHUNK], (self.quantity,), loading=self.loading)
            out[s:s + EVAL_CHUNK] = ev.values[self.quantity]
        self.evaluations += pts.shape[0]
        return self.sign * out

    def point(self, idx: np.ndarray, level: int) -> tuple[float, ...]:
        """The task point (m) of one node."""
        return tuple(float(c) for c in task_points(self.grid, self.task_names, self.coords(idx[None, :], level))[0])


@dataclass
class _Cells:
    """The live cells of one level: lower corner nodes ``lo`` (C, d), corner values ``cv``
    (C, 2^d), slope estimates ``est_l``/``est_h`` and the bounds in use ``lip``/``hol`` (C, d),
    and ``inherit`` (C,), the parent's bound for a cell with no feasible corner (+inf for a dropped one,
    else nan)."""

    lo: np.ndarray
    cv: np.ndarray
    est_l: np.ndarray
    est_h: np.ndarray
    lip: np.ndarray
    hol: np.ndarray
    inherit: np.ndarray

    def take(self, at: np.ndarray) -> "_Cells":
        # By index, not by mask: numpy's boolean indexing of (C, k) rows was a quarter of the search.
        return _Cells(*(np.take(a, at, axis=0) for a in (self.lo, self.cv, self.est_l, self.est_h, self.lip,
                                                          self.hol, self.inherit)))


def _block_max(a: np.ndarray) -> np.ndarray:
    """The largest value of each entry's 3^d block of neighbours (edges repeated), shape of ``a``.

    What ``scipy.ndimage.maximum_filter(a, size=3, mode="nearest")`` gives, exactly (a maximum
    picks a value, it rounds nothing), one axis after the other: a box's maximum is the maximum
    over each axis in turn. scipy.ndimage cost 0.37 s of every ``isoforce convergence`` to import.

    Examples
    --------
    >>> _block_max(np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 5.0]])).tolist()
    [[1.0, 1.0, 5.0, 5.0], [1.0, 1.0, 5.0, 5.0]]
    """
    for axis in range(a.ndim):
        n = a.shape[axis]
        padded = np.concatenate([a.take([0], axis=axis), a, a.take([n - 1], axis=axis)], axis=axis)
        a = np.maximum(np.maximum(padded.take(np.arange(n), axis=axis), padded.take(np.arange(1, n + 1), axis=axis)),
                       padded.take(np.arange(2, n + 2), axis=axis))
    return a


def _coarse_cells(lat: _Lattice, safety: float) -> tuple[_Cells, float, tuple[np.ndarray, int]]:
    """Level 0: the coarse grid's cells, and the best node (value, (node, level)).

    A cell's slope estimates are the largest over the corner pairs of its 3^d neighbourhood
    of cells, like a parent's block at finer levels.
    """
    d = lat.n0.size
    corners = _CORNERS[d]
    nodes = np.stack(np.meshgrid(*[np.arange(n) for n in lat.n0], indexing="ij"), axis=-1).reshape(-1, d)
    node_vals = lat.values(nodes, 0).reshape(tuple(lat.n0))
    best, best_at = np.inf, (nodes[0], 0)
    if np.any(~np.isnan(node_vals)):
        flat = np.where(np.isnan(node_vals), np.inf, node_vals).reshape(-1)
        i = int(np.argmin(flat))
        best, best_at = float(flat[i]), (nodes[i], 0)
    cell_shape = tuple(lat.n0 - 1)
    lo = np.stack(np.meshgrid(*[np.arange(n) for n in cell_shape], indexing="ij"), axis=-1).reshape(-1, d)
    cv = np.stack([node_vals[tuple((lo + c).T)] for c in corners], axis=1)           # (C, 2^d)
    lip0, hol0, _ = _slopes(cv, _neighbour_pairs(corners), lat.h0)
    est_l = np.stack([_block_max(lip0[:, i].reshape(cell_shape)).reshape(-1) for i in range(d)], axis=1)
    est_h = np.stack([_block_max(hol0[:, i].reshape(cell_shape)).reshape(-1) for i in range(d)], axis=1)
    cells = _Cells(lo, cv, est_l, est_h, safety * est_l, safety * est_h, np.full(lo.shape[0], np.nan))
    return cells, best, best_at


def _lower_bounds(cells: _Cells, width: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each cell's lower bound of ``sign * quantity`` (C,), and its count of feasible corners."""
    nc = cells.cv.shape[1]
    feasible = ~np.isnan(cells.cv)
    nfeas = _across(np.add, feasible)
    fmin = _across(np.minimum, np.where(feasible, cells.cv, np.inf))
    with np.errstate(invalid="ignore"):
        # All corners feasible: every point is within w/2 per axis of its nearest corner
        # (Lipschitz). Some infeasible: the cell holds the feasible set's boundary, where
        # the quantity can have an infinite slope (the five-bar's isotropic force goes
        # like sqrt(distance) at its reach boundary), so a Hoelder-1/2 bound over the
        # whole width. inf - inf (an infinite slope) is nan: keep such a cell.
        lb = np.where(nfeas == nc, fmin - cells.lip @ (0.5 * width), fmin - cells.hol @ np.sqrt(width))
        lb = np.where(np.isnan(lb), -np.inf, lb)
    # A cell with no feasible corner has its parent's bound (probation), or, on the
    # coarse grid, none at all: it is dropped (+inf), like a region the grid never sees.
    lb = np.where(nfeas == 0, np.where(np.isnan(cells.inherit), np.inf, cells.inherit), lb)
    return lb, nfeas


class _Blocks:
    """Index tables for splitting a cell into its 2^d children through its 3^d block of nodes."""

    def __init__(self, d: int) -> None:
        self.corners, self.block = _CORNERS[d], _BLOCK[d]
        self.even = np.all(self.block % 2 == 0, axis=1)
        self.new = self.block[~self.even]       # the block's nodes a split evaluates
        self.parent_slot = np.array([int(np.flatnonzero(np.all(self.corners == b // 2, axis=1))[0])
                                     for b in self.block[self.even]])
        self.child_slots = np.stack([_block_index(c + self.corners) for c in self.corners])   # (2^d, 2^d)
        self.pairs = _neighbour_pairs(self.block)
        # A new node with m coordinates on its cell's faces (offset 0 or 2: even at the finer level)
        # lies in at most 2^m cells' blocks, at an offset with the same m (the parities are the
        # node's own): (offsets with m, 2^m) for each m, for ``fewest_new``.
        faces = np.sum(self.new % 2 == 0, axis=1)
        self.sharing = [(int(np.sum(faces == m)), 2 ** m) for m in range(d + 1) if np.any(faces == m)]

    def fewest_new(self, cells: int) -> int:
        """A lower bound of the distinct new nodes of ``cells`` distinct cells (``_new_nodes``' U).

        ``cells * count`` (cell, offset) pairs of a class, each node of the class in at most
        ``2^m`` of them: at least ``ceil(cells * count / 2^m)`` nodes. 2D: ``3 * cells`` of ``5 * cells``.
        """
        return sum(-(-cells * count // share) for count, share in self.sharing)


def _children(kept: _Cells, lb_k: np.ndarray, probation_k: np.ndarray, nv: np.ndarray, bl: _Blocks,
              spacing: np.ndarray, safety: float) -> _Cells:
    """The children of the kept cells, from their blocks' node values ``nv`` (K, 3^d).

    Slopes over the parent's 3^d block at the children's spacing, shared by its children;
    the bound in use is the larger of that and the parent's own estimate (one level of
    memory: local enough to shrink near a smooth minimum, wide enough to see a kink).
    An axis with no finite pair in the block (a cell at the boundary, one column of
    feasible nodes) keeps the parent's estimate: the slope normal to the boundary is the
    one that matters there, and the block cannot see it.
    """
    d = kept.lo.shape[1]
    nc = bl.corners.shape[0]
    blk_l, blk_h, seen = _slopes(nv, bl.pairs, spacing)
    blk_l = np.where(seen, blk_l, kept.est_l)
    blk_h = np.where(seen, blk_h, kept.est_h)
    use_l = safety * np.maximum(blk_l, kept.est_l)
    use_h = safety * np.maximum(blk_h, kept.est_h)
    # Column by column (the same integers): numpy's broadcast sum over (K, 2^d, d) with its inner
    # axis of d took five times as long, 1.4 ms of a 37,000-cell level.
    lo = np.empty((kept.lo.shape[0], nc, d), np.int64)
    for axis in range(d):
        twice = 2 * kept.lo[:, axis]
        for c in range(nc):
            np.add(twice, bl.corners[c, axis], out=lo[:, c, axis])
    lo = lo.reshape(-1, d)
    cv = np.take(nv, bl.child_slots, axis=1).reshape(-1, nc)
    empty = _across(np.logical_and, np.isnan(cv))
    drop = empty & np.repeat(probation_k, nc)
    # A dropped child keeps its row with a bound of +inf (``_lower_bounds``): the next level
    # neither keeps it nor counts it as pruned, as if it were gone, and its arrays are not copied.
    inherit = np.where(drop, np.inf, np.where(empty, np.repeat(lb_k, nc), np.nan))
    return _Cells(lo, cv, np.repeat(blk_l, nc, axis=0), np.repeat(blk_h, nc, axis=0),
                  np.repeat(use_l, nc, axis=0), np.repeat(use_h, nc, axis=0), inherit)


def _refine(mechanism, grid: GridSpec, quantity: str, sign: float, tol: float, coarse_resolution,
            safety: float, max_evaluations: int, loading=None) -> Refinement:
    check_scalar_quantities(mechanism, (quantity,))
    if loading is not None:
        loading.check(mechanism)
    tol = positive_finite("tol", tol)
    safety = positive_finite("safety", safety)
    if isinstance(max_evaluations, bool) or not isinstance(max_evaluations, (int, np.integer)) or max_evaluations < 1:
        raise ValueError(f"max_evaluations must be a positive integer, got {max_evaluations!r}")
    coarse = grid.with_resolution(_coarse_resolution(grid, coarse_resolution))      # validates the counts
    d = len(grid.axes)
    start = time.perf_counter()
    lat = _Lattice(mechanism, grid, quantity, sign, coarse, loading)
    h0, n0a = lat.h0, lat.n0
    cells, best, best_at = _coarse_cells(lat, safety)
    bl = _Blocks(d)

    # Below a few ulps of the coordinates, new nodes would coincide with old ones.
    finest_step = 8.0 * float(np.spacing(np.max(np.abs(np.concatenate([lat.lower, lat.upper])))))
    level = 0
    pruned_bound = np.inf
    remaining_bound = np.inf
    history: list[tuple[int, int, int, float]] = []
    certified = False
    while True:
        lb, nfeas = _lower_bounds(cells, h0 / 2.0 ** level)
        keep = lb < best - tol
        # The finite bounds of the pruned cells, in one pass (a minimum is exact in any order).
        pruned_bound = min(pruned_bound, float(np.min(lb, where=~keep & np.isfinite(lb), initial=np.inf)))
        at = np.flatnonzero(keep)
        history.append((level, int(at.size), lat.evaluations, sign * best))
        if not at.size or best == -np.inf:
            certified = True
            break
        lb_k = np.take(lb, at)
        if np.any(h0 / 2.0 ** (level + 1) < finest_step):
            remaining_bound = float(lb_k.min())      # float64 cannot place finer nodes
            break
        # The split that would pass the budget is seen from a lower bound of its nodes where it
        # can be (the cells are distinct): its nodes and the kept cells are not made. A search
        # that ran out of its budget made them for nothing (a fifth of its node bookkeeping).
        if lat.evaluations + bl.fewest_new(at.size) > max_evaluations:
            remaining_bound = float(lb_k.min())
            break
        kept = cells.take(at)
        sizes = [int(n - 1) * 2 ** (level + 1) + 1 for n in n0a]
        uniq, inverse = _new_nodes(kept.lo, bl.new, sizes)                  # (U, d), (K, 3^d - 2^d)
        if lat.evaluations + uniq.shape[0] > max_evaluations:
            remaining_bound = float(lb_k.min())
            break
        vals = lat.values(uniq, level + 1)
        level += 1
        nv = np.empty((kept.lo.shape[0], bl.block.shape[0]))
        # np.take rather than fancy indexing throughout the loop: the same elements, a fraction of the time.
        nv[:, bl.even] = np.take(kept.cv, bl.parent_slot, axis=1)
        nv[:, ~bl.even] = np.take(vals, inverse)
        v = np.where(np.isnan(vals), np.inf, vals)       # all infeasible: inf, which improves nothing
        i = int(np.argmin(v))
        if v[i] < best:
            best, best_at = float(v[i]), (uniq[i], level)
        cells = _children(kept, lb_k, np.take(nfeas, at) == 0, nv, bl, h0 / 2.0 ** level, safety)
    bound_min = min(pruned_bound, remaining_bound, best)
    if best == np.inf:        # nothing feasible
        value, bound, point = math.nan, math.nan, ()
    else:
        value, bound, point = sign * best, sign * bound_min, lat.point(*best_at)
    return Refinement(quantity=quantity, sense="min" if sign > 0 else "max", value=value, point=point,
                      bound=bound, tol=tol, certified=certified and best != np.inf, evaluations=lat.evaluations,
                      seconds=time.perf_counter() - start, levels=level, coarse_resolution=tuple(int(n) for n in n0a),
                      finest_spacing=tuple(float(s) for s in h0 / 2.0 ** level), history=tuple(history))
