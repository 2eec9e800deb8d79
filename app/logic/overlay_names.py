"""The overlays a map can carry over its heat map, by name (plain Python, no matplotlib).

The GUI's model (``app.gui.model``) keeps the chosen one; ``app.plots.overlays`` draws them.
"""
from __future__ import annotations

#: Overlay name -> what it draws.
OVERLAYS = {"none": "no overlay", "bands": "condition-number bands (paper 002 Fig. 5)",
            "force ellipses": "force ellipses (paper 002 Fig. 9)",
            "velocity ellipses": "velocity ellipses (paper 002 Fig. 9)"}
