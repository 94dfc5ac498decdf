"""The 3D view: turns the Qt-free scene into pyvista actors inside a ``QtInteractor``.

Only this module touches VTK, and only on the GUI thread (``QtInteractor.render`` emits a signal).
Invalid values (NaN) are drawn magenta through the lookup table's NaN colour (SPEC 5); point actors
are unlit so a colour on screen is exactly the colour-map colour.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np
import pyvista as pv
from pyvistaqt import QtInteractor
from PySide6 import QtCore, QtGui

from ..scene import CURVE_LOCATION, Scene, SceneEvent
from .style import CLOUD_GREY, CURVE_EDGE, CURVE_VERTEX, MAGENTA, PICK_MARKER, SKELETAL_PLAIN, make_lut

__all__ = ["SceneView", "DropInteractor"]


class DropInteractor(QtInteractor):
    """A ``QtInteractor`` whose drag-and-drop goes to the viewer's loader, not pyvista's reader.

    pyvistaqt's own ``dropEvent`` reads any dropped file with ``pyvista.read`` and adds it as a mesh;
    that would bypass skelcore's loaders and the cloud / skeleton roles, so it is replaced.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.drop_handler: Callable[[QtGui.QDropEvent], None] | None = None
        self.drag_handler: Callable[[QtGui.QDragEnterEvent], None] | None = None

    def dragEnterEvent(self, event: QtGui.QDragEnterEvent) -> None:  # noqa: N802
        if self.drag_handler is not None:
            self.drag_handler(event)
        else:
            event.ignore()

    def dragMoveEvent(self, event: QtGui.QDragMoveEvent) -> None:  # noqa: N802
        if self.drag_handler is not None:
            self.drag_handler(event)
        else:
            event.ignore()

    def dropEvent(self, event: QtGui.QDropEvent) -> None:  # noqa: N802
        if self.drop_handler is not None:
            self.drop_handler(event)
        else:
            event.ignore()


class _ClickFilter(QtCore.QObject):
    """A press and release within a few pixels is a click (a pick); anything else is a drag."""

    def __init__(self, on_click: Callable[[QtCore.QPointF], None]) -> None:
        super().__init__()
        self._on_click = on_click
        self._pressed: QtCore.QPointF | None = None

    def eventFilter(self, obj: QtCore.QObject, event: QtCore.QEvent) -> bool:  # noqa: N802
        t = event.type()
        if t == QtCore.QEvent.Type.MouseButtonPress and event.button() == QtCore.Qt.MouseButton.LeftButton:
            self._pressed = event.position()
        elif t == QtCore.QEvent.Type.MouseButtonRelease and event.button() == QtCore.Qt.MouseButton.LeftButton:
            if self._pressed is not None and (event.position() - self._pressed).manhattanLength() <= 3:
                self._on_click(event.position())
            self._pressed = None
        return False


class SceneView:
    """Scene -> actors. ``widget`` is the interactor to put in a window."""

    def __init__(self, scene: Scene, parent: Any = None) -> None:
        self.scene = scene
        self.plotter = DropInteractor(parent, auto_update=False)
        self.widget = self.plotter
        self.plotter.set_background("white")
        self._actors: dict[str, Any] = {}
        self._pickable: dict[str, tuple[str, str]] = {}  # actor name -> (layer, location)
        self._camera_set = False
        self._render_pending = False
        self.on_pick: Callable[[dict[str, Any] | None], None] | None = None
        self._click_filter = _ClickFilter(self._clicked)
        self.plotter.installEventFilter(self._click_filter)
        scene.subscribe(self._on_scene)

    # ---- scene events ---------------------------------------------------------------------
    def _on_scene(self, event: SceneEvent) -> None:
        if event.kind == "layer":
            self._remove_marker()
            self._build(event.layer)
            if not self._camera_set and self.scene.layers:
                self._fit_camera()
                self._camera_set = True
        elif event.kind == "display":
            if event.layer == "curve":
                self._build("curve")
            else:
                self._apply_display(event.layer)
        elif event.kind in ("quantities", "colouring", "thresholds"):
            self._remove_marker()
            self._build("skeletal")
            self._build("curve")
        self._update_scalar_bar()
        self.request_render()

    def request_render(self) -> None:
        """Render once, on the next event-loop turn, however many scene changes arrive meanwhile
        (a frame of a large cloud costs tens to hundreds of ms in software GL)."""
        if not self._render_pending:
            self._render_pending = True
            QtCore.QTimer.singleShot(0, self._render_now)

    def _render_now(self) -> None:
        if self._render_pending and not getattr(self.plotter, "_closed", False):
            self._render_pending = False
            # A repaint request, not plotter.render(): pyvistaqt's paintGL always renders, so
            # render() followed by the paint it causes would draw every frame twice.
            self.plotter.update()

    def rebuild(self) -> None:
        for name in ("cloud", "skeletal", "curve"):
            self._build(name)
        self._update_scalar_bar()
        self.plotter.render()

    def _remove(self, *names: str) -> None:
        for name in [*names, *(f"{n}-nan" for n in names)]:
            if self._actors.pop(name, None) is not None:
                self.plotter.remove_actor(name, render=False)
            self._pickable.pop(name, None)

    def _build(self, name: str | None) -> None:
        if name == "cloud":
            self._build_cloud()
        elif name == "skeletal":
            self._build_skeletal()
        elif name == "curve":
            self._build_curve()

    def _points_actor(self, key: str, points: np.ndarray, layer: Any, values: np.ndarray | None,
                      plain: tuple[int, int, int], size: float, pickable: tuple[str, str] | None) -> None:
        poly = pv.PolyData(_display_coordinates(points))
        kwargs: dict[str, Any] = dict(
            style="points", point_size=size, opacity=layer.opacity, lighting=False, name=key,
            reset_camera=False, render=False, render_points_as_spheres=False, pickable=pickable is not None,
        )
        if values is not None:
            poly.point_data["values"] = np.asarray(values, dtype=float)
            clim = self.scene.colour_range()
            kwargs.update(scalars="values", cmap=make_lut(clim), clim=clim, show_scalar_bar=False)
        else:
            kwargs.update(color=plain)
        actor = self.plotter.add_mesh(poly, **kwargs)
        actor.SetVisibility(layer.visible)
        if key.startswith("curve"):
            _draw_in_front(actor)
        self._actors[key] = actor
        if pickable is not None:
            self._pickable[key] = pickable
        invalid = None if values is None else ~np.isfinite(np.asarray(values, dtype=float))
        if invalid is not None and invalid.any():
            # Invalid elements are few and matter: drawn larger, in front, so they are seen at a glance.
            nan_actor = self.plotter.add_mesh(
                pv.PolyData(_display_coordinates(np.asarray(points)[invalid])), color=MAGENTA, style="points",
                point_size=size + 4, lighting=False, name=f"{key}-nan", reset_camera=False, render=False,
                render_points_as_spheres=False, pickable=False,
            )
            nan_actor.SetVisibility(layer.visible)
            _draw_in_front(nan_actor, -400.0)
            self._actors[f"{key}-nan"] = nan_actor

    def _build_cloud(self) -> None:
        self._remove("cloud")
        layer = self.scene.cloud
        if layer is not None:
            self._points_actor("cloud", layer.points, layer, None, CLOUD_GREY, layer.point_size, None)

    def _build_skeletal(self) -> None:
        self._remove("skeletal")
        layer = self.scene.skeletal
        if layer is None:
            return
        q = layer.quantity(self.scene.metric)
        self._points_actor("skeletal", layer.points, layer, None if q is None else q.values, SKELETAL_PLAIN,
                           layer.point_size, ("skeletal", "points"))

    def _build_curve(self) -> None:
        self._remove("curve-edges", "curve-vertices", "curve-samples")
        layer = self.scene.curve
        if layer is None:
            return
        verts = np.ascontiguousarray(layer.points, dtype=float)
        edges = np.asarray(layer.edges, dtype=np.int64).reshape(-1, 2)
        if len(edges):
            cells = np.hstack([np.full((len(edges), 1), 2, dtype=np.int64), edges]).ravel()
            lines = pv.PolyData(verts, lines=cells)
            if self.scene.edges_as_tubes:
                radius = 0.004 * _diagonal(self.scene)
                mesh = lines.tube(radius=radius, n_sides=12)
                actor = self.plotter.add_mesh(mesh, color=CURVE_EDGE, name="curve-edges", reset_camera=False,
                                              render=False, pickable=False, smooth_shading=True)
            else:
                actor = self.plotter.add_mesh(lines, color=CURVE_EDGE, style="wireframe", line_width=2.5,
                                              lighting=False, name="curve-edges", reset_camera=False,
                                              render=False, pickable=False)
            actor.SetVisibility(layer.visible)
            _draw_in_front(actor)
            self._actors["curve-edges"] = actor
        location = CURVE_LOCATION[self.scene.metric]
        q = layer.quantity(self.scene.metric)
        vert_values = q.values if (q is not None and location == "vertices") else None
        self._points_actor("curve-vertices", verts, layer, vert_values, CURVE_VERTEX, layer.point_size,
                           ("curve", "vertices"))
        if layer.samples is not None and q is not None and location == "samples":
            self._points_actor("curve-samples", layer.samples, layer, q.values, CURVE_VERTEX,
                               max(layer.point_size - 2.0, 3.0), ("curve", "samples"))

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
            if actor is not None and actor.mapper.scalar_visibility and actor.GetVisibility():
                return actor
        return None

    def _update_scalar_bar(self) -> None:
        for title in list(self.plotter.scalar_bars.keys()):
            self.plotter.remove_scalar_bar(title, render=False)
        actor = self._coloured_actor()
        if actor is None:
            return
        self.plotter.add_scalar_bar(
            title=self.scene.metric, mapper=actor.mapper, n_labels=5, fmt="%.2f", color="black",
            nan_annotation=self.scene.n_invalid_shown() > 0, vertical=True, position_x=0.87, position_y=0.25,
            width=0.06, height=0.5, title_font_size=14, label_font_size=12, render=False,
        )

    # ---- camera ---------------------------------------------------------------------------
    def _fit_camera(self) -> None:
        """Frame the scene left of the colour bar: the projection centre moves left and the view
        zooms out a little, so the bar on the right edge does not cover the skeleton."""
        # Through the renderer: Plotter.reset_camera and a first Plotter.camera access both render a
        # frame synchronously, and a frame of a 1M-point cloud costs 0.3-1 s in software GL.
        ren = self.plotter.renderer
        camera = ren.camera
        if not camera.is_set:
            ren.camera_position = ren.get_default_cam_pos()
            camera.is_set = True
        ren.reset_camera(render=False)
        camera.SetWindowCenter(0.12, 0.0)
        camera.zoom(0.9)

    def reset_camera(self) -> None:
        self._fit_camera()
        self.request_render()

    def standard_view(self, name: str) -> None:
        """'xy', 'xz', 'yz' (and their negatives '-xy', ...) or 'iso'."""
        p = self.plotter
        views = {
            "xy": lambda: p.view_xy(), "-xy": lambda: p.view_xy(negative=True),
            "xz": lambda: p.view_xz(), "-xz": lambda: p.view_xz(negative=True),
            "yz": lambda: p.view_yz(), "-yz": lambda: p.view_yz(negative=True),
            "iso": lambda: p.view_isometric(),
        }
        if name not in views:
            raise ValueError(f"unknown view {name!r}")
        views[name]()
        self._fit_camera()
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
        self._render_pending = False
        self.plotter.render()
        img = self.plotter.screenshot(None, transparent_background=transparent, return_img=True, scale=int(scale))
        return np.asarray(img)

    def close(self) -> None:
        self.scene.unsubscribe(self._on_scene)
        self.plotter.close()


def _display_coordinates(points: np.ndarray) -> np.ndarray:
    """float32 for the GPU (a 1M-point cloud draws several times faster than from doubles) unless
    the coordinates are so far from the origin that float32 would visibly round them."""
    pts = np.asarray(points)
    if pts.size and float(np.abs(pts).max()) < 1e5:
        return np.ascontiguousarray(pts, dtype=np.float32)
    return np.ascontiguousarray(pts, dtype=np.float64)


def _draw_in_front(actor: Any, offset: float = -200.0) -> None:
    """The curve skeleton usually lies exactly on the skeletal points (both on the medial axis):
    a depth offset draws it in front of coincident points instead of a random z-fight."""
    import vtk

    vtk.vtkMapper.SetResolveCoincidentTopologyToPolygonOffset()
    mapper = actor.GetMapper()
    mapper.SetRelativeCoincidentTopologyPointOffsetParameter(offset)
    mapper.SetRelativeCoincidentTopologyLineOffsetParameters(0.0, offset)
    mapper.SetRelativeCoincidentTopologyPolygonOffsetParameters(0.0, offset)


def _diagonal(scene: Scene) -> float:
    for name in ("cloud", "curve", "skeletal"):
        layer = scene.layers.get(name)
        if layer is not None and len(layer.points):
            d = float(np.linalg.norm(layer.points.max(axis=0) - layer.points.min(axis=0)))
            if d > 0:
                return d
    return 1.0
