"""The semi-dextrous region in the 3D workspace view: a toggle, the bound, and the surface.

For a device with orientation freedoms the workspace view offers "Semi-dextrous region
(+-30 deg)" (off by default) with the bound as a spin box. On, the region
(``app.gui.dextrous``) is computed in the background on a job runner of its own (cancellable,
newest wins): a coarse grid first, then the full one, again whenever the design or the bound
changes (a drag's coarse regions follow it, the full one waits until it rests). It is drawn as
a smooth solid surface (``app.scenes.dextrous_figure.region_mesh``, mm, scaled to the view's metres)
with a caption under the controls: its volume in cm^3 and the volume's grid error. The caption
is Qt text, not text in the 3D scene: it wraps to the view's width, where a scene's corner text
ran under the view's "Reset view" button. Off, the surface and caption go and any job stops.
"""
from __future__ import annotations

import math

from PySide6.QtCore import Qt, QTimer
from PySide6.QtWidgets import QCheckBox, QDoubleSpinBox, QHBoxLayout, QLabel, QSizePolicy, QVBoxLayout, QWidget

from app.gui.dextrous import (
    COARSE_TAG,
    DEFAULT_ANGLE_DEG,
    FULL_TAG,
    has_region,
    region_request,
    region_text,
    run_region,
)
from app.gui.qt_model import QtJobRunner
from app.scenes.dextrous_figure import REGION_COLOUR, region_mesh

#: The region's actor name in the workspace view's plotter.
ACTOR = "dextrous_region"
#: How long the design must rest before the full region is computed, ms (as the maps' refinement).
REFINE_DELAY_MS = 250
#: The surface's opacity and the caption's colour (a darker shade of the region's).
REGION_OPACITY = 0.45
CAPTION_COLOUR = "#1f4e8c"


class DextrousLayer(QWidget):
    """The controls (a row for the view's bar), the region's caption under them, and its actor in ``plotter``."""

    def __init__(self, state, plotter, render, refit, annotate, parent=None) -> None:
        super().__init__(parent)
        self.state = state
        self.plotter = plotter
        self._render = render                   # asks the view for a new frame
        self._refit = refit                     # frames the view again, unless the user moved its camera
        self._annotate = annotate               # the view's axes drawn again round what it shows
        self.toggle = QCheckBox()
        self.toggle.setToolTip("The positions where the device can hold every orientation within the bound "
                               "(tip of the pen axis in any direction, roll, and the pure axis rotations; "
                               "paper 001 sec. V). Computed in the background, coarse first.")
        self.angle = QDoubleSpinBox()
        self.angle.setRange(1.0, 90.0)
        self.angle.setSingleStep(5.0)
        self.angle.setDecimals(1)
        self.angle.setSuffix(" deg")
        self.angle.setValue(DEFAULT_ANGLE_DEG)
        self.angle.setKeyboardTracking(False)
        self.angle.setToolTip("Orientation bound of the semi-dextrous region, deg, in (0, 90].")
        self.status = QLabel("")
        # Progress and errors may be long: they never widen the view (the splitter decides).
        self.status.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Preferred)
        #: The region's volume and grid, wrapped to the view's width (empty and hidden without a region).
        self.caption = QLabel("")
        self.caption.setWordWrap(True)
        self.caption.setStyleSheet(f"color: {CAPTION_COLOUR}")
        # Never wider than the view; as tall as its lines wrapped to the width it gets (height for
        # width: a policy set without it kept the one-line height, and at 1600 x 950 the wrapped
        # lines, centred in it, ran under the spin box and past the bottom).
        policy = QSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Preferred)
        policy.setHeightForWidth(True)
        self.caption.setSizePolicy(policy)
        self.caption.setAlignment(Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignTop)
        self.caption.hide()
        # Never wider than the view either: a view narrower than the controls' row (the splitter
        # decides) clips the row, and the caption wraps to the width it has (laid out at the row's
        # minimum width instead, it got fewer lines' height than it showed).
        self.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Preferred)
        column = QVBoxLayout(self)
        column.setContentsMargins(4, 0, 4, 0)
        column.setSpacing(0)
        row = QHBoxLayout()
        row.addWidget(self.toggle)
        row.addWidget(self.angle)
        row.addWidget(self.status, 1)
        column.addLayout(row)
        column.addWidget(self.caption)
        self.runner = QtJobRunner(run_region, self, name="isoforce-dextrous")
        self.runner.resultReady.connect(self._on_result)
        self.runner.progressed.connect(self._on_progress)
        self.region = None                      # the region drawn, and its request
        self.request = None
        self._refine = QTimer(self, singleShot=True, interval=REFINE_DELAY_MS)
        self._refine.timeout.connect(lambda: self._submit("full"))
        self.toggle.toggled.connect(self._changed)
        self.angle.valueChanged.connect(self._angle_changed)
        state.mechanismChanged.connect(self._design_changed)
        state.presetChanged.connect(self._preset_changed)
        self._preset_changed()

    # -- state -----------------------------------------------------------------------------
    def _label(self) -> None:
        self.toggle.setText(f"Semi-dextrous region (±{self.angle.value():g} deg)")

    def _preset_changed(self) -> None:
        """A new device: off, and offered only if it has orientation freedoms."""
        self.toggle.blockSignals(True)
        self.toggle.setChecked(False)
        self.toggle.blockSignals(False)
        self.setVisible(has_region(self.state.mechanism))
        self._label()
        self._clear()

    def _angle_changed(self) -> None:
        self._label()
        if self.toggle.isChecked():
            self._changed()

    def _design_changed(self) -> None:
        if not self.toggle.isChecked():
            return
        self.runner.cancel(FULL_TAG)            # the old design's full region would hold the worker
        self._submit("coarse")
        self._refine.start()

    def _changed(self, _=None) -> None:
        if not self.toggle.isChecked():
            self._clear()
            return
        self.runner.cancel()
        self._submit("coarse")
        self._submit("full")

    def _submit(self, stage: str) -> None:
        st = self.state
        try:
            request = region_request(st.mechanism, st.preset.grid, self.angle.value(), stage)
        except ValueError as exc:
            self.status.setText(f"No region: {exc}")
            return
        self.request = self.runner.submit(request)
        self.status.setText(f"computing the {stage} region...")

    def _clear(self) -> None:
        self._refine.stop()
        self.runner.cancel()
        self.region = self.request = None
        self.status.setText("")
        self._set_caption("")
        if self.plotter.actors.get(ACTOR) is not None:
            self.plotter.remove_actor(ACTOR, reset_camera=False, render=False)
            self._annotate()
        self._render()

    def _set_caption(self, text: str) -> None:
        self.caption.setText(text)
        self.caption.setVisible(bool(text))

    # -- results ---------------------------------------------------------------------------
    def wanted(self, request) -> bool:
        """Whether a result of ``request`` is of what the controls ask for now."""
        return (self.toggle.isChecked() and self.runner.is_current(request)
                and request.mechanism == self.state.mechanism and request.angle == math.radians(self.angle.value()))

    def _on_progress(self, request, fraction: float) -> None:
        if self.wanted(request):
            self.status.setText(f"computing the {request.stage} region... {100 * fraction:.0f} %")

    def _on_result(self, request, result) -> None:
        if not self.wanted(request) or getattr(self.plotter, "_closed", False):
            return
        if isinstance(result, Exception):
            self.status.setText(f"The region could not be computed: {result}")
            return
        shown = self.region[1] if self.region is not None else None
        if (request.tag == COARSE_TAG and shown is not None and shown.tag == FULL_TAG
                and shown.mechanism == request.mechanism and shown.angle == request.angle):
            return                              # its full region is on screen already
        self.region = (result, request)
        self.status.setText("" if request.stage == "full" else "coarse; refining...")
        self.draw()

    def draw(self) -> None:
        """The region's surface (m, as the view) and its caption; an empty region removes the surface."""
        region, request = self.region
        mesh = region_mesh(region)
        if mesh.n_points:
            first = self.plotter.actors.get(ACTOR) is None
            # See-through: the region holds the map's surface (and the device) inside it.
            self.plotter.add_mesh(mesh.scale(1e-3, inplace=False), color=REGION_COLOUR, smooth_shading=True,
                                  opacity=REGION_OPACITY, name=ACTOR, reset_camera=False, render=False)
            self._annotate()
            if first:
                # The region is a solid and may reach beyond the map drawn: the view frames both
                # (obliquely: ``WorkspaceView.fit_camera``), unless the user moved the camera.
                self._refit()
        elif self.plotter.actors.get(ACTOR) is not None:
            self.plotter.remove_actor(ACTOR, reset_camera=False, render=False)
            self._annotate()
        self._set_caption(region_text(region, request.stage))
        self._render()

    def shutdown(self) -> None:
        self._refine.stop()
        self.runner.shutdown()
