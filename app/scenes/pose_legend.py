"""What the pose scene says about itself: the legend's rows in the colours drawn, the caption
with the forces and drawing scales, and colour names for the text.
"""
from __future__ import annotations

import colorsys
import functools

import numpy as np

from app.logic.glyphs import seen_colour
from app.scenes.common import actor_named

#: Colours: links grey, polytope blue, isotropic sphere green, force ellipsoid orange,
#: velocity ellipsoid purple, inertia ellipsoid dark cyan (teal: a hue between the sphere's green
#: and the polytope's blue, darker than the clamped arrow's cyan), reference arrows per actuator,
#: desired red / clamped cyan (text naming them asks ``colour_name``).
from app.scenes.pose import (
    COLOURS,
    GLYPH_ACTORS,
    glyph_drawn,
    inertia_scale,
)
from metrics import wrenches

#: Names of hues for text that names a drawn colour (a tooltip): each band's upper end, degrees.
HUE_NAMES = ((15, "red"), (45, "orange"), (70, "yellow"), (165, "green"), (200, "cyan"), (255, "blue"),
             (290, "purple"), (340, "pink"), (360, "red"))


#: Below this saturation (HLS) a colour is named by its lightness: black, grey or white.
GREY_SATURATION = 0.15


def colour_name(colour: str) -> str:
    """A plain English name of ``colour`` (``"#rrggbb"``), by its hue (``HUE_NAMES``).

    Examples
    --------
    >>> colour_name(COLOURS["clamped"]), colour_name(COLOURS["sphere"]), colour_name(COLOURS["desired"])
    ('cyan', 'green', 'red')
    """
    red, green, blue = (int(colour[k:k + 2], 16) / 255.0 for k in (1, 3, 5))
    hue, lightness, saturation = colorsys.rgb_to_hls(red, green, blue)
    if saturation < GREY_SATURATION:
        return "black" if lightness < 0.15 else "white" if lightness > 0.9 else "grey"
    return next(name for top, name in HUE_NAMES if hue * 360.0 < top)


#: Legend rows per glyph: (label, colour).
LEGEND = {
    "links": (("links", COLOURS["links"]),),
    "polytope": (("force polytope", COLOURS["polytope"]),),
    "sphere": (("inscribed sphere", COLOURS["sphere"]),),
    "force_ellipsoid": (("force ellipsoid", COLOURS["force_ellipsoid"]),),
    "velocity_ellipsoid": (("velocity ellipsoid", COLOURS["velocity_ellipsoid"]),),
    "inertia_ellipsoid": (("inertia ellipsoid", COLOURS["inertia_ellipsoid"]),),
    "desired_force": (("desired force", COLOURS["desired"]), ("clamped force", COLOURS["clamped"])),
}


#: Per legend row of ``LEGEND``: the actors whose colour on screen its swatch takes, the first drawn.
LEGEND_ACTORS = {"links": ("links",), "force polytope": ("polytope", "polytope_edges"),
                 "desired force": ("desired_force",), "clamped force": ("clamped_force",)}


def drawn_colour(actor) -> str:
    """The colour (``"#rrggbb"``) ``actor`` shows on a white background, lit head on: its colour
    where opaque; a translucent one's blended with the white (``seen_colour``), a closed
    surface's two sheets (front and back: a spatial surface with faces) where a flat one (z = 0) is one."""
    prop = actor.GetProperty()
    colour = "#" + "".join(f"{int(round(255 * v)):02x}" for v in prop.GetColor())
    opacity = float(prop.GetOpacity())
    if opacity >= 1.0:
        return colour
    mesh = actor.GetMapper().GetInput()
    bounds = mesh.GetBounds()
    # (Plain floats, not numpy: the legend asks at every slider step.)
    flat = bounds[5] - bounds[4] <= 1e-12 * max(max(bounds) - min(bounds), 1e-300)
    layers = 1 if flat or mesh.GetNumberOfPolys() == 0 else 2
    return _seen_colour(colour, opacity, layers)


@functools.lru_cache(maxsize=64)
def _seen_colour(colour: str, opacity: float, layers: int) -> str:
    """``seen_colour``, kept: a legend asks the same few at every slider step (~0.1 ms each)."""
    return seen_colour(colour, opacity, layers)


def legend_rows(plotter, joint_names) -> list[tuple[str, str]]:
    """(label, colour) of every glyph drawn in ``plotter`` now (its actors), in menu order; an
    actuator's arrow is named after its joint (``joint_names``, the mechanism's), as the
    captions name the bottleneck ("theta_0 at full torque" beside "theta_0 limits").

    Each colour is the one the glyph shows (``drawn_colour``): a translucent surface's blended
    with the background, an outline's its own; a row whose actor is not drawn is left out."""
    rows = []
    for glyph, names in GLYPH_ACTORS.items():
        if glyph == "reference_forces":
            rows += [(f"{joint} at full torque", drawn_colour(actor)) for joint, name in zip(joint_names, names)
                     if (actor := actor_named(plotter, name)) is not None]
            continue
        if not glyph_drawn(plotter, glyph):
            continue
        for label, _ in LEGEND[glyph]:
            actors = [actor_named(plotter, name) for name in LEGEND_ACTORS.get(label, (glyph,))]
            actor = next((a for a in actors if a is not None), None)
            if actor is not None:
                rows.append((label, drawn_colour(actor)))
    return rows


def force_values_text(desired, clamped, along: float = float("nan")) -> str:
    """The desired and clamped forces with their components and magnitudes in N, which clamp
    it is (paper 000 eq. 9: to the isotropic force, the same in every direction), and ``along``,
    the largest force the actuators hold in the desired direction (``PoseReport.force_along``;
    left out where nan), so the clamp is not read as that."""
    def row(v):
        v = np.asarray(v, float)
        # "magnitude", not "|F|": a line may break after a "|", which split the norm in the caption.
        return "(" + ", ".join(f"{c:.3g}" for c in v) + f") N, magnitude {np.linalg.norm(v):.3g} N"
    text = f"desired {row(desired)}; clamped to the isotropic force {row(clamped)}"
    if np.isnan(along):
        return text
    return text + ("; no actuator limits its direction" if np.isinf(along)
                   else f"; the actuators hold up to {along:.3g} N in its direction")


def drawn_forces_text(plotter, mechanism, report, desired_force) -> str:
    """``force_values_text`` of the desired force (its force rows) and its clamp, when their
    arrows are drawn in ``plotter``; ``""`` otherwise. The app's caption and the exported
    figure's both print it: the clamped arrow lies inside the desired one and the glyphs."""
    if all(actor_named(plotter, n) is None for n in ("desired_force", "clamped_force")):
        return ""
    rows = list(wrenches.force_rows(mechanism)) if mechanism.has_orientation else slice(None)
    desired = np.asarray(desired_force, float)[rows]
    return force_values_text(desired, report.clamp(desired), report.force_along(desired) if desired.any() else np.nan)


def inertia_text(plotter, mechanism, report, glyphs) -> str:
    """What the caption says of the inertia ellipsoid: its scale (``inertia_scale``) where it is
    drawn in ``plotter``; where it is asked for (``glyphs``) but a direction's apparent mass is
    infinite (the handle cannot move along it: an inverse singularity), that direction instead
    of an endless axis; else ``""``.
    """
    ell = getattr(report, "inertia_ellipsoid", None)
    if glyph_drawn(plotter, "inertia_ellipsoid"):
        mm = 0.1 * inertia_scale(mechanism) * 1e3
        return f"inertia ellipsoid at 0.1 kg = {mm:.3g} mm"
    if "inertia_ellipsoid" not in glyphs or ell is None or not report.reachable:
        return ""
    radii = np.asarray(ell.radii, float)
    if np.any(np.isnan(radii)):
        return ""
    infinite = np.isinf(radii)
    if not np.any(infinite):
        return ""
    finite = ", ".join(f"{r:.3g}" for r in radii[~infinite])
    along = "; ".join("(" + ", ".join(f"{c:+.2f}" for c in np.asarray(ell.axes, float)[:, k]) + ")"
                      for k in np.flatnonzero(infinite))
    rest = f" (the others {finite} kg)" if finite else ""
    return (f"inertia ellipsoid not drawn: the apparent mass is infinite along {along}, where the handle "
            f"cannot move{rest}")


def pose_caption(report, scale: float, velocity_scale: float | None = None, inertia: str = "") -> str:
    """The numbers under the pose view: forces, bottleneck, conditioning, the drawing scale.

    ``velocity_scale`` (m per m/s): the velocity ellipsoid's scale, said only when the
    ellipsoid is drawn (None: it is not; ``glyph_drawn``, as the legend says). ``inertia``:
    ``inertia_text``'s, appended to the scales' line where not empty.
    """
    if not report.reachable:
        return "pose unreachable"
    where = "" if report.feasible else " [outside the joint limits]"
    scaling = getattr(report, "condition_number_scaling", None)
    if scaling is not None:
        velocity = ("" if velocity_scale is None
                    else f"; linear velocity ellipsoid at 1 m/s = {velocity_scale * 1e3:.0f} mm")
        return (f"at zero moment: isotropic force {report.isotropic_force:.3g} N, anisotropic "
                f"{report.anisotropic_force:.3g} N; at zero force: isotropic moment "
                f"{report.isotropic_moment:.3g} N m, anisotropic {report.anisotropic_moment:.3g} N m{where}\n"
                f"condition {report.condition_number:.3g} (moments scaled by L = {scaling['length_m'] * 1e3:.3g} mm); "
                f"forces drawn at 10 N = {10 * scale * 1e3:.0f} mm{velocity}{_then(inertia)}")
    velocity = "" if velocity_scale is None else f"; velocity ellipsoid at 1 m/s = {velocity_scale * 1e3:.0f} mm"
    return (f"isotropic force {report.isotropic_force:.3g} N ({report.bottleneck_phrase}), "
            f"anisotropic {report.anisotropic_force:.3g} N, condition {report.condition_number:.3g}{where}\n"
            f"forces drawn at 10 N = {10 * scale * 1e3:.0f} mm{velocity}{_then(inertia)}")


def _then(text: str) -> str:
    return f"; {text}" if text else ""
