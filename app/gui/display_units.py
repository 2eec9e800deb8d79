"""Readable units on screen for quantities whose SI values are awkward to read.

A spatial resolution of 2.3e-05 m reads better as 23 µm, an angular one of 0.0016 rad as
0.092 deg. The data stay SI everywhere (maps, exports, the command line); only what the map
view and the statistics panel print is scaled: ``display_map`` gives a copy of a map whose
array and statistics of one quantity are in its display unit. No Qt.
"""
from __future__ import annotations

from app.display_units import (  # noqa: F401 (the one shared table and its helpers, app/display_units.py)
    DISPLAY_UNITS,
    SCALED_FIGURES,
    display_map,
    display_unit,
    relabel,
    scaled_errors,
    scaled_stats,
)
