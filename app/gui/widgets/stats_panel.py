"""The map's global figures, with resolution, run time and estimated error.

One row per global figure (min, p05, median, mean, p95, max, SD of each of
``STATS_QUANTITIES``, below a heading row with the quantity's name) and the GCI, columns for the
value, its estimated resolution error, and, with a pinned reference, the reference value
and the relative change. Below: the global maximum isotropic force and where it occurs.

The panel is as wide as its table's columns need (``StatsPanel.widthNeeded``): the
reference columns are shown only while a reference is compared, and the texts above and
below the table wrap rather than widen it.
"""
from __future__ import annotations

import math

from PySide6.QtCore import QTimer, Signal
from PySide6.QtGui import QBrush, QColor
from PySide6.QtWidgets import (
    QHeaderView,
    QLabel,
    QSizePolicy,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from app.gui.model import STALE_DELAY_MS, loading_label
from app.gui.volumes import comparison_problem, workspace_size
from app.logic.display_units import display_unit, scaled_errors, scaled_stats
from app.logic.figure_digits import format_with_error, shown_error, unresolved_note
from app.logic.map_marks import on_cut_edge
from kinematics.units import task_display_units, task_from_si
from metrics.quantities import DYNAMIC_SUMMARY, QUANTITIES, SPEED_SUMMARY, STATS_QUANTITIES, available_quantities

FIGURES = ("min", "p05", "median", "mean", "p95", "max", "sd")
#: Column headers, short so the columns are no wider than their numbers, with what each means.
HEADERS = ("figure", "value", "± error", "ref.", "change")
HEADER_TIPS = ("The figure, of which quantity, and its display unit.",
               "The figure over this map's feasible points.",
               "Estimated resolution error: the change from the same map at half resolution; <0.0005: the\n"
               "half grids give the same figure. Red: the error is at least the figure (not resolved at\n"
               "this grid; its tooltip says which grid would resolve it).",
               "The same figure of the pinned reference (Compare > Pin), with its own digits.",
               "Relative change from the reference to this map, in %.")
#: The reference and change columns: shown only while a reference is compared.
REFERENCE_COLUMNS = (3, 4)
#: The panel's margins, px (the dock's frame is around them).
MARGIN = 4
#: Rows of one quantity: a heading (its name and unit, across the table), then one per figure.
#: The figure column is then as wide as "median (deg)", not as a quantity's name.
ROWS_PER_QUANTITY = 1 + len(FIGURES)
#: The GCI's row label (its tooltip says what it is).
GCI_LABEL = "GCI"
#: The colour of an error cell whose figure the grid does not resolve (the stale note's red).
UNRESOLVED_COLOUR = "#b00020"


#: What the panel says while its figures are older than the parameters on screen.
STALE_NOTE = ("Stale: these figures are of earlier parameters (or another rating or gravity); the current map "
              "is being computed.")


def figure_texts(stats, figure: str, error) -> tuple[str, str]:
    """One figure of a ``Stats`` and its error as the panel shows them: ``unbounded`` for an infinite
    supremum, an ``exact`` 0 for an infimum that vanishes at a singularity the map reaches.

    An error at the figure's rounding level counts as none (``shown_error``): below half a unit
    of the last digit, ``<0.0005``.
    """
    if figure == "max" and stats.unbounded:
        return "unbounded", "-"
    if figure == "min" and stats.vanishes:
        return "0", "exact"         # 0 in truth: the map reaches a singularity where it vanishes
    value = getattr(stats, figure)
    return format_with_error(value, shown_error(value, error))


def figure_text(stats, figure: str) -> str:
    """One figure of a ``Stats`` without its error: ``unbounded`` for an infinite supremum."""
    return figure_texts(stats, figure, None)[0]


def unresolved_summary(notes: list[str]) -> str:
    """The line under the table: figures the grid does not resolve, those with the same remedy together.

    ``notes`` are ``"<figure>: <unresolved_note>"``; empty for none.

    >>> print(unresolved_summary(["min of A: not resolved at this grid; a finer grid would resolve it",
    ...                           "p95 of B: not resolved at this grid; a finer grid would resolve it",
    ...                           "mean of C: not resolved at this grid; about 40 points per axis would resolve it"]))
    ... # doctest: +NORMALIZE_WHITESPACE
    Not resolved at this grid (the error is at least the figure): min of A, p95 of B (a finer grid would
    resolve them); mean of C (about 40 points per axis would resolve it).
    """
    remedies: dict[str, list[str]] = {}
    for note in notes:
        figure, _, rest = note.partition(": not resolved at this grid; ")
        remedies.setdefault(rest, []).append(figure)
    parts = [", ".join(figures) + f" ({rest if len(figures) == 1 else rest.replace('resolve it', 'resolve them')})"
             for rest, figures in remedies.items()]
    return "Not resolved at this grid (the error is at least the figure): " + "; ".join(parts) + "." if parts else ""


def relative_change(new: float, old: float) -> str:
    if not (math.isfinite(new) and math.isfinite(old)) or old == 0:
        return "-"
    return f"{100.0 * (new - old) / abs(old):+.1f} %"


def wrapping(label: QLabel) -> QLabel:
    """``label`` word-wrapped, its text's width ignored by the layout: it wraps to the panel, never widens it."""
    label.setWordWrap(True)
    policy = label.sizePolicy()             # (word wrap has set height-for-width: kept)
    policy.setHorizontalPolicy(QSizePolicy.Policy.Ignored)
    label.setSizePolicy(policy)
    return label


class StatsPanel(QWidget):
    """Reads ``state.current`` / ``state.reference``; never computes a map itself.

    Its minimum width is what the table's visible columns need (``content_width``); each
    change of it is announced with ``widthNeeded`` so the dock can follow.
    """

    NEEDS = STATS_QUANTITIES
    #: The panel's width for its columns changed (px): for the dock holding it.
    widthNeeded = Signal(int)

    @staticmethod
    def needs(mechanism) -> tuple[str, ...]:
        """``NEEDS``, and for a device with a mass model what its force costs (``DYNAMIC_SUMMARY``):
        a gear ratio's force gain and its apparent-mass cost in one table, with their change
        against a pinned reference; and where the motors' speeds are given, the isotropic velocity."""
        return (STATS_QUANTITIES + (DYNAMIC_SUMMARY if mechanism.has_mass_model else ())
                + (SPEED_SUMMARY if mechanism.joint_speed_limits() is not None else ()))

    def __init__(self, state, parent=None) -> None:
        super().__init__(parent)
        self.state = state
        self.header = wrapping(QLabel("No map yet."))
        self.table = QTableWidget(0, len(HEADERS))
        self.table.setHorizontalHeaderLabels(list(HEADERS))
        for c, tip in enumerate(HEADER_TIPS):
            self.table.horizontalHeaderItem(c).setToolTip(tip)
        header = self.table.horizontalHeader()
        # Columns sized to their cells; the last one shown takes any width the dock has to spare.
        header.setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        header.setStretchLastSection(True)
        # The width the cells need is announced after each refresh, once laid out (``_update_width``).
        self._width = 0
        self._width_timer = QTimer(self, singleShot=True, interval=0)
        self._width_timer.timeout.connect(self._update_width)
        self._show_reference(False)
        self.table.verticalHeader().setVisible(False)
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.table.setToolTip("Global figures over the feasible points of the map (SD with ddof = 1).\n"
                              "Estimated error: the change from the same map at half resolution.")
        self.global_label = wrapping(QLabel(""))
        # The figures whose error is at least the figure, and the grid that would resolve each.
        self.unresolved_label = wrapping(QLabel(""))
        self.unresolved_label.setStyleSheet(f"color: {UNRESOLVED_COLOUR};")
        self.unresolved_label.hide()
        # Shown (and the table greyed) while the figures are of parameters no longer on screen.
        self.stale_label = wrapping(QLabel(STALE_NOTE))
        self.stale_label.setStyleSheet("color: #b00020; font-weight: bold;")
        self.stale_label.hide()
        self._stale_timer = QTimer(self, singleShot=True, interval=STALE_DELAY_MS)
        self._stale_timer.timeout.connect(lambda: self._show_stale(self.stale()))
        layout = QVBoxLayout(self)
        layout.setContentsMargins(MARGIN, MARGIN, MARGIN, MARGIN)
        layout.addWidget(self.header)
        layout.addWidget(self.stale_label)
        layout.addWidget(self.table, 1)
        layout.addWidget(self.unresolved_label)
        layout.addWidget(self.global_label)
        state.mapChanged.connect(self.refresh)
        state.quantityChanged.connect(self.refresh)     # the map's own quantity has rows too
        state.referenceChanged.connect(self.refresh)
        state.presetChanged.connect(self.clear)
        state.mechanismChanged.connect(self.mark_stale)
        self.rows: dict[tuple[str, str], int] = {}
        self._figures_of = None     # (mechanism, loading) of the figures shown; None: none shown
        self._shape = None          # the quantities with rows, and whether a GCI row: which rows are headings
        self._update_width()

    # -- width ------------------------------------------------------------------------------
    def content_width(self, columns: int | None = None) -> int:
        """The panel's width that shows every visible column whole, px: the columns (``columns``
        px, default their cells' widths), the table's frame and vertical scroll bar (counted even
        while hidden: the rows rarely fit), the margins."""
        t = self.table
        columns = sum(self._column_widths()) if columns is None else columns
        table = (columns + 2 * t.frameWidth() + t.verticalScrollBar().sizeHint().width()
                 + (t.verticalHeader().width() if t.verticalHeader().isVisible() else 0))
        margins = self.layout().contentsMargins()
        return table + margins.left() + margins.right()

    def _column_widths(self) -> list[int]:
        """What ResizeToContents gives each visible column (the stretched last one included):
        its header's or its widest cell's width, px."""
        t = self.table
        header = t.horizontalHeader()
        widths = [max(header.sectionSizeHint(c), t.sizeHintForColumn(c))
                  for c in range(t.columnCount()) if not t.isColumnHidden(c)]
        # A quantity's heading spans the row: Qt widens the first column by what the heading
        # needs beyond the others, but only for headings among the rows in view when it measures
        # ("Max. anisotropic force (N)" came into view later: the table scrolled by 7 px).
        model = t.model()
        headings = [t.sizeHintForIndex(model.index(r, 0)).width() + int(t.showGrid())
                    for r in range(t.rowCount()) if t.columnSpan(r, 0) > 1]
        if widths and headings and max(headings) > sum(widths):
            widths[0] += max(headings) - sum(widths)
        return widths

    def _update_width(self) -> None:
        # Qt does not shrink the stretched last column when the cells beside it grow (the error
        # column kept the Inverse3's 65 px after a switch to the five-bar, which needs 57, and the
        # table scrolled sideways by the difference). When the columns overflow both their cells'
        # needs and the viewport, size them to their cells and stretch the last again (it keeps
        # its old size unless the stretch is set anew); 1.5 ms, so only then, not every refresh.
        header = self.table.horizontalHeader()
        columns = sum(self._column_widths())
        if header.length() > max(columns, self.table.viewport().width()):
            header.setStretchLastSection(False)
            header.resizeSections(QHeaderView.ResizeMode.ResizeToContents)
            header.setStretchLastSection(True)
        width = self.content_width(columns)
        margins = self.layout().contentsMargins()
        self.table.setMinimumWidth(width - margins.left() - margins.right())
        if width != self._width:
            self._width = width
            self.widthNeeded.emit(width)

    def _show_reference(self, shown: bool) -> None:
        """The reference and change columns, shown only while a reference is compared."""
        for c in REFERENCE_COLUMNS:
            if self.table.isColumnHidden(c) == shown:
                self.table.setColumnHidden(c, not shown)
                self._width_timer.start()

    def refresh(self) -> None:
        st = self.state
        slot = st.current
        if slot is None:
            self.clear()
            return
        if not self.holds_figures(slot):
            # A dragged slider's preview, of the map's quantities alone (``MainWindow.request_map``):
            # the figures shown stay, marked stale, until a map that holds them arrives.
            self.mark_stale()
            return
        self._figures_of = (slot.mechanism, slot.map.loading)
        self.mark_stale()
        wmap = slot.map
        ref = st.reference.map if st.reference is not None else None
        problem = None
        if ref is not None:
            # Figures of maps that vary other coordinates (a slice vs a box) are not compared.
            problem = comparison_problem(wmap, slot.mechanism, ref, st.reference.mechanism, "isotropic_force")
            ref = None if problem else ref
        # Pinned and comparable (its map may still be computing): the reference columns.
        self._show_reference(st.reference_mechanism is not None and not problem)
        errors = wmap.errors          # computed with the map (compute_map)
        res = " x ".join(str(n) for n in wmap.grid.resolution)
        kind, size, unit = workspace_size(slot.mechanism, wmap.grid, wmap.feasible_points)
        where = "volume (3D box)" if kind == "volume" else "slice"
        size_text = (f"; workspace {kind} {size:.4g} {unit} (feasible points x cell)" if math.isfinite(size)
                     else "")
        singular = (f", {wmap.singular_points} singular (left out of mean, SD and percentiles)"
                    if wmap.singular_points else "")
        if wmap.condition_number_scaling is not None:
            singular += (f"; condition numbers with moments scaled by L = "
                         f"{wmap.condition_number_scaling['length_m'] * 1e3:.4g} mm")
        reference = ""
        if st.reference is not None:
            name = st.reference_preset.name if st.reference_preset is not None else "the pinned design"
            reference = (f"<br><span style='color:#b00020'>Reference {name} not compared: {problem}.</span>"
                         if problem else f"<br>Reference: {name}")
            if not problem and st.reference_preset is not None:
                _, ref_size, _ = workspace_size(st.reference.mechanism, st.reference.map.grid,
                                                st.reference.map.feasible_points)
                reference += (f" ({' x '.join(map(str, st.reference.map.grid.resolution))} grid"
                              + (f", {kind} {ref_size:.4g} {unit}" if math.isfinite(ref_size) else "") + ")")
            if not problem and st.reference.map.loading != wmap.loading:
                theirs = loading_label(st.reference.map.loading)
                reference += (f"<br><span style='color:#b00020'>Reference under {theirs} (its device cannot "
                              f"take {loading_label(wmap.loading)})</span>")
        self.header.setText(f"<b>{st.preset.name}</b> &mdash; statistics over the {where}: {res} grid "
                            f"({slot.stage}), {wmap.feasible_points} feasible points{singular}{size_text}, "
                            f"computed in {wmap.seconds * 1e3:.0f} ms<br>Loading: <b>{wmap.loading.describe()}</b>"
                            f"{reference}")
        names = [q for q in STATS_QUANTITIES + DYNAMIC_SUMMARY + SPEED_SUMMARY if q in wmap.stats]
        if st.quantity in wmap.stats and st.quantity not in names:     # the map's own quantity, e.g. a resolution
            names.append(st.quantity)
        shape = (tuple(names), wmap.gci is not None)
        if shape != self._shape:
            # Another set of rows: built anew (a heading row must not keep a figure row's cells).
            self.table.clearSpans()
            self.table.setRowCount(0)
            self.table.setRowCount(len(names) * ROWS_PER_QUANTITY + shape[1])
            for i in range(len(names)):
                self.table.setSpan(i * ROWS_PER_QUANTITY, 0, 1, len(HEADERS))
            self._shape = shape
        self.rows = {}
        # Cells are updated in place with the model's signals held back, then announced at once:
        # a signal per cell (each resizing the columns to their contents) costs ~0.4 ms apiece.
        model = self.table.model()
        model.blockSignals(True)
        try:
            self._fill(names, wmap, ref, errors)
        finally:
            model.blockSignals(False)
        if self.table.rowCount():
            model.dataChanged.emit(model.index(0, 0), model.index(self.table.rowCount() - 1,
                                                                 self.table.columnCount() - 1))
        self._width_timer.start()
        iso = wmap.stats.get("isotropic_force")
        if iso is not None and iso.count:
            # Task coordinates in their display units (a pen's angles in deg, not "mm").
            mech = self.state.mechanism
            shown = task_from_si(mech, list(iso.argmin))
            where = ", ".join(f"{v:.1f} {u}" for v, u in zip(shown, task_display_units(mech)))
            if iso.vanishes:
                self.global_label.setText(
                    f"Global maximum isotropic force: <b>0 N</b> at ({where}): the map reaches a "
                    f"direct singularity, where the device cannot hold a force in some direction.")
            else:
                error = shown_error(iso.min, errors.get("isotropic_force", {}).get("min"))
                value, error = format_with_error(iso.min, error)
                # On the map's edge where feasible points reach it, the workspace may go on past the
                # grid, with a lower minimum: said, as the map's legend says it.
                edge = len(wmap.grid.axes) == 2 and on_cut_edge(
                    wmap, tuple(iso.argmin[wmap.task_names.index(a)] * 1e3 for a in wmap.grid.axes))
                self.global_label.setText(
                    f"Global maximum isotropic force: <b>{value} N</b> "
                    f"(± {error} N) at ({where}) &mdash; the largest force "
                    f"the device can render in every direction everywhere in this map"
                    + (" (on the map's edge: the workspace may go on past it)." if edge else "."))
        else:
            self.global_label.setText("No feasible point on this map." if iso is not None else "")

    def _fill(self, names, wmap, ref, errors) -> None:
        resolution = tuple(int(n) for n in wmap.grid.resolution)
        notes = []
        if wmap.gci is not None:
            r = len(names) * ROWS_PER_QUANTITY
            self.rows[("gci", "value")] = r
            old = ref.gci if ref is not None else None
            old_error = ref.gci_error if old is not None else None
            cells = [GCI_LABEL, *format_with_error(wmap.gci, shown_error(wmap.gci, wmap.gci_error)),
                     format_with_error(old, shown_error(old, old_error))[0] if old is not None else "",
                     relative_change(wmap.gci, old) if old is not None else ""]
            self._set_row(r, cells, "GCI, global conditioning index (Gosselin and Angeles 1991): the workspace "
                                    "mean of 1 / condition number, in [0, 1]; singular points count 0.")
            note = unresolved_note(wmap.gci, shown_error(wmap.gci, wmap.gci_error), wmap.gci_error_order, resolution)
            self._mark_unresolved(r, note)
            notes += [f"GCI: {note}"] if note else []
        for i, q in enumerate(names):
            node = QUANTITIES[q]
            # In the quantity's display unit (µm, deg for resolutions; ``display_units``), data SI.
            shown_unit, factor = display_unit(q)
            unit = f" ({shown_unit})" if shown_unit else ""
            stats = scaled_stats(wmap.stats[q], factor)
            q_errors = scaled_errors(errors.get(q, {}), factor)
            old_stats = scaled_stats(ref.stats[q], factor) if ref is not None and q in ref.stats else None
            # The reference's own error estimate sets its digits.
            old_errors = scaled_errors(ref.errors.get(q, {}), factor) if old_stats is not None else {}
            heading = i * ROWS_PER_QUANTITY
            self._set_row(heading, [f"{node.label}{unit}"], node.description, heading=True)
            for j, fig in enumerate(FIGURES):
                r = heading + 1 + j
                self.rows[(q, fig)] = r
                value = getattr(stats, fig)
                # The unit is the heading's, once: in every row it widened the figure column (the
                # masses' "median (m/s^2)" left the compared map too narrow for two panels).
                cells = [fig.upper() if fig == "sd" else fig, *figure_texts(stats, fig, q_errors.get(fig))]
                if old_stats is not None:
                    old = getattr(old_stats, fig)
                    cells += [figure_texts(old_stats, fig, old_errors.get(fig))[0], relative_change(value, old)]
                else:
                    cells += ["", ""]
                self._set_row(r, cells, node.description)
                error = q_errors.get(fig)
                note = ("" if error is None or (fig == "max" and stats.unbounded) else
                        unresolved_note(value, shown_error(value, error),
                                        wmap.error_orders.get(q, {}).get(fig), resolution))
                self._mark_unresolved(r, note)
                notes += [f"{fig.upper() if fig == 'sd' else fig} of {node.label}: {note}"] if note else []
        self.unresolved_label.setText(unresolved_summary(notes))
        self.unresolved_label.setVisible(bool(notes))

    def _mark_unresolved(self, r: int, note: str) -> None:
        """The error cell of row ``r`` red with ``note`` as its tooltip, or plain when ``note`` is empty."""
        item = self.table.item(r, 2)
        if item is None:
            return
        brush = QBrush(QColor(UNRESOLVED_COLOUR)) if note else QBrush()
        if item.foreground() != brush:
            item.setForeground(brush)
        tip = f"{note[0].upper()}{note[1:]}." if note else ""
        if item.toolTip() != tip:
            item.setToolTip(tip)

    def _set_row(self, r: int, cells: list[str], tooltip: str, heading: bool = False) -> None:
        for c, text in enumerate(cells):
            item = self.table.item(r, c)
            if item is None:
                item = QTableWidgetItem(text)
                if heading:
                    font = item.font()
                    font.setBold(True)
                    item.setFont(font)
                self.table.setItem(r, c, item)
            elif item.text() != text:
                item.setText(text)
            if c == 0 and item.toolTip() != tooltip:
                item.setToolTip(tooltip)

    def holds_figures(self, slot) -> bool:
        """Whether ``slot``'s map holds every quantity of the panel's its design has (``needs``)."""
        available = set(available_quantities(slot.mechanism))
        return {q for q in self.needs(slot.mechanism) if q in available} <= set(slot.map.values)

    def clear(self) -> None:
        """No figures until this device's first map arrives (never another device's)."""
        self._figures_of = None
        self.table.clearSpans()
        self.table.setRowCount(0)
        self._shape = None
        self.rows = {}
        self.global_label.setText("")
        self.unresolved_label.setText("")
        self.unresolved_label.hide()
        self._show_reference(self.state.reference_mechanism is not None)
        self._width_timer.start()
        self.mark_stale()
        self.header.setText(f"<b>{self.state.preset.name}</b> &mdash; computing the map...")

    def stale(self) -> bool:
        """Whether the figures shown are of other parameters than the state's (or, with a preview
        on the map, than the map's)."""
        st = self.state
        return st.stale in ("parameters", "loading") or (
            self._figures_of is not None and self._figures_of != (st.mechanism, st.loading))

    def mark_stale(self) -> None:
        """Grey the figures once they have stayed stale for ``STALE_DELAY_MS`` (the map view's
        rule: a slider's coarse maps replace each other sooner, and a note and a greyed table
        flashing at every step would relayout the dock twice a step); ungrey at once."""
        if not self.stale():
            self._stale_timer.stop()
            self._show_stale(False)
        elif not self.stale_label.isVisible() and not self._stale_timer.isActive():
            self._stale_timer.start()

    def _show_stale(self, stale: bool) -> None:
        self.stale_label.setVisible(stale)
        self.table.setEnabled(not stale)

    def cell(self, quantity: str, figure: str, column: int = 1) -> str:
        """Text of one cell (for tests): column 1 value, 2 error, 3 reference, 4 change."""
        return self.table.item(self.rows[(quantity, figure)], column).text()
