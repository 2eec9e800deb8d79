"""Readable 3D glyphs (issue 26, section 2): with every glyph on, the closed glyphs after the first
are outlines, the arrows are drawn over everything, each legend swatch is the colour its glyph
shows, the PHANToM's glyphs are drawn to its size, and a box map's iso-surfaces lie at quantiles
of the values present, each labelled.

Before: the translucent polytope, sphere and ellipsoids blended into one blob, the desired and
clamped arrows vanished inside it, the legend listed arrows hidden under a link (the five-bar's
theta_1 along the other arm's distal link) and the PHANToM's 1.5 N sphere was 9 mm across under
210 mm of links.
"""
from __future__ import annotations

import numpy as np
import pytest

from app import scenes
from app.logic.glyphs import CLOSED_GLYPHS, GLYPHS, outlined_glyphs, seen_colour
from app.render.views import _pose_scene, _workspace_scene
from app.scenes.common import actor_named
from app.scenes.pose import COLOURS, SPHERE_OVER_SIZE, depth_layer, draw_in_layer, pose_scale
from app.scenes.pose_legend import drawn_colour, legend_rows
from metrics.workspace import compute_map
from resources import load_preset

ALL = frozenset(GLYPHS)
FORCES = {"phantom_premium_15": (3.0, 2.0, 1.0), "fivebar_singh": (30.0, -5.0), "inverse3_prototype": (3.0, 2.0, 1.0)}
SIZE = (500, 400)


def _scene(key: str, glyphs=ALL, force=None):
    preset = load_preset(key)
    force = FORCES[key] if force is None else force
    plotter, report = _pose_scene(preset.mechanism, preset.pose, glyphs=glyphs, desired_force=force, size=SIZE)
    return preset, plotter, report


def _picture(plotter) -> np.ndarray:
    plotter.render()
    return np.asarray(plotter.screenshot(return_img=True), float)[..., :3]


def _rgb(colour: str) -> np.ndarray:
    return np.array([int(colour[k:k + 2], 16) for k in (1, 3, 5)], float)


def _is_outline(actor) -> bool:
    mesh = actor.GetMapper().GetInput()
    return (mesh.GetNumberOfPolys() == 0 and mesh.GetNumberOfLines() > 0 and actor.GetProperty().GetOpacity() == 1.0
            and not actor.GetProperty().GetLighting())


def test_only_the_first_closed_glyph_shown_is_a_surface():
    assert outlined_glyphs(CLOSED_GLYPHS) == frozenset(CLOSED_GLYPHS[1:])
    assert outlined_glyphs({"links", "velocity_ellipsoid", "reference_forces"}) == frozenset()
    assert outlined_glyphs({"inertia_ellipsoid", "sphere"}) == {"inertia_ellipsoid"}


@pytest.mark.parametrize("key", ["phantom_premium_15", "fivebar_singh", "inverse3_prototype"])
def test_with_every_glyph_on_the_closed_glyphs_after_the_polytope_are_outlines(key):
    preset, plotter, _ = _scene(key)
    try:
        polytope = actor_named(plotter, "polytope")
        assert polytope.GetMapper().GetInput().GetNumberOfPolys() > 0 and polytope.GetProperty().GetOpacity() < 1
        assert depth_layer(polytope) == "back"                    # behind every other glyph: it tints none
        assert actor_named(plotter, "polytope_edges") is not None
        for name in ("sphere", "force_ellipsoid", "velocity_ellipsoid", "inertia_ellipsoid"):
            actor = actor_named(plotter, name)
            assert actor is not None and _is_outline(actor), name
            assert depth_layer(actor) is None, name
        assert actor_named(plotter, "inertia_ellipsoid_edge") is None     # the outline is the edge already
    finally:
        plotter.close()


def test_without_the_polytope_the_sphere_is_the_surface_and_the_ellipsoids_outlines():
    _, plotter, _ = _scene("inverse3_prototype", glyphs=ALL - {"polytope"})
    try:
        sphere = actor_named(plotter, "sphere")
        assert sphere.GetMapper().GetInput().GetNumberOfPolys() > 0 and sphere.GetProperty().GetOpacity() < 1
        assert all(_is_outline(actor_named(plotter, n)) for n in ("force_ellipsoid", "velocity_ellipsoid"))
        assert actor_named(plotter, "polytope") is None and actor_named(plotter, "polytope_edges") is None
    finally:
        plotter.close()


def test_a_spatial_outline_is_three_principal_ellipses_on_the_ellipsoid():
    preset, plotter, report = _scene("phantom_premium_15")
    try:
        mesh = actor_named(plotter, "force_ellipsoid").GetMapper().GetInput()
        points = np.asarray(mesh.GetPoints().GetData(), float)
        assert mesh.GetNumberOfLines() == 3
        scale = pose_scale(preset.mechanism, report)
    finally:
        plotter.close()
    ell = report.force_ellipsoid
    local = (points - np.asarray(report.x, float)) @ np.asarray(ell.axes, float) / (np.asarray(ell.radii) * scale)
    # Every point on {p : |diag(1 / (s r)) A^T p| = 1}, and each ellipse in a plane of two axes.
    np.testing.assert_allclose(np.linalg.norm(local, axis=1), 1.0, atol=1e-9)
    assert np.all(np.min(np.abs(local), axis=1) < 1e-9)


@pytest.mark.parametrize("key", ["phantom_premium_15", "fivebar_singh"])
def test_arrows_are_drawn_over_the_links_and_surfaces(key):
    """Each arrow's actor writes its depth in front of every other actor's (the shader replacement
    set on it), the desired force just behind its clamp; and hiding an arrow the legend lists
    changes the picture: none is hidden under a link or inside a surface."""
    preset, plotter, _ = _scene(key)
    try:
        arrows = [f"reference_force_{u}" for u in range(preset.mechanism.n_joints)] + ["clamped_force"]
        for name in arrows:
            assert depth_layer(actor_named(plotter, name)) == "front", name
        assert depth_layer(actor_named(plotter, "desired_force")) == "over"
        shaders = actor_named(plotter, "clamped_force").GetShaderProperty()
        assert shaders.GetNumberOfShaderReplacements() == 1
        assert shaders.GetNthShaderReplacementTypeAsString(0) == "Fragment"
        listed = {label for label, _ in legend_rows(plotter, preset.mechanism.joint_names)}
        shown = _picture(plotter)
        for joint, name in zip(preset.mechanism.joint_names, arrows):
            assert f"{joint} at full torque" in listed
            actor = actor_named(plotter, name)
            actor.SetVisibility(False)
            try:
                hidden = _picture(plotter)
            finally:
                actor.SetVisibility(True)
            assert np.count_nonzero(np.any(shown != hidden, axis=2)) >= 30, name
    finally:
        plotter.close()


def test_the_five_bars_arrow_along_a_distal_link_shows_only_on_top():
    """theta_1's force at full torque lies along the other arm's distal link: drawn where its depth
    puts it, the link's tube hides most of it."""
    _, plotter, _ = _scene("fivebar_singh", glyphs=frozenset({"links", "reference_forces"}))
    try:
        arrow = actor_named(plotter, "reference_force_0")

        def seen() -> int:
            shown = _picture(plotter)
            arrow.SetVisibility(False)
            try:
                return int(np.count_nonzero(np.any(shown != _picture(plotter), axis=2)))
            finally:
                arrow.SetVisibility(True)
        on_top = seen()
        draw_in_layer(arrow, None)
        in_place = seen()
    finally:
        plotter.close()
    assert on_top > 2 * in_place


@pytest.mark.parametrize(("key", "glyphs", "surface"), [
    ("fivebar_singh", {"links", "polytope", "sphere", "force_ellipsoid", "velocity_ellipsoid"}, "force polytope"),
    ("inverse3_prototype", {"sphere", "force_ellipsoid", "velocity_ellipsoid"}, "inscribed sphere"),
])
def test_each_legend_swatch_is_the_colour_drawn(key, glyphs, surface):
    """The swatches are the colours on screen: the outlines' own colours (unlit) and the translucent
    surface's blended with the white background (one flat sheet, or a closed surface's front and
    back), each found in the rendered picture; the surface's is not its base colour."""
    _, plotter, _ = _scene(key, glyphs=frozenset(glyphs))
    try:
        rows = dict(legend_rows(plotter, load_preset(key).mechanism.joint_names))
        picture = _picture(plotter).reshape(-1, 3)
        names = {"force polytope": "polytope", "inscribed sphere": "sphere", "force ellipsoid": "force_ellipsoid",
                 "velocity ellipsoid": "velocity_ellipsoid"}
        for label, colour in rows.items():
            if label == "links":
                continue
            actor = actor_named(plotter, names[label])
            assert colour == drawn_colour(actor)
            # 8-bit rounding of the blend and of the swatch: a unit or two per channel.
            near = np.linalg.norm(picture - _rgb(colour), axis=1) <= 4.0
            assert np.count_nonzero(near) >= 100, (label, colour)
        prop = actor_named(plotter, names[surface]).GetProperty()
        layers = 1 if key == "fivebar_singh" else 2
        base = COLOURS["polytope" if surface == "force polytope" else "sphere"]
        assert rows[surface] == seen_colour(base, prop.GetOpacity(), layers) != base
    finally:
        plotter.close()


def test_the_phantoms_glyphs_are_drawn_to_its_size_and_the_caption_says_the_scale():
    preset, plotter, report = _scene("phantom_premium_15", glyphs=frozenset({"links", "sphere"}))
    mech = preset.mechanism
    try:
        scale = pose_scale(mech, report)
        caption = scenes.pose_caption(report, scale)
    finally:
        plotter.close()
    extent = float(np.max(np.ptp(scenes.to_3d(mech.link_points(report.joints)), axis=0)))
    assert report.isotropic_force * scale >= SPHERE_OVER_SIZE * extent
    assert scale > 3 * scenes.force_scale(mech)         # 5.8 mm/N before: a 9 mm sphere under 210 mm of links
    assert f"forces drawn at 10 N = {10 * scale * 1e3:.0f} mm" in caption
    # A device whose sphere is drawn large enough keeps its own scale.
    inverse3 = load_preset("inverse3_prototype")
    _, plotter, report = _scene("inverse3_prototype", glyphs=frozenset({"links", "sphere"}))
    plotter.close()
    assert pose_scale(inverse3.mechanism, report) == scenes.force_scale(inverse3.mechanism)


def test_iso_levels_are_quantiles_of_the_values_present():
    values = np.r_[np.linspace(0.0, 1.0, 901), np.full(99, 50.0), [np.nan, np.inf]]
    levels = scenes.iso_levels(values, "isotropic_force")
    finite = values[np.isfinite(values)]
    shares = [np.mean(finite <= v) for v in levels]
    # Evenly spaced in probability from the 10th to the 90th percentile, to one sample.
    np.testing.assert_allclose(shares, np.linspace(0.1, 0.9, scenes.ISO_LEVELS), atol=1.0 / finite.size)
    assert levels.max() < 1.0        # the 10 % of outliers at 50 take no level (evenly in value, two did)


def test_the_falcons_iso_surfaces_lie_at_quantiles_and_each_is_labelled():
    preset = load_preset("novint_falcon")
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution(21), ("isotropic_force",))
    plotter = _workspace_scene(preset.mechanism, wmap, "isotropic_force", size=(600, 500))
    try:
        values = scenes.box_image(wmap, "isotropic_force").point_data["isotropic_force"]
        levels = scenes.iso_levels(values, "isotropic_force")
        surfaces = plotter.actors["workspace"]
        drawn = np.unique(np.asarray(surfaces.mapper.dataset.point_data["isotropic_force"], float))
        texts = plotter.__dict__["_isoforce_iso_labels"][2].texts
        opacity = surfaces.GetProperty().GetOpacity()
        caption = scenes.box_caption(plotter)
    finally:
        plotter.close()
    finite = values[np.isfinite(values)]
    assert len(levels) == scenes.ISO_LEVELS and finite.min() < levels.min() and levels.max() < finite.max()
    np.testing.assert_allclose([np.mean(finite <= v) for v in levels], np.linspace(0.1, 0.9, len(levels)),
                               atol=1.0 / finite.size)
    np.testing.assert_allclose(drawn, levels, rtol=1e-12)                 # one surface per level
    assert texts == [f"{v:.3g} N" for v in levels]                        # and a label on each
    assert opacity == scenes.workspace.ISO_OPACITY < 0.5
    # The caption says where they sit among the values, low as they may be on the bar.
    values_text = ", ".join(f"{v:.3g}" for v in levels)
    assert f"isotropic force at {values_text} N, the 10, 37, 63, 90 % quantiles of its values" in caption


def test_a_desired_force_within_the_isotropic_force_is_one_visible_arrow():
    """Not clamped, the clamp's arrow would cover the desired one exactly (a legend row for an
    arrow no one sees): only the desired arrow is drawn, listed, and seen."""
    preset, plotter, report = _scene("inverse3_prototype", force=(3.0, 2.0, 1.0))
    try:
        assert np.linalg.norm([3.0, 2.0, 1.0]) < report.isotropic_force
        assert actor_named(plotter, "clamped_force") is None
        labels = [label for label, _ in legend_rows(plotter, preset.mechanism.joint_names)]
        assert "desired force" in labels and "clamped force" not in labels
        shown = _picture(plotter)
        actor_named(plotter, "desired_force").SetVisibility(False)
        assert np.count_nonzero(np.any(shown != _picture(plotter), axis=2)) >= 30
    finally:
        plotter.close()
