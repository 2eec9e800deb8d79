"""Workspace maps: grid validation and layout, map values and statistics, threads, progress,
cancellation. Headless: numpy only.
"""
from __future__ import annotations

import threading

import numpy as np
import pytest

from kinematics import FiveBar, Inverse3
from metrics import map_chunks
from metrics.quantities import evaluate
from metrics.workspace import Cancelled, GridSpec, compute_map

C = Inverse3().params.plane_offset
SLICE = GridSpec(("x", "z"), (-0.05, -0.15), (0.35, 0.5), (41, 53), (("y", C),))


# -- GridSpec -------------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, pattern", [
    (dict(axes=("x",), lower=(0.0,), upper=(1.0,), resolution=(3,)), r"a grid varies 2 or 3 coordinates"),
    (dict(axes=("x", "y", "z", "w"), lower=(0,) * 4, upper=(1,) * 4, resolution=(3,) * 4), r"2 or 3"),
    (dict(axes=("x", "z"), lower=(0.0,), upper=(1.0, 1.0), resolution=(3, 3)), r"lower needs 2 values"),
    (dict(axes=("x", "z"), lower=(0.0, 0.0), upper=(1.0,), resolution=(3, 3)), r"upper needs 2 values"),
    (dict(axes=("x", "z"), lower=(0.0, 0.0), upper=(1.0, 1.0), resolution=(3,)), r"resolution needs 2 values"),
    (dict(axes=("x", "z"), lower=(0.0, 1.0), upper=(1.0, 1.0), resolution=(3, 3)),
     r"range of axis 'z' must be finite with lower < upper, got \[1.0, 1.0\]"),
    (dict(axes=("x", "z"), lower=(2.0, 0.0), upper=(1.0, 1.0), resolution=(3, 3)), r"range of axis 'x'"),
    (dict(axes=("x", "z"), lower=(float("nan"), 0.0), upper=(1.0, 1.0), resolution=(3, 3)), r"range of axis 'x'"),
    (dict(axes=("x", "z"), lower=(0.0, 0.0), upper=(1.0, float("inf")), resolution=(3, 3)), r"range of axis 'z'"),
    (dict(axes=("x", "z"), lower=(0.0, 0.0), upper=(1.0, 1.0), resolution=(3, 1)),
     r"resolution of axis 'z' must be an integer >= 2, got 1"),
    (dict(axes=("x", "z"), lower=(0.0, 0.0), upper=(1.0, 1.0), resolution=(2.5, 3)), r"resolution of axis 'x'"),
])
def test_gridspec_validation_names_the_problem(kwargs, pattern):
    with pytest.raises(ValueError, match=pattern):
        GridSpec(**kwargs)


def test_points_layout_is_ij_with_fixed_coordinates():
    pts = SLICE.points(("x", "y", "z"))
    assert pts.shape == (41, 53, 3)
    xs, zs = np.linspace(-0.05, 0.35, 41), np.linspace(-0.15, 0.5, 53)
    np.testing.assert_array_equal(pts[:, :, 0], np.broadcast_to(xs[:, None], (41, 53)))
    np.testing.assert_array_equal(pts[:, :, 1], C)
    np.testing.assert_array_equal(pts[:, :, 2], np.broadcast_to(zs[None, :], (41, 53)))
    # Endpoints are included, spacing as documented.
    assert pts[0, 0, 0] == -0.05 and pts[-1, -1, 2] == 0.5
    assert SLICE.spacing() == pytest.approx((0.4 / 40, 0.65 / 52), rel=1e-14)
    # Swapping the axes transposes the layout.
    swapped = GridSpec(("z", "x"), (-0.15, -0.05), (0.5, 0.35), (53, 41), (("y", C),)).points(("x", "y", "z"))
    np.testing.assert_array_equal(swapped, np.swapaxes(pts, 0, 1))
    # Flat indices and slices pick the same points in C order.
    flat = pts.reshape(-1, 3)
    np.testing.assert_array_equal(SLICE.points(("x", "y", "z"), np.array([0, 7, 53, 2172])), flat[[0, 7, 53, 2172]])
    np.testing.assert_array_equal(SLICE.points(("x", "y", "z"), slice(100, 260)), flat[100:260])


def test_points_of_a_volume_and_missing_coordinates():
    vol = GridSpec(("x", "y", "z"), (0.0, -0.1, 0.1), (0.2, 0.1, 0.3), (3, 4, 5))
    pts = vol.points(("x", "y", "z"))
    assert pts.shape == (3, 4, 5, 3)
    np.testing.assert_array_equal(pts[2, 1, 3], [0.2, np.linspace(-0.1, 0.1, 4)[1], np.linspace(0.1, 0.3, 5)[3]])
    with pytest.raises(ValueError, match="grid has no value for task coordinate 'y'"):
        GridSpec(("x", "z"), (0.0, 0.0), (1.0, 1.0), (3, 3)).points(("x", "y", "z"))
    finer = SLICE.with_resolution(7)
    assert finer.resolution == (7, 7) and finer.fixed == SLICE.fixed and finer.lower == SLICE.lower
    assert SLICE.with_resolution((5, 9)).resolution == (5, 9)


# -- compute_map ------------------------------------------------------------------------------
NAMES = ("condition_number", "isotropic_force", "anisotropic_force", "bottleneck")


@pytest.fixture(scope="module")
def inverse3_map():
    return compute_map(Inverse3(), SLICE, NAMES, threads=False)


def test_map_values_equal_evaluate_on_the_grid_points(inverse3_map):
    wmap = inverse3_map
    pts = SLICE.points(("x", "y", "z"))
    ev = evaluate(Inverse3(), pts, NAMES)
    np.testing.assert_array_equal(wmap.feasible, ev.feasible)
    assert set(wmap.values) == set(NAMES)
    for name in NAMES:
        assert wmap.values[name].shape == (41, 53)
        np.testing.assert_array_equal(wmap.values[name], ev.values[name], err_msg=name)
    np.testing.assert_array_equal(wmap.points, pts)
    assert wmap.feasible_points == int(ev.feasible.sum())
    assert 100 < wmap.feasible_points < 41 * 53
    assert {"joints", "jacobian", "column_norms", "reference_forces"} <= set(wmap.computed)
    assert "singular_values" in wmap.computed and "force_ellipsoid_min_radius" not in wmap.computed


def test_map_statistics_equal_numpy_on_the_feasible_values(inverse3_map):
    wmap = inverse3_map
    pts = SLICE.points(("x", "y", "z"))
    assert set(wmap.stats) == {"condition_number", "isotropic_force", "anisotropic_force"}   # not categorical
    for name, st in wmap.stats.items():
        v = wmap.values[name][wmap.feasible]
        p = pts[wmap.feasible]
        assert np.all(np.isfinite(v))
        assert st.count == v.size == wmap.feasible_points
        assert st.min == v.min() and st.max == v.max()
        assert st.mean == pytest.approx(np.mean(v), rel=1e-13)
        assert st.sd == pytest.approx(np.std(v, ddof=1), rel=1e-12)
        assert st.sd != pytest.approx(np.std(v, ddof=0), rel=1e-6)          # ddof = 1, not 0
        np.testing.assert_array_equal(st.argmin, p[np.argmin(v)])
        np.testing.assert_array_equal(st.argmax, p[np.argmax(v)])
        assert st.as_dict(1e3)["argmin"] == pytest.approx([c * 1e3 for c in p[np.argmin(v)]], rel=1e-15)


def test_statistics_of_an_empty_map():
    grid = GridSpec(("x", "z"), (1.0, 1.0), (1.2, 1.2), (4, 4), (("y", 0.0),))     # out of reach
    wmap = compute_map(Inverse3(), grid, ["isotropic_force"], threads=False)
    assert wmap.feasible_points == 0
    st = wmap.stats["isotropic_force"]
    assert st.count == 0 and np.isnan(st.min) and np.isnan(st.mean) and np.isnan(st.sd)
    assert np.all(np.isnan(wmap.values["isotropic_force"]))


@pytest.mark.parametrize("mech, grid, names", [
    (Inverse3(), SLICE.with_resolution((61, 67)), NAMES),
    (FiveBar(), GridSpec(("x", "y"), (-0.25, -0.2), (0.25, 0.27), (59, 71)),
     ("condition_number", "isotropic_force", "singularity", "manipulability")),
])
def test_threads_give_exactly_the_same_map(monkeypatch, mech, grid, names):
    monkeypatch.setattr(map_chunks, "MIN_CHUNK", 700)      # chunk size independent of the CPU count
    monkeypatch.setattr(map_chunks, "CHUNK", 700)
    seen = []
    serial = compute_map(mech, grid, names, threads=False, progress=seen.append)
    assert len(seen) > 3                                                   # really chunked
    threaded = compute_map(mech, grid, names, threads=True)
    np.testing.assert_array_equal(threaded.feasible, serial.feasible)
    for name in names:
        np.testing.assert_array_equal(threaded.values[name], serial.values[name], err_msg=name)
    assert threaded.stats == serial.stats
    # ... and the same as one unchunked map.
    monkeypatch.setattr(map_chunks, "CHUNK", 10 ** 7)
    whole = compute_map(mech, grid, names, threads=False)
    for name in names:
        np.testing.assert_array_equal(whole.values[name], serial.values[name], err_msg=name)


def test_a_streamed_maps_statistics_do_not_depend_on_the_cores(monkeypatch):
    """The default chunking (no chunk size patched): a platform's map (its statistics summed per
    chunk in numpy) of 10,000 points gives the same bits with threads off and on 1, 2, 3 and 8 cores.
    Chunks that followed the core count gave its means another last bit with threads off."""
    from app.cli.stats import summary_quantities
    from resources import load_preset

    preset = load_preset("stewart_platform")
    mech, grid = preset.mechanism, preset.grid.with_resolution((100, 100))
    names = summary_quantities(mech)
    serial = compute_map(mech, grid, names, keep=False, threads=False)
    assert 100 * 100 > 2 * map_chunks.MIN_CHUNK and serial.feasible_points > 1000      # chunked, feasible
    map_chunks.chunk_pool()         # made now with the machine's workers, not a patched count's
    for cores in (1, 2, 3, 8):
        monkeypatch.setattr(map_chunks.os, "cpu_count", lambda cores=cores: cores)
        assert compute_map(mech, grid, names, keep=False, threads=True).stats == serial.stats, cores


@pytest.mark.parametrize("threads", [False, True])
def test_progress_rises_to_one(monkeypatch, threads):
    monkeypatch.setattr(map_chunks, "MIN_CHUNK", 512)      # chunk size independent of the CPU count
    monkeypatch.setattr(map_chunks, "CHUNK", 512)
    seen = []
    lock = threading.Lock()

    def progress(fraction):
        with lock:
            seen.append(fraction)

    grid = SLICE.with_resolution((40, 50))
    compute_map(Inverse3(), grid, ["isotropic_force"], threads=threads, progress=progress)
    assert len(seen) == -(-2000 // 512)
    assert seen[-1] == 1.0
    assert all(b > a for a, b in zip(seen, seen[1:]))
    assert seen[0] == pytest.approx(512 / 2000)


@pytest.mark.parametrize("threads", [False, True])
def test_cancelled_raises(monkeypatch, threads):
    monkeypatch.setattr(map_chunks, "MIN_CHUNK", 512)      # chunk size independent of the CPU count
    monkeypatch.setattr(map_chunks, "CHUNK", 512)
    seen = []
    with pytest.raises(Cancelled):
        compute_map(Inverse3(), SLICE, ["isotropic_force"], threads=threads, progress=seen.append,
                    cancelled=lambda: True)
    assert seen == []
    # Cancelled after the first chunk (serially): the map stops early.
    calls = []

    def after_first():
        calls.append(1)
        return len(calls) > 1

    seen.clear()
    with pytest.raises(Cancelled):
        compute_map(Inverse3(), SLICE, ["isotropic_force"], threads=False, progress=seen.append,
                    cancelled=after_first)
    assert len(seen) == 1 and seen[0] < 1.0
    assert issubclass(Cancelled, Exception)


def test_compute_map_rejects_unknown_quantities():
    with pytest.raises(ValueError, match="unknown quantity 'colour'"):
        compute_map(Inverse3(), SLICE, ["isotropic_force", "colour"])
    with pytest.raises(ValueError, match="unknown quantity 'singularity'"):
        compute_map(Inverse3(), SLICE, ["singularity"])


def test_a_kept_compiled_chunk_holds_the_values_the_filling_kernel_writes():
    """A chunk's kernel leaves the values of the points that are not feasible unwritten and a kept map
    puts ``nan`` there in the requested rows (``ChunkWork._compiled_values``): the same bits as the
    kernel that fills every row (``quantities.compiled_evaluate``), on feasible, infeasible and handed-back
    (non-finite) points."""
    from metrics.map_chunks import ChunkWork
    from metrics.quantities import compiled_evaluate

    grid = SLICE.with_resolution((61, 67))
    work = ChunkWork.plan(Inverse3(), grid, ("condition_number", "anisotropic_force", "isotropic_force"), keep=True,
                          threads=False)
    assert work.kernel is not None
    points = grid.points(work.mechanism.task_names).reshape(-1, 3).copy()
    points[::97] = np.nan                   # handed back to the numpy path
    _, ev, *_ = work.at(np.arange(len(points)), points)
    ref = compiled_evaluate(work.kernel, points, work.request, work.loading, threads=False)
    assert 0 < np.count_nonzero(ref.feasible) < len(points)
    np.testing.assert_array_equal(ev.feasible, ref.feasible)
    for name in work.request:
        assert ev.values[name].tobytes() == ref.values[name].tobytes(), name     # nan's bits too


@pytest.mark.parametrize("mech, grid, names", [
    (FiveBar(), GridSpec(("x", "y"), (-0.25, -0.2), (0.25, 0.27), (159, 171)),
     ("condition_number", "isotropic_force", "singularity")),
    (Inverse3(), SLICE.with_resolution((61, 67)), NAMES),
])
def test_a_map_of_its_extremes_alone_has_the_whole_map_s_extremes_arrays_and_errors(mech, grid, names):
    """``compute_map(figures="extremes")``: every array, and the figures a legend shows (the extremes,
    where, whether unbounded or vanishing, their resolution errors and orders, the counts and singular
    points) are the whole map's, bit for bit, with threads on and off, whatever its spans (they follow
    the cores: ``map_chunks.worker_chunk``); the mean, SD, quantiles and GCI are not taken (``nan``)."""
    whole = compute_map(mech, grid, names, threads=False)
    for threads in (False, True):
        part = compute_map(mech, grid, names, threads=threads, figures="extremes")
        assert part.feasible.tobytes() == whole.feasible.tobytes()
        assert part.singular.tobytes() == whole.singular.tobytes()
        for name in names:
            assert part.values[name].tobytes() == whole.values[name].tobytes(), name
        assert part.stats.keys() == whole.stats.keys() and part.gci is None
        for q, s in whole.stats.items():
            kept = {k: v for k, v in vars(s).items() if k not in ("mean", "sd", "median", "p05", "p95")}
            assert {k: v for k, v in vars(part.stats[q]).items() if k in kept} == kept, q
            assert all(np.isnan(getattr(part.stats[q], k)) for k in ("mean", "sd", "median", "p05", "p95")), q
            for figs, mine in ((whole.errors[q], part.errors[q]), (whole.error_orders[q], part.error_orders[q])):
                assert mine.keys() == figs.keys()
                assert np.array_equal([mine[k] for k in ("min", "max")], [figs[k] for k in ("min", "max")],
                                      equal_nan=True), q
                assert all(np.isnan(v) for k, v in mine.items() if k not in ("min", "max")), q
    with pytest.raises(ValueError, match="figures"):
        compute_map(mech, grid, names, figures="median")

