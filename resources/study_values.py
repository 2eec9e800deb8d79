"""The value readers every study table uses: each error names the file and the key
(``StudyError`` through ``study_error``)."""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from kinematics.base import MechanismBase

from .study_file import study_error


def param_info(mech: MechanismBase, name: str):
    for info in mech.PARAM_INFO:
        if info.name == name:
            return info
    return None


def read_number(source: str, key: str, value: Any, *, positive: bool = False, integer: bool = False) -> float:
    ok = isinstance(value, int) if integer else isinstance(value, (int, float))
    if isinstance(value, bool) or not ok or not math.isfinite(value) or (positive and value <= 0):
        what = "a positive " if positive else "a finite "
        raise study_error(source, key, f"needs {what}{'integer' if integer else 'number'}, got {value!r}")
    return value


def read_numbers(source: str, key: str, value: Any, count: int | None = None, *, integer: bool = False) -> list:
    if not isinstance(value, list) or (count is not None and len(value) != count) or not value:
        want = f"{count} " if count is not None else ""
        raise study_error(source, key, f"needs a list of {want}{'integers' if integer else 'numbers'}, got {value!r}")
    return [read_number(source, key, v, integer=integer) for v in value]


def read_table(source: str, key: str, value: Any, allowed: set[str] | None = None) -> dict:
    if not isinstance(value, dict):
        raise study_error(source, key, f"must be a table, got {value!r}")
    if allowed is not None:
        unknown = sorted(set(value) - allowed)
        if unknown:
            raise study_error(source, f"{key}.{unknown[0]}",
                        f"is not a key of [{key}]; expected one of {', '.join(sorted(allowed))}")
    return value


def read_string(source: str, key: str, value: Any, choices: Sequence[str] | None = None) -> str:
    if not isinstance(value, str) or (choices is not None and value not in choices):
        extra = f" one of {', '.join(map(repr, choices))}" if choices is not None else " a string"
        raise study_error(source, key, f"must be{extra}, got {value!r}")
    return value
