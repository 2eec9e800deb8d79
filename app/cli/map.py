"""``isoforce map DEVICE --quantity Q --out FILE``: a heat map (.png/.svg/.pdf) or the data (.csv/.npz).
"""
from __future__ import annotations

import argparse

from app.cli._args import (
    MapJob,
    UsageError,
    add_device_argument,
    add_loading_arguments,
    add_max_time_argument,
    add_resolution_argument,
    check_job,
    check_out,
    device_grid,
    job_points,
    load_device,
    loading_of,
)
from app.cli._plane import add_plane_argument, plane_of
from app.cli._progress import progress_for
from app.files.export import FIGURE_SUFFIXES, MAP_SUFFIXES, write_map
from app.logic.planes import plane_text, slice_grid
from metrics.quantities import MAP_QUANTITIES, available_quantities, check_quantities, quantity_scope_help
from metrics.workspace import compute_map


def register(subparsers) -> None:
    p = subparsers.add_parser("map", help="heat map (.png/.svg/.pdf) or data (.csv/.npz) of a quantity",
                              description="Compute a quantity over the device's default map and write a heat "
                                          "map with colour bar (.png, .svg, .pdf) or the data (.csv, .npz). "
                                          "Data files take several quantities, comma-separated. Forces at "
                                          "the continuous torque rating with gravity off unless --rating and "
                                          "--gravity say otherwise (the line it prints says which).")
    add_device_argument(p)
    p.add_argument("--quantity", required=True, metavar="Q",
                   help=f"one of {', '.join(MAP_QUANTITIES)} ({quantity_scope_help()})")
    p.add_argument("--out", required=True, metavar="FILE", help="output file: .png, .svg, .pdf, .csv or .npz")
    add_plane_argument(p)
    add_resolution_argument(p)
    add_loading_arguments(p)
    add_max_time_argument(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    preset = load_device(args)
    mech = preset.mechanism
    loading = loading_of(args, preset)
    target = check_out(args.out, FIGURE_SUFFIXES + MAP_SUFFIXES)
    figure = target.suffix.lower() in FIGURE_SUFFIXES
    names = [q.strip() for q in args.quantity.split(",")]
    try:
        check_quantities(mech, names)
        bad = [q for q in names if q not in available_quantities(mech)]
        if bad:
            raise ValueError(f"{bad[0]!r} is not a per-point quantity; choose from "
                             f"{', '.join(available_quantities(mech))}")
    except ValueError as exc:
        raise UsageError(f"--quantity: {exc}") from None
    if figure and len(names) != 1:
        raise UsageError(f"--quantity: a figure shows one quantity, got {args.quantity!r}")
    grid = device_grid(preset, args.resolution)
    # A figure of a 3D box is one plane of it, and so are the data with --plane (without: the volume).
    plane = plane_of(args.plane, grid, preset) if figure or args.plane is not None else None
    if plane is not None:
        grid = slice_grid(grid, *plane)
    output = "figure" if figure else target.suffix.lower().lstrip(".")
    map_job = MapJob(mech, grid, tuple(names), output=output, loading=loading)
    job = check_job("map", map_job, max_time=args.max_time)
    with progress_for("isoforce map", job and job.seconds, job_points(map_job)) as progress:
        wmap = compute_map(mech, grid, names, loading=loading, progress=progress)
    if figure:
        from app.logic.colour_scale import plane_scale
        from app.plots.figures import map_figure, save_figure  # matplotlib only when drawing
        scale = plane_scale(wmap, wmap, names[0], preset) if plane is not None else None
        save_figure(map_figure(wmap, names[0], preset, scale=scale), target, name="--out")
    else:
        write_map(wmap, target, device=preset.key, name="--out")
    where = f"; {plane_text(device_grid(preset, args.resolution), *plane, mech)}" if plane is not None else ""
    print(f"wrote {target} ({' x '.join(map(str, wmap.grid.resolution))} grid{where}, "
          f"{wmap.feasible_points} feasible points, {wmap.seconds:.3f} s; {loading.describe()})"
          + ("; no feasible point: the map is blank (check the map's range and the parameters)"
             if wmap.feasible_points == 0 else ""))
    return 0
