"""The 3D workspace view: the map revolved into a volume, cut by a plane or as iso-surfaces.

A 3D box map (a delta's) is drawn as it is: its workspace boundary, iso-surfaces of the
chosen quantity and the plane the map view shows (``scenes.draw_box_workspace``). Its coarse
maps are drawn too (at most 24^3 points), so the volume follows a design slider; moving the
plane only replaces the plane's geometry.

The meshes (a volume, its cut, contours, smoothing) are built on a worker thread of their own
(``app.scenes.workspace_job`` on a ``QtJobRunner``, newest wins): the GUI thread only swaps the
actors and renders, and the scene shown stays until its successor is ready. A moved plane of
a box map is cut from the kept volume at once, on the GUI thread (a millisecond).

See-through surfaces are what a software-OpenGL frame spends its time on (a 60^3 Falcon volume:
~350 ms with the translucent boundary and iso-surfaces, ~50 ms for the plane alone). So while a
slider is held (``state.interaction``) only cheap geometry is drawn: dragging the plane shows
the plane alone, dragging a design parameter its iso-surfaces opaque without the boundary; the
full look comes back when the slider is released.

The camera (``plotter_widget``): drag turns it about the scene's centre, the wheel zooms towards
the cursor, ``R`` or "Reset view" frames the scene again; each device keeps its own camera.
Planar devices' maps are flat coloured surfaces seen from above. Axes are labelled in mm and
each iso-surface with its value (``scenes.workspace_annotations``).
"""
from __future__ import annotations

from PySide6.QtWidgets import QComboBox, QHBoxLayout, QLabel, QVBoxLayout, QWidget

from app.gui.qt_model import QtJobRunner
from app.gui.views import camera, dextrous_layer
from app.gui.views.camera import CameraState, shown_bounds
from app.gui.views.dextrous_layer import DextrousLayer
from app.gui.views.plotter_widget import PlotterWidget
from app.gui.volumes import is_volume
from app.scenes import WORKSPACE_MODES as MODES  # noqa: F401 (re-exported)
from app.scenes import (
    axes_margin,
    box_scene_parts,
    clear_clip_plane,
    clear_workspace_scene,
    frame_workspace_camera,
    is_revolved,
    workspace_annotations,
)
from app.scenes.workspace_job import BOX, SceneRequest, build_scene, show_scene

#: The share of the view left free on each side when framing: the mm axes' labels sit there.
AXES_MARGIN = 0.14
#: Per held slider (``AppModel.interaction``): actor -> opacity while it is held (0: hidden).
DRAG_LOOKS = {"plane": {"box_hull": 0.0, "workspace": 0.0}, "design": {"box_hull": 0.0, "workspace": 1.0}}


class WorkspaceView(QWidget):
    """Shows ``state.current`` as a 3D volume; redrawn only for full maps and while visible."""

    def __init__(self, state, parent=None) -> None:
        super().__init__(parent)
        self.state = state
        self.mode = QComboBox()
        self.mode.addItems(MODES)
        self.mode.setToolTip("Cut the revolved workspace with a draggable plane, or show iso-surfaces.")
        self.mode_label = QLabel("Show:")
        # A 3D box map shows its iso-surfaces and the map view's plane together: no mode to choose.
        self.box_label = QLabel("Iso-surfaces and the map view's plane (move it there)")
        bar = QHBoxLayout()
        bar.addWidget(self.mode_label)
        bar.addWidget(self.mode)
        bar.addWidget(self.box_label)
        bar.addStretch(1)
        # Off-screen VTK painted as an image (see ``plotter_widget``).
        self.view = PlotterWidget(self)
        self.plotter = self.view.plotter
        self.plotter.set_background("white")
        self.plotter.add_axes()
        self.view.fit = self.fit_camera
        # Devices with orientation freedoms: their semi-dextrous region, on request.
        self.dextrous = DextrousLayer(state, self.plotter, self.view.request_render, self._refit, self._annotate)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addLayout(bar)
        layout.addWidget(self.dextrous)         # a row of its own: the view's width stays the map's to take
        layout.addWidget(self.view)
        self._drawn = None                  # the key of the scene shown (``redraw``)
        self._scene_of = None               # the preset key of that scene
        self._wanted = None                 # the key of the scene being built, if any
        self._box_cache: dict = {}          # the volume's meshes while only the plane moves
        self._shown_volume = None           # the box volume drawn (its image, by identity)
        # The scene's meshes are built off the GUI thread, newest wins (``app.scenes.workspace_job``).
        self.builder = QtJobRunner(build_scene, self, name="isoforce-scene")
        self.builder.resultReady.connect(self._on_built)
        self._camera_for = None
        self._cameras: dict = {}            # preset key -> CameraState the user left it at
        self._looks: dict = {}              # actor name -> (actor, its own opacity) before a drag look
        self._show_mode_controls()
        self.mode.currentTextChanged.connect(lambda _: self.redraw(force=True))
        state.mapChanged.connect(self.redraw)
        state.quantityChanged.connect(self.redraw)
        state.sliceChanged.connect(self.redraw)
        state.presetChanged.connect(self._show_mode_controls)
        state.interactionChanged.connect(self._on_interaction)

    def _show_mode_controls(self) -> None:
        """The mode to choose for a revolved slice only: a box map shows both its views at once,
        a flat picture has one (``draw_workspace``)."""
        box = is_volume(self.state.preset.grid)
        revolved = is_revolved(self.state.mechanism, self.state.preset.grid)
        self.mode_label.setVisible(revolved)
        self.mode.setVisible(revolved)
        self.box_label.setVisible(box)

    def showEvent(self, event) -> None:   # noqa: N802 (Qt name)
        super().showEvent(event)
        self.redraw()

    def redraw(self, force: bool = False) -> None:
        """Show the current map's scene: at once when only a box map's plane moved (its volume's
        meshes are kept), else built on the scene worker (``builder``) and shown when it arrives."""
        st = self.state
        slot = st.current
        box = slot is not None and is_volume(slot.map.grid)
        # Leave out what is not seen: no volume while hidden, none for coarse drag maps of a
        # revolved slice (hundreds of thousands of cells); a 3D box's coarse volume is small.
        if (slot is None or not self.isVisible() or (slot.stage != "full" and not box)
                or st.quantity not in slot.map.values or getattr(self.plotter, "_closed", False)):
            if slot is not None and self.isVisible() and self._scene_of not in (None, st.preset.key):
                self._clear(f"The workspace of {st.preset.name} is drawn once its full map is ready.")
            return
        if box:
            key = (slot.generation, st.quantity, st.slice_axis, st.slice_value, BOX)
            request = SceneRequest(slot.map, st.quantity, st.mechanism, BOX, st.slice_axis, st.slice_value, key)
        else:
            key = (slot.generation, st.quantity, self.mode.currentText())
            request = SceneRequest(slot.map, st.quantity, st.mechanism, self.mode.currentText(), view_key=key)
        if key == self._drawn and not force:
            return
        cache = self._box_cache
        if box and cache.get("map") is slot.map and cache.get("quantity") == st.quantity:
            # Only the plane moved: a new cut of the kept volume (a millisecond), here.
            parts = box_scene_parts(slot.map, st.quantity, st.slice_axis, st.slice_value, cache=cache,
                                    mechanism=st.mechanism)
            self._wanted = None
            self.builder.cancel(request.tag)
            self._show(request, parts)
            return
        if key == self._wanted and not force:
            return              # being built
        self._wanted = key
        self.builder.submit(request)

    def _on_built(self, request: SceneRequest, parts) -> None:
        """A scene built on the worker: shown if it is still the one wanted (a newer map, quantity,
        plane or mode asked for another meanwhile: dropped)."""
        slot = self.state.current
        if (not self.builder.is_current(request) or request.view_key != self._wanted
                or slot is None or slot.map is not request.workspace_map          # another device's, say
                or getattr(self.plotter, "_closed", False)):
            return
        self._wanted = None
        if isinstance(parts, Exception):
            self.view.set_caption(f"The 3D scene could not be drawn: {parts}")
            return
        self._show(request, parts)

    def _show(self, request: SceneRequest, parts: dict) -> None:
        """Swap the scene's actors for ``parts`` (of ``request``), frame, label and render it."""
        st = self.state
        box = request.mode == BOX
        with self.view.quiet():
            self.view.set_caption("")
            if box:
                if self._drawn is None or self._drawn[-1] != BOX:
                    clear_clip_plane(self.plotter)      # the revolved slice's cut plane, if any
                same = self._drawn is not None and self._drawn[-1] == BOX and self._shown_volume is parts.get("image")
                show_scene(self.plotter, request, parts, same_volume=same)
                self._box_cache = {"map": request.workspace_map, "quantity": request.quantity,
                                   "volume": {k: v for k, v in parts.items() if k not in ("plane", "at")}}
                self._shown_volume = parts.get("image")
            else:
                self._box_cache = {}
                self._shown_volume = None
                show_scene(self.plotter, request, parts)
            self._annotate()
            if st.preset.key != self._camera_for:
                # Each device keeps its camera: the one it was left at, else a framing of it.
                if self._camera_for is not None:
                    self._cameras[self._camera_for] = CameraState.of(self.plotter.renderer)
                kept = self._cameras.get(st.preset.key)
                if kept is None:
                    self.view.reset_camera()
                else:
                    kept.apply(self.plotter.renderer)
                    self.view.fitted = False
                self._camera_for = st.preset.key
            self._drawn = request.view_key
            self._scene_of = st.preset.key
            self._apply_look()
        self.view.request_render()

    def _clear(self, caption: str) -> None:
        """Take another device's scene away (a slice's coarse map draws none): switched from the
        Falcon to the Twin-Pantograph, the Falcon's iso-surfaces, caption and colour bar stayed
        beside the new device's semi-dextrous region until its full map came."""
        with self.view.quiet():
            clear_workspace_scene(self.plotter)
            self._box_cache, self._shown_volume = {}, None
            self._drawn = self._scene_of = None
            self._annotate()
            self.view.set_caption(caption)
        self.view.request_render()

    def _annotate(self) -> None:
        """The iso-surfaces' labels and the axes in mm, round the scene and the semi-dextrous
        region if shown (a solid beyond the flat map: the map's own box put the axes' labels
        over it)."""
        workspace_annotations(self.plotter, self.state.quantity, also=(dextrous_layer.ACTOR,))

    def _refit(self) -> None:
        """Frame the scene again if the camera is still where a fit left it (``PlotterWidget.fitted``)."""
        if self.view.fitted:
            self.view.reset_camera()

    def fit_camera(self) -> None:
        """Frame the scene: flat maps square on (a planar one from above), volumes and a shown
        semi-dextrous region (a solid around the flat slice) obliquely."""
        if self.plotter.actors.get(dextrous_layer.ACTOR) is not None:
            self.plotter.view_isometric(render=False)
        else:
            frame_workspace_camera(self.plotter, self.state.mechanism, self.state.preset.grid)
        camera.fit_bounds(self.plotter.renderer, shown_bounds(self.plotter),
                          margin=axes_margin(self.plotter, AXES_MARGIN))

    def _apply_look(self) -> None:
        """Cheap geometry while a slider is held (``DRAG_LOOKS``), each actor's own look otherwise."""
        look = DRAG_LOOKS.get(self.state.interaction, {})
        for name in ("box_hull", "workspace"):
            actor = self.plotter.actors.get(name)
            if actor is None:
                continue
            kept = self._looks.get(name)
            if kept is None or kept[0] is not actor:        # a new actor: remember its own opacity
                kept = self._looks[name] = (actor, actor.prop.opacity)
            opacity = look.get(name, kept[1])
            actor.SetVisibility(opacity > 0)
            actor.prop.opacity = opacity if opacity > 0 else kept[1]
        # The plane's blank (infeasible) cells are see-through, which makes the whole plane a
        # translucent actor; alone in the view while dragged, they may as well be opaque white.
        plane = self.plotter.actors.get("box_plane")
        if plane is not None:
            lut = plane.mapper.lookup_table
            kept = self._looks.get("box_plane")
            if kept is None or kept[0] is not lut:
                kept = self._looks["box_plane"] = (lut, tuple(lut.GetNanColor()))
            nan = (1.0, 1.0, 1.0, 1.0) if self.state.interaction == "plane" else kept[1]
            if tuple(lut.GetNanColor()) != nan:
                lut.SetNanColor(*nan)
                plane.mapper.Modified()

    def _on_interaction(self) -> None:
        if self._drawn is not None and self._drawn[-1] == "box" and self.isVisible():
            self._apply_look()
            self.view.request_render()

    def close_plotter(self) -> None:
        self.dextrous.shutdown()        # before the plotter: no region or scene may arrive at a closed one
        self.builder.shutdown()
        self.view.close_plotter()
