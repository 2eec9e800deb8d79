"""The map view: a heat map of the chosen quantity on the slice, with a colour bar.

A 3D box map (a delta's) is shown through one plane of it: the axis and position come from
the controls above the canvas (``state.slice_axis``, ``state.slice_value``), the colour scale
spans the plane's own values or, chosen there, the whole volume's (then moving the plane never
rescales it; the colour bar's title says which), and the plane's own extremes are marked. A
reference whose map varies other coordinates or units than the current one's is not drawn
beside it: the note above the canvas says why.

The view turns the state into a ``MapPicture`` (``app.logic.map_picture``: the same colour scale,
titles, extremes and overlay as the exported figures of ``app.plots.figures``) and hands it to its
``MapCanvas``, which paints it with QPainter: a new map is on screen in a frame, where a
matplotlib canvas took 100-200 ms of text and layout per slider step. A click on the map
moves the device there (``poseRequested``). With a pinned reference the view shows the
reference and the current map side by side, or their difference.

A map older than the design on screen is veiled (``STALE_TEXTS``) once it has stayed stale
for ``STALE_DELAY_MS``: while a slider moves, each coarse map replaces the last within a
frame or two, and a veil flashing at every step would say nothing.
"""
from __future__ import annotations

from dataclasses import replace
from html import escape

import numpy as np
from matplotlib.colors import to_hex, to_rgba
from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtWidgets import QComboBox, QDoubleSpinBox, QGridLayout, QLabel, QSlider, QVBoxLayout, QWidget

from app.gui.model import STALE_DELAY_MS, loading_label
from app.gui.views.map_canvas import SIDE_BY_SIDE_PX, MapCanvas
from app.gui.volumes import comparison_problem, is_volume, slice_grid, slice_index, volume_slice
from app.logic.colour_scale import COLOUR_RANGES, colour_scale
from app.logic.display_units import display_map, display_unit, relabel
from app.logic.map_marks import grid_extent
from app.logic.map_picture import map_picture
from app.logic.planes import plane_value
from app.plots.overlays import default_spacing, ellipse_field, overlay_available, overlay_drawing
from metrics.quantities import QUANTITIES

__all__ = ["MapView", "SliceControls", "SIDE_BY_SIDE_PX", "MIN_PANEL_PX", "STALE_TEXTS", "legend_html"]

#: Decimals of the plane spin box (mm): a micrometre, the digits a grid plane's title shows.
PLANE_DECIMALS = 3
#: Smallest width and height of one map panel, in pixels, at which the layout holds.
MIN_PANEL_PX = 360
#: What the stale overlay says, by reason (``AppModel.stale``).
STALE_TEXT = "STALE\nmap of earlier\nparameters; the\nnew one computes"
STALE_TEXTS = {"parameters": STALE_TEXT, "quantity": "STALE\nmap of another\nquantity; the\nnew one computes",
               "loading": "STALE\nmap of another\nrating or gravity;\nthe new one computes",
               "range": "STALE\nmap of the old\nrange; the new\none computes"}


def _frame(grid) -> tuple:
    """What fixes a map's axes: the slice, not its resolution."""
    return (grid.axes, grid.lower, grid.upper, grid.fixed)


def _plane_frame(grid) -> tuple:
    """What fixes the axes of a plane of a 3D box: which plane, not where (the title says where)."""
    return (grid.axes, grid.lower, grid.upper, tuple(name for name, _ in grid.fixed))


def reference_problem(state) -> str | None:
    """Why the reference on screen is not drawn as a comparison (``volumes.comparison_problem``), or None."""
    current, reference = state.current, state.reference
    if current is None or reference is None or state.quantity not in current.map.values:
        return None
    return comparison_problem(current.map, current.mechanism, reference.map, reference.mechanism, state.quantity)


def _grid_text(name: str, grid) -> str:
    """``"PHANToM Omni: 301 x 431 over x -60-270, z -140-260 mm"``: a map's grid, for a reason."""
    spans = ", ".join(f"{a} {lo * 1e3:g} to {hi * 1e3:g} mm" for a, lo, hi in zip(grid.axes, grid.lower, grid.upper))
    return f"{name}: {' x '.join(map(str, grid.resolution))} points over {spans}"


def difference_problem(state) -> str | None:
    """Why Compare > Difference cannot be drawn for the comparison in ``state``, or None when it can.

    A difference is taken point by point, so both maps must be on one grid: two devices' maps
    (each on its own grid) are not resampled onto a common one, because an interpolated value
    near a workspace boundary or a singularity, where these quantities change fastest, would be
    a number neither device has. A class map (the bottleneck) has no difference either.
    """
    if state.reference is None:
        return "no reference: pin a design or choose a reference device first"
    if QUANTITIES[state.quantity].categorical:
        return f"{QUANTITIES[state.quantity].label.lower()} is a class per point, which has no difference"
    ours, theirs = state.preset.grid, state.reference_grid
    if ours != theirs:
        other = state.reference_preset.name if state.reference_preset is not None else "reference"
        return ("the two maps are on different grids, and a point-by-point difference would need one "
                f"resampled ({_grid_text(other, theirs)}; {_grid_text(state.preset.name, ours)})")
    return None


class SliceControls(QWidget):
    """Axis and position (mm) of the plane of a 3D box map: a combo box, a slider and a spin box."""

    def __init__(self, state, parent=None) -> None:
        super().__init__(parent)
        self.state = state
        self.axis = QComboBox()
        self.axis.setToolTip("The axis the plane is normal to.")
        self.slider = QSlider(Qt.Orientation.Horizontal)
        self.slider.setToolTip("Move the plane through the volume (one step per grid plane).")
        self.spin = QDoubleSpinBox()
        self.spin.setSuffix(" mm")
        # To the micrometre: the grid plane the map is on, as its title prints it (172.222 mm, not 170.0).
        self.spin.setDecimals(PLANE_DECIMALS)
        self.spin.setKeyboardTracking(False)
        self.spin.setToolTip("Position of the plane, mm: a typed value moves to the nearest grid plane, "
                             "the one the map is drawn on.")
        # Two rows (the plane, then the slider and the colour range): in one row the controls
        # held the map view 515 px wide, and with a reference's columns in the statistics dock the
        # window could not keep 1600 px (the Falcon's grew to 1643 px).
        grid = QGridLayout(self)
        grid.setContentsMargins(4, 2, 4, 2)
        grid.addWidget(QLabel("Plane normal to"), 0, 0)
        grid.addWidget(self.axis, 0, 1)
        grid.addWidget(QLabel("at"), 0, 2)
        grid.addWidget(self.spin, 0, 3)
        # The colour range: a plane of 2-7 N drawn on the volume's 0-18 N is one colour.
        self.colours = QComboBox()
        for key, text in (("plane", "this plane"), ("volume", "whole volume")):
            self.colours.addItem(text, key)
        self.colours.setToolTip("Colour range of the map: this plane's values (each plane's detail), or the "
                                "whole volume's (the same colour means the same value on every plane). "
                                "Exported figures use the same.")
        grid.addWidget(self.slider, 1, 0, 1, 2)
        grid.addWidget(QLabel("Colours:"), 1, 2)
        grid.addWidget(self.colours, 1, 3)
        grid.setColumnStretch(4, 1)
        self.axis.currentTextChanged.connect(self._axis_chosen)
        self.slider.valueChanged.connect(self._from_slider)
        # While the plane is dragged the views draw only what is cheap (``AppModel.interaction``).
        self.slider.sliderPressed.connect(lambda: state.set_interaction("plane"))
        self.slider.sliderReleased.connect(lambda: state.set_interaction(None))
        self.spin.valueChanged.connect(lambda mm: self._set(self.axis.currentText(), mm / 1e3))
        state.sliceChanged.connect(self.sync)
        state.presetChanged.connect(self.sync)
        self.sync()

    def _set(self, axis: str, value: float) -> None:
        grid = self.state.preset.grid
        if axis and axis in grid.axes:
            # Snapped here: the model, the spin box and the map's title then name one plane.
            self.state.set_slice(axis, plane_value(grid, axis, value))

    def _axis_chosen(self, axis: str) -> None:
        grid = self.state.preset.grid
        if axis and axis in grid.axes and axis != self.state.slice_axis:
            k = grid.axes.index(axis)       # a new axis: its middle plane
            self._set(axis, 0.5 * (grid.lower[k] + grid.upper[k]))

    def _from_slider(self, i: int) -> None:
        grid = self.state.preset.grid
        axis = self.axis.currentText()
        if axis in grid.axes:
            self._set(axis, float(grid.coordinates()[grid.axes.index(axis)][i]))

    def sync(self) -> None:
        """Show the model's plane (signals held back: no feedback into the model)."""
        grid = self.state.preset.grid
        self.setVisible(is_volume(grid))
        if not is_volume(grid) or self.state.slice_axis is None:
            return
        axis, value = self.state.slice_axis, self.state.slice_value
        k = grid.axes.index(axis)
        for widget in (self.axis, self.slider, self.spin):
            widget.blockSignals(True)
        try:
            if [self.axis.itemText(i) for i in range(self.axis.count())] != list(grid.axes):
                self.axis.clear()
                self.axis.addItems(grid.axes)
            self.axis.setCurrentText(axis)
            self.slider.setRange(0, grid.resolution[k] - 1)
            self.slider.setValue(slice_index(grid, axis, value))
            self.spin.setRange(grid.lower[k] * 1e3, grid.upper[k] * 1e3)
            self.spin.setSingleStep(grid.spacing()[k] * 1e3)
            self.spin.setValue(plane_value(grid, axis, value) * 1e3)
        finally:
            for widget in (self.axis, self.slider, self.spin):
                widget.blockSignals(False)


class ClickableCanvas(MapCanvas):
    """A ``MapCanvas`` that reports left clicks (widget pixels)."""

    clicked = Signal(float, float)

    def mousePressEvent(self, event) -> None:   # noqa: N802 (Qt name)
        if event.button() == Qt.MouseButton.LeftButton:
            self.clicked.emit(event.position().x(), event.position().y())
        super().mousePressEvent(event)


class MapView(QWidget):
    """Shows ``state.current`` (and ``state.reference``) for ``state.quantity``."""

    #: Emitted with a task-space point (m) when the user clicks inside the map.
    poseRequested = Signal(object)
    #: What this view needs computed, beyond its quantity.
    NEEDS: tuple[str, ...] = ()

    def __init__(self, state, parent=None) -> None:
        super().__init__(parent)
        self.state = state
        self.canvas = ClickableCanvas()
        self.canvas.setToolTip("Click a point to move the device there.")
        self.canvas.setMinimumSize(MIN_PANEL_PX, MIN_PANEL_PX)
        self.slice_controls = SliceControls(state)
        self.slice_controls.colours.currentIndexChanged.connect(self.redraw)
        # Says why a reference is not drawn beside the current map (other coordinates or units).
        self.note = QLabel("")
        self.note.setWordWrap(True)
        self.note.setStyleSheet("color: #b00020; font-weight: bold; padding: 2px 4px;")
        self.note.hide()
        # Why Compare > Difference is unavailable (its menu item is disabled with the same reason).
        self.difference_note = QLabel("")
        self.difference_note.setObjectName("difference_note")
        self.difference_note.setWordWrap(True)
        self.difference_note.setStyleSheet("color: #595959; padding: 2px 4px;")
        self.difference_note.hide()
        # The overlay's key (``app.plots.overlays``), as text below the canvas: it never covers the map.
        self.overlay_legend = QLabel("")
        self.overlay_legend.setObjectName("overlay_legend")
        self.overlay_legend.setWordWrap(True)
        self.overlay_legend.setTextFormat(Qt.TextFormat.RichText)
        self.overlay_legend.setStyleSheet("padding: 2px 6px;")
        self.overlay_legend.hide()
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.slice_controls)
        layout.addWidget(self.note)
        layout.addWidget(self.difference_note)
        layout.addWidget(self.canvas, 1)
        layout.addWidget(self.overlay_legend)
        self.picture = None                 # the ``MapPicture`` on screen
        self._drawn_grid = None             # the 2D grid of the current map's panel as drawn
        self._volume_scale = None           # (key, colour scale, layers) of the volumes shown (``planes``)
        self._display: dict = {}            # (id(map), quantity) -> (map, its copy in display units)
        self._ellipses = None               # (key, EllipseField) of the design last drawn
        self._stale_timer = QTimer(self, singleShot=True, interval=STALE_DELAY_MS)
        self._stale_timer.timeout.connect(self._veil_if_stale)
        self.canvas.clicked.connect(self._on_click)
        # A full map is drawn in a turn of the event loop of its own, after the statistics panel
        # took it: its picture (the colour scale's percentiles over ~4 x 10^5 values, ~8 ms)
        # and the rest of its arrival then never block the GUI thread together (issue 11: no
        # block over 20 ms during a refine). A coarse map (a slider step) is drawn at once.
        self._redraw_timer = QTimer(self, singleShot=True, interval=0)
        self._redraw_timer.timeout.connect(self.redraw)
        state.mapChanged.connect(self._map_changed)
        for signal in (state.quantityChanged, state.referenceChanged, state.compareModeChanged,
                       state.sliceChanged, state.overlayChanged):
            signal.connect(self.redraw)
        state.interactionChanged.connect(self._on_interaction)
        state.poseChanged.connect(self._place_pose_marker)
        # New parameters on screen: the map shown is now older than them until its successor arrives.
        state.mechanismChanged.connect(self._show_stale)
        state.staleChanged.connect(self._show_stale)

    def needs(self) -> set[str]:
        """The map's quantity, and the condition number the bands overlay draws."""
        return {self.state.quantity} | ({"condition_number"} if self.state.overlay == "bands" else set())

    # -- what to draw ----------------------------------------------------------------------
    def panels(self) -> list[tuple[str, object, np.ndarray | None]]:
        """What to draw: (title, map, values override) per panel (a 3D box's whole volume)."""
        st = self.state
        current = st.current.map if st.current is not None else None
        reference = st.reference.map if st.reference is not None else None
        q = st.quantity
        if reference is None or current is None or q not in reference.values or reference_problem(st):
            return [("", current, None)] if current is not None else []
        if st.compare_mode == "difference" and reference.grid == current.grid and not QUANTITIES[q].categorical:
            diff = np.where(current.feasible & reference.feasible, current.values[q] - reference.values[q], np.nan)
            return [("current - reference", current, diff)]
        other = st.reference_preset
        if other is not None:           # another device: the titles name both
            return [(f"reference {other.name}", reference, None), (f"current {st.preset.name}", current, None)]
        return [("reference", reference, None), ("current", current, None)]

    def shown(self, panels) -> list:
        """``panels`` in the quantity's display unit (``display_units``: µm, deg); the data stay SI.

        The scaled copies are kept per map, so a plane that moves through a volume reuses them
        (and the colour scale made of them).
        """
        q = self.state.quantity
        _, factor = display_unit(q)
        if factor == 1.0:
            return panels
        out = []
        for title, wmap, values in panels:
            key = (id(wmap), q)
            if key not in self._display or self._display[key][0] is not wmap:
                self._display[key] = (wmap, display_map(wmap, q))
                while len(self._display) > 4:
                    self._display.pop(next(iter(self._display)))
            out.append((title, self._display[key][1], None if values is None else values * factor))
        return out

    @property
    def colour_range(self) -> str:
        """The colour range of a 3D box's plane: ``"plane"`` (default) or ``"volume"`` (``figures.COLOUR_RANGES``)."""
        return self.slice_controls.colours.currentData() or "plane"

    def set_colour_range(self, key: str) -> None:
        """Colour a 3D box's plane over ``key``'s range (``colour_range``): a session's choice."""
        box = self.slice_controls.colours
        index = box.findData(key)
        if index < 0:
            raise ValueError(f"colour range must be one of plane, volume, got {key!r}")
        box.setCurrentIndex(index)          # (redraws: ``currentIndexChanged``)

    def planes(self, panels) -> tuple[list, dict | None]:
        """``panels`` as drawn: a 3D box's plane at the state's slice, and its colour scale.

        The scale spans the planes' values or the whole volumes' (``colour_range``), and its
        colour bar says which. Returns the panels (2D maps) and the scale (None: ``map_picture``
        makes it from the panels, as for 2D maps).
        """
        if not panels or not is_volume(panels[0][1].grid):
            return panels, None
        st = self.state
        q = st.quantity
        difference = any(values is not None for _, _, values in panels)
        out = []
        for title, wmap, values in panels:
            plane = volume_slice(wmap, st.slice_axis, st.slice_value,
                                 extra={"_values": values} if values is not None else None, stats_of=(q,))
            out.append((title, plane, plane.values.pop("_values") if values is not None else None))
        if QUANTITIES[q].categorical:
            source = panels                 # classes: every class of the volume, whatever the plane holds
        else:
            source = panels if self.colour_range == "volume" else out
        layers = [(values if values is not None else wmap.values[q], wmap.feasible) for _, wmap, values in source]
        # The volumes' scale (percentiles of every feasible value: ~5 ms for 60^3) does not
        # change while only the plane moves: kept for the same arrays (held, so ids stay theirs).
        note = None if QUANTITIES[q].categorical else COLOUR_RANGES["volume" if source is panels else "plane"]
        key = (q, difference, note, tuple((id(v), id(f)) for v, f in layers))
        if self._volume_scale is None or self._volume_scale[0] != key:
            scale = colour_scale(q, st.preset, layers, difference=difference)
            self._volume_scale = (key, scale if note is None else scale.with_note(note), layers)
        return out, self._volume_scale[1]

    def _job_scale(self, raw, panels) -> dict | None:
        """The colour scale of the current map drawn alone, from the colour limits its map job
        computed (``MapSlot.colour_limits``, SI; scaled to the display unit); None otherwise
        (several panels, a difference, another quantity: ``map_picture`` computes the scale)."""
        st = self.state
        q = st.quantity
        if len(raw) != 1 or raw[0][2] is not None or st.current is None or raw[0][1] is not st.current.map:
            return None
        limits = st.current.colour_limits.get(q)
        if limits is None:
            return None
        _, factor = display_unit(q)
        lo, hi, capped = limits
        wmap = panels[0][1]
        return colour_scale(q, st.preset, [(wmap.values[q], wmap.feasible)], limits=(lo * factor, hi * factor, capped))

    def stale(self) -> str | None:
        """Why the current map on screen is older than the state (None: it is up to date).

        The model says (``AppModel.stale``): a map of other parameters or of another quantity
        stays on screen, marked, until its successor arrives.
        """
        return self.state.stale

    def side_by_side_fits(self) -> bool:
        """Whether two panels fit next to each other in the canvas as it is now."""
        return self.canvas.width() >= SIDE_BY_SIDE_PX

    def holding(self) -> bool:
        """The plane slider is held: titles, legends and extremes wait for its release.

        Each step of a held plane slider changes the plane's title and extremes; hidden,
        nothing stale is on screen (the spin box beside the slider says where the plane is).
        """
        return self.state.interaction == "plane"

    def title_of(self, title: str, wmap, plane: bool) -> str:
        """A panel's title: its own (or the device's name), then how the map was loaded (rating, gravity)."""
        head = title or (f"{self.state.preset.name}, plane" if plane else self.state.preset.name)
        return f"{loading_label(wmap.loading)}\n{head}"      # a line of its own: narrow panels clip

    def _on_interaction(self) -> None:
        """A plane slider pressed or released: a 3D box's labels hide or come back (``holding``)."""
        if self.state.current is not None and is_volume(self.state.current.map.grid):
            self.redraw()

    # -- drawing ---------------------------------------------------------------------------
    def _map_changed(self) -> None:
        current = self.state.current
        if current is not None and current.stage == "full":
            self._redraw_timer.start()
        else:
            self.redraw()

    def redraw(self) -> None:
        self._redraw_timer.stop()          # drawn now: a pending full-map redraw would repeat it
        st = self.state
        q = st.quantity
        if st.current is not None and q not in st.current.map.values:
            self._show_stale()   # a newly chosen quantity: the old picture, marked, until its map arrives
            return
        problem = reference_problem(st)
        self.note.setText(f"Not compared: {problem}." if problem else "")
        self.note.setVisible(bool(problem))
        # Only a comparison that is drawn (side by side) but cannot be a difference gets this note.
        no_difference = difference_problem(st) if st.reference is not None and not problem else None
        if no_difference is not None and QUANTITIES[q].categorical:
            no_difference = None            # (classes are always side by side: nothing to explain)
        self.difference_note.setText(f"Side by side; no difference: {no_difference}." if no_difference else "")
        self.difference_note.setVisible(bool(no_difference))
        raw = self.panels()
        panels, scale = self.planes(self.shown(raw))
        if scale is None:
            scale = self._job_scale(raw, panels)
        frame = _frame if scale is None or not is_volume(st.preset.grid) else _plane_frame
        full = st.preset.grid
        if is_volume(full) and st.slice_axis is not None:
            full = slice_grid(full, st.slice_axis, st.slice_value)
        limits = [grid_extent(full) if frame(full) == frame(wmap.grid) else None for _, wmap, _ in panels]
        plane = scale is not None and is_volume(st.preset.grid)
        picture = map_picture([(self.title_of(title, wmap, plane), wmap, values)
                               for title, wmap, values in panels], q, st.preset, scale=scale, limits=limits,
                              narrow=True)       # coordinates on a line of their own: none clipped
        if not panels:
            picture.message = f"Computing the map of\n{st.preset.name}..."
        for panel, (title, _, _) in zip(picture.panels, panels):
            panel.labels_shown = not self.holding()
            panel.reference = title.startswith("reference")      # the pinned design: never stale
        self._relabel(picture)
        self._drawn_grid = panels[-1][1].grid if panels else None
        self._add_overlay(picture, plane=plane)
        self.picture = picture
        self.canvas.show_picture(picture)
        self._place_pose_marker()
        self._show_stale()

    def _relabel(self, picture) -> None:
        """The colour bar's label and the legend's extremes in the display unit the values were drawn in."""
        q = self.state.quantity
        if display_unit(q)[1] == 1.0 or picture.bar is None:
            return
        picture.bar = replace(picture.bar, label=relabel(picture.bar.label, q))
        for panel in picture.panels:
            panel.legend = tuple((symbol, colour, relabel(text, q)) for symbol, colour, text in panel.legend)

    def _add_overlay(self, picture, *, plane: bool) -> None:
        """The state's overlay over the current map's panel (the last), its key below the canvas.

        Drawn from the map on screen and the design it was computed for (``MapSlot.mechanism``),
        so a stale map carries its own overlay. A device or map the overlay does not apply to
        gets the reason in place of the key.
        """
        st = self.state
        overlay, current = st.overlay, st.current
        problem = None
        if current is not None:
            problem = overlay_available(overlay, current.mechanism, current.map.grid)
        if overlay == "none" or current is None or problem is not None or plane or not picture.panels:
            self.overlay_legend.setText(f"<b>Overlay not drawn:</b> {problem}." if problem else "")
            self.overlay_legend.setVisible(problem is not None)
            return
        field = self._ellipse_field(current, overlay.split()[0]) if overlay.endswith("ellipses") else None
        drawing = overlay_drawing(overlay, current.map, current.mechanism, field=field)
        picture.panels[-1].overlay = drawing
        self.overlay_legend.setText(legend_html(drawing))
        self.overlay_legend.show()

    def _ellipse_field(self, slot, kind: str):
        """The ellipse field of the design on screen, computed once per design, grid and kind."""
        key = (slot.mechanism, slot.map.grid, kind)
        if self._ellipses is None or self._ellipses[0] != key:
            grid = self.state.preset.grid        # one lattice for the coarse and the full map
            self._ellipses = (key, ellipse_field(slot.mechanism, slot.map.grid, default_spacing(grid), kind=kind))
        return self._ellipses[1]

    def _show_stale(self, *_) -> None:
        """The map on screen is older than the state: veiled once it has stayed so for a moment."""
        if self.stale() is None:
            self._stale_timer.stop()
            self.canvas.set_stale(None)
        elif self.canvas.stale is None and not self._stale_timer.isActive():
            self._stale_timer.start()
        elif self.canvas.stale is not None:
            self.canvas.set_stale(STALE_TEXTS.get(self.stale(), STALE_TEXT))

    def _veil_if_stale(self) -> None:
        reason = self.stale()
        self.canvas.set_stale(STALE_TEXTS.get(reason, STALE_TEXT) if reason is not None else None)

    def _place_pose_marker(self) -> None:
        pose, grid = self.state.pose, self._drawn_grid
        if pose is None or grid is None or self.state.current is None:
            self.canvas.set_pose(None)
            return
        names = self.state.mechanism.task_names
        self.canvas.set_pose(*pose_on_plane(pose, names, grid, self.state.current.map.grid))

    # -- interaction -----------------------------------------------------------------------
    def _on_click(self, px: float, py: float) -> None:
        hit = self.canvas.to_data(px, py)
        if hit is None or self.state.current is None:
            return
        self.poseRequested.emit(self.point_at(hit[1], hit[2]))

    def point_at(self, x_mm: float, y_mm: float) -> tuple[float, ...]:
        """The task point (m) under map coordinates (mm), fixed coordinates filled in (a plane's position too)."""
        grid = self._drawn_grid if self._drawn_grid is not None else self.state.current.map.grid
        names = self.state.mechanism.task_names
        fixed = dict(grid.fixed)
        point = []
        for name in names:
            if name == grid.axes[0]:
                point.append(x_mm / 1e3)
            elif name == grid.axes[1]:
                point.append(y_mm / 1e3)
            else:
                point.append(fixed[name])
        return tuple(point)

    def data_to_widget(self, x_mm: float, y_mm: float, panel: int = -1) -> tuple[int, int]:
        """Widget pixel (for tests and scripts) of a map point in the given panel."""
        p = self.canvas.to_pixel(panel % len(self.canvas.layouts), x_mm, y_mm)
        return int(round(p.x())), int(round(p.y()))


def pose_on_plane(pose, names, drawn, volume) -> tuple[tuple[float, float] | None, str | None]:
    """Where the pose cross goes on the map drawn on grid ``drawn`` (mm), or None and where the pose is.

    On a plane of a 3D box (``volume``, the grid of the map it was cut from) the cross is drawn
    only when the pose's nearest grid plane is this one; otherwise the note says where the pose
    is ("pose at z = 110 mm"). On a 2D map the cross is always drawn.
    """
    at = tuple(pose[names.index(a)] * 1e3 for a in drawn.axes[:2])
    if not is_volume(volume):
        return at, None
    for axis, value in drawn.fixed:
        if axis in volume.axes and axis in names:
            there = pose[names.index(axis)]
            if slice_index(volume, axis, there) != slice_index(volume, axis, value):
                return None, f"pose at {axis} = {there * 1e3:g} mm"
    return at, None


def legend_html(drawing) -> str:
    """An overlay's legend (``app.plots.overlays.OverlayDrawing``: ``title``, ``rows``) as rich text, a swatch a row."""
    rows = []
    for _, colour, text in drawing.rows:
        swatch = f'<span style="color:{to_hex(to_rgba(colour))}">&#9632;</span> ' if colour is not None else ""
        rows.append(swatch + escape(text))
    return f"<b>{escape(drawing.title)}</b><br>" + " &nbsp; ".join(rows)
