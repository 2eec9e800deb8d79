"""Interactive-speed benchmark of the desktop app (run under a display, e.g. Xvfb).

    xvfb-run -a -s "-screen 0 1920x1080x24" python scripts/bench_gui.py [--steps 21] [--refines 4] [--json]

``--json`` prints one JSON object on stdout instead (the readable report goes to stderr):
``slider_to_screen_ms`` (``median``, ``p90``, ``max``: a step until the coarse map with its
legend, colour bar and title *and* the glyphs are on screen), ``map_painted_ms``,
``refine_gui_block_ms`` (``median``, ``max``: the longest heartbeat gap per refine),
``refine_gui_cpu_block_ms`` (the GUI thread's CPU time of its longest event dispatch per refine:
what the app itself blocks it for, where a heartbeat gap also holds the wait for a core on a loaded machine),
``drag_30hz_maps_shown`` of ``drag_30hz_calls``, ``drag_full_res_maps_shown`` (``{device: steps}``,
part 4b; ``drag_30hz_by_device`` adds the maps shown at any resolution, and what the app predicted
for a dragged slider's full map: ``drag_full_map_predicted_ms``, ``full_map_within_frame``),
``gui_block_ms`` (``{device: {action: ms}}``, part 5),
``window``, ``map_canvas_px`` and the load average.

Drives the real ``MainWindow`` and its real scheduler (Inverse3 prototype, throw-away
settings file) and prints figures; it asserts nothing (tests never time anything):

1. Non-GUI baselines from the same run: ``compute_map`` of the coarse slice (``COARSE_POINTS``
   along its longer axis) and of the full 1000 x 1000 one, ``analyse_pose``, and the same map drawn by
   ``figures.draw_map`` on an off-screen Agg figure of the canvas's size (the export path), and
   ``map_picture`` (what the app's map view paints).
2. Slider steps: gear ratio theta_0 stepping 6.0 .. 8.0 through ``on_parameter_edited(...,
   dragging=True)``, one step at a time (the next step starts once the previous one is on
   screen, well inside the refine delay, so every step is a coarse map). Latency from the
   call until (a) the map canvas has painted a map *of that mechanism* (its ``paintEvent``
   after the canvas was drawn, or its plot region blitted, with the map ``MapView.redraw``
   applied), (b) the pose view has painted its glyphs for that mechanism (``paintGL`` of
   pyvistaqt's widget, or ``paintEvent`` of the app's off-screen ``PlotterWidget``), and
   (c) the map's legend, colour bar and title are on screen too (a map view that blits
   draws them a few ms after the heat map). Split into the worker's compute time, the wait
   for the GUI thread, applying the result (``_on_result``), the canvas draw or blit and
   paint; the pose update and the pose view's paint (its VTK render) on the GUI thread.
3. A drag at 30 Hz: the same steps issued every 33 ms without waiting, as a mouse does;
   latency of each map that reaches the screen from its own call (superseded ones never do).
4. Refines: a released slider, then the full 1000 x 1000 map after ``REFINE_DELAY_MS``.
   A 2 ms heartbeat ``QTimer`` on the GUI thread; its longest gap from the full request
   until the full map is painted (and 150 ms beyond) is the longest time the GUI thread was
   blocked, including applying and drawing the full map.
4b. A drag at 30 Hz per device (``--drag-devices``: the Inverse3, the five-bar, the Twin-Pantograph),
   on part 5's slider: of its ``--steps`` calls, how many showed a map of their own design at the
   preset's full resolution (and at any), painted before the next call.
5. GUI blocks per device and action (``--devices``; ``--blocks-only`` runs this part alone):
   the longest stall of the event loop (the 2 ms heartbeat's longest gap), from the action
   until what it changes is on screen (and 200 ms beyond): ``switch`` (the device list's
   choice, until its full map, glyphs and, if shown, 3D workspace are painted), ``step`` and
   ``release`` (a slider step with ``dragging=True``, the largest of ``--block-steps``, and its
   release until the full map), ``workspace_tab`` (the Workspace (3D) tab opened, until its
   scene is painted), ``step_workspace`` and ``release_workspace`` (the same with that tab
   shown). The slider is the device's first gear ratio, else its first parameter (x 1.01 a step).
"""
from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import statistics as pystats
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402
from PySide6.QtCore import QEventLoop, Qt, QTimer  # noqa: E402
from PySide6.QtWidgets import QApplication  # noqa: E402
from pyvistaqt.rwi import QVTKRenderWindowInteractor  # noqa: E402

from app.gui import main_window as mw  # noqa: E402
from app.gui.views.map_canvas import MapCanvas  # noqa: E402
from app.gui.views.map_view import MapView  # noqa: E402
from app.gui.views.pose_view import PoseView  # noqa: E402
from app.gui.volumes import is_volume  # noqa: E402
from app.gui.widgets.stats_panel import StatsPanel  # noqa: E402

try:
    from app.gui.views.plotter_widget import PlotterWidget  # noqa: E402
except ImportError:          # an app whose 3D views are pyvistaqt's OpenGL widgets
    PlotterWidget = None

now = time.perf_counter
GEAR_REST = (5.957, 5.957)
#: The window's size while timing, px.
WINDOW = (1800, 1000)


# -- figures --------------------------------------------------------------------------------
def pct(values, p: float) -> float:
    return float(np.percentile(np.asarray(values, float), p)) if len(values) else float("nan")


def line(label: str, values_s, unit: str = "ms") -> str:
    v = [x * 1e3 for x in values_s]
    if not v:
        return f"  {label:<44s} (none)"
    return (f"  {label:<44s} median {pystats.median(v):7.1f}  p90 {pct(v, 90):7.1f}  max {max(v):7.1f} {unit}"
            f"  (n={len(v)})")


# -- instrumentation ------------------------------------------------------------------------
class Probe:
    """Timing wrappers on the app's classes (installed before the window is built, so the
    window's own signal connections go through them), plus a waiter on a QEventLoop."""

    def __init__(self) -> None:
        self.events: list[tuple[str, float, float, object]] = []   # (what, start, end, info)
        self.jobs: dict[int, tuple[str, float, float, float]] = {}  # generation -> (stage, t0, t1, seconds)
        self.window = None
        self.map_applied = None        # MapSlot that MapView.redraw last drew
        self.map_drawn = None          # MapSlot in the canvas buffer after the last draw
        self.painted: list[tuple[float, object]] = []       # (time, MapSlot) per canvas paint
        self.pose_built = None         # mechanism of the last PoseView.redraw (scene built)
        self.pose_rendered: list[tuple[float, object]] = []  # (time, mechanism) per pose-view paint
        self.requests: list[tuple[float, object]] = []       # (time, MapRequest) per request_map
        self.completed: list[tuple[float, object]] = []      # (time, MapSlot): map and annotations shown
        self._loop: QEventLoop | None = None
        self._predicate = None

    def _timed(self, what: str, fn, info=None):
        probe = self

        def wrapper(*args, **kwargs):
            t0 = now()
            try:
                return fn(*args, **kwargs)
            finally:
                t1 = now()
                probe.events.append((what, t0, t1, info(args) if info else None))
                probe.poke()
        wrapper.__wrapped__ = fn
        return wrapper

    def install(self) -> None:
        probe = self
        mw.MainWindow._on_result = self._timed(
            "apply", mw.MainWindow._on_result, lambda a: (a[1].generation, a[1].stage))
        mw.MainWindow.update_pose = self._timed("update_pose", mw.MainWindow.update_pose)
        StatsPanel.refresh = self._timed("stats", StatsPanel.refresh)
        draw_map_view = MapView.redraw

        def map_redraw(view, *a, **k):
            t0 = now()
            try:
                return draw_map_view(view, *a, **k)
            finally:
                probe.map_applied = view.state.current
                probe.events.append(("map_redraw", t0, now(), None))
        MapView.redraw = map_redraw
        pose_redraw = PoseView.redraw

        def pose(view, *a, **k):
            t0 = now()
            try:
                return pose_redraw(view, *a, **k)
            finally:
                probe.events.append(("pose_redraw", t0, now(), None))
                probe.pose_built = view.state.mechanism
        PoseView.redraw = pose
        # The glyphs are on screen once the pose view's widget has painted (rendered the VTK
        # scene and shown it) after a redraw for the edited design: ``paintGL`` of pyvistaqt's
        # OpenGL widget, or ``paintEvent`` of the app's off-screen ``PlotterWidget``.
        def pose_paint_hook(cls, name):
            original = getattr(cls, name)

            def pose_paint(widget, *a, **k):
                t0 = now()
                try:
                    return original(widget, *a, **k)
                finally:
                    view = probe.window.pose_view if probe.window is not None else None
                    if view is not None and widget in (view.plotter, getattr(view, "view", None)):
                        t1 = now()
                        probe.events.append(("pose_paint", t0, t1, None))
                        probe.pose_rendered.append((t1, probe.pose_built))
                        probe.poke()
            setattr(cls, name, pose_paint)
        pose_paint_hook(QVTKRenderWindowInteractor, "paintGL")
        if PlotterWidget is not None:
            pose_paint_hook(PlotterWidget, "paintEvent")
        # The map view's canvas paints the whole picture (heat map, markers, legend, colour bar,
        # titles) in one paintEvent: a map is on screen, complete, when that paint returns.
        paint = MapCanvas.paintEvent

        def paint_event(canvas, event):
            t0 = now()
            try:
                return paint(canvas, event)
            finally:
                if probe.window is not None and canvas is probe.window.map_view.canvas:
                    t1 = now()
                    probe.map_drawn = probe.map_applied
                    probe.events.append(("canvas_paint", t0, t1, None))
                    probe.painted.append((t1, probe.map_drawn))
                    probe.completed.append((t1, probe.map_drawn))
                    probe.poke()
        MapCanvas.paintEvent = paint_event
        request_map = mw.MainWindow.request_map

        def request(win, stage, tag="current", **kwargs):
            req = request_map(win, stage, tag, **kwargs)
            probe.requests.append((now(), req))
            return req
        mw.MainWindow.request_map = request

    def attach(self, window) -> None:
        """Time the scheduler's jobs on its worker thread."""
        self.window = window
        core = window.scheduler.core
        job = core._job
        probe = self

        def timed_job(request, progress, cancelled):
            t0 = now()
            result = job(request, progress, cancelled)
            probe.jobs[request.generation] = (request.stage, t0, now(), getattr(result, "seconds", float("nan")))
            return result
        core._job = timed_job

    # -- waiting ---------------------------------------------------------------------------
    def poke(self) -> None:
        if self._loop is not None and self._predicate is not None and self._predicate():
            self._loop.quit()

    def wait(self, predicate, timeout_s: float) -> bool:
        if predicate():
            return True
        loop = QEventLoop()
        self._loop, self._predicate = loop, predicate
        QTimer.singleShot(int(timeout_s * 1e3), loop.quit)
        loop.exec()
        self._loop = self._predicate = None
        return predicate()

    def idle(self, seconds: float) -> None:
        loop = QEventLoop()
        QTimer.singleShot(int(seconds * 1e3), loop.quit)
        loop.exec()

    # -- queries ---------------------------------------------------------------------------
    def first_paint(self, mechanism, after: float, stage: str | None = None):
        for t, slot in self.painted:
            if t >= after and slot is not None and slot.mechanism == mechanism and (stage is None or
                                                                                  slot.stage == stage):
                return t, slot
        return None

    def first_complete(self, mechanism, after: float):
        """When a map of ``mechanism`` was on screen with its legend, colour bar and title."""
        for t, slot in self.completed:
            if t >= after and slot is not None and slot.mechanism == mechanism:
                return t
        return None

    def first_pose(self, mechanism, after: float):
        for t, mech in self.pose_rendered:
            if t >= after and mech == mechanism:
                return t
        return None

    def spans(self, what: str, start: float, end: float) -> list[tuple[float, float, object]]:
        return [(t0, t1, info) for w, t0, t1, info in self.events if w == what and start <= t0 <= end]


class ViewPaints:
    """When each of the app's off-screen 3D views painted, and what it showed (``PlotterWidget.paintEvent``).

    ``paints`` holds ``(time, widget, drawn)``: ``drawn`` is the owning view's ``_drawn`` key at
    the paint (the workspace view's ``(generation, ...)``), None for the pose view."""

    def __init__(self) -> None:
        self.paints: list[tuple[float, object, object]] = []
        self.window = None
        self.poke = None

    def install(self) -> None:
        if PlotterWidget is None:
            return
        paints = self
        original = PlotterWidget.paintEvent

        def paint_event(widget, *a, **k):
            try:
                return original(widget, *a, **k)
            finally:
                ws = getattr(paints.window, "workspace_view", None)
                drawn = ws._drawn if ws is not None and widget is ws.view else None
                paints.paints.append((now(), widget, drawn))
                if paints.poke is not None:
                    paints.poke()
        PlotterWidget.paintEvent = paint_event

    def workspace_shows(self, generation: int, after: float) -> bool:
        """The workspace view painted a scene of map ``generation`` at or after ``after``."""
        ws = self.window.workspace_view
        return any(t >= after and w is ws.view and d is not None and d[0] == generation
                   for t, w, d in self.paints)


#: The shortest event dispatch ``CpuSlots`` keeps, s (the heartbeat's own ticks take microseconds).
SLOT_KEPT_S = 2e-4


class CpuSlots(QApplication):
    """The application, timing the GUI thread's CPU (``thread_time``) of each top-level event dispatch.

    ``slots`` holds ``(end, cpu seconds, receiver class, event type)``: a heartbeat gap is the
    thread's block *and* its wait for a core (on a loaded 2-core machine most of it); this is the
    block alone."""

    def __init__(self, argv) -> None:
        super().__init__(argv)
        self.slots: list[tuple[float, float, str, str]] = []
        self._depth = 0

    def notify(self, receiver, event):   # noqa: D102 (Qt's)
        if self._depth:
            return super().notify(receiver, event)
        self._depth += 1
        cpu = time.thread_time()
        try:
            return super().notify(receiver, event)
        finally:
            self._depth -= 1
            cpu = time.thread_time() - cpu
            if cpu >= SLOT_KEPT_S:
                self.slots.append((now(), cpu, type(receiver).__name__, event.type().name))

    def longest(self, start: float, end: float) -> float:
        """The most CPU (s) one dispatch ending in [start, end] took (nan: none, or another application)."""
        return max((c for t, c, _, _ in self.slots if start <= t <= end), default=float("nan"))


class Heartbeat:
    """A 2 ms timer on the GUI thread; long gaps between its ticks are blocks."""

    def __init__(self) -> None:
        self.ticks: list[float] = []
        self.timer = QTimer(interval=2)
        self.timer.setTimerType(Qt.TimerType.PreciseTimer)
        self.timer.timeout.connect(lambda: self.ticks.append(now()))

    def start(self) -> None:
        self.ticks.clear()
        self.timer.start()

    def stop(self) -> None:
        self.timer.stop()

    def gaps(self, start: float, end: float) -> list[tuple[float, float]]:
        """(gap, time of the tick that ended it) for ticks in [start, end]."""
        t = [x for x in self.ticks if start <= x <= end]
        return [(b - a, b) for a, b in zip(t, t[1:])]


# -- parts of the run -----------------------------------------------------------------------
def baselines(canvas_px: tuple[int, int] | None = None) -> dict:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from app.logic.glyphs import DEFAULT_GLYPHS, pose_parts
    from app.plots.figures import draw_map
    from metrics.pose import analyse_pose
    from metrics.quantities import CORE_QUANTITIES
    from metrics.workspace import compute_map
    from resources import load_preset

    preset = load_preset(mw.DEFAULT_DEVICE)
    quantities = tuple(sorted(set(CORE_QUANTITIES) | {"isotropic_force"}))
    coarse = mw.coarse_grid(preset.grid)
    out = {"coarse_grid": coarse.resolution, "full_grid": preset.grid.resolution}
    compute_map(preset.mechanism, coarse, quantities)        # warm-up
    coarse_s = []
    for g in np.linspace(6.0, 8.0, 15):
        mech = preset.mechanism.replace_display(gear_ratios=(float(g), *GEAR_REST))
        t0 = now()
        wmap = compute_map(mech, coarse, quantities)
        coarse_s.append(now() - t0)
    out["compute_coarse"] = coarse_s
    full_s = []
    for _ in range(2):
        t0 = now()
        full = compute_map(preset.mechanism, preset.grid, quantities)
        full_s.append(now() - t0)
    out["compute_full"] = full_s
    pose_s = []
    for _ in range(20):
        t0 = now()
        analyse_pose(preset.mechanism, np.asarray(preset.pose),
                     parts=pose_parts(DEFAULT_GLYPHS))
        pose_s.append(now() - t0)
    out["analyse_pose"] = pose_s
    # The same maps drawn off-screen (Agg), at the size of the app's canvas.
    w, h = canvas_px or (800, 900)
    for key, m in (("agg_coarse", wmap), ("agg_full", full)):
        fig = Figure(figsize=(w / 100, h / 100), dpi=100, layout="compressed")
        FigureCanvasAgg(fig)
        ax = fig.add_subplot()
        times = []
        artists = None
        for _ in range(5):
            t0 = now()
            artists = draw_map(fig, ax, m, "isotropic_force", preset, artists=artists)
            fig.canvas.draw()
            times.append(now() - t0)
        out[key] = times
    # What the app's map view does instead: the picture (colour scale, colours, texts) built.
    from app.logic.map_picture import map_picture
    for key, m in (("picture_coarse", wmap), ("picture_full", full)):
        times = []
        for _ in range(5):
            t0 = now()
            map_picture([("", m, None)], "isotropic_force", preset)
            times.append(now() - t0)
        out[key] = times
    return out


def step_test(app, window, probe: Probe, values, *, timeout_s: float = 5.0) -> list[dict]:
    rows = []
    for g in values:
        value = (round(float(g), 4), *GEAR_REST)
        box = {}

        def fire():
            box["t0"] = now()
            window.on_parameter_edited("gear_ratios", value, True)
            box["t_ret"] = now()
            box["mech"] = window.state.mechanism
        QTimer.singleShot(0, fire)
        probe.wait(lambda: "mech" in box and probe.first_paint(box["mech"], box["t0"]) is not None
                   and probe.first_pose(box["mech"], box["t0"]) is not None
                   and probe.first_complete(box["mech"], box["t0"]) is not None, timeout_s)
        t0, mech = box["t0"], box["mech"]
        painted = probe.first_paint(mech, t0)
        posed = probe.first_pose(mech, t0)
        if painted is None or posed is None:
            print(f"  step {value[0]}: not on screen within {timeout_s} s", flush=True)
            continue
        t_map, slot = painted
        job = probe.jobs.get(slot.generation, (None, float("nan"), float("nan"), float("nan")))
        applies = [s for s in probe.spans("apply", t0, t_map) if s[2] == (slot.generation, slot.stage)]
        draws = probe.spans("canvas_draw", t0, t_map) + probe.spans("map_blit", t0, t_map)
        paints = probe.spans("canvas_paint", t0, t_map)
        rows.append({
            "value": value[0], "stage": slot.stage, "grid": "x".join(map(str, slot.map.grid.resolution)),
            "map": t_map - t0, "pose": posed - t0,
            "both": max(t_map, posed) - t0, "call": box["t_ret"] - t0,
            "submit_wait": job[1] - t0, "compute": job[2] - job[1],
            "queue": (applies[-1][0] - job[2]) if applies else float("nan"),
            "apply": sum(b - a for a, b, _ in applies),
            "stats": sum(b - a for a, b, _ in probe.spans("stats", applies[-1][0], applies[-1][1])) if applies else 0.0,
            "map_redraw": sum(b - a for a, b, _ in probe.spans("map_redraw", applies[-1][0], applies[-1][1]))
            if applies else 0.0,
            "complete": (probe.first_complete(mech, t0) or float("nan")) - t0,
            "draw": sum(b - a for a, b, _ in draws), "paint": sum(b - a for a, b, _ in paints[-1:]),
            "update_pose": sum(b - a for a, b, _ in probe.spans("update_pose", t0, posed)),
            "pose_redraw": sum(b - a for a, b, _ in probe.spans("pose_redraw", t0, posed)),
            "pose_paint": sum(b - a for a, b, _ in probe.spans("pose_paint", t0, posed)),
        })
        probe.idle(0.03)
    return rows


def drag_test(app, window, probe: Probe, values, period_s: float = 0.033) -> tuple[list[float], int]:
    calls: list[tuple[float, object]] = []
    values = list(values)
    timer = QTimer(interval=int(period_s * 1e3))
    timer.setTimerType(Qt.TimerType.PreciseTimer)

    def tick():
        if len(calls) == len(values):
            timer.stop()
            return
        value = (round(float(values[len(calls)]), 4), *GEAR_REST)
        t0 = now()
        window.on_parameter_edited("gear_ratios", value, True)
        calls.append((t0, window.state.mechanism))
    timer.timeout.connect(tick)
    start = now()
    timer.start()
    probe.wait(lambda: len(calls) == len(values) and probe.first_paint(calls[-1][1], calls[-1][0], "coarse")
               is not None, 10.0)
    latencies = []
    for t0, mech in calls:
        hit = probe.first_paint(mech, t0, "coarse")
        if hit is not None:
            latencies.append(hit[0] - t0)
    shown = len({id(slot) for t, slot in probe.painted if t >= start and slot is not None and slot.stage == "coarse"})
    return latencies, shown


def refine_test(app, window, probe: Probe, beat: Heartbeat, values) -> list[dict]:
    rows = []
    for g in values:
        value = (round(float(g), 4), *GEAR_REST)
        probe.idle(0.3)
        beat.start()
        probe.idle(0.05)
        t0 = now()
        window.on_parameter_edited("gear_ratios", value, False)
        mech = window.state.mechanism
        ok = probe.wait(lambda: probe.first_paint(mech, t0, "full") is not None, 30.0)
        if not ok:
            beat.stop()
            print(f"  refine {value[0]}: full map not on screen within 30 s", flush=True)
            continue
        t_paint, slot = probe.first_paint(mech, t0, "full")
        probe.idle(0.15)
        beat.stop()
        t_req = next(t for t, req in probe.requests if t >= t0 and req.stage == "full" and req.mechanism == mech)
        job = probe.jobs.get(slot.generation, (None, float("nan"), float("nan"), float("nan")))
        gaps = beat.gaps(t_req, t_paint + 0.15)
        during = [g for g, t in gaps if t <= job[2]]
        after = [g for g, t in gaps if t > job[2]]
        applies = [s for s in probe.spans("apply", t_req, t_paint) if s[2] == (slot.generation, "full")]
        draws = probe.spans("canvas_draw", job[2], t_paint) + probe.spans("map_blit", job[2], t_paint)
        rows.append({
            "value": value[0], "latency": t_paint - t_req, "compute": job[2] - job[1],
            "max_gap": max(g for g, _ in gaps), "max_gap_compute": max(during, default=float("nan")),
            "max_cpu": app.longest(t_req, t_paint + 0.15) if isinstance(app, CpuSlots) else float("nan"),
            "max_gap_apply": max(after, default=float("nan")), "ticks": len(gaps),
            "apply": sum(b - a for a, b, _ in applies),
            "map_redraw": sum(b - a for a, b, _ in probe.spans("map_redraw", applies[-1][0], applies[-1][1]))
            if applies else 0.0,
            "stats": sum(b - a for a, b, _ in probe.spans("stats", applies[-1][0], applies[-1][1])) if applies else 0.0,
            "draw": sum(b - a for a, b, _ in draws), "paint": sum(b - a for a, b, _ in
                                                                  probe.spans("canvas_paint", job[2], t_paint)),
            "gaps": [g for g, _ in gaps],
        })
    return rows


#: Devices of part 4b (``--drag-devices``): the Inverse3, the five-bar of paper 002, the Twin-Pantograph.
DRAG_DEVICES = "inverse3_prototype,fivebar_singh,twin_pantograph"


def full_res_drag_test(window, probe: Probe, devices, steps: int, period_s: float = 0.033) -> dict:
    """Part 4b: per device, a 30 Hz drag of its slider (``_slider``, x 1.01 a step): of its ``steps``
    calls, how many showed a map of their own design at the preset's full resolution (``full_res``)
    and at any resolution (``any``), painted between the call and the next one (the last call:
    within ``REFINE_DELAY_MS``, before the release's refinement could show one)."""
    st = window.state
    out: dict = {}
    for key in devices:
        if st.preset.key != key:
            window.choose_device(key)
        probe.wait(lambda: mw.map_ready_for(st) and not st.busy, 60.0)
        probe.idle(0.3)
        name, value = _slider(st.mechanism)
        full = st.preset.grid.resolution
        full_ms = round(st.current.map.seconds * 1e3, 1)     # (the full map's, with the statistics' quantities)
        calls: list[tuple[float, object]] = []
        timer = QTimer(interval=int(period_s * 1e3))
        timer.setTimerType(Qt.TimerType.PreciseTimer)

        def tick():
            if len(calls) == steps:
                timer.stop()
                return
            t0 = now()
            window.on_parameter_edited(name, _stepped(value, len(calls) + 1), True)
            calls.append((t0, st.mechanism))
        timer.timeout.connect(tick)
        timer.start()
        probe.wait(lambda: len(calls) == steps, 30.0)
        # At the drag's last step: whether the app takes a dragged slider's full map (the map view's
        # quantities alone) for one within a frame, from the time it predicts for it
        # (``MainWindow.rates``; None: that kind never measured).
        direct = getattr(window, "full_map_within_frame", None)
        try:
            direct = None if direct is None else bool(direct(st.mechanism, preview=True))
        except TypeError:           # an app whose drag maps are decided on the statistics' kind
            direct = bool(direct(st.mechanism))
        predict = getattr(window, "_request_quantities", None)
        predicted = None if predict is None else window.rates.seconds(
            mw.rate_key(st.mechanism, predict(st.mechanism, True)), math.prod(full))
        predicted_ms = None if predicted is None else round(predicted * 1e3, 1)
        probe.idle(mw.REFINE_DELAY_MS / 1e3)
        ends = [t for t, _ in calls[1:]] + [calls[-1][0] + mw.REFINE_DELAY_MS / 1e3]
        shown = {"full_res": 0, "any": 0}
        latencies = []
        for (t0, mech), t1 in zip(calls, ends):
            hits = [(t, slot) for t, slot in probe.painted
                    if t0 <= t < t1 and slot is not None and slot.mechanism == mech]
            if hits:
                shown["any"] += 1
            full_hits = [t for t, slot in hits if slot.map.grid.resolution == full]
            if full_hits:
                shown["full_res"] += 1
                latencies.append(full_hits[0] - t0)
        # Back to the preset's design, unmeasured.
        window.on_parameter_edited(name, value, False)
        probe.wait(lambda: mw.map_ready_for(st) and not st.busy, 60.0)
        out[key] = {**shown, "calls": steps, "grid": list(full), "full_map_compute_ms": full_ms,
                    "drag_full_map_predicted_ms": predicted_ms, "full_map_within_frame": direct,
                    "full_res_latency_ms": summary(latencies)}
        print(f"  {key:<22s} grid {' x '.join(map(str, full))} (full map computed in {full_ms:.0f} ms; a drag's "
              f"predicted {predicted_ms} ms, within a frame: {direct}): {shown['full_res']} of {steps} steps showed a "
              f"full-resolution map of their own design, {shown['any']} a map at any resolution", flush=True)
    return out


#: Devices of part 5 (``--devices``): the revolved Inverse3 slice, the Falcon's 3D box, the Inoue platform.
BLOCK_DEVICES = "inverse3_prototype,novint_falcon,inoue_platform"
#: The device part 5's own window starts on (a planar one: cheap), and switches to before
#: measuring a switch to the device already shown.
OTHER_DEVICE = "haply_2diy"
#: How long after an action's result is on screen the heartbeat keeps listening, s.
BLOCK_SETTLE_S = 0.2


def _slider(mechanism) -> tuple[str, object]:
    """The parameter part 5 steps: the first gear ratio if the device has them, else its first parameter."""
    table = [(info.name, value) for info, value in mechanism.parameter_table()
             if isinstance(value, (float, tuple)) and not isinstance(value, bool)]
    return next(((n, v) for n, v in table if n == "gear_ratios"), table[0])


def _stepped(value, k: int):
    """``value`` (a number or a tuple, display units) with its first entry times 1.01^k."""
    if isinstance(value, tuple):
        return (round(value[0] * 1.01 ** k, 6), *value[1:])
    return round(value * 1.01 ** k, 6)


def block_test(window, probe: Probe, views: ViewPaints, beat: Heartbeat, devices, steps: int) -> dict:
    """Part 5: ``{device: {action: longest GUI stall in ms}}`` (see the module docstring)."""
    st = window.state
    ws = window.workspace_view

    def on_screen(t0: float, stage: str) -> bool:
        """The design's map of ``stage`` (or later) painted since t0 (a full map: painted at all,
        as after a release where the slider rested long enough for it already), its glyphs too
        (a step), and the workspace scene of the map on screen if that tab is shown."""
        cur = st.current
        if cur is None or cur.mechanism != st.mechanism or (stage == "full" and cur.stage != "full"):
            return False
        since = 0.0 if stage == "full" else t0
        if probe.first_paint(st.mechanism, since, "full" if stage == "full" else None) is None:
            return False
        if stage != "full" and window.pose_view.isVisible() and probe.first_pose(st.mechanism, t0) is None:
            return False
        if ws.isVisible() and (cur.stage == "full" or is_volume(cur.map.grid)):
            return views.workspace_shows(cur.generation, since)
        return True

    def stall(action, until, timeout_s: float = 60.0) -> float:
        probe.idle(0.1)
        beat.start()
        probe.idle(0.05)
        box = {}

        def fire():
            box["t0"] = now()
            action()
        QTimer.singleShot(0, fire)
        # (Waited again while the deadline allows: the predicate may hold for a moment before
        # the action's own result is on screen, as it may between the action and its first paint.)
        deadline, ok = now() + timeout_s, False
        while not ok and now() < deadline:
            ok = probe.wait(lambda: "t0" in box and until(box["t0"]), deadline - now())
        probe.idle(BLOCK_SETTLE_S)
        beat.stop()
        if not ok:
            cur = st.current
            print(f"    (not on screen within {timeout_s:.0f} s: map {cur and cur.stage} of this design "
                  f"{cur is not None and cur.mechanism == st.mechanism}, workspace drawn {ws._drawn and ws._drawn[0]})",
                  flush=True)
        # Every tick since the heartbeat started (50 ms before the action): the gap that holds the
        # action's own call starts at the last tick before it.
        gaps = [g for g, _ in beat.gaps(0.0, now())]
        return 1e3 * max(gaps, default=float("nan"))

    def steps_and_release(prefix: str) -> dict:
        name, value = _slider(st.mechanism)
        blocks = [stall(lambda k=k: window.on_parameter_edited(name, _stepped(value, k), True),
                        lambda t0: on_screen(t0, "coarse")) for k in range(1, steps + 1)]
        release = stall(lambda: window.on_parameter_edited(name, _stepped(value, steps), False),
                        lambda t0: on_screen(t0, "full"))
        # Back to the preset's value, unmeasured (the next action starts from the preset's design).
        window.on_parameter_edited(name, value, False)
        probe.wait(lambda: on_screen(0.0, "full") and not st.busy, 60.0)
        return {f"{prefix}": round(max(blocks), 1), f"{prefix}_median": round(pystats.median(blocks), 1),
                f"release{prefix[4:]}": round(release, 1)}

    out: dict = {}
    views.window, views.poke = window, probe.poke
    for key in devices:
        window.tabs.setCurrentWidget(window.pose_view)
        if key == st.preset.key:            # a switch to the device shown changes nothing on screen
            window.choose_device(OTHER_DEVICE if key != OTHER_DEVICE else mw.DEFAULT_DEVICE)
            probe.wait(lambda: on_screen(0.0, "full") and not st.busy, 60.0)
        row = {"switch": round(stall(lambda key=key: window.choose_device(key), lambda t0: on_screen(t0, "full")), 1)}
        probe.wait(lambda: not st.busy, 60.0)
        row.update(steps_and_release("step"))
        row["workspace_tab"] = round(stall(lambda: window.tabs.setCurrentWidget(ws),
                                           lambda t0: views.workspace_shows(st.current.generation, t0)), 1)
        row.update(steps_and_release("step_workspace"))
        window.tabs.setCurrentWidget(window.pose_view)
        out[key] = row
        print(f"  {key:<22s} " + "  ".join(f"{k} {v:.0f}" for k, v in row.items()) + " ms", flush=True)
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=21, help="slider steps from 6.0 to 8.0")
    parser.add_argument("--refines", type=int, default=4, help="full-map refines to time")
    parser.add_argument("--json", action="store_true", help="print one JSON object of the headline figures")
    parser.add_argument("--devices", default=BLOCK_DEVICES, help="part 5's devices, comma-separated preset keys")
    parser.add_argument("--drag-devices", default=DRAG_DEVICES, help="part 4b's devices, comma-separated preset keys")
    parser.add_argument("--block-steps", type=int, default=4, help="part 5's slider steps per device and tab")
    parser.add_argument("--blocks-only", action="store_true", help="run part 5 (GUI blocks per device) alone")
    args = parser.parse_args()
    if not args.json:
        return run(args, None)
    figures: dict = {}
    with contextlib.redirect_stdout(sys.stderr):
        status = run(args, figures)
    print(json.dumps(figures, indent=2))
    return status


def summary(values_s) -> dict:
    """median, p90 and max in ms (None for no values: JSON has no NaN)."""
    v = [x * 1e3 for x in values_s if np.isfinite(x)]
    if not v:
        return {"median": None, "p90": None, "max": None, "n": 0}
    return {"median": round(pystats.median(v), 2), "p90": round(pct(v, 90), 2), "max": round(max(v), 2), "n": len(v)}


def run(args, figures: dict | None) -> int:
    """The benchmark; the headline figures go into ``figures`` when it is a dict."""
    app = QApplication.instance() or CpuSlots(sys.argv[:1])
    probe = Probe()
    probe.install()
    views = ViewPaints()
    views.install()
    if args.blocks_only:
        return run_blocks(args, probe, views, figures)

    load_start = round(os.getloadavg()[0], 2)
    print("isoforce GUI benchmark: Inverse3 prototype, gear ratio theta_0 slider; load average "
          f"{os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs", flush=True)
    base = baselines()
    print(f"\nNon-GUI baselines (same process, before the window): coarse grid "
          f"{' x '.join(map(str, base['coarse_grid']))}, full grid {' x '.join(map(str, base['full_grid']))}")
    print(line("compute_map coarse (Table 3 quantities)", base["compute_coarse"]))
    print(line("compute_map full", base["compute_full"]))
    print(line("analyse_pose (default glyphs)", base["analyse_pose"]))
    print(line("draw_map + Agg draw, coarse map (800x900)", base["agg_coarse"]))
    print(line("draw_map + Agg draw, full map (800x900)", base["agg_full"]))
    print(line("map_picture (the app's map view), coarse", base["picture_coarse"]))
    print(line("map_picture (the app's map view), full", base["picture_full"]))

    with tempfile.TemporaryDirectory() as tmp:
        window = mw.MainWindow(device=mw.DEFAULT_DEVICE, settings_file=Path(tmp) / "settings.ini")
        probe.attach(window)
        window.resize(*WINDOW)
        window.move(0, 0)
        window.show()
        mech0 = window.state.mechanism
        if not probe.wait(lambda: probe.first_paint(mech0, 0.0, "full") is not None, 60.0):
            print("the first full map never reached the screen", flush=True)
            return 1
        probe.idle(1.0)
        canvas = window.map_view.canvas
        print(f"\nWindow {WINDOW[0]} x {WINDOW[1]}; map canvas {canvas.width()} x {canvas.height()} px; "
              f"REFINE_DELAY_MS {mw.REFINE_DELAY_MS}")

        beat = Heartbeat()
        beat.start()
        t_idle = now()
        probe.idle(1.0)
        beat.stop()
        idle_gaps = [g for g, _ in beat.gaps(t_idle, now())]
        print(f"\nIdle window, 1 s of 2 ms heartbeat: longest gap {max(idle_gaps) * 1e3:.1f} ms, "
              f"median {pystats.median(idle_gaps) * 1e3:.2f} ms")

        steps = step_test(app, window, probe, np.linspace(6.0, 8.0, args.steps))
        grids = {g: sum(r["grid"] == g for r in steps) for g in sorted({r["grid"] for r in steps})}
        print(f"\nSlider steps (dragging=True), one at a time: latency from on_parameter_edited to screen "
              f"({len(steps)} steps, stages {sorted({r['stage'] for r in steps})}, map grids {grids})")
        print(line("map + glyphs on screen (the bar: <= 50 ms)", [r["both"] for r in steps]))
        print(line("  map painted", [r["map"] for r in steps]))
        print(line("  map with legend, colour bar, title", [r["complete"] for r in steps]))
        print(line("  glyphs rendered", [r["pose"] for r in steps]))
        print("  split of the map latency:")
        print(line("    on_parameter_edited returns (GUI)", [r["call"] for r in steps]))
        print(line("    job starts on the worker", [r["submit_wait"] for r in steps]))
        print(line("    compute (worker thread)", [r["compute"] for r in steps]))
        print(line("    wait for the GUI thread", [r["queue"] for r in steps]))
        print(line("    apply result (_on_result, GUI)", [r["apply"] for r in steps]))
        print(line("      of it MapView.redraw (draw_map)", [r["map_redraw"] for r in steps]))
        print(line("      of it StatsPanel.refresh", [r["stats"] for r in steps]))
        print(line("    canvas draw or blit (Agg render, GUI)", [r["draw"] for r in steps]))
        print(line("    canvas paint (GUI)", [r["paint"] for r in steps]))
        print("  split of the glyph latency:")
        print(line("    update_pose (analyse_pose + PoseView.redraw)", [r["update_pose"] for r in steps]))
        print(line("      of it PoseView.redraw (scene)", [r["pose_redraw"] for r in steps]))
        print(line("    pose view paint (VTK render + blit)", [r["pose_paint"] for r in steps]))

        probe.idle(1.5)       # let the refine after the steps finish
        probe.wait(lambda: not window.state.busy, 30.0)
        probe.idle(0.3)
        latencies, shown = drag_test(app, window, probe, np.linspace(8.0, 6.0, args.steps))
        print(f"\nDrag at 30 Hz ({args.steps} calls every 33 ms, no waiting): {shown} coarse maps reached the "
              f"screen")
        print(line("latency of each shown map from its call", latencies))

        probe.idle(1.5)
        probe.wait(lambda: not window.state.busy, 30.0)
        refines = refine_test(app, window, probe, beat, np.linspace(6.5, 7.5, args.refines))
        print(f"\nRefines (slider released, full {' x '.join(map(str, base['full_grid']))} map after "
              f"{mw.REFINE_DELAY_MS} ms), 2 ms heartbeat on the GUI thread ({len(refines)} refines)")
        print(line("longest GUI block per refine (bar: <= 50 ms)", [r["max_gap"] for r in refines]))
        print(line("  its CPU: longest event dispatch (thread_time)", [r["max_cpu"] for r in refines]))
        print(line("  longest block while computing", [r["max_gap_compute"] for r in refines]))
        print(line("  longest block applying/drawing full map", [r["max_gap_apply"] for r in refines]))
        print(line("all heartbeat gaps during refines", [g for r in refines for g in r["gaps"]]))
        print(line("full request -> full map painted", [r["latency"] for r in refines]))
        print(line("  compute (worker thread)", [r["compute"] for r in refines]))
        print(line("  apply result (_on_result, GUI)", [r["apply"] for r in refines]))
        print(line("    of it MapView.redraw (draw_map)", [r["map_redraw"] for r in refines]))
        print(line("    of it StatsPanel.refresh", [r["stats"] for r in refines]))
        print(line("  canvas draw or blit (Agg render, GUI)", [r["draw"] for r in refines]))
        print(line("  canvas paint (GUI)", [r["paint"] for r in refines]))
        if figures is not None:
            figures.update({
                "slider_to_screen_ms": summary([max(r["complete"], r["pose"]) for r in steps]),
                "slider_map_grids": grids,
                "map_painted_ms": summary([r["map"] for r in steps]),
                "glyphs_ms": summary([r["pose"] for r in steps]),
                "refine_gui_block_ms": summary([r["max_gap"] for r in refines]),
                "refine_gui_cpu_block_ms": summary([r["max_cpu"] for r in refines]),
                "drag_30hz_maps_shown": shown, "drag_30hz_calls": args.steps,
                "drag_30hz_latency_ms": summary(latencies),
                "window": list(WINDOW), "map_canvas_px": [canvas.width(), canvas.height()],
                "cpus": os.cpu_count(), "load_average_start": load_start,
            })
        print(f"\nDrag at 30 Hz per device ({args.steps} calls, the slider of part 5), maps of each step's own "
              f"design shown before the next step:")
        drags = full_res_drag_test(window, probe, args.drag_devices.split(","), args.steps)
        if figures is not None:
            figures["drag_full_res_maps_shown"] = {k: v["full_res"] for k, v in drags.items()}
            figures["drag_30hz_by_device"] = drags
        window.choose_device(mw.DEFAULT_DEVICE)
        probe.wait(lambda: mw.map_ready_for(window.state) and not window.state.busy, 60.0)
        print(f"\nGUI blocks (longest event-loop stall, 2 ms heartbeat) per device and action, "
              f"{args.block_steps} slider steps each:")
        blocks = block_test(window, probe, views, beat, args.devices.split(","), args.block_steps)
        if figures is not None:
            figures["gui_block_ms"] = blocks
        window.close()
    print(f"\nLoad average at the end: {os.getloadavg()[0]:.2f}")
    if figures is not None:
        figures["load_average_end"] = round(os.getloadavg()[0], 2)
    return 0



def run_blocks(args, probe: Probe, views: ViewPaints, figures: dict | None) -> int:
    """Part 5 alone, on its own window (``--blocks-only``)."""
    with tempfile.TemporaryDirectory() as tmp:
        window = mw.MainWindow(device=OTHER_DEVICE, settings_file=Path(tmp) / "settings.ini")
        probe.attach(window)
        window.resize(*WINDOW)
        window.move(0, 0)
        window.show()
        mech0 = window.state.mechanism
        if not probe.wait(lambda: probe.first_paint(mech0, 0.0, "full") is not None, 60.0):
            print("the first full map never reached the screen", flush=True)
            return 1
        probe.idle(1.0)
        print(f"isoforce GUI blocks: window {WINDOW[0]} x {WINDOW[1]}, load average {os.getloadavg()[0]:.2f} on "
              f"{os.cpu_count()} CPUs; longest event-loop stall (2 ms heartbeat) per device and action, "
              f"{args.block_steps} slider steps each:", flush=True)
        blocks = block_test(window, probe, views, Heartbeat(), args.devices.split(","), args.block_steps)
        if figures is not None:
            figures.update({"gui_block_ms": blocks, "window": list(WINDOW), "cpus": os.cpu_count(),
                            "load_average_end": round(os.getloadavg()[0], 2)})
        window.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
