"""The scene view: turns the Qt-free scene into pyvista actors inside a ``DropInteractor``.

It subscribes to the ``Scene`` and, per event, builds, recolours or hides actors, then asks for one
frame; it also picks elements (numpy projection, :mod:`.picking`) and renders images at any scale.
Only the view touches VTK, and only on the GUI thread. NaN is drawn magenta through the lookup
table's NaN colour (docs/metrics.md 5.5); point actors are unlit (exact colour-map colours) unless drawn as shaded
spheres. Big layers get a level-of-detail twin shown while the camera moves, its size set from the
measured time of the moving frames (:mod:`.lod`); at rest they draw only their points that can show
(:mod:`.culling`).
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np
import pyvista as pv
import shiboken6
from PySide6 import QtCore

from ..scene import CURVE_LOCATION, Scene, SceneEvent
from .actors import curve_polylines, display_coordinates, draw_in_front, line_cells, scene_diagonal
from .camera import apply_camera_state, axes_viewport, camera_state, fit_camera, orient_standard_view
from .cloud_layer import MIN_CLOUD_POINTS, CloudFrame, CloudLayer
from .colorbar import ColourBar
from .culling import CulledLayer, RestingCull
from .eye_dome import EyeDome
from .frames import FrameScheduler
from .interactor import ClickFilter, DropInteractor
from .lod import LOD_POINTS, DetailLevel, MotionFilter, lod_order
from .picking import front_pick, near_on_screen, pick_layout
from .style import (
    CLOUD_GREY, CURVE_EDGE, CURVE_VERTEX, MAGENTA, PICK_MARKER, SKELETAL_PLAIN, greyed, make_lut, plain_lut,
)

__all__ = ["SceneView", "EMPTY_HINT"]

EMPTY_HINT = "Drop a cloud and its skeleton here, or File > Open"
KEPT_ACTORS = ("curve-vertices", "curve-samples")
"""Small layers' actors kept (hidden) when dropped and given their next points in place."""


class SceneView:
    """Scene -> actors. ``widget`` is the interactor to put in a window."""

    def __init__(self, scene: Scene, parent: Any = None) -> None:
        self.scene = scene
        self.plotter = DropInteractor(parent, auto_update=False)
        self.widget = self.plotter
        self.plotter.set_background("white")
        self._actors: dict[str, Any] = {}
        self._sources: dict[str, np.ndarray] = {}  # actor name -> the points array it was built from
        self._coloured: dict[str, bool] = {}  # actor name -> coloured by a metric (not its plain colour)
        self._meshes: dict[str, pv.PolyData] = {}  # actor name -> its points
        self._pickable: dict[str, tuple[str, str]] = {}  # actor name -> (layer, location)
        self._lod: dict[str, np.ndarray] = {}  # layer actor name -> indices of its level-of-detail twin
        self._pick_coords: dict[str, np.ndarray] = {}  # actor name -> its points laid out for picking
        self._invalid: dict[str, np.ndarray] = {}  # actor name -> its elements drawn as magenta markers
        self._spare: dict[str, Any] = {}  # KEPT_ACTORS name -> its hidden actor, dropped from the scene
        self.picked: dict[str, Any] | None = None  # the picked element (marked in 3-D until the data changes)
        self._lut: tuple[tuple[tuple[float, float], bool], pv.LookupTable] | None = None
        self._edges_as_tubes: bool | None = None  # how the curve's edge actor was built
        self._colour_bar = ColourBar(self.plotter)
        self._camera_set = False
        self._fit_pending = False
        self.moving = False  # the camera is being moved: level-of-detail twins shown
        self.detail = DetailLevel()  # how many points the twins draw
        self._moving_frames = 0  # frames begun since the camera started moving
        self._full_points = 0  # points of the big layers in the last frame begun at full detail
        self._detail_fitted = False  # the twins' count was set from a full-detail frame of this data
        self._resting = RestingCull()  # at rest, big layers draw only the points that can show
        self._scale = 1  # the scale of the picture being rendered (1: the view itself)
        # every render, also those VTK's interaction starts itself, draws the points of its own camera
        self._start_observer = self.plotter.ren_win.AddObserver("StartEvent", lambda *_: self._before_render())
        self._picture = False  # a picture is being rendered (image()): the cloud drawn whole
        self._closed = False
        self._cloud_layer = CloudLayer(self.plotter, self._cloud_frame)  # the far cloud drawn once (at rest)
        self._frames = FrameScheduler(self.plotter)  # also sets plotter.on_frame
        self.plotter.before_frame = self._before_frame
        self.on_pick: Callable[[dict[str, Any] | None], None] | None = None
        self._click_filter = ClickFilter(self._clicked)
        self.plotter.installEventFilter(self._click_filter)
        self._motion_filter = MotionFilter(self._set_moving)
        self.plotter.installEventFilter(self._motion_filter)
        self._hint = self._make_hint()
        self._axes_shown = False
        self._eye_dome = False
        self.eye_dome = EyeDome(self.plotter)  # the scene shaded, the 2-D overlays on top unshaded
        self._apply_style()
        scene.subscribe(self._on_scene)

    # ---- scene events ---------------------------------------------------------------------
    def _on_scene(self, event: SceneEvent) -> None:
        if event.kind == "layer":
            self._remove_marker()
            self._build(event.layer)
            if f"{event.layer}-lod" in self._actors:
                self._coarse_first = True  # new big data: seen at once through its twins, then in full
            # A new cloud is new data: the camera frames it (and whatever came with it) afresh.
            if self.scene.layers and (not self._camera_set or (event.layer == "cloud" and self.scene.cloud is not None)):
                self._fit_pending = True
                self._camera_set = True
            if not self.scene.layers:
                self._camera_set = False
            self._hint.SetVisibility(not self.scene.layers)
        elif event.kind == "display":
            if event.layer == "curve" and self._edges_as_tubes != self.scene.edges_as_tubes:
                self._build_curve_edges()
            self._apply_display(event.layer)
        elif event.kind in ("quantities", "colouring", "thresholds", "stale"):
            # Only values changed: the skeleton actors are recoloured in place, not rebuilt. The picked
            # element stays marked while only the colouring changes (another metric, thresholds).
            if event.kind == "quantities":
                self._remove_marker()
            # A layer just replaced (its evaluation cleared before its "layer" event, Scene._replace)
            # is rebuilt by that event: coloured once, not twice (an edit's key, docs/performance.md 6.10).
            if not self._replaced("skeletal", "skeletal"):
                self._colour_skeletal()
            if not self._replaced("curve", "curve-vertices"):
                self._colour_curve()
                if self.scene.edges_as_tubes:
                    self._build_curve_edges()
        elif event.kind == "style":
            self._apply_style()
        self._update_scalar_bar()
        self.request_render()

    def _replaced(self, name: str, key: str) -> bool:
        """Layer ``name``'s actor ``key`` was built from points the layer no longer has: the layer
        was replaced and its "layer" event, which rebuilds the actor, is still to come."""
        layer = self.scene.layers.get(name)
        return layer is not None and key in self._sources and self._sources[key] is not layer.points

    def request_render(self) -> None:
        """Render once, soon, however many scene changes arrive meanwhile (see :mod:`.frames`)."""
        self._frames.request()

    @property
    def render_pending(self) -> bool:
        """A frame is due, or the cloud's image (:mod:`.cloud_layer`) is about to be made."""
        return self._frames.pending or self._cloud_layer.build_pending

    def hold_frames(self, seconds: float) -> None:
        """Requested frames wait at most ``seconds`` or until :meth:`release_frames` (an edit's curve
        and its scores in one frame, :mod:`.frames`)."""
        self._frames.hold(seconds)

    def release_frames(self) -> None:
        self._frames.release()

    @property
    def frames_held(self) -> bool:
        """Frames wait for an edit's scores (:meth:`hold_frames`, neither released nor run out)."""
        return self._frames.held

    def draw_now(self) -> None:
        """The pending frame drawn at once, before the panels' repaint (:meth:`.frames.FrameScheduler.draw_now`)."""
        self._frames.draw_now()

    def after_render(self, fn: Callable[[], None]) -> None:
        """Call ``fn`` once the pending frame has been painted (at once if none is pending), so work
        that follows a change (the plots) starts after the frame, never in the same event-loop turn."""
        self._frames.after_frame(fn)

    _coarse_first = False

    def _before_frame(self) -> None:
        """Right before a frame is drawn, at the widget's real size: a pending camera fit. The first
        frame of newly loaded big layers shows their level-of-detail twins (80k points each: a tenth
        of a second in software GL where full detail takes seconds) and asks for the
        full-detail frame right after it."""
        self._size_axes()
        if self._fit_pending:
            self._fit_pending = False
            fit_camera(self.plotter, self._visible_points())
        if self.moving:
            # the previous frame was drawn moving too (the first one after a press may upload a twin)
            if self._moving_frames and self.detail.frame_took(self.plotter.frame_seconds):
                self._apply_detail()
            self._moving_frames += 1
        if self._coarse_first:
            self._coarse_first = False
            if not self.moving:
                self._set_moving(True)
                self._frames.after_frame(lambda: self._set_moving(False))  # requests the full frame
        if not self.moving:
            self._rest_detail()
        self._full_points = 0 if self.moving else sum(
            self._resting.drawn.get(k, len(self._sources[k])) for k in self._lod if self._actors[k].GetVisibility())

    def _before_render(self) -> None:
        """Right before every render: at rest, the points each big layer draws, and the cloud's near
        points over its image when that shows this view (:mod:`.cloud_layer`)."""
        if self.moving:
            self._cloud_layer.off(self._cloud_frame())
            return
        self._rest_detail()
        self._cloud_layer.apply()

    def _cloud_frame(self) -> CloudFrame | None:
        actor, mesh = self._actors.get("cloud"), self._meshes.get("cloud")
        if actor is None or mesh is None or mesh.n_points < MIN_CLOUD_POINTS:
            return None
        allowed = (bool(self.plotter.software_gl) and self._scale == 1 and not self.moving and not self._picture
                   and not self._eye_dome and self.plotter.devicePixelRatioF() == 1.0)
        return CloudFrame(actor, mesh, self._pick_layout("cloud"),
                          self._resting.drawn.get("cloud", mesh.n_points) == mesh.n_points, allowed)

    def _rest_detail(self) -> None:
        """At rest, each big layer draws only its points that can show in this frame (:mod:`.culling`):
        under software GL, flat points, at a device pixel ratio of 1 and the view's own scale."""
        thin = (bool(self.plotter.software_gl) and self._scale == 1 and not self.scene.style["spheres"]
                and self.plotter.devicePixelRatioF() == 1.0)
        layers = {k: CulledLayer(self._meshes[k], self._actors[k], self._pick_layout(k)) for k in self._lod}
        self._resting.apply(self.plotter.renderer, layers, thin)

    def rebuild(self) -> None:
        for name in ("cloud", "skeletal", "curve"):
            self._build(name)
        self._update_scalar_bar()
        self.plotter.render()

    def _remove(self, *names: str) -> None:
        for name in names:
            self._drop(name)
            self._drop(f"{name}-nan")
            self._drop(f"{name}-lod")

    def _drop(self, name: str) -> None:
        actor = self._actors.pop(name, None)
        if actor is not None:
            if name in KEPT_ACTORS:  # hidden, kept for the next points of this name (:meth:`_swap_points`)
                actor.SetVisibility(False)
                self._spare[name] = actor
            else:
                self.plotter.remove_actor(name, render=False)
        self._pickable.pop(name, None)
        self._sources.pop(name, None)
        self._coloured.pop(name, None)
        self._meshes.pop(name, None)
        self._lod.pop(name, None)
        self._pick_coords.pop(name, None)
        self._invalid.pop(name, None)

    def _build(self, name: str | None) -> None:
        if name == "cloud":
            self._build_cloud()
        elif name == "skeletal":
            self._build_skeletal()
        elif name == "curve":
            self._build_curve()

    def _lookup_table(self) -> pv.LookupTable:
        """One lookup table shared by every coloured actor and the colour bar, remade only when the
        colour range changes (building one from the colour map costs more than recolouring)."""
        key = (self.scene.colour_range(), bool(self.scene.stale))
        if self._lut is None or self._lut[0] != key:
            self._lut = (key, make_lut(key[0], stale=key[1]))
        return self._lut[1]

    def _points_actor(self, key: str, points: np.ndarray, layer: Any, values: np.ndarray | None,
                      plain: tuple[int, int, int], size: float, pickable: tuple[str, str] | None,
                      lod: bool = True) -> None:
        """Draw ``points`` coloured by ``values`` (plain colour when None). An actor already built
        from the same array is recoloured in place: a new result re-uploads scalars, not geometry.
        A layer of more than LOD_POINTS points also gets a subsampled twin, shown while the camera moves."""
        actor = self._actors.get(key)
        if (not lod and values is None and actor is not None and self._sources.get(key) is points
                and self._coloured.get(key) is False and f"{key}-nan" not in self._actors):
            actor.SetVisibility(self._shown(key, layer))  # plain already: the landing's curve vertices
            return
        if (actor is None or self._sources.get(key) is not points) and not lod:
            actor = self._swap_points(key, points, layer, size, pickable)
        if actor is None or self._sources.get(key) is not points:
            self._remove(key)
            mesh = pv.PolyData(display_coordinates(points))
            actor = self._add_points(key, mesh, plain, size, layer.opacity, pickable is not None)
            if key.startswith("curve"):
                draw_in_front(actor)
            self._actors[key] = actor
            self._sources[key] = points
            self._meshes[key] = mesh
            self._resting.forget(key)  # a new mesh draws every point
            if pickable is not None:
                self._pickable[key] = pickable
                if len(points) > LOD_POINTS:  # laid out for picking once drawn, not at the first click
                    QtCore.QTimer.singleShot(0, self.plotter, lambda k=key, p=points: self.after_render(
                        lambda: self._sources.get(k) is p and self._pick_layout(k)))
            if lod and len(points) > LOD_POINTS:
                idx = lod_order(len(points), LOD_POINTS)  # any prefix is a spread subsample
                twin = pv.PolyData(display_coordinates(np.asarray(points)[idx]))
                self._actors[f"{key}-lod"] = self._add_points(f"{key}-lod", twin, plain, size, layer.opacity, False,
                                                              spheres=False)  # flat discs while moving
                self._meshes[f"{key}-lod"] = twin
                self._lod[key] = idx
                self._detail_fitted = False  # new big data: its first drag starts from its full frame's cost
                self._apply_detail(key)
        if values is not None:
            values = np.asarray(values, dtype=float)
        self._colour_points(key, values, plain)
        if key in self._lod:
            self._colour_points(f"{key}-lod", None if values is None else values[self._lod[key]], plain)
        self._coloured[key] = values is not None
        actor.SetVisibility(self._shown(key, layer))
        if f"{key}-lod" in self._actors:
            self._actors[f"{key}-lod"].SetVisibility(self._shown(f"{key}-lod", layer))
        self._drop(f"{key}-nan")
        invalid = ~np.isfinite(values) if values is not None else None
        self._invalid.pop(key, None)
        if invalid is not None and invalid.any():
            self._invalid[key] = invalid
            # Invalid elements are few and matter: drawn larger, in front, so they are seen at a glance.
            nan_actor = self._add_points(f"{key}-nan", pv.PolyData(display_coordinates(np.asarray(points)[invalid])),
                                         greyed(MAGENTA) if self.scene.stale else MAGENTA, size + 4, 1.0, False)
            nan_actor.SetVisibility(layer.visible)
            draw_in_front(nan_actor, -400.0)
            self._actors[f"{key}-nan"] = nan_actor

    def _swap_points(self, key: str, points: np.ndarray, layer: Any, size: float,
                     pickable: tuple[str, str] | None) -> Any:
        """The actor of a small layer (one of KEPT_ACTORS: the curve's vertices and samples) given
        new points in place: an edit's new curve, its samples once scored. A new actor costs pyvista
        several ms (add_mesh, remove_actor) on the path from an edit's key to its recoloured frame
        (docs/performance.md 6.10); the mapper, its shader and its depth offset stay. None when the
        key has no actor to keep."""
        if key not in KEPT_ACTORS:
            return None
        actor = self._actors.get(key) or self._spare.pop(key, None)
        if actor is None:
            return None
        self._drop(f"{key}-nan")
        for kept in (self._pick_coords, self._invalid, self._pickable):
            kept.pop(key, None)
        mesh = pv.PolyData(display_coordinates(points))
        actor.mapper.dataset = mesh
        spheres = self.scene.style["spheres"]
        actor.prop.render_points_as_spheres = spheres
        actor.prop.lighting = spheres
        actor.prop.point_size = size
        actor.prop.opacity = layer.opacity
        self._actors[key] = actor
        self._sources[key] = points
        self._meshes[key] = mesh
        if pickable is not None:
            self._pickable[key] = pickable
        return actor

    def _add_points(self, key: str, mesh: pv.PolyData, colour: Any, size: float, opacity: float, pickable: bool,
                    spheres: bool | None = None) -> Any:
        spheres = self.scene.style["spheres"] if spheres is None else spheres
        actor = self.plotter.add_mesh(
            mesh, color=colour, style="points", point_size=size, opacity=opacity, lighting=spheres, name=key,
            reset_camera=False, render=False, render_points_as_spheres=spheres, pickable=pickable,
        )
        return actor

    def _colour_points(self, key: str, values: np.ndarray | None, plain: tuple[int, int, int]) -> None:
        actor = self._actors[key]
        mapper = actor.mapper
        if values is None and key.startswith("cloud"):
            mapper.scalar_visibility = False
            actor.prop.color = plain
            return
        # Skeleton elements are always drawn through scalars and a lookup table, their plain
        # colour as a one-colour table: the first result then needs no new GL shader program,
        # whose compilation made its frame ~20 ms slower in software GL.
        shown = values is not None
        values = values if shown else np.zeros(self._meshes[key].n_points)
        # Into the mesh itself (the mapper's dataset is the output of pyvista's active-scalars
        # filter, empty until the next render): replaces the previous values.
        self._meshes[key].point_data.set_array(values, "values")
        lut, clim = (self._lookup_table(), self.scene.colour_range()) if shown else (plain_lut(plain), (0.0, 1.0))
        mapper.set_scalars(values, "values", cmap=lut, clim=clim)
        mapper.scalar_visibility = True

    def _shown(self, key: str, layer: Any) -> bool:
        """A layer's actor is visible with its layer; of a layer and its level-of-detail twin,
        exactly one shows: the twin while the camera moves."""
        if not layer.visible:
            return False
        if key.endswith("-lod"):
            return self.moving
        return not (self.moving and f"{key}-lod" in self._actors)

    def _apply_detail(self, key: str | None = None) -> None:
        """Each twin (or ``key``'s) draws its first ``detail.points`` points: a new vertex list, its
        points and colours already uploaded."""
        for name in [key] if key is not None else list(self._lod):
            twin = self._meshes[f"{name}-lod"]
            keep = min(self.detail.points, twin.n_points)
            if twin.n_verts != keep:
                twin.verts = np.column_stack([np.ones(keep, dtype=np.int64), np.arange(keep)]).ravel()

    def _set_moving(self, moving: bool) -> None:
        """The camera starts or stops moving (mouse drag, wheel): swap in or out the twins (visibility
        only: both stay built); the colour bar keeps its layout while moving (the view's size holds)."""
        if moving == self.moving:
            return
        self.moving = moving
        self._moving_frames = 0
        self._colour_bar.held = moving
        for key in list(self._lod):
            layer = self.scene.layers.get(key.split("-")[0])
            if layer is None:
                continue
            self._actors[key].SetVisibility(self._shown(key, layer))
            self._actors[f"{key}-lod"].SetVisibility(self._shown(f"{key}-lod", layer))
        if moving and self._full_points and not self._detail_fitted:
            # the first drag over this data: from the last full-detail frame's cost a point
            shown = sum(1 for k in self._lod if self._actors[f"{k}-lod"].GetVisibility())
            self.detail.fit(self.plotter.frame_seconds, self._full_points, shown)
            self._detail_fitted = True
            self._apply_detail()
        if self._lod and not moving:
            self.request_render()  # the full-detail frame once the camera rests

    def _build_cloud(self) -> None:
        self._remove("cloud")
        layer = self.scene.cloud
        if layer is not None:
            values = self._cloud_values
            if values is not None and len(values) != layer.n_points:
                values = self._cloud_values = None
            self._points_actor("cloud", layer.points, layer, values, CLOUD_GREY, layer.point_size, None)

    _cloud_values: np.ndarray | None = None

    def set_cloud_values(self, values: np.ndarray | None) -> None:
        """Colour the cloud by per-point values in [0, 1] (the coverage gap), NaN magenta; None: grey.
        Grey asked again of a grey cloud (every result landing asks) redraws nothing: at 100k points
        the cloud's actor takes 80 ms to build, which an edit's recoloured frame would wait for."""
        if values is None and self._cloud_values is None and "cloud" in self._actors:
            return
        self._cloud_values = None if values is None else np.asarray(values, dtype=float)
        self._build_cloud()
        self.request_render()

    def _build_skeletal(self) -> None:
        self._remove("skeletal")
        self._colour_skeletal()

    def _colour_skeletal(self) -> None:
        layer = self.scene.skeletal
        if layer is None:
            self._remove("skeletal")
            return
        q = layer.quantity(self.scene.metric)
        self._points_actor("skeletal", layer.points, layer, None if q is None else q.values, SKELETAL_PLAIN,
                           layer.point_size, ("skeletal", "points"))

    def _build_curve(self) -> None:
        self._remove("curve-vertices", "curve-samples")
        self._build_curve_edges()
        self._colour_curve()

    def _tube_values(self) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Polylines (points, VTK line cells, values) the tubes are drawn along, coloured by the
        shown metric: through the curve samples (boundedness, centeredness) or the vertices
        (smoothness); None before an evaluation (plain tubes)."""
        layer = self.scene.curve
        q = layer.quantity(self.scene.metric)
        if q is None:
            return None
        return curve_polylines(layer.points, np.asarray(layer.edges).reshape(-1, 2), q.values, q.location,
                               layer.samples, layer.sample_edge, layer.sample_t)

    def _build_curve_edges(self) -> None:
        layer = self.scene.curve
        if self._swap_lines(layer):
            return
        self._remove("curve-edges")
        self._edges_as_tubes = None
        if layer is None:
            return
        self._edges_as_tubes = self.scene.edges_as_tubes
        verts = np.ascontiguousarray(layer.points, dtype=float)
        edges = np.asarray(layer.edges, dtype=np.int64).reshape(-1, 2)
        if not len(edges):
            return
        if self.scene.edges_as_tubes:
            radius = 0.004 * scene_diagonal(self.scene)
            coloured = self._tube_values()
            if coloured is None:
                cells = line_cells(edges)
                mesh = pv.PolyData(verts, lines=cells).tube(radius=radius, n_sides=12)
                actor = self.plotter.add_mesh(mesh, color=CURVE_EDGE, name="curve-edges", reset_camera=False,
                                              render=False, pickable=False, smooth_shading=True)
            else:
                pts, cells, values = coloured
                lines = pv.PolyData(pts, lines=cells)
                lines.point_data.set_array(values, "values")
                mesh = lines.tube(radius=radius, n_sides=12)
                actor = self.plotter.add_mesh(mesh, scalars="values", cmap=self._lookup_table(),
                                              clim=self.scene.colour_range(),
                                              nan_color=greyed(MAGENTA) if self.scene.stale else MAGENTA,
                                              name="curve-edges",
                                              reset_camera=False, render=False, pickable=False, smooth_shading=True,
                                              show_scalar_bar=False)
        else:
            cells = line_cells(edges)
            lines = pv.PolyData(verts, lines=cells)
            actor = self.plotter.add_mesh(lines, color=CURVE_EDGE, style="wireframe", line_width=2.5,
                                          lighting=False, name="curve-edges", reset_camera=False,
                                          render=False, pickable=False)
        actor.SetVisibility(layer.visible)
        draw_in_front(actor)
        self._actors["curve-edges"] = actor

    def _swap_lines(self, layer: Any) -> bool:
        """The curve's edges drawn as lines again (an edit, its undo or redo): the new lines go into
        the actor already built, as :meth:`_swap_points` does for the points."""
        actor = self._actors.get("curve-edges")
        if (actor is None or layer is None or self.scene.edges_as_tubes or self._edges_as_tubes is not False
                or not len(layer.edges)):
            return False
        lines = line_cells(layer.edges)
        actor.mapper.dataset = pv.PolyData(np.ascontiguousarray(layer.points, dtype=float), lines=lines)
        actor.SetVisibility(layer.visible)
        return True

    def _colour_curve(self) -> None:
        layer = self.scene.curve
        if layer is None:
            self._remove("curve-edges", "curve-vertices", "curve-samples")
            return
        location = CURVE_LOCATION[self.scene.metric]
        q = layer.quantity(self.scene.metric)
        vert_values = q.values if (q is not None and location == "vertices") else None
        self._points_actor("curve-vertices", layer.points, layer, vert_values, CURVE_VERTEX, layer.point_size,
                           ("curve", "vertices"), lod=False)
        if layer.samples is not None and q is not None and location == "samples":
            self._points_actor("curve-samples", layer.samples, layer, q.values, CURVE_VERTEX,
                               max(layer.point_size - 1.0, 3.0), ("curve", "samples"), lod=False)
        else:
            self._remove("curve-samples")

    def _apply_display(self, name: str | None) -> None:
        layer = self.scene.layers.get(name or "")
        if layer is None:
            return
        for key, actor in self._actors.items():
            if key == name or key.startswith(f"{name}-"):
                actor.SetVisibility(self._shown(key, layer) if key in self._lod or key.endswith("-lod") else layer.visible)
                if key != "curve-edges":
                    size = layer.point_size if not key.startswith("curve-samples") else max(layer.point_size - 1, 3)
                    actor.prop.point_size = size + (4 if key.endswith("-nan") else 0)
                    actor.prop.opacity = layer.opacity if not key.endswith("-nan") else 1.0

    def _apply_style(self) -> None:
        """The figure options: shaded spheres, eye-dome lighting, the orientation axes."""
        style = self.scene.style
        for key, actor in self._actors.items():
            if key not in ("curve-edges", "pick-marker") and not key.endswith("-lod"):  # twins: flat discs
                actor.prop.render_points_as_spheres = style["spheres"]
                actor.prop.lighting = style["spheres"]
        if style["eye_dome"] != self._eye_dome:
            self._eye_dome = style["eye_dome"]
            self.eye_dome.set(self._eye_dome)
        if style["axes"] != self._axes_shown:
            self._axes_shown = style["axes"]
            if self._axes_shown:
                if self.plotter.renderer.axes_widget is None:
                    fixed_size_labels(self.plotter.add_axes(interactive=False, color="black", line_width=2))
                else:
                    self.plotter.show_axes()
                self._size_axes()
            else:
                self.plotter.hide_axes()

    def _size_axes(self) -> None:
        """The orientation axes in a fixed square of the lower-left corner, whatever the view's size."""
        widget = self.plotter.renderer.axes_widget
        if widget is not None:
            w, h = self.plotter.renderer.GetSize()
            port = axes_viewport(w, h, self.plotter.devicePixelRatioF())
            if tuple(widget.GetViewport()) != port:
                widget.SetViewport(*port)

    def _make_hint(self) -> Any:
        """The empty window's hint, centred; hidden once anything is loaded."""
        from vtkmodules.vtkRenderingCore import vtkTextActor  # one module: `import vtk` loads all of VTK (seconds)

        text = vtkTextActor()
        text.SetInput(EMPTY_HINT)
        prop = text.GetTextProperty()
        prop.SetFontSize(20)
        prop.SetColor(0.45, 0.45, 0.45)
        prop.SetJustificationToCentered()
        prop.SetVerticalJustificationToCentered()
        text.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
        text.SetPosition(0.5, 0.5)
        self.plotter.renderer.AddViewProp(text)
        return text

    @property
    def hint_visible(self) -> bool:
        return bool(self._hint.GetVisibility())

    def _coloured_actor(self) -> Any:
        for key in ("skeletal", "curve-samples", "curve-vertices"):
            actor = self._actors.get(key)
            if actor is not None and self._coloured.get(key) and self.scene.layers.get(key.split("-")[0]).visible:
                return actor
        return None

    def _update_scalar_bar(self) -> None:
        self._colour_bar.update(self._coloured_actor(), self.scene)

    # ---- camera ---------------------------------------------------------------------------
    def _visible_points(self) -> list[np.ndarray]:
        out = []
        for layer in self.scene.layers.values():
            if layer.visible:
                out.append(layer.points)
                if layer.samples is not None:
                    out.append(layer.samples)
        return out

    def reset_camera(self) -> None:
        """Frame every visible layer (R), at the next frame (the widget's size is then final)."""
        self._fit_pending = True
        self.request_render()

    def frame_box(self, lo: Any, hi: Any, min_share: float = 0.08, margin: float = 0.25) -> None:
        """Frame the box (lo, hi) (a defect's place), grown by ``margin`` of its size and to at
        least ``min_share`` of the scene's diagonal on every side, so that it is seen in its context."""
        from .actors import scene_diagonal

        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        half = np.maximum((hi - lo) / 2 * (1 + margin), 0.5 * min_share * scene_diagonal(self.scene))
        centre = (lo + hi) / 2
        corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half + centre
        self._fit_pending = False
        self._camera_set = True
        fit_camera(self.plotter, [corners])
        self.request_render()

    def standard_view(self, name: str) -> None:
        """'xy', 'xz', 'yz' (and their negatives '-xy', ...) or 'iso'."""
        orient_standard_view(self.plotter, name)
        fit_camera(self.plotter, self._visible_points())
        self.request_render()

    def set_parallel_projection(self, on: bool) -> None:
        self.plotter.renderer.GetActiveCamera().SetParallelProjection(bool(on))
        fit_camera(self.plotter, self._visible_points())
        self.request_render()

    @property
    def parallel_projection(self) -> bool:
        return bool(self.plotter.renderer.GetActiveCamera().GetParallelProjection())

    def camera_state(self) -> dict[str, Any]:
        self._before_frame()
        return camera_state(self.plotter)

    def set_camera_state(self, state: dict[str, Any]) -> None:
        """A saved view (View > Load camera, ``--camera FILE``): no automatic fit replaces it."""
        self._fit_pending = False
        self._camera_set = True
        apply_camera_state(self.plotter, state)
        self.request_render()

    # ---- picking --------------------------------------------------------------------------
    def _clicked(self, pos: QtCore.QPointF) -> None:
        ratio = self.plotter.devicePixelRatioF()
        x = pos.x() * ratio
        y = (self.plotter.height() - pos.y()) * ratio
        info = self.pick_display(x, y)
        if self.on_pick is not None:
            self.on_pick(info)

    def world_to_display(self, xyz: Any) -> tuple[float, float]:
        """Display coordinates (VTK's: pixels, origin bottom left) of a world point."""
        ren = self.plotter.renderer
        ren.SetWorldPoint(float(xyz[0]), float(xyz[1]), float(xyz[2]), 1.0)
        ren.WorldToDisplay()
        x, y, _ = ren.GetDisplayPoint()
        return float(x), float(y)

    def display_to_world(self, x: float, y: float, at: Any) -> tuple[float, float, float]:
        """The world point drawn at display point (x, y) (VTK's pixels, origin bottom left) at the depth
        of world point ``at``: on the plane through ``at`` facing the camera (a dragged vertex)."""
        ren = self.plotter.renderer
        ren.SetWorldPoint(float(at[0]), float(at[1]), float(at[2]), 1.0)
        ren.WorldToDisplay()
        z = ren.GetDisplayPoint()[2]
        ren.SetDisplayPoint(float(x), float(y), float(z))
        ren.DisplayToWorld()
        wx, wy, wz, w = ren.GetWorldPoint()
        w = w or 1.0
        return wx / w, wy / w, wz / w

    def qt_to_display(self, pos: QtCore.QPointF) -> tuple[float, float]:
        """A widget position (Qt's, origin top left, device-independent pixels) as VTK's display point."""
        ratio = self.plotter.devicePixelRatioF()
        return pos.x() * ratio, (self.plotter.height() - pos.y()) * ratio

    def pick_display(self, x: float, y: float) -> dict[str, Any] | None:
        """The skeleton element drawn nearest to display point (x, y), with every local value.

        A numpy projection of the visible skeleton elements (tens of ms for a million points, where
        VTK's point picker took seconds); of those near the click, what is drawn on top there wins
        (:func:`.picking.front_pick`: a curve vertex over the skeletal point under it)."""
        ratio = self.plotter.devicePixelRatioF()
        candidates = []
        for key, where in self._pickable.items():
            actor = self._actors.get(key)
            layer = self.scene.layers.get(where[0])
            if actor is None or layer is None or not layer.visible:
                continue
            size = float(actor.prop.point_size)
            tolerance = ((max(size, 4.0) + 4.0) / 2 + 3) * ratio
            idx, dist, depth = near_on_screen(self.plotter.renderer, self._pick_layout(key), x, y, tolerance)
            if not len(idx):
                continue
            invalid = self._invalid.get(key)
            nan = np.zeros(len(idx), bool) if invalid is None else invalid[idx]
            radius = ((np.where(nan, size + 4.0, size)) / 2.0 + 1.0) * ratio  # the disc drawn, one pixel spare
            rank = np.where(nan, 0, 1 if key.startswith("curve") else 2)
            # per actor, the two that can win: the front-most covering one and the nearest on screen
            cover = np.flatnonzero(dist <= radius)
            picks = set()
            if len(cover):
                picks.add(int(cover[np.lexsort((dist[cover], depth[cover], rank[cover]))[0]]))
            picks.add(int(np.lexsort((depth, np.round(dist)))[0]))
            candidates += [(key, int(idx[j]), float(dist[j]), float(depth[j]), float(radius[j]), int(rank[j]))
                           for j in picks]
        best = front_pick(candidates)
        if best is None:
            self._remove_marker()
            self.request_render()
            return None
        where = self._pickable[best[0]]
        info = self.scene.element_info(where[0], where[1], best[1])
        self._show_marker(info["xyz"])
        self.picked = info
        return info

    def mark(self, xyz: tuple[float, float, float]) -> None:
        """Mark a point as the picked element (a pick made by index, e.g. from a saved session)."""
        self._show_marker(xyz)
    def _pick_layout(self, key: str) -> np.ndarray:
        """An actor's points laid out for picking (:func:`.picking.pick_layout`), made once."""
        if key not in self._pick_coords:
            self._pick_coords[key] = pick_layout(self._sources[key])
        return self._pick_coords[key]

    def _show_marker(self, xyz: tuple[float, float, float]) -> None:
        self._remove_marker()
        actor = self.plotter.add_mesh(
            pv.PolyData(np.array([xyz], dtype=float)), color=PICK_MARKER, style="points", point_size=16,
            render_points_as_spheres=True, name="pick-marker", reset_camera=False, render=False, pickable=False,
        )
        self._actors["pick-marker"] = actor
        self.request_render()

    def _remove_marker(self) -> None:
        self._remove("pick-marker")
        self.picked = None

    @property
    def marker_shown(self) -> bool:
        """Whether the picked element's marker is in the scene (and visible)."""
        actor = self._actors.get("pick-marker")
        return actor is not None and bool(actor.GetVisibility())

    # ---- images ---------------------------------------------------------------------------
    def image(self, scale: int = 1, transparent: bool = False, colour_bar: bool = True,
              background: str | None = None) -> np.ndarray:
        """The rendered 3D view as an (H, W, 3 or 4) uint8 array, ``scale`` times the widget size.

        Point sizes, line widths and every text grow with ``scale``, so the picture is the view as
        seen, at a higher resolution; ``colour_bar=False`` leaves the bar out. ``background`` is
        "white" (the view's), "black" (text turns white) or "transparent" (an alpha channel);
        ``transparent=True`` means "transparent"."""
        background = "transparent" if transparent else (background or "white")
        if background not in BACKGROUNDS:
            raise ValueError(f"background must be one of {', '.join(BACKGROUNDS)}, got {background!r}")
        self._before_frame()
        self._set_moving(False)
        scale = self._scale = int(scale)  # thinned for this view only: a picture at another scale draws every point
        self._picture = True
        restore = _scaled_props(self._actors.values(), scale)
        restore += self._colour_bar.for_picture(scale, visible=colour_bar, background=background)
        restore += _axes_for_picture(self.plotter.renderer.axes_actor if self._axes_shown else None, scale, background)
        if background == "black":
            self.plotter.set_background("black")
            restore.append(lambda: self.plotter.set_background("white"))
        try:
            self.plotter.render()
            img = self.plotter.screenshot(None, transparent_background=background == "transparent", return_img=True,
                                          scale=scale)
        finally:
            for undo in restore:
                undo()
            self._scale = 1
            self._picture = False
        self._frames.frame_done()  # the pending frame is the one rendered here
        if scale != 1 or not colour_bar or background != "white":
            self.request_render()  # the view itself back to its own sizes and colours
        return np.asarray(img)

    def close(self) -> None:
        """Let go of the scene, the view's filters, timers and VTK's window. Safe to call again (the
        main window's close, then its owner's) and after the widget was destroyed with its window
        (Qt's half then is gone: only the scene, VTK's observer and the timers are let go)."""
        if self._closed:
            return
        self._closed = True
        self.scene.unsubscribe(self._on_scene)
        alive = shiboken6.isValid(self.plotter)
        if alive:
            self.plotter.removeEventFilter(self._motion_filter)
        window = getattr(self.plotter, "ren_win", None)  # None once pyvista closed it
        if window is not None:
            window.RemoveObserver(self._start_observer)  # VTK's hold on this view let go
        self._frames.close()
        self._cloud_layer.close()
        if alive:
            self.eye_dome.close()
            self.plotter.close()


BACKGROUNDS = ("white", "black", "transparent")
"""A picture's backgrounds (File > Save picture, ``skelscope --background``)."""
AXES_LABEL_SIZE = 13


def fixed_size_labels(axes: Any) -> Any:
    """The orientation axes' letters at a fixed font size: pyvista scales them to fit a box, which
    VTK's tiles then grow once more, so a picture at scale 2 had letters three times too big."""
    for caption in (axes.GetXAxisCaptionActor2D(), axes.GetYAxisCaptionActor2D(), axes.GetZAxisCaptionActor2D()):
        caption.GetTextActor().SetTextScaleModeToNone()
        caption.GetCaptionTextProperty().SetFontSize(AXES_LABEL_SIZE)
    return axes


def _axes_for_picture(axes: Any, scale: int, background: str) -> list[Callable[[], None]]:
    """The orientation axes' lines ``scale`` times wider and their letters in the background's text
    colour, for one picture; the functions that undo it."""
    from .colorbar import TEXT_COLOURS

    undo: list[Callable[[], None]] = []
    if axes is None:
        return undo
    for prop in (axes.GetXAxisShaftProperty(), axes.GetYAxisShaftProperty(), axes.GetZAxisShaftProperty()):
        width = prop.GetLineWidth()
        prop.SetLineWidth(width * scale)
        undo.append(lambda p=prop, w=width: p.SetLineWidth(w))
    for caption in (axes.GetXAxisCaptionActor2D(), axes.GetYAxisCaptionActor2D(), axes.GetZAxisCaptionActor2D()):
        prop = caption.GetCaptionTextProperty()
        colour = prop.GetColor()
        prop.SetColor(*TEXT_COLOURS[background])
        undo.append(lambda p=prop, c=colour: p.SetColor(*c))
    return undo


def _scaled_props(actors: Any, scale: int) -> list[Callable[[], None]]:
    """Multiply every actor's point size and line width by ``scale``; the functions that undo it."""
    undo: list[Callable[[], None]] = []
    if scale == 1:
        return undo
    for actor in actors:
        prop = actor.GetProperty()
        size, width = prop.GetPointSize(), prop.GetLineWidth()
        prop.SetPointSize(size * scale)
        prop.SetLineWidth(width * scale)
        undo.append(lambda p=prop, s=size, w=width: (p.SetPointSize(s), p.SetLineWidth(w)))
    return undo
