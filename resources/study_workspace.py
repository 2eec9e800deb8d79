"""``[workspace]`` of a study file (and ``[workspace.orientations]``): where each design is judged."""
from __future__ import annotations

from typing import Any

from kinematics.base import MechanismBase
from kinematics.grid import GridSpec

from .study_file import WORKSPACE_KINDS, OrientationEntry, WorkspaceEntry, study_error
from .study_values import read_number, read_numbers, read_string, read_table

POSITION_NAMES = ("x", "y", "z")


def orientation_names(mech: MechanismBase) -> tuple[str, ...]:
    return tuple(n for n in mech.task_names if n not in POSITION_NAMES)


def _parse_orientations(source: str, table: Any, mech: MechanismBase) -> OrientationEntry:
    """``[workspace.orientations]`` validated (the samples are made by ``metrics.design``)."""
    key = "workspace.orientations"
    table = read_table(source, key, table, {"tip_bound", "rings", "roll", "rule", "tool_axis"})
    names = orientation_names(mech)
    for k in ("tip_bound", "rings"):
        if k not in table:
            raise study_error(source, f"{key}.{k}", "is missing")
    bound = read_number(source, f"{key}.tip_bound", table["tip_bound"], positive=True)
    if bound >= 180:
        raise study_error(source, f"{key}.tip_bound", f"must be below 180 deg, got {bound!r}")
    rings = int(read_number(source, f"{key}.rings", table["rings"], positive=True, integer=True))
    roll = read_numbers(source, f"{key}.roll", table.get("roll", [0.0]))
    if names != ("rx", "ry", "rz") and any(r != 0 for r in roll):
        raise study_error(source, f"{key}.roll",
                          f"must be [0] for a task without roll ({', '.join(names)}), got {roll!r}")
    rule = table.get("rule", "exact")                 # one of metrics.orientations.RULES, checked there
    axis = read_numbers(source, f"{key}.tool_axis", table.get("tool_axis", [0.0, 1.0, 0.0]), 3)
    return OrientationEntry(float(bound), rings, tuple(float(r) for r in roll), rule, tuple(float(a) for a in axis))


def _grid_spec(source: str, table: dict, mech: MechanismBase, grid: GridSpec | None = None) -> GridSpec:
    """The workspace grid (m): from ``axes``/``lower``/``upper``/``resolution``/``fixed`` (mm), or a
    preset's ``grid`` with an optional ``resolution``."""
    key = "workspace"
    names = tuple(n for n in mech.task_names if n in POSITION_NAMES)
    if grid is None:
        for k in ("axes", "lower", "upper", "resolution"):
            if k not in table:
                raise study_error(source, f"{key}.{k}", "is missing")
        axes = table["axes"]
        if (not isinstance(axes, list) or len(axes) not in (2, 3) or len(set(axes)) != len(axes)
                or any(a not in names for a in axes)):
            raise study_error(source, f"{key}.axes", f"needs 2 or 3 distinct names from {list(names)}, got {axes!r}")
        k = len(axes)
        lower = read_numbers(source, f"{key}.lower", table["lower"], k)
        upper = read_numbers(source, f"{key}.upper", table["upper"], k)
        res = read_numbers(source, f"{key}.resolution", table["resolution"], k, integer=True)
        for i, a in enumerate(axes):
            if not lower[i] < upper[i]:
                raise study_error(source, f"{key}.upper",
                            f"must exceed {key}.lower on axis {a!r}, got {lower[i]} >= {upper[i]}")
            if not 2 <= res[i] <= 20000:
                raise study_error(source, f"{key}.resolution",
                                  f"needs 2 to 20000 points per axis, got {res[i]} on {a!r}")
        fixed = read_table(source, f"{key}.fixed", table.get("fixed", {}))
        rest = [n for n in names if n not in axes]
        if sorted(fixed) != sorted(rest):
            raise study_error(source, f"{key}.fixed", f"needs exactly the coordinates {rest} (mm), got {sorted(fixed)}")
        for n, v in fixed.items():
            read_number(source, f"{key}.fixed.{n}", v)
        grid = GridSpec(tuple(axes), tuple(v / 1000.0 for v in lower), tuple(v / 1000.0 for v in upper),
                        tuple(res), tuple((n, fixed[n] / 1000.0) for n in rest))
    elif "resolution" in table:
        r = table["resolution"]
        res = [r] * len(grid.axes) if isinstance(r, int) and not isinstance(r, bool) else r
        res = read_numbers(source, f"{key}.resolution", res, len(grid.axes), integer=True)
        if any(not 2 <= v <= 20000 for v in res):
            raise study_error(source, f"{key}.resolution", f"needs 2 to 20000 points per axis, got {r!r}")
        grid = grid.with_resolution(tuple(res))
    return grid


def _centre(source: str, key: str, table: Any, names: tuple[str, ...]) -> tuple[tuple[str, float], ...]:
    out = []
    for n, v in read_table(source, key, table).items():
        if n not in names:
            raise study_error(source, f"{key}.{n}", f"is not a position coordinate; expected one of {list(names)}")
        out.append((n, float(read_number(source, f"{key}.{n}", v))))
    return tuple(out)


def parse_workspace(source: str, table: Any, mech: MechanismBase, preset) -> WorkspaceEntry:
    key = "workspace"
    allowed = {"kind", "axes", "lower", "upper", "resolution", "fixed", "centre", "name", "points", "orientations"}
    table = read_table(source, key, table, allowed)
    wkind = read_string(source, f"{key}.kind", table.get("kind"), WORKSPACE_KINDS)
    by_kind = {"grid": {"axes", "lower", "upper", "resolution", "fixed", "centre", "orientations"},
               "preset_map": {"resolution", "centre", "orientations"},
               "sampling": {"name"}, "points": {"points", "centre", "orientations"}}
    for k in table:
        if k != "kind" and k not in by_kind[wkind]:
            raise study_error(source, f"{key}.{k}", f"does not apply to a {wkind!r} workspace; it takes "
                                              f"{', '.join(sorted(by_kind[wkind]))}")
    names = tuple(n for n in mech.task_names if n in POSITION_NAMES)
    if wkind == "sampling":
        return WorkspaceEntry("sampling", sampling=table.get("name"))     # checked by metrics.design
    onames = orientation_names(mech)
    grid = None
    rows: tuple = ()
    if wkind == "points":
        raw = table.get("points")
        full_poses = bool(onames) and "orientations" not in table
        width = len(mech.task_names) if full_poses else len(names)
        what = "full task points (mm, deg)" if full_poses else "positions in mm"
        if not isinstance(raw, list) or not raw:
            raise study_error(source, f"{key}.points", f"needs a list of {what}, got {raw!r}")
        rows = tuple(tuple(float(v) for v in read_numbers(source, f"{key}.points", p, width)) for p in raw)
        if full_poses:                  # whole poses given: no orientation sampling
            centre = _centre(source, f"{key}.centre", table.get("centre", {}), names)
            return WorkspaceEntry("points", points=rows, full_poses=True, centre=centre)
    elif wkind == "preset_map":
        if preset is None:
            raise study_error(source, f"{key}.kind", "'preset_map' needs [mechanism] preset")
        grid = _grid_spec(source, table, mech, preset.grid)
    else:
        grid = _grid_spec(source, table, mech)
    centre = _centre(source, f"{key}.centre", table.get("centre", {}), names)
    ori = None
    if onames:
        if "orientations" not in table:
            raise study_error(source, f"{key}.orientations",
                        f"is missing: the task has orientation coordinates {list(onames)}")
        ori = _parse_orientations(source, table["orientations"], mech)
    elif "orientations" in table:
        raise study_error(source, f"{key}.orientations",
                    f"does not apply: the task {list(mech.task_names)} has no orientation")
    return WorkspaceEntry(wkind, grid=grid, points=rows, centre=centre, orientations=ori)
