"""Helpers for building the view's pyvista actors: coordinates for the GPU, depth offsets, sizes.

Stateless functions the scene view calls when it (re)builds an actor; kept apart so the view
class reads as scene -> actors and the VTK details live here.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..scene import Scene

__all__ = ["display_coordinates", "draw_in_front", "scene_diagonal", "line_cells", "curve_polylines"]


def display_coordinates(points: np.ndarray) -> np.ndarray:
    """float32 for the GPU (a 1M-point cloud draws several times faster than from doubles) unless
    the coordinates are so far from the origin that float32 would visibly round them."""
    pts = np.asarray(points)
    if pts.size and float(np.abs(pts).max()) < 1e5:
        return np.ascontiguousarray(pts, dtype=np.float32)
    return np.ascontiguousarray(pts, dtype=np.float64)


def draw_in_front(actor: Any, offset: float = -200.0) -> None:
    """The curve skeleton usually lies exactly on the skeletal points (both on the medial axis):
    a depth offset draws it in front of coincident points instead of a random z-fight."""
    from vtkmodules.vtkRenderingCore import vtkMapper  # one module: `import vtk` loads all of VTK (seconds)

    vtkMapper.SetResolveCoincidentTopologyToPolygonOffset()
    mapper = actor.GetMapper()
    mapper.SetRelativeCoincidentTopologyPointOffsetParameter(offset)
    mapper.SetRelativeCoincidentTopologyLineOffsetParameters(0.0, offset)
    mapper.SetRelativeCoincidentTopologyPolygonOffsetParameters(0.0, offset)


def scene_diagonal(scene: Scene) -> float:
    """The bounding-box diagonal of the first non-degenerate layer (cloud, then curve, then
    skeletal), 1.0 if none: the length the tube radius scales with."""
    for name in ("cloud", "curve", "skeletal"):
        layer = scene.layers.get(name)
        if layer is not None and len(layer.points):
            d = float(np.linalg.norm(layer.points.max(axis=0) - layer.points.min(axis=0)))
            if d > 0:
                return d
    return 1.0


def line_cells(edges: np.ndarray) -> np.ndarray:
    """VTK line cells (2, a, b per edge) of an (E, 2) edge array."""
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    return np.hstack([np.full((len(edges), 1), 2, dtype=np.int64), edges]).ravel()


def curve_polylines(vertices: np.ndarray, edges: np.ndarray, values: np.ndarray, location: str,
                    samples: np.ndarray | None = None, sample_edge: np.ndarray | None = None,
                    sample_t: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The curve as polylines carrying a metric, for tubes coloured by it: (points, VTK line cells,
    values per point).

    Per-vertex values (smoothness, docs/metrics.md 4): one line per edge between its two vertices. Per-sample
    values (boundedness, centeredness, docs/metrics.md 3): each edge becomes a polyline from its first vertex
    through its samples (in order of t) to its second vertex; a vertex takes the value of the sample
    nearest to it, so the colour along an edge is the samples' colour.
    """
    verts = np.asarray(vertices, dtype=float)
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    values = np.asarray(values, dtype=float)
    n_edges = len(edges)
    if location == "vertices" or samples is None or not len(samples):
        cells = line_cells(edges)
        vals = values if location == "vertices" else np.full(len(verts), np.nan)
        return verts, cells, vals
    from scipy.spatial import cKDTree

    samples = np.asarray(samples, dtype=float)
    se = np.asarray(sample_edge, dtype=np.int64)
    order = np.lexsort((np.asarray(sample_t, dtype=float), se))
    se_sorted = se[order]
    per_edge = np.bincount(se_sorted, minlength=n_edges)
    n_pts = per_edge + 2
    start = np.cumsum(n_pts) - n_pts  # where each edge's polyline starts in the point array
    total = int(n_pts.sum())
    pts = np.empty((total, 3))
    vals = np.empty(total)
    vertex_value = values[cKDTree(samples).query(verts)[1]]
    pts[start] = verts[edges[:, 0]]
    vals[start] = vertex_value[edges[:, 0]]
    pts[start + n_pts - 1] = verts[edges[:, 1]]
    vals[start + n_pts - 1] = vertex_value[edges[:, 1]]
    first = np.cumsum(per_edge) - per_edge  # each edge's first sample in the sorted order
    rank = np.arange(len(se_sorted)) - first[se_sorted]
    slot = start[se_sorted] + 1 + rank
    pts[slot] = samples[order]
    vals[slot] = values[order]
    cells = np.empty(n_edges + total, dtype=np.int64)
    header = start + np.arange(n_edges)
    cells[header] = n_pts
    mask = np.ones(len(cells), dtype=bool)
    mask[header] = False
    cells[mask] = np.arange(total)
    return pts, cells, vals
