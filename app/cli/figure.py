"""``isoforce figure``: the app's own views rendered off-screen, with no display.

``--view map`` heat map, ``pose`` the 3D pose with its force glyphs, ``workspace`` the 3D
workspace, ``compare`` the preset's own design (reference) against the design with the
``--set`` changes (current), ``bands`` paper 002's condition-number bands (its Fig. 5, with
the five-bar's dexterous annulus), ``ellipses`` its force or velocity ellipses over the map
(its Fig. 9; planar devices only). PNG/SVG/PDF by the suffix of ``--out``.

``--session FILE`` (the app's File > Save session) draws what the app showed: its design, map
quantity, overlay, map range (fitted to the workspace), plane and its colour range, pose,
desired force, glyphs, loading, comparison and the 3D views' directions; options given as well
override the session's.

Several views and several devices in one run (``--view pose,workspace,map``, DEVICE DEVICE ...)
share the start-up (importing PyVista and matplotlib is about 1 s of a single figure's 2 s
on a 2-core machine) and the maps: views of a device on the same grid compute it once. Each
file is named by ``--out`` with ``{device}`` and ``{view}`` in it (each needed when there are
several), or ``--out-dir DIR`` (``DIR/{device}_{view}.png``, ``--format`` for SVG or PDF). Two
figures that would write one file are refused before anything is computed. The files are
written all or none: a view that fails (or an interrupt) leaves none of them.
"""
from __future__ import annotations

import argparse
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

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
from app.files.export import FIGURE_SUFFIXES, check_output, staged
from app.logic.glyphs import DEFAULT_GLYPHS, GLYPHS, glyph_unavailable
from app.logic.planes import is_volume, plane_text, slice_grid
from app.render.views import (
    COLUMN_INCHES,
    FLAT_VIEWS,
    FONT_POINTS,
    VIEWS,
    export_view,
    parse_size,
    raster_note,
)
from app.scenes.snapshot import PRINT_DPI
from metrics.quantities import CORE_QUANTITIES, QUANTITIES, check_quantities

if TYPE_CHECKING:
    from app.files.session import Session

#: The placeholders in ``--out`` that each view's name and each device's name replace.
VIEW_FIELD, DEVICE_FIELD = "{view}", "{device}"
#: ``--out-dir``'s file names.
OUT_DIR_NAME = f"{DEVICE_FIELD}_{VIEW_FIELD}"
#: The views drawn from a 2D map: a 3D box map's are drawn on one plane of it (``--plane``).
FLAT_MAP_VIEWS = FLAT_VIEWS


def compute_map(*args, **kwargs):
    """``metrics.workspace.compute_map``, its module imported on first use: a pose figure
    computes no map and does not load the map's modules (0.03-0.1 s of its start-up)."""
    from metrics.workspace import compute_map as compute
    return compute(*args, **kwargs)


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


def device_name(text: str) -> str:
    """What ``{device}`` in ``--out`` becomes for a DEVICE argument: a preset key as typed, a
    ``.toml`` file's name without its folder and suffix.

    >>> device_name("inverse3_prototype"), device_name("designs/my_pen.toml")
    ('inverse3_prototype', 'my_pen')
    """
    path = Path(text)
    return path.stem if path.suffix.lower() == ".toml" else text


def _outputs(args, views: tuple[str, ...], devices: list[str]) -> dict[tuple[str, str], Path]:
    """Each figure's file, ``{(device, view): path}``, from ``--out`` (``{device}`` and ``{view}`` replaced)
    or ``--out-dir`` (``OUT_DIR_NAME`` with ``--format``'s suffix), each checked before computing.

    A UsageError when the names cannot tell the figures apart: several views without ``{view}``,
    several devices without ``{device}``, an unknown ``{field}``, or two figures on one file
    (two DEVICE files of one name in different folders)."""
    out, folder, fmt = args.out, getattr(args, "out_dir", None), getattr(args, "format", None)
    if out is not None and folder is not None:
        raise UsageError("--out and --out-dir both name the files: give one")
    if out is None and folder is None:
        raise UsageError("--out FILE or --out-dir DIR is required")
    if fmt is not None and folder is None:
        raise UsageError("--format applies to --out-dir; --out takes the format from its suffix")
    if folder is not None:
        if not Path(folder).is_dir():
            raise UsageError(f"--out-dir: folder {folder!r} does not exist")
        option, pattern = "--out-dir", str(Path(folder) / (OUT_DIR_NAME + "." + (fmt or "png")))
    else:
        option, pattern = "--out", out
        unknown = sorted(set(re.findall(r"\{[^{}]*\}", pattern)) - {VIEW_FIELD, DEVICE_FIELD})
        if unknown:
            raise UsageError(f"--out: unknown field {unknown[0]} in {pattern!r}; known: {VIEW_FIELD}, {DEVICE_FIELD}")
        if len(views) > 1 and VIEW_FIELD not in pattern:
            raise UsageError(f"--out needs {VIEW_FIELD} in its name for several views (one file each), "
                             f"e.g. figs/device_{VIEW_FIELD}.png; got {pattern!r}")
        if len(devices) > 1 and DEVICE_FIELD not in pattern:
            raise UsageError(f"--out needs {DEVICE_FIELD} in its name for several devices (one file each), "
                             f"e.g. figs/{DEVICE_FIELD}_{VIEW_FIELD}.pdf, or use --out-dir; got {pattern!r}")
    names = [device_name(d) for d in devices]
    targets, seen = {}, {}
    for device, name in zip(devices, names):
        for view in views:
            path = pattern.replace(DEVICE_FIELD, name).replace(VIEW_FIELD, view)
            try:
                target = check_output(path, FIGURE_SUFFIXES, option)
            except ValueError as exc:
                raise UsageError(str(exc)) from None
            key = os.path.normcase(os.path.abspath(target))
            if key in seen:
                raise UsageError(f"{option}: DEVICE {seen[key][0]!r} and {device!r} would both write {str(target)!r} "
                                 f"(--view {seen[key][1]} and {view}): their names must differ")
            seen[key] = (device, view)
            targets[device, view] = target
    return targets


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
        if not args.device:
            raise UsageError("DEVICE is required (a preset key or a .toml file), or --session FILE")
        if len(args.device) > 1 and args.overrides:
            raise UsageError("--set changes one device's design: give one DEVICE with --set")
        return None
    if args.device or args.overrides:
        raise UsageError("--session gives the device and its design: drop DEVICE and --set, or drop --session")
    # Imported here: a figure without a session does not load the session's file format.
    from app.files.session import SessionError, read_session
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


def _view_grid(view: str, preset, resolution: int | None, plane=None, colour_range: str = "plane"):
    """The grid ``view`` is drawn from (``None`` for the pose view, which needs no map): a flat
    view of a 3D box map is drawn on ``plane`` (``(axis, m)``), a 2D grid of its own, unless its
    colours span the whole volume (``colour_range`` ``"volume"``, a session's): then the volume
    is computed and ``export_view`` cuts the plane from it, as the app does."""
    if view == "pose":
        return None
    grid = device_grid(preset, resolution)
    if plane is not None and view in FLAT_MAP_VIEWS and colour_range != "volume":
        return slice_grid(grid, *plane)
    if view == "workspace" and resolution is None:
        from app.scenes import WORKSPACE_MAX_POINTS  # (the workspace scene's module: only this view's)
        # The 3D view draws at most WORKSPACE_MAX_POINTS per axis: a finer map would be computed
        # only to be subsampled (the Inverse3's 1000 x 1000 slice: 1 s and 70 MB for nothing).
        grid = grid.with_resolution(tuple(min(n, WORKSPACE_MAX_POINTS) for n in grid.resolution))
    return grid


@dataclass
class _Plan:
    """One device's part of a run: its design, what its views need, and the grids of its maps."""

    device: str                      # DEVICE as typed (or the session's design key)
    preset: object
    pose: tuple | None
    desired: tuple | None
    glyphs: frozenset
    spacing: float | None
    plane: tuple | None
    grids: dict                      # view -> grid (None: the pose view)
    distinct: list                   # the grids to compute, once each
    session: Session | None = None
    reference_grid: object = None
    maps: dict = field(default_factory=dict)
    reference_map: object = None
    reference: object = None

    @property
    def mechanism(self):
        return self.preset.mechanism

    def jobs(self, needed, views) -> list[MapJob]:
        """The maps ``check_job`` measures: each distinct grid (the compare view's reference held with it)."""
        compare = self.grids.get("compare")
        jobs = [MapJob(self.mechanism, grid, needed, output="figure", copies=2 if compare == grid else 1)
                for grid in self.distinct]
        if "compare" in views:
            jobs.append(MapJob(self.mechanism, compare, needed, output="figure", copies=2))
        return jobs


def _plan(args, device: str, views: tuple[str, ...], quantity: str, session: Session | None) -> _Plan:
    """Load ``device`` and check every option its views use, before any map is computed."""
    if session is not None:
        preset = session.design_preset
    else:
        preset = load_device(argparse.Namespace(device=device, overrides=args.overrides))
    mech = preset.mechanism
    try:
        check_quantities(mech, [quantity])
    except ValueError as exc:
        raise UsageError(f"--quantity: {exc}") from None
    if not QUANTITIES[quantity].scalar:
        raise UsageError(f"--quantity: {quantity!r} is not one number per point, so no map shows it")
    pose = tuple(parse_point(args.at, mech)) if args.at else preset.pose
    if "pose" in views:
        from app.cli.pose import check_pose  # (the pose command's checks: only this view's)
        if pose is None:
            raise UsageError(f"--at is required: preset {preset.key!r} has no default pose")
        check_pose(preset, np.asarray(pose, float), from_preset=not args.at)     # exit 2 like `pose`
    _check_unused(args, views, session)
    spacing = _check_overlay_args(args, preset, views)
    desired = _force(args.force, mech.task_dim) if args.force else None
    glyphs = _glyphs(args.glyphs, mech)
    flat = [v for v in views if v in FLAT_MAP_VIEWS]
    if args.plane is not None and not flat:
        raise UsageError(f"--plane applies to --view {', '.join(FLAT_MAP_VIEWS)} only, not --view {','.join(views)}")
    plane = plane_of(args.plane, device_grid(preset, args.resolution), preset) if flat else None
    if flat and args.plane is None and session is not None and session.plane is not None:
        plane = session.plane
    colours = session.colour_range if session is not None and plane is not None else "plane"
    grids = {v: _view_grid(v, preset, args.resolution, plane, colours) for v in views}
    distinct = list(dict.fromkeys(g for g in grids.values() if g is not None))
    reference_preset = session.reference_preset if session is not None else None
    reference_grid = (_view_grid("compare", reference_preset, args.resolution, plane, colours)
                      if reference_preset is not None and "compare" in views else grids.get("compare"))
    return _Plan(device, preset, pose, desired, glyphs, spacing, plane, grids, distinct, session, reference_grid)


def run(args: argparse.Namespace) -> int:
    session = _session(args)
    if session is not None:
        _from_session(args, session)
    args.quantity = args.quantity or "isotropic_force"
    devices = [session.design_preset.key] if session is not None else list(dict.fromkeys(args.device))
    views = _views(args.view)
    targets = _outputs(args, views, devices)
    try:
        size = parse_size(args.size) if args.size else None
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    column = _column(args, views)
    quantity = args.quantity
    plans = []
    for device in devices:           # every device checked before any map is computed
        try:
            plans.append(_plan(args, device, views, quantity, session))
        except UsageError as exc:
            if len(devices) == 1:
                raise
            raise UsageError(f"DEVICE {device!r}: {exc}") from None
    needed = tuple(sorted(set(CORE_QUANTITIES) | {quantity}))
    # Every map of the run checked against the memory and --max-time before any is computed.
    jobs = [job for plan in plans for job in plan.jobs(needed, views)]
    job = check_job("figure", jobs, max_time=args.max_time) if jobs else None    # (a pose figure has none)
    loading = session.loading if session is not None else None
    done = 0
    with progress_for("isoforce figure", job and job.seconds, job_points(jobs)) as progress:
        for plan in plans:
            for grid in plan.distinct:
                plan.maps[grid] = compute_map(plan.mechanism, grid, needed, loading=loading,
                                              progress=progress.part(done, math.prod(grid.resolution)))
                done += math.prod(grid.resolution)
            if "compare" in views:
                if session is not None:
                    plan.reference = session.reference_mechanism
                else:
                    from resources import load_preset
                    plan.reference = load_preset(plan.device).mechanism
                points = math.prod(plan.reference_grid.resolution)
                plan.reference_map = compute_map(plan.reference, plan.reference_grid, needed, loading=loading,
                                                 progress=progress.part(done, points))
                done += points
    # All or none: a view that fails (or an interrupt) leaves none of the run's files.
    try:
        with staged(targets.values()) as stages:
            for plan in plans:
                for view in views:
                    try:
                        export_view(view, stages[targets[plan.device, view]], preset=plan.preset,
                                    mechanism=plan.mechanism, workspace_map=plan.maps.get(plan.grids[view]),
                                    quantity=quantity, pose=plan.pose, glyphs=plan.glyphs,
                                    desired_force=plan.desired, reference_map=plan.reference_map, size=size,
                                    compare_mode=args.compare or "side", ellipse=args.ellipse or "force",
                                    spacing=plan.spacing, reference_mechanism=plan.reference, plane=plan.plane,
                                    loading=loading,
                                    # A 3D box's plane coloured over the range the app showed it in.
                                    colour_range=session.colour_range if session is not None else "plane",
                                    overlay=session.overlay if session is not None and view == "map" else "none",
                                    camera=session.cameras.get(view) if session is not None else None,
                                    column=column)
                    except (ValueError, RuntimeError) as exc:
                        # RuntimeError: FreeType refusing a font size, at a --size too small for the view's text.
                        which = f"DEVICE {plan.device!r} " if len(plans) > 1 else ""
                        raise UsageError(f"{which}--view {view}: {exc}; no file written") from None
    except OSError as exc:
        raise UsageError(f"--out: {exc}") from None
    for plan in plans:
        where = (plane_text(device_grid(plan.preset, args.resolution), *plan.plane, plan.mechanism)
                 if plan.plane is not None else None)
        for view in views:
            target = targets[plan.device, view]
            notes = [where] if where and view in FLAT_MAP_VIEWS else []
            notes += [raster_note(view, target)] if raster_note(view, target) else []
            # stdout: stderr is for errors and warnings only
            print(f"wrote {target}" + "".join(f" ({n})" for n in notes))
    return 0


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
    return args.width_in, font


def register(subparsers) -> None:
    p = subparsers.add_parser("figure", help="render one of the app's views to PNG/SVG/PDF, headless",
                              description=__doc__.split("\n\n")[0])
    # DEVICE may come from --session instead (``add_device_argument``'s, optional here).
    p.add_argument("device", metavar="DEVICE", nargs="*",
                   help="preset key (see `isoforce devices`) or path to a .toml; several are drawn in one run "
                        f"(one file each: {DEVICE_FIELD} in --out, or --out-dir); not with --session")
    p.add_argument("--set", dest="overrides", metavar="NAME=VALUE", action="extend", nargs="+", default=[],
                   help="override a parameter by the name `show` prints, in its display unit; vectors "
                        "comma-separated, e.g. gear_ratios=13.75,5.957,5.957 (takes several, so put DEVICE first)")
    p.add_argument("--session", metavar="FILE",
                   help="draw what the app showed: a session file (the app's File > Save session) gives the "
                        "design, quantity, overlay, map range, plane, pose, glyphs, loading, reference and 3D "
                        "directions")
    p.add_argument("--view", default="map", metavar="VIEW[,VIEW...]",
                   help=f"which view ({', '.join(VIEWS)}; default: map); several, comma-separated, are "
                        f"rendered in one run, with {VIEW_FIELD} in --out (or --out-dir)")
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
                   help="the page's width in inches, e.g. 3.5 for a journal column: the text at --font-pt and "
                        "nothing clipped. Flat views (map, compare, bands, ellipses) stay vector in PDF and SVG; "
                        "the 3D views (pose, workspace) have vector text and a raster picture at "
                        f"{PRINT_DPI:g} dpi, with a compact caption")
    p.add_argument("--font-pt", type=float, metavar="PT",
                   help="with --width-in: the body text's size in points (default 8)")
    p.add_argument("--ellipse", choices=("force", "velocity"),
                   help="ellipses view: force ellipses in N (default) or velocity ellipses in m/s per rad/s")
    p.add_argument("--spacing", type=float, metavar="MM",
                   help="ellipses view: spacing of the ellipses in mm (default: about 20 across the map)")
    add_plane_argument(p)
    add_resolution_argument(p)
    add_max_time_argument(p)
    p.add_argument("--out", metavar="FILE",
                   help=f"output file: .png, .svg or .pdf; {VIEW_FIELD} and {DEVICE_FIELD} in it are replaced by "
                        f"the view's and the device's name (each needed when there are several)")
    p.add_argument("--out-dir", metavar="DIR",
                   help=f"instead of --out: one file per device and view, DIR/{OUT_DIR_NAME}.png (or --format)")
    p.add_argument("--format", choices=("png", "svg", "pdf"),
                   help="with --out-dir: the files' format (default png)")
    p.set_defaults(func=run)
