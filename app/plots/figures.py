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
from matplotlib.image import AxesImage
from matplotlib.transforms import Bbox, IdentityTransform, ScaledTranslation, TransformedBbox

from app.files.export import FIGURE_SUFFIXES, atomic_write, check_suffix
from app.logic.colour_limits import LOG_QUANTITIES, colour_limits, layers_limits, log_colours, map_colour_limits  # noqa: F401
from app.logic.display_units import display_map, relabel_axes
from app.logic.figure_digits import format_with_error, shown_error
from kinematics.base import task_display_units
from metrics.bottleneck import BOTTLENECK_SHARED, BOTTLENECK_TIE
from metrics.quantities import QUANTITIES
from metrics.workspace import WorkspaceMap

#: Colour maps: sequential for magnitudes, qualitative for classes.
SEQUENTIAL_CMAP = "viridis"
CATEGORICAL_CMAP = "tab10"
#: How far below the axes the legend of extremes starts, pt: the tick labels and the x label
#: (10 pt text each, 3.5 pt ticks and their pads) above it.
LEGEND_DROP_PT = 34.0
#: Colour bar label size, pt: a line of it fits beside the bar of a map twice as wide as tall.
BAR_LABEL_PT = 9
#: Colour of singular points (condition number or anisotropic force ``inf``) inside the workspace.
SINGULAR_COLOUR = "#d62728"
#: Up to this many singular points are drawn as markers; more are drawn as cells.
MAX_SINGULAR_MARKERS = 2000
#: Bottleneck codes that name no single actuator (``metrics.bottleneck``): tick label and colour,
#: neutral greys so that they read as "no one actuator" next to the actuators' tab10 colours.
#: ``BOTTLENECK_INFEASIBLE`` (-1) and any other negative code are drawn blank.
BOTTLENECK_CODES = {BOTTLENECK_TIE: ("tie", "#3f3f3f"), BOTTLENECK_SHARED: ("shared (redundant)", "#c7c7c7")}
#: Colours of the actuator classes: tab10 without its grey (the bottleneck codes' colours).
_CLASS_COLOURS = tuple(i for i in range(10) if i != 7)


def _title_of(preset_or_title) -> str:
    """A preset's display name, or the string itself."""
    if isinstance(preset_or_title, str):
        return preset_or_title
    return getattr(preset_or_title, "name", str(preset_or_title))


def _category_names(quantity: str, preset_or_title) -> tuple[str, ...]:
    """Tick labels of a categorical quantity: actuator names for the bottleneck, the model's
    classes for singularity (``singularity_classes``); none without a mechanism (codes by number)."""
    mechanism = getattr(preset_or_title, "mechanism", None)
    if mechanism is None:
        return ()
    return tuple(mechanism.singularity_classes if quantity == "singularity" else mechanism.joint_names)


def quantity_label(wmap: WorkspaceMap, quantity: str, *, lower: bool = False) -> str:
    """The quantity's label, naming the task scaling of a condition number where J mixes m and rad."""
    label = QUANTITIES[quantity].label.lower() if lower else QUANTITIES[quantity].label
    scaling = wmap.condition_number_scaling
    if scaling is not None and quantity in ("condition_number", "inverse_condition_number"):
        label += f" (moments scaled by L = {scaling['length_m'] * 1e3:.4g} mm)"
    return label


def _figure_size(extent: tuple[float, float, float, float]) -> tuple[float, float]:
    """Inches for a map of this extent: the plot keeps the data's aspect, plus room for the colour bar."""
    width_mm, height_mm = extent[1] - extent[0], extent[3] - extent[2]
    aspect = height_mm / width_mm
    plot_w = 5.5 if aspect <= 1.2 else max(3.0, 6.0 / aspect)
    plot_h = plot_w * aspect
    return plot_w + 2.0, max(3.2, plot_h + 1.4)


def map_figure(wmap: WorkspaceMap, quantity: str, preset_or_title, *, dpi: int = 150,
               scale: dict | None = None, note: str | None = None) -> Figure:
    """A heat map of one quantity over a 2D workspace slice (or a plane of a 3D box, ``app.logic.planes``).

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
    scale : dict, optional
        A ``colour_scale`` (in the display unit) to colour with instead of this map's own, e.g. a
        whole volume's for one of its planes (``noted_scale`` says which on the colour bar).
    note : str, optional
        A line of the title under the device's name (e.g. which grid plane a typed one snapped to).

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
    # In the display unit the app shows (app.logic.display_units: µm, deg for resolutions); the data stay SI.
    ax = fig.add_subplot()
    # The loading on a line of its own above the device, as the app's map view titles it.
    title = f"{wmap.loading.describe()}\n{_title_of(preset_or_title)}" + (f"\n{note}" if note else "")
    draw_map(fig, ax, display_map(wmap, quantity), quantity, preset_or_title, title=title, scale=scale)
    relabel_axes(ax, quantity)
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
    return grid_extent(wmap.grid)


def grid_extent(grid) -> tuple[float, float, float, float]:
    """``_extent`` of a 2D ``GridSpec``: its cell edges in mm."""
    (x_mm, y_mm) = [c * 1e3 for c in grid.coordinates()]
    dx, dy = x_mm[1] - x_mm[0], y_mm[1] - y_mm[0]
    return (x_mm[0] - dx / 2, x_mm[-1] + dx / 2, y_mm[0] - dy / 2, y_mm[-1] + dy / 2)


class NearestImage(AxesImage):
    """An ``imshow`` image whose screen pixels each show the map sample under their centre.

    That is what ``interpolation="nearest"`` draws, without matplotlib's general resampler,
    which for a 1000 x 1000 map on a few hundred pixels costs 60-80 ms per draw (masked
    float arrays, then colour mapping, at the map's resolution): here the samples under the
    pixels are picked first and only those are coloured, a few ms for any map size. For
    images as ``draw_map`` makes them (linear axes, an extent, no rotation); the data
    (``get_array``) is the full map, as before.
    """

    def make_image(self, renderer, magnification=1.0, unsampled=False):
        if unsampled:
            return super().make_image(renderer, magnification, unsampled)
        x1, x2, y1, y2 = self.get_extent()
        box = TransformedBbox(Bbox([[x1, y1], [x2, y2]]), self.get_transform())
        clip = ((self.get_clip_box() or self.axes.bbox) if self.get_clip_on()
                else self.get_figure(root=True).bbox)
        shown = Bbox.intersection(box, clip)
        if shown is None or shown.width <= 0 or shown.height <= 0 or box.width == 0 or box.height == 0:
            return None, 0, 0, None
        x0, y0 = np.floor(shown.x0), np.floor(shown.y0)
        w = int(np.ceil((np.ceil(shown.x1) - x0) * magnification))
        h = int(np.ceil((np.ceil(shown.y1) - y0) * magnification))
        if w <= 0 or h <= 0:
            return None, 0, 0, None
        data = self.get_array()
        ny, nx = data.shape[:2]
        # Pixel centres -> fractions of the image box -> sample indices (row 0 at y1: origin lower).
        fx = (x0 + (np.arange(w) + 0.5) / magnification - box.x0) / box.width
        fy = (y0 + (np.arange(h) + 0.5) / magnification - box.y0) / box.height
        if self.origin == "upper":
            fy = 1.0 - fy
        ix, iy = np.floor(fx * nx).astype(np.intp), np.floor(fy * ny).astype(np.intp)
        inside = ((iy >= 0) & (iy < ny))[:, None] & ((ix >= 0) & (ix < nx))[None, :]
        picked = data[np.ix_(np.clip(iy, 0, ny - 1), np.clip(ix, 0, nx - 1))]
        rgba = self.to_rgba(picked, bytes=True)
        rgba[~inside] = 0
        return rgba, x0, y0, IdentityTransform()           # row 0 at the bottom, as Agg takes it


def draw_map(fig, ax, wmap: WorkspaceMap, quantity: str, preset_or_title, *, values=None,
             title: str | None = None, artists=None, limits=None, fast_image: bool = False,
             scale: dict | None = None, colorbar=True, narrow: bool = False):
    """Draw the heat map of ``quantity`` on ``ax`` (the app's map view and ``map_figure`` share it).

    ``values`` replaces the map's own array (e.g. a difference of two maps, drawn with a
    diverging scale); ``title`` is a prefix for the panel's title. ``artists`` is what an
    earlier call on the same axes returned. If that drew the same kind of scale (quantity,
    log or not, capped or not, the same classes) the image, colour bar, markers and labels
    are updated in place: no new axes, so the figure's layout still holds and a new map
    costs one draw of those artists (the app's map view redraws just them while a slider
    moves). Otherwise the axes are cleared and drawn anew. ``limits`` (mm, like ``extent``)
    fixes the axes' limits, e.g. to the full grid's cells while a coarser map of the same
    slice is shown. ``fast_image`` draws the heat map as a ``NearestImage`` (screens; files
    keep matplotlib's own resampling). ``scale`` is a ``colour_scale`` to use instead of one
    of this map alone (panels compared with one scale). ``colorbar``: True draws this panel's
    own colour bar, False none, a list of axes one bar beside all of them (one bar for the
    panels that share ``scale``). ``narrow`` puts the slice's fixed coordinates on a title line
    of their own (panels side by side). Returns the artists to pass next time (the same dict if
    updated in place).
    """
    _check_map(wmap, quantity)
    node = QUANTITIES[quantity]
    extent = _extent(wmap)
    x_mm, y_mm = [c * 1e3 for c in wmap.grid.coordinates()]
    raw = np.asarray(values, float) if values is not None else np.asarray(wmap.values[quantity])
    if scale is None:
        scale = colour_scale(quantity, preset_or_title, [(raw, wmap.feasible)], difference=values is not None)
    data = scale["to_data"](raw, wmap.feasible)
    wants_bar = colorbar is not False
    old_bar = artists.get("colorbar") if artists is not None else None
    same = (artists is not None and artists.get("ax") is ax and artists.get("kind") == scale["kind"]
            and (old_bar is not None) == wants_bar and (old_bar is None or old_bar.ax in fig.axes))
    if same:
        image, bar = artists["image"], old_bar
        image.set_data(data.T)
        image.set_extent(extent)
        if scale["clim"] is not None:
            image.set_clim(*scale["clim"])       # the colour bar follows (norm callbacks)
        for artist in artists["singular"]:
            artist.remove()
    else:
        if old_bar is not None and old_bar.ax in fig.axes:
            old_bar.remove()
        ax.clear()
        image = ax.imshow(data.T, origin="lower", extent=extent, cmap=scale["cmap"], norm=scale["norm"](),
                          interpolation="nearest", aspect="equal")
        if fast_image:
            image.__class__ = NearestImage     # the same artist, drawn by picking pixels (no state added)
        bar = (fig.colorbar(image, ax=ax if colorbar is True else list(colorbar), shrink=1.0, **scale["bar"])
               if wants_bar else None)
        ax.set_aspect("equal")
        ax.set_xlabel(f"{wmap.grid.axes[0]} (mm)")
        ax.set_ylabel(f"{wmap.grid.axes[1]} (mm)")
        artists = {"ax": ax, "kind": scale["kind"], "image": image, "colorbar": bar}
    if bar is not None:
        scale["label_bar"](bar)
    before = set(ax.lines) | set(ax.images)
    if values is None and not node.categorical:
        _draw_singular(ax, np.asarray(wmap.values[quantity]), wmap.feasible, extent, (x_mm, y_mm))
        _draw_cut_edges(ax, wmap)          # (where the legend is that says what they are)
    if values is not None:
        # A difference's "no change" is near white, as the background: the compared region's edge is drawn.
        for line in region_outline(wmap, wmap.feasible & np.isfinite(raw)):
            ax.plot(line[:, 0], line[:, 1], color=OUTLINE_COLOUR, linewidth=OUTLINE_WIDTH, label="_outline")
    artists["singular"] = [a for a in (*ax.lines, *ax.images) if a not in before]
    if values is None and not node.categorical:
        _mark_extremes(ax, wmap, quantity, artists)
    limits = extent if limits is None else limits
    if (ax.get_autoscalex_on() or ax.get_autoscaley_on()          # (set_xlim/ylim turn autoscaling off)
            or tuple(ax.get_xlim()) != (limits[0], limits[1]) or tuple(ax.get_ylim()) != (limits[2], limits[3])):
        ax.set_xlim(limits[0], limits[1])
        ax.set_ylim(limits[2], limits[3])
    ax.set_title(map_title(wmap, quantity, preset_or_title, title=title, narrow=narrow), fontsize=10)
    artists["bar_key"] = scale["bar_key"]
    return artists


def map_title(wmap: WorkspaceMap, quantity: str, preset_or_title, *, title: str | None = None,
              narrow: bool = False) -> str:
    """A map panel's title: the device (or ``title``), the quantity, the grid and its feasible points,
    and the slice's fixed coordinates (on a line of their own when ``narrow``)."""
    fixed = ", ".join(_coordinate_text(preset_or_title, n, v) for n, v in wmap.grid.fixed)
    nx, ny = wmap.grid.resolution
    subtitle = f"{nx} x {ny} grid, {wmap.feasible_points} feasible points" + (
        ("\n" if narrow else "; ") + fixed if fixed else "")
    head = f"{title}: " if title else f"{_title_of(preset_or_title)}: "
    return f"{head}{quantity_label(wmap, quantity, lower=True)}\n{subtitle}"


def colour_scale(quantity: str, preset_or_title, layers, *, difference: bool = False,
                 limits: tuple[float, float, bool] | None = None) -> dict:
    """One colour scale for one or several maps of ``quantity`` (a comparison shares one).

    Parameters
    ----------
    quantity : str
        A scalar quantity of ``metrics.quantities.QUANTITIES``.
    preset_or_title : resources.Preset or str
        A preset names the bottleneck's classes (its actuators).
    layers : sequence of (values, feasible)
        Each map's values and feasibility mask, arrays of one map's shape (nx, ny); the
        limits (or classes) cover every layer, so equal values get equal colours in all.
    difference : bool
        The values are a difference of two maps: a diverging scale centred at zero.
    limits : tuple, optional
        ``(lo, hi, capped)`` of a continuous quantity's layers, computed beforehand
        (``map_colour_limits``); default computed here.

    Returns
    -------
    dict
        ``to_data(values, feasible)`` gives a layer's masked array to draw; ``cmap`` and
        ``norm()``; ``bar`` (colour bar options) and ``label_bar(bar)``; ``clim`` for an
        in-place update; ``kind``: maps of the same kind can share one image and colour bar;
        ``bar_key``: what the colour bar shows (it is redrawn when this changes).
    """
    layers = [(np.asarray(v), np.asarray(f, bool)) for v, f in layers]
    if not layers:
        raise ValueError("layers must hold at least one (values, feasible) pair, got none")
    if difference:
        return _difference_scale(layers, quantity)
    if QUANTITIES[quantity].categorical:
        return _categorical_scale(layers, quantity, preset_or_title)
    return _continuous_scale(layers, quantity, limits)


def noted_scale(scale: dict, note: str) -> dict:
    """``scale`` with ``note`` on a line of its own under the colour bar's label, e.g. which colour
    range a plane of a volume is drawn with ("colours: this plane" or "colours: whole volume").

    The note is part of ``bar_key`` and ``label``, so a bar drawn in place or painted by the app
    (``app.plots.map_picture``) carries it too.
    """
    label = f"{scale['label']}\n{note}"

    def label_bar(bar):
        scale["label_bar"](bar)
        bar.set_label(label, fontsize=BAR_LABEL_PT)

    return {**scale, "label": label, "label_bar": label_bar, "bar_key": (scale["bar_key"], note)}


#: The colour ranges of a plane of a 3D box map: the plane's own values, or the whole volume's.
COLOUR_RANGES = {"plane": "colours: this plane", "volume": "colours: whole volume"}


def plane_scale(volume: WorkspaceMap, plane: WorkspaceMap, quantity: str, preset_or_title,
                colour_range: str = "plane") -> dict | None:
    """The colour scale a plane of a 3D box map is drawn with, in the display unit, its range named.

    Parameters
    ----------
    volume : WorkspaceMap
        The 3D box map (arrays (nx, ny, nz)).
    plane : WorkspaceMap
        One plane of it (``app.logic.planes.volume_slice``; arrays (n_a, n_b)).
    quantity : str
        A scalar quantity both hold.
    preset_or_title : resources.Preset or str
        As for ``colour_scale``.
    colour_range : {"plane", "volume"}
        Span the plane's feasible values (a plane of 2-7 N is not one colour in a volume of
        0-18 N), or the whole volume's (planes compared with each other as the slider moves).

    Returns
    -------
    dict or None
        A ``colour_scale`` whose bar says which range (``COLOUR_RANGES``); None for a
        categorical quantity (its classes have no range).
    """
    if colour_range not in COLOUR_RANGES:
        raise ValueError(f"colour_range must be one of {', '.join(COLOUR_RANGES)}, got {colour_range!r}")
    if QUANTITIES[quantity].categorical:
        return None
    source = volume if colour_range == "volume" else plane
    shown = display_map(source, quantity)
    scale = colour_scale(quantity, preset_or_title, [(shown.values[quantity], shown.feasible)])
    return noted_scale(scale, COLOUR_RANGES[colour_range])


def draw_panels(fig, axes, panels, quantity: str, preset_or_title, *, artists=None, limits=None,
                fast_image: bool = False, narrow: bool | None = None) -> list:
    """Draw several maps of ``quantity`` on ``axes`` with ONE colour scale and one colour bar.

    A comparison (reference and current design, the app's map view and ``isoforce``'s compare
    figure) must colour equal values alike in both panels: the scale spans every panel's
    feasible values (or classes), and a single colour bar stands beside all the axes.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    axes : sequence of Axes
        One per panel, already laid out (e.g. ``fig.add_subplot(1, 2, k)``).
    panels : sequence of (title, WorkspaceMap, values or None)
        ``values`` replaces the map's own array (a difference, on a diverging scale).
    quantity, preset_or_title
        As for ``draw_map``.
    artists : list or None
        What an earlier call on the same axes returned (in-place update).
    limits : list or None
        Per panel, ``draw_map``'s ``limits``.
    fast_image : bool
        As for ``draw_map``.
    narrow : bool, optional
        ``draw_map``'s ``narrow`` for every panel; default: when there are several panels.

    Returns
    -------
    list of dict
        ``draw_map``'s artists per panel; only the last panel's hold the colour bar.
    """
    if len(axes) != len(panels) or not panels:
        raise ValueError(f"axes and panels must be as many and at least one, got {len(axes)} and {len(panels)}")
    difference = any(values is not None for _, _, values in panels)
    layers = [(values if values is not None else wmap.values[quantity], wmap.feasible) for _, wmap, values in panels]
    scale = colour_scale(quantity, preset_or_title, layers, difference=difference)
    artists = list(artists) if artists is not None else [None] * len(panels)
    limits = list(limits) if limits is not None else [None] * len(panels)
    out = []
    for i, (title, wmap, values) in enumerate(panels):
        last = i == len(panels) - 1
        out.append(draw_map(fig, axes[i], wmap, quantity, preset_or_title, values=values, title=title,
                            artists=artists[i], limits=limits[i], fast_image=fast_image, scale=scale,
                            colorbar=(True if len(panels) == 1 else list(axes)) if last else False,
                            narrow=len(panels) > 1 if narrow is None else narrow))
    return out


# Each ``_*_scale`` says how maps are coloured (see ``colour_scale``).
def _difference_scale(layers, quantity) -> dict:
    """A difference of two maps on a diverging scale centred at zero."""
    node = QUANTITIES[quantity]
    shown = [f & np.isfinite(v) for v, f in layers]
    spans = [float(np.max(np.abs(v[s]))) for (v, _), s in zip(layers, shown) if np.any(s)]
    span = max(spans) if spans else 1.0
    clim = (-span or -1.0, span or 1.0)
    label = f"change of {node.label.lower()}" + (f" ({node.unit})" if node.unit else "")
    return {"kind": ("difference", quantity),
            "to_data": lambda v, f: np.ma.masked_array(v, mask=~(f & np.isfinite(v))),
            "cmap": _cmap("RdBu_r").with_extremes(bad=(0.0, 0.0, 0.0, 0.0)),
            "norm": lambda: colors.Normalize(vmin=clim[0], vmax=clim[1]), "clim": clim, "bar": {},
            "label_bar": lambda bar: bar.set_label(label, fontsize=BAR_LABEL_PT), "bar_key": (clim, label),
            "label": label, "log": False, "capped": False}


def _continuous_scale(layers, quantity, limits=None) -> dict:
    """Sequential colours; log scale for the condition number; capped at ``colour_limits``
    (``limits``, when the caller has them: ``map_colour_limits`` of the one layer)."""
    node = QUANTITIES[quantity]
    log = log_colours(quantity)
    lo, hi, capped = limits if limits is not None else layers_limits(layers, log=log)
    # The cap on a line of its own: one line as long as both was taller than a flat map's bar.
    label = node.label + (f" ({node.unit})" if node.unit else "") + (f"\ncolours capped at {hi:.3g}" if capped else "")

    def label_bar(bar):
        bar.set_label(label, fontsize=BAR_LABEL_PT)
        if log:
            _plain_log_ticks(bar, lo, hi)

    return {"kind": ("continuous", quantity, log, capped),
            "to_data": lambda v, f: np.ma.masked_array(v, mask=~(f & np.isfinite(v))),
            "cmap": _cmap(SEQUENTIAL_CMAP).with_extremes(bad=(0.0, 0.0, 0.0, 0.0)),   # masked cells stay blank
            "norm": lambda: colors.LogNorm(vmin=lo, vmax=hi) if log else colors.Normalize(vmin=lo, vmax=hi),
            "clim": (lo, hi), "bar": {"extend": "max" if capped else "neither"}, "label_bar": label_bar,
            "bar_key": (lo, hi, label), "label": label, "log": log, "capped": capped}


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


def _draw_cut_edges(ax, wmap: WorkspaceMap) -> None:
    """``cut_edges`` as dashed lines over the frame (unclipped), labelled once for the legend."""
    for k, (xa, xb, ya, yb) in enumerate(cut_edges(wmap)):
        ax.plot([xa, xb], [ya, yb], clip_on=False, label=CUT_EDGE_LABEL if k == 0 else "_cut", **CUT_EDGE_STYLE)


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


def _draw_singular(ax, values, feasible, extent, coords_mm) -> None:
    """``inf`` (singular) points inside the workspace, in a colour of their own."""
    singular = feasible & np.isposinf(values)
    count = int(np.count_nonzero(singular))
    legend = unbounded_legend(count)
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


def _plain_log_ticks(bar, lo: float, hi: float) -> None:
    """Ticks 1, 2, 5, 10, 20, ... as plain numbers: easier to read than 2 x 10^0 for a condition number."""
    ticks = log_ticks(lo, hi)
    bar.set_ticks(ticks, labels=[f"{t:.3g}" for t in ticks])
    bar.ax.yaxis.set_minor_formatter(ticker.NullFormatter())


def log_ticks(lo: float, hi: float) -> list[float]:
    """Colour-bar ticks of a log scale from ``lo`` to ``hi``: 1, 2, 5 x 10^k (finer within 1.5 decades)."""
    decades = range(int(np.floor(np.log10(lo))), int(np.ceil(np.log10(hi))) + 1)
    # Less than a decade and a half: finer steps, or the bar would carry one or two labels.
    mantissas = (1, 2, 5) if hi / lo > 30 else (1, 1.5, 2, 3, 5, 7)
    ticks = [m * 10.0 ** k for k in decades for m in mantissas if lo <= m * 10.0 ** k <= hi]
    return ticks if len(ticks) >= 2 else [lo, hi]


def category_classes(quantity: str, preset_or_title, codes) -> list[tuple[int, str, tuple]]:
    """The classes a categorical map draws: ``(code, tick label, RGBA colour)`` in colour-bar order.

    Every actuator (or singularity class) by name, then any larger code found by number, then
    the bottleneck's "tie" and "shared (redundant)" codes where they occur (``codes``: the codes
    found at feasible points). Other negative codes (``-1``, infeasible) have no class: blank.
    """
    codes = np.unique(np.asarray(codes, np.int64))
    names = list(_category_names(quantity, preset_or_title))
    top = int(codes.max()) + 1 if codes.size and codes.max() >= 0 else 0
    names += [str(i) for i in range(len(names), top)]
    palette = _cmap(CATEGORICAL_CMAP)
    classes = [(i, name, palette(_CLASS_COLOURS[i % len(_CLASS_COLOURS)])) for i, name in enumerate(names)]
    if quantity == "bottleneck":
        classes += [(code, label, colors.to_rgba(colour)) for code, (label, colour) in BOTTLENECK_CODES.items()
                    if code in codes]
    return classes


def _categorical_scale(layers, quantity, preset_or_title) -> dict:
    """One colour per class (bottleneck actuator, tie, shared; singularity class), ticks labelled by name."""
    found = [np.asarray(v[f]).astype(np.int64) for v, f in layers]
    classes = category_classes(quantity, preset_or_title, np.concatenate(found))
    if not classes:                 # no names and nothing feasible: one placeholder class
        classes = [(0, "0", _cmap(CATEGORICAL_CMAP)(0))]
    k = len(classes)
    code_of = np.array([code for code, _, _ in classes], np.int64)
    names = tuple(name for _, name, _ in classes)
    cmap = colors.ListedColormap([colour for _, _, colour in classes]).with_extremes(bad=(0.0, 0.0, 0.0, 0.0))
    # Counts next to the names: singular classes and ties cover a few grid points, too few to
    # see; with several maps sharing the bar, one count per map ("reference / current").
    counts = [[int(np.count_nonzero(codes == code)) for codes in found] for code in code_of]
    labels = [f"{name} ({' / '.join(map(str, c))})" for name, c in zip(names, counts)]

    def to_data(values, feasible):
        """Class index per point (position in the colour bar), masked off the classes."""
        values = np.asarray(values).astype(np.int64)
        index = np.full(values.shape, -1, np.int64)
        for k_class, code in enumerate(code_of):
            index[values == code] = k_class
        return np.ma.masked_array(index, mask=~(np.asarray(feasible, bool) & (index >= 0)))

    bar_label = QUANTITIES[quantity].label + (" (points per panel, left to right)" if len(layers) > 1 else "")

    def label_bar(bar):
        bar.ax.set_yticklabels(labels)
        bar.set_label(bar_label, fontsize=BAR_LABEL_PT)

    return {"kind": ("categorical", quantity, names), "to_data": to_data,
            "cmap": cmap, "norm": lambda: colors.BoundaryNorm(np.arange(-0.5, k), k), "clim": None,
            "bar": {"ticks": np.arange(k)}, "label_bar": label_bar, "bar_key": tuple(labels),
            "label": bar_label, "tick_labels": tuple(labels), "log": False, "capped": False}


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
        text = (f"max unbounded near ({px:.1f}, {py:.1f}) mm" if label == "max" and stats.unbounded
                else f"{label} {digits}{unit} {where}")
        out.append((marker, px, py, text))
    return out


def _mark_extremes(ax, wmap: WorkspaceMap, quantity: str, artists: dict) -> None:
    """Mark where the global minimum and maximum are, with their values in the legend.

    The markers and legend of an earlier call (in ``artists``) are moved and relabelled in
    place when the legend would list the same artists again (a new legend costs milliseconds).
    """
    old = artists.get("extremes", [])
    lines = []
    for k, (marker, px, py, text) in enumerate(extreme_marks(wmap, quantity)):
        if k < len(old) and old[k].axes is ax:
            old[k].set_data([px], [py])
            old[k].set_label(text)
            lines.append(old[k])
        else:
            lines += ax.plot(px, py, marker, markersize=9, markerfacecolor="white", markeredgecolor="black",
                             clip_on=False, label=text)
    for line in old[len(lines):]:
        if line.axes is ax:
            line.remove()
    artists["extremes"] = lines
    labelled = [line for line in ax.lines if not line.get_label().startswith("_")]
    legend = ax.get_legend()
    if lines and legend is not None and artists.get("legend_for") == labelled:
        for text, line in zip(legend.get_texts(), labelled):
            text.set_text(line.get_label())
        return
    if legend is not None:
        legend.remove()
    if lines:
        # Below the axes (under the x label), not over the data: the layout makes room for it.
        below = ax.transAxes + ScaledTranslation(0.0, -LEGEND_DROP_PT / 72.0, ax.figure.dpi_scale_trans)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, 0.0), bbox_transform=below, fontsize=8,
                  framealpha=0.85, borderaxespad=0.0)
    artists["legend_for"] = labelled


def _cmap(name: str):
    from matplotlib import colormaps
    return colormaps[name]


def round_below(value: float) -> float:
    """The largest 1, 2 or 5 x 10^k not above ``value`` (> 0): a scale bar's or a key's length.

    >>> round_below(37.0), round_below(0.149)
    (20.0, 0.1)
    """
    k = np.floor(np.log10(value))
    return float(max(m * 10.0 ** k for m in (1, 2, 5) if m * 10.0 ** k <= value * (1 + 1e-12)))


def save_figure(fig: Figure, path: str | os.PathLike, *, name: str = "path") -> Path:
    """Write ``fig`` as PNG, SVG or PDF (by suffix) through ``atomic_write``."""
    target = check_suffix(path, FIGURE_SUFFIXES, name)
    fmt = target.suffix.lower().lstrip(".")
    return atomic_write(target, lambda tmp: fig.savefig(tmp, format=fmt), name=name)


def _coordinate_text(preset_or_title, name: str, value: float) -> str:
    """A fixed task coordinate in display units: mm, or deg for a pen's orientation."""
    mechanism = getattr(preset_or_title, "mechanism", None)
    units = dict(zip(mechanism.task_names, task_display_units(mechanism))) if mechanism is not None else {}
    if units.get(name) == "deg":
        return f"{name} = {np.degrees(value):g} deg"
    return f"{name} = {value * 1e3:g} mm"
