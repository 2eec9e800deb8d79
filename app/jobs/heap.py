"""Hand freed heap memory back to the system, so a long session's RSS follows what it holds.

glibc keeps the memory that threads free in its arenas for reuse. A full map allocates and
frees hundreds of MB of NumPy temporaries on the map threads (the Inverse3's 1000 x 1000 grid),
and much of it stays with the process: after one tour of ``scripts/soak_gui.py --trim`` through
every preset the app held 551 MB (its RSS after ``malloc_trim``) but its RSS was 1,195 MB.
``release`` after each full map (``app.jobs.requests.run_map_for_view``, on the map worker
thread) kept the RSS at 596-723 MB where it was 985-1,082 MB over the same edits (Inverse3
scenario 3, five-bar, Inverse3 prototype; three cycles), for 9 ms a call (13 ms at most).

No Qt; nothing happens where the C library has no ``malloc_trim`` (not glibc).
"""
from __future__ import annotations

import ctypes
import ctypes.util
import functools

__all__ = ["release"]


@functools.cache
def _malloc_trim():
    """glibc's ``malloc_trim``, or None."""
    try:
        return ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6").malloc_trim
    except (OSError, AttributeError):
        return None


def release() -> bool:
    """Return the free heap to the system (``malloc_trim(0)``).

    Returns
    -------
    bool
        Whether there was a ``malloc_trim`` to call (glibc).

    Examples
    --------
    >>> release() in (True, False)
    True
    """
    trim = _malloc_trim()
    if trim is None:
        return False
    trim(0)
    return True
