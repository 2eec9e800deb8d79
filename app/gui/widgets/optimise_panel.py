"""The optimisation panel: run a study in the background, see the ranking, load a design.

The panel shows and asks; ``app.gui.optimise.StudyRunner`` runs the study and the main window
loads a chosen design into the main view (``designChosen(study, design_id)``). A study that
cannot be read is said in the panel and, through ``studyFailed(message)``, in an error dialog.
"""
from __future__ import annotations

from PySide6.QtCore import Signal
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
        self.summary = QLabel("Choose a study and press Run.")
        self.summary.setWordWrap(True)
        self.table = QTableWidget(0, 0)
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.table.setSelectionBehavior(QTableWidget.SelectionBehavior.SelectRows)
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        self.table.doubleClicked.connect(lambda _: self._load())
        self.load_button = QPushButton("Load selected design")
        self.load_button.setToolTip("Put the selected design into the main view (double-click a row does too).")
        self.load_button.clicked.connect(self._load)
        top = QHBoxLayout()
        top.addWidget(self.study_box, 1)
        top.addWidget(open_button)
        buttons = QHBoxLayout()
        buttons.addWidget(self.run_button)
        buttons.addWidget(self.cancel_button)
        buttons.addWidget(self.progress, 1)
        layout = QVBoxLayout(self)
        layout.addLayout(top)
        layout.addLayout(buttons)
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
        self.set_running(True)
        self.summary.setText(f"Running {study.name}: {study.n_designs} designs x {study.n_samples} samples ...")
        self.runRequested.emit(study)

    def set_running(self, running: bool) -> None:
        self.run_button.setEnabled(not running)
        self.cancel_button.setEnabled(running)
        if running:
            self.progress.setValue(0)

    def show_error(self, message: str) -> None:
        self.set_running(False)
        self.summary.setText(f"<b>Failed:</b> {message}")

    def show_cancelled(self) -> None:
        self.set_running(False)
        self.summary.setText("Cancelled.")

    def show_results(self, study, results) -> None:
        """The ranking of every run (one per series value), best first."""
        self.set_running(False)
        self.study, self.results = study, results
        names = results[0].study.parameter_names()
        series = study.series is not None
        unit = results[0].study.objective.unit
        head = (["series"] if series else []) + ["rank"] + names + [f"value ({unit})" if unit else "value"]
        rows = []
        for res in results:
            display = res.study.design_display(res.top_designs)
            for rank, (design, value) in enumerate(zip(res.top_designs, res.top_values), start=1):
                cells = ([f"{res.study.series_value:g}"] if series else []) + [str(rank)]
                cells += [f"{display[n][rank - 1]:g}" for n in names] + [f"{value:.6g}"]
                rows.append((res, int(design), cells))
        self.table.clear()
        self.table.setColumnCount(len(head))
        self.table.setHorizontalHeaderLabels(head)
        self.table.setRowCount(len(rows))
        self._rows = rows
        for r, (_, _, cells) in enumerate(rows):
            for c, text in enumerate(cells):
                self.table.setItem(r, c, QTableWidgetItem(text))
        first = results[0]
        seconds = sum(res.wall_seconds for res in results)
        evaluations = sum(res.evaluations for res in results)
        brute = sum(res.brute_force_evaluations for res in results)
        self.summary.setText(f"<b>{study.name}</b>: {evaluations:,} evaluations against brute force's {brute:,} "
                             f"({evaluations / brute:.2%}), {seconds:.2f} s. "
                             f"Objective: {first.study.objective.kind.replace('_', ' ')}.")
        if rows:
            self.table.selectRow(0)

    def _load(self) -> None:
        row = self.table.currentRow()
        if self.study is None or row < 0 or row >= len(getattr(self, "_rows", [])):
            return
        res, design, _ = self._rows[row]
        self.designChosen.emit(res.study, design)
