"""The optimisation panel: run a study in the background, see the ranking, load a design.

The panel shows and asks; ``app.gui.optimise.StudyRunner`` runs the study and the main window
loads a chosen design into the main view (``designChosen(study, design_id)``). A study that
cannot be read is said in the panel and, through ``studyFailed(message)``, in an error dialog.

The ranking's text (units in every header, shared ranks for ties, digits that tell values
apart) comes from ``app.gui.study_table``. Starting a study clears the previous ranking; the
progress bar and the summary line show the same percentage and phase (``show_progress``), and
a finished study reads 100 %.

The dock is shared with the statistics and is as narrow as their table, so the ranking has three
columns, rank, objective and design (``study_table.stacked_ranking``), and no horizontal scroll
bar: the design column takes the width left, its parameters stacked one a line, each value
(with its unit, or the one unit of all under the header) always whole at the right and the name
elided only where the dock is too narrow for it (``DesignDelegate``; the cell's tooltip has
every line in full, with units). A series' value heads its run's rows.
"""
from __future__ import annotations

from PySide6.QtCore import QRect, Qt, Signal
from PySide6.QtGui import QPalette
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
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from ..study_table import RankedDesign, stacked_ranking

#: The design column's ``(name, value)`` lines (``RankedDesign.parameters``), for ``DesignDelegate``.
LINES_ROLE = Qt.ItemDataRole.UserRole + 1
#: The columns of the ranking (``StackedRanking.header``'s order).
RANK_COLUMN, VALUE_COLUMN, DESIGN_COLUMN = 0, 1, 2
#: The ranking's cells: a design's lines start on the rank's and the value's line.
CELL_ALIGNMENT = Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignTop


def fitted_lines(lines, width: int, metrics) -> list[tuple[str, str]]:
    """A design cell's lines as drawn ``width`` px wide: each value whole, its name elided to the
    room left beside it (two spaces apart).

    Parameters
    ----------
    lines : sequence of (str, str)
        ``(name, value)`` per parameter, the value with its unit unless the header has it
        (``RankedDesign.parameters``).
    width : int
        The cell's text width, px.
    metrics : QFontMetrics
        The cell's font.

    Returns
    -------
    list of (str, str)
        ``(name as drawn, value)``, in the order of ``lines``.
    """
    gap = metrics.horizontalAdvance("  ")
    return [(metrics.elidedText(name, Qt.TextElideMode.ElideRight,
                                max(0, width - metrics.horizontalAdvance(value) - gap)), value)
            for name, value in lines]


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
    """Paints a design cell as lines of name (left) and value (right, with its unit unless the
    column's header has it).

    A value is never elided; a name is, only where the column is narrower than the name and the
    value two spaces apart (``fitted_lines``). The cell's height is the style's for its text (one
    line per parameter) and its width does not matter: the design column stretches.
    """

    def paint(self, painter, option, index) -> None:
        lines = index.data(LINES_ROLE)
        if not lines:
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
        for i, (name, value) in enumerate(fitted_lines(lines, rect.width(), metrics)):
            line = QRect(rect.left(), rect.top() + i * metrics.lineSpacing(), rect.width(), metrics.height())
            painter.drawText(line, Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter, value)
            painter.drawText(line, Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter, name)
        painter.restore()


class OptimisePanel(QWidget):
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
        open_button = QPushButton("Open...")
        open_button.clicked.connect(self._open)
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
        self._running_text = ""
        self._rows: list = []
        self.summary = QLabel("Choose a study and press Run.")
        self.summary.setWordWrap(True)
        self.table = QTableWidget(0, 0)
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.table.setSelectionBehavior(QTableWidget.SelectionBehavior.SelectRows)
        self.table.setWordWrap(False)                       # a cell's lines are its parameters, no more
        self.table.setItemDelegateForColumn(DESIGN_COLUMN, DesignDelegate(self.table))
        self.table.verticalHeader().setVisible(False)       # the rank column is the only rank
        self.table.verticalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
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
        layout.addLayout(top)
        layout.addLayout(buttons)
        layout.addWidget(self.progress)         # a row of its own: the dock stays as narrow as the statistics
        layout.addWidget(self.summary)
        layout.addWidget(self.table, 1)
        layout.addWidget(self.load_button)

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
        self._running_text = (f"Running <b>{study.name}</b>: {study.n_designs:,} designs x {study.n_samples:,} "
                              f"samples{per_run}")
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
        self.summary.setText(f"{self._running_text}: {phase + ', ' if phase else ''}{percent} % done.")

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
        for r, row in enumerate(table.rows):
            if isinstance(row, RankedDesign):
                self._put_design(r, row)
            else:
                self._put_heading(r, row.text)
        first = results[0]
        seconds = sum(res.wall_seconds for res in results)
        evaluations = sum(res.evaluations for res in results)
        brute = sum(res.brute_force_evaluations for res in results)
        runs = f" over {len(results)} runs" if len(results) > 1 else ""
        self.summary.setText(f"<b>{study.name}</b>: done (100 %){runs}, {evaluations:,} evaluations against "
                             f"brute force's {brute:,} ({evaluations / brute:.2%}), {seconds:.2f} s. "
                             f"Objective: {table.objective}, "
                             f"{'larger' if first.study.objective.direction == 'max' else 'smaller'} is better."
                             + (f" {table.note}" if table.note else ""))
        designs = [r for r, row in enumerate(table.rows) if isinstance(row, RankedDesign)]
        self._fit_columns(designs)
        self.load_button.setEnabled(bool(designs))
        if designs:
            self.table.selectRow(designs[0])

    def _put_design(self, r: int, row: RankedDesign) -> None:
        """Row ``r``: the design's rank, objective value and parameters (``DesignDelegate`` paints them)."""
        for c, text in ((RANK_COLUMN, row.rank), (VALUE_COLUMN, row.value), (DESIGN_COLUMN, row.text)):
            item = QTableWidgetItem(text)
            item.setTextAlignment(CELL_ALIGNMENT)
            self.table.setItem(r, c, item)
        design = self.table.item(r, DESIGN_COLUMN)
        design.setData(LINES_ROLE, list(row.parameters))
        design.setToolTip(row.full)            # the names in full where the column elides them, with units

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

    def _put_heading(self, r: int, text: str) -> None:
        """Row ``r``: a series run's heading across the row, shaded, not a design (not selectable).

        Not bold: a bold ``workspace.centre.z = 100 mm`` is wider than the narrow dock.
        """
        item = QTableWidgetItem(text)
        item.setFlags(Qt.ItemFlag.ItemIsEnabled)
        item.setToolTip(text)
        item.setBackground(self.palette().brush(QPalette.ColorRole.AlternateBase))
        self.table.setItem(r, 0, item)
        self.table.setSpan(r, 0, 1, self.table.columnCount())

    def _load(self) -> None:
        row = self.table.currentRow()
        if self.study is None or row < 0 or row >= len(self._rows) or not isinstance(self._rows[row], RankedDesign):
            return
        chosen = self._rows[row]
        self.designChosen.emit(chosen.result.study, chosen.design)
