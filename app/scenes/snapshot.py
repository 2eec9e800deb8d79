"""A PyVista scene as a publication figure: cropped to its content, with a scale bar, axes and legible text.

The 3D views of ``isoforce figure`` and the app's export used to be a screenshot of the
whole window: the device in the middle of a mostly empty canvas, no scale, VTK text a
fixed number of points high however large the image. Here the scene is rendered once in
a parallel projection at exactly the pixels its content needs (``fit_camera``: the
actors' points projected on the view plane, so no probe render and no empty margin), and
matplotlib composes the picture with a title, a scale bar in mm, an axes triad, a colour
bar and the caption, with fonts a fixed share of the image height. PNG, SVG and PDF are
written by matplotlib: its text, scale bar, axes triad, colour bar and legend are vector
graphics in SVG and PDF, and the 3D picture is embedded as one raster image (``RASTER_NOTE``).

VTK cannot do better here: its GL2PS exporter (``vtkGL2PSExporter``, PyVista's
``Plotter.save_graphic``) writes only 2D props (text actors, 2D charts) as vectors on VTK's
OpenGL2 back-end; every 3D prop (the meshes, lines and glyphs of these scenes) it writes as a
raster of the window, with or without ``Write3DPropsAsRasterImage`` and with the prop in its
``RasterExclusions`` (tested with VTK 9.7 off-screen through EGL and on an X server), and it
exports with ``GL2PS_NO_BLENDING``, so a translucent surface (the force polytope, the
reachable hull, iso-surfaces) would be opaque even where it did write vectors. So matplotlib
draws everything but the scene, as vectors, and the scene is the raster.

``column`` (``scene_figure``) lays the figure out for a journal column: exactly ``width_in``
inches wide, every text at ``font_pt`` points, the picture rendered at ``PRINT_DPI`` for that
size (its lines as thick as on screen).

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
#: The 3D picture's resolution in a figure laid out for a column (``scene_figure``'s ``column``).
PRINT_DPI = 300.0
#: matplotlib's colour bar tick length, tick label pad and axis label pad (points, its defaults).
TICK_PADS_PT = 3.5 + 3.5 + 4.0
#: The tallest a column figure's picture may be, as a share of the column's width.
COLUMN_PICTURE_ASPECT = 1.1
#: What a 3D view's SVG or PDF holds (``isoforce figure`` prints it beside the file's name).
RASTER_NOTE = "3D picture embedded as a raster image: VTK exports 3D geometry as pixels only; text is vector"
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
        # A line that fits is kept whole, measured once: word by word would keep it too (no part
        # of a line, a word or a run of words, is wider than the whole line). Not one that starts
        # with a space: word by word drops that.
        if not line.startswith(" ") and _text_width(line, font_px) <= width_px:
            lines.append(line)
            continue
        # Only a glued phrase (one holding a no-break space) can be split, so only those are measured.
        words = [part for word in line.split(" ")
                 for part in (word.split("\u00a0") if "\u00a0" in word and _text_width(word, font_px) > width_px
                              else [word])]
        while words:
            count = _words_that_fit(words, font_px, width_px)
            lines.append(_joined(words[:count]))
            words = words[count:]
    return [line.replace("\u00a0", " ") for line in lines]     # plain spaces in the file's text


def _joined(words: list[str]) -> str:
    """``words`` as the wrap joins them: one space after each, none after an empty start."""
    return functools.reduce(lambda line, word: f"{line} {word}" if line else word, words, "")


def _words_that_fit(words: list[str], font_px: float, width_px: float) -> int:
    """How many of ``words`` (at least one) the greedy wrap puts on a line of ``width_px``.

    Word by word, the wrap ends a line before the first word that takes a non-empty line past
    the width. Each longer line holds the shorter one as its start, so its width never shrinks
    and that first word is found by bisection: a few measures (FreeType lays the text out each
    time) where adding words one at a time took one per word.
    """
    lo, hi = 1, len(words)
    while lo < hi:
        mid = (lo + hi) // 2
        head = _joined(words[:mid])
        if head and _text_width(_joined(words[:mid + 1]), font_px) > width_px:
            hi = mid
        else:
            lo = mid + 1
    return lo


def scene_figure(plotter, max_size: tuple[int, int] | None, *, title: str = "", caption: str = "",
                 colour_bar: dict | None = None, axes: str = "xyz", column: tuple[float, float] | None = None,
                 print_dpi: float = PRINT_DPI, legend_names=None) -> "SceneFigure":
    """Render ``plotter`` cropped to its content and compose the figure; at most ``max_size`` pixels.

    Parameters
    ----------
    plotter : pyvista.Plotter
        An off-screen plotter with the scene drawn (and no VTK text, axes widget or scalar bar).
    max_size : (int, int)
        Largest width and height of the figure, px (ignored with ``column``).
    title, caption : str
        Text above and below the picture (the caption may hold several lines).
    colour_bar : dict, optional
        ``colour_bar_of``'s description: drawn as a horizontal bar under the picture.
    axes : str
        Which axes the triad shows (``"xy"`` for a planar device seen from above).
    column : (float, float), optional
        ``(width in inches, font size in points)``: the figure exactly that wide, its text at
        that size (the title a little larger), the picture at most ``COLUMN_PICTURE_ASPECT``
        times the width tall and rendered at ``print_dpi``.
    legend_names : sequence of str, optional
        Names a legend will take the colour bar's place with (``app.render.views``): the bar's
        band is made tall enough for them at the text size (``legend_lines``).

    Returns
    -------
    SceneFigure
        The figure (Agg canvas, laid out in pixels at ``DPI``) with the picture beside it, to
        be pasted in (PNG) or embedded (SVG, PDF) by ``SceneFigure.save``.
    """
    line = 1.35
    if column is None:
        w_max, h_max = max_size
        title_px = max(MIN_FONT_PX, TITLE_SHARE * h_max)
        text_px = max(MIN_FONT_PX, TEXT_SHARE * h_max)
        scale = 1.0
    else:
        width_in, font_pt = column
        w_max = width_in * DPI
        text_px = font_pt * DPI / 72.0
        title_px = text_px * TITLE_SHARE / TEXT_SHARE
        scale = print_dpi / DPI
    # Text first: its lines, wrapped to the widest the figure may be, fix the picture's room.
    lines = _text_block(caption, text_px, w_max - 2 * text_px) if caption else []
    titles = _text_block(title, title_px, w_max - 2 * text_px) if title else []
    head = line * title_px * len(titles) + 0.5 * text_px
    # The colour bar's ticks and label pads are points, not a share of the text: small text (a
    # column's) needs them added to the bar's room (at a screen figure's size they fit in it).
    ticks_px = (TICK_PADS_PT * DPI / 72.0) if column is not None else 0.0
    bar_h = 5.0 * text_px + ticks_px if colour_bar else 0.0     # bar, tick labels, its title
    if colour_bar and legend_names:
        # A column's band is the legend's (no gap under a short one); a screen figure keeps its bar's room.
        needed = legend_lines(legend_names, text_px, w_max) * text_px
        bar_h = needed if column is not None else max(bar_h, needed)
    strip_h = 4.2 * text_px               # the scale bar and the axes triad, under the picture
    foot = line * text_px * len(lines) + 0.5 * text_px
    if column is None:
        room = (w_max, max(32, int(h_max - head - strip_h - bar_h - foot)))
    else:
        room = (w_max, COLUMN_PICTURE_ASPECT * w_max)
        _thicken_lines(plotter, scale)
    window, px_per_m = fit_camera(plotter, (int(room[0] * scale), max(32, int(room[1] * scale))))
    image = plotter.screenshot(None, return_img=True)
    pw, ph = image.shape[1] / scale, image.shape[0] / scale       # the picture's room in the layout, px
    px_per_m /= scale
    if column is None:
        # Narrow content: the figure is as wide as the picture or its text, whichever is wider.
        text_w = max([_text_width(s, text_px) for s in lines] + [_text_width(s, title_px) for s in titles],
                     default=0.0) + 2 * text_px
        fig_w = int(min(w_max, np.ceil(max(pw, text_w, 24 * text_px if colour_bar else 0))))
        fig_h = int(np.ceil(head + ph + strip_h + bar_h + foot))
    else:
        fig_w = w_max                       # the column's width exactly
        fig_h = head + ph + strip_h + bar_h + foot
    fig = Figure(figsize=(fig_w / DPI, fig_h / DPI), dpi=DPI)
    FigureCanvasAgg(fig)
    pt = 72.0 / DPI                                  # points per pixel
    left = (fig_w - pw) / 2
    bottom = foot + bar_h + strip_h
    for k, text in enumerate(titles):
        fig.text(0.5, 1 - (k + 0.5) * line * title_px / fig_h, text, ha="center", va="center", fontsize=title_px * pt)
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
        cax = fig.add_axes((0.2, (foot + 3.4 * text_px + ticks_px) / fig_h, 0.6, 0.9 * text_px / fig_h))
        _colour_bar(cax, colour_bar, text_px * pt)
    band = (foot, foot + bar_h) if colour_bar else None
    if column is None:
        return SceneFigure(fig, image, int(round(left)), int(round(bottom)), band=band)
    return SceneFigure(fig, image, left, bottom, scale, band)


def legend_lines(names, font_px: float, width_px: float) -> float:
    """Text lines (of ``font_px``) a legend of ``names`` under its title takes at that size, in as
    many columns as fit ``width_px`` (``app.render.views``' legend: swatch 1.2 em, gap 0.8 em,
    columns 1.2 em apart, rows 0.3 em apart)."""
    column = max(_text_width(str(n), font_px) for n in names) + 3.2 * font_px
    columns = max(1, min(len(names), int((0.96 * width_px + 1.2 * font_px) // column)))
    rows = -(-len(names) // columns)
    return 1.2 * (rows + 1) + 0.3 * rows + 0.8


def _thicken_lines(plotter, scale: float) -> None:
    """Line widths and point sizes (pixels) of every actor times ``scale``: a picture rendered at
    ``scale`` times the layout's pixels draws its lines as thick as the screen does."""
    if scale == 1.0:
        return
    for actor in plotter.renderer.actors.values():
        prop = getattr(actor, "GetProperty", None)
        prop = prop() if prop is not None else None
        if prop is not None and hasattr(prop, "GetLineWidth"):
            prop.SetLineWidth(prop.GetLineWidth() * scale)
            prop.SetPointSize(prop.GetPointSize() * scale)


def _scale_bar(strip, px_per_m: float, left: float, pw: int, text_px: float) -> None:
    """A bar of a round length in mm, about a fifth of the picture wide, under its left side."""
    length_mm = round_below(max(0.2 * pw, 4 * text_px) / px_per_m * 1e3)
    length_px = length_mm * 1e-3 * px_per_m
    label = f"{length_mm:g} mm"
    # Its label, centred over the bar, kept inside the figure when the bar is shorter than it.
    x0 = max(left, 0.5 * text_px, 0.5 * (_text_width(label, text_px) - length_px) + 0.5 * text_px)
    y0 = 1.3 * text_px
    strip.plot([x0, x0 + length_px], [y0, y0], color="black", linewidth=3, solid_capstyle="butt")
    strip.text(x0 + length_px / 2, y0 + 0.4 * text_px, label, ha="center", va="bottom",
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
        # Heads at most matplotlib's default size (10 pt), smaller with small text (a column's).
        strip.annotate("", origin + vec, origin, arrowprops={"arrowstyle": "-|>", "color": AXIS_COLOURS[name],
                                                             "linewidth": 1.5,
                                                             "mutation_scale": min(10.0, 0.6 * text_px * 72.0 / DPI)})
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
    """A composed figure and its 3D picture: ``image`` (h, w, 3) uint8 with its lower-left corner
    at (xo, yo) px of the figure's layout, ``scale`` image pixels to a layout pixel (``PRINT_DPI`` /
    ``DPI`` in a column figure, else 1); ``more`` further pictures as ``(image, xo, yo)`` (the
    panels of a figure of several scenes)."""

    figure: Figure
    image: np.ndarray
    xo: float
    yo: float
    scale: float = 1.0
    #: The colour bar's band (bottom, top) px of the layout, where a legend may take its place.
    band: tuple[float, float] | None = None
    more: tuple = ()

    def pictures(self) -> list[tuple[np.ndarray, float, float]]:
        return [(self.image, self.xo, self.yo), *self.more]

    def png_pixels(self) -> np.ndarray:
        """The figure as RGBA pixels (H, W, 4) uint8, the pictures pasted in as they were rendered.

        Pasted into the canvas's buffer rather than drawn by ``figimage``: matplotlib's image
        path copies a picture of a few megapixels to float RGBA several times (150 MB, 0.3 s).
        A column figure is drawn at the picture's resolution (``scale`` times ``DPI``).
        """
        if self.scale != 1.0:
            self.figure.set_dpi(DPI * self.scale)
        self.figure.canvas.draw()
        pixels = np.array(self.figure.canvas.buffer_rgba())
        for image, x0, y0 in self.pictures():
            h, w = min(image.shape[0], pixels.shape[0]), min(image.shape[1], pixels.shape[1])
            xo = max(0, min(int(round(x0 * self.scale)), pixels.shape[1] - w))
            top = max(0, pixels.shape[0] - int(round(y0 * self.scale)) - h)
            pixels[top:top + h, xo:xo + w, :3] = image[:h, :w]
            pixels[top:top + h, xo:xo + w, 3] = 255
        return pixels

    def save(self, path: Path) -> Path:
        """Write PNG, SVG or PDF (by suffix) through ``atomic_write``; SVG and PDF embed each picture
        as one raster image (``RASTER_NOTE``) at its own resolution, everything else as vectors."""
        fmt = path.suffix.lower().lstrip(".")
        if fmt == "png":
            pixels = self.png_pixels()
            dpi = DPI * self.scale
            # zlib level 3, not PIL's 6: a third of the encoding time for a file ~20 % larger.
            return atomic_write(path, lambda tmp: imsave(tmp, pixels, format="png", dpi=dpi,
                                                         pil_kwargs={"compress_level": 3}))
        for image, x0, y0 in self.pictures():
            if self.scale == 1.0:
                rgba = np.concatenate([image, np.full(image.shape[:2] + (1,), 255, np.uint8)], axis=-1)
                self.figure.figimage(rgba, xo=x0, yo=y0, origin="upper")
                continue
            # An axes the picture's size in the layout: the image keeps its pixels (interpolation
            # "none" embeds it unsampled in PDF and SVG), PRINT_DPI at the page's size.
            w, h = self.figure.get_size_inches() * DPI
            ph, pw = image.shape[0] / self.scale, image.shape[1] / self.scale
            ax = self.figure.add_axes((x0 / w, y0 / h, pw / w, ph / h))
            ax.imshow(image, interpolation="none", aspect="auto")
            ax.set_axis_off()

        def write(tmp: Path) -> None:
            # SVG text stays text (as VTK's exporter wrote it): searchable, editable in a paper.
            with rc_context({"svg.fonttype": "none"}):
                self.figure.savefig(tmp, format=fmt, dpi=DPI)

        return atomic_write(path, write)
