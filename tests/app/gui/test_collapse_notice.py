"""A design whose workspace collapses, or a pose it leaves, is said in the status bar, not left blank.

Before: a 1 mm link was accepted without a word; the map went empty and the pose view blank.
"""
from __future__ import annotations


def test_a_collapsed_workspace_and_a_lost_pose_are_said(make_window, waits, qtbot):
    window = make_window("inverse3_prototype", longest=30)
    bar = window.statusBar()
    assert window.state.pose_report.reachable
    window.on_parameter_edited("proximal_length", 1.0, False)       # mm: the arms no longer reach
    waits.full(window)
    assert window.state.current.map.feasible_points == 0
    qtbot.waitUntil(lambda: "No feasible point" in bar.currentMessage(), timeout=5000)
    assert not window.state.pose_report.reachable
    assert window.pose_label.text() == "pose outside the workspace"
    window.undo()
    waits.full(window)
    assert window.state.current.map.feasible_points > 0 and window.state.pose_report.reachable


def test_the_pose_leaving_the_workspace_is_said_once(make_window, qtbot):
    window = make_window("inverse3_prototype", longest=30)
    bar = window.statusBar()
    window.state.set_pose((5.0, 5.0, 5.0))          # m: far outside any reach
    qtbot.waitUntil(lambda: "outside this design's workspace" in bar.currentMessage(), timeout=5000)
