"""A session file: what the app shows, in a small TOML file the app and ``isoforce figure`` read.

The design is a reference to its preset (a shipped preset's key, or a TOML file's path) and
the parameters changed from it, in display units (the names and units ``--set`` and the
sliders use); then the comparison's reference (another device, or a pinned design of this
one), the map's quantity, overlay, plane and compare mode, the pose, desired force and glyphs,
the loading, the map's range when it is not the preset's (View > Fit map to workspace), a 3D
box map's plane with its colour range, and the 3D views' cameras::

    version = 1

    [design]
    preset = "inverse3_prototype"
    [design.values]
    gear_ratios = [13.75, 5.957, 5.957]

    [reference]
    preset = "inverse3_prototype"
    [reference.values]

    [view]
    quantity = "isotropic_force"
    overlay = "none"
    ...

    [view.map]              # only when fitted: the preset's own range is not repeated
    axes = ["x", "z"]
    lower = [35.0, -110.0]  # mm (deg for an angle)
    upper = [305.0, 410.0]
    resolution = [1000, 1000]

    [view.plane]
    axis = "z"
    mm = 10.0
    colour_range = "volume"

    [camera.pose]
    position = [0.6, -0.5, 0.4]
    ...

``read_session`` checks every key and raises one ``SessionError`` naming the file and the key
(``"session 'a.toml': key 'view.quantity': unknown quantity 'x'; ..."``); ``write_session``
writes through ``atomic_write``. No Qt, no plotting.
"""
from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from app.files.export import atomic_write
from app.logic.colour_scale import COLOUR_RANGES
from app.logic.design_changes import _same
from app.logic.glyphs import DEFAULT_GLYPHS, GLYPHS
from app.logic.overlay_names import OVERLAYS
from kinematics.contract import Mechanism
from kinematics.gravity import MOUNTINGS
from kinematics.grid import GridSpec
from kinematics.units import task_scales
from metrics.loading import DEFAULT_LOADING, RATINGS, Loading
from metrics.quantities import QUANTITIES, available_quantities
from resources import Preset, PresetError, load_preset

SESSION_VERSION = 1
#: The compare modes (``app.gui.model.COMPARE_MODES``: this floor cannot import the GUI).
COMPARE_MODES = ("side", "difference")
#: The 3D views whose cameras a session keeps, and a camera's keys (``app.gui.views.camera.CameraState``).
CAMERA_VIEWS = ("pose", "workspace")
CAMERA_KEYS = ("position", "focal_point", "view_up", "view_angle", "parallel_scale", "parallel")
SUFFIX = ".toml"
#: Points per axis a session's map may have (a preset file's bound, ``resources.schema``).
MAX_POINTS = 20000


class SessionError(ValueError):
    """A session file that cannot be used; the message names the file and the key."""


@dataclass(frozen=True)
class Session:
    """What a session file holds, as the app's objects (SI units inside, as everywhere).

    ``reference_preset`` is another device compared against; ``reference_mechanism`` without it
    is a pinned design of ``preset``'s device. ``preset.grid`` is the map's range on screen: the
    preset's own, or one fitted to the workspace (written as ``[view.map]`` when it differs from
    what the preset's key or file gives, ``preset_grid``). ``plane`` is ``(axis, m)`` of a 3D box map,
    coloured over ``colour_range`` (``app.logic.colour_scale.COLOUR_RANGES``: the plane's values
    or the whole volume's).
    ``cameras`` maps a 3D view (``CAMERA_VIEWS``) to its camera's numbers (``CAMERA_KEYS``).
    """

    preset: Preset
    mechanism: Mechanism
    quantity: str = "isotropic_force"
    overlay: str = "none"
    compare_mode: str = "side"
    glyphs: frozenset[str] = DEFAULT_GLYPHS
    pose: tuple[float, ...] | None = None
    desired_force: tuple[float, ...] | None = None
    plane: tuple[str, float] | None = None
    colour_range: str = "plane"
    loading: Loading = DEFAULT_LOADING
    reference_preset: Preset | None = None
    reference_mechanism: Mechanism | None = None
    cameras: dict[str, dict[str, Any]] = field(default_factory=dict)

    @property
    def design_preset(self) -> Preset:
        """The preset with the session's parameters (what ``--set`` makes of it)."""
        return self.preset.replace(mechanism=self.mechanism)


# -- writing -------------------------------------------------------------------------------
def preset_reference(preset: Preset) -> str:
    """What names ``preset`` in a session: its key for a shipped preset, else its file's path."""
    source = str(preset.source or "")
    if source.endswith(SUFFIX) and ("/" in source or "\\" in source):
        return str(Path(source).resolve())
    return preset.key


def changed_values(base: Mechanism, mechanism: Mechanism) -> dict[str, Any]:
    """The parameters of ``mechanism`` that differ from ``base``'s, by name, in display units."""
    old = {info.name: v for info, v in base.parameter_table()}
    return {info.name: v for info, v in mechanism.parameter_table() if not _same(old.get(info.name), v)}


def preset_grid(preset: Preset, load: Callable[[str], Preset] = load_preset) -> GridSpec | None:
    """The map grid ``preset``'s key or file gives (``preset_reference``), whatever range the
    window fitted since; None if it cannot be loaded (a file moved: the range is then written)."""
    try:
        return load(preset_reference(preset)).grid
    except PresetError:
        return None


def _axis_scales(mechanism: Mechanism) -> dict[str, float]:
    """Display units per SI unit of each task coordinate: 1e3 for m -> mm, 180/pi for rad -> deg."""
    return {name: float(v) for name, v in zip(mechanism.task_names, task_scales(mechanism))}


def map_table(grid: GridSpec, mechanism: Mechanism) -> dict[str, Any]:
    """``[view.map]``: the grid's axes, range in display units (mm, deg) and points per axis."""
    scale = _axis_scales(mechanism)
    return {"axes": list(grid.axes), "lower": [v * scale[a] for a, v in zip(grid.axes, grid.lower)],
            "upper": [v * scale[a] for a, v in zip(grid.axes, grid.upper)], "resolution": list(grid.resolution)}


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))          # a count (a map's points per axis); every parameter is a float
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(value, str):
        return json.dumps(value)        # a TOML basic string: JSON's escapes are TOML's
    if isinstance(value, (tuple, list, np.ndarray)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"no TOML form for {value!r}")


def _table(name: str, values: dict[str, Any], comment: str = "") -> list[str]:
    lines = [f"[{name}]" + (f"    # {comment}" if comment else "")]
    lines += [f"{key} = {_toml_value(v)}" for key, v in values.items() if v is not None]
    return lines + [""]


def session_to_toml(session: Session, *, load: Callable[[str], Preset] = load_preset) -> str:
    """The session's TOML text, in the schema ``read_session`` reads (``load``, as there, loads
    the preset whose own map range a fitted one is compared with)."""
    mech = session.mechanism
    lines = ["# isoforce session: the design, its comparison and the views (isoforce figure --session FILE)",
             f"version = {SESSION_VERSION}", ""]
    lines += _table("design", {"preset": preset_reference(session.preset)},
                    "a preset key or a TOML file")
    lines += _table("design.values", changed_values(session.preset.mechanism, mech),
                    "parameters changed from the preset, display units")
    if session.reference_mechanism is not None:
        ref_preset = session.reference_preset or session.preset
        lines += _table("reference", {"preset": preset_reference(ref_preset)},
                        "the comparison's reference design")
        lines += _table("reference.values", changed_values(ref_preset.mechanism, session.reference_mechanism))
    loading = session.loading
    gravity: Any = "off"
    if loading.biased:
        gravity = loading.mounting if loading.mounting is not None else list(loading.gravity)
    scales = task_scales(mech)
    view = {"quantity": session.quantity, "overlay": session.overlay, "compare_mode": session.compare_mode,
            "glyphs": sorted(session.glyphs),
            "pose": None if session.pose is None else list(np.asarray(session.pose, float) * scales),
            "desired_force": None if session.desired_force is None else list(session.desired_force),
            "rating": loading.rating, "gravity": gravity}
    lines += _table("view", view, "pose in mm (deg for angles), desired force in N, gravity a mounting or m/s^2")
    if session.preset.grid != preset_grid(session.preset, load):
        lines += _table("view.map", map_table(session.preset.grid, mech),
                        "the map's range fitted to the workspace, mm (deg for angles)")
    if session.plane is not None:
        lines += _table("view.plane", {"axis": session.plane[0], "mm": session.plane[1] * 1e3,
                                       "colour_range": session.colour_range},
                        "the plane of a 3D box map; its colours over this plane's values or the whole volume's")
    for name, camera in session.cameras.items():
        lines += _table(f"camera.{name}", {k: camera[k] for k in CAMERA_KEYS if k in camera},
                        "m and deg" if name == CAMERA_VIEWS[0] else "")
    return "\n".join(lines)


def write_session(path, session: Session, *, load: Callable[[str], Preset] = load_preset) -> Path:
    """Write ``session`` to ``path`` (through ``atomic_write``: a failed write leaves the old file)."""
    text = session_to_toml(session, load=load)
    return atomic_write(Path(path), lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


# -- reading -------------------------------------------------------------------------------
class _Reader:
    """Checks keys of one session file; ``fail`` raises the one error naming file and key."""

    def __init__(self, path: Path) -> None:
        self.name = path.name

    def fail(self, key: str, message: str):
        raise SessionError(f"session {self.name!r}: key {key!r}: {message}")

    def table(self, data: dict, key: str, known: tuple[str, ...], *, required: bool = False) -> dict:
        value = data.get(key.rsplit(".", 1)[-1])
        if value is None:
            if required:
                self.fail(key, "missing")
            return {}
        if not isinstance(value, dict):
            self.fail(key, f"needs a table, got {value!r}")
        for name in value:
            if known and name not in known:
                self.fail(f"{key}.{name}", f"unknown key; known: {', '.join(known)}")
        return value

    def string(self, table: dict, key: str, *, choices=None, default=None) -> str | None:
        value = table.get(key.rsplit(".", 1)[-1], default)
        if value is None:
            return None
        if not isinstance(value, str):
            self.fail(key, f"needs a string, got {value!r}")
        if choices is not None and value not in choices:
            self.fail(key, f"must be one of {', '.join(choices)}, got {value!r}")
        return value

    def numbers(self, table: dict, key: str, count: int | None = None) -> tuple[float, ...] | None:
        value = table.get(key.rsplit(".", 1)[-1])
        if value is None:
            return None
        if not isinstance(value, list) or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                   for v in value):
            self.fail(key, f"needs a list of numbers, got {value!r}")
        if count is not None and len(value) != count:
            self.fail(key, f"needs {count} numbers, got {len(value)}")
        if not all(math.isfinite(v) for v in value):
            self.fail(key, f"needs finite numbers, got {value!r}")
        return tuple(float(v) for v in value)

    def map_range(self, view: dict, preset: Preset, mechanism: Mechanism) -> Preset:
        """``preset`` with ``[view.map]``'s range (View > Fit map to workspace), if the file has one."""
        table = self.table(view, "view.map", ("axes", "lower", "upper", "resolution"))
        if not table:
            return preset
        grid = preset.grid
        if table.get("axes") != list(grid.axes):
            self.fail("view.map.axes", f"needs the preset's map axes {list(grid.axes)}, got {table.get('axes')!r}")
        k = len(grid.axes)
        lower, upper = self.numbers(table, "view.map.lower", k), self.numbers(table, "view.map.upper", k)
        if lower is None or upper is None:
            self.fail("view.map", "needs lower and upper (mm, deg for an angle)")
        for axis, lo, hi in zip(grid.axes, lower, upper):
            if not lo < hi:
                self.fail("view.map.upper", f"must exceed lower on axis {axis!r}, got {lo:g} >= {hi:g}")
        resolution = table.get("resolution", list(grid.resolution))
        if (not isinstance(resolution, list) or len(resolution) != k
                or not all(type(n) is int and 2 <= n <= MAX_POINTS for n in resolution)):
            self.fail("view.map.resolution", f"needs {k} whole numbers of points, 2 to {MAX_POINTS}, "
                                             f"got {resolution!r}")
        scale = _axis_scales(mechanism)
        return preset.replace(grid=GridSpec(grid.axes, tuple(v / scale[a] for a, v in zip(grid.axes, lower)),
                                            tuple(v / scale[a] for a, v in zip(grid.axes, upper)),
                                            tuple(resolution), grid.fixed))

    def design(self, data: dict, key: str, folder: Path, load: Callable[[str], Preset]) -> tuple[Preset, Mechanism]:
        table = self.table(data, key, ("preset", "values"), required=True)
        ref = self.string(table, f"{key}.preset")
        if ref is None:
            self.fail(f"{key}.preset", "missing: a preset key or a TOML file's path")
        if ref.endswith(SUFFIX) and not Path(ref).is_absolute():
            ref = str(folder / ref)          # a file named relative to the session's folder
        try:
            preset = load(ref)
        except PresetError as exc:
            self.fail(f"{key}.preset", str(exc))
        values = table.get("values", {})
        if not isinstance(values, dict):
            self.fail(f"{key}.values", f"needs a table, got {values!r}")
        known = {info.name: info for info, _ in preset.mechanism.parameter_table()}
        changes = {}
        for name, value in values.items():
            if name not in known:
                self.fail(f"{key}.values.{name}", f"{preset.key!r} has no such parameter; known: {', '.join(known)}")
            if isinstance(value, bool) or isinstance(value, list) and any(isinstance(v, bool) for v in value):
                self.fail(f"{key}.values.{name}", f"needs a number, numbers or a choice, got {value!r}")
            changes[name] = tuple(value) if isinstance(value, list) else value
        try:
            mechanism = preset.mechanism.replace_display(**changes) if changes else preset.mechanism
        except (ValueError, TypeError) as exc:
            where = next(iter(changes)) if len(changes) == 1 else ", ".join(changes)
            self.fail(f"{key}.values.{where}" if len(changes) == 1 else f"{key}.values", str(exc))
        return preset, mechanism


def read_session(path, *, load: Callable[[str], Preset] = load_preset) -> Session:
    """Read a session file; ``load`` loads a preset by key or path (the app passes its own).

    Raises
    ------
    SessionError
        One message naming the file and the key at fault.
    """
    path = Path(path)
    r = _Reader(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise SessionError(f"session {path.name!r}: cannot be read: {exc.strerror or exc}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise SessionError(f"session {path.name!r}: not a TOML file: {exc}") from None
    for name in data:
        if name not in ("version", "design", "reference", "view", "camera"):
            r.fail(name, "unknown key; known: version, design, reference, view, camera")
    version = data.get("version")
    if version != SESSION_VERSION:
        r.fail("version", f"this isoforce reads session version {SESSION_VERSION}, got {version!r}")
    folder = path.resolve().parent
    preset, mech = r.design(data, "design", folder, load)
    reference_preset = reference_mechanism = None
    if "reference" in data:
        ref_preset, reference_mechanism = r.design(data, "reference", folder, load)
        same = preset_reference(ref_preset) == preset_reference(preset)
        reference_preset = None if same else ref_preset
    view = r.table(data, "view", ("quantity", "overlay", "compare_mode", "glyphs", "pose", "desired_force",
                                  "rating", "gravity", "map", "plane"))
    preset = r.map_range(view, preset, mech)
    quantity = r.string(view, "view.quantity", default="isotropic_force")
    if quantity not in QUANTITIES or not QUANTITIES[quantity].scalar:
        r.fail("view.quantity", f"unknown map quantity {quantity!r}; `isoforce map --help` lists them")
    if quantity not in available_quantities(mech):
        r.fail("view.quantity", f"{preset.key!r} cannot compute {quantity!r}")
    overlay = r.string(view, "view.overlay", choices=tuple(OVERLAYS), default="none")
    compare_mode = r.string(view, "view.compare_mode", choices=COMPARE_MODES, default="side")
    glyphs = view.get("glyphs", sorted(DEFAULT_GLYPHS))
    if not isinstance(glyphs, list) or not all(isinstance(g, str) for g in glyphs):
        r.fail("view.glyphs", f"needs a list of glyph names, got {glyphs!r}")
    for g in glyphs:
        if g not in GLYPHS:
            r.fail("view.glyphs", f"unknown glyph {g!r}; known: {', '.join(GLYPHS)}")
    pose = r.numbers(view, "view.pose", mech.task_dim)
    if pose is not None:
        pose = tuple(float(v) for v in np.asarray(pose) / task_scales(mech))
    force = r.numbers(view, "view.desired_force", mech.task_dim)
    rating = r.string(view, "view.rating", choices=RATINGS, default="continuous")
    gravity = view.get("gravity", "off")
    try:
        if gravity == "off":
            loading = Loading(rating=rating)
        elif isinstance(gravity, str):
            if gravity not in MOUNTINGS:
                r.fail("view.gravity", f"must be off, one of {', '.join(MOUNTINGS)} or 3 numbers, got {gravity!r}")
            loading = Loading.mounted(gravity, rating=rating)
        else:
            loading = Loading(rating=rating, gravity=r.numbers(view, "view.gravity", 3))
        loading.check(mech, device=preset.name)
    except ValueError as exc:
        if isinstance(exc, SessionError):
            raise
        r.fail("view.gravity" if "gravity" in str(exc) else "view.rating", str(exc))
    plane, colour_range = None, "plane"
    plane_table = r.table(view, "view.plane", ("axis", "mm", "colour_range"))
    if plane_table:
        grid = preset.grid
        if len(grid.axes) != 3:
            r.fail("view.plane", f"{preset.key!r} maps a {len(grid.axes)}D slice, not a 3D box: it has no plane")
        axis = r.string(plane_table, "view.plane.axis", choices=grid.axes)
        mm = plane_table.get("mm")
        if axis is None or not isinstance(mm, (int, float)) or isinstance(mm, bool) or not math.isfinite(mm):
            r.fail("view.plane", f"needs axis (one of the 3D map's axes) and mm (a number), got {plane_table!r}")
        plane = (axis, float(mm) / 1e3)
        colour_range = r.string(plane_table, "view.plane.colour_range", choices=tuple(COLOUR_RANGES), default="plane")
    cameras = {}
    for name, camera in r.table(data, "camera", CAMERA_VIEWS).items():
        key = f"camera.{name}"
        if not isinstance(camera, dict):
            r.fail(key, f"needs a table, got {camera!r}")
        for k in camera:
            if k not in CAMERA_KEYS:
                r.fail(f"{key}.{k}", f"unknown key; known: {', '.join(CAMERA_KEYS)}")
        out: dict[str, Any] = {}
        for k in ("position", "focal_point", "view_up"):
            out[k] = r.numbers(camera, f"{key}.{k}", 3)
            if out[k] is None:
                r.fail(f"{key}.{k}", "missing")
        for k in ("view_angle", "parallel_scale"):
            v = camera.get(k)
            if v is not None and (not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v)):
                r.fail(f"{key}.{k}", f"needs a number, got {v!r}")
            if v is not None:
                out[k] = float(v)
        if "parallel" in camera:
            if not isinstance(camera["parallel"], bool):
                r.fail(f"{key}.parallel", f"needs true or false, got {camera['parallel']!r}")
            out["parallel"] = camera["parallel"]
        if np.allclose(out["position"], out["focal_point"]):
            r.fail(f"{key}.position", "is the focal point: the camera looks nowhere")
        cameras[name] = out
    return Session(preset=preset, mechanism=mech, quantity=quantity, overlay=overlay, compare_mode=compare_mode,
                   glyphs=frozenset(glyphs), pose=pose, desired_force=force, plane=plane,
                   colour_range=colour_range, loading=loading,
                   reference_preset=reference_preset, reference_mechanism=reference_mechanism, cameras=cameras)
