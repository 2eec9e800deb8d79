"""Colour limits of a map: which values a colour scale spans, log or linear, capped or not.

Numpy only (no matplotlib): the app's map job computes them on its worker thread
(``app.jobs.requests.run_map_for_view``), the map drawers (``app.plots.figures``) and the 3D
scenes (``app.scenes.workspace``) use them.
"""
from __future__ import annotations

import numpy as np

from app.logic.tail_percentiles import percentiles
from metrics.quantities import QUANTITIES
from metrics.workspace import WorkspaceMap

#: Quantities coloured on a log scale: positive everywhere and spanning decades near a
#: singularity (the PHANToM's heaviest apparent mass runs from 65 g to 2 t towards its base axis).
LOG_QUANTITIES = frozenset({"condition_number", "mass_condition_number", "apparent_mass_max"})


def log_colours(quantity: str) -> bool:
    """Whether ``quantity`` is coloured on a log scale (``LOG_QUANTITIES``)."""
    return quantity in LOG_QUANTITIES


def layers_limits(layers, *, log: bool) -> tuple[float, float, bool]:
    """``colour_limits`` of the feasible finite values of every layer (positive ones on a log scale).

    Parameters
    ----------
    layers : sequence of (values, feasible)
        Arrays of one map's shape (nx, ny) (or (nx, ny, nz)), float and bool.
    log : bool
        A log scale.
    """
    parts = [v[f & np.isfinite(v)].astype(float, copy=False) for v, f in layers]
    finite = parts[0] if len(parts) == 1 else np.concatenate(parts)      # (one layer: a copy already)
    if log:
        finite = finite[finite > 0]
    return colour_limits(finite, log=log)


def map_colour_limits(wmap: WorkspaceMap, name: str) -> tuple[float, float, bool] | None:
    """The colour limits one map of ``name`` is drawn with (``layers_limits`` of its values), or
    None for a quantity drawn without them (categorical, not scalar, not in the map).

    A full map's take a few ms (1.7 ms for the Inverse3's 1000 x 1000 isotropic force, its p1 and p99
    taken from the tails, ``tail_percentiles``): the app's map job computes
    them with the map (``app.jobs.requests.run_map_for_view``) and the map view passes them in
    (``colour_scale(..., limits=...)``).
    """
    node = QUANTITIES.get(name)
    if name not in wmap.values or node is None or not node.scalar or node.categorical:
        return None
    return layers_limits([(wmap.values[name], wmap.feasible)], log=log_colours(name))


def colour_limits(finite: np.ndarray, *, log: bool = False) -> tuple[float, float, bool]:
    """Colour-scale limits ``(lo, hi, capped)`` for the finite values of a map.

    Near a singularity the condition number, the anisotropic force and (where a leg folds)
    the five-bar's isotropic force grow without bound; a handful of such points would
    squeeze the rest of the map into one colour. So the upper limit is capped at
    ``p99 + (p99 - p1)`` (percentiles, in log space for a log scale) when the maximum
    lies beyond it; the colour bar then gets an arrow and says so. The extremes marked on
    the map keep their true values.
    """
    if finite.size == 0:
        return (1.0, 10.0, False) if log else (0.0, 1.0, False)
    data = np.log10(finite) if log else finite
    lo, hi = float(data.min()), float(data.max())
    p1, p99 = percentiles(data, [1.0, 99.0])        # np.percentile's, from the tails (tail_percentiles)
    limit = float(2.0 * p99 - p1)
    capped = hi > limit and limit > lo
    if capped:
        hi = limit
    if not hi > lo:      # a constant map still needs a non-empty range
        hi = lo + (0.01 if log else max(abs(lo) * 1e-3, 1e-12))
    return (10.0 ** lo, 10.0 ** hi, capped) if log else (lo, hi, capped)
