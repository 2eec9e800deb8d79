"""A figure and its estimated error as text, with the digits the error supports (no Qt).

Shared by the statistics panel and the map's legend, so the same figure reads the same in
both: ``format_with_error(2.28, 1.176) == ("2.3", "1.2")``.
"""
from __future__ import annotations

import math

#: An error estimate below this fraction of its figure is rounding, not resolution: the
#: half-resolution map gave the same figure (the same extreme point, summed in another order).
ROUNDING = 1e-12


def format_number(value: float) -> str:
    """A figure without an error estimate: 4 significant digits; ``-`` for none, ``nan``, ``inf`` spelled out."""
    if value is None:
        return "-"
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return f"{value:.4g}" if abs(value) < 1e4 else f"{value:.3e}"


#: Fixed notation while no number reaches 10^5 and the last digit shown is at 10^-9 or above
#: (10^-4 for numbers below 10^-3, which would otherwise start with a run of zeros); beyond
#: that both numbers are written with one shared exponent.
FIXED_PLACES = (-9, 5)
SMALL = (1e-3, -4)


def _fixed_notation(top: float, place: int) -> bool:
    """Whether ``value ± error`` (larger magnitude ``top``, last digit at 10^``place``) reads well fixed."""
    if top >= 10.0 ** FIXED_PLACES[1]:
        return False
    return place >= (FIXED_PLACES[0] if top >= SMALL[0] else SMALL[1])


def error_place(error: float) -> int:
    """The decimal place (power of ten) of the last significant digit of ``error`` (finite, > 0).

    Two significant digits when the error, rounded to two, starts with 1 or 2 (one digit would
    round it by up to 25 %), else one: 1.176 -> 1.2 (place -1), 0.1635 -> 0.16 (-2), 0.46 -> 0.5 (-1),
    0.0296 -> 0.030 -> 0.03 (-2), 96 -> 100 (2).

    >>> error_place(1.176), error_place(0.1635), error_place(0.46), error_place(0.0296), error_place(96.0)
    (-1, -2, -1, -2, 2)
    """
    k = math.floor(math.log10(error))
    lead = round(error / 10.0 ** k, 1)          # 1.0 <= lead <= 10.0 (10.0: 9.96 rounds up)
    if lead >= 10.0:
        k, lead = k + 1, lead / 10.0
    if lead < 3.0:
        return k - 1
    return k + 1 if round(lead) >= 10 else k       # 9.6 -> 10: one digit of the next place


def _fixed(value: float, place: int) -> str:
    text = f"{round(value, -place):.{max(0, -place)}f}"
    return text[1:] if text.startswith("-") and float(text) == 0.0 else text    # no "-0.00"


def format_with_error(value, error) -> tuple[str, str]:
    """``value`` and its ``error`` as two texts with the digits the error supports, in one notation.

    The error keeps 1-2 significant digits (``error_place``) and the value is rounded to the
    same decimal place. Both are fixed-point, or both scientific with the exponent of the
    larger of |value| and error (``_fixed_notation``). A value whose error is 0 (the half
    grids reproduce it, or the error is below its rounding: ``shown_error``) keeps 4
    significant digits, and the error reads as below half a unit of the last one, ``<0.0005``
    (never ``0.000``, which would claim an error of exactly 0). A value without a usable error (None,
    ``nan``, ``inf``) keeps 4 significant digits; ``nan``/``inf`` are spelled out, never
    rounded to a number.

    Parameters
    ----------
    value, error : float or None
        A figure and its estimated error (same unit; the error's sign is ignored).

    Returns
    -------
    (str, str)
        The value's and the error's text; ``-`` for a missing one.

    Examples
    --------
    >>> format_with_error(2.28, 1.176)
    ('2.3', '1.2')
    >>> format_with_error(2.998e-05, 0.1635)
    ('0.00', '0.16')
    >>> format_with_error(2.998e-05, 1.234e-07)
    ('2.998e-05', '0.012e-05')
    >>> format_with_error(float("inf"), 0.5), format_with_error(3.0, float("nan"))
    (('inf', '0.5'), ('3', 'nan'))
    >>> format_with_error(1.5290001, 0.0), format_with_error(2.998e-05, 0.0), format_with_error(0.0, 0.0)
    (('1.529', '<0.0005'), ('2.998e-05', '<0.0005e-05'), ('0', '0'))
    """
    # (Subnormal values keep format_number's 4 digits: their powers of ten underflow.)
    exact = error == 0.0 and value is not None and math.isfinite(value) and abs(value) >= 1e-300
    if not exact and (error is None or not math.isfinite(error) or error == 0.0):
        err_text = "-" if error is None else ("0" if error == 0.0 else format_number(abs(error)))
        return format_number(value), err_text
    error = abs(error)
    # No error the grid can see (the half grid gave the same figure): 4 significant digits,
    # and the error as below half a unit of the last (1.529 and <0.0005, not 0.000 nor 0).
    place = math.floor(math.log10(abs(value))) - 3 if exact else error_place(error)
    if value is None or not math.isfinite(value):
        return format_number(value), _fixed(error, place) if _fixed_notation(error, place) else f"{error:.1e}"
    top = max(abs(value), error)
    if _fixed_notation(top, place):
        return _fixed(value, place), ("<" + _fixed(0.5 * 10.0 ** place, place - 1) if exact else _fixed(error, place))
    exponent = math.floor(math.log10(top))
    # Rounding may carry the larger number to the next power of ten (9.996e-05 -> 1.000e-04).
    if round(top / 10.0 ** exponent, exponent - place) >= 10.0:
        exponent += 1
    digits = max(0, exponent - place)

    def sci(x: float) -> str:
        mantissa = _fixed(x / 10.0 ** exponent, -digits)
        return f"{mantissa}e{exponent:+03d}"
    if exact:
        return sci(value), f"<{_fixed(0.5 * 10.0 ** (place - exponent), place - exponent - 1)}e{exponent:+03d}"
    return sci(value), sci(error)


def shown_error(value, error):
    """``error``, or 0 where it is below the rounding of ``value`` (``ROUNDING``).

    Without this a figure the half-resolution map reproduces up to its last bits (1/condition
    no. max 0.877 ± 1.1e-17) would be written with 17 digits.

    >>> shown_error(0.877, 1.1e-17), shown_error(0.877, 0.002), shown_error(None, 1e-20)
    (0.0, 0.002, 1e-20)
    """
    if (value is not None and error is not None and math.isfinite(value) and math.isfinite(error)
            and abs(error) <= ROUNDING * abs(value)):
        return 0.0
    return error


def unresolved(value, error) -> bool:
    """Whether a figure's grid error is at least the figure itself: the grid does not resolve it.

    >>> unresolved(3e-06, 7e-06), unresolved(2.28, 0.003), unresolved(0.0, 0.0)
    (True, False, False)
    """
    return (value is not None and error is not None and math.isfinite(value) and math.isfinite(error)
            and error > 0.0 and abs(error) >= abs(value))


#: The fastest any grid figure converges: error ~ h^2 (an extreme at a smooth interior
#: maximum, the mean of a smooth field away from the boundary); an extreme or mean set by the
#: workspace's boundary converges as h^1. A faster observed order is noise in a two-step
#: estimate and is taken as this, so the resolution said is never an optimistic guess.
FASTEST_ORDER = 2.0
#: Below this observed order (half the boundary's h^1) the half grids' change is not the grid
#: error's trend: no resolution is extrapolated from it, "a finer grid" is said instead.
SLOWEST_ORDER = 0.5


def resolving_points(value, error, order, resolution) -> tuple[int, ...] | None:
    """Points per axis at which a figure's grid error, extrapolated as error ~ h^p, falls to half the figure.

    The figure is resolved when its error is below it (``unresolved``); half leaves room for
    an estimate from two grid steps. With spacing h ~ 1 / (n - 1) on an axis of n points,
    ``n' - 1 = (n - 1) * (2 * error / |value|) ** (1 / p)``, rounded up to two significant digits.

    Parameters
    ----------
    value, error : float
        The figure and its estimated grid error (same unit).
    order : float or None
        The observed order p of the error (``metrics.workspace.error_orders``); ``nan`` or None
        when none was measurable. Taken as at most ``FASTEST_ORDER``.
    resolution : sequence of int
        The grid's points per axis.

    Returns
    -------
    tuple of int or None
        Points per axis; None when the figure is resolved, is 0, or no order is measurable
        (``order`` missing or below ``SLOWEST_ORDER``).

    Examples
    --------
    >>> resolving_points(3e-06, 7e-06, 1.0, (100, 100))     # error ~ h: 99 * 14 / 3 + 1 = 463 -> 470
    (470, 470)
    >>> resolving_points(3e-06, 7e-06, 2.0, (100, 50))      # error ~ h^2: sqrt(14 / 3) x finer
    (220, 110)
    >>> resolving_points(3e-06, 7e-06, float("nan"), (100, 100)), resolving_points(2.28, 0.003, 1.0, (100, 100))
    (None, None)
    """
    if not unresolved(value, error) or value == 0.0 or order is None or not math.isfinite(order) \
            or order < SLOWEST_ORDER:
        return None
    factor = (2.0 * abs(error) / abs(value)) ** (1.0 / min(order, FASTEST_ORDER))
    return tuple(_round_up_2(math.ceil((int(n) - 1) * factor) + 1) for n in resolution)


def _round_up_2(n: int) -> int:
    """``n`` rounded up to two significant digits: 463 -> 470, 97 -> 97."""
    step = 10 ** max(0, len(str(n)) - 2)
    return -(-n // step) * step


def unresolved_note(value, error, order, resolution) -> str:
    """What a figure whose error is at least itself says: not resolved, and which grid would resolve it.

    Empty for a resolved figure (``unresolved``). The resolution comes from ``resolving_points``;
    where no order is measurable the note says "a finer grid".

    Examples
    --------
    >>> unresolved_note(3e-06, 7e-06, 1.0, (100, 100))
    'not resolved at this grid; about 470 points per axis would resolve it'
    >>> unresolved_note(3e-06, 7e-06, 2.0, (100, 50))
    'not resolved at this grid; about 220 x 110 points would resolve it'
    >>> unresolved_note(3e-06, 7e-06, float("nan"), (100, 100))
    'not resolved at this grid; a finer grid would resolve it'
    >>> unresolved_note(2.28, 0.003, 1.0, (100, 100))
    ''
    """
    if not unresolved(value, error):
        return ""
    points = resolving_points(value, error, order, resolution)
    if points is None:
        return "not resolved at this grid; a finer grid would resolve it"
    grid = (f"{points[0]} points per axis" if len(set(points)) == 1
            else " x ".join(str(n) for n in points) + " points")
    return f"not resolved at this grid; about {grid} would resolve it"
