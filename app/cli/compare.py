"""``isoforce compare DEVICE DEVICE ... [--json] [--out FILE]``: force figures of several devices side by side.

Each device over its own default map (the preset's grid, or ``--resolution`` points per axis
of it): workspace area (2D slice, cm^2) or volume (3D box, cm^3), the global minimum of the
maximum isotropic force (paper 000's "global maximum isotropic force"), its mean, SD,
median, 5th and 95th percentiles, the maximum anisotropic force (or "unbounded"), the GCI,
and each actuator's share of the workspace as the bottleneck. The figures are the streamed
statistics of ``metrics.workspace.compute_map(..., keep=False)`` (``isoforce stats`` gives
the same numbers with their grid errors); the bottleneck shares are counted by
``metrics.categories.category_counts``. ``--out`` writes the table (.csv, .json) or a figure
(.png, .svg, .pdf) of the isotropic-force distributions on one axis.
"""
from __future__ import annotations

import argparse
import csv
import io
import math
import sys
from typing import Any

from app.cli._args import (
    MapJob,
    UsageError,
    add_loading_arguments,
    add_max_time_argument,
    add_resolution_argument,
    check_job,
    check_memory,
    check_out,
    device_grid,
    job_points,
    load_device,
    loading_of,
)
from app.cli._format import loading_dict, number, print_json, table
from app.cli._progress import progress_for
from app.files.export import FIGURE_SUFFIXES, STATS_SUFFIXES, atomic_write
from app.files.stats_files import dumps
from app.logic.figure_digits import format_with_error, shown_error, unresolved, unresolved_note
from kinematics.units import task_display_units, task_scales
from metrics.bottleneck import BOTTLENECK_SHARED, BOTTLENECK_TIE
from metrics.categories import category_counts
from metrics.quantities import DYNAMIC_SUMMARY
from metrics.workspace import compute_map
from metrics.wrenches import condition_number_scaling

#: The quantities each device's map computes (1 / condition number for the GCI).
COMPARE_QUANTITIES = ("isotropic_force", "anisotropic_force", "inverse_condition_number")
#: Figures of the isotropic force in the comparison, in table order.
FORCE_FIGURES = ("min", "mean", "sd", "median", "p05", "p95")
#: Names of the bottleneck codes that are no single actuator.
SHARE_NAMES = {BOTTLENECK_TIE: "tie", BOTTLENECK_SHARED: "shared"}

WORKSPACE_DEFINITION = ("feasible grid points times the cell size (the product of the grid spacings): "
                        "area of the map's 2D slice in cm^2, volume of its 3D box in cm^3")
CSV_COLUMNS = ("device", "name", "workspace_kind", "workspace", "workspace_unit", "feasible_points",
               "total_points", "resolution", "cell_size", "isotropic_force_min", "isotropic_force_mean",
               "isotropic_force_sd", "isotropic_force_median", "isotropic_force_p05", "isotropic_force_p95",
               "anisotropic_force_max", "gci", "at_zero_moment", "bottleneck_shares", "rating", "gravity_m_s2")


def register(subparsers) -> None:
    p = subparsers.add_parser("compare", help="force figures of several devices side by side",
                              description="For each device over its own default map: workspace area (2D slice, "
                                          "cm^2) or volume (3D box, cm^3) as feasible points times the cell "
                                          "size, global minimum, mean, SD, median, 5th and 95th percentile of "
                                          "the maximum isotropic force, maximum anisotropic force, GCI, and "
                                          "the bottleneck actuator's share of the workspace. Devices with "
                                          "orientation freedoms report forces at zero moment. --out writes "
                                          "the table (.csv, .json) or a box-plot figure (.png, .svg, .pdf). "
                                          "Every device at the same --rating (default continuous) and, with "
                                          "--gravity, the same mounting; a device without that rating or a "
                                          "mass model is an error.")
    p.add_argument("devices", nargs="+", metavar="DEVICE",
                   help="preset keys (see `isoforce devices`) or paths to .toml presets")
    add_resolution_argument(p)
    add_loading_arguments(p)
    add_max_time_argument(p)
    p.add_argument("--out", metavar="FILE", help="also write the table (.csv, .json) or the figure (.png, .svg, .pdf)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def grid_text(mechanism, grid) -> str:
    """A map's range and points, fixed coordinates in their own display units (mm or deg)."""
    units = dict(zip(mechanism.task_names, task_display_units(mechanism)))
    scales = dict(zip(mechanism.task_names, task_scales(mechanism)))
    ranges = ", ".join(f"{a} {lo * scales[a]:g} to {hi * scales[a]:g} {units[a]}"
                       for a, lo, hi in zip(grid.axes, grid.lower, grid.upper))
    fixed = "".join(f", {n} = {v * scales[n]:g} {units[n]}" for n, v in grid.fixed)
    return f"{ranges}{fixed}; {' x '.join(str(r) for r in grid.resolution)} points"


def workspace_size(mechanism, grid, feasible_points: int) -> dict[str, Any]:
    """The map's feasible area or volume: ``feasible_points`` times the cell size.

    Returns a dict with ``kind`` (``"area"``, ``"volume"``), ``value`` (cm^2 or cm^3),
    ``unit`` and ``cell_size`` (same unit); ``value`` is ``nan`` when an axis is an angle.
    """
    units = dict(zip(mechanism.task_names, mechanism.task_units))
    dims = len(grid.axes)
    kind, unit, scale = ("area", "cm^2", 1e4) if dims == 2 else ("volume", "cm^3", 1e6)
    if any(units[a] != "m" for a in grid.axes):
        return {"kind": kind, "value": math.nan, "unit": unit, "cell_size": math.nan}
    cell = math.prod(grid.spacing()) * scale
    return {"kind": kind, "value": feasible_points * cell, "unit": unit, "cell_size": cell}


def map_quantities(mechanism) -> tuple[str, ...]:
    """The quantities of a device's map: ``COMPARE_QUANTITIES``, and ``DYNAMIC_SUMMARY`` with a mass model."""
    return COMPARE_QUANTITIES + (DYNAMIC_SUMMARY if mechanism.has_mass_model else ())


def device_summary(preset, resolution: int | None = None, *, loading=None, progress=None) -> dict[str, Any]:
    """The comparison row of one device (display units: N, cm^2 or cm^3, mm for the grid).

    Parameters
    ----------
    preset : Preset
        The device.
    resolution : int, optional
        Points per map axis (default: the preset's own grid).
    loading : metrics.loading.Loading, optional
        Torque rating and gravity; default continuous, gravity off.
    progress : callable ``(float) -> None``, optional
        ``compute_map``'s progress callback for the device's map.

    Returns
    -------
    dict
        ``key``, ``name``, ``grid``, ``resolution``, ``workspace`` (``workspace_size``),
        ``feasible_points``, ``total_points``, ``isotropic_force`` (``FORCE_FIGURES``, plus
        ``count`` and ``singular_points``), ``anisotropic_force_max`` (``inf`` when unbounded),
        ``anisotropic_force_unbounded``, ``gci``, ``at_zero_moment``, ``condition_number_scaling``,
        ``bottleneck_shares`` (name -> fraction of the feasible points), ``seconds``, ``loading``
        (``_format.loading_dict``: rating, gravity, the rated joint torque limits).
    """
    from metrics.loading import DEFAULT_LOADING

    loading = DEFAULT_LOADING if loading is None else loading
    mech = preset.mechanism
    grid = device_grid(preset, resolution)
    names = map_quantities(mech)
    check_memory(mech, grid, names, keep_maps=False)
    wmap = compute_map(mech, grid, names, keep=False, loading=loading, progress=progress)
    counts = category_counts(mech, grid, "bottleneck", loading=loading)
    iso, aniso = wmap.stats["isotropic_force"], wmap.stats["anisotropic_force"]
    shares = {SHARE_NAMES.get(code, mech.joint_names[code] if code >= 0 else str(code)): share
              for code, share in counts.shares().items()}
    return {
        "key": preset.key,
        "name": preset.name,
        "grid": grid_text(mech, grid),
        "resolution": list(grid.resolution),
        "workspace": workspace_size(mech, grid, wmap.feasible_points),
        "feasible_points": wmap.feasible_points,
        "total_points": counts.total_points,
        "isotropic_force": {**{k: getattr(iso, k) for k in FORCE_FIGURES},
                            "count": iso.count, "singular_points": iso.singular_points,
                            # 0 in truth: the map reaches a direct singularity (metrics.suprema.VANISHING_NEAR)
                            "min_vanishes": iso.vanishes,
                            # Each figure's grid error (the half grids') and its observed order, as `stats`.
                            "errors": {k: wmap.errors.get("isotropic_force", {}).get(k) for k in FORCE_FIGURES},
                            "error_orders": {k: wmap.error_orders.get("isotropic_force", {}).get(k)
                                             for k in FORCE_FIGURES}},
        "anisotropic_force_max": aniso.max,
        "anisotropic_force_unbounded": aniso.unbounded,
        "gci": wmap.gci if wmap.gci is not None else math.nan,
        "gci_error": wmap.gci_error,
        "gci_error_order": wmap.gci_error_order,
        "at_zero_moment": mech.has_orientation,
        "condition_number_scaling": condition_number_scaling(mech),
        "bottleneck_shares": shares,
        "seconds": wmap.seconds,
        "loading": loading_dict(loading, mech),
        # What the force costs in mass (links and rotors), or why it is not given.
        "masses": ({q: _figures(wmap.stats[q]) for q in DYNAMIC_SUMMARY} if mech.has_mass_model
                   else f"not computed: {mech._no_mass_model()}"),
    }


def _figures(stats) -> dict[str, Any]:
    """min, median, p95, max (``inf`` when unbounded) and whether it vanishes, of one quantity's statistics."""
    return {"min": 0.0 if stats.vanishes else stats.min, "median": stats.median, "p95": stats.p95,
            "max": math.inf if stats.unbounded else stats.max}


def summaries(keys, resolution: int | None = None, *, load=None) -> list[dict[str, Any]]:
    """``device_summary`` of each device key (or preset path)."""
    presets = [load(k) if load is not None else _load(k) for k in keys]
    return [device_summary(p, resolution) for p in presets]


def _load(key: str):
    return load_device(argparse.Namespace(device=key, overrides=[]))


def shares_text(shares: dict[str, float]) -> str:
    """``"theta_1 52.3%, theta_2 47.7%"``; ``"-"`` for none."""
    return ", ".join(f"{n} {100 * v:.1f}%" for n, v in shares.items()) or "-"


def figure_cell(value: float, error) -> str:
    """A figure with the digits its grid error supports (``figure_digits``, as ``stats`` and the app
    write it), ``*`` after one the grid does not resolve; 4 digits without an error."""
    if error is None:
        return number(value, 4)
    error = shown_error(value, error)
    return format_with_error(value, error)[0] + (" *" if unresolved(value, error) else "")


def force_cells(stats: dict) -> list[str]:
    """The isotropic force's ``FORCE_FIGURES`` as text; a minimum that is 0 in truth reads ``0 (singular)``."""
    errors = stats.get("errors", {})
    cells = [figure_cell(stats[k], errors.get(k)) for k in FORCE_FIGURES]
    if stats.get("min_vanishes"):
        cells[0] = "0 (singular)"
    return cells


def unresolved_lines(rows) -> list[str]:
    """One line per figure a device's grid does not resolve (marked ``*``): which grid would."""
    out = []
    for r in rows:
        s, resolution = r["isotropic_force"], r["resolution"]
        errors, orders = s.get("errors", {}), s.get("error_orders", {})
        figures = [(f"F_iso {k}", s[k], errors.get(k), orders.get(k)) for k in FORCE_FIGURES
                   if not (k == "min" and s.get("min_vanishes"))]
        figures.append(("GCI", r["gci"], r.get("gci_error"), r.get("gci_error_order")))
        for name, value, error, order in figures:
            note = "" if error is None else unresolved_note(value, shown_error(value, error), order, resolution)
            out += [f"  * {r['key']} {name}: {note}"] if note else []
    return out


def _aniso_text(row) -> str:
    return "unbounded" if row["anisotropic_force_unbounded"] else number(row["anisotropic_force_max"], 4)


def _workspace_text(row) -> str:
    w = row["workspace"]
    return f"{number(w['value'], 4)} {w['unit']}" if math.isfinite(w["value"]) else "n/a"


HEADER = ("device", "workspace", "F_iso min (N)", "mean", "SD", "median", "p05", "p95", "F_aniso max (N)",
          "GCI", "forces")


def table_rows(rows) -> list[tuple[str, ...]]:
    """The comparison as text cells, one row per device, ``HEADER`` first."""
    out = [HEADER]
    for r in rows:
        s = r["isotropic_force"]
        out.append((r["key"], _workspace_text(r), *force_cells(s), _aniso_text(r),
                    figure_cell(r["gci"], r.get("gci_error")),
                    "at zero moment" if r["at_zero_moment"] else "pure force"))
    return out


NOTES = ("workspace: " + WORKSPACE_DEFINITION + "; F_iso: maximum isotropic force (the global minimum is "
         "paper 000's \"global maximum isotropic force\"), statistics over the regular feasible points (SD ddof = 1, "
         "quantiles of the streamed histogram, within 1.2e-4 relative); F_aniso: maximum anisotropic force; "
         "GCI: mean of 1 / condition number (Gosselin and Angeles 1991); each over the device's own default map, "
         "so the figures depend on its range and resolution, each with the digits its grid error supports "
         "(see `isoforce stats` for the errors)")


def loading_phrase(rows) -> str:
    """``"at the continuous torque rating, gravity off"``: the loading every row shares."""
    first = rows[0]["loading"] if rows else {"rating": "continuous", "gravity": "off"}
    gravity = first["gravity"]
    if gravity == "off":
        where = "gravity off"
    else:
        vector = "(" + ", ".join(f"{v:g}" for v in gravity["vector"]) + ") m/s^2"
        where = f"gravity {gravity['mounting'] or 'along'} {vector} in each device's base frame"
    return f"at the {first['rating']} torque rating, {where}"


def format_text(rows) -> str:
    unresolved_figures = unresolved_lines(rows)
    lines = [f"forces {loading_phrase(rows)}:", table(table_rows(rows))]
    if unresolved_figures:
        lines += ["* not resolved at the device's grid (the error is at least the figure):", *unresolved_figures]
    lines += ["", "bottleneck actuator's share of the workspace (feasible points):"]
    lines += [f"  {r['key']}: {shares_text(r['bottleneck_shares'])}" for r in rows]
    lines += ["", "what the hand feels (links and rotors; median and 95th percentile over the map):"]
    lines += [f"  {r['key']}: {_mass_text(r['masses'])}" for r in rows]
    lines += ["", "maps:"]
    lines += [f"  {r['key']}: {r['grid']}; {r['feasible_points']} feasible, {r['isotropic_force']['singular_points']} "
              f"singular; {r['seconds']:.2f} s" for r in rows]
    lines += ["", NOTES]
    return "\n".join(lines)


def _mass_text(masses) -> str:
    """One device's masses line: heaviest and lightest apparent mass (g), isotropic acceleration (m/s^2)."""
    if isinstance(masses, str):
        return masses
    heavy, light, acc = masses["apparent_mass_max"], masses["apparent_mass_min"], masses["isotropic_acceleration"]
    top = "unbounded" if math.isinf(heavy["max"]) else f"{number(heavy['max'] * 1e3, 4)} g"
    return (f"heaviest direction {number(heavy['median'] * 1e3, 4)} g (p95 {number(heavy['p95'] * 1e3, 4)} g, "
            f"max {top}), lightest {number(light['median'] * 1e3, 4)} g; isotropic acceleration "
            f"{number(acc['median'], 4)} m/s^2 (min {number(acc['min'], 4)} m/s^2)")


def to_json(rows) -> dict[str, Any]:
    """The JSON object ``--json`` prints and ``--out FILE.json`` writes."""
    return {"devices": rows, "loading": loading_phrase(rows),
            "definitions": {"workspace": WORKSPACE_DEFINITION, "notes": NOTES},
            "units": {"force": "N", "area": "cm^2", "volume": "cm^3", "apparent_mass": "kg",
                      "isotropic_acceleration": "m/s^2"}}


def _gravity_cell(gravity) -> str:
    """``"off"``, or the vector ``"gx gy gz"`` (m/s^2, base frame) exactly."""
    return "off" if gravity == "off" else " ".join(repr(float(v)) for v in gravity["vector"])


def to_csv(rows) -> str:
    """One row per device, ``CSV_COLUMNS``; floats exact (``repr``), ``inf`` for an unbounded maximum."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    for r in rows:
        s, w = r["isotropic_force"], r["workspace"]
        writer.writerow([r["key"], r["name"], w["kind"], repr(float(w["value"])), w["unit"], r["feasible_points"],
                         r["total_points"], "x".join(map(str, r["resolution"])), repr(float(w["cell_size"])),
                         *(repr(float(s[k])) for k in FORCE_FIGURES), repr(float(r["anisotropic_force_max"])),
                         repr(float(r["gci"])), "true" if r["at_zero_moment"] else "false",
                         "; ".join(f"{n}={v!r}" for n, v in r["bottleneck_shares"].items()),
                         r["loading"]["rating"], _gravity_cell(r["loading"]["gravity"])])
    return buffer.getvalue()


def write_out(rows, target) -> None:
    """Write the table (.csv, .json) or the figure (.png, .svg, .pdf) atomically."""
    suffix = target.suffix.lower()
    if suffix in FIGURE_SUFFIXES:
        from app.plots.compare_figure import compare_figure  # matplotlib only when drawing
        from app.plots.figures import save_figure
        save_figure(compare_figure(rows), target, name="--out")
    else:
        text = dumps(to_json(rows)) + "\n" if suffix == ".json" else to_csv(rows)
        atomic_write(target, lambda tmp: tmp.write_text(text, encoding="utf-8", newline=""), name="--out")


def check_like_with_like(presets, resolution: int | None = None) -> None:
    """Refuse devices whose maps are of different kinds: a 2D slice's statistics are over an area,
    a 3D box's over a volume, so neither a workspace column nor a force figure compares them.

    Raises
    ------
    UsageError
        Naming each device with its kind, and which kind each of the others has.
    """
    kinds = {p.key: ("a 2D slice (statistics over its area, cm^2)" if len(device_grid(p, resolution).axes) == 2
                     else "a 3D box (statistics over its volume, cm^3)") for p in presets}
    if len(set(kinds.values())) > 1:
        listed = "; ".join(f"{key}: {kind}" for key, kind in kinds.items())
        raise UsageError(f"DEVICE: the maps are not of one kind ({listed}): a slice's figures and a box's are "
                         f"not over like regions; compare the slice devices and the box devices separately")


def run(args: argparse.Namespace) -> int:
    presets = [_load(k) for k in args.devices]           # every DEVICE checked before any map
    check_like_with_like(presets, args.resolution)
    loadings = [loading_of(args, p) for p in presets]    # ... and its rating and mass model
    target = check_out(args.out, STATS_SUFFIXES + FIGURE_SUFFIXES) if args.out is not None else None
    # Each device's map, then its bottleneck pass (timed as a map of that class alone).
    jobs = [MapJob(p.mechanism, device_grid(p, args.resolution), names, keep_maps=False, loading=loading)
            for p, loading in zip(presets, loadings) for names in (map_quantities(p.mechanism), ("bottleneck",))]
    job = check_job("compare", jobs, max_time=args.max_time,
                    what=f"the maps of {len(presets)} devices (a force map and a bottleneck pass each)")
    with progress_for("isoforce compare", job and job.seconds, job_points(jobs), json_out=args.json) as progress:
        done, rows = 0, []
        for p, loading in zip(presets, loadings):
            points = math.prod(device_grid(p, args.resolution).resolution)
            rows.append(device_summary(p, args.resolution, loading=loading, progress=progress.part(done, points)))
            done += 2 * points          # the map, then the bottleneck pass
    if target is not None:
        write_out(rows, target)
        print(f"wrote {target}", file=sys.stderr)
    if args.json:
        print_json(to_json(rows))
        return 0
    print(format_text(rows))
    return 0
