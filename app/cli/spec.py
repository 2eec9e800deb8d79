"""``isoforce spec DEVICE [--at P]``: the device's specification sheet at one pose (paper 001, Table X).

Per task axis: the workspace extent through the pose, the spatial resolution (where the
preset gives joint sensor resolutions), the continuous and peak force (moment) along the
axis, the dynamic range (where the preset's ``[spec]`` table gives minimum forces), the
effective mass and the acceleration it allows (where it gives a mass matrix). A row the
device's data do not support is named with the reason instead of being left out silently.
"""
from __future__ import annotations

import argparse

import numpy as np

from metrics.resolution import mechanism_steps
from metrics.spec_sheet import STANDARD_GRAVITY, spec_rows, weight_range

from ._args import UsageError, add_device_argument, load_device, parse_gravity, parse_point
from ._format import number, point_text, print_json, table

#: Half-width searched along a rotation axis for its extent, rad.
ROTATION_SPAN = np.pi / 2


def register(subparsers) -> None:
    p = subparsers.add_parser("spec", help="the device's specification sheet at one pose",
                              description="Per task axis at the preset's pose (or --at): workspace extent "
                                          "through the pose, spatial resolution, continuous and peak force "
                                          "along the axis (every other wrench component zero), dynamic range, "
                                          "effective mass (the mass matrix's diagonal) and the acceleration "
                                          "the force gives it. Rows need data the preset may not have; "
                                          "each missing row says why.")
    add_device_argument(p)
    p.add_argument("--at", metavar="X,Y,Z", help="the pose, mm (and deg for a pen's angles); default: the preset's")
    p.add_argument("--gravity", default="upright", metavar="MOUNTING|GX,GY,GZ",
                   help="mounting for the weight row (devices with a mass model): a mounting name or gravity in "
                        "m/s^2 in the base frame; default upright")
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


def peak_limits(mech):
    """The mechanism's peak actuator limits (N m), or None where its model gives no peak rating."""
    peak = mech.peak_torque_limits()
    return None if peak is None else np.asarray(peak, float)


def run(args: argparse.Namespace) -> int:
    preset = load_device(args)
    mech = preset.mechanism
    if args.at is not None:
        x = parse_point(args.at, mech)
    elif preset.pose is not None:
        x = np.asarray(preset.pose, float)
    else:
        raise UsageError(f"--at: {preset.key} has no [pose] in its preset; give the pose with --at")
    spec = preset.spec
    spans = _spans(preset)
    peak = peak_limits(mech)
    steps = mechanism_steps(mech)
    table_mass = None if spec is None else spec.mass_matrix
    mass, mass_source = _model_mass(mech, x), "the model's bodies and rotors (links + J_rotor N^2)"
    if mass is None:
        mass, mass_source = table_mass, "the preset's [spec] table"
    try:
        rows = spec_rows(mech, x, spans=spans, peak_limits=peak, steps=steps, mass_matrix=mass,
                         minimum_forces=None if spec is None else spec.minimum_forces)
    except ValueError as exc:
        raise UsageError(f"--at: {point_text(mech, x)}: {exc}") from None
    missing = {}
    if peak is None:
        missing["peak"] = "the model gives no peak torque rating"
    if steps is None:
        missing["resolution"] = "the preset gives no joint sensor resolution"
    if mass is None:
        missing["effective_mass"] = "the model has no mass model and the preset's [spec] table gives no mass matrix"
    if spec is None or spec.minimum_forces is None:
        missing["dynamic_range"] = "the preset's [spec] table gives no minimum (friction) forces"
    weight = _weight(preset, args.gravity)
    if weight is None:
        missing["weight"] = ("the model has no mass model (link masses and centres of mass)"
                             if not mech.has_mass_model else "--gravity off")
    force_row = "peak" if peak is not None else "continuous"
    if args.json:
        out = _json(preset, x, rows, missing, force_row, spans)
        if mass is not None:
            out["effective_mass_source"] = mass_source
        if weight is not None:
            low, high, count, g, res = weight
            out["weight"] = {"min": low, "max": high, "units": "N", "points": count, "gravity": g.tolist(),
                             "grid": list(res), "note": "the weight the hand holds with the motors off, "
                                                        "extremes over the default map's feasible regular points"}
        print_json(out)
        return 0
    print(f"{preset.name} ({preset.key}) at {point_text(mech, x)}")
    print(table(_text_rows(mech, rows, force_row, spans)))
    if np.any(np.abs(rows["workspace"]) >= spans[:, None]):
        print("reach: a + marks an end at the searched span (the default map's width; 90 deg for a rotation)")
    if weight is not None:
        low, high, count, g, res = weight
        print(f"weight held, motors off: {number(low, 3)} to {number(high, 3)} N "
              f"({number(low / STANDARD_GRAVITY * 1e3, 3)} to {number(high / STANDARD_GRAVITY * 1e3, 3)} g) over "
              f"{count} feasible points of the default map at {' x '.join(map(str, res))}, gravity "
              f"({', '.join(number(v, 6) for v in g)}) m/s^2")
    if mass is not None:
        print(f"effective and apparent mass, acceleration: from {mass_source}")
    for name, why in missing.items():
        print(f"{name.replace('_', ' ')}: not given ({why})")
    if spec is not None and spec.where:
        print(f"[spec] data: {spec.where}")
    return 0


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


def _text_rows(mech, rows, force_row, spans):
    units = _axis_units(mech)
    header = ["", *(f"{n} ({'deg' if rot else 'mm'})" for n, (rot, *_rest) in zip(mech.task_names, units))]
    out = [header]
    out.append(["reach through the pose", *(_pm(e, s, 180 / np.pi if rot else 1e3)
                                            for e, s, (rot, *_r) in zip(rows["workspace"], spans, units))])
    if "resolution" in rows:
        out.append(["spatial resolution", *(f"{number(r * 180 / np.pi, 3)} deg" if rot else f"{number(r * 1e6, 3)} um"
                                             for r, (rot, *_r) in zip(rows["resolution"], units))])
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
    return out


def _json(preset, x, rows, missing, force_row, spans) -> dict:
    mech = preset.mechanism
    si = {"workspace": "m or rad, offsets from the pose along each axis (the reach through it)",
          "continuous": "N or N m, along +e_i and -e_i",
          "peak": "N or N m, along +e_i and -e_i", "resolution": "m or rad",
          "effective_mass": "kg or kg m^2 (D_ii)", "apparent_mass": "kg or kg m^2 (1 / (D^-1)_ii)",
          "acceleration": f"m/s^2 or rad/s^2 ({force_row} force over D_ii)",
          "dynamic_range": f"{force_row} force over the minimum force"}
    return {"device": preset.key, "pose": [float(v) for v in x], "pose_units": list(mech.task_units),
            "axes": list(mech.task_names),
            "rows": {k: {"value": np.asarray(v).tolist(), "units": si[k]} for k, v in rows.items()},
            "reach_at_span": (np.abs(rows["workspace"]) >= spans[:, None]).tolist(), "spans": spans.tolist(),
            "missing": missing, "where": "" if preset.spec is None else preset.spec.where}
