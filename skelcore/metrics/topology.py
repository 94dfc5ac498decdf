"""Topological similarity of a skeletal point set to its cloud (paper Sec. 2.1, Prop. 1; SPEC 1).

A good skeleton keeps the shape's connectivity, so the H0 barcodes of cloud and skeleton are compared:
eps* (paper Eq. 2, 0.99 quantile per SPEC 1) picks the K compared bars, then the bottleneck distance
(Eq. 3) and the 1-Wasserstein distance divided by K (Eq. 4).  The H0 barcode of a Vietoris-Rips
filtration is exactly the Euclidean minimum spanning tree's edge lengths plus one infinite bar; the
EMST is computed exactly by Boruvka's algorithm on k-nearest-neighbour lists (points whose list stays
inside their own component are resolved by exact searches), so no Delaunay triangulation is needed
(slow on surface samples, undefined on the collinear or coplanar sets that contraction produces).
All bars are born at 0, so both distances are one-dimensional matchings with the diagonal (cost d/2
for the bar (0, d)), solved exactly: W1 by a slope-trick dynamic programme, the bottleneck by a
Hall-condition test inside an exact bisection, both O(K log K).
Equations, departures from the paper and the reference tool: docs/metrics.md.
"""

from __future__ import annotations

import heapq
import os

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components, minimum_spanning_tree
from scipy.spatial import cKDTree

from ..geometry import (
    Checkpoint, chunked_query, kd_tree, leaf_order, matlab_round, nearest_neighbor_distances, no_checkpoint, take_rows,
    unique_rows,
)
from ..parallel import side_by_side
from ..params import Params
from ..results import TopologyResult

__all__ = [
    "topological_similarity",
    "h0_barcode",
    "eps_star",
    "compared_bar_count",
    "bottleneck_h0",
    "wasserstein_h0",
]

_LIST_K = 10  # neighbours kept per point for Boruvka; larger lists resolve more points, cost more memory
_DEEP_K = 64  # neighbours of the second, exact-search pass for points whose list stayed inside
_FEW_COMPONENTS = 32  # up to this many components with pending points skip the deep pass
_DEEP_MAX_POINTS = 4096  # ... as do more fresh pending points than this or n/8 (far-apart clusters)
_CELL_MAX = 2048  # points per cell of the exact per-component search
_THREADED_QUERY = 16384  # smaller KD-tree queries run single-threaded (thread start-up dominates)
_PROBE = 32  # pending points nearest to a component's box probed first for a tight bound
_QUERY_CHUNK = 16384  # points per kNN query call, so the checkpoint is reached often
_DEEP_CHUNK = 4096  # points per deep (k = 65) query between checkpoints: ~0.1 s at 1M points
_ROUND_CHUNK = 262144  # neighbour lists scanned per block of a Boruvka round, between checkpoints
_SIDE_BY_SIDE = 16384  # both point sets at least this big: the two barcodes on two threads


# ---------------------------------------------------------------------------------------------
# H0 barcode = EMST edge lengths
# ---------------------------------------------------------------------------------------------
def _as_points(points: np.ndarray) -> np.ndarray:
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"expected an (n, 3) array of points, got shape {pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise ValueError("points contain NaN or inf")
    return pts


def _first_other(labels: np.ndarray, rows: np.ndarray, dist: np.ndarray, idx: np.ndarray):
    """For each row, the first list entry (sorted by distance) in another component."""
    other = labels[idx] != labels[rows][:, None]
    has = other.any(axis=1)
    col = other.argmax(axis=1)
    r = np.arange(len(rows))
    return has, dist[r, col], idx[r, col]


def _emst_lengths(points: np.ndarray, checkpoint: Checkpoint = no_checkpoint) -> tuple[np.ndarray, np.ndarray]:
    """Edge lengths of the Euclidean minimum spanning tree of distinct points (Boruvka, exact),
    and each point's nearest-neighbour distance (a by-product, used for eps*).

    Each round finds, for every component, its shortest outgoing edge. A point's candidate is the
    first entry of its sorted neighbour list in another component (exact for that point: every
    closer point is in the list). A point whose whole list lies in its own component keeps a lower
    bound (all points closer than it are in its component, which stays true as components merge);
    only if that bound is below its component's best candidate does an exact search settle it (a
    deeper kNN pass once per point, then KD-trees of the nearest other components, pruned by
    bounding boxes). Ties only ever form cycles of equal-length edges, which the MST over the
    chosen edges drops, so the multiset of lengths is exact.
    """
    n = len(points)
    if n < 2:
        return np.empty(0), np.zeros(n)
    tree = kd_tree(points, checkpoint)
    checkpoint(0.02)
    k = min(_LIST_K, n - 1)
    # the points are renumbered in the tree's leaf order, so that queries and every later gather
    # (labels[idx], cells) touch memory that spatial neighbours share; ``rank`` maps tree answers
    perm = leaf_order(tree)
    rank = np.empty(n, np.int64)
    rank[perm] = np.arange(n)
    points = take_rows(points, perm)
    dist, idx = chunked_query(tree, points, k + 1, checkpoint, 0.02, 0.5, chunk=_QUERY_CHUNK)
    for lo in range(0, n, _ROUND_CHUNK):  # back to leaf-order numbers, in blocks between checkpoints
        idx[lo : lo + _ROUND_CHUNK] = np.take(rank, idx[lo : lo + _ROUND_CHUNK])
        checkpoint(0.5)
    dist, idx = dist[:, 1:], idx[:, 1:]  # column 0 is the point itself (points are distinct)
    lower = dist[:, -1].copy()  # every point closer than this is in the point's own component
    deep_done = np.zeros(n, bool)
    lists_complete = k == n - 1
    # cells: compact groups of points (a component, until it grows past _CELL_MAX points, then
    # frozen) whose bounding boxes prune the exact searches; ids are never reused, so each cell's
    # KD-tree can be cached across rounds
    cells = np.arange(n)
    next_cell = n
    cell_trees: dict[int, tuple[np.ndarray, cKDTree]] = {}
    labels = np.arange(n)
    n_comp = n
    active = np.ones(n, bool)  # a list wholly inside its component stays so: never scanned again
    lengths: list[np.ndarray] = []
    while n_comp > 1:
        done = 0.5 + 0.5 * (1.0 - n_comp / n) ** 0.5
        rows = np.flatnonzero(active)
        parts = []
        for lo in range(0, len(rows), _ROUND_CHUNK):  # the first rounds scan every list: in blocks
            r = rows[lo : lo + _ROUND_CHUNK]
            parts.append(_first_other(labels, r, dist[r], idx[r]))
            checkpoint(done)
        if parts:
            has, cd, cb = (np.concatenate(x) for x in zip(*parts))
        else:
            has, cd, cb = np.zeros(0, bool), np.empty(0), np.empty(0, np.int64)
        active[rows[~has]] = False
        cand_a, cand_b, cand_d = rows[has], cb[has], cd[has]
        best = np.full(n_comp, np.inf)
        np.minimum.at(best, labels[cand_a], cand_d)
        checkpoint(done)

        if not lists_complete:
            pend = np.flatnonzero(~active)
            pend = pend[lower[pend] < best[labels[pend]]]
            if len(pend):
                ea, eb, ed = _resolve_pending(
                    points, tree, rank, labels, pend, best, lower, deep_done, cells, cell_trees,
                    lambda: checkpoint(done),
                )
                cand_a = np.concatenate([cand_a, ea])
                cand_b = np.concatenate([cand_b, eb])
                cand_d = np.concatenate([cand_d, ed])
                checkpoint(done)

        # one shortest candidate per component (``best`` holds each component's minimum), then
        # one edge per component pair: two components choosing each other pick equal lengths
        la = labels[cand_a]
        hit = np.flatnonzero(cand_d == best[la])
        pick = np.full(n_comp, -1)
        pick[la[hit]] = hit
        if np.any(pick < 0):  # cannot happen: every component has an outgoing edge
            raise RuntimeError("EMST: a component found no outgoing edge")
        u = np.arange(n_comp)
        v = labels[cand_b[pick]]
        w = cand_d[pick]
        keep = ~((v[v] == u) & (u > v))
        graph = coo_matrix((w[keep], (u[keep], v[keep])), shape=(n_comp, n_comp)).tocsr()
        checkpoint(done)
        forest = minimum_spanning_tree(graph)
        lengths.append(forest.data.copy())
        checkpoint(done)
        n_new, comp = connected_components(forest, directed=False)
        checkpoint(done)
        if n_new >= n_comp:  # cannot happen: every component has an outgoing edge
            raise RuntimeError("EMST: Boruvka round made no progress")
        labels = comp[labels]
        n_comp = n_new
        small = np.bincount(labels, minlength=n_comp)[labels] <= _CELL_MAX
        cells[small] = next_cell + labels[small]
        next_cell += n_comp
        checkpoint(0.5 + 0.5 * (1.0 - n_comp / n) ** 0.5)
    nn = np.empty(n)
    nn[perm] = dist[:, 0]  # back to the caller's numbering
    return (np.concatenate(lengths) if lengths else np.empty(0)), nn


def _resolve_pending(points, tree, rank, labels, pend, best, lower, deep_done, cells, cell_trees, tick):
    """Exact shortest outgoing edges for points whose neighbour list lies inside their component.

    ``points`` are numbered in leaf order, ``tree`` (built on the caller's order) answers in its
    own numbering, mapped by ``rank``.  ``best`` (per component), ``lower``/``deep_done`` (per
    point) and the cell KD-tree cache are updated in place; ``tick()`` reports progress (and may raise ``Cancelled``).
    Returns candidate edges (a, b, length) improving on the components' list candidates.
    """
    n = len(points)
    out_a, out_b, out_d = [], [], []
    # 1) many components involved: one deeper kNN pass (vectorized), at most once per point
    kk = min(_DEEP_K, n - 1)
    fresh = pend[~deep_done[pend]]
    many = len(np.unique(labels[pend])) > _FEW_COMPONENTS
    if kk > _LIST_K and 0 < len(fresh) <= max(_DEEP_MAX_POINTS, n // 8) and many:
        if len(fresh) > _DEEP_CHUNK:  # chunked, so a cancel is seen within ~0.1 s
            d2, i2 = chunked_query(tree, points[fresh], kk + 1, lambda _f: tick(), chunk=_DEEP_CHUNK)
        else:
            d2, i2 = tree.query(points[fresh], k=kk + 1, workers=1)
        i2 = rank[i2]  # the tree numbers points as given, ``points`` is in leaf order
        d2, i2 = d2[:, 1:], i2[:, 1:]
        has, cd, cb = _first_other(labels, fresh, d2, i2)
        deep_done[fresh] = True
        lower[fresh] = np.maximum(lower[fresh], np.where(has, cd, d2[:, -1]))
        ok = has & (cd < best[labels[fresh]])
        if ok.any():
            out_a.append(fresh[ok]), out_b.append(cb[ok]), out_d.append(cd[ok])
            np.minimum.at(best, labels[fresh[ok]], cd[ok])
        pend = pend[lower[pend] < best[labels[pend]]]
    # 2) per cell of pending points: KD-trees of other components' cells, nearest boxes first
    if len(pend):
        ids, cell_of = np.unique(cells, return_inverse=True)
        tick()
        for stale in set(cell_trees) - set(ids.tolist()):
            del cell_trees[stale]
        by_cell = np.argsort(cell_of, kind="stable")
        tick()
        starts = np.searchsorted(cell_of[by_cell], np.arange(len(ids) + 1))
        sorted_pts = points[by_cell]
        box_lo = np.minimum.reduceat(sorted_pts, starts[:-1], axis=0)
        box_hi = np.maximum.reduceat(sorted_pts, starts[:-1], axis=0)
        tick()
        cell_comp = labels[by_cell[starts[:-1]]]

        def cell_tree(y: int) -> tuple[np.ndarray, cKDTree]:
            key = int(ids[y])
            if key not in cell_trees:
                members = by_cell[starts[y] : starts[y + 1]]
                cell_trees[key] = (members, cKDTree(points[members]))
            return cell_trees[key]

        pc = cell_of[pend]
        order = np.lexsort((pc, labels[pend]))
        pend, pc = pend[order], pc[order]
        group = np.flatnonzero(np.r_[True, pc[1:] != pc[:-1]])
        for n_done, (s, e) in enumerate(zip(group, np.r_[group[1:], len(pend)])):
            if n_done % 64 == 63:
                tick()  # progress and cancel between cells
            q = pend[s:e]
            c = int(labels[q[0]])
            qp = points[q]
            qlo, qhi = qp.min(axis=0), qp.max(axis=0)
            gap = np.maximum(0.0, np.maximum(box_lo - qhi, qlo - box_hi))
            box_d = np.sqrt(np.einsum("ij,ij->i", gap, gap))
            box_d[cell_comp == c] = np.inf
            near = [int(np.argmin(box_d))] if not np.isfinite(best[c]) else []  # a finite bound first
            for stage in (0, 1):
                if stage == 1:
                    cand = np.flatnonzero(box_d < best[c])
                    near = cand[np.argsort(box_d[cand], kind="stable")].tolist()
                for y in near:
                    if not box_d[y] < best[c]:
                        break
                    members, t = cell_tree(y)
                    # only pending points closer to the other box than the bound can improve;
                    # probing the nearest few first tightens the bound cheaply
                    g = np.maximum(0.0, np.maximum(box_lo[y] - qp, qp - box_hi[y]))
                    to_box = np.sqrt(np.einsum("ij,ij->i", g, g))
                    sel = np.flatnonzero(to_box < best[c])
                    if len(sel) > 4 * _PROBE:
                        steps = (sel[np.argpartition(to_box[sel], _PROBE)[:_PROBE]], None)
                    else:
                        steps = (sel,)
                    for part in steps:
                        if part is None:
                            part = sel[to_box[sel] < best[c]]
                        if not len(part):
                            continue
                        workers = -1 if len(part) > _THREADED_QUERY else 1  # threads cost more on small
                        dq, jq = t.query(qp[part], k=1, distance_upper_bound=best[c], workers=workers)
                        i = int(np.argmin(dq))
                        if dq[i] < best[c]:
                            a, b = int(q[part[i]]), int(members[jq[i]])
                            best[c] = dq[i]
                            out_a.append([a]), out_b.append([b]), out_d.append([dq[i]])
                            if dq[i] < best[labels[b]]:  # the same edge also leaves b's component
                                best[labels[b]] = dq[i]
                                out_a.append([b]), out_b.append([a]), out_d.append([dq[i]])
    if not out_a:
        empty = np.empty(0, np.int64)
        return empty, empty, np.empty(0)
    return (
        np.concatenate(out_a).astype(np.int64),
        np.concatenate(out_b).astype(np.int64),
        np.concatenate(out_d).astype(float),
    )


def _barcode_and_nn(points: np.ndarray, checkpoint: Checkpoint) -> tuple[np.ndarray, np.ndarray]:
    """H0 barcode (see :func:`h0_barcode`) and every point's nearest-neighbour distance (0 for a
    duplicate), from one kNN pass."""
    if len(points) == 0:
        return np.empty((0, 2)), np.empty(0)
    checkpoint(0.0)
    uniq, inverse, counts = unique_rows(points, checkpoint)
    checkpoint(0.02)
    lengths, nn_unique = _emst_lengths(uniq, lambda f: checkpoint(0.02 + 0.96 * f))
    checkpoint(0.98)
    deaths = np.sort(lengths)[::-1]
    deaths = deaths[deaths > 0]
    bars = np.zeros((len(deaths) + 1, 2))
    bars[0, 1] = np.inf
    bars[1:, 1] = deaths
    nn = np.where(counts[inverse] > 1, 0.0, nn_unique[inverse])
    checkpoint(1.0)
    return bars, nn


def h0_barcode(points: np.ndarray, *, checkpoint: Checkpoint = no_checkpoint) -> np.ndarray:
    """H0 barcode of the Vietoris-Rips filtration of ``points`` (SPEC 1).

    Returns an (n, 2) array of (birth = 0, death) rows, longest first: the infinite bar, then one
    bar per EMST edge of the distinct points (full edge lengths). Duplicate points would give
    zero-length bars, which are dropped as gudhi does; one point (or all coincident) gives only
    the infinite bar; no points gives an empty (0, 2) array.

    Examples
    --------
    >>> h0_barcode(np.array([[0., 0, 0], [1, 0, 0], [3, 0, 0]]))[:, 1]
    array([inf,  2.,  1.])
    """
    return _barcode_and_nn(_as_points(points), checkpoint)[0]


# ---------------------------------------------------------------------------------------------
# eps* and the number of compared bars
# ---------------------------------------------------------------------------------------------
def eps_star(cloud: np.ndarray, quantile: float = 0.99) -> float:
    """SPEC 1: the ``quantile`` of the cloud's nearest-neighbour distances, as MATLAB's ``prctile``
    (numpy ``method="hazen"``); quantile 1.0 is the paper's maximum."""
    if not 0.0 < quantile <= 1.0:
        raise ValueError(f"quantile must be in (0, 1], got {quantile}")
    return _quantile(nearest_neighbor_distances(_as_points(cloud)), quantile)


def _quantile(nn: np.ndarray, quantile: float) -> float:
    return float(np.quantile(nn, quantile, method="hazen")) if len(nn) else 0.0


def compared_bar_count(cloud_barcode: np.ndarray, eps: float, n_cloud: int, *, params: Params = Params()) -> int:
    """SPEC 1: K = bars of the cloud with persistence > eps* (the infinite bar counts); if
    K < min_bar_fraction * N_o, the reference tool's fallback K = N_o - round(0.95 N_o) + 1."""
    bars = np.asarray(cloud_barcode, dtype=float).reshape(-1, 2)
    k = int(np.count_nonzero(bars[:, 1] - bars[:, 0] > eps))
    if k < params.min_bar_fraction * n_cloud:
        k = int(n_cloud - matlab_round(params.fallback_fraction * n_cloud) + 1)
    return k


# ---------------------------------------------------------------------------------------------
# distances between H0 diagrams (all births 0)
# ---------------------------------------------------------------------------------------------
def _split_deaths(diagram: np.ndarray) -> tuple[np.ndarray, int]:
    """Finite deaths (sorted ascending) and the number of infinite bars of an H0 diagram.

    Accepts an (n, 2) barcode with births 0 or a 1-D array of deaths.
    """
    arr = np.asarray(diagram, dtype=float)
    if arr.ndim == 2:
        if arr.shape[1] != 2:
            raise ValueError(f"expected an (n, 2) barcode, got shape {arr.shape}")
        if len(arr) and np.any(arr[:, 0] != 0):
            raise ValueError("H0 diagram distances need every bar born at 0")
        arr = arr[:, 1]
    elif arr.ndim != 1:
        raise ValueError(f"expected an (n, 2) barcode or 1-D deaths, got shape {arr.shape}")
    if np.any(np.isnan(arr)) or np.any(arr < 0):
        raise ValueError("deaths must be >= 0 and not NaN")
    inf = np.isposinf(arr)
    return np.sort(arr[~inf]), int(inf.sum())


def wasserstein_h0(a: np.ndarray, b: np.ndarray) -> float:
    """Exact 1-Wasserstein distance (L-infinity ground metric) between two H0 diagrams.

    Matching (0, x) to (0, y) costs |x - y|, sending (0, x) to the diagonal costs x / 2; infinite
    bars match each other at cost 0 (a different number of them gives inf, as gudhi). Matched pairs
    can be taken in sorted order, so the optimum is a dynamic programme over the merged sorted deaths
    whose state is the running imbalance F (matched x's minus matched y's so far). Its value is
    convex in F and each step (add gap * |F|; keep or match the next point) preserves convexity, so
    the slope sequence is kept in two heaps split at F = 0 (slope trick): O(K log K), exact.
    Not divided by the number of bars (``topological_similarity`` does that: d_Wp = W1 / K).
    """
    xa, ia = _split_deaths(a)
    xb, ib = _split_deaths(b)
    if ia != ib:
        return float("inf")
    if np.array_equal(xa, xb):  # identical diagrams: exactly 0 (the heaps' sums would round)
        return 0.0
    events = np.concatenate([xa, xb])
    side = np.concatenate([np.zeros(len(xa), bool), np.ones(len(xb), bool)])
    order = np.argsort(events, kind="stable")
    left: list[float] = []  # max-heap (negated) of slopes s(F) for F < 0, stored minus add_left
    right: list[float] = []  # min-heap of slopes for F >= 0, stored minus add_right
    add_left = add_right = 0.0
    sum_left = 0.0  # sum of stored values in ``left`` (actual sum = sum_left + add_left * len)
    g_lo = 0.0  # value of the convex function at its leftmost point lo
    lo = 0
    z_prev = 0.0
    for e in order.tolist():
        z = float(events[e])
        gap = z - z_prev
        z_prev = z
        if gap:
            add_left -= gap
            add_right += gap
            g_lo += gap * (-lo)
        c = z / 2.0
        if not side[e]:  # a point of ``a``: g'(F) = min(g(F) + c, g(F - 1)) inserts slope -c
            g_lo += c
            s = -c
            if left and s < -left[0] + add_left:
                top = -heapq.heappushpop(left, -(s - add_left)) + add_left
                sum_left += (s - add_left) - (top - add_left)
                heapq.heappush(right, top - add_right)
            else:
                heapq.heappush(right, s - add_right)
        else:  # a point of ``b``: g'(F) = min(g(F) + c, g(F + 1)) inserts slope +c, lo -= 1
            lo -= 1
            s = c
            if right and s > right[0] + add_right:
                low = heapq.heappushpop(right, s - add_right) + add_right
            else:
                low = s
            heapq.heappush(left, -(low - add_left))
            sum_left += low - add_left
    return max(0.0, float(g_lo + sum_left + add_left * len(left)))  # a distance: rounding never < 0


def _hall_ok(must: np.ndarray, other: np.ndarray, t: float) -> bool:
    """Can every point of sorted ``must`` be matched to a distinct point of sorted ``other`` within t?

    Neighbourhoods are intervals of equal width, so Hall's condition only needs contiguous runs
    must[i..j]: #other in [must_i - t, must_j + t] >= j - i + 1.
    """
    if len(must) == 0:
        return True
    j = np.arange(len(must))
    upper = j + 1 - np.searchsorted(other, must + t, side="right")
    lower = j - np.searchsorted(other, must - t, side="left")
    return bool(np.all(upper <= np.minimum.accumulate(lower)))


def _bottleneck_feasible(xa: np.ndarray, xb: np.ndarray, t: float) -> bool:
    # Points within 2t of 0 may go to the diagonal; the others need a partner within t. Matchings
    # covering each side's required points exist separately iff one covers both (Mendelsohn-Dulmage).
    return _hall_ok(xa[xa > 2 * t], xb, t) and _hall_ok(xb[xb > 2 * t], xa, t)


def bottleneck_h0(a: np.ndarray, b: np.ndarray) -> float:
    """Exact bottleneck distance (L-infinity ground metric) between two H0 diagrams.

    Same costs as :func:`wasserstein_h0`. The answer is one of x/2, y/2 or |x - y|; feasibility of
    a threshold is a Hall-condition test; bisection over floats brackets the optimum to one ulp and
    the nearest candidate value is returned, so the result is exact.
    """
    xa, ia = _split_deaths(a)
    xb, ib = _split_deaths(b)
    if ia != ib:
        return float("inf")
    if len(xa) == 0 and len(xb) == 0:
        return 0.0
    hi = max(xa[-1] if len(xa) else 0.0, xb[-1] if len(xb) else 0.0) / 2.0  # all to the diagonal
    lo = 0.0
    if _bottleneck_feasible(xa, xb, lo):
        return 0.0
    for _ in range(200):
        mid = (lo + hi) / 2.0
        if mid <= lo or mid >= hi:
            break
        if _bottleneck_feasible(xa, xb, mid):
            hi = mid
        else:
            lo = mid
    # snap to the nearest candidate value (exactly computed) to remove bisection rounding
    cands = [xa / 2.0, xb / 2.0]
    for x, y in ((xa, xb), (xb, xa)):
        if len(x) and len(y):
            for target in (x - hi, x + hi):
                pos = np.clip(np.searchsorted(y, target), 0, len(y) - 1)
                for p in (pos, np.maximum(pos - 1, 0)):
                    cands.append(np.abs(x - y[p]))
    cands = np.concatenate(cands)
    best = cands[np.argmin(np.abs(cands - hi))]
    return float(best) if abs(best - hi) <= 1e-12 * max(hi, 1e-300) + 1e-300 else float(hi)


# ---------------------------------------------------------------------------------------------
# the metric
# ---------------------------------------------------------------------------------------------
def topological_similarity(
    cloud: np.ndarray,
    skeletal: np.ndarray,
    *,
    params: Params = Params(),
    checkpoint: Checkpoint = no_checkpoint,
) -> TopologyResult:
    """Bottleneck and normalized 1-Wasserstein distances between the K longest H0 bars of the
    cloud and of the skeletal point set (SPEC 1; both inputs already normalized, SPEC 0).

    K comes from :func:`compared_bar_count`; a diagram with fewer than K bars is compared whole;
    d_Wp = W1 / K. Barcodes and eps* are returned in normalized units, every bar included.
    """
    cloud = _as_points(cloud)
    skeletal = _as_points(skeletal)
    if len(cloud) == 0 or len(skeletal) == 0:
        raise ValueError("topological similarity needs a non-empty cloud and skeletal point set")
    # the two barcodes are independent: the skeletal set's on a second thread (numpy and the KD-tree
    # release the GIL), when both are big enough to be worth it (docs/performance.md 6)
    if min(len(cloud), len(skeletal)) >= _SIDE_BY_SIDE and (os.cpu_count() or 1) > 1:
        (cloud_bars, cloud_nn), (skel_bars, _) = side_by_side(
            lambda ck: _barcode_and_nn(cloud, ck), lambda ck: _barcode_and_nn(skeletal, ck),
            lambda f: checkpoint(0.9 * f),
        )
    else:
        cloud_bars, cloud_nn = _barcode_and_nn(cloud, lambda f: checkpoint(0.45 * f))
        skel_bars, _ = _barcode_and_nn(skeletal, lambda f: checkpoint(0.45 + 0.45 * f))
    eps = _quantile(cloud_nn, params.eps_quantile)  # = eps_star(cloud, quantile), without a new kNN
    k = compared_bar_count(cloud_bars, eps, len(cloud), params=params)
    checkpoint(0.92)
    a, b = cloud_bars[:k], skel_bars[:k]
    d_b = bottleneck_h0(a, b)
    checkpoint(0.96)
    d_w = wasserstein_h0(a, b) / k
    checkpoint(1.0)
    return TopologyResult(
        bottleneck=float(d_b),
        wasserstein=float(d_w),
        eps_star=eps,
        n_bars=int(k),
        cloud_barcode=cloud_bars,
        skeletal_barcode=skel_bars,
    )
