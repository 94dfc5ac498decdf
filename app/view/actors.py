"""Helpers for building the view's pyvista actors: coordinates for the GPU, depth offsets, sizes.

Stateless functions the scene view calls when it (re)builds an actor; kept apart so the view
class reads as scene -> actors and the VTK details live here.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..scene import Scene

__all__ = ["display_coordinates", "draw_in_front", "scene_diagonal"]


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
    import vtk

    vtk.vtkMapper.SetResolveCoincidentTopologyToPolygonOffset()
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
