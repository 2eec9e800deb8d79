"""``isoforce stats DEVICE``: global figures of the default workspace map, streamed chunk by chunk.
"""
from __future__ import annotations

import argparse

from app.cli._args import (
    MapJob,
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
    overridden_values,
)
from app.cli._format import (
    condition_label,
    loading_dict,
    loading_text,
    point_text,
    print_json,
    table,
    with_error,
)
from app.cli._progress import progress_for
from app.files.export import STATS_SUFFIXES, atomic_write
from app.files.stats_files import dumps, stats_summary, write_stats
from app.logic.display_units import display_unit, scaled_errors, scaled_stats
from app.logic.figure_digits import shown_error, unresolved_note
from metrics.quantities import QUANTITIES, summary_quantities
from metrics.workspace import compute_map
from metrics.wrenches import condition_number_scaling


def register(subparsers) -> None:
    p = subparsers.add_parser("stats", help="global figures of the default workspace map",
                              description="Statistics (min, p05, median, mean, p95, max, SD with ddof = 1, count, "
                                          "where the extremes are) of the condition number, maximum anisotropic "
                                          "and isotropic force and 1 / condition number over the regular "
                                          "feasible points of the device's default map, and the global "
                                          "conditioning index. Singular points are counted and left out; a "
                                          "maximum that is infinite in truth is reported as unbounded. Global "
                                          "figures depend on the grid resolution: see `isoforce convergence`. "
                                          "The forces are at the continuous torque rating with gravity off "
                                          "unless --rating and --gravity say otherwise; the output says which.")
    add_device_argument(p)
    add_resolution_argument(p)
    add_loading_arguments(p)
    add_max_time_argument(p)
    p.add_argument("--out", metavar="FILE", help="also write the statistics to a .json or .csv file")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)



#: Whether ``isoforce stats`` holds the whole map while it takes the statistics: no, they are
#: streamed chunk by chunk (``compute_map(..., keep=False)``), so the memory estimate is by
#: chunk and does not grow with the resolution.
STATS_KEEPS_MAPS = False

NO_FEASIBLE_POINT = "no feasible point on this grid: no statistics (check the map's range and the parameters)"


def run(args: argparse.Namespace) -> int:
    preset = load_device(args)
    if args.out is not None:
        check_out(args.out, STATS_SUFFIXES)
    mech = preset.mechanism
    loading = loading_of(args, preset)
    grid = device_grid(preset, args.resolution)
    names = summary_quantities(mech)        # + the moment capabilities of a wrench device
    map_job = MapJob(mech, grid, names, keep_maps=STATS_KEEPS_MAPS, loading=loading)
    job = check_job("stats", map_job, max_time=args.max_time)
    with progress_for("isoforce stats", job and job.seconds, job_points(map_job), json_out=args.json) as progress:
        wmap = compute_map(mech, grid, names, keep=STATS_KEEPS_MAPS, loading=loading, progress=progress)
    summary = stats_summary(wmap, device=preset.key, quantities=names)
    summary["loading"] = loading_dict(loading, mech)
    scaling = condition_number_scaling(mech)
    if scaling is not None:
        summary["condition_number_scaling"] = scaling
    if args.overrides:
        summary["overrides"] = overridden_values(mech, args.overrides)
    if wmap.feasible_points == 0:
        summary["message"] = NO_FEASIBLE_POINT
    if args.out is not None and args.out.lower().endswith(".json"):
        # The summary printed by --json, loading included (write_stats would leave it out).
        text = dumps(summary) + "\n"
        atomic_write(check_out(args.out, STATS_SUFFIXES), lambda tmp: tmp.write_text(text, encoding="utf-8"),
                     name="--out")
    elif args.out is not None:
        write_stats(wmap, args.out, device=preset.key, quantities=names, name="--out")
    if args.json:
        print_json(summary)
        return 0
    print(f"{preset.name} ({preset.key}): {' x '.join(map(str, summary['resolution']))} grid over "
          f"{', '.join(summary['axes'])}; {summary['feasible_points']} of {summary['total_points']} points "
          f"feasible, {wmap.singular_points} of them singular; {summary['seconds']:.3f} s")
    print(loading_text(loading, mech))
    if wmap.feasible_points == 0:
        print(NO_FEASIBLE_POINT)
        return 0
    print(stats_table(mech, wmap, names))
    if scaling is not None:
        print(f"condition_number: {condition_label(scaling)}; isotropic/anisotropic_force at zero moment, "
              f"isotropic/anisotropic_moment at zero force")
    return 0


def stats_table(mech, wmap, names) -> str:
    """The ``stats`` text: one row per quantity, its figures with their grid errors, then notes."""
    rows = [("quantity", "unit", "min", "p05", "median", "mean", "p95", "max", "sd", "argmin", "argmax")]
    notes = []
    unresolved_notes = []
    resolution = tuple(int(n) for n in wmap.grid.resolution)
    for q in names:
        unit, factor = display_unit(q)
        s = scaled_stats(wmap.stats[q], factor)
        err = scaled_errors(wmap.errors.get(q, {}), factor)
        cells = [with_error(getattr(s, k), err.get(k)) for k in ("min", "p05", "median", "mean", "p95")]
        if s.vanishes:
            cells[0] = "0 (singular)"
        cells.append("unbounded" if s.unbounded else with_error(s.max, err.get("max")))
        cells.append(with_error(s.sd, err.get("sd")))
        orders = wmap.error_orders.get(q, {})
        for k in ("min", "p05", "median", "mean", "p95", "max", "sd"):
            if not (k == "max" and s.unbounded) and err.get(k) is not None:
                note = unresolved_note(getattr(s, k), shown_error(getattr(s, k), err[k]), orders.get(k), resolution)
                unresolved_notes += [f"{q} {k}: {note}"] if note else []
        where_max = (point_text(mech, s.unbounded_at[0], 4) if s.unbounded
                     else point_text(mech, s.argmax, 4) if s.argmax else "-")
        rows.append((q, unit or "-", *cells,
                     point_text(mech, s.argmin, 4) if s.argmin else "-", where_max))
        if s.unbounded:
            why = {"N": "the ideal device resists unbounded force there",
                   "N m": "the ideal device resists unbounded moment there",
                   "m": "the end-effector moves there while no joint sensor counts",
                   "rad": "the end-effector turns there while no joint sensor counts"}.get(
                QUANTITIES[q].unit, "J or its inverse loses rank there")
            notes.append(f"{q}: max unbounded: the feasible set reaches a singularity, e.g. at "
                         f"{point_text(mech, s.unbounded_at[0], 4)} ({why}); the other figures are over "
                         f"regular points")
        if s.vanishes:
            notes.append(f"{q}: min 0: the feasible set reaches a singularity where it vanishes, e.g. at "
                         f"{point_text(mech, s.vanishes_at[0], 4)}; the grid's smallest value is not the minimum")
    lines = [table(rows)]
    if wmap.gci is not None:
        lines.append(f"global conditioning index (mean of 1 / condition number, Gosselin and Angeles 1991): "
                     f"{with_error(wmap.gci, wmap.gci_error)}")
        if wmap.gci_error is not None:
            note = unresolved_note(wmap.gci, shown_error(wmap.gci, wmap.gci_error), wmap.gci_error_order, resolution)
            unresolved_notes += [f"global conditioning index: {note}"] if note else []
    sing = next(iter(wmap.stats.values()), None)
    if sing is not None and sing.singular_points:
        where = ", ".join(point_text(mech, p, 4) for p in sing.singular_at[:3])
        lines.append(f"{sing.singular_points} singular feasible point(s) left out of mean, SD and percentiles, "
                     f"e.g. at {where}")
    lines += notes
    lines += unresolved_notes
    if unresolved_notes:
        lines.append("(unresolved: the error is at least the figure; the points per axis that would resolve it "
                     "extrapolate the error as h^p, p observed from the half and quarter grids; "
                     "`isoforce convergence` measures it)")
    below = ("; +- <0.0005 and the like: the half grids give the same figure, its error is below half a unit "
             "of its last digit" if "+- <" in lines[0] or "+- <" in "".join(lines[1:2]) else "")
    lines.append("(+- : estimated error from the grid resolution, the change from half the resolution"
                 f"{below}; `isoforce convergence` measures it)")
    return "\n".join(lines)
