"""A large map's image is coloured a band of rows per turn of the event loop (``MapCanvas._prepare``).

The image so coloured must be the one coloured in one piece (``PanelPicture.sample_colours`` of
every pixel's sample, the reference), whether the bands all ran or a paint came between them
and coloured the rest at once; the paint is asked for only once the image is whole.
"""
from __future__ import annotations

import numpy as np
import pytest

from app.gui.views import map_canvas
from app.gui.views.map_canvas import MapCanvas
from app.logic.map_picture import map_picture
from metrics.workspace import compute_map
from resources import load_preset


@pytest.fixture(scope="module")
def picture():
    preset = load_preset("fivebar_singh")                 # 521 x 261 samples: more than the canvas's pixels
    wmap = compute_map(preset.mechanism, preset.grid, ("isotropic_force",))
    return map_picture([("", wmap, None)], "isotropic_force", preset)


def reference_pixels(canvas: MapCanvas, panel) -> np.ndarray:
    """The panel's image coloured in one piece, (h, w, 4) RGBA bytes."""
    _, _, ix, iy = canvas._plan(0, panel)
    assert ix is not None and iy is not None          # (the banded path: more samples than pixels)
    return panel.sample_colours(ix, iy)


def image_pixels(canvas: MapCanvas, panel) -> np.ndarray:
    kept = canvas._images[id(panel)]
    assert kept[0] is panel
    return kept[3]


def make_canvas(qtbot, picture, monkeypatch) -> MapCanvas:
    # Bands of a few rows: many turns for one image.
    monkeypatch.setattr(map_canvas, "BAND_PIXELS", 4000)
    canvas = MapCanvas()
    qtbot.addWidget(canvas)
    canvas.resize(420, 320)
    canvas.show()
    qtbot.waitExposed(canvas)
    canvas.picture = picture
    canvas._layout()
    return canvas


def test_the_bands_colour_the_image_coloured_in_one_piece(qtbot, picture, monkeypatch):
    canvas = make_canvas(qtbot, picture, monkeypatch)
    panel = picture.panels[0]
    paints = canvas.paints
    canvas._prepare()
    # One band coloured, the rest left to later turns; nothing painted meanwhile.
    assert id(panel) not in canvas._images and canvas._prepare_timer.isActive()
    qtbot.waitUntil(lambda: id(panel) in canvas._images)
    np.testing.assert_array_equal(image_pixels(canvas, panel), reference_pixels(canvas, panel))
    assert not canvas._bands
    qtbot.waitUntil(lambda: canvas.paints > paints)      # the paint asked for once the image is whole


def test_a_paint_between_the_bands_colours_the_rest_at_once(qtbot, picture, monkeypatch):
    canvas = make_canvas(qtbot, picture, monkeypatch)
    panel = picture.panels[0]
    canvas._prepare()
    assert canvas._bands and canvas._bands[id(panel)][6] > 0        # some rows coloured
    canvas._prepare_timer.stop()
    canvas.grab()                   # a paint (into a pixmap) before the next band
    np.testing.assert_array_equal(image_pixels(canvas, panel), reference_pixels(canvas, panel))
    assert not canvas._bands
