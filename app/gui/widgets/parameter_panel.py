"""Every parameter of the device as a labelled slider with a spin box and its unit.

The panel only reports edits (``edited(name, value)`` in display units, a tuple for vector
parameters); the main window turns them into a new mechanism. ``dragging`` tells whether a
slider is still held, so the map can follow coarsely and refine on release.
"""
from __future__ import annotations

import math

import shiboken6
from PySide6.QtCore import Qt, Signal
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
        decimals = spin_decimals(value, unit)
        self.spin.setDecimals(decimals)
        # Angles and offsets at zero may go negative; other values stay positive.
        signed = unit == "deg" and name not in STEP_PARAMETERS or value == 0.0
        self.spin.setRange(-1e6 if signed else 10.0 ** -decimals, 1e6)
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


class ParameterPanel(QWidget):
    """Preset chooser and one row per parameter of the current mechanism."""

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
        self.body = QWidget()
        layout = QVBoxLayout(self)
        head = QFormLayout()
        head.addRow("Device", self.preset_box)
        layout.addLayout(head)
        layout.addWidget(self.body)
        layout.addStretch(1)
        self.rows: dict[tuple[str, int], ParameterRow] = {}
        self.choices: dict[str, QComboBox] = {}
        self._built_for = None
        state.presetChanged.connect(self.rebuild)
        state.mechanismChanged.connect(self.sync)
        self.rebuild()

    def rebuild(self) -> None:
        """One row per parameter of the preset's mechanism (rebuilt when the preset changes)."""
        st = self.state
        self.show_preset(st.preset)
        old = self.body
        self.body = QWidget()
        self.layout().replaceWidget(old, self.body)
        old.hide()
        # Deleted now, with its rows: ``deleteLater`` waits for an event loop to return to the
        # level it was called from, so while something drives Qt with ``processEvents`` (a
        # script, a test) every old panel stayed alive, a hidden top-level window (135 widgets
        # per switch of the Inverse3). Nothing in the body sends the signals that rebuild it
        # (the preset list is outside it; a choice's edit keeps the mechanism's class).
        shiboken6.delete(old)
        self.rows, self.choices = {}, {}
        outer = QVBoxLayout(self.body)
        outer.setContentsMargins(0, 0, 0, 0)
        groups: dict[str, QFormLayout] = {}
        boxes: dict[str, QGroupBox] = {}
        for name in GROUPS:
            boxes[name] = QGroupBox(name)
            groups[name] = QFormLayout(boxes[name])
            outer.addWidget(boxes[name])
        for info, value in st.mechanism.parameter_table():
            form = groups[group_of(info)]
            tooltip = info.description + (f" ({info.unit})" if info.unit else "")
            if info.choices:
                combo = QComboBox()
                combo.addItems(info.choices)
                combo.setCurrentText(value)
                combo.setToolTip(tooltip)
                combo.currentTextChanged.connect(lambda text, n=info.name: self.edited.emit(n, text, False))
                self.choices[info.name] = combo
                form.addRow(_label(info.name, ""), combo)
            elif info.is_vector:
                for i, (label, v) in enumerate(zip(info.labels, value)):
                    row = ParameterRow(v, info.unit, f"{tooltip}: {label}", name=info.name)
                    row.changed.connect(lambda val, drag, n=info.name, k=i: self._vector_edit(n, k, val, drag))
                    self.rows[(info.name, i)] = row
                    form.addRow(_label(f"{info.name} [{label}]", ""), row)
            else:
                row = ParameterRow(value, info.unit, tooltip, name=info.name)
                row.changed.connect(lambda val, drag, n=info.name: self.edited.emit(n, val, drag))
                self.rows[(info.name, -1)] = row
                form.addRow(_label(info.name, ""), row)
        for name, form in groups.items():       # a model with nothing in a group shows no empty box
            boxes[name].setVisible(form.rowCount() > 0)
        self._built_for = type(st.mechanism)

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
        """Show the state's mechanism's values (after a load, a revert or a replace)."""
        if type(self.state.mechanism) is not self._built_for:
            self.rebuild()
            return
        for info, value in self.state.mechanism.parameter_table():
            if info.choices:
                combo = self.choices[info.name]
                combo.blockSignals(True)
                combo.setCurrentText(value)
                combo.blockSignals(False)
            elif info.is_vector:
                for i, v in enumerate(value):
                    row = self.rows[(info.name, i)]
                    if not math.isclose(row.value(), v, rel_tol=1e-9, abs_tol=1e-9):
                        row.set_value(v)
            else:
                row = self.rows[(info.name, -1)]
                if not math.isclose(row.value(), value, rel_tol=1e-9, abs_tol=1e-9):
                    row.set_value(value)


def _label(text: str, tooltip: str) -> QLabel:
    label = QLabel(text.replace("_", " "))
    if tooltip:
        label.setToolTip(tooltip)
    return label
