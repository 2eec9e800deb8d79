"""The map view: a heat map of the chosen quantity on the slice, with a colour bar.

A 3D box map (a delta's) is shown through one plane of it: the axis and position come from
the controls above the canvas (``state.slice_axis``, ``state.slice_value``), the colour scale
spans the whole volume (moving the plane never rescales it), and the plane's own extremes
are marked. A reference whose map varies other coordinates or units than the current one's
is not drawn beside it: the note above the canvas says why.

Matplotlib on a Qt canvas. The image artist is kept and only its data and norm change on an
update, so a new map costs one canvas draw, not a rebuilt figure. A click on the map moves
the device there (``poseRequested``). With a pinned reference the view shows the reference
and the current map side by side, or their difference.

A full draw of the figure (layout, axes, ticks, every label) takes 100-200 ms, too long for
a map that follows a slider. So what a new map changes is drawn by blitting: the image,
markers and legend, the title and the colour bar are *animated* artists, left out of the
full draw, whose background pixels are kept; a new map restores those regions and draws
just those artists into them (a title or colour bar only if its text or scale changed).
A coarse map (a slider moving) goes on screen whole, in one blit: heat map, legend, colour
bar and title of the same design in the same frame. For a full map the heat map and its
markers go on screen at once (the legend's last pixels kept in place); the legend, colour bar
and title follow one per turn of the event loop, so no step blocks the GUI thread for long
(matplotlib's text is the slow part). The full draw runs only when
the figure's layout changes: another quantity, panels or slice, a colour scale of another
kind, or a resize. The axes' limits are the full grid's cells, so a coarse map and the full
one share a layout.
"""
from __future__ import annotations

from html import escape

import numpy as np
from matplotlib.backends.backend_qtagg import FigureCanvasQTAgg
from matplotlib.colors import to_hex, to_rgba
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle
from matplotlib.transforms import Bbox
from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtWidgets import QComboBox, QDoubleSpinBox, QHBoxLayout, QLabel, QSlider, QVBoxLayout, QWidget

from app.figures import colour_scale, draw_map, draw_panels, grid_extent
from app.overlays import default_spacing, draw_overlay, ellipse_field, overlay_available
from metrics.quantities import QUANTITIES

from ..display_units import display_map, display_unit, relabel
from ..model import loading_label
from ..volumes import comparison_problem, is_volume, slice_grid, slice_index, volume_slice

#: Smallest width and height of one map panel, in pixels, at which the layout holds.
MIN_PANEL_PX = 360
#: Narrowest canvas that holds a reference and a current map side by side (two panels
#: without a colour bar of their own, and one shared bar); narrower, they stack.
SIDE_BY_SIDE_PX = 660
#: What the stale overlay says, and its colour.
STALE_TEXT = "STALE\nmap of earlier\nparameters; the\nnew one computes"
STALE_COLOUR = "#b00020"
#: The stale overlay's text by reason (``AppModel.stale``).
STALE_TEXTS = {"parameters": STALE_TEXT, "quantity": "STALE\nmap of another\nquantity; the\nnew one computes",
               "loading": "STALE\nmap of another\nrating or gravity;\nthe new one computes"}


#: Pause before each deferred group (legend, colour bar, title) is drawn, ms.
LATER_MS = 8


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
        self.spin.setDecimals(1)
        self.spin.setKeyboardTracking(False)
        self.spin.setToolTip("Position of the plane, mm (the nearest grid plane is shown).")
        row = QHBoxLayout(self)
        row.setContentsMargins(4, 2, 4, 2)
        row.addWidget(QLabel("Plane normal to"))
        row.addWidget(self.axis)
        row.addWidget(QLabel("at"))
        row.addWidget(self.slider, 1)
        row.addWidget(self.spin)
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
        if axis:
            self.state.set_slice(axis, value)

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
            self.spin.setValue(value * 1e3)
        finally:
            for widget in (self.axis, self.slider, self.spin):
                widget.blockSignals(False)


class MapView(QWidget):
    """Shows ``state.current`` (and ``state.reference``) for ``state.quantity``."""

    #: Emitted with a task-space point (m) when the user clicks inside the map.
    poseRequested = Signal(object)
    #: What this view needs computed, beyond its quantity.
    NEEDS: tuple[str, ...] = ()

    def __init__(self, state, parent=None) -> None:
        super().__init__(parent)
        self.state = state
        self.figure = Figure(figsize=(6, 5), layout="compressed")
        self.canvas = FigureCanvasQTAgg(self.figure)
        self.canvas.setToolTip("Click a point to move the device there.")
        # Below about 340 px a panel's colour bar, labels and legend leave the axes no room
        # (matplotlib's layout collapses and warns); the splitter may not squeeze it further.
        self.canvas.setMinimumSize(MIN_PANEL_PX, MIN_PANEL_PX)
        self.slice_controls = SliceControls(state)
        # Says why a reference is not drawn beside the current map (other coordinates or units).
        self.note = QLabel("")
        self.note.setWordWrap(True)
        self.note.setStyleSheet("color: #b00020; font-weight: bold; padding: 2px 4px;")
        self.note.hide()
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.slice_controls)
        layout.addWidget(self.note)
        layout.addWidget(self.canvas, 1)
        # The overlay's key (``app.overlays``): Qt text below the canvas, so it costs no
        # matplotlib layout and never covers the map.
        self.overlay_legend = QLabel("")
        self.overlay_legend.setObjectName("overlay_legend")
        self.overlay_legend.setWordWrap(True)
        self.overlay_legend.setTextFormat(Qt.TextFormat.RichText)
        self.overlay_legend.setStyleSheet("padding: 2px 6px;")
        self.overlay_legend.hide()
        layout.addWidget(self.overlay_legend)
        self._overlay_artists: list = []    # what the overlay added to the current map's axes
        self._ellipses = None               # (mechanism, grid, kind, EllipseField) last computed
        self._drawn_grid = None             # the 2D grid of the current map's panel as drawn
        self._volume_scale = None           # (key, colour scale, layers) of the volumes shown (``planes``)
        self._display: dict = {}            # (id(map), quantity) -> (map, its copy in display units)
        self._axes: list = []
        self._artists: list = []
        self._layout_key = None
        self._pose_marker = None
        self._stale_artists: list = []      # per panel: (veil, text) drawn over a stale map
        self._side_by_side = False
        # Blitting (see the module's docstring): region -> (Bbox, background pixels) per
        # group ("plot" | "title" | "bar", panel); what each group shows; the canvas size.
        self._regions: dict = {}
        self._shown: dict = {}
        self._background_size = None
        self._full_draw_pending = False
        self._legend_pixels: dict = {}      # panel -> the legend's pixels as last drawn
        self._later: list = []              # groups still to draw, one per turn of the event loop
        # A few ms apart: what else waits for the GUI thread (a 3D view's new frame) goes first.
        self._later_timer = QTimer(self, singleShot=True, interval=LATER_MS)
        self._later_timer.timeout.connect(self._draw_later)
        self.canvas.mpl_connect("draw_event", self._on_full_draw)
        self.canvas.mpl_connect("button_press_event", self._on_click)
        for signal in (state.mapChanged, state.quantityChanged, state.referenceChanged, state.compareModeChanged,
                       state.sliceChanged, state.overlayChanged):
            signal.connect(self.redraw)
        state.poseChanged.connect(self._draw_pose_marker)
        state.interactionChanged.connect(self._on_interaction)
        # New parameters on screen: the map shown is now older than them until its successor arrives.
        state.mechanismChanged.connect(self._show_stale)
        # Two panels sit side by side when the canvas is wide enough; a resize may change that.
        self._relayout_timer = QTimer(self, singleShot=True, interval=50)
        self._relayout_timer.timeout.connect(self._relayout_if_needed)

    def needs(self) -> set[str]:
        """The map's quantity, and the condition number the bands overlay draws."""
        return {self.state.quantity} | ({"condition_number"} if self.state.overlay == "bands" else set())

    # -- drawing ---------------------------------------------------------------------------
    def panels(self) -> list[tuple[str, object, np.ndarray | None]]:
        """What to draw: (title, map, values override) per axes (a 3D box's whole volume)."""
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

    def _relabel(self) -> None:
        """The colour bar's label and the legend's extremes in the display unit the values were drawn in."""
        q = self.state.quantity
        if display_unit(q)[1] == 1.0:
            return
        for ax, art in zip(self._axes, self._artists):
            if art is None:
                continue
            bar = art["colorbar"]
            if bar is not None:
                label = bar.ax.get_ylabel() if bar.orientation == "vertical" else bar.ax.get_xlabel()
                bar.set_label(relabel(label, q))
            for line in art.get("extremes", []):
                line.set_label(relabel(line.get_label(), q))
            legend = ax.get_legend()
            if legend is not None:
                for text in legend.get_texts():
                    text.set_text(relabel(text.get_text(), q))

    def planes(self, panels) -> tuple[list, dict | None]:
        """``panels`` as drawn: a 3D box's plane at the state's slice, and the volumes' one colour scale.

        Returns the panels (2D maps) and the scale (None: ``draw_panels`` makes it from the
        panels, as for 2D maps).
        """
        if not panels or not is_volume(panels[0][1].grid):
            return panels, None
        st = self.state
        q = st.quantity
        difference = any(values is not None for _, _, values in panels)
        layers = [(values if values is not None else wmap.values[q], wmap.feasible) for _, wmap, values in panels]
        # The volumes' scale (percentiles of every feasible value: ~5 ms for 60^3) does not
        # change while only the plane moves: kept for the same arrays (held, so ids stay theirs).
        key = (q, difference, tuple((id(v), id(f)) for v, f in layers))
        if self._volume_scale is None or self._volume_scale[0] != key:
            self._volume_scale = (key, colour_scale(q, st.preset, layers, difference=difference), layers)
        scale = self._volume_scale[1]
        out = []
        for title, wmap, values in panels:
            plane = volume_slice(wmap, st.slice_axis, st.slice_value,
                                 extra={"_values": values} if values is not None else None, stats_of=(q,))
            out.append((title, plane, plane.values.pop("_values") if values is not None else None))
        return out, scale

    def stale(self) -> str | None:
        """Why the current map on screen is older than the state (None: it is up to date).

        The model says (``AppModel.stale``): a map of other parameters or of another quantity
        stays on screen, marked, until its successor arrives.
        """
        return self.state.stale

    def side_by_side_fits(self) -> bool:
        """Whether two panels fit next to each other in the canvas as it is now."""
        return self.canvas.width() >= SIDE_BY_SIDE_PX

    def redraw(self) -> None:
        q = self.state.quantity
        if self.state.current is not None and q not in self.state.current.map.values:
            self._show_stale()   # a newly chosen quantity: the old picture, marked, until its map arrives
            return
        problem = reference_problem(self.state)
        self.note.setText(f"Not compared: {problem}." if problem else "")
        self.note.setVisible(bool(problem))
        panels, scale = self.planes(self.shown(self.panels()))
        frame = _frame if scale is None else _plane_frame
        titles = [self.title_of(title, wmap, scale is not None) for title, wmap, _ in panels]
        side = len(panels) > 1 and self.side_by_side_fits()
        key = (q, tuple(title for title, _, _ in panels), tuple(frame(m.grid) for _, m, _ in panels), side)
        rebuild = key != self._layout_key
        if rebuild:
            self.figure.clear()
            # A comparison: side by side, one colour bar at the right; stacked only when the
            # canvas is too narrow for two.
            rows, cols = (1, len(panels)) if side else (len(panels), 1)
            self._axes = [self.figure.add_subplot(rows, cols, i + 1) for i in range(len(panels))]
            self._artists = [None] * len(panels)
            self._stale_artists = []
            self._pose_marker = None
            self._layout_key = key
            self._side_by_side = side
            self._overlay_artists = []      # gone with the axes
            if not panels and self.state.current is None:
                self.figure.text(0.5, 0.5, f"Computing the map of\n{self.state.preset.name}...", ha="center",
                                 va="center", fontsize=10, color="0.35")
        full = self.state.preset.grid
        if is_volume(full) and self.state.slice_axis is not None:
            full = slice_grid(full, self.state.slice_axis, self.state.slice_value)
        self._drawn_grid = panels[-1][1].grid if panels else None
        # Off the axes before the map's legend is remade (it would list the overlay's labelled artists).
        for artist in self._overlay_artists:
            artist.remove()
        self._overlay_artists = []
        if panels:
            limits = [grid_extent(full) if frame(full) == frame(wmap.grid) else None for _, wmap, _ in panels]
            old = list(self._artists)
            if scale is None:
                self._artists = draw_panels(self.figure, self._axes, [
                    (title, wmap, values) for title, (_, wmap, values) in zip(titles, panels)], q, self.state.preset,
                    artists=old, limits=limits, fast_image=True, narrow=True)   # coordinates on a line: none clipped
            else:
                self._artists = self._draw_planes(panels, scale, old, limits, titles)
            # New axes content (another kind of scale): a new layout.
            rebuild = rebuild or any(a is not b for a, b in zip(self._artists, old))
        self._relabel()
        self._draw_overlay(plane=scale is not None)
        self._hold_labels()
        self._place_pose_marker()
        self._place_stale_marks()
        self._show_changes(full_draw=rebuild)

    def _draw_overlay(self, *, plane: bool) -> None:
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
        if overlay == "none" or current is None or problem is not None or plane or not self._axes \
                or st.quantity not in current.map.values:
            self.overlay_legend.setText(f"<b>Overlay not drawn:</b> {problem}." if problem else "")
            self.overlay_legend.setVisible(problem is not None)
            return
        field = self._ellipse_field(current, overlay.split()[0]) if overlay.endswith("ellipses") else None
        drawn = draw_overlay(self._axes[-1], overlay, current.map, current.mechanism, field=field)
        self._overlay_artists = list(drawn["artists"])
        for artist in self._overlay_artists:
            artist.set_in_layout(False)     # the key's text may reach out of the axes: no new layout
        self.overlay_legend.setText(legend_html(drawn))
        self.overlay_legend.show()

    def _ellipse_field(self, slot, kind: str):
        """The ellipse field of the design on screen, computed once per design, grid and kind."""
        key = (slot.mechanism, slot.map.grid, kind)
        if self._ellipses is None or self._ellipses[0] != key:
            grid = self.state.preset.grid        # one lattice for the coarse and the full map
            self._ellipses = (key, ellipse_field(slot.mechanism, slot.map.grid, default_spacing(grid), kind=kind))
        return self._ellipses[1]

    def holding(self) -> bool:
        """The plane slider is held: only the heat map follows it (``_hold_labels``)."""
        return self.state.interaction == "plane"

    def _hold_labels(self) -> None:
        """Titles, legends and extreme markers hidden while the plane slider is held, shown otherwise.

        Each step of a held plane slider changes the plane's title (its position, feasible
        points) and its extremes; their text is most of a step's drawing time (~150 of ~200 ms).
        Hidden, nothing stale is on screen (the spin box beside the slider says where the
        plane is); on release they are drawn once for the plane shown.
        """
        shown = not self.holding()
        for ax, art in zip(self._axes, self._artists):
            if art is None:
                continue
            ax.title.set_visible(shown)
            legend = ax.get_legend()
            for artist in [*art.get("extremes", []), *([legend] if legend is not None else [])]:
                artist.set_visible(shown)

    def _on_interaction(self) -> None:
        if self.state.current is not None and is_volume(self.state.current.map.grid):
            self.redraw()

    def title_of(self, title: str, wmap, plane: bool) -> str:
        """A panel's title: its own (or the device's name), then how the map was loaded (rating, gravity)."""
        head = title or (f"{self.state.preset.name}, plane" if plane else self.state.preset.name)
        return f"{loading_label(wmap.loading)}\n{head}"      # a line of its own: narrow panels clip

    def _draw_planes(self, panels, scale, old, limits, titles) -> list:
        """``draw_panels`` with the colour scale of the whole volumes (``planes``), not of the planes shown."""
        out = []
        for i, ((_, wmap, values), title) in enumerate(zip(panels, titles)):
            last = i == len(panels) - 1
            out.append(draw_map(self.figure, self._axes[i], wmap, self.state.quantity, self.state.preset,
                                values=values, title=title,
                                artists=old[i], limits=limits[i], fast_image=True, scale=scale,
                                colorbar=(True if len(panels) == 1 else list(self._axes)) if last else False,
                                narrow=True))
        return out

    def _place_stale_marks(self) -> None:
        """A veil and a note over the current map's panel while it is stale (kept, hidden, otherwise)."""
        stale = self.stale()
        titles = self._layout_key[1] if self._layout_key is not None else ()
        marks = []
        for i, ax in enumerate(self._axes):
            old = self._stale_artists[i] if i < len(self._stale_artists) else None
            if old is None or old[0].axes is not ax:
                veil = ax.add_patch(Rectangle((0.0, 0.0), 1.0, 1.0, transform=ax.transAxes, facecolor="white",
                                              alpha=0.6, edgecolor=STALE_COLOUR, linewidth=3.0, hatch="//",
                                              zorder=10, clip_on=False, label="_stale"))
                text = ax.text(0.5, 0.5, STALE_TEXT, transform=ax.transAxes, ha="center", va="center",
                               fontsize=9, fontweight="bold", color=STALE_COLOUR, zorder=11, clip_on=True,
                               bbox={"boxstyle": "round", "facecolor": "white", "edgecolor": STALE_COLOUR})
                old = (veil, text)
            # The reference panel shows the pinned design: only the current one can be stale.
            shown = stale is not None and (i >= len(titles) or not titles[i].startswith("reference"))
            old[1].set_text(STALE_TEXTS.get(stale, STALE_TEXT))
            for artist in old:
                artist.set_visible(shown)
            marks.append(old)
        self._stale_artists = marks

    def _show_stale(self) -> None:
        """The parameters (or quantity) changed: mark the map on screen as stale, at once."""
        if not self._axes:
            return
        self._place_stale_marks()
        # The veil covers the axes only; the legend, below them, keeps its pixels (not redrawn:
        # its text is most of a blit's time).
        self._show_changes(full_draw=False, data=False)

    def resizeEvent(self, event) -> None:   # noqa: N802 (Qt name)
        super().resizeEvent(event)
        self._relayout_timer.start()

    def _relayout_if_needed(self) -> None:
        if len(self._axes) > 1 and self.side_by_side_fits() != self._side_by_side:
            self.redraw()

    def _draw_pose_marker(self) -> None:
        self._place_pose_marker()
        self._show_changes(full_draw=False, data=False)

    def _place_pose_marker(self) -> None:
        pose = self.state.pose
        plots = self._axes
        if pose is None or not plots or self.state.current is None or self._drawn_grid is None:
            return
        grid = self._drawn_grid
        names = self.state.mechanism.task_names
        px, py = (pose[names.index(a)] * 1e3 for a in grid.axes[:2])
        if self._pose_marker is not None and all(line.axes is ax for line, ax in zip(self._pose_marker, plots)):
            for line in self._pose_marker:
                line.set_data([px], [py])
        else:
            self._pose_marker = [ax.plot([px], [py], "+", color="red", markersize=16, mew=2.5,
                                         label="_pose")[0] for ax in plots]

    # -- blitting --------------------------------------------------------------------------
    def _groups(self, i: int) -> dict:
        """The animated artists of panel ``i`` by group, in drawing order."""
        ax, art = self._axes[i], self._artists[i]
        legend = ax.get_legend()
        marks = list(self._stale_artists[i]) if i < len(self._stale_artists) else []
        overlay = self._overlay_artists if i == len(self._axes) - 1 else []
        drawn = {id(a): a for a in [*ax.images, *ax.lines, *overlay, *([legend] if legend is not None else []),
                                    *marks]}
        plot = sorted(drawn.values(), key=lambda a: a.zorder)
        bar = art["colorbar"]
        return {("plot", i): plot, ("title", i): [ax.title], ("bar", i): [bar.ax] if bar is not None else []}

    def _show_changes(self, *, full_draw: bool, data: bool = True, legend: bool = False) -> None:
        """Put what changed on screen: blit the changed groups, or (layout changed) draw all."""
        panels = [i for i, art in enumerate(self._artists) if art is not None]
        for i in panels:
            for artists in self._groups(i).values():
                for artist in artists:
                    artist.set_animated(True)
        size = tuple(self.figure.bbox.size)
        if full_draw or self._full_draw_pending or not self._regions or size != self._background_size:
            self._full_draw_pending = True
            self.canvas.draw_idle()
            return
        changed = sorted((g for g, shown in self._shown.items() if g[0] != "plot" and self._group_key(g) != shown),
                         key=lambda g: (g[0] != "bar", g[1]))
        current = self.state.current
        if data and current is not None and current.stage == "coarse":
            # A map that follows a slider: the heat map, its legend, colour bar and title in one
            # frame (one blit), so what is on screen always belongs together.
            self._later = []
            self._blit({("plot", i) for i in panels} | set(changed))
            return
        # A full map (one per refine): the heat map now, under the legend as it was; then the
        # legend, and what changed of the colour bars and titles, one group per turn of the
        # event loop, so no step of it blocks the GUI thread for long.
        if data:
            self._later = [("plot", i) for i in panels if self._axes[i].get_legend() is not None
                           and self._axes[i].get_legend().get_visible()] + changed
        self._blit({("plot", i) for i in panels}, legend=legend)
        if self._later:
            self._later_timer.start()

    def _draw_later(self) -> None:
        if not self._later:
            return
        if self._full_draw_pending or tuple(self.figure.bbox.size) != self._background_size:
            self._later = []
            return
        self._blit({self._later.pop(0)})
        if self._later:
            self._later_timer.start()

    def _group_key(self, group) -> object:
        kind, i = group
        if kind == "title":
            title = self._axes[i].title
            return title.get_text() if title.get_visible() else None
        if kind == "bar":
            return self._artists[i]["bar_key"]
        return None

    def _on_full_draw(self, event) -> None:
        """After a full draw (animated artists left out): keep the backgrounds, draw the rest."""
        if event.renderer is not getattr(self.canvas, "renderer", None):
            return                          # the figure drawn elsewhere (saved to a file)
        self._full_draw_pending = False
        renderer = event.renderer
        fig_box = self.figure.bbox
        pad = 5.0 * self.figure.dpi / 72.0       # markers drawn unclipped at the frame: 5 pt
        regions = {}
        for i, art in enumerate(self._artists):
            if art is None:
                continue
            ax = self._axes[i]
            title = ax.title.get_window_extent(renderer)
            bar = art["colorbar"].ax.get_tightbbox(renderer) if art["colorbar"] is not None else None
            plot = ax.bbox.padded(pad)
            legend = ax.get_legend()
            if legend is not None:          # a legend may reach out of narrow axes (and grow)
                extent = legend.get_window_extent(renderer)
                plot = Bbox.union([plot, Bbox.from_extents(extent.x0 - pad, extent.y0 - pad,
                                                           extent.x1 + 4 * pad, extent.y1 + pad)])
            boxes = {
                ("plot", i): plot,
                # A longer title or tick label must still fit: room to the sides.
                ("title", i): Bbox.from_extents(min(title.x0, ax.bbox.x0) - 4 * pad,
                                                max(title.y0, ax.bbox.y1 + pad + 1),
                                                max(title.x1, ax.bbox.x1) + 4 * pad, title.y1 + 0.5 * pad),
            }
            if bar is not None:           # a comparison's one colour bar belongs to its last panel
                # Not above the panels' tops (+ half a tick label): the title's region starts there,
                # and a bar overlapping it would be redrawn with every new title.
                top = max(a.bbox.y1 for a in self._axes) + pad
                boxes[("bar", i)] = Bbox.from_extents(bar.x0 - pad, bar.y0 - 2 * pad, bar.x1 + 4 * pad,
                                                      min(bar.y1 + 2 * pad, top))
            if bar is not None:
                self._split_from_bar(boxes, i, ax.bbox.x1, title.x1, bar.x0)
            for group, box in boxes.items():
                box = Bbox.intersection(box, fig_box)
                if box is not None and box.width > 0 and box.height > 0:
                    regions[group] = (box, self.canvas.copy_from_bbox(box))
        self._regions = regions
        self._background_size = tuple(fig_box.size)
        self._shown = {}
        self._legend_pixels = {}
        self._later = []
        for group in regions:
            self._draw_group(group, renderer)

    @staticmethod
    def _split_from_bar(boxes: dict, i: int, plot_x1: float, title_x1: float, bar_x0: float) -> None:
        """Regions that overlap the colour bar's are cut at the gap between them, when there is one.

        Overlapping regions are redrawn together (restoring one's background erases the
        other's pixels), so without the cut every heat-map update redrew the colour bar's
        axes too (~80 ms of text); the padding that made them overlap is for markers and a
        longer title, which stay left of the bar.
        """
        bar = boxes[("bar", i)]
        for group, right in ((("plot", i), plot_x1), (("title", i), title_x1)):
            box = boxes[group]
            if box.overlaps(bar) and right < bar_x0:
                cut = 0.5 * (right + bar_x0)
                boxes[group] = Bbox.from_extents(box.x0, box.y0, min(box.x1, cut), box.y1)
                bar = Bbox.from_extents(max(bar.x0, cut), bar.y0, bar.x1, bar.y1)
        boxes[("bar", i)] = bar

    def _blit(self, groups, legend: bool = True) -> None:
        """Restore the groups' backgrounds, draw them (plots without a new legend), show them."""
        todo = {g for g in groups if g in self._regions}
        # Restoring a region's background erases whatever overlaps it: redraw that too.
        grown = True
        while grown:
            grown = False
            for g, (box, _) in self._regions.items():
                if g not in todo and any(box.overlaps(self._regions[h][0]) for h in todo):
                    todo.add(g)
                    grown = True
        if not todo:
            return
        for g in todo:
            self.canvas.restore_region(self._regions[g][1])
        renderer = self.canvas.get_renderer()
        for g in sorted(todo, key=lambda g: ("plot", "bar", "title").index(g[0])):
            self._draw_group(g, renderer, legend=legend or g not in groups)
        self.canvas.blit(Bbox.union([self._regions[g][0] for g in todo]))

    def _draw_group(self, group, renderer, legend: bool = True) -> None:
        kind, i = group
        ax = self._axes[i]
        shown_legend = ax.get_legend() is not None and ax.get_legend().get_visible()
        old_legend = None if legend or not shown_legend else self._legend_pixels.get(i)
        for artist in self._groups(i)[group]:
            if artist is ax.get_legend() and old_legend is not None:
                continue
            artist.draw(renderer)
            if artist is ax.get_legend() and shown_legend:
                self._legend_pixels[i] = self.canvas.copy_from_bbox(      # with the frame's edge
                    Bbox.intersection(artist.get_window_extent(renderer).padded(2), self._regions[group][0]))
        if kind == "plot":
            for spine in ax.spines.values():     # the frame goes over the image
                spine.draw(renderer)
            if old_legend is not None:
                self.canvas.restore_region(old_legend)
        self._shown[group] = self._group_key(group)

    # -- interaction -----------------------------------------------------------------------
    def _on_click(self, event) -> None:
        if event.inaxes is None or event.xdata is None or self.state.current is None:
            return
        if event.inaxes not in self._axes:
            return
        self.poseRequested.emit(self.point_at(event.xdata, event.ydata))

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
        ax = self._axes[panel]
        # Draw only if the layout is not current: each full draw lets matplotlib's compressed
        # layout move the axes by a pixel or two (it does not settle), blits keep it still.
        if self._full_draw_pending or not self._regions or tuple(self.figure.bbox.size) != self._background_size:
            self.canvas.draw()
        px, py = ax.transData.transform((x_mm, y_mm))
        ratio = self.canvas.device_pixel_ratio or 1.0
        return int(round(px / ratio)), int(round(self.canvas.height() - py / ratio))


def legend_html(drawn: dict) -> str:
    """An overlay's legend (``app.overlays.draw_*``: ``title``, ``handles``) as rich text: a swatch per entry."""
    rows = []
    for handle in drawn["handles"]:
        colour = None
        for getter in ("get_facecolor", "get_markeredgecolor", "get_color", "get_edgecolor"):
            value = getattr(handle, getter, lambda: None)()
            if value is not None and np.size(value) and to_rgba(value)[3] > 0:
                colour = to_hex(to_rgba(value), keep_alpha=False)
                break
        if getattr(handle, "get_linestyle", lambda: "")() == "None" and getattr(handle, "get_marker", None) \
                and handle.get_marker() in (" ", "", "None", None):
            colour = None                       # a text-only entry (counts of what is not drawn)
        swatch = f'<span style="color:{colour}">&#9632;</span> ' if colour else ""
        rows.append(swatch + escape(handle.get_label()))
    return f"<b>{escape(drawn['title'])}</b><br>" + " &nbsp; ".join(rows)
