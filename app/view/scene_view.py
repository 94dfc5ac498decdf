"""The scene view: turns the Qt-free scene into pyvista actors inside a ``DropInteractor``.

It subscribes to the ``Scene`` and, per event, builds, recolours or hides actors, then asks for one
frame; it also picks elements and renders images. Only the view touches VTK, and only on the GUI
thread. NaN is drawn magenta through the lookup table's NaN colour (SPEC 5); point actors are unlit
so a colour on screen is exactly the colour-map colour.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np
import pyvista as pv
from PySide6 import QtCore

from ..scene import CURVE_LOCATION, Scene, SceneEvent
from .actors import display_coordinates, draw_in_front, scene_diagonal
from .camera import fit_camera, orient_standard_view
from .colorbar import ColourBar
from .frames import FrameScheduler
from .interactor import ClickFilter, DropInteractor
from .style import CLOUD_GREY, CURVE_EDGE, CURVE_VERTEX, MAGENTA, PICK_MARKER, SKELETAL_PLAIN, make_lut, plain_lut

__all__ = ["SceneView"]


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
        self._lut: tuple[tuple[float, float], pv.LookupTable] | None = None
        self._edges_as_tubes: bool | None = None  # how the curve's edge actor was built
        self._colour_bar = ColourBar(self.plotter)
        self._camera_set = False
        self._frames = FrameScheduler(self.plotter)  # also sets plotter.on_frame
        self.on_pick: Callable[[dict[str, Any] | None], None] | None = None
        self._click_filter = ClickFilter(self._clicked)
        self.plotter.installEventFilter(self._click_filter)
        scene.subscribe(self._on_scene)

    # ---- scene events ---------------------------------------------------------------------
    def _on_scene(self, event: SceneEvent) -> None:
        if event.kind == "layer":
            self._remove_marker()
            self._build(event.layer)
            if not self._camera_set and self.scene.layers:
                fit_camera(self.plotter)
                self._camera_set = True
        elif event.kind == "display":
            if event.layer == "curve" and self._edges_as_tubes != self.scene.edges_as_tubes:
                self._build_curve_edges()
            self._apply_display(event.layer)
        elif event.kind in ("quantities", "colouring", "thresholds"):
            # Only values changed: the skeleton actors are recoloured in place, not rebuilt.
            self._remove_marker()
            self._colour_skeletal()
            self._colour_curve()
        self._update_scalar_bar()
        self.request_render()

    def request_render(self) -> None:
        """Render once, soon, however many scene changes arrive meanwhile (see :mod:`.frames`)."""
        self._frames.request()

    @property
    def render_pending(self) -> bool:
        return self._frames.pending

    def after_render(self, fn: Callable[[], None]) -> None:
        """Call ``fn`` once the pending frame has been painted (at once if none is pending), so work
        that follows a change (the plots) starts after the frame, never in the same event-loop turn."""
        self._frames.after_frame(fn)

    def rebuild(self) -> None:
        for name in ("cloud", "skeletal", "curve"):
            self._build(name)
        self._update_scalar_bar()
        self.plotter.render()

    def _remove(self, *names: str) -> None:
        for name in names:
            self._drop(name)
            self._drop(f"{name}-nan")

    def _drop(self, name: str) -> None:
        if self._actors.pop(name, None) is not None:
            self.plotter.remove_actor(name, render=False)
        self._pickable.pop(name, None)
        self._sources.pop(name, None)
        self._coloured.pop(name, None)
        self._meshes.pop(name, None)

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
        clim = self.scene.colour_range()
        if self._lut is None or self._lut[0] != clim:
            self._lut = (clim, make_lut(clim))
        return self._lut[1]

    def _points_actor(self, key: str, points: np.ndarray, layer: Any, values: np.ndarray | None,
                      plain: tuple[int, int, int], size: float, pickable: tuple[str, str] | None) -> None:
        """Draw ``points`` coloured by ``values`` (plain colour when None). An actor already built
        from the same array is recoloured in place: a new result re-uploads scalars, not geometry."""
        actor = self._actors.get(key)
        if actor is None or self._sources.get(key) is not points:
            self._remove(key)
            mesh = pv.PolyData(display_coordinates(points))
            actor = self.plotter.add_mesh(
                mesh, color=plain, style="points", point_size=size,
                opacity=layer.opacity, lighting=False, name=key, reset_camera=False, render=False,
                render_points_as_spheres=False, pickable=pickable is not None,
            )
            if key.startswith("curve"):
                draw_in_front(actor)
            self._actors[key] = actor
            self._sources[key] = points
            self._meshes[key] = mesh
            if pickable is not None:
                self._pickable[key] = pickable
        mapper = actor.mapper
        if values is None and key == "cloud":
            mapper.scalar_visibility = False
            actor.prop.color = plain
        else:
            # Skeleton elements are always drawn through scalars and a lookup table, their plain
            # colour as a one-colour table: the first result then needs no new GL shader program,
            # whose compilation made its frame ~20 ms slower in software GL.
            shown = values is not None
            values = np.asarray(values, dtype=float) if shown else np.zeros(len(points))
            # Into the mesh itself (the mapper's dataset is the output of pyvista's active-scalars
            # filter, empty until the next render): replaces the previous values.
            self._meshes[key].point_data.set_array(values, "values")
            lut, clim = (self._lookup_table(), self.scene.colour_range()) if shown else (plain_lut(plain), (0.0, 1.0))
            mapper.set_scalars(values, "values", cmap=lut, clim=clim)
            mapper.scalar_visibility = True
            self._coloured[key] = shown
        actor.SetVisibility(layer.visible)
        self._drop(f"{key}-nan")
        invalid = ~np.isfinite(values) if self._coloured.get(key) else None
        if invalid is not None and invalid.any():
            # Invalid elements are few and matter: drawn larger, in front, so they are seen at a glance.
            nan_actor = self.plotter.add_mesh(
                pv.PolyData(display_coordinates(np.asarray(points)[invalid])), color=MAGENTA, style="points",
                point_size=size + 4, lighting=False, name=f"{key}-nan", reset_camera=False, render=False,
                render_points_as_spheres=False, pickable=False,
            )
            nan_actor.SetVisibility(layer.visible)
            draw_in_front(nan_actor, -400.0)
            self._actors[f"{key}-nan"] = nan_actor

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
        """Colour the cloud by per-point values in [0, 1] (the coverage gap), NaN magenta; None: grey."""
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

    def _build_curve_edges(self) -> None:
        self._remove("curve-edges")
        self._edges_as_tubes = None
        layer = self.scene.curve
        if layer is None:
            return
        self._edges_as_tubes = self.scene.edges_as_tubes
        verts = np.ascontiguousarray(layer.points, dtype=float)
        edges = np.asarray(layer.edges, dtype=np.int64).reshape(-1, 2)
        if not len(edges):
            return
        cells = np.hstack([np.full((len(edges), 1), 2, dtype=np.int64), edges]).ravel()
        lines = pv.PolyData(verts, lines=cells)
        if self.scene.edges_as_tubes:
            radius = 0.004 * scene_diagonal(self.scene)
            mesh = lines.tube(radius=radius, n_sides=12)
            actor = self.plotter.add_mesh(mesh, color=CURVE_EDGE, name="curve-edges", reset_camera=False,
                                          render=False, pickable=False, smooth_shading=True)
        else:
            actor = self.plotter.add_mesh(lines, color=CURVE_EDGE, style="wireframe", line_width=2.5,
                                          lighting=False, name="curve-edges", reset_camera=False,
                                          render=False, pickable=False)
        actor.SetVisibility(layer.visible)
        draw_in_front(actor)
        self._actors["curve-edges"] = actor

    def _colour_curve(self) -> None:
        layer = self.scene.curve
        if layer is None:
            self._remove("curve-edges", "curve-vertices", "curve-samples")
            return
        location = CURVE_LOCATION[self.scene.metric]
        q = layer.quantity(self.scene.metric)
        vert_values = q.values if (q is not None and location == "vertices") else None
        self._points_actor("curve-vertices", layer.points, layer, vert_values, CURVE_VERTEX, layer.point_size,
                           ("curve", "vertices"))
        if layer.samples is not None and q is not None and location == "samples":
            self._points_actor("curve-samples", layer.samples, layer, q.values, CURVE_VERTEX,
                               max(layer.point_size - 2.0, 3.0), ("curve", "samples"))
        else:
            self._remove("curve-samples")

    def _apply_display(self, name: str | None) -> None:
        layer = self.scene.layers.get(name or "")
        if layer is None:
            return
        for key, actor in self._actors.items():
            if key == name or key.startswith(f"{name}-"):
                actor.SetVisibility(layer.visible)
                if key != "curve-edges":
                    size = layer.point_size if not key.startswith("curve-samples") else max(layer.point_size - 2, 3)
                    actor.prop.point_size = size + (4 if key.endswith("-nan") else 0)
                    actor.prop.opacity = layer.opacity

    def _coloured_actor(self) -> Any:
        for key in ("skeletal", "curve-samples", "curve-vertices"):
            actor = self._actors.get(key)
            if actor is not None and self._coloured.get(key) and actor.GetVisibility():
                return actor
        return None

    def _update_scalar_bar(self) -> None:
        self._colour_bar.update(self._coloured_actor(), self.scene)

    # ---- camera ---------------------------------------------------------------------------
    def reset_camera(self) -> None:
        fit_camera(self.plotter)
        self.request_render()

    def standard_view(self, name: str) -> None:
        """'xy', 'xz', 'yz' (and their negatives '-xy', ...) or 'iso'."""
        orient_standard_view(self.plotter, name)
        fit_camera(self.plotter)
        self.plotter.render()

    def set_parallel_projection(self, on: bool) -> None:
        if on:
            self.plotter.enable_parallel_projection()
        else:
            self.plotter.disable_parallel_projection()
        self.plotter.render()

    @property
    def parallel_projection(self) -> bool:
        return bool(self.plotter.camera.GetParallelProjection())

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

    def pick_display(self, x: float, y: float) -> dict[str, Any] | None:
        """The skeleton element drawn nearest to display point (x, y), with every local value."""
        import vtk

        picker = vtk.vtkPointPicker()
        picker.SetTolerance(0.01)
        picker.PickFromListOn()
        keyed = {}
        for key, where in self._pickable.items():
            actor = self._actors.get(key)
            if actor is not None and actor.GetVisibility():
                picker.AddPickList(actor)
                keyed[actor.GetAddressAsString("vtkObject")] = where
        if not keyed or not picker.Pick(x, y, 0.0, self.plotter.renderer):
            self._remove_marker()
            return None
        actor, pid = picker.GetActor(), picker.GetPointId()
        where = keyed.get(actor.GetAddressAsString("vtkObject")) if actor is not None else None
        if where is None or pid < 0:
            self._remove_marker()
            return None
        info = self.scene.element_info(where[0], where[1], pid)
        self._show_marker(info["xyz"])
        return info

    def _show_marker(self, xyz: tuple[float, float, float]) -> None:
        self._remove_marker()
        actor = self.plotter.add_mesh(
            pv.PolyData(np.array([xyz], dtype=float)), color=PICK_MARKER, style="points", point_size=16,
            render_points_as_spheres=True, name="pick-marker", reset_camera=False, render=False, pickable=False,
        )
        self._actors["pick-marker"] = actor
        self.plotter.render()

    def _remove_marker(self) -> None:
        self._remove("pick-marker")

    # ---- images ---------------------------------------------------------------------------
    def image(self, scale: int = 1, transparent: bool = False) -> np.ndarray:
        """The rendered 3D view as an (H, W, 3 or 4) uint8 array, ``scale`` times the widget size."""
        self.plotter.render()
        img = self.plotter.screenshot(None, transparent_background=transparent, return_img=True, scale=int(scale))
        self._frames.frame_done()  # the pending frame is the one rendered here
        return np.asarray(img)

    def close(self) -> None:
        self.scene.unsubscribe(self._on_scene)
        self._frames.close()
        self.plotter.close()
