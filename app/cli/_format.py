"""Text and JSON output shared by the subcommands: numbers, vectors, tables, task points.

Display units at the edge: lengths in mm, angles in deg (``kinematics.base.task_from_si``),
forces in N; strict JSON through ``app.logic.json_values.dumps`` (``nan`` as null, ``inf`` as "inf").
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from app.logic.figure_digits import format_with_error, shown_error, unresolved
from app.logic.json_values import dumps
from kinematics.base import task_display_units, task_from_si


def units_phrase(mechanism) -> str:
    """How task points are typed: "millimetres", or "mm and deg (mm, mm, mm, deg, ...)"."""
    units = task_display_units(mechanism)
    return "millimetres" if set(units) == {"mm"} else "mm and deg (" + ", ".join(units) + ")"


#: Decimal places of a printed task coordinate (mm or deg): 1 um, 0.001 deg. Finer digits are
#: below any device's resolution and would print rounding residue as "2.834e-07 mm".
POINT_PLACES = 3


def point_text(mechanism, x, digits: int = 6) -> str:
    """A task point (SI) as display text with its units, e.g. "(170, 22.3, 230) mm": ``digits``
    significant figures, none below ``POINT_PLACES`` decimal places."""
    units = task_display_units(mechanism)
    suffix = "mm" if set(units) == {"mm"} else "(" + ", ".join(units) + ")"
    shown = np.round(np.asarray(task_from_si(mechanism, x), float), POINT_PLACES) + 0.0     # (+ 0.0: no "-0")
    return f"{vector(shown, digits)} {suffix}"


def print_json(obj: Any) -> None:
    """Print one strict JSON object (``nan`` as null, ``inf`` as "inf")."""
    print(dumps(obj))


def number(value: float, digits: int = 6) -> str:
    """A float for a table: ``digits`` significant figures, ``inf``/``nan`` spelled out."""
    value = float(value)
    if not np.isfinite(value):
        return "nan" if np.isnan(value) else ("inf" if value > 0 else "-inf")
    return f"{value:.{digits}g}"


def vector(values, digits: int = 6) -> str:
    """A vector, shape (k,), as ``"(a, b, c)"``, rounding noise shown as 0 (see ``clean``)."""
    return "(" + ", ".join(number(float(v), digits) for v in clean(values)) + ")"


def clean(values) -> np.ndarray:
    """For printing only: entries below 1e-12 of the largest finite magnitude are rounding noise, shown as 0."""
    arr = np.array(values, dtype=float)
    finite = np.abs(arr[np.isfinite(arr)])
    if finite.size:
        arr[np.abs(arr) < 1e-12 * finite.max()] = 0.0
    return arr


def table(rows: list[Sequence[str]], indent: str = "") -> str:
    """Rows of cells as left-aligned columns."""
    widths = [max(len(r[i]) for r in rows if i < len(r)) for i in range(max(len(r) for r in rows))]
    return "\n".join(indent + "  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows)


def grid_box(grid, mechanism=None) -> str:
    """A map's range, e.g. "x -100 to 100 mm, z 50 to 250 mm, y = 0 mm"; a pen's angles in deg (given ``mechanism``)."""
    units = dict(zip(mechanism.task_names, mechanism.task_units)) if mechanism is not None else {}

    def shown(name: str, value: float) -> str:
        return f"{np.degrees(value):g} deg" if units.get(name) == "rad" else f"{value * 1e3:g} mm"

    ranges = ", ".join(f"{a} {shown(a, lo).split()[0]} to {shown(a, hi)}"
                       for a, lo, hi in zip(grid.axes, grid.lower, grid.upper))
    return ranges + "".join(f", {n} = {shown(n, v)}" for n, v in grid.fixed)


def describe_grid(grid, mechanism=None) -> str:
    """A map's range and its points, e.g. "x -100 to 100 mm, z 50 to 250 mm; 200 x 200 points"."""
    return f"{grid_box(grid, mechanism)}; {' x '.join(str(r) for r in grid.resolution)} points"


def with_error(value: float, error) -> str:
    """``value +- error`` with the digits the error supports (``figure_digits.format_with_error``:
    the app's rule); a figure whose error is at least its own size is marked "(unresolved)"."""
    if error is None:
        return number(value)
    error = shown_error(value, float(error))
    value_text, error_text = format_with_error(value, error)
    return f"{value_text} +- {error_text}" + (" (unresolved)" if unresolved(value, error) else "")


def joints_display(mech, joints) -> tuple[np.ndarray, tuple[str, ...]]:
    """Joint values in display units: deg for revolute joints, mm for prismatic ones."""
    units = mech.joint_units
    scale = np.array([1000.0 if u == "m" else 180.0 / np.pi for u in units])
    return np.asarray(joints, float) * scale, tuple("mm" if u == "m" else "deg" for u in units)


def condition_label(scaling: dict | None) -> str:
    """``"condition number"``, naming the task scaling where J mixes m and rad."""
    if scaling is None:
        return "condition number"
    return f"condition number (moments scaled by L = {number(scaling['length_m'] * 1e3)} mm)"


def loading_dict(loading, mechanism) -> dict[str, Any]:
    """The loading as JSON: ``rating``, ``gravity`` (``Loading.as_dict``) and the rated ``torque_limits``.

    ``torque_limits`` are joint-side, one per actuator, with ``torque_unit`` (``"N m"``, or per
    actuator where some joints are prismatic, ``"N"``).
    """
    units = ["N" if u == "m" else "N m" for u in mechanism.joint_units]
    return {**loading.as_dict(), "torque_limits": [float(v) for v in loading.torque_limits(mechanism)],
            "torque_unit": units[0] if len(set(units)) == 1 else units,
            "joint_names": list(mechanism.joint_names)}


def loading_text(loading, mechanism) -> str:
    """One line: the rating with its joint torque limits, and gravity, e.g. for ``stats`` and ``pose``."""
    units = ["N" if u == "m" else "N m" for u in mechanism.joint_units]
    limits = ", ".join(f"{n} = {number(v)} {u}"
                       for n, v, u in zip(mechanism.joint_names, loading.torque_limits(mechanism), units))
    gravity = loading.describe().split(", ", 1)[1]
    shifted = ("; the force set is shifted by the gravity torque at each pose (isotropic force: distance "
               "to the nearest facet)" if loading.biased else "")
    return f"torque rating: {loading.rating} ({limits}); {gravity}{shifted}"
