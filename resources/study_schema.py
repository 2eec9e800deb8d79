"""Design studies as TOML data: reading and validating a study file (``load_study``).

A study names the mechanism, the parameter grid, the workspace and the objective. This
module turns the file into validated plain data, a ``StudyFile`` of numbers, strings,
``kinematics`` models and ``kinematics.grid.GridSpec`` grids; ``metrics.design.build_study``
makes the searchable ``metrics.design.Study`` from it (sample points, orientation samples,
memory checks). ``resources`` depends on ``kinematics`` only. (A little over the ~600-line
guide: the file format's reference below and one validator per table belong together.)

The study file
--------------
Lengths in mm, angles in deg, torques in N m (the display units ``isoforce show`` prints);
forces in N. Every error names the file and the key (``StudyError``)::

    name = "..."                     # optional, default: the file's stem
    description = "..."              # optional

    [mechanism]
    preset = "fivebar_singh"         # a preset key or a .toml path, OR
    kind = "fivebar"                 # fivebar | inverse3 | twin_pantograph | stewart
    parameters = { working_mode = "+-" }   # base values, display units (override the preset)

    [grid]                           # the design space, first entry slowest (design id = C order)
    proximal = { min = 90.0, max = 120.0, step = 10.0 }     # a scalar parameter, display units
    distal = [110.0, 130.0, 150.0]                           # or an explicit list
    gear_ratios.theta_0 = { min = 6.875, max = 16.0, step = 0.005 }   # one entry of a vector
    Q1 = { targets = ["motor_torques.q1", "motor_torques.q4"], values = [0.12, 0.16] }  # tied

    [workspace]
    kind = "grid"                    # grid | preset_map | sampling | points
    axes = ["x", "y"]                # grid: as a preset's [map], mm
    lower = [-60.0, 100.0]
    upper = [60.0, 180.0]
    resolution = [40, 25]
    fixed = {}                       # task coordinates not on an axis, mm
    centre = { y = 0.0 }             # optional shift of the named coordinates, mm
    # preset_map: the preset's own [map], optionally `resolution = [200, 200]` (subsampled)
    # sampling:   `name = "normalised_arcs"`, a five-bar sampling of metrics.sweeps.SAMPLINGS
    # points:     `points = [[x, y], ...]` in mm (pen mechanisms without [workspace.orientations]:
    #             whole poses [x, y, z, rx, rz] in mm and deg)
    [workspace.orientations]         # pen mechanisms (task rx, rz / rx, ry, rz) only
    tip_bound = 45.0                 # deg (paper 001 eqs. 14-16)
    rings = 2                        # N
    roll = [0.0]                     # deg, 6-DOF tasks only
    rule = "exact"                   # or "float" (metrics.orientations)

    [objective]
    kind = "min_isotropic_force"     # | "gii" | "count_condition_above" | "sensor_gii"
                                     # | "min_force_per_apparent_mass" (N/kg = m/s^2, below)
    direction = "max"                # optional; must be the kind's own (below)
    infeasible = "fail"              # "fail": a design must reach every sample; "skip"
    threshold = 5.0                  # count_condition_above only
    S_T = "human_hand"               # gii only: paper 001 Table I, or m numbers (SI: moments / F_i in m)
                                     # sensor_gii: "hand_velocity" (paper 001 eq. 27), or m numbers (m/s, rad/s)
    frame = "end_effector"           # gii, sensor_gii: rotate the task rows into the pen frame first
    max_apparent_mass = 0.15         # optional, any kind, kg: a design whose largest apparent mass
                                     # exceeds it at any sample is infeasible (ranked last)
    top_k = 5

``min_force_per_apparent_mass`` (direction max) is the workspace minimum of the isotropic force
over the largest apparent mass at each sample, in N/kg (= m/s^2: the acceleration an isotropic
force buys against the heaviest direction). It and ``max_apparent_mass`` need a mechanism with
a mass model (``has_mass_model``) and a workspace other than ``sampling``.

    [report]                         # optional
    reference = { "gear_ratios.theta_0" = 13.75 }   # one design, every grid parameter named
    tolerance = 1e-3                 # relative
    smallest = "gear_ratios.theta_0" # the smallest value of this parameter within tolerance
    checks = [{ label = "+60 %", "gear_ratios.theta_0" = 11.0 }]    # designs to evaluate

    [series]                         # optional: one optimization per value
    key = "workspace.centre.z"       # or "mechanism.parameters.NAME"
    values = [150.0, 200.0]
    paper = [0.089, 0.182]           # optional figures to print alongside
    parameters = { upper_arm = [170.0, 145.0] }   # optional: mechanism parameters per value (display units)
"""
from __future__ import annotations

import copy
import hashlib
import json
import math
import tomllib
from collections.abc import Sequence
from dataclasses import replace
from decimal import Decimal, InvalidOperation
from importlib import resources as _res
from pathlib import Path
from typing import Any

from kinematics.base import MechanismBase
from kinematics.grid import GridSpec
from kinematics.registry import MECHANISMS, kind_of

from .study_file import (  # noqa: F401
    CHECK_EVERY_VALUE,
    DIRECTIONS,
    HUMAN_HAND_TASK,
    MASS_OBJECTIVES,
    MAX_DESIGNS,
    OBJECTIVES,
    SCALED_OBJECTIVES,
    WORKSPACE_KINDS,
    Check,
    GridEntry,
    ObjectiveEntry,
    OrientationEntry,
    Report,
    Series,
    StudyError,
    StudyFile,
    Target,
    WorkspaceEntry,
    study_error,
)

_TOP_KEYS = {"name", "description", "mechanism", "grid", "workspace", "objective", "report", "series"}
_POSITION_NAMES = ("x", "y", "z")
_fail = study_error


def _info(mech: MechanismBase, name: str):
    for info in mech.PARAM_INFO:
        if info.name == name:
            return info
    return None


# ------------------------------------------------------------------------------------------
# Parsing
# ------------------------------------------------------------------------------------------


def _number(source: str, key: str, value: Any, *, positive: bool = False, integer: bool = False) -> float:
    ok = isinstance(value, int) if integer else isinstance(value, (int, float))
    if isinstance(value, bool) or not ok or not math.isfinite(value) or (positive and value <= 0):
        what = "a positive " if positive else "a finite "
        raise _fail(source, key, f"needs {what}{'integer' if integer else 'number'}, got {value!r}")
    return value


def _numbers(source: str, key: str, value: Any, count: int | None = None, *, integer: bool = False) -> list:
    if not isinstance(value, list) or (count is not None and len(value) != count) or not value:
        want = f"{count} " if count is not None else ""
        raise _fail(source, key, f"needs a list of {want}{'integers' if integer else 'numbers'}, got {value!r}")
    return [_number(source, key, v, integer=integer) for v in value]


def _table(source: str, key: str, value: Any, allowed: set[str] | None = None) -> dict:
    if not isinstance(value, dict):
        raise _fail(source, key, f"must be a table, got {value!r}")
    if allowed is not None:
        unknown = sorted(set(value) - allowed)
        if unknown:
            raise _fail(source, f"{key}.{unknown[0]}",
                        f"is not a key of [{key}]; expected one of {', '.join(sorted(allowed))}")
    return value


def _string(source: str, key: str, value: Any, choices: Sequence[str] | None = None) -> str:
    if not isinstance(value, str) or (choices is not None and value not in choices):
        extra = f" one of {', '.join(map(repr, choices))}" if choices is not None else " a string"
        raise _fail(source, key, f"must be{extra}, got {value!r}")
    return value


def _range(source: str, key: str, spec: dict) -> tuple[str, str, int]:
    """``min``, ``max``, ``step`` -> ``(start, step, count)``, exact decimals as text, both ends
    included (``GridEntry.values`` makes the values)."""
    for k in ("min", "max", "step"):
        if k not in spec:
            raise _fail(source, f"{key}.{k}", "is missing (a range needs min, max and step, or give values)")
        _number(source, f"{key}.{k}", spec[k], positive=(k == "step"))
    lo, hi, step = (Decimal(repr(float(spec[k]))) for k in ("min", "max", "step"))
    if hi < lo:
        raise _fail(source, f"{key}.max", f"must be at least {key}.min, got {spec['max']!r} < {spec['min']!r}")
    try:
        n = (hi - lo) / step
    except InvalidOperation:      # pragma: no cover
        n = Decimal("nan")
    if n != n.to_integral_value():
        raise _fail(source, f"{key}.step", f"must divide max - min = {hi - lo} into whole steps, got {spec['step']!r}")
    count = int(n) + 1
    if count > MAX_DESIGNS:
        raise _fail(source, key, f"has {count} values, more than a study can hold")
    return str(lo), str(step), count


def _grid_values(source: str, key: str, spec: Any) -> tuple[tuple[float, ...] | None, str, str, int]:
    """A grid entry's values: ``(listed, start, step, count)``, ``listed`` None for a range."""
    if isinstance(spec, list):
        vals = _numbers(source, key, spec)
    elif isinstance(spec, dict) and "values" in spec:
        extra = sorted(set(spec) - {"values", "targets", "unit"})
        if extra:
            raise _fail(source, f"{key}.{extra[0]}", "cannot be combined with values")
        vals = _numbers(source, f"{key}.values", spec["values"])
    elif isinstance(spec, dict):
        extra = sorted(set(spec) - {"min", "max", "step", "targets", "unit"})
        if extra:
            raise _fail(source, f"{key}.{extra[0]}", "is not a grid key; expected min, max, step (or values), targets")
        start, step, count = _range(source, key, spec)
        return None, start, step, count
    else:
        raise _fail(source, key, f"needs {{min, max, step}}, {{values = [...]}} or a list of numbers, got {spec!r}")
    if len(set(vals)) != len(vals):
        raise _fail(source, key, f"must not repeat a value, got {vals!r}")
    return tuple(float(v) for v in vals), "", "", len(vals)


def _target(source: str, key: str, mech: MechanismBase, text: str) -> Target:
    name, _, label = text.partition(".")
    info = _info(mech, name)
    numeric = [i.name for i in mech.PARAM_INFO if not i.choices]
    if info is None or info.choices:
        raise _fail(source, key, f"names {text!r}, which is not a numeric parameter of {type(mech).__name__}; "
                                 f"expected one of {', '.join(numeric)}")
    if info.is_vector:
        if not label:
            raise _fail(source, key, f"names the vector parameter {name!r}; name an entry: "
                                     f"{', '.join(name + '.' + lab for lab in info.labels)}")
        if label not in info.labels:
            raise _fail(source, key, f"names entry {label!r} of {name!r}; expected one of {', '.join(info.labels)}")
        return Target(name, info.labels.index(label), text)
    if label:
        raise _fail(source, key, f"names {text!r}, but {name!r} is a scalar parameter")
    return Target(name, None, text)


def _parse_grid(source: str, table: Any, mech: MechanismBase) -> tuple[GridEntry, ...]:
    table = _table(source, "grid", table)
    if not table:
        raise _fail(source, "grid", "needs at least one parameter")
    out: list[GridEntry] = []
    entries: list[tuple] = []
    for name, spec in table.items():
        key = f"grid.{name}"
        info = _info(mech, name)
        if isinstance(spec, dict) and "targets" in spec:
            texts = spec["targets"]
            if not isinstance(texts, list) or not texts or not all(isinstance(t, str) for t in texts):
                raise _fail(source, f"{key}.targets", f"needs a list of parameter names, got {texts!r}")
            targets = tuple(_target(source, f"{key}.targets", mech, t) for t in texts)
            grid_list = [(name, key, spec, targets)]
        elif info is not None and info.is_vector and isinstance(spec, dict) and not (set(spec) & {"min", "values"}):
            grid_list = []
            for label, sub in spec.items():
                text = f"{name}.{label}"
                grid_list.append((text, f"{key}.{label}", sub, (_target(source, f"{key}.{label}", mech, text),)))
        else:
            grid_list = [(name, key, spec, (_target(source, key, mech, name),))]
        entries.extend(grid_list)
    total = math.prod(c for c in (_spec_count(e[2]) for e in entries) if c is not None)   # Python ints: exact
    if total > MAX_DESIGNS:
        raise _fail(source, "grid", f"spans {total:,} designs, more than {MAX_DESIGNS:,}: use coarser steps or "
                                    f"fewer parameters")
    for pname, pkey, pspec, targets in entries:
        units = {_info(mech, t.field).unit for t in targets}
        if len(units) != 1:
            raise _fail(source, pkey, f"ties parameters of different units {sorted(units)}")
        listed, start, step, count = _grid_values(source, pkey, pspec)
        entry = GridEntry(pname, targets, units.pop(), count, listed, start, step)
        # A range's values lie between its ends and every parameter's valid set is an
        # interval, so a long range is checked at its ends only (one model per value would
        # take minutes for a million values); its values are made later, after the memory check.
        if listed is not None or count <= CHECK_EVERY_VALUE:
            checked = entry.values()
        else:
            checked = [float(Decimal(start)), float(Decimal(start) + (count - 1) * Decimal(step))]
        for v in checked:
            for t in targets:
                try:
                    _apply(mech, t, v)
                except ValueError as exc:
                    raise _fail(source, pkey, f"value {v!r} is out of range: {exc}") from None
        if any(p.name == pname for p in out):
            raise _fail(source, pkey, "is given twice")
        out.append(entry)
    seen: dict[tuple, str] = {}
    for p in out:
        for t in p.targets:
            k = (t.field, t.index)
            if k in seen:
                raise _fail(source, f"grid.{p.name}", f"sets {t.label!r}, which grid.{seen[k]} sets too")
            seen[k] = p.name
    total = math.prod(p.count for p in out)
    if total > MAX_DESIGNS:
        raise _fail(source, "grid", f"spans {total:,} designs, more than {MAX_DESIGNS:,}")
    return tuple(out)


def _spec_count(spec: Any) -> int | None:
    """Values a grid entry will have, counted without making them (None: let parsing say why)."""
    if isinstance(spec, list):
        return len(spec)
    if not isinstance(spec, dict):
        return None
    if "values" in spec:
        return len(spec["values"]) if isinstance(spec["values"], list) else None
    try:
        lo, hi, step = (Decimal(repr(float(spec[k]))) for k in ("min", "max", "step"))
        n = (hi - lo) / step
    except (KeyError, TypeError, ValueError, ArithmeticError):
        return None
    if not (n.is_finite() and step > 0 and n >= 0 and n == n.to_integral_value()):
        return None
    return int(n) + 1


def _apply(mech: MechanismBase, t: Target, display_value: float) -> MechanismBase:
    if t.index is None:
        return mech.replace_display(**{t.field: display_value})
    info = _info(mech, t.field)
    vec = [info.from_si(v) for v in getattr(mech.params, t.field)]
    vec[t.index] = display_value
    return mech.replace_display(**{t.field: vec})


def _orientation_names(mech: MechanismBase) -> tuple[str, ...]:
    return tuple(n for n in mech.task_names if n not in _POSITION_NAMES)


def _parse_orientations(source: str, table: Any, mech: MechanismBase) -> OrientationEntry:
    """``[workspace.orientations]`` validated (the samples are made by ``metrics.design``)."""
    key = "workspace.orientations"
    table = _table(source, key, table, {"tip_bound", "rings", "roll", "rule", "tool_axis"})
    names = _orientation_names(mech)
    for k in ("tip_bound", "rings"):
        if k not in table:
            raise _fail(source, f"{key}.{k}", "is missing")
    bound = _number(source, f"{key}.tip_bound", table["tip_bound"], positive=True)
    if bound >= 180:
        raise _fail(source, f"{key}.tip_bound", f"must be below 180 deg, got {bound!r}")
    rings = int(_number(source, f"{key}.rings", table["rings"], positive=True, integer=True))
    roll = _numbers(source, f"{key}.roll", table.get("roll", [0.0]))
    if names != ("rx", "ry", "rz") and any(r != 0 for r in roll):
        raise _fail(source, f"{key}.roll", f"must be [0] for a task without roll ({', '.join(names)}), got {roll!r}")
    rule = table.get("rule", "exact")                 # one of metrics.orientations.RULES, checked there
    axis = _numbers(source, f"{key}.tool_axis", table.get("tool_axis", [0.0, 1.0, 0.0]), 3)
    return OrientationEntry(float(bound), rings, tuple(float(r) for r in roll), rule, tuple(float(a) for a in axis))


def _grid_spec(source: str, table: dict, mech: MechanismBase, grid: GridSpec | None = None) -> GridSpec:
    """The workspace grid (m): from ``axes``/``lower``/``upper``/``resolution``/``fixed`` (mm), or a
    preset's ``grid`` with an optional ``resolution``."""
    key = "workspace"
    names = tuple(n for n in mech.task_names if n in _POSITION_NAMES)
    if grid is None:
        for k in ("axes", "lower", "upper", "resolution"):
            if k not in table:
                raise _fail(source, f"{key}.{k}", "is missing")
        axes = table["axes"]
        if (not isinstance(axes, list) or len(axes) not in (2, 3) or len(set(axes)) != len(axes)
                or any(a not in names for a in axes)):
            raise _fail(source, f"{key}.axes", f"needs 2 or 3 distinct names from {list(names)}, got {axes!r}")
        k = len(axes)
        lower = _numbers(source, f"{key}.lower", table["lower"], k)
        upper = _numbers(source, f"{key}.upper", table["upper"], k)
        res = _numbers(source, f"{key}.resolution", table["resolution"], k, integer=True)
        for i, a in enumerate(axes):
            if not lower[i] < upper[i]:
                raise _fail(source, f"{key}.upper",
                            f"must exceed {key}.lower on axis {a!r}, got {lower[i]} >= {upper[i]}")
            if not 2 <= res[i] <= 20000:
                raise _fail(source, f"{key}.resolution", f"needs 2 to 20000 points per axis, got {res[i]} on {a!r}")
        fixed = _table(source, f"{key}.fixed", table.get("fixed", {}))
        rest = [n for n in names if n not in axes]
        if sorted(fixed) != sorted(rest):
            raise _fail(source, f"{key}.fixed", f"needs exactly the coordinates {rest} (mm), got {sorted(fixed)}")
        for n, v in fixed.items():
            _number(source, f"{key}.fixed.{n}", v)
        grid = GridSpec(tuple(axes), tuple(v / 1000.0 for v in lower), tuple(v / 1000.0 for v in upper),
                        tuple(res), tuple((n, fixed[n] / 1000.0) for n in rest))
    elif "resolution" in table:
        r = table["resolution"]
        res = [r] * len(grid.axes) if isinstance(r, int) and not isinstance(r, bool) else r
        res = _numbers(source, f"{key}.resolution", res, len(grid.axes), integer=True)
        if any(not 2 <= v <= 20000 for v in res):
            raise _fail(source, f"{key}.resolution", f"needs 2 to 20000 points per axis, got {r!r}")
        grid = grid.with_resolution(tuple(res))
    return grid


def _centre(source: str, key: str, table: Any, names: tuple[str, ...]) -> tuple[tuple[str, float], ...]:
    out = []
    for n, v in _table(source, key, table).items():
        if n not in names:
            raise _fail(source, f"{key}.{n}", f"is not a position coordinate; expected one of {list(names)}")
        out.append((n, float(_number(source, f"{key}.{n}", v))))
    return tuple(out)


def _parse_workspace(source: str, table: Any, mech: MechanismBase, kind: str, preset) -> WorkspaceEntry:
    key = "workspace"
    allowed = {"kind", "axes", "lower", "upper", "resolution", "fixed", "centre", "name", "points", "orientations"}
    table = _table(source, key, table, allowed)
    wkind = _string(source, f"{key}.kind", table.get("kind"), WORKSPACE_KINDS)
    by_kind = {"grid": {"axes", "lower", "upper", "resolution", "fixed", "centre", "orientations"},
               "preset_map": {"resolution", "centre", "orientations"},
               "sampling": {"name"}, "points": {"points", "centre", "orientations"}}
    for k in table:
        if k != "kind" and k not in by_kind[wkind]:
            raise _fail(source, f"{key}.{k}", f"does not apply to a {wkind!r} workspace; it takes "
                                              f"{', '.join(sorted(by_kind[wkind]))}")
    names = tuple(n for n in mech.task_names if n in _POSITION_NAMES)
    if wkind == "sampling":
        if kind != "fivebar":
            raise _fail(source, f"{key}.kind", f"'sampling' is for the five-bar (metrics.sweeps), got a {kind}")
        return WorkspaceEntry("sampling", sampling=table.get("name"))     # checked by metrics.design
    onames = _orientation_names(mech)
    grid = None
    rows: tuple = ()
    if wkind == "points":
        raw = table.get("points")
        full_poses = bool(onames) and "orientations" not in table
        width = len(mech.task_names) if full_poses else len(names)
        what = "full task points (mm, deg)" if full_poses else "positions in mm"
        if not isinstance(raw, list) or not raw:
            raise _fail(source, f"{key}.points", f"needs a list of {what}, got {raw!r}")
        rows = tuple(tuple(float(v) for v in _numbers(source, f"{key}.points", p, width)) for p in raw)
        if full_poses:                  # whole poses given: no orientation sampling
            centre = _centre(source, f"{key}.centre", table.get("centre", {}), names)
            return WorkspaceEntry("points", points=rows, full_poses=True, centre=centre)
    elif wkind == "preset_map":
        if preset is None:
            raise _fail(source, f"{key}.kind", "'preset_map' needs [mechanism] preset")
        grid = _grid_spec(source, table, mech, preset.grid)
    else:
        grid = _grid_spec(source, table, mech)
    centre = _centre(source, f"{key}.centre", table.get("centre", {}), names)
    ori = None
    if onames:
        if "orientations" not in table:
            raise _fail(source, f"{key}.orientations",
                        f"is missing: the task has orientation coordinates {list(onames)}")
        ori = _parse_orientations(source, table["orientations"], mech)
    elif "orientations" in table:
        raise _fail(source, f"{key}.orientations",
                    f"does not apply: the task {list(mech.task_names)} has no orientation")
    return WorkspaceEntry(wkind, grid=grid, points=rows, centre=centre, orientations=ori)


def _parse_objective(source: str, table: Any, mech: MechanismBase) -> ObjectiveEntry:
    key = "objective"
    table = _table(source, key, table, {"kind", "direction", "infeasible", "threshold", "S_T", "frame", "top_k",
                                        "max_apparent_mass"})
    kind = _string(source, f"{key}.kind", table.get("kind"), OBJECTIVES)
    if kind in MASS_OBJECTIVES and not mech.has_mass_model:
        raise _fail(source, f"{key}.kind", f"{kind!r}: the mechanism has no mass model ({type(mech).__name__} "
                                           f"without bodies); choose a preset or parameters that give one")
    max_mass = None
    if "max_apparent_mass" in table:
        max_mass = float(_number(source, f"{key}.max_apparent_mass", table["max_apparent_mass"], positive=True))
        if not mech.has_mass_model:
            raise _fail(source, f"{key}.max_apparent_mass", f"the mechanism has no mass model "
                                                            f"({type(mech).__name__} without bodies), so no "
                                                            f"apparent mass to bound")
    direction = table.get("direction", DIRECTIONS[kind])
    if direction != DIRECTIONS[kind]:
        raise _fail(source, f"{key}.direction", f"must be {DIRECTIONS[kind]!r} for {kind} (the search maximises a "
                                                f"minimum over the workspace, or minimises a count), got {direction!r}")
    top_k = int(_number(source, f"{key}.top_k", table.get("top_k", 5), positive=True, integer=True))
    threshold = s_t = s_t_name = None
    frame = "base"
    for k in ("threshold",):
        if k in table and kind != "count_condition_above":
            raise _fail(source, f"{key}.{k}", "applies to count_condition_above only")
    for k in ("S_T", "frame"):
        if k in table and kind not in SCALED_OBJECTIVES:
            raise _fail(source, f"{key}.{k}", f"applies to {' and '.join(SCALED_OBJECTIVES)} only")
    if kind == "count_condition_above":
        if "threshold" not in table:
            raise _fail(source, f"{key}.threshold", "is missing (the condition number above which a sample counts)")
        threshold = float(_number(source, f"{key}.threshold", table["threshold"], positive=True))
        if "infeasible" in table:
            raise _fail(source, f"{key}.infeasible", "does not apply to a count: unreachable samples never count")
        infeasible = "skip"
    else:
        infeasible = _string(source, f"{key}.infeasible", table.get("infeasible", "fail"), ("fail", "skip"))
    if kind == "gii":
        raw = table.get("S_T")
        m = mech.task_dim
        if raw == "human_hand":
            if not set(mech.task_names) <= set(HUMAN_HAND_TASK):
                raise _fail(source, f"{key}.S_T", f"'human_hand' needs task coordinates among {HUMAN_HAND_TASK}")
            s_t_name = raw
        elif isinstance(raw, list) and len(raw) == m and all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0 for v in raw):
            s_t = tuple(float(v) for v in raw)
        else:
            raise _fail(source, f"{key}.S_T", f"needs 'human_hand' or {m} positive numbers (SI) for the task "
                                              f"rows {list(mech.task_names)}, got {raw!r}")
    if kind == "sensor_gii":
        s_t, s_t_name = _velocity_scaling(source, f"{key}.S_T", table.get("S_T", "hand_velocity"), mech)
    if kind in SCALED_OBJECTIVES:
        # The force GII's default is the pen frame (Table I is relative to the hand); the
        # hand's velocities are the same in every direction, so the sensor GII's is the base.
        default = "end_effector" if _orientation_names(mech) and kind == "gii" else "base"
        frame = _string(source, f"{key}.frame", table.get("frame", default), ("base", "end_effector"))
        if frame == "end_effector" and not _orientation_names(mech):
            raise _fail(source, f"{key}.frame", "'end_effector' needs a task with orientation coordinates")
    return ObjectiveEntry(kind, DIRECTIONS[kind], infeasible, top_k, threshold, s_t, s_t_name, frame, max_mass)


def _velocity_scaling(source: str, key: str, raw: Any, mech: MechanismBase) -> tuple[tuple | None, str | None]:
    """``S_T`` of a ``sensor_gii`` objective: ``(numbers, None)`` or ``(None, "hand_velocity")``."""
    m = mech.task_dim
    if raw == "hand_velocity":
        if not set(mech.task_names) <= set(HUMAN_HAND_TASK):
            raise _fail(source, key, f"'hand_velocity' needs task coordinates among {HUMAN_HAND_TASK}")
        return None, raw
    if isinstance(raw, list) and len(raw) == m and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0 for v in raw):
        return tuple(float(v) for v in raw), None
    raise _fail(source, key, f"needs 'hand_velocity' or {m} positive velocities (m/s, rad/s) for the task "
                             f"rows {list(mech.task_names)}, got {raw!r}")


def _grid_dict(source: str, key: str, table: Any, params: tuple[GridEntry, ...], extra: set[str]) -> dict:
    table = _table(source, key, table)
    names = {p.name for p in params}
    out = {}
    for k, v in table.items():
        if k in extra:
            continue
        if k not in names:
            raise _fail(source, f"{key}.{k}", f"is not a grid parameter; expected {', '.join(sorted(names))}")
        out[k] = float(_number(source, f"{key}.{k}", v))
    missing = sorted(names - set(out))
    if missing:
        raise _fail(source, key, f"must give every grid parameter; {missing[0]!r} is missing")
    return out


def _parse_report(source: str, table: Any, params: tuple[GridEntry, ...]) -> Report:
    key = "report"
    table = _table(source, key, table, {"reference", "tolerance", "smallest", "checks"})
    reference = (_grid_dict(source, f"{key}.reference", table["reference"], params, set())
                 if "reference" in table else None)
    tol = float(_number(source, f"{key}.tolerance", table.get("tolerance", 1e-3)))
    if tol < 0:
        raise _fail(source, f"{key}.tolerance", f"must be >= 0, got {tol!r}")
    smallest = table.get("smallest")
    if smallest is not None:
        _string(source, f"{key}.smallest", smallest, tuple(p.name for p in params))
        if reference is None:
            raise _fail(source, f"{key}.smallest", "needs report.reference (the value to reach)")
    checks = []
    raw = table.get("checks", [])
    if not isinstance(raw, list):
        raise _fail(source, f"{key}.checks", f"must be a list of tables, got {raw!r}")
    for i, c in enumerate(raw):
        ck = f"{key}.checks[{i}]"
        c = _table(source, ck, c)
        label = _string(source, f"{ck}.label", c.get("label", f"check {i + 1}"))
        checks.append(Check(label, _grid_dict(source, ck, c, params, {"label"})))
    return Report(reference, tol, smallest, tuple(checks))


def _parse_series(source: str, table: Any, mech: MechanismBase) -> Series:
    key = "series"
    table = _table(source, key, table, {"key", "values", "paper", "unit", "parameters"})
    skey = _string(source, f"{key}.key", table.get("key"))
    values = tuple(float(v) for v in _numbers(source, f"{key}.values", table.get("values")))
    paper = table.get("paper")
    if paper is not None:
        paper = tuple(float(v) for v in _numbers(source, f"{key}.paper", paper, len(values)))
    parts = skey.split(".")
    if parts[:2] == ["workspace", "centre"] and len(parts) == 3 and parts[2] in _POSITION_NAMES:
        unit = "mm"
    elif parts[:2] == ["mechanism", "parameters"] and len(parts) == 3:
        info = _info(mech, parts[2])
        if info is None or info.is_vector or info.choices:
            raise _fail(source, f"{key}.key", f"names {parts[2]!r}, not a scalar numeric parameter of "
                                              f"{type(mech).__name__}")
        unit = info.unit
    else:
        raise _fail(source, f"{key}.key", f"must be 'workspace.centre.<x|y|z>' or 'mechanism.parameters.<name>', "
                                          f"got {skey!r}")
    per_value = []
    for name, vals in _table(source, f"{key}.parameters", table.get("parameters", {})).items():
        pkey = f"{key}.parameters.{name}"
        info = _info(mech, name)
        if info is None or info.is_vector or info.choices:
            raise _fail(source, pkey, f"names {name!r}, not a scalar numeric parameter of {type(mech).__name__}")
        if parts[:2] == ["mechanism", "parameters"] and parts[2] == name:
            raise _fail(source, pkey, f"is the series key {skey!r} itself")
        nums = tuple(float(v) for v in _numbers(source, pkey, vals, len(values)))
        for v in nums:
            try:
                mech.replace_display(**{name: v})
            except ValueError as exc:
                raise _fail(source, pkey, f"value {v!r} is out of range: {exc}") from None
        per_value.append((name, nums))
    return Series(skey, values, str(table.get("unit", unit)), paper, tuple(per_value))


def _with_series_value(data: dict, series: Series, index: int) -> dict:
    out = copy.deepcopy(data)
    out.pop("series", None)
    value = series.values[index]
    parts = series.key.split(".")
    if parts[0] == "workspace":
        out.setdefault("workspace", {}).setdefault("centre", {})[parts[2]] = value
    else:
        out.setdefault("mechanism", {}).setdefault("parameters", {})[parts[2]] = value
    for name, vals in series.parameters:
        out.setdefault("mechanism", {}).setdefault("parameters", {})[name] = vals[index]
    return out


def study_from_data(data: dict, source: str, key: str = "", *, text: str = "") -> StudyFile:
    """Validate a parsed TOML study (a dict); ``[mechanism] preset`` is read with
    ``resources.load_preset``.

    Raises
    ------
    StudyError
        The message names ``source`` and the key.
    """
    if not isinstance(data, dict):
        raise StudyError(f"study '{source}': is not a table")
    unknown = sorted(set(data) - _TOP_KEYS)
    if unknown:
        raise _fail(source, unknown[0], f"is not a study key; expected one of {', '.join(sorted(_TOP_KEYS))}")
    for k in ("mechanism", "grid", "workspace", "objective"):
        if k not in data:
            raise _fail(source, k, "is missing")
    name = data.get("name", key or Path(source).stem)
    _string(source, "name", name)
    description = _string(source, "description", data.get("description", ""))
    mtable = _table(source, "mechanism", data["mechanism"], {"preset", "kind", "parameters"})
    preset = None
    if "preset" in mtable:
        if "kind" in mtable:
            raise _fail(source, "mechanism.kind", "cannot be combined with mechanism.preset (the preset has one)")
        pname = _string(source, "mechanism.preset", mtable["preset"])
        from . import load_preset
        try:
            preset = load_preset(pname)
        except ValueError as exc:
            raise _fail(source, "mechanism.preset", f"cannot be loaded: {exc}") from None
        mech = preset.mechanism
        kind = kind_of(mech)
    else:
        kind = _string(source, "mechanism.kind", mtable.get("kind"), tuple(MECHANISMS))
        mech = MECHANISMS[kind]()
    params = _table(source, "mechanism.parameters", mtable.get("parameters", {}))
    for pname, value in params.items():
        info = _info(mech, pname)
        if info is None:
            raise _fail(source, f"mechanism.parameters.{pname}", f"is not a parameter of {kind}; expected one of "
                                                                 f"{', '.join(i.name for i in mech.PARAM_INFO)}")
        try:
            mech = mech.replace_display(**{pname: value})
        except ValueError as exc:
            raise _fail(source, f"mechanism.parameters.{pname}", f"is out of range: {exc}") from None
    series = _parse_series(source, data["series"], mech) if "series" in data else None
    grid = _parse_grid(source, data["grid"], mech)
    objective = _parse_objective(source, data["objective"], mech)
    workspace = _parse_workspace(source, data["workspace"], mech, kind, preset)
    if workspace.kind == "sampling" and (objective.max_apparent_mass is not None or objective.kind in MASS_OBJECTIVES):
        mkey = "objective.max_apparent_mass" if objective.max_apparent_mass is not None else "objective.kind"
        raise _fail(source, mkey, "needs the apparent mass at fixed workspace points; a 'sampling' workspace "
                                  "scales its points per design (use kind = 'grid' or 'points')")
    report = _parse_report(source, data["report"], grid) if "report" in data else None
    digest = hashlib.sha1((text or json.dumps(data, sort_keys=True, default=str)).encode()).hexdigest()[:16]
    spec = StudyFile(key=key or Path(source).stem, name=name, description=description, source=source, kind=kind,
                     mechanism=mech, grid=grid, workspace=workspace, objective=objective, report=report,
                     series=series, fingerprint=digest, raw=data)
    if series is not None:
        runs = []
        for i, v in enumerate(series.values):
            sub = study_from_data(_with_series_value(data, series, i), source, key)
            runs.append(replace(sub, series=series, series_value=v, fingerprint=f"{digest}-{v!r}"))
        spec = replace(spec, runs=tuple(runs))
    return spec


def parse_study_text(text: str, source: str, key: str = "") -> StudyFile:
    """Validate a study from TOML text; ``source`` names it in errors (a file name)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"study '{source}': is not valid TOML: {exc}") from None
    return study_from_data(data, source, key, text=text)


def read_study_file(path: str | Path) -> StudyFile:
    """Load and validate a study from a TOML file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise StudyError(f"study '{path}': cannot be read: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise StudyError(f"study '{path}': is not UTF-8 text (TOML must be): byte 0x{exc.object[exc.start]:02x} "
                         f"at offset {exc.start}") from None
    return parse_study_text(text, str(path), path.stem)


def list_studies() -> list[str]:
    """Keys of the studies shipped in ``resources/studies`` (file stems), sorted."""
    folder = _res.files("resources").joinpath("studies")
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def load_study(name: str) -> StudyFile:
    """A shipped study by key, or a study file by path (ending in ``.toml`` or holding a
    path separator), validated; ``metrics.design.build_study`` makes it searchable.

    Raises
    ------
    StudyError
        Unknown, unreadable or invalid; the message names the file and key.
    """
    if name.endswith(".toml") or "/" in name or "\\" in name:
        return read_study_file(Path(name))
    known = list_studies()
    if name not in known:
        raise StudyError(f"unknown study {name!r}; shipped: {', '.join(known)} (or a path to a .toml file)")
    text = _res.files("resources").joinpath("studies", f"{name}.toml").read_text(encoding="utf-8")
    return parse_study_text(text, f"{name}.toml", name)
