"""Shared small geometry: the normalization transform, kNN helpers, MATLAB-compatible rounding.

Every metric works in normalized space (docs/metrics.md 0); everything written out goes back to user units.
"""

from __future__ import annotations

import hashlib
import threading
import weakref
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.spatial import cKDTree

Checkpoint = Callable[[float], None]
"""``checkpoint(fraction_done_in_stage)``: reports progress and raises ``Cancelled`` to stop."""


def no_checkpoint(_fraction: float) -> None:
    """Default checkpoint: does nothing."""


def scaled_checkpoint(checkpoint: Checkpoint, lo: float, hi: float) -> Checkpoint:
    """``checkpoint`` for a part of the work that runs from fraction ``lo`` to ``hi`` of the whole."""
    return lambda f: checkpoint(lo + (hi - lo) * min(max(f, 0.0), 1.0))


def matlab_round(x: float) -> int:
    """Round half away from zero, as MATLAB's ``round`` (Python's ``round`` rounds half to even)."""
    return int(np.sign(x) * np.floor(abs(x) + 0.5))


def bounding_box(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(min, max) of each column of an (N, 3) array: the same values as ``points.min(axis=0)`` and
    ``points.max(axis=0)``, about 10 x faster on a million rows (the rows are reduced 256 at a time
    as one contiguous block, not 3 values at a time)."""
    points = np.ascontiguousarray(points, dtype=float)
    d = points.shape[1]
    block = 256
    m = len(points) - len(points) % block
    parts_lo, parts_hi = [], []
    if m:
        flat = points[:m].reshape(-1, block * d)
        parts_lo.append(flat.min(axis=0).reshape(block, d).min(axis=0))
        parts_hi.append(flat.max(axis=0).reshape(block, d).max(axis=0))
    if m < len(points):
        parts_lo.append(points[m:].min(axis=0))
        parts_hi.append(points[m:].max(axis=0))
    if not parts_lo:
        raise ValueError("bounding box of no points")
    return np.min(parts_lo, axis=0), np.max(parts_hi, axis=0)


@dataclass(frozen=True)
class Normalization:
    """``normalized = (x - center) * scale``; built from the cloud's axis-aligned bounding box."""

    center: np.ndarray
    scale: float

    @classmethod
    def from_cloud(cls, cloud: np.ndarray, by: str = "longest_side", size: float = 1.6) -> "Normalization":
        lo, hi = bounding_box(cloud)
        extent = hi - lo
        measure = float(np.linalg.norm(extent)) if by == "diagonal" else float(extent.max())
        if not measure > 0:
            raise ValueError("all points coincide: the bounding box has no extent")
        return cls(center=(lo + hi) / 2.0, scale=size / measure)

    def apply(self, points: np.ndarray) -> np.ndarray:
        return (np.asarray(points, dtype=float) - self.center) * self.scale

    def invert(self, points: np.ndarray) -> np.ndarray:
        return np.asarray(points, dtype=float) / self.scale + self.center


QUERY_CHUNK = 65536
"""Points per KD-tree query call between checkpoints (about 0.1 s for k <= 16 on one 2-core machine)."""

THREADED_BUILD = 131072
"""From this many points a checkpointed :func:`kd_tree` build runs in a helper thread (cKDTree
releases the GIL while it builds) and the caller polls the checkpoint every ``_POLL`` seconds."""
_POLL = 0.05


def kd_tree(points: np.ndarray, checkpoint: Checkpoint | None = None, fraction: float = 0.0) -> cKDTree:
    """A cKDTree built the fast way (sliding-midpoint splits, no node shrinking): about 2.5 x faster
    to build than the default on a million points, queries about as fast (docs/performance.md).

    With a ``checkpoint``, a large build runs in a helper thread while this thread calls
    ``checkpoint(fraction)`` every 50 ms, so a cancel is seen during the build (the abandoned build
    finishes in the background and is dropped).  The tree is the same either way."""
    points = np.asarray(points, dtype=float)
    if checkpoint is None or len(points) < THREADED_BUILD:
        return cKDTree(points, balanced_tree=False, compact_nodes=False)
    import threading

    box: list = []

    def build() -> None:
        try:
            box.append(cKDTree(points, balanced_tree=False, compact_nodes=False))
        except BaseException as exc:  # handed to the calling thread
            box.append(exc)

    worker = threading.Thread(target=build, name="kd_tree build", daemon=True)
    worker.start()
    while True:
        worker.join(_POLL)
        if not worker.is_alive():
            break
        checkpoint(fraction)
    if isinstance(box[0], BaseException):
        raise box[0]
    return box[0]


def leaf_order(tree: cKDTree) -> np.ndarray:
    """The tree's points in leaf order: consecutive entries are spatial neighbours.  Queries made in
    this order reuse the same tree nodes and data (cache-warm): about 1.6 x faster at 1M points."""
    return np.asarray(tree.indices, dtype=np.int64)


def chunked_query(
    tree: cKDTree, queries: np.ndarray, k: int, checkpoint: Checkpoint = no_checkpoint,
    lo: float = 0.0, hi: float = 1.0, order: np.ndarray | None = None, chunk: int = QUERY_CHUNK, **kwargs,
) -> tuple[np.ndarray, np.ndarray]:
    """``tree.query(queries, k)`` in chunks of ``chunk`` with a checkpoint after each (progress
    from ``lo`` to ``hi``).  Returns 2-D (n, k) distances and indices, all threads used.

    ``order`` (a permutation of the query rows, e.g. :func:`leaf_order`) sets the order in which the
    rows are asked; the results come back in row order and are the same as without it."""
    n = len(queries)
    return _query_spans(tree, queries, k, ((a, min(n, a + chunk)) for a in range(0, n, chunk)), checkpoint,
                        lo, hi, order, kwargs)


#: spans of fewer query rows run on one thread: a 4096-row k = 5 query took 4.6 ms of CPU on one
#: thread and 4.9 ms with all (2 cores, loaded), 256 rows 0.25 against 0.66 ms (docs/performance.md 6.3)
THREAD_QUERY_ROWS = 8192


def query_workers(rows: int) -> int:
    """cKDTree's ``workers`` for a query of ``rows`` rows: all threads from ``THREAD_QUERY_ROWS``, else one
    (the answers do not depend on it)."""
    return -1 if rows >= THREAD_QUERY_ROWS else 1


def _query_spans(tree, queries, k, spans, checkpoint, lo, hi, order, kwargs) -> tuple[np.ndarray, np.ndarray]:
    """The k-NN answers of ``queries`` asked span by span (rows ``order[start:stop]`` or start:stop),
    a checkpoint after each: the loop of :func:`chunked_query` and :func:`timed_query`."""
    queries = np.asarray(queries, dtype=float)
    n = len(queries)
    dist = np.empty((n, k))
    idx = np.empty((n, k), np.int64)
    for start, stop in spans:
        rows = slice(start, stop) if order is None else order[start:stop]
        # below THREAD_QUERY_ROWS, starting the threads costs more than they save (the same answers)
        d, i = tree.query(queries[rows], k=k, workers=query_workers(stop - start), **kwargs)
        dist[rows] = d.reshape(stop - start, k)
        idx[rows] = i.reshape(stop - start, k)
        checkpoint(lo + (hi - lo) * stop / max(n, 1))
    return dist, idx


class TimedChunks:
    """Row ranges sized so that each takes about ``target`` seconds (from the rate of the last
    one), starting at ``first`` rows: for work whose cost per row is unknown and may be large
    (medial points asking for their nearest surface point visit many KD-tree nodes, docs/performance.md)."""

    def __init__(self, n: int, first: int = 256, target: float = 0.1, most: int = QUERY_CHUNK) -> None:
        self.n, self.size, self.target, self.most = int(n), max(1, int(first)), float(target), int(most)

    def __iter__(self):
        import time

        start = 0
        while start < self.n:
            stop = min(self.n, start + self.size)
            t0 = time.perf_counter()
            yield start, stop
            spent = time.perf_counter() - t0
            rate = (stop - start) / max(spent, 1e-6)
            # grow at most 4 x per step, never past ``most``
            self.size = int(min(self.most, 4 * (stop - start), max(1, rate * self.target)))
            start = stop


def timed_query(
    tree: cKDTree, queries: np.ndarray, k: int, checkpoint: Checkpoint = no_checkpoint,
    lo: float = 0.0, hi: float = 1.0, order: np.ndarray | None = None, **kwargs,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`chunked_query` with chunks sized by :class:`TimedChunks` (about 0.1 s each)."""
    return _query_spans(tree, queries, k, TimedChunks(len(queries)), checkpoint, lo, hi, order, kwargs)


def nearest_neighbor_distances(
    points: np.ndarray, tree: cKDTree | None = None, checkpoint: Checkpoint = no_checkpoint
) -> np.ndarray:
    """Distance from each point to its nearest *other* point (0 for duplicates)."""
    points = np.asarray(points, dtype=float)
    if len(points) < 2:
        return np.zeros(len(points))
    tree = kd_tree(points, checkpoint) if tree is None else tree
    checkpoint(0.0)
    return chunked_query(tree, points, 2, checkpoint, order=leaf_order(tree))[0][:, 1]


def knn(points: np.ndarray, queries: np.ndarray, k: int, tree: cKDTree | None = None) -> tuple[np.ndarray, np.ndarray]:
    """k nearest neighbours of each query among ``points`` (query itself included if present).

    Returns (distances, indices), each (len(queries), min(k, len(points))), always 2-D.
    """
    points = np.asarray(points, dtype=float)
    k = int(min(k, len(points)))
    tree = cKDTree(points) if tree is None else tree
    dist, idx = tree.query(np.asarray(queries, dtype=float), k=k, workers=-1)
    if k == 1:
        dist, idx = dist[:, None], idx[:, None]
    return dist, idx


def take_rows(array: np.ndarray, index: np.ndarray) -> np.ndarray:
    """``array[index]`` along the first axis (any index shape), by ``np.take``: the same values, 2.5-4 x
    faster than fancy indexing for rows of 3 (a million rows: 0.27 -> 0.07 s; docs/performance.md 6.4)."""
    return np.take(array, index, axis=0)


def group_min_median_max(values: np.ndarray, groups: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per group 0..n-1 the min, median and max of ``values`` (NaN for an empty group; groups outside
    0..n-1 left out), all groups in one sort; the median is np.median's (the middle value, or the mean
    of the two middle ones)."""
    lo_v, med, hi_v = np.full(n, np.nan), np.full(n, np.nan), np.full(n, np.nan)
    order = np.lexsort((values, groups))
    vs = values[order]
    bounds = np.searchsorted(groups[order], np.arange(n + 1))
    count = np.diff(bounds)
    has = count > 0
    lo, count = bounds[:-1][has], count[has]
    lo_v[has], hi_v[has] = vs[lo], vs[lo + count - 1]
    med[has] = (vs[lo + (count - 1) // 2] + vs[lo + count // 2]) / 2.0
    return lo_v, med, hi_v


def stable_argsort(values: np.ndarray) -> np.ndarray:
    """``np.argsort(values, kind="stable")`` of a 1-D array (equal values by index; NaN last), by numpy's
    unstable (vectorised) sort and a re-sort of the indices inside each run of equal values: 2-3 x faster
    when ties are few (docs/performance.md 6.4)."""
    values = np.asarray(values)
    if len(values) < 4096:  # below this the fix-up's few calls cost more than the sort saves
        return np.argsort(values, kind="stable")
    order = np.argsort(values)
    v = values[order]
    eq = v[1:] == v[:-1]
    if values.dtype.kind == "f":
        eq |= np.isnan(v[1:]) & np.isnan(v[:-1])
    if eq.any():
        in_run = np.zeros(len(v), bool)
        in_run[1:] |= eq
        in_run[:-1] |= eq
        at = np.flatnonzero(in_run)
        run = np.cumsum(np.r_[True, ~eq])[at]  # run number of each tied position (increasing)
        order[at] = order[at][np.lexsort((order[at], run))]
    return order


def lex_order(points: np.ndarray) -> np.ndarray:
    """``np.lexsort(points.T[::-1])`` (rows by x, then y, then z, equal rows by row index), about
    10 x faster on a million points: one unstable argsort by x, then a lexsort of only the rows
    whose x occurs more than once."""
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or len(points) < 2:
        return np.lexsort(points.T[::-1]) if points.ndim == 2 else np.argsort(points, kind="stable")
    order = np.argsort(points[:, 0])
    xs = np.take(points[:, 0], order)
    eq = xs[1:] == xs[:-1]
    if eq.any():
        in_run = np.zeros(len(points), bool)
        in_run[1:] |= eq
        in_run[:-1] |= eq
        at = np.flatnonzero(in_run)  # whole runs of equal x, in increasing x
        rows = np.sort(order[at])  # by row index, so the stable lexsort breaks full ties by row
        order[at] = rows[np.lexsort(points[rows].T[::-1])]
    return order


def unique_rows(points: np.ndarray, checkpoint: Checkpoint = no_checkpoint) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(unique points, inverse, counts), comparing values (so -0.0 equals 0.0), unique points in
    lexicographic order.

    Contraction stacks many skeletal points at one position; metrics work once per position.
    Faster than ``np.unique(axis=0)``, which compares bytes.  From ``_MEMO_ROWS`` rows the answer is
    kept (read-only) for the same array with the same contents: an evaluation's boundedness, topology,
    smoothness and coverage each asked for the skeletal set's (1M rows: ~0.4 CPU s each,
    docs/performance.md 6.4); a second caller meanwhile waits for the first.
    """
    points = np.asarray(points, dtype=float)
    if len(points) < _MEMO_ROWS:
        return _unique_rows(points, checkpoint)
    return _UNIQUE_MEMO.get(points, lambda: _unique_rows(points, checkpoint))


def _unique_rows(points: np.ndarray, checkpoint: Checkpoint) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    order = lex_order(points)
    checkpoint(0.0)  # (``checkpoint(0.0)`` between the passes: a cancel is seen at 1M points)
    srt = take_rows(points, order)
    new = np.ones(len(srt), bool)
    if len(srt) > 1:
        new[1:] = np.any(srt[1:] != srt[:-1], axis=1)
    checkpoint(0.0)
    group = np.cumsum(new) - 1
    inverse = np.empty(len(points), np.int64)
    inverse[order] = group
    return srt[new], inverse, np.bincount(group, minlength=int(new.sum()))


class _ArrayMemo:
    """Results of a function of one array, kept for that array object while its bytes are unchanged
    (blake2b digest, ~25 ms for 1M rows), a few at a time, read-only; one computation per array at
    once (a second caller waits for the first, then reads its answer)."""

    def __init__(self, size: int = 4):
        self._size = size
        self._entries: dict[int, tuple] = {}  # id -> (weakref to the array, digest, lock, result box)
        # reentrant: the cyclic garbage collector may free a kept array (and call _drop) in this very
        # thread while it holds the lock
        self._lock = threading.RLock()

    def get(self, array: np.ndarray, compute):
        digest = hashlib.blake2b(np.ascontiguousarray(array).view(np.uint8), digest_size=16).digest()
        key = id(array)
        with self._lock:
            entry = self._entries.get(key)
            if entry is None or entry[0]() is not array or entry[1] != digest:
                try:
                    ref = weakref.ref(array, lambda r, k=key: self._drop(k, r))
                except TypeError:  # not weak-referenceable: no memo
                    return compute()
                entry = (ref, digest, threading.Lock(), [])
                self._entries[key] = entry
                while len(self._entries) > self._size:
                    self._entries.pop(next(iter(self._entries)))
        _, _, lock, box = entry
        with lock:
            if not box:
                result = compute()
                for a in result:
                    a.flags.writeable = False
                box.append(result)
            return box[0]

    def _drop(self, key: int, ref) -> None:
        with self._lock:
            if key in self._entries and self._entries[key][0] is ref:
                del self._entries[key]


#: unique_rows' memo (from this many rows): from the hammer's size, the skeletal set's positions are one
#: read-only array for every stage, so centeredness and smoothness share their index (metrics/position_knn.py;
#: docs/performance.md 6.4)
_MEMO_ROWS = 1024
_UNIQUE_MEMO = _ArrayMemo()


def as_points(name: str, points: object) -> np.ndarray:
    """Validate user points as a finite, non-empty (N, 3) float array, else a one-line SkelInputError.
    Other libraries' objects (an Open3D PointCloud, a trimesh mesh, ...) give their points
    (:func:`skelcore.interop.points_of`); an unknown object is a TypeError naming what is accepted."""
    from .errors import SkelInputError

    if not isinstance(points, np.ndarray):
        from .interop.objects_in import points_of

        points = points_of(points, name)
    try:
        arr = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise SkelInputError(f"{name}: coordinates are not numbers") from None
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise SkelInputError(f"{name}: expected an N x 3 array of points, got shape {arr.shape}")
    if len(arr) == 0:
        raise SkelInputError(f"{name}: no points")
    if not np.all(np.isfinite(arr)):
        raise SkelInputError(f"{name}: coordinates contain NaN or inf")
    check_magnitude(name, arr)
    return arr


#: the largest coordinate (in absolute value) and the smallest extent of a point set that the engine
#: accepts: squared distances (and their reciprocals, the smoothness weights) stay finite and normal
#: in double precision well inside these bounds (docs/metrics.md 0)
COORDINATE_LIMIT = 1e100
EXTENT_LIMIT = 1e-100


def check_magnitude(name: str, points: np.ndarray) -> None:
    """A one-line SkelInputError when a finite coordinate exceeds :data:`COORDINATE_LIMIT` in absolute
    value: the distances the engine computes in the user's units (stray points, openings, spacing)
    would overflow (docs/metrics.md 0)."""
    from .errors import SkelInputError

    top = float(np.max(np.abs(points), initial=0.0))
    if top > COORDINATE_LIMIT:
        raise SkelInputError(f"{name}: coordinates reach {top:.3g}, above {COORDINATE_LIMIT:.0e}: squared distances "
                             "would overflow in double precision; rescale the points")


def check_extent(name: str, points: np.ndarray) -> None:
    """A one-line SkelInputError when the bounding box's longest side is positive but below
    :data:`EXTENT_LIMIT`: squared distances would underflow to 0 (docs/metrics.md 0)."""
    from .errors import SkelInputError

    lo, hi = bounding_box(points)
    side = float(np.max(hi - lo, initial=0.0))
    if 0 < side < EXTENT_LIMIT:
        raise SkelInputError(f"{name}: the points span only {side:.3g}, below {EXTENT_LIMIT:.0e}: squared distances "
                             "would underflow in double precision; rescale the points")


def bbox_diagonal(points: np.ndarray) -> float:
    lo, hi = bounding_box(points)
    return float(np.linalg.norm(hi - lo))


def unit_rows(vectors: np.ndarray) -> np.ndarray:
    """Rows scaled to unit length; zero rows become NaN (an undefined direction is invalid)."""
    vectors = np.asarray(vectors, dtype=float)
    norms = np.linalg.norm(vectors, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = vectors / norms
    out[np.broadcast_to(norms == 0, out.shape)] = np.nan
    return out
