"""Soak run of the desktop app: a long session of slider edits with device and tab switches.

    xvfb-run -a -s "-screen 0 1920x1080x24" python scripts/soak_gui.py [--edits 1500] [--per-device 25]
        [--presets all|family|KEY,KEY...] [--longest N] [--trim] [--json]

Drives the real ``MainWindow`` (throw-away settings) as a person does, through its widgets'
own signals: each *edit* is one step of a parameter slider held down (``QSlider.setSliderDown``,
then ``setValue``: the map follows coarsely), out and back (``DRAG_PATH``), then the slider is
released (the full map refines; it is waited for). Each drag takes the next row of the panel.
After every other drag the 3D views' tab flips (Pose / Workspace). Every ``--per-device``
edits the next quantity of the list is chosen and the device list moves to the next preset
(``activated``, as a click does): every preset in turn, then round again. An error dialog
or a modal window is counted, its text kept, and closed, and the run goes on.

A *step* is timed from the slider's move until the map of that design is in the window (the
coarse map, or the one on screen if the edit changed nothing) and the events it queued
have run.

Per 100 edits it reports RSS (``VmRSS``), Qt widgets (all and top-level), threads (the
process's, Python's), open file descriptors, objects tracked by the garbage collector (the
window freezes the ~2 x 10^5 alive when it opens: those are not counted), ``sys.getrefcount(None)``,
the median and p90 step, and the devices edited. The summary compares the *tour starts*: the
moment each tour through the presets is back on the first preset, its full map shown and the
garbage collected (the same device in the same state), so what grows there grows with the
session; the first tour is warm-up (caches, a camera per device, each device's first popups).
It also gives ``None``'s drift over each device visit's drags (no widget built there: a
binding that drops references shows as a fall) and the median step per device.

``--presets family`` tours the first preset of each mechanism class only (7 of 13: tour starts
come twice as often), ``--presets KEY`` repeats one preset's edit loop (each tour start is then
a visit of it). ``--longest N`` shrinks every preset's grid as the GUI tests do; ``--trim`` adds
the RSS after ``malloc_trim`` at each tour start (held memory, not what the allocator keeps for
reuse). Read growth from ``--trim`` over several tour starts: the plain RSS at a tour start
swings by 10-15 MB either way with what the GUI thread last freed (colouring, a revolved
volume: ~45 MB above the held memory after a full Inverse3 redraw of the Workspace tab), so
two tour starts alone can show 35 MB per 1,000 edits where nothing is held. Measured
(``--presets family --per-device 6``, full grids, after warm-up): RSS 590.1 -> 588.2 -> 582.0 MB,
after ``malloc_trim`` 581.0 -> 575.2 -> 578.7 MB over 84 edits; on 40-point grids
(``--longest 40 --per-device 12``) 509.8 -> 504.4 MB held over 588 edits.
``--json`` prints JSON lines (``{"block": ...}`` per 100 edits, ``{"tour": ...}`` per tour
start, then ``{"summary": ...}``); the readable report goes to stderr. It asserts nothing;
``tests/app/gui/test_soak.py`` runs a short soak on shrunk grids and asserts.
"""
from __future__ import annotations

import argparse
import ctypes
import gc
import json
import os
import statistics
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from PySide6.QtCore import QEventLoop, QTimer  # noqa: E402
from PySide6.QtWidgets import QApplication  # noqa: E402

from resources import list_presets  # noqa: E402

now = time.perf_counter
#: A drag: slider offsets (in slider steps, ``ParameterRow.step`` each) from where it was, one per edit.
DRAG_PATH = (10, 20, 30, 20, 10, 0)
#: Edits per report block.
BLOCK = 100
#: How long a step may wait for its map, and a release or a switch for the full map, s.
STEP_TIMEOUT_S, FULL_TIMEOUT_S = 20.0, 120.0


def one_per_family() -> list[str]:
    """The first preset of each mechanism class, in the presets' order."""
    from resources import load_preset
    first: dict[type, str] = {}
    for key in list_presets():
        first.setdefault(type(load_preset(key).mechanism), key)
    return list(first.values())


def process_figures() -> dict:
    """RSS (MB), threads and open file descriptors of this process (Linux ``/proc``)."""
    status = {}
    with open("/proc/self/status", encoding="ascii") as f:
        for line in f:
            key, _, value = line.partition(":")
            status[key] = value.strip()
    return {"rss_mb": round(int(status["VmRSS"].split()[0]) / 1024, 1),
            "hwm_mb": round(int(status["VmHWM"].split()[0]) / 1024, 1),
            "threads": int(status["Threads"]), "python_threads": threading.active_count(),
            "fds": len(os.listdir("/proc/self/fd"))}


def qt_figures() -> dict:
    return {"widgets": len(QApplication.allWidgets()), "top_level": len(QApplication.topLevelWidgets())}


def trimmed_rss_mb() -> float | None:
    """RSS after glibc's ``malloc_trim(0)`` has handed the free heap back: what is still held, not
    what the allocator keeps for reuse (None off glibc)."""
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except OSError:
        return None
    return process_figures()["rss_mb"]


def figures(collect: bool = False, trim: bool = False) -> dict:
    """Everything a block reports; ``collect`` (tour starts): after a full garbage collection;
    ``trim``: with the RSS after ``malloc_trim`` too (``rss_mb`` is taken before it)."""
    if collect:
        gc.collect()
    out = {**process_figures(), **qt_figures(), "gc_objects": len(gc.get_objects()),
           "none_refs": sys.getrefcount(None)}
    if trim:
        out["rss_trimmed_mb"] = trimmed_rss_mb()
    return out


class _Waiter:
    """Runs Qt's event loop (a real ``QEventLoop``, as ``app.exec`` does) until a condition holds.

    One loop and one polling timer, connected once: with PySide6 6.11 every ``connect`` and
    every ``QTimer.singleShot`` with a delay leaves a reference to ``None`` behind (+1 and
    +3 to +4 per call, measured), so a harness that made its own per wait would drift the very
    count it watches.
    """

    def __init__(self) -> None:
        self.loop = QEventLoop()
        self.timer = QTimer(interval=2)
        self.timer.timeout.connect(self._check)
        self.predicate = lambda: True
        self.deadline = 0.0

    def _check(self) -> None:
        if self.predicate() or now() > self.deadline:
            self.loop.quit()

    def until(self, predicate, timeout_s: float, *, turn: bool = False) -> bool:
        """``turn``: run the loop at least once (until the next poll) even if ``predicate()`` holds."""
        if predicate() and not turn:
            return True
        self.predicate, self.deadline = predicate, now() + timeout_s
        self.timer.start()
        self.loop.exec()
        self.timer.stop()
        return bool(predicate())


_WAITER: _Waiter | None = None


def wait_until(predicate, timeout_s: float, *, turn: bool = False) -> bool:
    """Run Qt's event loop until ``predicate()`` or ``timeout_s``; returns ``predicate()``."""
    global _WAITER
    if _WAITER is None:
        _WAITER = _Waiter()
    return _WAITER.until(predicate, timeout_s, turn=turn)


def settle(ms: int = 10) -> None:
    """Let the events already queued run (a paint, a deferred delete), and ``ms`` more."""
    end = now() + ms / 1e3
    wait_until(lambda: now() >= end, ms / 1e3 + 1.0, turn=True)


@dataclass
class Soak:
    """A soak session on ``window``; ``run(edits)`` does the edits and fills ``blocks`` and ``tours``.

    ``presets`` are visited in turn, ``per_device`` edits each; ``on_block(dict)`` and
    ``on_tour(dict)`` hear each report as it is made.
    """

    window: object
    presets: list[str]
    per_device: int = 25
    trim: bool = False
    refine: bool = True         # wait for the full map after each release (else the next drag follows at once)
    pace_s: float | None = None  # a step waits at most this long for its map (a hand that does not wait), s
    on_block: object = None
    on_tour: object = None
    steps: list[tuple[str, float]] = field(default_factory=list)        # (device, seconds) per edit
    blocks: list[dict] = field(default_factory=list)
    tours: list[dict] = field(default_factory=list)
    visits: list[dict] = field(default_factory=list)    # per device visit: its edits and None's drift over them
    dialogs: list[str] = field(default_factory=list)
    start: float = field(default_factory=now)

    # -- the user's moves ------------------------------------------------------------------
    def _map_of_design(self) -> bool:
        st = self.window.state
        return st.current is not None and st.current.mechanism == st.mechanism and not self._dialog_open()

    def _full_map(self) -> bool:
        from app.gui.main_window import map_ready_for
        return map_ready_for(self.window.state) and not self.window.state.busy

    def _dialog_open(self) -> bool:
        box = self.window.error_box
        return (box is not None and box.isVisible()) or QApplication.activeModalWidget() is not None

    def close_dialogs(self) -> None:
        """Count and close an error box or a modal window (the run goes on)."""
        box = self.window.error_box
        if box is not None and box.isVisible():
            self.dialogs.append(box.text())
            box.close()
        modal = QApplication.activeModalWidget()
        if modal is not None:
            self.dialogs.append(f"{type(modal).__name__}: {getattr(modal, 'text', lambda: '')()}")
            modal.close()

    def drag(self, row, device: str) -> None:
        """One drag of ``row``'s slider along ``DRAG_PATH`` (an edit per step), then its release."""
        slider = row.slider
        origin = slider.value()
        sign = -1 if origin + max(DRAG_PATH) > slider.maximum() else 1
        slider.setSliderDown(True)
        for offset in DRAG_PATH:
            t0 = now()
            slider.setValue(origin + sign * offset)
            wait_until(self._map_of_design, self.pace_s or STEP_TIMEOUT_S)
            settle(0)
            self.steps.append((device, now() - t0))
            self.close_dialogs()
            if len(self.steps) % BLOCK == 0:
                self.report_block()
        slider.setSliderDown(False)             # sliderReleased: the full map refines
        if self.refine:
            wait_until(self._full_map, FULL_TIMEOUT_S)
        else:
            settle(0)
        self.close_dialogs()

    def switch_device(self, key: str) -> None:
        """The next quantity of the list, then ``key`` chosen in the device list."""
        window = self.window
        box = window.quantity_box
        box.setCurrentIndex((box.currentIndex() + 1) % box.count())
        presets = window.param_panel.preset_box
        index = presets.findData(key)
        presets.setCurrentIndex(index)
        presets.activated.emit(index)
        self.until_full_map()
        self.close_dialogs()

    def until_full_map(self) -> None:
        """Until the design's full map and its glyphs are shown, and the queued events have run."""
        wait_until(self._full_map, FULL_TIMEOUT_S)
        # A switch's glyphs come a few passes of the event loop after its map
        # (``MainWindow._defer_pose``), and a visit's drags must not count them.
        wait_until(lambda: not self.window._pose_deferred, FULL_TIMEOUT_S)
        settle(20)

    def flip_tab(self) -> None:
        tabs = self.window.tabs
        tabs.setCurrentIndex(1 - tabs.currentIndex())
        settle(20)

    # -- the run ---------------------------------------------------------------------------
    def run(self, edits: int) -> None:
        drags = 0
        visit = 0
        while len(self.steps) < edits:
            key = self.presets[visit % len(self.presets)]
            if visit > 0:
                self.switch_device(key)
            if visit % len(self.presets) == 0:
                self.report_tour(visit // len(self.presets))
            visit += 1
            rows = list(self.window.param_panel.rows.values())
            done, before = 0, self._none_refs()
            while done < self.per_device and len(self.steps) < edits:
                row = rows[drags % len(rows)]
                self.drag(row, key)
                drags += 1
                done += len(DRAG_PATH)
                if drags % 2 == 0:
                    self.flip_tab()
            # None's count is compared in like states: at the start the switch's full map is shown,
            # so the end waits for the last release's (a preview map's objects hold other references).
            self.until_full_map()
            self.visits.append({"device": key, "edits": done, "none_drift": self._none_refs() - before})

    @staticmethod
    def _none_refs() -> int:
        """``sys.getrefcount(None)`` once the queued events have run and the garbage is collected."""
        settle(20)
        gc.collect()
        return sys.getrefcount(None)

    def report_block(self) -> None:
        block = self.steps[-BLOCK:]
        times = sorted(1e3 * t for _, t in block)
        devices = list(dict.fromkeys(d for d, _ in block))
        row = {"edits": len(self.steps), "seconds": round(now() - self.start, 1), **figures(),
               "step_ms_median": round(statistics.median(times), 1),
               "step_ms_p90": round(times[int(0.9 * (len(times) - 1))], 1),
               "devices": devices, "dialogs": len(self.dialogs)}
        self.blocks.append(row)
        if self.on_block:
            self.on_block(row)

    def report_tour(self, tour: int) -> None:
        settle(50)
        row = {"tour": tour, "edits": len(self.steps), "device": self.window.state.preset.key,
               **figures(collect=True, trim=self.trim)}
        self.tours.append(row)
        if self.on_tour:
            self.on_tour(row)

    def summary(self) -> dict:
        """Growth between tour starts after warm-up (the first tour), step medians per device."""
        after = self.tours[1:]
        out = {"edits": len(self.steps), "seconds": round(now() - self.start, 1), "presets": len(self.presets),
               "tours_started": len(self.tours), "dialogs": self.dialogs}
        if len(after) >= 2:
            first, last = after[0], after[-1]
            span = last["edits"] - first["edits"]
            out["after_warm_up"] = {
                "edits": span,
                "rss_mb": [t["rss_mb"] for t in after],
                "rss_growth_mb_per_1000_edits": round(1000 * (last["rss_mb"] - first["rss_mb"]) / span, 1),
                **({"rss_trimmed_mb": [t["rss_trimmed_mb"] for t in after],
                    "rss_trimmed_growth_mb_per_1000_edits": round(
                        1000 * (last["rss_trimmed_mb"] - first["rss_trimmed_mb"]) / span, 1)}
                   if first.get("rss_trimmed_mb") is not None and last.get("rss_trimmed_mb") is not None else {}),
                **{key: [t[key] for t in after]
                   for key in ("widgets", "top_level", "threads", "fds", "gc_objects", "none_refs")},
            }
        drifts = [v["none_drift"] for v in self.visits[len(self.presets):]]
        if drifts:
            out["none_drift_per_visit_after_warm_up"] = {"min": min(drifts), "max": max(drifts),
                                                         "visits": len(drifts)}
        per_device: dict[str, list[float]] = {}
        for device, t in self.steps:
            per_device.setdefault(device, []).append(1e3 * t)
        out["step_ms_median_by_device"] = {d: round(statistics.median(v), 1) for d, v in per_device.items()}
        return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--edits", type=int, default=1500, help="slider steps in all (default 1500)")
    parser.add_argument("--per-device", type=int, default=25, help="edits before the next device (default 25)")
    parser.add_argument("--longest", type=int, default=None,
                        help="shrink every preset's map grid to this many points along its longer axis "
                             "(as the GUI tests do); default: the presets' own grids")
    parser.add_argument("--trim", action="store_true",
                        help="at each tour start also report the RSS after malloc_trim (what is held, not what "
                             "the allocator keeps); it hands memory back, so later RSS figures are lower")
    parser.add_argument("--presets", default="all",
                        help="the presets toured: 'all' (default), 'family' (the first of each mechanism class, "
                             "as the suite's short soak) or keys separated by commas; fewer presets give tour "
                             "starts sooner, and one preset repeats its edit loop")
    parser.add_argument("--json", action="store_true", help="JSON lines on stdout (the report on stderr)")
    args = parser.parse_args()
    app = QApplication.instance() or QApplication(sys.argv[:1])
    from app.gui import file_actions
    from app.gui import main_window as mw
    if args.longest:
        from resources import load_preset

        def shrunk(key):        # as the GUI tests' ``make_window(..., longest=N)``: aspect kept
            preset = load_preset(key)
            top = max(preset.grid.resolution)
            if top <= args.longest:
                return preset
            return preset.replace(grid=preset.grid.with_resolution(
                tuple(max(3, round(n * args.longest / top)) for n in preset.grid.resolution)))
        mw.load_preset = file_actions.load_preset = shrunk      # the first device and every later one

    def say(text: str) -> None:
        print(text, file=sys.stderr if args.json else sys.stdout, flush=True)

    def emit(kind: str, row: dict) -> None:
        if args.json:
            print(json.dumps({kind: row}), flush=True)

    def on_block(row: dict) -> None:
        emit("block", row)
        say(f"{row['edits']:5d} edits {row['seconds']:7.1f} s  RSS {row['rss_mb']:7.1f} MB  widgets "
            f"{row['widgets']:4d} ({row['top_level']} top)  threads {row['threads']:3d}  fds {row['fds']:3d}  "
            f"gc {row['gc_objects']:7d}  None refs {row['none_refs']:6d}  step median {row['step_ms_median']:6.1f} "
            f"p90 {row['step_ms_p90']:6.1f} ms  {', '.join(row['devices'])}" + (
                f"  dialogs {row['dialogs']}" if row["dialogs"] else ""))

    def on_tour(row: dict) -> None:
        emit("tour", row)
        trimmed = f" ({row['rss_trimmed_mb']} MB after malloc_trim)" if "rss_trimmed_mb" in row else ""
        say(f"tour {row['tour']} starts at {row['edits']} edits on {row['device']}: RSS {row['rss_mb']} MB{trimmed}, "
            f"widgets {row['widgets']} ({row['top_level']} top), threads {row['threads']}, fds {row['fds']}, "
            f"gc {row['gc_objects']}, None refs {row['none_refs']}")

    presets = (list_presets() if args.presets == "all" else one_per_family() if args.presets == "family"
               else [key.strip() for key in args.presets.split(",") if key.strip()])
    with tempfile.TemporaryDirectory() as tmp:
        window = mw.MainWindow(device=presets[0], settings_file=Path(tmp) / "settings.ini")
        window.resize(1600, 950)
        window.show()
        wait_until(lambda: mw.map_ready_for(window.state), FULL_TIMEOUT_S)
        say(f"soak: {args.edits} edits, {args.per_device} per device, through {len(presets)} presets"
            + (f" (grids shrunk to {args.longest} points)" if args.longest else "") + "; "
            f"PySide6 {__import__('PySide6').__version__}, Python {sys.version.split()[0]}")
        soak = Soak(window, presets, per_device=args.per_device, trim=args.trim, on_block=on_block, on_tour=on_tour)
        soak.run(args.edits)
        summary = soak.summary()
        emit("summary", summary)
        say(json.dumps(summary, indent=2))
        window.close()
    del app
    return 0


if __name__ == "__main__":
    sys.exit(main())
