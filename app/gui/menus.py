"""The window's menu bar: File (devices, sessions, export), Edit (undo, redo), View (glyphs, overlay),
Compare, Help.

``build_menus`` adds the menus to a ``MainWindow`` and connects them to its slots; it returns
the actions the window keeps in step with its state (``MenuActions``).
"""
from __future__ import annotations

from dataclasses import dataclass

from PySide6.QtGui import QAction, QActionGroup, QKeySequence

from app.gui.export_job import application_shortcut
from app.gui.map_fit import MapFitter
from app.gui.model import GLYPHS
from app.gui.views.map_view import difference_problem
from app.plots.overlays import OVERLAYS
from metrics.quantities import QUANTITIES


@dataclass(frozen=True)
class MenuActions:
    """The actions whose state follows the app's: checked glyphs and overlay, the report shortcut."""

    report: QAction
    glyphs: dict[str, QAction]
    overlays: dict[str, QAction]
    undo: QAction
    redo: QAction


def _action(window, menu, text: str, slot, shortcut=None, tip: str = "") -> QAction:
    action = QAction(text, window)
    if shortcut:
        action.setShortcut(QKeySequence(shortcut))
    if tip:
        action.setToolTip(tip)
        action.setStatusTip(tip)
    action.triggered.connect(slot)
    menu.addAction(action)
    return action


def _checkable(window, text: str, checked: bool, shortcut: str, tip: str = "") -> QAction:
    action = QAction(text, window, checkable=True)
    action.setChecked(checked)
    action.setShortcut(QKeySequence(shortcut))
    if tip:
        action.setToolTip(tip)
        action.setStatusTip(tip)
    return action


#: The difference item's tooltip when it can be drawn.
DIFFERENCE_TIP = "The current map minus the reference's, point by point, on a diverging colour scale."


def _follow_difference(st, modes: dict[str, QAction]) -> None:
    """Compare > Difference enabled only when the comparison can be one (``map_view.difference_problem``),
    its tooltip the reason when not; a difference already chosen then goes back to side by side."""
    action = modes["difference"]

    def update() -> None:
        problem = difference_problem(st) if st.reference is not None else None
        action.setEnabled(problem is None)
        tip = DIFFERENCE_TIP if problem is None else f"Unavailable: {problem}."
        action.setToolTip(tip)
        action.setStatusTip(tip)
        if problem is not None and st.reference is not None and st.compare_mode == "difference" \
                and not QUANTITIES[st.quantity].categorical:
            st.set_compare_mode("side")
        modes["side"].setChecked(st.compare_mode == "side")
        action.setChecked(st.compare_mode == "difference")

    for signal in (st.referenceChanged, st.presetChanged, st.quantityChanged, st.compareModeChanged):
        signal.connect(update)
    update()


#: The longest edit an Undo or Redo item names before it is cut short with "...".
EDIT_TEXT_CHARS = 60


def _edit_text(verb: str, label: str | None) -> str:
    """``"&Undo gear_ratios 6.875 -> 13.75"``; ``"&Undo"`` when there is nothing to undo."""
    if label is None:
        return verb
    if len(label) > EDIT_TEXT_CHARS:
        label = label[:EDIT_TEXT_CHARS - 3].rstrip() + "..."
    return f"{verb} {label}"


def _follow_history(st, undo: QAction, redo: QAction) -> None:
    """Undo and Redo name the step they take and are enabled only when there is one.

    While a design slider is held (``st.interaction == "design"``) only their enabled states
    follow each step: the menu cannot be opened with the mouse on the slider, and naming the
    step (``History.undo_text``: both designs' parameter tables, in display units) took ~1 ms of
    the GUI thread a step. The release names it (``interactionChanged``)."""
    held = [False]                  # a step went by unnamed while the slider was held

    def update() -> None:
        history = st.history
        if st.interaction == "design":
            undo.setEnabled(history.can_undo())
            redo.setEnabled(history.can_redo())
            held[0] = True
            return
        held[0] = False
        for action, verb, label, can in ((undo, "&Undo", history.undo_text(), history.can_undo()),
                                         (redo, "&Redo", history.redo_text(), history.can_redo())):
            action.setText(_edit_text(verb, label))
            action.setEnabled(can)
            word = verb.replace("&", "")
            tip = f"{word} {label}" if label else f"Nothing to {word.lower()}"
            action.setToolTip(tip)
            action.setStatusTip(tip)

    def released() -> None:
        if held[0] and st.interaction != "design":
            update()

    st.historyChanged.connect(update)
    st.interactionChanged.connect(released)
    update()


def build_menus(window) -> MenuActions:
    """Add the menus to ``window`` (a ``MainWindow``), connected to its slots and state."""
    st = window.state
    bar = window.menuBar()
    file = bar.addMenu("&File")
    _action(window, file, "&Open device...", window.open_device_dialog, QKeySequence.StandardKey.Open,
            "Load a device preset from a TOML file.")
    _action(window, file, "&Save device as...", window.save_device_dialog, QKeySequence.StandardKey.SaveAs,
            "Save the current design as a TOML preset.")
    file.addSeparator()
    _action(window, file, "Open sess&ion...", window.open_session_dialog, "Ctrl+Alt+O",
            "Show a saved session: the design, the comparison, the map's settings and the 3D views' cameras.")
    _action(window, file, "Save sessio&n...", window.save_session_dialog, "Ctrl+Alt+S",
            "Save the design, the comparison, the map's settings and the 3D views' cameras in a TOML file "
            "(isoforce figure --session FILE draws it).")
    file.addSeparator()
    export = file.addMenu("&Export")
    _action(window, export, "Map image (PNG/SVG/PDF)...", lambda: window.export_dialog("map"), "Ctrl+Shift+M")
    _action(window, export, "Pose view image (PNG/SVG/PDF)...", lambda: window.export_dialog("pose"))
    _action(window, export, "Workspace view image (PNG/SVG/PDF)...", lambda: window.export_dialog("workspace"))
    _action(window, export, "Map data (CSV/NPZ)...", lambda: window.export_dialog("data"))
    _action(window, export, "Statistics (CSV/JSON)...", lambda: window.export_dialog("stats"))
    report = _action(window, file, "Export &report...", window.export_report_dialog, "Ctrl+E",
                     "Write every figure, the map data and the statistics into a folder.")
    application_shortcut(report)     # also while a spin box has focus (export_job)
    file.addSeparator()
    _action(window, file, "&Quit", window.close, QKeySequence.StandardKey.Quit)

    edit = bar.addMenu("&Edit")
    undo = _action(window, edit, "&Undo", window.undo, QKeySequence.StandardKey.Undo)
    redo = _action(window, edit, "&Redo", window.redo, "Ctrl+Shift+Z")
    for action in (undo, redo):
        application_shortcut(action)     # also while a spin box has focus: the app's undo, not its text's
    _follow_history(st, undo, redo)

    view = bar.addMenu("&View")
    glyphs: dict[str, QAction] = {}
    for i, (name, tip) in enumerate(GLYPHS.items()):
        action = _checkable(window, name.replace("_", " ").capitalize(), name in st.glyphs, f"Alt+{i + 1}", tip)
        action.toggled.connect(lambda on, n=name: st.set_glyph(n, on))
        view.addAction(action)
        glyphs[name] = action
    view.addSeparator()
    overlay_menu = view.addMenu("Map &overlay")
    overlay_menu.setToolTipsVisible(True)
    group = QActionGroup(window)
    overlays: dict[str, QAction] = {}
    for i, (name, text) in enumerate(OVERLAYS.items()):
        action = _checkable(window, text[0].upper() + text[1:], name == st.overlay, f"Ctrl+Alt+{i}")
        action.triggered.connect(lambda _=False, n=name: st.set_overlay(n))
        group.addAction(action)
        overlay_menu.addAction(action)
        overlays[name] = action
    view.addSeparator()
    # The handler of View > Fit map to workspace, owned by the window (a thread's result comes back to it).
    window.map_fitter = MapFitter(window)
    _action(window, view, "&Fit map to workspace", window.map_fitter.start, "Ctrl+Shift+F",
            "Set the map's range to this design's workspace (the preset's range is drawn around its own "
            "link lengths).")
    _action(window, view, "Recompute map", lambda: window.request_map("full"), "F5")

    compare = bar.addMenu("&Compare")
    _action(window, compare, "&Pin current design as reference", window.pin_reference, "Ctrl+P",
            "Keep this design's map to compare later designs against.")
    _action(window, compare, "Reference &device...", window.reference_device_dialog, "Ctrl+Alt+P",
            "Compare against another device (a preset or a TOML file) as the reference.")
    _action(window, compare, "&Clear reference", st.clear_reference, "Ctrl+Shift+P")
    group = QActionGroup(window)
    modes = {}
    for mode, key in (("side", "Ctrl+["), ("difference", "Ctrl+]")):
        action = _checkable(window, "Side by side" if mode == "side" else "Difference (current - reference)",
                            st.compare_mode == mode, key)
        action.triggered.connect(lambda _=False, m=mode: st.set_compare_mode(m))
        group.addAction(action)
        compare.addAction(action)
        modes[mode] = action
    _follow_difference(st, modes)

    helpm = bar.addMenu("&Help")
    _action(window, helpm, "&Quantities", window.show_quantity_help, "F1")
    return MenuActions(report=report, glyphs=glyphs, overlays=overlays, undo=undo, redo=redo)
