"""Device presets as TOML: reading, validating, writing.

A preset has top-level ``name``, ``mechanism`` (``"inverse3"`` or ``"fivebar"``) and
``description``; a ``[parameters]`` table keyed by the parameter names ``isoforce show``
prints, in display units (mm, deg, N m), plus a family's non-slider ``PRESET_PARAMS`` (e.g. the
serial arm's centres of mass and inertia tensors, which the app's parameter panel does not
show); a ``[map]`` table (``axes``, ``lower``, ``upper``, ``resolution``, optional ``fixed``);
an optional ``[pose]`` table with ``at``; an optional ``[motors]`` table with ``max_speeds`` (each
motor's largest speed, rad/s at the motor, m/s for a linear motor, one per ``gear_ratios`` entry: the
joint's is that over its gear ratio; the model's ``motor_speeds``) and its ``source``. Task
coordinates are in mm, orientation coordinates of pen mechanisms (``task_units`` "rad")
in deg. Every error names the file, the key, what was expected and what was found.
"""
from __future__ import annotations

import tomllib
from dataclasses import dataclass
from importlib import resources as _res
from pathlib import Path
from typing import Any

from kinematics.base import MechanismBase, task_from_si, task_scales, task_to_si
from kinematics.grid import GridSpec

# The one registry of mechanism kinds lives in kinematics (re-exported here for presets).
from kinematics.registry import MECHANISMS  # noqa: E402
from kinematics.validation import check_number, validate_number_list

from .spec_table import DeviceSpec, parse_spec, spec_lines

_TOP_KEYS = {"name", "mechanism", "description", "parameters", "map", "pose", "source", "spec", "motors"}
_MOTOR_KEYS = {"max_speeds", "source"}
_MAP_KEYS = {"axes", "lower", "upper", "resolution", "fixed"}


class PresetError(ValueError):
    """A preset file that cannot be used; the message names the file and key."""


@dataclass(frozen=True)
class Preset:
    """A device: its model, its default map and pose (m), and where it came from."""

    key: str
    name: str
    description: str
    mechanism: MechanismBase
    grid: GridSpec
    pose: tuple[float, ...] | None
    source: str
    #: The ``[source]`` table (where the numbers come from), flattened: ``(dotted key, value)``
    #: pairs in file order, a value a string, a number or a tuple of them.
    provenance: tuple[tuple[str, Any], ...] = ()
    #: The ``[spec]`` table (``resources.spec_table``): mass matrix, minimum forces; None if absent.
    spec: DeviceSpec | None = None
    #: Where the ``[motors]`` table's speeds come from ("" without one).
    motor_speeds_source: str = ""

    @property
    def motor_speeds(self) -> tuple[float, ...] | None:
        """The ``[motors]`` table's speeds, rad/s at each motor (m/s for a linear motor), as the model
        carries them (``params.motor_speeds``, one per joint; ``joint_speed_limits`` divides them by the
        gear ratios); None where the preset gives none."""
        return getattr(self.mechanism.params, "motor_speeds", None)

    @property
    def kind(self) -> str:
        return next(k for k, cls in MECHANISMS.items() if isinstance(self.mechanism, cls))

    def replace(self, **changes) -> "Preset":
        from dataclasses import replace
        return replace(self, **changes)


def _fail(source: str, key: str, message: str) -> PresetError:
    return PresetError(f"preset '{source}': key '{key}' {message}")


def _numbers(source: str, key: str, value: Any, count: int, *, integer: bool = False) -> list:
    try:
        return validate_number_list(value, name=f"key '{key}'", count=count, integer=integer)
    except ValueError as exc:
        raise PresetError(f"preset '{source}': {exc}") from None


def _number(source: str, key: str, value: Any, unit: str, *, finite: bool = False) -> None:
    try:
        check_number(value, name=f"key '{key}'", unit=unit, finite=finite)
    except ValueError as exc:
        raise PresetError(f"preset '{source}': {exc}") from None


def parse_preset(data: dict, source: str, key: str = "") -> Preset:
    """Validate a parsed TOML document and build the preset."""
    unknown = sorted(set(data) - _TOP_KEYS)
    if unknown:
        raise _fail(source, unknown[0], f"is not a preset key; expected one of {', '.join(sorted(_TOP_KEYS))}")
    kind = data.get("mechanism")
    if kind not in MECHANISMS:
        raise _fail(source, "mechanism", f"must be one of {', '.join(repr(k) for k in MECHANISMS)}, got {kind!r}")
    cls = MECHANISMS[kind]
    name = data.get("name", key or source)
    if not isinstance(name, str):
        raise _fail(source, "name", f"must be a string, got {name!r}")
    params = data.get("parameters", {})
    if not isinstance(params, dict):
        raise _fail(source, "parameters", f"must be a table, got {params!r}")
    mech = cls()
    infos = {info.name: info for info in cls.PARAM_INFO}
    extra = {info.name: info for info in preset_params(cls)}
    for pname, value in params.items():
        info = infos.get(pname) or extra.get(pname)
        if info is None:
            raise _fail(source, f"parameters.{pname}",
                        f"is not a parameter of {kind}; expected one of {', '.join([*infos, *extra])}")
        if info.is_vector:
            numbers = _numbers(source, f"parameters.{pname}", value, len(info.labels))
        elif not info.choices:
            _number(source, f"parameters.{pname}", value, info.unit or "no unit")
        try:
            if pname in extra:        # not in PARAM_INFO: convert here (every PRESET_PARAMS row is a vector)
                mech = mech.replace(**{pname: tuple(info.to_si(float(v)) for v in numbers)})
            else:
                mech = mech.replace_display(**{pname: value})
        except ValueError as exc:
            raise _fail(source, f"parameters.{pname}", f"is out of range: {exc}") from None
    grid = _parse_map(data.get("map"), source, mech)
    pose = None
    if "pose" in data:
        table = data["pose"]
        if not isinstance(table, dict) or set(table) != {"at"}:
            raise _fail(source, "pose", f"must be a table with the single key 'at', got {table!r}")
        pose = tuple(float(v) for v in task_to_si(mech, _numbers(source, "pose.at", table["at"], mech.task_dim)))
    description = data.get("description", "")
    if not isinstance(description, str):
        raise _fail(source, "description", f"must be a string, got {description!r}")
    provenance = _parse_provenance(data.get("source", {}), source)
    spec = parse_spec(data["spec"], source, mech.task_dim, _fail) if "spec" in data else None
    speeds, speeds_source = _parse_motors(data.get("motors"), source, mech)
    if speeds is not None:
        try:
            mech = mech.replace(motor_speeds=speeds)
        except ValueError as exc:
            raise _fail(source, "motors.max_speeds", f"is out of range: {exc}") from None
    return Preset(key=key or Path(source).stem, name=name, description=description, mechanism=mech,
                  grid=grid, pose=pose, source=source, provenance=provenance, spec=spec,
                  motor_speeds_source=speeds_source)


def _parse_motors(table: Any, source: str, mech: MechanismBase) -> tuple[tuple[float, ...] | None, str]:
    """``[motors]``: ``max_speeds`` (one positive speed per actuator, rad/s at the motor) and ``source``."""
    if table is None:
        return None, ""
    if not isinstance(table, dict):
        raise _fail(source, "motors", f"must be a table with max_speeds and source, got {table!r}")
    unknown = sorted(set(table) - _MOTOR_KEYS)
    if unknown:
        raise _fail(source, f"motors.{unknown[0]}",
                    f"is not a motors key; expected one of {', '.join(sorted(_MOTOR_KEYS))}")
    for needed in sorted(_MOTOR_KEYS):
        if needed not in table:
            raise _fail(source, f"motors.{needed}", "is missing")
    # One per gear ratio, as motor_torques: a model listing its passive joints too (Twin-Pantograph,
    # Inoue) takes one for each, the actuated ones used.
    labels = {info.name: info.labels for info in mech.PARAM_INFO}["gear_ratios"]
    speeds = _numbers(source, "motors.max_speeds", table["max_speeds"], len(labels))
    for label, v in zip(labels, speeds):
        _number(source, f"motors.max_speeds[{label}]", v, "rad/s at the motor", finite=True)
        if not v > 0:
            raise _fail(source, "motors.max_speeds",
                        f"needs positive speeds (rad/s at the motor), got {v!r} for {label}")
    if not isinstance(table["source"], str) or not table["source"].strip():
        raise _fail(source, "motors.source", f"must say where the speeds come from (a string), got {table['source']!r}")
    return tuple(float(v) for v in speeds), table["source"]


def preset_params(cls) -> tuple:
    """A family's ``PRESET_PARAMS``: ParamInfo rows a preset may set that are not in PARAM_INFO.

    They are not sliders (the app's parameter panel builds its rows from PARAM_INFO alone), but a
    preset reads and writes them in their display units like any parameter. Every row is a vector.
    """
    return tuple(getattr(cls, "PRESET_PARAMS", ()))


def _parse_provenance(table: Any, source: str, prefix: str = "source") -> tuple[tuple[str, Any], ...]:
    """The ``[source]`` table flattened to ``(dotted key, value)`` pairs below ``prefix``."""
    if not isinstance(table, dict):
        raise _fail(source, prefix, f"must be a table (repository, path, what was taken), got {table!r}")
    out: list[tuple[str, Any]] = []
    for k, v in table.items():
        name = f"{prefix}.{k}"
        if isinstance(v, dict):
            out += [(f"{k}.{sub}", w) for sub, w in _parse_provenance(v, source, name)]
        elif isinstance(v, (str, int, float)) and not isinstance(v, bool):
            out.append((k, v))
        elif isinstance(v, list) and all(isinstance(w, (str, int, float)) and not isinstance(w, bool) for w in v):
            out.append((k, tuple(v)))
        else:
            raise _fail(source, name, f"must be a string, a number, a list of them or a table, got {v!r}")
    return tuple(out)


def _parse_map(table: Any, source: str, mech: MechanismBase) -> GridSpec:
    if not isinstance(table, dict):
        raise _fail(source, "map", f"must be a table with {', '.join(sorted(_MAP_KEYS - {'fixed'}))}, got {table!r}")
    unknown = sorted(set(table) - _MAP_KEYS)
    if unknown:
        raise _fail(source, f"map.{unknown[0]}", f"is not a map key; expected one of {', '.join(sorted(_MAP_KEYS))}")
    for needed in ("axes", "lower", "upper", "resolution"):
        if needed not in table:
            raise _fail(source, f"map.{needed}", "is missing")
    axes = table["axes"]
    names = mech.task_names
    if (not isinstance(axes, list) or len(axes) not in (2, 3) or len(set(axes)) != len(axes)
            or any(a not in names for a in axes)):
        raise _fail(source, "map.axes", f"needs 2 or 3 distinct names from {list(names)}, got {axes!r}")
    k = len(axes)
    lower = _numbers(source, "map.lower", table["lower"], k)
    upper = _numbers(source, "map.upper", table["upper"], k)
    res = _numbers(source, "map.resolution", table["resolution"], k, integer=True)
    for i, axis in enumerate(axes):
        if not lower[i] < upper[i]:
            raise _fail(source, "map.upper", f"must exceed map.lower on axis {axis!r}, got {lower[i]} >= {upper[i]}")
        if not 2 <= res[i] <= 20000:
            raise _fail(source, "map.resolution", f"needs 2 to 20000 points per axis, got {res[i]} on {axis!r}")
    fixed = table.get("fixed", {})
    if not isinstance(fixed, dict):
        raise _fail(source, "map.fixed", f"must be a table of coordinates in mm, got {fixed!r}")
    rest = [n for n in names if n not in axes]
    if sorted(fixed) != sorted(rest):
        raise _fail(source, "map.fixed", f"needs exactly the coordinates {rest} (mm), got {sorted(fixed)}")
    for n, v in fixed.items():
        _number(source, f"map.fixed.{n}", v, "mm", finite=True)
    scale = {n: float(v) for n, v in zip(names, task_scales(mech))}
    return GridSpec(axes=tuple(axes), lower=tuple(v / scale[a] for a, v in zip(axes, lower)),
                    upper=tuple(v / scale[a] for a, v in zip(axes, upper)),
                    resolution=tuple(res), fixed=tuple((n, fixed[n] / scale[n]) for n in rest))


def read_preset_file(path: str | Path) -> Preset:
    """Load and validate a preset from a TOML file on disk."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise PresetError(f"preset '{path}': cannot be read: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise PresetError(f"preset '{path}': is not UTF-8 text (TOML must be): byte 0x{exc.object[exc.start]:02x} "
                          f"at offset {exc.start}") from None
    return parse_preset_text(text, str(path), path.stem)


def parse_preset_text(text: str, source: str, key: str = "") -> Preset:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise PresetError(f"preset '{source}': is not valid TOML: {exc}") from None
    return parse_preset(data, source, key)


def _toml_value(value: Any) -> str:
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(float(value))      # float(): numpy scalars repr as np.float64(...)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {value!r} to TOML")


def _toml_key(dotted: str) -> str:
    """A flattened provenance key as a TOML dotted key (segments bare where TOML allows)."""
    return ".".join(seg if seg and all(c.isascii() and (c.isalnum() or c in "_-") for c in seg)
                    else _toml_value(seg) for seg in dotted.split("."))


def _shown(value: Any, unit: str) -> str:
    """A parameter's display value as text: ``140 mm``, ``(6.875, 5.957, 5.957)``, ``+-``."""
    if isinstance(value, tuple):
        text = "(" + ", ".join(f"{v:g}" for v in value) + ")"
    else:
        text = f"{value:g}" if isinstance(value, float) else str(value)
    return f"{text} {unit}".rstrip()


def with_changes(preset: Preset, mechanism: MechanismBase) -> Preset:
    """``preset`` with ``mechanism`` (its parameters edited), its ``[source]`` saying what changed.

    The preset's sources describe its own values: each parameter that differs gets a
    ``changed.NAME`` entry ("140 mm in the source above; now 160 mm"), so a file saved from an
    edited design, or ``isoforce show --set``, does not pass the new value off as the source's.
    Entries of an earlier save are kept (its first value stays the source's).

    Examples
    --------
    >>> p = load_preset("inverse3_prototype")
    >>> dict(with_changes(p, p.mechanism.replace_display(proximal_length=160)).provenance)["changed.proximal_length"]
    '140 mm in the source above; now 160 mm'
    """
    before = dict((info.name, value) for info, value in preset.mechanism.parameter_table())
    earlier = dict(preset.provenance)
    changes = []
    for info, value in mechanism.parameter_table():
        key = f"changed.{info.name}"
        if value != before[info.name] or key in earlier:
            origin = str(earlier[key]).split(";")[0] if key in earlier else \
                f"{_shown(before[info.name], info.unit)} in the source above"
            changes.append((key, f"{origin}; now {_shown(value, info.unit)}"))
    kept = tuple((k, v) for k, v in preset.provenance if not k.startswith("changed."))
    return preset.replace(mechanism=mechanism, provenance=kept + tuple(changes))


def preset_to_toml(preset: Preset) -> str:
    """The TOML text of a preset, in the same schema ``parse_preset`` reads."""
    mech, grid = preset.mechanism, preset.grid
    scale = {n: float(v) for n, v in zip(mech.task_names, task_scales(mech))}
    lines = [f"name = {_toml_value(preset.name)}", f"mechanism = {_toml_value(preset.kind)}",
             f"description = {_toml_value(preset.description)}", "", "[parameters]"]
    for info, value in mech.parameter_table():
        value = list(value) if isinstance(value, tuple) else value
        lines.append(f"{info.name} = {_toml_value(value)}")
    # Preset-only rows are written where they differ from the family's defaults: a default (a source's
    # SI value, e.g. the PHANToM's centres in m) need not survive display units and back exactly.
    defaults = type(mech)().params
    for info in preset_params(type(mech)):
        value = getattr(mech.params, info.name)
        if value != getattr(defaults, info.name):
            lines.append(f"{info.name} = {_toml_value([info.from_si(v) for v in value])}")
    lines += ["", "[map]", f"axes = {_toml_value(list(grid.axes))}",
              f"lower = {_toml_value([v * scale[a] for a, v in zip(grid.axes, grid.lower)])}",
              f"upper = {_toml_value([v * scale[a] for a, v in zip(grid.axes, grid.upper)])}",
              f"resolution = {_toml_value(list(grid.resolution))}"]
    if grid.fixed:
        lines.append("fixed = { " + ", ".join(f"{n} = {_toml_value(v * scale[n])}" for n, v in grid.fixed) + " }")
    if preset.pose is not None:
        lines += ["", "[pose]", f"at = {_toml_value([float(v) for v in task_from_si(mech, preset.pose)])}"]
    if preset.provenance:
        lines += ["", "[source]"]
        lines += [f"{_toml_key(k)} = {_toml_value(list(v) if isinstance(v, tuple) else v)}"
                  for k, v in preset.provenance]
    if preset.spec is not None:
        lines += ["", "[spec]"] + spec_lines(preset.spec, _toml_value)
    if preset.motor_speeds is not None:
        lines += ["", "[motors]", f"max_speeds = {_toml_value([float(v) for v in preset.motor_speeds])}",
                  f"source = {_toml_value(preset.motor_speeds_source)}"]
    return "\n".join(lines) + "\n"


def list_presets() -> list[str]:
    """Keys of the shipped presets (file stems), sorted."""
    folder = _res.files("resources").joinpath("presets")
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def load_preset(name: str) -> Preset:
    """A shipped preset by key, or a TOML file by path (anything ending in ``.toml``)."""
    if name.endswith(".toml") or "/" in name:
        return read_preset_file(Path(name))
    known = list_presets()
    if name not in known:
        raise PresetError(f"unknown device {name!r}; known: {', '.join(known)} (or a path to a .toml file)")
    text = _res.files("resources").joinpath("presets", f"{name}.toml").read_text(encoding="utf-8")
    return parse_preset_text(text, f"{name}.toml", name)
