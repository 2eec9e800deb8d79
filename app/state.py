"""The one place the app's truth lives. Widgets change it and listen to it.

``AppState`` holds the preset, the current mechanism (sliders replace it), the map quantity,
the selected pose and desired force, which glyphs and views are visible, the latest maps
(current and pinned reference) and their stage. It never computes anything itself: the
main window turns its changes into requests for the scheduler and feeds results back.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from PySide6.QtCore import QObject, Signal

from metrics.workspace import WorkspaceMap
from resources import Preset

from .glyphs import DEFAULT_GLYPHS, GLYPHS, pose_parts  # noqa: F401 (re-exported)

@dataclass(frozen=True)
class MapSlot:
    """A map result with what produced it."""

    map: WorkspaceMap
    mechanism: object
    stage: str
    generation: int


class AppState(QObject):
    presetChanged = Signal()
    mechanismChanged = Signal()
    quantityChanged = Signal()
    poseChanged = Signal()
    poseReportChanged = Signal()
    glyphsChanged = Signal()
    mapChanged = Signal()          # current map replaced
    referenceChanged = Signal()    # pinned reference set, cleared or its map replaced
    compareModeChanged = Signal()
    progressChanged = Signal(float)
    busyChanged = Signal(bool)

    def __init__(self, preset: Preset, quantity: str = "isotropic_force") -> None:
        super().__init__()
        self.preset = preset
        self.mechanism = preset.mechanism
        self.quantity = quantity
        self.pose = preset.pose
        self.desired_force: tuple[float, ...] = (0.0,) * preset.mechanism.task_dim
        self.pose_report = None        # metrics.pose.PoseReport of (mechanism, pose, glyphs)
        self.glyphs: frozenset[str] = DEFAULT_GLYPHS
        self.current: MapSlot | None = None
        self.reference_mechanism = None
        self.reference: MapSlot | None = None
        self.compare_mode = "side"     # "side" or "difference"
        self.busy = False

    # -- changes ---------------------------------------------------------------------------
    def set_preset(self, preset: Preset) -> None:
        self.preset = preset
        self.mechanism = preset.mechanism
        self.pose = preset.pose
        self.desired_force = (0.0,) * preset.mechanism.task_dim
        self.current = None
        self.reference_mechanism = None
        self.reference = None
        self.presetChanged.emit()
        self.mechanismChanged.emit()
        self.poseChanged.emit()
        self.referenceChanged.emit()

    def set_mechanism(self, mechanism) -> None:
        if mechanism == self.mechanism:
            return
        self.mechanism = mechanism
        self.mechanismChanged.emit()

    def set_quantity(self, quantity: str) -> None:
        if quantity != self.quantity:
            self.quantity = quantity
            self.quantityChanged.emit()

    def set_pose(self, pose) -> None:
        pose = tuple(float(v) for v in pose)
        if pose != self.pose:
            self.pose = pose
            self.poseChanged.emit()

    def set_desired_force(self, force) -> None:
        force = tuple(float(v) for v in force)
        if force != self.desired_force:
            self.desired_force = force
            self.poseChanged.emit()

    def set_glyph(self, name: str, visible: bool) -> None:
        if name not in GLYPHS:
            raise ValueError(f"unknown glyph {name!r}; known: {', '.join(GLYPHS)}")
        glyphs = self.glyphs | {name} if visible else self.glyphs - {name}
        if glyphs != self.glyphs:
            self.glyphs = frozenset(glyphs)
            self.glyphsChanged.emit()

    def set_pose_report(self, report) -> None:
        self.pose_report = report
        self.poseReportChanged.emit()

    def set_current_map(self, slot: MapSlot) -> None:
        self.current = slot
        self.mapChanged.emit()

    def pin_reference(self) -> None:
        """Pin the current design (and its map, if it is up to date) as the reference."""
        self.reference_mechanism = self.mechanism
        current = self.current
        self.reference = current if current is not None and current.mechanism == self.mechanism else None
        self.referenceChanged.emit()

    def clear_reference(self) -> None:
        self.reference_mechanism = None
        self.reference = None
        self.referenceChanged.emit()

    def set_reference_map(self, slot: MapSlot) -> None:
        self.reference = slot
        self.referenceChanged.emit()

    def set_compare_mode(self, mode: str) -> None:
        if mode not in ("side", "difference"):
            raise ValueError(f"compare mode must be 'side' or 'difference', got {mode!r}")
        if mode != self.compare_mode:
            self.compare_mode = mode
            self.compareModeChanged.emit()

    def set_busy(self, busy: bool) -> None:
        if busy != self.busy:
            self.busy = busy
            self.busyChanged.emit(busy)
