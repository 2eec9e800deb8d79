"""Make the README's screenshots of the desktop app (run under a display, e.g. Xvfb).

    xvfb-run -a -s "-screen 0 1920x1080x24" python scripts/screenshots.py [--out docs/screenshots]

Starts the real main window with a throw-away settings file, waits until the full map is
on screen, and saves the window for a few states: the first screen, the five-bar with its
condition number, and the Scenario 2 comparison (paper 000 Fig. 5 a/b).
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from PySide6.QtWidgets import QApplication  # noqa: E402

from app.gui import MainWindow  # noqa: E402


def settle(app, window, seconds: float = 0.3, timeout: float = 30.0) -> None:
    """Process events until no map is being computed, then a little longer."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        app.processEvents()
        if not window.state.busy and window.state.current is not None and window.state.current.stage == "full":
            break
        time.sleep(0.01)
    window.map_view.canvas.draw()        # paint the newest map now, not at the next idle moment
    stop = time.monotonic() + seconds
    while time.monotonic() < stop:
        app.processEvents()
        time.sleep(0.01)


def grab(window, path: Path) -> None:
    screen = window.screen()
    pixmap = screen.grabWindow(0, window.x(), window.y(), window.frameGeometry().width(),
                               window.frameGeometry().height())
    pixmap.save(str(path))
    print(f"wrote {path}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="docs/screenshots", help="folder for the PNGs")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    app = QApplication.instance() or QApplication(sys.argv[:1])
    with tempfile.TemporaryDirectory() as tmp:
        window = MainWindow(device="inverse3_prototype", settings_file=Path(tmp) / "settings.ini")
        window.resize(1800, 1000)
        window.move(0, 0)
        window.show()
        settle(app, window)
        grab(window, out / "app_inverse3_isotropic.png")

        window.state.set_desired_force((12.0, 0.0, 4.0))
        window.state.set_glyph("force_ellipsoid", True)
        settle(app, window)
        grab(window, out / "app_inverse3_glyphs.png")

        window.pin_reference()
        settle(app, window)
        window.on_parameter_edited("gear_ratios", (13.75, 5.957, 5.957), False)
        settle(app, window, seconds=1.0)
        grab(window, out / "app_compare_scenario2.png")

        window.state.clear_reference()
        window.load_device("fivebar_singh")
        window.quantity_box.setCurrentIndex(window.quantity_box.findData("condition_number"))
        settle(app, window)
        window.tabs.setCurrentWidget(window.workspace_view)
        settle(app, window, seconds=0.5)
        window.tabs.setCurrentWidget(window.pose_view)
        settle(app, window)
        grab(window, out / "app_fivebar_condition.png")
        window.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
