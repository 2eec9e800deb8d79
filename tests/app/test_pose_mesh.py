"""The pose scene's spheres are round with few triangles: a software renderer (llvmpipe) pays for
every triangle on each frame of a slider step (issue 11, sec. 2)."""
from __future__ import annotations

import numpy as np

from app.render.views import _pose_scene
from app.scenes import pose as pose_scene
from app.scenes.common import actor_named
from resources import load_preset


def test_joint_balls_carry_their_exact_normals():
    centres = np.array([[0.0, 0.0, 0.0], [0.1, -0.2, 0.3]])
    balls = pose_scene._balls(centres, 0.01)
    per_ball = balls.n_points // len(centres)
    offsets = balls.points - np.repeat(centres, per_ball, axis=0)
    # Each point's normal is the unit vector from its ball's centre: shaded round, not by facets.
    np.testing.assert_allclose(balls.point_data.active_normals, offsets / 0.01, atol=1e-12)


def test_the_pose_view_draws_a_few_thousand_triangles():
    preset = load_preset("inverse3_prototype")
    plotter, _ = _pose_scene(preset.mechanism, preset.pose, size=(330, 896))
    try:
        joints = actor_named(plotter, "joints").mapper.dataset
        assert joints.n_cells == len(preset.mechanism.link_points(np.zeros(3))) * 2 * 16 * 14
        total = sum(a.mapper.dataset.n_cells for a in plotter.renderer.actors.values()
                    if getattr(a, "mapper", None) is not None and a.mapper.dataset is not None)
        # 16,455 with balls of 30 x 30 and a sphere of 48 x 48; 5,335 with 16 x 16 and 32 x 32.
        assert total < 8000
    finally:
        plotter.close()


def test_the_caption_gives_the_velocity_ellipsoids_scale_only_where_it_is_drawn():
    """The caption said "velocity ellipsoid at 1 m/s = 250 mm" with no ellipsoid drawn or in the
    legend (found by the audit): its scale is said with the glyph only."""
    from app.logic.glyphs import DEFAULT_GLYPHS
    from app.render.views import pose_plotter

    preset = load_preset("inverse3_prototype")
    for glyphs, said in ((DEFAULT_GLYPHS, False), (DEFAULT_GLYPHS | {"velocity_ellipsoid"}, True)):
        plotter, _ = pose_plotter(preset.mechanism, preset.pose, glyphs=glyphs)
        try:
            caption = plotter.actors["pose_caption"].get_text(1)
        finally:
            plotter.close()
        assert ("velocity ellipsoid at 1 m/s" in caption) == said, caption
        assert "forces drawn at 10 N" in caption
