"""The main window's file and message actions: devices (open, save, reference), sessions, exports and error dialogs.

``FileActions`` is a mixin of ``MainWindow`` (``main_window``): its methods use the window's
``state``, ``settings``, ``param_panel``, ``request_map`` and status bar, and the tests and
menus call them on the window. A bad file or a failed export gets one error dialog and changes
nothing (``show_error``). A session (``app.files.session``) is the design, its comparison and
the views' settings and cameras: ``save_session`` and ``open_session``.

A modified design is autosaved as a session beside the settings file (``autosave_path``) a
moment after each edit, and the file is removed once the design is saved, undone back to the
one loaded, or discarded at the close prompt. Whatever else ends the app with a modified design
(a crash, a killed process, a window closed without the prompt) leaves it there, and the next
start restores it (``restore_autosave``): the design as an undoable edit of its preset, marked
unsaved, the views as they were, and a status-bar note saying from when.
"""
from __future__ import annotations

import os
import time
from pathlib import Path

from PySide6.QtWidgets import QFileDialog, QInputDialog, QMessageBox

from app.files.export import atomic_write
from app.files.session import Session, SessionError, read_session, write_session
from app.gui.export_job import exporter_of
from app.gui.export_size import ask_column
from app.gui.history import preset_label
from app.gui.views.camera import CameraState
from app.logic.display_units import display_unit
from app.render import views as render
from metrics.quantities import QUANTITIES
from resources import PresetError, list_presets, load_preset, preset_to_toml, read_preset_file
from resources.schema import with_changes

#: The autosaved session's name: the settings file's stem with this (``FileActions.autosave_path``).
AUTOSAVE_SUFFIX = ".autosave.toml"


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

    def choose_device(self, key_or_path: str) -> bool:
        """The device list's choice: asks first about a modified design (``may_drop_design``)."""
        if not self.may_drop_design(f"switching to {key_or_path}"):
            self.param_panel.show_preset(self.state.preset)     # the list shows the device kept
            return False
        return self.load_device(key_or_path)

    def open_device_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open device", "", "Device presets (*.toml)")
        if path and self.may_drop_design("opening another device"):
            self.load_device(path)

    def save_device(self, path: str | os.PathLike) -> Path:
        # The saved [source] says which values differ from the ones its sources describe.
        preset = with_changes(self.state.preset, self.state.mechanism).replace(pose=self.state.pose)
        return atomic_write(Path(path), lambda tmp: Path(tmp).write_text(preset_to_toml(preset), encoding="utf-8"))

    def save_device_dialog(self) -> bool:
        """File > Save device as...; True once the design is written (no longer modified)."""
        path, _ = QFileDialog.getSaveFileName(self, "Save device", f"{self.state.preset.key}.toml",
                                              "Device presets (*.toml)")
        if not path:
            return False
        try:
            self.save_device(path)
            read_preset_file(path)
        except (OSError, ValueError) as exc:
            self.show_error(f"Could not save the device: {exc}")
            return False
        self.state.mark_saved()
        self.statusBar().showMessage(f"Saved {path}", 5000)
        return True

    def may_drop_design(self, doing: str) -> bool:
        """Whether the design on screen may go: True when it is unmodified, when the window does
        not ask (``ask_to_save`` off: scripts, tests), or when the user saves it or discards it;
        False when the user cancels (or the save fails or is cancelled)."""
        st = self.state
        if not self.ask_to_save or not st.modified:
            return True
        answer = QMessageBox.question(
            self, "isoforce", f"The design of {preset_label(st.preset)} has changed. Save it before {doing}?",
            QMessageBox.StandardButton.Save | QMessageBox.StandardButton.Discard | QMessageBox.StandardButton.Cancel,
            QMessageBox.StandardButton.Save)
        if answer == QMessageBox.StandardButton.Discard:
            return True
        if answer == QMessageBox.StandardButton.Save:
            return self.save_device_dialog()
        return False

    # -- sessions --------------------------------------------------------------------------
    def _cameras(self) -> dict[str, dict]:
        """The 3D views' cameras, by ``app.files.session.CAMERA_VIEWS`` name (a view never drawn: none)."""
        out = {}
        for name, view in (("pose", self.pose_view), ("workspace", self.workspace_view)):
            if view._camera_for is not None and not getattr(view.plotter, "_closed", False):
                out[name] = vars(CameraState.of(view.plotter.renderer))
        return out

    def session(self) -> Session:
        """What the window shows, as a session (``app.files.session``)."""
        st = self.state
        return Session(preset=st.preset, mechanism=st.mechanism, quantity=st.quantity, overlay=st.overlay,
                       compare_mode=st.compare_mode, glyphs=st.glyphs, pose=st.pose,
                       desired_force=st.desired_force, loading=st.loading,
                       plane=(st.slice_axis, st.slice_value) if st.slice_axis is not None else None,
                       colour_range=self.map_view.colour_range,
                       reference_preset=st.reference_preset, reference_mechanism=st.reference_mechanism,
                       cameras=self._cameras())

    def save_session(self, path: str | os.PathLike) -> Path:
        """Write the session to ``path`` (atomically); the design is then saved (not modified)."""
        written = write_session(path, self.session(), load=load_preset)
        self.state.mark_saved()
        return written

    def open_session(self, path: str | os.PathLike) -> bool:
        """Show a session file: its design (one undoable step), comparison, view settings and cameras.
        A bad file gets one error dialog naming the file and key, and changes nothing."""
        try:
            session = read_session(path, load=load_preset)
        except SessionError as exc:
            self.show_error(str(exc))
            return False
        st = self.state
        self.scheduler.cancel("current")
        st.set_interaction(None)
        st.set_design(session.preset, session.mechanism)
        self._apply_views(session)
        self.request_map("coarse")
        self.request_map("full")
        self.statusBar().showMessage(f"Opened session {path}", 5000)
        return True

    def _apply_views(self, session: Session) -> None:
        """A session's loading, map and pose settings, glyphs, comparison and cameras (its design is set)."""
        st = self.state
        st.set_loading(session.loading)            # (read_session checked the device takes it)
        st.set_quantity(session.quantity)
        if session.pose is not None:
            st.set_pose(session.pose)
        if session.desired_force is not None:
            st.set_desired_force(session.desired_force)
        for glyph in sorted(set(st.glyphs) | set(session.glyphs)):
            st.set_glyph(glyph, glyph in session.glyphs)
        st.set_overlay(session.overlay)
        st.set_compare_mode(session.compare_mode)
        if session.plane is not None:
            st.set_slice(*session.plane)
        self.map_view.set_colour_range(session.colour_range)
        if session.reference_mechanism is None:
            st.clear_reference()
        elif session.reference_preset is not None:
            st.set_reference_device(session.reference_preset.replace(mechanism=session.reference_mechanism))
        else:
            st.pin_reference(session.reference_mechanism)
        for name, numbers in session.cameras.items():
            self._set_camera(name, CameraState(**{"view_angle": 30.0, "parallel_scale": 1.0, "parallel": False,
                                                  **numbers}))

    # -- autosave --------------------------------------------------------------------------
    def autosave_path(self) -> Path:
        """The autosaved session of a modified design: ``<settings>.autosave.toml`` beside the
        settings file (``~/.config/isoforce/settings.autosave.toml``; ``ISOFORCE_SETTINGS`` or
        ``XDG_CONFIG_HOME`` move both)."""
        settings = Path(self.settings.fileName())
        return settings.with_name(f"{settings.stem}{AUTOSAVE_SUFFIX}")

    def autosave(self) -> Path | None:
        """Write the session of a modified design to ``autosave_path``, or remove that file when
        the design is unmodified; the file written, or None. A failed write is said once in the
        status bar (the design on screen is untouched)."""
        path = self.autosave_path()
        if not self.state.modified:
            path.unlink(missing_ok=True)
            return None
        try:
            return write_session(path, self.session(), load=load_preset)
        except (OSError, ValueError) as exc:
            self.statusBar().showMessage(f"Could not autosave the design to {path}: {exc}", 8000)
            return None

    def autosaved_session(self) -> Session | None:
        """The session ``autosave_path`` holds, if any; an unreadable one is moved aside (renamed
        ``*.unreadable.toml``) and said in ``autosave_problem``, so it is not tried again."""
        path = self.autosave_path()
        self.autosave_problem = None
        if not path.exists():
            return None
        try:
            session = read_session(path, load=load_preset)
        except SessionError as exc:
            aside = path.with_name(f"{path.stem}.unreadable{path.suffix}")
            try:
                path.replace(aside)
            except OSError:
                aside = path
            self.autosave_problem = f"The unsaved design autosaved in {aside} could not be restored: {exc}"
            return None
        self.autosaved_at = time.localtime(path.stat().st_mtime)
        return session

    def restore_autosave(self, session: Session) -> None:
        """Show the autosaved ``session`` (the window was built on its preset): the design as an
        undoable edit of the preset (modified: the title's "*", the close prompt), the views as
        ``open_session`` sets them, and a status-bar note with the time it was autosaved."""
        st = self.state
        st.set_mechanism(session.mechanism)          # one step: Edit > Undo goes back to the preset
        self._apply_views(session)
        when = time.strftime("%Y-%m-%d %H:%M", self.autosaved_at)
        step = st.history.undo_text()
        self.show_notice(f"Restored the unsaved design of {preset_label(st.preset)} from {when}"
                         + (f" ({step})" if step else "") + ": Edit > Undo goes back to the preset, "
                         "File > Save device keeps it")

    def _set_camera(self, name: str, camera: CameraState) -> None:
        """A 3D view's camera: applied now if the view shows this device, else kept for when it
        draws it (each view keeps one camera per device)."""
        st = self.state
        view = self.pose_view if name == "pose" else self.workspace_view
        key = (st.preset.key, st.mechanism.task_dim) if name == "pose" else st.preset.key
        if view._camera_for == key:
            camera.apply(view.plotter.renderer)
            view.view.fitted = False
            view.view.request_render()
        else:
            view._cameras[key] = camera

    def save_session_dialog(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Save session", f"{self.state.preset.key}_session.toml",
                                              "Sessions (*.toml)")
        if path:
            try:
                self.save_session(path)
                self.statusBar().showMessage(f"Saved session {path}", 5000)
            except (OSError, ValueError) as exc:
                self.show_error(f"Could not save the session, nothing was written: {exc}")

    def open_session_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open session", "", "Sessions (*.toml)")
        if path and self.may_drop_design("opening a session"):
            self.open_session(path)

    # -- export ----------------------------------------------------------------------------
    def export_dialog(self, what: str) -> None:
        filters = {"map": "PNG (*.png);;SVG (*.svg);;PDF (*.pdf)", "pose": "PNG (*.png);;SVG (*.svg);;PDF (*.pdf)",
                   "workspace": "PNG (*.png);;SVG (*.svg);;PDF (*.pdf)", "data": "CSV (*.csv);;NumPy (*.npz)",
                   "stats": "CSV (*.csv);;JSON (*.json)"}[what]
        path, _ = QFileDialog.getSaveFileName(self, f"Export {what}", "", filters)
        if not path:
            return
        size = column = None
        if path.lower().endswith(".png") and what in ("map", "pose", "workspace"):
            text, ok = QInputDialog.getText(self, "Image size", "Width x height in pixels:", text="1600x1200")
            if not ok:
                return
            size = render.parse_size(text)
        elif path.lower().endswith((".pdf", ".svg")) and what in ("map", "pose", "workspace"):
            # A page for print: a column's width and font, as `isoforce figure --width-in --font-pt`.
            ok, column = ask_column(self, self.settings, what)
            if not ok:
                return
        try:
            self.export(what, path, size=size, column=column)
            self.statusBar().showMessage(f"Wrote {path}", 5000)
        except (OSError, ValueError) as exc:
            self.show_error(f"Export failed, nothing was written: {exc}")

    def _export_inputs(self) -> dict:
        """What every export writes: the full map of the design on screen, or a clear refusal."""
        st = self.state
        current = st.current
        # (A dragged slider's map holds its legend's figures alone, ``figures="extremes"``: the map at
        # rest, with every statistic, follows it.)
        if current is None or current.stage != "full" or current.mechanism != st.mechanism \
                or current.map.figures != "all":
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

    def export(self, what: str, path, *, size=None, column: tuple[float, float] | None = None) -> Path:
        """Write one export (the dialogs call this; so do tests): ``size`` (w, h) in pixels for a
        PNG, ``column`` (width in, font pt) for a PDF or SVG laid out for a journal column."""
        return render.export_view(what, path, size=size, column=column, compare_mode=self.state.compare_mode,
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
        # In the units the map, the statistics and ``isoforce spec`` show (um, deg), not SI.
        lines = [f"<b>{q.label}</b> ({display_unit(name)[0] or 'no unit'}): {q.description}"
                 for name, q in QUANTITIES.items() if q.scalar]
        box = QMessageBox(QMessageBox.Icon.Information, "Quantities", "<br>".join(lines),
                          QMessageBox.StandardButton.Ok, self)
        box.setModal(False)
        box.show()

