"""Semi-dextrous regions drawn in 3D (PyVista, off-screen): one device, or several side by side.

``region_mesh`` is the surface the app's 3D workspace view can show: the 0.5 iso-surface of the
region's indicator (1 inside, 0 outside) over the grid, padded by one layer of zeros so it
closes at the box, then Taubin-smoothed (which smooths the marching-cubes steps without
shrinking the body). Coordinates are in mm. The reported volume is the grid count
(``metrics.dextrous.indicator_volume``), not this surface's volume.

``dextrous_plotter`` draws each region (solid) with its constant-orientation workspace (the
positions reachable at zero orientation, translucent), the base origin and the box outline,
one panel per device, all panels on the same scale and view; ``save_dextrous_figure`` writes
PNG (screenshot) or SVG/PDF (VTK's GL2PS exporter) through ``app.files.export.atomic_write``.
No Qt.
"""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np
import pyvista as pv

from app.files.export import FIGURE_SUFFIXES, atomic_write, check_suffix
from app.scenes.snapshot import use_headless_gl
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


def _cm3(value_m3: float, digits: int = 4) -> str:
    text = f"{value_m3 * 1e6:.{digits}g}"
    return f"{float(text):.0f}" if "e+" in text else text


def caption(region: DextrousRegion) -> str:
    """The lines under a panel: the volume with its grid error (or ">= V (clipped by the box)" when the
    region touches its box: a lower bound), the constant-orientation volume likewise, a key."""
    v, r = region.volume, region.reachable_volume
    if region.clipped:
        volume = f">= {_cm3(v.value)} cm^3 ({LOWER_BOUND_NOTE})"
    else:
        volume = f"{_cm3(v.value)} +- {_cm3(v.error, 2)} cm^3"
    reach = f">= {_cm3(r.value)} cm^3 ({LOWER_BOUND_NOTE})" if region.reachable_clipped else f"{_cm3(r.value)} cm^3"
    text = (f"semi-dextrous +-{np.degrees(region.orientations.angle):g} deg: {volume}\n"
            f"reachable at zero orientation: {reach}")
    text += "\n(solid: semi-dextrous; grey: reachable at zero orientation; dot: base origin)"
    return text


def _bounds(regions: Sequence[DextrousRegion]) -> np.ndarray:
    lo = np.min([np.asarray(r.grid.lower) for r in regions], axis=0) * 1e3
    hi = np.max([np.asarray(r.grid.upper) for r in regions], axis=0) * 1e3
    return np.stack([lo, hi], -1).ravel()


def dextrous_plotter(regions: Sequence[DextrousRegion], titles: Sequence[str], *, size=None) -> pv.Plotter:
    """An off-screen plotter with one panel per region, side by side, on one scale.

    Parameters
    ----------
    regions : sequence of DextrousRegion
    titles : sequence of str
        One per region.
    size : (int, int), optional
        Window size in pixels (default ``PANEL_SIZE`` per panel).

    Returns
    -------
    pyvista.Plotter
        Off-screen; the caller closes it.
    """
    n = len(regions)
    if n == 0 or len(titles) != n:
        raise ValueError(f"dextrous_plotter needs one title per region, got {n} regions and {len(titles)} titles")
    window = list(size) if size is not None else [PANEL_SIZE[0] * n, PANEL_SIZE[1]]
    use_headless_gl()          # before the render window: no X attempt, no 'bad X server' line
    plotter = pv.Plotter(off_screen=True, shape=(1, n), window_size=window, border=False)
    plotter.set_background("white")
    bounds = _bounds(regions)
    box = pv.Box(bounds=tuple(bounds))
    for i, (region, title) in enumerate(zip(regions, titles)):
        plotter.subplot(0, i)
        reach = indicator_mesh(region.reachable, region.grid)
        if reach.n_points:
            plotter.add_mesh(reach, color=REACHABLE_COLOUR, opacity=0.18, name="reachable")
        body = region_mesh(region)
        if body.n_points:
            plotter.add_mesh(body, color=REGION_COLOUR, smooth_shading=True, specular=0.3, name="dextrous")
        plotter.add_mesh(box.outline(), color="black", line_width=1, name="box")
        plotter.add_mesh(pv.Sphere(radius=0.01 * float(np.ptp(bounds.reshape(3, 2), axis=1).max()),
                                   center=(0.0, 0.0, 0.0)), color="black", name="base_origin")
        plotter.add_text(title, font_size=11, color="black", position="upper_edge")
        plotter.add_text(caption(region), font_size=8, color="black", position="lower_left")
        plotter.show_bounds(bounds=tuple(bounds), xtitle="x (mm)", ytitle="y (mm)", ztitle="z (mm)",
                            color="black", font_size=12, grid=False, location="outer")
        plotter.view_isometric()
        plotter.reset_camera(bounds=tuple(bounds))
        plotter.camera.zoom(1.1)
    if n > 1:
        plotter.link_views()
    return plotter


def save_dextrous_figure(regions: Sequence[DextrousRegion], titles: Sequence[str], path, *, size=None,
                         name: str = "path") -> Path:
    """Write the figure of ``dextrous_plotter`` to ``path`` (.png, .svg, .pdf), atomically.

    Parameters
    ----------
    regions, titles, size
        As ``dextrous_plotter``.
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
    plotter = dextrous_plotter(regions, titles, size=size)
    fmt = target.suffix.lower()

    def write(tmp: Path) -> None:
        if fmt == ".png":
            plotter.screenshot(str(tmp))
        else:
            plotter.save_graphic(str(tmp), title="isoforce semi-dextrous workspace")

    try:
        return atomic_write(target, write, name=name)
    finally:
        plotter.close()
