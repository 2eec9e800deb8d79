"""The shared thread pool that runs a map's chunks (and a region's calls), its window, its cancel signal.

Apart from ``metrics.map_chunks`` so that a caller of the pool alone (``metrics.dextrous``) does
not import the map's quantities and kernels with it.
"""
from __future__ import annotations

import os
import threading
from collections import deque
from concurrent.futures import ThreadPoolExecutor

_POOL: ThreadPoolExecutor | None = None
_POOL_LOCK = threading.Lock()


def chunk_pool() -> ThreadPoolExecutor:
    """The process's one pool of map threads, one per core, made on first use."""
    global _POOL
    with _POOL_LOCK:
        if _POOL is None:
            _POOL = ThreadPoolExecutor(max_workers=max(1, os.cpu_count() or 1), thread_name_prefix="isoforce-map")
        return _POOL


class Cancelled(Exception):
    """Raised by ``compute_map`` when its ``cancelled`` callback says so."""


def windowed(work, items, workers: int):
    """``work`` over ``items`` on the pool, results in order, with at most ``2 * workers`` in flight.

    ``Executor.map`` submits every chunk at once, so results pile up when the consumer is
    slower than the workers; a window keeps memory at a few chunks whatever the resolution.
    """
    pool, pending = chunk_pool(), deque()
    try:
        for item in items:
            pending.append(pool.submit(work, item))
            if len(pending) >= 2 * workers:
                yield pending.popleft().result()
        while pending:
            yield pending.popleft().result()
    finally:
        for future in pending:
            future.cancel()
