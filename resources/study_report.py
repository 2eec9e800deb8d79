"""``[report]`` and ``[series]`` of a study file: designs to evaluate beside the optimum, and one
optimization per value of a series."""
from __future__ import annotations

import copy
from typing import Any

from kinematics.base import MechanismBase

from .study_file import Check, GridEntry, Report, Series, study_error
from .study_values import param_info, read_number, read_numbers, read_string, read_table
from .study_workspace import POSITION_NAMES


def _grid_dict(source: str, key: str, table: Any, params: tuple[GridEntry, ...], extra: set[str]) -> dict:
    table = read_table(source, key, table)
    names = {p.name for p in params}
    out = {}
    for k, v in table.items():
        if k in extra:
            continue
        if k not in names:
            raise study_error(source, f"{key}.{k}", f"is not a grid parameter; expected {', '.join(sorted(names))}")
        out[k] = float(read_number(source, f"{key}.{k}", v))
    missing = sorted(names - set(out))
    if missing:
        raise study_error(source, key, f"must give every grid parameter; {missing[0]!r} is missing")
    return out


def parse_report(source: str, table: Any, params: tuple[GridEntry, ...]) -> Report:
    key = "report"
    table = read_table(source, key, table, {"reference", "tolerance", "smallest", "checks"})
    reference = (_grid_dict(source, f"{key}.reference", table["reference"], params, set())
                 if "reference" in table else None)
    tol = float(read_number(source, f"{key}.tolerance", table.get("tolerance", 1e-3)))
    if tol < 0:
        raise study_error(source, f"{key}.tolerance", f"must be >= 0, got {tol!r}")
    smallest = table.get("smallest")
    if smallest is not None:
        read_string(source, f"{key}.smallest", smallest, tuple(p.name for p in params))
        if reference is None:
            raise study_error(source, f"{key}.smallest", "needs report.reference (the value to reach)")
    checks = []
    raw = table.get("checks", [])
    if not isinstance(raw, list):
        raise study_error(source, f"{key}.checks", f"must be a list of tables, got {raw!r}")
    for i, c in enumerate(raw):
        ck = f"{key}.checks[{i}]"
        c = read_table(source, ck, c)
        label = read_string(source, f"{ck}.label", c.get("label", f"check {i + 1}"))
        checks.append(Check(label, _grid_dict(source, ck, c, params, {"label"})))
    return Report(reference, tol, smallest, tuple(checks))


def parse_series(source: str, table: Any, mech: MechanismBase) -> Series:
    key = "series"
    table = read_table(source, key, table, {"key", "values", "paper", "unit", "parameters"})
    skey = read_string(source, f"{key}.key", table.get("key"))
    values = tuple(float(v) for v in read_numbers(source, f"{key}.values", table.get("values")))
    paper = table.get("paper")
    if paper is not None:
        paper = tuple(float(v) for v in read_numbers(source, f"{key}.paper", paper, len(values)))
    parts = skey.split(".")
    if parts[:2] == ["workspace", "centre"] and len(parts) == 3 and parts[2] in POSITION_NAMES:
        unit = "mm"
    elif parts[:2] == ["mechanism", "parameters"] and len(parts) == 3:
        info = param_info(mech, parts[2])
        if info is None or info.is_vector or info.choices:
            raise study_error(source, f"{key}.key", f"names {parts[2]!r}, not a scalar numeric parameter of "
                                              f"{type(mech).__name__}")
        unit = info.unit
    else:
        raise study_error(source, f"{key}.key", f"must be 'workspace.centre.<x|y|z>' or 'mechanism.parameters.<name>', "
                                          f"got {skey!r}")
    per_value = []
    for name, vals in read_table(source, f"{key}.parameters", table.get("parameters", {})).items():
        pkey = f"{key}.parameters.{name}"
        info = param_info(mech, name)
        if info is None or info.is_vector or info.choices:
            raise study_error(source, pkey, f"names {name!r}, not a scalar numeric parameter of {type(mech).__name__}")
        if parts[:2] == ["mechanism", "parameters"] and parts[2] == name:
            raise study_error(source, pkey, f"is the series key {skey!r} itself")
        nums = tuple(float(v) for v in read_numbers(source, pkey, vals, len(values)))
        for v in nums:
            try:
                mech.replace_display(**{name: v})
            except ValueError as exc:
                raise study_error(source, pkey, f"value {v!r} is out of range: {exc}") from None
        per_value.append((name, nums))
    return Series(skey, values, str(table.get("unit", unit)), paper, tuple(per_value))


def with_series_value(data: dict, series: Series, index: int) -> dict:
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
