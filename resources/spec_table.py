"""A preset's ``[spec]`` table: measured or modelled figures a datasheet needs beyond kinematics.

::

    [spec]
    # The task-space mass matrix D (f = D a) at the preset's pose, SI: kg for translation rows
    # and columns, kg m where they meet, kg m^2 for rotations; one row per task coordinate.
    mass_matrix = [[0.19, ...], ...]
    # Static friction to overcome along each task axis, N (N m for a rotation): the minimum force.
    minimum_forces = [0.022, ...]
    # Peak (stall or peak-current) motor torques, N m (N for a prismatic actuator), one per joint in
    # the layout of the mechanism's continuous ``motor_torques`` parameter; the mechanism's gear
    # ratios and actuated joints apply as they do to the continuous rating. Used only where the
    # mechanism's own model gives no peak rating (``Mechanism.peak_torque_limits``).
    peak_motor_torques = [2.29, 0.97, ...]
    # The control loop's rate, Hz: the sampling period T = 1 / rate of the passivity bounds.
    control_rate = 1000.0
    # The device's physical viscous damping along each task axis, N s/m (N m s/rad for a rotation).
    physical_damping = [0.5, ...]
    # Where the numbers come from (free text, printed by `isoforce spec`).
    where = "paper 001, eq. 28 and Table X"

Each key is optional; every error names the file and the key. ``peak_motor_torques`` is checked
against the mechanism when it is used (``peak_torque_limits``): the table is parsed knowing only
the number of task coordinates.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

_SPEC_KEYS = {"mass_matrix", "minimum_forces", "peak_motor_torques", "control_rate", "physical_damping", "where"}


@dataclass(frozen=True)
class DeviceSpec:
    """The ``[spec]`` table, SI: ``mass_matrix`` (m rows of m), ``minimum_forces`` (m),
    ``peak_motor_torques`` (one per joint), ``control_rate`` (Hz), ``physical_damping`` (m), ``where``."""

    mass_matrix: tuple[tuple[float, ...], ...] | None = None
    minimum_forces: tuple[float, ...] | None = None
    peak_motor_torques: tuple[float, ...] | None = None
    control_rate: float | None = None
    physical_damping: tuple[float, ...] | None = None
    where: str = ""


def _positive_list(table, key: str, source: str, error, count: int | None, what: str) -> tuple[float, ...] | None:
    """``table[key]`` as positive finite floats (``count`` of them when given), or None when absent."""
    if key not in table:
        return None
    values = table[key]
    try:
        arr = np.array(values, dtype=float)
    except (TypeError, ValueError):
        arr = np.empty((0, 0))
    if arr.ndim != 1 or (count is not None and arr.shape != (count,)) or arr.size == 0 \
            or not np.all(np.isfinite(arr) & (arr > 0)):
        many = f"{count} positive numbers" if count is not None else "a list of positive numbers"
        raise error(source, f"spec.{key}", f"must be {many} ({what}), got {values!r}")
    return tuple(float(v) for v in arr)


def parse_spec(table: Any, source: str, m: int, error) -> DeviceSpec:
    """Validate a ``[spec]`` table for a mechanism of ``m`` task coordinates.

    Parameters
    ----------
    table : object
        The parsed TOML value.
    source : str
        The file, for messages.
    m : int
        Task coordinates of the preset's mechanism.
    error : callable
        ``error(source, key, message)`` -> the exception to raise (``schema._fail``).

    Returns
    -------
    DeviceSpec
    """
    if not isinstance(table, dict):
        raise error(source, "spec", f"must be a table, got {table!r}")
    unknown = sorted(set(table) - _SPEC_KEYS)
    if unknown:
        raise error(source, f"spec.{unknown[0]}", f"is not a spec key; expected one of {', '.join(sorted(_SPEC_KEYS))}")
    mass = None
    if "mass_matrix" in table:
        rows = table["mass_matrix"]
        try:
            arr = np.array(rows, dtype=float)
        except (TypeError, ValueError):
            arr = np.empty(0)
        if arr.shape != (m, m) or not np.all(np.isfinite(arr)):
            raise error(source, "spec.mass_matrix", f"must be {m} rows of {m} finite numbers (kg, kg m, kg m^2), "
                                                    f"got {rows!r}")
        if not np.all(np.linalg.eigvalsh(0.5 * (arr + arr.T)) > 0) or not np.array_equal(arr, arr.T):
            raise error(source, "spec.mass_matrix", "must be symmetric positive definite")
        mass = tuple(tuple(float(v) for v in row) for row in arr)
    minimum = _positive_list(table, "minimum_forces", source, error, m, "N, N m")
    peak = _positive_list(table, "peak_motor_torques", source, error, None, "N m, one per joint")
    damping = _positive_list(table, "physical_damping", source, error, m, "N s/m, N m s/rad")
    rate = None
    if "control_rate" in table:
        value = table["control_rate"]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not (np.isfinite(value) and value > 0):
            raise error(source, "spec.control_rate", f"must be a positive number (Hz), got {value!r}")
        rate = float(value)
    where = table.get("where", "")
    if not isinstance(where, str):
        raise error(source, "spec.where", f"must be a string, got {where!r}")
    return DeviceSpec(mass_matrix=mass, minimum_forces=minimum, peak_motor_torques=peak, control_rate=rate,
                      physical_damping=damping, where=where)


def peak_torque_limits(spec: DeviceSpec | None, mechanism):
    """Joint-side peak limits of the actuated joints from ``spec.peak_motor_torques``, (n,), or None without them.

    The peak torques take the place of the continuous ``motor_torques`` in a copy of the
    mechanism, whose ``torque_limits`` then applies the gear ratios and picks the actuated joints
    exactly as for the continuous rating.

    Parameters
    ----------
    spec : DeviceSpec or None
    mechanism : Mechanism
        With a ``motor_torques`` parameter.

    Returns
    -------
    ndarray, shape (n,), or None
        N m (N for a prismatic actuator).

    Raises
    ------
    ValueError
        Naming ``[spec] peak_motor_torques``, where the mechanism takes no ``motor_torques`` or
        another number of them.
    """
    if spec is None or spec.peak_motor_torques is None:
        return None
    current = getattr(mechanism.params, "motor_torques", None)
    if current is None:
        raise ValueError(f"[spec] peak_motor_torques: {type(mechanism).__name__} has no motor_torques parameter "
                         f"for a peak rating to stand beside")
    if len(spec.peak_motor_torques) != len(current):
        raise ValueError(f"[spec] peak_motor_torques must have {len(current)} values, one per joint as "
                         f"motor_torques, got {len(spec.peak_motor_torques)}")
    try:
        return mechanism.replace(motor_torques=tuple(spec.peak_motor_torques)).torque_limits()
    except ValueError as exc:
        raise ValueError(f"[spec] peak_motor_torques: {exc}") from None


def spec_lines(spec: DeviceSpec, toml_value) -> list[str]:
    """The ``[spec]`` table's body as TOML lines (``toml_value`` writes one value), for saving a preset."""
    lines = []
    if spec.mass_matrix is not None:
        lines.append(f"mass_matrix = {toml_value([list(row) for row in spec.mass_matrix])}")
    if spec.minimum_forces is not None:
        lines.append(f"minimum_forces = {toml_value(list(spec.minimum_forces))}")
    if spec.peak_motor_torques is not None:
        lines.append(f"peak_motor_torques = {toml_value(list(spec.peak_motor_torques))}")
    if spec.control_rate is not None:
        lines.append(f"control_rate = {toml_value(spec.control_rate)}")
    if spec.physical_damping is not None:
        lines.append(f"physical_damping = {toml_value(list(spec.physical_damping))}")
    if spec.where:
        lines.append(f"where = {toml_value(spec.where)}")
    return lines
