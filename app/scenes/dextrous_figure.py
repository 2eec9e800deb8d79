"""Semi-dextrous regions drawn in 3D (PyVista, off-screen): one device, or several side by side.

``region_mesh`` is the surface the app's 3D workspace view can show: the 0.5 iso-surface of the
region's indicator (1 inside, 0 outside) over the grid, padded by one layer of zeros so it
closes at the box, then Taubin-smoothed (which smooths the marching-cubes steps without
shrinking the body). Coordinates are in mm. The reported volume is the grid count
(``metrics.dextrous.indicator_volume``), not this surface's volume.

``panel_plotter`` draws one region (solid) with its constant-orientation workspace (the
positions reachable at zero orientation, translucent), the base origin and the outline of the
box all panels share; ``dextrous_figure`` renders one such panel per device, side by side on one
scale and from one direction (parallel projection, cropped by ``snapshot.fit_camera``), and
composes them with matplotlib as the other 3D figures are (``app.scenes.snapshot``): each
device's title and volumes above and under its picture, a scale bar in mm and an axes triad
under the pictures, and the key with the box's extent. Volumes carry the digits their grid error
supports (``app.logic.volume_digits``). ``save_dextrous_figure`` writes PNG, or SVG/PDF with
vector text and the pictures as rasters (``snapshot.RASTER_NOTE``), through
``app.files.export.atomic_write``. No Qt.

The figure was VTK's own before (a GL2PS export with VTK text and cube axes): the title lost
its second line, "+-" and the caption's line breaks went missing in the PDF, the axes' tick
labels ("-320.0", "-555.0") ran over each other and out of the picture.
"""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np
import pyvista as pv
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from app.files.export import FIGURE_SUFFIXES, check_suffix
from app.logic.volume_digits import volume_text
from app.scenes.snapshot import (
    COLUMN_PICTURE_ASPECT,
    DPI,
    MIN_FONT_PX,
    PRINT_DPI,
    TEXT_SHARE,
    TITLE_SHARE,
    SceneFigure,
    _scale_bar,
    _text_block,
    _thicken_lines,
    _triad,
    fit_camera,
    use_headless_gl,
)
from metrics.dextrous import LOWER_BOUND_NOTE, DextrousRegion

REGION_COLOUR = "#4a90d9"
REACHABLE_COLOUR = "#b0b0b0"
#: Pixels per panel when no size is given.
PANEL_SIZE = (900, 900)


def indicator_mesh(inside: np.ndarray, grid, *, smooth: int = 30) -> pv.PolyData:
    """The smoothed 0.5 iso-surface of a boolean grid (shape ``grid.resolution``), mm; empty if none.

    Parameters
    ----------
    inside : ndarray of bool, shape (i, j, k)
        The region on ``grid``.
    grid : GridSpec
        Axes x, y, z in m.
    smooth : int
        Taubin smoothing iterations (0: the raw marching-cubes surface).

    Returns
    -------
    pyvista.PolyData
        Triangles in mm.
    """
    mask = np.asarray(inside, bool)
    if not mask.any():
        return pv.PolyData()
    spacing = np.asarray(grid.spacing()) * 1e3
    origin = np.asarray(grid.lower) * 1e3 - spacing          # one padding layer below the box
    padded = np.pad(mask, 1, constant_values=False).astype(np.float64)
    image = pv.ImageData(dimensions=padded.shape, spacing=tuple(spacing), origin=tuple(origin))
    image.point_data["inside"] = padded.ravel(order="F")     # VTK's x-fastest point order
    surface = image.contour([0.5], scalars="inside")
    if smooth and surface.n_points:
        surface = surface.smooth_taubin(n_iter=smooth, pass_band=0.1)
    return surface


def region_mesh(region: DextrousRegion, *, smooth: int = 30) -> pv.PolyData:
    """The semi-dextrous region's surface, mm (``indicator_mesh`` of ``region.inside``).

    Parameters
    ----------
    region : DextrousRegion
        From ``metrics.dextrous.dextrous_region``.
    smooth : int
        Taubin smoothing iterations.

    Returns
    -------
    pyvista.PolyData
        Empty when the region is empty.
    """
    return indicator_mesh(region.inside, region.grid, smooth=smooth)


#: What the panels' colours are, said once under them.
KEY = "solid: semi-dextrous; grey: reachable at zero orientation; dot: base origin"


def caption(region: DextrousRegion, key: bool = True) -> str:
    """The lines under a panel: the volume with its grid error (or ">= V (clipped by the box)" when the
    region touches its box: a lower bound), the constant-orientation volume likewise, and (``key``)
    what the colours are. Digits to the error (``volume_digits``), cm^3."""
    v, r = region.volume, region.reachable_volume
    volume = volume_text(v.value * 1e6, v.error * 1e6, region.clipped, LOWER_BOUND_NOTE)
    reach = volume_text(r.value * 1e6, r.error * 1e6, region.reachable_clipped, LOWER_BOUND_NOTE)
    text = (f"semi-dextrous +-{np.degrees(region.orientations.angle):g} deg: {_unit(volume)}\n"
            f"reachable at zero orientation: {_unit(reach)}")
    return text + (f"\n({KEY})" if key else "")


def _unit(text: str) -> str:
    """``"V +- E"`` -> ``"V +- E cm^3"``; ``">= V (note)"`` -> ``">= V cm^3 (note)"``."""
    head, sep, tail = text.partition(" (")
    return f"{head} cm^3" + (f" ({tail}" if sep else "")


def _bounds(regions: Sequence[DextrousRegion]) -> np.ndarray:
    lo = np.min([np.asarray(r.grid.lower) for r in regions], axis=0) * 1e3
    hi = np.max([np.asarray(r.grid.upper) for r in regions], axis=0) * 1e3
    return np.stack([lo, hi], -1).ravel()


def box_text(bounds: np.ndarray) -> str:
    """``"box x -450 to 450, y -555 to 555, z -320 to 420 mm"`` (``bounds`` mm, as ``_bounds``)."""
    b = np.asarray(bounds, float).reshape(3, 2)
    return "box " + ", ".join(f"{a} {lo:.4g} to {hi:.4g}" for a, (lo, hi) in zip("xyz", b)) + " mm"


def panel_plotter(region: DextrousRegion, bounds, *, window=(PANEL_SIZE[0], PANEL_SIZE[1])) -> pv.Plotter:
    """An off-screen plotter with one region, its reachable set, the base origin and the box
    ``bounds`` (mm) outlined, seen from the isometric direction; no text. The caller closes it."""
    use_headless_gl()          # before the render window: no X attempt, no 'bad X server' line
    plotter = pv.Plotter(off_screen=True, window_size=list(window))
    plotter.set_background("white")
    bounds = np.asarray(bounds, float)
    reach = indicator_mesh(region.reachable, region.grid)
    if reach.n_points:
        plotter.add_mesh(reach, color=REACHABLE_COLOUR, opacity=0.18, name="reachable")
    body = region_mesh(region)
    if body.n_points:
        plotter.add_mesh(body, color=REGION_COLOUR, smooth_shading=True, specular=0.3, name="dextrous")
    plotter.add_mesh(pv.Box(bounds=tuple(bounds)).outline(), color="black", line_width=1, name="box")
    plotter.add_mesh(pv.Sphere(radius=0.01 * float(np.ptp(bounds.reshape(3, 2), axis=1).max()),
                               center=(0.0, 0.0, 0.0)), color="black", name="base_origin")
    plotter.view_isometric()
    plotter.reset_camera(bounds=tuple(bounds))
    return plotter


def dextrous_figure(regions: Sequence[DextrousRegion], titles: Sequence[str], *, size=None,
                    column: tuple[float, float] | None = None) -> SceneFigure:
    """One panel per region, side by side on one scale, composed with its text (``SceneFigure``).

    Parameters
    ----------
    regions : sequence of DextrousRegion
    titles : sequence of str
        One per region (a line break in one starts a second line).
    size : (int, int), optional
        The whole figure in pixels (default ``PANEL_SIZE`` per panel).
    column : (float, float), optional
        ``(width in inches, font size in points)``: laid out for a journal column instead, the
        pictures at ``snapshot.PRINT_DPI``.
    """
    n = len(regions)
    if n == 0 or len(titles) != n:
        raise ValueError(f"a dextrous figure needs one title per region, got {n} regions and {len(titles)} titles")
    line = 1.35
    if column is None:
        width, height = size if size is not None else (PANEL_SIZE[0] * n, PANEL_SIZE[1])
        text_px = max(MIN_FONT_PX, TEXT_SHARE * height)
        title_px = max(MIN_FONT_PX, TITLE_SHARE * height)
        scale = 1.0
    else:
        width, height = column[0] * DPI, None
        text_px = column[1] * DPI / 72.0
        title_px = text_px * TITLE_SHARE / TEXT_SHARE
        scale = PRINT_DPI / DPI
    panel = width / n
    bounds = _bounds(regions)
    heads = [_text_block(t, title_px, panel - text_px) for t in titles]
    feet = [_text_block(caption(r, key=False), text_px, panel - text_px) for r in regions]
    key = _text_block(f"{KEY}; {box_text(bounds)}", text_px, width - 2 * text_px)
    head_h = line * title_px * max(map(len, heads)) + 0.5 * text_px
    foot_h = line * text_px * max(map(len, feet)) + 0.3 * text_px
    strip_h = 4.2 * text_px
    key_h = line * text_px * len(key) + 0.5 * text_px
    text_h = head_h + foot_h + strip_h + key_h
    room = (panel - 0.5 * text_px, (height - text_h) if column is None else COLUMN_PICTURE_ASPECT * panel)
    window = (max(32, int(room[0] * scale)), max(32, int(room[1] * scale)))
    plotters, images = [], []
    try:
        for region in regions:
            plotters.append(panel_plotter(region, bounds, window=window))
            _thicken_lines(plotters[-1], scale)
            # Every panel holds the same box outline: the same crop and scale (px per m) for each.
            _, px_per_m = fit_camera(plotters[-1], window)
            images.append(plotters[-1].screenshot(None, return_img=True))
        ph = max(image.shape[0] for image in images) / scale
        pw = max(image.shape[1] for image in images) / scale
        fig_h = height if column is None else text_h + ph
        fig = Figure(figsize=(width / DPI, fig_h / DPI), dpi=DPI)
        FigureCanvasAgg(fig)
        pt = 72.0 / DPI
        picture_y = key_h + strip_h + foot_h + max(0.0, (fig_h - text_h - ph) / 2)
        pictures = []
        for i, (image, head, foot) in enumerate(zip(images, heads, feet)):
            centre = (i + 0.5) * panel
            for k, text in enumerate(head):
                fig.text(centre / width, 1 - (k + 0.5) * line * title_px / fig_h, text, ha="center", va="center",
                         fontsize=title_px * pt)
            for k, text in enumerate(foot):
                fig.text(centre / width, (key_h + strip_h + foot_h - (k + 0.6) * line * text_px) / fig_h, text,
                         ha="center", va="center", fontsize=text_px * pt)
            pictures.append((image, centre - image.shape[1] / scale / 2, picture_y))
        for k, text in enumerate(key):
            fig.text(0.5, (key_h - (k + 0.75) * line * text_px) / fig_h, text, ha="center", va="center",
                     fontsize=text_px * pt)
        strip = fig.add_axes((0.0, key_h / fig_h, 1.0, strip_h / fig_h))
        strip.set_xlim(0, width)
        strip.set_ylim(0, strip_h)
        strip.set_axis_off()
        left = pictures[0][1]
        if np.isfinite(px_per_m):
            _scale_bar(strip, px_per_m / scale * 1e3, left, pw, text_px)     # the mesh is in mm: px per mm
            _triad(strip, plotters[-1], "xyz", pictures[-1][1] + pw, text_px)
    finally:
        for plotter in plotters:
            plotter.close()
    (image, xo, yo), more = pictures[0], tuple(pictures[1:])
    return SceneFigure(fig, image, xo, yo, scale, more=more)


def save_dextrous_figure(regions: Sequence[DextrousRegion], titles: Sequence[str], path, *, size=None,
                         column: tuple[float, float] | None = None, name: str = "path") -> Path:
    """Write ``dextrous_figure`` to ``path`` (.png, .svg, .pdf), atomically.

    Parameters
    ----------
    regions, titles, size, column
        As ``dextrous_figure``.
    path : str or Path
        The target; its suffix picks the format.
    name : str
        The argument's name in error messages (``"--out"``).

    Returns
    -------
    Path
        ``path``.
    """
    target = check_suffix(path, FIGURE_SUFFIXES, name)
    return dextrous_figure(regions, titles, size=size, column=column).save(target)
