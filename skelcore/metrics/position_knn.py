"""The k-d tree of a skeletal set's distinct positions and the head of each position's neighbour list,
shared by skeletal centeredness and smoothness (docs/performance.md 6.4).

Both stages ask every distinct position for its nearest positions in the same tree: centeredness for
k_center (30 at 1M points), smoothness for tangent_k + 1 (9).  The first k answers of a query are
fixed by the tree alone once their distances strictly increase up to the (k + 1)-th, so a row that
centeredness has answered needs no second query for smoothness; a row with equal distances there is
asked again (scipy orders ties by its own search).  One index is kept, for the last array of distinct
positions (``unique_rows``' read-only answer) while that array lives; smoothness closes it when done.
Its tree is :class:`ExactKnn`: the compiled kNN of ``_emst.c``, scipy's answers where distances fix them.
"""

from __future__ import annotations

import threading
import weakref

import numpy as np
from scipy.spatial import cKDTree

from ..geometry import Checkpoint, kd_tree, leaf_order, no_checkpoint
from ..parallel import polled_build
from . import _emst

__all__ = ["ExactKnn", "PositionNeighbours", "position_neighbours", "published_others", "HEAD", "SHARED_FROM"]

#: neighbour columns kept per position (smoothness asks for tangent_k + 1 = 9 by default)
HEAD = 10
# from this many distinct positions the index is shared: on the hammer (4,096) the compiled kNN and the
# reused heads cut centeredness + smoothness from 36 to 25 CPU ms (docs/performance.md 3, "The hammer's
# Python stages, cut"); below, a query takes well under a millisecond
SHARED_FROM = 1024


class ExactKnn:
    """``cKDTree.query``'s answers (distances and indices, nearest first) from the compiled kNN of
    ``_emst.c`` (docs/performance.md 6.4): about 1.7 x less CPU for k = 30 at 1M points.  The kernel
    asks k + 1 neighbours, squared distances summed as cKDTree sums them; a row whose k + 1 squared
    distances are all distinct has scipy's answer by its distances alone, a row with equal ones (a tie
    scipy orders by its own search, or at the k-th, picks) is asked of ``geometry.kd_tree`` of the same
    points, built at the first such row.  ``indices``: the kernel's leaf order (cache-warm visits)."""

    def __init__(self, points: np.ndarray, handle: object):
        self.points = points
        self._handle = handle
        self._scipy: cKDTree | None = None
        self._lock = threading.Lock()
        self.indices = np.empty(len(points), np.int64)
        _emst.knn_order(handle, self.indices)

    @classmethod
    def build(cls, points: np.ndarray, checkpoint: Checkpoint = no_checkpoint,
              fraction: float = 0.0) -> "ExactKnn | None":
        """The kernel's tree of finite ``points`` (n, 3), a cancel seen while it builds; None otherwise."""
        pts = np.ascontiguousarray(points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) == 0 or not np.isfinite(pts).all():
            return None
        handle = polled_build(lambda stop: _emst.knn_tree(pts, stop), len(pts), lambda f: checkpoint(fraction),
                              "kNN tree build")
        return None if handle is None else cls(pts, handle)

    def scipy_tree(self) -> cKDTree:
        """``geometry.kd_tree`` of the points (rows with equal distances are its answers), built once."""
        with self._lock:
            if self._scipy is None:
                self._scipy = kd_tree(self.points)
            return self._scipy

    def query(self, x: np.ndarray, k: int = 1, workers: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """``cKDTree(points).query(x, k, workers=workers)`` with ``kd_tree``'s answers, the same bits."""
        x = np.ascontiguousarray(x, dtype=np.float64)
        n = len(self.points)
        if k < 2 or k > min(n, 255) or x.ndim != 2 or x.shape[1] != 3 or not np.isfinite(x).all():
            return self.scipy_tree().query(x, k=k, workers=workers)
        kq = min(k + 1, n)  # one more: the k-th must be strictly nearer than the next
        dist, idx = np.empty((len(x), kq)), np.empty((len(x), kq), np.int64)
        unsure = np.empty(len(x), np.uint8)
        flagged = _emst.knn_query(self._handle, x, kq, dist, idx, unsure)
        dist, idx = dist[:, :k], idx[:, :k]
        if flagged:
            rows = np.flatnonzero(unsure)
            dist[rows], idx[rows] = self.scipy_tree().query(x[rows], k=k, workers=workers)
        return np.ascontiguousarray(dist), np.ascontiguousarray(idx)


class PositionNeighbours:
    """One array of distinct positions: its tree (built once, under a lock) and, per position, the
    first ``HEAD`` neighbour indices published by a query of more neighbours, with how many leading
    columns their distances fix (``sure``; 0 = not published)."""

    def __init__(self, n: int):
        self._tree: tuple[ExactKnn | cKDTree, np.ndarray] | None = None
        self._build = threading.Lock()
        self._table = threading.Lock()
        self.head = np.zeros((n, HEAD), np.int32)
        self.sure = np.zeros(n, np.int8)
        self.width = HEAD  # columns of ``head`` every publication filled
        self.closed = False

    def tree(self, positions: np.ndarray, checkpoint: Checkpoint = no_checkpoint,
             fraction: float = 0.0) -> tuple[ExactKnn | cKDTree, np.ndarray]:
        """(a tree of ``positions`` whose ``query`` answers as ``geometry.kd_tree``'s: :class:`ExactKnn`,
        or that tree itself for points the kernel does not take; its leaf order), made by the first
        caller; a second caller waits for it, calling its checkpoint every 50 ms (a cancel is seen
        meanwhile)."""
        while not self._build.acquire(timeout=0.05):
            checkpoint(fraction)
        try:
            if self._tree is None:
                tree = ExactKnn.build(positions, checkpoint, fraction) or kd_tree(positions, checkpoint, fraction)
                self._tree = (tree, leaf_order(tree))
            return self._tree
        finally:
            self._build.release()

    def publish(self, rows: np.ndarray, dist: np.ndarray, near: np.ndarray) -> None:
        """Keep the head of ``rows``' answers (``tree.query`` distances and indices, nearest first)."""
        cols = min(HEAD + 1, near.shape[1])
        if cols < 2 or self.closed:
            return
        tie = dist[:, 1:cols] == dist[:, : cols - 1]  # columns j and j + 1 tie: j columns at most are fixed
        sure = np.where(tie.any(axis=1), tie.argmax(axis=1), cols - 1).astype(np.int8)
        with self._table:
            if not self.closed:
                self.head[rows, : cols - 1] = near[:, : cols - 1]
                self.sure[rows] = sure
                self.width = min(self.width, cols - 1)

    def reuse(self, rows: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
        """(which of ``rows`` have their k nearest fixed by a published answer, those answers)."""
        with self._table:
            if k > HEAD or self.closed:
                return np.zeros(len(rows), bool), np.empty((0, k), np.int32)
            ready = self.sure[rows] >= k
            return ready, self.head[rows[ready], :k]

    def others(self, k: int) -> np.ndarray | None:
        """Every position's k nearest other positions, nearest first (columns 1..k of the published
        answers; column 0 is the position itself, the only one at distance 0), or None unless every
        row is published with that many columns."""
        with self._table:
            if self.closed or k + 1 > self.width or not self.sure.all():
                return None
            if not np.array_equal(self.head[:, 0], np.arange(len(self.head))):
                return None
            return self.head[:, 1 : k + 1].copy()

    def close(self) -> None:
        """Drop the table and the tree: nothing will read them again."""
        with self._table:
            self.closed = True
            self.head = self.sure = None
        with self._build:
            self._tree = None


_kept: dict = {}
_kept_lock = threading.Lock()


def position_neighbours(positions: np.ndarray) -> PositionNeighbours | None:
    """The shared :class:`PositionNeighbours` of this array object (read-only, as ``unique_rows`` keeps
    it), a new one for another; None for a small or writeable array or a closed index (each stage then
    works alone, as it would without the other)."""
    if len(positions) < SHARED_FROM or positions.flags.writeable:
        return None
    with _kept_lock:
        ref = _kept.get("positions")
        if ref is None or ref() is not positions:
            try:
                ref = weakref.ref(positions, lambda r: _kept.clear() if _kept.get("positions") is r else None)
            except TypeError:  # not weak-referenceable: not shared
                return None
            _kept.clear()
            _kept.update(positions=ref, index=PositionNeighbours(len(positions)))
        index = _kept["index"]
        return None if index.closed else index


def published_others(positions: np.ndarray, k: int) -> np.ndarray | None:
    """:meth:`PositionNeighbours.others` of the index kept for this very array, when one is (never
    makes one): topology's EMST takes them as its first round (docs/performance.md 6.1)."""
    with _kept_lock:
        ref = _kept.get("positions")
        index = _kept.get("index") if ref is not None and ref() is positions else None
    return None if index is None else index.others(k)
