"""Streamed statistics hold a few chunks at any resolution, and the memory estimate is their true peak.

Before: ``compute_map`` made a list of every chunk's span before the first chunk ran (1.2 GB
at 8000^3 points, 2.3 GB at 10^6 x 10^6; at 10^6 per axis of a 3D box it never started), and
the printed estimate, about 114 MB, was 8 to 34 times below the measured peak.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from kinematics.grid import GridSpec
from metrics.budget import map_estimate
from metrics.map_chunks import CHUNK, chunk_results
from metrics.quantities import STATS_QUANTITIES
from metrics.workspace import Cancelled, chunk_bytes_per_point, compute_map
from resources import load_preset

ROOT = Path(__file__).resolve().parents[2]


def test_chunk_spans_are_made_as_the_pool_takes_them():
    """10^18 points: the first results come at once, and no more spans are started than the window holds."""
    seen, lock = [], threading.Lock()

    def work(span):
        with lock:
            seen.append(span)
        return span

    results = chunk_results(work, 10 ** 18)
    first = [next(results) for _ in range(3)]
    results.close()
    assert first == [(0, CHUNK), (CHUNK, 2 * CHUNK), (2 * CHUNK, 3 * CHUNK)]
    workers = os.cpu_count() or 1
    assert len(seen) <= 3 + 2 * workers          # the window: 2 spans per worker ahead of the consumer


def test_a_grid_of_10_to_the_12_points_starts_and_stops_within_the_estimate():
    """A 10^6 x 10^6 streamed map, cancelled after a few chunks: its peak allocation is the
    estimate's by-chunk bound, which does not depend on the resolution (a list of its
    15 million spans alone was some 1.5 GB)."""
    preset = load_preset("fivebar_singh")
    mech, grid = preset.mechanism, preset.grid.with_resolution(10 ** 6)
    names = STATS_QUANTITIES
    bound = map_estimate(mech, grid.resolution, names, keep_maps=False, baseline=0,
                         work_bytes=chunk_bytes_per_point(mech, grid, names)).bytes
    polls = iter(range(10 ** 9))
    tracemalloc.start()
    try:
        with pytest.raises(Cancelled):
            compute_map(mech, grid, names, keep=False, cancelled=lambda: next(polls) >= 4)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak <= bound, (peak, bound)


def test_points_of_a_chunk_need_no_whole_axis():
    """GridSpec.points at a few indices of 10^6 points per axis allocates for those points only,
    and gives the coordinates of ``coordinates()`` to the last bit."""
    grid = GridSpec(("x", "y", "z"), (-0.1, 0.02, 0.3), (0.1, 0.9, 0.31), (10 ** 6, 10 ** 6 + 1, 7))
    index = np.array([0, 1, 12345678901, grid.resolution[0] * grid.resolution[1] * 7 - 1])
    tracemalloc.start()
    try:
        pts = grid.points(("x", "y", "z"), index)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 64 * 1024, peak                 # an axis of 10^6 points is 8 MB
    ijk = np.unravel_index(index, grid.resolution)
    expected = np.stack([np.linspace(lo, hi, n)[i] for lo, hi, n, i in
                         zip(grid.lower, grid.upper, grid.resolution, ijk)], axis=-1)
    assert np.array_equal(pts, expected)


_PEAK_SCRIPT = """
import json, sys
import numpy as np
from kinematics.grid import GridSpec
from metrics.budget import map_estimate
from metrics.quantities import STATS_QUANTITIES, evaluate
from metrics.workspace import chunk_bytes_per_point, compute_map
from resources import load_preset

key, points = sys.argv[1], int(sys.argv[2])
preset = load_preset(key)
mech = preset.mechanism
# A box inside the workspace, so that every chunk is feasible: the interior of a big grid,
# where the peak is reached (a corner of infeasible chunks holds less).
coarse = preset.grid.with_resolution(41 if len(preset.grid.axes) == 2 else 15)
ok = evaluate(mech, coarse.points(mech.task_names).reshape(-1, mech.task_dim), []).feasible.reshape(coarse.resolution)
inner = ok.copy()
for axis in range(ok.ndim):
    for shift in (-1, 1):
        inner &= np.roll(ok, shift, axis=axis)
c = np.unravel_index(np.argmax(inner), ok.shape)
coords, step, k = coarse.coordinates(), coarse.spacing(), len(coarse.axes)
n = round(points ** (1 / k))
grid = GridSpec(coarse.axes, tuple(coords[i][c[i]] - step[i] / 2 for i in range(k)),
                tuple(coords[i][c[i]] + step[i] / 2 for i in range(k)), (n,) * k, coarse.fixed)
est = map_estimate(mech, grid.resolution, STATS_QUANTITIES, keep_maps=False,
                   work_bytes=chunk_bytes_per_point(mech, grid, STATS_QUANTITIES))
wmap = compute_map(mech, grid, STATS_QUANTITIES, keep=False)
# VmHWM, this process's own peak: ru_maxrss also holds the parent's peak when it was spawned by
# vfork (the kernel records the borrowed memory's high-water mark at exec).
with open("/proc/self/status") as fh:
    peak = next(int(line.split()[1]) * 1024 for line in fh if line.startswith("VmHWM:"))
print(json.dumps({"estimate": est.peak, "baseline": est.baseline, "peak": peak,
                  "feasible": wmap.feasible_points / int(np.prod(grid.resolution))}))
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc/self/status and /proc/self/statm: Linux")
@pytest.mark.parametrize("key", ["fivebar_singh", "novint_falcon"])
def test_the_estimate_is_the_peak_resident_size_within_a_stated_factor(key):
    """The printed estimate against the peak resident size of a fresh process (VmHWM).

    It must not be below the peak (a refusal would let through what cannot fit), nor far above
    it. Upper: ``RESIDENT_PER_TRACED`` (1.25) covers the allocator's slack over the traced
    chunk bytes, measured at 0.90 to 1.09. Lower: the sketch allowance (4 MB per accumulator,
    often a fraction used) put the peak at 0.57 (Stewart) to 0.74 (Twin-Pantograph) of the
    estimate over six shipped devices; these two at 0.57 and 0.62 (0.61 and 0.64 before the
    helper thread's scratch was counted: ``chunk_bytes_per_point``).
    """
    proc = subprocess.run([sys.executable, "-c", _PEAK_SCRIPT, key, str(6 * CHUNK)], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    r = json.loads(proc.stdout)
    assert r["feasible"] == 1.0                   # the case the estimate is for
    assert r["peak"] <= r["estimate"] <= 2.5 * r["peak"], r


def test_a_compiled_kernel_holds_one_chunk_a_core():
    """Its chunks take the pool as the numpy path's do, one chunk a worker (each on the kernel's serial build);
    a grid of a single chunk stays in the caller's thread, with or without the kernel."""
    from metrics import kernels
    from metrics.workspace import chunks_in_flight

    preset = load_preset("inverse3_prototype")
    cores = max(1, os.cpu_count() or 1)
    small = preset.grid.with_resolution(40)       # 1600 points: one chunk
    assert chunks_in_flight(preset.mechanism, preset.grid, STATS_QUANTITIES) == cores
    assert chunks_in_flight(preset.mechanism, small, STATS_QUANTITIES) == 1
    with kernels.use_compiled(False):
        assert chunks_in_flight(preset.mechanism, preset.grid, STATS_QUANTITIES) == cores
        assert chunks_in_flight(preset.mechanism, small, STATS_QUANTITIES) == 1


def _helper_takes_the_first(pool):
    """A schedule ``partials.shared`` takes on an idle core: the helper thread (``pool``'s) takes the first
    quantity, this thread the others. On a loaded machine this thread takes every one (``threads=False``)."""
    def shared(count, one, *, helper):
        first = [pool.submit(one, 0).result()] if helper else []
        return first + [one(i) for i in range(len(first), count)]
    return shared


@pytest.mark.parametrize("key", ["inverse3_prototype", "fivebar_singh"])
def test_the_measured_bytes_are_a_full_chunk_of_distinct_feasible_points(key, monkeypatch):
    """``chunk_bytes_per_point`` traces two small chunks; at a full chunk its line, times the allocator's
    slack the estimate adds (``RESIDENT_PER_TRACED``), covers the traced peak of a job's first full chunk
    of distinct feasible points, and is not more than twice it (one 256-point chunk's peak per point gave
    4.7 times it for the Inverse3). The first chunk is the one that grows the buffers a thread keeps from
    chunk to chunk (``kernels.partials.scratch``: 10.5 MB of a 23.5 MB peak); later chunks reuse them.

    The peak depends on the statistics' helper thread (``partials.shared``): when it takes a quantity it
    makes its own dense bins and bins out, 5 MB more at a full chunk; the scheduler decides. Both
    schedules are run here, each made certain: the estimate must cover the larger peak and be at most
    twice the smaller. (Left to the scheduler, the estimate's own line counted the helper's bins or
    not, 26 or 53 MB, against a peak of 21 or 26 MB: the bounds held by under 1 %, and not always.)"""
    import math
    from concurrent.futures import ThreadPoolExecutor

    from metrics.budget import RESIDENT_PER_TRACED
    from metrics.kernels import partials
    from metrics.map_chunks import ChunkWork
    from metrics.quantities import evaluate
    from metrics.workspace import sample_grid

    preset = load_preset(key)
    mech, grid = preset.mechanism, preset.grid
    per_point = chunk_bytes_per_point(mech, grid, STATS_QUANTITIES)
    pts = sample_grid(grid, 4 * CHUNK).points(mech.task_names).reshape(-1, mech.task_dim)
    with np.errstate(all="ignore"):
        inside = pts[evaluate(mech, pts, ()).feasible]
    assert inside.shape[0] >= CHUNK                 # distinct points fill the chunk
    chunk, index = inside[:CHUNK], np.arange(CHUNK) % math.prod(grid.resolution)
    peaks = {}
    with ThreadPoolExecutor(max_workers=1) as pool:
        pool.submit(int).result()                   # its thread started before the tracing
        for schedule in ("alone", "helper"):
            work = ChunkWork.plan(mech, grid, STATS_QUANTITIES, keep=False, threads=schedule == "helper")
            with monkeypatch.context() as patch:
                if schedule == "helper":
                    patch.setattr(partials, "shared", _helper_takes_the_first(pool))
                work.at(index, chunk)
                # As in a fresh process (``isoforce stats``): every thread's buffers start empty.
                patch.setattr(partials, "_SCRATCH", partials._Scratch())
                tracemalloc.start()
                try:
                    work.at(index, chunk)
                    peaks[schedule] = tracemalloc.get_traced_memory()[1]
                finally:
                    tracemalloc.stop()
    assert peaks["helper"] > peaks["alone"]         # the helper's own bins: the schedule was the one asked for
    estimate = RESIDENT_PER_TRACED * per_point * CHUNK
    assert max(peaks.values()) <= estimate <= 2 * RESIDENT_PER_TRACED * min(peaks.values()), (per_point * CHUNK, peaks)
