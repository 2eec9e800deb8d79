"""A region's volume and its grid error as text, in cm^3, with the digits the error supports (no Qt).

``figure_digits.format_with_error``'s rule (the error to 1-2 significant digits, the value to
the same decimal place), always in fixed notation: a workspace of 10^5 cm^3 reads
``105000 +- 3000``, not ``1.05e+05 +- 0.03e+05`` (the semi-dextrous figure once printed
``3.046e+04``). Shared by ``isoforce dextrous``' table and its figure.
"""
from __future__ import annotations

import math

from app.logic.figure_digits import error_place


def _fixed(value: float, place: int) -> str:
    text = f"{round(value, -place):.{max(0, -place)}f}"
    return text[1:] if text.startswith("-") and float(text) == 0.0 else text


def plain(value: float, digits: int = 4) -> str:
    """A volume without an error: ``digits`` significant figures, no exponent.

    >>> plain(30460.2), plain(392.54), plain(1.2964)
    ('30460', '392.5', '1.296')
    """
    if not math.isfinite(value):
        return str(value)
    text = f"{float(value):.{digits}g}"
    return f"{float(text):.0f}" if "e+" in text else text


def volume_with_error(value: float, error: float) -> tuple[str, str]:
    """``value`` and ``error`` (cm^3) as texts with the digits the error supports, fixed notation.

    >>> volume_with_error(49420.3, 4800.1), volume_with_error(104980.0, 2950.0), volume_with_error(392.54, 21.7)
    (('49000', '5000'), ('105000', '3000'), ('393', '22'))
    >>> volume_with_error(1.2964, 0.0), volume_with_error(0.0, 0.0)
    (('1.296', '0'), ('0', '0'))
    """
    if not (math.isfinite(value) and math.isfinite(error) and error > 0):
        return plain(value), plain(error, 2) if math.isfinite(error) and error else "0"
    place = error_place(error)
    return _fixed(value, place), _fixed(error, place)


def volume_text(value: float, error: float, lower_bound: bool = False, note: str = "clipped by the box") -> str:
    """``"V +- E"``, or ``">= V (note)"`` for a region that touches its box: a lower bound, its
    value rounded down to the error's place (rounded to the nearest it could claim more than
    was counted), in cm^3 without the unit.

    >>> volume_text(49420.3, 4800.1), volume_text(49720.3, 4800.1, True)
    ('49000 +- 5000', '>= 49000 (clipped by the box)')
    """
    if lower_bound and math.isfinite(value) and math.isfinite(error) and error > 0:
        place = error_place(error)
        return f">= {_fixed(math.floor(value / 10.0 ** place) * 10.0 ** place, place)} ({note})"
    value_text, error_text = volume_with_error(value, error)
    return f">= {value_text} ({note})" if lower_bound else f"{value_text} +- {error_text}"
