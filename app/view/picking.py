"""Picking by projection: the element drawn nearest to a click, found with numpy.

Every visible skeleton element is projected through the camera's composite matrix (a 4x4 product:
tens of ms for a million points, where VTK's point picker took seconds with a synchronous frame).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["project_to_display", "nearest_on_screen"]


def project_to_display(renderer: Any, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Display coordinates (pixels, origin bottom left, VTK's convention) and depth of world points."""
    w, h = renderer.GetSize()
    x0, y0, _, _ = renderer.GetViewport()
    win_w, win_h = renderer.GetRenderWindow().GetSize()
    camera = renderer.GetActiveCamera()
    m = camera.GetCompositeProjectionTransformMatrix(w / h if h else 1.0, -1, 1)
    mat = np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)], dtype=np.float64)
    pts = np.asarray(points, dtype=np.float64)
    hom = pts @ mat[:3, :3].T + mat[:3, 3]
    wv = pts @ mat[3, :3] + mat[3, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        xv, yv, zv = hom[:, 0] / wv, hom[:, 1] / wv, hom[:, 2] / wv
    xd = (xv + 1.0) * 0.5 * w + x0 * win_w
    yd = (yv + 1.0) * 0.5 * h + y0 * win_h
    zd = np.where(wv > 0, zv, np.inf)  # behind the camera: never picked
    return xd, yd, zd


def nearest_on_screen(renderer: Any, points: np.ndarray, x: float, y: float,
                      tolerance: float) -> tuple[int, float, float] | None:
    """(index, pixel distance, depth) of the point drawn nearest to display point (x, y) within
    ``tolerance`` pixels (the front-most of those equally near), None when none is that near."""
    if not len(points):
        return None
    xd, yd, zd = project_to_display(renderer, points)
    d2 = (xd - x) ** 2 + (yd - y) ** 2
    near = np.flatnonzero((d2 <= tolerance * tolerance) & np.isfinite(zd))
    if not len(near):
        return None
    dist = np.sqrt(d2[near])
    order = np.lexsort((zd[near], np.round(dist)))
    i = int(near[order[0]])
    return i, float(np.sqrt(d2[i])), float(zd[i])
