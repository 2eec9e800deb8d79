"""The optimization panel: run a study in the background, see the ranking, load a design.

The panel shows and asks; ``app.gui.optimize.StudyRunner`` runs the study and the main window
loads a chosen design into the main view (``designChosen(study, design_id)``). A study that
cannot be read is said in the panel and, through ``studyFailed(message)``, in an error dialog.

The ranking's text (units in every header, shared ranks for ties, digits that tell values
apart) comes from ``app.gui.study_table``. Starting a study clears the previous ranking; the
progress bar and the summary line show the same percentage and phase (``show_progress``), and
a finished study reads 100 %.

The dock is shared with the statistics and is as narrow as their table (about 230 px), so the
ranking has three columns, rank, objective and design (``study_table.stacked_ranking``), and no
horizontal scroll bar: the design column takes the width left and ``DesignDelegate`` draws each
parameter's name in full, as the Design dock writes it, with its value (and unit, or the one
unit of all under the header) at the right: beside the name where both fit, else on the line
below the name, which wraps at its spaces (``design_lines``). Every row of the column is laid
out alike (by each parameter's widest value), and the cell's tooltip has the study's keys and
units. A series' value heads its run's rows, and a tie that goes on past a run's list is said
under it; both lines wrap rather than elide (``AcrossDelegate``).

The summary stays a few lines tall in the narrow dock (``SummaryLabel``): the study's name in
bold on one line, elided where the dock is narrower (the label's tooltip has it whole), then
what the run did in a sentence or two.
"""
from __future__ import annotations

from html import escape

from PySide6.QtCore import QRect, QSize, Qt, Signal
from PySide6.QtGui import QFont, QFontMetrics, QPalette
from PySide6.QtWidgets import (
    QApplication,
    QComboBox,
    QFileDialog,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QProgressBar,
    QPushButton,
    QStyle,
    QStyledItemDelegate,
    QStyleOptionViewItem,
    QTableView,
    QTableWidget,
    QTableWidgetItem,
    QToolButton,
    QVBoxLayout,
    QWidget,
)

from app.gui.study_table import RankedDesign, RunHeading, stacked_ranking
from app.gui.widgets.stats_panel import MARGIN

#: The design column's ``(label, value)`` lines, the label in full (``StackedRanking.labels``).
LINES_ROLE = Qt.ItemDataRole.UserRole + 1
#: Per parameter, the widest of its values in the column: every row is laid out alike.
WIDEST_ROLE = Qt.ItemDataRole.UserRole + 2
#: A row's text across the table, a run's heading or note (``RunHeading``, ``RunNote``), for ``AcrossDelegate``.
ACROSS_ROLE = Qt.ItemDataRole.UserRole + 3
#: The columns of the ranking (``StackedRanking.header``'s order).
RANK_COLUMN, VALUE_COLUMN, DESIGN_COLUMN = 0, 1, 2
#: The ranking's cells: a design's lines start on the rank's and the value's line.
CELL_ALIGNMENT = Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignTop


def wrapped(text: str, width: int, metrics) -> list[str]:
    """``text`` in lines at most ``width`` px wide, broken at its spaces; a word wider than
    ``width`` alone is broken between its characters. Nothing is elided: the lines joined by
    spaces (or, for a broken word, by nothing) are ``text``.

    Parameters
    ----------
    text : str
        A parameter's label, e.g. ``"shoulder separation"``.
    width : int
        The room for a line, px.
    metrics : QFontMetrics
        The font it is drawn in.

    Returns
    -------
    list of str
        At least one line.
    """
    lines: list[str] = []
    line = ""
    for word in text.split(" "):
        joined = f"{line} {word}" if line else word
        if metrics.horizontalAdvance(joined) <= width:
            line = joined
            continue
        if line:
            lines.append(line)
        line = ""
        for char in word:                  # the word on a line of its own, broken where it must be
            if line and metrics.horizontalAdvance(line + char) > width:
                lines.append(line)
                line = char
            else:
                line += char
    lines.append(line)
    return lines


def design_lines(lines, width: int, metrics, widest=None) -> list[tuple[str, str]]:
    """A design cell's lines as drawn ``width`` px wide, each ``(left, right)``: a parameter whose
    label and widest value fit beside each other (two spaces apart) is one line ``(label,
    value)``; any other has its label on lines of its own (``wrapped``), then ``("", value)``.

    Parameters
    ----------
    lines : sequence of (str, str)
        ``(label, value)`` per parameter, the value with its unit unless the header has it.
    width : int
        The cell's text width, px.
    metrics : QFontMetrics
        The cell's font.
    widest : sequence of str, optional
        Per parameter, the widest value of the column (so that every row is laid out alike);
        by default the cell's own values.

    Returns
    -------
    list of (str, str)
        In the order of ``lines``; no label is elided and no value is split.
    """
    gap = metrics.horizontalAdvance("  ")
    widest = [value for _, value in lines] if widest is None else widest
    drawn: list[tuple[str, str]] = []
    for (label, value), wide in zip(lines, widest, strict=True):
        room = width - gap - max(metrics.horizontalAdvance(wide), metrics.horizontalAdvance(value))
        if metrics.horizontalAdvance(label) <= room:
            drawn.append((label, value))
        else:
            drawn += [(piece, "") for piece in wrapped(label, width, metrics)]
            drawn.append(("", value))
    return drawn


def text_rect(opt: QStyleOptionViewItem) -> QRect:
    """Where the style writes an item's text: its text rectangle, inset by the margin the style
    keeps between a cell's edge and its text (as for the rank and objective cells)."""
    style = opt.widget.style() if opt.widget is not None else QApplication.style()
    margin = style.pixelMetric(QStyle.PixelMetric.PM_FocusFrameHMargin, None, opt.widget) + 1
    return style.subElementRect(QStyle.SubElement.SE_ItemViewItemText, opt, opt.widget).adjusted(
        margin, 0, -margin, 0)


def text_colour(opt: QStyleOptionViewItem):
    """The colour the style writes an item's text in: highlighted when selected, dimmed when inactive."""
    group = (QPalette.ColorGroup.Normal if opt.state & QStyle.StateFlag.State_Active
             else QPalette.ColorGroup.Inactive)
    selected = bool(opt.state & QStyle.StateFlag.State_Selected)
    return opt.palette.color(group, QPalette.ColorRole.HighlightedText if selected else QPalette.ColorRole.Text)


class DesignDelegate(QStyledItemDelegate):
    """Paints a design cell as ``design_lines``: each parameter's label in full at the left and
    its value (with its unit unless the column's header has it) at the right, beside the label
    or on the line below it.

    The cell's height follows the column's width (``sizeHint``); the table re-fits its rows when
    the column is resized. Its width does not matter: the design column stretches.
    """

    def drawn_lines(self, option: QStyleOptionViewItem, index) -> list[tuple[str, str]]:
        """``design_lines`` of the cell at ``index`` in the column's present width."""
        opt = QStyleOptionViewItem(option)
        self.initStyleOption(opt, index)
        view = opt.widget
        if isinstance(view, QTableView):
            # A size hint's option has no cell rectangle: the text width is the column's.
            opt.rect = QRect(0, 0, view.columnWidth(index.column()), max(1, opt.rect.height()))
        return design_lines(index.data(LINES_ROLE), text_rect(opt).width(), opt.fontMetrics,
                            index.data(WIDEST_ROLE))

    def sizeHint(self, option, index) -> QSize:
        hint = super().sizeHint(option, index)      # the item's text: one line per parameter
        lines = index.data(LINES_ROLE)
        if lines:
            extra = len(self.drawn_lines(option, index)) - len(lines)
            hint.setHeight(hint.height() + extra * option.fontMetrics.lineSpacing())
        return hint

    def paint(self, painter, option, index) -> None:
        if not index.data(LINES_ROLE):
            super().paint(painter, option, index)
            return
        opt = QStyleOptionViewItem(option)
        self.initStyleOption(opt, index)
        opt.text = ""                      # background, selection and focus by the style; the text here
        style = opt.widget.style() if opt.widget is not None else QApplication.style()
        style.drawControl(QStyle.ControlElement.CE_ItemViewItem, opt, painter, opt.widget)
        rect = text_rect(opt)
        metrics = opt.fontMetrics
        painter.save()
        painter.setClipRect(opt.rect)      # a column narrower than a value cuts it, not its neighbour
        painter.setPen(text_colour(opt))
        painter.setFont(opt.font)
        drawn = design_lines(index.data(LINES_ROLE), rect.width(), metrics, index.data(WIDEST_ROLE))
        for i, (left, right) in enumerate(drawn):
            line = QRect(rect.left(), rect.top() + i * metrics.lineSpacing(), rect.width(), metrics.height())
            painter.drawText(line, Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter, right)
            painter.drawText(line, Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter, left)
        painter.restore()


class AcrossDelegate(QStyledItemDelegate):
    """Paints a text across its row (a series run's heading ``key = value unit``, or the note on a
    tie under a run), wrapped at its spaces where the row is narrower (``wrapped``): nothing is
    elided. Other cells of its column are the style's."""

    def across_lines(self, option: QStyleOptionViewItem, index) -> list[str]:
        """The text's lines in the row's present width (a size hint's option has no rectangle)."""
        opt = QStyleOptionViewItem(option)
        self.initStyleOption(opt, index)
        view = opt.widget
        if isinstance(view, QTableView):
            opt.rect = QRect(0, 0, sum(view.columnWidth(c) for c in range(view.columnCount())),
                             max(1, opt.rect.height()))
        return wrapped(index.data(ACROSS_ROLE), text_rect(opt).width(), opt.fontMetrics)

    def sizeHint(self, option, index) -> QSize:
        hint = super().sizeHint(option, index)
        if index.data(ACROSS_ROLE):
            extra = len(self.across_lines(option, index)) - 1
            hint.setHeight(hint.height() + extra * option.fontMetrics.lineSpacing())
        return hint

    def paint(self, painter, option, index) -> None:
        text = index.data(ACROSS_ROLE)
        if not text:
            super().paint(painter, option, index)
            return
        opt = QStyleOptionViewItem(option)
        self.initStyleOption(opt, index)
        opt.text = ""                      # the shading by the style; the text here
        style = opt.widget.style() if opt.widget is not None else QApplication.style()
        style.drawControl(QStyle.ControlElement.CE_ItemViewItem, opt, painter, opt.widget)
        rect = text_rect(opt)
        metrics = opt.fontMetrics
        painter.save()
        painter.setClipRect(opt.rect)
        painter.setPen(text_colour(opt))
        painter.setFont(opt.font)
        for i, line in enumerate(wrapped(text, rect.width(), metrics)):
            painter.drawText(QRect(rect.left(), rect.top() + i * metrics.lineSpacing(), rect.width(), metrics.height()),
                             Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter, line)
        painter.restore()


class SummaryLabel(QLabel):
    """The panel's word-wrapped summary. ``set_summary(head, body)`` puts ``head`` (the study's
    name) in bold on the first line, elided to the label's width, and ``body`` (rich text) below;
    the tooltip has both whole. ``setText`` shows a text as it is."""

    def __init__(self, text: str = "", parent=None) -> None:
        super().__init__(text, parent)
        self.setWordWrap(True)
        self._head, self._body = "", ""

    def set_summary(self, head: str, body: str) -> None:
        self._head, self._body = head, body
        self.setToolTip(f"<b>{escape(head, quote=False)}</b><br>{body}")
        self._fit()

    def setText(self, text: str) -> None:
        self._head, self._body = "", ""
        self.setToolTip("")
        super().setText(text)

    def _fit(self) -> None:
        """The text for the present width: the head elided to one line (none if empty)."""
        if not self._head:
            super().setText(self._body)
            return
        bold = QFont(self.font())
        bold.setBold(True)
        # A pixel short of the width: the label's text layout and the metrics may round apart.
        head = QFontMetrics(bold).elidedText(self._head, Qt.TextElideMode.ElideRight,
                                             max(0, self.contentsRect().width() - 1))
        text = f"<b>{escape(head, quote=False)}</b><br>{self._body}"
        if text != self.text():
            super().setText(text)

    def resizeEvent(self, event) -> None:
        if self._head:
            self._fit()
        super().resizeEvent(event)


class OptimizePanel(QWidget):
    runRequested = Signal(object)             # a metrics.design.Study
    cancelRequested = Signal()
    designChosen = Signal(object, int)        # study, design id
    studyFailed = Signal(str)                 # why the chosen study cannot be read

    def __init__(self, studies: list[str], load_study, parent=None) -> None:
        super().__init__(parent)
        self._load_study = load_study
        self.study = None
        self.results = []
        self.study_box = QComboBox()
        self.study_box.addItems(studies)
        self.study_box.setToolTip("A shipped design study (resources/studies), or open your own TOML.")
        # Narrower than its longest study name (elided): the dock it shares with the statistics
        # would otherwise be as wide as a study path.
        self.study_box.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
        self.study_box.setMinimumContentsLength(8)
        # A small button beside the study's name (a labelled one there cut the name short:
        # "inverse3_gear_rat"; in the row of Run and Cancel it widened the dock by 50 px).
        open_button = QToolButton()
        open_button.setIcon(self.style().standardIcon(QStyle.StandardPixmap.SP_DialogOpenButton))
        open_button.setToolTip("Open a design study of your own (a TOML file)...")
        open_button.setAccessibleName("Open study...")
        open_button.clicked.connect(self._open)
        self.open_button = open_button
        self.run_button = QPushButton("Run")
        self.run_button.setToolTip("Search the study's design grid exactly (culling), in the background.")
        self.run_button.clicked.connect(self._run)
        self.cancel_button = QPushButton("Cancel")
        self.cancel_button.setEnabled(False)
        self.cancel_button.clicked.connect(self.cancelRequested.emit)
        self.progress = QProgressBar()
        self.progress.setRange(0, 100)
        self.progress.setValue(0)
        self.progress.setFormat("idle")
        self._runs = 1
        self._fraction = 0.0
        self._running = ("", "")               # the study's name and what is being run
        self._rows: list = []
        self.summary = SummaryLabel("Choose a study and press Run.")
        self.table = QTableWidget(0, 0)
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.table.setSelectionBehavior(QTableWidget.SelectionBehavior.SelectRows)
        self.table.setWordWrap(False)                       # a cell's lines are its parameters, no more
        self.table.setItemDelegateForColumn(DESIGN_COLUMN, DesignDelegate(self.table))
        self.table.setItemDelegateForColumn(RANK_COLUMN, AcrossDelegate(self.table))
        self.table.verticalHeader().setVisible(False)       # the rank column is the only rank
        self.table.verticalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        self.table.horizontalHeader().sectionResized.connect(self._column_resized)
        self.table.doubleClicked.connect(lambda _: self._load())
        self.load_button = QPushButton("Load selected design")
        self.load_button.setToolTip("Put the selected design into the main view (double-click a row does too).")
        self.load_button.clicked.connect(self._load)
        self.load_button.setEnabled(False)
        top = QHBoxLayout()
        top.addWidget(self.study_box, 1)
        top.addWidget(open_button)
        buttons = QHBoxLayout()
        buttons.addWidget(self.run_button)
        buttons.addWidget(self.cancel_button)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(MARGIN, MARGIN, MARGIN, MARGIN)     # the statistics' tab's: room for the text
        layout.addLayout(top)
        layout.addLayout(buttons)
        layout.addWidget(self.progress)         # a row of its own: the dock stays as narrow as the statistics
        layout.addWidget(self.summary)
        layout.addWidget(self.table, 1)
        layout.addWidget(self.load_button)

    def _column_resized(self, column: int, _old: int, _new: int) -> None:
        """A design's and a heading's height follow the design column's width (a label that no
        longer fits beside its value moves above it, a heading wraps): re-fit the rows."""
        if column == DESIGN_COLUMN:
            self.table.resizeRowsToContents()

    def _open(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open study", "", "Design studies (*.toml)")
        if path:
            if self.study_box.findText(path) < 0:
                self.study_box.addItem(path)
            self.study_box.setCurrentText(path)

    def _run(self) -> None:
        try:
            study = self._load_study(self.study_box.currentText())
        except ValueError as exc:
            self.summary.setText(f"<b>Cannot run:</b> {exc}")
            self.studyFailed.emit(f"The study cannot be run: {exc}")
            return
        self.clear_ranking()
        self._runs = len(study.runs())
        per_run = " per run" if self._runs > 1 else ""
        self._running = (study.name, f"Running: {study.n_designs:,} designs x {study.n_samples:,} samples{per_run}")
        self.set_running(True)
        self.runRequested.emit(study)

    def clear_ranking(self) -> None:
        """Empty the table: what it showed belonged to the previous study."""
        self.study, self.results, self._rows = None, [], []
        self.table.clear()
        self.table.clearSpans()
        self.table.setRowCount(0)
        self.table.setColumnCount(0)
        self.load_button.setEnabled(False)

    def phase(self, fraction: float) -> str:
        """``"run k of n"`` for the run a job ``fraction`` lies in (empty for a single run)."""
        if self._runs <= 1:
            return ""
        # The job reports (runs done + fraction of this run) / runs: a fraction just past k / n is
        # run k + 1. The 1e-9 absorbs the rounding of that division at a run's boundary.
        k = min(self._runs, int(fraction * self._runs + 1e-9) + 1)
        return f"run {k} of {self._runs}"

    def show_progress(self, fraction: float) -> None:
        """Put a job fraction in [0, 1] on the bar and in the summary, as the same percentage and phase."""
        self._fraction = fraction = min(max(float(fraction), 0.0), 1.0)
        percent = int(round(100 * fraction))
        phase = self.phase(fraction)
        self.progress.setValue(percent)
        self.progress.setFormat(f"{phase}: %p %" if phase else "%p %")
        name, running = self._running
        self.summary.set_summary(name, f"{running}: {phase + ', ' if phase else ''}{percent} % done.")

    def set_running(self, running: bool) -> None:
        self.run_button.setEnabled(not running)
        self.cancel_button.setEnabled(running)
        if running:
            self.show_progress(0.0)

    def _stopped(self, word: str) -> str:
        """Freeze the bar with ``word`` ("cancelled", "failed") and return the same words for the summary."""
        self.set_running(False)
        phase = self.phase(self._fraction)
        where = f"{self.progress.value()} %" + (f" ({phase})" if phase else "")
        self.progress.setFormat(f"{word} at %p %")
        return f"{word.capitalize()} at {where}"

    def show_error(self, message: str) -> None:
        self.summary.setText(f"<b>{self._stopped('failed')}:</b> {message}")

    def show_cancelled(self) -> None:
        self.summary.setText(f"{self._stopped('cancelled')}; no ranking.")

    def show_results(self, study, results) -> None:
        """The ranking of every run (one per series value), best first, ties sharing a rank."""
        self.set_running(False)
        self.progress.setValue(100)
        self.progress.setFormat("done: %p %")
        self.study, self.results = study, results
        table = stacked_ranking(study, results)
        self.table.clear()
        self.table.clearSpans()
        self.table.setColumnCount(len(table.header))
        self.table.setHorizontalHeaderLabels(table.header)
        for c, tip in enumerate(table.tooltips):
            self.table.horizontalHeaderItem(c).setToolTip(tip)
        self.table.setRowCount(len(table.rows))
        self._rows = table.rows
        ranked = [row for row in table.rows if isinstance(row, RankedDesign)]
        advance = self.table.fontMetrics().horizontalAdvance
        widest = [max((row.parameters[k][1] for row in ranked), key=advance, default="")
                  for k in range(len(table.labels))]
        for r, row in enumerate(table.rows):
            if isinstance(row, RankedDesign):
                self._put_design(r, row, table.labels, widest)
            else:
                self._put_across(r, row.text, shaded=isinstance(row, RunHeading))
        first = results[0]
        seconds = sum(res.wall_seconds for res in results)
        evaluations = sum(res.evaluations for res in results)
        brute = sum(res.brute_force_evaluations for res in results)
        runs = f" over {len(results)} runs" if len(results) > 1 else ""
        best = "largest" if first.study.objective.direction == "max" else "smallest"
        # A dimensionless objective's "(-)" is the header's placeholder for no unit: no fact to repeat.
        objective = table.objective.removesuffix(" (-)")
        unit = first.study.objective.unit
        if unit and objective.startswith(f"{unit} "):
            # A count says its unit first: "fewest samples with κ > 5", not "smallest ... (samples)".
            objective = objective.removesuffix(f" ({unit})")
            best = "most" if first.study.objective.direction == "max" else "fewest"
        note = f" {table.note}" if table.note else ""
        self.summary.set_summary(study.name, escape(
            f"done (100 %){runs}, {seconds:.2f} s: {evaluations:,} evaluations, {100 * evaluations / brute:.2f} % "
            f"of brute force's {brute:,}. Best: {best} {objective}.{note}", quote=False))
        designs = [r for r, row in enumerate(table.rows) if isinstance(row, RankedDesign)]
        self._fit_columns(designs)
        self.load_button.setEnabled(bool(designs))
        if designs:
            self.table.selectRow(designs[0])

    def _put_design(self, r: int, row: RankedDesign, labels, widest: list[str]) -> None:
        """Row ``r``: the design's rank, objective value and parameters, which ``DesignDelegate``
        paints under their ``labels``, laid out for the ``widest`` value of each."""
        for c, text in ((RANK_COLUMN, row.rank), (VALUE_COLUMN, row.value), (DESIGN_COLUMN, row.text)):
            item = QTableWidgetItem(text)
            item.setTextAlignment(CELL_ALIGNMENT)
            self.table.setItem(r, c, item)
        design = self.table.item(r, DESIGN_COLUMN)
        design.setData(LINES_ROLE, [(label, value) for label, (_, value) in zip(labels, row.parameters, strict=True)])
        design.setData(WIDEST_ROLE, widest)
        design.setToolTip(row.full)            # the study's keys, each value with its unit

    def _fit_columns(self, designs: list[int]) -> None:
        """Rank and objective columns as wide as their header and their widest cell in the rows
        ``designs``, the design column whatever width is left.

        Not ``ResizeToContents``: a series heading spans the row from the rank column, and its
        text would widen that column.
        """
        header, model = self.table.horizontalHeader(), self.table.model()
        grid = int(self.table.showGrid())          # the line between cells, as sizeHintForColumn counts it
        for c in (RANK_COLUMN, VALUE_COLUMN):
            cells = [self.table.sizeHintForIndex(model.index(r, c)).width() + grid for r in designs]
            header.setSectionResizeMode(c, QHeaderView.ResizeMode.Fixed)
            header.resizeSection(c, max([header.sectionSizeHint(c)] + cells))
        header.setSectionResizeMode(DESIGN_COLUMN, QHeaderView.ResizeMode.Stretch)

    def _put_across(self, r: int, text: str, *, shaded: bool) -> None:
        """Row ``r``: a text across the row, not a design (not selectable), wrapped where the dock is
        narrower (``AcrossDelegate``): a series run's heading, ``shaded``, or a note under a run.

        Not bold: a bold ``workspace.centre.z = 100 mm`` is wider than the narrow dock.
        """
        item = QTableWidgetItem(text)
        item.setData(ACROSS_ROLE, text)
        item.setFlags(Qt.ItemFlag.ItemIsEnabled)
        item.setToolTip(text)
        if shaded:
            item.setBackground(self.palette().brush(QPalette.ColorRole.AlternateBase))
        self.table.setItem(r, 0, item)
        self.table.setSpan(r, 0, 1, self.table.columnCount())

    def _load(self) -> None:
        row = self.table.currentRow()
        if self.study is None or row < 0 or row >= len(self._rows) or not isinstance(self._rows[row], RankedDesign):
            return
        chosen = self._rows[row]
        self.designChosen.emit(chosen.result.study, chosen.design)
