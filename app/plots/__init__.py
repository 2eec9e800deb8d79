"""The matplotlib floor: map drawers, colour scales, overlays, the compare figure and what the
map view paints (``map_picture``). No PyVista, no Qt.
"""
