"""``[grid]`` of a study file: the design space, each entry a range, a list or tied targets."""
from __future__ import annotations

import math
from decimal import Decimal, InvalidOperation
from typing import Any

from kinematics.base import MechanismBase

from .study_file import CHECK_EVERY_VALUE, MAX_DESIGNS, GridEntry, Target, study_error
from .study_values import param_info, read_number, read_numbers, read_table


def _range(source: str, key: str, spec: dict) -> tuple[str, str, int]:
    """``min``, ``max``, ``step`` -> ``(start, step, count)``, exact decimals as text, both ends
    included (``GridEntry.values`` makes the values)."""
    for k in ("min", "max", "step"):
        if k not in spec:
            raise study_error(source, f"{key}.{k}", "is missing (a range needs min, max and step, or give values)")
        read_number(source, f"{key}.{k}", spec[k], positive=(k == "step"))
    lo, hi, step = (Decimal(repr(float(spec[k]))) for k in ("min", "max", "step"))
    if hi < lo:
        raise study_error(source, f"{key}.max", f"must be at least {key}.min, got {spec['max']!r} < {spec['min']!r}")
    try:
        n = (hi - lo) / step
    except InvalidOperation:      # pragma: no cover
        n = Decimal("nan")
    if n != n.to_integral_value():
        raise study_error(source, f"{key}.step",
                          f"must divide max - min = {hi - lo} into whole steps, got {spec['step']!r}")
    count = int(n) + 1
    if count > MAX_DESIGNS:
        raise study_error(source, key, f"has {count} values, more than a study can hold")
    return str(lo), str(step), count


def _grid_values(source: str, key: str, spec: Any) -> tuple[tuple[float, ...] | None, str, str, int]:
    """A grid entry's values: ``(listed, start, step, count)``, ``listed`` None for a range."""
    if isinstance(spec, list):
        vals = read_numbers(source, key, spec)
    elif isinstance(spec, dict) and "values" in spec:
        extra = sorted(set(spec) - {"values", "targets", "unit"})
        if extra:
            raise study_error(source, f"{key}.{extra[0]}", "cannot be combined with values")
        vals = read_numbers(source, f"{key}.values", spec["values"])
    elif isinstance(spec, dict):
        extra = sorted(set(spec) - {"min", "max", "step", "targets", "unit"})
        if extra:
            raise study_error(source, f"{key}.{extra[0]}",
                              "is not a grid key; expected min, max, step (or values), targets")
        start, step, count = _range(source, key, spec)
        return None, start, step, count
    else:
        raise study_error(source, key,
                          f"needs {{min, max, step}}, {{values = [...]}} or a list of numbers, got {spec!r}")
    if len(set(vals)) != len(vals):
        raise study_error(source, key, f"must not repeat a value, got {vals!r}")
    return tuple(float(v) for v in vals), "", "", len(vals)


def target(source: str, key: str, mech: MechanismBase, text: str) -> Target:
    name, _, label = text.partition(".")
    info = param_info(mech, name)
    numeric = [i.name for i in mech.PARAM_INFO if not i.choices]
    if info is None or info.choices:
        raise study_error(source, key, f"names {text!r}, which is not a numeric parameter of {type(mech).__name__}; "
                                 f"expected one of {', '.join(numeric)}")
    if info.is_vector:
        if not label:
            raise study_error(source, key, f"names the vector parameter {name!r}; name an entry: "
                                     f"{', '.join(name + '.' + lab for lab in info.labels)}")
        if label not in info.labels:
            raise study_error(source, key,
                              f"names entry {label!r} of {name!r}; expected one of {', '.join(info.labels)}")
        return Target(name, info.labels.index(label), text)
    if label:
        raise study_error(source, key, f"names {text!r}, but {name!r} is a scalar parameter")
    return Target(name, None, text)


def parse_grid(source: str, table: Any, mech: MechanismBase) -> tuple[GridEntry, ...]:
    table = read_table(source, "grid", table)
    if not table:
        raise study_error(source, "grid", "needs at least one parameter")
    out: list[GridEntry] = []
    entries: list[tuple] = []
    for name, spec in table.items():
        key = f"grid.{name}"
        info = param_info(mech, name)
        if isinstance(spec, dict) and "targets" in spec:
            texts = spec["targets"]
            if not isinstance(texts, list) or not texts or not all(isinstance(t, str) for t in texts):
                raise study_error(source, f"{key}.targets", f"needs a list of parameter names, got {texts!r}")
            targets = tuple(target(source, f"{key}.targets", mech, t) for t in texts)
            grid_list = [(name, key, spec, targets)]
        elif info is not None and info.is_vector and isinstance(spec, dict) and not (set(spec) & {"min", "values"}):
            grid_list = []
            for label, sub in spec.items():
                text = f"{name}.{label}"
                grid_list.append((text, f"{key}.{label}", sub, (target(source, f"{key}.{label}", mech, text),)))
        else:
            grid_list = [(name, key, spec, (target(source, key, mech, name),))]
        entries.extend(grid_list)
    total = math.prod(c for c in (_spec_count(e[2]) for e in entries) if c is not None)   # Python ints: exact
    if total > MAX_DESIGNS:
        raise study_error(source, "grid", f"spans {total:,} designs, more than {MAX_DESIGNS:,}: use coarser steps or "
                                    f"fewer parameters")
    for pname, pkey, pspec, targets in entries:
        units = {param_info(mech, t.field).unit for t in targets}
        if len(units) != 1:
            raise study_error(source, pkey, f"ties parameters of different units {sorted(units)}")
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
                    apply_target(mech, t, v)
                except ValueError as exc:
                    raise study_error(source, pkey, f"value {v!r} is out of range: {exc}") from None
        if any(p.name == pname for p in out):
            raise study_error(source, pkey, "is given twice")
        out.append(entry)
    seen: dict[tuple, str] = {}
    for p in out:
        for t in p.targets:
            k = (t.field, t.index)
            if k in seen:
                raise study_error(source, f"grid.{p.name}", f"sets {t.label!r}, which grid.{seen[k]} sets too")
            seen[k] = p.name
    total = math.prod(p.count for p in out)
    if total > MAX_DESIGNS:
        raise study_error(source, "grid", f"spans {total:,} designs, more than {MAX_DESIGNS:,}")
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


def apply_target(mech: MechanismBase, t: Target, display_value: float) -> MechanismBase:
    if t.index is None:
        return mech.replace_display(**{t.field: display_value})
    info = param_info(mech, t.field)
    vec = [info.from_si(v) for v in getattr(mech.params, t.field)]
    vec[t.index] = display_value
    return mech.replace_display(**{t.field: vec})
