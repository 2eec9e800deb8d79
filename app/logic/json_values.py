"""Plain JSON values and strict JSON text: numpy to Python, ``nan`` to ``null``, ``+-inf`` to ``"inf"``.

The rule every JSON output follows (``isoforce ... --json``, the statistics files, the pose
report: see ``app.logic.pose_report`` for what ``null`` and ``"inf"`` mean there). Its own module,
with no import from ``metrics``, so that printing JSON costs no compute module a command does
not use.
"""
from __future__ import annotations

import json
import math
from typing import Any

import numpy as np


def json_safe(value: Any) -> Any:
    """``value`` as plain JSON types: numpy to Python, ``nan`` to ``None``, ``+-inf`` to ``"inf"``.

    Tuples and arrays become lists, mappings keep their (string) keys. The result always
    passes ``json.dumps(..., allow_nan=False)``.
    """
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return json_safe(value.tolist())
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        number = float(value)
        if math.isnan(number):
            return None
        if math.isinf(number):
            return "inf" if number > 0 else "-inf"
        return number
    return value


def dumps(obj: Any) -> str:
    """Strict JSON text of ``obj`` (after ``json_safe``): never ``NaN`` or ``Infinity``."""
    return json.dumps(json_safe(obj), indent=2, allow_nan=False)
