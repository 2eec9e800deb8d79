"""Maps over a 3D box, as the views show them: slices, workspace volume, comparability, joints.

Plain Python and numpy, no Qt (tested without it). A delta's map is a volume, not a slice of
an axisymmetric device: the map view shows one plane of it (``volume_slice``), the statistics
are over the whole volume (``workspace_size`` in cm^3), and a reference of another device is
compared only where the two maps mean the same thing (``comparison_problem``).
"""
from __future__ import annotations

import math

import numpy as np

# The planes of a box are shared with the command line's --plane, so they live outside app.gui.
from app.logic.planes import is_volume, slice_grid, slice_index, volume_slice  # noqa: F401  (re-exported)
from kinematics.base import task_display_units
from kinematics.grid import GridSpec
from kinematics.units import joint_display_units, joints_from_si, joints_to_si
from metrics.quantities import QUANTITIES
from metrics.workspace import WorkspaceMap

#: The largest coarse volume that follows a moving slider: points per axis (issue 9: <= 24^3).
COARSE_VOLUME_POINTS = 24
#: Largest difference (deg or mm) between typed joints and the joints the working mode gives at
#: their point for them to count as one configuration: a tenth of the last digit of a value typed
#: to 4 decimals (the same bar as ``isoforce pose --joints``).
SAME_JOINTS = 1e-5


def coarse_volume(grid: GridSpec, points: int = COARSE_VOLUME_POINTS) -> GridSpec:
    """``grid`` with at most ``points`` along each axis (a volume shrinks by its cube)."""
    return grid.with_resolution(tuple(min(n, points) for n in grid.resolution))


def workspace_size(mechanism, grid: GridSpec, feasible_points: int) -> tuple[str, float, str]:
    """The map's feasible area (2D slice, cm^2) or volume (3D box, cm^3): points times cell size.

    Returns ``(kind, value, unit)``: ``kind`` is ``"area"`` or ``"volume"``; ``value`` is
    ``nan`` when an axis is an angle (no area in length units).

    Examples
    --------
    >>> from kinematics.fivebar import FiveBar
    >>> g = GridSpec(("x", "y"), (0.0, 0.0), (0.1, 0.1), (11, 11))
    >>> workspace_size(FiveBar(), g, 100)
    ('area', 100.0, 'cm^2')
    """
    units = dict(zip(mechanism.task_names, mechanism.task_units))
    kind, unit, scale = ("area", "cm^2", 1e4) if len(grid.axes) == 2 else ("volume", "cm^3", 1e6)
    if any(units.get(a) != "m" for a in grid.axes):
        return kind, math.nan, unit
    return kind, float(feasible_points * math.prod(grid.spacing()) * scale), unit


def _axes_units(mechanism, grid: GridSpec) -> tuple:
    units = dict(zip(mechanism.task_names, task_display_units(mechanism)))
    return tuple((a, units.get(a)) for a in grid.axes)


def comparison_problem(current: WorkspaceMap, current_mech, reference: WorkspaceMap, reference_mech,
                       quantity: str) -> str | None:
    """Why two maps must not be drawn as a comparison of ``quantity``, or None when they may be.

    Maps compare when they vary the same task coordinates in the same units (a 2D slice
    against a 3D box, or an (x, y) slice against an (x, z) one, is no comparison), and the
    quantity means the same: the same task scaling of a condition number, for classes (the
    bottleneck) the same actuator names, for forces actuators of one kind. Two devices' slices
    may lie in different planes (each device's own): the panels' titles say where.
    """
    if quantity not in reference.values:
        return f"the reference map has no {QUANTITIES[quantity].label.lower()}"
    a, b = _axes_units(current_mech, current.grid), _axes_units(reference_mech, reference.grid)
    if a != b:
        def text(pairs):
            return ", ".join(f"{n} ({u})" for n, u in pairs)
        return f"the maps vary different coordinates: current {text(a)}, reference {text(b)}"
    if current.condition_number_scaling != reference.condition_number_scaling and quantity in (
            "condition_number", "inverse_condition_number"):
        return "the condition numbers use different task scalings"
    if QUANTITIES[quantity].categorical and tuple(current_mech.joint_names) != tuple(reference_mech.joint_names):
        return (f"the devices' actuators differ ({', '.join(current_mech.joint_names)} vs "
                f"{', '.join(reference_mech.joint_names)}): their classes are not the same")
    if tuple(current_mech.joint_units) != tuple(reference_mech.joint_units) and quantity in (
            "isotropic_force", "anisotropic_force", "bottleneck"):
        return "the devices' actuators are of different kinds (revolute / prismatic)"
    return None


def parse_joints(text: str, mechanism) -> np.ndarray:
    """``"A, B, C"`` in display units (deg, mm for prismatic legs) as joints in SI, shape (n,).

    Raises ``ValueError`` naming the joints and their units when the text is not n finite numbers.
    """
    n = mechanism.n_joints
    try:
        values = [float(v) for v in text.replace(";", ",").split(",")]
    except ValueError:
        values = []
    if len(values) != n or not all(np.isfinite(values)):
        wanted = ", ".join(f"{j} ({u})" for j, u in zip(mechanism.joint_names, joint_display_units(mechanism)))
        raise ValueError(f"joints need {n} comma-separated numbers: {wanted}, got {text!r}")
    return joints_to_si(mechanism, values)


def point_of_joints(mechanism, q) -> np.ndarray:
    """The task point (SI, (m,)) of actuated joints ``q`` (SI, (n,)), as ``isoforce pose --joints``.

    Raises ``ValueError`` when the joints do not assemble, or when the model's working mode
    reaches their point with other joints (the pose shown would be another configuration);
    revolute joints are compared modulo 360 deg.
    """
    q = np.asarray(q, float)
    units = joint_display_units(mechanism)
    typed = ", ".join(f"{n} = {v:.4g} {u}" for n, v, u in zip(mechanism.joint_names, joints_from_si(mechanism, q),
                                                             units))
    x, ok = mechanism.forward(q)
    if not bool(ok) or not np.all(np.isfinite(x)):
        raise ValueError(f"joints {typed}: the mechanism does not assemble there (forward kinematics has no solution)")
    back, reachable = mechanism.inverse(x)
    if bool(reachable):
        diff = np.abs(joints_from_si(mechanism, back) - joints_from_si(mechanism, q))
        revolute = np.array([u == "deg" for u in units])
        shown, again = joints_from_si(mechanism, q), joints_from_si(mechanism, back)
        diff[revolute] = np.abs((again[revolute] - shown[revolute] + 180.0) % 360.0 - 180.0)
        if np.all(np.isfinite(diff)) and diff.max() > SAME_JOINTS:
            other = ", ".join(f"{n} = {v:.4g} {u}" for n, v, u in zip(mechanism.joint_names, again, units))
            raise ValueError(f"joints {typed}: their point is reached in this working mode with other joints "
                             f"({other}); these are another assembly or IK branch")
    return np.asarray(x, float)
