"""The numpy-only floor: every decision a view makes, drawn by nobody here.

Colour limits, display units, the digits a figure's error supports, pose text, glyph needs,
a box's planes, overlay names, what changed between two designs. No matplotlib, PyVista or Qt
(an import-linter contract); the GUI's model and the command line both read it.
"""
