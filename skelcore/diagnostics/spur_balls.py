"""Which curve balls may explain cloud points in the spur test: the balls of the shape.

The explanation measure reads the rest of the skeleton's balls (radius r(x), the distance from x to
the cloud) as a reconstruction of the shape. A curve point through the air (an edge that leaves the
shape) has a ball as large as its distance to the nearest part, often tens of local radii, whose
grown shell sweeps over every twig around it: those twigs would be "explained" by air. A ball is
of the shape when the voxelized solid (:mod:`.interior`, the cycle test's) holds its centre and the
26 lattice directions at r(x) less one voxel; a ball under one voxel is below what the grid can
judge and is kept (docs/diagnostics.md "Spurious branches", rule 2).
"""

from __future__ import annotations

import numpy as np

from .interior import LATTICE_DIRECTIONS, VoxelShape

__all__ = ["balls_in_shape"]

_DIRECTIONS = LATTICE_DIRECTIONS / np.linalg.norm(LATTICE_DIRECTIONS, axis=1, keepdims=True)
_CHUNK = 1 << 15  # balls probed at once


def balls_in_shape(voxel_shape: VoxelShape, pts: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """(n,) bool: the ball of ``radius`` at each of ``pts`` lies in the shape's solid (module
    docstring); True for balls under one voxel. A function of the point and the cloud alone."""
    pts = np.asarray(pts, float)
    radius = np.asarray(radius, float)
    size = float(voxel_shape.size)
    keep = ~(radius > size)
    big = np.flatnonzero(~keep)
    if not len(big):
        return keep
    solid = voxel_shape.solid()
    rays = np.vstack([np.zeros((1, 3)), _DIRECTIONS])
    for a in range(0, len(big), _CHUNK):  # bounded memory: 27 probes per ball
        part = big[a:a + _CHUNK]
        probes = pts[part, None, :] + (radius[part] - size)[:, None, None] * rays
        ijk = voxel_shape.index_of(probes.reshape(-1, 3))
        keep[part] = solid[ijk[:, 0], ijk[:, 1], ijk[:, 2]].reshape(len(part), -1).all(axis=1)
    return keep
