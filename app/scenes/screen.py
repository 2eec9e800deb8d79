"""Where world points and texts fall on screen: a renderer's display pixels of many points at
once (``display_points``), the pixel boxes of texts as VTK draws them (``iso_label_boxes``),
and whether a render's view differs from the last placing's (``new_view``).
"""
from __future__ import annotations

import numpy as np


def display_points(renderer, points: np.ndarray) -> np.ndarray:
    """Display pixels of world points through the renderer's active camera.

    VTK's world-to-display transform for many points at once (``vtkCoordinate`` does one at a
    time, and ``GetComputedDisplayValue`` rounds its result down to whole pixels).

    Parameters
    ----------
    renderer : vtkRenderer
        Its size, origin in the window and active camera are used.
    points : array_like, shape (k, 3)
        World points, m.

    Returns
    -------
    ndarray, shape (k, 2)
        Pixels, x right and y up from the window's bottom-left corner; ``nan`` for a point
        behind the camera.
    """
    pts = np.asarray(points, float).reshape(-1, 3)
    w, h = renderer.GetSize()
    ox, oy = renderer.GetOrigin()
    m = renderer.GetActiveCamera().GetCompositeProjectionTransformMatrix(renderer.GetTiledAspectRatio(), -1, 1)
    mat = np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])
    hom = np.column_stack([pts, np.ones(len(pts))]) @ mat.T
    with np.errstate(divide="ignore", invalid="ignore"):
        ndc = np.where(hom[:, 3:4] > 0, hom[:, :2] / hom[:, 3:4], np.nan)
    return np.column_stack([ox + 0.5 * (ndc[:, 0] + 1) * w, oy + 0.5 * (ndc[:, 1] + 1) * h])


def iso_label_boxes(text_property, texts, margin: float, dpi: int) -> np.ndarray:
    """Each label's box as drawn, relative to its anchor.

    The text's extent as VTK's label mapper measures it (``vtkTextRenderer.GetBoundingBox``,
    as ``vtkFreeTypeLabelRenderStrategy.ComputeLabelBounds`` does, justification and line
    offset included), grown by the ``margin`` of the box ``vtkLabelPlacementMapper`` draws
    round it.

    Parameters
    ----------
    text_property : vtkTextProperty
        The labels' text property (font, size, justification).
    texts : sequence of str, length k
        The labels.
    margin : float
        The mapper's margin, px.
    dpi : int
        The render window's dpi (font sizes are points).

    Returns
    -------
    ndarray, shape (k, 4)
        (left, right, bottom, top) px from the anchor's display pixel.
    """
    from vtkmodules.vtkRenderingCore import vtkTextRenderer

    renderer = vtkTextRenderer.GetInstance()
    out = []
    for text in texts:
        bbox = [0, 0, 0, 0]
        renderer.GetBoundingBox(text_property, text, bbox, dpi)
        offset = text_property.GetLineOffset()
        out.append([bbox[0] - margin, bbox[1] + margin, bbox[2] - offset - margin, bbox[3] - offset + margin])
    return np.asarray(out, float).reshape(-1, 4)


def new_view(renderer, seen: tuple | None) -> tuple | None:
    """What texts placed on screen depend on (the camera's modification time, the view's size
    and origin, the window's dpi last: font sizes are points), when it differs from ``seen``
    (the last placing's) and the view has pixels to place in; else None: nothing to place."""
    window = renderer.GetVTKWindow()
    dpi = int(window.GetDPI()) if window is not None else 72
    stamp = renderer.GetActiveCamera().GetMTime(), tuple(renderer.GetSize()), tuple(renderer.GetOrigin()), dpi
    return None if stamp == seen or min(renderer.GetSize()) <= 1 else stamp
