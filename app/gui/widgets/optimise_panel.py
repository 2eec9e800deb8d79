"""The optimisation panel: run a study in the background, see the ranking, load a design.

The panel shows and asks; ``app.gui.optimise.StudyRunner`` runs the study and the main window
loads a chosen design into the main view (``designChosen(study, design_id)``). A study that
cannot be read is said in the panel and, through ``studyFailed(message)``, in an error dialog.

The ranking's text (units in every header, shared ranks for ties, digits that tell values
apart) comes from ``app.gui.study_table``. Starting a study clears the previous ranking; the
progress bar and the summary line show the same percentage and phase (``show_progress``), and
a finished study reads 100 %.
"""
from __future__ import annotations

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import (
    QComboBox,
    QFileDialog,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QProgressBar,
    QPushButton,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from ..study_table import ranking_table


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
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        self.table.verticalHeader().setVisible(False)       # the rank column is the only rank
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
        table = ranking_table(study, results)
        self.table.clear()
        self.table.setColumnCount(len(table.header))
        self.table.setHorizontalHeaderLabels(table.header)
        for c, tip in enumerate(table.tooltips):
            self.table.horizontalHeaderItem(c).setToolTip(tip)
        self.table.setRowCount(len(table.rows))
        self._rows = table.rows
        for r, (_, _, cells) in enumerate(table.rows):
            for c, text in enumerate(cells):
                item = QTableWidgetItem(text)
                item.setTextAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
                self.table.setItem(r, c, item)
        first = results[0]
        seconds = sum(res.wall_seconds for res in results)
        evaluations = sum(res.evaluations for res in results)
        brute = sum(res.brute_force_evaluations for res in results)
        runs = f" over {len(results)} runs" if len(results) > 1 else ""
        self.summary.setText(f"<b>{study.name}</b>: done (100 %){runs}, {evaluations:,} evaluations against "
                             f"brute force's {brute:,} ({evaluations / brute:.2%}), {seconds:.2f} s. "
                             f"Objective: {table.header[-1].replace(chr(10), ' ')}, "
                             f"{'larger' if first.study.objective.direction == 'max' else 'smaller'} is better."
                             + (f" {table.note}" if table.note else ""))
        self.load_button.setEnabled(bool(table.rows))
        if table.rows:
            self.table.selectRow(0)

    def _load(self) -> None:
        row = self.table.currentRow()
        if self.study is None or row < 0 or row >= len(self._rows):
            return
        res, design, _ = self._rows[row]
        self.designChosen.emit(res.study, design)
