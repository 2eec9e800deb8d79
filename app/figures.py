"""Publication figures of workspace maps, drawn with matplotlib off-screen.

Figures are built on ``matplotlib.figure.Figure`` with an Agg canvas, never through
``pyplot``: no global backend switch, no display needed, no figure registry to leak, and
the desktop app may use its own matplotlib backend alongside. Only app code imports this
module; the compute layers stay free of matplotlib.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from matplotlib import colors
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from metrics.quantities import QUANTITIES
from metrics.workspace import WorkspaceMap

from .export import FIGURE_SUFFIXES, atomic_write, check_suffix

#: Colour maps: sequential for magnitudes, qualitative for classes.
SEQUENTIAL_CMAP = "viridis"
CATEGORICAL_CMAP = "tab10"
#: Colour of singular points (condition number or anisotropic force ``inf``) inside the workspace.
SINGULAR_COLOUR = "#d62728"
#: Singularity class names of the five-bar, in ``kinematics.Singularity`` order.
SINGULARITY_NAMES = ("none", "inverse", "direct", "combined")


def _title_of(preset_or_title) -> str:
    """A preset's display name, or the string itself."""
    return preset_or_title if isinstance(preset_or_title, str) else getattr(preset_or_title, "name", str(preset_or_title))


def _category_names(quantity: str, preset_or_title) -> tuple[str, ...]:
    """Tick labels of a categorical quantity: actuator names for the bottleneck, classes for singularity."""
    if quantity == "singularity":
        return SINGULARITY_NAMES
    mechanism = getattr(preset_or_title, "mechanism", None)
    if mechanism is not None:
        return tuple(mechanism.joint_names)
    return ()


def _figure_size(extent: tuple[float, float, float, float]) -> tuple[float, float]:
    """Inches for a map of this extent: the plot keeps the data's aspect, plus room for the colour bar."""
    width_mm, height_mm = extent[1] - extent[0], extent[3] - extent[2]
    aspect = height_mm / width_mm
    plot_w = 5.5 if aspect <= 1.2 else max(3.0, 6.0 / aspect)
    plot_h = plot_w * aspect
    return plot_w + 2.0, max(3.2, plot_h + 1.4)


def map_figure(wmap: WorkspaceMap, quantity: str, preset_or_title, *, dpi: int = 150) -> Figure:
    """A heat map of one quantity over a 2D workspace slice.

    Parameters
    ----------
    wmap : WorkspaceMap
        A 2D map (``len(wmap.grid.axes) == 2``) that holds ``quantity``.
    quantity : str
        A scalar quantity of ``metrics.quantities.QUANTITIES``.
    preset_or_title : resources.Preset or str
        A preset gives the title and the actuator names (bottleneck ticks); a string is the
        title.
    dpi : int
        Resolution of raster output.

    Returns
    -------
    matplotlib.figure.Figure
        With an Agg canvas: axes in mm, equal aspect, infeasible points blank, a colour bar
        in the quantity's unit; the condition number on a log scale; categorical quantities
        with one colour per class and labelled ticks; the global minimum and maximum marked.
    """
    if len(wmap.grid.axes) != 2:
        raise ValueError(f"wmap must be a 2D slice for a heat map, got axes {wmap.grid.axes!r}")
    if quantity not in wmap.values:
        raise ValueError(f"quantity {quantity!r} is not in this map; it holds {', '.join(wmap.values)}")
    node = QUANTITIES[quantity]
    values = np.asarray(wmap.values[quantity])
    if values.shape != tuple(wmap.grid.resolution):
        raise ValueError(f"quantity {quantity!r} is not a per-point scalar (shape {values.shape})")

    (x_mm, y_mm) = [c * 1e3 for c in wmap.grid.coordinates()]
    dx, dy = x_mm[1] - x_mm[0], y_mm[1] - y_mm[0]
    # Cell edges half a step beyond the outer samples, so each sample is a cell centre.
    extent = (x_mm[0] - dx / 2, x_mm[-1] + dx / 2, y_mm[0] - dy / 2, y_mm[-1] + dy / 2)

    fig = Figure(figsize=_figure_size(extent), dpi=dpi, layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    if node.categorical:
        _draw_categorical(fig, ax, values, wmap.feasible, extent, quantity, preset_or_title)
    else:
        _draw_continuous(fig, ax, values, wmap.feasible, extent, quantity)
        _mark_extremes(ax, wmap, quantity)
    ax.set_aspect("equal")
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_xlabel(f"{wmap.grid.axes[0]} (mm)")
    ax.set_ylabel(f"{wmap.grid.axes[1]} (mm)")
    fixed = ", ".join(f"{n} = {v * 1e3:g} mm" for n, v in wmap.grid.fixed)
    nx, ny = wmap.grid.resolution
    subtitle = f"{nx} x {ny} grid, {wmap.feasible_points} feasible points" + (f"; {fixed}" if fixed else "")
    ax.set_title(f"{_title_of(preset_or_title)}: {node.label.lower()}\n{subtitle}", fontsize=10)
    return fig


def _draw_continuous(fig, ax, values, feasible, extent, quantity) -> None:
    """Sequential colours; log scale for the condition number; ``inf`` in a colour of its own."""
    node = QUANTITIES[quantity]
    shown = feasible & np.isfinite(values)
    singular = feasible & np.isposinf(values)
    cmap = _cmap(SEQUENTIAL_CMAP).copy()
    cmap.set_bad(alpha=0.0)          # masked (infeasible) cells stay blank
    finite = values[shown]
    lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    if quantity == "condition_number":
        # The condition number spans decades near a singularity and is >= 1 everywhere.
        norm = colors.LogNorm(vmin=max(lo, 1.0), vmax=max(hi, lo * 1.0001, 1.0001))
    else:
        norm = colors.Normalize(vmin=lo, vmax=hi if hi > lo else lo + 1.0)
    data = np.ma.masked_array(values, mask=~shown)
    image = ax.imshow(data.T, origin="lower", extent=extent, cmap=cmap, norm=norm,
                      interpolation="nearest", aspect="equal")
    label = node.label + (f" ({node.unit})" if node.unit else "")
    bar = fig.colorbar(image, ax=ax, shrink=0.9)
    bar.set_label(label)
    if np.any(singular):
        # Singular points are feasible but unbounded: draw them on top so they are not lost.
        ax.imshow(np.ma.masked_array(np.ones_like(values), mask=~singular).T, origin="lower", extent=extent,
                  cmap=colors.ListedColormap([SINGULAR_COLOUR]), interpolation="nearest", aspect="equal")
        ax.plot([], [], "s", color=SINGULAR_COLOUR, label=f"singular ({np.count_nonzero(singular)} pts)")


def _draw_categorical(fig, ax, values, feasible, extent, quantity, preset_or_title) -> None:
    """One colour per class (bottleneck actuator, singularity class), ticks labelled by name."""
    names = _category_names(quantity, preset_or_title)
    k = max(len(names), int(values[feasible].max()) + 1 if np.any(feasible) else 1)
    names = tuple(names) + tuple(str(i) for i in range(len(names), k))
    cmap = colors.ListedColormap([_cmap(CATEGORICAL_CMAP)(i % 10) for i in range(k)])
    cmap.set_bad(alpha=0.0)
    norm = colors.BoundaryNorm(np.arange(-0.5, k), k)
    data = np.ma.masked_array(values, mask=~feasible)
    image = ax.imshow(data.T, origin="lower", extent=extent, cmap=cmap, norm=norm,
                      interpolation="nearest", aspect="equal")
    bar = fig.colorbar(image, ax=ax, shrink=0.9, ticks=np.arange(k))
    bar.ax.set_yticklabels(names)
    bar.set_label(QUANTITIES[quantity].label)


def _mark_extremes(ax, wmap: WorkspaceMap, quantity: str) -> None:
    """Mark where the global minimum and maximum are, with their values in the legend."""
    stats = wmap.stats.get(quantity)
    node = QUANTITIES[quantity]
    if stats is None or stats.count == 0:
        return
    # argmin/argmax are task points in m; the slice shows the two grid axes of them.
    ix, iy = _axis_columns(wmap)
    unit = f" {node.unit}" if node.unit else ""
    for label, point, value, marker in (("min", stats.argmin, stats.min, "v"), ("max", stats.argmax, stats.max, "^")):
        px, py = point[ix] * 1e3, point[iy] * 1e3
        ax.plot(px, py, marker, markersize=9, markerfacecolor="white", markeredgecolor="black",
                label=f"{label} {value:.4g}{unit} at ({px:.1f}, {py:.1f}) mm")
    ax.legend(loc="upper left", fontsize=8, framealpha=0.85)


def _axis_columns(wmap: WorkspaceMap) -> tuple[int, int]:
    """Which task coordinates of ``wmap.points`` the grid's two axes are.

    ``points[..., j]`` varies along grid dimension d exactly when coordinate j is axis d.
    """
    columns = []
    for d in range(2):
        moving = [j for j in range(wmap.points.shape[-1])
                  if np.any(np.take(wmap.points[..., j], 0, axis=d) != np.take(wmap.points[..., j], -1, axis=d))]
        columns.append(moving[0])
    return columns[0], columns[1]


def _cmap(name: str):
    from matplotlib import colormaps
    return colormaps[name]


def save_figure(fig: Figure, path: str | os.PathLike, *, name: str = "path") -> Path:
    """Write ``fig`` as PNG, SVG or PDF (by suffix) through ``atomic_write``."""
    target = check_suffix(path, FIGURE_SUFFIXES, name)
    fmt = target.suffix.lower().lstrip(".")
    return atomic_write(target, lambda tmp: fig.savefig(tmp, format=fmt), name=name)
