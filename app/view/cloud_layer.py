"""The translucent cloud drawn once into a background image that frames of the skeleton alone reuse.

Under software GL a frame's cost is mostly the cloud's points (docs/performance.md 6.10, "The frame
of an edit": at 100k points about 55 of a frame's 75 CPU ms). A frame that changes only the skeleton
(an edit's recoloured curve, another metric, a marker) keeps the camera, so the cloud's points that
touch no pixel of a skeleton element draw the same pixels as before. Those ("far") are drawn once,
when the view is idle, into an image that becomes the renderer's background; each frame then draws
only the cloud's points near the drawn skeleton over it. Every point of a one-colour translucent
cloud applies the same blend to a pixel, so the order in which points are drawn changes nothing, and
no far point covers a pixel of the skeleton: the frame is the same image to the bit
(tests/app/test_app_cloud_layer.py).

Only where that holds: software GL, the view's own scale, a one-colour translucent cloud of flat
points drawn whole (not thinned at rest, :mod:`.culling`), every other 3-D actor points or lines
without a transform, no eye-dome shading. A frame after the camera, the view's size or the cloud's
look changed, or with a skeleton element drawn off the near pixels, draws the whole cloud, and the
image is made again once no frame has come for BUILD_DELAY_MS.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
from PySide6 import QtCore
from scipy.ndimage import maximum_filter

from .culling import camera_key, set_vertices
from .picking import pick_layout, project_to_display

__all__ = ["BUILD_DELAY_MS", "MIN_CLOUD_POINTS", "CloudFrame", "CloudLayer", "footprint_points"]

BUILD_DELAY_MS = 300
"""The background image is made this long after the last frame that could not use it."""
LINE_STEP_PX = 0.5
"""A line's footprint: points this far apart on screen along each of its segments."""
MIN_CLOUD_POINTS = 50_000
"""Smaller clouds draw in a few ms: the image would cost more than it saves."""
MAX_SKELETON_POINTS = 50_000
"""Other 3-D actors are projected at every frame to check their footprint: at most this many points."""


@dataclass
class CloudFrame:
    """What a frame draws, as the view knows it: the cloud's actor, mesh and points (``pick_layout``),
    whether the cloud is drawn whole at rest (``whole``) and the frame may use the image at all
    (``allowed``: software GL, the view's own scale, not moving, no eye-dome shading)."""

    actor: Any
    mesh: Any
    points_t: np.ndarray
    whole: bool
    allowed: bool


def footprint_points(renderer: Any, actor: Any) -> tuple[np.ndarray, np.ndarray, float] | None:
    """Display x, y of what ``actor`` draws (its points; along its lines, every LINE_STEP_PX) and the
    half width of its footprint in pixels; None when it draws surfaces or has a transform (its
    footprint is then not known from its points)."""
    data = _input(actor)
    matrix = actor.GetUserMatrix()
    if data is None or not hasattr(data, "GetPolys") or (matrix is not None and not matrix.IsIdentity()):
        return None
    if (data.GetNumberOfPolys() or data.GetNumberOfStrips() or tuple(actor.GetPosition()) != (0.0, 0.0, 0.0)
            or tuple(actor.GetScale()) != (1.0, 1.0, 1.0) or tuple(actor.GetOrientation()) != (0.0, 0.0, 0.0)):
        return None
    from vtkmodules.util.numpy_support import vtk_to_numpy

    prop = actor.GetProperty()
    if data.GetNumberOfPoints() == 0:
        return np.empty(0), np.empty(0), 0.0
    pts = vtk_to_numpy(data.GetPoints().GetData())
    x, y, _z = project_to_display(renderer, pick_layout(pts))
    # the point size counts only where points are drawn: a lines actor drawn as lines (no vertex
    # cells, not as points) covers its line width alone (the curve's edges: 1.25 px, not 2.5)
    points_drawn = (not data.GetNumberOfLines() or data.GetNumberOfVerts() or prop.GetRepresentation() == 0
                    or prop.GetVertexVisibility())
    half = 0.5 * float(prop.GetPointSize()) if points_drawn else 0.0
    if data.GetNumberOfLines():
        lines = data.GetLines()
        offsets = vtk_to_numpy(lines.GetOffsetsArray()).astype(np.int64)
        conn = vtk_to_numpy(lines.GetConnectivityArray()).astype(np.int64)
        last = np.zeros(len(conn), dtype=bool)
        last[offsets[1:] - 1] = True  # a cell's last point starts no segment
        a = conn[~last]
        b = conn[np.flatnonzero(~last) + 1]
        n = np.ceil(np.hypot(x[b] - x[a], y[b] - y[a]) / LINE_STEP_PX).astype(np.int64) + 1
        n = np.clip(np.nan_to_num(n, nan=1), 1, 1 << 16)
        seg = np.repeat(np.arange(len(a)), n)
        t = (np.arange(len(seg)) - np.repeat(np.cumsum(n) - n, n)) / np.repeat(np.maximum(n - 1, 1), n)
        x = np.concatenate([x, x[a][seg] + t * (x[b] - x[a])[seg]])
        y = np.concatenate([y, y[a][seg] + t * (y[b] - y[a])[seg]])
        half = max(half, 0.5 * float(prop.GetLineWidth()))
    keep = np.isfinite(x) & np.isfinite(y)
    return x[keep], y[keep], half


class CloudLayer:
    """The background image of a view's far cloud points, and the near points each frame draws.

    ``frame()`` gives the :class:`CloudFrame` of the next frame (None: no cloud shown); ``apply()``
    runs right before every render of the view; ``build()`` makes the image (called by its timer)."""

    def __init__(self, plotter: Any, frame: Callable[[], CloudFrame | None]) -> None:
        self.plotter = plotter
        self._frame = frame
        self._key: tuple | None = None  # what the image shows (camera, size, the cloud's look)
        self._covered: np.ndarray | None = None  # pixels where a skeleton element may be drawn
        self._half = 0.0  # the widest skeleton footprint's half width when the image was made
        self._near: np.ndarray | None = None  # the cloud points a frame over the image draws
        self._mesh: Any = None  # the mesh whose vertex list is the near points (while applied)
        self._texture: Any = None
        self.applied = False  # the last frame drew the near points over the image
        self.builds = 0  # images made (for tests and benchmarks)
        self._building = False
        self._refused: tuple | None = None  # a view whose own image did not cover its skeleton
        self._timer = QtCore.QTimer()
        self._timer.setSingleShot(True)
        self._timer.setInterval(BUILD_DELAY_MS)
        self._timer.timeout.connect(self.build)

    @property
    def build_pending(self) -> bool:
        return self._timer.isActive()

    @property
    def renderer(self) -> Any:
        return self.plotter.renderer

    # ---- before each render ----------------------------------------------------------------
    def apply(self) -> None:
        """The cloud's vertex list and the background for this render: the near points over the image
        when it shows this view, else the whole cloud (and the image made again once idle)."""
        if self._building:
            return
        frame = self._frame()
        if frame is None or not self._usable(frame):
            self.off(frame)
            self._timer.stop()
            return
        dynamic = self._dynamic(frame)
        if dynamic is not None and self._shows(frame) and self._covers(dynamic):
            if not self.applied or self._mesh is not frame.mesh:
                self._use(frame)
            return
        self.off(frame)
        if dynamic is not None and self._frame_key(frame) != self._refused:
            self._timer.start()  # restarted by every frame: made once frames stop

    def off(self, frame: CloudFrame | None = None) -> None:
        """The whole cloud drawn, no background image (it stays kept for a later frame)."""
        if not self.applied:
            return
        self.applied = False
        self.renderer.TexturedBackgroundOff()
        if frame is not None and frame.mesh is self._mesh and frame.whole:
            set_vertices(frame.mesh, None)
        self._mesh = None

    def close(self) -> None:
        self._timer.stop()
        self.renderer.TexturedBackgroundOff()
        self.renderer.SetBackgroundTexture(None)
        self._texture = None

    # ---- the image ---------------------------------------------------------------------------
    def build(self) -> None:
        """Draw the far points alone (nothing else, the background) and keep the picture as the
        renderer's background texture; the near points are those within reach of the skeleton's
        footprint. Not shown: the next frame draws the near points and the skeleton over it."""
        frame = self._frame()
        if frame is None or not self._usable(frame) or getattr(self.plotter, "_closed", False):
            return
        if not self.plotter.isVisible():
            return
        dynamic = self._dynamic(frame)
        if dynamic is None:
            return
        ren = self.renderer
        w, h = ren.GetSize()
        x, y, half = dynamic
        covered = np.zeros((h, w), dtype=bool)
        ix, iy = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
        on = (ix >= 0) & (ix < w) & (iy >= 0) & (iy < h)
        covered[iy[on], ix[on]] = True
        covered = maximum_filter(covered, size=3)  # a later element within a pixel of one drawn now
        size = float(frame.actor.GetProperty().GetPointSize())
        reach = int(math.ceil(0.5 * size + half)) + 2  # a point's square and an element's, both rounded
        near_pixels = maximum_filter(covered, size=2 * reach + 1)
        cx, cy, cz = project_to_display(ren, frame.points_t)
        px, py = np.floor(np.nan_to_num(cx, nan=-1e9)), np.floor(np.nan_to_num(cy, nan=-1e9))
        inside = (px >= 0) & (px < w) & (py >= 0) & (py < h) & np.isfinite(cz)
        near = np.zeros(len(cx), dtype=bool)
        near[inside] = near_pixels[py[inside].astype(np.int64), px[inside].astype(np.int64)]
        # points off the view whose square still reaches into it: drawn by each frame
        margin = reach + size
        near |= ~inside & (px > -margin) & (px < w + margin) & (py > -margin) & (py < h + margin) & np.isfinite(cz)
        near_idx, far_idx = np.flatnonzero(near), np.flatnonzero(~near)
        self._texture = self._draw_far(frame, far_idx, w, h)
        self._near, self._covered, self._half = near_idx, covered, half
        self._key = (frame.actor, frame.mesh, self._frame_key(frame))  # the actor and mesh by identity
        self._refused = None
        self.applied = False
        self.builds += 1
        if not self._covers(dynamic):  # an element just off the view: never made again for this view
            self._refused, self._key = self._frame_key(frame), None
            set_vertices(frame.mesh, None)
            return
        self._use(frame)  # set now, while idle: the frame on screen is already this picture

    def _use(self, frame: CloudFrame) -> None:
        """The near points over the image from the next render on."""
        set_vertices(frame.mesh, self._near)
        self._mesh = frame.mesh
        self.renderer.SetBackgroundTexture(self._texture)
        self.renderer.TexturedBackgroundOn()
        self.applied = True

    def _draw_far(self, frame: CloudFrame, far_idx: np.ndarray, w: int, h: int) -> Any:
        from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
        from vtkmodules.vtkCommonCore import vtkUnsignedCharArray
        from vtkmodules.vtkCommonDataModel import vtkImageData
        from vtkmodules.vtkRenderingCore import vtkTexture

        ren, window = self.renderer, self.plotter.ren_win
        hidden = [p for p in _props(ren) if p is not frame.actor and p.GetVisibility()]
        others = [r for r in _renderers(window) if r is not ren and r.GetDraw()]
        self._building = True
        try:
            for p in hidden:
                p.SetVisibility(False)
            for r in others:
                r.SetDraw(False)
            ren.TexturedBackgroundOff()
            set_vertices(frame.mesh, far_idx)
            window.SwapBuffersOff()  # kept in VTK's framebuffer: not shown, no repaint asked
            window.Render()
            window.MakeCurrent()  # VTK's own make-current: Qt's would rebind the widget's framebuffer
            x0, y0 = ren.GetOrigin()
            pixels = vtkUnsignedCharArray()
            window.GetRGBACharPixelData(x0, y0, x0 + w - 1, y0 + h - 1, 0, pixels)
        except BaseException:
            set_vertices(frame.mesh, None)
            raise
        finally:
            window.SwapBuffersOn()
            for p in hidden:
                p.SetVisibility(True)
            for r in others:
                r.SetDraw(True)
            self._building = False
        rgb = np.ascontiguousarray(vtk_to_numpy(pixels).reshape(-1, 4)[:, :3])  # opaque: no blend with the background
        image = vtkImageData()
        image.SetDimensions(w, h, 1)
        image.GetPointData().SetScalars(numpy_to_vtk(rgb, deep=True))
        texture = vtkTexture()
        texture.SetInputData(image)
        texture.SetInterpolate(False)
        return texture

    # ---- checks ------------------------------------------------------------------------------
    def _usable(self, frame: CloudFrame) -> bool:
        prop = frame.actor.GetProperty()
        return bool(frame.allowed and frame.whole and frame.mesh.n_points >= MIN_CLOUD_POINTS and frame.actor.GetVisibility() and prop.GetOpacity() < 1.0
                    and not frame.actor.GetMapper().GetScalarVisibility() and not prop.GetRenderPointsAsSpheres()
                    and frame.mesh.n_points and self.renderer.GetUseDepthPeeling() == 0
                    and not self.renderer.GetUseOIT())

    def _shows(self, frame: CloudFrame) -> bool:
        """Whether the image is of this frame's view: the same camera, size, cloud and look."""
        key = self._key
        return key is not None and key[0] is frame.actor and key[1] is frame.mesh and key[2] == self._frame_key(frame)

    def _frame_key(self, frame: CloudFrame) -> tuple:
        prop = frame.actor.GetProperty()
        return (camera_key(self.renderer), tuple(self.plotter.ren_win.GetSize()), frame.mesh.n_points, tuple(prop.GetColor()), prop.GetOpacity(), prop.GetPointSize(),
                tuple(self.renderer.GetBackground()), tuple(self.renderer.GetBackground2()),
                bool(self.renderer.GetGradientBackground()))

    def _dynamic(self, frame: CloudFrame) -> tuple[np.ndarray, np.ndarray, float] | None:
        """The footprint of every other visible 3-D actor (display x, y and the widest half width);
        None when one has a footprint not known from its points."""
        xs, ys, half = [np.empty(0)], [np.empty(0)], 0.0
        actors = self.renderer.GetActors()
        actors.InitTraversal()
        shown = [a for a in (actors.GetNextActor() for _ in range(actors.GetNumberOfItems()))
                 if a is not frame.actor and a.GetVisibility()]
        data = [_input(a) for a in shown]
        if sum(d.GetNumberOfPoints() for d in data if d is not None) > MAX_SKELETON_POINTS:
            return None
        for actor in shown:
            found = footprint_points(self.renderer, actor)
            if found is None:
                return None
            xs.append(found[0])
            ys.append(found[1])
            half = max(half, found[2])
        return np.concatenate(xs), np.concatenate(ys), half

    def _covers(self, dynamic: tuple[np.ndarray, np.ndarray, float]) -> bool:
        """Whether every skeleton element of this frame lies where one lay when the image was made."""
        x, y, half = dynamic
        if self._covered is None or half > self._half:
            return False
        h, w = self._covered.shape
        ix, iy = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
        on = (ix >= 0) & (ix < w) & (iy >= 0) & (iy < h)
        if not np.all(on | (ix < -64) | (ix >= w + 64) | (iy < -64) | (iy >= h + 64)):
            return False  # just off the view: its square may reach in
        return bool(self._covered[iy[on], ix[on]].all())


def _input(actor: Any) -> Any:
    """The dataset an actor's mapper draws, None without one."""
    mapper = actor.GetMapper()
    return None if mapper is None else mapper.GetInput()


def _props(renderer: Any) -> list[Any]:
    props = renderer.GetViewProps()
    props.InitTraversal()
    return [props.GetNextProp() for _ in range(props.GetNumberOfItems())]


def _renderers(window: Any) -> list[Any]:
    renderers = window.GetRenderers()
    renderers.InitTraversal()
    return [renderers.GetNextItem() for _ in range(renderers.GetNumberOfItems())]
