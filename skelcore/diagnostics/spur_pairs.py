"""The spur test's nearest-ball search (:func:`skelcore.diagnostics.spurs._explained_elsewhere`) when its
balls hold few points: each curve point's ball asked once of a tree of the queries, every pair found
tested as the level search tests it, so the answers are the same bits (docs/performance.md 3, "The
hammer"). On a small cloud this replaces the levels' k-nearest rounds (about two thirds of the test)."""

from __future__ import annotations

import itertools

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["explained_by_balls"]

#: at most this many (curve point, query) pairs inside the balls: beyond, the level search (less memory)
PAIRS_MAX = 1 << 18
#: and only when queries x curve points is at most this (counting the pairs is then cheap)
CELLS_MAX = 1 << 24
#: up to this many queries x curve points the pairs are listed without counting them first (the lists
#: then hold at most as many entries as a chunk of the level search, 2^20)
CELLS_LISTED = 1 << 20
#: balls smaller than this share of the largest (a curve point on a cloud point): the level search
TINY = 2.0**-40


def explained_by_balls(pts: np.ndarray, pts_branch: np.ndarray, reach: np.ndarray, queries: np.ndarray,
                       own: np.ndarray, tree: cKDTree | None = None) -> np.ndarray | None:
    """For each query q, whether a curve point x of another branch than ``own[q]`` has
    |q - x| <= reach(x) (the norm computed as the level search computes it); None when the balls hold
    more than ``PAIRS_MAX`` pairs or the search is too large to count them (the caller's search then).
    ``tree``: a KD-tree the caller has, used when its points are ``queries`` (the cloud's, when every
    cloud point is asked): any tree finds the same pairs, which the test below decides."""
    n = len(queries)
    if n == 0 or len(pts) * n > CELLS_MAX:
        return None
    idx = np.flatnonzero(np.isfinite(reach) & (reach >= 0))
    out = np.zeros(n, bool)
    if not len(idx):
        return out
    if reach[idx].min() < reach[idx].max() * TINY:
        return None  # the level search's bound underflows for such balls (a zero ball explains nothing there)
    # a little wider than the balls (the tree's squared distances round otherwise): the test below decides
    radius = reach[idx] * (1.0 + 1e-9) + 1e-300
    if tree is None or tree.n != n or not np.array_equal(tree.data, queries):
        tree = cKDTree(queries)
    found = None
    if len(idx) * n <= CELLS_LISTED:
        found = tree.query_ball_point(pts[idx], radius, return_sorted=False)
        counts = np.fromiter(map(len, found), np.int64, len(idx))
    else:  # counted first: the lists of PAIRS_MAX pairs at most
        counts = np.asarray(tree.query_ball_point(pts[idx], radius, return_length=True), np.int64)
    total = int(counts.sum())
    if total > PAIRS_MAX:
        return None
    if total == 0:
        return out
    if found is None:
        found = tree.query_ball_point(pts[idx], radius, return_sorted=False)
    qi = np.fromiter(itertools.chain.from_iterable(found), np.int64, count=total)  # no generator frame per pair
    xi = np.repeat(idx, counts)
    other = pts_branch[xi] != own[qi]
    xi, qi = xi[other], qi[other]
    dist = np.linalg.norm(pts[xi] - queries[qi], axis=1)
    out[qi[dist <= reach[xi]]] = True
    return out
