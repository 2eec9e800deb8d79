"""Parameter rows show what the model holds: enough decimals, and a step size's slider never crosses zero."""
from __future__ import annotations

import pytest

from app.gui.widgets.parameter_panel import STEP_PARAMETERS, group_of, slider_range, spin_decimals
from kinematics.inverse3 import Inverse3


@pytest.mark.parametrize("value, unit, shown", [(0.0256, "deg", "0.0256"), (140.0, "mm", "140.00"),
                                                (0.1, "N m", "0.1000"), (0.00660832, "deg", "0.00661"),
                                                (6.875, "", "6.8750")])
def test_decimals_keep_three_significant_digits(value, unit, shown):
    assert f"{value:.{spin_decimals(value, unit)}f}" == shown


def test_a_resolution_slider_scales_instead_of_adding_180_deg():
    assert "joint_resolution" in STEP_PARAMETERS
    lo, hi = slider_range(0.0256, "deg", "joint_resolution")
    assert 0 < lo < 0.0256 < hi
    assert slider_range(45.0, "deg", "upper_limits") == (0.0, 90.0)


def test_sensor_and_rating_rows_sit_with_the_actuators():
    infos = {i.name: i for i in Inverse3.PARAM_INFO}
    assert group_of(infos["joint_resolution"]) == "Actuators"


def test_the_panel_shows_the_inverse3_resolution_unrounded(qtbot):
    from app.gui.main_window import MainWindow

    win = MainWindow(device="inverse3_prototype")
    qtbot.addWidget(win)
    row = win.param_panel.rows[("joint_resolution", 0)]
    assert row.spin.text().startswith("0.0256")
    win.close()


@pytest.mark.parametrize(("unit", "span"), [("mm", 100.0), ("N m", 1.0), ("", 1.0)])
def test_a_parameter_at_zero_gets_a_slider_either_side_of_it(qtbot, unit, span):
    from app.gui.widgets.parameter_panel import ParameterRow
    assert slider_range(0.0, unit, "reference_offset") == (-span, span)
    row = ParameterRow(0.0, unit, "an offset", name="reference_offset")      # no division by a zero span
    qtbot.addWidget(row)
    assert row.value() == 0.0 and row.slider.value() == row.slider.maximum() // 2
    row.slider.setValue(0)
    assert row.value() == -span
