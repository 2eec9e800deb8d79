"""Design studies as data: a TOML file names the mechanism, the parameter grid, the workspace and
the objective; ``run_study`` finds the best designs exactly, on one process, local processes
or a Dask cluster.

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
    kind = "min_isotropic_force"     # | "gii" | "count_condition_above"
    direction = "max"                # optional; must be the kind's own (below)
    infeasible = "fail"              # "fail": a design must reach every sample; "skip"
    threshold = 5.0                  # count_condition_above only
    S_T = "human_hand"               # gii only: paper 001 Table I, or m numbers (SI: moments / F_i in m)
    frame = "end_effector"           # gii only: rotate the task rows into the pen frame first
    top_k = 5

    [report]                         # optional
    reference = { "gear_ratios.theta_0" = 13.75 }   # one design, every grid parameter named
    tolerance = 1e-3                 # relative
    smallest = "gear_ratios.theta_0" # the smallest value of this parameter within tolerance
    checks = [{ label = "+60 %", "gear_ratios.theta_0" = 11.0 }]    # designs to evaluate

    [series]                         # optional: one optimisation per value
    key = "workspace.centre.z"       # or "mechanism.parameters.NAME"
    values = [150.0, 200.0]
    paper = [0.089, 0.182]           # optional figures to print alongside

Objectives
----------
=========================  ==============================================  ==============
kind                       F(p), per design                                 direction
=========================  ==============================================  ==============
``min_isotropic_force``    ``min_x`` maximum isotropic force (N), the       max
                           paper-000 "global maximum isotropic force"
``gii``                    ``min_x sigma_min / max_x sigma_max`` of the     max
                           scaled matrix (paper 001 eq. 11, metrics.gii)
``count_condition_above``  number of samples with condition number >        min
                           ``threshold`` (paper 002); unreachable samples
                           do not count
=========================  ==============================================  ==============

The first two are max-min problems and run on ``metrics.culling.culling_search`` (forms
``"min"`` and ``"ratio"``). The count is a *sum* over the workspace, which the min-form bounds
do not cover; ``count_search`` below is the same algorithm with the bound that fits a sum of
non-negative integers: a partial count over some samples is a lower bound of the final count,
so ``-partial`` is an upper bound of ``F = -count`` that only falls as samples are added.
Counts are sums of 0/1 in float64, exact in any order, so its result equals brute force
bit for bit (tested).

Splitting the design space
--------------------------
``run_study`` cuts the design ids into chunks (``plan_chunks``: a strided warm-up chunk
spread over the whole space, then contiguous pieces) and searches each exactly
(``culling_search`` / ``count_search``), on the calling process, on a
``ProcessPoolExecutor`` or on a ``dask.distributed`` client. A chunk started after others
finished gets their merged K-th best as its ``floor`` and their worst samples as its first
probes; ``merge_top_k`` of all chunks is the global top K, identical to a single-process run
whatever the order chunks finish in (proof in ``metrics.culling``). Only the *cost* depends on
the scheduling.

Evaluators
----------
``make_evaluator`` picks the fastest exact one: ``TorqueOnly`` when the grid varies torques or
gear ratios only (J's column norms are computed once), ``FiveBarBatch`` for five-bar link
lengths (``metrics.design_batch``: designs broadcast against points, no model per design),
else ``Generic`` (one model per design, ``metrics.quantities.evaluate`` or the scaled
singular values of ``metrics.gii``). Each gives a (design, sample) value that does not depend
on which other pairs share the call, which the searches' exactness needs.

The [report] table
------------------
``reference``: one design's exact value; ``target`` = that value within ``tolerance``
(relative). ``smallest``: the smallest value of the named grid parameter at which a design
reaches the target (``first_reaching``: exact, no monotonicity assumed). ``checks``: designs
(on the grid or not) evaluated exactly and compared with the reference.

What the results hold
---------------------
Every design gets a record: ``exact`` designs were evaluated on the whole workspace and
carry their value; culled designs carry the bound the search had when it dropped them
(``min_isotropic_force``, ``gii``: an *upper* bound of the value; count: a *lower* bound of
the count), with the number of samples it came from.
"""
from __future__ import annotations

import copy
import hashlib
import heapq
import inspect
import json
import math
import os
import threading
import time
import tomllib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from decimal import Decimal, InvalidOperation
from pathlib import Path
from typing import Any

import numpy as np

from kinematics import FiveBar, Inverse3
from kinematics.base import FloatArray, MechanismBase

from . import gii as gii_mod
from .culling import BLOCK_PAIRS, SearchResult, _TopK, brute_force, culling_search, merge_top_k, ranking
from .design_batch import fivebar_batch, isotropic_force_fast
from .quantities import evaluate, redundant

OBJECTIVES = ("min_isotropic_force", "gii", "count_condition_above")
#: The direction each objective is optimised in (the search maximises F; a count is minimised).
DIRECTIONS = {"min_isotropic_force": "max", "gii": "max", "count_condition_above": "min"}
UNITS = {"min_isotropic_force": "N", "gii": "", "count_condition_above": "samples"}
METHODS = ("culling", "brute_force")
WORKSPACE_KINDS = ("grid", "preset_map", "sampling", "points")
#: What a culled design's stored number means, per objective.
BOUND_MEANING = {
    "min_isotropic_force": "upper bound of the global minimum isotropic force (from the samples evaluated)",
    "gii": "upper bound of the GII (min sigma_min / max sigma_max over the samples evaluated)",
    "count_condition_above": "lower bound of the count (ill-conditioned samples among those evaluated)",
}
#: Largest design space a study may have.
MAX_DESIGNS = 1 << 31
_TOP_KEYS = {"name", "description", "mechanism", "grid", "workspace", "objective", "report", "series"}
_POSITION_NAMES = ("x", "y", "z")


class StudyError(ValueError):
    """A study file that cannot be used; the message names the file and key."""


def _fail(source: str, key: str, message: str) -> StudyError:
    return StudyError(f"study '{source}': key '{key}' {message}")


def mechanism_kinds() -> dict[str, type[MechanismBase]]:
    """Mechanism kinds a study can name, by key (the pen mechanisms when their modules exist)."""
    kinds: dict[str, type[MechanismBase]] = {"fivebar": FiveBar, "inverse3": Inverse3}
    try:
        from kinematics.twin_pantograph import TwinPantograph
        kinds["twin_pantograph"] = TwinPantograph
    except ImportError:        # pragma: no cover - module written concurrently
        pass
    try:
        from kinematics.stewart import StewartPlatform
        kinds["stewart"] = StewartPlatform
    except ImportError:        # pragma: no cover
        pass
    return kinds


# ------------------------------------------------------------------------------------------
# The parsed study
# ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Target:
    """One mechanism parameter (``field``) or one entry of a vector parameter (``index``)."""

    field: str
    index: int | None
    label: str             # as written: "proximal" or "gear_ratios.theta_0"


@dataclass(frozen=True)
class GridParameter:
    """A design variable: its name, the mechanism entries it sets, and its values.

    ``display`` holds the values as typed (display units), ``si`` the same in SI.
    """

    name: str
    targets: tuple[Target, ...]
    unit: str
    display: tuple[float, ...]
    si: tuple[float, ...]

    @property
    def size(self) -> int:
        return len(self.display)


@dataclass(frozen=True)
class Workspace:
    """The workspace samples: ``points`` (S, m) in SI, or a per-design ``sampling`` frame."""

    kind: str
    points: FloatArray
    description: str
    sampling: Any = None                 # metrics.sweeps.Sampling for kind "sampling"
    positions: int = 0
    orientations: int = 1

    @property
    def size(self) -> int:
        return int(self.points.shape[0])


@dataclass(frozen=True)
class Objective:
    kind: str
    direction: str
    infeasible: str
    top_k: int
    threshold: float | None = None
    s_t: tuple[float, ...] | None = None
    frame: str = "base"

    @property
    def form(self) -> str:
        """Form of the max-min search: ``"min"``, ``"ratio"`` or ``"sum"`` (the count)."""
        return {"min_isotropic_force": "min", "gii": "ratio", "count_condition_above": "sum"}[self.kind]

    @property
    def unit(self) -> str:
        return UNITS[self.kind]


@dataclass(frozen=True)
class Check:
    label: str
    values: dict[str, float]              # grid parameter name -> display value


@dataclass(frozen=True)
class Report:
    reference: dict[str, float] | None
    tolerance: float
    smallest: str | None
    checks: tuple[Check, ...]


@dataclass(frozen=True)
class Series:
    key: str
    values: tuple[float, ...]
    unit: str
    paper: tuple[float, ...] | None


@dataclass(frozen=True)
class Study:
    """A validated study. ``runs()`` expands a series into one study per value."""

    key: str
    name: str
    description: str
    source: str
    kind: str                             # mechanism kind key
    mechanism: MechanismBase              # base model (grid values replace its parameters)
    parameters: tuple[GridParameter, ...]
    workspace: Workspace
    objective: Objective
    report: Report | None = None
    series: Series | None = None
    series_value: float | None = None     # set on the studies ``runs()`` returns
    fingerprint: str = ""
    raw: dict = field(default_factory=dict, repr=False, compare=False)
    _runs: tuple = field(default=(), repr=False, compare=False)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(p.size for p in self.parameters)

    @property
    def n_designs(self) -> int:
        return int(np.prod(self.shape, dtype=np.int64))

    @property
    def n_samples(self) -> int:
        """Workspace samples as written (the search may drop samples no design can use; see
        ``StudyResult.n_samples``)."""
        return self.workspace.size

    def runs(self) -> list["Study"]:
        """One study per series value (``[self]`` without a series)."""
        return list(self._runs) if self._runs else [self]

    def parameter_names(self) -> list[str]:
        return [p.name for p in self.parameters]

    def design_display(self, ids: Any) -> dict[str, np.ndarray]:
        """Grid values (display units) of design ids, one (k,) array per parameter."""
        idx = np.unravel_index(np.asarray(ids, dtype=np.int64), self.shape)
        return {p.name: np.asarray(p.display)[i] for p, i in zip(self.parameters, idx)}

    def design_id(self, values: dict[str, float], where: str = "design") -> int:
        """The id of the grid design with these display values (each parameter named)."""
        idx = []
        for p in self.parameters:
            if p.name not in values:
                raise _fail(self.source, where, f"must give every grid parameter; {p.name!r} is missing")
            hits = np.flatnonzero(np.isclose(np.asarray(p.display), float(values[p.name]), rtol=1e-12, atol=0.0))
            if hits.size != 1:
                raise _fail(self.source, f"{where}.{p.name}", f"must be a value of the grid, got {values[p.name]!r}")
            idx.append(int(hits[0]))
        return int(np.ravel_multi_index(idx, self.shape))

    def field_values(self, ids: Any) -> dict[str, np.ndarray]:
        """SI values of every varied mechanism field for design ids: scalar fields (k,),
        vector fields (k, n) with the base model's other entries."""
        ids = np.asarray(ids, dtype=np.int64)
        idx = np.unravel_index(ids, self.shape)
        out: dict[str, np.ndarray] = {}
        params = self.mechanism.params
        for p, i in zip(self.parameters, idx):
            vals = np.asarray(p.si)[i]
            for t in p.targets:
                if t.index is None:
                    out[t.field] = vals
                else:
                    if t.field not in out:
                        base = np.asarray(getattr(params, t.field), dtype=np.float64)
                        out[t.field] = np.tile(base, (ids.size, 1))
                    out[t.field][:, t.index] = vals
        return out

    def values_mechanism(self, values: dict[str, float]) -> MechanismBase:
        """The model with grid parameters at these display values (any value, on the grid or not)."""
        changes: dict[str, Any] = {}
        params = self.mechanism.params
        for p in self.parameters:
            if p.name not in values:
                raise ValueError(f"values must name every grid parameter; {p.name!r} is missing")
            si = _to_si(self.mechanism, p.targets[0].field, float(values[p.name]))
            for t in p.targets:
                if t.index is None:
                    changes[t.field] = si
                else:
                    vec = list(changes.get(t.field, getattr(params, t.field)))
                    vec[t.index] = si
                    changes[t.field] = tuple(vec)
        return self.mechanism.replace(**changes)

    def design_mechanism(self, design: int) -> MechanismBase:
        disp = self.design_display([design])
        return self.values_mechanism({k: float(v[0]) for k, v in disp.items()})


def _info(mech: MechanismBase, name: str):
    for info in mech.PARAM_INFO:
        if info.name == name:
            return info
    return None


def _to_si(mech: MechanismBase, fieldname: str, value: float) -> float:
    return _info(mech, fieldname).to_si(value)


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
            raise _fail(source, f"{key}.{unknown[0]}", f"is not a key of [{key}]; expected one of {', '.join(sorted(allowed))}")
    return value


def _string(source: str, key: str, value: Any, choices: Sequence[str] | None = None) -> str:
    if not isinstance(value, str) or (choices is not None and value not in choices):
        extra = f" one of {', '.join(map(repr, choices))}" if choices is not None else " a string"
        raise _fail(source, key, f"must be{extra}, got {value!r}")
    return value


def _range_values(source: str, key: str, spec: dict) -> list[float]:
    """``min``, ``max``, ``step`` -> the values as typed (exact decimals), both ends included."""
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
    return [float(lo + i * step) for i in range(count)]


def _grid_values(source: str, key: str, spec: Any) -> list[float]:
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
        vals = _range_values(source, key, spec)
    else:
        raise _fail(source, key, f"needs {{min, max, step}}, {{values = [...]}} or a list of numbers, got {spec!r}")
    if len(set(vals)) != len(vals):
        raise _fail(source, key, f"must not repeat a value, got {vals!r}")
    return [float(v) for v in vals]


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


def _parse_grid(source: str, table: Any, mech: MechanismBase) -> tuple[GridParameter, ...]:
    table = _table(source, "grid", table)
    if not table:
        raise _fail(source, "grid", "needs at least one parameter")
    out: list[GridParameter] = []
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
    _check_design_count(source, [_spec_count(e[2]) for e in entries])
    for pname, pkey, pspec, targets in entries:
        units = {_info(mech, t.field).unit for t in targets}
        if len(units) != 1:
            raise _fail(source, pkey, f"ties parameters of different units {sorted(units)}")
        vals = _grid_values(source, pkey, pspec)
        # A range's values lie between its ends and every parameter's valid set is an
        # interval, so a long range is checked at its ends only (one model per value would
        # take minutes for a million values).
        checked = vals if len(vals) <= 4096 or not isinstance(pspec, dict) or "values" in pspec \
            else [vals[0], vals[-1]]
        for v in checked:
            for t in targets:
                try:
                    _apply(mech, t, v)
                except ValueError as exc:
                    raise _fail(source, pkey, f"value {v!r} is out of range: {exc}") from None
        si = [_to_si(mech, targets[0].field, v) for v in vals]
        if any(p.name == pname for p in out):
            raise _fail(source, pkey, "is given twice")
        out.append(GridParameter(pname, targets, units.pop(), tuple(vals), tuple(si)))
    seen: dict[tuple, str] = {}
    for p in out:
        for t in p.targets:
            k = (t.field, t.index)
            if k in seen:
                raise _fail(source, f"grid.{p.name}", f"sets {t.label!r}, which grid.{seen[k]} sets too")
            seen[k] = p.name
    total = math.prod(p.size for p in out)          # Python ints: exact
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


def _check_design_count(source: str, counts: list[int | None]) -> None:
    """Refuse a design grid too large to hold, before any of its values are made.

    The count is an exact Python-int product; the memory estimate is
    ``metrics.budget.study_estimate`` without samples (the workspace is checked when the study
    runs, ``run_study``).
    """
    from .budget import BudgetError, check_fits, study_estimate

    total = 1
    for c in counts:
        total *= c if c is not None else 1
    if total > MAX_DESIGNS:
        raise _fail(source, "grid", f"spans {total:,} designs, more than {MAX_DESIGNS:,}: use coarser steps or "
                                    f"fewer parameters")
    try:
        check_fits(study_estimate(total, 0, 0), advice="use coarser steps or fewer parameters")
    except BudgetError as exc:
        raise _fail(source, "grid", f"is too large: {exc}") from None


def _check_samples(source: str, key: str, resolution, task_dim: int) -> None:
    """Refuse a workspace grid whose points cannot be held, before making them."""
    from .budget import BudgetError, check_fits, grid_points, study_estimate

    try:
        check_fits(study_estimate(1, grid_points(resolution), task_dim), advice="use a coarser workspace resolution")
    except BudgetError as exc:
        raise _fail(source, f"{key}.resolution", f"is too large: {exc}") from None


def _apply(mech: MechanismBase, t: Target, display_value: float) -> MechanismBase:
    if t.index is None:
        return mech.replace_display(**{t.field: display_value})
    info = _info(mech, t.field)
    vec = [info.from_si(v) for v in getattr(mech.params, t.field)]
    vec[t.index] = display_value
    return mech.replace_display(**{t.field: vec})


def _orientation_names(mech: MechanismBase) -> tuple[str, ...]:
    return tuple(n for n in mech.task_names if n not in _POSITION_NAMES)


def _parse_orientations(source: str, table: Any, mech: MechanismBase) -> FloatArray:
    """Orientation coordinates (K, r) of the pen samples (paper 001 eqs. 14-16)."""
    from .orientations import RULES, orientation_samples

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
    rule = _string(source, f"{key}.rule", table.get("rule", "exact"), RULES)
    axis = _numbers(source, f"{key}.tool_axis", table.get("tool_axis", [0.0, 1.0, 0.0]), 3)
    try:
        samples = orientation_samples(math.radians(bound), rings, roll=np.radians(roll), rule=rule, tool_axis=axis)
    except ValueError as exc:
        raise _fail(source, key, f"is not valid: {exc}") from None
    if names == ("rx", "rz"):
        tilt = samples.tilt_vectors
        if np.max(np.abs(tilt[:, 1])) > 1e-12:
            raise _fail(source, f"{key}.tool_axis", "must be the pen axis y = [0, 1, 0] for a task with tilts (rx, rz)")
        return tilt[:, [0, 2]]
    if names == ("rx", "ry", "rz"):
        from kinematics.rotations import rotation_vector
        return rotation_vector(samples.rotations)
    raise _fail(source, key, f"needs a task with orientation coordinates (rx, rz) or (rx, ry, rz), "
                             f"got {', '.join(mech.task_names)}")


def _grid_points(source: str, table: dict, mech: MechanismBase, grid=None) -> tuple[FloatArray, str]:
    from .workspace import GridSpec

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
                raise _fail(source, f"{key}.upper", f"must exceed {key}.lower on axis {a!r}, got {lower[i]} >= {upper[i]}")
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
    _check_samples(source, key, grid.resolution, len(mech.task_names))
    pos = grid.points(names).reshape(-1, len(names))
    desc = (f"{' x '.join(str(r) for r in grid.resolution)} grid over "
            + ", ".join(f"{a} in [{lo * 1e3:g}, {hi * 1e3:g}] mm" for a, lo, hi in zip(grid.axes, grid.lower, grid.upper))
            + "".join(f", {n} = {v * 1e3:g} mm" for n, v in grid.fixed))
    return pos, desc


def _parse_workspace(source: str, table: Any, mech: MechanismBase, kind: str, preset) -> Workspace:
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
        from .sweeps import SAMPLINGS
        if kind != "fivebar":
            raise _fail(source, f"{key}.kind", f"'sampling' is for the five-bar (metrics.sweeps), got a {kind}")
        sname = _string(source, f"{key}.name", table.get("name"), tuple(SAMPLINGS))
        sampling = SAMPLINGS[sname]
        pts = sampling.points((0.10, 0.15, 0.03))
        probe = sampling.points((0.09, 0.11, 0.05))
        if probe.shape != pts.shape or not np.array_equal(probe, pts):
            raise _fail(source, f"{key}.name", f"sampling {sname!r} gives each design its own points; a study "
                                               f"needs one sample set (use a normalised or fixed-box sampling)")
        return Workspace("sampling", pts, f"sampling {sname!r}: {sampling.description}", sampling, len(pts), 1)
    onames = _orientation_names(mech)
    if wkind == "points":
        raw = table.get("points")
        full_poses = bool(onames) and "orientations" not in table
        width = len(mech.task_names) if full_poses else len(names)
        what = "full task points (mm, deg)" if full_poses else "positions in mm"
        if not isinstance(raw, list) or not raw:
            raise _fail(source, f"{key}.points", f"needs a list of {what}, got {raw!r}")
        rows = np.array([_numbers(source, f"{key}.points", p, width) for p in raw], float)
        if full_poses:                  # whole poses given: no orientation sampling
            from kinematics.base import task_to_si
            pts = task_to_si(mech, rows)
            for n, v in _table(source, f"{key}.centre", table.get("centre", {})).items():
                if n not in names:
                    raise _fail(source, f"{key}.centre.{n}", f"is not a position coordinate; expected one of "
                                                             f"{list(names)}")
                pts[:, mech.task_names.index(n)] += _number(source, f"{key}.centre.{n}", v) / 1000.0
            return Workspace("points", pts, f"{len(pts)} listed poses", None, len(pts), 1)
        pos = rows / 1000.0
        desc = f"{len(pos)} listed points"
    elif wkind == "preset_map":
        if preset is None:
            raise _fail(source, f"{key}.kind", "'preset_map' needs [mechanism] preset")
        pos, desc = _grid_points(source, table, mech, preset.grid)
        desc = f"preset map: {desc}"
    else:
        pos, desc = _grid_points(source, table, mech)
    centre = _table(source, f"{key}.centre", table.get("centre", {}))
    for n, v in centre.items():
        if n not in names:
            raise _fail(source, f"{key}.centre.{n}", f"is not a position coordinate; expected one of {list(names)}")
        pos[:, names.index(n)] += _number(source, f"{key}.centre.{n}", v) / 1000.0
    if centre:
        desc += ", centred at " + ", ".join(f"{n} + {v:g} mm" for n, v in centre.items())
    if onames:
        if "orientations" not in table:
            raise _fail(source, f"{key}.orientations", f"is missing: the task has orientation coordinates {list(onames)}")
        ori = _parse_orientations(source, table["orientations"], mech)
        o = table["orientations"]
        desc += f" x {len(ori)} orientations (tip bound {o['tip_bound']:g} deg, N = {o['rings']})"
    elif "orientations" in table:
        raise _fail(source, f"{key}.orientations", f"does not apply: the task {list(mech.task_names)} has no orientation")
    else:
        ori = np.zeros((1, 0))
    # points: position-major, orientation fastest; columns in the task's order
    p, k = len(pos), len(ori)
    full = np.empty((p * k, len(mech.task_names)))
    for j, n in enumerate(mech.task_names):
        if n in names:
            full[:, j] = np.repeat(pos[:, names.index(n)], k)
        else:
            full[:, j] = np.tile(ori[:, onames.index(n)], p)
    return Workspace(wkind, full, desc, None, p, k)


def _parse_objective(source: str, table: Any, mech: MechanismBase) -> Objective:
    key = "objective"
    table = _table(source, key, table, {"kind", "direction", "infeasible", "threshold", "S_T", "frame", "top_k"})
    kind = _string(source, f"{key}.kind", table.get("kind"), OBJECTIVES)
    direction = table.get("direction", DIRECTIONS[kind])
    if direction != DIRECTIONS[kind]:
        raise _fail(source, f"{key}.direction", f"must be {DIRECTIONS[kind]!r} for {kind} (the search maximises a "
                                                f"minimum over the workspace, or minimises a count), got {direction!r}")
    top_k = int(_number(source, f"{key}.top_k", table.get("top_k", 5), positive=True, integer=True))
    threshold = s_t = None
    frame = "base"
    for k in ("threshold",):
        if k in table and kind != "count_condition_above":
            raise _fail(source, f"{key}.{k}", "applies to count_condition_above only")
    for k in ("S_T", "frame"):
        if k in table and kind != "gii":
            raise _fail(source, f"{key}.{k}", "applies to gii only")
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
            full = np.asarray(gii_mod.HUMAN_HAND_S_T)
            order = ("x", "y", "z", "rx", "ry", "rz")
            if not set(mech.task_names) <= set(order):
                raise _fail(source, f"{key}.S_T", f"'human_hand' needs task coordinates among {order}")
            s_t = tuple(float(full[order.index(n)]) for n in mech.task_names)
        elif isinstance(raw, list) and len(raw) == m and all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0 for v in raw):
            s_t = tuple(float(v) for v in raw)
        else:
            raise _fail(source, f"{key}.S_T", f"needs 'human_hand' or {m} positive numbers (SI) for the task "
                                              f"rows {list(mech.task_names)}, got {raw!r}")
        default = "end_effector" if _orientation_names(mech) else "base"
        frame = _string(source, f"{key}.frame", table.get("frame", default), ("base", "end_effector"))
        if frame == "end_effector" and not _orientation_names(mech):
            raise _fail(source, f"{key}.frame", "'end_effector' needs a task with orientation coordinates")
    return Objective(kind, DIRECTIONS[kind], infeasible, top_k, threshold, s_t, frame)


def _grid_dict(source: str, key: str, table: Any, params: tuple[GridParameter, ...], extra: set[str]) -> dict:
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


def _parse_report(source: str, table: Any, params: tuple[GridParameter, ...]) -> Report:
    key = "report"
    table = _table(source, key, table, {"reference", "tolerance", "smallest", "checks"})
    reference = _grid_dict(source, f"{key}.reference", table["reference"], params, set()) if "reference" in table else None
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
    table = _table(source, key, table, {"key", "values", "paper", "unit"})
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
    return Series(skey, values, str(table.get("unit", unit)), paper)


def _with_series_value(data: dict, series: Series, value: float) -> dict:
    out = copy.deepcopy(data)
    out.pop("series", None)
    parts = series.key.split(".")
    if parts[0] == "workspace":
        out.setdefault("workspace", {}).setdefault("centre", {})[parts[2]] = value
    else:
        out.setdefault("mechanism", {}).setdefault("parameters", {})[parts[2]] = value
    return out


def parse_study(data: dict, source: str, key: str = "", *, load_preset: Callable[[str], Any] | None = None,
                text: str = "") -> Study:
    """Validate a parsed TOML study and build it.

    ``load_preset(name)`` resolves ``[mechanism] preset`` (``resources.load_preset``: metrics
    does not import resources); it must return an object with ``mechanism`` and ``grid``.
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
    kinds = mechanism_kinds()
    preset = None
    if "preset" in mtable:
        if "kind" in mtable:
            raise _fail(source, "mechanism.kind", "cannot be combined with mechanism.preset (the preset has one)")
        pname = _string(source, "mechanism.preset", mtable["preset"])
        if load_preset is None:
            raise _fail(source, "mechanism.preset", "needs a preset loader (pass load_preset=resources.load_preset)")
        try:
            preset = load_preset(pname)
        except ValueError as exc:
            raise _fail(source, "mechanism.preset", f"cannot be loaded: {exc}") from None
        mech = preset.mechanism
        kind = next((k for k, cls in kinds.items() if isinstance(mech, cls)), type(mech).__name__)
    else:
        kind = _string(source, "mechanism.kind", mtable.get("kind"), tuple(kinds))
        mech = kinds[kind]()
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
    report = _parse_report(source, data["report"], grid) if "report" in data else None
    digest = hashlib.sha1((text or json.dumps(data, sort_keys=True, default=str)).encode()).hexdigest()[:16]
    study = Study(key=key or Path(source).stem, name=name, description=description, source=source, kind=kind,
                  mechanism=mech, parameters=grid, workspace=workspace, objective=objective, report=report,
                  series=series, fingerprint=digest, raw=data)
    if series is not None:
        runs = []
        for v in series.values:
            sub = parse_study(_with_series_value(data, series, v), source, key, load_preset=load_preset)
            runs.append(replace(sub, series=series, series_value=v, fingerprint=f"{digest}-{v!r}"))
        study = replace(study, _runs=tuple(runs))
    return study


def parse_study_text(text: str, source: str, key: str = "", *, load_preset=None) -> Study:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"study '{source}': is not valid TOML: {exc}") from None
    return parse_study(data, source, key, load_preset=load_preset, text=text)


def read_study_file(path: str | Path, *, load_preset=None) -> Study:
    """Load and validate a study from a TOML file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise StudyError(f"study '{path}': cannot be read: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise StudyError(f"study '{path}': is not UTF-8 text (TOML must be): byte 0x{exc.object[exc.start]:02x} "
                         f"at offset {exc.start}") from None
    return parse_study_text(text, str(path), path.stem, load_preset=load_preset)


# ------------------------------------------------------------------------------------------
# Evaluators: f(design, sample) blocks for the searches
# ------------------------------------------------------------------------------------------


class Evaluator:
    """``evaluate(design_ids (k,), sample_ids (m,))`` for a study, plus what the searches need.

    ``samples`` are positions into ``study.workspace.points`` (an evaluator may drop samples
    no design can use, see ``TorqueOnly``); ``values(fields, sample_ids)`` evaluates designs
    given by their SI field values (``Study.field_values``), so designs off the grid (report
    checks) use the same code.
    """

    def __init__(self, study: Study) -> None:
        self.study = study
        self.form = study.objective.form
        self.samples = np.arange(study.n_samples)
        self.note = ""

    @property
    def n_samples(self) -> int:
        return int(self.samples.size)

    def __call__(self, design_ids: np.ndarray, sample_ids: np.ndarray):
        return self.values(self.study.field_values(design_ids), self.samples[sample_ids])

    def values(self, fields: dict[str, np.ndarray], sample_pos: np.ndarray):   # pragma: no cover
        raise NotImplementedError

    def at(self, values: dict[str, float]):
        """Per-sample values of one design given by display values (on the grid or not)."""
        mech = self.study.values_mechanism(values)
        fields = {}
        for p in self.study.parameters:
            for t in p.targets:
                v = getattr(mech.params, t.field)
                fields[t.field] = np.asarray(v, float)[None] if t.index is not None else np.array([float(v)])
        return self.values(fields, self.samples)

    def _finish(self, value: np.ndarray, feasible: np.ndarray) -> np.ndarray:
        """Objective values (k, m) from a quantity and the feasible mask."""
        obj = self.study.objective
        if obj.kind == "count_condition_above":
            with np.errstate(invalid="ignore"):
                return (feasible & (value > obj.threshold)).astype(np.float64)
        return np.where(feasible, value, np.nan)


class FiveBarBatch(Evaluator):
    """Five-bar designs vectorised with ``metrics.design_batch.fivebar_batch``."""

    FIELDS = {"proximal", "distal", "half_base", "motor_torques", "gear_ratios"}

    def __init__(self, study: Study) -> None:
        super().__init__(study)
        self.points = study.workspace.points
        self.sampling = study.workspace.sampling
        self.note = "design-vectorised five-bar (metrics.design_batch)"

    def values(self, fields, sample_pos):
        p = self.study.mechanism.params
        k = next(iter(fields.values())).shape[0]

        def col(name):
            v = fields.get(name)
            return getattr(p, name) if v is None else v.reshape(k, 1)

        a1, a2, a3 = col("proximal"), col("distal"), col("half_base")
        if "motor_torques" in fields or "gear_ratios" in fields:
            motor = fields.get("motor_torques", np.asarray(p.motor_torques, float)[None])
            gear = fields.get("gear_ratios", np.asarray(p.gear_ratios, float)[None])
            t = motor * gear
            t0, t1 = t[:, 0:1], t[:, 1:2]
        else:
            t0, t1 = (m * g for m, g in zip(p.motor_torques, p.gear_ratios))
        pts = self.points[sample_pos]
        px, py = pts[None, :, 0], pts[None, :, 1]
        obj = self.study.objective
        normalised = self.sampling is not None and self.sampling.frame == "normalised"
        if obj.kind == "count_condition_above":
            a1, a2, a3 = (np.broadcast_to(np.asarray(v, float), (k, 1)) for v in (a1, a2, a3))
            if normalised:
                s = (a1 + a2 + a3) / 3.0
                a1, a2, a3 = a1 / s, a2 / s, a3 / s       # metrics.sweeps.Sampling.mechanism
            out = fivebar_batch(a1, a2, a3, pts[None], quantities=("condition_number",),
                                working_mode=p.working_mode)
            return self._finish(out.values["condition_number"], out.feasible)
        if normalised:                                    # physical frame for forces
            s = (np.asarray(a1) + a2 + a3) / 3.0
            px, py = px * s, py * s
        f = isotropic_force_fast(a1, a2, a3, px, py, t0, t1, p.working_mode)
        return np.broadcast_to(f, (k, pts.shape[0]))


class TorqueOnly(Evaluator):
    """Grids that vary torques or gear ratios only, objective ``min_isotropic_force``: the
    geometry, hence J's column norms and the feasible set, is the same for every design, so
    they are computed once; ``F = min_x min_u t_u / |J[:, u]|`` per design is then a few
    array operations. With ``infeasible = "skip"`` the samples outside the feasible set are
    dropped up front (they would be skipped for every design)."""

    def __init__(self, study: Study) -> None:
        super().__init__(study)
        ev = evaluate(study.mechanism, study.workspace.points, ("column_norms",))
        self.norms = ev.values["column_norms"]
        self.feasible = ev.feasible
        if study.objective.infeasible == "skip":
            self.samples = np.flatnonzero(ev.feasible)
        self.note = (f"column norms cached once ({int(ev.feasible.sum())} of {ev.feasible.size} samples feasible"
                     + ("; the others dropped" if study.objective.infeasible == "skip" else "") + ")")

    def values(self, fields, sample_pos):
        p = self.study.mechanism.params
        k = next(iter(fields.values())).shape[0]
        n = len(p.motor_torques)
        motor = fields.get("motor_torques", np.broadcast_to(np.asarray(p.motor_torques, float), (k, n)))
        gear = fields.get("gear_ratios", np.broadcast_to(np.asarray(p.gear_ratios, float), (k, n)))
        t = np.asarray(motor, float) * np.asarray(gear, float)
        mech = self.study.mechanism
        if hasattr(mech, "actuated"):                        # mechanisms with passive joints
            t = t[:, list(mech.actuated)]
        if t.shape[1] != self.norms.shape[1]:                # pragma: no cover - model mismatch
            raise ValueError(f"{t.shape[1]} torque limits for {self.norms.shape[1]} Jacobian columns")
        norms = self.norms[sample_pos]
        with np.errstate(divide="ignore", invalid="ignore"):
            f = np.min(t[:, None, :] / norms[None, :, :], axis=-1)
        return np.where(self.feasible[sample_pos][None, :], f, np.nan)


def _jacobian_at(mech, q, x):
    if "x" in inspect.signature(mech.jacobian).parameters:
        return mech.jacobian(q, x)
    return mech.jacobian(q)


class Generic(Evaluator):
    """Any mechanism and parameter: one model per design, ``metrics.quantities.evaluate`` (or
    the GII's scaled singular values) on the requested samples."""

    CACHE = 64

    def __init__(self, study: Study) -> None:
        super().__init__(study)
        self.points = study.workspace.points
        self._mechs: dict[tuple, MechanismBase] = {}
        self._lock = threading.Lock()
        self.note = "one model per design (metrics.quantities.evaluate)"
        if study.objective.kind == "gii":
            self.note = "one model per design, scaled singular values (metrics.gii)"

    def _mech(self, fields: dict[str, np.ndarray], i: int) -> MechanismBase:
        changes = {}
        for name, v in fields.items():
            row = v[i]
            changes[name] = tuple(float(x) for x in row) if np.ndim(row) else float(row)
        key = tuple(sorted(changes.items()))
        with self._lock:
            mech = self._mechs.get(key)
        if mech is None:
            mech = self.study.mechanism.replace(**changes)
            with self._lock:
                if len(self._mechs) >= self.CACHE:
                    self._mechs.pop(next(iter(self._mechs)))
                self._mechs[key] = mech
        return mech

    def values(self, fields, sample_pos):
        k = next(iter(fields.values())).shape[0]
        x = self.points[sample_pos]
        obj = self.study.objective
        if obj.kind == "gii":
            a = np.empty((k, x.shape[0]))
            b = np.empty((k, x.shape[0]))
            for i in range(k):
                a[i], b[i] = self._gii_rows(self._mech(fields, i), x)
            return a, b
        q = "condition_number" if obj.kind == "count_condition_above" else "isotropic_force"
        out = np.empty((k, x.shape[0]))
        for i in range(k):
            ev = evaluate(self._mech(fields, i), x, (q,))
            out[i] = self._finish(ev.values[q][None], ev.feasible[None])[0]
        return out

    def _gii_rows(self, mech, x):
        obj = self.study.objective
        qj, ok = mech.inverse(x)
        feas = ok.copy()
        if ok.any():
            feas[ok] = mech.feasible(qj[ok], x[ok])
        a = np.full(x.shape[0], np.nan)
        b = np.full(x.shape[0], np.nan)
        if not feas.any():
            return a, b
        xf, qf = x[feas], qj[feas]
        if mech.is_redundant or mech.has_orientation:           # wrench devices: the paper's force map
            mat, kind = mech.force_map(qf, xf), "force_map"
        else:
            mat, kind = _jacobian_at(mech, qf, xf), "jacobian"
        if obj.frame == "end_effector":
            mat = _rows_in_tool_frame(mech, mat, xf)
        sv = gii_mod.scaled_singular_values(mat, mech.torque_limits(), obj.s_t, kind=kind)
        a[feas], b[feas] = sv[:, -1], sv[:, 0]
        return a, b


def _rows_in_tool_frame(mech, mat: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Task rows in the pen frame (paper 001: "the Jacobian is expressed in the end-effector
    coordinate frame prior to scaling", because Table I is relative to the hand).

    6-DOF rows ``(f, m)`` (or ``(v, omega)``) in the base frame: ``blockdiag(R^T, R^T)``. 5-DOF
    pen rows ``(f, m . a, m . b)`` (``kinematics.twin_pantograph``): the moment rows already are
    pen-frame components, so only the force rows turn, ``R^T f``.
    """
    from kinematics.rotations import rotation_matrix, tilt_matrix

    names = mech.task_names
    if names == ("x", "y", "z", "rx", "ry", "rz"):
        return gii_mod.rotate_task_rows(mat, rotation_matrix(x[..., 3:6]))
    if names == ("x", "y", "z", "rx", "rz"):
        rt = np.swapaxes(tilt_matrix(x[..., 3:5]), -1, -2)
        out = mat.copy()
        out[..., :3, :] = rt @ mat[..., :3, :]
        return out
    raise ValueError(f"frame 'end_effector' needs pen task coordinates, got {names}")


def make_evaluator(study: Study) -> Evaluator:
    """The fastest exact evaluator for the study (see the classes above)."""
    fields = {t.field for p in study.parameters for t in p.targets}
    kind = study.objective.kind
    if kind == "min_isotropic_force" and fields <= {"motor_torques", "gear_ratios"} \
            and study.workspace.sampling is None and not redundant(study.mechanism):
        return TorqueOnly(study)        # (redundant actuation: a zonotope, not J's column norms)
    if isinstance(study.mechanism, FiveBar) and kind != "gii" and fields <= FiveBarBatch.FIELDS \
            and study.mechanism.params.joint_limits is None:
        return FiveBarBatch(study)
    if study.workspace.sampling is not None:
        raise ValueError("a 'sampling' workspace needs the design-vectorised five-bar evaluator")
    return Generic(study)


_EVALUATORS: dict[str, Evaluator] = {}
_EVALUATORS_LOCK = threading.Lock()


def evaluator_for(study: Study) -> Evaluator:
    """``make_evaluator``, built once per process (workers reuse it across chunks)."""
    key = study.fingerprint or str(id(study))
    with _EVALUATORS_LOCK:
        ev = _EVALUATORS.get(key)
    if ev is None:
        ev = make_evaluator(study)
        with _EVALUATORS_LOCK:
            if len(_EVALUATORS) > 16:
                _EVALUATORS.clear()
            _EVALUATORS[key] = ev
    return ev


# ------------------------------------------------------------------------------------------
# The count (sum form): exact culling with partial counts as bounds
# ------------------------------------------------------------------------------------------


def _sum_result(method, t0, D, S, evaluations, keys, exact, probes) -> SearchResult:
    top_values = np.array([-n for n, _ in keys], dtype=np.float64)
    top_designs = np.array([d for _, d in keys], dtype=np.int64)
    value, design = (float(top_values[0]), int(top_designs[0])) if keys else (float("nan"), -1)
    return SearchResult(value=value, design=design, evaluations=evaluations, seconds=time.perf_counter() - t0,
                        top_designs=top_designs, top_values=top_values, n_designs=D, n_samples=S, method=method,
                        exact_designs=exact, probes=np.asarray(probes, np.int64))


def _sum_ids(designs, samples):
    d = np.arange(designs) if isinstance(designs, (int, np.integer)) else np.sort(np.asarray(designs, np.int64))
    s = np.arange(samples) if isinstance(samples, (int, np.integer)) else np.asarray(samples, np.int64)
    if d.size == 0 or s.size == 0:
        raise ValueError(f"designs and samples must be non-empty, got {d.size} and {s.size}")
    return d, s


def _check_counts(block: np.ndarray, k: int, m: int) -> np.ndarray:
    arr = np.asarray(block, dtype=np.float64)
    if arr.shape != (k, m):
        raise ValueError(f"evaluate must return shape ({k}, {m}), got {arr.shape}")
    if not np.all((arr == 0.0) | (arr == 1.0)):
        raise ValueError("a count evaluator must return 0 or 1 per (design, sample)")
    return arr


def count_brute_force(evaluate, designs, samples, *, top_k: int = 1) -> SearchResult:
    """Every design on every sample: ``F = -(number of samples with value 1)``, ranked as in
    ``metrics.culling`` (``F`` descending = count ascending, then id ascending)."""
    t0 = time.perf_counter()
    ids, sids = _sum_ids(designs, samples)
    rows = max(1, BLOCK_PAIRS // sids.size)
    counts = np.zeros(ids.size)
    for start in range(0, ids.size, rows):
        d = ids[start:start + rows]
        counts[start:start + d.size] = _check_counts(evaluate(d, sids), d.size, sids.size).sum(axis=1)
    values = -counts
    order = ranking(values, ids)[:top_k]
    keys = [(-float(values[i]), int(ids[i])) for i in order]
    return _sum_result("brute_force", t0, ids.size, sids.size, ids.size * sids.size, keys, ids.size, [])


def count_search(evaluate, designs, samples, *, top_k: int = 1, initial_samples=None, first_chunk: int = 64,
                 floor: tuple[float, int] | None = None) -> SearchResult:
    """Exact search for the ``top_k`` designs with the smallest count (``F = -count`` largest).

    ``evaluate(design_ids, sample_ids)`` returns 0/1 blocks (1: the sample counts, e.g. its
    condition number exceeds the threshold). The bound: a design evaluated on a prefix of the
    sample order has ``count >= partial``, so ``F <= -partial``; a design whose bound ranks
    after the K-th best exact design (``metrics.culling``'s rule and tie order, and its
    ``floor`` for split runs) is culled. Sample order: ``initial_samples`` (a permutation, e.g.
    ``probes`` of an earlier chunk), else the middle design is evaluated exactly and its
    counted samples go first (they tend to count for its neighbours too). Every design is
    then evaluated on the first ``first_chunk`` samples; best-first, the live design with the
    highest bound evaluates its next chunk (doubling) until it is exact or culled.
    Same result as ``count_brute_force``, exactly (integer sums), with ``probes`` = the order.
    """
    t0 = time.perf_counter()
    ids, sids = _sum_ids(designs, samples)
    D, S = ids.size, sids.size
    top = _TopK(int(top_k), floor)      # the culling search's own K-best list and threshold
    evaluations = 0
    counts = np.zeros(D)
    pos = np.zeros(D, np.int64)
    exact = 0

    def block(dpos, spos):
        nonlocal evaluations
        evaluations += dpos.size * spos.size
        return _check_counts(evaluate(ids[dpos], sids[spos]), dpos.size, spos.size)

    if initial_samples is not None:
        init = np.asarray(initial_samples, np.int64)
        lookup = {int(s): i for i, s in enumerate(sids.tolist())}
        first = [lookup[int(s)] for s in init.tolist() if int(s) in lookup]
        seen = np.zeros(S, bool)
        seen[first] = True
        order = np.concatenate([np.asarray(first, np.int64), np.flatnonzero(~seen)])
        skip = -1
    else:
        skip = D // 2
        row = block(np.array([skip]), np.arange(S))[0]
        order = np.argsort(-row, kind="stable")
        counts[skip], pos[skip] = row.sum(), S
        top.add(-counts[skip], ids[skip])
        exact += 1
    n0 = min(first_chunk, S)
    live = np.flatnonzero(np.arange(D) != skip)
    rows = max(1, BLOCK_PAIRS // n0)
    for start in range(0, live.size, rows):
        dpos = live[start:start + rows]
        counts[dpos] = block(dpos, order[:n0]).sum(axis=1)
        pos[dpos] = n0
    for p in live[pos[live] == S]:
        top.add(-counts[p], ids[p])
        exact += 1
    live = live[pos[live] < S]
    keep = ~top.cullable_array(-counts[live], ids[live])
    heap = list(zip(counts[live[keep]].tolist(), ids[live[keep]].tolist(), live[keep].tolist()))
    heapq.heapify(heap)
    while heap:
        c, d, p = heap[0]
        if top.cullable(-c, d):
            break
        heapq.heappop(heap)
        size = max(first_chunk, int(pos[p]))
        spos = order[pos[p]:pos[p] + size]
        counts[p] += block(np.array([p]), spos)[0].sum()
        pos[p] += spos.size
        if pos[p] == S:
            top.add(-counts[p], d)
            exact += 1
        elif not top.cullable(-counts[p], d):
            heapq.heappush(heap, (float(counts[p]), d, p))
    return _sum_result("culling", t0, D, S, evaluations, top.keys, exact, sids[order])


# ------------------------------------------------------------------------------------------
# Per-design records: what every design ended with
# ------------------------------------------------------------------------------------------


def _ratio(num, den):
    with np.errstate(divide="ignore", invalid="ignore"):
        r = num / den
    return np.where((num == 0.0) | (den == np.inf), 0.0, r)


class Recorder:
    """Wraps an evaluator and keeps, per design of a chunk, the running min (max) and the number
    of samples seen, with ``metrics.culling``'s conventions for infeasible samples. After the
    search, ``records()`` gives each design's exact value (all samples seen) or bound."""

    def __init__(self, evaluate, design_ids: np.ndarray, n_samples: int, form: str, infeasible: str) -> None:
        self.evaluate = evaluate
        self.ids = np.asarray(design_ids, np.int64)
        self.S = n_samples
        self.form = form
        self.fail = infeasible == "fail"
        n = self.ids.size
        self.A = np.full(n, np.inf)
        self.B = np.zeros(n)
        self.sum = np.zeros(n)
        self.seen = np.zeros(n, np.int64)
        self.feasible_seen = np.zeros(n, bool)
        self.bad = np.zeros(n, bool)

    def __call__(self, design_ids, sample_ids):
        out = self.evaluate(design_ids, sample_ids)
        loc = np.searchsorted(self.ids, design_ids)
        self.seen[loc] += len(sample_ids)
        if self.form == "sum":
            self.sum[loc] += np.asarray(out, float).sum(axis=1)
            return out
        if self.form == "ratio":
            a, b = (np.asarray(v, float) for v in out)
            infeas = np.isnan(a) | (a == -np.inf) | np.isnan(b) | (b == -np.inf)
            self.B[loc] = np.maximum(self.B[loc], np.where(infeas, 0.0, b).max(axis=1, initial=0.0))
        else:
            a = np.asarray(out, float)
            infeas = np.isnan(a) | (a == -np.inf)
        self.A[loc] = np.minimum(self.A[loc], np.where(infeas, np.inf, a).min(axis=1, initial=np.inf))
        self.feasible_seen[loc] |= ~infeas.all(axis=1)
        self.bad[loc] |= infeas.any(axis=1)
        return out

    def records(self) -> dict[str, np.ndarray]:
        """``design``, ``exact`` (bool), ``value`` (objective units: a count for the sum form;
        exact, or the bound where not exact), ``samples`` (evaluated)."""
        exact = self.seen == self.S
        if self.form == "sum":
            value = self.sum.copy()
        else:
            u = _ratio(self.A, self.B) if self.form == "ratio" else self.A.copy()
            u = np.where(self.feasible_seen, u, np.where(exact, -np.inf, np.inf))
            if self.fail:
                u = np.where(self.bad, -np.inf, u)
            value = u
        return {"design": self.ids.copy(), "exact": exact, "value": value, "samples": self.seen.copy()}


# ------------------------------------------------------------------------------------------
# Running a study
# ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ChunkOutcome:
    result: SearchResult
    records: dict[str, np.ndarray]
    wall: float


def search_chunk(study: Study, design_ids: np.ndarray, *, method: str = "culling", top_k: int | None = None,
                 floor: tuple[float, int] | None = None, initial_samples=None) -> ChunkOutcome:
    """Search one chunk of design ids exactly (the unit of work a worker runs)."""
    t0 = time.perf_counter()
    ev = evaluator_for(study)
    k = int(top_k or study.objective.top_k)
    rec = Recorder(ev, np.sort(np.asarray(design_ids, np.int64)), ev.n_samples, ev.form, study.objective.infeasible)
    S = ev.n_samples
    ids = rec.ids
    if ev.form == "sum":
        if method == "brute_force":
            res = count_brute_force(rec, ids, S, top_k=k)
        else:
            res = count_search(rec, ids, S, top_k=k, floor=floor, initial_samples=initial_samples)
    else:
        if method == "brute_force":
            res = brute_force(rec, ids, S, form=ev.form, infeasible=study.objective.infeasible, top_k=k)
        else:
            res = culling_search(rec, ids, S, form=ev.form, infeasible=study.objective.infeasible, top_k=k,
                                 floor=floor, initial_samples=initial_samples)
    records = rec.records()
    # The recorder saw exactly what the search saw: the listed designs' values must agree.
    internal = records["value"] if ev.form != "sum" else -records["value"]
    loc = np.searchsorted(ids, res.top_designs)
    if not (np.all(records["exact"][loc]) and np.array_equal(internal[loc], res.top_values)):
        raise RuntimeError("per-design records disagree with the search result: the evaluator is not "
                           "deterministic (a value depends on which pairs share a call)")
    return ChunkOutcome(res, records, time.perf_counter() - t0)


@dataclass(frozen=True)
class ReportResult:
    """Answers to the study's [report] table. Values in objective units (counts positive)."""

    reference: dict[str, float] | None
    reference_value: float | None
    tolerance: float
    target: float | None                   # the value a design must reach (reference within tolerance)
    smallest: str | None
    smallest_design: dict[str, float] | None
    smallest_value: float | None
    checks: list[dict[str, Any]]
    evaluations: int


@dataclass(frozen=True)
class StudyResult:
    """Outcome of ``run_study`` for one study (one series value)."""

    study: Study
    method: str
    top_designs: np.ndarray                # (K,) ids, best first
    top_values: np.ndarray                 # (K,) objective units (counts positive)
    n_designs: int
    n_samples: int                         # samples the search used (see Evaluator)
    evaluations: int
    exact_designs: int
    wall_seconds: float
    work_seconds: float
    chunks: int
    workers: int
    engine: str
    records: dict[str, np.ndarray]         # per design (sorted ids): exact, value, samples
    evaluator_note: str = ""
    report: ReportResult | None = None

    @property
    def brute_force_evaluations(self) -> int:
        """``D * S``: what brute force evaluates (computed, not run)."""
        return self.n_designs * self.n_samples

    @property
    def ratio(self) -> float:
        """Evaluations over brute force's ``D * S``."""
        return self.evaluations / self.brute_force_evaluations

    @property
    def value(self) -> float:
        return float(self.top_values[0])

    @property
    def design(self) -> int:
        return int(self.top_designs[0])

    def top(self) -> list[dict[str, Any]]:
        """The ranking: ``rank``, ``design`` id, each parameter's display value, ``value``."""
        disp = self.study.design_display(self.top_designs)
        return [{"rank": i + 1, "design": int(d), **{k: float(v[i]) for k, v in disp.items()},
                 "value": float(self.top_values[i])} for i, d in enumerate(self.top_designs)]


def _to_objective(study: Study, internal: np.ndarray) -> np.ndarray:
    """Search values (maximised) -> objective units (a count is positive)."""
    return -internal if study.objective.form == "sum" else internal


def plan_chunks(n_designs: int, n_chunks: int, *, warmup: int = 1024) -> list[np.ndarray]:
    """Design ids cut into chunks: a strided *warm-up* chunk spread over the whole design space
    (``min(warmup, n_designs // 8)`` designs), then the rest in ``n_chunks`` contiguous pieces;
    one chunk when ``n_chunks == 1`` and the space is small. The warm-up runs first and alone:
    its K-th best becomes the floor, and its worst samples the probes, of every later chunk,
    which then cull most of their designs on the first probes. Any split gives the same result
    (``merge_top_k``); only the cost changes."""
    ids = np.arange(n_designs, dtype=np.int64)
    size = min(warmup, n_designs // 8)
    if size < 1 or (n_chunks == 1 and n_designs <= 65536):
        return [part for part in np.array_split(ids, n_chunks)]
    stride = n_designs // size
    first = ids[stride // 2::stride][:size]
    mask = np.ones(n_designs, bool)
    mask[first] = False
    rest = ids[mask]
    # Never more pieces than designs left: an empty chunk has nothing to search.
    return [first] + [part for part in np.array_split(rest, min(n_chunks, rest.size)) if part.size]


def default_chunks(n_designs: int, parallel: int) -> int:
    """Chunks to cut a design space into: about 64k designs each, and at least four per worker
    when there are several (so floors from finished chunks reach the later ones)."""
    n = max(1, math.ceil(n_designs / 65536))
    if parallel > 1:
        n = max(n, 4 * parallel)
    return int(min(n, n_designs))


def process_pool(workers: int):
    """A ``ProcessPoolExecutor`` for ``run_study(executor=...)``: spawn start method (no fork of
    a parent that may hold threads, e.g. a Qt app or a dask client)."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor
    return ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                               initializer=_worker_ignores_sigint)


def _worker_ignores_sigint() -> None:
    """In a pool's worker: Ctrl-C (sent by a terminal to the whole process group) is the parent's
    to handle; it stops the workers (``stop_process_pool``) instead of each printing a traceback."""
    import signal
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def stop_process_pool(executor) -> None:
    """Stop a ``process_pool`` now: queued chunks cancelled, running worker processes terminated.

    For an interrupt (Ctrl-C, SIGTERM, MemoryError): ``shutdown(wait=True)`` would wait for every
    running chunk to finish.
    """
    procs = list((getattr(executor, "_processes", None) or {}).values())
    executor.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join(timeout=2.0)


class _LocalPool:
    """A concurrent.futures executor; closed at the end only if ``run_study`` made it."""

    def __init__(self, workers: int, executor=None) -> None:
        self.owned = executor is None
        self.pool = process_pool(workers) if executor is None else executor

    def submit(self, fn, *args, **kwargs):
        return self.pool.submit(fn, *args, **kwargs)

    @staticmethod
    def wait_first(futures):
        from concurrent.futures import FIRST_COMPLETED, wait
        done, _ = wait(futures, return_when=FIRST_COMPLETED)
        return done

    def close(self) -> None:
        if self.owned:
            self.pool.shutdown(wait=True, cancel_futures=True)

    def abort(self) -> None:
        """Interrupted: stop an owned pool's processes at once (a caller's pool is the caller's)."""
        if self.owned:
            stop_process_pool(self.pool)
            self.owned = False


class _DaskPool:
    def __init__(self, client) -> None:
        self.client = client

    def submit(self, fn, *args, **kwargs):
        return self.client.submit(fn, *args, pure=False, **kwargs)

    @staticmethod
    def wait_first(futures):
        from distributed import wait
        done, _ = wait(list(futures), return_when="FIRST_COMPLETED")
        return done

    def close(self) -> None:
        pass

    def abort(self) -> None:
        pass


def dask_threads(client) -> int:
    """Total worker threads of a dask client's cluster."""
    info = client.scheduler_info()
    workers = info.get("workers", {}) if isinstance(info, dict) else {}
    return max(1, sum(int(w.get("nthreads", 1)) for w in workers.values()))


def run_study(study: Study, *, workers: int = 1, client=None, executor=None, chunks: int | None = None,
              method: str = "culling",
              top_k: int | None = None, progress: Callable[[dict], None] | None = None,
              max_probes: int = 32, with_report: bool = True) -> StudyResult:
    """Search ``study`` (one series value; see ``Study.runs``) exactly.

    Parameters
    ----------
    workers : local worker processes (1: this process, no pool).
    client : a ``dask.distributed.Client``; chunks run on its cluster (``workers`` unused).
    executor : a ``concurrent.futures`` executor of ``workers`` processes to use (and leave
        open), e.g. ``process_pool(n)`` shared by the runs of a series; default: one is made.
    chunks : how many chunks to cut the design ids into (default ``default_chunks``).
    method : ``"culling"`` or ``"brute_force"`` (every design on every sample).
    top_k : designs to rank (default the study's ``top_k``).
    progress : called with a dict (``chunks_done``, ``chunks``, ``designs_done``, ``designs``,
        ``evaluations``, ``seconds``) after each chunk.
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    if study._runs:
        raise ValueError("run_study takes one study of a series; loop over study.runs()")
    k = int(top_k or study.objective.top_k)
    if k < 1:
        raise ValueError(f"top_k must be a positive integer, got {top_k!r}")
    t0 = time.perf_counter()
    D = study.n_designs
    # Local processes beyond the CPU count, or beyond the designs, only add start-up time.
    parallel = dask_threads(client) if client is not None else max(1, min(int(workers), os.cpu_count() or 1, D))
    n_chunks = int(chunks) if chunks is not None else default_chunks(D, parallel)
    if not 1 <= n_chunks <= D:
        raise ValueError(f"chunks must be between 1 and the {D} designs, got {chunks!r}")
    parts = plan_chunks(D, n_chunks) if chunks is None else np.array_split(np.arange(D, dtype=np.int64), n_chunks)
    n_chunks = len(parts)
    local_ev = evaluator_for(study)
    S = local_ev.n_samples
    from .budget import check_fits, study_estimate
    check_fits(study_estimate(D, S, len(study.mechanism.task_names), workers=parallel if client is None else 1),
               advice="use a coarser design grid or workspace, or fewer workers")
    if client is not None:
        pool, engine = _DaskPool(client), "dask"
    elif parallel > 1 and n_chunks > 1:
        pool, engine = _LocalPool(min(parallel, n_chunks), executor), "processes"
    else:
        pool, engine = None, "single process"
    outcomes: list[ChunkOutcome] = []
    done_designs = 0

    def state():
        if not outcomes:
            return None, None
        merged = merge_top_k([o.result for o in outcomes], top_k=k)
        floor = merged.kth if len(merged.top_designs) == k else None
        probes = merged.probes[:max_probes] if study.objective.form != "sum" else merged.probes[:S]
        return floor, (probes if probes.size else None)

    def report(o: ChunkOutcome):
        nonlocal done_designs
        outcomes.append(o)
        done_designs += o.result.n_designs
        if progress is not None:
            progress({"chunks_done": len(outcomes), "chunks": n_chunks, "designs_done": done_designs,
                      "designs": D, "evaluations": sum(x.result.evaluations for x in outcomes),
                      "seconds": time.perf_counter() - t0})

    if pool is None:
        for ids in parts:
            floor, probes = state()
            report(search_chunk(study, ids, method=method, top_k=k, floor=floor, initial_samples=probes))
    else:
        try:
            queue = list(parts)
            running = set()
            slots = min(parallel, n_chunks)
            if len(parts) > 1 and parts[0].size != parts[1].size and chunks is None:
                report(pool.submit(search_chunk, study, queue.pop(0), method=method, top_k=k).result())
            while queue or running:
                while queue and len(running) < slots:
                    floor, probes = state()
                    running.add(pool.submit(search_chunk, study, queue.pop(0), method=method, top_k=k,
                                            floor=floor, initial_samples=probes))
                for fut in pool.wait_first(running):
                    running.discard(fut)
                    report(fut.result())
        except BaseException:
            pool.abort()
            raise
        finally:
            pool.close()
    merged = merge_top_k([o.result for o in outcomes], top_k=k)
    keep = merged.top_designs >= 0
    rec = {name: np.concatenate([o.records[name] for o in outcomes]) for name in outcomes[0].records}
    order = np.argsort(rec["design"], kind="stable")
    rec = {name: v[order] for name, v in rec.items()}
    result = StudyResult(
        study=study, method=method, top_designs=merged.top_designs[keep],
        top_values=_to_objective(study, merged.top_values[keep]), n_designs=D, n_samples=S,
        evaluations=merged.evaluations, exact_designs=int(rec["exact"].sum()),
        wall_seconds=time.perf_counter() - t0, work_seconds=float(sum(o.wall for o in outcomes)),
        chunks=n_chunks, workers=(parallel if pool is not None else 1), engine=engine, records=rec,
        evaluator_note=local_ev.note)
    if with_report and study.report is not None:
        result = replace(result, report=study_report(study, result))
    return result


def _worst_samples(form: str, out, fail: bool) -> list[int]:
    """Positions (within a block of one design) of the samples that lower its bound most:
    the counted ones (sum), the smallest value (min; an infeasible one first under "fail"),
    the smallest numerator and the largest denominator (ratio)."""
    if form == "sum":
        return [int(np.argmax(np.asarray(out)[0]))]
    a = np.asarray(out[0] if form == "ratio" else out, float)[0]
    bad = np.isnan(a) | (a == -np.inf)
    picks = [int(np.argmin(np.where(bad, -np.inf if fail else np.inf, a)))]
    if form == "ratio":
        b = np.asarray(out[1], float)[0]
        bad |= np.isnan(b) | (b == -np.inf)
        picks.append(int(np.argmax(np.where(bad, -np.inf, b))))
    return picks


def first_reaching(study: Study, ev: Evaluator, parameter: str, target: float, *,
                   first_chunk: int = 32, max_probes: int = 8) -> tuple[tuple[int, float] | None, int]:
    """The best design at the smallest value of ``parameter`` whose search value reaches
    ``target`` (``F >= target``, ``F`` maximised as in the searches), and the evaluations spent.

    Exact without assuming ``F`` monotone in the parameter: designs are visited in ascending
    parameter value (then id); each is evaluated on the probes (the samples that dropped
    earlier designs) and then on the rest in doubling chunks, and dropped as soon as its
    upper bound (``Recorder``) falls below ``target``. The first parameter value with a
    design that completes at ``F >= target`` is the answer; the other designs at that value
    are finished too, and the best of them (ranking order) is returned.
    """
    D, S = study.n_designs, ev.n_samples
    col = study.design_display(np.arange(D))[parameter]
    sign = -1.0 if ev.form == "sum" else 1.0
    fail = study.objective.infeasible == "fail"
    probes: list[int] = []
    evaluations = 0
    found: list[tuple[float, int]] = []
    stop_at = None
    for d in np.lexsort((np.arange(D), col)).tolist():
        if stop_at is not None and col[d] != stop_at:
            break
        rec = Recorder(ev, np.array([d]), S, ev.form, study.objective.infeasible)
        todo = np.ones(S, bool)
        first = np.asarray(probes, np.int64)
        chunk = first_chunk
        reached = True
        while todo.any():
            if first.size:
                spos, first = first, first[:0]
            else:
                spos = np.flatnonzero(todo)[:chunk]
                chunk *= 2
            out = rec(np.array([d]), spos)
            evaluations += spos.size
            todo[spos] = False
            if sign * rec.records()["value"][0] < target:
                reached = False
                for w in _worst_samples(ev.form, out, fail):
                    if int(spos[w]) not in probes:
                        probes.insert(0, int(spos[w]))
                del probes[max_probes:]
                break
        if reached:
            found.append((float(sign * rec.records()["value"][0]), d))
            stop_at = col[d]
    if not found:
        return None, evaluations
    value, d = min(found, key=lambda vd: (-vd[0], vd[1]))
    return (d, value), evaluations


def study_report(study: Study, result: StudyResult) -> ReportResult:
    """The [report] table's answers, all by exact evaluation (no monotonicity assumed).

    ``smallest``: ``first_reaching`` (the smallest value of the named parameter at which some
    design reaches ``target``, the reference's value within the relative tolerance).
    """
    rep = study.report
    ev = evaluator_for(study)
    S = ev.n_samples
    evaluations = 0
    sign = -1.0 if study.objective.form == "sum" else 1.0    # search maximises sign * value

    def value_at(values: dict[str, float]) -> float:
        nonlocal evaluations
        out = ev.at(values)
        evaluations += S
        if ev.form == "sum":
            return float(np.asarray(out).sum())
        if ev.form == "ratio":
            rec = Recorder(lambda d, s: out, np.array([0]), S, "ratio", study.objective.infeasible)
        else:
            rec = Recorder(lambda d, s: out, np.array([0]), S, "min", study.objective.infeasible)
        rec(np.array([0]), np.arange(S))
        return float(rec.records()["value"][0])

    ref_value = target = None
    smallest_design = smallest_value = None
    if rep.reference is not None:
        ref_value = value_at(rep.reference)
        target = ref_value - rep.tolerance * abs(ref_value) if sign > 0 else ref_value + rep.tolerance * abs(ref_value)
    if rep.smallest is not None and target is not None and np.isfinite(target):
        found, count = first_reaching(study, ev, rep.smallest, sign * target)
        evaluations += count
        if found is not None:
            d, internal = found
            smallest_design = {k: float(v[0]) for k, v in study.design_display([d]).items()}
            smallest_value = float(sign * internal)
    checks = []
    for c in rep.checks:
        v = value_at(c.values)
        entry: dict[str, Any] = {"label": c.label, **c.values, "value": v}
        if ref_value is not None:
            entry["vs_reference"] = v / ref_value - 1.0 if ref_value else float("nan")
            entry["reaches"] = bool(v >= target) if sign > 0 else bool(v <= target)
        checks.append(entry)
    return ReportResult(rep.reference, ref_value, rep.tolerance, target, rep.smallest, smallest_design,
                        smallest_value, checks, evaluations)
