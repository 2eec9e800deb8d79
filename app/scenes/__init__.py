"""PyVista scene builders shared by the desktop app and the headless ``figure`` command.

Each ``draw_*`` function adds named actors to a plotter from plain arrays, so the same code
draws in the Qt window and in an off-screen plotter. One module per scene, and what they
share:

================  ==========================================================================
``pose``          a device's links and its force glyphs at one pose (``draw_pose_scene``)
``workspace``     a workspace map's quantity in 3D (``draw_workspace``, ``draw_box_workspace``)
``classes``       a class quantity there as the map view draws it: its colours and names
``slice_mesh``    a 2D map's samples as that scene's mesh (revolved or flat), filled at its edge
``iso_labels``    the workspace's iso-surface labels, kept apart on screen, and its axes in mm
                  (``workspace_annotations``)
``volume_axes``   a volume's three axes in mm on its box's outer edges, placed at each render
``screen``        where world points and texts fall on screen (display pixels, text boxes)
``common``        actors found by name and redrawn cheaply; points lifted to 3D (``to_3d``)
================  ==========================================================================

The public names of the scene modules are here too (``from app import scenes; scenes.draw_pose_scene``),
each loaded with its module on first use (PEP 562): a pose figure does not import the workspace's
modules, nor a workspace figure the pose's (each module costs its import on every ``isoforce figure``).
"""
from __future__ import annotations

from kinematics.lazy import public_names

#: Each scene module and the public names it lends the package, in the order above.
_HOMES = {
    "classes": ("class_key", "class_lookup_table", "class_names"),
    "common": ("actor_named", "to_3d"),
    "iso_labels": (
        "ISO_LABEL_ACTOR", "ISO_LABEL_CANDIDATES", "ISO_LABEL_FONT_SIZE", "ISO_LABEL_GAP", "ISO_LABEL_MARGIN",
        "ISO_LABELS", "iso_label_candidates", "iso_label_points", "label_iso_surfaces", "spread_labels",
        "workspace_annotations",
    ),
    "pose": (
        "ACTUATOR_COLOURS", "BALL_FRACTION", "COLOURS", "GLYPH_ACTORS", "SPHERE_OVER_BALL", "TUBE_FRACTION",
        "device_size", "draw_desired_force", "draw_ellipsoid", "draw_links", "draw_polytope", "draw_pose_scene",
        "draw_reference_forces", "draw_sphere", "ellipsoid_mesh", "force_scale", "frame_pose_camera", "glyph_drawn",
        "hide_glyph", "inertia_scale", "polytope_edges", "polytope_mesh", "pose_scale", "velocity_scale",
    ),
    "pose_legend": (
        "LEGEND", "colour_name", "drawn_forces_text", "force_values_text", "inertia_text", "legend_rows",
        "pose_caption",
    ),
    "screen": ("display_points", "iso_label_boxes"),
    "slice_mesh": ("is_revolved",),
    "volume_axes": (
        "VOLUME_AXES", "VOLUME_BOX", "axes_margin", "axis_ticks", "outer_edges", "remove_volume_axes", "volume_axes",
        "widget_box",
    ),
    "workspace": (
        "BAR_LOOK", "BOX_ACTORS", "CUT_FACE_ACTOR", "ISO_LEVELS", "ISO_PERCENTILES", "SMOOTH_ITERATIONS",
        "SMOOTH_PASS_BAND", "WORKSPACE_MAX_POINTS", "WORKSPACE_MODES", "bar_title", "box_caption", "box_image",
        "box_scene_parts", "clear_clip_plane", "clear_workspace_scene", "colour_range", "draw_box_workspace",
        "draw_workspace", "flat_axes", "frame_workspace_camera", "iso_levels", "workspace_volume",
    ),
}
_MODULE_OF = {name: module for module, names in _HOMES.items() for name in names}
__all__ = list(_MODULE_OF)


__getattr__, __dir__ = public_names(__name__, _MODULE_OF)
