"""The compiled kernel's tree of bounding spheres (``_balls.c``) and its timed, threaded queries: nearest
cloud point (coverage's r(x), tau's spacings), gap and cover to a set of balls (docs/metrics.md
5.2).  Coverage, the cloud's shared index (:mod:`.cloud_index`) and the diagnostics' ball tests use it.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ..geometry import Checkpoint, TimedChunks, no_checkpoint
from ..parallel import polled_build, pool_width
from . import _balls

__all__ = ["BallTree", "NODE", "LEAF", "COVER_EPS"]

# one tree node as the kernel reads it (struct Node in _balls.c): 136 bytes
NODE = np.dtype([("c", "<f8", (3,)), ("rho", "<f8"), ("rg", "<f8"), ("rc", "<f8"), ("n", "<f8", (3,)),
                 ("t", "<f8"), ("w", "<f8"), ("k", "<f8", (3,)), ("rk", "<f8"), ("kid", "<i4"), ("lo", "<i4"), ("hi", "<i4"), ("pad", "<i4")])
# points per tree leaf at most
LEAF = 8
# rows per timed chunk at most (a chunk is split over the threads)
MOST_ROWS = 262144
# below this many rows a chunk runs on the calling thread alone: the evaluation's stages already run side
# by side, and on a small cloud the pieces' hand-over cost more than their work (docs/performance.md 6.2)
THREAD_ROWS = 8192
# covered: |p - x|^2 - R(x)^2 <= COVER_EPS x R_max^2 (the rounding allowance of the 4-D lifted query before)
COVER_EPS = 1e-12
# blocks=None walks the tree once per 16 queries from this many queries per ball (a curve's coverage: its
# 100k points against 1,322 balls 51 -> 35 ms; a skeletal set's 3,912 against 4,096 balls 4.1 -> 5.6 ms:
# docs/performance.md 6.10)
BLOCK_QUERIES = 4
# a timed chunk of at least twice this many rows is split over the threads (slow rows: a chunk of ~0.1 s
# may hold only a few thousand, e.g. cloud points among a million overlapping balls)
PIECE_ROWS = 256


class BallTree:
    """Points in a balanced KD-tree of bounding spheres (``_balls.build_tree``), in tree order:
    ``points`` = input rows ``perm``.  With ``slab`` every node also bounds its points by a plane
    (for nearest-point queries from inside a surface)."""

    def __init__(self, points: np.ndarray, slab: bool = False, checkpoint: Checkpoint = no_checkpoint):
        pts = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
        n = len(pts)
        perm, srt = np.empty(n, np.int32), np.empty((n, 3))
        nodes = np.empty(max(1, 2 * ((n + 3) // 4) + 2), NODE)
        threads = max(1, os.cpu_count() or 1)
        m = _build_polling(lambda stop: _balls.build_tree(pts, perm, srt, nodes, slab, stop, LEAF, threads), n, checkpoint)
        self.nodes = nodes[:m]
        self.perm = perm
        self.points = srt
        self.stats = np.zeros(2, np.int64)  # node visits, point tests of the queries so far

    def nearest(self, queries: np.ndarray, checkpoint: Checkpoint = no_checkpoint,
                workers: int | None = None, others: bool = False, return_index: bool = False):
        """Distance from each query row to its nearest point, exact; ask in spatial order.  With
        ``others`` the queries are ``self.points`` and each skips itself (nearest other point).  The
        nearest point's tree position of each query is ``last_index``, or returned with the distances
        with ``return_index`` (for a tree that threads share: :class:`.cloud_index.CloudIndex`)."""
        q = np.ascontiguousarray(queries, dtype=np.float64)
        out, idx = np.empty(len(q)), np.empty(len(q), np.int32)

        def run(i0: int, i1: int) -> None:
            st = np.zeros(2, np.int64)
            _balls.nearest(self.nodes, self.points, q, i0, i1, out, idx, st, others)
            self.stats += st

        _chunked(run, len(q), checkpoint, workers)
        if return_index:
            return out, idx
        self.last_index = idx  # the nearest point of each query (tree order)
        return out

    def set_radii(self, r: np.ndarray, big_r: np.ndarray, contact: np.ndarray | None = None,
                  checkpoint: Checkpoint = no_checkpoint, workers: int | None = None) -> None:
        """Ball radii r (gap) and R (cover) of the points, tree order: every node's bounds.  ``contact``
        (each ball's nearest cloud point, where r came from) lets a node bound its balls tighter."""
        self.r = np.ascontiguousarray(r, dtype=np.float64)
        self.big_r = np.ascontiguousarray(big_r, dtype=np.float64)
        con = np.empty(0) if contact is None else np.ascontiguousarray(contact, dtype=np.float64)
        _chunked(lambda i0, i1: _balls.refit(self.nodes, self.points, self.r, self.big_r, con, i0, i1),
                 len(self.nodes), checkpoint, workers)

    def balls(self, queries: np.ndarray, gap: bool = True, cover: bool = True, floor: float = -np.inf,
              checkpoint: Checkpoint = no_checkpoint, workers: int | None = None,
              top: float | None = None, blocks: bool | None = False) -> tuple:
        """(min_x |q - x| - r(x), exact where above ``floor``, else some value <= floor; is some
        |q - x|^2 - R(x)^2 <= COVER_EPS R_max^2) per query row, each None unless asked for.  ``top``:
        the R_max of that allowance (default these balls'; a subset of balls asked as their whole set).
        ``blocks``: one walk of the tree per 16 consecutive queries (``_balls.balls_block``: the same gaps
        where above ``floor``, the same verdicts; for queries in spatial order, many per ball); None: from
        ``BLOCK_QUERIES`` queries per ball (docs/performance.md 6.10)."""
        q = np.ascontiguousarray(queries, dtype=np.float64)
        out_g = np.empty(len(q) if gap else 0)
        out_c = np.zeros(len(q) if cover else 0, np.uint8)
        if top is None:
            top = float(self.big_r.max()) if len(self.big_r) else 0.0
        eps = COVER_EPS * max(top * top, 1e-300)
        if blocks is None:
            blocks = len(q) >= BLOCK_QUERIES * len(self.points)
        kernel = _balls.balls_block if blocks else _balls.balls

        def run(i0: int, i1: int) -> None:
            st = np.zeros(2, np.int64)
            kernel(self.nodes, self.points, self.r, self.big_r, q, i0, i1, float(floor), eps, out_g, out_c, st)
            self.stats += st

        _chunked(run, len(q), checkpoint, workers)
        return (out_g if gap else None), (out_c.view(bool) if cover else None)


def _chunked(fn, n: int, checkpoint: Checkpoint, workers: int | None = None) -> None:
    """``fn(i0, i1)`` over [0, n) in chunks of about 0.1 s (``TimedChunks``), a checkpoint after each;
    a chunk is cut in 4 x ``workers`` contiguous pieces that ``workers`` threads (None: every core;
    the kernel releases the GIL) take as they finish, so an unlucky piece delays little.  Threads only
    for ``n`` >= ``THREAD_ROWS``; a chunk is split when it holds >= 2 ``PIECE_ROWS`` (it was only from
    ``THREAD_ROWS`` rows, so slow rows, ~0.1 s in fewer, ran on one thread: docs/performance.md 6.6).  On a
    :func:`skelcore.parallel.run_graph` lane only as many threads as it has cores (:func:`pool_width`)."""
    if n < THREAD_ROWS:
        _pieces(fn, n, checkpoint, None, 1)
        return
    with pool_width(workers) as width:  # on a lane: its own core and the free ones
        pool = ThreadPoolExecutor(max_workers=width) if width > 1 else None
        try:
            _pieces(fn, n, checkpoint, pool, width)
        finally:
            if pool is not None:
                pool.shutdown(wait=True)


def _pieces(fn, n: int, checkpoint: Checkpoint, pool: ThreadPoolExecutor | None, workers: int) -> None:
    """The timed chunks of :func:`_chunked`, each cut over ``pool``'s ``workers`` threads (None: here)."""
    for lo, hi in TimedChunks(n, first=256, most=MOST_ROWS):
        if pool is None or hi - lo < 2 * PIECE_ROWS:
            fn(lo, hi)
        else:
            pieces = min(4 * workers, (hi - lo) // PIECE_ROWS)
            cuts = np.linspace(lo, hi, pieces + 1).astype(int)
            for fut in [pool.submit(fn, a, b) for a, b in zip(cuts[:-1], cuts[1:])]:
                fut.result()
        checkpoint(hi / n)


def _build_polling(build, n: int, checkpoint: Checkpoint) -> int:
    """The kernel's tree build, polled (:func:`skelcore.parallel.polled_build`), then one checkpoint."""
    m = polled_build(build, n, checkpoint, "skelscope-coverage-tree")
    checkpoint(0.0)
    return m
