"""Publication figures of workspace maps, drawn with matplotlib off-screen.

Figures are built on ``matplotlib.figure.Figure`` with an Agg canvas, never through
``pyplot``: no global backend switch, no display needed, no figure registry to leak, and
the desktop app may use its own matplotlib backend alongside. Only app code imports this
module; the compute layers stay free of matplotlib.
"""
from __future__ import annotations

import os
import textwrap
import warnings
from pathlib import Path

import numpy as np
from matplotlib import colors, ticker
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.image import AxesImage
from matplotlib.text import Text
from matplotlib.transforms import Bbox, IdentityTransform, ScaledTranslation, TransformedBbox

from app.files.export import FIGURE_SUFFIXES, atomic_write, check_suffix
from app.logic.colour_limits import LOG_QUANTITIES, colour_limits, layers_limits, log_colours, map_colour_limits  # noqa: F401
from app.logic.colour_scale import ColourScale, colour_scale
from app.logic.display_units import display_map, relabel_axes
from app.logic.map_marks import (
    CUT_EDGE_LABEL,
    CUT_EDGE_STYLE,
    MAX_SINGULAR_MARKERS,
    OUTLINE_COLOUR,
    OUTLINE_WIDTH,
    SINGULAR_COLOUR,
    cut_edges,
    extreme_marks,
    grid_extent,
    map_title,
    region_outline,
    title_of,
    unbounded_legend,
)
from app.logic.ticks import log_ticks
from metrics.quantities import QUANTITIES
from metrics.workspace import WorkspaceMap

#: How far below the axes the legend of extremes starts, pt: the tick labels and the x label
#: (10 pt text each, 3.5 pt ticks and their pads) above it.
LEGEND_DROP_PT = 34.0
#: Colour bar label size, pt: a line of it fits beside the bar of a map twice as wide as tall.
BAR_LABEL_PT = 9


def _figure_size(extent: tuple[float, float, float, float]) -> tuple[float, float]:
    """Inches for a map of this extent: the plot keeps the data's aspect, plus room for the colour bar."""
    width_mm, height_mm = extent[1] - extent[0], extent[3] - extent[2]
    aspect = height_mm / width_mm
    plot_w = 5.5 if aspect <= 1.2 else max(3.0, 6.0 / aspect)
    plot_h = plot_w * aspect
    return plot_w + 2.0, max(3.2, plot_h + 1.4)


def map_figure(wmap: WorkspaceMap, quantity: str, preset_or_title, *, dpi: int = 150,
               scale: ColourScale | None = None, note: str | None = None) -> Figure:
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
        whole volume's for one of its planes (``ColourScale.with_note`` says which on the colour bar).
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
    title = f"{wmap.loading.describe()}\n{title_of(preset_or_title)}" + (f"\n{note}" if note else "")
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


def matplotlib_cmap(scale: ColourScale) -> colors.ListedColormap:
    """``scale``'s lookup table as a matplotlib colour map; masked cells stay blank."""
    return colors.ListedColormap(scale.lut).with_extremes(bad=(0.0, 0.0, 0.0, 0.0))


def matplotlib_norm(scale: ColourScale) -> colors.Normalize:
    """``scale``'s normalisation: one class per colour, or its limits on a linear or log scale."""
    if scale.categorical:
        k = len(scale.lut)
        return colors.BoundaryNorm(np.arange(-0.5, k), k)
    lo, hi = scale.limits
    return colors.LogNorm(vmin=lo, vmax=hi) if scale.log else colors.Normalize(vmin=lo, vmax=hi)


def _bar_options(scale: ColourScale) -> dict:
    """``Figure.colorbar`` options: a tick per class, or an arrow where the colours are capped."""
    if scale.categorical:
        return {"ticks": np.arange(len(scale.lut))}
    return {"extend": "max" if scale.capped else "neither"} if scale.kind[0] == "continuous" else {}


def _label_bar(bar, scale: ColourScale) -> None:
    """The colour bar's label, and its ticks: the classes' names, or 1-2-5 on a log scale."""
    if scale.categorical:
        bar.ax.set_yticklabels(scale.tick_labels)
    elif scale.log:
        ticks = log_ticks(*scale.limits)
        bar.set_ticks(ticks, labels=[f"{t:.3g}" for t in ticks])
        bar.ax.yaxis.set_minor_formatter(ticker.NullFormatter())
    bar.set_label(scale.label, fontsize=BAR_LABEL_PT)


def draw_map(fig, ax, wmap: WorkspaceMap, quantity: str, preset_or_title, *, values=None,
             title: str | None = None, artists=None, limits=None, fast_image: bool = False,
             scale: ColourScale | None = None, colorbar=True, narrow: bool = False):
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
    data = scale.to_data(raw, wmap.feasible)
    wants_bar = colorbar is not False
    old_bar = artists.get("colorbar") if artists is not None else None
    same = (artists is not None and artists.get("ax") is ax and artists.get("kind") == scale.kind
            and (old_bar is not None) == wants_bar and (old_bar is None or old_bar.ax in fig.axes))
    if same:
        image, bar = artists["image"], old_bar
        image.set_data(data.T)
        image.set_extent(extent)
        if scale.limits is not None:
            image.set_clim(*scale.limits)       # the colour bar follows (norm callbacks)
        for artist in artists["singular"]:
            artist.remove()
    else:
        if old_bar is not None and old_bar.ax in fig.axes:
            old_bar.remove()
        ax.clear()
        image = ax.imshow(data.T, origin="lower", extent=extent, cmap=matplotlib_cmap(scale),
                          norm=matplotlib_norm(scale), interpolation="nearest", aspect="equal")
        if fast_image:
            image.__class__ = NearestImage     # the same artist, drawn by picking pixels (no state added)
        bar = (fig.colorbar(image, ax=ax if colorbar is True else list(colorbar), shrink=1.0, **_bar_options(scale))
               if wants_bar else None)
        ax.set_aspect("equal")
        ax.set_xlabel(f"{wmap.grid.axes[0]} (mm)")
        ax.set_ylabel(f"{wmap.grid.axes[1]} (mm)")
        artists = {"ax": ax, "kind": scale.kind, "image": image, "colorbar": bar}
    if bar is not None:
        _label_bar(bar, scale)
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
    artists["bar_key"] = scale.bar_key
    return artists


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


def _draw_cut_edges(ax, wmap: WorkspaceMap) -> None:
    """``cut_edges`` as dashed lines over the frame (unclipped), labelled once for the legend."""
    for k, (xa, xb, ya, yb) in enumerate(cut_edges(wmap)):
        ax.plot([xa, xb], [ya, yb], clip_on=False, label=CUT_EDGE_LABEL if k == 0 else "_cut", **CUT_EDGE_STYLE)


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


#: The body text of the figures (titles, tick labels), pt: a column's font size scales every text by
#: its ratio to this, so the smaller legends and colour-bar labels keep their place below it.
BODY_PT = 10.0


#: The flattest page (height / width) a column figure gets.
MIN_COLUMN_ASPECT = 0.85


def fit_to_column(fig: Figure, width_in: float, font_pt: float) -> Figure:
    """``fig`` resized to a journal column: ``width_in`` inches wide, its body text ``font_pt`` points.

    The height follows the figure's aspect, then grows until every text and artist is inside
    the page (a narrower figure wraps nothing: its layout makes room). Raises ``ValueError``
    when something is wider than the column at that font size.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure of this module or ``app.plots.overlays``, with its layout engine.
    width_in : float
        The page's width, inches (a single journal column is about 3.3-3.5 in).
    font_pt : float
        The body text's size, points.

    Returns
    -------
    matplotlib.figure.Figure
        ``fig`` itself.
    """
    # A legend beside the axes (a tall map's overlay key) would take the column's width: below them.
    ratio = font_pt / BODY_PT
    # Legends below or beside the axes (the extremes, an overlay's key) as the figure's, which the
    # layout makes room for: an axes' legend centred under an off-centre map can leave the page.
    for legend in [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None] + list(fig.legends):
        handles, labels = legend.legend_handles, [text.get_text() for text in legend.get_texts()]
        title, size = legend.get_title().get_text(), legend.get_texts()[0].get_fontsize() if labels else BODY_PT
        # Long labels wrapped to the column (a character is about half the font size wide).
        chars = max(20, int(0.8 * width_in * 72 / (0.5 * size * ratio)) - 6)
        labels = ["\n".join(textwrap.wrap(label, chars)) or label for label in labels]
        legend.remove()
        fig.legend(handles=handles, labels=labels, loc="outside lower center", fontsize=size, title=title or None,
                   title_fontsize=size, frameon=False)
    for ax in fig.axes:            # a title line longer than the column wraps (a character is ~half its size)
        size = ax.title.get_fontsize() * ratio
        chars = max(20, int(0.65 * width_in * 72 / (0.5 * size)))    # (the colour bar takes the rest)
        ax.title.set_text("\n".join(textwrap.fill(line, chars) for line in ax.title.get_text().split("\n")))
    for text in fig.findobj(Text):
        text.set_fontsize(text.get_fontsize() * ratio)
    for ax in fig.axes:
        ax.tick_params(labelsize=font_pt)
    w, h = fig.get_size_inches()
    # The figure's aspect, but no flatter than MIN_COLUMN_ASPECT: a wide map's title, legend and axis
    # labels keep their size in points while its axes shrink with the width.
    fig.set_size_inches(width_in, max(h / w, MIN_COLUMN_ASPECT) * width_in)
    for _ in range(8):                 # the layout settles in two or three rounds
        renderer = fig.canvas.get_renderer()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            fig.draw_without_rendering()
        width, height = fig.get_size_inches()
        box = fig.get_tightbbox(renderer)          # inches
        words = _text_box(fig, renderer)           # inches: the texts alone (markers may touch the edge)
        if any("collapsed" in str(w.message) for w in caught) and words.width <= width:
            fig.set_size_inches(width, 1.5 * height)       # no room left for the axes: taller
            continue
        if words.x0 < -0.01 or words.x1 > width + 0.01:
            raise ValueError(f"the figure's text is {words.width:.2f} in wide at {font_pt:g} pt, more than the "
                             f"column's {width_in:g} in: use a wider column or a smaller font")
        if box.y0 >= -0.01 and box.y1 <= height + 0.01:
            return fig
        fig.set_size_inches(width, height + max(0.0, -box.y0) + max(0.0, box.y1 - height) + 0.02)
    raise ValueError(f"the figure's text leaves its axes no room in a {width_in:g} in column at {font_pt:g} pt: "
                     f"use a wider column or a smaller font")


def _text_box(fig: Figure, renderer) -> Bbox:
    """Where the figure's drawn text is, inches: titles, axis labels and tick labels, legends."""
    boxes = [legend.get_window_extent(renderer) for legend in fig.legends]
    for ax in fig.axes:
        boxes += [ax.xaxis.get_tightbbox(renderer), ax.yaxis.get_tightbbox(renderer)]
        boxes += [text.get_window_extent(renderer) for text in (ax.title, ax._left_title, ax._right_title)
                  if text.get_text()]
        if ax.get_legend() is not None:
            boxes.append(ax.get_legend().get_window_extent(renderer))
    boxes = [b for b in boxes if b is not None and b.width > 0]
    return Bbox.union(boxes).transformed(fig.dpi_scale_trans.inverted())


def save_figure(fig: Figure, path: str | os.PathLike, *, name: str = "path") -> Path:
    """Write ``fig`` as PNG, SVG or PDF (by suffix) through ``atomic_write``."""
    target = check_suffix(path, FIGURE_SUFFIXES, name)
    fmt = target.suffix.lower().lstrip(".")
    return atomic_write(target, lambda tmp: fig.savefig(tmp, format=fmt), name=name)


