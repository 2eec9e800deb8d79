"""The torque rating and gravity controls: how the device is loaded (``metrics.loading``).

Two combo boxes for the toolbar. "Rating": continuous (always) or peak, disabled, with the
reason in its tooltip, for a device whose source gives no peak rating. "Gravity": off or one of
the mounting orientations of ``kinematics.gravity.MOUNTINGS`` (the base-frame axis that points
up), disabled with the reason for a device without a mass model. They write the model
(``AppModel.set_loading``) and follow it (a new device resets them to what it supports).
"""
from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QComboBox, QHBoxLayout, QLabel, QWidget

from app.gui.model import loading_refusals
from kinematics.gravity import MOUNTINGS
from metrics.loading import RATINGS, Loading, LoadingError

RATING_TIP = ("Which torque rating limits the actuators: the continuous one, or the peak (stall, short-time) "
              "one where the device's source gives it. Every map, statistic and pose glyph uses it.")
GRAVITY_TIP = ("Gravity by mounting orientation (the base-frame axis that points up): the joints spend torque "
               "holding the links, which shifts the force set. Every map, statistic and pose glyph uses it.")


class LoadingControls(QWidget):
    """"Rating" and "Gravity" combo boxes bound to ``state.loading``."""

    def __init__(self, state, parent=None) -> None:
        super().__init__(parent)
        self.state = state
        self.rating = QComboBox()
        for name in RATINGS:
            self.rating.addItem(name, name)
        self.gravity = QComboBox()
        self.gravity.addItem("off", None)
        for name, up in MOUNTINGS.items():
            self.gravity.addItem(name, name)
            axis = max(range(3), key=lambda k: abs(up[k]))
            self.gravity.setItemData(self.gravity.count() - 1, f"mounted with the base's {'xyz'[axis]} axis "
                                     f"pointing {'up' if up[axis] > 0 else 'down'}", Qt.ItemDataRole.ToolTipRole)
        row = QHBoxLayout(self)
        row.setContentsMargins(0, 0, 0, 0)
        row.addWidget(QLabel(" Rating "))
        row.addWidget(self.rating)
        row.addWidget(QLabel(" Gravity "))
        row.addWidget(self.gravity)
        self.rating.currentIndexChanged.connect(self._chosen)
        self.gravity.currentIndexChanged.connect(self._chosen)
        state.loadingChanged.connect(self.sync)
        state.presetChanged.connect(self.sync)
        self.sync()

    def _chosen(self, _=None) -> None:
        mounting = self.gravity.currentData()
        loading = Loading(rating=self.rating.currentData(), mounting=mounting)
        try:
            self.state.set_loading(loading)
        except LoadingError:
            self.sync()             # (the disabled controls never offer one; a device change may race)

    def sync(self) -> None:
        """Show the model's loading and what this device supports (signals held back)."""
        st = self.state
        refused = loading_refusals(st.mechanism, st.preset.name)
        loading = st.loading
        for box in (self.rating, self.gravity):
            box.blockSignals(True)
        try:
            self.rating.setCurrentIndex(max(0, self.rating.findData(loading.rating)))
            self.rating.setEnabled(refused["rating"] is None)
            self.rating.setToolTip(RATING_TIP if refused["rating"] is None
                                   else f"Peak rating unavailable: {refused['rating']}.")
            index = self.gravity.findData(loading.mounting) if loading.biased else 0
            self.gravity.setCurrentIndex(max(0, index))
            self.gravity.setEnabled(refused["gravity"] is None)
            self.gravity.setToolTip(GRAVITY_TIP if refused["gravity"] is None
                                    else f"Gravity unavailable: {refused['gravity']}.")
        finally:
            for box in (self.rating, self.gravity):
                box.blockSignals(False)
