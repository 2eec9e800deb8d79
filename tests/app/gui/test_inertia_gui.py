"""View > Inertia ellipsoid (issue 22 sec. 5): toggling it adds and removes its actor, legend row and
caption scale; it is computed only while shown; a device without a mass model has it disabled,
with the reason as tooltip."""
from __future__ import annotations

import numpy as np

from app import scenes
from app.logic.glyphs import GLYPHS
from metrics.pose import analyse_pose
from tests.preset_files import massless_omni

SMALL = 41      # points along the longer map axis

ROW = ("inertia ellipsoid", scenes.COLOURS["inertia_ellipsoid"])


def legend(window) -> list:
    return scenes.legend_rows(window.pose_view.plotter, window.state.mechanism.joint_names)


def test_toggling_the_inertia_ellipsoid_adds_and_removes_it(make_window):
    window = make_window("phantom_premium_15", longest=SMALL)
    st, view = window.state, window.pose_view
    action = window.glyph_actions["inertia_ellipsoid"]
    assert action.isEnabled() and action.toolTip() == GLYPHS["inertia_ellipsoid"]
    assert not action.isChecked() and "inertia_ellipsoid" not in st.glyphs
    assert st.pose_report.inertia_ellipsoid is None                 # hidden: not computed
    assert "inertia_ellipsoid" not in view.plotter.actors and ROW not in legend(window)

    action.trigger()                                                # View > Inertia ellipsoid on
    assert "inertia_ellipsoid" in st.glyphs
    report = st.pose_report
    full = analyse_pose(st.mechanism, np.asarray(st.pose), loading=st.loading)
    np.testing.assert_allclose(report.inertia_ellipsoid.radii, full.inertia_ellipsoid.radii, rtol=1e-12)
    assert "inertia_ellipsoid" in view.plotter.actors
    assert ROW in legend(window) and ROW in view._legend_rows     # the legend drawn in the view
    assert "inertia ellipsoid at 0.1 kg = 25 mm" in view.view.caption

    action.trigger()                                                # and off again
    assert "inertia_ellipsoid" not in st.glyphs
    assert st.pose_report.inertia_ellipsoid is None
    assert "inertia_ellipsoid" not in view.plotter.actors
    assert ROW not in legend(window) and ROW not in view._legend_rows
    assert "inertia ellipsoid" not in view.view.caption



def test_a_device_without_a_mass_model_has_the_toggle_disabled(make_window, tmp_path, qtbot):
    window = make_window("phantom_premium_15", longest=SMALL)
    st, view = window.state, window.pose_view
    action = window.glyph_actions["inertia_ellipsoid"]
    action.trigger()
    assert "inertia_ellipsoid" in view.plotter.actors

    assert window.load_device(massless_omni(tmp_path))
    # A new device's glyphs come a few passes of the event loop after the switch (``_defer_pose``).
    qtbot.waitUntil(lambda: not window._pose_deferred, timeout=10_000)
    assert not st.mechanism.has_mass_model
    assert not action.isEnabled()
    assert "no mass model" in action.toolTip() and action.toolTip() != GLYPHS["inertia_ellipsoid"]
    # Still asked for, but nothing computed, drawn, listed or said.
    assert st.pose_report.inertia_ellipsoid is None
    assert "inertia_ellipsoid" not in view.plotter.actors and ROW not in legend(window)
    assert "inertia" not in view.view.caption
    for name, other in window.glyph_actions.items():
        if name != "inertia_ellipsoid":
            assert other.isEnabled() and other.toolTip() == GLYPHS[name], name

    assert window.load_device("phantom_premium_15")                 # a mass model again: drawn again
    qtbot.waitUntil(lambda: not window._pose_deferred, timeout=10_000)
    assert action.isEnabled() and action.toolTip() == GLYPHS["inertia_ellipsoid"]
    assert "inertia_ellipsoid" in view.plotter.actors and ROW in legend(window)
