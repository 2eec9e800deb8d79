"""What a map panel says besides its colours, as plain data: title, extremes, singular points,
cut edges and a difference's outline.

The app's painted map (``app.logic.map_picture``) and the exported matplotlib figures
(``app.plots.figures``) both take these decisions from here, so both show the same thing.
No matplotlib (``contourpy``, matplotlib's own contouring library, traces the outlines).
"""
from __future__ import annotations

import numpy as np

from app.logic.figure_digits import format_with_error, shown_error, unresolved_note
from kinematics.base import task_display_units
from metrics.quantities import QUANTITIES
from metrics.workspace import WorkspaceMap

#: Colour of singular points (condition number or anisotropic force ``inf``) inside the workspace.
SINGULAR_COLOUR = "#d62728"


#: Up to this many singular points are drawn as markers; more are drawn as cells.
MAX_SINGULAR_MARKERS = 2000


def title_of(preset_or_title) -> str:
    """A preset's display name, or the string itself."""
    if isinstance(preset_or_title, str):
        return preset_or_title
    return getattr(preset_or_title, "name", str(preset_or_title))


def quantity_label(wmap: WorkspaceMap, quantity: str, *, lower: bool = False) -> str:
    """The quantity's label, naming the task scaling of a condition number where J mixes m and rad."""
    label = QUANTITIES[quantity].label.lower() if lower else QUANTITIES[quantity].label
    scaling = wmap.condition_number_scaling
    if scaling is not None and quantity in ("condition_number", "inverse_condition_number"):
        label += f" (moments scaled by L = {scaling['length_m'] * 1e3:.4g} mm)"
    return label


def grid_extent(grid) -> tuple[float, float, float, float]:
    """``_extent`` of a 2D ``GridSpec``: its cell edges in mm."""
    (x_mm, y_mm) = [c * 1e3 for c in grid.coordinates()]
    dx, dy = x_mm[1] - x_mm[0], y_mm[1] - y_mm[0]
    return (x_mm[0] - dx / 2, x_mm[-1] + dx / 2, y_mm[0] - dy / 2, y_mm[-1] + dy / 2)


def map_title(wmap: WorkspaceMap, quantity: str, preset_or_title, *, title: str | None = None,
              narrow: bool = False) -> str:
    """A map panel's title: the device (or ``title``), the quantity, the grid and its feasible points,
    and the slice's fixed coordinates (on a line of their own when ``narrow``)."""
    fixed = ", ".join(coordinate_text(preset_or_title, n, v) for n, v in wmap.grid.fixed)
    nx, ny = wmap.grid.resolution
    subtitle = f"{nx} x {ny} grid, {wmap.feasible_points} feasible points" + (
        ("\n" if narrow else "; ") + fixed if fixed else "")
    head = f"{title}: " if title else f"{title_of(preset_or_title)}: "
    return f"{head}{quantity_label(wmap, quantity, lower=True)}\n{subtitle}"


def unbounded_legend(count: int) -> str:
    """The legend of the map's points where its quantity is infinite (a singularity of the kind
    that makes this quantity unbounded; the statistics count every singular point, which may be
    more: the five-bar's isotropic force is finite where one leg is stretched).

    >>> unbounded_legend(1), unbounded_legend(29)
    ('unbounded here (1 point)', 'unbounded here (29 points)')
    """
    return f"unbounded here ({count} point{'' if count == 1 else 's'})"


#: Where feasible samples reach the map's edge: the workspace may go on past the grid, so that
#: edge is no workspace boundary (and an extreme on it may not be the workspace's). A dashed line.
CUT_EDGE_LABEL = "feasible up to the map's edge: the workspace may go on"


CUT_EDGE_STYLE = {"color": "#e6550d", "linewidth": 2.0, "linestyle": (0, (3, 2))}   # orange: not a viridis colour


def cut_edges(wmap: WorkspaceMap) -> list[tuple[float, float, float, float]]:
    """The stretches of the map's edge that feasible samples reach, ``(x0, x1, y0, y1)`` in mm each.

    Each run of feasible samples along one of the grid's four border rows gives a stretch of
    the cells' outer edge (``grid_extent``) from its first sample's cell to its last's.

    Examples
    --------
    >>> from metrics.workspace import GridSpec
    >>> grid = GridSpec(axes=("x", "y"), lower=(0.0, 0.0), upper=(0.003, 0.002), resolution=(4, 3))
    >>> ok = np.array([[1, 1, 0], [1, 0, 0], [0, 0, 0], [0, 0, 1]], bool)
    >>> class Map:
    ...     pass
    >>> m = Map(); m.grid, m.feasible = grid, ok
    >>> cut_edges(m)
    [(-0.5, 1.5, -0.5, -0.5), (2.5, 3.5, 2.5, 2.5), (-0.5, -0.5, -0.5, 1.5), (3.5, 3.5, 1.5, 2.5)]
    """
    feasible = wmap.feasible
    if feasible is None or feasible.ndim != 2 or min(feasible.shape) < 2:
        return []
    x0, x1, y0, y1 = grid_extent(wmap.grid)
    nx, ny = feasible.shape
    dx, dy = (x1 - x0) / nx, (y1 - y0) / ny
    out = []
    for row, along, edge in ((feasible[:, 0], "x", y0), (feasible[:, -1], "x", y1),
                             (feasible[0, :], "y", x0), (feasible[-1, :], "y", x1)):
        flags = np.concatenate([[False], row, [False]]).astype(np.int8)
        starts, ends = np.flatnonzero(np.diff(flags) == 1), np.flatnonzero(np.diff(flags) == -1)
        for a, b in zip(starts, ends):         # samples a .. b - 1
            if along == "x":
                out.append((x0 + a * dx, x0 + b * dx, edge, edge))
            else:
                out.append((edge, edge, y0 + a * dy, y0 + b * dy))
    return [tuple(float(v) for v in seg) for seg in out]


def on_cut_edge(wmap: WorkspaceMap, point_mm: tuple[float, float]) -> bool:
    """Whether a sample at ``point_mm`` (its two map coordinates, mm) is a feasible one on the
    map's border (``cut_edges``): an extreme there may be the grid's, not the workspace's."""
    feasible = wmap.feasible
    if feasible is None or feasible.ndim != 2:
        return False
    coords = [c * 1e3 for c in wmap.grid.coordinates()]
    i, j = (int(np.argmin(np.abs(c - p))) for c, p in zip(coords, point_mm))
    border = i in (0, feasible.shape[0] - 1) or j in (0, feasible.shape[1] - 1)
    return bool(border and feasible[i, j])


#: The compared region's edge on a difference map: a thin grey line.
OUTLINE_COLOUR, OUTLINE_WIDTH = "#737373", 0.8


def region_outline(wmap: WorkspaceMap, region: np.ndarray) -> list[np.ndarray]:
    """The edge of ``region`` (n0, n1 bool: the samples a difference compares) as polylines,
    each (k, 2) in mm: its 0/1 indicator's one-half contour through the sample points."""
    if not region.any() or region.all() or min(region.shape) < 2:
        return []
    import contourpy  # (matplotlib's own contouring, without an axes: the app paints it too)

    x_mm, y_mm = (c * 1e3 for c in wmap.grid.coordinates())
    lines = contourpy.contour_generator(x_mm, y_mm, region.T.astype(float)).lines(0.5)
    return [np.asarray(line, float) for line in lines if len(line) > 1]


#: An extreme taken by at least this share of a map's regular samples is a plateau: the legend
#: says how much of the map reaches it, not one point (the PHANToM Premium's isotropic force is
#: at its maximum on 73 % of its map, which "at (-78.0, 352.0) mm" hid).
PLATEAU_SHARE = 0.01


def _plateau_share(wmap: WorkspaceMap, quantity: str, value: float) -> float:
    """The share of the map's regular samples equal to ``value`` (to rounding); 0 for a streamed map."""
    values = wmap.values.get(quantity)
    if values is None or wmap.feasible is None or not np.isfinite(value):
        return 0.0
    regular = (wmap.feasible if wmap.singular is None else wmap.feasible & ~wmap.singular).ravel()
    flat = np.asarray(values).ravel()
    # A look at every 64th sample first: a map redrawn on the GUI thread (10^6 samples) pays for
    # the exact count only where a plateau may be.
    step = 64 if flat.size > 64 * 1000 else 1
    near = np.abs(flat[::step] - value) <= 1e-9 * abs(value)
    if np.count_nonzero(near & regular[::step]) < 0.5 * PLATEAU_SHARE * max(1, np.count_nonzero(regular[::step])):
        return 0.0
    n = np.count_nonzero(regular)
    return float(np.count_nonzero((np.abs(flat - value) <= 1e-9 * abs(value)) & regular) / n) if n else 0.0


def extreme_marks(wmap: WorkspaceMap, quantity: str) -> list[tuple[str, float, float, str]]:
    """Where the global minimum and maximum of ``quantity`` are: ``(marker, x mm, y mm, text)`` each.

    ``marker`` is ``"v"`` (minimum) or ``"^"`` (maximum); ``text`` gives the value with its
    unit, with the digits its resolution error supports (as the statistics panel writes it:
    ``figure_digits.format_with_error``), and where: a point, or the share of the map that
    reaches it when that is at least ``PLATEAU_SHARE`` (the marker is then one point of it); or
    says the maximum is unbounded. Empty for a map with no feasible point.
    """
    stats = wmap.stats.get(quantity)
    if stats is None or not stats.count:
        return []
    node = QUANTITIES[quantity]
    # argmin/argmax are task points in m; the slice shows the two grid axes of them.
    ix, iy = (wmap.task_names.index(axis) for axis in wmap.grid.axes)
    unit = f" {node.unit}" if node.unit else ""
    errors = wmap.errors.get(quantity, {})
    out = []
    for label, point, value, marker in (("min", stats.argmin, stats.min, "v"), ("max", stats.argmax, stats.max, "^")):
        px, py = point[ix] * 1e3, point[iy] * 1e3
        digits = format_with_error(value, shown_error(value, errors.get(label)))[0]
        share = _plateau_share(wmap, quantity, value)
        where = f"on {100 * share:.0f} % of the map" if share >= PLATEAU_SHARE else f"at ({px:.1f}, {py:.1f}) mm"
        if share < PLATEAU_SHARE and on_cut_edge(wmap, (px, py)):
            where += ", on the map's edge"
        error = shown_error(value, errors.get(label))
        note = unresolved_note(value, error, wmap.error_orders.get(quantity, {}).get(label), wmap.grid.resolution)
        note = f" ({note})" if note else ""
        text = (f"max unbounded near ({px:.1f}, {py:.1f}) mm" if label == "max" and stats.unbounded
                else f"{label} {digits}{unit}{note} {where}")
        out.append((marker, px, py, text))
    return out


def coordinate_text(preset_or_title, name: str, value: float) -> str:
    """A fixed task coordinate in display units: mm, or deg for a pen's orientation."""
    mechanism = getattr(preset_or_title, "mechanism", None)
    units = dict(zip(mechanism.task_names, task_display_units(mechanism))) if mechanism is not None else {}
    if units.get(name) == "deg":
        return f"{name} = {np.degrees(value):g} deg"
    return f"{name} = {value * 1e3:g} mm"
