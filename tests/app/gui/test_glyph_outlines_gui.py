"""Every glyph on in the app's pose view (issue 26 sec. 2): the closed glyphs after the first are
outlines, the arrows are drawn over everything, and the legend the view draws has each glyph's
colour as it shows on screen."""
from __future__ import annotations

from app.logic.glyphs import CLOSED_GLYPHS
from app.scenes.common import actor_named
from app.scenes.pose import depth_layer
from app.scenes.pose_legend import drawn_colour

SMALL = 41      # points along the longer map axis
NAMES = {"links": "links", "force polytope": "polytope", "inscribed sphere": "sphere",
         "force ellipsoid": "force_ellipsoid", "velocity ellipsoid": "velocity_ellipsoid",
         "inertia ellipsoid": "inertia_ellipsoid", "desired force": "desired_force", "clamped force": "clamped_force"}


def test_every_glyph_on_draws_outlines_arrows_on_top_and_true_swatches(make_window, qtbot):
    window = make_window("phantom_premium_15", longest=SMALL)
    window.tabs.setCurrentWidget(window.pose_view)
    st, view = window.state, window.pose_view
    plotter = view.plotter
    for action in window.glyph_actions.values():
        if action.isEnabled() and not action.isChecked():
            action.trigger()
    st.set_desired_force((3.0, 2.0, 1.0))
    qtbot.waitUntil(lambda: all(actor_named(plotter, n) is not None
                                for n in ("inertia_ellipsoid", "velocity_ellipsoid", "clamped_force")), timeout=10_000)
    surface, *outlines = CLOSED_GLYPHS
    assert actor_named(plotter, surface).GetProperty().GetOpacity() < 1 and depth_layer(actor_named(plotter, surface))
    for name in outlines:
        actor = actor_named(plotter, name)
        mesh = actor.GetMapper().GetInput()
        assert mesh.GetNumberOfPolys() == 0 and mesh.GetNumberOfLines() > 0, name
        assert actor.GetProperty().GetOpacity() == 1.0 and not actor.GetProperty().GetLighting(), name
    joints = st.mechanism.joint_names
    for u, joint in enumerate(joints):
        assert depth_layer(actor_named(plotter, f"reference_force_{u}")) == "front", joint
    assert depth_layer(actor_named(plotter, "clamped_force")) == "front"
    # The legend drawn in the view: every row, each the colour its actor shows.
    rows = dict(view._legend_rows)
    names = {**NAMES, **{f"{joint} at full torque": f"reference_force_{u}" for u, joint in enumerate(joints)}}
    assert set(rows) == set(names)
    for label, colour in rows.items():
        assert colour == drawn_colour(actor_named(plotter, names[label])), label
    assert rows["force polytope"] != "#4a90d9"                     # translucent: lighter than its base colour
    assert (rows["inscribed sphere"], rows["force ellipsoid"]) == ("#2ca02c", "#ff7f0e")     # outlines: their own
