"""3-D highlights of the picked element's support (issue 11), drawn over the scene in the same plotter.

A curve sample: its slab's cloud points and the ring kept, the ellipse's centre. A skeletal point: its
k neighbours, their corresponding cloud points and the two centroids m_s, m_o of paper Eq. 10, with
lines from each neighbour to its cloud point. Actors are named ``support-*``, kept apart from the
scene view's own, and removed whenever the scene's layers or results change.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyvista as pv

from ..scene.supports import ElementSupport
from .actors import display_coordinates, draw_in_front

__all__ = ["SupportOverlay", "OVERLAY_COLOURS"]

# (colour, point size) per highlighted set; chosen off the viridis map and off magenta
OVERLAY_COLOURS: dict[str, tuple[tuple[int, int, int], float]] = {
    "slab": ((230, 120, 20), 5.0),
    "ring": ((200, 20, 20), 7.0),
    "centre": ((20, 160, 40), 14.0),
    "neighbours": ((20, 60, 200), 9.0),
    "cloud": ((230, 120, 20), 7.0),
    "m_s": ((20, 160, 40), 16.0),
    "m_o": ((200, 20, 20), 16.0),
}


class SupportOverlay:
    def __init__(self, view: Any) -> None:
        self.view = view
        self.names: list[str] = []
        self.support: ElementSupport | None = None

    @property
    def plotter(self) -> Any:
        return self.view.plotter

    def clear(self) -> None:
        for name in self.names:
            self.plotter.remove_actor(name, render=False)
        had = bool(self.names)
        self.names = []
        self.support = None
        if had:
            self.view.request_render()

    def show(self, support: ElementSupport | None) -> None:
        self.clear()
        self.support = support
        if support is None or support.kind not in ("slab", "knn"):
            return
        pts = support.points3d
        if support.kind == "knn" and len(pts.get("neighbours", ())):
            nb, cl = pts["neighbours"], pts["cloud"]
            segs = np.empty((2 * len(nb), 3))
            segs[0::2], segs[1::2] = nb, cl
            cells = np.column_stack([np.full(len(nb), 2), 2 * np.arange(len(nb)), 2 * np.arange(len(nb)) + 1]).ravel()
            lines = pv.PolyData(display_coordinates(segs), lines=cells)
            self._add("support-links", lines, (120, 120, 120), 1.0, style="wireframe")
        for key, (colour, size) in OVERLAY_COLOURS.items():
            arr = pts.get(key)
            if arr is None or not len(arr):
                continue
            self._add(f"support-{key}", pv.PolyData(display_coordinates(arr)), colour, size)
        self.view.request_render()

    def _add(self, name: str, mesh: pv.PolyData, colour: Any, size: float, style: str = "points") -> None:
        kwargs = {"point_size": size} if style == "points" else {"line_width": 1.5}
        actor = self.plotter.add_mesh(mesh, color=colour, style=style, lighting=False, name=name,
                                      reset_camera=False, render=False, pickable=False,
                                      render_points_as_spheres=style == "points" and size >= 12, **kwargs)
        draw_in_front(actor, -600.0)
        self.names.append(name)
