"""The axis a one-sided scan was seen along, read from the cloud alone (docs/metrics.md 6.4).

A scanner keeps what is first along each line of sight: seen along its own axis, a one-sided scan's
depth image keeps most of it (share ``outlier_view_share`` and more; 0.69-0.88 on the one-sided tuning
neurons and synthetic shapes, the rest lost on oblique parts wider than the depth tolerance), while a
cloud sampled all round keeps about its front half (0.39-0.61) along any axis.  Depth images along ``VIEW_DIRECTIONS`` directions of a sample of the
cloud, pixels ``VIEW_PIXEL`` spacings wide, a point kept within ``VIEW_DEPTH`` spacings of its pixel's
front.  The sign of the axis is left open: its two ends keep nearly the same share.  A lone point lying
along that axis from its nearest surface points (:func:`along_axis`) lies in their shadow or before
them: where a scan sees a sample past a nearer part's silhouette, its neighbours hidden by that part.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..params import Params

__all__ = ["view_axis", "along_axis"]

#: directions tried (a Fibonacci sphere: about 12 degrees apart), cloud points sampled for the images,
#: pixel width and depth tolerance in the sample's median spacings
VIEW_DIRECTIONS = 300
VIEW_SAMPLE = 30_000
VIEW_PIXEL = 2.5
VIEW_DEPTH = 2.0


def _directions(n: int) -> np.ndarray:
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    r = np.sqrt(1.0 - z * z)
    a = np.pi * (1.0 + 5.0**0.5) * i
    return np.c_[r * np.cos(a), r * np.sin(a), z]


def _kept_share(points: np.ndarray, d: np.ndarray, pixel: float, depth_tol: float) -> float:
    """The share of ``points`` within ``depth_tol`` of the front of their pixel of the image along ``d``."""
    u = np.cross(d, [0.3, 0.5, 0.8])
    u /= np.linalg.norm(u)
    w = np.cross(d, u)
    ij = np.floor(np.c_[points @ u, points @ w] / pixel).astype(np.int64)
    ij -= ij.min(axis=0)
    key = ij[:, 0] * (int(ij[:, 1].max()) + 1) + ij[:, 1]
    depth = points @ d
    front = np.full(int(key.max()) + 1, -np.inf)
    np.maximum.at(front, key, depth)
    return float(np.mean(depth >= front[key] - depth_tol))


def view_axis(cloud: np.ndarray, params: Params = Params()) -> np.ndarray | None:
    """The unit axis whose depth image keeps the largest share of ``cloud`` when that share reaches
    ``params.outlier_view_share`` (a one-sided scan, module docstring), else None."""
    cloud = np.asarray(cloud, float)
    if len(cloud) < 4:
        return None
    sample = cloud if len(cloud) <= VIEW_SAMPLE else cloud[
        np.random.default_rng(0).choice(len(cloud), VIEW_SAMPLE, replace=False)]
    spacing = float(np.median(cKDTree(sample).query(sample, k=2)[0][:, 1]))
    if not spacing > 0:
        return None
    dirs = _directions(VIEW_DIRECTIONS)
    shares = np.array([_kept_share(sample, d, VIEW_PIXEL * spacing, VIEW_DEPTH * spacing) for d in dirs])
    best = int(np.argmax(shares))
    return dirs[best] if shares[best] >= float(params.outlier_view_share) else None


def along_axis(points: np.ndarray, base: np.ndarray, near: np.ndarray, axis: np.ndarray,
               params: Params = Params()) -> np.ndarray:
    """(len(points),) bool: for most of each point's nearest surface points (rows of ``near`` into
    ``base``) the offset to it makes ``|cos|`` above ``params.outlier_view_cos`` with ``axis``."""
    points = np.asarray(points, float)
    if len(points) == 0:
        return np.zeros(0, bool)
    offset = base[near] - points[:, None, :]
    cos = np.abs(offset @ np.asarray(axis, float)) / np.maximum(np.linalg.norm(offset, axis=2), 1e-300)
    return 2 * (cos > float(params.outlier_view_cos)).sum(axis=1) > near.shape[1]
