"""Full detail at rest for less: each big layer draws only its points that can show (:mod:`.visibility`).

Under software GL a frame's cost is per point drawn, and at rest most of a million points lose every
depth test. Before a full-detail frame, when the camera, the view's size or the layers changed since
the last one, every big layer is projected (numpy) and its vertex list set to the points that can win
a pixel, in their order: the same image, far fewer points. Only flat points of whole-pixel sizes at a
device pixel ratio of 1 are thinned (their footprint is known); otherwise a layer draws all its points.
A translucent layer hides nothing, so only its points behind opaque ones or off the view drop: it is
thinned only when most of its box lies off the view (its points behind the skeletal set inside it
were a few percent at 1M, for more time than they saved).
The layers' arrays stay whole: picking and colouring index the real points.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from .picking import project_to_display
from .visibility import ScreenPoints, visible_points

__all__ = ["CulledLayer", "RestingCull", "camera_key", "set_vertices"]


@dataclass
class CulledLayer:
    """A big layer's mesh (its points in the layer's order), actor and points as ``pick_layout`` gives them."""

    mesh: Any
    actor: Any
    points_t: np.ndarray


def set_vertices(mesh: Any, idx: np.ndarray | None) -> None:
    """Draw the points ``idx`` of ``mesh`` (all of them for None) as its vertex cells."""
    from vtkmodules.util.numpy_support import numpy_to_vtkIdTypeArray
    from vtkmodules.vtkCommonDataModel import vtkCellArray

    idx = np.arange(mesh.n_points, dtype=np.int64) if idx is None else np.asarray(idx, dtype=np.int64)
    cells = vtkCellArray()
    cells.SetData(numpy_to_vtkIdTypeArray(np.arange(len(idx) + 1, dtype=np.int64), deep=True),
                  numpy_to_vtkIdTypeArray(idx, deep=True))
    mesh.SetVerts(cells)


def camera_key(renderer: Any) -> tuple:
    """What a frame's projection of the points depends on: the renderer's size and viewport, the camera."""
    cam = renderer.GetActiveCamera()
    return (tuple(renderer.GetSize()), tuple(renderer.GetViewport()), cam.GetPosition(), cam.GetFocalPoint(),
            cam.GetViewUp(), cam.GetViewAngle(), cam.GetParallelProjection(), cam.GetParallelScale())


def _rounding(renderer: Any, points_t: np.ndarray) -> np.ndarray:
    """A bound (pixels) on how far float32 projections (numpy's here, GL's) may put each point from its
    exact display position: tiny, unless the camera is zoomed so far in that a pixel nears the
    coordinates' float32 spacing. From the composite matrix, the coordinates' magnitude and each point's w."""
    w, h = renderer.GetSize()
    m = renderer.GetActiveCamera().GetCompositeProjectionTransformMatrix(w / h if h else 1.0, -1, 1)
    mat = np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])
    reach = np.abs(mat[:, :3]) @ np.abs(points_t).max(axis=1).astype(float) + np.abs(mat[:, 3])
    hw = mat[3, :3].astype(np.float32) @ points_t + np.float32(mat[3, 3])
    scale = 16 * float(np.finfo(np.float32).eps) * 0.5 * max(w, h) * (max(reach[0], reach[1]) + reach[3])
    with np.errstate(divide="ignore"):
        return np.float32(scale) / np.abs(hw)


def _mostly_off_view(renderer: Any, points_t: np.ndarray) -> bool:
    """Whether most of the screen box of the points' bounding box lies off the view (or behind the
    camera). From the points themselves: VTK's bounds of a thinned mesh are those of its drawn points."""
    lo, hi = points_t.min(axis=1), points_t.max(axis=1)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])],
                       dtype=np.float32).T
    x, y, z = project_to_display(renderer, corners)
    if not np.all(np.isfinite(z)):
        return True
    w, h = renderer.GetSize()
    x0, y0 = (renderer.GetViewport()[i] * renderer.GetRenderWindow().GetSize()[i] for i in (0, 1))
    x, y = x - x0, y - y0
    area = max(float(np.ptp(x) * np.ptp(y)), 1e-9)
    inside = max(0.0, min(x.max(), w) - max(x.min(), 0)) * max(0.0, min(y.max(), h) - max(y.min(), 0))
    return inside / area < 0.5


class RestingCull:
    """The vertex lists the big layers draw at rest, recomputed only when what they depend on changed."""

    def __init__(self) -> None:
        self._key: tuple | None = None
        self.drawn: dict[str, int] = {}  # layer actor name -> points it draws
        self.seconds = 0.0  # how long the last recomputation took (projection and visibility)

    def forget(self, name: str) -> None:
        """Layer ``name`` was rebuilt (its new mesh draws every point): recompute at the next frame."""
        self._key = None
        self.drawn.pop(name, None)

    def apply(self, renderer: Any, layers: dict[str, CulledLayer], thin: bool) -> None:
        """Set each visible layer's vertex list for the camera of ``renderer``; ``thin`` False: all points."""
        shown = {k: c for k, c in layers.items() if c.actor.GetVisibility()}
        sizes = {k: float(c.actor.GetProperty().GetPointSize()) for k, c in shown.items()}
        key = (thin, camera_key(renderer) if thin else None,
               tuple((k, id(c.mesh), sizes[k], c.actor.GetProperty().GetOpacity()) for k, c in sorted(shown.items())))
        if key == self._key:
            return
        self._key = key
        culled = {k: c for k, c in shown.items() if thin and sizes[k] == int(sizes[k]) and sizes[k] >= 1
                  and (c.actor.GetProperty().GetOpacity() >= 1.0 or _mostly_off_view(renderer, c.points_t))}
        for k, c in shown.items():
            if k not in culled and self.drawn.get(k, c.mesh.n_points) != c.mesh.n_points:
                set_vertices(c.mesh, None)
            self.drawn[k] = c.mesh.n_points
        if not culled:
            return
        start = time.perf_counter()
        w, h = renderer.GetSize()
        x0, y0 = (renderer.GetViewport()[i] * renderer.GetRenderWindow().GetSize()[i] for i in (0, 1))
        screen = []
        for k, c in culled.items():
            x, y, z = project_to_display(renderer, c.points_t)
            screen.append(ScreenPoints(x - x0, y - y0, z, int(sizes[k]), c.actor.GetProperty().GetOpacity() >= 1.0,
                                       _rounding(renderer, c.points_t)))
        for (k, c), idx in zip(culled.items(), visible_points(screen, w, h)):
            set_vertices(c.mesh, idx)
            self.drawn[k] = len(idx)
        self.seconds = time.perf_counter() - start
