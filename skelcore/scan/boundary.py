"""The cloud's boundary points: where a closed surface was not sampled (docs/metrics.md 6.1).

A point inside a sampled surface has neighbours all around it in its tangent plane; a point on the rim
of an opening has them on one side only (its neighbourhood is a half disc).  As PCL's
``pcl::BoundaryEstimation``: the tangent plane from the PCA of the k nearest neighbours, the
neighbours' directions projected into it, and the point is on the boundary when the largest angle
between two consecutive directions exceeds ``open_angle`` (PCL's default pi / 2).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..geometry import Checkpoint, no_checkpoint

__all__ = ["boundary_mask", "largest_angle_gap", "tangent_frames"]

#: points per batch of the vectorised tests (about 10 MB of temporaries at k = 30)
CHUNK = 32768


def tangent_frames(cloud: np.ndarray, neighbours: np.ndarray) -> np.ndarray:
    """(N, 3, 3) orthonormal frames per point: rows u, v span the tangent plane of the PCA of the
    point's neighbours (rows of ``neighbours``), row 3 is the normal (smallest eigenvalue)."""
    nb = cloud[neighbours]
    centred = nb - nb.mean(axis=1, keepdims=True)
    cov = np.matmul(centred.transpose(0, 2, 1), centred)  # batched 3 x k @ k x 3 (einsum: 5 x slower)
    _, vecs = np.linalg.eigh(cov)  # ascending eigenvalues: column 0 is the normal
    return np.stack([vecs[:, :, 2], vecs[:, :, 1], vecs[:, :, 0]], axis=1)


def largest_angle_gap(vectors: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """Largest angle between consecutive directions of ``vectors`` (N, k, 3) projected into the
    tangent planes of ``frames`` (N, 3, 3), wrapping round; 2 pi when fewer than two are left."""
    x = np.einsum("nki,ni->nk", vectors, frames[:, 0])
    y = np.einsum("nki,ni->nk", vectors, frames[:, 1])
    angle = np.arctan2(y, x)
    flat = (x == 0) & (y == 0)
    angle[flat] = np.nan  # a neighbour at the point itself has no direction
    angle = np.sort(angle, axis=1)  # NaN last
    n_ok = np.count_nonzero(~flat, axis=1)
    gaps = np.diff(angle, axis=1)
    gaps = np.where(np.isnan(gaps), -np.inf, gaps)
    first = angle[:, 0]
    last = np.take_along_axis(angle, np.maximum(n_ok - 1, 0)[:, None], axis=1)[:, 0]
    wrap = first + 2 * np.pi - last
    out = np.maximum(gaps.max(axis=1, initial=-np.inf), wrap)
    out[n_ok < 2] = 2 * np.pi
    return out


def boundary_mask(
    cloud: np.ndarray,
    *,
    k: int = 30,
    angle: float = np.pi / 2,
    tree: cKDTree | None = None,
    spacing_out: np.ndarray | None = None,
    reach_out: np.ndarray | None = None,
    checkpoint: Checkpoint = no_checkpoint,
) -> np.ndarray:
    """True for the points on the cloud's boundary (PCL's angle criterion, see the module docstring).

    Parameters
    ----------
    cloud : (N, 3) points, any units.
    k : neighbours per point (itself excluded); PCL users pass a radius, we keep the count fixed so
        that uneven density does not change the test.  With k = 30 a random interior neighbourhood has
        a gap above pi / 2 with probability about 29 (3/4)^28 = 0.001.
    angle : the largest gap (radians) that an interior point may have.
    spacing_out : an (N,) array that receives each point's distance to its nearest other point.
    reach_out : an (N,) array that receives each point's distance to its k-th nearest other point.

    Examples
    --------
    >>> from skelcore.shapes import cylinder
    >>> open_tube = cylinder(4000, capped=False).cloud
    >>> rim = boundary_mask(open_tube)
    >>> bool(rim.any()), bool(open_tube[rim, 2].min() < 0.2 or open_tube[rim, 2].max() > 3.8)
    (True, True)
    """
    cloud = np.asarray(cloud, dtype=float)
    n = len(cloud)
    k = int(min(k, n - 1))
    if k < 3:
        return np.zeros(n, bool)
    tree = cKDTree(cloud) if tree is None else tree
    out = np.zeros(n, bool)
    for i0 in range(0, n, CHUNK):
        i1 = min(n, i0 + CHUNK)
        dist, idx = tree.query(cloud[i0:i1], k=k + 1, workers=-1)
        if spacing_out is not None:
            spacing_out[i0:i1] = dist[:, 1]
        if reach_out is not None:
            reach_out[i0:i1] = dist[:, k]
        nb = idx[:, 1:]
        frames = tangent_frames(cloud, idx)
        out[i0:i1] = largest_angle_gap(cloud[nb] - cloud[i0:i1, None, :], frames) > angle
        checkpoint(i1 / n)
    return out
