"""Make the README's screenshots of the desktop app (run under a display, e.g. Xvfb).

    xvfb-run -a -s "-screen 0 1920x1080x24" python scripts/screenshots.py [--out docs/screenshots]

Starts the real main window with a throw-away settings file, waits until the full map is
on screen, and saves the window for a few states: the first screen, the five-bar with its
condition number and with paper 002's overlays (force ellipses, condition bands), the
Scenario 2 comparison (paper 000 Fig. 5 a/b), the PHANToM Premium under its peak rating with
gravity (upright), the Falcon's 3D box map with the plane slider held, and
the Twin-Pantograph's spatial resolution (µm) with its semi-dextrous region.
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
    window.map_view.canvas.repaint()     # paint the newest map now, not at the next idle moment
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
    parser.add_argument("--size", default="1800x1000", help="window size WxH in pixels")
    args = parser.parse_args()
    width, height = (int(v) for v in args.size.lower().split("x"))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    app = QApplication.instance() or QApplication(sys.argv[:1])
    with tempfile.TemporaryDirectory() as tmp:
        window = MainWindow(device="inverse3_prototype", settings_file=Path(tmp) / "settings.ini")
        window.resize(width, height)
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

        window.quantity_box.setCurrentIndex(window.quantity_box.findData("isotropic_force"))
        window.state.set_overlay("force ellipses")
        settle(app, window)
        grab(window, out / "app_fivebar_ellipses.png")
        window.state.set_overlay("bands")
        window.quantity_box.setCurrentIndex(window.quantity_box.findData("condition_number"))
        settle(app, window)
        grab(window, out / "app_fivebar_bands.png")
        window.state.set_overlay("none")

        window.load_device("phantom_premium_15")
        window.loading_controls.rating.setCurrentIndex(window.loading_controls.rating.findData("peak"))
        window.loading_controls.gravity.setCurrentIndex(window.loading_controls.gravity.findData("upright"))
        settle(app, window, seconds=1.0)
        grab(window, out / "app_phantom_peak_gravity.png")
        # The loading stays with the window across devices: back to the defaults for the next scenes.
        window.loading_controls.rating.setCurrentIndex(window.loading_controls.rating.findData("continuous"))
        window.loading_controls.gravity.setCurrentIndex(0)          # "off"

        window.load_device("novint_falcon")
        window.tabs.setCurrentWidget(window.workspace_view)
        settle(app, window, seconds=1.0, timeout=120.0)
        slider = window.map_view.slice_controls.slider
        slider.setSliderDown(True)                  # as while dragging: the plane alone in 3D
        slider.setValue(slider.value() - 3)
        settle(app, window, seconds=0.5)
        grab(window, out / "app_falcon_plane_held.png")
        slider.setSliderDown(False)
        settle(app, window, seconds=1.0)
        grab(window, out / "app_falcon_plane.png")

        window.load_device("twin_pantograph")
        window.quantity_box.setCurrentIndex(window.quantity_box.findData("spatial_resolution"))
        window.tabs.setCurrentWidget(window.workspace_view)
        layer = window.workspace_view.dextrous
        layer.toggle.setChecked(True)
        end = time.monotonic() + 120.0
        while time.monotonic() < end and not (layer.region is not None and layer.region[1].stage == "full"):
            app.processEvents()
            time.sleep(0.01)
        settle(app, window, seconds=1.0)
        grab(window, out / "app_twin_pantograph_dextrous.png")
        window.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
