"""The toolbox's point one-rings (``compute_point_point_ring``): kNN, then a local 2-D Delaunay fan.

Each point's k nearest neighbours (itself first) are projected on their two principal axes; the
point's one-ring is its star in the Delaunay triangulation of that projection, walked as a fan. A
point inside its neighbourhood gets a closed ring (first vertex repeated at the end), one on its
boundary an open ring from the lower-ranked of its two hull neighbours. The star is found without
triangulating: after inversion about the point, its Delaunay neighbours are the vertices of the
convex hull of the inverted neighbours plus the origin (the origin itself on the hull = open ring),
hull order = fan order. All points at once, vectorized (Jarvis march over the (N, k) block).
See docs/skeletonize.md for where this departs from Qhull's triangle order.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["knn_count", "point_rings"]


def knn_count(n: int, min_k: int = 8, max_k: int = 30, fraction: float = 0.012) -> int:
    """``GS.compute_k_knn``: round(0.012 N) neighbours, clamped to [8, 30] (and to N)."""
    k = max(int(min_k), int(np.floor(n * fraction + 0.5)))  # MATLAB round: half away from zero
    return int(min(k, int(max_k), n))


def _neighbours(points: np.ndarray, k: int) -> np.ndarray:
    """(N, k) kNN indices, each row starting with the point itself (duplicates could push it back)."""
    _d, idx = cKDTree(points).query(points, k=k, workers=-1)
    idx = np.asarray(idx, np.int64).reshape(len(points), k)
    rows = np.arange(len(points))
    not_first = idx[:, 0] != rows
    if np.any(not_first):
        for i in np.flatnonzero(not_first):
            r = [int(i)] + [int(j) for j in idx[i] if j != i]
            idx[i] = r[:k]
    return idx


def _project(points: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Neighbourhoods on their two principal axes, relative to the point: (N, k, 2).

    Axes signed as MATLAB's ``pca`` signs its coefficients (largest-magnitude component positive).
    """
    nb = points[idx]  # (N, k, 3)
    centred = nb - nb.mean(axis=1, keepdims=True)
    cov = np.einsum("nki,nkj->nij", centred, centred)
    _w, vec = np.linalg.eigh(cov)  # ascending: the last two columns are the principal plane
    axes = vec[:, :, [2, 1]]
    big = np.argmax(np.abs(axes), axis=1)  # (N, 2)
    sign = np.sign(np.take_along_axis(axes, big[:, None, :], axis=1))
    axes = axes * np.where(sign == 0, 1.0, sign)
    rel = nb - nb[:, :1, :]
    return np.einsum("nki,nij->nkj", rel, axes)


def _hull_order(z: np.ndarray, valid: np.ndarray) -> list[np.ndarray]:
    """Counter-clockwise convex-hull vertices of each row's valid points of ``z`` (N, m, 2).

    Jarvis march for all rows at once; on collinear candidates the farthest is taken (a point in the
    middle of a hull side is not a vertex). Returns one index array per row.
    """
    n, m, _ = z.shape
    r2 = np.where(valid, np.einsum("nmk,nmk->nm", z, z), -1.0)
    start = np.argmax(r2, axis=1)
    rows = np.arange(n)
    cur = start.copy()
    # the farthest point is extreme along its own direction: the support line there is perpendicular
    d = z[rows, start]
    d = np.stack([-d[:, 1], d[:, 0]], axis=1)
    hull = np.full((n, m + 1), -1, np.int64)
    hull[:, 0] = start
    count = np.ones(n, np.int64)
    active = valid.sum(axis=1) >= 2
    for _step in range(m + 1):
        if not active.any():
            break
        a = np.flatnonzero(active)
        v = z[a] - z[a, cur[a]][:, None, :]  # (na, m, 2)
        dd = d[a][:, None, :]
        cross = dd[..., 0] * v[..., 1] - dd[..., 1] * v[..., 0]
        dot = dd[..., 0] * v[..., 0] + dd[..., 1] * v[..., 1]
        ang = np.arctan2(cross, dot)
        ang = np.where(ang < -1e-12, ang + 2 * np.pi, np.maximum(ang, 0.0))
        dist2 = np.einsum("nmk,nmk->nm", v, v)
        ok = valid[a] & (dist2 > 0)
        ang = np.where(ok, ang, np.inf)
        best = ang.min(axis=1, keepdims=True)
        tie = ok & (ang <= best + 1e-12)
        nxt = np.argmax(np.where(tie, dist2, -1.0), axis=1)
        d[a] = z[a, nxt] - z[a, cur[a]]
        cur[a] = nxt
        done = (nxt == start[a]) | (count[a] > m)
        go = a[~done]
        hull[go, count[go]] = nxt[~done]
        count[go] += 1
        active[a[done]] = False
    return [hull[i, : count[i]] for i in range(n)]


def _closed_start(rel: np.ndarray, h: np.ndarray) -> tuple[int, int]:
    """Where a closed ring starts and which way it runs: (first vertex, second vertex).

    The toolbox starts at the lower-ranked vertex of the first triangle of Qhull's output around the
    point and walks towards that triangle's other vertex; Qhull's output order is an artefact of its
    incremental construction. In its place: the fan triangle that the first principal axis (MATLAB's
    sign) passes through, a choice of the same kind (one triangle, determined by the geometry).
    """
    ang = np.arctan2(rel[h, 1], rel[h, 0])  # hull order is counter-clockwise around the point
    nxt = np.roll(np.arange(len(h)), -1)
    span = np.mod(ang[nxt] - ang, 2 * np.pi)
    off = np.mod(-ang, 2 * np.pi)  # direction of the +first axis (angle 0) from each vertex
    t = int(np.argmax(off < span)) if np.any(off < span) else 0
    a, b = int(h[t]), int(h[nxt[t]])
    return (a, b) if a < b else (b, a)


def point_rings(points: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One-rings of every point, CSR style: (indptr, indices, closed).

    ``indices[indptr[i]:indptr[i+1]]`` is point i's ring in fan order, global indices; a closed ring
    repeats its first vertex at the end, as the toolbox's rings do. A point whose neighbourhood is
    degenerate (all neighbours on one line in projection) gets its kNN list, nearest first.
    """
    pts = np.asarray(points, dtype=float)
    n = len(pts)
    k = int(min(k, n))
    idx = _neighbours(pts, k)
    rel = _project(pts, idx)[:, 1:, :]  # (N, m, 2), m = k - 1 candidates (local ranks 1..m)
    r2 = np.einsum("nmk,nmk->nm", rel, rel)
    scale = np.sqrt(np.max(r2, axis=1, keepdims=True))
    valid = r2 > (1e-12 * scale) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(valid[..., None], rel / np.where(valid, r2, 1.0)[..., None], 0.0)
    m = rel.shape[1]
    z = np.concatenate([inv, np.zeros((n, 1, 2))], axis=1)  # candidate m = the origin (the point)
    zvalid = np.concatenate([valid, np.ones((n, 1), bool)], axis=1)
    hulls = _hull_order(z, zvalid)

    out: list[np.ndarray] = []
    closed = np.zeros(n, bool)
    for i, h in enumerate(hulls):
        if len(h) < 3 and not (len(h) >= 2 and m in h):
            out.append(idx[i, 1:])
            continue
        if m in h:  # the point is on its neighbourhood's hull: an open fan from one hull neighbour
            p = int(np.flatnonzero(h == m)[0])
            seq = np.concatenate([h[p + 1:], h[:p]])
            if len(seq) < 2:
                out.append(idx[i, 1:])
                continue
            if seq[-1] < seq[0]:  # the toolbox starts at the lower-ranked end
                seq = seq[::-1]
        else:  # closed fan: see _closed_start
            a, b = _closed_start(rel[i], h)
            p = int(np.flatnonzero(h == a)[0])
            seq = np.roll(h, -p)
            if seq[1] != b:
                seq = np.concatenate([seq[:1], seq[1:][::-1]])
            seq = np.concatenate([seq, seq[:1]])
            closed[i] = True
        out.append(idx[i, seq + 1])
    lengths = np.fromiter((len(r) for r in out), np.int64, n)
    indptr = np.concatenate([[0], np.cumsum(lengths)])
    return indptr, np.concatenate(out).astype(np.int64), closed
