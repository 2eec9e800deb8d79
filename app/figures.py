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
from matplotlib import colors, ticker
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from kinematics import Singularity
from metrics.quantities import QUANTITIES
from metrics.workspace import WorkspaceMap

from .export import FIGURE_SUFFIXES, atomic_write, check_suffix

#: Colour maps: sequential for magnitudes, qualitative for classes.
SEQUENTIAL_CMAP = "viridis"
CATEGORICAL_CMAP = "tab10"
#: Colour of singular points (condition number or anisotropic force ``inf``) inside the workspace.
SINGULAR_COLOUR = "#d62728"
#: Up to this many singular points are drawn as markers; more are drawn as cells.
MAX_SINGULAR_MARKERS = 2000
#: Singularity class names of the five-bar, in ``kinematics.Singularity`` order.
SINGULARITY_NAMES = tuple(s.name.lower() for s in Singularity)


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
    extent = _extent(_check_map(wmap, quantity))
    fig = Figure(figsize=_figure_size(extent), dpi=dpi, layout="compressed")
    FigureCanvasAgg(fig)
    draw_map(fig, fig.add_subplot(), wmap, quantity, preset_or_title)
    return fig


def _check_map(wmap: WorkspaceMap, quantity: str) -> WorkspaceMap:
    if len(wmap.grid.axes) != 2:
        raise ValueError(f"wmap must be a 2D slice for a heat map, got axes {wmap.grid.axes!r}")
    if quantity not in wmap.values:
        raise ValueError(f"quantity {quantity!r} is not in this map; it holds {', '.join(wmap.values)}")
    if np.shape(wmap.values[quantity]) != tuple(wmap.grid.resolution):
        raise ValueError(f"quantity {quantity!r} is not a per-point scalar (shape {np.shape(wmap.values[quantity])})")
    return wmap


def _extent(wmap: WorkspaceMap) -> tuple[float, float, float, float]:
    """Cell edges (mm) half a step beyond the outer samples, so each sample is a cell centre."""
    (x_mm, y_mm) = [c * 1e3 for c in wmap.grid.coordinates()]
    dx, dy = x_mm[1] - x_mm[0], y_mm[1] - y_mm[0]
    return (x_mm[0] - dx / 2, x_mm[-1] + dx / 2, y_mm[0] - dy / 2, y_mm[-1] + dy / 2)


def draw_map(fig, ax, wmap: WorkspaceMap, quantity: str, preset_or_title, *, values=None,
             title: str | None = None, artists=None):
    """Draw the heat map of ``quantity`` on ``ax`` (the app's map view and ``map_figure`` share it).

    ``values`` replaces the map's own array (e.g. a difference of two maps, drawn with a
    diverging scale); ``title`` is a prefix for the panel's title. ``artists`` is what an
    earlier call on the same axes returned: its colour bar is removed before redrawing.
    Returns the artists to pass next time.
    """
    _check_map(wmap, quantity)
    if artists is not None and artists.get("colorbar") is not None:
        artists["colorbar"].remove()
    ax.clear()
    node = QUANTITIES[quantity]
    extent = _extent(wmap)
    x_mm, y_mm = [c * 1e3 for c in wmap.grid.coordinates()]
    if values is not None:
        bar = _draw_difference(fig, ax, np.asarray(values, float), wmap.feasible, extent, quantity)
    elif node.categorical:
        bar = _draw_categorical(fig, ax, np.asarray(wmap.values[quantity]), wmap.feasible, extent, quantity,
                          preset_or_title)
    else:
        bar = _draw_continuous(fig, ax, np.asarray(wmap.values[quantity]), wmap.feasible, extent, quantity,
                               (x_mm, y_mm))
        _mark_extremes(ax, wmap, quantity)
    ax.set_aspect("equal")
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_xlabel(f"{wmap.grid.axes[0]} (mm)")
    ax.set_ylabel(f"{wmap.grid.axes[1]} (mm)")
    fixed = ", ".join(f"{n} = {v * 1e3:g} mm" for n, v in wmap.grid.fixed)
    nx, ny = wmap.grid.resolution
    subtitle = f"{nx} x {ny} grid, {wmap.feasible_points} feasible points" + (f"; {fixed}" if fixed else "")
    head = f"{title}: " if title else f"{_title_of(preset_or_title)}: "
    ax.set_title(f"{head}{node.label.lower()}\n{subtitle}", fontsize=10)
    return {"colorbar": bar}


def _draw_difference(fig, ax, diff, feasible, extent, quantity):
    """A difference of two maps on a diverging scale centred at zero."""
    node = QUANTITIES[quantity]
    shown = feasible & np.isfinite(diff)
    span = float(np.max(np.abs(diff[shown]))) if np.any(shown) else 1.0
    cmap = _cmap("RdBu_r").with_extremes(bad=(0.0, 0.0, 0.0, 0.0))
    image = ax.imshow(np.ma.masked_array(diff, mask=~shown).T, origin="lower", extent=extent, cmap=cmap,
                      norm=colors.Normalize(vmin=-span or -1.0, vmax=span or 1.0), interpolation="nearest",
                      aspect="equal")
    bar = fig.colorbar(image, ax=ax, shrink=0.9)
    bar.set_label(f"change of {node.label.lower()}" + (f" ({node.unit})" if node.unit else ""))
    return bar


def _draw_continuous(fig, ax, values, feasible, extent, quantity, coords_mm):
    """Sequential colours; log scale for the condition number; ``inf`` in a colour of its own."""
    node = QUANTITIES[quantity]
    shown = feasible & np.isfinite(values)
    singular = feasible & np.isposinf(values)
    cmap = _cmap(SEQUENTIAL_CMAP).with_extremes(bad=(0.0, 0.0, 0.0, 0.0))   # masked (infeasible) cells stay blank
    # The condition number spans decades near a singularity and is >= 1 everywhere.
    log = quantity == "condition_number"
    finite = values[shown]
    if log:
        finite = finite[finite > 0]
    lo, hi, capped = colour_limits(finite, log=log)
    norm = colors.LogNorm(vmin=lo, vmax=hi) if log else colors.Normalize(vmin=lo, vmax=hi)
    data = np.ma.masked_array(values, mask=~shown)
    image = ax.imshow(data.T, origin="lower", extent=extent, cmap=cmap, norm=norm,
                      interpolation="nearest", aspect="equal")
    label = node.label + (f" ({node.unit})" if node.unit else "")
    bar = fig.colorbar(image, ax=ax, shrink=0.9, extend="max" if capped else "neither")
    bar.set_label(label + (f"; colours capped at {hi:.3g}" if capped else ""))
    if log:
        _plain_log_ticks(bar, lo, hi)
    count = int(np.count_nonzero(singular))
    legend = f"singular ({count} pts)"
    if 0 < count <= MAX_SINGULAR_MARKERS:
        # Singular points are feasible but unbounded, and usually a curve one cell wide on
        # the boundary: as cells they would vanish, so they get markers (unclipped at the frame).
        i, j = np.nonzero(singular)
        ax.plot(coords_mm[0][i], coords_mm[1][j], "x", color=SINGULAR_COLOUR, markersize=5, clip_on=False,
                label=legend)
    elif count:
        ax.imshow(np.ma.masked_array(np.ones_like(values), mask=~singular).T, origin="lower", extent=extent,
                  cmap=colors.ListedColormap([SINGULAR_COLOUR]), interpolation="nearest", aspect="equal")
        ax.plot([], [], "s", color=SINGULAR_COLOUR, label=legend)
    return bar


def _plain_log_ticks(bar, lo: float, hi: float) -> None:
    """Ticks 1, 2, 5, 10, 20, ... as plain numbers: easier to read than 2 x 10^0 for a condition number."""
    decades = range(int(np.floor(np.log10(lo))), int(np.ceil(np.log10(hi))) + 1)
    # Less than a decade and a half: finer steps, or the bar would carry one or two labels.
    mantissas = (1, 2, 5) if hi / lo > 30 else (1, 1.5, 2, 3, 5, 7)
    ticks = [m * 10.0 ** k for k in decades for m in mantissas if lo <= m * 10.0 ** k <= hi]
    if len(ticks) < 2:
        ticks = [lo, hi]
    bar.set_ticks(ticks, labels=[f"{t:.3g}" for t in ticks])
    bar.ax.yaxis.set_minor_formatter(ticker.NullFormatter())


def colour_limits(finite: np.ndarray, *, log: bool = False) -> tuple[float, float, bool]:
    """Colour-scale limits ``(lo, hi, capped)`` for the finite values of a map.

    Near a singularity the condition number, the anisotropic force and (where a leg folds)
    the five-bar's isotropic force grow without bound; a handful of such points would
    squeeze the rest of the map into one colour. So the upper limit is capped at
    ``p99 + (p99 - p1)`` (percentiles, in log space for a log scale) when the maximum
    lies beyond it; the colour bar then gets an arrow and says so. The extremes marked on
    the map keep their true values.
    """
    if finite.size == 0:
        return (1.0, 10.0, False) if log else (0.0, 1.0, False)
    data = np.log10(finite) if log else finite
    lo, hi = float(data.min()), float(data.max())
    p1, p99 = np.percentile(data, [1.0, 99.0])
    limit = float(2.0 * p99 - p1)
    capped = hi > limit and limit > lo
    if capped:
        hi = limit
    if not hi > lo:      # a constant map still needs a non-empty range
        hi = lo + (0.01 if log else max(abs(lo) * 1e-3, 1e-12))
    return (10.0 ** lo, 10.0 ** hi, capped) if log else (lo, hi, capped)


def _draw_categorical(fig, ax, values, feasible, extent, quantity, preset_or_title):
    """One colour per class (bottleneck actuator, singularity class), ticks labelled by name."""
    names = _category_names(quantity, preset_or_title)
    k = max(len(names), int(values[feasible].max()) + 1 if np.any(feasible) else 1)
    names = tuple(names) + tuple(str(i) for i in range(len(names), k))
    cmap = colors.ListedColormap([_cmap(CATEGORICAL_CMAP)(i % 10) for i in range(k)]).with_extremes(
        bad=(0.0, 0.0, 0.0, 0.0))
    norm = colors.BoundaryNorm(np.arange(-0.5, k), k)
    data = np.ma.masked_array(values, mask=~feasible)
    image = ax.imshow(data.T, origin="lower", extent=extent, cmap=cmap, norm=norm,
                      interpolation="nearest", aspect="equal")
    bar = fig.colorbar(image, ax=ax, shrink=0.9, ticks=np.arange(k))
    # Counts next to the names: singular classes cover a few grid points, too few to see.
    counts = np.bincount(values[feasible].astype(np.int64), minlength=k) if np.any(feasible) else np.zeros(k, int)
    bar.ax.set_yticklabels([f"{label} ({c})" for label, c in zip(names, counts)])
    bar.set_label(QUANTITIES[quantity].label)
    return bar


def _mark_extremes(ax, wmap: WorkspaceMap, quantity: str) -> None:
    """Mark where the global minimum and maximum are, with their values in the legend."""
    stats = wmap.stats.get(quantity)
    node = QUANTITIES[quantity]
    if stats is None or stats.count == 0:
        return
    # argmin/argmax are task points in m; the slice shows the two grid axes of them.
    ix, iy = (wmap.task_names.index(axis) for axis in wmap.grid.axes)
    unit = f" {node.unit}" if node.unit else ""
    for label, point, value, marker in (("min", stats.argmin, stats.min, "v"), ("max", stats.argmax, stats.max, "^")):
        px, py = point[ix] * 1e3, point[iy] * 1e3
        ax.plot(px, py, marker, markersize=9, markerfacecolor="white", markeredgecolor="black", clip_on=False,
                label=f"{label} {value:.4g}{unit} at ({px:.1f}, {py:.1f}) mm")
    ax.legend(loc="upper left", fontsize=8, framealpha=0.85)


def _cmap(name: str):
    from matplotlib import colormaps
    return colormaps[name]


def save_figure(fig: Figure, path: str | os.PathLike, *, name: str = "path") -> Path:
    """Write ``fig`` as PNG, SVG or PDF (by suffix) through ``atomic_write``."""
    target = check_suffix(path, FIGURE_SUFFIXES, name)
    fmt = target.suffix.lower().lstrip(".")
    return atomic_write(target, lambda tmp: fig.savefig(tmp, format=fmt), name=name)
