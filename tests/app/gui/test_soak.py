"""A short soak of the real window (issue 21 sec. 0): slider drags, device and tab switches.

``scripts/soak_gui.py`` drives the window (its ``Soak``) through one preset of each mechanism
family (the script's long run takes every preset), here on grids shrunk to ``LONGEST`` points
along their longer axis, three times round: 258 slider steps, 14 device switches, a tab flip
every other drag. The process stays up (a binding that drops references to ``None`` ended it
after 200-250 edits), no error dialog opens, and at the start of each tour after the first
(the first preset again, its full map shown, the garbage collected: the same state) the window
holds as many widgets, top-level widgets, threads and file descriptors as at the previous one.

``sys.getrefcount(None)`` is checked over each device visit's drags (18 edits: maps, glyphs,
paints, tab flips; no widget is built), after the first tour, from the switch's full map shown
to the last release's full map shown (like states: a preview map's objects hold other
references, and a visit that ended on one measured -154 in CI). Measured there with PySide6
6.11.3 it moved by -44 to +32, the same in runs alone, loaded and on one core; with 6.12.0,
which drops a reference per QPainter call and per widget setter, by -461 (a visit of 6 edits)
to -3,624, and a long session aborts in ``none_dealloc`` once the count reaches zero.
``NONE_FALL`` lies between. A rise does not free ``None``, but a steady one means objects pile
up: ``NONE_RISE`` is ten times the largest measured before the ends were made alike (+88).
(Across a device switch the count is not compared: 6.11.3 keeps a reference to ``None`` for
some calls on a new widget, +12 per ``ParameterRow`` built and deleted, +8 per
``QFormLayout.addRow``, +1 per ``connect``, so each parameter panel rebuilt raises it by
hundreds to thousands, harmlessly.)
"""
from __future__ import annotations

import gc

import shiboken6

from app.gui.widgets.parameter_panel import ParameterRow
from scripts.soak_gui import DRAG_PATH, Soak, one_per_family

LONGEST = 21            # points along the longer map axis of every preset (a Falcon box: 21 x 21 x 19)
PER_DEVICE = 3 * len(DRAG_PATH)      # three drags per visit
TOURS = 3
NONE_FALL, NONE_RISE = 100, 1000


def test_a_session_of_drags_and_switches_keeps_widgets_and_references_flat(make_window, qtbot):
    presets = one_per_family()
    # A smaller window than the other tests': the 3D views' software rendering costs by the pixel.
    window = make_window(presets[0], longest=LONGEST, size=(1000, 700))
    # A hand that moves on after 50 ms whether the map has followed or not (newer maps supersede
    # it), and the next drag at once after a release (its refinement cancelled); a device switch
    # waits for its full map, so each visit and each tour start has one.
    soak = Soak(window, presets, per_device=PER_DEVICE, refine=False, pace_s=0.05)
    # Up to the start of the last tour: two tours of edits, then back on the first preset.
    soak.run((TOURS - 1) * len(presets) * PER_DEVICE + 1)
    assert len(soak.tours) == TOURS, soak.tours
    assert soak.dialogs == []
    assert len(presets) >= 7 and len(soak.steps) >= 2 * len(presets) * PER_DEVICE
    second, third = soak.tours[1], soak.tours[2]
    for key in ("widgets", "top_level", "threads", "fds"):
        assert third[key] == second[key], (key, soak.tours)
    # What each redraw replaces is freed, not kept beside the new: PyVista's bookkeeping holds at
    # most the one cut volume, plane widget and colour bar on screen (``clear_clip_plane``; a kept
    # cut held its clipper and volume, 40-70 MB a full Inverse3 map), and the only parameter rows
    # whose widgets live are the panel's, one set per family (a switch reuses a family's rows).
    for view in (window.pose_view, window.workspace_view):
        plotter = view.plotter
        owner = getattr(plotter, "widgets", plotter)        # (``Plotter.widgets`` from PyVista 0.48)
        assert len(owner.plane_clipped_meshes) <= 1 and len(owner.plane_widgets) <= 1, view
        assert len(plotter.scalar_bars) <= 1, list(plotter.scalar_bars.keys())
    # The parameter rows alive are the panel's, one set per family shown (kept to be shown again).
    live_rows = [o for o in gc.get_objects() if isinstance(o, ParameterRow) and shiboken6.isValid(o)]
    kept = [row for body in window.param_panel._bodies.values() for row in body.rows.values()]
    assert set(map(id, window.param_panel.rows.values())) <= set(map(id, kept))
    # No row alive outside them. (The first device's rows were made before the window froze the
    # collector's objects, ``gc.freeze``, so ``gc.get_objects`` lists only the later ones.)
    assert set(map(id, live_rows)) <= set(map(id, kept)) and len(live_rows) >= len(kept) - len(
        next(iter(window.param_panel._bodies.values())).rows)
    drifts = [(visit["device"], visit["none_drift"]) for visit in soak.visits[len(presets):]
              if visit["edits"] == PER_DEVICE]
    assert len(drifts) == len(presets)
    assert all(-NONE_FALL <= drift <= NONE_RISE for _, drift in drifts), drifts
