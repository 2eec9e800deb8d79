"""The planes of a 3D box map: which one (``--plane z=110``, the app's plane controls), and the plane as a 2D map.

A volume device's map (a delta's) is a box; a heat map, a comparison or an exported figure
shows one plane of it. Both clients use these: the command line's ``--plane`` and the app's
map view and exports (which show the plane on screen), so the plane a figure is on is always
a grid plane, named in its title. Plain Python and numpy, no Qt and no matplotlib.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from kinematics.base import task_display_units
from kinematics.grid import GridSpec
from metrics.quantities import QUANTITIES

if TYPE_CHECKING:
    from metrics.workspace import WorkspaceMap

#: Relative distance (of a cell) below which a typed plane counts as on a grid plane: the
#: rounding of a position typed to the 3 decimals the titles print.
ON_PLANE = 1e-6


def is_volume(grid: GridSpec) -> bool:
    """Whether a map grid is a 3D box (three varied coordinates)."""
    return len(grid.axes) == 3


def slice_index(grid: GridSpec, axis: str, value: float) -> int:
    """Index of the grid plane along ``axis`` nearest ``value`` (m), clipped into the grid.

    Examples
    --------
    >>> g = GridSpec(("x", "y", "z"), (0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (3, 3, 5))
    >>> slice_index(g, "z", 0.6), slice_index(g, "z", 9.0), slice_index(g, "x", -1.0)
    (2, 4, 0)
    """
    if axis not in grid.axes:
        raise ValueError(f"axis must be one of the grid's axes {grid.axes!r}, got {axis!r}")
    k = grid.axes.index(axis)
    coords = grid.coordinates()[k]
    return int(np.argmin(np.abs(coords - float(value))))


def plane_value(grid: GridSpec, axis: str, value: float) -> float:
    """The position (m) of the grid plane along ``axis`` nearest ``value``: where a plane is drawn.

    >>> g = GridSpec(("x", "y", "z"), (0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (3, 3, 5))
    >>> plane_value(g, "z", 0.6)
    0.5
    """
    return float(grid.coordinates()[grid.axes.index(axis)][slice_index(grid, axis, value)])


def slice_grid(grid: GridSpec, axis: str, value: float) -> GridSpec:
    """The 2D grid of the plane of ``grid`` along ``axis`` nearest ``value`` (its exact position fixed)."""
    k = grid.axes.index(axis)
    at = plane_value(grid, axis, value)
    keep = [i for i in range(3) if i != k]
    return GridSpec(tuple(grid.axes[i] for i in keep), tuple(grid.lower[i] for i in keep),
                    tuple(grid.upper[i] for i in keep), tuple(grid.resolution[i] for i in keep),
                    fixed=tuple(grid.fixed) + ((axis, at),))


def volume_slice(wmap: WorkspaceMap, axis: str, value: float, extra: dict | None = None,
                 stats_of: tuple[str, ...] | None = None) -> WorkspaceMap:
    """The plane of a 3D box map along ``axis`` nearest ``value`` (m), as a 2D map.

    Its statistics are of the plane (the extremes a heat map of it marks); the volume's own
    stay with ``wmap``. ``extra`` maps names to further arrays of the volume's shape (e.g. a
    difference of two maps) that are sliced along and returned in ``values``.

    Parameters
    ----------
    wmap : WorkspaceMap
        A kept map on a 3D grid.
    axis : str
        One of ``wmap.grid.axes``.
    value : float
        Position of the plane along ``axis``, m (the nearest grid plane is taken).
    extra : dict of str to ndarray, shape ``wmap.grid.resolution``, optional
    stats_of : tuple of str, optional
        The quantities whose plane statistics are wanted (default: every scalar one).

    Returns
    -------
    WorkspaceMap
        On ``slice_grid(wmap.grid, axis, value)``: arrays of shape (n_a, n_b).
    """
    grid = wmap.grid
    if not is_volume(grid):
        raise ValueError(f"wmap must be a 3D box map, got axes {grid.axes!r}")
    at = slice_index(grid, axis, value)         # (checks the axis)
    k = grid.axes.index(axis)
    index = [slice(None)] * 3
    index[k] = at
    index = tuple(index)
    plane = slice_grid(grid, axis, value)
    feasible = wmap.feasible[index]
    singular = wmap.singular[index] if wmap.singular is not None else None
    inverse = wmap.inverse_singular[index] if wmap.inverse_singular is not None else None
    values = {name: np.asarray(v)[index] for name, v in wmap.values.items()
              if np.shape(v) == tuple(grid.resolution)}
    values.update({name: np.asarray(v)[index] for name, v in (extra or {}).items()})
    # Only a quantity with a finite limit at an inverse singularity takes its values there: the
    # others' are rounding noise (10^15), which a plane's statistics have no unbounded flag to hide.
    # Imported here: a pose figure, which cuts no plane, does not load the map's modules (0.05-0.1 s).
    from metrics.workspace import WorkspaceMap, statistics
    stats = {name: statistics(values[name], feasible, plane, wmap.task_names, singular,
                              inverse if name in wmap.finite_at_inverse else None)
             for name in values if name in QUANTITIES and not QUANTITIES[name].categorical
             and (stats_of is None or name in stats_of)}
    return WorkspaceMap(plane, wmap.task_names, feasible, values, stats, 0.0, computed=wmap.computed,
                        singular=singular, inverse_singular=inverse, finite_at_inverse=wmap.finite_at_inverse,
                        condition_number_scaling=wmap.condition_number_scaling, loading=wmap.loading)


def default_plane(grid: GridSpec, mechanism, pose=None) -> tuple[str, float] | tuple[None, None]:
    """The plane a 3D box map is first shown through: its last axis at the pose (else mid-range), m.

    The app's map view opens on it and ``--plane`` defaults to it. ``(None, None)`` for a 2D map.
    The value is the pose's coordinate clipped into the box, not yet snapped to a grid plane.
    """
    if not is_volume(grid):
        return None, None
    axis = grid.axes[-1]
    k = grid.axes.index(axis)
    names = tuple(mechanism.task_names)
    at = pose[names.index(axis)] if pose is not None and axis in names else None
    if at is None:
        return axis, 0.5 * (grid.lower[k] + grid.upper[k])
    return axis, float(min(max(float(at), grid.lower[k]), grid.upper[k]))


def _unit(mechanism, axis: str) -> tuple[str, float]:
    """Display unit of a task coordinate and its factor from SI: ("mm", 1e3) or ("deg", 180/pi)."""
    units = dict(zip(mechanism.task_names, task_display_units(mechanism)))
    return ("deg", 180.0 / math.pi) if units.get(axis) == "deg" else ("mm", 1e3)


def parse_plane(text: str, grid: GridSpec, mechanism, *, name: str = "--plane") -> tuple[str, float]:
    """``"z=110"`` (mm; deg for an angle) as ``(axis, value in SI)``, checked against the box ``grid``.

    Raises ``ValueError`` naming ``name`` for a 2D map, a malformed text, an axis the box does
    not vary, or a position outside the box (its range is in the message). The value is the
    one typed; ``slice_grid`` snaps it to the nearest grid plane.

    Examples
    --------
    >>> from kinematics.delta import Delta
    >>> g = GridSpec(("x", "y", "z"), (-0.09, -0.09, 0.03), (0.09, 0.09, 0.19), (41, 41, 37))
    >>> parse_plane("z=110", g, Delta())
    ('z', 0.11)
    """
    if not is_volume(grid):
        raise ValueError(f"{name} applies to a 3D box map; this map is a 2D slice over "
                         f"{', '.join(grid.axes)} (no plane to choose)")
    axis, sep, number = (text or "").partition("=")
    axis = axis.strip()
    try:
        shown = float(number)
    except ValueError:
        shown = math.nan
    example = f"{grid.axes[-1]}={_unit(mechanism, grid.axes[-1])[1] * 0.5 * (grid.lower[-1] + grid.upper[-1]):g}"
    if not sep or not math.isfinite(shown):
        raise ValueError(f"{name} needs AXIS=POSITION with AXIS one of {', '.join(grid.axes)} and the position "
                         f"in mm (e.g. {name} {example}), got {text!r}")
    if axis not in grid.axes:
        raise ValueError(f"{name}: axis {axis!r} is not one of the box's axes {', '.join(grid.axes)} "
                         f"(e.g. {name} {example})")
    k = grid.axes.index(axis)
    unit, factor = _unit(mechanism, axis)
    lo, hi = grid.lower[k] * factor, grid.upper[k] * factor
    # A half-ulp of slack at the ends: "z=190" is the top plane even when 0.19 * 1e3 rounds above 190.
    slack = 1e-9 * max(abs(lo), abs(hi), 1.0)
    if not lo - slack <= shown <= hi + slack:
        raise ValueError(f"{name} {text.strip()}: {axis} = {shown:g} {unit} is outside the map's box, "
                         f"{axis} from {lo:g} to {hi:g} {unit}")
    return axis, float(min(max(shown / factor, grid.lower[k]), grid.upper[k]))


def plane_text(grid: GridSpec, axis: str, value: float, mechanism, *, asked: float | None = None) -> str:
    """Where the plane nearest ``value`` (m) is, e.g. ``"plane z = 110 mm"``, saying when it was snapped
    from the position ``asked`` (m) to the nearest grid plane ("... (nearest grid plane to 112 mm)")."""
    unit, factor = _unit(mechanism, axis)
    at = plane_value(grid, axis, value)
    text = f"plane {axis} = {at * factor:.4g} {unit}"
    asked = value if asked is None else asked
    step = grid.spacing()[grid.axes.index(axis)]
    if abs(asked - at) > ON_PLANE * step:
        text += f" (nearest grid plane to {asked * factor:.4g} {unit})"
    return text
