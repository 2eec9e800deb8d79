"""Memory estimates before a job starts (metrics.budget): exact counts, bytes checked against
the arrays the compute layer really makes, refusals that say what to do."""
from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from metrics import budget
from metrics.budget import BudgetError, check_fits, check_map, grid_points, map_estimate, quantity_bytes
from metrics.quantities import CORE_QUANTITIES, MAP_QUANTITIES, QUANTITIES, check_quantities, evaluate
from metrics.workspace import compute_map
from resources import list_presets, load_preset

GiB = 1 << 30


def test_grid_points_are_exact_where_np_prod_overflows():
    # 2**32 points per axis: np.prod wraps int64 to 0, the true count is 2**64.
    res = (4294967296, 4294967296)
    assert int(np.prod(np.array(res, dtype=np.int64))) == 0      # the overflow this replaces
    assert grid_points(res) == 2 ** 64
    assert grid_points((3, 5, 7)) == 105
    with pytest.raises(ValueError, match="resolution"):
        grid_points((3, 0))
    with pytest.raises(ValueError, match="resolution"):
        grid_points((3, 2.5))


@pytest.mark.parametrize("key", list_presets())
def test_quantity_bytes_equal_the_arrays_evaluate_returns(key):
    """The per-point bytes of each quantity are those of the array ``evaluate`` returns for it."""
    preset = load_preset(key)
    mech = preset.mechanism
    pts = preset.grid.with_resolution(5).points(mech.task_names).reshape(-1, mech.task_dim)
    names = []
    for q in QUANTITIES:
        try:
            check_quantities(mech, [q])
        except ValueError:
            continue            # not defined for this device
        names.append(q)
    ev = evaluate(mech, pts, names)
    for q in names:
        assert ev.values[q].nbytes == len(pts) * quantity_bytes(mech, q), q


def test_map_estimate_grows_with_points_only_when_maps_are_kept():
    mech = load_preset("fivebar_singh").mechanism
    small, large = (map_estimate(mech, (n, n), CORE_QUANTITIES) for n in (1000, 2000))
    per_point = 1 + 3 * 8 + budget.STATS_BYTES           # mask, three floats, statistics temporaries
    assert small.per_point == large.per_point == per_point
    assert large.bytes - small.bytes == 3_000_000 * per_point
    streamed = [map_estimate(mech, (n, n), CORE_QUANTITIES, keep_maps=False) for n in (1000, 8000, 10 ** 6)]
    assert {e.bytes for e in streamed} == {streamed[0].bytes}       # by chunk: resolution-free
    assert streamed[-1].points == 10 ** 12
    assert streamed[0].bytes < 1 * GiB


def test_estimate_bounds_the_peak_allocation_of_a_kept_map():
    """tracemalloc sees numpy's allocations: the estimate must not be below the real peak."""
    mech = load_preset("inverse3_prototype").mechanism
    grid = load_preset("inverse3_prototype").grid.with_resolution(400)
    est = map_estimate(mech, grid.resolution, CORE_QUANTITIES)
    tracemalloc.start()
    try:
        wmap = compute_map(mech, grid, CORE_QUANTITIES)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert wmap.feasible_points > 0
    assert peak <= est.bytes, (peak, est.bytes)


def test_refusal_names_the_estimate_and_the_largest_resolution_that_fits():
    mech = load_preset("fivebar_singh").mechanism
    available = 8 * GiB
    with pytest.raises(BudgetError) as info:
        check_map(mech, (100000, 100000), CORE_QUANTITIES, available=available)
    text = str(info.value)
    assert "10,000,000,000 points" in text and "GB" in text and "--resolution" in text
    n = int(text.split("--resolution ")[1].split()[0])
    usable = budget.USABLE_FRACTION * available

    def fits(k):
        return map_estimate(mech, (k, k), CORE_QUANTITIES).bytes <= usable

    assert fits(n) and not fits(n + 1)           # brute force around the bisection's answer
    check_map(mech, (n, n), CORE_QUANTITIES, available=available)      # and that one runs
    with pytest.raises(BudgetError, match="index"):
        check_map(mech, (4294967296, 4294967296), CORE_QUANTITIES, available=available)


def test_available_memory_reads_meminfo_and_takes_an_override(monkeypatch):
    monkeypatch.delenv("ISOFORCE_MEMORY", raising=False)
    with open("/proc/meminfo") as fh:
        kb = next(int(line.split()[1]) for line in fh if line.startswith("MemAvailable:"))
    # MemAvailable changes between two reads; within 20 % (and 1 GiB) is the same reading.
    assert abs(budget.available_memory() - kb * 1024) <= max(0.2 * kb * 1024, GiB)
    monkeypatch.setenv("ISOFORCE_MEMORY", "512M")
    assert budget.available_memory() == 512 << 20
    monkeypatch.setenv("ISOFORCE_MEMORY", "lots")
    with pytest.raises(ValueError, match="ISOFORCE_MEMORY"):
        budget.available_memory()


def test_study_estimate_and_check_fits():
    est = budget.study_estimate(2_000_000_001, 0, 0)
    assert est.points == 2_000_000_001 and est.bytes == 2_000_000_001 * budget.STUDY_DESIGN_BYTES
    with pytest.raises(BudgetError, match="2,000,000,001 designs.*coarser"):
        check_fits(est, advice="use coarser steps", available=16 * GiB)
    ok = budget.study_estimate(60, 27000, 2, workers=2)
    assert check_fits(ok, advice="-", available=16 * GiB) is ok


def test_every_map_quantity_has_a_size():
    mech = load_preset("twin_pantograph").mechanism
    for q in MAP_QUANTITIES:
        assert quantity_bytes(mech, q) == (2 if QUANTITIES[q].categorical else 8)
    with pytest.raises(ValueError, match="unknown quantity"):
        quantity_bytes(mech, "nope")
