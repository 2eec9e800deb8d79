"""SI units inside, display units at the edges: the one place that converts between them.

A model computes in metres and radians. A person reads and types lengths in millimetres and
angles in degrees: parameters (``ParamInfo.unit``), task coordinates (``Mechanism.task_units``
``"m"`` -> ``"mm"``, ``"rad"`` -> ``"deg"``) and actuated joints (``Mechanism.joint_units``:
revolute joints in deg, prismatic legs in mm).
"""
from __future__ import annotations

import math
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from .arrays import FloatArray


class HasUnits(Protocol):
    """What unit conversion needs of a mechanism: the units of its coordinates (a part of
    ``kinematics.contract.Mechanism``, whose members these are)."""

    task_units: tuple[str, ...]
    joint_units: tuple[str, ...]

#: Display unit of each SI unit a task coordinate or an actuated joint may have.
DISPLAY_UNIT = {"m": "mm", "rad": "deg"}
#: Display units per SI unit.
DISPLAY_SCALE = {"mm": 1000.0, "deg": 180.0 / math.pi}


def to_si(value: float, unit: str, scale: float) -> float:
    """A number typed in display ``unit`` in SI units.

    Divides by 1000 for ``"mm"`` (so 350 mm is exactly 0.35 m) and uses ``math.radians`` for
    ``"deg"``; any other unit is multiplied by ``scale`` (display -> SI).

    Parameters
    ----------
    value : float
        The number in the display unit.
    unit : str
        The display unit, e.g. ``"mm"``, ``"deg"``, ``"N m"``.
    scale : float
        SI per display unit, used for units other than mm and deg.

    Returns
    -------
    float

    Examples
    --------
    >>> to_si(350, "mm", 1e-3)
    0.35
    """
    if unit == "mm":
        return value / 1000.0
    if unit == "deg":
        return math.radians(value)
    return value * scale


def from_si(value: float, unit: str, scale: float) -> float:
    """An SI number in display ``unit``: the shortest decimal that ``to_si`` maps back to ``value``.

    ``math.degrees(math.radians(114))`` is 114.00000000000001; a person (and a preset file
    written from the model) should see 114, which converts back to the very same radians.

    Parameters
    ----------
    value : float
        The SI value.
    unit, scale
        As for ``to_si``.

    Returns
    -------
    float

    Examples
    --------
    >>> from_si(math.radians(114), "deg", math.pi / 180)
    114.0
    """
    if unit == "mm":
        plain = value * 1000.0
    elif unit == "deg":
        plain = math.degrees(value)
    else:
        plain = value / scale
    if not math.isfinite(plain):
        return plain
    for digits in range(1, 18):
        candidate = float(f"{plain:.{digits}g}")
        if to_si(candidate, unit, scale) == value:
            return candidate
    return plain


def task_display_units(mechanism: HasUnits) -> tuple[str, ...]:
    """How a person reads each task coordinate: ``"mm"`` for lengths, ``"deg"`` for angles, length ``m``.

    Parameters
    ----------
    mechanism : HasUnits
        Any model (only ``task_units`` is read).

    Returns
    -------
    tuple of str, length ``m``

    Examples
    --------
    >>> from kinematics.stewart import StewartPlatform
    >>> task_display_units(StewartPlatform())
    ('mm', 'mm', 'mm', 'deg', 'deg', 'deg')
    """
    return tuple(DISPLAY_UNIT[u] for u in mechanism.task_units)


def task_scales(mechanism: HasUnits) -> FloatArray:
    """Display units per SI unit of each task coordinate, shape (m,): 1000 (mm) or 180/pi (deg).

    Parameters
    ----------
    mechanism : HasUnits
        Any model (only ``task_units`` is read).

    Returns
    -------
    ndarray, shape (m,)
    """
    return np.array([DISPLAY_SCALE[u] for u in task_display_units(mechanism)])


def task_to_si(mechanism: HasUnits, values: ArrayLike) -> FloatArray:
    """A task point (..., m) typed in display units (mm, deg) in SI units (m, rad), shape (..., m).

    Parameters
    ----------
    mechanism : HasUnits
        Any model (only ``task_units`` is read).
    values : array_like, shape (..., m)
        Task points in mm and deg.

    Returns
    -------
    ndarray, shape (..., m)
        m and rad.

    Examples
    --------
    >>> from kinematics.fivebar import FiveBar
    >>> task_to_si(FiveBar(), [0.0, 250.0]).tolist()
    [0.0, 0.25]
    """
    return np.asarray(values, float) / task_scales(mechanism)


def task_from_si(mechanism: HasUnits, values: ArrayLike) -> FloatArray:
    """A task point (..., m) in SI units in display units (mm, deg), shape (..., m).

    Parameters
    ----------
    mechanism : HasUnits
        Any model (only ``task_units`` is read).
    values : array_like, shape (..., m)
        Task points in m and rad.

    Returns
    -------
    ndarray, shape (..., m)
        mm and deg.
    """
    return np.asarray(values, float) * task_scales(mechanism)


def joint_display_units(mechanism: HasUnits) -> tuple[str, ...]:
    """How a person reads each actuated joint: ``"deg"`` (revolute) or ``"mm"`` (prismatic), length ``n``.

    Parameters
    ----------
    mechanism : HasUnits
        Any model (only ``joint_units`` is read).

    Returns
    -------
    tuple of str, length ``n``

    Examples
    --------
    >>> from kinematics.fivebar import FiveBar
    >>> joint_display_units(FiveBar())
    ('deg', 'deg')
    """
    return tuple(DISPLAY_UNIT[u] for u in mechanism.joint_units)


def joint_scales(mechanism: HasUnits) -> FloatArray:
    """Display units per SI unit of each actuated joint, shape (n,): 180/pi (deg) or 1000 (mm).

    Parameters
    ----------
    mechanism : HasUnits
        Any model (only ``joint_units`` is read).

    Returns
    -------
    ndarray, shape (n,)
    """
    return np.array([DISPLAY_SCALE[u] for u in joint_display_units(mechanism)])


def joints_from_si(mechanism: HasUnits, values: ArrayLike) -> FloatArray:
    """Joint values (..., n) in SI (rad, m) in display units (deg, mm), shape (..., n).

    Parameters
    ----------
    mechanism : HasUnits
        Any model (only ``joint_units`` is read).
    values : array_like, shape (..., n)
        Joint values in rad and m.

    Returns
    -------
    ndarray, shape (..., n)
        deg and mm.
    """
    return np.asarray(values, float) * joint_scales(mechanism)


def joints_to_si(mechanism: HasUnits, values: ArrayLike) -> FloatArray:
    """Joint values (..., n) typed in display units (deg, mm) in SI (rad, m), shape (..., n).

    Parameters
    ----------
    mechanism : HasUnits
        Any model (only ``joint_units`` is read).
    values : array_like, shape (..., n)
        Joint values in deg and mm.

    Returns
    -------
    ndarray, shape (..., n)
        rad and m.
    """
    return np.asarray(values, float) / joint_scales(mechanism)
