"""Design studies as TOML data: reading and validating a study file (``load_study``).

A study names the mechanism, the parameter grid, the workspace and the objective. This
module turns the file into validated plain data, a ``StudyFile`` of numbers, strings,
``kinematics`` models and ``kinematics.grid.GridSpec`` grids; ``metrics.design.build_study``
makes the searchable ``metrics.design.Study`` from it (sample points, orientation samples,
memory checks). ``resources`` depends on ``kinematics`` only. One module per table
(``study_grid``, ``study_workspace``, ``study_objective``, ``study_report``) validates it.

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

import hashlib
import json
import tomllib
from dataclasses import replace
from importlib import resources as _res
from pathlib import Path

from kinematics.registry import MECHANISMS, kind_of

from .schema import load_preset
from .study_file import StudyError, StudyFile, study_error
from .study_grid import parse_grid
from .study_objective import parse_objective
from .study_report import parse_report, parse_series, with_series_value
from .study_values import param_info, read_string, read_table
from .study_workspace import parse_workspace

_TOP_KEYS = {"name", "description", "mechanism", "grid", "workspace", "objective", "report", "series"}


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
        raise study_error(source, unknown[0], f"is not a study key; expected one of {', '.join(sorted(_TOP_KEYS))}")
    for k in ("mechanism", "grid", "workspace", "objective"):
        if k not in data:
            raise study_error(source, k, "is missing")
    name = data.get("name", key or Path(source).stem)
    read_string(source, "name", name)
    description = read_string(source, "description", data.get("description", ""))
    mtable = read_table(source, "mechanism", data["mechanism"], {"preset", "kind", "parameters"})
    preset = None
    if "preset" in mtable:
        if "kind" in mtable:
            raise study_error(source, "mechanism.kind", "cannot be combined with mechanism.preset (the preset has one)")
        pname = read_string(source, "mechanism.preset", mtable["preset"])
        try:
            preset = load_preset(pname)
        except ValueError as exc:
            raise study_error(source, "mechanism.preset", f"cannot be loaded: {exc}") from None
        mech = preset.mechanism
        kind = kind_of(mech)
    else:
        kind = read_string(source, "mechanism.kind", mtable.get("kind"), tuple(MECHANISMS))
        mech = MECHANISMS[kind]()
    params = read_table(source, "mechanism.parameters", mtable.get("parameters", {}))
    for pname, value in params.items():
        info = param_info(mech, pname)
        if info is None:
            raise study_error(source, f"mechanism.parameters.{pname}", f"is not a parameter of {kind}; expected one of "
                                                                 f"{', '.join(i.name for i in mech.PARAM_INFO)}")
        try:
            mech = mech.replace_display(**{pname: value})
        except ValueError as exc:
            raise study_error(source, f"mechanism.parameters.{pname}", f"is out of range: {exc}") from None
    series = parse_series(source, data["series"], mech) if "series" in data else None
    grid = parse_grid(source, data["grid"], mech)
    objective = parse_objective(source, data["objective"])
    workspace = parse_workspace(source, data["workspace"], mech, preset)
    report = parse_report(source, data["report"], grid) if "report" in data else None
    digest = hashlib.sha1((text or json.dumps(data, sort_keys=True, default=str)).encode()).hexdigest()[:16]
    study_file = StudyFile(key=key or Path(source).stem, name=name, description=description, source=source, kind=kind,
                     mechanism=mech, grid=grid, workspace=workspace, objective=objective, report=report,
                     series=series, fingerprint=digest, raw=data)
    if series is not None:
        runs = []
        for i, v in enumerate(series.values):
            sub = study_from_data(with_series_value(data, series, i), source, key)
            runs.append(replace(sub, series=series, series_value=v, fingerprint=f"{digest}-{v!r}"))
        study_file = replace(study_file, runs=tuple(runs))
    return study_file


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
