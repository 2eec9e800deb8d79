"""The desired-force field's tooltip names the arrows' colours the pose legend draws (issue 21 sec. 3:
it said the clamped arrow is green; the legend draws it cyan, and green is the inscribed sphere)."""
from __future__ import annotations

import colorsys

import pytest

from app.gui.model import AppModel
from app.gui.qt_model import QtAppState
from app.gui.widgets.view_toolbar import ViewToolBar
from app.scenes import LEGEND, colour_name
from resources import load_preset


def hue_degrees(colour: str) -> float:
    return 360.0 * colorsys.rgb_to_hls(*(int(colour[k:k + 2], 16) / 255.0 for k in (1, 3, 5)))[0]


@pytest.mark.parametrize(("colour", "name"), [("#ff0000", "red"), ("#00ff00", "green"), ("#00ffff", "cyan"),
                                              ("#0000ff", "blue"), ("#ff8000", "orange"), ("#808080", "grey"),
                                              ("#000000", "black"), ("#ffffff", "white"), ("#ff0010", "red")])
def test_colour_names_follow_the_hue(colour, name):
    assert colour_name(colour) == name


def test_the_desired_force_tooltip_names_the_legends_colours(qtbot):
    toolbar = ViewToolBar(QtAppState(AppModel(load_preset("fivebar_singh"))))
    qtbot.addWidget(toolbar)
    legend = dict(LEGEND["desired_force"])
    desired, clamped = legend["desired force"], legend["clamped force"]
    # The legend's own colours, measured: the clamped arrow's hue is cyan's (180 deg), not the sphere's green.
    assert abs(hue_degrees(clamped) - 180.0) < 20.0 and colour_name(clamped) == "cyan"
    assert abs(hue_degrees(dict(LEGEND["sphere"])["inscribed sphere"]) - 120.0) < 20.0
    tip = toolbar.force_edit.toolTip()
    assert f"the {colour_name(desired)} arrow" in tip and colour_name(desired) == "red"
    assert "clamped version in cyan" in tip and "green" not in tip, tip
