"""The statistics panel's digits: value and error with the digits the error supports (issue 11 sec. 5).

The reference is the definition itself, checked with ``decimal`` on the printed text: the
error keeps 1-2 significant digits, the value ends at the error's last decimal place and is
within half a unit of that place of the true value, and both share one notation.
"""
from __future__ import annotations

import math
from decimal import Decimal

import numpy as np
import pytest

from app.logic.figure_digits import format_with_error


def _split(text: str) -> tuple[Decimal, int | None]:
    """The number a text says, and its exponent (None in fixed notation)."""
    if "e" in text:
        mantissa, exponent = text.split("e")
        return Decimal(mantissa).scaleb(int(exponent)), int(exponent)
    return Decimal(text), None


def _last_place(text: str) -> int:
    """The power of ten of the last significant digit written (an integer's trailing zeros are not)."""
    mantissa, _, exponent = text.partition("e")
    place = Decimal(mantissa).as_tuple().exponent + (int(exponent) if exponent else 0)
    if "." not in mantissa and not exponent and Decimal(mantissa) != 0:
        place += len(mantissa) - len(mantissa.rstrip("0"))
    return place


def _significant(text: str) -> int:
    """Significant digits of a positive number down to its last written place (``100`` at place 2: 1)."""
    number, _ = _split(text)
    return number.adjusted() - _last_place(text) + 1


def check(value: float, error: float) -> None:
    v_text, e_text = format_with_error(value, error)
    (v, v_exp), (e, e_exp) = _split(v_text), _split(e_text)
    assert v_exp == e_exp, (v_text, e_text)                       # one notation, one exponent
    place = _last_place(e_text)
    if "." in e_text or "e" in e_text:
        assert _last_place(v_text) == place, (v_text, e_text)      # same decimal place
    else:
        # An integer's trailing zeros may be significant ("200" for 2.0e2): a multiple of the place below.
        assert "." not in v_text and Decimal(v_text) % Decimal(10) ** max(0, place - 1) == 0, (v_text, e_text)
    assert _significant(e_text) in (1, 2), (e_text, error)      # one or two significant digits
    half = Decimal(10) ** place / 2
    # Binary -> decimal: half a unit of the last place, plus the float's own spacing.
    slack = Decimal(4 * math.ulp(max(abs(value), error)))
    assert abs(v - Decimal(value)) <= half + slack, (v_text, value)
    assert abs(e - Decimal(error)) <= half + slack, (e_text, error)
    assert not v_text.startswith("-") or v < 0, v_text           # no "-0.00"


def test_the_issues_two_examples():
    # "2.28" next to "1.176": the error supports one decimal.
    assert format_with_error(2.28, 1.176) == ("2.3", "1.2")
    # "2.998e-05" next to "0.1635": the value is far below what the error resolves.
    assert format_with_error(2.998e-05, 0.1635) == ("0.00", "0.16")
    check(2.28, 1.176)
    check(2.998e-05, 0.1635)


@pytest.mark.parametrize("value, error, expected", [
    (23.14159, 0.46, ("23.1", "0.5")),            # one digit: leading 4
    (23.14159, 0.26, ("23.14", "0.26")),          # two digits: leading 2
    (0.3, 0.0296, ("0.30", "0.03")),              # 0.0296 rounds to 0.030: one digit
    (1234.5, 96.0, ("1200", "100")),              # 96 -> 1e2 (the carry), one digit
    (1234.6, 0.97, ("1235", "1")),
    (-0.001, 0.2, ("0.00", "0.20")),              # no "-0.00"
    (-1.26, 0.2, ("-1.26", "0.20")),
    (2.998e-05, 1.234e-07, ("2.998e-05", "0.012e-05")),
    (9.9996e-05, 2e-09, ("9.99960e-05", "0.00020e-05")),
    (2.120439, 2.5e-05, ("2.120439", "0.000025")),   # fixed down to 10^-9 for numbers from 10^-3
    (3.914002, 2.5e-07, ("3.91400200", "0.00000025")),
    (3.914002, 2.5e-10, ("3.91400200000e+00", "0.00000000025e+00")),
    (0.0123, 1.1e-05, ("0.012300", "0.000011")),
    (0.00012, 1.1e-05, ("1.20e-04", "0.11e-04")),     # below 10^-3: at most 4 decimals fixed
    (9.99996e-05, 4e-9, ("1.00000e-04", "0.00004e-04")),   # the value's rounding carries the exponent
    (1.5e6, 2.1e4, ("1.500e+06", "0.021e+06")),
    (3e-9, 2e-7, ("0.0e-07", "2.0e-07")),         # error larger than the value
])
def test_examples(value, error, expected):
    assert format_with_error(value, error) == expected
    check(value, error)


@pytest.mark.parametrize("value, error, expected", [
    (float("inf"), 0.5, ("inf", "0.5")),
    (float("-inf"), 0.5, ("-inf", "0.5")),
    (float("nan"), 0.5, ("nan", "0.5")),
    (3.0, float("nan"), ("3", "nan")),
    (3.0, float("inf"), ("3", "inf")),
    (3.0, None, ("3", "-")),
    (None, None, ("-", "-")),
    (2.5, 0.0, ("2.500", "<0.0005")),              # exact (no error): 4 digits, the error below the last
    (2.5, -0.26, ("2.50", "0.26")),                # the error's sign is ignored
])
def test_inf_nan_and_missing_are_spelled_out(value, error, expected):
    assert format_with_error(value, error) == expected


def test_random_values_and_errors_over_many_decades():
    rng = np.random.default_rng(11)
    for _ in range(3000):
        error = float(10.0 ** rng.uniform(-12, 9))
        value = float(rng.choice([-1, 1]) * 10.0 ** rng.uniform(-12, 9))
        check(value, error)

