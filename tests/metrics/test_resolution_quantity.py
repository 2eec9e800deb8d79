"""The ``spatial_resolution`` / ``angular_resolution`` / ``axis_resolution`` quantities against real encoder
steps through the forward kinematics, and where they apply."""
from __future__ import annotations

import numpy as np
import pytest

from metrics.quantities import available_quantities, evaluate, summary_quantities
from metrics.resolution import mechanism_steps
from resources import load_preset


def _feasible_points(preset, count, seed):
    mech = preset.mechanism
    rng = np.random.default_rng(seed)
    pts = preset.grid.points(mech.task_names).reshape(-1, mech.task_dim)
    q, ok = mech.inverse(pts)
    good = np.flatnonzero(ok & mech.feasible(q, pts))
    return pts[rng.choice(good, count, replace=False)]


def test_inverse3_resolution_is_one_encoder_count_through_the_forward_kinematics():
    preset = load_preset("inverse3_prototype")
    mech = preset.mechanism
    pts = _feasible_points(preset, 25, 3)
    ev = evaluate(mech, pts, ("spatial_resolution", "axis_resolution")).values
    steps = mechanism_steps(mech)
    assert steps.tolist() == pytest.approx(np.radians([0.0256, 0.0339, 0.0339]).tolist(), rel=1e-15)
    q, _ = mech.inverse(pts)
    moves = []
    for u in range(3):
        dq = np.zeros(3)
        dq[u] = steps[u]
        plus, _ = mech.forward(q + dq)
        minus, _ = mech.forward(q - dq)
        moves.append(0.5 * (plus - minus))       # J e_u delta_u + O(delta^3)
    moves = np.stack(moves, axis=-1)             # (k, 3 task, 3 joints)
    want_overall = np.max(np.linalg.norm(moves, axis=-2), axis=-1)
    want_axis = np.max(np.abs(moves), axis=-1)
    # The symmetric step's error is |x'''| delta^3 / 6 <= 1 m * (6e-4)^3 / 6 < 1e-10 m, and FK's rounding
    # eps |x| / delta ~ 1e-16 * 0.5 / 6e-4 < 1e-12 m: both far below the 1e-5 m values.
    assert ev["spatial_resolution"] == pytest.approx(want_overall, abs=1e-10)
    assert ev["axis_resolution"] == pytest.approx(want_axis, abs=1e-10)


def test_pen_resolution_keeps_metres_and_radians_apart():
    preset = load_preset("twin_pantograph_prototype")
    mech = preset.mechanism
    pts = np.array([preset.pose])
    ev = evaluate(mech, pts, ("spatial_resolution", "angular_resolution", "jacobian")).values
    jac = ev["jacobian"][0]
    steps = mechanism_steps(mech)
    assert ev["spatial_resolution"][0] == pytest.approx(np.max(np.linalg.norm(jac[:3], axis=0) * steps), rel=1e-14)
    assert ev["angular_resolution"][0] == pytest.approx(np.max(np.linalg.norm(jac[3:], axis=0) * steps), rel=1e-14)


def test_resolution_applies_only_where_sensors_are_modelled():
    five = load_preset("fivebar_singh").mechanism
    assert "spatial_resolution" not in available_quantities(five)
    assert "spatial_resolution" not in summary_quantities(five)
    inv3 = load_preset("inverse3_prototype").mechanism
    assert "spatial_resolution" in summary_quantities(inv3) and "angular_resolution" not in summary_quantities(inv3)
    twin = load_preset("twin_pantograph").mechanism
    assert {"spatial_resolution", "angular_resolution"} <= set(summary_quantities(twin))


def test_resolution_is_unbounded_next_to_a_direct_singularity_the_workspace_reaches():
    # The Falcon's feasible set crosses its coplanar-bars surface (a direct singularity, kinematics.delta):
    # there J -> inf, so one sensor count stands for an unbounded move.
    from metrics.workspace import compute_map

    preset = load_preset("novint_falcon")
    mech = preset.mechanism
    direct = mech.singular_loci().get("direct", np.empty((0, 3)))
    assert len(direct)
    wmap = compute_map(mech, preset.grid.with_resolution(21), ("spatial_resolution",), keep=False)
    assert wmap.stats["spatial_resolution"].unbounded
    # Approaching a direct locus point along the line from a regular feasible point, the resolution grows
    # without bound: it at least doubles between 1e-3 and 1e-5 of the way from the locus.
    p = direct[0]
    start = np.array(preset.pose)
    values = []
    for gap in (1e-3, 1e-5):
        x = p + gap * (start - p)
        values.append(evaluate(mech, x[None], ("spatial_resolution",)).values["spatial_resolution"][0])
    assert np.all(np.isfinite(values)) and values[1] > 2 * values[0]
