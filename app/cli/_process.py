"""The command line's own process (``python -m app.cli``): its start-up without collections, its end without teardown.

A command's process makes most of its objects as it starts (the modules' and numba's, the
kernels' as they load from the cache) and keeps them to its exit, which frees them all at
once. The interpreter's cyclic garbage collector traverses them meanwhile, and again, for
nothing. Here, for a process that runs one command and ends:

- ``start_up_without_collections`` (its entry, before ``main``) turns the automatic collector
  off; ``start_up_over`` (``main``, before the command runs) and ``start_up_window`` (around
  ``check_job``, which loads the kernels and samples the maps) freeze what exists then (the
  collector never traverses it again) and turn the collector back on for the work;
- ``end_process`` ends the process without the interpreter's teardown once ``main`` returned.

The ``isoforce`` script and ``python -m app`` (``app.launch.main`` without arguments) do the same
for a command. A process that calls ``main`` itself (a test, ``app.launch.main(argv)``) turns nothing
off: ``start_up_over`` and ``start_up_window`` change nothing there, and its collections, its
objects and its freeze count stay as they were.
"""
from __future__ import annotations

import contextlib
import gc
import os
import sys
import threading
from typing import Iterator, NoReturn

#: Holds True while the process's entry has the collector off for its start-up (``start_up_without_collections``).
_OWNED: list[bool] = []


def start_up_without_collections() -> None:
    """Turn the automatic garbage collector off for the start-up of this process's one command.

    Only for a process that runs one command and ends (``python -m app.cli``): ``start_up_over``
    and ``start_up_window`` turn it back on. The collections the start-up of ``isoforce
    convergence`` ran were 0.05-0.07 s of CPU on the main thread (152 of the youngest generation,
    13 of the middle, one full; ``gc.callbacks`` with ``time.thread_time``, load 4-5), nearly all
    within imports, numba's above all.
    """
    if gc.isenabled():
        gc.disable()
        _OWNED[:] = [True]


def start_up_over() -> None:
    """The start-up is over: freeze the objects it made and turn the collector back on (if it was turned off).

    Frozen objects are never traversed again and live to the process's exit, which they would
    have anyway (modules, functions, numba's dispatchers and types). A command's own work (its
    maps, searches, figures) runs with the collector on.
    """
    if _OWNED and not gc.isenabled():
        gc.freeze()
        gc.enable()


@contextlib.contextmanager
def start_up_window() -> Iterator[None]:
    """Within the block, the collector is off, and what the block made is frozen after it, in a command line process.

    For a part of a command that imports and loads once a process (``check_job``: numba's
    import and the kernels' loads from its cache, the pool's threads); elsewhere (a test's
    process) the block runs as it is.
    """
    if not (_OWNED and gc.isenabled()):
        yield
        return
    gc.disable()
    try:
        yield
    finally:
        start_up_over()


def end_process(status: int) -> NoReturn:
    """End a command line process with ``status``, skipping the interpreter's teardown.

    For ``python -m app.cli`` once ``main`` has returned: what the interpreter does at exit
    that is seen outside the process is done here, in its order (stdout and stderr flushed,
    the threads that are not daemons joined: the idle map and search pools' workers, then the
    ``atexit`` handlers); what it does after that is skipped (``os._exit``): the modules'
    teardown and the freeing of every object one by one, numba's and LLVM's included, which the
    kernel's freeing of the whole process replaces. 0.04-0.08 s of ``isoforce convergence``
    and ``stats``, after the output was written (this machine, load 5). A child process still
    alive (a process pool's) or a flush that fails (a closed pipe) gets the interpreter's own
    exit: its error message and status, its clean-up of the children.

    Parameters
    ----------
    status : int
        The exit status (``main``'s return value).
    """
    import atexit

    shutdown = getattr(threading, "_shutdown", None)
    run_handlers = getattr(atexit, "_run_exitfuncs", None)
    if shutdown is None or run_handlers is None or _has_children():
        sys.exit(status)
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    except (OSError, ValueError):
        sys.exit(status)
    shutdown()           # as the interpreter's exit: join the threads that are not daemons
    run_handlers()       # then the atexit handlers, last registered first (gc.freeze, logging ...)
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        _flush_c_streams()
    finally:
        os._exit(status)


def _flush_c_streams() -> None:
    """Flush the C library's buffered streams (``fflush(NULL)``), as the C exit ``os._exit`` skips
    would: text a compiled library wrote to its ``stdout`` (VTK's messages, say) is not lost when
    that stream is a pipe or a file (fully buffered there)."""
    import ctypes

    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):         # (no C library to load by name: nothing of it to flush)
        pass


def _has_children() -> bool:
    """Whether this process has child processes of ``multiprocessing`` alive (numba loads the module too)."""
    if "multiprocessing" not in sys.modules:
        return False
    import multiprocessing

    return bool(multiprocessing.active_children())
