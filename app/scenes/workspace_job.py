"""The workspace scene's meshes as a background job: the app's 3D workspace view builds them off
the GUI thread and only swaps the actors on it.

A ``SceneRequest`` names the map, quantity, design and how it is shown (a revolved or flat
slice's mode, or a 3D box map's plane); ``build_scene`` is the job ``app.jobs.runner.JobRunner``
runs (``job(request, progress, cancelled)``), returning the parts ``show_scene`` draws:
``workspace_parts`` or ``box_scene_parts`` (``app.scenes.workspace``). VTK's filters release
Python's interpreter lock while they run, so the GUI thread keeps turning meanwhile (the
Falcon's iso-surfaces and boundary, smoothed, took 150-350 ms of it; the Inverse3's revolved
slice, cut, 250 ms). Rendering stays on the GUI thread (``app.gui.views.plotter_widget``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

from app.scenes.workspace import box_scene_parts, show_box_parts, show_workspace_parts, workspace_parts
from kinematics.contract import Mechanism
from metrics.workspace import WorkspaceMap

#: A 3D box map's "mode": its boundary, iso-surfaces and the map view's plane.
BOX = "box"


@dataclass(frozen=True, eq=False)
class SceneRequest:
    """One workspace scene to build: ``mode`` is one of ``WORKSPACE_MODES`` for a 2D map (drawn as
    the app draws it: ``interactive``), or ``BOX`` with the plane ``slice_axis`` at ``slice_value`` (m).
    ``view_key`` is the caller's name for what it asked (returned with the result)."""

    workspace_map: WorkspaceMap
    quantity: str
    mechanism: Mechanism
    mode: str
    slice_axis: str | None = None
    slice_value: float | None = None
    view_key: Any = None
    tag: str = "workspace"
    generation: int = field(default=-1, compare=False)


def build_scene(request: SceneRequest, progress: Callable[[float], None], cancelled: Callable[[], bool]) -> dict:
    """The job: the parts of ``request``'s scene (``Cancelled`` raised between steps once a newer one is asked)."""
    if request.mode == BOX:
        return box_scene_parts(request.workspace_map, request.quantity, request.slice_axis, request.slice_value,
                               mechanism=request.mechanism, cancelled=cancelled)
    return workspace_parts(request.workspace_map, request.quantity, request.mechanism, request.mode,
                           interactive=True, cancelled=cancelled)


def show_scene(plotter, request: SceneRequest, parts: dict, *, same_volume: bool = False) -> None:
    """Draw ``build_scene``'s ``parts`` of ``request`` (on the GUI thread: actors only)."""
    if request.mode == BOX:
        show_box_parts(plotter, parts, request.quantity, request.slice_axis, same_volume=same_volume)
    else:
        show_workspace_parts(plotter, parts, interactive=True)
