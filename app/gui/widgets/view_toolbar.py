"""The window's toolbar: the quantity shown, the loading, the pose typed in, a desired force.

``ViewToolBar`` holds the controls and keeps their lists and hints in step with the device
(``fill_quantities``, ``pose_mode_texts``); the window connects their signals to its actions.
"""
from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QComboBox, QLabel, QLineEdit, QToolBar

from app.gui.widgets.loading_controls import LoadingControls
from app.logic.display_units import display_unit
from app.scenes import COLOURS, colour_name
from kinematics.base import task_display_units
from kinematics.units import joint_display_units
from metrics.quantities import QUANTITIES, available_quantities


class ViewToolBar(QToolBar):
    """Quantity box, loading controls, pose mode and pose box, desired-force box.

    Parameters
    ----------
    state : QtAppState
        The app's state (its mechanism names the pose coordinates; the loading controls edit it).
    """

    def __init__(self, state) -> None:
        super().__init__("View")
        self.setObjectName("view_toolbar")
        self.state = state
        self.addWidget(QLabel(" Quantity "))
        self.quantity_box = QComboBox()
        self.fill_quantities()
        # The box says what the shown quantity is, in its display unit (each item says its own).
        self.quantity_box.currentIndexChanged.connect(
            lambda _: self.quantity_box.setToolTip(quantity_tooltip(self.quantity_box.currentData())))
        self.addWidget(self.quantity_box)
        self.addSeparator()
        self.loading_controls = LoadingControls(state)
        self.addWidget(self.loading_controls)
        self.addSeparator()
        self.addWidget(QLabel(" Pose "))
        self.pose_mode = QComboBox()
        self.pose_mode.addItem("position", "position")
        self.pose_mode.addItem("joints", "joints")
        self.pose_mode.setToolTip("Type the pose as the end-effector position, or as the actuated joints "
                                  "(forward kinematics gives the point, as `isoforce pose DEVICE --joints`).")
        self.addWidget(self.pose_mode)
        self.pose_edit = QLineEdit()
        self.pose_edit.setMaximumWidth(220)
        self.addWidget(self.pose_edit)
        self.pose_mode_texts()
        self.addWidget(QLabel(" Desired force (N) "))
        self.force_edit = QLineEdit()
        self.force_edit.setPlaceholderText("fx, fy, fz")
        self.force_edit.setToolTip(f"A force to render; the {colour_name(COLOURS['desired'])} arrow, with its "
                                   f"clamped version in {colour_name(COLOURS['clamped'])} "
                                   "(paper 000 eq. 9: scaled down to the isotropic radius).")
        self.force_edit.setMaximumWidth(200)
        self.addWidget(self.force_edit)

    def pose_mode_texts(self) -> None:
        """The pose box's placeholder and tip name the coordinates and their units for its mode."""
        mech = self.state.mechanism
        if self.pose_mode.currentData() == "joints":
            names = [f"{n} ({u})" for n, u in zip(mech.joint_names, joint_display_units(mech))]
            self.pose_edit.setToolTip("Type the actuated joints, " + ", ".join(names) + ", and press Enter.")
        else:
            names = [f"{n} ({u})" for n, u in zip(mech.task_names, task_display_units(mech))]
            self.pose_edit.setToolTip("Type the end-effector position, " + ", ".join(names)
                                      + ", and press Enter (or click the map).")
        self.pose_edit.setPlaceholderText(", ".join(names))

    def fill_quantities(self) -> None:
        """The quantities the design can compute, the state's selected, without announcing a change
        (refilled only when they change: it is called at every slider step)."""
        box = self.quantity_box
        names = available_quantities(self.state.mechanism)
        box.blockSignals(True)
        if names != tuple(box.itemData(i) for i in range(box.count())):
            box.clear()
            for name in names:
                box.addItem(QUANTITIES[name].label, name)
                box.setItemData(box.count() - 1, QUANTITIES[name].description, Qt.ItemDataRole.ToolTipRole)
        box.setCurrentIndex(max(0, box.findData(self.state.quantity)))
        box.setToolTip(quantity_tooltip(box.currentData()))
        box.blockSignals(False)


def quantity_tooltip(name: str | None) -> str:
    """What a map quantity is, in the unit the app shows it in: "Spatial resolution (µm): ..."."""
    if name not in QUANTITIES:
        return "The quantity the map shows"
    unit = display_unit(name)[0]
    return f"{QUANTITIES[name].label} ({unit or 'no unit'}): {QUANTITIES[name].description}"
