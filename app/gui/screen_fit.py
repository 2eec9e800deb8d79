"""Where the main window goes on a screen, and how its docks share a narrow one (no Qt).

A first start opens ``DEFAULT_SIZE`` where the screen has room and the screen's available area
where it has not (a 1366 x 768 laptop showed a 1600 x 950 window with its statistics dock, status
bar and the map's x axis off screen); a saved geometry larger than today's screen is shrunk to
it. Below ``NARROW_SCREEN_PX`` of available width three columns of docks leave the map and 3D
views too little room, so the statistics and optimize docks are tabbed with the design dock.
"""
from __future__ import annotations

#: Window size on a first start where the screen has room (no saved layout), px.
DEFAULT_SIZE = (1600, 950)
#: Below this available width (px) the right-hand docks join the design dock as tabs.
NARROW_SCREEN_PX = 1500


def fitted_rect(available: tuple[int, int, int, int], wanted: tuple[int, int] = DEFAULT_SIZE,
                at: tuple[int, int] | None = None) -> tuple[int, int, int, int]:
    """The window's frame ``(x, y, width, height)`` inside the screen's ``available`` area.

    Parameters
    ----------
    available : (x, y, width, height)
        The screen's available geometry (without task bars), px.
    wanted : (width, height)
        The size asked for (``DEFAULT_SIZE`` or a saved one), px.
    at : (x, y), optional
        Where the frame's top-left corner was (a saved geometry); default: centred.

    Returns
    -------
    (x, y, width, height)
        No larger than ``available`` and wholly inside it.

    Examples
    --------
    >>> fitted_rect((0, 0, 1366, 768))
    (0, 0, 1366, 768)
    >>> fitted_rect((0, 0, 1920, 1080))
    (160, 65, 1600, 950)
    >>> fitted_rect((0, 0, 1920, 1080), (1000, 700), at=(1500, 900))
    (920, 380, 1000, 700)
    """
    ax, ay, aw, ah = available
    width, height = min(wanted[0], aw), min(wanted[1], ah)
    if at is None:
        x, y = ax + (aw - width) // 2, ay + (ah - height) // 2
    else:
        x = min(max(at[0], ax), ax + aw - width)
        y = min(max(at[1], ay), ay + ah - height)
    return x, y, width, height


def narrow_screen(available_width: int) -> bool:
    """Whether the docks share one column (``NARROW_SCREEN_PX``).

    >>> narrow_screen(1280), narrow_screen(1920)
    (True, False)
    """
    return available_width < NARROW_SCREEN_PX
