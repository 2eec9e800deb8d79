"""Paper 002's map overlays (``app.plots.overlays``): condition-number bands and ellipse fields.

The bands are checked against a classification written out by hand from the paper's words;
the ellipses' semi-axes against the boundary of the torque box's image traced point by point
(no SVD), and the drawing against those numbers at the one drawing scale.
"""
from __future__ import annotations

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import EllipseCollection
from matplotlib.figure import Figure

from app.plots import overlays
from metrics.workspace import compute_map
from resources import load_preset


@pytest.fixture(scope="module")
def fivebar():
    preset = load_preset("fivebar_singh")
    wmap = compute_map(preset.mechanism, preset.grid, ["condition_number", "isotropic_force"])   # 1 mm: singular points
    return preset, wmap


def by_hand(k: float, feasible: bool) -> int:
    """Paper 002 sec. 4.1: plus K < 5, asterisk 5 <= K <= 10, square 10 < K < 100, diamond K > 100."""
    if not feasible or np.isnan(k):
        return -1
    if k == np.inf:
        return overlays.BAND_SINGULAR
    if k < 5:
        return 0
    if k <= 10:
        return 1
    if k < 100:
        return 2
    return 3          # K > 100, and K = 100, which the paper leaves in no band


def test_bands_at_the_papers_boundaries():
    kappa = [1.0, 4.999, 5.0, 10.0, 10.001, 99.99, 100.0, 1e9, np.inf, np.nan, 2.0]
    feasible = [True] * 10 + [False]
    assert overlays.condition_bands(kappa, feasible).tolist() == [by_hand(k, f) for k, f in zip(kappa, feasible)]


def test_bands_of_a_map_match_the_hand_classification_point_by_point(fivebar):
    preset, wmap = fivebar
    kappa, feasible = wmap.values["condition_number"], wmap.feasible
    bands = overlays.condition_bands(kappa, feasible)
    # Every point of every band that occurs, plus points outside the workspace.
    rng = np.random.default_rng(0)
    picks = []
    for code in np.unique(bands):
        idx = np.argwhere(bands == code)
        picks += [tuple(i) for i in idx[rng.choice(len(idx), size=min(len(idx), 20), replace=False)]]
    assert {bands[p] for p in picks} >= {-1, 0, 1, 2, overlays.BAND_SINGULAR}      # the map has them all
    for p in picks:
        assert bands[p] == by_hand(float(kappa[p]), bool(feasible[p])), (p, kappa[p])


def test_bands_overlay_draws_each_band_and_states_its_count(fivebar):
    preset, wmap = fivebar
    fig = Figure()
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    overlay = overlays.draw_condition_bands(ax, wmap, preset.mechanism)
    bands = overlays.condition_bands(wmap.values["condition_number"], wmap.feasible)
    image = overlay["artists"][0]
    drawn = np.ma.filled(image.get_array().T.astype(int), -1)
    np.testing.assert_array_equal(drawn, np.where(bands == overlays.BAND_SINGULAR, -1, bands))
    labels = [h.get_label() for h in overlay["handles"]]
    for k, (name, _) in enumerate(overlays.BANDS):
        assert f"{name} ({np.count_nonzero(bands == k)} pts)" in labels
    singular = overlay["handles"][len(overlays.BANDS)]
    assert len(singular.get_xdata()) == np.count_nonzero(bands == overlays.BAND_SINGULAR) > 0
    # The annulus is 0.9 L .. 1.7 L of this design, L = (a1 + a2 + a3) / 3 = (100 + 150 + 30) / 3 mm.
    radii = [a.get_radius() for a in overlay["artists"] if hasattr(a, "get_radius")]
    np.testing.assert_allclose(radii, [0.9 * 280 / 3, 1.7 * 280 / 3], rtol=1e-12)
    overlays.remove_overlay(overlay)
    assert not ax.images and not ax.lines and not ax.patches


def test_no_annulus_for_a_device_that_is_not_a_five_bar():
    assert overlays.dexterous_annulus(load_preset("inverse3_prototype").mechanism) is None


def boundary_radii(A: np.ndarray, samples: int):
    """Largest and smallest |A u| over ``samples`` unit vectors u, and the u-image at the largest."""
    phi = np.linspace(0.0, 2 * np.pi, samples, endpoint=False)
    image = A @ np.stack([np.cos(phi), np.sin(phi)])          # (2, samples): the ellipse's boundary
    norms = np.linalg.norm(image, axis=0)
    return norms.max(), norms.min(), image[:, norms.argmax()] / norms.max()


@pytest.mark.parametrize("kind", overlays.ELLIPSE_KINDS)
def test_ellipse_semi_axes_are_the_boundary_of_the_torque_or_speed_box_image(fivebar, kind):
    preset, _ = fivebar
    mech = preset.mechanism
    field = overlays.ellipse_field(mech, preset.grid, 0.04, kind=kind)
    assert len(field.centres) + field.outside + field.singular == overlays.lattice_size(preset.grid, 0.04)
    assert len(field.centres) > 20
    q, ok = mech.inverse(field.centres)
    assert ok.all()
    jac = mech.jacobian(q, field.centres)
    t = mech.torque_limits()
    samples = 3600
    h = 2 * np.pi / samples
    # The sampled u nearest an extreme direction is at most h/2 from it, and there
    # |A u|^2 = r1^2 - (r1^2 - r2^2) sin^2(delta) (or r2^2 + (r1^2 - r2^2) sin^2(delta)): the sampled
    # maximum lies in [r1 sqrt(1 - s), r1] and the minimum in [r2, sqrt(r2^2 + (r1^2 - r2^2) s)],
    # s = sin^2(h/2); the image's direction at the maximum is within h/2 of the major axis.
    # (1e-12: rounding of the two computations, relative to the radii.)
    s = np.sin(h / 2) ** 2
    for k, J in enumerate(jac):
        # Force: f = J^-T diag(t) u, |u| <= 1 (the torques' unit ball); velocity: J qdot, |qdot| <= 1 rad/s.
        A = np.linalg.solve(J.T, np.diag(t)) if kind == "force" else J
        big, small, direction = boundary_radii(A, samples)
        r1, r2 = field.radii[k]
        assert r1 * np.sqrt(1 - s) * (1 - 1e-12) <= big <= r1 * (1 + 1e-12), (k, r1, big)
        assert r2 * (1 - 1e-12) <= small <= np.sqrt(r2 ** 2 + (r1 ** 2 - r2 ** 2) * s) * (1 + 1e-12), (k, r2, small)
        assert abs(direction @ field.axes[k][:, 0]) >= np.cos(h)


def test_ellipses_are_drawn_on_one_scale_with_a_key(fivebar):
    preset, wmap = fivebar
    field = overlays.ellipse_field(preset.mechanism, preset.grid, 0.03)
    fig = Figure()
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_xlim(-260, 260)
    ax.set_ylim(0, 260)
    overlay = overlays.draw_ellipse_field(ax, field)
    mm_per_n, key = overlays.ellipse_scale(field)
    (collection,) = [a for a in overlay["artists"] if isinstance(a, EllipseCollection)]
    shown = field.radii[:, 0] * mm_per_n <= field.spacing * 1e3
    np.testing.assert_allclose(collection.get_widths(), 2 * field.radii[shown, 0] * mm_per_n, rtol=1e-12)
    np.testing.assert_allclose(collection.get_heights(), 2 * field.radii[shown, 1] * mm_per_n, rtol=1e-12)
    np.testing.assert_allclose(collection.get_offsets(), field.centres[shown] * 1e3, rtol=1e-12)
    # The 90th percentile is drawn 0.45 spacing long; the key is the round value just below it.
    typical = np.percentile(field.radii[:, 0], 90)
    assert typical * mm_per_n == pytest.approx(overlays.ELLIPSE_FILL * 30.0, rel=1e-12)
    assert key <= typical < 2.5 * key
    (circle,) = [a for a in overlay["artists"] if hasattr(a, "get_radius")]
    assert circle.get_radius() == pytest.approx(key * mm_per_n, rel=1e-12)
    labels = " ".join(h.get_label() for h in overlay["handles"])
    assert f"{field.outside} lattice points outside the workspace, {field.singular} singular" in labels


def test_a_spatial_device_has_no_ellipse_field():
    preset = load_preset("inverse3_prototype")
    with pytest.raises(ValueError, match="planar device"):
        overlays.ellipse_field(preset.mechanism, preset.grid, 0.02)


def test_a_spacing_that_gives_too_many_ellipses_is_refused():
    preset = load_preset("fivebar_singh")
    with pytest.raises(ValueError, match="larger spacing"):
        overlays.ellipse_field(preset.mechanism, preset.grid, 0.001)
    with pytest.raises(ValueError, match="spacing must be a positive length"):
        overlays.ellipse_field(preset.mechanism, preset.grid, -0.01)
