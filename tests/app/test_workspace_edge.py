"""The workspace views' edge is smooth, and still puts every sample on its own side (issue 11, sec. 3:
"a smooth surface (no voxel staircase or banding)").

The edge is where a field, interpolated linearly between the samples, crosses one half. With
the 0/1 feasibility indicator every crossing is at the middle of a grid edge, so a slanted
edge is a terrace of flat and 45-degree steps; revolved (the Inverse3), each step is a ring of
light or shade. ``_edge_field`` smooths the indicator and holds every sample on its side.
"""
from __future__ import annotations

from collections import defaultdict

import numpy as np
import pytest

from app.scenes import workspace as scene_workspace
from app.scenes.slice_mesh import EDGE_MARGIN, _edge_field
from metrics.workspace import compute_map
from resources import load_preset


def _crossings(field: np.ndarray) -> np.ndarray:
    """Where ``field`` (n0, n1) crosses one half along the grid's edges, linearly: (k, 2) in sample steps."""
    points = []
    for axis in (0, 1):
        a = field if axis == 0 else field.T
        f0, f1 = a[:-1], a[1:]
        i, j = np.nonzero((f0 - 0.5) * (f1 - 0.5) < 0)
        t = (f0[i, j] - 0.5) / (f0[i, j] - f1[i, j])
        p = np.stack([i + t, j.astype(float)], axis=-1)
        points.append(p if axis == 0 else p[:, ::-1])
    return np.concatenate(points)


def _line_residual(points: np.ndarray) -> float:
    """The largest distance (steps) of ``points`` (k, 2) from their least-squares line j = a i + b."""
    design = np.column_stack([points[:, 0], np.ones(len(points))])
    coef, *_ = np.linalg.lstsq(design, points[:, 1], rcond=None)
    return float(np.max(np.abs(points[:, 1] - design @ coef)) / np.hypot(1.0, coef[0]))


@pytest.mark.parametrize("seed", range(6))
def test_every_sample_stays_on_its_side(seed):
    # Random masks have one-sample holes, spurs and cracks: none may be smoothed over.
    rng = np.random.default_rng(seed)
    ok = rng.random((23, 31)) < rng.uniform(0.3, 0.7)
    field = _edge_field(ok)
    assert np.all(field[ok] >= 0.5 + EDGE_MARGIN)
    assert np.all(field[~ok] <= 0.5 - EDGE_MARGIN)


def test_a_one_sample_hole_and_spur_are_kept():
    ok = np.zeros((9, 9), bool)
    ok[1:8, 1:5] = True
    ok[4, 2] = False            # a hole inside
    ok[4, 6] = True             # a lone sample outside
    field = _edge_field(ok)
    assert field[4, 2] < 0.5 and field[4, 6] > 0.5
    assert np.array_equal(field > 0.5, ok)


@pytest.mark.parametrize("slope", [1 / 2, 1 / 3, 1 / 5])
@pytest.mark.parametrize("offset", [20.0, 20.3, 20.77])
def test_a_slanted_edge_is_straight(slope, offset):
    # The samples of a half-plane j <= slope * i + offset; its crossings, away from the grid's border.
    i, j = np.meshgrid(np.arange(80), np.arange(80), indexing="ij")
    ok = j - slope * i - offset <= 0
    inner = lambda p: p[(p[:, 0] > 5) & (p[:, 0] < 74) & (p[:, 1] > 5) & (p[:, 1] < 74)]  # noqa: E731
    # The midpoint rule's terraces stand 0.23-0.41 steps off the line; the smoothed edge 0.005-0.09
    # (measured for these slopes). In between, with room on both sides.
    assert _line_residual(inner(_crossings(ok.astype(float)))) > 0.2
    assert _line_residual(inner(_crossings(_edge_field(ok)))) < 0.12


def _mean_turn_degrees(volume) -> float:
    """The mean angle (degrees) the outline of a flat picture turns at each of its vertices."""
    edges = volume.extract_surface(algorithm=None).extract_feature_edges(
        boundary_edges=True, feature_edges=False, manifold_edges=False, non_manifold_edges=False)
    neighbours = defaultdict(list)
    for a, b in edges.lines.reshape(-1, 3)[:, 1:]:
        neighbours[a].append(b)
        neighbours[b].append(a)
    turns = []
    for v, ends in neighbours.items():
        if len(ends) == 2:
            u, w = edges.points[v] - edges.points[ends[0]], edges.points[ends[1]] - edges.points[v]
            cos = np.dot(u, w) / (np.linalg.norm(u) * np.linalg.norm(w))
            turns.append(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
    return float(np.mean(turns))


@pytest.mark.parametrize("key, quantity", [("fivebar_singh", "condition_number"),
                                           ("phantom_premium_15", "isotropic_force")])
def test_the_flat_workspace_picture_has_a_smooth_outline(key, quantity, monkeypatch):
    preset = load_preset(key)
    grid = preset.grid.with_resolution((81,) * len(preset.grid.resolution))
    wmap = compute_map(preset.mechanism, grid, (quantity,))
    smooth = _mean_turn_degrees(scene_workspace.workspace_volume(wmap, quantity, preset.mechanism))
    monkeypatch.setattr(scene_workspace, "_edge_field", lambda ok: ok.astype(float))   # the 0/1 indicator
    terraced = _mean_turn_degrees(scene_workspace.workspace_volume(wmap, quantity, preset.mechanism))
    # Measured: 4.7 and 5.2 degrees per vertex against 17.8 and 17.3 for the terraces (whose
    # steps turn by 45 degrees). A smooth closed outline of ~300 vertices turns ~1.2 degrees
    # per vertex, plus the workspace's own corners.
    assert terraced > 15.0
    assert smooth < 8.0


@pytest.mark.parametrize("seed", range(6))
def test_class_picture_corners_keep_their_side(seed):
    from app.scenes.classes import _corner_field, _corner_mean

    rng = np.random.default_rng(100 + seed)
    ok = rng.random((19, 27)) < rng.uniform(0.3, 0.7)
    share = _corner_mean(ok.astype(float))       # of four samples: 0, 1/4, 1/2, 3/4 or 1
    field = _corner_field(ok)
    # A corner with three or four classed samples around it stays inside (a classed sample's
    # whole cell is drawn, a hole's cell is whole for the centred rule), none or one outside.
    assert np.all(field[share > 0.5] >= 0.5 + EDGE_MARGIN)
    assert np.all(field[share < 0.5] <= 0.5 - EDGE_MARGIN)


def _outline_roughness(volume, step: float) -> float:
    """RMS distance (in grid steps) of a flat picture's outline from its own moving average.

    Each closed outline is resampled every quarter step along its length; a point's moving
    average is the mean of the points within two steps either side. A terrace of steps stands
    off that average by a fraction of a step all along the edge; a smooth outline only at the
    workspace's real corners.
    """
    edges = volume.extract_surface(algorithm=None).extract_feature_edges(
        boundary_edges=True, feature_edges=False, manifold_edges=False, non_manifold_edges=False).clean(tolerance=1e-12)
    neighbours = defaultdict(list)
    for a, b in edges.lines.reshape(-1, 3)[:, 1:]:
        neighbours[a].append(b)
        neighbours[b].append(a)
    seen, deviations = set(), []
    for start in neighbours:
        if start in seen or len(neighbours[start]) != 2:
            continue
        loop, previous, current = [start], start, neighbours[start][0]
        seen.add(start)
        while current != start and current not in seen and len(neighbours[current]) == 2:
            loop.append(current)
            seen.add(current)
            ahead = neighbours[current]
            previous, current = current, ahead[0] if ahead[0] != previous else ahead[1]
        if current != start:
            continue                                    # an open chain: not an outline
        points = edges.points[loop + [start]]
        along = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))]
        t = np.arange(0.0, along[-1], step / 4)
        curve = np.column_stack([np.interp(t, along, points[:, k]) for k in range(3)])
        window = (np.arange(len(curve))[:, None] + np.arange(-8, 9)[None]) % len(curve)
        deviations.append(np.linalg.norm(curve - curve[window].mean(axis=1), axis=1))
    return float(np.sqrt(np.mean(np.concatenate(deviations) ** 2)) / step)


@pytest.mark.parametrize("key, quantity", [("fivebar_singh", "bottleneck"), ("fivebar_singh", "isotropic_force"),
                                           ("phantom_premium_15", "bottleneck"),
                                           ("phantom_premium_15", "isotropic_force")])
def test_flat_pictures_outline_is_smoother_than_the_plain_cut(key, quantity, monkeypatch):
    from app.scenes import classes
    from app.scenes.classes import _corner_mean

    preset = load_preset(key)
    grid = preset.grid.with_resolution((81, 81))
    step = (grid.upper[0] - grid.lower[0]) / 80
    wmap = compute_map(preset.mechanism, grid, (quantity,))
    smooth = _outline_roughness(scene_workspace.workspace_volume(wmap, quantity, preset.mechanism), step)
    # The plain cuts: the 0/1 indicator (magnitudes), the share of classed samples (classes).
    monkeypatch.setattr(scene_workspace, "_edge_field", lambda ok: ok.astype(float))
    monkeypatch.setattr(classes, "_corner_field", lambda ok: _corner_mean(ok.astype(float)))
    plain = _outline_roughness(scene_workspace.workspace_volume(wmap, quantity, preset.mechanism), step)
    # Measured (steps), five-bar then PHANToM: classes 0.121 against 0.143 and 0.092 against 0.121;
    # magnitudes 0.117 against 0.172 and 0.101 against 0.192. The workspaces' real corners are in both.
    assert smooth < 0.9 * plain
