"""``hypot`` as glibc's libm computes it, inlined in a kernel's loop: no libm call.

glibc (2.35 on, ``sysdeps/ieee754/dbl-64/e_hypot.c``: Borges's algorithm, the variant without FMA,
which x86-64's generic build takes) forms ``h = sqrt(ax^2 + ay^2)`` (``ax >= ay >= 0``) and corrects it
once, ``h -= (t1 + t2) / (2 h)``, from the rounding of ``h^2`` against ``ax^2 + ay^2``; ``ax + ay``
where ``ay <= 2^-54 ax``; and scales its inputs by a power of two where ``ax`` is above ``2^511`` or
``ay`` below ``2^-511``. ``hypot_fast`` is that common path with its branch taken as a select, so a loop
over a block of points runs it in vector registers. Where it does not hold (``hypot_covers`` False:
``ay`` below ``2^-400`` or ``ax`` above ``2^400``, a margin inside glibc's bounds, or inf / nan) the
caller calls libm.

The Inverse3 pass takes ``hypot(|u|, w)`` at every point within the outer reach, 68 % of the
1000 x 1000 map's: as a libm call (30 ns each, not inlined) 20 ms of the pass's 40 ms of CPU on one
thread, as ``hypot_fast`` under a millisecond.

The model (``Inverse3.inverse``) takes ``np.hypot``, libm's. ``matches_libm`` says whether the two agree
bit for bit on a probe of pairs over every ratio ``ay / ax`` from 1 to ``2^-80`` (numpy's arithmetic:
the same IEEE operations, each rounded once, as the compiled ones);
where they do not (another libc, or glibc before 2.35) a kernel calls libm instead (``inverse3.pack``).
On this machine's glibc 2.36 the two agree on every probe pair, 4 million random pairs and all 1
million of the 1000 x 1000 map's (``tests/metrics/test_kernel_hypot.py``).
"""
from __future__ import annotations

import functools
import math

import numpy as np

from .jit import jit

#: ``ay`` at or below ``EPS ax``: glibc returns ``ax + ay``.
EPS = 2.0 ** -54
#: The range ``hypot_fast`` covers: both inputs' magnitudes within it (glibc scales outside ``2^+-511``).
TINY, LARGE = 2.0 ** -400, 2.0 ** 400


@jit(inline=True)
def hypot_fast(x, y):
    """``hypot(x, y)`` by glibc's common path (module docstring), without a branch; right where ``hypot_covers``."""
    a, b = abs(x), abs(y)
    ax, ay = max(a, b), min(a, b)
    h = math.sqrt(ax * ax + ay * ay)
    # glibc's two corrections, the one it takes chosen by a select.
    d1 = h - ay
    t1a = ax * (2.0 * d1 - ax)
    t2a = (d1 - 2.0 * (ax - ay)) * d1
    d2 = h - ax
    t1b = 2.0 * d2 * (ax - 2.0 * ay)
    t2b = (4.0 * d2 - ay) * ay + d2 * d2
    close = h <= 2.0 * ay
    t1 = t1a if close else t1b
    t2 = t2a if close else t2b
    h = h - (t1 + t2) / (2.0 * h)
    return ax + ay if ay <= ax * EPS else h


@jit(inline=True)
def hypot_covers(x, y):
    """Whether ``hypot_fast(x, y)`` is glibc's ``hypot(x, y)``: both magnitudes within ``[TINY, LARGE]``."""
    a, b = abs(x), abs(y)
    return min(a, b) >= TINY and max(a, b) <= LARGE


def _numpy_hypot(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``hypot_fast`` in numpy's arithmetic (the same operations, each rounded once), for ``matches_libm``."""
    a, b = np.abs(x), np.abs(y)
    ax, ay = np.maximum(a, b), np.minimum(a, b)
    h = np.sqrt(ax * ax + ay * ay)
    d1, d2 = h - ay, h - ax
    t1 = np.where(h <= 2.0 * ay, ax * (2.0 * d1 - ax), 2.0 * d2 * (ax - 2.0 * ay))
    t2 = np.where(h <= 2.0 * ay, (d1 - 2.0 * (ax - ay)) * d1, (4.0 * d2 - ay) * ay + d2 * d2)
    h = h - (t1 + t2) / (2.0 * h)
    return np.where(ay <= ax * EPS, ax + ay, h)


@functools.cache
def matches_libm() -> bool:
    """Whether ``np.hypot`` (libm) is ``hypot_fast`` on a fixed set of pairs, once a process (a millisecond).

    The pairs: every ratio ``2^-k`` (k < 81) times 24 mantissas over [1, 2), at magnitudes ``2^-300``,
    1 and ``2^300`` (within ``hypot_fast``'s range a power-of-two scale changes no rounding), both orders
    and signs. A kernel calls libm where this is False.

    Returns
    -------
    bool
    """
    mant = 1.0 + np.arange(24) / 24.0
    ratio = np.ldexp(1.0, -np.arange(81))
    scale = np.array([2.0 ** -300, 1.0, 2.0 ** 300])
    x = np.broadcast_to(mant[:, None, None] * scale[None, None, :], (24, 81, 3)).ravel()
    y = (mant[::-1, None, None] * ratio[None, :, None] * scale[None, None, :] / 2.0).ravel()
    y = np.where(np.arange(y.size) % 2 == 0, y, -y)
    return bool(np.array_equal(_numpy_hypot(x, y), np.hypot(x, y)) and np.array_equal(_numpy_hypot(y, x),
                                                                                      np.hypot(y, x)))
