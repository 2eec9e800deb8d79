"""A span of a grid's points, compiled: ``GridSpec.points(task_names, slice(start, stop))`` to the last bit.

``GridSpec.points`` (numpy) unravels each flat index and forms ``i * step + lo`` per axis
(``i / (n - 1) * (hi - lo) + lo`` where the step underflows to 0), with the last point set to
``hi``: ``np.linspace``'s arithmetic. Here the same operations run point by point, straight into the array
the kernel reads, with no index arrays in between.
"""
from __future__ import annotations

import numpy as np

from .jit import jit


def layout(grid, task_names) -> tuple[np.ndarray, ...]:
    """The grid as the compiled loop reads it: ``(resolution, axis_of, lower, upper, step, fixed)``.

    Parameters
    ----------
    grid : GridSpec
        The grid.
    task_names : tuple of str
        The mechanism's task coordinates, in order.

    Returns
    -------
    tuple of ndarray
        ``resolution`` (d,) int64; per task coordinate ``axis_of`` (m,) int64 (-1: fixed), and
        ``lower``, ``upper``, ``step``, ``fixed`` (m,) float64.

    Raises
    ------
    ValueError
        If a task coordinate is neither an axis nor fixed (as ``GridSpec.points`` says it).
    """
    fixed = dict(grid.fixed)
    m = len(task_names)
    axis_of = np.full(m, -1, np.int64)
    lower, upper, step, value = (np.zeros(m) for _ in range(4))
    for j, name in enumerate(task_names):
        if name in grid.axes:
            k = grid.axes.index(name)
            axis_of[j] = k
            lower[j], upper[j] = grid.lower[k], grid.upper[k]
            step[j] = (grid.upper[k] - grid.lower[k]) / (int(grid.resolution[k]) - 1)
        elif name in fixed:
            value[j] = fixed[name]
        else:
            raise ValueError(f"grid has no value for task coordinate {name!r}: add it to axes or fixed")
    return np.array([int(r) for r in grid.resolution], np.int64), axis_of, lower, upper, step, value


@jit(inline=True)
def _coordinate(c, n, lower, upper, step):
    """Point ``c`` of ``n`` from ``lower`` to ``upper``, as ``GridSpec.points`` forms it (``np.linspace``)."""
    if c == n - 1:
        return upper
    if step != 0.0:
        return np.float64(c) * step + lower
    return np.float64(c) / (n - 1) * (upper - lower) + lower


@jit(allocates=True)
def fill(start, out, resolution, axis_of, lower, upper, step, fixed):
    """``out[i]`` (k, m) is the point of flat grid index ``start + i`` (C order, 2 or 3 axes).

    The start is unravelled once; then the points go a run of the last axis at a time (up to its end or
    ``out``'s), each coordinate of the run in a loop of its own (the last axis's values, or one value), and
    the index is carried to the next run: no division and no per-point test of the coordinate's axis (a
    division per axis and point made this loop cost as much as numpy's; the per-point tests, twice this).
    """
    dims = resolution.shape[0]
    m = out.shape[1]
    coord = np.zeros(3, np.int64)
    rest = start
    for d in range(dims - 1, -1, -1):
        coord[d] = rest % resolution[d]
        rest //= resolution[d]
    last = dims - 1
    n_last = resolution[last]
    i, k = 0, out.shape[0]
    while i < k:
        first = coord[last]
        run = min(n_last - first, k - i)
        for j in range(m):
            a = axis_of[j]
            if a == last:
                for t in range(run):
                    out[i + t, j] = _coordinate(first + t, n_last, lower[j], upper[j], step[j])
            else:
                value = fixed[j] if a < 0 else _coordinate(coord[a], resolution[a], lower[j], upper[j], step[j])
                for t in range(run):
                    out[i + t, j] = value
        i += run
        coord[last] = first + run
        d = last
        while d > 0 and coord[d] == resolution[d]:
            coord[d] = 0
            d -= 1
            coord[d] += 1
