"""Round tick values for axes and colour bars, without matplotlib.

``nice_ticks`` is matplotlib's ``MaxNLocator(nbins, steps).tick_values`` (3.11, the default
``axes.autolimit_mode = "data"``, no axis) ported to plain numpy, so the app's painted map
and the exported figures pick the same ticks; ``tests/app/test_ticks.py`` compares the two
over many ranges. ``log_ticks`` and ``round_below`` are our own 1-2-5 rules.
"""
from __future__ import annotations

import math

import numpy as np

#: The steps of the map's axes and continuous colour bars (times a power of ten).
AXIS_STEPS = (1.0, 2.0, 2.5, 5.0, 10.0)


def _nonsingular(vmin: float, vmax: float, expander: float = 1e-13, tiny: float = 1e-14) -> tuple[float, float]:
    """matplotlib's ``transforms.nonsingular``: a range of nonzero width around the given ends."""
    if not (np.isfinite(vmin) and np.isfinite(vmax)):
        return -expander, expander
    swapped = vmax < vmin
    if swapped:
        vmin, vmax = vmax, vmin
    maxabs = max(abs(vmin), abs(vmax))
    if maxabs < (1e6 / tiny) * np.finfo(float).tiny:
        vmin, vmax = -expander, expander
    elif vmax - vmin <= maxabs * tiny:
        if vmax == 0 and vmin == 0:
            vmin, vmax = -expander, expander
        else:
            vmin -= expander * abs(vmin)
            vmax += expander * abs(vmax)
    return (vmax, vmin) if swapped else (vmin, vmax)


def _scale_range(vmin: float, vmax: float, n: int, threshold: float = 100) -> tuple[float, float]:
    dv = abs(vmax - vmin)
    meanv = (vmax + vmin) / 2
    offset = 0.0 if abs(meanv) / dv < threshold else math.copysign(10 ** (math.log10(abs(meanv)) // 1), meanv)
    return 10 ** (math.log10(dv / n) // 1), offset


def _close_to(ms: float, edge: float, step: float, offset: float) -> bool:
    """matplotlib's ``_Edge_integer.closeto``: more slop when the offset is large beside the step."""
    if offset > 0:
        tol = min(0.4999, max(1e-10, 10 ** (np.log10(offset / step) - 12)))
    else:
        tol = 1e-10
    return abs(ms - edge) < tol


def nice_ticks(lo: float, hi: float, nbins: int, steps=AXIS_STEPS, min_n_ticks: int = 2) -> np.ndarray:
    """Round ticks covering ``[lo, hi]``: at most about ``nbins`` intervals of a step from ``steps``
    times a power of ten, as ``matplotlib.ticker.MaxNLocator(nbins=nbins, steps=steps)`` gives them.

    The ends may lie a step beyond ``lo`` and ``hi`` (as matplotlib's do); filter for the
    ticks inside.

    Parameters
    ----------
    lo, hi : float
        The range.
    nbins : int
        The most intervals wanted.
    steps : sequence of float
        Increasing steps from 1 to 10.

    Returns
    -------
    ndarray, shape (k,)

    Examples
    --------
    >>> nice_ticks(0.0, 1.0, 5).tolist()
    [0.0, 0.2, 0.4, 0.6000000000000001, 0.8, 1.0]
    """
    vmin, vmax = _nonsingular(float(lo), float(hi))
    steps = np.asarray(steps, float)
    extended = np.concatenate([0.1 * steps[:-1], steps, [10 * steps[1]]])
    scale, offset = _scale_range(vmin, vmax, nbins)
    _vmin, _vmax = vmin - offset, vmax - offset
    candidates = extended * scale
    large = candidates >= (_vmax - _vmin) / nbins
    istep = int(np.nonzero(large)[0][0]) if large.any() else len(candidates) - 1
    ticks = np.array([])
    for step in candidates[: istep + 1][::-1]:
        best_vmin = (_vmin // step) * step
        d, m = divmod(_vmin - best_vmin, step)
        low = d + 1 if _close_to(m / step, 1, step, abs(offset)) else d
        d, m = divmod(_vmax - best_vmin, step)
        high = d if _close_to(m / step, 0, step, abs(offset)) else d + 1
        ticks = np.arange(low, high + 1) * step + best_vmin
        if ((ticks <= _vmax) & (ticks >= _vmin)).sum() >= min_n_ticks:
            break
    return ticks + offset


def axis_ticks(lo: float, hi: float, pixels: float) -> list[float]:
    """Round tick values (mm) between ``lo`` and ``hi``, about one per 70 pixels of axis.

    >>> axis_ticks(-60.0, 60.0, 400.0)
    [-50.0, -25.0, 0.0, 25.0, 50.0]
    """
    nbins = max(2, min(9, int(pixels // 70)))
    slack = 1e-9 * (hi - lo)
    return [float(t) for t in nice_ticks(lo, hi, nbins) if lo - slack <= t <= hi + slack]


def log_ticks(lo: float, hi: float) -> list[float]:
    """Colour-bar ticks of a log scale from ``lo`` to ``hi``: 1, 2, 5 x 10^k (finer within 1.5 decades).

    >>> log_ticks(1.0, 100.0)
    [1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0]
    """
    decades = range(int(np.floor(np.log10(lo))), int(np.ceil(np.log10(hi))) + 1)
    # Less than a decade and a half: finer steps, or the bar would carry one or two labels.
    mantissas = (1, 2, 5) if hi / lo > 30 else (1, 1.5, 2, 3, 5, 7)
    ticks = [m * 10.0 ** k for k in decades for m in mantissas if lo <= m * 10.0 ** k <= hi]
    return ticks if len(ticks) >= 2 else [lo, hi]


def round_below(value: float) -> float:
    """The largest 1, 2 or 5 x 10^k not above ``value`` (> 0): a scale bar's or a key's length.

    >>> round_below(37.0), round_below(0.149)
    (20.0, 0.1)
    """
    k = np.floor(np.log10(value))
    return float(max(m * 10.0 ** k for m in (1, 2, 5) if m * 10.0 ** k <= value * (1 + 1e-12)))
