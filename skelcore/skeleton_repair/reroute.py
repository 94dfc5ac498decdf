"""A new route through the shape between two curve vertices (docs/repair.md "Rerouting"): the
cheapest path between inside voxels of the diagnostics' interior, each step's cost its length over
the voxel's depth (so the path keeps to the middle), kept away from the rest of the curve (a voxel
within the local radius of another part of the curve is closed, but for the balls around both ends),
thinned to about the curve's edge length. Used when an edge outside the shape cannot just go."""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton

__all__ = ["route_inside"]

_OFFSETS = np.array([(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)
                     if (i, j, k) > (0, 0, 0)])


def _curve_points(curve: CurveSkeleton, skip: int, step: float) -> np.ndarray:
    pts = [curve.vertices[np.bincount(curve.edges.ravel(), minlength=curve.n_vertices) > 0]]
    for k, (a, b) in enumerate(curve.edges):
        if k == skip:
            continue
        m = int(np.ceil(np.linalg.norm(curve.vertices[b] - curve.vertices[a]) / step))
        if m > 1:
            t = np.linspace(0, 1, m + 1)[1:-1, None]
            pts.append(curve.vertices[a] + t * (curve.vertices[b] - curve.vertices[a]))
    return np.vstack(pts)


def route_inside(curve: CurveSkeleton, edge: int, vs: Any, norm: Any) -> np.ndarray | None:
    """Inner points (user units, ends excluded) of a route through the shape from the lower to the
    higher vertex of ``edge``, avoiding the rest of the curve; None when there is none."""
    solid = vs.solid()
    if not solid.any():
        return None
    depth = ndimage.distance_transform_edt(solid)
    ids = np.full(solid.shape, -1, np.int64)
    where = np.argwhere(solid)
    ids[tuple(where.T)] = np.arange(len(where))
    centres = vs.origin + where * vs.size
    a, b = (int(v) for v in curve.edges[edge])
    ends = norm.apply(curve.vertices[[a, b]])
    tree = cKDTree(centres)
    ia, ib = (int(i) for i in tree.query(ends)[1])
    # closed: voxels within the local radius of another part of the curve, outside both end balls
    cp = _curve_points(curve, edge, 0.5 * vs.size / float(norm.scale))
    cpn = norm.apply(cp)
    cp_depth = depth[tuple(vs.index_of(cpn).T)] * vs.size
    dist, near = cKDTree(cpn).query(centres)
    closed = dist < np.maximum(cp_depth[near], vs.size)
    for i in (ia, ib):
        r = max(1.5 * depth[tuple(where[i])] * vs.size, 2 * vs.size)
        closed &= np.linalg.norm(centres - centres[i], axis=1) > r
    rows, cols, w = [], [], []
    dv = depth[tuple(where.T)]
    for off in _OFFSETS:
        nb = where + off
        ok = np.all((nb >= 0) & (nb < solid.shape), axis=1)
        j = np.full(len(where), -1, np.int64)
        j[ok] = ids[tuple(nb[ok].T)]
        ok = (j >= 0) & ~closed
        ok[ok] &= ~closed[j[ok]]
        src = np.flatnonzero(ok)
        rows.append(src)
        cols.append(j[src])
        w.append(np.linalg.norm(off) / (0.5 * (dv[src] + dv[j[src]])) ** 2)
    n = len(where)
    g = coo_matrix((np.concatenate(w), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)).tocsr()
    dist_a, pred = dijkstra(g, directed=False, indices=ia, return_predecessors=True)
    if not np.isfinite(dist_a[ib]) or ia == ib:
        return None
    path = [ib]
    while path[-1] != ia:
        path.append(int(pred[path[-1]]))
    pts = norm.invert(centres[path[::-1]])
    e = curve.edges
    spacing = float(np.median(np.linalg.norm(curve.vertices[e[:, 0]] - curve.vertices[e[:, 1]], axis=1)))
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    m = max(1, int(round(arc[-1] / max(spacing, 1e-12))))
    if m < 2:
        return None
    keep = np.searchsorted(arc, np.linspace(0, arc[-1], m + 1)[1:-1])
    return pts[np.unique(keep)]
