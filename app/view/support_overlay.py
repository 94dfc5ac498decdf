"""3-D highlights of the picked element's support, drawn over the scene in the same plotter.

A curve sample: its slab's cloud points, the ring kept, the fitted ellipse and its centre. A skeletal
point's centeredness: its k neighbours, their corresponding cloud points and the two centroids m_s,
m_o of paper Eq. 10, with lines from each neighbour to its cloud point. Smoothness: the tangent at
the point, its neighbours and their tangents, the one setting the value marked (Eq. 13-14); a curve
vertex's two edges (Eq. 15). Colours come from :data:`skelcore.colors.SUPPORT_COLORS`, apart from
the skeleton's; every set drawn has an entry in a legend in the view's top left corner. Actors are named
``support-*``, kept apart from the scene view's own, and removed whenever the scene's layers or
results change.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyvista as pv

from skelcore.colors import PICK_COLOR, SUPPORT_COLORS

from ..scene.supports import ElementSupport
from .actors import display_coordinates, draw_in_front

__all__ = ["SupportOverlay", "OVERLAY_COLOURS", "OVERLAY_LINES", "legend_entries"]

C = SUPPORT_COLORS
# (colour, point size, legend label per support kind) per highlighted point set
OVERLAY_COLOURS: dict[str, tuple[tuple[int, int, int], float, dict[str, str]]] = {
    "slab": (C["slab"], 5.0, {"slab": "slab's cloud points"}),
    "ring": (C["ring"], 7.0, {"slab": "ring kept"}),
    "centre": (C["centre"], 14.0, {"slab": "ellipse centre"}),
    "cloud": (C["slab"], 7.0, {"knn": "corresponding cloud points"}),
    "neighbours": (C["ring"], 9.0, {"knn": "k neighbours", "smoothness": "neighbours compared"}),
    "worst": (C["centre"], 12.0, {"smoothness": "neighbour setting s"}),
    "m_s": (C["centre"], 16.0, {"knn": "m_s (skeletal centroid)"}),
    "m_o": (C["m_o"], 16.0, {"knn": "m_o (cloud centroid)"}),
}
# (colour, line width, legend label per support kind) per highlighted set of lines
OVERLAY_LINES: dict[str, tuple[tuple[int, int, int], float, dict[str, str]]] = {
    "links": (C["links"], 1.5, {"knn": "neighbour -> its cloud point"}),
    "ellipse": (C["ellipse"], 3.0, {"slab": "fitted ellipse"}),
    "tangent": (C["ellipse"], 4.0, {"smoothness": "tangent at the point"}),
    "neighbour_tangents": (C["ring"], 2.5, {"smoothness": "neighbours' tangents"}),
    "worst_tangent": (C["centre"], 3.5, {"smoothness": "tangent setting s"}),
    "edges": (C["ellipse"], 4.0, {"smoothness": "the vertex's two edges"}),
}


def legend_entries(support: ElementSupport) -> list[tuple[str, tuple[int, int, int]]]:
    """(label, colour) of every set the overlay draws for ``support``, the picked element first."""
    out = [("picked element", PICK_COLOR)]
    for table, drawn in ((OVERLAY_COLOURS, support.points3d), (OVERLAY_LINES, support.lines3d)):
        for key, (colour, _size, labels) in table.items():
            arr = drawn.get(key)
            if arr is not None and len(arr) and support.kind in labels:
                out.append((labels[support.kind], colour))
    return out


class SupportOverlay:
    def __init__(self, view: Any) -> None:
        self.view = view
        self.names: list[str] = []
        self.support: ElementSupport | None = None
        self.legend: list[tuple[str, tuple[int, int, int]]] = []

    @property
    def plotter(self) -> Any:
        return self.view.plotter

    def clear(self) -> None:
        for name in self.names:
            self.plotter.remove_actor(name, render=False)
        had = bool(self.names) or bool(self.legend)
        if self.legend:
            self.plotter.remove_legend(render=False)
        self.names = []
        self.legend = []
        self.support = None
        if had:
            self.view.request_render()

    def show(self, support: ElementSupport | None) -> None:
        self.clear()
        self.support = support
        if support is None or support.kind not in ("slab", "knn", "smoothness"):
            return
        pts = dict(support.points3d)
        lines = dict(support.lines3d)
        for key, (colour, width, labels) in OVERLAY_LINES.items():
            arr = lines.get(key)
            if arr is None or not len(arr) or support.kind not in labels:
                continue
            self._add(f"support-{key}", _polylines(arr), colour, width, style="wireframe")
        for key, (colour, size, labels) in OVERLAY_COLOURS.items():
            arr = pts.get(key)
            if arr is None or not len(arr) or support.kind not in labels:
                continue
            self._add(f"support-{key}", pv.PolyData(display_coordinates(arr)), colour, size)
        self.legend = legend_entries(support)
        if len(self.legend) > 1:
            # top left: the colour bar and its NaN key hold the right side, the axes the bottom left
            self.plotter.add_legend(labels=[[label, colour] for label, colour in self.legend], bcolor="#ececec",
                                    border=True, size=(0.2, 0.028 * len(self.legend)), loc="upper left",
                                    face="circle")
        self.view.request_render()

    def _add(self, name: str, mesh: pv.PolyData, colour: Any, size: float, style: str = "points") -> None:
        kwargs = {"point_size": size} if style == "points" else {"line_width": size}
        actor = self.plotter.add_mesh(mesh, color=colour, style=style, lighting=False, name=name,
                                      reset_camera=False, render=False, pickable=False,
                                      render_points_as_spheres=style == "points" and size >= 12, **kwargs)
        draw_in_front(actor, -600.0)
        self.names.append(name)


def _polylines(arr: np.ndarray) -> pv.PolyData:
    """(n, 2, 3) segments, or an (n, 3) closed polyline (the ellipse), as VTK lines."""
    arr = np.asarray(arr, dtype=float)
    if arr.ndim == 3:
        n = len(arr)
        cells = np.column_stack([np.full(n, 2), 2 * np.arange(n), 2 * np.arange(n) + 1]).ravel()
        return pv.PolyData(display_coordinates(arr.reshape(-1, 3)), lines=cells)
    n = len(arr)
    cells = np.concatenate([[n + 1], np.arange(n), [0]])
    return pv.PolyData(display_coordinates(arr), lines=cells)
