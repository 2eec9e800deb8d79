"""``isoforce pose DEVICE [--at P]``: everything about one pose, as a table or one JSON object.
"""
from __future__ import annotations

import argparse

import numpy as np

from metrics.pose import PoseReport, analyse_pose

from ..pose_report import to_dict
from ._args import UsageError, add_device_argument, load_device, parse_point
from ._format import clean, condition_label, joints_display, number, point_text, print_json, table, vector


def register(subparsers) -> None:
    p = subparsers.add_parser("pose", help="joints, Jacobian, force polytope and ellipsoids at one point",
                              description="Analyse one pose: joint angles, J, singular values, condition "
                                          "number, maximum isotropic force and its bottleneck actuator, "
                                          "maximum anisotropic force, polytope vertices, force and velocity "
                                          "ellipsoids. A point outside the workspace exits with status 2.")
    add_device_argument(p)
    p.add_argument("--at", metavar="X,Y,Z", help="task point in mm (five-bar: X,Y); default: the preset's pose")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def check_pose(preset, x, *, from_preset: bool) -> PoseReport:
    """``analyse_pose`` of ``x`` (SI), or a UsageError when it is outside the workspace.

    The error names where the point came from: ``--at``, or the preset's key ``pose.at`` when
    the preset's own default pose is the one outside (the file is wrong, not the command).
    """
    mech = preset.mechanism
    report = analyse_pose(mech, x)
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
        raise UsageError(f"--at {where} is outside the workspace of {preset.key}: {why}")
    return report


def run(args: argparse.Namespace) -> int:
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
    lines = [f"{title} at {point_text(mech, report.x)} ({', '.join(tasks)})"]
    values, units = joints_display(mech, report.joints)
    label = "joints (" + ", ".join(sorted(set(units))) + ")"
    rows = [(label, ", ".join(f"{n} = {number(q)}" for n, q in zip(joints, clean(values))))]
    u = d["units"]
    wrench = report.condition_number_scaling is not None
    rows.append((condition_label(report.condition_number_scaling), number(report.condition_number)))
    zero_m = " at zero moment" if wrench else ""
    rows.append((f"isotropic force{zero_m}",
                 f"{number(report.isotropic_force)} N, bottleneck {report.bottleneck_name}"))
    rows.append((f"anisotropic force{zero_m}", f"{number(report.anisotropic_force)} N"))
    if wrench:
        rows.append(("isotropic moment at zero force", f"{number(report.isotropic_moment)} N m"))
        rows.append(("anisotropic moment at zero force", f"{number(report.anisotropic_moment)} N m"))
    rows.append(("facet distances (N)",
                 ", ".join(f"{n} = {number(v)}" for n, v in zip(joints, report.facet_distances))))
    limits = _unit_list(u["torque_limits"], len(joints))
    rows.append((f"actuator limits ({', '.join(sorted(set(limits)))})",
                 ", ".join(f"{n} = {number(v)}" for n, v in zip(joints, report.torque_limits))))
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
    lines.append(f"  reference forces ({_labelled(tasks, ref_units) if wrench else 'N'}), "
                 "one per actuator at full torque:")
    ref = clean(report.reference_forces)
    finite_ref = bool(np.all(np.isfinite(report.reference_forces)))
    if finite_ref or wrench:
        lines.extend(f"    {n}: {vector(ref[:, u])}" for u, n in enumerate(joints))
    else:
        lines.append("    none: J is singular here, J^-T does not exist (the force set is unbounded)")
    if wrench:
        lines.append("  force set at zero moment: vertices (N)")
        lines.extend(f"    {vector(vertex)}  |f| = {number(float(np.linalg.norm(vertex)))}"
                     for vertex in report.vertices)
    elif not np.all(np.isfinite(report.vertices)):
        lines.append("  polytope vertices (N): none, the force polytope is unbounded at a singular J")
    else:
        lines.append("  polytope vertices (N), by torque sign pattern:")
        for signs, vertex in zip(d["signs"], report.vertices):
            pattern = "".join("+" if s > 0 else "-" for s in signs)
            lines.append(f"    {pattern}  {vector(vertex)}  |f| = {number(float(np.linalg.norm(vertex)))}")
    speeds = ", ".join(sorted(set(_unit_list(u["joint_speeds"], len(joints)))))
    for label, ell, unit, scale in (("force ellipsoid" + zero_m, report.force_ellipsoid, "N", 1.0),
                                    (("linear " if wrench else "") + f"velocity ellipsoid (1 {speeds} joints)",
                                     report.velocity_ellipsoid, "mm/s", 1e3)):
        lines.append(f"  {label}: radius ({unit}) along axis")
        lines.extend(f"    {number(r * scale)}  along {vector(ell.axes[:, k], 4)}" for k, r in enumerate(ell.radii))
    return "\n".join(lines)
