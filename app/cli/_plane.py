"""``--plane AXIS=MM``: which plane of a 3D box map a figure shows (``isoforce map``, ``isoforce figure``)."""
from __future__ import annotations

from app.cli._args import UsageError
from app.logic.planes import default_plane, is_volume, parse_plane


def add_plane_argument(parser) -> None:
    parser.add_argument("--plane", metavar="AXIS=MM",
                        help="a device with a 3D box map (e.g. the Novint Falcon): the plane a figure shows, "
                             "e.g. z=110 (mm along one of the box's axes; the nearest grid plane is drawn and "
                             "named). Default: the preset's plane, the one the app opens on. With .csv/.npz "
                             "it writes that plane's data instead of the whole volume's")


def plane_of(text: str | None, grid, preset) -> tuple[str, float] | None:
    """The plane ``(axis, m)`` of the 3D box ``grid`` that ``--plane`` names (default: the preset's);
    None for a 2D map without ``--plane``; a UsageError naming --plane otherwise."""
    if text is None:
        if not is_volume(grid):
            return None
        return default_plane(grid, preset.mechanism, preset.pose)
    try:
        return parse_plane(text, grid, preset.mechanism, name="--plane")
    except ValueError as exc:
        raise UsageError(f"{exc} (preset {preset.key!r})") from None
