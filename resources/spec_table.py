"""A preset's ``[spec]`` table: measured or modelled figures a datasheet needs beyond kinematics.

::

    [spec]
    # The task-space mass matrix D (f = D a) at the preset's pose, SI: kg for translation rows
    # and columns, kg m where they meet, kg m^2 for rotations; one row per task coordinate.
    mass_matrix = [[0.19, ...], ...]
    # Static friction to overcome along each task axis, N (N m for a rotation): the minimum force.
    minimum_forces = [0.022, ...]
    # Where the numbers come from (free text, printed by `isoforce spec`).
    where = "paper 001, eq. 28 and Table X"

Each key is optional; every error names the file and the key.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

_SPEC_KEYS = {"mass_matrix", "minimum_forces", "where"}


@dataclass(frozen=True)
class DeviceSpec:
    """The ``[spec]`` table, SI: ``mass_matrix`` (m rows of m), ``minimum_forces`` (m), ``where``."""

    mass_matrix: tuple[tuple[float, ...], ...] | None = None
    minimum_forces: tuple[float, ...] | None = None
    where: str = ""


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
    minimum = None
    if "minimum_forces" in table:
        values = table["minimum_forces"]
        try:
            arr = np.array(values, dtype=float)
        except (TypeError, ValueError):
            arr = np.empty(0)
        if arr.shape != (m,) or not np.all(np.isfinite(arr) & (arr > 0)):
            raise error(source, "spec.minimum_forces", f"must be {m} positive numbers (N, N m), got {values!r}")
        minimum = tuple(float(v) for v in arr)
    where = table.get("where", "")
    if not isinstance(where, str):
        raise error(source, "spec.where", f"must be a string, got {where!r}")
    return DeviceSpec(mass_matrix=mass, minimum_forces=minimum, where=where)


def spec_lines(spec: DeviceSpec, toml_value) -> list[str]:
    """The ``[spec]`` table's body as TOML lines (``toml_value`` writes one value), for saving a preset."""
    lines = []
    if spec.mass_matrix is not None:
        lines.append(f"mass_matrix = {toml_value([list(row) for row in spec.mass_matrix])}")
    if spec.minimum_forces is not None:
        lines.append(f"minimum_forces = {toml_value(list(spec.minimum_forces))}")
    if spec.where:
        lines.append(f"where = {toml_value(spec.where)}")
    return lines
