"""Whether an isolated point lies off the sampled surface or in a gap of it (docs/metrics.md 6.4).

A stray point lands anywhere in the volume, and the shortest way from it to a surface runs along the
surface's normal: its nearest surface points see it straight above their tangent plane.  A surface
point left alone by the sampling (a one-sided scan's occlusions, a part sampled 10 x more sparsely)
lies in a gap of that surface: its nearest surface points see it along their tangent plane, or lie
on the rim of the gap (PCL's boundary test, :mod:`.boundary`).  Isolation alone cannot tell the two
apart (a one-sided neuron scan leaves lone points 10-30 spacings from the rest); the direction can.
A one-sided scan also keeps lone samples seen just past the silhouette of a nearer part: they lie behind
that part's visible front, on the side its surface bends towards (:func:`concave_side`), where a stray
falling outside a convex part never lies.  Where the front bends the other way (a saddle, a flat
patch), the ray from each of its nearest surface points straight away from the point tells
(:func:`behind_front`): it leaves the surface's box unstopped when that front was seen from that side,
while outside a closed part it meets the part's far wall.
A point beyond the box of the surface points is in no gap: it stays a stray whatever its direction.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..params import Params
from .boundary import largest_angle_gap, tangent_frames
from .enclosed import free_rays

__all__ = ["off_surface", "beyond_box", "concave_side", "behind_front"]


def off_surface(cloud: np.ndarray, rows: np.ndarray, surface: np.ndarray, params: Params = Params(),
                reach: float = np.inf, spacing: float = 0.0) -> np.ndarray:
    """(len(rows),) bool: the point at each row lies off the surface sampled by the rows ``surface``
    (a bool mask of the cloud): the median |cos| between its offset from its ``outlier_surface_points``
    nearest surface points and their normals (PCA of their ``open_k`` nearest surface points) exceeds
    ``outlier_off_surface_cos``, none of them is a rim point (largest angular gap between its
    neighbours above ``open_angle``) and it lies on their convex side (:func:`concave_side`, patches
    of at most ``reach``) and not behind the front they show (:func:`behind_front`, rays of the
    boundedness' radius ``rays_radius_factor`` x ``spacing``; not asked when ``spacing`` is 0); or
    it lies beyond the surface points' box (a gap lies between them; such a point sets the
    normalization).  All True when the surface has too few points to judge."""
    cloud = np.asarray(cloud, dtype=float)
    rows = np.asarray(rows, np.int64)
    base = cloud[np.asarray(surface, bool)]
    k = int(params.open_k)
    m = int(params.outlier_surface_points)
    if len(rows) == 0 or len(base) < max(k, m) + 1:
        return np.ones(len(rows), bool)
    tree = cKDTree(base)
    _, near = tree.query(cloud[rows], k=m, workers=-1)
    near = near.reshape(len(rows), m)
    uniq, inverse = np.unique(near, return_inverse=True)
    _, nb = tree.query(base[uniq], k=k + 1, workers=-1)
    frames = tangent_frames(base, nb)
    rim = largest_angle_gap(base[nb[:, 1:]] - base[uniq][:, None, :], frames) > np.radians(params.open_angle)
    inverse = inverse.reshape(near.shape)
    offset = cloud[rows][:, None, :] - base[near]
    length = np.linalg.norm(offset, axis=2)
    cos = np.abs(np.einsum("ijk,ijk->ij", offset, frames[inverse, 2])) / np.maximum(length, 1e-300)
    gap = (np.median(cos, axis=1) <= float(params.outlier_off_surface_cos)) | rim[inverse].any(axis=1)
    gap |= concave_side(cloud[rows], base, near, frames[inverse, 2], reach, tree)
    if spacing > 0 and not gap.all():
        ask = np.flatnonzero(~gap)
        gap[ask] = behind_front(cloud[rows[ask]], base, near[ask], float(params.rays_radius_factor) * spacing, tree)
    return ~(gap & ~beyond_box(cloud, rows, base))


def beyond_box(cloud: np.ndarray, rows: np.ndarray, base: np.ndarray) -> np.ndarray:
    """(len(rows),) bool: the point at each row lies outside the bounding box of the points ``base``
    (the surface's): no gap of the surface lies there, and such a point sets the normalization."""
    return ~np.all((cloud[rows] >= base.min(axis=0)) & (cloud[rows] <= base.max(axis=0)), axis=1)


def concave_side(points: np.ndarray, base: np.ndarray, near: np.ndarray, normals: np.ndarray, reach: float,
                 tree: cKDTree) -> np.ndarray:
    """(len(points),) bool: each point lies on the side its nearest surface points' patches bend
    towards, for most of them (rows of ``near`` into ``base``, with their ``normals``): the centroid of
    the surface points within the point's distance (at most ``reach``) of each lies on the point's side
    of that one's tangent plane.  A one-sided scan sees a lone sample past the silhouette of a nearer
    part, behind its visible front: on its concave side.  A stray outside a convex part lies on the
    other side; above a flat patch, either."""
    points = np.asarray(points, float)
    if len(points) == 0:
        return np.zeros(0, bool)
    at = base[near]  # (rows, m, 3)
    offset = points[:, None, :] - at
    radius = np.minimum(np.linalg.norm(offset, axis=2), float(reach))
    side = np.zeros(near.shape, bool)
    for (i, j), members in zip(np.ndindex(near.shape), tree.query_ball_point(at.reshape(-1, 3), radius.ravel())):
        bend = (base[members].mean(axis=0) - at[i, j]) @ normals[i, j]
        side[i, j] = bend * (offset[i, j] @ normals[i, j]) > 0
    return 2 * side.sum(axis=1) > near.shape[1]


def behind_front(points: np.ndarray, base: np.ndarray, near: np.ndarray, radius: float,
                 tree: cKDTree) -> np.ndarray:
    """(len(points),) bool: each point lies behind the front its nearest surface points show (rows of
    ``near`` into ``base``, ``tree`` its kd-tree), for most of them: the ray from that surface point
    straight away from the point leaves the box of ``base`` with no surface point within ``radius``
    of it more than ``radius`` past its start (:func:`.enclosed.free_rays`): the start's own patch,
    whose samples rise a fraction of a spacing into the ray (noise, a scan's depth tolerance,
    curvature), stops no ray (docs/diagnostics.md "A front's own patch").
    A scan sees a front from the open side: beyond it on that ray lies nothing, so a point on the
    other side is behind it, a sample seen past a silhouette.  Outside a closed part, the ray from its
    nearest surface points crosses the part and meets its far wall (the boundedness' rays stop there,
    docs/metrics.md 2); a front curving towards the ray by more than the radius meets it at once."""
    points = np.asarray(points, float)
    if len(points) == 0 or not radius > 0:
        return np.zeros(len(points), bool)
    start = base[near].reshape(-1, 3)
    way = start - np.repeat(points, near.shape[1], axis=0)
    way /= np.maximum(np.linalg.norm(way, axis=1, keepdims=True), 1e-300)
    free = free_rays(start, way, radius, tree, base.min(axis=0), base.max(axis=0), beyond=radius)
    return 2 * free.reshape(near.shape).sum(axis=1) > near.shape[1]
