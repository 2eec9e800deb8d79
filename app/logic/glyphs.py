"""The glyphs of the 3D pose view and what each needs computed. No Qt: the headless
``isoforce figure`` uses this too."""
from __future__ import annotations

import numpy as np

#: Glyphs of the 3D pose view, in menu order, with a one-line tooltip each.
GLYPHS = {
    "links": "The mechanism's links and joints at the selected pose.",
    "polytope": "Force polytope: every force the actuators can hold here (translucent, edges drawn).",
    "sphere": "Inscribed sphere: its radius is the maximum isotropic force (paper 000 eq. 8).",
    "force_ellipsoid": "Force ellipsoid {f : |diag(1/t) J^T f| <= 1}, inside the polytope.",
    "velocity_ellipsoid": "Velocity ellipsoid for unit joint rates {J qdot : |qdot| <= 1 rad/s}.",
    "inertia_ellipsoid": ("Inertia ellipsoid: each semi-axis is the apparent mass a hand pushing along it "
                          "feels (kg, links and rotors; devices with a mass model)."),
    "reference_forces": "Arrows of each actuator's force at full torque (columns of J^-T diag(t)).",
    "desired_force": "A desired force and its clamped version (paper 000 eq. 9).",
}
DEFAULT_GLYPHS = frozenset({"links", "polytope", "sphere", "reference_forces", "desired_force"})
#: The parts of ``metrics.pose.analyse_pose`` each glyph needs; hidden glyphs' parts are not computed.
GLYPH_PARTS = {
    "links": (),
    "polytope": ("vertices",),
    "sphere": (),
    "force_ellipsoid": ("force_ellipsoid",),
    "velocity_ellipsoid": ("velocity_ellipsoid",),
    "inertia_ellipsoid": ("inertia_ellipsoid",),
    "reference_forces": ("reference_forces",),
    "desired_force": (),
}


def pose_parts(glyphs) -> frozenset[str]:
    """Union of what the visible glyphs need from the pose analysis."""
    return frozenset(part for glyph in glyphs for part in GLYPH_PARTS[glyph])


def glyph_unavailable(glyph: str, mechanism) -> str | None:
    """Why ``mechanism`` cannot draw ``glyph`` (one sentence), or None where it can.

    The inertia ellipsoid needs the bodies' masses and inertias (``has_mass_model``).
    """
    if glyph == "inertia_ellipsoid" and not mechanism.has_mass_model:
        return (f"No inertia ellipsoid: this device ({type(mechanism).__name__}) has no mass model "
                "(bodies' masses and inertias).")
    return None


#: Closed glyphs (surfaces round the end-effector), in menu order. Several shown at once drawn
#: translucent blended into one blob, with the arrows lost inside it: only the first shown is a
#: surface, the others are outlines (``outlined_glyphs``).
CLOSED_GLYPHS = ("polytope", "sphere", "force_ellipsoid", "velocity_ellipsoid", "inertia_ellipsoid")


def outlined_glyphs(shown) -> frozenset[str]:
    """The closed glyphs among ``shown`` drawn as outlines: all but the first in ``CLOSED_GLYPHS`` order.

    Examples
    --------
    >>> sorted(outlined_glyphs({"links", "sphere", "velocity_ellipsoid", "polytope"}))
    ['sphere', 'velocity_ellipsoid']
    >>> outlined_glyphs({"links", "force_ellipsoid"})
    frozenset()
    """
    closed = [glyph for glyph in CLOSED_GLYPHS if glyph in shown]
    return frozenset(closed[1:])


def seen_colour(colour: str, opacity: float = 1.0, layers: int = 1, background: str = "#ffffff") -> str:
    """The colour (``"#rrggbb"``) a surface of ``colour`` looks over ``background``: ``layers``
    sheets of it, each of ``opacity``, blended over the background (a closed translucent surface
    is two: its front and its back), lit head on.

    Examples
    --------
    >>> seen_colour("#ff0000", 0.5)
    '#ff8080'
    >>> seen_colour("#000000", 0.5, layers=2)
    '#404040'
    >>> seen_colour("#123456")
    '#123456'
    """
    cover = 1.0 - (1.0 - float(opacity)) ** int(layers)
    fg = np.array([int(colour[k:k + 2], 16) for k in (1, 3, 5)], float)
    bg = np.array([int(background[k:k + 2], 16) for k in (1, 3, 5)], float)
    mixed = np.clip(np.round(cover * fg + (1.0 - cover) * bg), 0, 255).astype(int)
    return "#" + "".join(f"{v:02x}" for v in mixed)
