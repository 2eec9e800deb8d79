"""What differs between two designs, in words: the compare figure says what was changed.

Plain Python on the mechanisms' ``parameter_table`` (display units, the names ``--set`` and
the app's sliders use); no plotting, no Qt.
"""
from __future__ import annotations

import math


def _value_text(value, digits: int = 4) -> str:
    """A parameter's value as typed: numbers to ``digits`` significant digits, vectors comma-separated."""
    if isinstance(value, tuple):
        return ", ".join(_value_text(v, digits) for v in value)
    if isinstance(value, float):
        return f"{value:.{digits}g}"
    return str(value)


def _change_text(old, new) -> str:
    """``"old -> new"`` with the fewest digits (4 or more) that write the two values apart:
    100 -> 100.02 is not "100 -> 100"."""
    for digits in (4, 6, 8, 10, 12, 17):
        before, after = _value_text(old, digits), _value_text(new, digits)
        if before != after:
            break
    return f"{before} -> {after}"


def _same(a, b) -> bool:
    if isinstance(a, tuple) and isinstance(b, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float):
        return a == b or math.isclose(a, b, rel_tol=1e-12, abs_tol=0.0)
    return a == b


def parameter_changes(reference, current) -> list[str]:
    """The parameters in which ``current`` differs from ``reference`` (two mechanisms).

    Parameters
    ----------
    reference, current : Mechanism
        The designs compared (``kinematics.contract.Mechanism``).

    Returns
    -------
    list of str
        One phrase per differing parameter, in display units and the models' display order,
        e.g. ``"gear_ratios 6.875, 5.957, 5.957 -> 13.75, 5.957, 5.957"`` or ``"proximal (mm)
        100 -> 110"`` (with the unit where it has one); ``[]`` where none
        differs. Mechanisms of different kinds are not compared parameter by parameter: one
        phrase names both kinds.

    Examples
    --------
    >>> from resources import load_preset
    >>> mech = load_preset("fivebar_singh").mechanism
    >>> parameter_changes(mech, mech.replace_display(gear_ratios=(12.0, 10.0)))
    ['gear_ratios 10, 10 -> 12, 10']
    >>> parameter_changes(mech, mech.replace_display(proximal=100.02))    # digits enough to differ
    ['proximal (mm) 100 -> 100.02']
    >>> parameter_changes(mech, mech)
    []
    """
    if type(reference) is not type(current):
        return [f"another mechanism: {type(reference).__name__} -> {type(current).__name__}"]
    before = {info.name: value for info, value in reference.parameter_table()}
    phrases = []
    for info, value in current.parameter_table():
        old = before.get(info.name)
        if not _same(old, value):
            unit = f" ({info.unit})" if info.unit and not info.choices else ""
            phrases.append(f"{info.name}{unit} {_change_text(old, value)}")
    return phrases
