"""What a design study is: the searchable ``Study`` with its grid, workspace and objective.

``metrics.design.build_study`` makes one from a validated study file
(``resources.load_study``); ``run_study`` searches it.

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
``sensor_gii``             eq. 11 of the velocity map ``K`` scaled by the   max
                           sensor resolutions and the hand's velocities
                           (paper 001 eqs. 23-27, ``metrics.sensor_gii.velocity_gii``)
``min_force_per_apparent_  ``min_x`` isotropic force / largest apparent     max
mass``                     mass (N/kg = m/s^2): the acceleration an
                           isotropic force buys against the heaviest
                           direction (``metrics.quantities``
                           ``isotropic_force``, ``apparent_mass_max``)
=========================  ==============================================  ==============

``max_apparent_mass`` (kg, any kind): a design whose largest apparent mass exceeds it at some
sample is infeasible. Its evaluator returns ``metrics.design.ranking.VETO`` (a count: ``inf``)
for such a (design, sample) pair, whatever ``infeasible`` says, so the design ranks after
every feasible one and the culling search drops it on the first such sample it meets
(``metrics.design.evaluators.ApparentMass``). Both need ``Mechanism.has_mass_model``; the
dynamic quantities cost up to twice the static ones (``docs/dynamics.md``, Cost), so they are
computed only when a study asks.

For ``sensor_gii`` the joint-side sensor resolution of each actuator is taken proportional to
its ``gear_ratios`` entry: identical encoders on every motor, seen through the transmission
(counts per joint radian = counts per motor radian x ratio). A study varies the resolution
ratio ``R_w / R_s`` through the waists' ratios; only the product matters to the index.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from kinematics.arrays import FloatArray
from kinematics.base import MechanismBase

OBJECTIVES = ("min_isotropic_force", "gii", "count_condition_above", "sensor_gii", "min_force_per_apparent_mass")
#: The direction each objective is optimized in (the search maximises F; a count is minimised).
DIRECTIONS = {"min_isotropic_force": "max", "gii": "max", "count_condition_above": "min", "sensor_gii": "max",
              "min_force_per_apparent_mass": "max"}
#: Form of each objective's search (``metrics.design.culling`` forms, and the count's ``"sum"``).
FORMS = {"min_isotropic_force": "min", "gii": "ratio", "count_condition_above": "sum", "sensor_gii": "ratio",
         "min_force_per_apparent_mass": "min"}
UNITS = {"min_isotropic_force": "N", "gii": "", "count_condition_above": "samples", "sensor_gii": "",
         "min_force_per_apparent_mass": "N/kg"}
METHODS = ("culling", "brute_force")
#: What a culled design's stored number means, per objective.
BOUND_MEANING = {
    "min_isotropic_force": "upper bound of the global minimum isotropic force (from the samples evaluated)",
    "gii": "upper bound of the GII (min sigma_min / max sigma_max over the samples evaluated)",
    "count_condition_above": "lower bound of the count (ill-conditioned samples among those evaluated)",
    "sensor_gii": "upper bound of the sensor GII (min sigma_min / max sigma_max over the samples evaluated)",
    "min_force_per_apparent_mass": "upper bound of the global minimum isotropic force per largest apparent mass "
                                   "(from the samples evaluated)",
}


@dataclass(frozen=True)
class GridParameter:
    """A design variable: its name, the mechanism entries it sets, and its values.

    ``display`` holds the values as typed (display units), ``si`` the same in SI.
    """

    name: str
    targets: tuple                        # resources.study_schema.Target: field, index, label
    unit: str
    display: tuple[float, ...]
    si: tuple[float, ...]

    @property
    def size(self) -> int:
        """Number of values.

        Returns
        -------
        int
        """
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
        """``S``, the number of samples.

        Returns
        -------
        int
        """
        return int(self.points.shape[0])


@dataclass(frozen=True)
class Objective:
    """What a study optimizes: ``kind`` (``OBJECTIVES``), its ``direction``, the infeasible
    rule, ``top_k`` designs to rank, and the kind's own settings (``threshold``, ``s_t``, ``frame``)."""

    kind: str
    direction: str
    infeasible: str
    top_k: int
    threshold: float | None = None
    s_t: tuple[float, ...] | None = None
    frame: str = "base"
    max_apparent_mass: float | None = None     # kg (see the module docstring)

    @property
    def uses_mass(self) -> bool:
        """Whether the study needs the apparent mass (a bound, or the force-per-mass kind).

        Returns
        -------
        bool
        """
        return self.max_apparent_mass is not None or self.kind == "min_force_per_apparent_mass"

    @property
    def form(self) -> str:
        """Form of the max-min search: ``"min"``, ``"ratio"`` or ``"sum"`` (the count).

        Returns
        -------
        str
        """
        return FORMS[self.kind]

    @property
    def unit(self) -> str:
        """Unit of the objective's values (``UNITS``): ``"N"``, ``""`` or ``"samples"``.

        Returns
        -------
        str
        """
        return UNITS[self.kind]


@dataclass(frozen=True)
class Study:
    """A validated study. ``runs()`` expands a series into one study per value.

    Examples
    --------
    >>> from types import SimpleNamespace as Target
    >>> from kinematics import FiveBar
    >>> a1 = GridParameter("a1", (Target(field="proximal", index=None),), "mm", (100.0, 120.0), (0.1, 0.12))
    >>> a3 = GridParameter("a3", (Target(field="half_base", index=None),), "mm", (40.0, 50.0, 60.0),
    ...                    (0.04, 0.05, 0.06))
    >>> study = Study("example", "Example", "", "example.toml", "fivebar",
    ...               FiveBar(proximal=0.1, distal=0.1, half_base=0.05), (a1, a3),
    ...               Workspace("points", np.zeros((5, 2)), "5 listed points"),
    ...               Objective("min_isotropic_force", "max", "fail", 1))
    >>> study.shape, study.n_designs, study.n_samples
    ((2, 3), 6, 5)
    >>> study.design_id({"a1": 120.0, "a3": 50.0})
    4
    >>> {k: v.tolist() for k, v in study.design_display([4, 5]).items()}
    {'a1': [120.0, 120.0], 'a3': [50.0, 60.0]}
    >>> {k: v.tolist() for k, v in study.field_values([4]).items()}
    {'proximal': [0.12], 'half_base': [0.05]}
    >>> round(study.design_mechanism(4).params.proximal, 9)
    0.12
    """

    key: str
    name: str
    description: str
    source: str
    kind: str                             # mechanism kind key
    mechanism: MechanismBase              # base model (grid values replace its parameters)
    parameters: tuple[GridParameter, ...]
    workspace: Workspace
    objective: Objective
    report: Any = None                    # resources.study_schema.Report (plain data)
    series: Any = None                    # resources.study_schema.Series
    series_value: float | None = None     # set on the studies ``runs()`` returns
    fingerprint: str = ""
    raw: dict = field(default_factory=dict, repr=False, compare=False)
    _runs: tuple = field(default=(), repr=False, compare=False)
    study_file: Any = field(default=None, repr=False, compare=False)   # the resources.StudyFile it was built from

    def error(self, key: str, message: str) -> ValueError:
        """The file's ``StudyError`` naming ``key`` (a plain ValueError for a study made in code).

        Parameters
        ----------
        key : str
            The study file's key, e.g. ``"grid.a1"``.
        message : str
            What is wrong with it.

        Returns
        -------
        ValueError
            For the caller to raise.
        """
        if self.study_file is not None:
            return self.study_file.error(key, message)
        return ValueError(f"study '{self.source}': key '{key}' {message}")

    @property
    def shape(self) -> tuple[int, ...]:
        """Values per grid parameter: the design grid's shape (C order gives the ids).

        Returns
        -------
        tuple of int
        """
        return tuple(p.size for p in self.parameters)

    @property
    def n_designs(self) -> int:
        """``D``, designs in the grid.

        Returns
        -------
        int
        """
        return int(np.prod(self.shape, dtype=np.int64))

    @property
    def n_samples(self) -> int:
        """Workspace samples as written (the search may drop samples no design can use; see
        ``StudyResult.n_samples``).

        Returns
        -------
        int
        """
        return self.workspace.size

    def runs(self) -> list["Study"]:
        """One study per series value (``[self]`` without a series).

        Returns
        -------
        list of Study
        """
        return list(self._runs) if self._runs else [self]

    def parameter_names(self) -> list[str]:
        """The grid parameters' names, in grid order.

        Returns
        -------
        list of str
        """
        return [p.name for p in self.parameters]

    def design_display(self, ids: Any) -> dict[str, np.ndarray]:
        """Grid values (display units) of design ids, one (k,) array per parameter.

        Parameters
        ----------
        ids : array_like of int, shape (k,)
            Design ids.

        Returns
        -------
        dict of str to ndarray, shape (k,)
        """
        idx = np.unravel_index(np.asarray(ids, dtype=np.int64), self.shape)
        return {p.name: np.asarray(p.display)[i] for p, i in zip(self.parameters, idx)}

    def design_id(self, values: dict[str, float], where: str = "design") -> int:
        """The id of the grid design with these display values (each parameter named).

        Parameters
        ----------
        values : dict of str to float
            Each grid parameter's value in its display unit.
        where : str
            The study file's key for the error message.

        Returns
        -------
        int
        """
        idx = []
        for p in self.parameters:
            if p.name not in values:
                raise self.error(where, f"must give every grid parameter; {p.name!r} is missing")
            hits = np.flatnonzero(np.isclose(np.asarray(p.display), float(values[p.name]), rtol=1e-12, atol=0.0))
            if hits.size != 1:
                raise self.error(f"{where}.{p.name}", f"must be a value of the grid, got {values[p.name]!r}")
            idx.append(int(hits[0]))
        return int(np.ravel_multi_index(idx, self.shape))

    def field_values(self, ids: Any) -> dict[str, np.ndarray]:
        """SI values of every varied mechanism field for design ids: scalar fields (k,),
        vector fields (k, n) with the base model's other entries.

        Parameters
        ----------
        ids : array_like of int, shape (k,)
            Design ids.

        Returns
        -------
        dict of str to ndarray, shape (k,) or (k, n)
        """
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
        """The model with grid parameters at these display values (any value, on the grid or not).

        Parameters
        ----------
        values : dict of str to float
            Each grid parameter's value in its display unit.

        Returns
        -------
        MechanismBase
        """
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
        """The model of one grid design.

        Parameters
        ----------
        design : int
            A design id.

        Returns
        -------
        MechanismBase
        """
        disp = self.design_display([design])
        return self.values_mechanism({k: float(v[0]) for k, v in disp.items()})


def _info(mech: MechanismBase, name: str):
    for info in mech.PARAM_INFO:
        if info.name == name:
            return info
    return None


def _to_si(mech: MechanismBase, fieldname: str, value: float) -> float:
    return _info(mech, fieldname).to_si(value)
