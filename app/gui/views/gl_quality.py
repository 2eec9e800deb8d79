"""Render quality of the 3D views by the OpenGL renderer found at start.

On a software renderer (Mesa llvmpipe / softpipe / swrast, SwiftShader, Windows' basic
renderer; virtual machines, Xvfb, remote desktops) multisampling triples a frame's cost and
depth peeling (order-independent translucency) doubles it, so both stay off there. On a
hardware renderer the views get FXAA (a post-pass, so it applies to a window already made),
4x multisampling where the window can still take it, and depth peeling of the translucent glyphs.
The renderer is asked once, from the first render window (``detect``), and kept.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

#: Substrings (lower case) of the OpenGL renderer string of software renderers.
SOFTWARE_RENDERERS = ("llvmpipe", "softpipe", "swrast", "software", "swiftshader", "gdi generic",
                      "microsoft basic render", "mesa offscreen", "lavapipe")


@dataclass(frozen=True)
class GlQuality:
    """The settings a view's render window gets: ``multisamples`` and ``depth_peeling``."""

    renderer: str
    software: bool
    multisamples: int
    depth_peeling: bool


def renderer_string(capabilities: str) -> str:
    """The renderer from VTK's ``ReportCapabilities()`` text ('' when it names none)."""
    match = re.search(r"OpenGL renderer string:[ \t]*(.*)", capabilities or "")
    return match.group(1).strip() if match else ""


def quality_for(renderer: str) -> GlQuality:
    """The settings for an OpenGL ``renderer`` string; an unknown ('') renderer counts as software
    (the cheap settings are always correct, only less smooth)."""
    name = renderer.lower()
    software = not name or any(s in name for s in SOFTWARE_RENDERERS)
    if software:
        return GlQuality(renderer, True, 0, False)
    return GlQuality(renderer, False, 4, True)


_DETECTED: GlQuality | None = None


def detect(ren_win) -> GlQuality:
    """The quality for the renderer behind ``ren_win`` (an initialised render window), asked once."""
    global _DETECTED
    if _DETECTED is None:
        _DETECTED = quality_for(renderer_string(ren_win.ReportCapabilities()))
    return _DETECTED


def apply(plotter, quality: GlQuality) -> None:
    """Set ``plotter``'s multisampling and translucency to ``quality``."""
    plotter.ren_win.SetMultiSamples(quality.multisamples)
    plotter.renderer.SetUseOIT(False)
    if quality.depth_peeling:
        plotter.enable_depth_peeling()
    else:
        plotter.renderer.SetUseDepthPeeling(False)
    plotter.renderer.SetUseFXAA(not quality.software)
