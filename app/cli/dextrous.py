"""``isoforce dextrous DEVICE [DEVICE ...]``: the semi-dextrous workspace (paper 001, sec. V, Figs. 13-14).

The positions of a 3D grid where the device can hold every orientation within the bound
``--angle`` (deg; tip of the pen axis y in any direction, roll about it, and the pure rotations about x, y, z:
``metrics.dextrous``), with its volume in cm^3 and the volume's grid-error estimate. Several
DEVICEs are computed one after the other and compared; ``--out`` draws them side by side in 3D
(PNG, SVG, PDF). ``--ujoint-limit`` sets the U-joint bend limit of every device that has one
(parameter ``ujoint_limit``: Twin-Pantograph, Inoue platform); the others are reported as not
applicable. Like is compared with like: beside a 6-DOF device, a 5-DOF roll-free Twin-Pantograph
is taken in its 6-DOF version (roll actuated, waist q4 passive: paper 001 Table III; ``--as-is``
keeps it as it is). Without ``--box`` each device's box starts from its map range and grows
until the region no longer touches it; a region that still does is printed as a lower bound
(">= V (clipped by the box)").
"""
from __future__ import annotations

import argparse
import math
import sys
from typing import Any

from app.cli._args import UsageError, add_device_argument, check_out, int_at_least, load_device
from app.cli._format import number, print_json, table
from app.cli._progress import Progress, progress_for
from app.files.export import FIGURE_SUFFIXES
from app.logic import volume_digits
from metrics.budget import BudgetError, check_fits
from metrics.dextrous import (
    LOWER_BOUND_NOTE,
    VOLUME_ERROR_LABEL,
    box_grid,
    dextrous_region,
    face_test,
    grown_grid,
    region_estimate,
)
from metrics.dextrous_orientations import orientation_set

DEFAULT_RESOLUTION = 25
UJOINT = "ujoint_limit"
#: Rounds a default box grows by (each moves every face the region touches out by the box's span on
#: that axis, the spacing kept); a region still clipped after them is printed as a lower bound.
GROW_ROUNDS = 3
#: The 6-DOF version of a 5-DOF, roll-free pen (paper 001 Table III: roll q7 actuated, waist q4 passive).
SIX_DOF = {"roll_actuator": "active", "redundant_waist": "passive"}
ROLL_FREE = ("rx", "rz")
DEFINITION = ("semi-dextrous workspace: the grid positions where every orientation sample within +-angle "
              "(tip of the pen axis y up to angle in any direction, roll about it up to +-angle, and the pure "
              "rotations of +-angle about x, y and z) is reachable and within every joint limit (paper 001 "
              "sec. V); volume = positions inside times the cell volume; an orientation between samples is "
              "not tested")


def register(subparsers) -> None:
    p = subparsers.add_parser("dextrous", help="semi-dextrous workspace: volume and 3D figure (paper 001 Figs. 13-14)",
                              description=__doc__.split("\n\n")[1].replace("\n", " ").replace("``", ""))
    add_device_argument(p)
    p.add_argument("more", nargs="*", metavar="DEVICE", help="more devices to compare (then --set is refused)")
    p.add_argument("--angle", type=float, default=30.0, metavar="DEG",
                   help="orientation bound in deg, in (0, 90] (default 30, the paper's)")
    p.add_argument("--ujoint-limit", type=float, metavar="DEG",
                   help="U-joint bend limit in deg for devices with one (default: each device's own; the "
                        "shipped presets have 85; 90 is the largest the models accept)")
    p.add_argument("--resolution", type=int_at_least(3), default=DEFAULT_RESOLUTION, metavar="N",
                   help=f"grid points per axis of the (starting) box (default {DEFAULT_RESOLUTION}); a grown box keeps "
                        "the spacing")
    p.add_argument("--box", metavar="X0,X1,Y0,Y1,Z0,Z1",
                   help="position box in mm, fixed (default: each preset's map range, its fixed axis given the "
                        "largest span of the others, grown until the region does not touch it)")
    p.add_argument("--as-is", action="store_true",
                   help="compare each device as its preset is: a 5-DOF, roll-free Twin-Pantograph is then tested "
                        "on tilts alone beside 6-DOF devices (default: its 6-DOF version, roll actuated)")
    p.add_argument("--rings", type=int_at_least(1), metavar="N",
                   help="eq. 16's N, tip rings besides the pole (default: one every 10 deg)")
    p.add_argument("--rolls", type=int_at_least(1), metavar="K",
                   help="roll angles over [-angle, angle] (default: every 10 deg)")
    p.add_argument("--size", metavar="WxH", help="PNG size of the whole figure in pixels (default 900x900 per device)")
    p.add_argument("--width-in", type=float, metavar="IN",
                   help="the figure's width in inches (e.g. 3.5 for a journal column) with its text at --font-pt; "
                        "PDF and SVG text stays vector, the pictures are rasters at 300 dpi")
    p.add_argument("--font-pt", type=float, metavar="PT", help="with --width-in: the text's size in points (default 8)")
    p.add_argument("--out", metavar="FILE", help="3D figure of the region(s): .png, .svg or .pdf")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def _angle(value: float, name: str, upper: float) -> float:
    if not (math.isfinite(value) and 0.0 < value <= upper):
        raise UsageError(f"{name} needs an angle in (0, {upper:g}] deg, got {value:g}")
    return math.radians(value)


def parse_box(text: str) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """``"X0,X1,Y0,Y1,Z0,Z1"`` in mm -> (lower, upper) in m; a UsageError naming --box otherwise."""
    try:
        v = [float(t) for t in text.split(",")]
    except ValueError:
        v = []
    if len(v) != 6 or not all(math.isfinite(x) for x in v) or not all(v[2 * i] < v[2 * i + 1] for i in range(3)):
        raise UsageError(f"--box needs X0,X1,Y0,Y1,Z0,Z1 in mm with X0 < X1, Y0 < Y1, Z0 < Z1, got {text!r}")
    return (v[0] / 1e3, v[2] / 1e3, v[4] / 1e3), (v[1] / 1e3, v[3] / 1e3, v[5] / 1e3)


def default_box(preset) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The preset's map range for x, y, z (m); a fixed position axis gets the largest span of the others."""
    grid = preset.grid
    ranges = {a: (lo, hi) for a, lo, hi in zip(grid.axes, grid.lower, grid.upper)}
    fixed = dict(grid.fixed)
    spans = [hi - lo for a, (lo, hi) in ranges.items() if a in ("x", "y", "z")]
    if not spans:
        raise UsageError(f"DEVICE {preset.key!r}: its map varies no position axis; give --box")
    half = 0.5 * max(spans)
    lower, upper = [], []
    for a in ("x", "y", "z"):
        if a in ranges:
            lo, hi = ranges[a]
        else:
            centre = fixed.get(a, 0.0)
            lo, hi = centre - half, centre + half
        lower.append(lo)
        upper.append(hi)
    return tuple(lower), tuple(upper)


def _with_ujoint(preset, limit_deg: float | None):
    """The preset with ``ujoint_limit`` set (if it has one), and the limit it then has (deg) or None."""
    mech = preset.mechanism
    info = {i.name: i for i in mech.PARAM_INFO}.get(UJOINT)
    if info is None:
        return preset, None
    if limit_deg is not None:
        try:
            mech = mech.replace_display(**{UJOINT: limit_deg})
        except ValueError as exc:
            raise UsageError(f"--ujoint-limit: {' '.join(str(exc).split())}") from None
        preset = preset.replace(mechanism=mech)
    return preset, info.from_si(getattr(mech.params, UJOINT))


def _load_all(args) -> list:
    keys = [args.device] + list(args.more)
    if args.overrides and len(keys) > 1:
        raise UsageError("--set applies to one DEVICE; to compare changed devices, give each as a .toml preset")
    presets = [load_device(argparse.Namespace(device=k, overrides=args.overrides if i == 0 else []))
               for i, k in enumerate(keys)]
    return presets


def _orientation_names(mech) -> tuple[str, ...]:
    return tuple(n for n in mech.task_names if n not in ("x", "y", "z"))


def like_with_like(presets, as_is: bool = False) -> tuple[list, list[str | None]]:
    """The presets to compare and, per preset, a note when it was changed to compare like with like.

    When roll-free (5-DOF: tilts ``rx, rz``) and 6-DOF devices are compared, each roll-free one is
    taken in its 6-DOF version (``SIX_DOF``: roll actuated, waist q4 passive, paper 001 Table III),
    unless ``as_is``. A roll-free device without such a version is refused.

    Parameters
    ----------
    presets : list of Preset
    as_is : bool
        Keep every preset as it is.

    Returns
    -------
    (list of Preset, list of str or None)

    Raises
    ------
    UsageError
        For a roll-free device with no 6-DOF version beside a 6-DOF one (without ``as_is``).
    """
    kinds = [_orientation_names(p.mechanism) for p in presets]
    notes: list[str | None] = [None] * len(presets)
    if as_is or ROLL_FREE not in kinds or all(k == ROLL_FREE for k in kinds):
        return list(presets), notes
    out = []
    for i, (p, kind) in enumerate(zip(presets, kinds)):
        if kind != ROLL_FREE:
            out.append(p)
            continue
        names = {info.name for info in p.mechanism.PARAM_INFO}
        if not set(SIX_DOF) <= names:
            raise UsageError(f"DEVICE {p.key!r} has no roll coordinate and no 6-DOF version; it cannot be compared "
                             f"with 6-DOF devices like with like (give --as-is to compare it as it is)")
        out.append(p.replace(mechanism=p.mechanism.replace(**SIX_DOF)))
        notes[i] = ("its 6-DOF version (roll q7 actuated, waist q4 passive: paper 001 Table III), to compare like "
                    "with like; the preset itself is 5-DOF, roll-free (--as-is)")
    return out, notes


def _fits(mech, grid, copies: int) -> bool:
    try:
        check_fits(region_estimate(mech, grid.resolution, copies=copies), advice="")
    except BudgetError:
        return False
    return True


def device_region(preset, args, angle: float, box, copies: int = 1, progress=None):
    """The preset (with --ujoint-limit applied), its region, its U-joint limit (deg or None) and the
    number of rounds its default box grew by (0 with --box). ``progress`` (``app.cli._progress``)
    hears the share of each region's orientations done and a step per grown box.

    A box that grows is left after testing its face points alone (``metrics.dextrous.face_test``):
    they decide the growth, and the grown box holds every point of it again. The region is the one
    computed in full on each box in turn would end with."""
    preset, ujoint = _with_ujoint(preset, args.ujoint_limit)
    mech = preset.mechanism
    try:
        orientations = orientation_set(mech, angle, rings=args.rings, rolls=args.rolls)
    except ValueError as exc:
        raise UsageError(f"DEVICE {preset.key!r}: {' '.join(str(exc).split())}") from None
    lower, upper = box if box is not None else default_box(preset)
    grid = box_grid(lower, upper, args.resolution)
    rounds, faces = 0, None
    while box is None and rounds < GROW_ROUNDS:
        faces = face_test(mech, grid, orientations)
        touched = faces.touched()
        if not touched:
            break
        bigger = grown_grid(grid, touched)
        if not _fits(mech, bigger, copies):
            break
        grid, rounds, faces = bigger, rounds + 1, None
        if progress is not None:        # the share starts again over the grown box
            progress.step(f"{preset.key}, grown box {rounds}")
    region = dextrous_region(mech, grid, orientations, progress=progress, faces=faces)
    return preset, region, ujoint, rounds


class _Part:
    """One device's share of the run's progress: called with the share of its region done."""

    def __init__(self, progress: Progress, index: int, key: str) -> None:
        self.progress, self.share = progress, progress.part(index, 1)
        progress.step(key)

    def __call__(self, fraction: float) -> None:
        self.share(fraction)

    def step(self, message: str) -> None:
        self.progress.step(message)


def summary(preset, region, ujoint, rounds: int = 0, note: str | None = None) -> dict[str, Any]:
    """One device's JSON row (display units: cm^3, mm, deg). A ``clipped`` volume is a lower bound."""
    v, r = region.volume, region.reachable_volume
    g = region.grid
    return {
        "key": preset.key,
        "name": preset.name,
        "task": list(preset.mechanism.task_names),
        "changed": note,
        "angle_deg": math.degrees(region.orientations.angle),
        "ujoint_limit_deg": ujoint,
        "volume_cm3": v.value * 1e6,
        "volume_error_cm3": v.error * 1e6,
        "volume_is_lower_bound": region.clipped,
        "reachable_volume_cm3": r.value * 1e6,
        "reachable_volume_error_cm3": r.error * 1e6,
        "reachable_volume_is_lower_bound": region.reachable_clipped,
        "points_inside": v.points,
        "boundary_points": v.boundary_points,
        "clipped": region.clipped,
        "reachable_clipped": region.reachable_clipped,
        "box_grew_rounds": rounds,
        "box_mm": {a: [lo * 1e3, hi * 1e3] for a, lo, hi in zip(g.axes, g.lower, g.upper)},
        "resolution": list(g.resolution),
        "cell_cm3": v.cell * 1e6,
        "orientations": {"count": region.orientations.count, "rings": region.orientations.rings,
                         "rolls": region.orientations.rolls, "roll_free": region.orientations.roll_free,
                         "tip_count": region.orientations.tip_count,
                         "description": region.orientations.description()},
        "poses_evaluated": region.poses_evaluated,
        "seconds": region.seconds,
    }


def cm3(value: float, digits: int = 4) -> str:
    """A volume in cm^3: ``digits`` significant figures, no exponent (30140, 392.5, 1.296)."""
    return volume_digits.plain(value, digits)


def volume_text(value: float, error: float, lower_bound: bool) -> str:
    """``"V +- E"`` with the digits E supports, or ``">= V (clipped by the box)"`` for a region that
    touches its box (cm^3; ``app.logic.volume_digits``, as the figure prints it)."""
    return volume_digits.volume_text(value, error, lower_bound, LOWER_BOUND_NOTE)


def format_text(rows) -> str:
    head = ("device", "semi-dextrous volume (cm^3)", "reachable at zero orientation (cm^3)", "U-joint limit (deg)")
    cells = [head] + [(r["key"], volume_text(r["volume_cm3"], r["volume_error_cm3"], r["volume_is_lower_bound"]),
                       volume_text(r["reachable_volume_cm3"], r["reachable_volume_error_cm3"],
                                   r["reachable_volume_is_lower_bound"]),
                       "n/a" if r["ujoint_limit_deg"] is None else number(r["ujoint_limit_deg"], 4)) for r in rows]
    lines = [table(cells), ""]
    for r in rows:
        box = ", ".join(f"{a} {lo:g} to {hi:g} mm" for a, (lo, hi) in r["box_mm"].items())
        grew = ""
        if r["box_grew_rounds"]:
            grew = f" (grown {r['box_grew_rounds']} time{'s' if r['box_grew_rounds'] > 1 else ''} from the map range)"
        lines.append(f"{r['key']}: {box}{grew}; {' x '.join(map(str, r['resolution']))} points "
                     f"(cell {number(r['cell_cm3'], 4)} cm^3); {r['orientations']['description']}; "
                     f"{r['poses_evaluated']:,} poses in {r['seconds']:.1f} s")
        if r["changed"]:
            lines.append(f"  {r['key']} is {r['changed']}")
    lines += ["", DEFINITION + ".", "+- : " + VOLUME_ERROR_LABEL + ".",
              f">= : {LOWER_BOUND_NOTE}: the region touches its box and may go on past it, so its volume is a "
              f"lower bound (give a larger --box)."]
    return "\n".join(lines)


def to_json(rows) -> dict[str, Any]:
    """The object ``--json`` prints."""
    return {"devices": rows, "definitions": {"semi_dextrous": DEFINITION, "volume_error": VOLUME_ERROR_LABEL,
                                             "lower_bound": f"{LOWER_BOUND_NOTE}: a volume whose region touches "
                                                            f"its box is a lower bound"},
            "units": {"volume": "cm^3", "length": "mm", "angle": "deg"}}


def _column(args) -> tuple[float, float] | None:
    """``(width in, font pt)`` from ``--width-in`` and ``--font-pt`` (as ``isoforce figure``'s), or None."""
    if args.width_in is None:
        if args.font_pt is not None:
            raise UsageError("--font-pt needs --width-in (the column the text is sized for)")
        return None
    font = 8.0 if args.font_pt is None else args.font_pt
    for flag, value, (lo, hi), unit in (("--width-in", args.width_in, (1.0, 20.0), "in"),
                                        ("--font-pt", font, (4.0, 30.0), "pt")):
        if not lo <= value <= hi:
            raise UsageError(f"{flag} must be {lo:g} to {hi:g} {unit}, got {value:g}")
    if args.size is not None:
        raise UsageError("--size (pixels) and --width-in (inches) both set the size: give one")
    if args.out is None:
        raise UsageError("--width-in sizes the figure: give --out")
    return args.width_in, font


def run(args: argparse.Namespace) -> int:
    angle = _angle(args.angle, "--angle", 90.0)
    if args.ujoint_limit is not None:
        _angle(args.ujoint_limit, "--ujoint-limit", 90.0)
    box = parse_box(args.box) if args.box is not None else None
    presets, notes = like_with_like(_load_all(args), args.as_is)
    target = check_out(args.out, FIGURE_SUFFIXES) if args.out is not None else None
    column = _column(args)
    size = None
    if args.size is not None:
        from app.render.views import parse_size
        try:
            size = parse_size(args.size)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
    for p in presets:
        try:
            check_fits(region_estimate(p.mechanism, (args.resolution,) * 3, copies=len(presets)),
                       advice="use a smaller --resolution")
        except BudgetError as exc:
            raise UsageError(f"--resolution: {exc}") from None
    # Not predicted: the bar shows once the regions have run PROGRESS_AFTER seconds.
    results = []
    with progress_for("isoforce dextrous", None, len(presets), unit="devices", json_out=args.json) as progress:
        for i, p in enumerate(presets):
            part = _Part(progress, i, p.key) if isinstance(progress, Progress) else None
            results.append(device_region(p, args, angle, box, copies=len(presets), progress=part))
    rows = [summary(p, region, uj, rounds, note) for (p, region, uj, rounds), note in zip(results, notes)]
    if target is not None:
        from app.scenes.dextrous_figure import save_dextrous_figure  # pyvista only when drawing
        from app.scenes.snapshot import RASTER_NOTE
        titles = [p.name + (" (6-DOF version)" if note else "") + (f"\nU-joints +-{uj:g} deg" if uj is not None else "")
                  for (p, _, uj, _), note in zip(results, notes)]
        save_dextrous_figure([r for _, r, _, _ in results], titles, target, size=size, column=column, name="--out")
        note = f" ({RASTER_NOTE})" if target.suffix.lower() in (".svg", ".pdf") else ""
        print(f"wrote {target}{note}", file=sys.stderr)
    if args.json:
        print_json(to_json(rows))
    else:
        print(format_text(rows))
    return 0

