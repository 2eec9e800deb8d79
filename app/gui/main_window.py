"""The desktop app: parameters on the left, map and 3D views in the middle, statistics right.

``MainWindow`` is the controller: it owns the ``AppModel`` (``self.model``, plain Python) and
its Qt adapter (``self.state``, which widgets listen to), turns model changes into map
requests for the job runner (coarse while a slider moves, full when it stops), computes the
cheap per-pose analysis on the GUI thread, and applies results that are still current. Its
file actions (devices, sessions, exports, error dialogs) are ``file_actions.FileActions``.

Design edits are undoable (Edit > Undo, ``AppModel.undo``); the title bar marks a design that
differs from the one last loaded or saved, and, with ``ask_to_save`` (the app started by
``run_app``; scripts and tests drive windows without it), closing the window or switching the
device asks whether to save it first. A modified design is also autosaved as a session, and
a window started without a device (``run_app``) restores the one the app last ended with
unsaved (``file_actions``: crashed, killed, or closed without the prompt).
"""
from __future__ import annotations

import gc
import importlib
import math
import os
import signal
import sys
import threading
import time
import tomllib
from importlib import resources as importlib_resources
from pathlib import Path

import numpy as np
from PySide6.QtCore import QRect, QSettings, Qt, QTimer
from PySide6.QtWidgets import (
    QApplication,
    QDockWidget,
    QLabel,
    QMainWindow,
    QMessageBox,
    QProgressBar,
    QScrollArea,
    QSplitter,
    QTabWidget,
)

from app.gui.file_actions import FileActions
from app.gui.history import preset_label
from app.gui.map_rate import FRAME_S, KEPT, MapRates, rate_key
from app.gui.menus import build_menus
from app.gui.model import AppModel, MapSlot, loading_label, pose_parts
from app.gui.optimize import StudyRunner
from app.gui.qt_model import QtAppState, QtJobRunner
from app.gui.studies import list_studies, load_study
from app.gui.views.map_view import MapView
from app.gui.views.pose_view import PoseView
from app.gui.views.workspace_view import WorkspaceView
from app.gui.volumes import coarse_volume, is_volume, parse_joints, point_of_joints
from app.gui.widgets.optimize_panel import OptimizePanel
from app.gui.widgets.parameter_panel import ParameterPanel
from app.gui.widgets.stats_panel import StatsPanel
from app.gui.widgets.view_toolbar import ViewToolBar
from app.gui.window_layout import WindowLayout
from app.jobs import map_worker
from app.jobs.requests import COARSE_TAG, PROBE_TAG, MapRequest, run_map_for_view
from app.logic.glyphs import GLYPHS, glyph_unavailable
from app.plots.overlays import OVERLAYS, overlay_available
from kinematics.base import task_from_si, task_scales
from kinematics.units import joints_from_si
from metrics.pose import analyse_pose
from metrics.quantities import available_quantities
from resources import PresetError, list_presets, load_preset

DEFAULT_DEVICE = "inverse3_prototype"
#: Points per axis of the map that follows a moving slider (the longer axis): 120 x 120 of the
#: Inverse3's statistics quantities take ~11-18 ms on the worker while the GUI thread draws the
#: glyphs (~25 ms), so the map is ready when the GUI thread is (``scripts/bench_gui.py``).
#: A kind of map measured slower in this session gets fewer (``PREVIEW_S``), never below
#: ``MIN_PREVIEW_POINTS``.
COARSE_POINTS = 120
#: The compute time a slice's preview is sized to once its rate is measured (``map_rate``), s: half a
#: frame, the other half left to applying and painting it. (The Twin-Pantograph's 97 x 120 preview
#: took ~50 ms a step: at 30 Hz no step's map reached the screen.)
PREVIEW_S = FRAME_S / 2
#: The fewest points per axis (the longer one) of a slice's preview.
MIN_PREVIEW_POINTS = 32
#: How often (ms) Qt's loop lets Python run a pending signal handler (Ctrl+C: ``run_app``).
SIGNAL_TURN_MS = 200
#: The status bar's pose label shrinks to its text once that needs less than this share of its width.
POSE_LABEL_SHRINK = 0.6
#: How long a slider must rest before the full map is computed, ms.
REFINE_DELAY_MS = 250
#: How long a dragged slider must rest before its preview's statistics follow, ms. While it moves,
#: a map too slow for a frame is previewed with the map view's quantities alone: the statistics
#: panel's (the Inverse3's seven, with its masses) took 13-31 ms of a 120 x 120 preview, the
#: map's own quantity 3-5 ms (``scripts/bench_gui.py``). The statistics' preview then waits for
#: a pause in the drag: a drag step's map would otherwise wait for it on the one worker.
FIGURES_DELAY_MS = 100
#: How long the status bar says what the app changed on its own (a quantity the device lacks), ms.
NOTICE_MS = 10_000
#: Share of the middle of the window (between the docks) the map view takes from the 3D views.
MAP_SHARE = 0.7
#: How long the design must rest before a modified one is autosaved (``FileActions.autosave``), ms.
AUTOSAVE_DELAY_MS = 1500


#: Modules the library imports on first use that the app's GUI thread would otherwise wait for:
#: SciPy's Qhull (a wrench device's force slices, ``metrics.wrench_slices``) took 0.5-1.1 s of the
#: first switch to the Inoue platform, the Stewart platform or a Twin-Pantograph.
WARM_IMPORTS = ("scipy.spatial",)


def warm_imports() -> threading.Thread:
    """Import ``WARM_IMPORTS`` on a thread of its own (the GUI thread, needing one meanwhile, waits
    for it only as long as the import has left)."""
    def work() -> None:
        for name in WARM_IMPORTS:
            try:
                importlib.import_module(name)
            except ImportError:          # the first use says what is missing
                pass
    thread = threading.Thread(target=work, name="isoforce-imports", daemon=True)
    thread.start()
    return thread


def settings_path() -> Path:
    """Where window layout and last device are remembered; ``ISOFORCE_SETTINGS`` overrides."""
    env = os.environ.get("ISOFORCE_SETTINGS")
    if env:
        return Path(env)
    base = Path(os.environ.get("XDG_CONFIG_HOME", Path.home() / ".config"))
    return base / "isoforce" / "settings.ini"


def preset_names(keys: list[str]) -> dict[str, str]:
    """The shipped presets' names (their TOML's ``name``) by key, for the device list; a preset
    whose file cannot be read keeps its key (loading it reports the error)."""
    folder = importlib_resources.files("resources").joinpath("presets")
    names = {}
    for key in keys:
        try:
            name = tomllib.loads(folder.joinpath(f"{key}.toml").read_text(encoding="utf-8")).get("name")
        except (OSError, tomllib.TOMLDecodeError):
            name = None
        names[key] = name if isinstance(name, str) and name else key
    return names


def coarse_grid(grid, points: float | None = None):
    """The preset grid with at most ``COARSE_POINTS`` along its longer axis, aspect kept; with
    ``points`` (a slice's measured budget: ``MainWindow.request_map``), at most about that many
    points in all, but never under ``MIN_PREVIEW_POINTS`` along the longer axis.

    A 3D box follows the slider at most ``COARSE_VOLUME_POINTS`` per axis (24^3 = 13824
    points: as many as a 118 x 118 slice).
    """
    if is_volume(grid):
        return coarse_volume(grid)
    longest, along = max(grid.resolution), COARSE_POINTS
    if points is not None:
        # A grid shrunk by f along each axis has f^2 as many points: the longer axis keeps f of its own.
        fitted = int(longest * math.sqrt(points / math.prod(grid.resolution)))
        along = min(along, max(MIN_PREVIEW_POINTS, fitted))
    if longest <= along:
        return grid
    return grid.with_resolution(tuple(max(2, round(n * along / longest)) for n in grid.resolution))


def map_ready_for(state) -> bool:
    """The full map of the state's design and loading is on screen."""
    cur = state.current
    return (cur is not None and cur.stage == "full" and cur.mechanism == state.mechanism
            and cur.map.loading == state.loading)


class MainWindow(FileActions, WindowLayout, QMainWindow):
    def __init__(self, device: str | None = None, settings_file: str | os.PathLike | None = None, *,
                 ask_to_save: bool = False) -> None:
        super().__init__()
        self.ask_to_save = ask_to_save      # close and device switch ask before a modified design is dropped
        self.settings = QSettings(str(settings_file or settings_path()), QSettings.Format.IniFormat)
        self.last_error: str | None = None
        self.error_box: QMessageBox | None = None
        self.notice: str | None = None      # the model's last notice (``show_notice``)
        self.autosave_problem: str | None = None     # an autosave that could not be restored (``autosaved_session``)
        # The design the app last ended with unsaved, restored when no device is asked for.
        restored = self.autosaved_session() if device is None else None
        preset = restored.preset if restored is not None else self._initial_preset(device)
        self.model = AppModel(preset)
        self.state = QtAppState(self.model, self)      # the model's events as Qt signals, for the widgets
        self.scheduler = QtJobRunner(run_map_for_view, self, name="isoforce-scheduler")
        self.scheduler.resultReady.connect(self._on_result)
        self.scheduler.progressed.connect(self._on_progress)
        self.pending: dict[str, MapRequest] = {}
        self._pose_reachable = True        # the last pose analysed was reachable (``update_pose``)
        self._pose_for = None               # (preset, mechanism, pose, glyphs, force, loading) of the last report
        self._pose_deferred = False         # a device switch's glyphs wait for the next turn (``_defer_pose``)
        self._pose_analysed = None          # (preset, pose key, report) analysed a pass before its scene
        # (A timer object: ``QTimer.singleShot(0, ...)`` is a posted event, sent in the same pass
        # of the event loop as the switch's other posted events, the block not split.)
        self._pose_timer = QTimer(self, singleShot=True, interval=0)
        self._pose_timer.timeout.connect(self._pose_after_switch)
        self._probe_timer = QTimer(self, singleShot=True, interval=0)      # (``_probe_if_current``)
        self._probe_timer.timeout.connect(self._probe_if_current)
        self._probe_generation = -1
        self._sizes_before_compare: list[int] | None = None     # splitter sizes to restore after comparing
        self.refine_timer = QTimer(self, singleShot=True, interval=REFINE_DELAY_MS)
        self.refine_timer.timeout.connect(lambda: self.request_map("full"))
        self.figures_timer = QTimer(self, singleShot=True, interval=FIGURES_DELAY_MS)
        self.figures_timer.timeout.connect(self._figures_after_preview)
        # How fast each kind of map computed in this session: whether a step needs a preview, and
        # its size. ``measure_rates`` False leaves ``rates`` as set (tests: no decision from timings).
        self.rates = MapRates()
        self.measure_rates = True
        self.autosave_timer = QTimer(self, singleShot=True, interval=AUTOSAVE_DELAY_MS)
        self.autosave_timer.timeout.connect(self.autosave)
        self._build_ui()
        self._connect()
        self._restore_layout()
        if restored is not None:
            self.restore_autosave(restored)
            self.autosave_timer.stop()      # the file holds it already (and keeps its time)
        elif self.autosave_problem:
            self.show_notice(self.autosave_problem)
        self._update_title()
        self.update_pose()
        # The objects alive now (the libraries' and the window's, ~2 x 10^5) are left out of the
        # garbage collector's full passes: a pass over them took ~100 ms of whichever thread
        # allocated, with the GIL held, and a map thread's stalled the GUI thread as long.
        gc.collect()
        gc.freeze()
        map_worker.shared().start()      # coarse maps beside the GUI thread, once it is ready (~0.5 s)
        warm_imports()
        self.request_map("coarse")
        self.request_map("full")

    # -- set-up ----------------------------------------------------------------------------
    def _initial_preset(self, device: str | None):
        key = device or self.settings.value("last_device", DEFAULT_DEVICE)
        try:
            return load_preset(str(key))
        except PresetError as exc:
            self.last_error = str(exc)
            return load_preset(DEFAULT_DEVICE)

    def _build_ui(self) -> None:
        st = self.state
        presets = list_presets()
        self.param_panel = ParameterPanel(st, presets, names=preset_names(presets))
        scroll = QScrollArea()
        scroll.setWidget(self.param_panel)
        scroll.setWidgetResizable(True)
        scroll.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        # As wide as the rows need (label, slider, spin box) and the vertical scroll bar: no wider.
        scroll.setMinimumWidth(self.param_panel.sizeHint().width() + scroll.verticalScrollBar().sizeHint().width())
        self.param_dock = QDockWidget("Design", self)
        self.param_dock.setObjectName("design_dock")
        self.param_dock.setWidget(scroll)
        self.addDockWidget(Qt.DockWidgetArea.LeftDockWidgetArea, self.param_dock)

        self.map_view = MapView(st)
        self.pose_view = PoseView(st)
        self.workspace_view = WorkspaceView(st)
        self.tabs = QTabWidget()
        self.tabs.addTab(self.pose_view, "Pose (3D)")
        self.tabs.addTab(self.workspace_view, "Workspace (3D)")
        # Never narrower than its tab titles: a clipped "Workspace (" with scroll arrows read as broken.
        self.tabs.setMinimumWidth(self.tabs.tabBar().sizeHint().width())
        self.splitter = QSplitter(Qt.Orientation.Horizontal)
        self.splitter.addWidget(self.map_view)
        self.splitter.addWidget(self.tabs)
        # The map is the main output: it takes MAP_SHARE of the middle, and of any growth.
        self.splitter.setStretchFactor(0, round(100 * MAP_SHARE))
        self.splitter.setStretchFactor(1, round(100 * (1 - MAP_SHARE)))
        self.splitter.setSizes([round(1000 * MAP_SHARE), round(1000 * (1 - MAP_SHARE))])
        self.setCentralWidget(self.splitter)

        self.stats_panel = StatsPanel(st)
        self.stats_dock = QDockWidget("Statistics", self)
        self.stats_dock.setObjectName("stats_dock")
        self.stats_dock.setWidget(self.stats_panel)
        self.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, self.stats_dock)
        # As wide as the table's visible columns (its minimum, StatsPanel.content_width), no wider.
        self._stats_dock_fit: int | None = None      # the width last fitted; None: fit at the next
        self.stats_panel.widthNeeded.connect(self._fit_stats_dock)

        self.optimize_panel = OptimizePanel(list_studies(), load_study)
        self.optimize_dock = QDockWidget("Optimize", self)
        self.optimize_dock.setObjectName("optimize_dock")
        self.optimize_dock.setWidget(self.optimize_panel)
        self.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, self.optimize_dock)
        self.tabifyDockWidget(self.stats_dock, self.optimize_dock)
        self.stats_dock.raise_()
        self.study_runner = StudyRunner(self)

        toolbar = ViewToolBar(st)
        self.addToolBar(toolbar)
        self.toolbar = toolbar
        # The toolbar's controls, by the names the window's slots and the tests use.
        self.quantity_box, self.loading_controls = toolbar.quantity_box, toolbar.loading_controls
        self.pose_mode, self.pose_edit, self.force_edit = toolbar.pose_mode, toolbar.pose_edit, toolbar.force_edit
        actions = build_menus(self)
        self.report_action, self.glyph_actions, self.overlay_actions = actions.report, actions.glyphs, actions.overlays
        self.undo_action, self.redo_action = actions.undo, actions.redo
        self.progress = QProgressBar()
        self.progress.setMaximumWidth(180)
        self.progress.setRange(0, 100)
        self.progress.setValue(0)
        self.pose_label = QLabel("")
        self.pose_label.setAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
        self.statusBar().addPermanentWidget(self.pose_label)
        self.statusBar().addPermanentWidget(self.progress)

    def _connect(self) -> None:
        st = self.state
        panel, runner = self.optimize_panel, self.study_runner
        panel.runRequested.connect(runner.start)
        panel.cancelRequested.connect(runner.cancel)
        panel.designChosen.connect(self.load_study_design)
        panel.studyFailed.connect(self.show_error)
        runner.progressed.connect(panel.show_progress)
        runner.finished.connect(panel.show_results)
        runner.failed.connect(panel.show_error)
        runner.cancelled.connect(panel.show_cancelled)
        st.progressChanged.connect(self._show_progress)
        self.param_panel.edited.connect(self.on_parameter_edited)
        self.param_panel.presetChosen.connect(self.choose_device)
        st.historyChanged.connect(self._update_title)
        st.historyChanged.connect(self.autosave_timer.start)      # (restarted by each edit: written at rest)
        st.presetChanged.connect(self._update_title)
        self.quantity_box.currentIndexChanged.connect(
            lambda i: self.on_quantity(self.quantity_box.itemData(i)))
        self.map_view.poseRequested.connect(st.set_pose)
        self.pose_edit.returnPressed.connect(self._pose_from_text)
        self.pose_mode.currentIndexChanged.connect(lambda _: (self.toolbar.pose_mode_texts(), self.update_pose()))
        st.presetChanged.connect(self.toolbar.pose_mode_texts)
        self.force_edit.returnPressed.connect(self._force_from_text)
        # A new design's glyphs are drawn at once, on the GUI thread, while its coarse map
        # computes on the other core (coarse maps run single-threaded for this reason).
        st.presetChanged.connect(self._defer_pose)
        for changed in (st.poseChanged, st.glyphsChanged, st.mechanismChanged):
            changed.connect(self.update_pose)
        st.referenceChanged.connect(self._reference_needs_map)
        st.loadingChanged.connect(self._on_loading)
        # The quantity list: what this design can compute (a device switch or a sensor turned
        # off may take some away; the model then falls back and says so: ``show_notice``).
        for changed in (st.presetChanged, st.mechanismChanged, st.quantityChanged):
            changed.connect(self.toolbar.fill_quantities)
        st.notice.connect(self.show_notice)
        st.referenceChanged.connect(self._fit_comparison)
        st.compareModeChanged.connect(self._fit_comparison)
        st.presetChanged.connect(self._sync_overlays)
        st.overlayChanged.connect(self._sync_overlays)
        self._sync_overlays()
        for changed in (st.presetChanged, st.mechanismChanged):
            changed.connect(self._sync_glyphs)
        self._sync_glyphs()

    def _show_progress(self, fraction: float) -> None:
        """The progress bar at ``fraction``, painted with the next paint: ``QProgressBar.setValue``
        repaints at once (4-20 ms of the GUI thread per new value on a loaded machine; a slider
        step set it twice)."""
        value = int(round(100 * fraction))
        if value != self.progress.value():
            self.progress.setUpdatesEnabled(False)
            self.progress.setValue(value)
            self.progress.setUpdatesEnabled(True)       # (asks for the repaint: not done here)

    def _update_title(self) -> None:
        """"Inverse3 prototype - isoforce", with Qt's modified mark ("*") while the design is unsaved.

        Each call of ``setWindowModified`` sets the platform window's title again, even unchanged
        (2 ms of the GUI thread per slider step under load); ``setWindowTitle`` skips an unchanged
        title itself."""
        self.setWindowTitle(f"{preset_label(self.state.preset)}[*] - isoforce")
        if self.isWindowModified() != self.state.modified:
            self.setWindowModified(self.state.modified)

    def show_notice(self, text: str) -> None:
        """The status bar says what the app chose on its own; the next map's timing does not hide it."""
        self.notice = text
        self.statusBar().showMessage(text, NOTICE_MS)

    def _sync_glyphs(self) -> None:
        """The glyph menu: a glyph this device cannot draw (the inertia ellipsoid without a mass
        model) disabled with the reason as tooltip. Its check stays the user's: a device that
        can draw it again draws it; meanwhile it is neither computed nor drawn (``analyse_pose``)."""
        for name, action in self.glyph_actions.items():
            problem = glyph_unavailable(name, self.state.mechanism)
            if action.isEnabled() != (problem is None):
                action.setEnabled(problem is None)
            tip = problem or GLYPHS[name]
            if action.toolTip() != tip:
                action.setToolTip(tip)

    def _sync_overlays(self) -> None:
        """The overlay menu: the state's overlay checked, those this device's map cannot carry
        disabled with the reason as tooltip (a device switch turns such an overlay off)."""
        st = self.state
        for name, action in self.overlay_actions.items():
            problem = overlay_available(name, st.mechanism, st.preset.grid)
            action.setEnabled(problem is None)
            action.setToolTip(problem or OVERLAYS[name])
            action.setChecked(name == st.overlay)
        if overlay_available(st.overlay, st.mechanism, st.preset.grid) is not None:
            st.set_overlay("none")
        elif st.current is not None and not set(self.map_view.needs()) <= set(st.current.map.values):
            self.request_map("coarse")
            self.request_map("full")

    def closeEvent(self, event) -> None:   # noqa: N802 (Qt name)
        if not self.may_drop_design("closing"):
            event.ignore()
            return
        # Kept for the next start only if no one was asked (a design saved, or discarded at the
        # prompt, is not offered again).
        self.autosave_timer.stop()
        if self.state.modified and not self.ask_to_save:
            self.autosave()
        else:
            self.autosave_path().unlink(missing_ok=True)
        if self._sizes_before_compare is not None:      # remember the layout, not the comparison's
            self.splitter.setSizes(self._sizes_before_compare)
        self.settings.setValue("geometry", self.saveGeometry())
        self.settings.setValue("window_state", self.saveState())
        self.settings.setValue("splitter", self.splitter.saveState())
        self.settings.setValue("last_device", self.state.preset.source if self.state.preset.source.endswith(
            ".toml") and os.path.sep in self.state.preset.source else self.state.preset.key)
        self.settings.sync()
        self.refine_timer.stop()        # a pending refinement must not reach the shut scheduler
        self.figures_timer.stop()       # (nor a preview's statistics)
        self.scheduler.shutdown()
        self.study_runner.shutdown()
        self.pose_view.close_plotter()
        self.workspace_view.close_plotter()
        super().closeEvent(event)

    # -- maps ------------------------------------------------------------------------------
    def map_quantities(self, mechanism=None) -> tuple[str, ...]:
        """The union of what the visible views draw for ``mechanism`` (default the current one): the
        map's quantity and the statistics' (with a mass model, its masses and acceleration)."""
        mechanism = self.state.mechanism if mechanism is None else mechanism
        needed = set(self.map_view.needs()) | set(StatsPanel.needs(mechanism))
        return tuple(sorted(needed))

    def _request_quantities(self, mechanism, preview: bool = False) -> tuple[str, ...]:
        """What a map of ``mechanism`` is asked for: ``map_quantities``, or with ``preview`` the map
        view's alone; of them, those ``mechanism`` has (another device, or a design about to replace
        this one with its sensors turned off, may lack one: the model falls back when it takes it)."""
        available = set(available_quantities(mechanism))
        needed = sorted(self.map_view.needs()) if preview else self.map_quantities(mechanism)
        return tuple(q for q in needed if q in available)

    def full_map_within_frame(self, mechanism, preview: bool = False) -> bool:
        """Whether the full map of ``mechanism`` on the preset's grid is predicted (``self.rates``, this
        session's measured rates) to compute within a frame: a slider step then needs no preview.
        ``preview``: the map of a dragged slider, with the map view's quantities alone
        (``_request_quantities``; measured as a kind of its own)."""
        grid = self.state.preset.grid
        key = rate_key(mechanism, self._request_quantities(mechanism, preview))
        return self.rates.within_frame(key, math.prod(grid.resolution))

    def _full_map_shown_or_asked(self) -> bool:
        """Whether the full map of the current design and loading, with every quantity the views
        need (``_request_quantities``), is on screen or asked for already: a released slider then
        needs no refinement. (A dragged slider's full map holds the map view's quantities alone.)"""
        st = self.state
        needed = set(self._request_quantities(st.mechanism))
        if map_ready_for(st) and needed <= set(st.current.map.values):
            return True
        pending = self.pending.get("current")
        return (pending is not None and pending.stage == "full" and pending.mechanism == st.mechanism
                and pending.loading == st.loading and needed <= set(pending.quantities))

    def request_map(self, stage: str, tag: str = "current", mechanism=None, *, preview: bool = False) -> MapRequest:
        """Submit the map of ``stage`` for ``tag``; ``mechanism`` (the current slot's only) is the
        design about to be set in the model, when the request goes out before the model changes;
        ``preview``: with the map view's quantities alone (a dragged slider's, ``FIGURES_DELAY_MS``)."""
        st = self.state
        mech = mechanism if mechanism is not None else st.mechanism if tag == "current" else st.reference_mechanism
        full = st.preset.grid if tag == "current" else st.reference_grid
        # A measurement of a dragged slider's map (``_probe_drag_rate``) gives way to any map asked for.
        self.scheduler.cancel(PROBE_TAG)
        quantities = self._request_quantities(mech, preview)
        # (A preview is computed on one core: sized by the rate of previews, not of full maps.)
        rate = self.rates.points_per_second(rate_key(mech, quantities, threads=False))
        grid = full if stage == "full" else coarse_grid(full, None if rate is None else rate * PREVIEW_S)
        available = set(available_quantities(mech))
        loading = st.loading if tag == "current" else st.reference_loading
        job_tag = COARSE_TAG if tag == "current" and stage == "coarse" else tag
        request = self.scheduler.submit(MapRequest(mech, grid, quantities, stage, job_tag, loading,
                                                   shown=st.quantity if st.quantity in available else None,
                                                   drag=preview, sent_at=time.perf_counter(),
                                                   figures=self._drag_figures(mech, quantities, stage, preview)))
        self.pending[tag] = request
        if tag == "current":            # only the current full map clears "busy" and fills the bar
            st.set_busy(True)
            st.set_progress(0.0)
        return request

    def _drag_figures(self, mechanism, quantities, stage: str, preview: bool) -> str:
        """The statistics a map takes (``MapRequest.figures``): a dragged slider's full map (``preview``)
        that lacks some of the statistics' quantities, so that the map at rest follows it, takes its
        legend's figures alone (``"extremes"``: no exact quantiles, ~1.3 ms of the five-bar's); any
        other map every figure (a drag's map that holds every quantity is the design's map at rest)."""
        if stage == "full" and preview and not set(self._request_quantities(mechanism)) <= set(quantities):
            return "extremes"
        return "all"

    def _on_progress(self, request: MapRequest, fraction: float) -> None:
        # (Not a dragged slider's full map: computed within a frame, the bar would only flicker, and
        # it fills for the map that holds the statistics too, at rest.)
        if request.tag == "current" and request.stage == "full" and not request.drag:
            self.state.set_progress(fraction)

    def _on_result(self, request: MapRequest, result) -> None:
        st = self.state
        if not self.scheduler.is_current(request):
            return
        if isinstance(result, Exception):
            if request.tag != PROBE_TAG:        # (a measurement that failed: the drag previews, as unmeasured)
                self.show_error(f"The map could not be computed: {result}")
            return
        if self.measure_rates:
            seconds = result.map.seconds if result.seconds is None else result.seconds
            self.rates.add(rate_key(request.mechanism, request.quantities, threads=request.stage != "coarse"),
                           math.prod(request.grid.resolution), seconds)
        if request.tag == PROBE_TAG:
            return            # measured, never shown
        current = request.slot == "current"
        expected = st.mechanism if current else st.reference_mechanism
        loading = st.loading if current else st.reference_loading
        if request.mechanism != expected or request.loading != loading:
            return            # stale parameters or loading: never shown
        if current and request.stage == "coarse" and st.current is not None and st.current.stage == "full" \
                and st.current.mechanism == request.mechanism and st.current.map.loading == request.loading \
                and set(request.quantities) <= set(st.current.map.values):
            return            # its full map is on screen already
        slot = MapSlot(map=result.map, mechanism=request.mechanism, stage=request.stage,
                       generation=request.generation, colour_limits=result.colour_limits)
        if current:
            st.set_current_map(slot)
            # (A dragged slider's full map without the statistics' quantities leaves their map to come.)
            if request.stage == "full" and set(self._request_quantities(request.mechanism)) <= set(request.quantities):
                st.set_progress(1.0)
                st.set_busy(False)
                if result.map.feasible_points == 0:
                    # Said, not left to a blank map: a link too short or a range that misses the workspace.
                    self.show_notice("No feasible point on the map at this design: its workspace collapsed or "
                                     "lies outside the map's range (Edit > Undo takes the edit back)")
                elif self.statusBar().currentMessage() != self.notice:
                    shape = " x ".join(map(str, result.map.grid.resolution))
                    self.statusBar().showMessage(f"Map {shape} in {result.map.seconds * 1e3:.0f} ms", 5000)
                # Once the map just delivered is painted (a zero timer object fires in a later pass of
                # the event loop than the events posted now, its paint among them; ``_pose_timer``):
                # timed beside that paint, the probe took 2-3x its own time.
                self._probe_generation = slot.generation
                self._probe_timer.start()
        else:
            st.set_reference_map(slot)

    def _probe_if_current(self) -> None:
        """``_probe_drag_rate`` if the map delivered before (``_probe_generation``) is still the one on
        screen: an edit since has asked for its own map, which a probe must not hold up."""
        if self.state.current is not None and self.state.current.generation == self._probe_generation:
            self._probe_drag_rate()

    def _probe_drag_rate(self) -> None:
        """The design rests with its full map shown: if a dragged slider's full map (the map view's
        quantities alone, ``full_map_within_frame``) was timed fewer than ``KEPT`` times at this grid's
        size, compute it once more, unseen (``PROBE_TAG``), so that drags are planned from its own
        measured time.

        Extrapolated from the previews instead (the only maps of that kind a drag asks for while it
        is predicted slow), it was predicted several times too slow (``map_rate``), and no drag ever
        asked for it. ``KEPT`` times, one a rest, so that one slow one (the first, beside the window's
        start-up) does not decide every drag: their median does. Each costs at most the map just shown
        (a subset of its quantities, on the same grid); any map asked for cancels it (``request_map``)."""
        st = self.state
        mech = st.mechanism
        quantities = self._request_quantities(mech, preview=True)
        key, points = rate_key(mech, quantities), math.prod(st.preset.grid.resolution)
        # (Timed again after a drag's map that was superseded unfinished: ``_superseded``.)
        if not self.measure_rates or not quantities or \
                (self.rates.measured(key, points) >= KEPT and not self.rates.bounded(key, points)):
            return
        shown = st.quantity if st.quantity in available_quantities(mech) else None
        self.scheduler.submit(MapRequest(mech, st.preset.grid, quantities, "full", PROBE_TAG, st.loading,
                                         shown=shown, drag=True,
                                         figures=self._drag_figures(mech, quantities, "full", True)))

    def on_parameter_edited(self, name: str, value, dragging: bool) -> None:
        st = self.state
        try:
            mech = st.mechanism.replace_display(**{name: value})
        except ValueError as exc:
            self.statusBar().showMessage(f"Not applied: {exc}", 8000)
            self.param_panel.sync()
            return
        if dragging:
            st.set_interaction("design")
        if mech == st.mechanism:
            st.set_interaction("design" if dragging else None)
            # A slider released where it was: its coarse map is computing or shown; only the
            # refinement is due (restarting the coarse map would throw its work away), unless its
            # full map is computing already (asked for at once: ``full_map_within_frame``).
            if not dragging and not self._full_map_shown_or_asked():
                self.refine_timer.start()
            return
        # The full map of earlier parameters would hold the one worker the coarse map needs.
        self._superseded()
        self.scheduler.cancel("current")
        # The map is submitted before the model changes: the worker computes it while the GUI
        # thread updates the glyphs and veils the old map (``mechanismChanged``). While dragged, a
        # map holds the map view's quantities alone (the statistics' follow at rest). A full map
        # this session computes within a frame is asked for at once; a slower one is previewed
        # (coarse) and refined once the slider rests.
        direct = self.full_map_within_frame(mech, preview=dragging)
        self.request_map("full" if direct else "coarse", mechanism=mech, preview=dragging)
        st.set_mechanism(mech)
        # Released after the change: a drag's last value joins its undo step (``AppModel.history``).
        st.set_interaction("design" if dragging else None)
        if direct:
            self.figures_timer.stop()
            if self._full_map_shown_or_asked():
                self.refine_timer.stop()
            else:                       # (a drag's full map without the statistics' quantities)
                self.refine_timer.start()
            return
        self.refine_timer.start()
        if dragging:
            self.figures_timer.start()

    def _superseded(self) -> None:
        """A new step while the last step's full map (asked for at once: ``full_map_within_frame``)
        is still computing: it took longer than predicted, and would never be recorded (it is
        cancelled). How long the step has waited for it since it was asked for (its queueing behind a
        map being cancelled included: the step waited for that too) is recorded, as a lower bound of
        its time (``MapRates.add(bound=True)``):
        otherwise a drag slowed down (a loaded machine) would go on asking for full maps that never
        reach the screen. The design's next rest times that kind of map again (``_probe_drag_rate``)."""
        st, pending = self.state, self.pending.get("current")
        if (not self.measure_rates or pending is None or pending.stage != "full" or not pending.drag
                or pending.sent_at is None or not self.scheduler.is_current(pending)
                or (st.current is not None and st.current.generation == pending.generation)):
            return
        key, points = rate_key(pending.mechanism, pending.quantities), math.prod(pending.grid.resolution)
        waited, predicted = time.perf_counter() - pending.sent_at, self.rates.seconds(key, points)
        if predicted is not None and waited > predicted:
            self.rates.add(key, points, waited, bound=True)

    def _figures_after_preview(self) -> None:
        """A dragged slider rested (``FIGURES_DELAY_MS``): the preview of its design with the
        statistics' quantities too, unless a map that holds them is asked for already."""
        st = self.state
        pending = self.pending.get("current")
        if (pending is not None and pending.stage == "coarse" and pending.mechanism == st.mechanism
                and pending.loading == st.loading
                and not set(self._request_quantities(st.mechanism)) <= set(pending.quantities)):
            self.request_map("coarse")

    # -- undo ------------------------------------------------------------------------------
    def undo(self) -> bool:
        """Edit > Undo: the design before the last edit, and its maps; False if there was none."""
        return self._replay(self.state.undo)

    def redo(self) -> bool:
        """Edit > Redo: the design after the last undone edit, and its maps; False if there was none."""
        return self._replay(self.state.redo)

    def _replay(self, step) -> bool:
        st = self.state
        st.set_interaction(None)
        preset, mechanism = st.preset, st.mechanism
        if not step():
            return False
        if st.preset is not preset or st.mechanism != mechanism:
            self.scheduler.cancel("current")
            self.request_map("coarse")
            self.request_map("full")
        return True

    def on_quantity(self, name: str) -> None:
        self.state.set_quantity(name)
        current = self.state.current
        if current is None or name not in current.map.values:
            self.request_map("coarse")
            self.request_map("full")
        reference = self.state.reference
        if self.state.reference_mechanism is not None and (reference is None or name not in reference.map.values):
            self.request_map("full", tag="reference")     # the comparison shows the new quantity too

    def pin_reference(self) -> None:
        self.state.pin_reference()

    def _on_loading(self) -> None:
        """Another rating or gravity: the pose glyphs at once, then every map shown under the new loading."""
        st = self.state
        self.update_pose()
        # The map on screen is of another loading, or none is yet (a new device's first maps,
        # requested under the old loading, would be dropped on arrival): request them anew.
        if st.stale == "loading" or st.current is None:
            self.request_map("coarse")
            self.request_map("full")
        if st.reference is not None and st.reference.map.loading != st.reference_loading:
            self.request_map("full", tag="reference")

    def _reference_needs_map(self) -> None:
        st = self.state
        if st.reference_mechanism is not None and st.reference is None:
            self.request_map("full", tag="reference")
        elif st.reference is not None and st.reference.stage != "full":
            self.request_map("full", tag="reference")

    # -- pose ------------------------------------------------------------------------------
    def _defer_pose(self) -> None:
        """A new device's glyphs after the switch, in two passes of the event loop of their own
        (the analysis, then the scene): the switch rebuilds the parameter panel and the views, and
        the pose's analysis and scene (50-100 ms for a wrench device) on top of it held the GUI
        thread 106-343 ms in one piece."""
        if not self._pose_deferred:
            self._pose_deferred = True
            self._pose_analysed = None
            self._pose_timer.start()

    def _pose_key(self) -> tuple:
        """What a pose report is of: the design, pose, glyphs, desired force and loading."""
        st = self.state
        return (st.mechanism, tuple(np.asarray(st.pose, float)), st.glyphs, st.desired_force, st.loading)

    def _pose_after_switch(self) -> None:
        st = self.state
        if self._pose_analysed is None and st.pose is not None:
            report = analyse_pose(st.mechanism, np.asarray(st.pose), parts=pose_parts(st.glyphs), loading=st.loading)
            self._pose_analysed = (st.preset, self._pose_key(), report)
            self._pose_timer.start()            # the scene in the next pass
            return
        self._pose_deferred = False
        self.update_pose()

    def update_pose(self) -> None:
        """Cheap per-pose work, on the GUI thread: only what the visible glyphs need (after a
        device switch: in the next turn of the event loop, ``_defer_pose``)."""
        st = self.state
        if st.pose is None or self._pose_deferred:
            return
        # One analysis and drawing per state: a device switch asks three times over (its mechanism,
        # pose and loading each say they changed), 20-75 ms each for a wrench device's slices.
        key = self._pose_key()
        analysed, self._pose_analysed = self._pose_analysed, None
        if self._pose_for is not None and self._pose_for[0] is st.preset and self._pose_for[1:] == key \
                and st.pose_report is not None:
            report = st.pose_report
        else:
            if analysed is not None and analysed[0] is st.preset and analysed[1] == key:
                report = analysed[2]            # (analysed a pass ago: ``_pose_after_switch``)
            else:
                report = analyse_pose(st.mechanism, np.asarray(st.pose), parts=pose_parts(st.glyphs),
                                      loading=st.loading)
            self._pose_for = (st.preset, *key)
            st.set_pose_report(report)
        if self.pose_mode.currentData() == "joints":
            shown = joints_from_si(st.mechanism, report.joints) if report.reachable else ()
            text = ", ".join(f"{v:.2f}" for v in shown)
        else:
            text = ", ".join(f"{v:.1f}" for v in task_from_si(st.mechanism, st.pose))
        if text != self.pose_edit.text():       # (the same text set again repaints the field at every slider step)
            self.pose_edit.setText(text)
        if report.reachable:
            self._show_pose_text(
                f"isotropic {report.isotropic_force:.3g} N"
                + (f" ({report.bottleneck_phrase})" if report.bottleneck_phrase else "")
                + f", cond {report.condition_number:.3g}" + ("" if report.feasible else "  [outside limits]")
                + f"; {loading_label(st.loading)}")
        else:
            self._show_pose_text("pose outside the workspace")
        if self._pose_reachable and not report.reachable:      # the pose just left it: say so once
            self.show_notice("The pose is outside this design's workspace: the pose view shows no device "
                             "(click the map or type a position to move it)")
        self._pose_reachable = report.reachable

    def _show_pose_text(self, text: str) -> None:
        """The status bar's pose figures. The label is fixed-size, grown to fit and shrunk only
        when the text needs well under its width: a label whose size follows its text asks the
        whole window to lay itself out again at every slider step (status bar, docks and
        splitter: a few ms of the GUI thread each time)."""
        label = self.pose_label
        label.setText(text)
        # What the text needs (QLabel.sizeHint's width, which a fixed width bounds from below).
        margins = label.contentsMargins()
        need = (label.fontMetrics().boundingRect(QRect(0, 0, 1 << 20, 1 << 10), int(label.alignment()), text).width()
                + 2 * label.margin() + margins.left() + margins.right())
        width = label.maximumWidth()
        if need > width or need < POSE_LABEL_SHRINK * width or label.sizeHint().height() != label.maximumHeight():
            label.setFixedSize(need, label.sizeHint().height())

    def _parse_vector(self, text: str, what: str, unit_scale) -> tuple[float, ...] | None:
        """m comma-separated numbers times ``unit_scale`` (a number or one per coordinate)."""
        m = self.state.mechanism.task_dim
        try:
            values = tuple(float(v) for v in text.replace(";", ",").split(","))
        except ValueError:
            values = ()
        if len(values) != m or not all(np.isfinite(values)):
            self.statusBar().showMessage(f"{what} needs {m} comma-separated numbers, got '{text}'", 8000)
            return None
        return tuple(float(v) for v in np.asarray(values) * unit_scale)

    def _pose_from_text(self) -> None:
        if self.pose_mode.currentData() == "joints":
            try:
                pose = point_of_joints(self.state.mechanism, parse_joints(self.pose_edit.text(), self.state.mechanism))
            except ValueError as exc:
                self.statusBar().showMessage(f"Pose not applied: {exc}", 8000)
                return
            self.state.set_pose(pose)
            return
        pose = self._parse_vector(self.pose_edit.text(), "Pose", 1.0 / task_scales(self.state.mechanism))
        if pose is not None:
            self.state.set_pose(pose)

    def _force_from_text(self) -> None:
        force = self._parse_vector(self.force_edit.text(), "Desired force", 1.0)
        if force is not None:
            self.state.set_desired_force(force)


def run_app(argv: list[str] | None = None, device: str | None = None) -> int:
    """Start the desktop app; returns Qt's exit code."""
    app = QApplication.instance() or QApplication(sys.argv if argv is None else argv)
    app.setApplicationName("isoforce")
    # Ctrl+C in the terminal (or SIGTERM) closes the window as its close button does (layout
    # saved, background work stopped), from the event loop: before, a KeyboardInterrupt came out
    # of whatever Python ran next (VTK then exits with status 1 from a render observer). Set
    # before the window is built: a signal while it is built closes it once the loop runs (before
    # this, ``app.launch`` leaves Ctrl+C to the system: the process ends). Python runs a handler
    # only when it runs bytecode: a timer gives it a turn while Qt's loop waits.
    def close_on_signal(signum, _frame) -> None:
        signal.signal(signum, signal.SIG_DFL)           # a second one ends the process at once
        QTimer.singleShot(0, app.closeAllWindows)

    previous = {signum: signal.signal(signum, close_on_signal) for signum in (signal.SIGINT, signal.SIGTERM)}
    turn = QTimer(app)
    turn.timeout.connect(lambda: None)
    turn.start(SIGNAL_TURN_MS)
    try:
        window = MainWindow(device=device, ask_to_save=True)
        window.show()
        if window.last_error:
            window.show_error(window.last_error)
        return app.exec()
    finally:
        turn.stop()
        for signum, handler in previous.items():
            signal.signal(signum, handler)
