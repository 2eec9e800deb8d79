"""A PyVista scene as a publication figure: cropped to its content, with a scale bar, axes and legible text.

The 3D views of ``isoforce figure`` and the app's export used to be a screenshot of the
whole window: the device in the middle of a mostly empty canvas, no scale, VTK text a
fixed number of points high however large the image. Here the scene is rendered once in
a parallel projection at exactly the pixels its content needs (``fit_camera``: the
actors' points projected on the view plane, so no probe render and no empty margin), and
matplotlib composes the picture with a title, a scale bar in mm, an axes triad, a colour
bar and the caption, with fonts a fixed share of the image height. PNG, SVG and PDF are
written by matplotlib, the 3D picture embedded as one raster image: a PDF of a pose is
tens of kB, where VTK's GL2PS vector export wrote every triangle (5.7 MB).

A parallel projection has one scale everywhere, so the scale bar holds for every length
parallel to the image plane (a perspective view would have none).
"""
from __future__ import annotations

import functools
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib import colors, rc_context, ticker
from matplotlib.backends.backend_agg import FigureCanvasAgg, RendererAgg
from matplotlib.colorbar import ColorbarBase
from matplotlib.figure import Figure
from matplotlib.font_manager import FontProperties
from matplotlib.image import imsave

from app.files.export import atomic_write
from app.logic.ticks import log_ticks, round_below

#: Font heights as shares of the requested image height (a 1200 px image: 26 px caption).
TITLE_SHARE, TEXT_SHARE = 0.026, 0.022
#: Smallest font (px) for small images, still readable on screen.
MIN_FONT_PX = 9.0
#: Empty border around the content, as a share of the picture's smaller side.
MARGIN_SHARE = 0.03
DPI = 100.0
AXIS_COLOURS = {"x": "#d62728", "y": "#2ca02c", "z": "#1f77b4"}


def use_headless_gl() -> None:
    """Render through EGL when there is no display, before the first render window is made.

    VTK (9.4+) picks its OpenGL window at run time and tries X first: with no display that
    fails with a ``bad X server connection`` warning on stderr before it falls back to EGL.
    ``VTK_DEFAULT_OPENGL_WINDOW`` (VTK's documented override) makes it go to EGL directly.
    With a display (the desktop app, a test under Xvfb) nothing is changed.
    """
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")


def _view_basis(camera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit vectors (3,) of the screen's right and up, and the viewing direction."""
    camera.OrthogonalizeViewUp()
    d = np.asarray(camera.GetDirectionOfProjection(), float)
    up = np.asarray(camera.GetViewUp(), float)
    right = np.cross(d, up)
    return right / np.linalg.norm(right), up / np.linalg.norm(up), d / np.linalg.norm(d)


def _scene_points(plotter) -> np.ndarray:
    """Every point (k, 3) of every visible mesh actor of the plotter, in m."""
    chunks = []
    for actor in plotter.renderer.actors.values():
        mapper = getattr(actor, "mapper", None)
        dataset = getattr(mapper, "dataset", None)
        if dataset is None or not actor.GetVisibility() or dataset.n_points == 0:
            continue
        chunks.append(np.asarray(dataset.points, float))
    return np.concatenate(chunks) if chunks else np.zeros((0, 3))


def fit_camera(plotter, max_size: tuple[int, int]) -> tuple[tuple[int, int], float]:
    """Aim a parallel camera at the content and size the window to it; return (pixels, px per m).

    The content's box on the view plane (its points projected on the camera's right and up
    vectors) fills ``max_size`` (w, h) in one direction, less a margin; the window is cut
    to the box in the other. The camera's direction is kept.
    """
    camera = plotter.camera
    camera.SetParallelProjection(True)
    points = _scene_points(plotter)
    w_max, h_max = max_size
    if len(points) == 0:
        plotter.window_size = [w_max, h_max]
        return (w_max, h_max), float("nan")
    right, up, d = _view_basis(camera)
    focal = np.asarray(camera.GetFocalPoint(), float)
    u, v = (points - focal) @ right, (points - focal) @ up
    width, height = max(np.ptp(u), 1e-9), max(np.ptp(v), 1e-9)
    margin = MARGIN_SHARE * min(w_max, h_max)
    px_per_m = min((w_max - 2 * margin) / width, (h_max - 2 * margin) / height)
    w_px = int(min(w_max, np.ceil(width * px_per_m + 2 * margin)))
    h_px = int(min(h_max, np.ceil(height * px_per_m + 2 * margin)))
    centre = focal + right * (u.min() + u.max()) / 2 + up * (v.min() + v.max()) / 2
    distance = camera.GetDistance()
    camera.SetFocalPoint(*centre)
    camera.SetPosition(*(centre - d * distance))
    camera.SetParallelScale(h_px / (2.0 * px_per_m))
    plotter.window_size = [w_px, h_px]
    plotter.renderer.ResetCameraClippingRange()
    return (w_px, h_px), px_per_m


def colour_bar_of(plotter, name: str = "workspace") -> dict | None:
    """The colours, range, log flag and title of actor ``name``'s scalars, and its VTK bar removed."""
    actor = plotter.actors.get(name)
    mapper = getattr(actor, "mapper", None)
    if mapper is None or not plotter.scalar_bars or not mapper.GetScalarVisibility():
        return None
    title = next(iter(plotter.scalar_bars.keys()))
    lut = mapper.lookup_table
    # One line: the figure's bar is as wide as the picture, and its layout leaves one line for the
    # title (the narrow app view's bar puts the colour cap on a second line).
    bar = {"colours": np.asarray(lut.values, float) / 255.0, "range": tuple(mapper.scalar_range),
           "log": bool(lut.log_scale), "title": title.replace("\n", ", ")}
    plotter.remove_scalar_bar()
    return bar


def _text_width(text: str, font_px: float) -> float:
    """Width in px of ``text`` in matplotlib's default font at ``font_px`` (Agg's own measure)."""
    return _measure().get_text_width_height_descent(text, FontProperties(size=font_px * 72.0 / DPI), ismath=False)[0]


@functools.lru_cache(maxsize=1)
def _measure():
    return RendererAgg(8, 8, DPI)


#: Spaces the caption's word wrap must not break (made non-breaking): a number and its unit
#: ("12.6 N", "0.0612 N m"), a word and the number it names ("condition 1.58"), and both
#: sides of "=" ("1 m/s = 250 mm"): lines wrapped there read "0.0612 N" / "m", "condition" /
#: "1.58" or "1 m/s" / "= 250 mm". Short phrases only: the app's caption breaks a glued phrase
#: wider than its view again, and so does ``_text_block``.
CAPTION_GLUE = re.compile(r"(?<=\d) (?=(?:N m|N|mm|m/s|m|kg|deg|µm|rad|%)(?![\w/]))|(?<=\bN) (?=m\b)"
                          r"|(?<==) (?=[-+]?\d)|(?<=\S) (?==)|(?<=[A-Za-z]) (?=[-+]?\d)")


def _text_block(text: str, font_px: float, width_px: float) -> list[str]:
    """``text``'s lines, each wrapped at spaces (greedily) to fit ``width_px``, never inside a
    phrase ``CAPTION_GLUE`` keeps together unless the phrase alone is wider than that.

    >>> _text_block("at zero force: isotropic moment 0.347 N m, anisotropic 0.869 N m", 10.0, 300.0)
    ['at zero force: isotropic moment 0.347 N m,', 'anisotropic 0.869 N m']
    """
    lines = []
    for line in CAPTION_GLUE.sub("\u00a0", text).splitlines():
        current = ""
        words = [part for word in line.split(" ")
                 for part in (word.split("\u00a0") if _text_width(word, font_px) > width_px else [word])]
        for word in words:
            trial = f"{current} {word}" if current else word
            if current and _text_width(trial, font_px) > width_px:
                lines.append(current)
                current = word
            else:
                current = trial
        lines.append(current)
    return [line.replace("\u00a0", " ") for line in lines]     # plain spaces in the file's text


def scene_figure(plotter, max_size: tuple[int, int], *, title: str = "", caption: str = "",
                 colour_bar: dict | None = None, axes: str = "xyz") -> Figure:
    """Render ``plotter`` cropped to its content and compose the figure; at most ``max_size`` pixels.

    Parameters
    ----------
    plotter : pyvista.Plotter
        An off-screen plotter with the scene drawn (and no VTK text, axes widget or scalar bar).
    max_size : (int, int)
        Largest width and height of the figure, px.
    title, caption : str
        Text above and below the picture (the caption may hold several lines).
    colour_bar : dict, optional
        ``colour_bar_of``'s description: drawn as a horizontal bar under the picture.
    axes : str
        Which axes the triad shows (``"xy"`` for a planar device seen from above).

    Returns
    -------
    SceneFigure
        The figure (Agg canvas, sized in pixels at ``DPI``) with the picture beside it, to
        be pasted in (PNG) or embedded (SVG, PDF) by ``SceneFigure.save``.
    """
    w_max, h_max = max_size
    title_px = max(MIN_FONT_PX, TITLE_SHARE * h_max)
    text_px = max(MIN_FONT_PX, TEXT_SHARE * h_max)
    line = 1.35
    # Text first: its lines, wrapped to the widest the figure may be, fix the picture's room.
    lines = _text_block(caption, text_px, w_max - 2 * text_px) if caption else []
    head = line * title_px * (1 if title else 0) + 0.5 * text_px
    bar_h = 5.0 * text_px if colour_bar else 0.0     # bar, tick labels, its title
    strip_h = 4.2 * text_px               # the scale bar and the axes triad, under the picture
    foot = line * text_px * len(lines) + 0.5 * text_px
    _, px_per_m = fit_camera(plotter, (w_max, max(32, int(h_max - head - strip_h - bar_h - foot))))
    image = plotter.screenshot(None, return_img=True)
    ph, pw = image.shape[:2]
    # Narrow content: the figure is as wide as the picture or its text, whichever is wider.
    text_w = max([_text_width(s, text_px) for s in lines] + [_text_width(title, title_px)]) + 2 * text_px
    fig_w = int(min(w_max, np.ceil(max(pw, text_w, 24 * text_px if colour_bar else 0))))
    fig_h = int(np.ceil(head + ph + strip_h + bar_h + foot))
    fig = Figure(figsize=(fig_w / DPI, fig_h / DPI), dpi=DPI)
    FigureCanvasAgg(fig)
    pt = 72.0 / DPI                                  # points per pixel
    left = (fig_w - pw) / 2
    picture = (image, int(round(left)), int(round(foot + bar_h + strip_h)))
    if title:
        fig.text(0.5, 1 - 0.5 * line * title_px / fig_h, title, ha="center", va="center", fontsize=title_px * pt)
    for k, text in enumerate(lines):
        fig.text(0.5, (foot - (k + 0.75) * line * text_px) / fig_h, text, ha="center", va="center",
                 fontsize=text_px * pt)
    strip = fig.add_axes((0.0, (foot + bar_h) / fig_h, 1.0, strip_h / fig_h))
    strip.set_xlim(0, fig_w)                        # in pixels, as the picture
    strip.set_ylim(0, strip_h)
    strip.set_axis_off()
    if np.isfinite(px_per_m):              # (nothing drawn, e.g. an unreachable pose: no scale, no axes)
        _scale_bar(strip, px_per_m, left, pw, text_px)
        _triad(strip, plotter, axes, left + pw, text_px)
    if colour_bar:
        cax = fig.add_axes((0.2, (foot + 3.4 * text_px) / fig_h, 0.6, 0.9 * text_px / fig_h))
        _colour_bar(cax, colour_bar, text_px * pt)
    return SceneFigure(fig, *picture)


def _scale_bar(strip, px_per_m: float, left: float, pw: int, text_px: float) -> None:
    """A bar of a round length in mm, about a fifth of the picture wide, under its left side."""
    length_mm = round_below(max(0.2 * pw, 4 * text_px) / px_per_m * 1e3)
    length_px = length_mm * 1e-3 * px_per_m
    x0, y0 = max(left, 0.5 * text_px), 1.3 * text_px
    strip.plot([x0, x0 + length_px], [y0, y0], color="black", linewidth=3, solid_capstyle="butt")
    strip.text(x0 + length_px / 2, y0 + 0.4 * text_px, f"{length_mm:g} mm", ha="center", va="bottom",
               fontsize=text_px * 72.0 / DPI)


def _triad(strip, plotter, axes: str, right_edge: float, text_px: float) -> None:
    """Arrows of the world axes as the camera sees them, under the picture's right side."""
    right, up, _ = _view_basis(plotter.camera)
    size = 1.4 * text_px          # labels at 1.3 size from the origin: inside the strip's 4.2 text_px
    origin = np.array([right_edge - 2.8 * size, 1.6 * text_px])
    for name in axes:
        e = np.eye(3)["xyz".index(name)]
        vec = np.array([e @ right, e @ up]) * size
        if np.hypot(*vec) < 0.2 * size:          # seen end-on: no arrow, it would point nowhere
            continue
        strip.annotate("", origin + vec, origin, arrowprops={"arrowstyle": "-|>", "color": AXIS_COLOURS[name],
                                                             "linewidth": 1.5})
        strip.text(*(origin + 1.3 * vec), name, color=AXIS_COLOURS[name], ha="center", va="center",
                   fontsize=text_px * 72.0 / DPI)


def _colour_bar(cax, bar: dict, font_pt: float) -> None:
    lo, hi = bar["range"]
    norm = colors.LogNorm(lo, hi) if bar["log"] and lo > 0 else colors.Normalize(lo, hi)
    cbar = ColorbarBase(cax, cmap=colors.ListedColormap(bar["colours"]), norm=norm, orientation="horizontal")
    cbar.set_label(bar["title"], fontsize=font_pt)
    if isinstance(norm, colors.LogNorm):
        # The map's ticks (1, 2, 5, 10, ...: plain numbers, not 10^1), so the two keys read alike.
        ticks = log_ticks(lo, hi)
        cbar.set_ticks(ticks, labels=[f"{t:.3g}" for t in ticks])
        cax.xaxis.set_minor_formatter(ticker.NullFormatter())
    cax.tick_params(labelsize=font_pt)


@dataclass(frozen=True)
class SceneFigure:
    """A composed figure and its 3D picture: ``image`` (h, w, 3) uint8 with its lower-left corner at (xo, yo) px."""

    figure: Figure
    image: np.ndarray
    xo: int
    yo: int

    def png_pixels(self) -> np.ndarray:
        """The figure as RGBA pixels (H, W, 4) uint8, the picture pasted in as it was rendered.

        Pasted into the canvas's buffer rather than drawn by ``figimage``: matplotlib's image
        path copies a picture of a few megapixels to float RGBA several times (150 MB, 0.3 s).
        """
        self.figure.canvas.draw()
        pixels = np.array(self.figure.canvas.buffer_rgba())
        h, w = self.image.shape[:2]
        top = pixels.shape[0] - self.yo - h
        pixels[top:top + h, self.xo:self.xo + w, :3] = self.image
        pixels[top:top + h, self.xo:self.xo + w, 3] = 255
        return pixels

    def save(self, path: Path) -> Path:
        """Write PNG, SVG or PDF (by suffix) through ``atomic_write``; SVG and PDF embed the picture as one raster."""
        fmt = path.suffix.lower().lstrip(".")
        if fmt == "png":
            pixels = self.png_pixels()
            # zlib level 3, not PIL's 6: a third of the encoding time for a file ~20 % larger.
            return atomic_write(path, lambda tmp: imsave(tmp, pixels, format="png", dpi=DPI,
                                                         pil_kwargs={"compress_level": 3}))
        rgba = np.concatenate([self.image, np.full(self.image.shape[:2] + (1,), 255, np.uint8)], axis=-1)
        self.figure.figimage(rgba, xo=self.xo, yo=self.yo, origin="upper")

        def write(tmp: Path) -> None:
            # SVG text stays text (as VTK's exporter wrote it): searchable, editable in a paper.
            with rc_context({"svg.fonttype": "none"}):
                self.figure.savefig(tmp, format=fmt, dpi=DPI)

        return atomic_write(path, write)
