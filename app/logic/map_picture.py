"""What the app's map view paints, as plain data: panels, colours, ticks, legends, overlays.

The on-screen map is painted by Qt (``app.gui.views.map_canvas``), not matplotlib: a slider
step must reach the screen in a frame or two, and matplotlib's text and layout cost 100 ms
and more per step. Exported figures stay matplotlib (``app.plots.figures``). So that both show
the same thing, both take every decision from this floor: the colour scale
(``colour_scale.colour_scale``: limits, cap, log, classes, lookup table), the title, extremes,
singular points and cut edges (``map_marks``), the ticks (``ticks``) and the overlay
(``overlay_drawing.OverlayDrawing``). No matplotlib and no Qt here (an import-linter
contract), so it is tested without a display.

Colours are looked up exactly as matplotlib's ``Colormap(Normalize(x), bytes=True)`` does
(``ColourScale.colours``): the same normalisation arithmetic, the index ``int(x N)`` clipped
to ``[0, N - 1]`` (the default under and over colours are the end colours), transparent
where the value is masked or not a number. A test compares them pixel for pixel.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from app.logic.colour_scale import ColourScale, colour_scale
from app.logic.map_marks import (
    CUT_EDGE_LABEL,
    CUT_EDGE_STYLE,
    MAX_SINGULAR_MARKERS,
    SINGULAR_COLOUR,
    cut_edges,
    extreme_marks,
    grid_extent,
    map_title,
    region_outline,
    unbounded_legend,
)
from app.logic.overlay_drawing import OverlayDrawing
from app.logic.ticks import axis_ticks, log_ticks
from kinematics.grid import GridSpec
from metrics.quantities import QUANTITIES

#: The singular colour as RGBA bytes.
SINGULAR_RGBA = np.frombuffer(bytes.fromhex(SINGULAR_COLOUR[1:]) + b"\xff", np.uint8)


@dataclass(frozen=True, eq=False)
class ColourBar:
    """A colour bar: ``colours`` (n, 4) uint8 bottom to top, ``ticks`` (fraction 0..1 from the
    bottom, label), its ``label`` (lines), an arrow at the top where the colours are capped, and
    whether the colours are classes (blocks) rather than a continuous scale."""

    colours: np.ndarray
    ticks: tuple
    label: str
    extend_max: bool
    categorical: bool


@dataclass
class PanelPicture:
    """One map panel: its title, grid and axes, the coloured samples, markers and legend.

    ``data`` (nx, ny) holds the values drawn (display units; masked where blank) and ``scale``
    the colour scale; ``singular_cells`` (nx, ny) marks cells drawn in the singular colour
    (where singular points are too many for markers) or is None. ``sample_colours`` colours
    any selection of samples, so a canvas colours only the samples under its pixels.
    ``extent`` (mm) spans the map's cells,
    ``limits`` (mm) the axes (the full grid's cells, so a coarse map shares the full map's
    axes). ``singular`` (k, 2) mm are markers of singular points; ``extremes`` the global
    minimum and maximum (marker, x, y, text); ``legend`` rows (symbol, colour, text).
    """

    title: str
    grid: GridSpec
    extent: tuple
    limits: tuple
    xlabel: str
    ylabel: str
    data: np.ndarray
    scale: ColourScale
    singular_cells: np.ndarray | None
    singular: np.ndarray
    extremes: tuple
    legend: tuple
    reference: bool = False
    #: Stretches of the map's edge that feasible samples reach (``map_marks.cut_edges``): dashed.
    cut_edges: tuple = ()
    #: A difference panel's compared region's edge: polylines (k, 2) in mm (``map_marks.region_outline``).
    outline: tuple = ()
    overlay: OverlayDrawing | None = None
    labels_shown: bool = True
    _flat: tuple | None = field(default=None, repr=False)

    def sample_colours(self, ix: np.ndarray, iy: np.ndarray) -> np.ndarray:
        """RGBA bytes (len(iy), len(ix), 4) of the samples ``data[ix][:, iy]``, rows in ``iy`` order.

        What the figure shows at those samples: ``colour_samples`` of the values, and the
        singular colour on ``singular_cells``.
        """
        if self._flat is None:          # the samples in C order, and their mask
            self._flat = (np.ascontiguousarray(np.ma.getdata(self.data)).ravel(),
                          np.ascontiguousarray(np.ma.getmaskarray(self.data)).ravel())
        # One gather of (len(iy), len(ix)) samples: sample (i, j) is at i ny + j.
        flat = np.asarray(ix, np.intp)[None, :] * self.data.shape[1] + np.asarray(iy, np.intp)[:, None]
        values, blank = (a.take(flat) for a in self._flat)
        rgba = self.scale.colours(values, blank)
        if self.singular_cells is not None and self.singular_cells.any():
            rgba[self.singular_cells.ravel().take(flat)] = SINGULAR_RGBA
        return rgba


@dataclass
class MapPicture:
    """Every panel of the map view (one, or a comparison's two) and their one colour bar."""

    quantity: str
    panels: list = field(default_factory=list)
    bar: ColourBar | None = None
    message: str = ""


def colour_samples(scale: ColourScale, data) -> np.ndarray:
    """RGBA bytes of ``data`` (masked where blank) under ``scale``, as ``cmap(norm(data), bytes=True)``.

    Parameters
    ----------
    scale : ColourScale
    data : numpy.ma.MaskedArray, shape (...)
        Values (or class indices) as ``scale.to_data`` gives them.

    Returns
    -------
    ndarray of uint8, shape (..., 4)
        Transparent where ``data`` is masked or not a number.
    """
    return scale.colours(np.ma.getdata(data), np.ma.getmaskarray(data))


def colour_bar(scale: ColourScale) -> ColourBar:
    """The colour bar of ``scale``: its colours, ticks and label."""
    if scale.categorical:
        labels = scale.tick_labels
        k = len(labels)
        ticks = tuple(((i + 0.5) / k, label) for i, label in enumerate(labels))
        return ColourBar(colours=scale.lut_bytes[:k], ticks=ticks, label=scale.label, extend_max=False,
                         categorical=True)
    lo, hi = scale.limits
    if scale.log:
        values = log_ticks(lo, hi)
        fraction = [(np.log10(t) - np.log10(lo)) / (np.log10(hi) - np.log10(lo)) for t in values]
        labels = [f"{t:.3g}" for t in values]
    else:
        values = axis_ticks(lo, hi, 350.0)
        fraction = [(t - lo) / (hi - lo) for t in values]
        step = values[1] - values[0] if len(values) > 1 else abs(hi - lo)
        digits = max(0, -int(np.floor(np.log10(step)))) if step > 0 else 0
        labels = [f"{t:.{digits}f}" if abs(step) >= 1e-4 and abs(t) < 1e6 else f"{t:.3g}" for t in values]
    return ColourBar(colours=scale.lut_bytes, ticks=tuple(zip(fraction, labels)), label=scale.label,
                     extend_max=scale.capped, categorical=False)


def panel_picture(wmap, quantity: str, preset_or_title, scale: ColourScale, *, values=None, title: str | None = None,
                  limits=None, narrow: bool = False) -> PanelPicture:
    """One panel as ``figures.draw_map`` draws it: the map (or ``values``) coloured by ``scale``.

    Parameters
    ----------
    wmap : WorkspaceMap
        A 2D map holding ``quantity`` (in the units it is drawn in).
    quantity : str
        The quantity drawn.
    preset_or_title : resources.Preset or str
        Names the device in the title.
    scale : ColourScale
        The colour scale shared by every panel.
    values : ndarray, shape (nx, ny), optional
        Drawn instead of the map's own values (a difference of two maps): no extremes then.
    title : str, optional
        The panel's title prefix (``map_marks.map_title``).
    limits : tuple, optional
        Axes limits (mm), default the map's own cells.
    narrow : bool
        The slice's fixed coordinates on a title line of their own.
    """
    node = QUANTITIES[quantity]
    raw = np.asarray(values, float) if values is not None else np.asarray(wmap.values[quantity])
    data = scale.to_data(raw, wmap.feasible)
    cells = None
    extent = grid_extent(wmap.grid)
    x_mm, y_mm = (c * 1e3 for c in wmap.grid.coordinates())
    legend = []
    cuts: tuple = ()
    markers = np.zeros((0, 2))
    extremes: tuple = ()
    if values is None and not node.categorical:
        singular = wmap.feasible & np.isposinf(raw)
        count = int(np.count_nonzero(singular))
        # As ``figures._draw_singular``: a singular curve is one cell wide, so markers while
        # they are few, coloured cells beyond that.
        if 0 < count <= MAX_SINGULAR_MARKERS:
            i, j = np.nonzero(singular)
            markers = np.stack([x_mm[i], y_mm[j]], axis=-1)
        elif count:
            cells = singular
        extremes = tuple(extreme_marks(wmap, quantity))
        # Within the axes: a coarse map's cells reach up to half a coarse cell past the full grid's frame.
        cuts = tuple(_within(segment, extent if limits is None else limits) for segment in cut_edges(wmap))
        # In the exported figure's legend order: the singular points are drawn first there.
        legend = [("x", SINGULAR_COLOUR, unbounded_legend(count))] if count else []
        legend += [("--", CUT_EDGE_STYLE["color"], CUT_EDGE_LABEL)] if cuts else []
        legend += [(marker, "black", text) for marker, _, _, text in extremes]
    return PanelPicture(title=map_title(wmap, quantity, preset_or_title, title=title, narrow=narrow),
                        grid=wmap.grid, extent=extent, limits=extent if limits is None else tuple(limits),
                        xlabel=f"{wmap.grid.axes[0]} (mm)", ylabel=f"{wmap.grid.axes[1]} (mm)", data=data,
                        scale=scale, singular_cells=cells, singular=markers, extremes=extremes, legend=tuple(legend),
                        cut_edges=cuts,
                        outline=() if values is None else tuple(region_outline(wmap, wmap.feasible & np.isfinite(raw))))


def _within(segment, limits) -> tuple:
    """A segment ``(x0, x1, y0, y1)`` (mm) clamped to the axes ``limits`` (x0, x1, y0, y1)."""
    x = np.clip(segment[:2], min(limits[:2]), max(limits[:2]))
    y = np.clip(segment[2:], min(limits[2:]), max(limits[2:]))
    return (float(x[0]), float(x[1]), float(y[0]), float(y[1]))


def map_picture(panels, quantity: str, preset_or_title, *, scale: ColourScale | None = None, limits=None,
                narrow: bool = False) -> MapPicture:
    """Every panel of the map view on ONE colour scale, and its colour bar (``figures.draw_panels``'s rule).

    Parameters
    ----------
    panels : sequence of (title, WorkspaceMap, values or None)
        As ``figures.draw_panels`` takes them; a panel titled "reference..." is the pinned one.
    quantity, preset_or_title
        As ``panel_picture``.
    scale : ColourScale, optional
        A colour scale to use (a 3D box's, spanning its whole volume); default one spanning
        every panel's feasible values.
    limits : sequence, optional
        Per panel, the axes limits (mm) or None.
    narrow : bool
        As ``panel_picture``.
    """
    picture = MapPicture(quantity=quantity)
    if not panels:
        return picture
    difference = any(values is not None for _, _, values in panels)
    if scale is None:
        layers = [(values if values is not None else wmap.values[quantity], wmap.feasible)
                  for _, wmap, values in panels]
        scale = colour_scale(quantity, preset_or_title, layers, difference=difference)
    limits = list(limits) if limits is not None else [None] * len(panels)
    for (title, wmap, values), lim in zip(panels, limits):
        panel = panel_picture(wmap, quantity, preset_or_title, scale, values=values, title=title, limits=lim,
                              narrow=narrow)
        panel.reference = title.startswith("reference")
        picture.panels.append(panel)
    picture.bar = colour_bar(scale)
    return picture
