"""Topological similarity of a skeletal point set to its cloud (paper Sec. 2.1, Prop. 1; docs/metrics.md 1).

A good skeleton keeps the shape's connectivity, so the H0 barcodes of cloud and skeleton are compared:
eps* (paper Eq. 2, 0.99 quantile per docs/metrics.md 1) picks the K compared bars, then the bottleneck distance
(Eq. 3) and the 1-Wasserstein distance divided by K (Eq. 4).  The H0 barcode of a Vietoris-Rips
filtration is exactly the Euclidean minimum spanning tree's edge lengths plus one infinite bar; the
EMST is computed exactly by Boruvka's algorithm over a KD-tree in compiled code (``_emst.c``), so no
Delaunay triangulation is needed (slow on surface samples, undefined on the collinear or coplanar sets
that contraction produces).
All bars are born at 0, so both distances are one-dimensional matchings with the diagonal (cost d/2
for the bar (0, d)), solved exactly: W1 by a slope-trick dynamic programme, the bottleneck by a
Hall-condition test inside an exact bisection, both O(K log K).
Equations, departures from the paper and the reference tool: docs/metrics.md.
"""

from __future__ import annotations

import heapq
import os
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..geometry import Checkpoint, matlab_round, nearest_neighbor_distances, no_checkpoint, unique_rows
from ..parallel import polled_build
from ..params import Params
from . import _emst
from .position_knn import published_others

__all__ = [
    "TopologyResult",
    "topological_similarity",
    "h0_barcode",
    "eps_star",
    "compared_bar_count",
    "bottleneck_h0",
    "wasserstein_h0",
]

_THREADED_EMST = 16384  # smaller sets: the kernel runs on this thread (a few ms, no polling needed)
_FIRST_ROUND = 6  # neighbours per point of the kernel's first round (KNN in _emst.c)


@dataclass
class TopologyResult:
    """docs/metrics.md 1: barcodes are (n, 2) arrays of (birth, death) in normalized units, longest first,
    the infinite bar first with death = inf; every bar, not only the K compared ones."""

    bottleneck: float
    wasserstein: float
    eps_star: float
    n_bars: int
    cloud_barcode: np.ndarray
    skeletal_barcode: np.ndarray


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


def _emst_lengths(points: np.ndarray, checkpoint: Checkpoint = no_checkpoint,
                  first: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Edge lengths of the Euclidean minimum spanning tree of distinct points (Boruvka over a KD-tree,
    exact; compiled in ``_emst.c``), and each point's nearest-neighbour distance (its first round, used
    for eps*).

    The kernel runs in a helper thread (all cores for its searches) while this thread calls the
    checkpoint every 50 ms with the share of components merged; a cancel stops it within one block of
    1024 searches.  The lengths do not depend on the number of threads (docs/performance.md 6.1).
    ``first``: each point's 6 nearest other points (rows, nearest first) from another search, the first
    round's lists instead of its own searches; the same bits either way (the rounds verify candidates).
    """
    n = len(points)
    if n < 2:
        return np.empty(0), np.zeros(n)
    pts = np.ascontiguousarray(points, dtype=np.float64)
    lengths = np.empty(n - 1)
    nn = np.empty(n)
    components = np.array([n], np.int64)
    threads = os.cpu_count() or 1
    if first is not None:
        first = np.ascontiguousarray(first, dtype=np.int32)
        if first.shape != (n, _FIRST_ROUND):
            first = None

    def merged() -> float:
        return (1.0 - float(components[0]) / n) ** 0.5

    m = polled_build(lambda stop: _emst.emst(pts, lengths, nn, stop, components, threads, first), n, checkpoint,
                     "skelscope-emst", _THREADED_EMST, progress=merged)
    if m != n - 1:  # cannot happen: every round merges, and a cancel is raised by polled_build's checkpoint
        raise RuntimeError(f"EMST: {m} edges for {n} points")
    return lengths, nn


def _barcode_and_nn(points: np.ndarray, checkpoint: Checkpoint,
                    shared: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """H0 barcode (see :func:`h0_barcode`) and every point's nearest-neighbour distance (0 for a
    duplicate), from one kNN pass; ``shared``: the first round from the distinct positions' neighbours
    that centeredness published (:mod:`.position_knn`), when it has."""
    if len(points) == 0:
        return np.empty((0, 2)), np.empty(0)
    checkpoint(0.0)
    uniq, inverse, counts = unique_rows(points, checkpoint)
    checkpoint(0.02)
    first = published_others(uniq, _FIRST_ROUND) if shared else None
    lengths, nn_unique = _emst_lengths(uniq, lambda f: checkpoint(0.02 + 0.96 * f), first)
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
    """H0 barcode of the Vietoris-Rips filtration of ``points`` (docs/metrics.md 1).

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
    """docs/metrics.md 1: the ``quantile`` of the cloud's nearest-neighbour distances, as MATLAB's ``prctile``
    (numpy ``method="hazen"``); quantile 1.0 is the paper's maximum."""
    if not 0.0 < quantile <= 1.0:
        raise ValueError(f"quantile must be in (0, 1], got {quantile}")
    return _quantile(nearest_neighbor_distances(_as_points(cloud)), quantile)


def _quantile(nn: np.ndarray, quantile: float) -> float:
    return float(np.quantile(nn, quantile, method="hazen")) if len(nn) else 0.0


def compared_bar_count(cloud_barcode: np.ndarray, eps: float, n_cloud: int, *, params: Params = Params()) -> int:
    """docs/metrics.md 1: K = bars of the cloud with persistence > eps* (the infinite bar counts); if
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
    if _bottleneck_feasible(xa, xb, 0.0):
        return 0.0
    least = _least_feasible(xa, xb, hi)
    if least is None:
        hi = _bisection_end(hi, lambda t: _bottleneck_feasible(xa, xb, t))
    else:
        hi = _bisection_end(hi, lambda t: t >= least)
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


def _bisection_end(hi: float, feasible: Callable[[float], bool]) -> float:
    """The bisection over floats from (0, ``hi``] (``hi`` feasible, 0 not): where its upper end stops."""
    lo = 0.0
    for _ in range(200):
        mid = (lo + hi) / 2.0
        if mid <= lo or mid >= hi:
            break
        if feasible(mid):
            hi = mid
        else:
            lo = mid
    return hi


def _least_feasible(xa: np.ndarray, xb: np.ndarray, hi: float) -> float | None:
    """The least float t with ``_bottleneck_feasible(xa, xb, t)``, when it is one of the likely
    candidates (each death / 2, each death's distance to the two nearest of the other diagram), else
    None.

    Feasibility is monotone in t (a larger t drops a prefix of the points that must be matched and
    widens every interval, also in rounded arithmetic), so the bisection's every answer is ``mid >=
    t``: the same end as asking the Hall test, in about 15 tests instead of about 55 (the test is
    most of the bottleneck's Python time; docs/performance.md 3, "The hammer's Python stages, cut")."""
    cands = [xa / 2.0, xb / 2.0, np.array([hi])]
    for x, y in ((xa, xb), (xb, xa)):
        if len(x) and len(y):
            pos = np.searchsorted(y, x)
            for p in (np.minimum(pos, len(y) - 1), np.maximum(pos - 1, 0)):
                cands.append(np.abs(x - y[p]))
    cands = np.unique(np.concatenate(cands))
    cands = cands[(cands > 0.0) & (cands <= hi)]
    lo_i, hi_i = -1, len(cands) - 1  # cands[hi_i] is feasible (hi is), cands[lo_i] not (or none)
    while hi_i - lo_i > 1:
        mid = (lo_i + hi_i) // 2
        if _bottleneck_feasible(xa, xb, float(cands[mid])):
            hi_i = mid
        else:
            lo_i = mid
    least = float(cands[hi_i])
    below = float(np.nextafter(least, 0.0))
    if below > 0.0 and _bottleneck_feasible(xa, xb, below):
        return None  # the least feasible float lies below this candidate: not one of these
    return least


# ---------------------------------------------------------------------------------------------
# the metric
# ---------------------------------------------------------------------------------------------
def topological_similarity(
    cloud: np.ndarray,
    skeletal: np.ndarray,
    *,
    params: Params = Params(),
    checkpoint: Checkpoint = no_checkpoint,
    cloud_spacings: Callable[[np.ndarray], None] | None = None,
) -> TopologyResult:
    """Bottleneck and normalized 1-Wasserstein distances between the K longest H0 bars of the
    cloud and of the skeletal point set (docs/metrics.md 1; both inputs already normalized, docs/metrics.md 0).

    K comes from :func:`compared_bar_count`; a diagram with fewer than K bars is compared whole;
    d_Wp = W1 / K. Barcodes and eps* are returned in normalized units, every bar included.
    ``cloud_spacings`` is called with each cloud row's distance to its nearest other row (0 for a copy;
    the EMST's first round, the bits of the coverage kernel's search) as soon as they are known, so the
    cloud's shared index need not search them again (docs/performance.md 6.6).
    """
    cloud = _as_points(cloud)
    skeletal = _as_points(skeletal)
    if len(cloud) == 0 or len(skeletal) == 0:
        raise ValueError("topological similarity needs a non-empty cloud and skeletal point set")
    # one after the other: each EMST's searches use every core (docs/performance.md 6.1)
    cloud_bars, cloud_nn = _barcode_and_nn(cloud, lambda f: checkpoint(0.45 * f))
    if cloud_spacings is not None:
        cloud_spacings(cloud_nn)
    skel_bars, _ = _barcode_and_nn(skeletal, lambda f: checkpoint(0.45 + 0.45 * f), shared=True)
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
