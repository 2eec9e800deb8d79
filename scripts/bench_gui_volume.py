"""Slider-to-screen time of the app for a 3D box map (run under a display, e.g. Xvfb).

    xvfb-run -a -s "-screen 0 1920x1080x24" python scripts/bench_gui_volume.py [--device novint_falcon]
        [--resolution 60] [--steps 15]

Drives the real ``MainWindow`` with the device's box map at ``resolution``^3 points (throw-away
settings, the Workspace (3D) tab shown) and prints figures; it asserts nothing:

1. Plane slider: ``SliceControls.slider`` stepped one grid plane at a time through the full
   volume, held (``setSliderDown(True)``: a drag, the views draw only cheap geometry) and not
   held (keyboard steps: everything redrawn). Latency from the step until both the map view
   (plane heat map blitted, deferred legend / colour bar / title drawn) and the workspace
   view (its off-screen VTK frame painted) are on screen; for the drag also from the release
   until the labels and the full 3D look are on screen.
2. Design slider: the first link-length parameter edited as while dragging. Latency from the
   edit until the coarse volume (``COARSE_VOLUME_POINTS``^3) of the new design is painted in
   the workspace view, until the full ``resolution``^3 volume is painted after the refine
   delay (slider still held), and from the release until the full look is painted.
"""
from __future__ import annotations

import argparse
import statistics as pystats
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from PySide6.QtWidgets import QApplication  # noqa: E402

from app.gui import main_window as mw  # noqa: E402
from app.gui.views.plotter_widget import PlotterWidget  # noqa: E402

now = time.perf_counter


def summary(label: str, seconds: list[float]) -> str:
    ms = sorted(s * 1e3 for s in seconds)
    if not ms:
        return f"  {label:<50s} (none)"
    p90 = ms[min(len(ms) - 1, int(round(0.9 * (len(ms) - 1))))]
    return f"  {label:<50s} median {pystats.median(ms):7.1f}  p90 {p90:7.1f}  max {ms[-1]:7.1f} ms  (n={len(ms)})"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--device", default="novint_falcon", help="a preset whose map is a 3D box")
    parser.add_argument("--resolution", type=int, default=60, help="points per axis of the full volume")
    parser.add_argument("--steps", type=int, default=15, help="plane slider steps and design edits")
    args = parser.parse_args()

    paints: list[float] = []
    original_paint = PlotterWidget.paintEvent

    def paint(widget, event):
        original_paint(widget, event)
        if window is not None and widget is window.workspace_view.view:
            paints.append(now())

    window = None
    PlotterWidget.paintEvent = paint
    load = mw.load_preset
    mw.load_preset = lambda key: (lambda p: p.replace(grid=p.grid.with_resolution(args.resolution)))(load(key))
    app = QApplication.instance() or QApplication(sys.argv[:1])

    def pump_until(predicate, timeout: float = 60.0) -> bool:
        end = now() + timeout
        while now() < end:
            app.processEvents()
            if predicate():
                return True
            time.sleep(0.0005)
        return False

    with tempfile.TemporaryDirectory() as tmp:
        window = mw.MainWindow(device=args.device, settings_file=Path(tmp) / "settings.ini")
        window.resize(1600, 950)
        window.show()
        st = window.state
        if len(st.preset.grid.axes) != 3:
            print(f"{args.device}: its map is not a 3D box", file=sys.stderr)
            return 2
        window.tabs.setCurrentWidget(window.workspace_view)
        pump_until(lambda: st.current is not None and st.current.stage == "full" and not st.busy, 300)
        pump_until(lambda: False, 1.0)
        print(f"{st.preset.name}: full volume {' x '.join(map(str, st.current.map.grid.resolution))} "
              f"computed in {st.current.map.seconds * 1e3:.0f} ms")

        view, controls = window.map_view, window.map_view.slice_controls
        start_index = max(0, controls.slider.value() - args.steps // 2)

        def settled(count):
            return len(paints) > count and not view._later and not view._full_draw_pending

        def steps(held: bool) -> tuple[list[float], list[float]]:
            plane, release = [], []
            controls.slider.setValue(start_index)
            pump_until(lambda: settled(0) and False, 0.5)
            if held:
                controls.slider.setSliderDown(True)        # emits sliderPressed, as a mouse press does
                pump_until(lambda: False, 0.3)
            for i in range(args.steps):
                count = len(paints)
                t0 = now()
                controls.slider.setValue(start_index + i + 1)
                if pump_until(lambda: settled(count), 10):
                    plane.append(now() - t0)
            if held:
                count = len(paints)
                t0 = now()
                controls.slider.setSliderDown(False)
                if pump_until(lambda: settled(count), 10):
                    release.append(now() - t0)
            pump_until(lambda: False, 0.3)
            return plane, release

        held, release = steps(True)
        loose, _ = steps(False)
        print("Plane slider (one grid plane per step):")
        print(summary("held: step -> map plane and 3D plane on screen", held))
        print(summary("held: release -> labels and full 3D look on screen", release))
        print(summary("not held: step -> everything on screen", loose))

        name = next(iter(window.param_panel.rows))
        row = window.param_panel.rows[name]
        coarse, full, rest = [], [], []
        for i in range(max(1, args.steps // 3)):
            value = row.spin.value() * (1.01 if i % 2 == 0 else 1 / 1.01)
            param = name[0] if isinstance(name, tuple) else name
            t0 = now()
            window.on_parameter_edited(param, value, True)
            mech = st.mechanism

            def drawn(stage):
                cur = st.current
                return (cur is not None and cur.mechanism == mech and cur.stage == stage
                        and window.workspace_view._drawn is not None
                        and window.workspace_view._drawn[0] == cur.generation and paints and paints[-1] > t0)
            if pump_until(lambda: drawn("coarse"), 30):
                coarse.append(paints[-1] - t0)
            if pump_until(lambda: drawn("full"), 120):
                full.append(paints[-1] - t0)
            count = len(paints)
            t1 = now()
            window.on_parameter_edited(param, value, False)     # the slider released where it rests
            if pump_until(lambda: len(paints) > count, 10):
                rest.append(paints[-1] - t1)
            pump_until(lambda: False, 0.3)
        print(f"Design slider ({param}), coarse {mw.coarse_grid(st.preset.grid).resolution} then full:")
        print(summary("edit -> coarse volume painted in the 3D view", coarse))
        print(summary("edit -> full volume painted (after refine delay)", full))
        print(summary("release -> full look painted", rest))
        window.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
