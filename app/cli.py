"""``isoforce``: the headless command line (and, with no arguments, the desktop app).

::

    isoforce                      launch the desktop app
    isoforce devices              list the shipped presets
    isoforce show DEVICE          every parameter with its name, unit and value
    isoforce stats DEVICE         global figures of the default map
    isoforce pose DEVICE --at P   everything about one pose
    isoforce map DEVICE --quantity Q --out FILE    heat map (.png/.svg/.pdf) or data (.csv/.npz)
    isoforce convergence ...      (app.convergence_cli)    isoforce bench ...   (app.bench)

DEVICE is a preset key (``isoforce devices``) or a path to a ``.toml`` preset. Lengths are
typed and printed in mm, angles in deg, torques in N m, forces in N.

Every subcommand lives behind the same convention: a ``register(subparsers)`` function adds
its parser and sets ``func``, which takes the parsed arguments and returns the exit status.
Bad input (unknown device, bad ``--set``, bad ``--at``, bad file name) gives one line on
stderr naming the argument, exit status 2, and no partial file. With ``--json`` stdout holds
exactly one JSON object (strict: no ``NaN``; ``nan`` is ``null``, ``inf`` is ``"inf"``), and
nothing at all when the command fails.
"""
from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys
import threading
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from kinematics.base import task_display_units, task_from_si, task_to_si

from metrics.pose import PoseReport, analyse_pose, to_dict
from metrics.quantities import MAP_QUANTITIES, QUANTITIES, STATS_QUANTITIES, TABLE3_QUANTITIES, available_quantities, \
    check_quantities
from metrics.quantities import summary_quantities
from metrics.workspace import compute_map
from metrics.wrenches import condition_number_scaling

from .export import FIGURE_SUFFIXES, MAP_SUFFIXES, STATS_SUFFIXES, check_output, dumps, stats_summary, write_map, \
    write_stats

PROG = "isoforce"
GUI_MISSING = "the desktop app is not built yet (issue 3); try `isoforce --help`"
#: Subcommands other modules contribute: (command, module exposing ``register``).
EXTERNAL_COMMANDS = (("convergence", "app.convergence_cli"), ("bench", "app.bench"), ("figure", "app.figure_cli"),
                     ("optimize", "app.optimize_cli"))


class UsageError(ValueError):
    """Bad command-line input: reported as one line on stderr with exit status 2."""


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors raise ``UsageError`` instead of printing usage and exiting.

    ``main`` turns that into the one-line message every other input error gets.
    """

    def error(self, message: str):  # type: ignore[override]
        raise UsageError(f"{message} (see `{self.prog} --help`)")


# -- shared helpers, also for the subcommands of other modules ------------------------------
def add_device_argument(parser: argparse.ArgumentParser, *, overrides: bool = True) -> None:
    """Add the ``DEVICE`` positional and, if ``overrides``, ``--set NAME=VALUE ...``."""
    parser.add_argument("device", metavar="DEVICE", help="preset key (see `isoforce devices`) or path to a .toml")
    if overrides:
        parser.add_argument("--set", dest="overrides", metavar="NAME=VALUE", action="extend", nargs="+",
                            default=[], help="override a parameter by the name `show` prints, in its display "
                                             "unit; vectors comma-separated, e.g. gear_ratios=13.75,5.957,5.957 "
                                             "(takes several, so put DEVICE first)")


def add_resolution_argument(parser: argparse.ArgumentParser) -> None:
    """Add ``--resolution N`` (points per axis; default: the preset's map)."""
    parser.add_argument("--resolution", type=_resolution, metavar="N",
                        help="points per map axis (default: the preset's own grid)")


def int_at_least(minimum: int) -> Callable[[str], int]:
    """An argparse ``type`` that accepts integers >= ``minimum`` and names the rule otherwise."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = minimum - 1
        if value < minimum:
            raise argparse.ArgumentTypeError(f"needs an integer >= {minimum}, got {text!r}")
        return value
    return parse


_resolution = int_at_least(2)


def load_device(args: argparse.Namespace):
    """The preset named by ``args.device`` with ``args.overrides`` (``--set``) applied.

    Raises
    ------
    UsageError
        Naming ``DEVICE`` or ``--set`` and the offending value.
    """
    from resources import PresetError, load_preset

    try:
        preset = load_preset(args.device)
    except PresetError as exc:
        raise UsageError(f"DEVICE: {exc}") from None
    changes = parse_overrides(preset.mechanism, getattr(args, "overrides", None) or [])
    if changes:
        try:
            preset = preset.replace(mechanism=preset.mechanism.replace_display(**changes))
        except ValueError as exc:
            raise UsageError(f"--set: {_typed_units_message(preset.mechanism, changes, exc)}") from None
    return preset


def _typed_units_message(mechanism, changes: dict[str, Any], exc: ValueError) -> str:
    """The model's message about ``--set`` values, with the values as typed, in the typed unit.

    The model validates SI values (``proximal_length ... in m, got -0.005``); a person typed
    ``proximal_length=-5`` in mm. When every typed value is a number (so the SI check is what
    failed), the SI tail after "got" and the SI unit are dropped and the typed values follow,
    each with its display unit. Other messages (not a number, wrong count) already show the
    typed text and are kept.
    """
    import re

    message = " ".join(str(exc).split())
    infos = {info.name: info for info in mechanism.PARAM_INFO}

    def numeric(value) -> bool:
        try:
            [float(v) for v in (value if isinstance(value, list) else [value])]
        except ValueError:
            return False
        return True

    if not all(numeric(v) for n, v in changes.items() if not infos[n].choices) or ", got " not in message:
        return message
    rule = re.sub(r" in (m|rad|m/s|rad/s)$", "", message.rsplit(", got ", 1)[0])
    typed = "; ".join(f"{n} = {', '.join(v) if isinstance(v, list) else v}"
                      + (f" {infos[n].unit}" if infos[n].unit and infos[n].unit != "-" else "")
                      for n, v in changes.items())
    return f"{rule}; got {typed}"


def parse_overrides(mechanism, items: Sequence[str]) -> dict[str, Any]:
    """``["name=value", ...]`` as display-unit changes for ``mechanism.replace_display``.

    Vector parameters split on commas; choice parameters stay strings; numbers are
    converted by ``replace_display`` itself, which names the parameter if they are not.
    """
    infos = {info.name: info for info in mechanism.PARAM_INFO}
    changes: dict[str, Any] = {}
    for item in items:
        name, sep, value = item.partition("=")
        name, value = name.strip(), value.strip()
        if not sep or not name:
            raise UsageError(f"--set needs NAME=VALUE, got {item!r}")
        info = infos.get(name)
        if info is None:
            raise UsageError(f"--set: {type(mechanism).__name__} has no parameter {name!r}; "
                             f"known: {', '.join(infos)}")
        changes[name] = [v.strip() for v in value.split(",")] if info.is_vector else value
    return changes


def overridden_values(mechanism, items: Sequence[str]) -> dict[str, Any]:
    """The values (display units) that ``--set`` gave ``mechanism``, as the model now holds them."""
    names = parse_overrides(mechanism, items)
    return {info.name: list(value) if isinstance(value, tuple) else value
            for info, value in mechanism.parameter_table() if info.name in names}


def parse_point(text: str, mechanism, name: str = "--at") -> np.ndarray:
    """``"X,Y,Z"`` in mm (angles of pen poses in deg) as a task point in SI, shape (m,).

    Raises a UsageError naming ``name`` when the text is not m numbers.
    """
    m = mechanism.task_dim
    wanted = ",".join(n.upper() for n in mechanism.task_names)
    parts = text.split(",")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != m or not all(np.isfinite(values)):
        raise UsageError(f"{name} needs {wanted} in {_units_phrase(mechanism)}, got {text!r}")
    return task_to_si(mechanism, values)


def _units_phrase(mechanism) -> str:
    units = task_display_units(mechanism)
    return "millimetres" if set(units) == {"mm"} else "mm and deg (" + ", ".join(units) + ")"


def _point_text(mechanism, x, digits: int = 6) -> str:
    """A task point (SI) as display text with its units, e.g. "(170, 22.3, 230) mm"."""
    units = task_display_units(mechanism)
    suffix = "mm" if set(units) == {"mm"} else "(" + ", ".join(units) + ")"
    return f"{_vector(task_from_si(mechanism, x), digits)} {suffix}"


def print_json(obj: Any) -> None:
    """Print one strict JSON object (``nan`` as null, ``inf`` as "inf")."""
    print(dumps(obj))


def _number(value: float, digits: int = 6) -> str:
    """A float for a table: ``digits`` significant figures, ``inf``/``nan`` spelled out."""
    if not np.isfinite(value):
        return "nan" if np.isnan(value) else ("inf" if value > 0 else "-inf")
    return f"{value:.{digits}g}"


def _vector(values, digits: int = 6) -> str:
    return "(" + ", ".join(_number(float(v), digits) for v in _clean(values)) + ")"


def _clean(values) -> np.ndarray:
    """For printing only: entries below 1e-12 of the largest finite magnitude are rounding noise, shown as 0."""
    arr = np.array(values, dtype=float)
    finite = np.abs(arr[np.isfinite(arr)])
    if finite.size:
        arr[np.abs(arr) < 1e-12 * finite.max()] = 0.0
    return arr


def _table(rows: list[Sequence[str]], indent: str = "") -> str:
    """Rows of cells as left-aligned columns."""
    widths = [max(len(r[i]) for r in rows if i < len(r)) for i in range(max(len(r) for r in rows))]
    return "\n".join(indent + "  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows)


# -- devices --------------------------------------------------------------------------------
def register_devices(subparsers) -> None:
    p = subparsers.add_parser("devices", help="list the shipped device presets",
                              description="List the shipped device presets.")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run_devices)


def run_devices(args: argparse.Namespace) -> int:
    from resources import list_presets, load_preset

    presets = [load_preset(key) for key in list_presets()]
    if args.json:
        print_json({"devices": [{"key": p.key, "name": p.name, "mechanism": p.kind,
                                 "description": p.description} for p in presets]})
        return 0
    print(_table([("key", "mechanism", "name")] + [(p.key, p.kind, p.name) for p in presets]))
    return 0


# -- show -----------------------------------------------------------------------------------
def register_show(subparsers) -> None:
    p = subparsers.add_parser("show", help="every parameter of a device with its unit and value",
                              description="Print every parameter of a device (name, unit, value), its default "
                                          "map and pose. The names are the ones --set takes.")
    add_device_argument(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run_show)


def device_description(preset) -> dict[str, Any]:
    """A preset as a JSON-ready dict: parameters in display units, default map and pose in mm."""
    params = []
    for info, value in preset.mechanism.parameter_table():
        entry: dict[str, Any] = {"name": info.name, "unit": info.unit,
                                 "value": list(value) if isinstance(value, tuple) else value,
                                 "description": info.description}
        if info.labels:
            entry["labels"] = list(info.labels)
        if info.choices:
            entry["choices"] = list(info.choices)
        params.append(entry)
    grid = preset.grid
    return {
        "device": preset.key, "name": preset.name, "mechanism": preset.kind,
        "description": preset.description, "source": preset.source,
        "task_names": list(preset.mechanism.task_names), "joint_names": list(preset.mechanism.joint_names),
        "parameters": params,
        "map": {"axes": list(grid.axes), "lower": [v * 1e3 for v in grid.lower],
                "upper": [v * 1e3 for v in grid.upper], "resolution": list(grid.resolution),
                "fixed": {n: v * 1e3 for n, v in grid.fixed}},
        "pose": [v * 1e3 for v in preset.pose] if preset.pose is not None else None,
    }


def run_show(args: argparse.Namespace) -> int:
    preset = load_device(args)
    info = device_description(preset)
    if args.json:
        print_json(info)
        return 0
    print(f"{preset.name} ({preset.key}, {preset.kind})")
    if preset.description:
        print(preset.description)
    rows = [("parameter", "unit", "value")]
    for p in info["parameters"]:
        if "labels" in p:
            value = ", ".join(f"{lab} = {_number(v)}" for lab, v in zip(p["labels"], p["value"]))
        elif isinstance(p["value"], str):
            value = p["value"]
        else:
            value = _number(p["value"])
        rows.append((p["name"], p["unit"] or "-", value))
    print()
    print(_table(rows))
    print()
    print(f"default map: {_describe_grid(preset.grid)}")
    if preset.pose is not None:
        print(f"default pose: {_point_text(preset.mechanism, preset.pose)}")
    return 0


def _describe_grid(grid) -> str:
    ranges = ", ".join(f"{a} {lo * 1e3:g} to {hi * 1e3:g} mm" for a, lo, hi in zip(grid.axes, grid.lower, grid.upper))
    fixed = "".join(f", {n} = {v * 1e3:g} mm" for n, v in grid.fixed)
    return f"{ranges}{fixed}; {' x '.join(str(r) for r in grid.resolution)} points"


# -- stats ----------------------------------------------------------------------------------
def register_stats(subparsers) -> None:
    p = subparsers.add_parser("stats", help="global figures of the default workspace map",
                              description="Statistics (min, p05, median, mean, p95, max, SD with ddof = 1, count, "
                                          "where the extremes are) of the condition number, maximum anisotropic "
                                          "and isotropic force and 1 / condition number over the regular "
                                          "feasible points of the device's default map, and the global "
                                          "conditioning index. Singular points are counted and left out; a "
                                          "maximum that is infinite in truth is reported as unbounded. Global "
                                          "figures depend on the grid resolution: see `isoforce convergence`.")
    add_device_argument(p)
    add_resolution_argument(p)
    p.add_argument("--out", metavar="FILE", help="also write the statistics to a .json or .csv file")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run_stats)


def device_grid(preset, resolution: int | None):
    """The preset's default grid, at ``resolution`` points per axis if given."""
    return preset.grid if resolution is None else preset.grid.with_resolution(resolution)


#: Whether ``isoforce stats`` holds the whole map while it takes the statistics: no, they are
#: streamed chunk by chunk (``compute_map(..., keep=False)``), so the memory estimate is by
#: chunk and does not grow with the resolution.
STATS_KEEPS_MAPS = False
#: Jobs estimated above this many bytes, or points, say so on stderr before they start (a
#: streamed map fits in memory at any resolution, but 10^10 points take hours).
NOTE_BYTES = 2 << 30
NOTE_POINTS = 10 ** 8


def check_memory(mechanism, grid, quantities, *, keep_maps: bool = True, output: str | None = None,
                 copies: int = 1, option: str = "--resolution"):
    """Refuse a map that cannot fit in the available memory, before computing anything.

    Returns the ``metrics.budget.Estimate``; a large job that fits gets a one-line note on
    stderr with its size. Raises a UsageError naming ``option`` with the estimate and the
    largest resolution that fits.
    """
    from metrics.budget import BudgetError, check_map

    try:
        est = check_map(mechanism, grid.resolution, quantities, keep_maps=keep_maps, output=output, copies=copies,
                        option=option)
    except BudgetError as exc:
        raise UsageError(f"{option}: {exc}") from None
    if est.bytes > NOTE_BYTES or est.points > NOTE_POINTS:
        print(f"{PROG}: note: {est.text()}", file=sys.stderr)
    return est


NO_FEASIBLE_POINT = "no feasible point on this grid: no statistics (check the map's range and the parameters)"


def run_stats(args: argparse.Namespace) -> int:
    preset = load_device(args)
    if args.out is not None:
        _check_out(args.out, STATS_SUFFIXES)
    mech = preset.mechanism
    grid = device_grid(preset, args.resolution)
    names = summary_quantities(mech)        # + the moment capabilities of a wrench device
    check_memory(mech, grid, names, keep_maps=STATS_KEEPS_MAPS)
    wmap = compute_map(mech, grid, names, keep=STATS_KEEPS_MAPS)
    summary = stats_summary(wmap, device=preset.key, quantities=names)
    scaling = condition_number_scaling(mech)
    if scaling is not None:
        summary["condition_number_scaling"] = scaling
    if args.overrides:
        summary["overrides"] = overridden_values(mech, args.overrides)
    if wmap.feasible_points == 0:
        summary["message"] = NO_FEASIBLE_POINT
    if args.out is not None:
        write_stats(wmap, args.out, device=preset.key, quantities=names, name="--out")
    if args.json:
        print_json(summary)
        return 0
    print(f"{preset.name} ({preset.key}): {' x '.join(map(str, summary['resolution']))} grid over "
          f"{', '.join(summary['axes'])}; {summary['feasible_points']} of {summary['total_points']} points "
          f"feasible, {wmap.singular_points} of them singular; {summary['seconds']:.3f} s")
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
    for q in names:
        s, err = wmap.stats[q], wmap.errors.get(q, {})
        cells = [_with_error(getattr(s, k), err.get(k)) for k in ("min", "p05", "median", "mean", "p95")]
        cells.append("unbounded" if s.unbounded else _with_error(s.max, err.get("max")))
        cells.append(_with_error(s.sd, err.get("sd")))
        where_max = (_point_text(mech, s.unbounded_at[0], 4) if s.unbounded
                     else _point_text(mech, s.argmax, 4) if s.argmax else "-")
        rows.append((q, QUANTITIES[q].unit or "-", *cells,
                     _point_text(mech, s.argmin, 4) if s.argmin else "-", where_max))
        if s.unbounded:
            why = ("J loses rank there" if QUANTITIES[q].unit != "N"
                   else "the ideal device resists unbounded force there")
            notes.append(f"{q}: max unbounded: the feasible set reaches a singularity, e.g. at "
                         f"{_point_text(mech, s.unbounded_at[0], 4)} ({why}); the other figures are over "
                         f"regular points")
    lines = [_table(rows)]
    if wmap.gci is not None:
        lines.append(f"global conditioning index (mean of 1 / condition number, Gosselin and Angeles 1991): "
                     f"{_with_error(wmap.gci, wmap.gci_error)}")
    sing = next(iter(wmap.stats.values()), None)
    if sing is not None and sing.singular_points:
        where = ", ".join(_point_text(mech, p, 4) for p in sing.singular_at[:3])
        lines.append(f"{sing.singular_points} singular feasible point(s) left out of every figure, e.g. at {where}")
    lines += notes
    lines.append("(+- : estimated error from the grid resolution, the change from half the resolution; "
                 "`isoforce convergence` measures it)")
    return "\n".join(lines)


def _with_error(value: float, error) -> str:
    """``value +- error`` with the error to 2 significant figures (JSON gives it as null or "inf" too)."""
    if error is None:
        return _number(value)
    error = float(error)
    return f"{_number(value)} +- {_number(error, 2)}"


def _check_out(path: str, suffixes: tuple[str, ...]) -> Path:
    """Fail fast on a bad ``--out``, before any computing: suffix, a file name, a writable folder."""
    try:
        return check_output(path, suffixes, "--out")
    except ValueError as exc:
        raise UsageError(str(exc)) from None


# -- pose -----------------------------------------------------------------------------------
def register_pose(subparsers) -> None:
    p = subparsers.add_parser("pose", help="joints, Jacobian, force polytope and ellipsoids at one point",
                              description="Analyse one pose: joint angles, J, singular values, condition "
                                          "number, maximum isotropic force and its bottleneck actuator, "
                                          "maximum anisotropic force, polytope vertices, force and velocity "
                                          "ellipsoids. A point outside the workspace exits with status 2.")
    add_device_argument(p)
    p.add_argument("--at", metavar="X,Y,Z", help="task point in mm (five-bar: X,Y); default: the preset's pose")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run_pose)


def check_pose(preset, x, *, from_preset: bool) -> PoseReport:
    """``analyse_pose`` of ``x`` (SI), or a UsageError when it is outside the workspace.

    The error names where the point came from: ``--at``, or the preset's key ``pose.at`` when
    the preset's own default pose is the one outside (the file is wrong, not the command).
    """
    mech = preset.mechanism
    report = analyse_pose(mech, x)
    if not report.feasible:
        where = _point_text(mech, x)
        if not report.reachable:
            why = "no joint angles reach it"
        else:
            joints = ", ".join(f"{n} = {v:.1f} {u}" for n, v, u in zip(mech.joint_names, *_joints_display(mech, report.joints)))
            why = f"it is reachable ({joints}) but violates a joint limit or physical constraint"
        if from_preset:
            raise UsageError(f"preset {preset.source!r}: key 'pose.at' {where} is outside the workspace of "
                             f"{preset.key}: {why}; pass --at or fix the preset")
        raise UsageError(f"--at {where} is outside the workspace of {preset.key}: {why}")
    return report


def run_pose(args: argparse.Namespace) -> int:
    preset = load_device(args)
    mech = preset.mechanism
    if args.at is not None:
        x = parse_point(args.at, mech)
    elif preset.pose is not None:
        x = np.array(preset.pose)
    else:
        raise UsageError(f"--at is required: preset {preset.key!r} has no default pose")
    report = check_pose(preset, x, from_preset=args.at is None)
    if args.json:
        out = to_dict(report)
        out["device"] = preset.key
        print_json(out)
        return 0
    print(format_pose(report, preset.name, mech))
    return 0


def _joints_display(mech, joints) -> tuple[np.ndarray, tuple[str, ...]]:
    """Joint values in display units: deg for revolute joints, mm for prismatic ones."""
    units = getattr(mech, "joint_units", ("rad",) * mech.n_joints)
    scale = np.array([1000.0 if u == "m" else 180.0 / np.pi for u in units])
    return np.asarray(joints, float) * scale, tuple("mm" if u == "m" else "deg" for u in units)


def condition_label(scaling: dict | None) -> str:
    """``"condition number"``, naming the task scaling where J mixes m and rad."""
    if scaling is None:
        return "condition number"
    return f"condition number (moments scaled by L = {_number(scaling['length_m'] * 1e3)} mm)"


def _unit_list(units, count: int) -> list[str]:
    """A ``to_dict`` unit (one string, or one per entry) as one string per entry."""
    return [units] * count if isinstance(units, str) else list(units)


def _labelled(names, units) -> str:
    """``x, y, z (mm), rx, ry, rz (rad)``: names with their units, runs of one unit grouped."""
    parts, run = [], []
    for i, (name, unit) in enumerate(zip(names, units)):
        run.append(name)
        if i + 1 == len(names) or units[i + 1] != unit:
            parts.append(f"{', '.join(run)} ({unit})")
            run = []
    return ", ".join(parts)


def format_pose(report: PoseReport, title: str, mech) -> str:
    """The human table of a pose report (mm, deg, N)."""
    d = to_dict(report)        # one conversion to display units, shared with --json
    joints, tasks = report.joint_names, report.task_names
    lines = [f"{title} at {_point_text(mech, report.x)} ({', '.join(tasks)})"]
    values, units = _joints_display(mech, report.joints)
    label = "joints (" + ", ".join(sorted(set(units))) + ")"
    rows = [(label, ", ".join(f"{n} = {_number(q)}" for n, q in zip(joints, _clean(values))))]
    u = d["units"]
    wrench = report.condition_number_scaling is not None
    rows.append((condition_label(report.condition_number_scaling), _number(report.condition_number)))
    zero_m = " at zero moment" if wrench else ""
    rows.append((f"isotropic force{zero_m}", f"{_number(report.isotropic_force)} N, bottleneck {report.bottleneck_name}"))
    rows.append((f"anisotropic force{zero_m}", f"{_number(report.anisotropic_force)} N"))
    if wrench:
        rows.append(("isotropic moment at zero force", f"{_number(report.isotropic_moment)} N m"))
        rows.append(("anisotropic moment at zero force", f"{_number(report.anisotropic_moment)} N m"))
    rows.append(("facet distances (N)", ", ".join(f"{n} = {_number(v)}" for n, v in zip(joints, report.facet_distances))))
    limits = _unit_list(u["torque_limits"], len(joints))
    rows.append((f"actuator limits ({', '.join(sorted(set(limits)))})",
                 ", ".join(f"{n} = {_number(v)}" for n, v in zip(joints, report.torque_limits))))
    rows.append((f"singular values ({u['singular_values']})", _vector(d["singular_values"])))
    rows.append(("manipulability", f"{_number(d['manipulability'])} {d['units']['manipulability']}"))
    if report.singularity is not None:
        legs = report.singular_legs
        which = f" ({', '.join(legs)} stretched or folded)" if report.singularity_name in ("inverse", "combined") \
            and legs else ""
        rows.append(("singularity", f"{report.singularity_name}{which}"))
    lines.append(_table(rows, "  "))
    lines.append(f"  Jacobian, rows {_labelled(tasks, u['jacobian_rows'])}, "
                 f"columns {_labelled(joints, u['jacobian_columns'])}:")
    jac = _clean(np.array(d["jacobian"], float))     # noise relative to the whole matrix, not one row
    lines.extend("    " + _vector(row) for row in jac)
    ref_units = _unit_list(u["reference_forces"], len(tasks))
    lines.append(f"  reference forces ({_labelled(tasks, ref_units) if wrench else 'N'}), "
                 "one per actuator at full torque:")
    ref = _clean(report.reference_forces)
    finite_ref = bool(np.all(np.isfinite(report.reference_forces)))
    if finite_ref or wrench:
        lines.extend(f"    {n}: {_vector(ref[:, u])}" for u, n in enumerate(joints))
    else:
        lines.append("    none: J is singular here, J^-T does not exist (the force set is unbounded)")
    if wrench:
        lines.append("  force set at zero moment: vertices (N)")
        lines.extend(f"    {_vector(vertex)}  |f| = {_number(float(np.linalg.norm(vertex)))}"
                     for vertex in report.vertices)
    elif not np.all(np.isfinite(report.vertices)):
        lines.append("  polytope vertices (N): none, the force polytope is unbounded at a singular J")
    else:
        lines.append("  polytope vertices (N), by torque sign pattern:")
        for signs, vertex in zip(d["signs"], report.vertices):
            pattern = "".join("+" if s > 0 else "-" for s in signs)
            lines.append(f"    {pattern}  {_vector(vertex)}  |f| = {_number(float(np.linalg.norm(vertex)))}")
    speeds = ", ".join(sorted(set(_unit_list(u["joint_speeds"], len(joints)))))
    for label, ell, unit, scale in (("force ellipsoid" + zero_m, report.force_ellipsoid, "N", 1.0),
                                    (("linear " if wrench else "") + f"velocity ellipsoid (1 {speeds} joints)",
                                     report.velocity_ellipsoid, "mm/s", 1e3)):
        lines.append(f"  {label}: radius ({unit}) along axis")
        lines.extend(f"    {_number(r * scale)}  along {_vector(ell.axes[:, k], 4)}" for k, r in enumerate(ell.radii))
    return "\n".join(lines)


# -- map ------------------------------------------------------------------------------------
def register_map(subparsers) -> None:
    p = subparsers.add_parser("map", help="heat map (.png/.svg/.pdf) or data (.csv/.npz) of a quantity",
                              description="Compute a quantity over the device's default map and write a heat "
                                          "map with colour bar (.png, .svg, .pdf) or the data (.csv, .npz). "
                                          "Data files take several quantities, comma-separated.")
    add_device_argument(p)
    p.add_argument("--quantity", required=True, metavar="Q",
                   help=f"one of {', '.join(MAP_QUANTITIES)} (singularity: five-bar only)")
    p.add_argument("--out", required=True, metavar="FILE", help="output file: .png, .svg, .pdf, .csv or .npz")
    add_resolution_argument(p)
    p.set_defaults(func=run_map)


def run_map(args: argparse.Namespace) -> int:
    preset = load_device(args)
    mech = preset.mechanism
    target = _check_out(args.out, FIGURE_SUFFIXES + MAP_SUFFIXES)
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
    check_memory(mech, grid, names, output="figure" if figure else target.suffix.lower().lstrip("."))
    wmap = compute_map(mech, grid, names)
    if figure:
        from .figures import map_figure, save_figure   # matplotlib only when drawing
        save_figure(map_figure(wmap, names[0], preset), target, name="--out")
    else:
        write_map(wmap, target, name="--out")
    print(f"wrote {target} ({' x '.join(map(str, wmap.grid.resolution))} grid, "
          f"{wmap.feasible_points} feasible points, {wmap.seconds:.3f} s)"
          + ("; no feasible point: the map is blank (check the map's range and the parameters)"
             if wmap.feasible_points == 0 else ""), file=sys.stderr)
    return 0


# -- the parser and main --------------------------------------------------------------------
def _register_external(subparsers, command: str, module_name: str) -> None:
    """Register another module's subcommand; if it cannot be imported, say why when it is used."""
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        if exc.name == module_name:
            return       # not written yet: the command simply does not exist
        reason = str(exc)

        def unavailable(args: argparse.Namespace) -> int:
            raise UsageError(f"`{PROG} {command}` is unavailable: {reason}")

        p = subparsers.add_parser(command, help=f"(unavailable: {reason})", add_help=False)
        p.add_argument("rest", nargs=argparse.REMAINDER)
        p.set_defaults(func=unavailable)
        return
    module.register(subparsers)


def build_parser() -> argparse.ArgumentParser:
    """The ``isoforce`` parser with every subcommand registered."""
    parser = _Parser(prog=PROG, description="Force capability of haptic devices: maps, poses, statistics. "
                                            "With no arguments, launch the desktop app.")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for register in (register_devices, register_show, register_stats, register_pose, register_map):
        register(subparsers)
    for command, module_name in EXTERNAL_COMMANDS:
        _register_external(subparsers, command, module_name)
    return parser


def _join_negative_values(argv: list[str], options: tuple[str, ...] = ("--at",)) -> list[str]:
    """``--at -10,150`` -> ``--at=-10,150``: argparse would read ``-10,150`` as an option."""
    out: list[str] = []
    i = 0
    while i < len(argv):
        token = argv[i]
        nxt = argv[i + 1] if i + 1 < len(argv) else ""
        if token in options and len(nxt) > 1 and nxt[0] == "-" and (nxt[1].isdigit() or nxt[1] == "."):
            out.append(f"{token}={nxt}")
            i += 2
        else:
            out.append(token)
            i += 1
    return out


def launch_gui() -> int:
    """Start the desktop app, or say it does not exist yet."""
    try:
        from app.main_window import run_app
    except ImportError as exc:
        if exc.name != "app.main_window":
            raise      # the app exists but something it needs is broken: show that
        print(GUI_MISSING)
        return 0
    status = run_app()
    return int(status or 0)


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread like Ctrl-C, so that every ``finally`` and atomic write
    cleans up on the way out (the default SIGTERM action kills the process on the spot)."""


def _on_sigterm(signum, frame) -> None:
    # A second SIGTERM during the clean-up must not interrupt it.
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    raise Terminated()


def _stop_workers() -> None:
    """After an interrupt or MemoryError: remove export temporaries, stop worker processes.

    Map threads need nothing: ``metrics.workspace`` keeps only a few chunks in flight, so they
    finish within a chunk once the main thread stops asking. Worker processes of a design study
    are stopped by ``app.optimize_cli``; any left (a pool made elsewhere) are terminated here.
    """
    from .export import remove_temporaries

    remove_temporaries()
    if "multiprocessing" in sys.modules:
        import multiprocessing

        children = multiprocessing.active_children()
        for child in children:
            child.terminate()
        for child in children:
            child.join(timeout=2.0)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status.

    0 ok, 2 bad input, 1 out of memory, 130 Ctrl-C, 143 SIGTERM: each failure is one line on
    stderr, never a traceback, and leaves no partial or temporary file.
    """
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv:
        return launch_gui()
    in_main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _on_sigterm) if in_main_thread else None
    try:
        return _main(argv)
    finally:
        if in_main_thread:
            signal.signal(signal.SIGTERM, previous if previous is not None else signal.SIG_DFL)


def _main(argv: list[str]) -> int:
    parser = build_parser()
    command = "?"
    try:
        args = parser.parse_args(_join_negative_values(argv))
        command = args.command
        if command is None:
            raise UsageError("a COMMAND is needed")
        func: Callable[[argparse.Namespace], int] = args.func
        return int(func(args) or 0)
    except SystemExit as exc:            # --help, or a subcommand that exits itself
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    except KeyboardInterrupt as exc:     # Ctrl-C, or SIGTERM (Terminated)
        _stop_workers()
        where = f"{PROG} {command}" if command not in (None, "?") else PROG
        what = "terminated (SIGTERM)" if isinstance(exc, Terminated) else "interrupted (Ctrl-C)"
        print(f"{where}: {what}: stopped, no partial file left", file=sys.stderr)
        return 143 if isinstance(exc, Terminated) else 130
    except MemoryError:
        _stop_workers()
        where = f"{PROG} {command}" if command not in (None, "?") else PROG
        print(f"{where}: error: out of memory: stopped, no partial file left; try a smaller --resolution "
              f"or fewer quantities (ISOFORCE_MEMORY sets the memory the estimate may plan for)", file=sys.stderr)
        return 1
    except BrokenPipeError:
        # The reader went away (`isoforce pose ... | head`): not an error worth a message. Point
        # stdout at devnull so the interpreter's final flush does not complain (Python docs).
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    except (ValueError, OSError) as exc:
        # ValueError: bad input (UsageError, PresetError, a parameter or file name out of
        # range); OSError: the file system refused. One line, no traceback (set
        # ISOFORCE_DEBUG=1 to see one when a ValueError is a bug rather than bad input).
        if os.environ.get("ISOFORCE_DEBUG"):
            raise
        where = f"{PROG} {command}" if command not in (None, "?") else PROG
        print(f"{where}: error: {_one_line(exc)}", file=sys.stderr)
        return 2


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        return f"{exc.strerror}: {exc.filename}" if exc.filename else exc.strerror
    return " ".join(str(exc).split())


if __name__ == "__main__":
    sys.exit(main())
