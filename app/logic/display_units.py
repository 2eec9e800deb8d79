"""One table of readable display units, shared by the screen and the exports (no Qt, no plotting).

A spatial resolution of 2.3e-05 m reads better as 23 µm, an angular one of 0.0016 rad as
0.092 deg. The data stay SI everywhere; what is printed or drawn of these quantities (the
app's map view and statistics panel, exported map figures) uses this table, so on-screen
and exported figures carry the same unit and the same numbers.
"""
from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

from metrics.quantities import QUANTITIES

if TYPE_CHECKING:         # (annotations only: a pose figure does not load the map's modules)
    from metrics.workspace import Stats, WorkspaceMap

#: Quantity -> (display unit, factor): display value = SI value * factor.
DISPLAY_UNITS: dict[str, tuple[str, float]] = {
    "spatial_resolution": ("µm", 1e6),
    "angular_resolution": ("deg", 180.0 / math.pi),
}


def display_unit(quantity: str) -> tuple[str, float]:
    """``(unit, factor)`` of ``quantity`` when shown: its display unit, or its SI unit and 1.

    >>> display_unit("spatial_resolution"), display_unit("isotropic_force")
    (('µm', 1000000.0), ('N', 1.0))
    """
    return DISPLAY_UNITS.get(quantity, (QUANTITIES[quantity].unit, 1.0))


#: The figures of a ``Stats`` that carry the quantity's unit (``count`` and points do not).
SCALED_FIGURES = ("min", "max", "mean", "sd", "median", "p05", "p95")


def scaled_stats(stats: Stats, factor: float) -> Stats:
    """``stats`` with every figure in the quantity's unit times ``factor`` (> 0); counts and points kept."""
    if factor == 1.0:
        return stats
    return dataclasses.replace(stats, **{f: getattr(stats, f) * factor for f in SCALED_FIGURES})


def scaled_errors(errors: dict, factor: float) -> dict:
    """A quantity's ``{figure: error}`` estimates times ``factor``."""
    return {fig: (None if e is None else e * factor) for fig, e in errors.items()}


def display_map(wmap: WorkspaceMap, quantity: str) -> WorkspaceMap:
    """``wmap`` with ``quantity``'s array, statistics and error estimates in its display unit.

    The same map (no copy) when the quantity has no display unit of its own or is absent.
    """
    unit, factor = display_unit(quantity)
    if factor == 1.0 or quantity not in wmap.values:
        return wmap
    values = dict(wmap.values)
    values[quantity] = wmap.values[quantity] * factor
    stats = dict(wmap.stats)
    if quantity in stats:
        stats[quantity] = scaled_stats(stats[quantity], factor)
    errors = dict(wmap.errors)
    if quantity in errors:
        errors[quantity] = scaled_errors(errors[quantity], factor)
    out = dataclasses.replace(wmap, values=values, stats=stats, errors=errors)
    out.condition_number_scaling = wmap.condition_number_scaling
    return out


def relabel(text: str, quantity: str) -> str:
    """A label or legend entry written with the quantity's SI unit, rewritten with its display unit.

    >>> relabel("Spatial resolution (m)", "spatial_resolution")
    'Spatial resolution (µm)'
    >>> relabel("min 23.1 m at (0.0, 250.0) mm", "spatial_resolution")
    'min 23.1 µm at (0.0, 250.0) mm'
    """
    unit, factor = display_unit(quantity)
    si = QUANTITIES[quantity].unit
    if factor == 1.0 or not si:
        return text
    return text.replace(f"({si})", f"({unit})").replace(f" {si} at ", f" {unit} at ")


def relabel_axes(ax, quantity: str) -> None:
    """A drawn map's colour bar label and legend (``figures.draw_map``) rewritten in the display unit."""
    if display_unit(quantity)[1] == 1.0:
        return
    for other in ax.figure.axes:                  # the colour bar's own axes
        if other is not ax and other.get_ylabel():
            other.set_ylabel(relabel(other.get_ylabel(), quantity))
    for line in ax.lines:
        line.set_label(relabel(line.get_label(), quantity))
    legend = ax.get_legend()
    if legend is not None:
        for text in legend.get_texts():
            text.set_text(relabel(text.get_text(), quantity))
