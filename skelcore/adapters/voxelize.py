"""A surface cloud as a solid binary volume, for the voxel skeletonizers (kimimaro, scikit-image).

Voxel ``i`` (an integer triple) is the cube of side ``size`` centred on ``origin + i * size``, so a
voxel index maps back to the cloud's frame by ``index * size + origin`` (no half-voxel shift: the
origin is the centre of voxel (0, 0, 0), not its corner). The voxels holding a point are the shell;
it is dilated ``closing`` voxels (6-neighbourhood) to close the gaps of a random sampling, its
interior filled (``scipy.ndimage.binary_fill_holes``) and eroded back. A shell the fill cannot
close, or a grid above ``max_voxels``, is a one-line ``SkelInputError`` naming the parameter.
Default voxel size: 2 x the median nearest-neighbour distance of the cloud, which with
``closing = 2`` closed every generated shape we tried (docs/skeletonizers.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from ..errors import SkelInputError
from .adapter_params import Param

__all__ = ["VoxelGrid", "default_voxel_size", "voxelize_solid", "VOXEL_SIZE_FACTOR", "VOXEL_PARAMS"]

#: the default voxel size in median nearest-neighbour distances of the cloud
VOXEL_SIZE_FACTOR = 2.0


@dataclass(frozen=True)
class VoxelGrid:
    """``solid[i, j, k]``: voxel (i, j, k) is inside; its centre is ``origin + (i, j, k) * size``."""

    solid: np.ndarray
    origin: np.ndarray
    size: float

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


def voxelize_solid(points: np.ndarray, size: float | None = None, *, closing: int = 2,
                   max_voxels: int = 50_000_000) -> VoxelGrid:
    """The solid the surface cloud ``points`` bounds, at voxel side ``size`` (None: derived)."""
    pts = np.asarray(points, dtype=float)
    if len(pts) < 4:
        raise SkelInputError(f"a voxel skeleton needs at least 4 points, got {len(pts)}")
    h = default_voxel_size(pts) if size is None else float(size)
    pad = closing + 2  # room for the dilation and a border of background around the shape
    origin = pts.min(axis=0) - pad * h
    shape = np.floor((pts.max(axis=0) - origin) / h + 0.5).astype(np.int64) + pad + 1
    total = int(np.prod(shape.astype(np.float64)))
    if total > max_voxels:
        raise SkelInputError(f"voxel_size {h:.4g} gives a {shape[0]} x {shape[1]} x {shape[2]} grid "
                             f"({total:,} voxels > max_voxels {max_voxels:,}): give a larger voxel_size")
    grid = VoxelGrid(np.zeros(tuple(int(s) for s in shape), dtype=bool), origin, h)
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
    return VoxelGrid(filled | shell, origin, h)


#: the parameters of every voxel adapter (kimimaro, skimage)
VOXEL_PARAMS = (
    Param("voxel_size", "float", None, "voxel side in the cloud's units (absent: 2 x the median "
          "nearest-neighbour distance)", minimum=0.0, positive=True, optional=True),
    Param("closing", "int", 2, "voxels the shell is grown by to close sampling gaps before the fill", minimum=0),
    Param("max_voxels", "int", 50_000_000, "refuse a larger grid (memory)", minimum=1),
)
