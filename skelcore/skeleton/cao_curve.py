"""``method="cao"``'s curve: the toolbox's ``rosa_lineextract(P, r, 1)`` step by step.

``farthest_sampling_by_sphere``: balls of radius r on the contracted points, farthest-first, a
sample sits on a contracted point and takes the ball's points it is closest to;
``connect_by_inherit_neigh``: each point links its sample with the sample of the first one-ring
neighbour (in ring order) that has another, isolated samples join their nearest sample;
``edge_collapse_update`` (collapse order 1: lowest cost, then shortest): triangle edges are
collapsed into their second vertex, placed at the edge's midpoint, until no edge of a triangle is
listed, keeping the toolbox's incremental edge list with its bookkeeping (costs of new entries use
half degrees, untouched entries keep their old cost) so the same edges go in the same order.
"""

from __future__ import annotations

import heapq
from typing import Callable

import numpy as np
from scipy.spatial import cKDTree

from ._farthest import sample as _farthest_sample
from .cao import Rings

__all__ = ["farthest_sampling_by_sphere", "connect_by_inherit_neigh", "edge_collapse_update", "cao_curve"]


def farthest_sampling_by_sphere(
    pts: np.ndarray, radius: float, check: Callable[[], None] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(sample point indices, per-point sample index). The toolbox's ``max(mindst)`` (first index of
    the largest, NaN ignored) is a heap of (-distance, index) with stale entries skipped. Run by the
    compiled loop ``_farthest.c`` (the same samples and labels, bit for bit: docs/repair.md "The fill
    curves compiled"); :func:`_farthest_sampling_loop` where it cannot run (a radius not positive and
    finite, a point not finite, a grid of balls too large)."""
    pts = np.ascontiguousarray(pts, dtype=float).reshape(-1, 3)
    n = len(pts)
    if n and np.isfinite(radius) and radius > 0 and np.isfinite(pts).all():
        corresp = np.empty(n, np.int64)
        samples = np.empty(n, np.int64)
        count = _farthest_sample(pts, float(radius), check, corresp, samples)
        if count is not None:
            return samples[:count].copy(), corresp
    return _farthest_sampling_loop(pts, radius, check)


def _farthest_sampling_loop(
    pts: np.ndarray, radius: float, check: Callable[[], None] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`farthest_sampling_by_sphere` in Python: a KD-tree's ball per sample tried."""
    check = check or (lambda: None)
    n = len(pts)
    tree = cKDTree(pts)
    corresp = np.full(n, -1, np.int64)
    mindst = np.full(n, np.nan)
    samples: list[int] = []
    unlabelled = n
    heap: list[tuple[float, int]] = []
    steps = 0
    for k in range(n):
        if corresp[k] >= 0:
            continue
        mindst[k] = np.inf
        heapq.heappush(heap, (-np.inf, k))
        while unlabelled > 0:
            while heap and -heap[0][0] != mindst[heap[0][1]]:
                heapq.heappop(heap)
            if not heap:
                break
            negd, idx = heap[0]
            if -negd == 0.0:
                break
            steps += 1
            if steps % 256 == 0:
                check()
            nbrs = np.asarray(tree.query_ball_point(pts[idx], radius), np.int64)
            if np.all(corresp[nbrs] >= 0):
                mindst[idx] = 0.0
                heapq.heappop(heap)
                continue
            d = np.linalg.norm(pts[nbrs] - pts[idx], axis=1)
            samples.append(idx)
            old = mindst[nbrs]
            better = np.isnan(old) | (old > d)
            unlabelled -= int(np.count_nonzero(corresp[nbrs[better]] < 0))
            upd = nbrs[better]
            mindst[upd] = d[better]
            corresp[upd] = len(samples) - 1
            for v, i in zip(d[better].tolist(), upd.tolist()):
                if v > 0.0:
                    heapq.heappush(heap, (-v, i))
    return np.asarray(samples, np.int64), corresp


def connect_by_inherit_neigh(spls: np.ndarray, corresp: np.ndarray, rings: Rings) -> np.ndarray:
    """Dense 0/1 adjacency of the samples (diagonal set, as the toolbox's matrix)."""
    ns = len(spls)
    A = np.zeros((ns, ns), bool)
    differ = corresp[rings.member] != corresp[rings.owner]
    p = np.flatnonzero(differ)
    _own, first = np.unique(rings.owner[p], return_index=True)  # first differing ring entry per point
    p = p[first]
    a, b = corresp[rings.owner[p]], corresp[rings.member[p]]
    A[a, b] = True
    A[b, a] = True
    A[np.arange(ns), np.arange(ns)] = True
    iso = np.flatnonzero(A.sum(axis=1) == 1)
    if len(iso) and ns >= 2:
        _d, nn = cKDTree(spls).query(spls[iso], k=2)
        for i, js in zip(iso, nn):
            A[i, js] = True
            A[js, i] = True
    return A


def _column_major_hits(sk: np.ndarray, v: int) -> tuple[np.ndarray, np.ndarray]:
    """MATLAB ``[rows, cols] = find(skeds(:, 1:2) == v)``: column 1's rows first, then column 2's."""
    cols, rows = np.nonzero(sk[:, :2].T == v)
    return rows, cols


def edge_collapse_update(
    spls: np.ndarray, A: np.ndarray, check: Callable[[], None] | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Collapse triangle edges; returns (positions with NaN rows for removed samples, adjacency,
    merged_into: the sample each original sample ended in)."""
    check = check or (lambda: None)
    spls = np.array(spls, dtype=float)
    A = np.array(A, dtype=bool)
    n = len(spls)
    merged = np.arange(n)
    deg = A.sum(axis=1).astype(float) - 1.0

    def dist(a: int, b: int) -> float:
        return float(np.linalg.norm(spls[a] - spls[b]))

    rows: list[list[float]] = []
    for i in range(n):
        nb = np.flatnonzero(A[i])
        nb = nb[nb > i]
        lns = len(nb)
        if lns < 2:
            continue
        jj, kk = np.nonzero(np.triu(A[np.ix_(nb, nb)], 1))
        for a, b in zip(nb[jj].tolist(), nb[kk].tolist()):
            rows.append([i, a, 0.5 * (lns + deg[a]), dist(i, a)])
            rows.append([a, b, 0.5 * (deg[a] + deg[b]), dist(a, b)])
            rows.append([i, b, 0.5 * (lns + deg[b]), dist(b, i)])
    sk = np.asarray(rows, float).reshape(-1, 4)

    steps = 0
    while len(sk):
        steps += 1
        if steps % 16 == 0:
            check()
        cand = np.flatnonzero(sk[:, 2] == sk[:, 2].min())
        r = int(cand[np.argmin(sk[cand, 3])])
        e1, e2 = int(sk[r, 0]), int(sk[r, 1])
        sk = np.delete(sk, r, axis=0)
        spls[e2] = 0.5 * (spls[e1] + spls[e2])
        spls[e1] = np.nan
        nb1 = np.flatnonzero(A[e1])
        A[e2, nb1] = True
        A[nb1, e2] = True
        A[e1, :] = False
        A[:, e1] = False
        merged[merged == e1] = e2

        # 1) entries with e1: dropped when their other end is already linked to e2, else renamed
        linked = np.concatenate([sk[sk[:, 0] == e2, 1], sk[sk[:, 1] == e2, 0]])
        hr, hc = _column_major_hits(sk, e1)
        drop = []
        for row, col in zip(hr.tolist(), hc.tolist()):
            if np.isin(sk[row, 1 - col], linked):
                drop.append(row)
            else:
                sk[row, col] = e2
        if drop:
            sk = np.delete(sk, drop, axis=0)

        # 2.1) the triangles now at e2
        nb = np.flatnonzero(A[e2])
        nb = nb[nb != e2]
        jj, kk = np.nonzero(np.triu(A[np.ix_(nb, nb)], 1))
        tmp_e = np.empty((2 * len(jj), 2), np.int64)
        tmp_e[0::2, 0] = e2
        tmp_e[0::2, 1] = nb[jj]
        tmp_e[1::2, 0] = e2
        tmp_e[1::2, 1] = nb[kk]
        tmp_e1 = np.column_stack([nb[jj], nb[kk]]).astype(np.int64)
        # 2.2) entries at e2 that are no longer triangle edges go; the rest need not be re-added
        hr, hc = _column_major_hits(sk, e2)
        drop, known = [], []
        for row, col in zip(hr.tolist(), hc.tolist()):
            hit = np.flatnonzero(tmp_e[:, 1] == sk[row, 1 - col])
            if len(hit):
                known.extend(h for h in hit.tolist() if h not in known)
            else:
                drop.append(row)
        if drop:
            sk = np.delete(sk, sorted(set(drop)), axis=0)
        if known:
            tmp_e = np.delete(tmp_e, known, axis=0)
        # 2.3) add the new triangle edges not listed yet
        new_rows = []
        for t1, t2 in np.vstack([tmp_e, tmp_e1]).tolist():
            listed = np.any(((sk[:, 0] == t1) & (sk[:, 1] == t2)) | ((sk[:, 0] == t2) & (sk[:, 1] == t1)))
            if not listed:
                listed = any((r[0] == t1 and r[1] == t2) or (r[0] == t2 and r[1] == t1) for r in new_rows)
            if not listed:
                deg[t1] = (A[t1].sum() - 1) * 0.5
                deg[t2] = (A[t2].sum() - 1) * 0.5
                new_rows.append([t1, t2, 0.5 * (deg[t1] + deg[t2]), dist(t1, t2)])
        if new_rows:
            sk = np.vstack([sk, np.asarray(new_rows, float)])
        # 3) refresh cost and length of the entries at e2
        hr, hc = _column_major_hits(sk, e2)
        deg[e2] = (A[e2].sum() - 1) * 0.5
        for row, col in zip(hr.tolist(), hc.tolist()):
            kv = int(sk[row, 1 - col])
            deg[kv] = (A[kv].sum() - 1) * 0.5
            sk[row, 2] = 0.5 * (deg[e2] + deg[kv])
            sk[row, 3] = dist(e2, kv)
    return spls, A, merged


def cao_curve(
    cpts: np.ndarray, rings: Rings, radius: float, check: Callable[[], None] | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """(curve vertices, edges, per-point curve vertex, number of samples before the collapse)."""
    samples, corresp = farthest_sampling_by_sphere(cpts, radius, check)
    spls = cpts[samples]
    A = connect_by_inherit_neigh(spls, corresp, rings)
    pos, A, merged = edge_collapse_update(spls, A, check)
    alive = ~np.isnan(pos[:, 0])
    new = np.cumsum(alive) - 1
    i, j = np.nonzero(np.triu(A, 1))
    keep = alive[i] & alive[j]
    edges = np.column_stack([new[i[keep]], new[j[keep]]]).astype(np.int64)
    return pos[alive], edges, new[merged[corresp]], len(samples)
