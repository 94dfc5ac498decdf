"""The axis curve by rings (docs/skeletonize.md "Thin parts"): the moved points (:mod:`.local_axis`)
cut into bands of geodesic distance from one end of each piece (the Reeb graph of that distance on
their kNN graph); each band's connected parts are the curve's vertices, at their points' centroids,
and two vertices are joined when points of their parts are near neighbours. A band is a cross-section
wherever the distance runs along a branch, so a twig whose radius is near the spacing still gets its
own vertex every band, at the centre of its points. Given the cloud, that centre weights each point by
its depth (distance to the nearest cloud point) to the power ``AxisParams.ring_depth_power``: the
medial axis is where the depth peaks, and a band's shallow points (the wall of a part the moves have
not yet shrunk, a flat fringe) pull its plain centroid off it. The curve is the minimum spanning forest
of the joins, its nearly straight degree-2 vertices dropped. Every length is in spacings.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix, csr_matrix
from scipy.sparse.csgraph import connected_components, dijkstra, minimum_spanning_tree
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from .skeleton_params import AxisParams

__all__ = ["ring_curve", "geodesic_bands", "simplify_chains", "depth_weights"]


def _knn(points: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    d, nb = cKDTree(points).query(points, k=k + 1, workers=-1)
    return d[:, 1:], nb[:, 1:]


def _graph(n: int, d: np.ndarray, nb: np.ndarray) -> csr_matrix:
    """The symmetric kNN graph, edges weighted by length (a tiny floor keeps coincident points joined)."""
    rows = np.repeat(np.arange(n), nb.shape[1])
    g = coo_matrix((d.ravel() + 1e-12 * (1.0 + float(d.max(initial=0.0))), (rows, nb.ravel())), shape=(n, n)).tocsr()
    return g.maximum(g.T).tocsr()


def geodesic_bands(points: np.ndarray, spacing: float, params: AxisParams | None = None) -> np.ndarray:
    """The band of each point: its geodesic distance on the kNN graph (``ring_neighbors``), from the
    point farthest from its piece's first point (one end), over ``ring_width`` spacings, rounded down."""
    p_ = params or AxisParams()
    n = len(points)
    k = int(min(p_.ring_neighbors, n - 1))
    g = _graph(n, *_knn(points, k))
    n_parts, part = connected_components(g, directed=False)
    dist = np.zeros(n)
    order = np.argsort(part, kind="stable")
    starts = np.searchsorted(part[order], np.arange(n_parts + 1))
    for c in range(n_parts):
        idx = order[starts[c]:starts[c + 1]]
        if len(idx) < 2:
            continue
        d0 = dijkstra(g, indices=int(idx[0]))
        end = int(idx[np.argmax(d0[idx])])
        dist[idx] = dijkstra(g, indices=end)[idx]
    return np.floor(dist / (float(p_.ring_width) * spacing)).astype(np.int64)


def depth_weights(points: np.ndarray, cloud: np.ndarray, power: float) -> np.ndarray:
    """Each moved point's weight in its band's centre: its distance to the nearest cloud point, to
    ``power`` (docs/skeletonize.md "Thin parts": the medial axis is where that depth peaks)."""
    depth, _ = cKDTree(np.asarray(cloud, float)).query(points, k=1, workers=-1)
    return np.asarray(depth, float) ** float(power)


def _part_centres(points: np.ndarray, part: np.ndarray, n_parts: int, weights: np.ndarray | None) -> np.ndarray:
    """Each part's centroid, weighted when ``weights`` are given (a part whose weights are all 0, every
    point on the cloud, gets its plain centroid)."""
    count = np.bincount(part, minlength=n_parts).astype(float)
    plain = np.column_stack([np.bincount(part, weights=points[:, j], minlength=n_parts) for j in range(3)]) / count[:, None]
    if weights is None:
        return plain
    total = np.bincount(part, weights=weights, minlength=n_parts)
    ok = total > 0
    weighted = np.column_stack([np.bincount(part, weights=weights * points[:, j], minlength=n_parts)
                                for j in range(3)]) / np.where(ok, total, 1.0)[:, None]
    return np.where(ok[:, None], weighted, plain)


def simplify_chains(curve: CurveSkeleton, tolerance: float, longest: float) -> CurveSkeleton:
    """Degree-2 vertices within ``tolerance`` of the segment joining their neighbours dropped (that
    segment taking their two edges) when it is no longer than ``longest``; never two neighbours at once,
    a few passes. Ends and junctions stay."""
    v, e = curve.vertices, curve.edges.copy()
    for _ in range(4):
        n = len(v)
        deg = np.bincount(e.ravel(), minlength=n)
        ends, other = np.concatenate([e[:, 0], e[:, 1]]), np.concatenate([e[:, 1], e[:, 0]])
        order = np.argsort(ends, kind="stable")
        first = np.r_[0, np.cumsum(deg)[:-1]]
        inner = np.flatnonzero(deg == 2)
        nb = np.full((n, 2), -1, np.int64)
        nb[inner, 0], nb[inner, 1] = other[order[first[inner]]], other[order[first[inner] + 1]]
        a, b = v[nb[inner, 0]], v[nb[inner, 1]]
        ab = b - a
        L = np.linalg.norm(ab, axis=1)
        t = np.clip(np.einsum("ij,ij->i", v[inner] - a, ab) / np.maximum(L * L, 1e-300), 0.0, 1.0)
        dev = np.linalg.norm(v[inner] - (a + t[:, None] * ab), axis=1)
        cand = inner[(dev <= tolerance) & (L <= longest) & (nb[inner, 0] != nb[inner, 1])]
        gone = np.zeros(n, bool)
        for x in cand.tolist():
            if not gone[nb[x, 0]] and not gone[nb[x, 1]]:
                gone[x] = True
        if not gone.any():
            break
        e = np.vstack([e[~gone[e].any(axis=1)], nb[gone]])
    used = np.unique(e)
    remap = np.full(len(v), -1, np.int64)
    remap[used] = np.arange(len(used))
    return CurveSkeleton.from_raw(v[used], remap[e])


def ring_curve(points: np.ndarray, spacing: float, params: AxisParams | None = None,
               cloud: np.ndarray | None = None) -> CurveSkeleton:
    """The curve of the moved points by rings (module docstring); with the ``cloud`` they were moved
    from, each band part's vertex is its points' depth-weighted centroid (:func:`depth_weights`), else
    (or with ``ring_depth_power`` 0) their plain centroid."""
    p_ = params or AxisParams()
    pts = np.asarray(points, float)
    n = len(pts)
    if n < 2:
        return CurveSkeleton.from_raw(pts.copy(), np.zeros((0, 2), np.int64))
    band = geodesic_bands(pts, spacing, p_)
    d, nb = _knn(pts, int(min(p_.ring_connect, n - 1)))
    rows = np.repeat(np.arange(n), nb.shape[1])
    cols = nb.ravel()
    same = band[rows] == band[cols]
    g = coo_matrix((np.ones(int(same.sum())), (rows[same], cols[same])), shape=(n, n))
    n_parts, part = connected_components(g, directed=False)
    power = float(p_.ring_depth_power)
    weights = None if cloud is None or power == 0 else depth_weights(pts, cloud, power)
    verts = _part_centres(pts, part, n_parts, weights)
    pairs = np.sort(np.column_stack([part[rows[~same]], part[cols[~same]]]), axis=1)
    pairs = np.unique(pairs[pairs[:, 0] != pairs[:, 1]], axis=0)
    if len(pairs) == 0:
        return CurveSkeleton.from_raw(verts, np.zeros((0, 2), np.int64))
    length = np.linalg.norm(verts[pairs[:, 0]] - verts[pairs[:, 1]], axis=1) + 1e-12 * spacing
    tree = minimum_spanning_tree(coo_matrix((length, (pairs[:, 0], pairs[:, 1])), shape=(n_parts, n_parts)).tocsr()).tocoo()
    curve = CurveSkeleton.from_raw(verts, np.column_stack([tree.row, tree.col]).astype(np.int64))
    return simplify_chains(curve, float(p_.simplify_spacings) * spacing, float(p_.simplify_longest) * spacing)
