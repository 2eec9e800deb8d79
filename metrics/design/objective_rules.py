"""A study's ``[objective]`` given its meaning: which kinds exist and which settings each takes.

``resources`` reads the table into typed values (``resources.study_file.ObjectiveEntry``:
strings, numbers, ``None`` where a key is absent) and knows no objective by name; the
vocabulary (``metrics.design.study.OBJECTIVES``, ``DIRECTIONS``) and the rules below live
here only, beside the search that uses them. Every error names the study file and key.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from .. import gii as gii_mod
from .study import DIRECTIONS, OBJECTIVES, Objective

#: The task coordinates of paper 001's hand figures (Table I, eq. 27), in their order.
HUMAN_HAND_TASK = ("x", "y", "z", "rx", "ry", "rz")
#: Objectives scaled by a task vector ``S_T`` (and an optional end-effector ``frame``), with
#: the name of paper 001's figures each may take instead of numbers.
SCALED = {"gii": "human_hand", "sensor_gii": "hand_velocity"}
_POSITION_NAMES = ("x", "y", "z")


def build_objective(study_file: Any) -> Objective:
    """The objective of a validated study file, its kind-specific rules checked.

    Parameters
    ----------
    study_file : resources.StudyFile
        Its ``objective`` holds the table as read; ``study_file.mechanism`` the base model.

    Returns
    -------
    Objective
        ``s_t`` in SI: the file's numbers, Table I's hand forces for ``"human_hand"`` (force
        GII), or ``None`` for ``"hand_velocity"`` (the sensor GII resolves eq. 27 itself,
        ``metrics.design.evaluators.hand_velocities``).

    Raises
    ------
    resources.StudyError
        Unknown kind, a direction against the kind's, a setting the kind does not take, a
        missing threshold, an ``S_T`` of the wrong length or name, a mass objective or bound
        on a mechanism without a mass model or on a per-design sampling.
    """
    o, mech = study_file.objective, study_file.mechanism
    key = "objective"
    if o.kind not in OBJECTIVES:
        raise study_file.error(f"{key}.kind", f"must be one of {', '.join(map(repr, OBJECTIVES))}, got {o.kind!r}")
    direction = DIRECTIONS[o.kind]
    if o.direction is not None and o.direction != direction:
        raise study_file.error(f"{key}.direction", f"must be {direction!r} for {o.kind} (the search maximises a "
                                                   f"minimum over the workspace, or minimises a count), "
                                                   f"got {o.direction!r}")
    objective = Objective(o.kind, direction, o.infeasible or "fail", o.top_k, o.threshold, None, o.frame or "base",
                          o.max_apparent_mass)
    _check_mass(study_file, objective)
    if o.kind == "count_condition_above":
        if o.threshold is None:
            raise study_file.error(f"{key}.threshold", "is missing (the condition number above which a sample counts)")
        if o.infeasible is not None:
            raise study_file.error(f"{key}.infeasible", "does not apply to a count: unreachable samples never count")
        objective = replace(objective, infeasible="skip")
    elif o.threshold is not None:
        raise study_file.error(f"{key}.threshold", "applies to count_condition_above only")
    if o.kind not in SCALED:
        for name, given in (("S_T", o.s_t is not None or o.s_t_name is not None), ("frame", o.frame is not None)):
            if given:
                raise study_file.error(f"{key}.{name}", f"applies to {' and '.join(SCALED)} only")
        return objective
    onames = tuple(n for n in mech.task_names if n not in _POSITION_NAMES)
    # The force GII's default is the pen frame (Table I is relative to the hand); the hand's
    # velocities are the same in every direction, so the sensor GII's is the base.
    frame = o.frame or ("end_effector" if onames and o.kind == "gii" else "base")
    if frame == "end_effector" and not onames:
        raise study_file.error(f"{key}.frame", "'end_effector' needs a task with orientation coordinates")
    return replace(objective, frame=frame, s_t=_task_scaling(study_file, o.kind))


def _check_mass(study_file: Any, objective: Objective) -> None:
    """Refuse a mass objective or bound the mechanism or the workspace cannot give."""
    if not objective.uses_mass:
        return
    mkey = "objective.max_apparent_mass" if objective.max_apparent_mass is not None else "objective.kind"
    what = "no apparent mass to bound" if objective.max_apparent_mass is not None else "no apparent mass"
    if not study_file.mechanism.has_mass_model:
        raise study_file.error(mkey, f"{objective.kind!r}: the mechanism has no mass model "
                               f"({type(study_file.mechanism).__name__} without bodies), so {what}; "
                               f"choose a preset or parameters that give one")
    if study_file.workspace.kind == "sampling":
        raise study_file.error(mkey, "needs the apparent mass at fixed workspace points; a 'sampling' workspace "
                               "scales its points per design (use kind = 'grid' or 'points')")


def _task_scaling(study_file: Any, kind: str) -> tuple[float, ...] | None:
    """``S_T`` (m,) in SI of a scaled objective, or ``None`` for the sensor GII's eq. 27."""
    o, mech = study_file.objective, study_file.mechanism
    key = "objective.S_T"
    name = SCALED[kind]
    raw_name = o.s_t_name if o.s_t is None else None
    if o.s_t is None and raw_name is None:
        if kind == "gii":
            raise study_file.error(key, f"needs {name!r} or {mech.task_dim} positive numbers (SI) for the task rows "
                                  f"{list(mech.task_names)}, got None")
        raw_name = name
    if raw_name is not None:
        if raw_name != name:
            raise study_file.error(key, f"needs {name!r} or {mech.task_dim} positive numbers for the task rows "
                                  f"{list(mech.task_names)}, got {raw_name!r}")
        if not set(mech.task_names) <= set(HUMAN_HAND_TASK):
            raise study_file.error(key, f"{name!r} needs task coordinates among {HUMAN_HAND_TASK}")
        if kind == "sensor_gii":
            return None
        full = np.asarray(gii_mod.HUMAN_HAND_S_T)
        return tuple(float(full[HUMAN_HAND_TASK.index(n)]) for n in mech.task_names)
    if len(o.s_t) != mech.task_dim:
        units = "SI" if kind == "gii" else "m/s, rad/s"
        raise study_file.error(key, f"needs {name!r} or {mech.task_dim} positive numbers ({units}) for the task rows "
                              f"{list(mech.task_names)}, got {list(o.s_t)!r}")
    return o.s_t

