"""Every view of the app, rendered off-screen to a file: the GUI's export and ``isoforce figure``.

Map and compare views are matplotlib figures (``app.plots.figures``); pose and workspace views
are PyVista scenes built by the same functions the Qt views use (``app.scenes``), in an
off-screen plotter, rendered cropped to their content and composed with a scale bar and
text by ``app.scenes.snapshot``. PNG at any size, SVG and PDF, all through matplotlib (a 3D view's
text, scale, legend and colour bar as vectors, its picture embedded as one raster image:
``raster_note``, and ``app.scenes.snapshot`` on why VTK's vector export cannot do better). With
``column`` every view is laid out for a journal column, a 3D view with its compact caption
(``compact_caption``). Every file is written through ``app.files.export.atomic_write``.
"""
from __future__ import annotations

import os
import re
import textwrap
from pathlib import Path

import numpy as np

from app import scenes
from app.files.export import FIGURE_SUFFIXES, atomic_write, check_suffix, write_map
from app.logic.display_units import display_unit
from app.logic.glyphs import DEFAULT_GLYPHS, pose_parts
from app.logic.planes import default_plane, is_volume, volume_slice
from app.scenes.snapshot import (
    DPI,
    MIN_FONT_PX,
    PRINT_DPI,
    RASTER_NOTE,
    TEXT_SHARE,
    colour_bar_of,
    scene_figure,
    use_headless_gl,
)
from kinematics.units import task_display_units, task_from_si
from metrics.pose import analyse_pose
from metrics.quantities import CORE_QUANTITIES, QUANTITIES

VIEWS = ("map", "pose", "workspace", "compare", "bands", "ellipses")
#: The views drawn by VTK: their SVG and PDF embed the 3D picture as a raster (``raster_note``).
SCENE_VIEWS = ("pose", "workspace")
DEFAULT_SIZE = (1600, 1200)
#: A column narrower or wider than these (inches) or a font outside these (points) is a typo
#: (``isoforce figure --width-in --font-pt`` and the app's export dialog).
COLUMN_INCHES, FONT_POINTS = (1.0, 20.0), (4.0, 30.0)
#: A journal's single column and its body text: the export dialog's first values.
DEFAULT_COLUMN = (3.5, 8.0)


def parse_size(text: str, name: str = "--size") -> tuple[int, int]:
    """``"1600x1200"`` -> (1600, 1200); raise naming ``name`` otherwise."""
    try:
        w, h = (int(v) for v in str(text).lower().replace(" ", "").split("x"))
    except ValueError:
        raise ValueError(f"{name} needs WIDTHxHEIGHT in pixels, e.g. 1600x1200, got {text!r}") from None
    # Below 64 px the fonts of the colour bar and the captions no longer fit (FreeType fails).
    if not (64 <= w <= 16384 and 64 <= h <= 16384):
        raise ValueError(f"{name} needs 64 to 16384 pixels per side, got {text!r}")
    return w, h


def _save_matplotlib(fig, path: Path, size, column=None) -> Path:
    fmt = path.suffix.lower().lstrip(".")
    if column is not None:
        # A journal column: that many inches wide, the text at that size, the page as laid out.
        from app.plots.figures import fit_to_column
        fit_to_column(fig, *column)
        return atomic_write(path, lambda tmp: fig.savefig(tmp, format=fmt, dpi=fig.dpi))
    if size is not None and fmt == "png":
        w, h = size
        # The same picture at the chosen pixels: a size below the figure's own gets a lower dpi,
        # never fewer inches, where the colour bar and labels would leave the axes no room
        # (matplotlib's layout collapses). Half a pixel over: the canvas truncates to pixels.
        dpi = min(w / fig.get_figwidth(), h / fig.get_figheight())
        fig.set_dpi(dpi)
        fig.set_size_inches((w + 0.5) / dpi, (h + 0.5) / dpi)
        return atomic_write(path, lambda tmp: fig.savefig(tmp, format=fmt, dpi=fig.dpi))
    # No size asked for: the figure's own, without the blank band an equal-aspect map leaves
    # above its title in a figure of another shape (80 px over the bands and ellipses).
    return atomic_write(path, lambda tmp: fig.savefig(tmp, format=fmt, dpi=fig.dpi, bbox_inches="tight",
                                                      pad_inches=TIGHT_PAD_IN))


#: The margin round a map figure cropped to its content (no ``--size``), inches.
TIGHT_PAD_IN = 0.1


def _axes_of(mechanism) -> str:
    return "xy" if mechanism.task_dim == 2 else "xyz"


def _workspace_caption(mechanism, workspace_map, compact: bool = False) -> str:
    """What the workspace picture is: its grid and, for the Inverse3, the revolved slice
    (``compact``: the same in a column's few words)."""
    grid = " x ".join(map(str, workspace_map.grid.resolution))
    revolved = scenes.is_revolved(mechanism, workspace_map.grid)
    if compact:
        what = ("slice revolved over the base joint's range, cut at y = 0" if revolved
                else "feasible points of the map's box" if len(workspace_map.grid.axes) == 3
                else "feasible points of the map's slice")
        return f"{what}; {grid} grid, {workspace_map.feasible_points} feasible points"
    what = ("the map's slice revolved over the base joint's range, cut open by the plane y = 0" if revolved
            else "the feasible points of the map's box" if len(workspace_map.grid.axes) == 3
            else "the feasible points of the map's slice")
    # The grid of the map the picture is drawn from: ``figure`` computes a 3D view's map on at most
    # WORKSPACE_MAX_POINTS per axis, so a map figure of the same device may name a finer one.
    return f"{what}, on a {grid} grid: {workspace_map.feasible_points} feasible points"


#: ``compact_caption``'s rewrites, in order: a pose's coordinate names (the values keep their
#: unit), the velocity ellipsoid's "linear" (said by its unit m/s), the iso-surfaces' quantity
#: (the colour bar names it).
_COMPACT = ((re.compile(r"\bat \([^()]*\) = \("), "at ("),
            (re.compile(r"\blinear velocity ellipsoid"), "velocity ellipsoid"),
            (re.compile(r"\biso-surfaces of [^;]*? at ([^;]*?), the ([^;]*?) quantiles of its values"),
             r"iso-surfaces at \1 (\2 quantiles)"))


def compact_caption(text: str) -> str:
    """A 3D figure's caption for a column: its lines run together as one paragraph of phrases
    ("; " between them) that the figure wraps to its width, the pose's coordinate names dropped.
    Every number and unit is kept.

    >>> compact_caption("at (x, y) = (0.0, 150.0) mm; continuous rating, gravity off\\nforces drawn at 10 N = 68 mm")
    'at (0.0, 150.0) mm; continuous rating, gravity off; forces drawn at 10 N = 68 mm'
    """
    for pattern, short in _COMPACT:
        text = pattern.sub(short, text)
    return "; ".join(line.strip().rstrip(";") for line in text.splitlines() if line.strip())


def raster_note(what: str, path) -> str | None:
    """What to say beside a written file whose 3D picture is a raster in a vector format, else None."""
    return RASTER_NOTE if what in SCENE_VIEWS and Path(path).suffix.lower() in (".svg", ".pdf") else None


def _save_scene(plotter, path: Path, size, *, title: str, caption: str, colour_bar=None, axes: str = "xyz",
                class_names=None, column=None) -> Path:
    """The scene cropped to its content with a scale bar and the text (``app.scenes.snapshot``), then written.

    ``class_names`` (a categorical quantity's, in index order: ``scenes.classes.class_names``)
    turn the colour bar into a legend of the classes (``_class_legend``). ``column`` ``(width in,
    font pt)``: laid out for a journal column (``scene_figure``), with the compact caption.
    """
    try:
        figure = scene_figure(plotter, tuple(size or DEFAULT_SIZE), title=title,
                              caption=compact_caption(caption) if column else caption,
                              colour_bar=colour_bar, axes=axes, column=column,
                              legend_names=class_names if colour_bar else None)
    finally:
        plotter.close()
    if class_names and colour_bar:
        _class_legend(figure.figure, colour_bar, class_names, figure.band)
    return figure.save(path)


def _legend_bar(rows) -> dict | None:
    """The pose figure's legend of glyphs (``scenes.legend_rows``: (name, colour) each), as a
    colour bar of one colour per glyph that ``_class_legend`` turns into swatches and names
    (the app's view has this legend; a printed figure without it left the reader to guess
    the polytope from the sphere and the actuators' arrows from each other)."""
    from matplotlib.colors import to_rgb

    if not rows:
        return None
    return {"colours": np.array([to_rgb(colour) for _, colour in rows]), "range": (0.0, float(len(rows))),
            "log": False, "title": "Legend"}


def _class_legend(fig, bar: dict, names, band=None) -> None:
    """The scene figure's colour bar of classes (``bar``: ``snapshot.colour_bar_of``'s, one colour
    per class, ``scenes.classes.class_lookup_table``) replaced, in its place, by a legend: a
    swatch of each class's colour and its name (``names``, in the bar's order), under its title.

    A bar labelled with names under its colours did not fit: seven classes on a narrow picture
    (the Twin-Pantograph's six actuators and "shared (redundant)") wrote their names over each
    other. The legend takes the bar's room (bar, tick labels and title), its entries in as few
    rows as keep the bar's text size, else in the rows that keep the text largest. ``band``
    (bottom, top px: ``SceneFigure.band``) is the room the figure made for it, else the bar's own.
    """
    from matplotlib.patches import Patch

    cax = next(ax for ax in fig.axes if ax.get_xlabel() == bar["title"])
    font = cax.xaxis.label.get_fontsize()
    renderer = fig.canvas.get_renderer()
    room = cax.get_tightbbox(renderer)                 # the bar with its tick labels and title, px
    top = cax.get_position().y1
    if band is not None:
        # The band in display pixels (the figure may be drawn at another dpi than its layout's).
        per_px = fig.bbox.height / (fig.get_size_inches()[1] * DPI)
        room = type(room).from_extents(0, band[0] * per_px, fig.bbox.width, band[1] * per_px)
        top = band[1] / (fig.get_size_inches()[1] * DPI) - 0.2 * font / 72 / fig.get_size_inches()[1]
    cax.set_visible(False)                          # (its remove() looks for a parent axes it has none of)
    handles = [Patch(facecolor=c, edgecolor="none") for c in bar["colours"][:len(names)]]
    width_px = 0.96 * fig.bbox.width

    def legend(rows: int, size: float):
        return fig.legend(handles, list(names), ncols=int(np.ceil(len(names) / rows)), loc="upper center",
                          bbox_to_anchor=(0.5, top), frameon=False, fontsize=size, title=bar["title"],
                          title_fontsize=size, handlelength=1.2, columnspacing=1.2, labelspacing=0.3,
                          borderpad=0.0, borderaxespad=0.0)

    best = (1, 0.0)                                   # rows, and the share of the text size that fits
    for rows in range(1, len(names) + 1):
        trial = legend(rows, font)
        box = trial.get_window_extent(renderer)
        trial.remove()
        scale = min(1.0, width_px / box.width, room.height / box.height)
        if scale > best[1]:
            best = (rows, scale)
        if scale >= 1.0:
            break
    legend(best[0], font * best[1])


def _plotter(size):
    use_headless_gl()          # before pyvista makes a render window: no X attempt, no warning
    import pyvista as pv
    # pyvista's first Plotter probes for a display (runs `xset -q`, else opens a GL context)
    # only to warn that an on-screen window may fail; this one is off-screen, through EGL or
    # the display there is. ALLOW_PLOTTING, pyvista's own switch, skips the probe (40 ms).
    previous = os.environ.get("ALLOW_PLOTTING")
    os.environ["ALLOW_PLOTTING"] = "true"
    try:
        plotter = pv.Plotter(off_screen=True, window_size=list(size or DEFAULT_SIZE))
    finally:
        if previous is None:
            del os.environ["ALLOW_PLOTTING"]
        else:
            os.environ["ALLOW_PLOTTING"] = previous
    plotter.set_background("white")
    return plotter


def _aim(plotter, camera) -> None:
    """Look from the direction of ``camera`` (a session's: ``app.files.session.CAMERA_KEYS``), if given:
    the app's view direction; the figure then frames its content (``snapshot.fit_camera`` keeps it)."""
    if camera:
        cam = plotter.camera
        cam.SetPosition(*camera["position"])
        cam.SetFocalPoint(*camera["focal_point"])
        cam.SetViewUp(*camera["view_up"])
        plotter.renderer.ResetCameraClippingRange()


def _pose_scene(mechanism, pose, *, glyphs=DEFAULT_GLYPHS, desired_force=None, size=None, loading=None,
                camera=None):
    """An off-screen plotter with the pose scene drawn (no text, no axes widget), and its pose
    report under ``loading`` (``metrics.loading.Loading``; None: continuous rating, gravity off),
    seen from ``camera``'s direction if given (``_aim``)."""
    report = analyse_pose(mechanism, np.asarray(pose, float), parts=pose_parts(glyphs), loading=loading)
    plotter = _plotter(size)
    desired = np.zeros(mechanism.task_dim) if desired_force is None else np.asarray(desired_force, float)
    scenes.draw_pose_scene(plotter, mechanism, report, glyphs, desired, scenes.pose_scale(mechanism, report))
    scenes.frame_pose_camera(plotter, mechanism)
    _aim(plotter, camera)
    return plotter, report


def _velocity_scale(plotter, mechanism) -> float | None:
    """The velocity ellipsoid's drawing scale when the plotter shows it, else None (not drawn)."""
    return scenes.velocity_scale(mechanism) if scenes.glyph_drawn(plotter, "velocity_ellipsoid") else None


def pose_plotter(mechanism, pose, *, glyphs=DEFAULT_GLYPHS, desired_force=None, size=None, title: str = ""):
    """An off-screen plotter with the pose view drawn, and its pose report."""
    plotter, report = _pose_scene(mechanism, pose, glyphs=glyphs, desired_force=desired_force, size=size)
    plotter.add_axes()
    if title:
        plotter.add_text(title, font_size=10, color="black")
    caption = scenes.pose_caption(report, scenes.pose_scale(mechanism, report), _velocity_scale(plotter, mechanism),
                                  scenes.inertia_text(plotter, mechanism, report, glyphs))
    plotter.add_text(caption, position="lower_right", font_size=8, color="black", name="pose_caption")
    return plotter, report


#: A figure's iso-surface labels, as a share of its caption's font (``snapshot.TEXT_SHARE``).
ISO_LABEL_SHARE = 0.7


def _workspace_scene(mechanism, workspace_map, quantity: str, *, mode: str = "cut plane", size=None, camera=None,
                     column=None):
    """An off-screen plotter with the workspace drawn, its iso-surfaces labelled, and framed (no axes widget)."""
    plotter = _plotter(size)
    scenes.draw_workspace(plotter, workspace_map, quantity, mechanism, mode, interactive=False)
    # Labels in pixels (VTK's points at 72 dpi) grow with the figure, as its other text does; in a
    # column figure its text size (the smallest a journal takes), in the picture's pixels (PRINT_DPI).
    font_px = max(MIN_FONT_PX, ISO_LABEL_SHARE * TEXT_SHARE * (size or DEFAULT_SIZE)[1])
    if column is not None:
        font_px = column[1] / 72.0 * PRINT_DPI
    scenes.label_iso_surfaces(plotter, quantity, font_size=round(font_px))
    scenes.frame_workspace_camera(plotter, mechanism, workspace_map.grid)
    _aim(plotter, camera)
    return plotter


def pose_text(mechanism, pose) -> str:
    """Where a pose figure is: ``"at (x, y, z) = (170.0, 22.3, 230.0) mm"``, each value with its
    unit where the units differ (a pen's orientation in deg).

    >>> from resources import load_preset
    >>> pose_text(load_preset("fivebar_singh").mechanism, (0.0, 0.15))
    'at (x, y) = (0.0, 150.0) mm'
    """
    values = task_from_si(mechanism, np.asarray(pose, float))
    units = task_display_units(mechanism)
    names = "(" + ", ".join(mechanism.task_names) + ")"
    if len(set(units)) == 1:
        return f"at {names} = (" + ", ".join(f"{v:.1f}" for v in values) + f") {units[0]}"
    return f"at {names} = (" + ", ".join(f"{v:.1f} {u}" for v, u in zip(values, units)) + ")"


def compare_figure(reference_map, current_map, quantity: str, preset, *, mode: str = "side",
                   reference_mechanism=None, mechanism=None):
    """Reference and current maps side by side on one colour scale (or their difference), with
    statistics changes, and what changed between the designs when both mechanisms are given
    (``design_changes.parameter_changes``)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from app.logic.design_changes import parameter_changes
    from app.plots.figures import draw_panels
    if mode == "difference" and current_map.grid != reference_map.grid:
        raise ValueError("a difference is taken point by point and needs both maps on one grid; these are on "
                         f"{' x '.join(map(str, reference_map.grid.resolution))} and "
                         f"{' x '.join(map(str, current_map.grid.resolution))} grids (draw them side by side)")
    panels = ([("current - reference", current_map,
                np.where(current_map.feasible & reference_map.feasible,
                         current_map.values[quantity] - reference_map.values[quantity], np.nan))]
              if mode == "difference" else [("reference", reference_map, None), ("current", current_map, None)])
    fig = Figure(figsize=(6.5 * len(panels), 6.8), dpi=150, layout="compressed")
    FigureCanvasAgg(fig)
    draw_panels(fig, [fig.add_subplot(1, len(panels), i + 1) for i in range(len(panels))], panels, quantity, preset,
                limits=shared_limits([wmap for _, wmap, _ in panels]))
    # Lines wrapped to the figure's width (an unwrapped line ran past both edges of one panel).
    chars = int(fig.get_figwidth() * 72.0 / (CHAR_WIDTH_EM * CHANGE_PT))
    text = change_lines(reference_map, current_map)
    if reference_mechanism is not None and mechanism is not None:
        changed = parameter_changes(reference_mechanism, mechanism)
        text.insert(0, "Changed (reference -> current): " + "; ".join(changed) if changed
                    else "The two designs have the same parameters.")
    lines = [part for line in text for part in textwrap.wrap(line, chars)]
    fig.supxlabel("\n".join(lines), fontsize=CHANGE_PT)
    return fig


def shared_limits(maps) -> list | None:
    """One pair of axis limits (mm) for panels of maps over the same coordinates: the union of
    their cells, so panels of equal size draw every map at one length scale (another device's
    slice three times larger is drawn three times larger). None for one panel or other axes."""
    from app.logic.map_marks import grid_extent
    if len(maps) < 2 or len({m.grid.axes for m in maps}) != 1:
        return None
    extents = np.array([grid_extent(m.grid) for m in maps])
    union = (extents[:, 0].min(), extents[:, 1].max(), extents[:, 2].min(), extents[:, 3].max())
    return [tuple(float(v) for v in union)] * len(maps)


#: The compare figure's lines of statistics changes: text size (pt), and the widest a character
#: of it is on average, in ems (DejaVu Sans' digits and letters are 0.55 to 0.64 em).
CHANGE_PT, CHAR_WIDTH_EM = 8.0, 0.6


def _stat_text(value: float) -> str:
    """A statistic of the compare figure: four significant digits kept (2.280, not 2.28),
    "unbounded" for an infinite one, "-" for none."""
    if np.isnan(value):
        return "-"
    if np.isinf(value):
        return "unbounded" if value > 0 else "-unbounded"
    return f"{value:#.4g}".rstrip(".")


def change_lines(reference_map, current_map) -> list[str]:
    """One line per core quantity both maps have: its min, max, mean and SD in the reference
    and the current map (display units, named with the quantity), and the relative change,
    e.g. "Max. isotropic force (N): min 2.280 -> 3.914 (+71.7 %), max ..., sd ...".
    """
    lines = []
    for q in CORE_QUANTITIES:
        if q in current_map.stats and q in reference_map.stats:
            unit, factor = display_unit(q)
            cells = []
            for figname in ("min", "max", "mean", "sd"):
                new, old = getattr(current_map.stats[q], figname), getattr(reference_map.stats[q], figname)
                comparable = np.isfinite(new) and np.isfinite(old) and old
                change = f"{100 * (new - old) / abs(old):+.1f} %" if comparable else "-"
                cells.append(f"{figname} {_stat_text(old * factor)} -> {_stat_text(new * factor)} ({change})")
            lines.append(f"{QUANTITIES[q].label}" + (f" ({unit})" if unit else "") + ": " + ", ".join(cells))
    return lines


def export_view(what: str, path, *, preset, mechanism, workspace_map, quantity, pose=None, glyphs=DEFAULT_GLYPHS,
                desired_force=None, reference_map=None, size=None, compare_mode: str = "side",
                ellipse: str = "force", spacing: float | None = None, overlay: str = "none",
                reference_mechanism=None, loading=None, plane=None, colour_range: str = "plane",
                camera=None, column: tuple[float, float] | None = None) -> Path:
    """Write one view (``map``, ``pose``, ``workspace``, ``compare``, ``bands``, ``ellipses``) or data.

    A 3D box map's flat views (``FLAT_VIEWS``) are drawn on one plane of it: ``plane``
    ``(axis, value in m)``, snapped to the nearest grid plane (default: ``app.logic.planes.default_plane``,
    the one the app opens on), coloured over that plane's range or the whole volume's
    (``colour_range``, ``"plane"`` or ``"volume"``, named on the colour bar). Its data and
    statistics, and the workspace view, are of the whole volume.

    ``overlay`` (a key of ``app.plots.overlays.OVERLAYS``) is drawn over the ``map`` view, as the
    app's map view draws it.

    ``bands`` and ``ellipses`` are paper 002's Figs. 5 and 9 (``app.plots.overlays``): ``ellipse``
    is ``"force"`` or ``"velocity"``, ``spacing`` the ellipses' spacing in m (default
    ``default_spacing``). ``data`` and ``stats`` write the map's values or statistics.
    ``reference_mechanism``, the design of ``reference_map``, lets ``compare`` say what changed.
    ``loading`` is the pose view's (the maps carry their own): the app's rating and gravity.
    ``camera`` (a session's camera of the pose or workspace view, ``app.files.session``) is the
    direction a 3D view is seen from; None: the view's own framing.

    ``column`` ``(width in inches, font size in points)`` lays a view out for a journal column:
    a flat view by ``app.plots.figures.fit_to_column`` (vector PDF and SVG at that width), a 3D
    view by ``app.scenes.snapshot.scene_figure`` (that width, its text at that size and vector,
    the picture a raster at ``PRINT_DPI``, the caption in its compact form: ``compact_caption``).
    """
    path = Path(path)
    if what == "data":
        return write_map(workspace_map, path, device=preset.key)
    if what == "stats":
        from app.files.stats_files import write_stats  # (the map's modules: not a pose figure's)
        return write_stats(workspace_map, path, device=preset.key)
    path = check_suffix(path, FIGURE_SUFFIXES, "path")
    title = f"{preset.name}"
    scale = None
    if what in FLAT_VIEWS and is_volume(workspace_map.grid):
        workspace_map, reference_map, scale = _on_plane(workspace_map, reference_map, quantity, preset, mechanism,
                                                        plane, colour_range)
    elif what in FLAT_VIEWS and plane is not None:      # a plane computed on its own (``isoforce figure``)
        from app.logic.colour_scale import plane_scale
        scale = plane_scale(workspace_map, workspace_map, quantity, preset)
    if what == "map" and overlay != "none":
        from app.plots.overlays import overlay_map_figure
        return _save_matplotlib(overlay_map_figure(workspace_map, quantity, preset, overlay, mechanism=mechanism),
                                path, size, column)
    if what == "map":
        from app.plots.figures import map_figure
        return _save_matplotlib(map_figure(workspace_map, quantity, preset, scale=scale), path, size, column)
    if what == "bands":
        from app.plots.overlays import bands_figure
        return _save_matplotlib(bands_figure(workspace_map, preset, mechanism=mechanism), path, size, column)
    if what == "ellipses":
        from app.plots.overlays import default_spacing, ellipse_field, ellipses_figure
        spacing = default_spacing(workspace_map.grid) if spacing is None else spacing
        field = ellipse_field(mechanism, workspace_map.grid, spacing, kind=ellipse)
        return _save_matplotlib(ellipses_figure(workspace_map, field, quantity, preset), path, size, column)
    if what == "compare":
        if reference_map is None:
            raise ValueError("the compare view needs a pinned reference design")
        return _save_matplotlib(compare_figure(reference_map, workspace_map, quantity, preset, mode=compare_mode,
                                               reference_mechanism=reference_mechanism, mechanism=mechanism),
                                path, size, column)
    if what == "pose":
        if pose is None:
            raise ValueError("the pose view needs a pose (--at)")
        plotter, report = _pose_scene(mechanism, pose, glyphs=glyphs, desired_force=desired_force, size=size,
                                      loading=loading, camera=camera)
        caption = scenes.pose_caption(report, scenes.pose_scale(mechanism, report),
                                      _velocity_scale(plotter, mechanism),
                                      scenes.inertia_text(plotter, mechanism, report, glyphs))
        caption = f"{pose_text(mechanism, pose)}; {report.loading.describe()}\n{caption}"     # where, and under what
        if desired_force is not None:
            caption = "\n".join(filter(None, [caption, scenes.drawn_forces_text(plotter, mechanism, report,
                                                                                 desired_force)]))
        rows = scenes.legend_rows(plotter, mechanism.joint_names)
        return _save_scene(plotter, path, size, title=title, caption=caption, axes=_axes_of(mechanism),
                           colour_bar=_legend_bar(rows), class_names=[name for name, _ in rows], column=column)
    if what == "workspace":
        from app.scenes.classes import class_names
        plotter = _workspace_scene(mechanism, workspace_map, quantity, size=size, camera=camera, column=column)
        caption = "\n".join(filter(None, [scenes.box_caption(plotter),
                                          _workspace_caption(mechanism, workspace_map, compact=column is not None)]))
        # Classes: the key of the actor that shows them (a box map's plane: classes have no iso-surfaces).
        bar_of = "box_plane" if class_names(plotter, "box_plane") else "workspace"
        names = class_names(plotter, bar_of)
        return _save_scene(plotter, path, size, title=title, colour_bar=colour_bar_of(plotter, bar_of), caption=caption,
                           axes=scenes.flat_axes(mechanism, workspace_map.grid), class_names=names, column=column)
    raise ValueError(f"view must be one of {', '.join(VIEWS)}, got {what!r}")


#: The views drawn from a 2D map: a 3D box map's are drawn on one plane of it.
FLAT_VIEWS = ("map", "compare", "bands", "ellipses")


def _on_plane(volume, reference, quantity, preset, mechanism, plane, colour_range):
    """A 3D box map's plane (and the reference's, if it is a box over the same axes) and its colour scale."""
    from app.logic.colour_scale import plane_scale
    axis, value = plane if plane is not None else default_plane(volume.grid, mechanism, preset.pose)
    flat = volume_slice(volume, axis, value)
    if reference is not None and is_volume(reference.grid) and axis in reference.grid.axes:
        reference = volume_slice(reference, axis, value)
    return flat, reference, plane_scale(volume, flat, quantity, preset, colour_range)


def export_report(folder, *, preset, mechanism, workspace_map, quantity, pose=None, glyphs=DEFAULT_GLYPHS,
                  desired_force=None, reference_map=None, overlay: str = "none",
                  reference_mechanism=None, loading=None, plane=None, colour_range: str = "plane") -> list[Path]:
    """Every figure (PNG, SVG, PDF), the map data (CSV, NPZ) and statistics (CSV, JSON) into ``folder``
    (a 3D box map's figures on ``plane``, as ``export_view``)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ValueError(f"report folder {str(folder)!r} does not exist")
    common = dict(preset=preset, mechanism=mechanism, workspace_map=workspace_map, quantity=quantity, pose=pose,
                  glyphs=glyphs, desired_force=desired_force, reference_map=reference_map, overlay=overlay,
                  reference_mechanism=reference_mechanism, loading=loading, plane=plane, colour_range=colour_range)
    jobs = report_files(quantity, pose=pose, reference_map=reference_map)
    return [export_view(what, folder / name, **common) for what, name in jobs]


def report_files(quantity: str, *, pose=None, reference_map=None) -> list[tuple[str, str]]:
    """The report's files in writing order: ``(what, file name)`` for ``export_view`` (the app's
    background report writes the same list one file at a time)."""
    jobs = [("map", f"map_{quantity}{ext}") for ext in FIGURE_SUFFIXES]
    if pose is not None:
        jobs += [("pose", f"pose{ext}") for ext in FIGURE_SUFFIXES]
    jobs += [("workspace", "workspace.png")]
    if reference_map is not None:
        jobs += [("compare", f"compare_{quantity}{ext}") for ext in FIGURE_SUFFIXES]
    return jobs + [("data", "map.csv"), ("data", "map.npz"), ("stats", "statistics.csv"), ("stats", "statistics.json")]
