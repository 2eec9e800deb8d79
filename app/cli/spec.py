"""``isoforce spec DEVICE [--at P]``: the device's specification sheet at one pose (paper 001, Table X).

Per task axis: the largest box of Table X's shape held at every orientation within +-45 deg
(``metrics.spec_box``) beside the workspace extent through the pose, the spatial resolution (where
the preset gives joint sensor resolutions), the minimum force (the preset's ``[spec]`` table:
measured), the continuous and peak force (moment) along the axis (the peak from the model's peak
rating or the ``[spec]`` table's ``peak_motor_torques``), the dynamic range and the acceleration
by Table X's definitions (peak force over the minimum force, over the effective mass), the
effective mass (where it gives a mass matrix), and two bounds for a passive virtual wall
(quantisation and sampling, ``metrics.spec_sheet``). A row the device's data do not support is
named with the reason instead of being left out silently, and the rows no model gives (Table X's
measured stiffness and damping) are named as such.
"""
from __future__ import annotations

import argparse
import math

import numpy as np

from app.cli._args import UsageError, add_device_argument, int_at_least, load_device, parse_gravity, parse_point
from app.cli._format import number, point_text, print_json, table, vector
from metrics.resolution import mechanism_steps
from metrics.spec_box import DEFAULT_POINTS, TABLE_X_HALF_WIDTHS, box_orientations, largest_held_box
from metrics.spec_sheet import STANDARD_GRAVITY, spec_rows, weight_range
from resources.spec_table import peak_torque_limits

#: Half-width searched along a rotation axis for its extent, rad.
ROTATION_SPAN = np.pi / 2


def register(subparsers) -> None:
    p = subparsers.add_parser("spec", help="the device's specification sheet at one pose",
                              description="Per task axis at the preset's pose (or --at): the largest box of "
                                          "Table X's shape held at every orientation within +-45 deg, the "
                                          "workspace extent through the pose, spatial resolution, minimum "
                                          "force, continuous and peak force along the axis (every other wrench "
                                          "component zero), dynamic range and acceleration from the peak force, "
                                          "effective mass (the mass matrix's diagonal), and bounds for a passive "
                                          "virtual wall. Rows need data the preset may not have; each missing "
                                          "row says why.")
    add_device_argument(p)
    p.add_argument("--at", metavar="X,Y,Z", help="the pose, mm (and deg for a pen's angles); default: the preset's")
    p.add_argument("--gravity", default="upright", metavar="MOUNTING|GX,GY,GZ",
                   help="mounting for the weight row (devices with a mass model): a mounting name or gravity in "
                        "m/s^2 in the base frame; default upright")
    p.add_argument("--box-angle", type=float, default=45.0, metavar="DEG",
                   help="orientation bound of the held box, deg in (0, 90] (default 45, Table X's)")
    p.add_argument("--box-shape", metavar="HX,HY,HZ",
                   help="the held box's half-widths at scale 1, mm (default Table X's 60,37.5,37.5); the box "
                        "printed is the largest of this shape")
    p.add_argument("--box-points", type=int_at_least(2), default=DEFAULT_POINTS, metavar="N",
                   help=f"grid points per axis tested over the box (default {DEFAULT_POINTS})")
    p.add_argument("--box-rings", type=int_at_least(1), metavar="N",
                   help="eq. 16's N for the held box's orientations, tip rings besides the pole (default: one "
                        "every 10 deg, as `isoforce dextrous`)")
    p.add_argument("--no-box", action="store_true", help="skip the held box (its search is the slowest row)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


#: Points per axis of the default map at most, for the weight range (a grid's extremes).
WEIGHT_GRID = 101


def _weight(preset, gravity_text: str):
    """``(low, high, count, gravity, grid resolution)`` of the weight the hand holds, or None without a mass model."""
    from kinematics.gravity import gravity_vector

    mech = preset.mechanism
    if not mech.has_mass_model:
        return None
    mounting, vector = parse_gravity(gravity_text)
    if mounting is None and vector is None:
        return None
    g = np.asarray(gravity_vector(mounting) if mounting is not None else vector, float)
    grid = preset.grid.with_resolution(tuple(min(r, WEIGHT_GRID) for r in preset.grid.resolution))
    pts = grid.points(mech.task_names).reshape(-1, mech.task_dim)
    low, high, count = weight_range(mech, pts, g)
    return low, high, count, g, grid.resolution


def _spans(preset) -> np.ndarray:
    """Half-widths searched per task axis: the default map's largest width for positions, 90 deg for rotations."""
    mech, grid = preset.mechanism, preset.grid
    width = max(hi - lo for lo, hi in zip(grid.lower, grid.upper))
    return np.array([ROTATION_SPAN if u == "rad" else width for u in mech.task_units])


def _model_mass(mech, x):
    """The model's task-space inertia (m, m) at ``x`` (links and rotors), or None without a mass model
    or where it is not finite and positive definite."""
    if not mech.has_mass_model:
        return None
    q, ok = mech.inverse(np.asarray(x, float)[None])
    if not ok[0]:
        return None
    lam = mech.task_inertia(q, np.asarray(x, float)[None])[0]
    if not np.all(np.isfinite(lam)):
        return None
    try:
        np.linalg.cholesky(lam)
    except np.linalg.LinAlgError:
        return None
    return lam


def peak_limits(preset):
    """``(limits, source)``: the peak actuator limits (N m) and where they come from, or ``(None, None)``.

    The model's own peak rating first (``Mechanism.peak_torque_limits``), else the preset's
    ``[spec]`` table's ``peak_motor_torques`` (``resources.spec_table.peak_torque_limits``).
    """
    mech = preset.mechanism
    peak = mech.peak_torque_limits()
    if peak is not None:
        return np.asarray(peak, float), "the model's peak rating (peak_motor_torques)"
    try:
        peak = peak_torque_limits(preset.spec, mech)
    except ValueError as exc:
        raise UsageError(f"DEVICE: {preset.key}: {exc}") from None
    if peak is None:
        return None, None
    line = dict(preset.provenance).get("lines.peak_motor_torques")
    return peak, "the preset's [spec] peak_motor_torques" + (f" ({line})" if line else "")


#: Why the model gives none of Table X's measured rows (paper 001, Sec. VI).
NOT_MODELLED = {
    "minimum_force": "static friction, measured on the built device; the model has no friction; the row shows "
                     "the preset's [spec] minimum_forces where it gives them",
    "max_stiffness": "a measured figure: Table X's comes from a PD controller tuned at a 1 kHz control rate with "
                     "a hand on the pen and low-pass-filtered finite-difference velocity; no model here has the "
                     "hand's impedance, the velocity filter or the tuning. The bound rows are conditions for a "
                     "passive wall with the device alone, not this figure",
    "max_damping": "a measured figure, from the same tuned PD controller; not modelled, for the same reasons",
}
BOUND_NOTE = ("bounds for a passive virtual wall (spring K, damper B) with the device alone, no hand: "
              "K <= 2 f_c / D (encoder quantisation against Coulomb friction, Abbott & Okamura 2005), "
              "f_c = the minimum force, D = the spatial resolution; b > K T / 2 + |B| (sampled PD, Colgate & "
              "Schenkel 1997), b the device's physical viscous damping, T = 1 / control rate; the rows take B = 0")


def _box_shape(text: str | None) -> np.ndarray:
    if text is None:
        return np.array(TABLE_X_HALF_WIDTHS)
    try:
        v = np.array([float(t) for t in text.split(",")])
    except ValueError:
        v = np.empty(0)
    if v.shape != (3,) or not np.all(np.isfinite(v) & (v > 0)):
        raise UsageError(f"--box-shape needs three positive half-widths HX,HY,HZ in mm, got {text!r}")
    return v / 1e3


def _box_options(args) -> np.ndarray:
    """Check ``--box-angle`` and ``--box-shape`` before anything is computed; the shape in m."""
    if not (math.isfinite(args.box_angle) and 0.0 < args.box_angle <= 90.0):
        raise UsageError(f"--box-angle needs an angle in (0, 90] deg, got {args.box_angle:g}")
    return _box_shape(args.box_shape)


def _held_box(args, mech, x, shape):
    """``(HeldBox, None)`` or ``(None, why not)`` for the box centred at the pose's position."""
    if args.no_box:
        return None, "--no-box"
    names = mech.task_names
    if not all(a in names for a in ("x", "y", "z")):
        return None, f"a box needs task coordinates x, y and z; this device's are {', '.join(names)}"
    centre = np.array([x[names.index(a)] for a in ("x", "y", "z")])
    try:
        orientations = box_orientations(mech, math.radians(args.box_angle), rings=args.box_rings)
        box = largest_held_box(mech, centre, shape, orientations=orientations, points=args.box_points)
    except ValueError as exc:
        return None, str(exc)
    return box, None


def run(args: argparse.Namespace) -> int:
    preset = load_device(args)
    mech = preset.mechanism
    shape = _box_options(args)
    if args.at is not None:
        x = parse_point(args.at, mech)
    elif preset.pose is not None:
        x = np.asarray(preset.pose, float)
    else:
        raise UsageError(f"--at: {preset.key} has no [pose] in its preset; give the pose with --at")
    spec = preset.spec
    spans = _spans(preset)
    peak, peak_source = peak_limits(preset)
    steps = mechanism_steps(mech)
    table_mass = None if spec is None else spec.mass_matrix
    mass, mass_source = _model_mass(mech, x), "the model's bodies and rotors (links + J_rotor N^2)"
    if mass is None:
        mass, mass_source = table_mass, "the preset's [spec] table"
    try:
        rows = spec_rows(mech, x, spans=spans, peak_limits=peak, steps=steps, mass_matrix=mass,
                         minimum_forces=None if spec is None else spec.minimum_forces,
                         control_rate=None if spec is None else spec.control_rate,
                         physical_damping=None if spec is None else spec.physical_damping)
    except ValueError as exc:
        raise UsageError(f"--at: {point_text(mech, x)}: {exc}") from None
    box, box_why = _held_box(args, mech, x, shape)
    missing = _missing(spec, peak, steps, mass, box_why)
    weight = _weight(preset, args.gravity)
    if weight is None:
        missing["weight"] = ("the model has no mass model (link masses and centres of mass)"
                             if not mech.has_mass_model else "--gravity off")
    force_row = "peak" if peak is not None else "continuous"
    if args.json:
        out = _json(preset, x, rows, missing, force_row, spans)
        if mass is not None:
            out["effective_mass_source"] = mass_source
        if peak is not None:
            out["peak_limits"] = {"value": peak.tolist(), "units": "N m (N), joint side, actuated joints",
                                  "source": peak_source}
        if box is not None:
            out["held_box"] = _box_json(mech, box)
        if weight is not None:
            low, high, count, g, res = weight
            out["weight"] = {"min": low, "max": high, "units": "N", "points": count, "gravity": g.tolist(),
                             "grid": list(res), "note": "the weight the hand holds with the motors off, "
                                                        "extremes over the default map's feasible regular points"}
        print_json(out)
        return 0
    print(f"{preset.name} ({preset.key}) at {point_text(mech, x)}")
    print(table(_text_rows(mech, rows, force_row, spans, box)))
    if np.any(np.abs(rows["workspace"]) >= spans[:, None]):
        print("reach: a + marks an end at the searched span (the default map's width; 90 deg for a rotation)")
    if box is not None:
        print(_box_text(mech, x, box))
    if weight is not None:
        low, high, count, g, res = weight
        print(f"weight held, motors off: {number(low, 3)} to {number(high, 3)} N "
              f"({number(low / STANDARD_GRAVITY * 1e3, 3)} to {number(high / STANDARD_GRAVITY * 1e3, 3)} g) over "
              f"{count} feasible points of the default map at {' x '.join(map(str, res))}, gravity "
              f"({', '.join(number(v, 6) for v in g)}) m/s^2")
        if high == 0.0:
            print(f"weight: none along the task coordinates {', '.join(mech.task_names)}: gravity is carried by the "
                  f"structure (the joints' axes), not by the hand")
    if mass is not None:
        print(f"effective and apparent mass, acceleration: from {mass_source}")
    if peak is not None:
        print(f"peak torque rating: {vector(peak, 4)} N m at the actuated joints, from {peak_source}")
    if any(k in rows for k in BOUND_ROWS):
        rate = "" if spec is None or spec.control_rate is None else \
            f" (T = 1 / {number(spec.control_rate, 6)} Hz = {number(1e3 / spec.control_rate, 4)} ms)"
        print(BOUND_NOTE + rate)
    for name, why in NOT_MODELLED.items():
        print(f"{name.replace('_', ' ')}: not modelled ({why})")
    for name, why in missing.items():
        print(f"{name.replace('_', ' ')}: not given ({why})")
    if spec is not None and spec.where:
        print(f"[spec] data: {spec.where}")
    return 0


#: The bound rows, in print order: (row key, label).
BOUND_ROWS = {
    "stiffness_bound_quantisation": "bound: stiffness K <= 2 f_c / D",
    "damping_needed_quantisation": "bound: damping b > K T/2 at that K",
    "stiffness_bound_sampling": "bound: stiffness K < 2 b / T",
    "damping_bound_sampling": "bound: damping |B| < b",
}


def _missing(spec, peak, steps, mass, box_why) -> dict[str, str]:
    """Why each row the device's data do not support is absent."""
    missing = {}
    if box_why is not None:
        missing["held_box"] = box_why
    if peak is None:
        missing["peak"] = "the model gives no peak torque rating and the preset's [spec] table no peak_motor_torques"
    if steps is None:
        missing["resolution"] = "the preset gives no joint sensor resolution"
    if mass is None:
        missing["effective_mass"] = "the model has no mass model and the preset's [spec] table gives no mass matrix"
    minimum = spec is not None and spec.minimum_forces is not None
    rate = spec is not None and spec.control_rate is not None
    if not minimum:
        missing["dynamic_range"] = "the preset's [spec] table gives no minimum (friction) forces"
    if not (minimum and steps is not None):
        missing["stiffness_bound_quantisation"] = "needs the minimum (friction) forces and the spatial resolution"
    elif not rate:
        missing["damping_needed_quantisation"] = "the preset's [spec] table gives no control_rate"
    damping = spec is not None and spec.physical_damping is not None
    if not (damping and rate):
        needs = [what for ok, what in ((damping, "the device's physical viscous damping b ([spec] physical_damping)"),
                                       (rate, "the control rate ([spec] control_rate)")) if not ok]
        missing["stiffness_bound_sampling"] = "needs " + " and ".join(needs)
    return missing


def _axis_units(mech):
    """Per task axis: (is rotation, length or angle unit, wrench unit, mass unit)."""
    return [(u == "rad", "deg" if u == "rad" else "mm", "N m" if u == "rad" else "N",
             "kg m^2" if u == "rad" else "kg") for u in mech.task_units]


def _pm(pair, span: float, scale: float) -> str:
    """An extent's two ends; ``+`` after one that reached the searched span (it may go further)."""
    ends = [f"{number(float(v) * scale, 4)}{'+' if abs(float(v)) >= span else ''}" for v in pair]
    return f"{ends[0]} / +{ends[1]}"


def _both(pair) -> str:
    """A force along +e_i and -e_i: one number when equal, both when not."""
    plus, minus = float(pair[0]), float(pair[1])
    if plus == minus or abs(plus - minus) <= 1e-12 * max(abs(plus), abs(minus)):
        return number(min(plus, minus), 4)
    return f"+{number(plus, 4)} / -{number(minus, 4)}"


def _acceleration(a: float, rotation: bool) -> str:
    if rotation:
        return f"{number(a, 4)} rad/s^2"
    return f"{number(a, 4)} m/s^2 ({number(a / STANDARD_GRAVITY, 3)} G)"


def _box_cells(mech, box) -> list[str]:
    """The held box per task axis: +-half-width (mm) for positions, +-the bound (deg) for rotations."""
    if box.failed_scale == 0.0:
        return ["none"] * len(mech.task_names)
    half = dict(zip(("x", "y", "z"), box.half_widths))
    angle = None if box.orientations is None else np.degrees(box.orientations.angle)
    cells = []
    for name in mech.task_names:
        if name in half:
            cells.append(f"+-{number(half[name] * 1e3, 4)}" + ("+" if box.failed_scale is None else ""))
        else:
            cells.append(f"+-{number(angle, 4)}" if angle is not None else "")
    return cells


def _box_text(mech, x, box) -> str:
    """The held box's definition, result, search and sampling, one paragraph."""
    shape = " x ".join(f"+-{number(v * 1e3, 4)}" for v in box.shape)
    whose = "Table X's shape" if np.array_equal(box.shape, TABLE_X_HALF_WIDTHS) else "the shape (--box-shape)"
    centre = vector(box.centre * 1e3, 6)
    bound = ("" if box.orientations is None
             else f" at every orientation within +-{number(np.degrees(box.orientations.angle), 4)} deg")
    head = (f"box held{bound}: the largest box of {whose}, {shape} mm in x, y, z, centred at {centre} mm at which "
            f"every sampled pose is reachable and feasible")
    if box.failed_scale is None:
        found = f"still held at {number(box.scale, 6)} x the shape, where the search stops (a lower bound)"
    elif box.scale == 0.0 and box.failed_scale == 0.0:
        found = f"none: the centre itself fails, {point_text(mech, box.failure)} is unreachable or infeasible"
    else:
        found = (f"{number(box.scale, 4)} x the shape (bisection on the scale to {number(box.resolution, 3)} of it: "
                 f"holds at {number(box.scale, 6)}, fails at {number(box.failed_scale, 6)}, where "
                 f"{point_text(mech, box.failure)} is unreachable or infeasible)")
    tail = (f"; sampling: {box.sampling()}; an estimate from above (a pose between samples is not tested), "
            f"{box.boxes_tested} boxes, {box.poses_evaluated} poses, {number(box.seconds, 2)} s")
    rot = [i for i, n in enumerate(mech.task_names) if n not in ("x", "y", "z")]
    if box.orientations is not None and rot and np.any(np.asarray(x, float)[rot] != 0.0):
        tail += "; orientations about zero rotation, not about the pose's"
    return f"{head}: {found}{tail}"


def _box_json(mech, box) -> dict:
    return {"half_widths": box.half_widths.tolist(), "units": "m", "centre": box.centre.tolist(),
            "shape": box.shape.tolist(), "scale": box.scale, "failed_scale": box.failed_scale,
            "failure": None if box.failure is None else box.failure.tolist(),
            "resolution": box.resolution, "points_per_axis": box.points,
            "angle": None if box.orientations is None else box.orientations.angle,
            "orientations": 0 if box.orientations is None else box.orientations.count,
            "sampling": box.sampling(), "boxes_tested": box.boxes_tested, "poses_evaluated": box.poses_evaluated,
            "note": "the largest box centre +- scale x shape (bisection on the scale) at which every sampled pose "
                    "(grid points x orientation samples) is reachable and feasible; an estimate from above"}


def _text_rows(mech, rows, force_row, spans, box):
    units = _axis_units(mech)
    header = ["", *(f"{n} ({'deg' if rot else 'mm'})" for n, (rot, *_rest) in zip(mech.task_names, units))]
    out = [header]
    if box is not None:
        bound = "" if box.orientations is None else f" at +-{number(np.degrees(box.orientations.angle), 4)} deg"
        out.append([f"box held{bound}", *_box_cells(mech, box)])
    out.append(["reach through the pose", *(_pm(e, s, 180 / np.pi if rot else 1e3)
                                            for e, s, (rot, *_r) in zip(rows["workspace"], spans, units))])
    if "resolution" in rows:
        out.append(["spatial resolution", *(f"{number(r * 180 / np.pi, 3)} deg" if rot else f"{number(r * 1e6, 3)} um"
                                             for r, (rot, *_r) in zip(rows["resolution"], units))])
    if "minimum_force" in rows:
        out.append(["minimum force ([spec])", *(f"{number(f, 4)} {w}" for f, (_rot, _l, w, _m) in
                                                zip(rows["minimum_force"], units))])
    for key, label in (("continuous", "continuous force"), ("peak", "peak force")):
        if key in rows:
            out.append([label, *(f"{_both(f)} {w}" for f, (_rot, _l, w, _m) in zip(rows[key], units))])
    if "dynamic_range" in rows:
        out.append([f"dynamic range ({force_row})", *(f"{number(d, 3)}:1" for d in rows["dynamic_range"])])
    if "effective_mass" in rows:
        out.append(["effective mass (D_ii)", *(f"{number(v, 4)} {mu}" for v, (*_r, mu) in
                                               zip(rows["effective_mass"], units))])
        out.append(["apparent mass 1/(D^-1)_ii", *(f"{number(v, 4)} {mu}" for v, (*_r, mu) in
                                                    zip(rows["apparent_mass"], units))])
        out.append([f"acceleration ({force_row} force)", *(_acceleration(a, rot) for a, (rot, *_r) in
                                                            zip(rows["acceleration"], units))])
    for key, label in BOUND_ROWS.items():
        if key in rows:
            unit = (("N m/rad", "N/m") if key.startswith("stiffness") else ("N m s/rad", "N s/m"))
            out.append([label, *(f"{number(v, 4)} {unit[0] if rot else unit[1]}" for v, (rot, *_r) in
                                 zip(rows[key], units))])
    return out


def _json(preset, x, rows, missing, force_row, spans) -> dict:
    mech = preset.mechanism
    si = {"workspace": "m or rad, offsets from the pose along each axis (the reach through it)",
          "continuous": "N or N m, along +e_i and -e_i",
          "peak": "N or N m, along +e_i and -e_i", "resolution": "m or rad",
          "minimum_force": "N or N m (the preset's [spec] minimum_forces: measured static friction)",
          "effective_mass": "kg or kg m^2 (D_ii)", "apparent_mass": "kg or kg m^2 (1 / (D^-1)_ii)",
          "acceleration": f"m/s^2 or rad/s^2 ({force_row} force over D_ii)",
          "dynamic_range": f"{force_row} force over the minimum force",
          "stiffness_bound_quantisation": "N/m or N m/rad: bound K <= 2 f_c / D, f_c the minimum force, D the "
                                          "spatial resolution (quantisation, Abbott & Okamura 2005)",
          "damping_needed_quantisation": "N s/m or N m s/rad: bound b > K T / 2 (Colgate & Schenkel 1997) at K "
                                         "the quantisation bound, B = 0: the physical damping it needs",
          "stiffness_bound_sampling": "N/m or N m/rad: bound K < 2 (b - |B|) / T at B = 0 (Colgate & Schenkel "
                                      "1997), b the [spec] physical_damping",
          "damping_bound_sampling": "N s/m or N m s/rad: bound |B| < b - K T / 2 at K = 0, b the [spec] "
                                    "physical_damping"}
    spec = preset.spec
    return {"device": preset.key, "pose": [float(v) for v in x], "pose_units": list(mech.task_units),
            "axes": list(mech.task_names),
            "rows": {k: {"value": np.asarray(v).tolist(), "units": si[k]} for k, v in rows.items()},
            "reach_at_span": (np.abs(rows["workspace"]) >= spans[:, None]).tolist(), "spans": spans.tolist(),
            "control_rate": None if spec is None else spec.control_rate,
            "bounds_note": BOUND_NOTE, "not_modelled": dict(NOT_MODELLED),
            "missing": missing, "where": "" if spec is None else spec.where}
