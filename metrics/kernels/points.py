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


@jit(allocates=True)
def fill(start, out, resolution, axis_of, lower, upper, step, fixed):
    """``out[i]`` (k, m) is the point of flat grid index ``start + i`` (C order, 2 or 3 axes).

    The start is unravelled once and the index then counted up with carries: no division per
    point (a division per axis and point made this loop cost as much as numpy's).
    """
    dims = resolution.shape[0]
    coord = np.zeros(3, np.int64)
    rest = start
    for d in range(dims - 1, -1, -1):
        coord[d] = rest % resolution[d]
        rest //= resolution[d]
    for i in range(out.shape[0]):
        for j in range(out.shape[1]):
            k = axis_of[j]
            if k < 0:
                out[i, j] = fixed[j]
                continue
            c = coord[k]
            n = resolution[k]
            if c == n - 1:
                out[i, j] = upper[j]
            elif step[j] != 0.0:
                out[i, j] = np.float64(c) * step[j] + lower[j]
            else:
                out[i, j] = np.float64(c) / (n - 1) * (upper[j] - lower[j]) + lower[j]
        d = dims - 1
        coord[d] += 1
        while d > 0 and coord[d] == resolution[d]:
            coord[d] = 0
            d -= 1
            coord[d] += 1
