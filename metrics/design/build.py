"""Building a searchable ``Study`` from a validated study file (``resources.load_study``).

``resources`` reads and validates the TOML into plain data (``resources.StudyFile``); this
module makes what needs the compute layer: the grid values in SI (after the memory check
of ``metrics.budget``), the workspace sample points, paper 001's orientation samples
(``metrics.orientations``), the five-bar samplings (``metrics.sweeps``) and the
``human_hand`` task scaling (``metrics.gii``). Its errors name the file and key, as the
reader's do (``study_file.error``).
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from kinematics.arrays import FloatArray
from kinematics.base import MechanismBase, task_to_si

from .objective_rules import build_objective
from .study import GridParameter, Study, Workspace

_POSITION_NAMES = ("x", "y", "z")


def _to_si(mech: MechanismBase, fieldname: str, value: float) -> float:
    return next(i for i in mech.PARAM_INFO if i.name == fieldname).to_si(value)


def _check_design_count(study_file) -> None:
    """Refuse a design grid too large to hold, before any of its values are made
    (``metrics.budget.study_estimate`` without samples; the workspace is checked when the
    study runs, ``run_study``)."""
    from ..budget import BudgetError, check_fits, study_estimate

    try:
        check_fits(study_estimate(study_file.n_designs, 0, 0), advice="use coarser steps or fewer parameters")
    except BudgetError as exc:
        raise study_file.error("grid", f"is too large: {exc}") from None


def _grid_parameters(study_file) -> tuple[GridParameter, ...]:
    _check_design_count(study_file)
    out = []
    for e in study_file.grid:
        vals = e.values()
        if e.listed is None and len(set(vals)) != len(vals):
            raise study_file.error(f"grid.{e.name}", f"must not repeat a value, got {vals!r}")
        si = [_to_si(study_file.mechanism, e.targets[0].field, v) for v in vals]
        out.append(GridParameter(e.name, e.targets, e.unit, tuple(vals), tuple(si)))
    return tuple(out)


def _orientations(study_file) -> FloatArray:
    """Orientation coordinates (K, r) of the pen samples (paper 001 eqs. 14-16)."""
    from ..orientations import RULES, orientation_samples

    key = "workspace.orientations"
    o = study_file.workspace.orientations
    mech = study_file.mechanism
    names = tuple(n for n in mech.task_names if n not in _POSITION_NAMES)
    if not isinstance(o.rule, str) or o.rule not in RULES:
        raise study_file.error(f"{key}.rule", f"must be one of {', '.join(map(repr, RULES))}, got {o.rule!r}")
    try:
        samples = orientation_samples(math.radians(o.tip_bound), o.rings, roll=np.radians(o.roll), rule=o.rule,
                                      tool_axis=list(o.tool_axis))
    except ValueError as exc:
        raise study_file.error(key, f"is not valid: {exc}") from None
    if names == ("rx", "rz"):
        tilt = samples.tilt_vectors
        if np.max(np.abs(tilt[:, 1])) > 1e-12:
            raise study_file.error(f"{key}.tool_axis",
                                   "must be the pen axis y = [0, 1, 0] for a task with tilts (rx, rz)")
        return tilt[:, [0, 2]]
    if names == ("rx", "ry", "rz"):
        from kinematics.rotations import rotation_vector
        return rotation_vector(samples.rotations)
    raise study_file.error(key, f"needs a task with orientation coordinates (rx, rz) or (rx, ry, rz), "
                          f"got {', '.join(mech.task_names)}")


def _grid_positions(study_file, names: tuple[str, ...]) -> tuple[FloatArray, str]:
    """Positions (P, len(names)) of the workspace grid, m, and their description."""
    from ..budget import BudgetError, check_fits, grid_points, study_estimate

    grid = study_file.workspace.grid
    try:
        check_fits(study_estimate(1, grid_points(grid.resolution), len(study_file.mechanism.task_names)),
                   advice="use a coarser workspace resolution")
    except BudgetError as exc:
        raise study_file.error("workspace.resolution", f"is too large: {exc}") from None
    pos = grid.points(names).reshape(-1, len(names))
    desc = (f"{' x '.join(str(r) for r in grid.resolution)} grid over "
            + ", ".join(f"{a} in [{lo * 1e3:g}, {hi * 1e3:g}] mm"
                        for a, lo, hi in zip(grid.axes, grid.lower, grid.upper))
            + "".join(f", {n} = {v * 1e3:g} mm" for n, v in grid.fixed))
    return pos, desc


def _sampling_workspace(study_file) -> Workspace:
    from ..sweeps import DESIGN_PARAMETERS, SAMPLED_TASK, SAMPLINGS

    key = "workspace"
    mech = study_file.mechanism
    if tuple(mech.task_names) != SAMPLED_TASK or not set(DESIGN_PARAMETERS) <= {i.name for i in mech.PARAM_INFO}:
        raise study_file.error(f"{key}.kind", f"'sampling' needs a planar task {SAMPLED_TASK} and the link lengths "
                                        f"{', '.join(DESIGN_PARAMETERS)} (the five-bar's, metrics.sweeps), "
                                        f"got a {study_file.kind}")
    sname = study_file.workspace.sampling
    if not isinstance(sname, str) or sname not in SAMPLINGS:
        raise study_file.error(f"{key}.name", f"must be one of {', '.join(map(repr, tuple(SAMPLINGS)))}, got {sname!r}")
    sampling = SAMPLINGS[sname]
    pts = sampling.points((0.10, 0.15, 0.03))
    probe = sampling.points((0.09, 0.11, 0.05))
    if probe.shape != pts.shape or not np.array_equal(probe, pts):
        raise study_file.error(f"{key}.name", f"sampling {sname!r} gives each design its own points; a study "
                                        f"needs one sample set (use a normalised or fixed-box sampling)")
    return Workspace("sampling", pts, f"sampling {sname!r}: {sampling.description}", sampling, len(pts), 1)


def _workspace(study_file) -> Workspace:
    """The sample points (S, m) in SI: positions major, orientations fastest, task order."""
    ws = study_file.workspace
    mech = study_file.mechanism
    if ws.kind == "sampling":
        return _sampling_workspace(study_file)
    names = tuple(n for n in mech.task_names if n in _POSITION_NAMES)
    onames = tuple(n for n in mech.task_names if n not in _POSITION_NAMES)
    if ws.kind == "points" and ws.full_poses:          # whole poses given: no orientation sampling
        pts = task_to_si(mech, np.array(ws.points, float))
        for n, v in ws.centre:
            pts[:, mech.task_names.index(n)] += v / 1000.0
        return Workspace("points", pts, f"{len(pts)} listed poses", None, len(pts), 1)
    if ws.kind == "points":
        pos = np.array(ws.points, float) / 1000.0
        desc = f"{len(pos)} listed points"
    else:
        pos, desc = _grid_positions(study_file, names)
        if ws.kind == "preset_map":
            desc = f"preset map: {desc}"
    for n, v in ws.centre:
        pos[:, names.index(n)] += v / 1000.0
    if ws.centre:
        desc += ", centred at " + ", ".join(f"{n} + {v:g} mm" for n, v in ws.centre)
    if onames:
        ori = _orientations(study_file)
        desc += f" x {len(ori)} orientations (tip bound {ws.orientations.tip_bound:g} deg, N = {ws.orientations.rings})"
    else:
        ori = np.zeros((1, 0))
    p, k = len(pos), len(ori)
    full = np.empty((p * k, len(mech.task_names)))
    for j, n in enumerate(mech.task_names):
        if n in names:
            full[:, j] = np.repeat(pos[:, names.index(n)], k)
        else:
            full[:, j] = np.tile(ori[:, onames.index(n)], p)
    return Workspace(ws.kind, full, desc, None, p, k)


def build_study(study_file: Any) -> Study:
    """The searchable study of a validated study file.

    Parameters
    ----------
    study_file : resources.StudyFile
        From ``resources.load_study`` (or ``resources.study_schema.parse_study_text``).

    Returns
    -------
    Study
        With one built study per series value in ``runs()``.

    Raises
    ------
    resources.StudyError
        The grid or workspace is too large for memory, or the workspace's samples cannot be
        made; the message names the file and key.
    """
    grid = _grid_parameters(study_file)
    objective = build_objective(study_file)
    workspace = _workspace(study_file)
    runs = tuple(build_study(r) for r in study_file.runs)
    f = study_file
    return Study(key=f.key, name=f.name, description=f.description, source=f.source, kind=f.kind,
                 mechanism=f.mechanism, parameters=grid, workspace=workspace, objective=objective,
                 report=f.report, series=f.series, series_value=f.series_value,
                 fingerprint=f.fingerprint, raw=f.raw, _runs=runs, study_file=f)
