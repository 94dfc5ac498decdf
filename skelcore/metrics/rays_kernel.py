"""Driver of the compiled ``rays`` kernel (``_raycast.c``): the cloud's tree, the cluster plan, the streams.

beta(q) is the share of raster samples whose ray from q meets a ball of radius h around a cloud point
(docs/metrics.md 2; the same samples as ``_rays.CapRaster``).  Queries are grouped in clusters (docs/boundedness.md
1.6-1.7: cubic cells, finer cells near the surface, near-surface queries alone); each cluster's far field
(points beyond its reach) is ray cast once from its centroid, its near field rasterised as exact caps
from every member.  A cluster of one query at its own position is exact.  Clusters run in long contiguous
streams on a thread pool (the kernel releases the GIL and keeps each sample's hint from one cluster to the
next; lone queries of a cloud beyond the caches a block at a time, band by band of the raster), while the
caller's thread polls its checkpoint; a cancel stops the kernel within one cluster or band.  The
kernel tests in SIMD lanes; on x86-64 it is also built for AVX2, used where the CPU has it (the same bits).
Design, costs and errors: docs/boundedness.md section 3.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
from ..geometry import Checkpoint, no_checkpoint, take_rows
from ..parallel import on_threads, polled_build, polled_streams
from .ray_hints import HintTables, seeds_for
from . import _raycast as _generic_kernel


def _fastest_kernel():
    """The kernel's AVX2 build where this CPU runs it (setup.py builds it on x86-64; the same source and the
    same bits, 10-20 % faster: docs/boundedness.md 3.11), else the build for any CPU."""
    if _generic_kernel.cpu_has_avx2():
        try:
            from . import _raycast_avx2

            return _raycast_avx2
        except ImportError:  # built elsewhere without it
            pass
    return _generic_kernel


_raycast = _fastest_kernel()

# queries closer than this many h to the cloud share only in finer cells, or are alone (1.7)
ALONE_WITHIN = 4.0
# near-surface queries share in finer cells with a near radius this many times the usual 10 cells
FINER_BOOST = 2.0
# cost units (about one tree-node visit each): one near cap, and a far ray per level of the tree
CAP_COST = 25.0
# clusters run in this many contiguous streams per core (a stream keeps its far rays' hints from one
# cluster to the next: 15-38 % fewer node visits than tasks of ~40 ms, docs/boundedness.md 3.9; several
# per core so that the cores finish together)
STREAMS_PER_WORKER = 8
# ... but no fewer clusters than this per stream (each stream starts with no hints: on the hammer's 866
# clusters 16 streams cost 2.6 % more kernel instructions than 4)
STREAM_CLUSTERS = 200
# seconds between two checkpoints while the streams run (the kernel stops within one cluster of a cancel)
POLL = 0.05
# points per nearest-neighbour call (about 30 ms of one core)
NN_CHUNK = 65536


# points per leaf at most (the kernel's own constant)
LEAF_SIZE = _raycast.LEAF_SIZE
# one tree node as the kernel reads it (struct Node in _raycast.c): 32 bytes
NODE = np.dtype([("c", "<f4", (3,)), ("r", "<f4"), ("kid", "<i4"), ("lo", "<i4"), ("hi", "<i4"), ("par", "<i4")])


class BallTree:
    """The distinct cloud points (raster frame) in a balanced KD-tree with a bounding sphere per node."""

    def __init__(self, pts: np.ndarray, checkpoint: Checkpoint = no_checkpoint):
        pts = np.ascontiguousarray(pts, dtype=np.float64)
        n = len(pts)
        cap = max(1, 2 * ((n + 3) // 4) + 2)
        perm = np.empty(n, np.int32)
        nodes = np.empty(cap, NODE)
        tree_points = np.empty((n, 3), np.float32)
        threads = os.cpu_count() or 1
        m = _build_polling(lambda stop: _raycast.build_tree(pts, perm, nodes, stop, threads, tree_points), n, checkpoint)
        checkpoint(0.0)
        self.points = tree_points
        nodes = _aligned(nodes[:m], 32)
        self.leaves = _aligned(_leaf_blocks(nodes, tree_points), 0)
        self.nodes = nodes
        self._wide: dict[str, np.ndarray] = {}
        self.perm = perm
        self.n = n
        self.depth = max(1.0, float(np.log2(max(2.0, n / 8.0))))

    def nearest_other(self, checkpoint: Checkpoint = no_checkpoint, workers: int | None = None) -> np.ndarray:
        """Distance from each point (tree order) to its nearest other point, exact; inf for a lone point."""
        leaves = np.flatnonzero(self.nodes["kid"] < 0)
        leaves = leaves[np.argsort(self.nodes["lo"][leaves])]
        leaf_of = np.repeat(leaves.astype(np.int32), self.nodes["hi"][leaves] - self.nodes["lo"][leaves])
        out = np.empty(self.n)

        def chunk(i0: int, i1: int) -> None:
            _raycast.nn_dist(self.points, self.nodes, leaf_of, i0, i1, out[i0:i1])

        spans = [(i, min(i + NN_CHUNK, self.n)) for i in range(0, self.n, NN_CHUNK)]
        on_threads(chunk, spans, workers, checkpoint)
        return out

    def median_spacing(self, counts: np.ndarray, checkpoint: Checkpoint = no_checkpoint) -> float:
        """Median nearest-neighbour distance over the original points, ``counts`` copies of each
        distinct point (input order): a point with copies is at distance 0 from one (the h of docs/metrics.md 2)."""
        if int(np.sum(counts)) < 2:
            return 0.0
        c = np.asarray(counts)[self.perm]
        d = np.where(c > 1, 0.0, self.nearest_other(checkpoint))
        checkpoint(1.0)
        return float(np.median(np.repeat(d, c)))

    def count_within(self, queries: np.ndarray, radius: float) -> np.ndarray:
        """Number of points within ``radius`` of each query."""
        q = np.ascontiguousarray(queries, np.float64)
        counts = np.empty(len(q), np.int64)
        _raycast.near_stats(self.points, self.nodes, q, float(radius), 0.0, counts, np.empty(0))
        return counts

    def clearance(self, queries: np.ndarray, bound: float, checkpoint: Checkpoint = no_checkpoint,
                  workers: int | None = None) -> np.ndarray:
        """Distance from each query to the nearest point, inf where it is not below ``bound``."""
        q = np.ascontiguousarray(queries, np.float64)
        out = np.empty(len(q))

        def chunk(i0: int, i1: int) -> None:
            _raycast.near_stats(self.points, self.nodes, q[i0:i1], 0.0, float(bound), np.empty(0, np.int64),
                                out[i0:i1])

        on_threads(chunk, [(i, min(i + NN_CHUNK, len(q))) for i in range(0, len(q), NN_CHUNK)], workers, checkpoint)
        return out

    def wide(self, kernel=None) -> np.ndarray:
        """The tree with 8 (AVX2) or 4 children a node that ``kernel``'s packets walk (default: the kernel in
        use), made once per build (each build's own layout, docs/boundedness.md 3.21)."""
        kernel = kernel or _raycast
        if kernel.__name__ not in self._wide:
            self._wide[kernel.__name__] = _wide_tree(self.nodes, kernel)
        return self._wide[kernel.__name__]

    @property
    def ray_cost(self) -> float:
        """Cost units of one far ray (node visits grow with the depth)."""
        return 2.0 + self.depth


def _aligned(a: np.ndarray, offset: int) -> np.ndarray:
    """A copy of ``a`` whose data starts ``offset`` bytes past a 64-byte cache line: with 32-byte nodes and
    the root alone at 0, offset 32 puts every sibling pair (kid, kid + 1; kid odd) in one line, and 0
    starts every other 96-byte leaf block on one (numpy aligns to 16 bytes only)."""
    raw = np.empty(a.nbytes + 64, np.uint8)
    skip = (offset - raw.ctypes.data) % 64
    out = raw[skip : skip + a.nbytes].view(a.dtype).reshape(a.shape)
    out[...] = a
    return out


def _wide_tree(nodes: np.ndarray, kernel) -> np.ndarray:
    """The tree with up to 8 (AVX2) or 4 children a node (a node's descendants three or two levels down side by
    side) that ``kernel``'s packets walk, as bytes on a 64-byte line; empty for a tree of fewer than 3 nodes
    (docs/boundedness.md 3.21)."""
    size = kernel.WIDE_BYTES
    raw = np.empty((len(nodes) // 2 + 1) * size + 64, np.uint8)
    skip = -raw.ctypes.data % 64
    out = raw[skip : skip + (len(nodes) // 2 + 1) * size]
    count = kernel.wide_tree(nodes, out)
    return out[: count * size]


def _leaf_blocks(nodes: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Each leaf's points as x[8], y[8], z[8] (unused lanes NaN, which never hit), for the kernel's ball tests
    4 or 8 lanes at a time; leaf b (in node order) gets kid = -1 - b (``nodes`` is changed in place)."""
    leaves = np.flatnonzero(nodes["kid"] < 0)
    lo, count = nodes["lo"][leaves].astype(np.int64), (nodes["hi"][leaves] - nodes["lo"][leaves]).astype(np.int64)
    if len(leaves) and int(count.max()) > LEAF_SIZE:
        raise RuntimeError(f"a leaf of the boundedness tree holds {int(count.max())} points, above {LEAF_SIZE}")
    nodes["kid"][leaves] = -1 - np.arange(len(leaves), dtype=np.int32)
    blocks = np.full((len(leaves), 3, LEAF_SIZE), np.nan, np.float32)
    leaf = np.repeat(np.arange(len(leaves)), count)
    lane = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    blocks[leaf, :, lane] = points[np.repeat(lo, count) + lane]
    return blocks


def _build_polling(build, n: int, checkpoint: Checkpoint) -> int:
    """The kernel's tree build, polled (:func:`skelcore.parallel.polled_build`)."""
    return polled_build(build, n, checkpoint, "skelscope-balltree")


@dataclass
class Plan:
    """Queries grouped by cluster: ``order`` (plan position -> query row), cluster ``starts`` (K + 1),
    ``centres`` (K, 3), ``reach`` (K,): points within reach of the centre are near."""

    order: np.ndarray
    starts: np.ndarray
    centres: np.ndarray
    reach: np.ndarray
    estimated_cost: float = 0.0
    estimated_near: float = 0.0


def exact_plan(queries: np.ndarray, reach: float) -> Plan:
    """Every query its own cluster at its own position: exact for any reach."""
    n = len(queries)
    return Plan(np.arange(n), np.arange(n + 1, dtype=np.int64), np.ascontiguousarray(queries, np.float64),
                np.full(n, float(reach)))


def shared_plan(
    queries: np.ndarray, h: float, near_radius: float, cell: float, clearance: np.ndarray,
    finer: bool = True, checkpoint: Checkpoint = no_checkpoint,
) -> Plan:
    """Clusters of cubic cells of side ``cell`` with reach ``near_radius`` + spread (docs/boundedness.md 1.6).

    A query closer than 4 h and 4 cells to the cloud shares only in finer cells (cell / 2^k down to
    h / 4, clearance >= 4 of them, twice the near radius), or is alone below that (1.7).
    """
    level = np.zeros(len(queries), np.int64)
    levels = max(0, int(np.floor(np.log2(cell / (h / 4.0))))) if finer else 0
    for k in range(1, levels + 1):
        need = ALONE_WITHIN * h if k == 1 else 0.0
        level[clearance < max(ALONE_WITHIN * cell / 2.0 ** (k - 1), need)] = k
    lone = clearance < (ALONE_WITHIN * cell / 2.0**levels if levels else ALONE_WITHIN * h)
    level_cell = cell / 2.0**level
    keys = np.floor(queries / level_cell[:, None]).astype(np.int64)
    keys = np.column_stack([keys, level, np.where(lone, np.arange(1, len(keys) + 1), 0)])
    checkpoint(0.0)
    cid = _group_ids(keys, checkpoint)
    checkpoint(0.0)
    # clusters in Morton order of their first query's cell: neighbours follow each other, so the
    # kernel's per-sample hints (the leaf the same sample hit from the previous cluster) stay good
    first = np.zeros(int(cid.max(initial=-1)) + 1, np.int64)
    first[cid[::-1]] = np.arange(len(cid))[::-1]
    rank = np.argsort(_morton(np.floor(queries[first] / (cell / 2.0**levels)).astype(np.int64)), kind="stable")
    inv = np.empty_like(rank)
    inv[rank] = np.arange(len(rank))
    cid = inv[cid]
    checkpoint(0.0)
    order = np.argsort(cid, kind="stable")
    checkpoint(0.0)
    cid = cid[order]
    q = take_rows(queries, order)
    starts = np.flatnonzero(np.r_[True, cid[1:] != cid[:-1], True]).astype(np.int64)
    sizes = np.diff(starts)
    checkpoint(0.0)
    centres = np.add.reduceat(q, starts[:-1], axis=0) / sizes[:, None]
    dist = np.linalg.norm(q - np.repeat(centres, sizes, axis=0), axis=1)
    spreads = np.maximum.reduceat(dist, starts[:-1])
    single = sizes == 1
    centres[single] = q[starts[:-1][single]]
    spreads[single] = 0.0
    cl_level = level[order][starts[:-1]]
    reach = near_radius * np.where(cl_level > 0, FINER_BOOST, 1.0) / 2.0**cl_level + spreads
    return Plan(order, starts, np.ascontiguousarray(centres), reach)


def _morton(cells: np.ndarray) -> np.ndarray:
    """Morton (Z-order) codes of integer cells (N, 3): 21 bits per axis, interleaved."""
    c = (cells - cells.min(axis=0, initial=0)).astype(np.uint64) & np.uint64((1 << 21) - 1)
    code = np.zeros(len(c), np.uint64)
    for bit in range(21):
        for axis in range(3):
            code |= ((c[:, axis] >> np.uint64(bit)) & np.uint64(1)) << np.uint64(3 * bit + axis)
    return code


def _codes(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """One int64 code per row of an int64 key matrix (mixed radix, increasing with the rows'
    lexicographic order), its per-column offset and spans; None when the key space is too big."""
    low = keys.min(axis=0)
    span = keys.max(axis=0) - low + 1
    if float(np.prod(span.astype(float))) >= 2.0**62:
        return None
    code = np.zeros(len(keys), np.int64)
    for j in range(keys.shape[1]):
        code = code * span[j] + (keys[:, j] - low[j])
    return code, low, span


def _group_ids(keys: np.ndarray, checkpoint: Checkpoint = no_checkpoint) -> np.ndarray:
    """Dense ids of equal rows of an int64 key matrix, in increasing key order: one 1-D unique of the
    rows' codes when the key space allows, with checkpoints around it (about 0.2 s at 1M rows)."""
    coded = _codes(keys) if len(keys) else None
    if coded is None:
        return np.unique(keys, axis=0, return_inverse=True)[1].ravel()
    checkpoint(0.0)
    ids = np.unique(coded[0], return_inverse=True)[1].ravel()
    checkpoint(0.0)
    return ids


def choose_plan(
    tree: BallTree, queries: np.ndarray, h: float, near_radius: float, cell: float,
    samples: int, exact_pairs: int, share: bool | None, checkpoint: Checkpoint = no_checkpoint,
) -> Plan:
    """Exact when small, forced, or cheaper; else the cheapest of seven cluster sizes (x 1/2 ... x 32;
    steps of sqrt 2 were tried: 100k faster, 1M 1.8 x slower, the near caps' cost misjudged).

    Estimated cost = clusters x samples x ray cost + queries x near points x cap cost, the near points
    counted on 256 sampled queries.
    """
    n_q = len(queries)
    sample = queries[np.random.default_rng(0).permutation(n_q)[:256]]
    checkpoint(0.0)
    near_exact = float(np.mean(tree.count_within(sample, near_radius)))
    exact_cost = n_q * (samples * tree.ray_cost + near_exact * CAP_COST)
    if share is False or (share is None and tree.n * n_q <= exact_pairs):
        plan = exact_plan(queries, near_radius)
        plan.estimated_cost, plan.estimated_near = exact_cost, near_exact
        return plan
    best = None
    cells = _CellCounts(queries, cell / 2.0, checkpoint)
    for halvings, scale in enumerate(2.0 ** np.arange(-1, 6)):
        reach = (near_radius + 0.87 * cell) * scale
        near = float(np.mean(tree.count_within(sample, reach)))
        if best is not None and n_q * near * CAP_COST >= best[0]:
            break  # the near part only grows with the size: no larger size can be cheaper
        checkpoint(0.0)
        clusters = cells.count(halvings)
        cost = clusters * samples * tree.ray_cost + n_q * near * CAP_COST
        if best is None or cost < best[0]:
            best = (cost, near, scale)
        checkpoint(0.0)
    cost, near, scale = best
    if share is None and cost > 0.75 * exact_cost:
        plan = exact_plan(queries, near_radius)
        plan.estimated_cost, plan.estimated_near = exact_cost, near_exact
        return plan
    # only "closer than 4 cells (or 4 h)" matters, and a bounded search is fast even from a tube's
    # axis, where the whole wall is nearly equidistant
    bound = ALONE_WITHIN * max(cell * scale, h) * (1.0 + 1e-9)
    clearance = tree.clearance(queries, bound, lambda f: checkpoint(0.0))
    plan = shared_plan(queries, h, near_radius * scale, cell * scale, clearance,
                       checkpoint=lambda f: checkpoint(0.0))
    plan.estimated_cost, plan.estimated_near = cost, near
    return plan


class _CellCounts:
    """Number of distinct cubic cells of side ``finest`` x 2^j holding points, for j = 0, 1, ... in
    turn: the distinct cells of each size from those of the size before (floor(floor(y / 2) / 2^(j-1))
    = floor(y / 2^j), and dividing by a power of 2 is exact in floating point), so the same counts as
    flooring every point at each size, from ever fewer rows (docs/performance.md 6.1)."""

    def __init__(self, points: np.ndarray, finest: float, checkpoint: Checkpoint = no_checkpoint):
        self._rows = _distinct_rows(np.floor(points / finest).astype(np.int64), checkpoint)
        self._size = 0
        self._checkpoint = checkpoint

    def count(self, halvings: int) -> int:
        while self._size < halvings:
            self._rows = _distinct_rows(np.floor_divide(self._rows, 2), self._checkpoint)
            self._size += 1
        return len(self._rows)


def _distinct_rows(keys: np.ndarray, checkpoint: Checkpoint = no_checkpoint) -> np.ndarray:
    """The distinct rows of an int64 key matrix, in increasing order (one 1-D sort of their codes when
    the key space allows: numpy 2.4's ``np.unique`` of 1M codes took 0.55 s, a sort and a diff 0.07 s)."""
    coded = _codes(keys) if len(keys) else None
    if coded is None:
        return np.unique(keys, axis=0) if len(keys) else keys
    code, low, span = coded
    checkpoint(0.0)
    code = np.sort(code)
    code = code[np.r_[True, code[1:] != code[:-1]]]
    checkpoint(0.0)
    columns = []
    for j in range(keys.shape[1] - 1, -1, -1):
        code, digit = np.divmod(code, span[j])
        columns.append(digit)
    return np.column_stack(columns[::-1]) + low


def run_plan(
    tree: BallTree, plan: Plan, queries: np.ndarray, h: float, rows: int, bins: int, workers: int | None = None,
    checkpoint: Checkpoint = no_checkpoint, stats: np.ndarray | None = None,
    seeds: HintTables | None = None, kept: np.ndarray | None = None,
    nearest: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """beta of every query row (in the input order), the plan's clusters in contiguous streams of about
    equal estimated cost on ``workers`` threads; the checkpoint is called every ``POLL`` s meanwhile (one
    stream on one worker with ``no_checkpoint``: on this thread, nothing to poll).
    ``seeds``: kept hint tables of this tree's cloud whose nearest start a cluster's rays where nearer than the
    cluster cast before (:func:`.ray_hints.seeds_for`); ``kept`` (K, 2 x rows x bins) int32: filled
    with each cluster's hint table after its rays (docs/boundedness.md 3.18). Neither changes beta.
    ``nearest``: ``seeds.nearest`` of the plan's centres, when the caller has it."""
    q_sorted = np.ascontiguousarray(take_rows(queries, plan.order), np.float64)
    n_clusters = len(plan.starts) - 1
    if n_clusters == 0:
        return np.zeros(len(q_sorted))
    sizes = np.diff(plan.starts)
    cost = np.cumsum(rows * bins * tree.ray_cost + sizes * max(plan.estimated_near, 1.0) * CAP_COST)
    workers = max(1, int(workers or os.cpu_count() or 1))
    n_streams = max(1, min(n_clusters // STREAM_CLUSTERS, workers * STREAMS_PER_WORKER), min(workers, n_clusters))
    cuts = np.searchsorted(cost, cost[-1] * np.arange(1, n_streams) / n_streams, side="right")
    bounds = np.unique(np.r_[0, cuts, n_clusters]).astype(int).tolist()
    streams = list(zip(bounds[:-1], bounds[1:]))
    out_sorted = np.zeros(len(q_sorted))
    stats = np.zeros(6, np.int64) if stats is None else stats
    stream_stats = np.zeros((len(streams), 6), np.int64)
    done = np.zeros(len(streams), np.int64)
    stop = np.zeros(1, np.int32)
    reach = np.ascontiguousarray(plan.reach, np.float64)
    centres = np.ascontiguousarray(plan.centres, np.float64)
    starts = np.ascontiguousarray(plan.starts, np.int64)
    if seeds is not None and seeds.tables.shape[1:] != (2 * rows * bins,):
        seeds = None  # another raster's tables
    seed_of = seeds_for(seeds, centres, bounds[:-1], nearest)
    none = np.zeros(0, np.int32)
    if kept is not None and kept.shape != (n_clusters, 2 * rows * bins):
        raise ValueError(f"run_plan: kept needs shape ({n_clusters}, {2 * rows * bins}), got {kept.shape}")

    wide = tree.wide(_raycast)

    def stream(i: int) -> None:
        k0, k1 = streams[i]
        extra = (
            -1, -1, -1,  # the kernel's own hint rule and prefetch threshold
            none if seed_of is None else seeds.tables, none if seed_of is None else seeds.origins,
            none if seed_of is None else np.ascontiguousarray(seed_of[k0:k1]),
            none if kept is None else kept[k0:k1], none if kept is None else np.arange(k1 - k0, dtype=np.int32),
            -1, wide)  # the kernel's own block rule; the wide tree its packets walk
        _raycast.clusters(
            tree.points, tree.nodes, tree.leaves, q_sorted[starts[k0] : starts[k1]], np.ascontiguousarray(starts[k0 : k1 + 1] - starts[k0]),
            centres, reach, k0, k1, float(h), rows, bins, out_sorted[starts[k0] : starts[k1]], stream_stats[i], stop,
            done[i : i + 1], *extra,
        )

    if len(streams) == 1 and workers == 1 and checkpoint is no_checkpoint:
        stream(0)  # nothing to poll: the one stream on this thread, without a pool's thread start and wait
    else:
        polled_streams(stream, [(i,) for i in range(len(streams))], workers, checkpoint,
                       lambda: float(done.sum()) / max(1, n_clusters), stop, POLL)
    stats[:] += stream_stats.sum(axis=0)
    out = np.empty(len(q_sorted))
    out[plan.order] = out_sorted
    return out


def run_plan_here(tree, plan: Plan, queries: np.ndarray, h: float, rows: int, bins: int,
                  stop: np.ndarray | None = None) -> np.ndarray:
    """:func:`run_plan` in the calling thread as one stream, without its pool and polling: for callers
    that run many small plans on their own threads (skelcore.scan.viewpoint: one ray per query and
    direction).  ``tree`` needs ``points``, ``nodes`` and ``leaves`` as :class:`BallTree`'s; a set
    ``stop[0]`` makes the kernel return after the cluster it is in (the rest stays 0)."""
    q_sorted = np.ascontiguousarray(take_rows(queries, plan.order), np.float64)
    n_clusters = len(plan.starts) - 1
    out_sorted = np.zeros(len(q_sorted))
    if n_clusters > 0:
        stop = np.zeros(1, np.int32) if stop is None else stop
        _raycast.clusters(tree.points, tree.nodes, tree.leaves, q_sorted, np.ascontiguousarray(plan.starts, np.int64),
                          np.ascontiguousarray(plan.centres, np.float64), np.ascontiguousarray(plan.reach, np.float64),
                          0, n_clusters, float(h), int(rows), int(bins), out_sorted, np.zeros(6, np.int64), stop,
                          np.zeros(1, np.int64))
    out = np.empty(len(q_sorted))
    out[plan.order] = out_sorted
    return out
