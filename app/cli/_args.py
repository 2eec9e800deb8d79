"""Argument parsing shared by the subcommands: the usage error, validators and device loading.

Every check here raises ``UsageError`` (a ``ValueError``) naming the argument and the value
as typed; ``app.cli.main`` turns it into one line on stderr and exit status 2.
"""
from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from app.cli._format import units_phrase
from app.cli._usage import PROG, UsageError
from app.files.export import check_output
from kinematics.base import task_to_si
from kinematics.units import joint_display_units, joints_to_si


def add_device_argument(parser: argparse.ArgumentParser, *, overrides: bool = True) -> None:
    """Add the ``DEVICE`` positional and, if ``overrides``, ``--set NAME=VALUE ...``."""
    parser.add_argument("device", metavar="DEVICE", help="preset key (see `isoforce devices`) or path to a .toml")
    if overrides:
        parser.add_argument("--set", dest="overrides", metavar="NAME=VALUE", action="extend", nargs="+",
                            default=[], help="override a parameter by the name `show` prints, in its display "
                                             "unit; vectors comma-separated, e.g. gear_ratios=13.75,5.957,5.957 "
                                             "(takes several, so put DEVICE first)")


def add_loading_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--rating continuous|peak`` and ``--gravity [MOUNTING | GX,GY,GZ]`` (``metrics.loading``)."""
    from kinematics.gravity import MOUNTINGS
    from metrics.loading import RATINGS

    parser.add_argument("--rating", choices=RATINGS, default="continuous",
                        help="which torque rating limits the actuators: the continuous one (default) or the "
                             "peak (stall, short-time) one, where the device's source gives it")
    parser.add_argument("--gravity", nargs="?", const="upright", default=None, metavar="MOUNTING|GX,GY,GZ",
                        help="bias the force set by the torque the joints spend holding the links (devices "
                             "with a mass model): a mounting orientation, " + ", ".join(MOUNTINGS)
                             + " (the base-frame axis that points up; alone, --gravity is upright), or "
                               "gravity in the base frame in m/s^2, e.g. 0,0,-9.80665; default off")


def parse_gravity(text: str | None):
    """``--gravity`` text as ``(mounting, vector)``: a ``MOUNTINGS`` name, ``"off"``, or three numbers in m/s^2.

    Raises a UsageError naming ``--gravity`` otherwise.
    """
    from kinematics.gravity import MOUNTINGS, check_gravity

    if text is None or text.strip().lower() == "off":
        return None, None
    name = text.strip().lower()
    if name in MOUNTINGS:
        return name, None
    try:
        return None, check_gravity([float(v) for v in text.split(",")], "--gravity")
    except ValueError:
        raise UsageError(f"--gravity needs a mounting ({', '.join(MOUNTINGS)}, or off) or gravity GX,GY,GZ "
                         f"in m/s^2 in the device's base frame, got {text!r}") from None


def loading_of(args: argparse.Namespace, preset):
    """The ``metrics.loading.Loading`` of ``--rating`` and ``--gravity``, checked against ``preset``'s model.

    Raises
    ------
    UsageError
        Naming ``--rating peak`` or ``--gravity`` and the device, when its model has no peak
        rating or no mass model.
    """
    from metrics.loading import Loading, LoadingError

    mounting, vector = parse_gravity(getattr(args, "gravity", None))
    loading = Loading(rating=getattr(args, "rating", "continuous"), gravity=vector, mounting=mounting)
    try:
        loading.check(preset.mechanism, device=f"device {preset.key}")
    except LoadingError as exc:
        option = "--rating peak" if exc.argument == "rating" else f"--gravity {args.gravity}"
        hint = "use --rating continuous" if exc.argument == "rating" else "leave out --gravity"
        raise UsageError(f"{option}: {exc.args[0].split(': ', 1)[1]}; {hint}") from None
    return loading


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

_DURATION_UNITS = {"": 1.0, "s": 1.0, "min": 60.0, "h": 3600.0, "d": 86400.0}


def parse_duration(text: str, name: str = "--max-time") -> float:
    """``"3600"``, ``"1e9"``, ``"90s"``, ``"30min"``, ``"2h"``, ``"3d"`` as seconds (> 0).

    Raises a UsageError naming ``name`` otherwise.
    """
    t = str(text).strip().lower()
    number = t.rstrip("abcdefghijklmnopqrstuvwxyz")
    if number.endswith("e"):             # "1e" of "1e9" is not a unit
        number = t
    unit = t[len(number):].strip()
    try:
        value = float(number) * _DURATION_UNITS[unit]
    except (ValueError, KeyError):
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise UsageError(f"{name} needs a positive duration in seconds, or with a unit (90s, 30min, 2h, 3d), "
                         f"got {text!r}")
    return value


def add_max_time_argument(parser: argparse.ArgumentParser) -> None:
    """Add ``--max-time SECONDS``: the longest predicted run time a job may start with (default an hour)."""
    parser.add_argument("--max-time", metavar="SECONDS", default=None,
                        help="refuse a job whose run time, predicted from a timed sample, is longer than this "
                             "(seconds, or 90s, 30min, 2h, 3d; default 1 h); nothing is computed or written")


def load_device(args: argparse.Namespace):
    """The preset named by ``args.device`` with ``args.overrides`` (``--set``) applied.

    Raises
    ------
    UsageError
        Naming ``DEVICE`` or ``--set`` and the offending value.
    """
    from resources import PresetError, load_preset
    from resources.schema import with_changes

    try:
        preset = load_preset(args.device)
    except PresetError as exc:
        raise UsageError(f"DEVICE: {exc}") from None
    changes = parse_overrides(preset.mechanism, getattr(args, "overrides", None) or [])
    if changes:
        try:
            # Its [source] says which values --set changed: the sources describe the preset's own.
            preset = with_changes(preset, preset.mechanism.replace_display(**changes))
        except ValueError as exc:
            raise UsageError(f"--set: {_typed_units_message(preset.mechanism, changes, exc)}") from None
    return preset


def _typed_units_message(mechanism, changes: dict[str, Any], exc: ValueError) -> str:
    """The model's message about ``--set`` values, with the values as typed, in the typed unit.

    The model validates SI values (``proximal_length ... in m, got -0.005``); a person typed
    ``proximal_length=-5`` in mm. When every typed value is a number (so the SI check is what
    failed), the SI tail after "got" and the SI unit are dropped and the typed values of the
    parameters the message names follow, each with its display unit. Other messages (not a
    number, wrong count) already show the typed text and are kept.
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
    # The SI unit the model was given ("... in m", "(given in rad)") is not what the person typed.
    rule = re.sub(r" in (m|rad|m/s|rad/s)$", "", message.rsplit(", got ", 1)[0])
    rule = re.sub(r" \(given in [^)]*\)", "", rule)
    # Only the values the message is about: the parameters it names (all typed ones if it names none).
    named = [n for n in changes if re.search(rf"\b{re.escape(n)}\b", rule)] or list(changes)
    typed = "; ".join(f"{n} = {', '.join(changes[n]) if isinstance(changes[n], list) else changes[n]}"
                      + (f" {infos[n].unit}" if infos[n].unit and infos[n].unit != "-" else "")
                      for n in named)
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
        raise UsageError(f"{name} needs {wanted} in {units_phrase(mechanism)}, got {text!r}")
    return task_to_si(mechanism, values)



def parse_joints(text: str, mechanism, name: str = "--joints") -> np.ndarray:
    """``"A,B,C"`` typed in display units (deg for revolute joints, mm for prismatic ones) as joints in SI, (n,).

    Raises a UsageError naming ``name`` when the text is not n finite numbers.
    """
    n = mechanism.n_joints
    units = joint_display_units(mechanism)
    try:
        values = [float(p) for p in text.split(",")]
    except ValueError:
        values = []
    if len(values) != n or not all(np.isfinite(values)):
        wanted = ", ".join(f"{j} ({u})" for j, u in zip(mechanism.joint_names, units))
        raise UsageError(f"{name} needs {n} comma-separated numbers: {wanted}, got {text!r}")
    return joints_to_si(mechanism, values)


def device_grid(preset, resolution: int | None):
    """The preset's default grid, at ``resolution`` points per axis if given."""
    return preset.grid if resolution is None else preset.grid.with_resolution(resolution)



#: Jobs estimated above this many bytes, or points, say so on stderr before they start (a
#: streamed map fits in memory at any resolution, but 10^10 points take hours).
NOTE_BYTES = 2 << 30
NOTE_POINTS = 10 ** 8
#: Runs predicted to take longer than this (seconds) say so before they start (their progress
#: shows from ``app.cli._progress.PROGRESS_AFTER`` on, sooner).
NOTE_SECONDS = 10.0


def check_memory(mechanism, grid, quantities, *, keep_maps: bool = True, output: str | None = None,
                 copies: int = 1, option: str = "--resolution", work_bytes: float | None = None,
                 workers: int | None = None, note: bool = True):
    """Refuse a map that cannot fit in the available memory, before computing anything.

    Returns the ``metrics.budget.Estimate``; a large job that fits gets a one-line note on
    stderr with its size (unless ``note`` is false). Raises a UsageError naming ``option`` with
    the estimate and the largest resolution that fits. ``work_bytes``: a chunk's bytes per
    point, measured, and ``workers``: the chunks in flight (``metrics.budget.map_estimate``).
    """
    from metrics.budget import BudgetError, check_map

    try:
        est = check_map(mechanism, grid.resolution, quantities, keep_maps=keep_maps, output=output, copies=copies,
                        option=option, work_bytes=work_bytes, workers=workers)
    except BudgetError as exc:
        raise UsageError(f"{option}: {exc}") from None
    if note and (est.bytes > NOTE_BYTES or est.points > NOTE_POINTS):
        print(f"{PROG}: note: {est.text()}", file=sys.stderr)
    return est


@dataclass(frozen=True)
class MapJob:
    """One map a command will compute: what ``check_job`` measures and checks.

    ``points_at(n)`` gives its points at ``--resolution n`` (default every axis ``n``), for the
    advice of a refusal; ``copies`` maps of it are held at once.
    """

    mechanism: Any
    grid: Any
    quantities: tuple[str, ...]
    keep_maps: bool = True
    output: str | None = None
    copies: int = 1
    loading: Any = None
    points_at: Callable[[int], int] | None = None


def job_points(jobs) -> int:
    """Grid points of ``jobs`` (a ``MapJob`` or several) in all: a progress bar's whole."""
    jobs = [jobs] if isinstance(jobs, MapJob) else list(jobs)
    return sum(math.prod(j.grid.resolution) for j in jobs)


def check_job(command: str, jobs, *, max_time: str | None, option: str = "--resolution", what: str | None = None):
    """Refuse maps that will not fit in memory or in ``--max-time``, before computing anything.

    ``jobs`` (a ``MapJob`` or several, run one after another) are checked against the memory
    (``check_memory``). Jobs of more than ``metrics.runtime.UNTIMED_POINTS`` points in all are
    then measured on samples of their grids: the bytes a full chunk of feasible points
    allocates (``metrics.workspace.chunk_bytes_per_point``) and the chunks in flight
    (``chunks_in_flight``), which make the memory estimate the job's own, and the time per
    point (``metrics.runtime.seconds_per_point``, on ``sample_points`` of the jobs' points: a
    32nd, at most 32,768). Jobs over the same range share one measurement, taken on the
    largest of them (a convergence ladder's finest rung). The measurement loads the compiled
    kernel the maps use (its first load, from numba's cache, is most of the check's time, and
    the maps would pay it); its own cost is that sample, one chunk of 8,192 points and two
    traced chunks of 2,048 and 8,192 points.
    Smaller jobs are not timed; one small map per device (``metrics.runtime.warm_up``) pays
    their first-map costs (imports, the compiled code's load) before their clocks start.
    A run predicted to take longer than ``max_time`` (default an hour) is refused with the
    prediction and the largest ``option`` that finishes in time: one line, exit status 2,
    nothing computed or written. A large run gets one note on stderr with its peak memory and
    predicted time.

    Parameters
    ----------
    command : str
        The subcommand, for the note.
    jobs : MapJob or sequence of MapJob
        The maps.
    max_time : str or None
        ``--max-time`` as typed (default an hour).
    option : str
        The option the advice names.
    what : str, optional
        The run in the messages (default: the map's own description, or "N maps").

    Returns
    -------
    metrics.runtime.Prediction or None
        The predicted run time of the maps, when they were timed.
    """
    from app.cli._process import start_up_window

    # Its first call loads numba and the kernels: a start-up's objects (``app.cli._process``).
    with start_up_window():
        return _check_job(command, jobs, max_time=max_time, option=option, what=what)


def _check_job(command: str, jobs, *, max_time: str | None, option: str, what: str | None):
    from metrics.budget import format_bytes, grid_points
    from metrics.runtime import (
        MAX_SECONDS,
        UNTIMED_POINTS,
        RunTimeError,
        check_run_time,
        format_duration,
        sample_points,
        seconds_per_point,
        warm_up,
    )
    from metrics.workspace import chunk_bytes_per_point, chunks_in_flight

    jobs = [jobs] if isinstance(jobs, MapJob) else list(jobs)
    limit = MAX_SECONDS if max_time is None else parse_duration(max_time)
    estimates = [check_memory(j.mechanism, j.grid, j.quantities, keep_maps=j.keep_maps, output=j.output,
                              copies=j.copies, option=option, note=False) for j in jobs]
    points = sum(e.points for e in estimates)
    if points <= UNTIMED_POINTS:
        # Not timed, but its first-map costs are paid here as a timed job's are by its sample, so
        # that a map's seconds are its own (a platform's stats paid numba's import in them).
        for j in {(id(j.mechanism), tuple(j.quantities), j.keep_maps, j.loading): j for j in jobs}.values():
            warm_up(j.mechanism, j.grid, j.quantities, keep=j.keep_maps, loading=j.loading)
        return None
    sample = sample_points(points)

    def same_range(j: MapJob) -> tuple:
        return (id(j.mechanism), j.grid.axes, j.grid.lower, j.grid.upper, j.grid.fixed, tuple(j.quantities),
                j.keep_maps, j.loading)

    # A convergence ladder's rungs share one measurement, on the finest: a sample grid has no more
    # points per axis than its grid, and the coarsest rung's 50 x 50 (its first) made the sample
    # 2,500 points, whose per-call costs predicted the ladder at 2-3 µs a point for 0.6-0.9.
    finest: dict[tuple, MapJob] = {}
    for j in jobs:
        held = finest.setdefault(same_range(j), j)
        if math.prod(j.grid.resolution) > math.prod(held.grid.resolution):
            finest[same_range(j)] = j
    measured: dict[tuple, tuple[float | None, int, float]] = {}
    rates = []
    for k, j in enumerate(jobs):
        key = same_range(j)
        if key not in measured:
            f = finest[key]
            measured[key] = (chunk_bytes_per_point(f.mechanism, f.grid, f.quantities, keep=f.keep_maps,
                                                   loading=f.loading),
                             chunks_in_flight(f.mechanism, f.grid, f.quantities, loading=f.loading),
                             seconds_per_point(f.mechanism, f.grid, f.quantities, keep=f.keep_maps,
                                               loading=f.loading, sample=sample))
        work, workers, rate = measured[key]
        estimates[k] = check_memory(j.mechanism, j.grid, j.quantities, keep_maps=j.keep_maps, output=j.output,
                                    copies=j.copies, option=option, work_bytes=work, workers=workers, note=False)
        rates.append(rate)
    seconds = sum(e.points * r for e, r in zip(estimates, rates))

    def seconds_at(n: int) -> float:
        return sum(r * (j.points_at(n) if j.points_at is not None else grid_points((n,) * len(j.grid.axes)))
                   for j, r in zip(jobs, rates))

    biggest = max(estimates, key=lambda e: e.peak)
    if what is None:
        what = biggest.what if len(jobs) == 1 else f"{len(jobs)} maps"
    try:
        prediction = check_run_time(what, points, seconds, seconds_at=seconds_at, max_seconds=limit, option=option)
    except RunTimeError as exc:
        raise UsageError(f"--max-time: {exc}") from None
    if biggest.bytes > NOTE_BYTES or points > NOTE_POINTS or seconds > NOTE_SECONDS:
        # Maps run one after another: the peak is the largest one's; the time and points are all of them.
        print(f"{PROG} {command}: note: {what}: {points:,} points, about {format_bytes(biggest.peak)} at peak, "
              f"about {format_duration(seconds)} ({format_duration(prediction.seconds_per_point)} a point, "
              f"timed on a sample)", file=sys.stderr)
    return prediction


def check_out(path: str, suffixes: tuple[str, ...]) -> Path:
    """Fail fast on a bad ``--out``, before any computing: suffix, a file name, a writable folder."""
    try:
        return check_output(path, suffixes, "--out")
    except ValueError as exc:
        raise UsageError(str(exc)) from None

