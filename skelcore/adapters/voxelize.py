"""A surface cloud as a solid binary volume, for the voxel skeletonizers (kimimaro, scikit-image).

Voxel ``i`` (an integer triple) is the cube of side ``size`` centred on ``origin + i * size``, so a
voxel index maps back to the cloud's frame by ``index * size + origin`` (no half-voxel shift: the
origin is the centre of voxel (0, 0, 0), not its corner). The voxels holding a point are the shell;
it is dilated ``closing`` voxels (6-neighbourhood) to close the gaps of a random sampling, its
interior filled (``scipy.ndimage.binary_fill_holes``) and eroded back. A shell the fill cannot
close, or a given voxel size whose grid is above ``max_voxels``, is a one-line ``SkelInputError``
naming the parameter. Default voxel size: 2 x the median nearest-neighbour distance of the cloud,
which with ``closing = 2`` closed every generated shape we tried (docs/skeletonizers.md), or, when
that grid is above ``max_voxels``, the smallest size whose grid fits (:func:`fitting_voxel_size`);
``VoxelGrid.source`` says which.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from ..errors import SkelInputError
from .adapter_params import Param

__all__ = ["VoxelGrid", "default_voxel_size", "fitting_voxel_size", "grid_shape", "voxelize_solid",
           "VOXEL_SIZE_FACTOR", "VOXEL_PARAMS"]

#: the default voxel size in median nearest-neighbour distances of the cloud
VOXEL_SIZE_FACTOR = 2.0


@dataclass(frozen=True)
class VoxelGrid:
    """``solid[i, j, k]``: voxel (i, j, k) is inside; its centre is ``origin + (i, j, k) * size``."""

    solid: np.ndarray
    origin: np.ndarray
    size: float
    source: str = "given"  # "given", "spacing" (the default) or "max_voxels" (the default was too fine)

    def info(self) -> dict[str, Any]:
        """What an adapter reports: the voxel size, where it came from, the grid and its solid voxels."""
        return {"voxel_size": float(self.size), "voxel_size_source": self.source,
                "grid": [int(n) for n in self.solid.shape], "voxels": int(self.solid.sum())}

    def to_cloud_frame(self, index: np.ndarray) -> np.ndarray:
        """Voxel indices (integer or fractional, N x 3) as points of the cloud's frame."""
        return np.asarray(index, dtype=float) * self.size + self.origin

    def index_of(self, points: np.ndarray) -> np.ndarray:
        """The voxel holding each point (N x 3 int64)."""
        return np.floor((np.asarray(points, dtype=float) - self.origin) / self.size + 0.5).astype(np.int64)


def default_voxel_size(points: np.ndarray) -> float:
    """``VOXEL_SIZE_FACTOR`` x the median distance from a point to its nearest other point."""
    d = cKDTree(points).query(points, k=2, workers=-1)[0][:, 1]
    d = d[np.isfinite(d) & (d > 0)]
    if len(d) == 0:
        raise SkelInputError("cannot derive a voxel size: every point of the cloud coincides (give voxel_size)")
    return VOXEL_SIZE_FACTOR * float(np.median(d))


def _origin(lo: np.ndarray, size: float, closing: int) -> np.ndarray:
    return np.asarray(lo, dtype=float) - (closing + 2) * size  # room for the dilation and a background border


def grid_shape(lo: np.ndarray, hi: np.ndarray, size: float, closing: int) -> np.ndarray:
    """The grid :func:`voxelize_solid` makes for a cloud whose bounding box runs from ``lo`` to ``hi``."""
    index = np.floor((np.asarray(hi, dtype=float) - _origin(lo, size, closing)) / size + 0.5).astype(np.int64)
    return index + closing + 3  # the last point's voxel, the border beyond it and one for the count


def _voxel_count(box: tuple[np.ndarray, np.ndarray], size: float, closing: int) -> float:
    return float(np.prod(grid_shape(*box, size, closing).astype(np.float64)))


def fitting_voxel_size(lo: np.ndarray, hi: np.ndarray, size: float, closing: int, max_voxels: int) -> float:
    """The smallest voxel size >= ``size`` whose grid (:func:`grid_shape`) has at most ``max_voxels``
    voxels (``size`` itself when it fits; bisection to float precision otherwise)."""
    box = (lo, hi)
    if _voxel_count(box, size, closing) <= max_voxels:
        return float(size)
    floor = (2 * closing + 5) ** 3  # the grid of a shape much smaller than one voxel
    if floor > max_voxels:
        raise SkelInputError(f"max_voxels {max_voxels:,} is below the smallest grid with closing {closing} "
                             f"({floor:,} voxels): raise max_voxels")
    lo_size, hi_size = float(size), float(size)
    while _voxel_count(box, hi_size, closing) > max_voxels:
        lo_size, hi_size = hi_size, hi_size * 2
    for _ in range(200):  # lo_size does not fit, hi_size does
        mid = 0.5 * (lo_size + hi_size)
        if not lo_size < mid < hi_size:
            break
        lo_size, hi_size = (lo_size, mid) if _voxel_count(box, mid, closing) <= max_voxels else (mid, hi_size)
    return hi_size


def voxelize_solid(points: np.ndarray, size: float | None = None, *, closing: int = 2,
                   max_voxels: int = 50_000_000) -> VoxelGrid:
    """The solid the surface cloud ``points`` bounds, at voxel side ``size``; None: the spacing
    default, raised to the smallest size whose grid fits ``max_voxels`` (a given size never is)."""
    pts = np.asarray(points, dtype=float)
    if len(pts) < 4:
        raise SkelInputError(f"a voxel skeleton needs at least 4 points, got {len(pts)}")
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    if size is None:
        h0 = default_voxel_size(pts)
        h = fitting_voxel_size(lo, hi, h0, closing, max_voxels)
        source = "spacing" if h == h0 else "max_voxels"
    else:
        h, source = float(size), "given"
    origin = _origin(lo, h, closing)
    shape = grid_shape(lo, hi, h, closing)
    total = int(np.prod(shape.astype(np.float64)))
    if total > max_voxels:
        raise SkelInputError(f"voxel_size {h:.4g} gives a {shape[0]} x {shape[1]} x {shape[2]} grid "
                             f"({total:,} voxels > max_voxels {max_voxels:,}): give a larger voxel_size")
    grid = VoxelGrid(np.zeros(tuple(int(s) for s in shape), dtype=bool), origin, h, source)
    idx = grid.index_of(pts)
    shell = grid.solid
    shell[idx[:, 0], idx[:, 1], idx[:, 2]] = True
    cross = ndimage.generate_binary_structure(3, 1)
    grown = ndimage.binary_dilation(shell, cross, iterations=closing) if closing else shell
    filled = ndimage.binary_fill_holes(grown)
    if closing:
        filled = ndimage.binary_erosion(filled, cross, iterations=closing, border_value=0)
    inside = filled & ~ndimage.binary_dilation(shell, cross, iterations=closing) if closing else filled & ~shell
    if not inside.any():
        raise SkelInputError(f"the cloud's voxel shell does not close at voxel_size {h:.4g} with closing "
                             f"{closing}: nothing inside to skeletonize (raise closing or voxel_size)")
    return VoxelGrid(filled | shell, origin, h, source)


#: the parameters of every voxel adapter (kimimaro, skimage)
VOXEL_PARAMS = (
    Param("voxel_size", "float", None, "voxel side in the cloud's units (absent: 2 x the median "
          "nearest-neighbour distance)", minimum=0.0, positive=True, optional=True),
    Param("closing", "int", 2, "voxels the shell is grown by to close sampling gaps before the fill", minimum=0),
    Param("max_voxels", "int", 50_000_000, "largest grid (memory): without voxel_size, the smallest size "
          "that fits is chosen; a given voxel_size whose grid is larger is refused", minimum=1),
)
