"""``isoforce figure``: the app's own views rendered off-screen, with no display.

``--view map`` heat map, ``pose`` the 3D pose with its force glyphs, ``workspace`` the 3D
workspace, ``compare`` the preset's own design (reference) against the design with the
``--set`` changes (current), ``bands`` paper 002's condition-number bands (its Fig. 5, with
the five-bar's dexterous annulus), ``ellipses`` its force or velocity ellipses over the map
(its Fig. 9; planar devices only). PNG/SVG/PDF by the suffix of ``--out``.

``--session FILE`` (the app's File > Save session) draws what the app showed: its design, map
quantity, overlay, plane, pose, desired force, glyphs, loading, comparison and the 3D views'
directions; options given as well override the session's.

Several views in one run (``--view pose,workspace,map --out figs/inverse3_{view}.pdf``)
share the start-up (importing PyVista and matplotlib is about 1 s of a single figure's 2 s
on a 2-core machine) and the maps: views on the same grid compute it once. The files are
written all or none: a view that fails leaves none of them.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from app.cli._args import (
    MapJob,
    UsageError,
    add_max_time_argument,
    add_resolution_argument,
    check_job,
    device_grid,
    job_points,
    load_device,
    parse_point,
)
from app.cli._plane import add_plane_argument, plane_of
from app.cli._progress import progress_for
from app.cli.pose import check_pose
from app.files.export import FIGURE_SUFFIXES, check_output, staged
from app.files.session import Session, SessionError, read_session
from app.logic.glyphs import DEFAULT_GLYPHS, GLYPHS, glyph_unavailable
from app.logic.planes import is_volume, plane_text, slice_grid
from app.render.views import FLAT_VIEWS, VIEWS, export_view, parse_size
from app.scenes import WORKSPACE_MAX_POINTS
from metrics.quantities import CORE_QUANTITIES, QUANTITIES, check_quantities
from metrics.workspace import compute_map

#: The placeholder in ``--out`` that each view's name replaces.
VIEW_FIELD = "{view}"
#: The views drawn from a 2D map: a 3D box map's are drawn on one plane of it (``--plane``).
FLAT_MAP_VIEWS = FLAT_VIEWS


def _glyphs(text: str | None, mechanism=None) -> frozenset[str]:
    """``--glyphs``' names (default ``DEFAULT_GLYPHS``); a UsageError for an unknown one, or one
    ``mechanism`` cannot draw (``glyph_unavailable``: the inertia ellipsoid without a mass model)."""
    if text is None:
        return DEFAULT_GLYPHS
    names = frozenset(t.strip() for t in text.split(",") if t.strip())
    unknown = sorted(names - set(GLYPHS))
    if unknown:
        raise UsageError(f"--glyphs: unknown glyph {unknown[0]!r}; known: {', '.join(GLYPHS)}")
    for name in sorted(names) if mechanism is not None else ():
        problem = glyph_unavailable(name, mechanism)
        if problem is not None:
            raise UsageError(f"--glyphs {name}: {problem}")
    return names


def _force(text: str, m: int) -> tuple[float, ...]:
    """``"FX,FY,FZ"`` in N, or a UsageError naming --force."""
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != m:
        raise UsageError(f"--force needs {m} comma-separated numbers in N, got {text!r}")
    return values


def _views(text: str) -> tuple[str, ...]:
    """``"pose,workspace"`` -> the views in order, each once; a UsageError naming --view otherwise."""
    names = tuple(dict.fromkeys(t.strip() for t in text.split(",") if t.strip()))
    unknown = [n for n in names if n not in VIEWS]
    if not names or unknown:
        raise UsageError(f"--view: unknown view {(unknown or [text])[0]!r}; known: {', '.join(VIEWS)}")
    return names


def _outputs(pattern: str, views: tuple[str, ...]) -> dict[str, Path]:
    """Each view's output file: ``{view}`` in ``--out`` replaced by its name, each checked before computing."""
    if len(views) > 1 and VIEW_FIELD not in pattern:
        raise UsageError(f"--out needs {VIEW_FIELD} in its name for several views (one file each), "
                         f"e.g. figs/device_{VIEW_FIELD}.png; got {pattern!r}")
    try:
        return {v: check_output(pattern.replace(VIEW_FIELD, v), FIGURE_SUFFIXES, "--out") for v in views}
    except ValueError as exc:
        raise UsageError(str(exc)) from None


def _check_overlay_args(args, preset, views: tuple[str, ...]) -> float | None:
    """``--ellipse`` and ``--spacing`` (mm -> m) for ``--view ellipses``; a UsageError otherwise."""
    mech = preset.mechanism
    if "ellipses" not in views:
        for option, value in (("--ellipse", args.ellipse), ("--spacing", args.spacing)):
            if value is not None:
                raise UsageError(f"{option} applies to --view ellipses only, not --view {','.join(views)}")
        return None
    if mech.task_dim != 2 or set(preset.grid.axes) != set(mech.task_names) or is_volume(preset.grid):
        raise UsageError(f"--view ellipses needs a planar device (2D task): {preset.key!r} has task "
                         f"{', '.join(mech.task_names)}; its ellipsoids have no one in-plane ellipse "
                         "(use --view pose for the 3D ellipsoid at a point)")
    if args.spacing is None:
        return None
    # Imported here: the pose and workspace views draw no overlay.
    from app.plots.overlays import MAX_ELLIPSES, lattice_size
    if not (np.isfinite(args.spacing) and args.spacing > 0):
        raise UsageError(f"--spacing needs a positive length in mm, got {args.spacing:g}")
    count = lattice_size(preset.grid, args.spacing / 1e3)
    if count > MAX_ELLIPSES:
        raise UsageError(f"--spacing {args.spacing:g} mm gives {count} ellipses over the map, more than "
                         f"{MAX_ELLIPSES}: use a larger spacing")
    return args.spacing / 1e3


def _session(args) -> Session | None:
    """``--session``'s file, read (a UsageError naming the file and key if it is bad); None without it."""
    if args.session is None:
        if args.device is None:
            raise UsageError("DEVICE is required (a preset key or a .toml file), or --session FILE")
        return None
    if args.device is not None or args.overrides:
        raise UsageError("--session gives the device and its design: drop DEVICE and --set, or drop --session")
    try:
        return read_session(args.session)
    except SessionError as exc:
        raise UsageError(f"--session: {exc}") from None


def _from_session(args, session: Session) -> None:
    """Fill the options not given on the command line from the session (display units, as typed)."""
    from kinematics.units import task_from_si
    mech = session.mechanism
    if args.quantity is None:
        args.quantity = session.quantity
    if args.at is None and session.pose is not None:
        args.at = ",".join(repr(float(v)) for v in task_from_si(mech, session.pose))
    if args.force is None and session.desired_force is not None and any(session.desired_force):
        args.force = ",".join(repr(float(v)) for v in session.desired_force)
    if args.glyphs is None:
        args.glyphs = ",".join(sorted(session.glyphs))
    if args.compare is None and session.reference_mechanism is not None:
        args.compare = session.compare_mode


def _check_unused(args, views: tuple[str, ...], session: Session | None = None) -> None:
    """A UsageError for an option none of ``views`` uses (it would be ignored without a word),
    and for a comparison with nothing to compare (no ``--set``: the preset against itself)."""
    if session is not None:
        if "compare" in views and session.reference_mechanism is None:
            raise UsageError(f"--view compare: session {args.session!r} has no reference (Compare > Pin in the app)")
        return          # the session's settings are for whichever view draws them
    for option, value, view in (("--at", args.at, "pose"), ("--force", args.force, "pose"),
                                ("--glyphs", args.glyphs, "pose"), ("--compare", args.compare, "compare")):
        if value is not None and view not in views:
            raise UsageError(f"{option} applies to --view {view} only, not --view {','.join(views)}")
    if "compare" in views and not getattr(args, "overrides", None):
        raise UsageError("--view compare compares the preset with the design --set makes of it "
                         "(e.g. --set gear_ratios=13.75,5.957,5.957); without --set there is nothing to compare")


def _view_grid(view: str, preset, resolution: int | None, plane=None):
    """The grid ``view`` is drawn from (``None`` for the pose view, which needs no map): a flat
    view of a 3D box map is drawn on ``plane`` (``(axis, m)``), a 2D grid of its own."""
    if view == "pose":
        return None
    grid = device_grid(preset, resolution)
    if plane is not None and view in FLAT_MAP_VIEWS:
        return slice_grid(grid, *plane)
    if view == "workspace" and resolution is None:
        # The 3D view draws at most WORKSPACE_MAX_POINTS per axis: a finer map would be computed
        # only to be subsampled (the Inverse3's 1000 x 1000 slice: 1 s and 70 MB for nothing).
        grid = grid.with_resolution(tuple(min(n, WORKSPACE_MAX_POINTS) for n in grid.resolution))
    return grid


def run(args: argparse.Namespace) -> int:
    session = _session(args)
    if session is not None:
        preset = session.design_preset
        _from_session(args, session)
    else:
        preset = load_device(args)
    args.quantity = args.quantity or "isotropic_force"
    mech = preset.mechanism
    loading = session.loading if session is not None else None
    views = _views(args.view)
    targets = _outputs(args.out, views)
    try:
        size = parse_size(args.size) if args.size else None
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    column = _column(args, views)
    quantity = args.quantity
    try:
        check_quantities(mech, [quantity])
    except ValueError as exc:
        raise UsageError(f"--quantity: {exc}") from None
    if not QUANTITIES[quantity].scalar:
        raise UsageError(f"--quantity: {quantity!r} is not one number per point, so no map shows it")
    pose = tuple(parse_point(args.at, mech)) if args.at else preset.pose
    if "pose" in views:
        if pose is None:
            raise UsageError(f"--at is required: preset {preset.key!r} has no default pose")
        check_pose(preset, np.asarray(pose, float), from_preset=not args.at)     # exit 2 like `pose`
    _check_unused(args, views, session)
    spacing = _check_overlay_args(args, preset, views)
    desired = _force(args.force, mech.task_dim) if args.force else None
    glyphs = _glyphs(args.glyphs, mech)
    needed = tuple(sorted(set(CORE_QUANTITIES) | {quantity}))
    # One map per distinct grid, each checked against the memory before any is computed.
    flat = [v for v in views if v in FLAT_MAP_VIEWS]
    if args.plane is not None and not flat:
        raise UsageError(f"--plane applies to --view {', '.join(FLAT_MAP_VIEWS)} only, not --view {','.join(views)}")
    plane = plane_of(args.plane, device_grid(preset, args.resolution), preset) if flat else None
    if flat and args.plane is None and session is not None and session.plane is not None:
        plane = session.plane
    grids = {v: _view_grid(v, preset, args.resolution, plane) for v in views}
    distinct = list(dict.fromkeys(g for g in grids.values() if g is not None))
    # The compare view's reference map is held with its own (copies) and timed as the device's.
    jobs = [MapJob(mech, grid, needed, output="figure", copies=2 if grids.get("compare") == grid else 1)
            for grid in distinct]
    jobs += [MapJob(mech, grids["compare"], needed, output="figure", copies=2)] if "compare" in views else []
    reference_preset = session.reference_preset if session is not None else None
    reference_grid = (_view_grid("compare", reference_preset, args.resolution, plane)
                      if reference_preset is not None and "compare" in views else grids.get("compare"))
    job = check_job("figure", jobs, max_time=args.max_time)
    maps, reference_map, reference, done = {}, None, None, 0
    with progress_for("isoforce figure", job and job.seconds, job_points(jobs)) as progress:
        for grid in distinct:
            maps[grid] = compute_map(mech, grid, needed, progress=progress.part(done, math.prod(grid.resolution)),
                                     loading=loading)
            done += math.prod(grid.resolution)
        if "compare" in views:
            if session is not None:
                reference = session.reference_mechanism
            else:
                from resources import load_preset
                reference = load_preset(args.device).mechanism
            reference_map = compute_map(reference, reference_grid, needed, loading=loading,
                                        progress=progress.part(done, math.prod(reference_grid.resolution)))
    # All or none: a view that fails (or an interrupt) leaves none of the run's files.
    try:
        with staged(targets.values()) as stages:
            for view in views:
                try:
                    export_view(view, stages[targets[view]], preset=preset, mechanism=mech,
                                workspace_map=maps.get(grids[view]), quantity=quantity, pose=pose, glyphs=glyphs,
                                desired_force=desired, reference_map=reference_map, size=size,
                                compare_mode=args.compare or "side", ellipse=args.ellipse or "force", spacing=spacing,
                                reference_mechanism=reference, plane=plane, loading=loading,
                                overlay=session.overlay if session is not None and view == "map" else "none",
                                camera=session.cameras.get(view) if session is not None else None,
                                column=column)
                except (ValueError, RuntimeError) as exc:
                    # RuntimeError: FreeType refusing a font size, at a --size too small for the view's text.
                    raise UsageError(f"--view {view}: {exc}; no file written") from None
    except OSError as exc:
        raise UsageError(f"--out: {exc}") from None
    where = plane_text(device_grid(preset, args.resolution), *plane, mech) if plane is not None else None
    for view in views:
        # stdout: stderr is for errors and warnings only
        print(f"wrote {targets[view]}" + (f" ({where})" if where and view in FLAT_MAP_VIEWS else ""))
    return 0


#: A page narrower or wider than these (inches) or a font outside these (points) is a typo.
COLUMN_INCHES, FONT_POINTS = (1.0, 20.0), (4.0, 30.0)


def _column(args, views) -> tuple[float, float] | None:
    """``(width in, font pt)`` from ``--width-in`` and ``--font-pt``, or None; checked."""
    if args.width_in is None:
        if args.font_pt is not None:
            raise UsageError("--font-pt needs --width-in (the column the text is sized for)")
        return None
    font = 8.0 if args.font_pt is None else args.font_pt
    for flag, value, (lo, hi), unit in (("--width-in", args.width_in, COLUMN_INCHES, "in"),
                                        ("--font-pt", font, FONT_POINTS, "pt")):
        if not lo <= value <= hi:
            raise UsageError(f"{flag} must be {lo:g} to {hi:g} {unit}, got {value:g}")
    if args.size:
        raise UsageError("--size (pixels) and --width-in (inches) both set the size: give one")
    raster = [v for v in views if v in ("pose", "workspace")]
    if raster:
        raise UsageError(f"--width-in applies to the flat views (map, compare, bands, ellipses), not --view "
                         f"{','.join(raster)}: the 3D views are rasters, sized by --size")
    return args.width_in, font


def register(subparsers) -> None:
    p = subparsers.add_parser("figure", help="render one of the app's views to PNG/SVG/PDF, headless",
                              description=__doc__.split("\n\n")[0])
    # DEVICE may come from --session instead (``add_device_argument``'s, optional here).
    p.add_argument("device", metavar="DEVICE", nargs="?",
                   help="preset key (see `isoforce devices`) or path to a .toml; not with --session")
    p.add_argument("--set", dest="overrides", metavar="NAME=VALUE", action="extend", nargs="+", default=[],
                   help="override a parameter by the name `show` prints, in its display unit; vectors "
                        "comma-separated, e.g. gear_ratios=13.75,5.957,5.957 (takes several, so put DEVICE first)")
    p.add_argument("--session", metavar="FILE",
                   help="draw what the app showed: a session file (the app's File > Save session) gives the "
                        "design, quantity, overlay, plane, pose, glyphs, loading, reference and 3D directions")
    p.add_argument("--view", default="map", metavar="VIEW[,VIEW...]",
                   help=f"which view ({', '.join(VIEWS)}; default: map); several, comma-separated, are "
                        f"rendered in one run, with {VIEW_FIELD} in --out")
    p.add_argument("--quantity", help="map quantity (default: isotropic_force, or the session's)")
    p.add_argument("--at", metavar="X,Y,...",
                   help="pose for the pose view: the device's task coordinates, comma-separated (mm; deg for "
                        "angles; as many as the default pose `isoforce show DEVICE` prints; default: that pose)")
    p.add_argument("--force", metavar="FX,FY,...",
                   help="pose view: a desired force in N (one value per force coordinate, 2 for a planar "
                        "device), drawn with its clamp to the isotropic force")
    p.add_argument("--glyphs", metavar="NAMES", help=f"comma-separated glyphs to draw ({', '.join(GLYPHS)})")
    p.add_argument("--compare", choices=("side", "difference"),
                   help="compare view: side by side (default) or current - reference")
    p.add_argument("--size", metavar="WxH",
                   help="PNG size in pixels. Map views are drawn at that size (default: their own, about "
                        "1100 px wide); 3D views are cropped to their content within it (default 1600x1200)")
    p.add_argument("--width-in", type=float, metavar="IN",
                   help="flat views (map, compare, bands, ellipses): the page's width in inches, e.g. 3.5 for a "
                        "journal column; the text at --font-pt and nothing clipped (PDF and SVG stay vector)")
    p.add_argument("--font-pt", type=float, metavar="PT",
                   help="with --width-in: the body text's size in points (default 8)")
    p.add_argument("--ellipse", choices=("force", "velocity"),
                   help="ellipses view: force ellipses in N (default) or velocity ellipses in m/s per rad/s")
    p.add_argument("--spacing", type=float, metavar="MM",
                   help="ellipses view: spacing of the ellipses in mm (default: about 20 across the map)")
    add_plane_argument(p)
    add_resolution_argument(p)
    add_max_time_argument(p)
    p.add_argument("--out", required=True,
                   help=f"output file: .png, .svg or .pdf; {VIEW_FIELD} in it is replaced by the view's name")
    p.set_defaults(func=run)
