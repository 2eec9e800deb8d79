"""How the compiled kernels are compiled: numba, its on-disk cache and its fallbacks, one parallel caller.

Caching. ``cache=True`` keeps machine code between processes. numba writes it next to the
source (``__pycache__``) and, where the package is installed read-only, in the user's cache
directory (``~/.cache/numba``, or ``NUMBA_CACHE_DIR``). Where neither is writable numba refuses
to decorate a cached function (``RuntimeError: no locator available``); ``jit`` then compiles
the same function without a cache, in memory: a read-only install still works and pays the
compile on first use in every process.

One parallel caller. The ``prange`` kernels run on numba's ``workqueue`` threading layer (unless
``NUMBA_THREADING_LAYER`` says otherwise): its idle workers sleep, where OpenMP's spin, and on this
2-core machine shared with other work the 1000 x 1000 Inverse3 map took 0.45 s wall and 0.32 s CPU
on it against 1.0-1.2 s wall and 0.5 s CPU on ``omp``. ``workqueue`` must not be entered by two
threads at once: ``parallel_slot`` lets one caller at a time take the ``prange`` builds, and any
other thread runs the serial build of the same loop meanwhile (the same per-point results).
"""
from __future__ import annotations

import contextlib
import os
import threading

import numba

if "NUMBA_THREADING_LAYER" not in os.environ:
    numba.config.THREADING_LAYER = "workqueue"

#: Whether the kernels were decorated with an on-disk cache (False: compiled in memory).
CACHED = True
_PARALLEL = threading.Lock()


def jit(parallel: bool = False):
    """``numba.njit`` with ``cache=True``, ``nogil``, ``fastmath`` off; in memory where no cache dir is writable.

    Parameters
    ----------
    parallel : bool
        Compile ``prange`` loops for the cores.

    Returns
    -------
    callable
        A decorator.
    """
    def wrap(func):
        try:
            return numba.njit(cache=True, nogil=True, parallel=parallel, error_model="numpy")(func)
        except RuntimeError:           # numba: "cannot cache function ...: no locator available"
            global CACHED
            CACHED = False
            return numba.njit(cache=False, nogil=True, parallel=parallel, error_model="numpy")(func)
    return wrap


@contextlib.contextmanager
def parallel_slot(threads: bool):
    """Yield whether this caller may run the ``prange`` build (``threads`` and no other caller in it).

    Parameters
    ----------
    threads : bool
        The caller wants every core (``compute_map(threads=True)``).

    Yields
    ------
    bool
    """
    got = threads and _PARALLEL.acquire(blocking=False)
    try:
        yield got
    finally:
        if got:
            _PARALLEL.release()
