"""``[objective]`` of a study file: what the search maximises or minimises, and its bounds."""
from __future__ import annotations

import math
from typing import Any

from kinematics.base import MechanismBase

from .study_file import (
    DIRECTIONS,
    HUMAN_HAND_TASK,
    MASS_OBJECTIVES,
    OBJECTIVES,
    SCALED_OBJECTIVES,
    ObjectiveEntry,
    study_error,
)
from .study_values import read_number, read_string, read_table
from .study_workspace import orientation_names


def parse_objective(source: str, table: Any, mech: MechanismBase) -> ObjectiveEntry:
    key = "objective"
    table = read_table(source, key, table, {"kind", "direction", "infeasible", "threshold", "S_T", "frame", "top_k",
                                        "max_apparent_mass"})
    kind = read_string(source, f"{key}.kind", table.get("kind"), OBJECTIVES)
    if kind in MASS_OBJECTIVES and not mech.has_mass_model:
        raise study_error(source, f"{key}.kind", f"{kind!r}: the mechanism has no mass model ({type(mech).__name__} "
                                           f"without bodies); choose a preset or parameters that give one")
    max_mass = None
    if "max_apparent_mass" in table:
        max_mass = float(read_number(source, f"{key}.max_apparent_mass", table["max_apparent_mass"], positive=True))
        if not mech.has_mass_model:
            raise study_error(source, f"{key}.max_apparent_mass", f"the mechanism has no mass model "
                                                            f"({type(mech).__name__} without bodies), so no "
                                                            f"apparent mass to bound")
    direction = table.get("direction", DIRECTIONS[kind])
    if direction != DIRECTIONS[kind]:
        raise study_error(source, f"{key}.direction",
                          f"must be {DIRECTIONS[kind]!r} for {kind} (the search maximises a "
                                                f"minimum over the workspace, or minimises a count), got {direction!r}")
    top_k = int(read_number(source, f"{key}.top_k", table.get("top_k", 5), positive=True, integer=True))
    threshold = s_t = s_t_name = None
    frame = "base"
    for k in ("threshold",):
        if k in table and kind != "count_condition_above":
            raise study_error(source, f"{key}.{k}", "applies to count_condition_above only")
    for k in ("S_T", "frame"):
        if k in table and kind not in SCALED_OBJECTIVES:
            raise study_error(source, f"{key}.{k}", f"applies to {' and '.join(SCALED_OBJECTIVES)} only")
    if kind == "count_condition_above":
        if "threshold" not in table:
            raise study_error(source, f"{key}.threshold",
                              "is missing (the condition number above which a sample counts)")
        threshold = float(read_number(source, f"{key}.threshold", table["threshold"], positive=True))
        if "infeasible" in table:
            raise study_error(source, f"{key}.infeasible", "does not apply to a count: unreachable samples never count")
        infeasible = "skip"
    else:
        infeasible = read_string(source, f"{key}.infeasible", table.get("infeasible", "fail"), ("fail", "skip"))
    if kind == "gii":
        raw = table.get("S_T")
        m = mech.task_dim
        if raw == "human_hand":
            if not set(mech.task_names) <= set(HUMAN_HAND_TASK):
                raise study_error(source, f"{key}.S_T", f"'human_hand' needs task coordinates among {HUMAN_HAND_TASK}")
            s_t_name = raw
        elif isinstance(raw, list) and len(raw) == m and all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0 for v in raw):
            s_t = tuple(float(v) for v in raw)
        else:
            raise study_error(source, f"{key}.S_T", f"needs 'human_hand' or {m} positive numbers (SI) for the task "
                                              f"rows {list(mech.task_names)}, got {raw!r}")
    if kind == "sensor_gii":
        s_t, s_t_name = _velocity_scaling(source, f"{key}.S_T", table.get("S_T", "hand_velocity"), mech)
    if kind in SCALED_OBJECTIVES:
        # The force GII's default is the pen frame (Table I is relative to the hand); the
        # hand's velocities are the same in every direction, so the sensor GII's is the base.
        default = "end_effector" if orientation_names(mech) and kind == "gii" else "base"
        frame = read_string(source, f"{key}.frame", table.get("frame", default), ("base", "end_effector"))
        if frame == "end_effector" and not orientation_names(mech):
            raise study_error(source, f"{key}.frame", "'end_effector' needs a task with orientation coordinates")
    return ObjectiveEntry(kind, DIRECTIONS[kind], infeasible, top_k, threshold, s_t, s_t_name, frame, max_mass)


def _velocity_scaling(source: str, key: str, raw: Any, mech: MechanismBase) -> tuple[tuple | None, str | None]:
    """``S_T`` of a ``sensor_gii`` objective: ``(numbers, None)`` or ``(None, "hand_velocity")``."""
    m = mech.task_dim
    if raw == "hand_velocity":
        if not set(mech.task_names) <= set(HUMAN_HAND_TASK):
            raise study_error(source, key, f"'hand_velocity' needs task coordinates among {HUMAN_HAND_TASK}")
        return None, raw
    if isinstance(raw, list) and len(raw) == m and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0 for v in raw):
        return tuple(float(v) for v in raw), None
    raise study_error(source, key, f"needs 'hand_velocity' or {m} positive velocities (m/s, rad/s) for the task "
                             f"rows {list(mech.task_names)}, got {raw!r}")
