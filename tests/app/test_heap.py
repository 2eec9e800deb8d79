"""``app.jobs.heap.release``: freed heap goes back to the system, and the app's full maps call it."""
from __future__ import annotations

import sys

import pytest

from app.jobs import heap

CHUNK, CHUNKS = 64 * 1024, 3200        # 200 MB in blocks glibc serves from its heap (under its mmap threshold)


def rss_mb() -> float:
    with open("/proc/self/status", encoding="ascii") as f:
        return next(int(line.split()[1]) / 1024 for line in f if line.startswith("VmRSS"))


@pytest.mark.skipif(not sys.platform.startswith("linux") or heap._malloc_trim() is None, reason="glibc only")
def test_release_hands_freed_heap_back():
    blocks = [bytearray(CHUNK) for _ in range(CHUNKS)]      # written (zeroed): resident
    keep = blocks[-1]                                        # the heap's top stays in use: free() cannot shrink it
    before = rss_mb()
    del blocks
    freed = rss_mb()
    assert heap.release()
    after = rss_mb()
    size = CHUNK * CHUNKS / 2**20
    if before - freed > 0.5 * size:
        pytest.skip(f"this allocator gave {before - freed:.0f} MB back at free() already")
    assert freed - after > 0.8 * size, (before, freed, after)  # given back
    del keep


def test_full_maps_release_the_heap_and_coarse_ones_do_not(monkeypatch):
    from app.jobs.requests import MapRequest, run_map_for_view
    from metrics.workspace import Cancelled
    from resources import load_preset

    preset = load_preset("fivebar_singh")
    grid = preset.grid.with_resolution((9, 5))
    calls = []
    monkeypatch.setattr(heap, "release", lambda: calls.append(1) or True)
    # (A dragged slider's full map leaves it to the map of the released slider.)
    for stage, drag, released in (("coarse", False, 0), ("full", False, 1), ("full", True, 0)):
        calls.clear()
        run_map_for_view(MapRequest(preset.mechanism, grid, ("isotropic_force",), stage, "current", drag=drag),
                         lambda f: None, lambda: False)
        assert len(calls) == released, (stage, drag)
    calls.clear()                                            # a full map stopped half way releases too
    with pytest.raises(Cancelled):
        run_map_for_view(MapRequest(preset.mechanism, grid, ("isotropic_force",), "full", "current"),
                         lambda f: None, lambda: True)
    assert len(calls) == 1
