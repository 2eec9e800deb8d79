"""Argument validation for the whole library, in the style of pyvista's ``_validation``.

``check_*`` functions only raise; ``validate_*`` functions return the normalised value (a
float, a tuple, an array). Every one takes ``name=``, the argument's name as the caller sees
it, so an error says which argument was wrong, what was expected and what was given::

    proximal must be a positive finite number in m, got -0.14

The models and some metrics call the short positional forms at the end (``positive_finite``,
``positive_vector``, ``finite_angles``, ``choice``, ``as_points``): each is one ``validate_*``
with the argument's name first, so the checks and messages are the same.

Structural misuse raises ``ValueError``; bad samples inside valid arrays are the callers'
business (``nan`` with a mask), never an error here.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def _in(unit: str) -> str:
    return f" in {unit}" if unit else ""


# -- scalars ------------------------------------------------------------------------------------
def validate_positive_number(value: Any, *, name: str, unit: str = "") -> float:
    """``value`` as a float if it is finite and > 0, else a ValueError naming ``name`` (and ``unit``).

    Parameters
    ----------
    value : object
        Anything ``float`` accepts.
    name : str
        The argument's name for the message.
    unit : str
        Its SI unit for the message (``"m"``, ``"N m"``), or ``""``.

    Returns
    -------
    float

    Examples
    --------
    >>> validate_positive_number("0.25", name="tol")
    0.25
    """
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive finite number{_in(unit)}, got {value!r}") from None
    if not (math.isfinite(number) and number > 0.0):
        raise ValueError(f"{name} must be a positive finite number{_in(unit)}, got {value!r}")
    return number


def validate_angle_in(value: Any, *, name: str, lower: float, upper: float, open_lower: bool = False) -> float:
    """``value`` as a float (rad) in ``(lower, upper)`` (``open_lower``: ``(lower, upper]``), or raise.

    The message names ``name`` and the range in degrees.

    Parameters
    ----------
    value : object
        An angle in rad.
    name : str
        The argument's name for the message.
    lower, upper : float
        The open range, rad.
    open_lower : bool
        Include ``upper`` (the range is open at ``lower`` only).

    Returns
    -------
    float
    """
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    inside = (lower < number <= upper) if open_lower else (lower < number < upper)
    if not (math.isfinite(number) and inside):
        hi = "]" if open_lower else ")"
        raise ValueError(f"{name} must be an angle in ({math.degrees(lower):g}, {math.degrees(upper):g}{hi} deg "
                         f"(given in rad), got {value!r}")
    return number


def check_choice(value: Any, *, name: str, choices: tuple[str, ...]) -> None:
    """Raise a ValueError naming ``name`` unless ``value`` is one of ``choices``.

    Parameters
    ----------
    value : object
        The value to check.
    name : str
        The argument's name for the message.
    choices : tuple of str
        The allowed values.

    Returns
    -------
    None

    Examples
    --------
    >>> check_choice("cubic", name="method", choices=("linear", "nearest"))
    Traceback (most recent call last):
        ...
    ValueError: method must be one of 'linear', 'nearest', got 'cubic'
    """
    if value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(repr(c) for c in choices)}, got {value!r}")


def validate_choice(value: Any, *, name: str, choices: tuple[str, ...]) -> str:
    """``value`` if it is one of ``choices``, else a ValueError naming ``name`` (``check_choice``).

    Parameters
    ----------
    value : object
        The value to check.
    name : str
        The argument's name for the message.
    choices : tuple of str
        The allowed values.

    Returns
    -------
    str
        ``value`` itself.

    Examples
    --------
    >>> validate_choice("up", name="assembly_mode", choices=("up", "down"))
    'up'
    """
    check_choice(value, name=name, choices=choices)
    return value


def check_number(value: Any, *, name: str, unit: str, finite: bool = False) -> None:
    """Raise unless ``value`` is a real number (not a bool; with ``finite``, also finite).

    The message reads ``"{name} needs a [finite ]number in {unit}, got {value!r}"``, e.g.
    ``key 'map.fixed.y' needs a finite number in mm, got 'a'``.

    Parameters
    ----------
    value : object
        The value to check; an ``int`` or ``float`` passes, a ``bool`` does not.
    name : str
        The argument's name for the message.
    unit : str
        The unit the number is read in, for the message.
    finite : bool
        Also require a finite number.

    Returns
    -------
    None

    Examples
    --------
    >>> check_number("a", name="key 'map.fixed.y'", unit="mm", finite=True)
    Traceback (most recent call last):
        ...
    ValueError: key 'map.fixed.y' needs a finite number in mm, got 'a'
    """
    ok = not isinstance(value, bool) and isinstance(value, (int, float))
    if ok and finite:
        ok = math.isfinite(value)
    if not ok:
        raise ValueError(f"{name} needs a {'finite ' if finite else ''}number in {unit}, got {value!r}")


# -- vectors ------------------------------------------------------------------------------------
def validate_positive_vector(values: Any, *, name: str, labels: tuple[str, ...], unit: str = "") -> tuple[float, ...]:
    """``values`` as a tuple of positive finite floats, one per label, or a ValueError naming ``name``.

    Parameters
    ----------
    values : sequence
        One number per label.
    name : str
        The argument's name; an entry is named ``name[label]``.
    labels : tuple of str
        Names of the entries, e.g. ``("theta_0", "p1", "p2")``.
    unit : str
        Their SI unit for the message.

    Returns
    -------
    tuple of float, length ``len(labels)``
    """
    if isinstance(values, (str, bytes)) or not hasattr(values, "__len__"):
        raise ValueError(f"{name} needs {len(labels)} values ({', '.join(labels)}), got {values!r}")
    if len(values) != len(labels):
        raise ValueError(
            f"{name} needs {len(labels)} values ({', '.join(labels)}), got {len(values)}: {list(values)!r}"
        )
    return tuple(validate_positive_number(v, name=f"{name}[{label}]", unit=unit) for label, v in zip(labels, values))


def validate_angles(values: Any, *, name: str, labels: tuple[str, ...]) -> tuple[float, ...]:
    """``values`` as a tuple of finite floats (rad), one per label, or a ValueError naming ``name``.

    Parameters
    ----------
    values : sequence
        One angle (rad) per label.
    name : str
        The argument's name; an entry is named ``name[label]``.
    labels : tuple of str
        Names of the entries.

    Returns
    -------
    tuple of float, length ``len(labels)``
    """
    if isinstance(values, (str, bytes)) or not hasattr(values, "__len__") or len(values) != len(labels):
        raise ValueError(f"{name} needs {len(labels)} values ({', '.join(labels)}) in rad, got {values!r}")
    out = []
    for label, v in zip(labels, values):
        try:
            number = float(v)
        except (TypeError, ValueError):
            raise ValueError(f"{name}[{label}] must be a finite angle in rad, got {v!r}") from None
        if not math.isfinite(number):
            raise ValueError(f"{name}[{label}] must be a finite angle in rad, got {v!r}")
        out.append(number)
    return tuple(out)


def validate_number_list(value: Any, *, name: str, count: int, integer: bool = False) -> list:
    """``value`` if it is a list of ``count`` finite numbers (``integer``: ints), else raise.

    A file's lists (TOML arrays): the message reads ``"{name} needs a list of {count}
    [finite ]numbers|integers, got {value!r}"``.

    Parameters
    ----------
    value : object
        The value read from the file; must be a ``list``.
    name : str
        The argument's (or key's) name for the message.
    count : int
        The required length.
    integer : bool
        Require ``int`` entries instead of any finite number (``bool`` never passes).

    Returns
    -------
    list, length ``count``
        ``value`` itself.

    Examples
    --------
    >>> validate_number_list([1, 2.5], name="lower", count=2)
    [1, 2.5]
    """
    kind = "integers" if integer else "numbers"
    if not isinstance(value, list) or len(value) != count:
        raise ValueError(f"{name} needs a list of {count} {kind}, got {value!r}")
    for v in value:
        ok = isinstance(v, int) if integer else isinstance(v, (int, float))
        if isinstance(v, bool) or not ok or not math.isfinite(v):
            raise ValueError(f"{name} needs a list of {count} finite {kind}, got {value!r}")
    return value


# -- arrays -------------------------------------------------------------------------------------
def validate_points(x: ArrayLike, *, name: str, m: int) -> FloatArray:
    """``x`` as a float64 array whose last axis has length ``m``, shape (..., m), or raise naming ``name``.

    Parameters
    ----------
    x : array_like, shape (..., m)
        Points or joint vectors, batch axes leading.
    name : str
        The argument's name for the message.
    m : int
        The required length of the last axis.

    Returns
    -------
    ndarray, shape (..., m)

    Examples
    --------
    >>> validate_points([[1, 2, 3]], name="x", m=3).dtype
    dtype('float64')
    >>> validate_points([1, 2], name="x", m=3)
    Traceback (most recent call last):
        ...
    ValueError: x must have shape (..., 3), got (2,)
    """
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim == 0 or arr.shape[-1] != m:
        raise ValueError(f"{name} must have shape (..., {m}), got {arr.shape}")
    return arr


def validate_actuator_limits(limits: ArrayLike, *, name: str, n: int) -> FloatArray:
    """Positive finite per-actuator limits broadcastable to ``(..., n)``, or raise naming ``name``.

    Parameters
    ----------
    limits : array_like, shape (..., n)
        Torque (or speed) limit of each of the Jacobian's ``n`` columns.
    name : str
        The argument's name for the message.
    n : int
        The number of actuators.

    Returns
    -------
    ndarray, shape (..., n)
    """
    arr = np.asarray(limits, dtype=np.float64)
    if arr.ndim == 0 or arr.shape[-1] != n:
        raise ValueError(f"{name} must have shape (..., {n}) to match the Jacobian's {n} columns, got {arr.shape}")
    if not np.all(np.isfinite(arr) & (arr > 0)):
        raise ValueError(f"{name} must be positive and finite, got {arr.tolist()}")
    return arr


# -- positional forms ---------------------------------------------------------------------------
# The short positional names the models and the metrics modules call: each is one of the
# ``validate_*`` above (its checks and messages), with the argument's name first.
def positive_finite(name: str, value: Any, unit: str = "") -> float:
    """``validate_positive_number(value, name=name, unit=unit)``.

    Parameters
    ----------
    name : str
        The argument's name for the message.
    value : object
        Anything ``float`` accepts.
    unit : str
        Its SI unit for the message, or ``""``.

    Returns
    -------
    float

    Examples
    --------
    >>> positive_finite("proximal", 0.14, "m")
    0.14
    """
    return validate_positive_number(value, name=name, unit=unit)


def positive_vector(name: str, values: Any, labels: tuple[str, ...], unit: str = "") -> tuple[float, ...]:
    """``validate_positive_vector(values, name=name, labels=labels, unit=unit)``.

    Parameters
    ----------
    name : str
        The argument's name; an entry is named ``name[label]``.
    values : sequence
        One number per label.
    labels : tuple of str
        Names of the entries.
    unit : str
        Their SI unit for the message, or ``""``.

    Returns
    -------
    tuple of float, length ``len(labels)``

    Examples
    --------
    >>> positive_vector("gear_ratios", [1, 2], ("theta_1", "theta_2"))
    (1.0, 2.0)
    """
    return validate_positive_vector(values, name=name, labels=labels, unit=unit)


def optional_positive_vector(name: str, values: Any, labels: tuple[str, ...],
                             unit: str = "") -> tuple[float, ...] | None:
    """``None`` (not given) or ``positive_vector(name, values, labels, unit)``.

    Examples
    --------
    >>> optional_positive_vector("motor_speeds", None, ("q1", "q2")) is None
    True
    >>> optional_positive_vector("motor_speeds", [500, 400], ("q1", "q2"), "rad/s")
    (500.0, 400.0)
    """
    return None if values is None else positive_vector(name, values, labels, unit)


def nonnegative_vector(name: str, values: Any, labels: tuple[str, ...], unit: str = "") -> tuple[float, ...]:
    """One finite number >= 0 per label (a rotor inertia may be neglected), or a ValueError naming ``name[label]``.

    Examples
    --------
    >>> nonnegative_vector("rotor_inertias", [0, 1e-6], ("q1", "q2"), "kg m^2")
    (0.0, 1e-06)
    """
    if isinstance(values, (str, bytes)) or not hasattr(values, "__len__") or len(values) != len(labels):
        raise ValueError(f"{name} needs {len(labels)} values ({', '.join(labels)}){_in(unit)}, got {values!r}")
    out = []
    for label, v in zip(labels, values):
        try:
            number = float(v)
        except (TypeError, ValueError):
            number = math.nan
        if not (math.isfinite(number) and number >= 0):
            raise ValueError(f"{name}[{label}] must be a finite number >= 0{_in(unit)}, got {v!r}")
        out.append(number)
    return tuple(out)


def finite_angles(name: str, values: Any, labels: tuple[str, ...]) -> tuple[float, ...]:
    """``validate_angles(values, name=name, labels=labels)``.

    Parameters
    ----------
    name : str
        The argument's name; an entry is named ``name[label]``.
    values : sequence
        One angle (rad) per label.
    labels : tuple of str
        Names of the entries.

    Returns
    -------
    tuple of float, length ``len(labels)``
        The angles, rad.
    """
    return validate_angles(values, name=name, labels=labels)


def choice(name: str, value: Any, choices: tuple[str, ...]) -> str:
    """``validate_choice(value, name=name, choices=choices)``.

    Parameters
    ----------
    name : str
        The argument's name for the message.
    value : object
        The value to check.
    choices : tuple of str
        The allowed values.

    Returns
    -------
    str
        ``value`` itself.

    Examples
    --------
    >>> choice("assembly_mode", "up", ("up", "down"))
    'up'
    """
    return validate_choice(value, name=name, choices=choices)


def as_points(name: str, x: ArrayLike, m: int) -> FloatArray:
    """``validate_points(x, name=name, m=m)``: shape (..., m) float64.

    Parameters
    ----------
    name : str
        The argument's name for the message.
    x : array_like, shape (..., m)
        Points (or joint vectors) with batch axes leading.
    m : int
        The required length of the last axis.

    Returns
    -------
    ndarray, shape (..., m)
        ``x`` as float64.

    Examples
    --------
    >>> as_points("x", [[0, 1], [2, 3]], 2).shape
    (2, 2)
    """
    return validate_points(x, name=name, m=m)
