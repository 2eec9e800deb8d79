"""``isoforce pose DEVICE [--at P | --joints Q]``: everything about one pose, as a table or one JSON object.

``--joints`` gives the actuated joints (deg, mm for prismatic legs) instead of the task point:
the model's forward kinematics turns them into the point, and the report is the one ``--at``
of that point gives. Joints that do not assemble, that lie outside the workspace, or that the
preset's working mode (IK branch) would not reach at their own point exit with status 2.
"""
from __future__ import annotations

import argparse

import numpy as np

from app.cli._args import (
    UsageError,
    add_device_argument,
    add_loading_arguments,
    load_device,
    loading_of,
    parse_joints,
    parse_point,
)
from app.cli._format import (
    clean,
    condition_label,
    joints_display,
    loading_text,
    number,
    point_text,
    print_json,
    table,
    vector,
)
from app.logic.pose_report import to_dict, velocity_dict
from metrics.pose import PoseReport, analyse_pose
from metrics.pose_dynamics import analyse_dynamics, dynamics_dict
from metrics.pose_velocity import analyse_pose_velocity


def register(subparsers) -> None:
    p = subparsers.add_parser("pose", help="joints, Jacobian, force polytope and ellipsoids at one point",
                              description="Analyse one pose: joint angles, J, singular values, condition "
                                          "number, maximum isotropic force and its bottleneck actuator, "
                                          "maximum anisotropic force, polytope vertices, force and velocity "
                                          "ellipsoids. A point outside the workspace exits with status 2.")
    add_device_argument(p)
    where = p.add_mutually_exclusive_group()
    where.add_argument("--at", metavar="X,Y,Z", help="task point in mm (five-bar: X,Y); default: the preset's pose")
    where.add_argument("--joints", metavar="A,B,C", help="actuated joints in deg (mm for prismatic legs), "
                                                          "in the order `show` names them; forward "
                                                          "kinematics gives the point")
    add_loading_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


#: Largest difference, in display units (deg or mm), between the typed joints and the joints the
#: model's inverse kinematics gives at their point for them to count as the same configuration:
#: a tenth of the last digit of a value typed to 4 decimals. Another working mode differs by
#: degrees; a round trip FK -> IK by rounding (about 1e-12 deg here, more only right at a singularity).
SAME_JOINTS = 1e-5


def point_of_joints(preset, q) -> np.ndarray:
    """The task point (SI) of actuated joints ``q`` (SI, (n,)), checked for ``--joints``.

    Raises a UsageError naming ``--joints`` when the joints do not assemble, or when the
    preset's working mode reaches their point with other joints (the report would then be of
    another configuration): revolute joints are compared modulo 360 deg.
    """
    mech = preset.mechanism
    typed = ", ".join(f"{n} = {number(v)} {u}" for n, v, u in zip(mech.joint_names, *joints_display(mech, q)))
    x, ok = mech.forward(np.asarray(q, float))
    if not bool(ok) or not np.all(np.isfinite(x)):
        raise UsageError(f"--joints {typed}: the mechanism {preset.key} does not assemble at these joints "
                         f"(forward kinematics has no solution)")
    q_back, reachable = mech.inverse(x)
    if bool(reachable):
        shown, units = joints_display(mech, q)
        back, _ = joints_display(mech, q_back)
        diff = np.abs(back - shown)
        revolute = np.array([u == "deg" for u in units])
        diff[revolute] = np.abs((back[revolute] - shown[revolute] + 180.0) % 360.0 - 180.0)
        if np.all(np.isfinite(diff)) and diff.max() > SAME_JOINTS:
            other = ", ".join(f"{n} = {number(v)} {u}" for n, v, u in zip(mech.joint_names, back, units))
            raise UsageError(f"--joints {typed}: the point {point_text(mech, x)} is reached in {preset.key}'s "
                             f"working mode with other joints ({other}): these joints are another assembly "
                             f"or IK branch (change the working mode with --set, or pass --at)")
    return x


def check_pose(preset, x, *, from_preset: bool, option: str = "--at", loading=None) -> PoseReport:
    """``analyse_pose`` of ``x`` (SI), or a UsageError when it is outside the workspace.

    The error names where the point came from: ``--at``, or the preset's key ``pose.at`` when
    the preset's own default pose is the one outside (the file is wrong, not the command).
    """
    mech = preset.mechanism
    report = analyse_pose(mech, x, loading=loading)
    if not report.feasible:
        where = point_text(mech, x)
        if not report.reachable:
            why = "no joint angles reach it"
        else:
            shown = zip(mech.joint_names, *joints_display(mech, report.joints))
            joints = ", ".join(f"{n} = {v:.1f} {u}" for n, v, u in shown)
            why = f"it is reachable ({joints}) but violates a joint limit or physical constraint"
        if from_preset:
            raise UsageError(f"preset {preset.source!r}: key 'pose.at' {where} is outside the workspace of "
                             f"{preset.key}: {why}; pass --at or fix the preset")
        raise UsageError(f"{option} {where} is outside the workspace of {preset.key}: {why}")
    return report


def run(args: argparse.Namespace) -> int:
    preset = load_device(args)
    mech = preset.mechanism
    loading = loading_of(args, preset)
    option = "--at"
    if args.joints is not None:
        option = f"--joints {args.joints}: its point"
        x = point_of_joints(preset, parse_joints(args.joints, mech))
    elif args.at is not None:
        x = parse_point(args.at, mech)
    elif preset.pose is not None:
        x = np.array(preset.pose)
    else:
        raise UsageError(f"--at or --joints is required: preset {preset.key!r} has no default pose")
    report = check_pose(preset, x, from_preset=args.at is None and args.joints is None, option=option,
                        loading=loading)
    dyn = analyse_dynamics(mech, report.x, loading=loading) if mech.has_mass_model else None
    velocity, why_not = pose_velocity(preset, report)
    if args.json:
        out = to_dict(report)
        out["device"] = preset.key
        if dyn is None:
            out["dynamics"] = f"not computed: {mech._no_mass_model()}"
        else:
            out.update(dynamics_dict(dyn, mech))
        out.update(velocity_dict(velocity, reason=why_not, source=preset.motor_speeds_source,
                                 task_units=mech.task_units))
        print_json(out)
        return 0
    print(format_pose(report, preset.name, mech))
    print(format_dynamics(dyn, mech))
    print(format_velocity(velocity, why_not, mech))
    return 0


def pose_velocity(preset, report):
    """The velocity polytope at the report's pose from the preset's motor speeds, or (None, why not)."""
    mech = preset.mechanism
    if mech.joint_speed_limits() is None:
        return None, (f"preset {preset.key!r} gives no motor speeds ([motors] max_speeds, rad/s at the motor): "
                      f"no velocity polytope, isotropic or peak velocity")
    return analyse_pose_velocity(mech, report.x), ""


def format_velocity(velocity, why_not: str, mech) -> str:
    """The velocity polytope's summary (m/s), or why there is none."""
    if velocity is None:
        return f"  velocity: not computed: {why_not}"
    joints = ", ".join(f"{n} = {number(v)}" for n, v in zip(mech.joint_names, velocity.joint_speed_limits))
    fastest = float(np.max(np.linalg.norm(velocity.vertices, axis=-1)))
    linear = "linear " if len(velocity.rows) < mech.task_dim else ""
    still = " at zero angular velocity" if linear else ""
    rows = [("joint speed limits (rad/s)", f"{joints} (motor no-load speeds / gear ratios)"),
            (f"isotropic {linear}velocity{still}", f"{number(velocity.isotropic_velocity)} m/s (every direction)"),
            (f"fastest {linear}velocity{still}", f"{number(fastest)} m/s (the velocity polytope's farthest vertex)")]
    if velocity.peak_velocity is not None:
        units = ["m/s" if u == "m" else "rad/s" for u in mech.task_units]
        rows.append(("peak velocity (pure motion)", ", ".join(f"{n} = {number(v)} {u}" for n, v, u in
                                                              zip(mech.task_names, velocity.peak_velocity, units))))
    return "  velocity with the motors' speeds:\n" + table(rows, "  ")


def format_dynamics(dyn, mech) -> str:
    """The pose's masses, accelerations and weight (g, m/s^2, N), or why there are none.

    At a pose the model classes singular some figures have no value (the bodies cannot be
    differenced there): they read "undefined (singular pose)", never "nan"; an unbounded one "inf".
    """
    if dyn is None:
        return f"  dynamics: not computed: {mech._no_mass_model()}"

    def shown(value, unit="") -> str:
        if np.isnan(value):
            return "undefined (singular pose)"
        return f"{number(value)}{' ' + unit if unit else ''}"

    names = mech.task_names
    grams = ["g" if u == "m" else "g cm^2" for u in mech.task_units]
    scale = np.array([1e3 if u == "m" else 1e7 for u in mech.task_units])
    accel = ["m/s^2" if u == "m" else "rad/s^2" for u in mech.task_units]
    low, high = dyn.apparent_mass_range
    gravity = ", ".join(f"{g:g}" for g in dyn.gravity)
    rows = [("effective mass Lambda_ii", ", ".join(f"{n} = {shown(v, u)}" for n, v, u in
                                                    zip(names, dyn.effective_mass * scale, grams))),
            ("apparent mass 1/(Lambda^-1)_ii", ", ".join(f"{n} = {shown(v, u)}" for n, v, u in
                                                         zip(names, dyn.apparent_mass * scale, grams))),
            ("apparent mass over directions", f"{shown(low * 1e3, 'g')} to {shown(high * 1e3, 'g')} (pure force)"),
            ("mass condition number", shown(dyn.mass_condition_number)),
            ("isotropic acceleration", shown(dyn.isotropic_acceleration, "m/s^2")),
            (f"peak acceleration ({dyn.peak_rating} rating)",
             ", ".join(f"{n} = {shown(v, u)}" for n, v, u in zip(names, dyn.peak_acceleration, accel))),
            ("weight at the handle", f"{shown(dyn.weight, 'N')} under g = ({gravity})")]
    linear = "linear " if len(dyn.acceleration_ellipsoid.radii) < mech.task_dim else ""
    rows.append((f"{linear}acceleration ellipsoid (per unit of the torque set)",
                 ", ".join(shown(r, "m/s^2") for r in dyn.acceleration_ellipsoid.radii)))
    return "  links and rotors (J_rotor N^2):\n" + table(rows, "  ")



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
    lines = [f"{title} at {point_text(mech, report.x)} ({', '.join(tasks)})",
             "  " + loading_text(report.loading, mech)]
    values, units = joints_display(mech, report.joints)
    label = "joints (" + ", ".join(sorted(set(units))) + ")"
    rows = [(label, ", ".join(f"{n} = {number(q)}" for n, q in zip(joints, clean(values))))]
    u = d["units"]
    wrench = report.condition_number_scaling is not None
    rows.append((condition_label(report.condition_number_scaling), number(report.condition_number)))
    zero_m = " at zero moment" if wrench else ""
    rows.append((f"isotropic force{zero_m}",
                 f"{number(report.isotropic_force)} N, bottleneck {report.bottleneck_name}"
                 + (f" ({report.bottleneck_phrase})" if report.bottleneck_name in ("tie", "shared") else "")))
    rows.append((f"anisotropic force{zero_m}", f"{number(report.anisotropic_force)} N"))
    if wrench:
        rows.append(("isotropic moment at zero force", f"{number(report.isotropic_moment)} N m"))
        rows.append(("anisotropic moment at zero force", f"{number(report.anisotropic_moment)} N m"))
    rows.append(("facet distances (N)",
                 ", ".join(f"{n} = {number(v)}" for n, v in zip(joints, report.facet_distances))))
    limits = _unit_list(u["torque_limits"], len(joints))
    rows.append((f"actuator limits ({', '.join(sorted(set(limits)))})",
                 ", ".join(f"{n} = {number(v)}" for n, v in zip(joints, report.torque_limits))))
    if report.loading.biased:
        rows.append((f"gravity torque ({', '.join(sorted(set(limits)))})",
                     ", ".join(f"{n} = {number(v)}" for n, v in zip(joints, clean(report.torque_bias)))))
        rows.append(("force set centre (N)", vector(report.force_centre)))
    rows.append((f"singular values ({u['singular_values']})", vector(d["singular_values"])))
    rows.append(("manipulability", f"{number(d['manipulability'])} {d['units']['manipulability']}"))
    if report.singularity is not None:
        legs = report.singular_legs
        which = f" ({', '.join(legs)} stretched or folded)" if report.singularity_name in ("inverse", "combined") \
            and legs else ""
        rows.append(("singularity", f"{report.singularity_name}{which}"))
    lines.append(table(rows, "  "))
    lines.append(f"  Jacobian, rows {_labelled(tasks, u['jacobian_rows'])}, "
                 f"columns {_labelled(joints, u['jacobian_columns'])}:")
    jac = clean(np.array(d["jacobian"], float))     # noise relative to the whole matrix, not one row
    lines.extend("    " + vector(row) for row in jac)
    ref_units = _unit_list(u["reference_forces"], len(tasks))
    biased = report.loading.biased
    lines.append(f"  reference forces ({_labelled(tasks, ref_units) if wrench else 'N'}), "
                 + ("half-edges of the shifted polytope about its centre, one per actuator:" if biased
                    else "one per actuator at full torque:"))
    ref = clean(report.reference_forces)
    finite_ref = bool(np.all(np.isfinite(report.reference_forces)))
    if finite_ref or wrench:
        lines.extend(f"    {n}: {vector(ref[:, u])}" for u, n in enumerate(joints))
    else:
        lines.append("    none: J is singular here, J^-T does not exist (the force set is unbounded)")
    if wrench:
        lines.append("  force set at zero moment: vertices (N)")
        lines.extend(f"    {vector(vertex)}  |f| = {number(_norm(vertex))}"
                     for vertex in report.vertices)
    elif not np.all(np.isfinite(report.vertices)):
        lines.append("  polytope vertices (N): none, the force polytope is unbounded at a singular J")
    else:
        lines.append("  polytope vertices (N), by torque sign pattern"
                     + (" (shifted by the gravity torque):" if biased else ":"))
        for signs, vertex in zip(d["signs"], report.vertices):
            pattern = "".join("+" if s > 0 else "-" for s in signs)
            lines.append(f"    {pattern}  {vector(vertex)}  |f| = {number(_norm(vertex))}")
    speeds = ", ".join(sorted(set(_unit_list(u["joint_speeds"], len(joints)))))
    force_label = "force ellipsoid" + zero_m + (" (unbiased: the rating's, about the origin)" if biased else "")
    for label, ell, unit, scale in ((force_label, report.force_ellipsoid, "N", 1.0),
                                    (("linear " if wrench else "") + f"velocity ellipsoid (1 {speeds} joints)",
                                     report.velocity_ellipsoid, "mm/s", 1e3)):
        lines.append(f"  {label}: radius ({unit}) along axis")
        lines.extend(f"    {number(r * scale)}  along {vector(ell.axes[:, k], 4)}" for k, r in enumerate(ell.radii))
    return "\n".join(lines)


def _norm(v) -> float:
    """``|v|`` of a vector (k,) without squaring its entries: a force of 1e300 N (a gear ratio of
    1e300) has a finite norm whose square overflows."""
    v = np.asarray(v, float)
    scale = float(np.max(np.abs(v))) if v.size else 0.0
    if scale == 0.0 or not np.isfinite(scale):
        return scale
    return scale * float(np.linalg.norm(v / scale))
