"""The main window's file and message actions: devices (open, save, reference), exports and error dialogs.

``FileActions`` is a mixin of ``MainWindow`` (``main_window``): its methods use the window's
``state``, ``settings``, ``param_panel``, ``request_map`` and status bar, and the tests and
menus call them on the window. A bad file or a failed export gets one error dialog and changes
nothing (``show_error``).
"""
from __future__ import annotations

import os
from pathlib import Path

from PySide6.QtWidgets import QFileDialog, QInputDialog, QMessageBox

from app.files.export import atomic_write
from app.gui.export_job import exporter_of
from app.render import views as render
from metrics.quantities import QUANTITIES
from resources import PresetError, list_presets, load_preset, preset_to_toml, read_preset_file


class FileActions:
    """Devices, exports and messages of ``MainWindow`` (a mixin: see the module docstring)."""

    def load_device(self, key_or_path: str) -> bool:
        """Load a preset by key or path; a bad file gets an error dialog and changes nothing."""
        try:
            preset = load_preset(key_or_path)
        except PresetError as exc:
            self.show_error(str(exc))
            self.param_panel.show_preset(self.state.preset)
            return False
        self.state.set_preset(preset)
        self.settings.setValue("last_device", key_or_path)
        self.request_map("coarse")
        self.request_map("full")
        return True

    def load_study_design(self, study, design: int) -> None:
        """Put one design of a study into the main view (loading the study's device if needed)."""
        mech = study.design_mechanism(design)
        if type(mech) is not type(self.state.mechanism):
            preset_key = (study.raw.get("mechanism") or {}).get("preset")
            if not preset_key or not self.load_device(preset_key):
                self.show_error(f"study {study.name!r} is for a {study.kind} device; load one first")
                return
        self.state.set_mechanism(mech)
        self.request_map("coarse")
        self.request_map("full")
        shown = ", ".join(f"{k} = {float(v[0]):g}" for k, v in study.design_display([design]).items())
        self.statusBar().showMessage(f"Loaded design {shown} from {study.name}", 8000)

    def set_reference_device(self, key_or_path: str) -> bool:
        """Another device (preset key or TOML path) as the comparison's reference; a bad file gets an error."""
        try:
            preset = load_preset(key_or_path)
        except PresetError as exc:
            self.show_error(str(exc))
            return False
        self.state.set_reference_device(preset)
        self.statusBar().showMessage(f"Reference: {preset.name}; its map computes on its own grid.", 5000)
        return True

    def reference_device_dialog(self) -> None:
        other = "Other TOML file..."
        keys = list_presets()
        key, ok = QInputDialog.getItem(self, "Reference device", "Compare against:", keys + [other], 0, False)
        if not ok:
            return
        if key == other:
            key, _ = QFileDialog.getOpenFileName(self, "Reference device", "", "Device presets (*.toml)")
            if not key:
                return
        self.set_reference_device(key)

    def open_device_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open device", "", "Device presets (*.toml)")
        if path:
            self.load_device(path)

    def save_device(self, path: str | os.PathLike) -> Path:
        preset = self.state.preset.replace(mechanism=self.state.mechanism, pose=self.state.pose)
        return atomic_write(Path(path), lambda tmp: Path(tmp).write_text(preset_to_toml(preset), encoding="utf-8"))

    def save_device_dialog(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Save device", f"{self.state.preset.key}.toml",
                                              "Device presets (*.toml)")
        if path:
            try:
                self.save_device(path)
                read_preset_file(path)
            except (OSError, ValueError) as exc:
                self.show_error(f"Could not save the device: {exc}")

    # -- export ----------------------------------------------------------------------------
    def export_dialog(self, what: str) -> None:
        filters = {"map": "PNG (*.png);;SVG (*.svg);;PDF (*.pdf)", "pose": "PNG (*.png);;SVG (*.svg);;PDF (*.pdf)",
                   "workspace": "PNG (*.png);;SVG (*.svg);;PDF (*.pdf)", "data": "CSV (*.csv);;NumPy (*.npz)",
                   "stats": "CSV (*.csv);;JSON (*.json)"}[what]
        path, _ = QFileDialog.getSaveFileName(self, f"Export {what}", "", filters)
        if not path:
            return
        size = None
        if path.lower().endswith(".png") and what in ("map", "pose", "workspace"):
            text, ok = QInputDialog.getText(self, "Image size", "Width x height in pixels:", text="1600x1200")
            if not ok:
                return
            size = render.parse_size(text)
        try:
            self.export(what, path, size=size)
            self.statusBar().showMessage(f"Wrote {path}", 5000)
        except (OSError, ValueError) as exc:
            self.show_error(f"Export failed, nothing was written: {exc}")

    def _export_inputs(self) -> dict:
        """What every export writes: the full map of the design on screen, or a clear refusal."""
        st = self.state
        current = st.current
        if current is None or current.stage != "full" or current.mechanism != st.mechanism:
            raise ValueError("the full-resolution map of this design is still being computed; "
                             "export again when the progress bar is full")
        return dict(preset=st.preset, mechanism=st.mechanism, workspace_map=current.map, quantity=st.quantity,
                    pose=st.pose, glyphs=st.glyphs, desired_force=st.desired_force,
                    reference_map=st.reference.map if st.reference is not None else None, overlay=st.overlay,
                    reference_mechanism=st.reference_mechanism if st.reference is not None else None,
                    loading=st.loading,
                    # A 3D box map's figures: the plane on screen, in the colour range on screen.
                    plane=(st.slice_axis, st.slice_value) if st.slice_axis is not None else None,
                    colour_range=getattr(self.map_view, "colour_range", "plane"))

    def export(self, what: str, path, *, size=None) -> Path:
        """Write one export (the dialogs call this; so do tests)."""
        return render.export_view(what, path, size=size, compare_mode=self.state.compare_mode,
                                  **self._export_inputs())

    def export_report(self, folder) -> list[Path]:
        return render.export_report(folder, **self._export_inputs())

    def export_report_dialog(self) -> None:
        folder = QFileDialog.getExistingDirectory(self, "Export report into folder")
        if folder:
            try:
                exporter_of(self).start(folder, self._export_inputs())   # in the background (export_job)
            except (OSError, ValueError) as exc:
                self.show_error(f"Report export failed: {exc}")

    # -- messages --------------------------------------------------------------------------
    def show_error(self, message: str) -> None:
        """A non-blocking error dialog; the app keeps working behind it.

        One dialog at a time: while one is open a new message replaces its text (the same
        message again only raises it), so repeated failures do not stack identical boxes.
        """
        self.last_error = message
        box = self.error_box
        if box is not None and box.isVisible():
            if box.text() != message:
                box.setText(message)
            box.raise_()
            return
        if box is not None:
            box.deleteLater()       # the last one, closed: hidden boxes must not pile up in a long session
        box = QMessageBox(QMessageBox.Icon.Critical, "isoforce", message, QMessageBox.StandardButton.Ok, self)
        box.setModal(False)
        box.show()
        self.error_box = box

    def show_quantity_help(self) -> None:
        lines = [f"<b>{q.label}</b> ({q.unit or 'no unit'}): {q.description}"
                 for name, q in QUANTITIES.items() if q.scalar]
        box = QMessageBox(QMessageBox.Icon.Information, "Quantities", "<br>".join(lines),
                          QMessageBox.StandardButton.Ok, self)
        box.setModal(False)
        box.show()

