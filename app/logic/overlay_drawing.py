"""What an overlay draws over a map, as plain data for either canvas (no matplotlib).

``app.plots.overlays`` computes it (condition bands, ellipse fields); the exported figures
draw it with matplotlib and the app's map view paints it with Qt (``app.logic.map_picture``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class OverlayDrawing:
    """What an overlay draws over a map, in mm, for any canvas (matplotlib's or the app's painter).

    ``lines``: (colour, polylines (k, 2)) per line set; ``markers``: (symbol ``"x"`` | ``"^"``,
    colour, points (k, 2)); ``circles``: dashed circles (cx, cy, r); ``ellipses`` (k, 5): centre
    x, y, full width and height (mm) and angle (deg) of each ellipse; ``key``: the radius (mm)
    of the ellipses' key circle and its text; ``rows``: the legend, (symbol, colour, text) with
    symbol ``"patch"``, ``"line"``, ``"dashed"``, ``"x"``, ``"o"``, ``"^"`` or None (text only);
    ``title``: the legend's title.
    """

    title: str
    rows: tuple
    lines: tuple = ()
    markers: tuple = ()
    circles: tuple = ()
    ellipses: np.ndarray | None = None
    key: tuple | None = None
