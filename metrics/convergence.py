"""Error against run time: how a map's global figures depend on its resolution.

Two tools, both headless (numpy/scipy only):

``convergence_study``
    Runs ``compute_map`` at a ladder of resolutions and records, for every rung, the wall
    time, the point counts, every global figure (min, max, mean, SD of each quantity) and its
    error, absolute and relative, against the finest run (the reference). Where an exact
    value exists it is used as well: the global min and max of each quantity are located by
    ``refine_global_minimum`` / ``refine_global_maximum`` to a tolerance far below the grid
    spacing, so ``exact_errors`` are true errors, not differences between two grids.
    Only statistics are kept: each map is dropped before the next rung runs, so a
    2000 x 2000 ladder needs the memory of one map, not of the whole ladder.

``refine_global_minimum``
    Branch and bound on a quadtree (octree in 3D) over the grid's box: start from a coarse
    grid, give every cell a lower bound from its corner values and local slope estimates,
    discard cells whose bound cannot beat the best value found by more than
    ``tol``, and split the rest in ``2^d`` until none is left. It works on the same
    continuous domain the dense grid samples (grid box intersected with the feasible set),
    including its boundary, where the minimum isotropic force of the Inverse3 lies.

Ladder convention: a rung ``n`` puts ``n`` points on the grid's longest axis (the axis with
most points in the preset) and scales the others in proportion to the preset's own
resolution (at least 2), so the ladder keeps the preset's aspect: the Inverse3 slice
(1000 x 1000) gives ``n x n``, the five-bar half plane (521 x 261) about ``n x n/2``.

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
is such a case). ``convergence_study`` therefore checks every refined extreme against every
grid rung and marks it "contradicted" when a grid point beats it. The tests check the
minimum against an analytic value (Inverse3) and brute-force fine grids (five-bar).
"""
from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
from scipy import ndimage

from kinematics.base import positive_finite

from .quantities import QUANTITIES, STATS_QUANTITIES, TABLE3_QUANTITIES, check_quantities, evaluate
from .workspace import GridSpec, compute_map

#: Points on the longest axis of each rung of the default ladder.
DEFAULT_LADDER = (50, 100, 200, 500, 1000, 2000)
#: The global figures of every quantity, in table order.
FIGURES = ("min", "max", "mean", "sd", "median", "p05", "p95")
#: Points per evaluate() call in the refinement (bounds the temporary memory).
EVAL_CHUNK = 65536


# -- helpers --------------------------------------------------------------------------------

def ladder_resolution(grid: GridSpec, n: int) -> tuple[int, ...]:
    """Per-axis resolution of a rung with ``n`` points on the grid's longest axis.

    The others scale with the grid's own resolution, rounded, at least 2: the rung keeps the
    preset's aspect. ``n`` must be an integer >= 2.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 2:
        raise ValueError(f"a ladder rung needs an integer number of points >= 2, got {n!r}")
    top = max(grid.resolution)
    return tuple(max(2, int(round(r * int(n) / top))) for r in grid.resolution)


def _check_scalar_quantities(mechanism, quantities) -> tuple[str, ...]:
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
                             f"choose a scalar quantity such as {', '.join(TABLE3_QUANTITIES)}")
    if len(set(names)) != len(names):
        raise ValueError(f"quantities must not repeat a name, got {list(names)}")
    return names


def _finite_or_none(value: Any) -> float | None:
    """A float for JSON, or None where it is not finite (JSON has no nan/inf)."""
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def _task_points(grid: GridSpec, task_names: tuple[str, ...], coords: np.ndarray) -> np.ndarray:
    """Task-space points (N, m) from coordinates along the grid's axes (N, d)."""
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


# -- adaptive refinement of a global extreme ------------------------------------------------

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
        """Plain JSON values (points in m); non-finite numbers become None."""
        return {
            "quantity": self.quantity, "sense": self.sense, "value": _finite_or_none(self.value),
            "point": [float(c) for c in self.point], "bound": _finite_or_none(self.bound),
            "tol": self.tol, "certified": self.certified, "evaluations": self.evaluations,
            "seconds": self.seconds, "levels": self.levels,
            "coarse_resolution": list(self.coarse_resolution),
            "finest_spacing": list(self.finest_spacing),
            "history": [{"level": lv, "cells": c, "evaluations": e, "best": _finite_or_none(b)}
                        for lv, c, e, b in self.history],
        }


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
            diff = np.abs(values[:, b] - values[:, a])
        finite = np.isfinite(diff)
        diff = np.where(finite, diff, 0.0).max(axis=1)
        lip[:, axis] = diff / spacing[axis]
        hol[:, axis] = diff / math.sqrt(spacing[axis])
        seen[:, axis] = finite.any(axis=1)
    return lip, hol, seen


def _unique_rows(rows: np.ndarray, sizes: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """Unique integer rows and the inverse index; a single int64 key where it fits."""
    if math.prod(sizes) < 2 ** 62:
        key = np.zeros(rows.shape[0], dtype=np.int64)
        for axis, size in enumerate(sizes):
            key = key * size + rows[:, axis]
        _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
        return rows[first], inverse.reshape(-1)
    uniq, inverse = np.unique(rows, axis=0, return_inverse=True)
    return uniq, inverse.reshape(-1)


def refine_global_minimum(mechanism, grid: GridSpec, quantity: str = "isotropic_force", *, tol: float,
                          coarse_resolution: int | tuple[int, ...] = 64, safety: float = 2.0,
                          max_evaluations: int = 2_000_000) -> Refinement:
    """Global minimum of ``quantity`` over ``grid``'s box and the feasible set, to within ``tol``.

    Parameters
    ----------
    mechanism : a kinematics model.
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

    Returns
    -------
    Refinement
    """
    return _refine(mechanism, grid, quantity, +1.0, tol, coarse_resolution, safety, max_evaluations)


def refine_global_maximum(mechanism, grid: GridSpec, quantity: str = "isotropic_force", *, tol: float,
                          coarse_resolution: int | tuple[int, ...] = 64, safety: float = 2.0,
                          max_evaluations: int = 2_000_000) -> Refinement:
    """Global maximum of ``quantity`` (the minimum of its negative); see ``refine_global_minimum``."""
    return _refine(mechanism, grid, quantity, -1.0, tol, coarse_resolution, safety, max_evaluations)


def _refine(mechanism, grid: GridSpec, quantity: str, sign: float, tol: float, coarse_resolution,
            safety: float, max_evaluations: int) -> Refinement:
    _check_scalar_quantities(mechanism, (quantity,))
    tol = positive_finite("tol", tol)
    safety = positive_finite("safety", safety)
    if isinstance(max_evaluations, bool) or not isinstance(max_evaluations, (int, np.integer)) or max_evaluations < 1:
        raise ValueError(f"max_evaluations must be a positive integer, got {max_evaluations!r}")
    if isinstance(coarse_resolution, (int, np.integer)) and not isinstance(coarse_resolution, bool):
        n0 = ladder_resolution(grid, int(coarse_resolution))
    else:
        try:
            n0 = tuple(int(r) for r in coarse_resolution)
        except TypeError:
            raise ValueError(f"coarse_resolution must be an int or one int per axis {grid.axes!r}, "
                             f"got {coarse_resolution!r}") from None
    coarse = grid.with_resolution(n0)      # validates the counts
    d = len(grid.axes)
    start = time.perf_counter()
    lower, upper = np.array(grid.lower), np.array(grid.upper)
    h0 = np.array(coarse.spacing())
    n0a = np.array(coarse.resolution, dtype=np.int64)
    task_names = tuple(mechanism.task_names)
    evaluations = 0

    def f(idx: np.ndarray, level: int) -> np.ndarray:
        """sign * quantity at lattice nodes ``idx`` (N, d) of ``level``; nan where infeasible."""
        nonlocal evaluations
        coords = np.minimum(lower + idx * (h0 / 2.0 ** level), upper)
        pts = _task_points(grid, task_names, coords)
        out = np.empty(pts.shape[0])
        for s in range(0, pts.shape[0], EVAL_CHUNK):
            ev = evaluate(mechanism, pts[s:s + EVAL_CHUNK], (quantity,))
            out[s:s + EVAL_CHUNK] = ev.values[quantity]
        evaluations += pts.shape[0]
        return sign * out

    def point_of(idx: np.ndarray, level: int) -> tuple[float, ...]:
        coords = np.minimum(lower + idx[None, :] * (h0 / 2.0 ** level), upper)
        return tuple(float(c) for c in _task_points(grid, task_names, coords)[0])

    corners, block = _CORNERS[d], _BLOCK[d]
    nc = corners.shape[0]

    # Level 0: the coarse grid. A cell's slope estimates are the largest over the corner
    # pairs of its 3^d neighbourhood of cells, like a parent's block at finer levels.
    nodes = np.stack(np.meshgrid(*[np.arange(n) for n in n0a], indexing="ij"), axis=-1).reshape(-1, d)
    node_vals = f(nodes, 0).reshape(tuple(n0a))
    best, best_at = np.inf, (nodes[0], 0)
    if np.any(~np.isnan(node_vals)):
        flat = np.where(np.isnan(node_vals), np.inf, node_vals).reshape(-1)
        i = int(np.argmin(flat))
        best, best_at = float(flat[i]), (nodes[i], 0)
    cell_shape = tuple(n0a - 1)
    lo = np.stack(np.meshgrid(*[np.arange(n) for n in cell_shape], indexing="ij"), axis=-1).reshape(-1, d)
    cv = np.stack([node_vals[tuple((lo + c).T)] for c in corners], axis=1)           # (C, 2^d)
    lip0, hol0, _ = _slopes(cv, _neighbour_pairs(corners), h0)
    est_l = np.stack([ndimage.maximum_filter(lip0[:, i].reshape(cell_shape), size=3, mode="nearest").reshape(-1)
                      for i in range(d)], axis=1)
    est_h = np.stack([ndimage.maximum_filter(hol0[:, i].reshape(cell_shape), size=3, mode="nearest").reshape(-1)
                      for i in range(d)], axis=1)
    lip, hol = safety * est_l, safety * est_h                                         # (C, d) bounds in use
    inherit = np.full(lo.shape[0], np.nan)                                            # bound of probation cells

    even = np.all(block % 2 == 0, axis=1)
    parent_slot = np.array([int(np.flatnonzero(np.all(corners == b // 2, axis=1))[0]) for b in block[even]])
    child_slots = np.stack([_block_index(c + corners) for c in corners])              # (2^d children, 2^d corners)
    block_pairs = _neighbour_pairs(block)

    # Below a few ulps of the coordinates, new nodes would coincide with old ones.
    finest_step = 8.0 * float(np.spacing(np.max(np.abs(np.concatenate([lower, upper])))))
    level = 0
    pruned_bound = np.inf
    remaining_bound = np.inf
    history: list[tuple[int, int, int, float]] = []
    certified = False
    while True:
        width = h0 / 2.0 ** level
        feasible = ~np.isnan(cv)
        nfeas = feasible.sum(axis=1)
        fmin = np.where(feasible, cv, np.inf).min(axis=1)
        with np.errstate(invalid="ignore"):
            # All corners feasible: every point is within w/2 per axis of its nearest corner
            # (Lipschitz). Some infeasible: the cell holds the feasible set's boundary, where
            # the quantity can have an infinite slope (the five-bar's isotropic force goes
            # like sqrt(distance) at its reach boundary), so a Hoelder-1/2 bound over the
            # whole width. inf - inf (an infinite slope) is nan: keep such a cell.
            lb = np.where(nfeas == nc, fmin - lip @ (0.5 * width), fmin - hol @ np.sqrt(width))
            lb = np.where(np.isnan(lb), -np.inf, lb)
        # A cell with no feasible corner has its parent's bound (probation), or, on the
        # coarse grid, none at all: it is dropped (+inf), like a region the grid never sees.
        lb = np.where(nfeas == 0, np.where(np.isnan(inherit), np.inf, inherit), lb)
        keep = lb < best - tol
        pruned = lb[~keep]
        pruned = pruned[np.isfinite(pruned)]
        if pruned.size:
            pruned_bound = min(pruned_bound, float(pruned.min()))
        history.append((level, int(keep.sum()), evaluations, sign * best))
        if not keep.any() or best == -np.inf:
            certified = True
            break
        lo_k, cv_k, lb_k = lo[keep], cv[keep], lb[keep]
        if np.any(h0 / 2.0 ** (level + 1) < finest_step):
            remaining_bound = float(lb_k.min())      # float64 cannot place finer nodes
            break
        est_lk, est_hk = est_l[keep], est_h[keep]
        probation_k = nfeas[keep] == 0
        kids = 2 * lo_k[:, None, :] + block[None, :, :]                               # (K, 3^d, d)
        sizes = [int(n - 1) * 2 ** (level + 1) + 1 for n in n0a]
        uniq, inverse = _unique_rows(kids[:, ~even, :].reshape(-1, d), sizes)
        if evaluations + uniq.shape[0] > max_evaluations:
            remaining_bound = float(lb_k.min())
            break
        vals = f(uniq, level + 1)
        level += 1
        nv = np.empty((lo_k.shape[0], block.shape[0]))
        nv[:, even] = cv_k[:, parent_slot]
        nv[:, ~even] = vals[inverse].reshape(lo_k.shape[0], -1)
        if np.any(~np.isnan(vals)):
            v = np.where(np.isnan(vals), np.inf, vals)
            i = int(np.argmin(v))
            if v[i] < best:
                best, best_at = float(v[i]), (uniq[i], level)
        # Slopes over the parent's 3^d block at the children's spacing, shared by its children;
        # the bound in use is the larger of that and the parent's own estimate (one level of
        # memory: local enough to shrink near a smooth minimum, wide enough to see a kink).
        # An axis with no finite pair in the block (a cell at the boundary, one column of
        # feasible nodes) keeps the parent's estimate: the slope normal to the boundary is the
        # one that matters there, and the block cannot see it.
        blk_l, blk_h, seen = _slopes(nv, block_pairs, h0 / 2.0 ** level)
        blk_l = np.where(seen, blk_l, est_lk)
        blk_h = np.where(seen, blk_h, est_hk)
        use_l = safety * np.maximum(blk_l, est_lk)
        use_h = safety * np.maximum(blk_h, est_hk)
        lo = (2 * lo_k[:, None, :] + corners[None, :, :]).reshape(-1, d)
        cv = nv[:, child_slots].reshape(-1, nc)
        est_l, est_h = np.repeat(blk_l, nc, axis=0), np.repeat(blk_h, nc, axis=0)
        lip, hol = np.repeat(use_l, nc, axis=0), np.repeat(use_h, nc, axis=0)
        empty = np.all(np.isnan(cv), axis=1)
        drop = empty & np.repeat(probation_k, nc)
        inherit = np.where(empty, np.repeat(lb_k, nc), np.nan)
        keep_kids = ~drop
        lo, cv, inherit = lo[keep_kids], cv[keep_kids], inherit[keep_kids]
        est_l, est_h, lip, hol = est_l[keep_kids], est_h[keep_kids], lip[keep_kids], hol[keep_kids]
    bound_min = min(pruned_bound, remaining_bound, best)
    if best == np.inf:        # nothing feasible
        value, bound, point = math.nan, math.nan, ()
    else:
        value, bound, point = sign * best, sign * bound_min, point_of(*best_at)
    return Refinement(quantity=quantity, sense="min" if sign > 0 else "max", value=value, point=point,
                      bound=bound, tol=tol, certified=certified and best != np.inf, evaluations=evaluations,
                      seconds=time.perf_counter() - start, levels=level, coarse_resolution=tuple(int(n) for n in n0a),
                      finest_spacing=tuple(float(s) for s in h0 / 2.0 ** level), history=tuple(history))


# -- the convergence study ------------------------------------------------------------------

@dataclass(frozen=True)
class ConvergenceRow:
    """One rung: its size, run time, global figures and their errors.

    ``figures[q][f]`` is figure ``f`` (min, max, mean, sd) of quantity ``q``;
    ``abs_errors``/``rel_errors`` compare it with the reference run (relative to
    ``|reference|``); ``exact_errors[q][f]`` is ``|figure - exact|`` for min and max where
    a usable exact value exists. Missing or non-finite errors are ``nan``.
    """

    resolution: tuple[int, ...]
    points: int
    feasible_points: int
    seconds: float
    figures: dict[str, dict[str, float]]
    abs_errors: dict[str, dict[str, float]]
    rel_errors: dict[str, dict[str, float]]
    exact_errors: dict[str, dict[str, float]]
    is_reference: bool = False

    def to_dict(self) -> dict:
        q = {}
        for name, figs in self.figures.items():
            q[name] = {f: {"value": _finite_or_none(figs[f]),
                           "abs_error": _finite_or_none(self.abs_errors[name][f]),
                           "rel_error": _finite_or_none(self.rel_errors[name][f]),
                           "exact_error": _finite_or_none(self.exact_errors[name].get(f))}
                       for f in FIGURES}
        return {"resolution": list(self.resolution), "points": self.points,
                "feasible_points": self.feasible_points, "seconds": self.seconds,
                "is_reference": self.is_reference, "quantities": q}


@dataclass(frozen=True)
class ExactFigure:
    """A global min or max located beyond the grid, and whether it can serve as the truth.

    ``status``: ``"certified"`` (refinement reached its tolerance ``tol``), ``"attained"``
    (the reference grid already holds ``inf``, e.g. a node on a singularity), ``"not
    certified"`` (budget ran out; ``value`` is only the best found), ``"contradicted"`` (a
    grid rung found a value beyond ``value`` by more than ``tol``: the refinement's local
    slope estimate failed, typically next to a singularity where the quantity is unbounded).
    Only the first two are used for ``exact_errors``.
    """

    figure: str
    value: float
    status: str
    tol: float
    note: str
    refinement: Refinement | None

    @property
    def usable(self) -> bool:
        return self.status in ("certified", "attained")

    def to_dict(self) -> dict:
        return {"figure": self.figure, "value": _finite_or_none(self.value), "status": self.status,
                "tol": _finite_or_none(self.tol), "note": self.note,
                "refinement": self.refinement.to_dict() if self.refinement is not None else None}


def _error(value: float, ref: float) -> tuple[float, float]:
    """|value - ref| and that over |ref|; nan where either is not finite (or ref is 0)."""
    if not (math.isfinite(value) and math.isfinite(ref)):
        return math.nan, math.nan
    err = abs(value - ref)
    return err, (err / abs(ref) if ref != 0.0 else math.nan)


@dataclass(frozen=True)
class ConvergenceStudy:
    """The ladder's rows (coarse to fine), the reference row, exact extremes and fitted rates.

    ``rates[q][f]`` is ``p`` in ``error ~ n^-p`` (``n`` points on the longest axis), a
    least-squares fit over the non-reference rows with a finite non-zero error against the
    reference; nan with fewer than two such rows. A ``p`` near 0 or below means the figure
    does not converge (or the reference is no better than the rungs). ``exact_rates`` is
    the same fit against the usable exact values, over every row including the reference.
    """

    grid: GridSpec
    quantities: tuple[str, ...]
    rows: tuple[ConvergenceRow, ...]
    reference: ConvergenceRow
    exact: dict[str, dict[str, ExactFigure]]
    rates: dict[str, dict[str, float]]
    exact_rates: dict[str, dict[str, float]]
    units: dict[str, str]

    def exact_value(self, quantity: str, figure: str) -> float | None:
        """The usable exact value of a figure, or None."""
        ex = self.exact.get(quantity, {}).get(figure)
        return ex.value if ex is not None and ex.usable else None

    def to_dict(self) -> dict:
        """A JSON-ready dict (``json.dumps(..., allow_nan=False)`` works; nan/inf are None)."""
        g = self.grid
        return {
            "grid": {"axes": list(g.axes), "lower": list(g.lower), "upper": list(g.upper),
                     "resolution": list(g.resolution), "fixed": {k: v for k, v in g.fixed}, "unit": "m"},
            "ladder": "rung n puts n points on the grid's longest axis; other axes scale with the grid's resolution",
            "quantities": list(self.quantities),
            "units": dict(self.units),
            "reference": self.reference.to_dict(),
            "rows": [r.to_dict() for r in self.rows],
            "exact": {q: {f: e.to_dict() for f, e in figs.items()} for q, figs in self.exact.items()},
            "rates": {q: {f: _finite_or_none(p) for f, p in figs.items()} for q, figs in self.rates.items()},
            "exact_rates": {q: {f: _finite_or_none(p) for f, p in figs.items()}
                            for q, figs in self.exact_rates.items()},
        }

    def format_table(self) -> str:
        """Text tables: the rungs, then per quantity each figure's error against the reference.

        Columns ``min-exact``/``max-exact`` give the error against a usable exact value.
        ``-`` marks an error that is not finite (an ``inf`` figure) or not defined.
        """
        ref = self.reference
        lines = [f"reference: {_resolution_label(ref.resolution)} ({ref.points:,} points, "
                 f"{ref.feasible_points:,} feasible, {ref.seconds:.3f} s)", "",
                 f"{'resolution':>13} {'points':>11} {'feasible':>11} {'seconds':>9}"]
        for r in self.rows:
            lines.append(f"{_resolution_label(r.resolution):>13} {r.points:>11,} {r.feasible_points:>11,} "
                         f"{r.seconds:>9.4f}" + ("  (reference)" if r.is_reference else ""))
        for q in self.quantities:
            unit = self.units.get(q, "")
            lines += ["", f"{q}" + (f" [{unit}]" if unit else "") + ": |figure - reference figure|"]
            figs = ref.figures[q]
            lines.append("  reference: " + "  ".join(f"{f} {_num(figs[f])}" for f in FIGURES))
            ex = self.exact.get(q, {})
            for f, e in ex.items():
                lines.append(f"  exact {f}: {_num(e.value)}  [{e.status}] {e.note}")
            ex_figs = [f for f in ("min", "max") if f in ex and ex[f].usable]
            header = f"  {'resolution':>13} {'seconds':>9}" + "".join(f" {f:>10}" for f in FIGURES)
            header += "".join(f" {f + '-exact':>10}" for f in ex_figs)
            lines.append(header)
            for r in self.rows:
                row = f"  {_resolution_label(r.resolution):>13} {r.seconds:>9.4f}"
                row += "".join(f" {'(ref)' if r.is_reference else _err(r.abs_errors[q][f]):>10}" for f in FIGURES)
                row += "".join(f" {_err(r.exact_errors[q].get(f, math.nan)):>10}" for f in ex_figs)
                lines.append(row)
            rates, ex_rates = self.rates[q], self.exact_rates.get(q, {})
            lines.append(f"  {'rate p':>13} {'':>9}" + "".join(f" {_rate(rates[f]):>10}" for f in FIGURES)
                         + "".join(f" {_rate(ex_rates.get(f, math.nan)):>10}" for f in ex_figs)
                         + "   (error ~ n^-p, n points per axis)")
        return "\n".join(lines)


def _num(value: float) -> str:
    return f"{value:.7g}" if math.isfinite(value) else str(value)


def _err(value: float | None) -> str:
    if value is None or not math.isfinite(value):
        return "-"
    return "0" if value == 0.0 else f"{value:.2e}"


def _rate(value: float) -> str:
    return f"{value:.2f}" if math.isfinite(value) else "-"


def _fit_rate(ns: list[float], errs: list[float]) -> float:
    pairs = [(n, e) for n, e in zip(ns, errs) if math.isfinite(e) and e > 0.0]
    if len(pairs) < 2 or len({p[0] for p in pairs}) < 2:
        return math.nan
    x = np.log([p[0] for p in pairs])
    y = np.log([p[1] for p in pairs])
    return float(-np.polyfit(x, y, 1)[0])


def _exact_figure(figure: str, r: Refinement, rungs: list[tuple[tuple[int, ...], dict]], q: str) -> ExactFigure:
    """Judge a refinement against every grid rung: no grid point may beat a true extreme."""
    note = (f"(+-{r.tol:.2g}; {r.evaluations:,} evaluations, {r.seconds:.3f} s, "
            f"coarse {_resolution_label(r.coarse_resolution)}, {r.levels} levels)")
    if math.isinf(r.value):
        return ExactFigure(figure, r.value, "attained", 0.0,
                           f"(the refinement reached a node where {q} is {r.value}: a singularity; "
                           f"{r.evaluations:,} evaluations)", r)
    for res, figs in rungs:
        grid_value = figs[q][figure]
        beyond = grid_value < r.value - r.tol if figure == "min" else grid_value > r.value + r.tol
        if beyond:
            return ExactFigure(figure, r.value, "contradicted", r.tol,
                               f"by the {_resolution_label(res)} grid ({_num(grid_value)}) " + note, r)
    if not r.certified:
        return ExactFigure(figure, r.value, "not certified", r.tol,
                           f"best found; the true {figure} lies between {_num(r.bound)} and it " + note, r)
    return ExactFigure(figure, r.value, "certified", r.tol, note, r)


def convergence_study(mechanism, grid: GridSpec, quantities=STATS_QUANTITIES, resolutions=DEFAULT_LADDER, *,
                      reference_resolution: int | None = None, exact_rtol: float | None = 1e-5,
                      exact_budget: int = 600_000, coarse_resolution: int = 64,
                      progress: Callable[[str], None] | None = None) -> ConvergenceStudy:
    """Run ``grid``'s map at each rung of ``resolutions`` and compare every global figure.

    Parameters
    ----------
    mechanism : a kinematics model.
    grid : GridSpec
        The map; its box and fixed coordinates are kept, its resolution sets the aspect.
    quantities : sequence of str
        Scalar map quantities (default: condition number, anisotropic and isotropic force).
    resolutions : sequence of int
        Points on the longest axis of each rung (see the module notes); at least two unless
        ``reference_resolution`` is given.
    reference_resolution : int, optional
        Run the reference at this rung instead of the finest of ``resolutions``; it must be
        finer than every rung.
    exact_rtol : float or None
        Locate the global min and max of each quantity by ``refine_global_minimum`` /
        ``refine_global_maximum`` to ``exact_rtol * |reference figure|`` (None: skip). A
        figure already infinite on the reference grid is exact as it stands.
    exact_budget : int
        ``max_evaluations`` of each of those refinements.
    coarse_resolution : int
        Their coarse grid (points on the longest axis).
    progress : callable, optional
        Called with a short message before each step (for a command line's stderr).

    Memory: each map is reduced to its statistics and dropped before the next rung runs.
    """
    names = _check_scalar_quantities(mechanism, quantities)
    if isinstance(resolutions, (int, np.integer)):
        resolutions = (resolutions,)
    try:
        ladder = sorted({int(n) for n in resolutions})
    except (TypeError, ValueError):
        raise ValueError(f"resolutions must be integers (points on the longest axis), got {resolutions!r}") from None
    if not ladder:
        raise ValueError("resolutions needs at least one rung, got none")
    if reference_resolution is None and len(ladder) < 2:
        raise ValueError(f"resolutions needs at least two rungs (the finest is the reference), got {ladder!r}")
    for n in ladder:
        ladder_resolution(grid, n)
    if reference_resolution is not None:
        ladder_resolution(grid, reference_resolution)
        if reference_resolution <= ladder[-1]:
            raise ValueError(f"reference_resolution must exceed every rung ({ladder[-1]}), got {reference_resolution}")
    if exact_rtol is not None:
        exact_rtol = positive_finite("exact_rtol", exact_rtol)

    raw: list[tuple[tuple[int, ...], int, int, float, dict]] = []
    for n in ladder + ([int(reference_resolution)] if reference_resolution is not None else []):
        res = ladder_resolution(grid, n)
        if progress is not None:
            progress(f"map {_resolution_label(res)}")
        # Statistics only, streamed: memory does not grow with the rung's resolution.
        wmap = compute_map(mechanism, grid.with_resolution(res), names, keep=False)
        raw.append((res, math.prod(res), wmap.feasible_points, float(wmap.seconds),
                    {q: {f: getattr(wmap.stats[q], f) for f in FIGURES} for q in names}))
        del wmap
    ref_figs = raw[-1][4]

    exact: dict[str, dict[str, ExactFigure]] = {}
    if exact_rtol is not None:
        rungs = [(res, figs) for res, _, _, _, figs in raw]
        for q in names:
            exact[q] = {}
            for f, refine in (("min", refine_global_minimum), ("max", refine_global_maximum)):
                value = ref_figs[q][f]
                if math.isinf(value):
                    exact[q][f] = ExactFigure(f, value, "attained", 0.0,
                                              "(unbounded: the mechanism's singularity analysis puts a singularity "
                                              "in the feasible set's closure)", None)
                    continue
                if not math.isfinite(value):
                    continue   # nan: nothing feasible
                if progress is not None:
                    progress(f"refine {f} {q}")
                tol = exact_rtol * max(abs(value), np.finfo(float).tiny)
                r = refine(mechanism, grid, q, tol=tol, coarse_resolution=coarse_resolution,
                           max_evaluations=exact_budget)
                exact[q][f] = _exact_figure(f, r, rungs, q)

    rows = []
    for i, (res, points, feas, sec, figs) in enumerate(raw):
        abs_e: dict[str, dict[str, float]] = {}
        rel_e: dict[str, dict[str, float]] = {}
        ex_e: dict[str, dict[str, float]] = {}
        for q in names:
            abs_e[q], rel_e[q], ex_e[q] = {}, {}, {}
            for f in FIGURES:
                abs_e[q][f], rel_e[q][f] = _error(figs[q][f], ref_figs[q][f])
            for f, e in exact.get(q, {}).items():
                if e.usable:
                    ex_e[q][f] = 0.0 if figs[q][f] == e.value else _error(figs[q][f], e.value)[0]
        rows.append(ConvergenceRow(res, points, feas, sec, figs, abs_e, rel_e, ex_e, is_reference=i == len(raw) - 1))
    reference = rows[-1]
    if reference_resolution is not None:
        rows = rows[:-1]
    rungs_only = [r for r in rows if not r.is_reference]
    rates = {q: {f: _fit_rate([max(r.resolution) for r in rungs_only], [r.abs_errors[q][f] for r in rungs_only])
                 for f in FIGURES} for q in names}
    everything = list(rows) + ([reference] if reference_resolution is not None else [])
    exact_rates = {q: {f: _fit_rate([max(r.resolution) for r in everything],
                                    [r.exact_errors[q].get(f, math.nan) for r in everything])
                       for f, e in exact.get(q, {}).items() if e.usable} for q in names}
    units = {q: QUANTITIES[q].unit for q in names}
    return ConvergenceStudy(grid=grid, quantities=names, rows=tuple(rows), reference=reference, exact=exact,
                            rates=rates, exact_rates=exact_rates, units=units)


# -- refinement against the uniform grid ----------------------------------------------------

@dataclass(frozen=True)
class UniformMatch:
    """The coarsest rung from which every finer rung is within ``tol`` of ``exact``.

    ``lucky`` lists coarser rungs that are within ``tol`` too but are followed by a finer
    rung that is not (a node happened to fall near the extreme). When no rung qualifies,
    ``extrapolated`` is True and ``resolution``/``points``/``seconds`` are an estimate from
    the finest rung with ``error ~ n^-rate``: ``rate`` is fitted to the rows' errors against
    ``exact`` (clamped to [0.25, 2]; 1 when it cannot be fitted), time scales with points.
    """

    quantity: str
    figure: str
    tol: float
    exact: float
    resolution: tuple[int, ...] | None
    points: int | None
    seconds: float | None
    error: float | None
    extrapolated: bool
    lucky: tuple[tuple[int, ...], ...] = ()
    finest_error: float = math.nan
    rate: float = math.nan

    def to_dict(self) -> dict:
        return {"quantity": self.quantity, "figure": self.figure, "tol": self.tol,
                "exact": _finite_or_none(self.exact),
                "resolution": list(self.resolution) if self.resolution is not None else None,
                "points": self.points, "seconds": self.seconds, "error": _finite_or_none(self.error),
                "extrapolated": self.extrapolated, "lucky": [list(r) for r in self.lucky],
                "finest_error": _finite_or_none(self.finest_error), "rate": _finite_or_none(self.rate)}


def uniform_grid_for(study: ConvergenceStudy, quantity: str, *, exact: float, tol: float,
                     figure: str = "min") -> UniformMatch:
    """The uniform rung of ``study`` that reaches ``|figure - exact| <= tol`` for good.

    Every rung counts, the reference included (rows sorted by points). The cost of a rung is
    its point count (``compute_map`` evaluates every grid point) and its ``seconds``.
    """
    tol = positive_finite("tol", tol)
    if quantity not in study.quantities:
        raise ValueError(f"quantity {quantity!r} is not in the study; it has {', '.join(study.quantities)}")
    if figure not in FIGURES:
        raise ValueError(f"figure must be one of {', '.join(FIGURES)}, got {figure!r}")
    rows = list(study.rows) + ([] if study.reference in study.rows else [study.reference])
    rows.sort(key=lambda r: r.points)
    errs = [abs(r.figures[quantity][figure] - exact) if math.isfinite(r.figures[quantity][figure]) else math.inf
            for r in rows]
    ok = [e <= tol for e in errs]
    first = None
    for i in range(len(rows) - 1, -1, -1):
        if not ok[i]:
            break
        first = i
    if first is not None:
        r = rows[first]
        lucky = tuple(rows[i].resolution for i in range(first) if ok[i])
        return UniformMatch(quantity, figure, tol, exact, r.resolution, r.points, r.seconds, errs[first], False,
                            lucky, finest_error=errs[-1])
    lucky = tuple(rows[i].resolution for i in range(len(rows)) if ok[i])
    finest = rows[-1]
    e = errs[-1]
    if not (math.isfinite(e) and e > 0.0):
        return UniformMatch(quantity, figure, tol, exact, None, None, None, None, True, lucky, finest_error=e)
    rate = _fit_rate([max(r.resolution) for r in rows], errs)
    rate = 1.0 if not math.isfinite(rate) else min(2.0, max(0.25, rate))
    factor = (e / tol) ** (1.0 / rate)
    res = tuple(max(2, int(math.ceil(n * factor))) for n in finest.resolution)
    points = int(math.prod(res))
    seconds = finest.seconds * points / finest.points
    return UniformMatch(quantity, figure, tol, exact, res, points, seconds, tol, True, lucky,
                        finest_error=e, rate=rate)
