"""A pose report (``metrics.pose.PoseReport``, SI) in display units, as plain JSON values.

Shared by both clients: ``isoforce pose --json`` prints ``to_dict``, its table reads the same
dict, and exports use ``json_safe`` (``app.logic.json_values``). The analysis itself stays in
``metrics.pose``.

JSON (``to_dict``)
------------------
``to_dict(report)`` gives plain Python values that ``json.dumps(..., allow_nan=False)``
accepts. Non-finite floats are written as follows, chosen so that a reader in Python gets
the number back with ``float(value)`` and a reader in any language can tell "no value"
from "unbounded":

======================  =======================  ==========================================
float                   JSON                     meaning here
======================  =======================  ==========================================
``nan``                 ``null``                 no value: the point is unreachable
``inf`` / ``-inf``      ``"inf"`` / ``"-inf"``   unbounded: e.g. the condition number or the
                                                 anisotropic force at a singularity
======================  =======================  ==========================================
"""
from __future__ import annotations

from typing import Any

import numpy as np

from app.logic.json_values import json_safe
from metrics.ellipsoids import Ellipsoid
from metrics.pose import PoseReport
from metrics.torque_box import sign_patterns
from metrics.velocity import PoseVelocity


def to_dict(report: PoseReport, *, mm: bool = True) -> dict[str, Any]:
    """A JSON-ready dict of ``report`` (see the module docstring for ``nan`` and ``inf``).

    Parameters
    ----------
    report : PoseReport
    mm : bool
        Lengths in millimetres (positions, Jacobian, singular values, velocities) when true,
        metres when false. Forces are always N, torques N m, joint angles deg.

    Returns
    -------
    dict
        Keys as the report's attributes (parts not computed are ``null``), plus ``units``:
        one string per key when every entry has that unit, else a list of per-entry units
        nested like the value (``jacobian``: row unit / column unit, e.g. ``"rad/mm"``, with
        ``jacobian_rows`` and ``jacobian_columns`` always listed; ``torque_limits``: ``"N"``
        for a prismatic leg, ``"N m"`` for a revolute joint; ``reference_forces``: per
        component, ``"N"`` for a force row, ``"N m"`` for a moment row). Vectors
        belonging to actuators or axes are listed one per entry: ``reference_forces[u]`` is
        actuator u's force (a column of the (m, n) matrix) and ``axes[k]`` the unit direction
        of ``radii[k]``. ``vertices[k]`` belongs to sign vector ``signs[k]``; devices with
        orientation freedoms (``condition_number_scaling`` not null) list the force set at zero
        moment instead (``signs`` null) and add ``isotropic_moment``, ``anisotropic_moment``.
        Task coordinates ``x`` are in mm (or m) and deg. ``loading`` is the torque rating and
        gravity (``metrics.loading.Loading.as_dict``), ``torque_bias`` the joint torque spent
        holding the links (N m; zeros with gravity off) and ``force_centre`` the force set's centre
        (N; 0 with gravity off, ``null`` where it is not a parallelepiped).
    """
    length = 1e3 if mm else 1.0
    unit = "mm" if mm else "m"
    m = len(report.x)
    n = len(report.joints)
    # Each task coordinate (row of J) and joint (column) in its own unit: a length in mm
    # (or m), an angle in deg for positions and in rad for the per-radian entries of J.
    task_si = report.task_units or ("m",) * m
    joint_si = report.joint_units or ("rad",) * n
    rows_unit = [unit if u == "m" else "rad" for u in task_si]
    cols_unit = [unit if u == "m" else "rad" for u in joint_si]
    row_scale = np.array([length if u == "m" else 1.0 for u in task_si])
    col_scale = np.array([length if u == "m" else 1.0 for u in joint_si])
    wrench = "rad" in task_si
    # Singular values of a wrench device's J are those of the task-scaled J: rows in length units.
    sv_row = unit if wrench else (rows_unit[0] if len(set(rows_unit)) == 1 else "mixed")
    sv_col = cols_unit[0] if len(set(cols_unit)) == 1 else "mixed"
    out: dict[str, Any] = {
        "x": np.array([v * length if u == "m" else np.degrees(v) for v, u in zip(report.x, task_si)]),
        "reachable": report.reachable,
        "feasible": report.feasible,
        "task_names": report.task_names,
        "joint_names": report.joint_names,
        # Revolute joints in deg, prismatic ones in the length unit.
        "joints": np.array([v * length if u == "m" else np.degrees(v)
                            for v, u in zip(report.joints, report.joint_units or ("rad",) * len(report.joints))]),
        "jacobian": report.jacobian * row_scale[:, None] / col_scale[None, :],
        "singular_values": report.singular_values * length / (col_scale[0] if sv_col != "mixed" else 1.0),
        "condition_number": report.condition_number,
        "condition_number_scaling": report.condition_number_scaling,
        "manipulability": report.manipulability * (length / (col_scale[0] if sv_col != "mixed" else 1.0)) ** m,
        "torque_limits": report.torque_limits,
        "isotropic_force": report.isotropic_force,
        "bottleneck": report.bottleneck,
        "bottleneck_actuator": report.bottleneck_name,
        "facet_distances": report.facet_distances,
        "anisotropic_force": report.anisotropic_force,
        "reference_forces": None if report.reference_forces is None else report.reference_forces.T,
        # Wrench devices: ``vertices`` are the force set's at zero moment, not signed sums.
        "signs": None if wrench else sign_patterns(len(report.joints)).astype(int),
        "vertices": report.vertices,
        "faces": report.faces,
        "force_ellipsoid": _ellipsoid_dict(report.force_ellipsoid, 1.0),
        "velocity_ellipsoid": _ellipsoid_dict(report.velocity_ellipsoid, length),
        "joint_speeds": report.joint_speeds * col_scale,
        # The rating whose limits ``torque_limits`` are, gravity, and what gravity does here.
        "loading": report.loading.as_dict(),
        "torque_bias": report.torque_bias,
        "force_centre": report.force_centre,
    }
    joint_unit = ", ".join(sorted({unit if u == "m" else "deg" for u in report.joint_units})) or "deg"
    units = {"x": _per_entry([unit if u == "m" else "deg" for u in task_si]), "joints": joint_unit,
             "jacobian": _per_entry([[f"{r}/{c}" for c in cols_unit] for r in rows_unit]),
             "jacobian_rows": rows_unit, "jacobian_columns": cols_unit,
             "singular_values": f"{sv_row}/{sv_col}", "condition_number": "",
             "manipulability": f"({sv_row}/{sv_col})^{m}",
             # Leg forces in N, joint torques in N m.
             "torque_limits": _per_entry(["N" if u == "m" else "N m" for u in joint_si]),
             "isotropic_force": "N", "facet_distances": "N", "anisotropic_force": "N",
             "reference_forces": _per_entry(["N" if u == "m" else "N m" for u in task_si]),
             "vertices": "N", "force_ellipsoid.radii": "N",
             "velocity_ellipsoid.radii": f"{unit}/s",
             "joint_speeds": _per_entry([f"{c}/s" for c in cols_unit]),
             "torque_bias": _per_entry(["N" if u == "m" else "N m" for u in joint_si]), "force_centre": "N"}
    if wrench:
        out["isotropic_moment"] = report.isotropic_moment
        out["anisotropic_moment"] = report.anisotropic_moment
        units.update(isotropic_moment="N m", anisotropic_moment="N m")
    if report.singularity is not None:
        out["singularity"] = report.singularity_name
        out["singular_legs"] = report.singular_legs
    out["units"] = units
    return json_safe(out)


def _per_entry(units: list) -> str | list:
    """One unit string when every entry shares it, else the per-entry list (nested like the value)."""
    flat = [u for row in units for u in (row if isinstance(row, list) else [row])]
    return flat[0] if flat and len(set(flat)) == 1 else units


def _ellipsoid_dict(ellipsoid: Ellipsoid | None, scale: float) -> dict[str, Any] | None:
    """Radii (times ``scale``) and axes as a list of unit vectors, ``axes[k]`` along ``radii[k]``."""
    if ellipsoid is None:
        return None
    return {"radii": ellipsoid.radii * scale, "axes": ellipsoid.axes.T}


#: The keys ``velocity_dict`` adds to ``isoforce pose --json`` (``"velocity"`` alone says why there are none).
VELOCITY_KEYS = ("velocity_polytope", "isotropic_velocity", "peak_velocity", "joint_speed_limits", "velocity_units",
                 "velocity")


def velocity_dict(velocity: PoseVelocity | None, *, reason: str = "", source: str = "",
                  task_units: tuple[str, ...] = ()) -> dict[str, Any]:
    """The keys the velocity polytope adds to ``isoforce pose --json``, SI (m/s), or why there are none.

    ``velocity_polytope``: ``vertices[k]`` (m/s) is the image of the speed-box corner ``signs[k]``
    (a device with orientation freedoms: a vertex of the slice at zero angular velocity, ``signs``
    +-1 where a joint is at its limit, 0 where not); ``isotropic_velocity``: the largest speed the
    handle reaches in every direction (m/s); ``peak_velocity``: the fastest pure motion along each
    task axis (m/s, rad/s for an angle; ``task_units`` says which); ``joint_speed_limits``: the
    motors' speeds over the gear ratios (rad/s at the joints). Without motor speeds, the single key
    ``velocity`` says why (``reason``).
    """
    if velocity is None:
        return {"velocity": f"not computed: {reason}"}
    out = {
        "velocity_polytope": {"vertices": velocity.vertices, "signs": velocity.signs.astype(int)},
        "isotropic_velocity": velocity.isotropic_velocity,
        "joint_speed_limits": velocity.joint_speed_limits,
        "velocity_units": {"velocity_polytope.vertices": "m/s", "isotropic_velocity": "m/s",
                           "joint_speed_limits": "rad/s (m/s for a prismatic joint)",
                           "source": source},
    }
    if velocity.peak_velocity is not None:
        out["peak_velocity"] = velocity.peak_velocity
        out["velocity_units"]["peak_velocity"] = ["m/s" if u == "m" else "rad/s" for u in task_units] or "m/s"
    return json_safe(out)
