"""Building a searchable ``Study`` from a validated study file (``resources.load_study``).

``resources`` reads and validates the TOML into plain data (``resources.StudyFile``); this
module makes what needs the compute layer: the grid values in SI (after the memory check
of ``metrics.budget``), the workspace sample points, paper 001's orientation samples
(``metrics.orientations``), the five-bar samplings (``metrics.sweeps``) and the
``human_hand`` task scaling (``metrics.gii``). Its errors name the file and key, as the
reader's do (``spec.error``).
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


def _check_design_count(spec) -> None:
    """Refuse a design grid too large to hold, before any of its values are made
    (``metrics.budget.study_estimate`` without samples; the workspace is checked when the
    study runs, ``run_study``)."""
    from ..budget import BudgetError, check_fits, study_estimate

    try:
        check_fits(study_estimate(spec.n_designs, 0, 0), advice="use coarser steps or fewer parameters")
    except BudgetError as exc:
        raise spec.error("grid", f"is too large: {exc}") from None


def _grid_parameters(spec) -> tuple[GridParameter, ...]:
    _check_design_count(spec)
    out = []
    for e in spec.grid:
        vals = e.values()
        if e.listed is None and len(set(vals)) != len(vals):
            raise spec.error(f"grid.{e.name}", f"must not repeat a value, got {vals!r}")
        si = [_to_si(spec.mechanism, e.targets[0].field, v) for v in vals]
        out.append(GridParameter(e.name, e.targets, e.unit, tuple(vals), tuple(si)))
    return tuple(out)


def _orientations(spec) -> FloatArray:
    """Orientation coordinates (K, r) of the pen samples (paper 001 eqs. 14-16)."""
    from ..orientations import RULES, orientation_samples

    key = "workspace.orientations"
    o = spec.workspace.orientations
    mech = spec.mechanism
    names = tuple(n for n in mech.task_names if n not in _POSITION_NAMES)
    if not isinstance(o.rule, str) or o.rule not in RULES:
        raise spec.error(f"{key}.rule", f"must be one of {', '.join(map(repr, RULES))}, got {o.rule!r}")
    try:
        samples = orientation_samples(math.radians(o.tip_bound), o.rings, roll=np.radians(o.roll), rule=o.rule,
                                      tool_axis=list(o.tool_axis))
    except ValueError as exc:
        raise spec.error(key, f"is not valid: {exc}") from None
    if names == ("rx", "rz"):
        tilt = samples.tilt_vectors
        if np.max(np.abs(tilt[:, 1])) > 1e-12:
            raise spec.error(f"{key}.tool_axis", "must be the pen axis y = [0, 1, 0] for a task with tilts (rx, rz)")
        return tilt[:, [0, 2]]
    if names == ("rx", "ry", "rz"):
        from kinematics.rotations import rotation_vector
        return rotation_vector(samples.rotations)
    raise spec.error(key, f"needs a task with orientation coordinates (rx, rz) or (rx, ry, rz), "
                          f"got {', '.join(mech.task_names)}")


def _grid_positions(spec, names: tuple[str, ...]) -> tuple[FloatArray, str]:
    """Positions (P, len(names)) of the workspace grid, m, and their description."""
    from ..budget import BudgetError, check_fits, grid_points, study_estimate

    grid = spec.workspace.grid
    try:
        check_fits(study_estimate(1, grid_points(grid.resolution), len(spec.mechanism.task_names)),
                   advice="use a coarser workspace resolution")
    except BudgetError as exc:
        raise spec.error("workspace.resolution", f"is too large: {exc}") from None
    pos = grid.points(names).reshape(-1, len(names))
    desc = (f"{' x '.join(str(r) for r in grid.resolution)} grid over "
            + ", ".join(f"{a} in [{lo * 1e3:g}, {hi * 1e3:g}] mm"
                        for a, lo, hi in zip(grid.axes, grid.lower, grid.upper))
            + "".join(f", {n} = {v * 1e3:g} mm" for n, v in grid.fixed))
    return pos, desc


def _sampling_workspace(spec) -> Workspace:
    from ..sweeps import DESIGN_PARAMETERS, SAMPLED_TASK, SAMPLINGS

    key = "workspace"
    mech = spec.mechanism
    if tuple(mech.task_names) != SAMPLED_TASK or not set(DESIGN_PARAMETERS) <= {i.name for i in mech.PARAM_INFO}:
        raise spec.error(f"{key}.kind", f"'sampling' needs a planar task {SAMPLED_TASK} and the link lengths "
                                        f"{', '.join(DESIGN_PARAMETERS)} (the five-bar's, metrics.sweeps), "
                                        f"got a {spec.kind}")
    sname = spec.workspace.sampling
    if not isinstance(sname, str) or sname not in SAMPLINGS:
        raise spec.error(f"{key}.name", f"must be one of {', '.join(map(repr, tuple(SAMPLINGS)))}, got {sname!r}")
    sampling = SAMPLINGS[sname]
    pts = sampling.points((0.10, 0.15, 0.03))
    probe = sampling.points((0.09, 0.11, 0.05))
    if probe.shape != pts.shape or not np.array_equal(probe, pts):
        raise spec.error(f"{key}.name", f"sampling {sname!r} gives each design its own points; a study "
                                        f"needs one sample set (use a normalised or fixed-box sampling)")
    return Workspace("sampling", pts, f"sampling {sname!r}: {sampling.description}", sampling, len(pts), 1)


def _workspace(spec) -> Workspace:
    """The sample points (S, m) in SI: positions major, orientations fastest, task order."""
    ws = spec.workspace
    mech = spec.mechanism
    if ws.kind == "sampling":
        return _sampling_workspace(spec)
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
        pos, desc = _grid_positions(spec, names)
        if ws.kind == "preset_map":
            desc = f"preset map: {desc}"
    for n, v in ws.centre:
        pos[:, names.index(n)] += v / 1000.0
    if ws.centre:
        desc += ", centred at " + ", ".join(f"{n} + {v:g} mm" for n, v in ws.centre)
    if onames:
        ori = _orientations(spec)
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


def build_study(spec: Any) -> Study:
    """The searchable study of a validated study file.

    Parameters
    ----------
    spec : resources.StudyFile
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
    grid = _grid_parameters(spec)
    objective = build_objective(spec)
    workspace = _workspace(spec)
    runs = tuple(build_study(r) for r in spec.runs)
    return Study(key=spec.key, name=spec.name, description=spec.description, source=spec.source, kind=spec.kind,
                 mechanism=spec.mechanism, parameters=grid, workspace=workspace, objective=objective,
                 report=spec.report, series=spec.series, series_value=spec.series_value,
                 fingerprint=spec.fingerprint, raw=spec.raw, _runs=runs, spec=spec)
