"""The normalized cloud's search structures that several stages of one evaluation share
(docs/performance.md 6.6): its coverage tree (:class:`~.ball_tree.BallTree` with slab bounds), each cloud
point's distance to its nearest other point (coverage's tau, docs/metrics.md 5.2), and the spread of the estimated
coverage's subsample (each cloud point's nearest sampled point, docs/metrics.md 5.2).  At a million
points each is about a CPU second, and the skeletal and curve coverage and tau made them one by one.

Each is made once, by the first stage that asks, under its own lock; a stage that asks meanwhile waits
for it (a cancel stops the maker at its next checkpoint, and the waiter then at its first).  Every value
is the one the stages computed alone: the same kernel on the same tree (tested).
"""

from __future__ import annotations

import hashlib
import threading
import weakref

import numpy as np

from ..geometry import Checkpoint, no_checkpoint, scaled_checkpoint
from .ball_tree import BallTree

__all__ = ["CloudIndex", "kept_index"]


class CloudIndex:
    """Lazily built, thread-safe search structures of one normalized cloud (module docstring)."""

    def __init__(self, cloud: np.ndarray):
        self.cloud = np.ascontiguousarray(cloud, dtype=np.float64).reshape(-1, 3)
        self._surface: BallTree | None = None
        self._spacings: np.ndarray | None = None
        self._median: float | None = None
        self._spread: dict[bytes, np.ndarray] = {}
        self._locks = {name: threading.Lock() for name in ("surface", "spacings", "spread")}

    def surface(self, checkpoint: Checkpoint = no_checkpoint) -> BallTree:
        """The cloud's BallTree with slab bounds (coverage's r(x) and gap searches)."""
        with self._locks["surface"]:
            if self._surface is None:
                self._surface = BallTree(self.cloud, slab=True, checkpoint=checkpoint)
            return self._surface

    def spacings(self, checkpoint: Checkpoint = no_checkpoint) -> np.ndarray:
        """Per cloud row, the distance to its nearest other point (0 for a copy), exact."""
        with self._locks["spacings"]:
            if self._spacings is None:
                if len(self.cloud) < 2:
                    self._spacings = np.zeros(len(self.cloud))
                else:
                    tree = self.surface(scaled_checkpoint(checkpoint, 0.0, 0.3))
                    d, _ = tree.nearest(tree.points, scaled_checkpoint(checkpoint, 0.3, 1.0), others=True, return_index=True)
                    out = np.empty(len(d))
                    out[tree.perm] = d
                    self._spacings = out
            return self._spacings

    def median_spacing(self, checkpoint: Checkpoint = no_checkpoint) -> float:
        """``np.median(self.spacings())``, kept (coverage's tau: an edit's update asks it at every curve,
        2 ms of CPU at 100k points, docs/performance.md 6.10)."""
        spacings = self.spacings(checkpoint)
        with self._locks["spacings"]:
            if self._median is None:
                self._median = float(np.median(spacings))
            return self._median

    def offer_spacings(self, spacings: np.ndarray) -> None:
        """Take the spacings from a search already made (topology's EMST, the same bits as
        :meth:`spacings`) unless they are known or being searched right now."""
        if self._spacings is not None or not self._locks["spacings"].acquire(blocking=False):
            return
        try:
            if self._spacings is None and len(spacings) == len(self.cloud):
                self._spacings = np.asarray(spacings, dtype=np.float64)
        finally:
            self._locks["spacings"].release()

    def nearest_sampled(self, at: np.ndarray, checkpoint: Checkpoint = no_checkpoint) -> np.ndarray:
        """For every point of the surface tree (tree order), the tree position of its nearest point
        among the tree positions ``at`` (a subsample; each sampled point is its own)."""
        key = np.ascontiguousarray(at, dtype=np.int64).tobytes()
        with self._locks["spread"]:
            if key not in self._spread:
                surface = self.surface(scaled_checkpoint(checkpoint, 0.0, 0.1))
                near = BallTree(surface.points[at], checkpoint=scaled_checkpoint(checkpoint, 0.1, 0.3))
                _, idx = near.nearest(surface.points, scaled_checkpoint(checkpoint, 0.3, 1.0), return_index=True)
                self._spread = {key: at[near.perm[idx]]}  # one subsample per evaluation: keep the last
            return self._spread[key]


# the last CloudIndex of kept_index: its points' digest, the index, and a weak reference to its owner
_kept: dict = {}
_kept_lock = threading.Lock()


def kept_index(points: np.ndarray, owner: np.ndarray) -> CloudIndex:
    """A :class:`CloudIndex` of ``points``, the same one while points of the same bytes come back and
    ``owner`` (the array they were taken from, or the array it is a view of) lives: a missing-parts search on a subsample of a
    million-point cloud rebuilds its tree and spacings (about a CPU second) at every edit's update
    otherwise. Only the last is kept; the values are those of a new index (the same structures)."""
    pts = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    digest = hashlib.blake2b(pts.view(np.uint8), digest_size=16).digest()
    while isinstance(getattr(owner, "base", None), np.ndarray):  # a view's buffer: the array that lives
        owner = owner.base
    with _kept_lock:
        ref = _kept.get("owner")
        if ref is not None and ref() is owner and _kept.get("digest") == digest:
            return _kept["index"]
        index = CloudIndex(pts)
        try:
            ref = weakref.ref(owner, lambda r: _kept.clear() if _kept.get("owner") is r else None)
        except TypeError:  # not weak-referenceable: not kept
            _kept.clear()
            return index
        _kept.update(owner=ref, digest=digest, index=index)
        return index
