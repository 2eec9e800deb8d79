"""Map overlays of paper 002: condition-number bands (its Fig. 5) and ellipse fields (its Fig. 9).

Shared by ``isoforce figure --view bands|ellipses`` and, as overlays, by the app's map view:
the ``draw_*`` functions take a matplotlib ``Axes`` already showing a 2D map (axes in mm) and
return the artists they added, so a view can remove them (``remove_overlay``) and redraw.
No Qt here; matplotlib only, through ``Figure`` and an Agg canvas.

Bands. Paper 002 (sec. 4.1) marks each workspace point by its condition number ``K``:
plus ``K < 5``, asterisk ``5 <= K <= 10``, square ``10 < K < 100``, diamond ``K > 100``. The
paper leaves ``K = 100`` in no band; here it joins the top band (``K >= 100``). A singular
point (``K = inf``) is not a number in that top band: it is a class of its own, drawn as a
marker. Its dexterous workspace is "an annulus region between 0.9 and 1.7 (normalized
lengths)", lengths normalised by ``L = (a1 + a2 + a3) / 3``; the paper draws it about the
origin of its frame, the midpoint of the base (our five-bar's origin too), and states it for
the generalised design of its Fig. 5, "which is later optimized". So it is drawn for a
five-bar at 0.9 L and 1.7 L of *this* design, labelled with the share of its feasible points
that are in fact ``K < 5`` here: a claim the figure checks rather than repeats.

Ellipses. Force ellipses ``{f : |diag(1/t) J^T f| <= 1}`` (N) or velocity ellipses of unit
joint rates ``{J qdot : |qdot| <= 1 rad/s}`` (m/s per rad/s), from ``metrics.ellipsoids``,
on a lattice of the map's plane at a chosen spacing, all on ONE scale (mm of paper per N, or
per m/s) with a key. Only planar devices (2D task): a spatial device's ellipsoid has no
single in-plane ellipse (its section and its projection differ), so the figure refuses it
rather than pick one silently. Points outside the workspace and singular points get no
ellipse; they are counted in the legend.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from contourpy import LineType, contour_generator
from matplotlib import colors
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import EllipseCollection, LineCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch

from app.logic.map_marks import CUT_EDGE_LABEL, SINGULAR_COLOUR, coordinate_text, grid_extent, title_of
from app.logic.overlay_drawing import OverlayDrawing
from app.logic.overlay_names import OVERLAYS
from app.logic.ticks import round_below
from app.plots.figures import _figure_size, draw_map, map_figure
from kinematics import DEXTEROUS_ANNULUS
from metrics.ellipsoids import force_ellipsoid, velocity_ellipsoid
from metrics.quantities import evaluate
from metrics.workspace import WorkspaceMap

#: Paper 002's bands: (label, lower bound, upper bound, marker of its Fig. 5), K in [lo, hi)
#: except the second band, which the paper closes at 10 (``5 <= K <= 10``).
BANDS = (("K < 5", "plus"), ("5 <= K <= 10", "asterisk"), ("10 < K < 100", "square"), ("K >= 100", "diamond"))
#: Code of a singular point (K = inf) in ``condition_bands``; -1 is outside the workspace.
BAND_SINGULAR = len(BANDS)
#: Band colours: good (green) to poor (red-brown); singular points are ``SINGULAR_COLOUR`` markers.
BAND_COLOURS = ("#1a9850", "#a6d96a", "#fdae61", "#a50026")
ELLIPSE_KINDS = ("force", "velocity")
#: The 90th percentile of the major semi-axes is drawn this fraction of the spacing long.
ELLIPSE_FILL = 0.45


def condition_bands(kappa, feasible) -> np.ndarray:
    """Paper 002's band of each condition number: 0..3 (``BANDS``), ``BAND_SINGULAR``, or -1.

    Parameters
    ----------
    kappa : array_like, shape (...)
        Condition numbers (>= 1; ``inf`` singular; ``nan`` where not computed).
    feasible : array_like of bool, shape (...)
        Points inside the workspace.

    Returns
    -------
    ndarray of int8, shape (...)
        0 ``K < 5``, 1 ``5 <= K <= 10``, 2 ``10 < K < 100``, 3 ``K >= 100`` (finite),
        ``BAND_SINGULAR`` (4) for ``K = inf``, -1 outside the workspace or ``nan``.

    Examples
    --------
    >>> condition_bands([1.0, 5.0, 10.0, 10.5, 100.0, np.inf, np.nan], [True] * 7).tolist()
    [0, 1, 1, 2, 3, 4, -1]
    """
    k = np.asarray(kappa, float)
    ok = np.asarray(feasible, bool) & ~np.isnan(k)
    band = np.select([k < 5.0, k <= 10.0, k < 100.0, np.isfinite(k)], [0, 1, 2, 3], BAND_SINGULAR)
    return np.where(ok, band, -1).astype(np.int8)


def dexterous_annulus(mechanism) -> tuple[float, float] | None:
    """Inner and outer radius (m) of paper 002's dexterous annulus about the base's centre, or
    None: the model's ``dexterous_annulus`` (``(0.9 L, 1.7 L)``, ``L = (a1 + a2 + a3) / 3``, for a
    five-bar; paper 002 sec. 2 and 4.1)."""
    return mechanism.dexterous_annulus


def draw_condition_bands(ax, wmap: WorkspaceMap, mechanism=None, *, alpha: float = 1.0) -> dict:
    """Draw paper 002's bands of ``wmap``'s condition number on ``ax`` (mm), with a legend.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes in mm of the map's two grid axes.
    wmap : WorkspaceMap
        A 2D map holding ``condition_number``.
    mechanism : Mechanism, optional
        A five-bar gets paper 002's dexterous annulus (``dexterous_annulus``) drawn and checked.
    alpha : float
        Opacity of the band cells (below 1 as an overlay over another map).

    Returns
    -------
    dict
        ``artists``: everything added (image, singular markers, annulus circles), for
        ``remove_overlay``; ``handles`` and ``title`` for a legend (``overlay_legend``, or the
        caller's own ``ax.legend(handles=...)``).
    """
    if len(wmap.grid.axes) != 2 or "condition_number" not in wmap.values:
        raise ValueError(f"bands need a 2D map holding condition_number, got axes {wmap.grid.axes!r} "
                         f"and quantities {', '.join(wmap.values)}")
    band = condition_bands(wmap.values["condition_number"], wmap.feasible)
    extent = grid_extent(wmap.grid)
    cells = np.ma.masked_array(band, mask=~((band >= 0) & (band < BAND_SINGULAR)))
    cmap = colors.ListedColormap(BAND_COLOURS).with_extremes(bad=(0.0, 0.0, 0.0, 0.0))
    added = [ax.imshow(cells.T, origin="lower", extent=extent, cmap=cmap, alpha=alpha,
                       norm=colors.BoundaryNorm(np.arange(-0.5, len(BANDS)), len(BANDS)),
                       interpolation="nearest", aspect="equal")]
    handles = [Patch(facecolor=c, label=f"{label} ({np.count_nonzero(band == k)} pts)")
               for k, ((label, _), c) in enumerate(zip(BANDS, BAND_COLOURS))]
    x_mm, y_mm = (c * 1e3 for c in wmap.grid.coordinates())
    i, j = np.nonzero(band == BAND_SINGULAR)
    # A singular curve is one cell wide: as cells it would vanish, so it gets markers.
    added += ax.plot(x_mm[i], y_mm[j], "x", color=SINGULAR_COLOUR, markersize=4, clip_on=False,
                     label=f"singular, K = inf ({len(i)} pts)")
    handles.append(added[-1])
    circles, rows = _annulus(wmap, band, mechanism)
    for k, (cx, cy, r) in enumerate(circles):
        added.append(ax.add_patch(Circle((cx, cy), r, fill=False, edgecolor="black", linestyle="--", linewidth=1.2,
                                         label=rows[0][2] if k == 0 else "_annulus")))
    handles += added[len(added) - len(circles):][:1]
    return {"artists": added, "handles": handles, "title": "condition number K (paper 002 Fig. 5)"}


#: The condition numbers between paper 002's bands, drawn as lines by ``band_boundaries``.
BAND_LIMITS = (5.0, 10.0, 100.0)


def band_boundaries(wmap: WorkspaceMap, mechanism=None) -> OverlayDrawing:
    """Paper 002's bands as an overlay on a heat map: the lines ``K = 5, 10, 100`` between them.

    Cells would hide the map under them (or, translucent, mix their colours with its colour
    scale into colours neither key explains); the boundaries leave both readable. Each line
    is contoured from the map's own samples over whole grid cells (``contourpy``, linear
    along each cell edge, so every vertex lies on a grid edge and the grid's spacing decides
    where it runs), in the colour of the worse band it bounds; singular points (``K = inf``)
    are markers and a five-bar gets paper 002's dexterous annulus, as ``draw_condition_bands``
    draws them. The legend counts each band's points as the bands figure does.

    Parameters
    ----------
    wmap : WorkspaceMap
        A 2D map holding ``condition_number``.
    mechanism : Mechanism, optional
        A five-bar gets paper 002's dexterous annulus (``dexterous_annulus``).

    Returns
    -------
    OverlayDrawing
    """
    if len(wmap.grid.axes) != 2 or "condition_number" not in wmap.values:
        raise ValueError(f"band boundaries need a 2D map holding condition_number, got axes {wmap.grid.axes!r} "
                         f"and quantities {', '.join(wmap.values)}")
    kappa = wmap.values["condition_number"]
    band = condition_bands(kappa, wmap.feasible)
    # Outside the workspace and at singular points (inf) there is nothing to interpolate.
    field = np.ma.masked_invalid(np.where(wmap.feasible, kappa, np.nan))
    x_mm, y_mm = (c * 1e3 for c in wmap.grid.coordinates())
    lines = []
    if field.count():
        contours = contour_generator(x_mm, y_mm, field.T, name="mpl2014", corner_mask=False,
                                     line_type=LineType.SeparateCode)
        lines = [(colour, tuple(contours.lines(level)[0])) for level, colour in zip(BAND_LIMITS, BAND_COLOURS[1:])]
    rows = []
    for k, ((label, _), colour) in enumerate(zip(BANDS, BAND_COLOURS)):
        bound = f"its lower edge the K = {BAND_LIMITS[k - 1]:g} line" if k else "within the K = 5 line"
        rows.append(("line" if k else "patch", colour, f"{label} ({np.count_nonzero(band == k)} pts; {bound})"))
    i, j = np.nonzero(band == BAND_SINGULAR)
    rows.append(("x", SINGULAR_COLOUR, f"singular, K = inf ({len(i)} pts)"))
    circles, annulus_row = _annulus(wmap, band, mechanism)
    rows += annulus_row
    return OverlayDrawing(title="condition number K bands (paper 002 Fig. 5)", rows=tuple(rows), lines=tuple(lines),
                          markers=(("x", SINGULAR_COLOUR, np.stack([x_mm[i], y_mm[j]], axis=-1)),),
                          circles=circles)


def draw_overlay_drawing(ax, drawing: OverlayDrawing) -> dict:
    """Draw an ``OverlayDrawing`` on matplotlib axes (mm); returns ``artists``, ``handles``, ``title``.

    The legend handles stand for ``drawing.rows`` (each row's symbol in its colour; text only
    where a row has none), so a figure's legend reads as the app's key.
    """
    added = []
    for colour, polylines in drawing.lines:
        if polylines:
            added.append(ax.add_collection(LineCollection(polylines, colors=colour, linewidths=1.6)))
    for symbol, colour, points in drawing.markers:
        if len(points):
            added += ax.plot(points[:, 0], points[:, 1], symbol, color=colour, markerfacecolor="none",
                             markersize=4 if symbol == "x" else 5, clip_on=False, label="_overlay")
    for cx, cy, r in drawing.circles:
        added.append(ax.add_patch(Circle((cx, cy), r, fill=False, edgecolor="black", linestyle="--", linewidth=1.2)))
    if drawing.ellipses is not None and len(drawing.ellipses):
        e = drawing.ellipses
        added.append(ax.add_collection(EllipseCollection(e[:, 2], e[:, 3], e[:, 4], units="xy", offsets=e[:, :2],
                                                         offset_transform=ax.transData, facecolors="none",
                                                         edgecolors="black", linewidths=0.9)))
    if drawing.key is not None:
        radius, text = drawing.key
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        centre = key_centre((x0, x1, y0, y1), radius)
        added.append(ax.add_patch(Circle(centre, radius, fill=False, edgecolor="black", linewidth=1.4)))
        added.append(ax.annotate(text, (centre[0] - radius, centre[1]), xytext=(-4, 0), textcoords="offset points",
                                 ha="right", va="center", fontsize=8))
    handles = [_handle(symbol, colour, text) for symbol, colour, text in drawing.rows]
    return {"artists": added, "handles": handles, "title": drawing.title}


def _handle(symbol, colour, text):
    """A legend handle drawing ``symbol`` in ``colour`` (``OverlayDrawing.rows``)."""
    if symbol == "patch":
        return Patch(facecolor=colour, edgecolor=colour, label=text)
    if symbol in ("line", "dashed"):
        return Line2D([], [], color=colour, linewidth=1.6, linestyle="--" if symbol == "dashed" else "-", label=text)
    if symbol in ("x", "o", "^"):
        return Line2D([], [], linestyle="none", marker=symbol, color=colour, markerfacecolor="none", label=text)
    return Line2D([], [], linestyle="none", label=text)


def key_centre(limits, radius: float) -> tuple[float, float]:
    """Centre (mm) of the ellipses' key circle: the upper right corner of axes ``limits`` (x0, x1, y0, y1)."""
    x0, x1, y0, y1 = limits
    return x1 - 0.04 * (x1 - x0) - radius, y1 - 0.04 * (y1 - y0) - radius


def _annulus(wmap: WorkspaceMap, band: np.ndarray, mechanism) -> tuple[tuple, list]:
    """Paper 002's dexterous annulus of a five-bar: its circles (cx, cy, r) mm and its legend row
    (the share of the annulus's feasible points that are ``K < 5``); none for other devices."""
    annulus = dexterous_annulus(mechanism) if mechanism is not None else None
    if annulus is None or set(wmap.grid.axes) != {"x", "y"}:
        return (), []
    r = np.hypot(*np.meshgrid(*wmap.grid.coordinates(), indexing="ij"))      # the map's shape, either axis order
    inside = (r >= annulus[0]) & (r <= annulus[1]) & (band >= 0)
    share = np.count_nonzero(band[inside] == 0) / max(1, np.count_nonzero(inside))
    length_mm = annulus[0] / DEXTEROUS_ANNULUS[0] * 1e3
    text = (f"paper 002 dexterous annulus {DEXTEROUS_ANNULUS[0]} L to {DEXTEROUS_ANNULUS[1]} L "
            f"(L = {length_mm:.4g} mm): K < 5 at {100 * share:.0f} % of its {np.count_nonzero(inside)} feasible pts")
    return tuple((0.0, 0.0, radius * 1e3) for radius in annulus), [("dashed", "black", text)]


def remove_overlay(overlay: dict) -> None:
    """Remove what a ``draw_*`` function of this module added (its ``"artists"``)."""
    for artist in overlay["artists"]:
        artist.remove()


def overlay_legend(fig, overlay: dict, *, loc: str = "outside lower center"):
    """The overlay's legend outside the axes (the map stays visible): below, or right of a tall map."""
    return fig.legend(handles=overlay["handles"], loc=loc, fontsize=8, title=overlay["title"], title_fontsize=8,
                      frameon=False)


def _legend_room(fig, overlay: dict, extent) -> None:
    """The overlay's legend outside the axes, the figure grown to hold it: below a wide map, right of a tall one."""
    w, h = fig.get_size_inches()
    if (extent[3] - extent[2]) > 1.2 * (extent[1] - extent[0]):
        longest = max(len(getattr(hd, "get_label", lambda: "")()) for hd in overlay["handles"])
        fig.set_size_inches(w + min(4.5, 0.3 + 0.065 * max(longest, len(overlay["title"]))), h)
        overlay_legend(fig, overlay, loc="outside right upper")
    else:
        fig.set_size_inches(w, h + 0.19 * (len(overlay["handles"]) + 1) + 0.1)
        overlay_legend(fig, overlay)


def bands_figure(wmap: WorkspaceMap, preset_or_title, *, mechanism=None, dpi: int = 150) -> Figure:
    """Paper 002's Fig. 5 for a map: the condition-number bands, singular points, the dexterous annulus.

    ``mechanism`` defaults to the preset's; it gives the five-bar's annulus.
    """
    mechanism = mechanism if mechanism is not None else getattr(preset_or_title, "mechanism", None)
    extent = grid_extent(wmap.grid)
    w, h = _figure_size(extent)
    fig = Figure(figsize=(w - 1.0, h), dpi=dpi, layout="compressed")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    overlay = draw_condition_bands(ax, wmap, mechanism)
    _legend_room(fig, overlay, extent)
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_aspect("equal")
    ax.set_xlabel(f"{wmap.grid.axes[0]} (mm)")
    ax.set_ylabel(f"{wmap.grid.axes[1]} (mm)")
    nx, ny = wmap.grid.resolution
    # Where the slice (or the plane of a 3D box) is, as the heat map's title says it.
    fixed = ", ".join(coordinate_text(preset_or_title, n, v) for n, v in wmap.grid.fixed)
    ax.set_title(f"{title_of(preset_or_title)}: condition-number bands\n"
                 f"{nx} x {ny} grid, {wmap.feasible_points} feasible points" + (f"; {fixed}" if fixed else ""),
                 fontsize=10)
    return fig


@dataclass(frozen=True)
class EllipseField:
    """Ellipses on a lattice of a planar map: what ``draw_ellipse_field`` draws.

    ``centres`` (k, 2) m; ``radii`` (k, 2), largest first, in ``unit``; ``axes`` (k, 2, 2),
    unit semi-axis directions as columns; ``outside`` lattice points outside the workspace
    (or its limits) and ``singular`` ones (unbounded or degenerate ellipse), neither drawn;
    ``spacing`` (m) of the lattice.
    """

    kind: str
    centres: np.ndarray
    radii: np.ndarray
    axes: np.ndarray
    outside: int
    singular: int
    spacing: float
    unit: str


def _lattice_counts(grid, spacing: float) -> list[int]:
    # (1e-9: a span that is a whole number of spacings, up to rounding, gets its end point)
    return [int(np.floor((hi - lo) / spacing + 1e-9)) + 1 for lo, hi in zip(grid.lower, grid.upper)]


def lattice(grid, spacing: float) -> np.ndarray:
    """Points (k, 2) in m every ``spacing`` m over a 2D grid's box, centred in it, x fastest."""
    axes = [lo + ((hi - lo) - (n - 1) * spacing) / 2.0 + spacing * np.arange(n)
            for lo, hi, n in zip(grid.lower, grid.upper, _lattice_counts(grid, spacing))]
    a, b = np.meshgrid(*axes, indexing="xy")
    return np.stack([a.ravel(), b.ravel()], axis=-1)


#: At most this many lattice points per ellipse field (a figure of 10^4 ellipses is a grey field).
MAX_ELLIPSES = 10_000


def default_spacing(grid) -> float:
    """A round spacing (m) giving about 20 ellipses across the map's wider side."""
    return round_below(max(hi - lo for lo, hi in zip(grid.lower, grid.upper)) / 20.0)


def lattice_size(grid, spacing: float) -> int:
    """How many lattice points ``lattice(grid, spacing)`` has."""
    return int(np.prod(_lattice_counts(grid, spacing)))


def ellipse_field(mechanism, grid, spacing: float, *, kind: str = "force", joint_speeds=None) -> EllipseField:
    """Force or velocity ellipses of a planar device every ``spacing`` m over ``grid``'s plane.

    Parameters
    ----------
    mechanism : Mechanism
        A device with a 2D task whose map axes are its task coordinates.
    grid : GridSpec
        The map's 2D grid (its box is covered).
    spacing : float
        Lattice spacing, m.
    kind : {"force", "velocity"}
        Force ellipses (N, the device's torque limits) or velocity ellipses (m/s at joint
        speeds ``joint_speeds``, default 1 rad/s each).

    Returns
    -------
    EllipseField
    """
    if not (np.isfinite(spacing) and spacing > 0):
        raise ValueError(f"spacing must be a positive length in m, got {spacing!r}")
    if kind not in ELLIPSE_KINDS:
        raise ValueError(f"kind must be one of {', '.join(ELLIPSE_KINDS)}, got {kind!r}")
    if mechanism.task_dim != 2 or len(grid.axes) != 2 or set(grid.axes) != set(mechanism.task_names):
        raise ValueError(f"ellipses need a planar device mapped over its own task plane; this one has task "
                         f"{', '.join(mechanism.task_names)} and map axes {', '.join(grid.axes)} "
                         "(a spatial device's ellipsoid has no one in-plane ellipse)")
    if lattice_size(grid, spacing) > MAX_ELLIPSES:
        raise ValueError(f"spacing {spacing * 1e3:g} mm gives {lattice_size(grid, spacing)} ellipses over this map, "
                         f"more than {MAX_ELLIPSES}: use a larger spacing")
    points = lattice(grid, spacing)
    order = [grid.axes.index(name) for name in mechanism.task_names]
    result = evaluate(mechanism, points[:, order], ["jacobian", "condition_number"])
    jac = result.values["jacobian"]
    regular = result.feasible & np.isfinite(result.values["condition_number"])
    n = mechanism.n_joints
    if kind == "force":
        ell, unit = force_ellipsoid(jac[regular], torque_limits=mechanism.torque_limits()), "N"
    else:
        speeds = np.ones(n) if joint_speeds is None else joint_speeds
        ell, unit = velocity_ellipsoid(jac[regular], joint_speed_limits=speeds), "m/s"
    ok = np.all(np.isfinite(ell.radii) & (ell.radii > 0), axis=-1)
    task_axes = ell.axes[ok][:, order, :]          # rows in the map's axis order
    return EllipseField(kind=kind, centres=points[regular][ok], radii=ell.radii[ok], axes=task_axes,
                        outside=int(np.count_nonzero(~result.feasible)),
                        singular=int(np.count_nonzero(result.feasible) - np.count_nonzero(ok)),
                        spacing=float(spacing), unit=unit)


def ellipse_scale(field: EllipseField) -> tuple[float, float]:
    """``(mm per unit, key value)``: ONE drawing scale for every ellipse of the field, and its key.

    The 90th percentile of the major semi-axes is drawn ``ELLIPSE_FILL`` of the spacing long
    (a percentile, not the maximum: near a singularity a force ellipse grows without bound
    and would shrink all others to dots). The key is the round value 1, 2, 5 x 10^k just
    below that percentile.
    """
    if field.radii.size == 0:
        return 1.0, 1.0
    typical = float(np.percentile(field.radii[:, 0], 90))
    return ELLIPSE_FILL * field.spacing * 1e3 / typical, round_below(typical)


def ellipse_drawing(field: EllipseField) -> OverlayDrawing:
    """``field``'s ellipses on one scale (mm per unit, ``ellipse_scale``), with a key and counts.

    An ellipse whose semi-major axis is drawn longer than the spacing (it would cover its
    neighbours' centres) is drawn as a hollow triangle at its centre instead, and counted.
    """
    mm_per_unit, key = ellipse_scale(field)
    unit = field.unit if field.kind == "force" else "m/s per rad/s"
    major = field.radii[:, 0] * mm_per_unit if len(field.radii) else np.zeros(0)
    big = major > field.spacing * 1e3
    keep = ~big
    angles = np.degrees(np.arctan2(field.axes[keep, 1, 0], field.axes[keep, 0, 0])) if keep.any() else np.zeros(0)
    ellipses = np.column_stack([field.centres[keep] * 1e3, 2 * field.radii[keep, 0] * mm_per_unit,
                                2 * field.radii[keep, 1] * mm_per_unit, angles]).reshape(-1, 5)
    rows = [("o", "black", f"{field.kind} ellipses, {np.count_nonzero(keep)} drawn every {field.spacing * 1e3:g} mm; "
                      f"key circle of radius {key:g} {unit}")]
    markers = ()
    if big.any():
        markers = (("^", "black", field.centres[big] * 1e3),)
        rows.append(("^", "black", f"{np.count_nonzero(big)} ellipses whose semi-major axis would pass a neighbour's "
                              f"centre (> {field.spacing * 1e3 / mm_per_unit:.3g} {unit}): triangles"))
    rows.append((None, None,
                 f"not drawn: {field.outside} lattice points outside the workspace, {field.singular} singular"))
    return OverlayDrawing(title=f"{field.kind} ellipses ({unit}), one scale: a semi-axis of 1 {unit} drawn "
                                f"{mm_per_unit:.3g} mm long",
                          rows=tuple(rows), markers=markers, ellipses=ellipses,
                          key=(key * mm_per_unit, f"key: {key:g} {unit}"))


def draw_ellipse_field(ax, field: EllipseField) -> dict:
    """Draw ``field``'s ellipses on ``ax`` (mm): ``ellipse_drawing`` through ``draw_overlay_drawing``."""
    return draw_overlay_drawing(ax, ellipse_drawing(field))


def ellipses_figure(wmap: WorkspaceMap, field: EllipseField, quantity: str, preset_or_title, *,
                    dpi: int = 150) -> Figure:
    """Paper 002's Fig. 9 for a map: the ellipse field over the heat map of ``quantity``."""
    extent = grid_extent(wmap.grid)
    fig = Figure(figsize=_figure_size(extent), dpi=dpi, layout="compressed")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    artists = draw_map(fig, ax, wmap, quantity, preset_or_title,
                       title=f"{title_of(preset_or_title)}, {field.kind} ellipses over the map of")
    # The map's extremes, its edge marks and their legend make way for the ellipses' (they would
    # read as glyphs; the edge marks would be left with no legend row).
    edges = [a for a in artists.get("singular", []) if a.get_label() in (CUT_EDGE_LABEL, "_cut")]
    for line in artists.get("extremes", []) + edges:
        line.remove()
    if ax.get_legend() is not None:
        ax.get_legend().remove()
    _legend_room(fig, draw_ellipse_field(ax, field), extent)
    return fig


#: The map view's overlays (``overlay_map_figure``): key -> what it draws.


def overlay_available(overlay: str, mechanism, grid) -> str | None:
    """Why ``overlay`` cannot be drawn over a map of ``grid`` for ``mechanism`` (None: it can).

    Bands need a 2D map (any device: its condition number on the slice); ellipses a planar
    device mapped over its own task plane (``ellipse_field``).
    """
    if overlay not in OVERLAYS:
        raise ValueError(f"overlay must be one of {', '.join(OVERLAYS)}, got {overlay!r}")
    if overlay == "none":
        return None
    if len(grid.axes) != 2:
        return "overlays are drawn on 2D maps; this map is a 3D box"
    if overlay.endswith("ellipses") and (mechanism.task_dim != 2 or set(grid.axes) != set(mechanism.task_names)):
        return ("ellipses are drawn for planar devices over their own task plane (a spatial device's "
                "ellipsoid has no one in-plane ellipse)")
    return None


def overlay_drawing(overlay: str, wmap: WorkspaceMap, mechanism, *,
                    field: EllipseField | None = None) -> OverlayDrawing | None:
    """What ``overlay`` (``OVERLAYS``) draws over a heat map of ``wmap``; None for ``"none"``.

    ``field`` is a computed ellipse field to reuse (the map view keeps one per design);
    otherwise the ellipses are computed at ``default_spacing``.
    """
    problem = overlay_available(overlay, mechanism, wmap.grid)
    if problem is not None:
        raise ValueError(problem)
    if overlay == "none":
        return None
    if overlay == "bands":
        return band_boundaries(wmap, mechanism)
    if field is None:
        field = ellipse_field(mechanism, wmap.grid, default_spacing(wmap.grid), kind=overlay.split()[0])
    return ellipse_drawing(field)


def overlay_map_figure(wmap: WorkspaceMap, quantity: str, preset, overlay: str, *, mechanism=None,
                       dpi: int = 150) -> Figure:
    """The app's map view as a figure: the heat map of ``quantity`` with ``overlay`` over it and its legend.

    ``mechanism`` defaults to the preset's (the design the map was computed for).
    """
    mechanism = mechanism if mechanism is not None else preset.mechanism
    fig = map_figure(wmap, quantity, preset, dpi=dpi)
    drawing = overlay_drawing(overlay, wmap, mechanism)
    if drawing is not None:
        _legend_room(fig, draw_overlay_drawing(fig.axes[0], drawing), grid_extent(wmap.grid))
    return fig
