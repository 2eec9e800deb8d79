"""The one place the app's truth lives, in plain Python: widgets change it and listen to it.

``AppModel`` holds the preset, the current mechanism (sliders replace it), the map quantity,
the selected pose and desired force, which glyphs are visible, the compare mode, the latest
maps (current and pinned reference), whether the map on screen is stale, whether a map
is being computed, and the undo history of design edits (``history``, ``app.gui.history``:
every change of preset or mechanism is a step, a slider drag one step from press to release).
It never computes anything itself: the main window turns its changes
into requests for the job runner and feeds results back.

Every change emits an event of ``model.events`` (as napari's layers do), after the model
has changed: ``model.events.pose.connect(callback)``. No Qt here, so the model is tested
without it; ``app.gui.qt_model.QtAppState`` re-emits the events as Qt signals for widgets.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Callable

from app.gui.history import Design, History
from app.logic.glyphs import DEFAULT_GLYPHS, GLYPHS, pose_parts  # noqa: F401 (re-exported)
from app.logic.overlay_names import OVERLAYS
from app.logic.planes import default_plane
from kinematics.contract import Mechanism
from metrics.loading import DEFAULT_LOADING, Loading, LoadingError
from metrics.pose import PoseReport
from metrics.quantities import QUANTITIES, available_quantities
from metrics.workspace import WorkspaceMap
from resources import Preset

COMPARE_MODES = ("side", "difference")
#: How long the maps and figures on screen must have been stale before the views mark them, ms:
#: while a slider moves, each coarse map replaces the last within a frame or two.
STALE_DELAY_MS = 150
#: What a held slider moves (``AppModel.interaction``): the plane of a 3D box map, a design parameter, or nothing.
INTERACTIONS = ("plane", "design", None)
#: The map's first quantity, and where it falls back to when a device cannot compute the one chosen.
DEFAULT_QUANTITY = "isotropic_force"


class Event:
    """A list of callbacks called, in the order connected, with the event's arguments."""

    def __init__(self, name: str) -> None:
        self.name = name
        self._callbacks: list[Callable[..., Any]] = []

    def connect(self, callback: Callable[..., Any]) -> Callable[..., Any]:
        """Call ``callback(*args)`` on every ``emit(*args)``; returns it (usable as a decorator)."""
        self._callbacks.append(callback)
        return callback

    def disconnect(self, callback: Callable[..., Any]) -> None:
        self._callbacks.remove(callback)

    def emit(self, *args: Any) -> None:
        for callback in list(self._callbacks):
            callback(*args)


class ModelEvents:
    """The model's events; each is emitted after the change it names."""

    NAMES = ("preset", "mechanism", "quantity", "pose", "pose_report", "glyphs", "map", "reference",
             "compare_mode", "progress", "busy", "stale", "slice", "loading", "interaction", "overlay", "notice",
             "history")

    def __init__(self) -> None:
        self.preset = Event("preset")                # a new device: everything below changed too
        self.mechanism = Event("mechanism")          # new parameters of the same device
        self.quantity = Event("quantity")
        self.pose = Event("pose")                    # the selected pose or the desired force
        self.pose_report = Event("pose_report")
        self.glyphs = Event("glyphs")
        self.map = Event("map")                      # current map replaced
        self.reference = Event("reference")          # pinned reference set, cleared or its map replaced
        self.compare_mode = Event("compare_mode")
        self.progress = Event("progress")            # (fraction,)
        self.busy = Event("busy")                    # (busy,)
        self.stale = Event("stale")                  # (reason or None,) when ``AppModel.stale`` changes
        self.slice = Event("slice")                  # the plane shown of a 3D box map moved
        self.loading = Event("loading")              # the torque rating or gravity changed
        self.interaction = Event("interaction")      # a slider was pressed or released (``AppModel.interaction``)
        self.overlay = Event("overlay")              # the map view's overlay (``AppModel.overlay``) changed
        self.notice = Event("notice")                # (text,) a choice the model changed on its own, for the status bar
        self.history = Event("history")              # the undo history, or what was last saved, changed

    def all(self) -> dict[str, Event]:
        """Every event by name, in ``NAMES`` order."""
        return {name: vars(self)[name] for name in self.NAMES}


def loading_refusals(mechanism: Mechanism, device: str | None = None) -> dict[str, str | None]:
    """Why ``mechanism`` cannot take a peak rating or gravity: ``{"rating": reason, "gravity": reason}``.

    A reason is ``None`` where the model can; otherwise the compute layer's own message
    (``metrics.loading.Loading.check``), e.g. "... has no peak torque rating ...".
    """
    out: dict[str, str | None] = {}
    for argument, loading in (("rating", Loading(rating="peak")), ("gravity", Loading.mounted("upright"))):
        try:
            loading.check(mechanism, device=device)
            out[argument] = None
        except LoadingError as exc:
            out[argument] = str(exc).split(": ", 1)[-1]
    return out


def supported_loading(loading: Loading, mechanism: Mechanism) -> Loading:
    """``loading`` with what ``mechanism`` cannot take turned off: continuous rating, gravity off."""
    refused = loading_refusals(mechanism)
    rating = loading.rating if refused["rating"] is None else "continuous"
    if refused["gravity"] is not None or not loading.biased:
        return Loading(rating=rating)
    return Loading(rating=rating, gravity=loading.gravity, mounting=loading.mounting)


def loading_label(loading: Loading) -> str:
    """A short phrase for a title: ``"continuous rating, gravity off"``, ``"peak rating, gravity upright"``."""
    if not loading.biased:
        gravity = "off"
    elif loading.mounting is not None:
        gravity = loading.mounting
    else:
        gravity = "(" + ", ".join(f"{v:g}" for v in loading.gravity) + ") m/s^2"
    return f"{loading.rating} rating, gravity {gravity}"


def map_range(grid) -> tuple:
    """What a map covers, whatever its points per axis (a coarse map covers the full one's range)."""
    return (grid.axes, grid.lower, grid.upper, grid.fixed)


@dataclass(frozen=True)
class MapSlot:
    """A map result with what produced it, and the colour limits computed with it
    (``app.jobs.requests.MapResult``: quantity -> ``(lo, hi, capped)``)."""

    map: WorkspaceMap
    mechanism: Mechanism
    stage: str
    generation: int
    colour_limits: Mapping[str, tuple[float, float, bool]] = field(default_factory=dict)


class AppModel:
    """The app's state and its change events; see the module docstring."""

    def __init__(self, preset: Preset, quantity: str = DEFAULT_QUANTITY) -> None:
        self.events = ModelEvents()
        self.preset = preset
        self.mechanism = preset.mechanism
        self.quantity = quantity
        self.pose = preset.pose
        self.desired_force: tuple[float, ...] = (0.0,) * preset.mechanism.task_dim
        self.pose_report: PoseReport | None = None     # of (mechanism, pose, glyphs)
        self.glyphs: frozenset[str] = DEFAULT_GLYPHS
        self.current: MapSlot | None = None
        self.reference_mechanism: Mechanism | None = None
        self.reference_preset: Preset | None = None    # another device as the reference; None: this one
        self.reference: MapSlot | None = None
        self.compare_mode = "side"     # "side" or "difference"
        self.busy = False
        self.progress = 0.0
        self._stale = self.stale
        self.slice_axis, self.slice_value = self._default_slice()
        self.loading: Loading = DEFAULT_LOADING     # torque rating and gravity of every map, pose and figure
        # What the user is dragging: "plane" (the 3D box map's plane slider), "design" (a
        # parameter slider) or None. Views draw only cheap geometry meanwhile (``INTERACTIONS``).
        self.interaction: str | None = None
        # Drawn over the map: paper 002's condition bands or an ellipse field (``app.plots.overlays.OVERLAYS``).
        self.overlay = "none"
        # Design edits, undoable; the design last loaded or saved (``modified``).
        self.history = History(saved=self.design)
        self._replaying = False         # an undo or redo is applying a design: record nothing

    @property
    def design(self) -> Design:
        """The device and its parameters now: what the undo history records."""
        return Design(self.preset, self.mechanism)

    @property
    def modified(self) -> bool:
        """The design differs from the one last loaded or saved (the title bar's mark)."""
        return self.history.modified(self.design)

    # -- derived ---------------------------------------------------------------------------
    @property
    def stale(self) -> str | None:
        """Why the current map is older than the state: ``"parameters"``, ``"loading"``, ``"quantity"``,
        ``"range"`` (the map's range was fitted anew) or None.

        A map of other parameters (a slow device, a drag faster than the computation) or of
        another quantity than the one chosen stays on screen, marked, until its successor
        arrives. A coarse map of the current parameters is not stale; no map is not stale.
        """
        if self.current is None:
            return None
        if self.current.mechanism != self.mechanism:
            return "parameters"
        if self.current.map.loading != self.loading:
            return "loading"
        if self.quantity not in self.current.map.values:
            return "quantity"
        if map_range(self.current.map.grid) != map_range(self.preset.grid):
            return "range"
        return None

    def _default_slice(self) -> tuple[str | None, float | None]:
        """A 3D box map is shown through the plane of its last axis at the pose (else mid-range)."""
        return default_plane(self.preset.grid, self.preset.mechanism, self.pose)   # (``--plane``'s default too)

    @property
    def reference_loading(self) -> Loading:
        """The loading of the reference's map: the current one, less what the reference device cannot take."""
        if self.reference_mechanism is None:
            return self.loading
        return supported_loading(self.loading, self.reference_mechanism)

    @property
    def reference_grid(self):
        """The grid the reference's map is computed on: its own device's, or this preset's."""
        return (self.reference_preset or self.preset).grid

    def _check_stale(self) -> None:
        stale = self.stale
        if stale != self._stale:
            self._stale = stale
            self.events.stale.emit(stale)

    def _fit_quantity(self, device: str) -> str | None:
        """Fall back to a quantity the mechanism can compute if it cannot compute the one chosen
        (a WoodenHaptics has no joint sensors: no spatial resolution); returns the notice, or None."""
        available = available_quantities(self.mechanism)
        if self.quantity in available:
            return None
        old = self.quantity
        self.quantity = DEFAULT_QUANTITY if DEFAULT_QUANTITY in available else available[0]
        return (f"{device} cannot compute {QUANTITIES[old].label.lower()}: "
                f"the map shows {QUANTITIES[self.quantity].label.lower()}")

    # -- changes ---------------------------------------------------------------------------
    def set_preset(self, preset: Preset) -> None:
        """A new device; the quantity falls back (``_fit_quantity``, with a ``notice``) if it has not the one shown.

        An undoable step; the new device is also the design last loaded (not modified).
        """
        before = self.design
        self.preset = preset
        self.mechanism = preset.mechanism
        notice = self._fit_quantity(preset.name or preset.key)
        self.pose = preset.pose
        self.desired_force = (0.0,) * preset.mechanism.task_dim
        self.current = None
        self.reference_mechanism = None
        self.reference_preset = None
        self.reference = None
        self.slice_axis, self.slice_value = self._default_slice()
        # A new device starts from what it supports of the loading chosen (peak only with a peak
        # rating, gravity only with a mass model).
        self.loading = supported_loading(self.loading, preset.mechanism)
        self.events.preset.emit()
        if notice:
            self.events.quantity.emit()
        self.events.mechanism.emit()
        self.events.pose.emit()
        self.events.reference.emit()
        self.events.slice.emit()
        self.events.loading.emit()
        self._check_stale()
        if not self._replaying:
            self.history.mark_saved(self.design)
        self._record(before)
        if notice:
            self.events.notice.emit(notice)

    def set_mechanism(self, mechanism: Mechanism) -> None:
        """New parameters; the quantity falls back as in ``set_preset`` (``joint_sensors = "none"``)."""
        if mechanism == self.mechanism:
            return
        before = self.design
        self.mechanism = mechanism
        notice = self._fit_quantity("this design")
        if notice:
            self.events.quantity.emit()
        self.events.mechanism.emit()
        self._check_stale()
        self._record(before, merge=self.interaction == "design")
        if notice:
            self.events.notice.emit(notice)

    def set_loading(self, loading: Loading) -> None:
        """The torque rating and gravity of every map, statistic and pose glyph.

        Raises a ``LoadingError`` (a ``ValueError`` naming ``rating`` or ``gravity``) when the
        device cannot take it; nothing changes then.
        """
        loading.check(self.mechanism, device=self.preset.name)
        if loading != self.loading:
            self.loading = loading
            self.events.loading.emit()
            self._check_stale()

    def set_interaction(self, interaction: str | None) -> None:
        """``"plane"``, ``"design"`` (a slider held) or ``None`` (released)."""
        if interaction not in INTERACTIONS:
            raise ValueError(f"interaction must be one of {INTERACTIONS!r}, got {interaction!r}")
        if interaction != self.interaction:
            self.interaction = interaction
            if interaction != "design":
                self.history.close()        # a drag's step ends at the release
            self.events.interaction.emit()

    # -- undo ------------------------------------------------------------------------------
    def _record(self, before: Design, *, merge: bool = False) -> None:
        if not self._replaying:
            self.history.record(before, self.design, merge=merge)
            self.events.history.emit()

    def undo(self) -> bool:
        """Take back the last design edit (a device switch brings the old device back); False if none."""
        if not self.history.can_undo():
            return False
        self._replay(self.history.undo())
        return True

    def redo(self) -> bool:
        """Do the last undone design edit again; False if none."""
        if not self.history.can_redo():
            return False
        self._replay(self.history.redo())
        return True

    def _replay(self, design: Design) -> None:
        self._replaying = True
        try:
            if design.preset is not self.preset:
                self.set_preset(design.preset)
            self.set_mechanism(design.mechanism)
        finally:
            self._replaying = False
        self.events.history.emit()

    def set_design(self, preset: Preset, mechanism: Mechanism) -> None:
        """A device with parameters of its own (a session file's): one undoable step, not modified
        (it is on disk), the rest of the state as after ``set_preset``."""
        before = self.design
        self._replaying = True
        try:
            if preset is not self.preset:
                self.set_preset(preset)
            self.set_mechanism(mechanism)
        finally:
            self._replaying = False
        self.history.mark_saved(self.design)
        self._record(before)

    def mark_saved(self) -> None:
        """The design on screen is now on disk: not modified."""
        self.history.mark_saved(self.design)
        self.events.history.emit()

    def set_map_grid(self, grid) -> None:
        """The map's range (and points) for this device: View > Fit map to workspace.

        The preset is replaced by one with ``grid`` and the undo history follows it (``History.rebase``):
        a map range is not a design edit. A pinned design of this device loses its map (it is of the
        old range); the plane of a 3D box goes back to the pose's.
        """
        if grid == self.preset.grid:
            return
        old = self.preset
        self.preset = old.replace(grid=grid)
        self.history.rebase(old, self.preset)
        if self.reference_preset is None and self.reference_mechanism is not None:
            self.reference = None
            self.events.reference.emit()
        self.slice_axis, self.slice_value = self._default_slice()
        self.events.slice.emit()
        self._check_stale()

    def set_quantity(self, quantity: str) -> None:
        if quantity != self.quantity:
            self.quantity = quantity
            self.events.quantity.emit()
            self._check_stale()

    def set_pose(self, pose) -> None:
        """``pose``: task point, shape (m,), SI units."""
        pose = tuple(float(v) for v in pose)
        if pose != self.pose:
            self.pose = pose
            self.events.pose.emit()

    def set_desired_force(self, force) -> None:
        """``force``: shape (m,), N (and N m for moments)."""
        force = tuple(float(v) for v in force)
        if force != self.desired_force:
            self.desired_force = force
            self.events.pose.emit()

    def set_glyph(self, name: str, visible: bool) -> None:
        if name not in GLYPHS:
            raise ValueError(f"unknown glyph {name!r}; known: {', '.join(GLYPHS)}")
        glyphs = self.glyphs | {name} if visible else self.glyphs - {name}
        if glyphs != self.glyphs:
            self.glyphs = frozenset(glyphs)
            self.events.glyphs.emit()

    def set_pose_report(self, report: PoseReport | None) -> None:
        self.pose_report = report
        self.events.pose_report.emit()

    def set_current_map(self, slot: MapSlot) -> None:
        self.current = slot
        self.events.map.emit()
        self._check_stale()

    def pin_reference(self, mechanism: Mechanism | None = None) -> None:
        """Pin the current design, or ``mechanism`` (another design of this device: a session's
        reference), with the current map if it is of that design and up to date, as the reference."""
        mechanism = self.mechanism if mechanism is None else mechanism
        self.reference_mechanism = mechanism
        self.reference_preset = None
        current = self.current
        self.reference = current if current is not None and current.mechanism == mechanism else None
        self.events.reference.emit()

    def set_reference_device(self, preset: Preset) -> None:
        """Another device (a preset or a TOML file's) as the reference; its map is computed on its own grid."""
        self.reference_mechanism = preset.mechanism
        self.reference_preset = preset
        self.reference = None
        self.events.reference.emit()

    def clear_reference(self) -> None:
        self.reference_mechanism = None
        self.reference_preset = None
        self.reference = None
        self.events.reference.emit()

    def set_slice(self, axis: str, value: float) -> None:
        """The plane of a 3D box map to show: ``axis`` (one of the grid's) at ``value`` (m), clipped to its range."""
        grid = self.preset.grid
        if axis not in grid.axes or len(grid.axes) != 3:
            raise ValueError(f"slice axis must be one of the 3D map's axes {grid.axes!r}, got {axis!r}")
        k = grid.axes.index(axis)
        value = float(min(max(float(value), grid.lower[k]), grid.upper[k]))
        if (axis, value) != (self.slice_axis, self.slice_value):
            self.slice_axis, self.slice_value = axis, value
            self.events.slice.emit()

    def set_reference_map(self, slot: MapSlot) -> None:
        self.reference = slot
        self.events.reference.emit()

    def set_compare_mode(self, mode: str) -> None:
        if mode not in COMPARE_MODES:
            raise ValueError(f"compare mode must be 'side' or 'difference', got {mode!r}")
        if mode != self.compare_mode:
            self.compare_mode = mode
            self.events.compare_mode.emit()

    def set_overlay(self, overlay: str) -> None:
        """Draw ``overlay`` (a key of ``app.plots.overlays.OVERLAYS``) over the map; "none" for none."""
        if overlay not in OVERLAYS:
            raise ValueError(f"overlay must be one of {', '.join(OVERLAYS)}, got {overlay!r}")
        if overlay != self.overlay:
            self.overlay = overlay
            self.events.overlay.emit()

    def set_progress(self, fraction: float) -> None:
        """Progress of the current full map, in [0, 1]."""
        fraction = float(fraction)
        if fraction != self.progress:
            self.progress = fraction
            self.events.progress.emit(fraction)

    def set_busy(self, busy: bool) -> None:
        if busy != self.busy:
            self.busy = busy
            self.events.busy.emit(busy)
