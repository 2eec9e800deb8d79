"""Every parameter of the device as a labelled slider with a spin box and its unit.

The panel only reports edits (``edited(name, value)`` in display units, a tuple for vector
parameters); the main window turns them into a new mechanism. ``dragging`` tells whether a
slider is still held, so the map can follow coarsely and refine on release.
"""
from __future__ import annotations

import math
import time

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtWidgets import (
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QSlider,
    QVBoxLayout,
    QWidget,
)

#: Parameter groups, top to bottom.
GROUPS = ("Links", "Actuators", "Limits and offsets")
#: How long a new family's panel is built in one turn of the event loop before the rest waits
#: for the next, ms (a row takes 1-4 ms: the GUI thread is never held much beyond this).
BUILD_SLICE_MS = 15.0


#: Parameters in deg that are a step size, not an angle: their slider scales the value (an
#: angle's slider adds +-180 deg, which would cross zero).
STEP_PARAMETERS = ("joint_resolution",)


#: Half the slider's span for a parameter at zero (an offset), by unit: no ratio of zero spans anything.
ZERO_SPANS = {"mm": 100.0, "N m": 1.0}
#: Half the slider's span as a share of the value it starts from (a length, torque, ratio or
#: step size): a fine edit. A 76 px drag took the Inverse3's 140 mm proximal link to 317 mm
#: when the slider spanned value / 4 to value * 2.5; the spin box takes any value beyond.
FINE_SPAN = 0.5
#: Half the slider's span for an angle, deg (it spanned +-180 deg, 2.7 deg a pixel).
ANGLE_SPAN = 45.0
#: About this many slider steps either side of the value: each a round 1, 2 or 5 x 10^k of the
#: unit (``slider_step``), so a drag reads 141, 142 mm rather than 140.14, 140.49 mm.
STEPS_EACH_SIDE = 50


def half_span(value: float, unit: str, name: str = "") -> float:
    """Half the slider's span around ``value`` (display units): ``FINE_SPAN`` of it, ``ANGLE_SPAN``
    for an angle, ``ZERO_SPANS`` at zero.

    >>> half_span(140.0, "mm"), half_span(30.0, "deg", "upper_limits"), half_span(0.0, "N m")
    (70.0, 45.0, 1.0)
    """
    if unit == "deg" and name not in STEP_PARAMETERS:
        return ANGLE_SPAN
    if value == 0.0:
        return ZERO_SPANS.get(unit, 1.0)
    return FINE_SPAN * abs(value)


def slider_step(half: float) -> float:
    """The round step (1, 2 or 5 x 10^k) that gives at least ``STEPS_EACH_SIDE`` steps in ``half``.

    >>> slider_step(70.0), slider_step(45.0), slider_step(3.4375), slider_step(0.0128)
    (1.0, 0.5, 0.05, 0.0002)
    """
    raw = half / STEPS_EACH_SIDE
    k = math.floor(math.log10(raw))
    for m in (5.0, 2.0, 1.0):
        if m * 10.0 ** k <= raw * (1 + 1e-12):
            return float(f"{m * 10.0 ** k:.12g}")
    return float(f"{10.0 ** k:.12g}")


def slider_range(value: float, unit: str, name: str = "") -> tuple[float, float]:
    """The slider's span around ``value``, display units: a whole number of ``slider_step`` either
    side of it, so the value itself and round steps from it are positions of the slider.

    >>> slider_range(140.0, "mm"), slider_range(45.0, "deg", "upper_limits")
    ((70.0, 210.0), (0.0, 90.0))
    """
    half = half_span(value, unit, name)
    step = slider_step(half)
    n = math.ceil(half / step - 1e-9)
    return value - n * step, value + n * step


def spin_decimals(value: float, unit: str) -> int:
    """Decimals that show at least 3 significant digits of ``value`` (0.0256 deg must not read 0.03)."""
    base = 4 if unit in ("N m", "") else 2
    if value == 0 or not math.isfinite(value):
        return base
    return int(min(8, max(base, 2 - math.floor(math.log10(abs(value))))))


def group_of(info) -> str:
    """Links (lengths and geometry), Actuators (torques, ratios, modes), or Limits and offsets."""
    limit_words = ("limit", "offset", "body", "spread", "min_", "max_", "height")
    if info.name in ("motor_torques", "motor_forces", "peak_motor_torques", "gear_ratios", "working_mode",
                     "assembly_mode", "redundant_waist", "roll_actuator", "peak_rating", "joint_resolution",
                     "joint_sensors"):
        return "Actuators"
    if any(word in info.name for word in limit_words) or info.choices:
        return "Limits and offsets"
    return "Links"


class ParameterRow(QWidget):
    """Slider + spin box for one number, kept in step with each other."""

    changed = Signal(float, bool)     # value, slider still held

    def __init__(self, value: float, unit: str, tooltip: str, parent=None, name: str = "") -> None:
        super().__init__(parent)
        self.unit, self.name = unit, name
        self.slider = QSlider(Qt.Orientation.Horizontal)
        self.spin = QDoubleSpinBox()
        self._centre(value)
        self._spin_format(value)
        self.spin.setSuffix(f" {unit}" if unit else "")
        self.spin.setKeyboardTracking(False)
        self.spin.setMinimumWidth(110)
        for w in (self.slider, self.spin):
            w.setToolTip(tooltip)
        layout = QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.slider, 1)
        layout.addWidget(self.spin)
        self.set_value(value)
        self.slider.valueChanged.connect(self._from_slider)
        self.slider.sliderReleased.connect(lambda: self.changed.emit(self.spin.value(), False))
        self.spin.valueChanged.connect(self._from_spin)

    def value(self) -> float:
        return self.spin.value()

    def reset(self, value: float) -> None:
        """Show another device's ``value`` (a panel reused for a device of the same family): the
        slider's span, the spin box's decimals and sign as a row built for it, no signal sent."""
        self._centre(value)
        self._spin_format(value)
        self.set_value(value)

    def _spin_format(self, value: float) -> None:
        decimals = spin_decimals(value, self.unit)
        self.spin.blockSignals(True)
        self.spin.setDecimals(decimals)
        # Angles and offsets at zero may go negative; other values stay positive.
        signed = self.unit == "deg" and self.name not in STEP_PARAMETERS or value == 0.0
        self.spin.setRange(-1e6 if signed else 10.0 ** -decimals, 1e6)
        self.spin.blockSignals(False)

    def _centre(self, value: float) -> None:
        """The slider's span around ``value`` (``slider_range``), one slider step per ``slider_step``."""
        self.lo, self.hi = slider_range(value, self.unit, self.name)
        self.step = slider_step(half_span(value, self.unit, self.name))
        self.slider.blockSignals(True)
        self.slider.setRange(0, round((self.hi - self.lo) / self.step))
        self.slider.setSingleStep(1)
        self.slider.setPageStep(10)
        self.slider.blockSignals(False)
        self.spin.setSingleStep(self.step)

    def _follow(self, value: float) -> None:
        """A value typed or set beyond the slider's span (spin box, undo, a loaded design): the
        span moves to be around it, so the slider edits it finely from there."""
        if not self.lo - 1e-9 * abs(self.hi - self.lo) <= value <= self.hi + 1e-9 * abs(self.hi - self.lo):
            self._centre(value)

    def set_value(self, value: float) -> None:
        for w in (self.slider, self.spin):
            w.blockSignals(True)
        self.spin.setValue(value)
        self._follow(self.spin.value())
        self.slider.setValue(self._to_steps(value))
        for w in (self.slider, self.spin):
            w.blockSignals(False)

    def _to_steps(self, value: float) -> int:
        frac = (value - self.lo) / (self.hi - self.lo)
        return int(round(min(max(frac, 0.0), 1.0) * self.slider.maximum()))

    def _from_slider(self, steps: int) -> None:
        value = self.lo + self.step * steps
        self.spin.blockSignals(True)
        self.spin.setValue(value)
        self.spin.blockSignals(False)
        self.changed.emit(self.spin.value(), self.slider.isSliderDown())

    def _from_spin(self, value: float) -> None:
        self._follow(value)
        self.slider.blockSignals(True)
        self.slider.setValue(self._to_steps(value))
        self.slider.blockSignals(False)
        self.changed.emit(value, False)


def layout_key(table) -> tuple:
    """What a panel's widgets depend on besides the values, from ``Mechanism.parameter_table()``:
    each parameter's ``ParamInfo`` (name, unit, description, labels, choices) and a vector's
    length. Devices of one family share it."""
    return tuple((info, len(value) if info.is_vector else None) for info, value in table)


class _Body:
    """The rows of one family's parameters (``layout_key``) in their group boxes: built once, over
    several turns of the event loop (``pending``), and shown again for each device of the family."""

    def __init__(self, table, parent: QWidget) -> None:
        # A child of the panel out of its layout, hidden while its rows are built: rows added to
        # a widget on screen had the window lay itself out and paint again in every turn.
        self.widget = QWidget(parent)
        self.widget.hide()
        outer = QVBoxLayout(self.widget)
        outer.setContentsMargins(0, 0, 0, 0)
        self.forms: dict[str, QFormLayout] = {}
        used = {group_of(info) for info, _ in table}
        for name in GROUPS:
            box = QGroupBox(name)
            self.forms[name] = QFormLayout(box)
            outer.addWidget(box)
            box.setVisible(name in used)        # a model with nothing in a group shows no empty box
        self.rows: dict[tuple[str, int], ParameterRow] = {}
        self.choices: dict[str, QComboBox] = {}
        # (ParamInfo, the preset's value) not built yet, in the panel's order.
        self.pending: list[tuple[object, object]] = list(table)


class ParameterPanel(QWidget):
    """Preset chooser and one row per parameter of the current mechanism.

    A device switch shows the rows of its family (``layout_key``): built the first time, out of
    sight over turns of the event loop of at most about ``BUILD_SLICE_MS`` each (69 rows of the
    Inoue platform took 130-280 ms of the GUI thread in one piece), the last device's rows greyed
    out meanwhile; only given the new device's values when the family was shown before. ``rows``,
    ``choices`` and ``body`` finish a build under way first, so a caller sees every row.
    """

    edited = Signal(str, object, bool)     # name, value (display units), dragging
    presetChosen = Signal(str)

    def __init__(self, state, presets: list[str], parent=None, names: dict[str, str] | None = None) -> None:
        super().__init__(parent)
        self.state = state
        self.preset_box = QComboBox()
        # The list shows the devices' names; each item's data is its key (what ``presetChosen`` sends).
        names = names or {}
        for key in presets:
            self.preset_box.addItem(names.get(key, key), key)
        self.preset_box.setToolTip("Device preset (File > Open device... loads your own TOML).")
        self.preset_box.activated.connect(lambda i: self.presetChosen.emit(self.preset_box.itemData(i)))
        self._placeholder = QWidget()
        layout = QVBoxLayout(self)
        head = QFormLayout()
        head.addRow("Device", self.preset_box)
        layout.addLayout(head)
        layout.addWidget(self._placeholder)
        layout.addStretch(1)
        self._bodies: dict[tuple, _Body] = {}
        # The next part of a build. A timer object, not ``QTimer.singleShot(0, ...)``: Qt 6 posts
        # that as an event, and events posted while posted events are sent are sent in the same
        # pass, so every part ran in one block; a zero timer fires once per pass of the loop.
        self._next_part = QTimer(self, singleShot=True, interval=0)
        self._next_part.timeout.connect(self._build_some)
        self._body: _Body | None = None         # the family of the state's design (``rows``)
        self._shown: _Body | None = None        # the one in the layout: ``_body`` once it is built
        self._built_for = None
        state.presetChanged.connect(self.rebuild)
        state.mechanismChanged.connect(self.sync)
        self.rebuild()
        # The first device's rows all at once: the window is laid out (the dock's width taken from
        # them) before it is shown, not around an empty panel.
        self._finish()

    # -- the rows shown ----------------------------------------------------------------------
    @property
    def rows(self) -> dict[tuple[str, int], ParameterRow]:
        """``(name, entry)`` -> row (entry -1 for a scalar), every row of the device shown."""
        self._finish()
        return self._body.rows

    @property
    def choices(self) -> dict[str, QComboBox]:
        """name -> the combo box of a parameter with choices."""
        self._finish()
        return self._body.choices

    @property
    def body(self) -> QWidget:
        """The widget holding the shown device's group boxes and rows."""
        self._finish()
        return self._body.widget

    def rebuild(self) -> None:
        """Show the rows of the preset's family with its values (built if the family is new)."""
        st = self.state
        self.show_preset(st.preset)
        table = st.mechanism.parameter_table()
        key = layout_key(table)
        body = self._bodies.get(key)
        if body is None:
            body = self._bodies[key] = _Body(table, self)
        else:
            self._reset(body, table)
        self._body = body
        self._built_for = key
        if body.pending and self._shown is not None and self._shown is not body:
            # The last device's rows stay on screen, greyed out, until the new ones are built: no
            # edit of them can reach the new design, and the window is laid out once, at the swap.
            self._shown.widget.setEnabled(False)
        self._build_some()

    def _swap(self) -> None:
        """Put the built ``_body`` in the layout in place of the one shown (kept, hidden, for the
        next device of its family)."""
        body, shown = self._body, self._shown
        old = shown.widget if shown is not None else self._placeholder
        if body.widget is not old:
            self.layout().replaceWidget(old, body.widget)
            old.hide()
            old.setEnabled(True)
            body.widget.show()
        body.widget.setEnabled(True)        # (greyed out if a switch away from it was undone mid-build)
        self._shown = body

    def _reset(self, body: _Body, table) -> None:
        """``body``'s rows (built or not) show another device's values, centred on them."""
        values = dict(table)
        body.pending = [(info, values[info]) for info, _ in body.pending]
        for info, value in table:
            if info.choices and info.name in body.choices:
                combo = body.choices[info.name]
                combo.blockSignals(True)
                combo.setCurrentText(value)
                combo.blockSignals(False)
            elif info.is_vector and (info.name, 0) in body.rows:
                for i, v in enumerate(value):
                    body.rows[(info.name, i)].reset(v)
            elif (info.name, -1) in body.rows:
                body.rows[(info.name, -1)].reset(value)

    def _build_some(self) -> None:
        """Build ``_body``'s pending rows for about ``BUILD_SLICE_MS``, then let the event loop run
        (a timer, paints, the map's result) and go on in its next turn; swap it in once built."""
        body = self._body
        start = time.perf_counter()
        current = self._current()
        while body.pending:          # at least one parameter a part, however slow
            self._build_one(body, *body.pending.pop(0), current)
            if (time.perf_counter() - start) * 1e3 >= BUILD_SLICE_MS:
                break
        if not body.pending:
            self._swap()
        else:
            self._next_part.start()

    def _finish(self) -> None:
        body, current = self._body, self._current()
        while body.pending:
            self._build_one(body, *body.pending.pop(0), current)
        self._swap()

    def _current(self) -> dict:
        """The state's values by ``ParamInfo``, if its design is of the family shown (else none)."""
        table = self.state.mechanism.parameter_table()
        return dict(table) if layout_key(table) == self._built_for else {}

    def _build_one(self, body: _Body, info, value, current: dict) -> None:
        """One parameter's row (a vector's one row per entry, a choice's combo box), at the preset's
        ``value`` (the slider's span around it), then showing the state's value if it differs."""
        form = body.forms[group_of(info)]
        tooltip = info.description + (f" ({info.unit})" if info.unit else "")
        if info.choices:
            combo = QComboBox()
            combo.addItems(info.choices)
            combo.setCurrentText(value)
            combo.setToolTip(tooltip)
            combo.currentTextChanged.connect(lambda text, n=info.name: self.edited.emit(n, text, False))
            body.choices[info.name] = combo
            form.addRow(_label(info.name, ""), combo)
        elif info.is_vector:
            for i, (label, v) in enumerate(zip(info.labels, value)):
                row = ParameterRow(v, info.unit, f"{tooltip}: {label}", name=info.name)
                row.changed.connect(lambda val, drag, n=info.name, k=i: self._vector_edit(n, k, val, drag))
                body.rows[(info.name, i)] = row
                form.addRow(_label(f"{info.name} [{label}]", ""), row)
        else:
            row = ParameterRow(value, info.unit, tooltip, name=info.name)
            row.changed.connect(lambda val, drag, n=info.name: self.edited.emit(n, val, drag))
            body.rows[(info.name, -1)] = row
            form.addRow(_label(info.name, ""), row)
        if current.get(info, value) != value:
            self._show_value(body, info, current[info])

    def show_preset(self, preset) -> None:
        """Select ``preset`` in the device list (a file's preset is added under its name)."""
        box = self.preset_box
        index = box.findData(preset.key)
        if index < 0:
            box.addItem(preset.name or preset.key, preset.key)
            index = box.count() - 1
        box.blockSignals(True)
        box.setCurrentIndex(index)
        box.blockSignals(False)

    def _vector_edit(self, name: str, index: int, value: float, dragging: bool) -> None:
        # The other entries come from the model, not from the (rounded) spin boxes.
        current = dict((info.name, v) for info, v in self.state.mechanism.parameter_table())[name]
        values = list(current)
        values[index] = value
        self.edited.emit(name, tuple(values), dragging)

    def sync(self) -> None:
        """Show the state's mechanism's values (after a load, a revert or a replace); rows not built
        yet take them when they are."""
        table = self.state.mechanism.parameter_table()
        if layout_key(table) != self._built_for:
            self.rebuild()
            return
        for info, value in table:
            self._show_value(self._body, info, value)

    @staticmethod
    def _show_value(body: _Body, info, value) -> None:
        if info.choices:
            combo = body.choices.get(info.name)
            if combo is not None:
                combo.blockSignals(True)
                combo.setCurrentText(value)
                combo.blockSignals(False)
        elif info.is_vector:
            for i, v in enumerate(value):
                row = body.rows.get((info.name, i))
                if row is not None and not math.isclose(row.value(), v, rel_tol=1e-9, abs_tol=1e-9):
                    row.set_value(v)
        else:
            row = body.rows.get((info.name, -1))
            if row is not None and not math.isclose(row.value(), value, rel_tol=1e-9, abs_tol=1e-9):
                row.set_value(value)


def _label(text: str, tooltip: str) -> QLabel:
    label = QLabel(text.replace("_", " "))
    if tooltip:
        label.setToolTip(tooltip)
    return label
