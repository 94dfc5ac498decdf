"""Camera placement for the 3D view: framing all the data beside the colour bar, standard views, and
camera files (View > Save camera, ``skelscope --camera FILE``).

Works on the renderer directly where pyvista's Plotter helpers would render a frame synchronously
(a frame of a 1M-point cloud costs 0.3-1 s in software GL).
"""

from __future__ import annotations

import json
import os
from typing import Any, Iterable

import numpy as np

from skelcore.errors import SkelInputError
from skelcore.io.atomic import atomic_open

__all__ = ["fit_camera", "axes_viewport", "AXES_PIXELS", "orient_standard_view", "camera_state", "apply_camera_state", "save_camera", "load_camera",
           "check_camera", "FIT_X", "FIT_Y", "MAX_VIEW_SIZE"]

WINDOW_CENTER_X = 0.12
"""The projection centre moves this far right (viewport units, [-1, 1]): the data sits left of the bar."""
FIT_X = (-0.95, 0.72)
"""Where the data may lie across the view (viewport units): the colour bar starts at 0.74 (x = 0.87)."""
FIT_Y = (-0.92, 0.92)
AXES_PIXELS = 120
"""The orientation axes' square in the view's lower-left corner, in pixels at scale 1: pyvista's
default, a fifth of the view's width and height, drew the axes over the data at 1920 x 1080."""
_AXES_MARGIN = 8  # pixels kept free around the axes' square (a point drawn beside it has a size)
_FIT_POINTS = 20000  # points per layer projected to fit the view (plus each layer's extreme points)


def _fit_samples(point_sets: Iterable[np.ndarray]) -> np.ndarray:
    """The points the view must show: every point of small sets; a spread subsample of big ones,
    with each set's extreme points along x, y, z (the subsample could miss a thin arm's tip)."""
    out = []
    for pts in point_sets:
        pts = np.asarray(pts)  # subsampled before any copy to float (a 1M-point copy is 24 MB)
        if not len(pts):
            continue
        if len(pts) > _FIT_POINTS:
            extremes = np.concatenate([pts.argmin(axis=0), pts.argmax(axis=0)])
            idx = np.concatenate([np.linspace(0, len(pts) - 1, _FIT_POINTS).astype(np.int64), extremes])
            pts = pts[idx]
        out.append(np.asarray(pts, dtype=float))
    return np.concatenate(out) if out else np.zeros((0, 3))


def axes_viewport(width: int, height: int, ratio: float = 1.0) -> tuple[float, float, float, float]:
    """The orientation axes' viewport (render-window units, [0, 1]) for a view of ``width`` x ``height``
    device pixels at ``ratio`` device pixels a pixel: an ``AXES_PIXELS`` square in the lower-left corner."""
    side = AXES_PIXELS * ratio
    return 0.0, 0.0, min(0.5, side / max(width, 1)), min(0.5, side / max(height, 1))


def _keep_clear(plotter: Any) -> tuple[float, float] | None:
    """The lower-left box (view units, [-1, 1]) the data must stay out of: the orientation axes' square
    and a margin, when the axes are shown."""
    widget = getattr(plotter.renderer, "axes_widget", None)
    if widget is None or not widget.GetEnabled():
        return None
    w, h = plotter.renderer.GetSize()
    _x0, _y0, x1, y1 = widget.GetViewport()
    return -1.0 + 2.0 * (x1 + _AXES_MARGIN / max(w, 1)), -1.0 + 2.0 * (y1 + _AXES_MARGIN / max(h, 1))


def fit_camera(plotter: Any, point_sets: Iterable[np.ndarray] = ()) -> None:
    """Frame the data left of the colour bar: the projection centre moves left, then the view zooms
    so that every point in ``point_sets`` (all visible data when empty) lies inside FIT_X x FIT_Y and
    out of the orientation axes' corner (zooming out further only if the data reaches into it)."""
    # Through the renderer: Plotter.reset_camera and a first Plotter.camera access both render a
    # frame synchronously, and a frame of a 1M-point cloud costs 0.3-1 s in software GL.
    ren = plotter.renderer
    camera = ren.camera
    pts = _fit_samples(point_sets)
    if not camera.is_set:
        # pyvista's default direction, about the points' box centre (its own asks VTK for every
        # actor's bounds: 0.2 s at 1M points)
        ren.camera_position = ren.get_default_cam_pos() if not len(pts) else _default_position(pts)
        camera.is_set = True
    if len(pts):
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        ren.ResetCamera(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])
    else:
        ren.reset_camera(render=False)
    camera.SetWindowCenter(WINDOW_CENTER_X, 0.0)
    if not len(pts):
        camera.zoom(0.9)
        return
    clear = _keep_clear(plotter)
    for _ in range(4):  # perspective: zooming scales projected offsets exactly; depth clipping may shift a bit
        x, y = _view_coordinates(ren, pts)
        if not len(x):
            break
        # Centre the data in the free area (its box centre need not be its picture's centre): pan
        # the camera by the world offset between the two view points at the focal point's depth.
        fp = np.asarray(camera.GetFocalPoint())
        ren.SetWorldPoint(*fp, 1.0)
        ren.WorldToView()
        depth = ren.GetViewPoint()[2]
        now = _view_to_world(ren, (x.max() + x.min()) / 2, (y.max() + y.min()) / 2, depth)
        goal = _view_to_world(ren, (FIT_X[0] + FIT_X[1]) / 2, (FIT_Y[0] + FIT_Y[1]) / 2, depth)
        shift = now - goal
        camera.SetFocalPoint(*(fp + shift))
        camera.SetPosition(*(np.asarray(camera.GetPosition()) + shift))
        x, y = _view_coordinates(ren, pts)
        # Zooming scales the view about the focal point's image (the window centre moved it left).
        (cx,), (cy,) = _view_coordinates(ren, np.asarray([camera.GetFocalPoint()]))
        need = max(
            (x.max() - cx) / (FIT_X[1] - cx), (cx - x.min()) / (cx - FIT_X[0]),
            (y.max() - cy) / (FIT_Y[1] - cy), (cy - y.min()) / (cy - FIT_Y[0]), 1e-6,
        )
        if clear is not None and cx > clear[0] and cy > clear[1]:
            # a point in the corner leaves it once zooming brings it right of or above the box
            inside = (x < clear[0]) & (y < clear[1])
            if inside.any():
                need = max(need, float(np.minimum((cx - x[inside]) / (cx - clear[0]),
                                                  (cy - y[inside]) / (cy - clear[1])).max()))
        if 0.98 <= need <= 1.0:
            break
        need *= 1.003  # land just inside the free area
        if camera.GetParallelProjection():
            camera.SetParallelScale(camera.GetParallelScale() * need)
        else:
            camera.Zoom(1.0 / need)
    ren.ResetCameraClippingRange()


def _view_coordinates(ren: Any, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Normalized viewport coordinates ([-1, 1]) of world points, by the camera's composite matrix."""
    w, h = ren.GetSize()
    aspect = w / h if h else 1.0
    near, far = ren.GetActiveCamera().GetClippingRange()
    m = ren.GetActiveCamera().GetCompositeProjectionTransformMatrix(aspect, -1, 1)
    mat = np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])
    # einsum's own loop, not a BLAS call: threaded BLAS on a (n, 4) product waits on busy cores
    hom = np.einsum("ij,kj->ik", pts, mat[:, :3]) + mat[:, 3]
    wv = hom[:, 3]
    ok = wv > 1e-12
    return hom[ok, 0] / wv[ok], hom[ok, 1] / wv[ok]


def _default_position(pts: np.ndarray) -> list:
    """pyvista's default camera (its theme's direction and view-up) about the centre of ``pts``' box."""
    import pyvista as pv

    centre = (pts.min(axis=0) + pts.max(axis=0)) / 2
    theme = pv.global_theme.camera
    return [tuple(np.asarray(theme.position, dtype=float) + centre), tuple(centre), tuple(theme.viewup)]


def _view_to_world(ren: Any, x: float, y: float, z: float) -> np.ndarray:
    ren.SetViewPoint(float(x), float(y), float(z))
    ren.ViewToWorld()
    wp = ren.GetWorldPoint()
    return np.asarray(wp[:3]) / (wp[3] if wp[3] else 1.0)


def orient_standard_view(plotter: Any, name: str) -> None:
    """Turn the camera to 'xy', 'xz', 'yz' (and their negatives '-xy', ...) or 'iso'."""
    p = plotter
    views = {
        "xy": lambda: p.view_xy(render=False), "-xy": lambda: p.view_xy(negative=True, render=False),
        "xz": lambda: p.view_xz(render=False), "-xz": lambda: p.view_xz(negative=True, render=False),
        "yz": lambda: p.view_yz(render=False), "-yz": lambda: p.view_yz(negative=True, render=False),
        "iso": lambda: p.view_isometric(render=False),
    }
    if name not in views:
        raise ValueError(f"unknown view {name!r}")
    views[name]()


_KEYS = ("position", "focal_point", "view_up", "view_angle", "parallel_projection", "parallel_scale")


def camera_state(plotter: Any) -> dict[str, Any]:
    """The camera as plain values (what a camera file holds), with the view's size in pixels: the
    same camera frames the data alike only in a view of the same shape (``skelscope --size``)."""
    cam = plotter.renderer.GetActiveCamera()
    return {
        "position": list(cam.GetPosition()), "focal_point": list(cam.GetFocalPoint()), "view_up": list(cam.GetViewUp()),
        "view_angle": cam.GetViewAngle(), "parallel_projection": bool(cam.GetParallelProjection()),
        "parallel_scale": cam.GetParallelScale(), "window_center": list(cam.GetWindowCenter()),
        "view_size": [int(v) for v in plotter.render_window.GetSize()],
    }


def apply_camera_state(plotter: Any, state: dict[str, Any]) -> None:
    ren = plotter.renderer
    cam = ren.GetActiveCamera()
    cam.SetPosition(*state["position"])
    cam.SetFocalPoint(*state["focal_point"])
    cam.SetViewUp(*state["view_up"])
    cam.SetViewAngle(float(state["view_angle"]))
    cam.SetParallelProjection(bool(state["parallel_projection"]))
    cam.SetParallelScale(float(state["parallel_scale"]))
    cam.SetWindowCenter(*state.get("window_center", (WINDOW_CENTER_X, 0.0)))
    ren.camera.is_set = True
    ren.ResetCameraClippingRange()


def save_camera(path: str | os.PathLike, state: dict[str, Any], inputs: Iterable[str] = ()) -> str:
    """Write a camera file (JSON), atomically and never over a loaded input."""
    with atomic_open(path, "w", inputs=tuple(inputs)) as fh:
        json.dump({"skelscope_camera": 1, **state}, fh, indent=2)
        fh.write("\n")
    return str(path)


def load_camera(path: str | os.PathLike) -> dict[str, Any]:
    """Read a camera file; SkelInputError naming the file and the problem otherwise."""
    try:
        with open(path, encoding="utf-8") as fh:
            doc = json.load(fh)
    except FileNotFoundError:
        raise SkelInputError("camera file not found", path) from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise SkelInputError(f"not a camera file ({exc})", path) from None
    missing = [k for k in _KEYS if not isinstance(doc, dict) or k not in doc]
    if missing:
        raise SkelInputError(f"not a camera file (missing {', '.join(missing)})", path)
    try:
        for key in ("position", "focal_point", "view_up"):
            vec = [float(v) for v in doc[key]]
            if len(vec) != 3 or not np.all(np.isfinite(vec)):
                raise ValueError(key)
            doc[key] = vec
        doc["view_angle"], doc["parallel_scale"] = float(doc["view_angle"]), float(doc["parallel_scale"])
    except (TypeError, ValueError):
        raise SkelInputError("not a camera file (bad vector or number)", path) from None
    return check_camera(doc, path)


def check_camera(doc: dict[str, Any], path: str | os.PathLike = "camera") -> dict[str, Any]:
    """The optional ``view_size`` of a camera record (two positive integers, or absent: files from
    before it was saved), checked; SkelInputError naming ``path`` otherwise."""
    size = doc.get("view_size")
    if size is not None:
        try:
            size = [int(v) for v in size]
        except (TypeError, ValueError):
            size = []
        if len(size) != 2 or min(size) < 1 or max(size) > MAX_VIEW_SIZE:
            raise SkelInputError(f"not a camera file (view_size must be two integers in 1..{MAX_VIEW_SIZE})", path)
        doc["view_size"] = size
    return doc


MAX_VIEW_SIZE = 16384
"""The largest view side a camera file or ``--size`` may ask for, in pixels."""
