"""Laplacian-based contraction skeletonization (Cao et al. 2010), the method the paper evaluates.

From a bare cloud to both skeletal representations the metrics score:

1. **Contraction** (skeletal point set, pointwise correspondence). Each point keeps the one-ring it
   has in the original cloud (the local-Delaunay neighbours of ``robust_laplacian``'s point-cloud
   Laplacian); the triangles of those one-rings form a triangle soup whose cotangent Laplacian is
   recomputed on the current positions at every iteration (``robust_laplacian.mesh_laplacian``, whose
   intrinsic mollification keeps nearly collapsed triangles finite). Each iteration solves the
   least-squares system ``[W_L L; W_H] X' = [0; W_H X]`` through its normal equations; ``W_L`` grows by
   ``contraction_scale`` per iteration and ``W_H`` is each point's one-ring shrink ratio, as Cao's
   toolbox does. Iterations stop when the mean one-ring size stops shrinking.
2. **Curve** (Cao's ROSA-style line extraction). Farthest-point sampling of the contracted points with
   balls of radius ``sample_radius_factor`` x the cloud's bounding-box diagonal; two samples are
   connected when points of their balls are one-ring neighbours in the original cloud. Then, in
   order: stray single-point balls are dropped; shortcut edges (another path at most
   ``shortcut_ratio`` x as long) are removed; edges of triangles are collapsed (lowest mean degree
   first, then shortest; Cao's rule) until no triangle is left; cycles shorter than
   ``short_cycle_factor`` sample radii (left by incomplete contraction) are collapsed shortest edge
   first; short end-cap spurs are pruned. A curve vertex sits at the centroid of the contracted
   points it stands for. Everything beyond Cao's collapse is an addition of ours (see the params).

Everything runs in normalized coordinates (SPEC 0 transform, longest side 1.6, like the reference
toolbox's ``GS.normalize``) and is returned in the user's units. Deterministic: no randomness.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, fields
from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.spatial import cKDTree

from .curve import CurveSkeleton
from .errors import Cancelled, SkelInputError
from .geometry import Normalization, as_points, unique_rows

__all__ = ["SkeletonizeParams", "SkeletonizeInfo", "skeletonize", "contract", "extract_curve"]

Progress = Callable[[float, str], None]


@dataclass(frozen=True)
class SkeletonizeParams:
    """Constants of the skeletonizer; defaults follow Cao et al.'s toolbox (``GS.m``) where it has one.

    Attributes
    ----------
    laplacian_neighbors : candidate neighbours per point for robust_laplacian's local Delaunay
        one-rings (its default, 30).
    mollify_factor : robust_laplacian's intrinsic mollification (its default, 1e-5).
    contraction_weight : initial contraction weight W_L; None = sqrt(N / reference_points) /
        (5 x mean one-ring edge length) in normalized units: the toolbox's
        ``compute_init_laplacian_constraint_weight`` made density independent (the cotangent
        Laplacian scales with the area per point).
    reference_points : cloud size at which the default W_L and its cap equal the toolbox's (4096,
        the paper's clouds).
    contraction_scale : W_L is multiplied by this each iteration (s_L = 3, toolbox; the paper says 2).
    contraction_weight_max : cap on W_L (2048, from Au et al.'s implementation), scaled by
        sqrt(N / reference_points) like the start.
    attraction_weight : initial attraction weight W_H (1).
    attraction_weight_max : cap on W_H (10000).
    max_iterations : contraction iterations at most (20, toolbox).
    termination_ratio : stop when the mean one-ring size ratio (current / original) decreased by less
        than this in the last iteration (0.01, toolbox's ``CONTRACT_TERMINATION_CONDITION``) ...
    started_ratio : ... and that ratio is already below this (0.9): unlike the toolbox, a first
        iteration that hardly moved anything does not end the contraction.
    bbox_growth_limit : an iteration whose result's bounding box (0.1%-99.9% quantiles) grows on any axis by more than
        (factor - 1) x the original's longest side is rejected and contraction stops (1.2; the
        toolbox compares each axis with itself, which stops flat shapes early).
    sample_radius_factor : ball radius of the farthest-point sampling = factor x bounding-box diagonal
        of the normalized cloud (0.02, as the paper's demo).
    connect_neighbors : original-cloud kNN neighbours whose ball labels connect two samples; None =
        the one-ring neighbours of the Laplacian (Cao's "inherited" connectivity).
    short_cycle_factor : after triangles are gone, cycles shorter (total edge length) than this x the
        sample radius are collapsed, shortest edge first: two strands of samples along a tube that
        did not contract to a line, or quads left in a flat cap. A real hole (torus: ~80 radii) is longer.
        0 keeps every cycle.
    shortcut_ratio : before collapsing, an edge is dropped when another path joins its ends at most
        this x its length (a shortcut along a line of samples, e.g. the long side of a triangle
        with an angle above ~100 degrees); 1 = Cao's plain collapse.
    prune_branch_factor : leaf branches shorter than this x the sample radius that hang off a
        junction are removed (end-cap spurs); 0 keeps them.
    prune_thickness_factor : ... as are leaf branches shorter than this x the shape's thickness at
        their junction (mean distance of the junction's original points to it): a flat end cap
        contracts to a cross as wide as the tube; 0 turns this off.
    min_sample_points : a sample ball holding fewer contracted points than this is dropped with its
        points when it is isolated or a leaf on an edge longer than two radii (stray points thrown
        out of the shape would add long spokes to the curve).
    """

    laplacian_neighbors: int = 30
    mollify_factor: float = 1e-5
    contraction_weight: float | None = None
    contraction_scale: float = 3.0
    contraction_weight_max: float = 2048.0
    reference_points: int = 4096
    attraction_weight: float = 1.0
    attraction_weight_max: float = 10000.0
    max_iterations: int = 20
    termination_ratio: float = 0.01
    started_ratio: float = 0.9
    bbox_growth_limit: float = 1.2
    sample_radius_factor: float = 0.02
    connect_neighbors: int | None = None
    short_cycle_factor: float = 20.0
    shortcut_ratio: float = 1.3
    prune_branch_factor: float = 3.0
    prune_thickness_factor: float = 1.0
    min_sample_points: int = 3

    def __post_init__(self) -> None:
        def bad(name: str, why: str) -> None:
            raise ValueError(f"skeletonize parameter {name}={getattr(self, name)!r}: {why}")

        for name in ("mollify_factor", "contraction_weight_max", "attraction_weight",
                     "attraction_weight_max", "termination_ratio", "sample_radius_factor"):
            if not float(getattr(self, name)) > 0:
                bad(name, "must be > 0")
        if self.contraction_weight is not None and not float(self.contraction_weight) > 0:
            bad("contraction_weight", "must be > 0 or None")
        if not 0.0 < float(self.started_ratio) <= 1.0:
            bad("started_ratio", "must be in (0, 1]")
        if int(self.reference_points) < 1:
            bad("reference_points", "must be >= 1")
        if not float(self.contraction_scale) >= 1.0:
            bad("contraction_scale", "must be >= 1")
        if not float(self.bbox_growth_limit) > 1.0:
            bad("bbox_growth_limit", "must be > 1")
        if int(self.laplacian_neighbors) < 3:
            bad("laplacian_neighbors", "must be >= 3")
        if int(self.max_iterations) < 1:
            bad("max_iterations", "must be >= 1")
        if self.connect_neighbors is not None and int(self.connect_neighbors) < 2:
            bad("connect_neighbors", "must be >= 2 or None")
        if not float(self.shortcut_ratio) >= 1.0:
            bad("shortcut_ratio", "must be >= 1")
        if float(self.prune_thickness_factor) < 0:
            bad("prune_thickness_factor", "must be >= 0")
        if float(self.prune_branch_factor) < 0:
            bad("prune_branch_factor", "must be >= 0")
        if int(self.min_sample_points) < 1:
            bad("min_sample_points", "must be >= 1")
        if float(self.short_cycle_factor) < 0:
            bad("short_cycle_factor", "must be >= 0")

    def replace(self, **changes) -> "SkeletonizeParams":
        known = {f.name for f in fields(self)}
        unknown = sorted(set(changes) - known)
        if unknown:
            raise ValueError(f"unknown skeletonize parameter(s): {', '.join(unknown)}")
        import dataclasses

        return dataclasses.replace(self, **changes)


@dataclass
class SkeletonizeInfo:
    """What happened: iterations run, the one-ring size ratio after each, why it stopped, timings."""

    iterations: int
    ring_ratios: list[float]
    stop_reason: str
    sample_radius: float
    n_samples: int
    timings: dict[str, float]


# ---------------------------------------------------------------------------------------------
# progress plumbing


class _Reporter:
    """Maps stage fractions onto one overall fraction and raises ``Cancelled`` when asked to."""

    _SPAN = {"laplacian": (0.0, 0.1), "contraction": (0.1, 0.85), "curve": (0.85, 1.0)}

    def __init__(self, progress: Progress | None, cancel: Callable[[], bool] | None) -> None:
        self.progress = progress
        self.cancel = cancel
        self._last = -1.0

    def __call__(self, stage: str, fraction: float) -> None:
        if self.cancel is not None and self.cancel():
            raise Cancelled(f"cancelled during skeletonization ({stage})")
        if self.progress is not None:
            lo, hi = self._SPAN[stage]
            overall = lo + (hi - lo) * min(max(fraction, 0.0), 1.0)
            if overall - self._last >= 0.005 or overall >= 1.0:
                self._last = overall
                self.progress(overall, stage)


# ---------------------------------------------------------------------------------------------
# one-rings and the Laplacian


def _one_ring_graph(points: np.ndarray, params: SkeletonizeParams) -> sp.csr_matrix:
    """Symmetric 0/1 adjacency of the local-Delaunay one-rings (robust_laplacian's sparsity)."""
    import robust_laplacian

    k = int(min(params.laplacian_neighbors, len(points) - 1))
    L, _ = robust_laplacian.point_cloud_laplacian(points, mollify_factor=params.mollify_factor, n_neighbors=k)
    L = sp.coo_matrix(L)
    off = (L.row != L.col) & (L.data != 0)
    n = len(points)
    adj = sp.coo_matrix((np.ones(int(off.sum())), (L.row[off], L.col[off])), shape=(n, n)).tocsr()
    adj = ((adj + adj.T) > 0).astype(np.int8).tocsr()
    adj.eliminate_zeros()
    return adj


def _triangles(adj: sp.csr_matrix) -> np.ndarray:
    """All 3-cliques (i < j < k) of the one-ring graph: the triangle soup of the one-rings."""
    upper = sp.triu(adj, k=1).tocsr()
    upper.sort_indices()
    indptr, indices = upper.indptr, upper.indices
    rows = np.repeat(np.arange(upper.shape[0]), np.diff(indptr))
    # for every edge (i, j), candidates k among the upper neighbours of i, kept if (j, k) is an edge
    deg = np.diff(indptr)
    tris = []
    n = upper.shape[0]
    keys = rows.astype(np.int64) * n + indices  # sorted: CSR rows in order, sorted indices
    for offset in range(int(deg.max(initial=0))):
        has = deg[rows] > offset
        i = rows[has]
        j = indices[has]
        kk = indices[indptr[i] + offset]
        ok = kk > j
        i, j, kk = i[ok], j[ok], kk[ok]
        q = j.astype(np.int64) * n + kk
        pos = np.searchsorted(keys, q)
        pos = np.minimum(pos, len(keys) - 1)
        hit = keys[pos] == q
        tris.append(np.column_stack([i[hit], j[hit], kk[hit]]))
    if not tris:
        return np.empty((0, 3), np.int64)
    return np.vstack(tris).astype(np.int64)


def _ring_sizes(points: np.ndarray, adj: sp.csr_matrix) -> np.ndarray:
    """Per point, the shortest distance to a one-ring neighbour (toolbox's ``one_ring_size`` type 1)."""
    coo = adj.tocoo()
    d = np.linalg.norm(points[coo.row] - points[coo.col], axis=1)
    out = np.full(len(points), np.inf)
    np.minimum.at(out, coo.row, d)
    out[~np.isfinite(out)] = 0.0
    return out


def _cotan_laplacian(points: np.ndarray, faces: np.ndarray, mollify: float) -> sp.csr_matrix:
    import robust_laplacian

    L, _ = robust_laplacian.mesh_laplacian(np.ascontiguousarray(points), faces, mollify_factor=mollify)
    return sp.csr_matrix(L)


# ---------------------------------------------------------------------------------------------
# contraction


def _robust_extent(points: np.ndarray) -> np.ndarray:
    """Bounding-box sides ignoring the 0.1% most extreme points per side: a few points thrown out by
    a degenerate one-ring must not stop the contraction of everything else (boundedness shows them)."""
    if len(points) < 1000:
        return points.max(axis=0) - points.min(axis=0)
    lo, hi = np.quantile(points, [0.001, 0.999], axis=0)
    return hi - lo


def contract(
    points_n: np.ndarray,
    params: SkeletonizeParams = SkeletonizeParams(),
    *,
    report: Callable[[str, float], None] | None = None,
) -> tuple[np.ndarray, sp.csr_matrix, dict]:
    """Cao et al.'s iterative Laplacian contraction of normalized points.

    Returns (contracted points, one-ring adjacency of the original points, info dict).
    """
    report = report or (lambda _stage, _f: None)
    n = len(points_n)
    report("laplacian", 0.0)
    adj = _one_ring_graph(points_n, params)
    faces = _triangles(adj)
    report("laplacian", 1.0)

    sizes0 = _ring_sizes(points_n, adj)
    coo = adj.tocoo()
    mean_edge = float(np.mean(np.linalg.norm(points_n[coo.row] - points_n[coo.col], axis=1))) if coo.nnz else 1.0
    # Cao's toolbox starts at 1 / (5 h). The Laplacian of a sampled surface scales with the area per
    # point (h^2), so that start contracts a dense cloud far more weakly than a sparse one; scaling it
    # by sqrt(N / reference_points) gives the same first step as the toolbox's on a cloud of the
    # reference size (the paper's 4096) of the same surface, whatever the density. The cap scales alike.
    density = float(np.sqrt(n / params.reference_points))
    if params.contraction_weight is not None:
        wl = float(params.contraction_weight)
    else:
        wl = density / (5.0 * mean_edge)
    wl_max = params.contraction_weight_max * density
    wh = np.full(n, float(params.attraction_weight))
    extent0 = np.maximum(_robust_extent(points_n), 1e-12)
    total0 = float(sizes0.sum()) or 1.0

    current = points_n.copy()
    ratios: list[float] = [1.0]
    stop = "max_iterations"
    iterations = 0
    if len(faces) == 0:
        return current, adj, {"iterations": 0, "ring_ratios": ratios, "stop_reason": "no one-ring triangles"}
    for it in range(int(params.max_iterations)):
        report("contraction", it / params.max_iterations)
        L = _cotan_laplacian(current, faces, params.mollify_factor)
        A = (wl * wl) * (L.T @ L) + sp.diags(wh * wh)
        rhs = (wh * wh)[:, None] * current
        new = spla.spsolve(A.tocsc(), rhs)
        new = np.asarray(new).reshape(n, 3)
        if not np.all(np.isfinite(new)):
            stop = "non-finite solve"
            break
        extent = _robust_extent(new)
        # relative to the longest side: a thin axis of a sheet may widen a little without diverging
        if np.any(extent - extent0 > (params.bbox_growth_limit - 1.0) * extent0.max()):
            stop = "bounding box grew"
            break
        sizes = _ring_sizes(new, adj)
        ratio = float(sizes.sum()) / total0
        iterations += 1
        decrease = ratios[-1] - ratio
        current = new
        ratios.append(ratio)
        # the toolbox also stops when nothing has moved yet (a fat part under weak first weights)
        if decrease < params.termination_ratio and ratio < params.started_ratio:
            stop = "one-ring size stopped shrinking"
            break
        wl = min(wl * params.contraction_scale, wl_max)
        with np.errstate(divide="ignore", invalid="ignore"):
            wh = params.attraction_weight * np.where(sizes > 0, sizes0 / sizes, params.attraction_weight_max)
        wh = np.clip(np.nan_to_num(wh, nan=params.attraction_weight), params.attraction_weight, params.attraction_weight_max)
    report("contraction", 1.0)
    return current, adj, {"iterations": iterations, "ring_ratios": ratios, "stop_reason": stop}


# ---------------------------------------------------------------------------------------------
# curve extraction


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

    def pos(self, v: int) -> tuple[float, float, float]:
        return self._pos[v]

    def length(self, a: int, b: int) -> float:
        return math.dist(self._pos[a], self._pos[b])

    def collapse(self, keep: int, gone: int) -> None:
        """Merge ``gone`` into ``keep``: the merged vertex is the centroid of both balls' points."""
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


def _shortest_path(g: _Graph, a: int, b: int, budget: float) -> list[int] | None:
    """Shortest a -> b path (Dijkstra) no longer than ``budget``, not using the edge (a, b)."""
    import heapq

    dist = {a: 0.0}
    prev = {a: -1}
    heap = [(0.0, a)]
    done: set[int] = set()
    while heap:
        d, u = heapq.heappop(heap)
        if u in done:
            continue
        done.add(u)
        if u == b:
            path = [b]
            while path[-1] != a:
                path.append(prev[path[-1]])
            return path
        for w in sorted(g.adj[u]):
            if u == a and w == b:
                continue
            nd = d + g.length(u, w)
            if nd <= budget and nd < dist.get(w, np.inf):
                dist[w] = nd
                prev[w] = u
                heapq.heappush(heap, (nd, w))
    return None


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


def _short_cycle(g: _Graph, max_length: float) -> list[int] | None:
    """A cycle shorter than ``max_length`` (total edge length), as its vertex list, or None."""
    if max_length <= 0:
        return None
    for a in np.flatnonzero(g.alive):
        a = int(a)
        for b in sorted(g.adj[a]):
            if b > a:
                path = _shortest_path(g, a, b, max_length - g.length(a, b))
                if path is not None:
                    return path
    return None


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
    while True:
        report("curve", 0.8)
        cycle = _short_cycle(g, params.short_cycle_factor * radius)
        if cycle is None:
            break
        ring = list(zip(cycle, cycle[1:] + cycle[:1]))
        a, b = min(ring, key=lambda e: (g.length(*e), e))
        g.collapse(a, b)
        _collapse_triangles(g, report)
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


# ---------------------------------------------------------------------------------------------
# public entry point


def skeletonize(
    cloud: np.ndarray,
    params: SkeletonizeParams = SkeletonizeParams(),
    progress: Progress | None = None,
    cancel: Callable[[], bool] | None = None,
    *,
    return_info: bool = False,
):
    """Skeletonize a point cloud by Laplacian-based contraction (Cao et al. 2010).

    Parameters
    ----------
    cloud : (N, 3) points in the user's units (at least 10 distinct points).
    params : :class:`SkeletonizeParams`.
    progress : ``progress(fraction, stage)``; stages "laplacian", "contraction", "curve".
    cancel : returning True makes the next checkpoint raise :class:`~skelcore.errors.Cancelled`.
    return_info : also return a :class:`SkeletonizeInfo`.

    Returns
    -------
    skeletal : (N, 3) contracted points, row i is where cloud row i went (pointwise correspondence).
    curve : :class:`~skelcore.curve.CurveSkeleton` in the user's units.

    Examples
    --------
    >>> from skelcore import shapes
    >>> skeletal, curve = skeletonize(shapes.cylinder(2048).cloud)      # doctest: +SKIP
    >>> int(curve.degrees().max())                                       # doctest: +SKIP
    2
    """
    t0 = time.perf_counter()
    pts = as_points("cloud", cloud)
    if len(unique_rows(pts)[0]) < 10:
        raise SkelInputError("cloud: at least 10 distinct points are needed to skeletonize")
    norm = Normalization.from_cloud(pts, "longest_side", 1.6)
    pts_n = norm.apply(pts)
    report = _Reporter(progress, cancel)

    t = time.perf_counter()
    contracted, adj, info = contract(pts_n, params, report=report)
    t_contract = time.perf_counter() - t
    diag = float(np.linalg.norm(pts_n.max(axis=0) - pts_n.min(axis=0)))
    radius = params.sample_radius_factor * diag
    t = time.perf_counter()
    verts, edges, _labels = extract_curve(contracted, adj, radius, params, original_n=pts_n, report=report)
    t_curve = time.perf_counter() - t

    skeletal = norm.invert(contracted)
    curve = CurveSkeleton.from_raw(norm.invert(verts), edges)
    if not return_info:
        return skeletal, curve
    sk_info = SkeletonizeInfo(
        iterations=info["iterations"],
        ring_ratios=[float(r) for r in info["ring_ratios"]],
        stop_reason=info["stop_reason"],
        sample_radius=radius / norm.scale,
        n_samples=int(curve.n_vertices),
        timings={"contraction": t_contract, "curve": t_curve, "total": time.perf_counter() - t0},
    )
    return skeletal, curve, sk_info
