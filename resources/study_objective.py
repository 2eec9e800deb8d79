"""``[objective]`` of a study file, read as typed values.

Which objective kinds exist, the direction each is searched in and which settings each
takes are the search's rules: ``metrics.design.objective_rules`` checks them, with the one
vocabulary (``metrics.design.study.OBJECTIVES``). This reader checks only that each key
holds the kind of value it must, and leaves ``None`` where a key is absent.
"""
from __future__ import annotations

import math
from typing import Any

from .study_file import ObjectiveEntry, study_error
from .study_values import read_number, read_string, read_table

KEYS = {"kind", "direction", "infeasible", "threshold", "S_T", "frame", "top_k", "max_apparent_mass"}


def parse_objective(source: str, table: Any) -> ObjectiveEntry:
    """The ``[objective]`` table as typed values.

    Parameters
    ----------
    source : str
        The study file, for error messages.
    table : Any
        The TOML value under ``objective``.

    Returns
    -------
    ObjectiveEntry

    Raises
    ------
    StudyError
        An unknown key or a value of the wrong type; the message names the file and key.
    """
    key = "objective"
    table = read_table(source, key, table, KEYS)

    def optional(name: str, read, *args, **kwargs):
        return read(source, f"{key}.{name}", table[name], *args, **kwargs) if name in table else None

    number = optional("threshold", read_number, positive=True)
    mass = optional("max_apparent_mass", read_number, positive=True)
    s_t, s_t_name = _task_scaling(source, f"{key}.S_T", table.get("S_T"))
    return ObjectiveEntry(
        kind=read_string(source, f"{key}.kind", table.get("kind")),
        direction=optional("direction", read_string, ("max", "min")),
        infeasible=optional("infeasible", read_string, ("fail", "skip")),
        top_k=int(read_number(source, f"{key}.top_k", table.get("top_k", 5), positive=True, integer=True)),
        threshold=None if number is None else float(number),
        s_t=s_t, s_t_name=s_t_name,
        frame=optional("frame", read_string, ("base", "end_effector")),
        max_apparent_mass=None if mass is None else float(mass))


def _task_scaling(source: str, key: str, raw: Any) -> tuple[tuple[float, ...] | None, str | None]:
    """``S_T`` as ``(numbers, None)``, ``(None, name)`` or ``(None, None)`` when absent."""
    if raw is None or isinstance(raw, str):
        return None, raw
    if isinstance(raw, list) and raw and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0 for v in raw):
        return tuple(float(v) for v in raw), None
    raise study_error(source, key, f"needs a name of a figure set or a list of positive numbers, got {raw!r}")
