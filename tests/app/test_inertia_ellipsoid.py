"""The pose view's inertia ellipsoid (issue 22 sec. 5): its semi-axes are the apparent masses along
the principal directions of ``((Lambda^-1)_tt)^-1``, drawn at ``scenes.inertia_scale`` m/kg, computed
only when shown, offered only with a mass model, and in exported pose figures."""
from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET

import matplotlib
import numpy as np
import pytest

from app import scenes
from app.cli import main
from app.logic.glyphs import DEFAULT_GLYPHS, GLYPHS, glyph_unavailable, pose_parts
from app.render.views import _pose_scene, pose_plotter
from app.scenes.common import actor_named
from metrics.ellipsoids import Ellipsoid
from metrics.pose import analyse_pose
from metrics.wrenches import force_rows
from resources import load_preset
from tests.preset_files import massless_omni

WITH = DEFAULT_GLYPHS | {"inertia_ellipsoid"}


def apparent_mass_axes(mechanism, x) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (kg, descending) and eigenvectors of the apparent-mass matrix
    ``((Lambda^-1)_tt)^-1``, from the mechanism's ``task_inertia`` by plain inverses."""
    x = np.asarray(x, float)
    q, ok = mechanism.inverse(x[None])
    assert ok[0]
    lam = mechanism.task_inertia(q, x[None])[0]
    rows = list(force_rows(mechanism))
    block = np.linalg.inv(lam)[np.ix_(rows, rows)]
    masses, axes = np.linalg.eigh(np.linalg.inv(block))
    return masses[::-1], axes[:, ::-1]


@pytest.mark.parametrize("key", ["phantom_premium_15", "fivebar_singh", "stewart_platform", "inverse3_prototype"])
def test_the_drawn_ellipsoid_is_the_apparent_mass_matrix_times_the_scale(key):
    preset = load_preset(key)
    mech = preset.mechanism
    masses, axes = apparent_mass_axes(mech, preset.pose)
    plotter, report = _pose_scene(mech, preset.pose, glyphs=WITH, size=(400, 300))
    try:
        mesh = actor_named(plotter, "inertia_ellipsoid").mapper.dataset
        points = np.asarray(mesh.points, float)
        assert ("inertia ellipsoid", scenes.COLOURS["inertia_ellipsoid"]) in scenes.legend_rows(
            plotter, mech.joint_names)
    finally:
        plotter.close()
    np.testing.assert_allclose(report.inertia_ellipsoid.radii, masses, rtol=1e-9)
    scale = scenes.inertia_scale(mech)
    k = len(masses)
    centre = scenes.to_3d(np.asarray(preset.pose, float)[list(force_rows(mech))])[0]
    offsets = (points - centre)[:, :k]
    if k == 2:
        assert np.allclose(points[:, 2], 0.0)
    # Every point of the drawn surface on {p : p^T V diag(1 / (s m)^2) V^T p = 1}: the ellipsoid with
    # semi-axes s m_i along v_i (a quadric through a closed surface of points is determined by them).
    form = axes @ np.diag(1.0 / (scale * masses) ** 2) @ axes.T
    # (VTK keeps the points in float32.)
    np.testing.assert_allclose(np.einsum("pi,ij,pj->p", offsets, form, offsets), 1.0, rtol=1e-5)
    # Its extent along each principal axis is the scaled mass.
    along = offsets @ axes
    np.testing.assert_allclose(np.max(np.abs(along), axis=0), scale * masses, rtol=0.01)


def test_the_ellipsoid_is_computed_only_when_shown(monkeypatch):
    preset = load_preset("phantom_premium_15")
    mech = preset.mechanism
    calls = []
    for name in ("mass_matrix", "task_inertia"):
        original = getattr(type(mech), name)

        def counted(self, *a, _original=original, **k):
            calls.append(1)
            return _original(self, *a, **k)
        monkeypatch.setattr(type(mech), name, counted)
    hidden = analyse_pose(mech, preset.pose, parts=pose_parts(DEFAULT_GLYPHS | {"force_ellipsoid"}))
    assert hidden.inertia_ellipsoid is None and not calls
    shown = analyse_pose(mech, preset.pose, parts=pose_parts(WITH))
    assert shown.inertia_ellipsoid is not None and calls



def test_only_devices_with_a_mass_model_offer_it(tmp_path):
    omni = load_preset(massless_omni(tmp_path))
    assert not omni.mechanism.has_mass_model
    problem = glyph_unavailable("inertia_ellipsoid", omni.mechanism)
    assert problem and "mass model" in problem
    assert glyph_unavailable("inertia_ellipsoid", load_preset("phantom_premium_15").mechanism) is None
    assert all(glyph_unavailable(g, omni.mechanism) is None for g in GLYPHS if g != "inertia_ellipsoid")
    # Asked for anyway (the API): nothing computed, nothing drawn, nothing said.
    plotter, report = pose_plotter(omni.mechanism, omni.pose, glyphs=WITH)
    try:
        assert report.inertia_ellipsoid is None
        assert not scenes.glyph_drawn(plotter, "inertia_ellipsoid")
        assert "inertia" not in plotter.actors["pose_caption"].get_text(1)
    finally:
        plotter.close()


def test_its_colour_is_no_other_glyphs():
    colour = scenes.COLOURS["inertia_ellipsoid"].lower()
    others = [c.lower() for k, c in scenes.COLOURS.items() if k != "inertia_ellipsoid"]
    assert colour not in others + [c.lower() for c in scenes.ACTUATOR_COLOURS]


def test_the_caption_gives_its_scale_or_the_direction_it_cannot_move_in():
    preset = load_preset("inverse3_prototype")
    mech = preset.mechanism
    for glyphs, said in ((DEFAULT_GLYPHS, False), (WITH, True)):
        plotter, _ = pose_plotter(mech, preset.pose, glyphs=glyphs)
        try:
            caption = plotter.actors["pose_caption"].get_text(1)
        finally:
            plotter.close()
        mm = 0.1 * scenes.inertia_scale(mech) * 1e3
        assert (f"inertia ellipsoid at 0.1 kg = {mm:.3g} mm" in caption) == said, caption
    # An inverse singularity: an infinite apparent mass is said with its direction, never drawn.
    report = analyse_pose(mech, preset.pose, parts=pose_parts(WITH))
    singular = dataclasses.replace(report, inertia_ellipsoid=Ellipsoid(radii=np.array([np.inf, 0.08, 0.05]),
                                                                       axes=np.eye(3)))
    plotter, _ = _pose_scene(mech, preset.pose, glyphs=WITH, size=(400, 300))
    try:
        assert scenes.glyph_drawn(plotter, "inertia_ellipsoid")
        scenes.draw_pose_scene(plotter, mech, singular, WITH, np.zeros(3), scenes.pose_scale(mech, singular))
        assert not scenes.glyph_drawn(plotter, "inertia_ellipsoid")
        assert "inertia ellipsoid" not in dict(scenes.legend_rows(plotter, mech.joint_names))
        text = scenes.inertia_text(plotter, mech, singular, WITH)
    finally:
        plotter.close()
    assert "infinite along (+1.00, +0.00, +0.00)" in text and "0.08, 0.05 kg" in text, text
    assert "infinite" in scenes.pose_caption(singular, 1e-3, None, text)


def test_an_exported_pose_figure_draws_it_with_its_legend_and_scale(capsys, tmp_path, monkeypatch):
    monkeypatch.setitem(matplotlib.rcParams, "svg.fonttype", "none")
    out = tmp_path / "pose.svg"
    capsys.readouterr()
    status = main(["figure", "phantom_premium_15", "--view", "pose", "--glyphs", "links,inertia_ellipsoid",
                   "--size", "800x600", "--out", str(out)])
    assert status == 0, capsys.readouterr().err
    text = " ".join(" ".join(el.itertext()) for el in ET.parse(out).iter() if el.tag.endswith("text"))
    text = " ".join(text.split())
    assert "inertia ellipsoid" in text and "inertia ellipsoid at 0.1 kg = 25 mm" in text, text
    capsys.readouterr()
    status = main(["figure", massless_omni(tmp_path), "--view", "pose", "--glyphs", "links,inertia_ellipsoid",
                   "--out", str(tmp_path / "omni.png")])
    err = capsys.readouterr().err
    assert status == 2 and "--glyphs inertia_ellipsoid" in err and "no mass model" in err, err
    assert not (tmp_path / "omni.png").exists()
