"""Curve extraction from contracted points (Cao's ROSA-style line extraction), plus our clean-up.

Farthest-point sampling of the contracted points with balls of radius ``sample_radius_factor`` x the
cloud's bounding-box diagonal; two samples are connected when points of their balls are one-ring
neighbours in the original cloud. Then, in order: stray single-point balls are dropped; shortcut
edges (another path at most ``shortcut_ratio`` x as long) are removed; edges of triangles are
collapsed (lowest mean degree first, then shortest; Cao's rule) until no triangle is left; cycles
shorter than ``short_cycle_factor`` sample radii are collapsed shortest edge first (the search for
them incremental, :class:`_ShortCycles`); short end-cap spurs are pruned. A curve vertex sits at the
centroid of the contracted points it stands for.
Everything beyond Cao's collapse is an addition of ours (see :class:`SkeletonizeParams`).
"""

from __future__ import annotations

import heapq
import math
from typing import Callable

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from .skeleton_params import SkeletonizeParams

__all__ = ["extract_curve"]

def _farthest_sampling_by_sphere(
    pts: np.ndarray, radius: float, report: Callable[[str, float], None]
) -> tuple[np.ndarray, np.ndarray]:
    """Ball-based farthest-point sampling (Cao's ``farthest_sampling_by_sphere``).

    Starting at the lowest-index uncovered point, repeatedly take the covered point farthest from its
    sample, open a ball there, and hand the ball's points to it when it is their closest sample.
    Returns (sample point indices, per-point sample label).
    """
    n = len(pts)
    tree = cKDTree(pts)
    label = np.full(n, -1, np.int64)
    mindst = np.full(n, -1.0)  # -1: not reached by any ball yet
    centres: list[int] = []
    unlabelled = n
    skips = 0
    for start in range(n):
        if unlabelled == 0:
            break
        if label[start] >= 0:
            continue
        mindst[start] = np.inf
        while unlabelled > 0:  # as the toolbox: stop as soon as every point has a sample
            idx = int(np.argmax(mindst))
            if mindst[idx] <= 0:
                break
            nbrs = np.asarray(tree.query_ball_point(pts[idx], radius), dtype=np.int64)
            if idx != start and np.all(label[nbrs] >= 0):
                mindst[idx] = 0.0
                skips += 1
                if skips >= 32:
                    # Many covered points in a row with nothing new in reach (the rest of the cloud is
                    # another component): retire every candidate with no unlabelled point within the
                    # radius at once. Labels are never taken back, so this only skips what the loop
                    # would skip one by one.
                    skips = 0
                    cand = np.flatnonzero(mindst > 0)
                    free = np.flatnonzero(label < 0)
                    if len(cand) and len(free):
                        d, _ = cKDTree(pts[free]).query(pts[cand], distance_upper_bound=radius * (1 + 1e-12))
                        mindst[cand[~np.isfinite(d)]] = 0.0
                continue
            skips = 0
            d = np.linalg.norm(pts[nbrs] - pts[idx], axis=1)
            centres.append(idx)
            better = (label[nbrs] < 0) | (mindst[nbrs] > d)
            unlabelled -= int(np.count_nonzero(label[nbrs] < 0))
            mindst[nbrs[better]] = d[better]
            label[nbrs[better]] = len(centres) - 1
            mindst[idx] = 0.0
            if len(centres) % 32 == 0:
                report("curve", 0.5 * (1.0 - unlabelled / n))
    return np.asarray(centres, np.int64), label


class _Graph:
    """Small mutable graph of curve vertices: adjacency sets, point sums for centroids.

    Plain Python floats and sets: the graph has hundreds of vertices and is edited one collapse at a
    time, where numpy's per-call overhead would dominate.
    """

    def __init__(self, pos: np.ndarray, counts: np.ndarray, edges: np.ndarray) -> None:
        self.sum = [list(map(float, p * c)) for p, c in zip(pos, counts)]
        self.count = [float(c) for c in counts]
        self._pos = [tuple(map(float, p)) for p in pos]
        self.alive = np.ones(len(pos), bool)
        self.adj: list[set[int]] = [set() for _ in range(len(pos))]
        for a, b in edges:
            if a != b:
                self.adj[a].add(int(b))
                self.adj[b].add(int(a))
        self.merged_into = np.arange(len(pos))
        # the vertices collapses kept: every edge a collapse adds or lengthens or shortens ends at one
        # (read and cleared by _ShortCycles)
        self.kept: set[int] = set()

    def pos(self, v: int) -> tuple[float, float, float]:
        return self._pos[v]

    def length(self, a: int, b: int) -> float:
        return math.dist(self._pos[a], self._pos[b])

    def collapse(self, keep: int, gone: int) -> None:
        """Merge ``gone`` into ``keep``: the merged vertex is the centroid of both balls' points."""
        self.kept.add(keep)
        sk, sg = self.sum[keep], self.sum[gone]
        for i in range(3):
            sk[i] += sg[i]
        self.count[keep] += self.count[gone]
        c = self.count[keep]
        self._pos[keep] = (sk[0] / c, sk[1] / c, sk[2] / c)
        for w in self.adj[gone]:
            self.adj[w].discard(gone)
            if w != keep:
                self.adj[w].add(keep)
                self.adj[keep].add(w)
        self.adj[gone] = set()
        self.adj[keep].discard(keep)
        self.alive[gone] = False
        self.merged_into[gone] = keep

    def in_triangle(self, a: int, b: int) -> bool:
        return not self.adj[a].isdisjoint(self.adj[b])

    def cost(self, a: int, b: int) -> tuple[float, float]:
        return (0.5 * (len(self.adj[a]) + len(self.adj[b])), self.length(a, b))


def _collapse_triangles(g: _Graph, report: Callable[[str, float], None]) -> None:
    """Collapse triangle edges (lowest mean degree, then shortest, first) until no triangle is left
    (Cao's ``edge_collapse_update`` ordering, after Li et al. 2001)."""
    tri_edges: set[tuple[int, int]] = set()
    for a in range(len(g.adj)):
        for b in g.adj[a]:
            if a < b and g.in_triangle(a, b):
                tri_edges.add((a, b))
    steps = 0
    while tri_edges:
        a, b = min(tri_edges, key=lambda e: (g.cost(*e), e))
        keep, gone = (a, b) if len(g.adj[a]) >= len(g.adj[b]) else (b, a)
        g.collapse(keep, gone)
        tri_edges = {e for e in tri_edges if gone not in e}
        touched = {keep} | g.adj[keep]
        for u in touched:
            for w in g.adj[u]:
                e = (min(u, w), max(u, w))
                if g.in_triangle(u, w):
                    tri_edges.add(e)
                else:
                    tri_edges.discard(e)
        steps += 1
        if steps % 64 == 0:
            report("curve", 0.6)


def _drop_strays(g: _Graph, counts: np.ndarray, min_points: int, long_edge: float) -> None:
    """Remove samples of a few stray points: a ball holding fewer than ``min_points`` points that is
    isolated, or a leaf hanging on an edge longer than ``long_edge``. Contraction throws single
    points out of thin parts (the horse's ears, the paper notes); they would add long spokes. A small
    ball inside a chain (a sparse branch) is kept: dropping it would cut the curve.
    """
    changed = True
    while changed:
        changed = False
        for v in np.flatnonzero(g.alive):
            v = int(v)
            if counts[v] >= min_points or len(g.adj[v]) > 1:
                continue
            if g.adj[v] and g.length(v, next(iter(g.adj[v]))) <= long_edge:
                continue
            for w in g.adj[v]:
                g.adj[w].discard(v)
            g.adj[v] = set()
            g.alive[v] = False
            changed = True


def _dijkstra(g: _Graph, sources: list[int], budget: float, target: int = -1
              ) -> tuple[dict[int, int], set[int]]:
    """Dijkstra from ``sources`` (ties by vertex number) up to ``budget``, not using the edge
    (sources[0], target), stopping when ``target`` is settled: (each reached vertex's predecessor,
    -1 at a source; the settled vertices)."""
    pos, adj = g._pos, g.adj
    a = sources[0]
    dist = dict.fromkeys(sources, 0.0)
    prev = dict.fromkeys(sources, -1)
    heap = [(0.0, v) for v in sources]
    done: set[int] = set()
    while heap:
        d, u = heapq.heappop(heap)
        if u in done:
            continue
        done.add(u)
        if u == target:
            break
        pu = pos[u]
        for w in sorted(adj[u]):
            if u == a and w == target:
                continue
            nd = d + math.dist(pu, pos[w])  # g.length(u, w)
            if nd <= budget and nd < dist.get(w, math.inf):
                dist[w] = nd
                prev[w] = u
                heapq.heappush(heap, (nd, w))
    return prev, done


def _shortest_path(g: _Graph, a: int, b: int, budget: float) -> list[int] | None:
    """Shortest a -> b path no longer than ``budget``, not using the edge (a, b)."""
    prev, done = _dijkstra(g, [a], budget, b)
    if b not in done:
        return None
    path = [b]
    while path[-1] != a:
        path.append(prev[path[-1]])
    return path


def _within(g: _Graph, sources: list[int], budget: float) -> set[int]:
    """The vertices at most ``budget`` along the graph from any of ``sources``."""
    return _dijkstra(g, sources, budget)[1]


def _remove_shortcuts(g: _Graph, ratio: float) -> None:
    """Drop every edge (longest first) that another path joins at most ``ratio`` x as long.

    Contraction is uneven, so two original neighbours can land several balls apart along the same
    line: their edge is a shortcut of the path through the samples in between (the long side of a
    flat triangle is the simplest case). Collapsing it instead, as Cao's rule would for a triangle,
    merges runs of samples into a few far-apart vertices; keeping it leaves a cycle.
    """
    edges = sorted(
        ((g.length(int(a), b), int(a), b) for a in np.flatnonzero(g.alive) for b in g.adj[int(a)] if b > a),
        reverse=True,
    )
    for length, a, b in edges:
        if b in g.adj[a] and _shortest_path(g, a, b, ratio * length) is not None:
            g.adj[a].discard(b)
            g.adj[b].discard(a)


def _prune_short_branches(g: _Graph, min_length: Callable[[int], float]) -> None:
    """Remove leaf branches shorter than ``min_length(junction)`` that hang off a junction (degree >= 3).

    The flat end caps of a tube contract to small stars or crosses whose arms would otherwise show
    up as spurs; the branch's vertices are handed to the junction. Shortest branch first, so a
    junction never loses its last two branches and a path is never shortened.
    """
    while True:
        best = None
        for leaf in np.flatnonzero(g.alive):
            leaf = int(leaf)
            if len(g.adj[leaf]) != 1:
                continue
            chain, prev, cur, length = [leaf], -1, leaf, 0.0
            while True:
                w = next(x for x in g.adj[cur] if x != prev)
                length += g.length(cur, w)
                prev, cur = cur, w
                if len(g.adj[cur]) != 2:
                    break
                chain.append(cur)
            if len(g.adj[cur]) >= 3 and length < min_length(cur) and (best is None or length < best[0]):
                best = (length, chain, cur)
        if best is None:
            return
        _length, chain, junction = best
        for v in chain:
            for w in list(g.adj[v]):
                g.adj[w].discard(v)
            g.adj[v] = set()
            g.alive[v] = False
            g.merged_into[v] = junction


def _roots(merged_into: np.ndarray) -> np.ndarray:
    """Follow merges to the surviving vertex of each sample."""
    root = merged_into.copy()
    while True:
        nxt = root[root]
        if np.array_equal(nxt, root):
            return root
        root = nxt


class _ShortCycles:
    """The first cycle shorter than ``max_length`` in scan order, found again after each collapse.

    The scan (edges (a, b), a < b, in increasing order; for each, the shortest a -> b path avoiding the
    edge within ``max_length`` - |ab|) returns the first edge's cycle, as a scan from scratch would.
    Kept between calls: the edges whose search found nothing, and the scan's frontier (the edges from
    it on were never asked). A collapse adds, lengthens or shortens only edges at the vertex it keeps
    (:attr:`_Graph.kept`), so a cycle it makes passes through one of those, and both ends of each of
    its edges lie within half its length (less than ``max_length`` / 2) of it. Only the edges with both
    ends that near a kept vertex (one Dijkstra from all of them, with a margin for rounding), and the
    new ones, are searched again, in scan order, before the frontier's (docs/repair.md "The
    short-cycle search incremental").
    """

    def __init__(self, g: _Graph, max_length: float) -> None:
        self.g = g
        self.max_length = max_length
        self.clear: set[tuple[int, int]] = set()  # edges below the frontier known to close no cycle
        self.pending: set[tuple[int, int]] = set()  # edges below the frontier to search again
        self.frontier = (-1, -1)
        g.kept.clear()

    def _search(self, a: int, b: int) -> list[int] | None:
        g = self.g
        path = _shortest_path(g, a, b, self.max_length - g.length(a, b))
        if path is None:
            self.clear.add((a, b))
        return path

    def _forget_near_kept(self) -> None:
        g = self.g
        kept = [v for v in sorted(g.kept) if g.alive[v]]
        g.kept.clear()
        if not kept:
            return
        near = _within(g, kept, 0.5 * self.max_length * (1.0 + 1e-9))
        for v in kept:  # new edges and moved ones: all at a kept vertex
            for w in g.adj[v]:
                e = (v, w) if v < w else (w, v)
                if e < self.frontier:
                    self.clear.discard(e)
                    self.pending.add(e)
        for v in near:
            for w in g.adj[v]:
                if v < w and w in near and (v, w) in self.clear:
                    self.clear.discard((v, w))
                    self.pending.add((v, w))

    def find(self) -> list[int] | None:
        """The cycle (its vertex list) the from-scratch scan would return first, or None."""
        if self.max_length <= 0:
            return None
        g = self.g
        self._forget_near_kept()
        for e in sorted(self.pending):
            a, b = e
            if b not in g.adj[a]:
                self.pending.discard(e)
                continue
            path = self._search(a, b)
            if path is not None:
                return path
            self.pending.discard(e)
        a0, b0 = self.frontier
        for a in np.flatnonzero(g.alive[max(a0, 0):]) + max(a0, 0):
            a = int(a)
            for b in sorted(g.adj[a]):
                if b > a and (a, b) >= (a0, b0):
                    path = self._search(a, b)
                    if path is not None:
                        self.frontier = (a, b)
                        return path
        self.frontier = (len(g.adj), 0)
        return None


def _collapse_short_cycles(g: _Graph, max_length: float, report: Callable[[str, float], None]) -> None:
    """Collapse the first short cycle's shortest edge (then any triangle it makes) until none is left."""
    cycles = _ShortCycles(g, max_length)
    while True:
        report("curve", 0.8)
        cycle = cycles.find()
        if cycle is None:
            return
        ring = list(zip(cycle, cycle[1:] + cycle[:1]))
        a, b = min(ring, key=lambda e: (g.length(*e), e))
        g.collapse(a, b)
        _collapse_triangles(g, report)


def extract_curve(
    contracted_n: np.ndarray,
    adjacency: sp.csr_matrix,
    radius: float,
    params: SkeletonizeParams = SkeletonizeParams(),
    *,
    original_n: np.ndarray | None = None,
    report: Callable[[str, float], None] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Curve skeleton of contracted points: sampling, inherited connectivity, edge collapse.

    Returns (vertices, edges, per-point vertex label; -1 for a point of a dropped stray ball) in the
    contracted points' coordinates.
    """
    report = report or (lambda _stage, _f: None)
    original_n = contracted_n if original_n is None else original_n
    report("curve", 0.0)
    centres, label = _farthest_sampling_by_sphere(contracted_n, radius, report)
    m = len(centres)
    valid = label >= 0
    counts = np.bincount(label[valid], minlength=m).astype(float)
    sums = np.zeros((m, 3))
    np.add.at(sums, label[valid], contracted_n[valid])
    pos = sums / np.maximum(counts, 1)[:, None]
    coo = adjacency.tocoo()
    la, lb = label[coo.row], label[coo.col]
    diff = (la != lb) & (la >= 0) & (lb >= 0)
    edges = np.unique(np.sort(np.column_stack([la[diff], lb[diff]]), axis=1), axis=0) if diff.any() else np.empty((0, 2), np.int64)
    g = _Graph(pos, np.maximum(counts, 1), edges)
    report("curve", 0.55)
    _drop_strays(g, counts, params.min_sample_points, 2.0 * radius)
    if params.shortcut_ratio > 1.0:
        _remove_shortcuts(g, params.shortcut_ratio)
    _collapse_triangles(g, report)
    _collapse_short_cycles(g, params.short_cycle_factor * radius, report)
    if params.prune_branch_factor > 0 or params.prune_thickness_factor > 0:
        # local thickness: mean distance of a vertex's original points to it (about the tube radius)
        owner = _roots(g.merged_into)[np.maximum(label, 0)]
        vpos = np.array(g._pos)
        dist = np.linalg.norm(original_n - vpos[owner], axis=1)
        w = valid.astype(float)
        thickness = np.bincount(owner, weights=dist * w, minlength=m) / np.maximum(np.bincount(owner, weights=w, minlength=m), 1)
        _prune_short_branches(
            g, lambda j: max(params.prune_branch_factor * radius, params.prune_thickness_factor * thickness[j])
        )
    alive = np.flatnonzero(g.alive)
    new_index = np.full(m, -1, np.int64)
    new_index[alive] = np.arange(len(alive))
    verts = np.array([g.pos(int(v)) for v in alive]).reshape(-1, 3)
    out_edges = sorted({(min(new_index[a], new_index[b]), max(new_index[a], new_index[b]))
                        for a in alive for b in g.adj[a]})
    root = _roots(g.merged_into)
    report("curve", 1.0)
    final = np.where(valid, new_index[root[np.maximum(label, 0)]], -1)
    return verts, np.asarray(out_edges, np.int64).reshape(-1, 2), final
