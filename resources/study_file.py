"""A validated study file as plain data (``StudyFile``): numbers, strings, ``kinematics`` models
and grids. ``resources.study_schema`` makes it from TOML; ``metrics.design.build_study`` makes
the searchable study from it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from decimal import Decimal
from typing import Any

from kinematics.base import MechanismBase
from kinematics.grid import GridSpec

WORKSPACE_KINDS = ("grid", "preset_map", "sampling", "points")
#: Largest design space a study may have.
MAX_DESIGNS = 1 << 31
#: Ranges longer than this are checked at their ends only (every valid set is an interval).
CHECK_EVERY_VALUE = 4096


class StudyError(ValueError):
    """A study file that cannot be used; the message names the file and key."""


def study_error(source: str, key: str, message: str) -> StudyError:
    """``StudyError("study '<source>': key '<key>' <message>")``."""
    return StudyError(f"study '{source}': key '{key}' {message}")


@dataclass(frozen=True)
class Target:
    """One mechanism parameter (``field``) or one entry of a vector parameter (``index``)."""

    field: str
    index: int | None
    label: str             # as written: "proximal" or "gear_ratios.theta_0"


@dataclass(frozen=True)
class GridEntry:
    """A design variable as written: its name, the mechanism entries it sets, and its values.

    ``listed`` holds explicit values (display units); a range keeps ``start`` and ``step``
    (exact decimals, as text) and ``count``, so a long range is not made until it is needed
    (``values``).
    """

    name: str
    targets: tuple[Target, ...]
    unit: str
    count: int
    listed: tuple[float, ...] | None = None
    start: str = ""
    step: str = ""

    def values(self) -> list[float]:
        """The display values, shape (count,): the list, or the range with both ends included."""
        if self.listed is not None:
            return list(self.listed)
        lo, step = Decimal(self.start), Decimal(self.step)
        return [float(lo + i * step) for i in range(self.count)]


@dataclass(frozen=True)
class OrientationEntry:
    """``[workspace.orientations]``: paper 001's pen orientation sampling (eqs. 14-16), deg."""

    tip_bound: float
    rings: int
    roll: tuple[float, ...]
    rule: Any
    tool_axis: tuple[float, float, float]


@dataclass(frozen=True)
class WorkspaceEntry:
    """``[workspace]``: a grid (``grid``, m), listed ``points`` (mm, or mm and deg for whole
    poses), or a named five-bar ``sampling``; ``centre`` shifts position coordinates (mm)."""

    kind: str
    grid: GridSpec | None = None
    points: tuple[tuple[float, ...], ...] = ()
    full_poses: bool = False
    centre: tuple[tuple[str, float], ...] = ()
    orientations: OrientationEntry | None = None
    sampling: Any = None                  # a name of metrics.sweeps.SAMPLINGS, checked there


@dataclass(frozen=True)
class ObjectiveEntry:
    """``[objective]`` as read: typed values, ``None`` where the file leaves a key out.

    ``metrics.design.objective_rules.build_objective`` gives them meaning (which kinds
    exist, which settings each takes, the defaults). ``S_T`` is either numbers (``s_t``, SI)
    or a name (``s_t_name``: ``"human_hand"``, paper 001 Table I; ``"hand_velocity"``, eq. 27).
    """

    kind: str
    direction: str | None
    infeasible: str | None
    top_k: int
    threshold: float | None = None
    s_t: tuple[float, ...] | None = None
    s_t_name: str | None = None
    frame: str | None = None
    max_apparent_mass: float | None = None   # kg: a design above it at any sample is infeasible


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
    #: Per-value mechanism parameters (display units), ``(name, one value per series value)``.
    parameters: tuple[tuple[str, tuple[float, ...]], ...] = ()


@dataclass(frozen=True)
class StudyFile:
    """A validated study file. ``runs`` holds one spec per series value (empty without one)."""

    key: str
    name: str
    description: str
    source: str
    kind: str                             # mechanism kind key (kinematics.registry)
    mechanism: MechanismBase              # base model (grid values replace its parameters)
    grid: tuple[GridEntry, ...]
    workspace: WorkspaceEntry
    objective: ObjectiveEntry
    report: Report | None = None
    series: Series | None = None
    series_value: float | None = None
    fingerprint: str = ""
    raw: dict = field(default_factory=dict, repr=False, compare=False)
    runs: tuple["StudyFile", ...] = field(default=(), repr=False, compare=False)

    @property
    def n_designs(self) -> int:
        """Designs of the grid, an exact Python int."""
        return math.prod(e.count for e in self.grid)

    def error(self, key: str, message: str) -> StudyError:
        """A ``StudyError`` naming this study's file and ``key``."""
        return study_error(self.source, key, message)
