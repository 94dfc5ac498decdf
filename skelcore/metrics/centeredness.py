"""Centeredness of a skeletal point set and of curve-skeleton samples (paper Sec. 2.3; docs/metrics.md 3).

A skeleton should approximate the medial axis; without a surface, the paper measures how far a
skeleton element is from the centre of the cloud points it stands for.  ``skeletal_centeredness``:
kNN centroids of skeletal points vs. their corresponding cloud points (paper Eq. 10,
``eq.skeletal_point_centeredness``).  ``curve_centeredness``: a slab cut across the curve direction,
ellipse fit of the nearest cross-section (Eq. 11, ``eq.curve_point_centeredness``).
Both return raw local values: c in [0, 1], NaN where invalid.  The rule "not bounded -> c = 0" and
the overall score (Eq. 12) are applied later in :mod:`skelcore.evaluation`, so the viewer can change
beta* and c* without recomputing.  Departures from the paper and the reference tool: docs/metrics.md.
"""

from __future__ import annotations

import os
import threading
from contextlib import contextmanager
from typing import Callable, Iterator

import numpy as np
from scipy.spatial import cKDTree

from ..geometry import (
    Checkpoint, bbox_diagonal, bounding_box, kd_tree, leaf_order, lex_order, no_checkpoint, stable_argsort, take_rows,
    unique_rows, unit_rows,
)
from ..parallel import on_threads
from ..params import Params, k_center_for
from . import _centroids, _rings as _rings_kernel
from .ellipse_fit import EllipseSums, ellipse_sums, ellipses_from_sums
from .position_knn import SHARED_FROM, PositionNeighbours, position_neighbours

__all__ = ["skeletal_centeredness", "curve_centeredness", "slab_grid", "ring_length", "cross_section_centeredness"]

# rows of skeletal points per kNN chunk: bounds memory (chunk x k x 3 floats) and keeps checkpoints
# under ~0.1 s apart on a loaded machine
_SKELETAL_CHUNK = 4096
_CURVE_SPAN = 4  # curve samples per thread task (about 5-25 ms at 1M points)
_CURVE_AT_ONCE = 50_000  # smaller clouds: all samples at once in flat arrays; larger: per sample on threads
_CURVE_SOLVE_BATCH = 8192  # sets per stacked solve after the spans (about 50 CPU ms each, load 7)
_CURVE_BATCH_PAIRS = 2_000_000  # ball candidates per batch of samples taken at once (memory: about 60 bytes each)
_BALL_ROUNDS = 1  # ball searches before a sample's whole slab is taken (the next ones rarely end a ring)
# the first ball's 2-D reach, in alpha / 2 (neuron, 100k points: 6.5 CPU s, 8.6 with 1.0; one run each, load 8.7)
_BALL_FIRST = 0.5
_BALL_MARGIN = 1e-9  # relative: the ring search's balls and the box's reach are this much larger than exact
# rings by the compiled kernel (_rings.c); False: by the array code below, its reference (the same bits, tested)
_COMPILED_RINGS = True
# a sample's share of a batch of _CURVE_BATCH_PAIRS on small clouds with the kernel (256 samples per call by
# default, a checkpoint between calls)
_KERNEL_SAMPLE_PAIRS = _CURVE_BATCH_PAIRS // 256
_RING_ROWS = 1 << 16  # the compiled rings' first buffers (rows of each coordinate)
# the kernel orders a ring's distances by the square roots of their squares, libm's hypot only where two come
# within 1e-13 (the same rings; False: hypot for every point, as numpy's np.hypot)
_BY_ROOTS = True
_RING_CHUNK = 16  # samples of a span's first kernel call (then as many as _RING_CHUNK_ROWS ring points take)
_RING_CHUNK_ROWS = 1 << 20  # ring points per kernel call in a span (16 MB of rings: an edit's 180 samples at 1M
# points in 4 calls, at 100k in 2; 2^18: 12 calls, 5 % more CPU in the calls' own work)


def skeletal_centeredness(
    corresponding_cloud: np.ndarray,
    skeletal: np.ndarray,
    *,
    params: Params = Params(),
    depth: np.ndarray | None = None,
    checkpoint: Checkpoint = no_checkpoint,
) -> np.ndarray:
    """Centeredness of every skeletal point (docs/metrics.md 3; paper Eq. 10, ``eq.skeletal_point_centeredness``).

    For skeletal point q_i take its k nearest skeletal neighbours (itself included; k from
    :func:`skelcore.params.k_center_for`, at most N_s), their centroid m_s, the centroid m_o of
    their corresponding cloud points (same rows of ``corresponding_cloud``) and M, the mean distance
    from m_s to those cloud points: c_i = max(0, 1 - |m_o - m_s| / M). M = 0 gives NaN.

    Ties: contraction leaves many skeletal points at exactly the same position, so "the k nearest"
    is often ambiguous and the choice changes m_o. Equal distances are ordered by row index, as
    MATLAB's ``knnsearch`` (the reference tool) does: in a cluster of more than k coincident points
    every member gets the k lowest-index members as its neighbours (itself not necessarily among
    them). The result does not depend on the kd-tree's internals.

    Parameters
    ----------
    corresponding_cloud : (N_s, 3) cloud point of each skeletal point (row i <-> row i).
    skeletal : (N_s, 3) skeletal point set, normalized like the cloud; finite.
    depth : SkelScope's viewpoint extension (docs/metrics.md 6.3), None for the paper's Eq. 10:
        (N_s, 3), per skeletal point a viewing direction d of length w <= 1; the component of
        m_o - m_s along d / |d|, turned square to the neighbours' line, is left out times w (w = 1:
        nothing was observed behind).

    Returns
    -------
    (N_s,) raw centeredness; the unbounded -> 0 rule is NOT applied here. Empty input -> empty.

    Examples
    --------
    >>> ring = np.array([[np.cos(a), np.sin(a), 0] for a in np.linspace(0, 2 * np.pi, 12, endpoint=False)])
    >>> skeletal_centeredness(ring, np.zeros((12, 3)), params=Params(k_center=12)).round(12).tolist()[:3]
    [1.0, 1.0, 1.0]
    """
    cloud = np.asarray(corresponding_cloud, dtype=float)
    skel = np.asarray(skeletal, dtype=float)
    if skel.ndim != 2 or skel.shape[1] != 3 or cloud.shape != skel.shape:
        raise ValueError(
            f"skeletal points {skel.shape} and their corresponding cloud points {cloud.shape} "
            "must both be (N, 3) with the same N"
        )
    if not np.all(np.isfinite(skel)):
        raise ValueError("skeletal points contain NaN or inf")
    n = len(skel)
    if n == 0:
        return np.full(0, np.nan)
    k = min(k_center_for(n, params), n)
    checkpoint(0.0)
    groups = _CoincidentGroups(skel, checkpoint)
    checkpoint(0.0)
    # the tree, and the head of each answer, shared with skeletal smoothness (docs/performance.md 6.4)
    shared = _shared_neighbours(skel, groups.positions, checkpoint)
    if shared is None:
        tree = kd_tree(groups.positions, checkpoint)
        # groups are visited in the tree's leaf order and the rows gathered in member (x-sorted) order:
        # both keep a chunk's memory traffic local (3 x faster at 1M points, same arithmetic)
        visit = leaf_order(tree)
    else:
        tree, visit = shared.tree(groups.positions, checkpoint)
    checkpoint(0.0)
    skel_m = take_rows(skel, groups.members)
    checkpoint(0.0)
    cloud_m = take_rows(cloud, groups.members)
    checkpoint(0.0)
    n_groups = len(groups.positions)
    per_group = np.full(n_groups, np.nan)
    if depth is not None:
        depth = np.asarray(depth, dtype=float)
        first_row = np.zeros(n_groups, np.int64)
        first_row[groups.group_of[::-1]] = np.arange(n)[::-1]
    threads = (os.cpu_count() or 1) if n_groups >= 2 * _SKELETAL_CHUNK else 1

    def span(lo: int, hi: int) -> None:
        which = visit[lo:hi]
        slot = groups.k_nearest_slots(tree, which, k, workers=1, publish=None if shared is None else shared.publish)
        m_s, m_o, spread = _neighbour_sums(skel_m, cloud_m, slot)
        shift = m_o - m_s
        if depth is not None:  # coincident points share a position, hence a depth: the group's first row's
            shift = shift - _unobserved(shift, depth[first_row[which]], take_rows(skel_m, slot) - m_s[:, None, :])
        offset = np.linalg.norm(shift, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            c = np.maximum(0.0, 1.0 - offset / spread)
        c[~(spread > 0)] = np.nan
        per_group[which] = c

    # chunks on every core, each query single-threaded (docs/performance.md 6.3); one chunk (a small set)
    # runs on this thread alone: the evaluation's other stages run beside it (docs/performance.md 6.2)
    on_threads(span, [(lo, min(lo + _SKELETAL_CHUNK, n_groups)) for lo in range(0, n_groups, _SKELETAL_CHUNK)],
               threads, checkpoint)
    # coincident points have the same neighbours (ties go by index, not by self), so the same c
    return per_group[groups.group_of]


def _shared_neighbours(skel: np.ndarray, positions: np.ndarray, checkpoint: Checkpoint) -> PositionNeighbours | None:
    """The distinct positions' shared index (:mod:`.position_knn`) when ``positions`` are, byte for byte,
    ``unique_rows``' kept answer for these skeletal points (the array smoothness reads), else None."""
    if len(positions) < SHARED_FROM:
        return None
    uniq = unique_rows(skel, checkpoint)[0]
    if uniq.shape != positions.shape or uniq.tobytes() != positions.tobytes():  # -0.0: other bytes, not shared
        return None
    return position_neighbours(uniq)


def _unobserved(shift: np.ndarray, depth: np.ndarray, around: np.ndarray) -> np.ndarray:
    """The part of m_o - m_s that a one-sided view makes up (docs/metrics.md 6.3): its component along
    the viewing direction d / |d| turned square to the skeleton's local direction (the neighbours'
    ``around`` principal axis, as far as they lie on a line: a tube seen obliquely shows the side facing
    the sensor), times the weight |d|."""
    w = np.linalg.norm(depth, axis=1)
    u = np.divide(depth, w[:, None], out=np.zeros_like(depth), where=w[:, None] > 0)
    vals, vecs = np.linalg.eigh(np.matmul(around.transpose(0, 2, 1), around))
    line = np.where(vals[:, 2] > 0, 1.0 - vals[:, 1] / np.where(vals[:, 2] > 0, vals[:, 2], 1.0), 0.0)
    t = vecs[:, :, 2]
    u = u - (line * np.einsum("ij,ij->i", u, t))[:, None] * t
    n = np.linalg.norm(u, axis=1, keepdims=True)
    u = np.divide(u, n, out=np.zeros_like(u), where=n > 1e-6)
    return (np.einsum("ij,ij->i", shift, u) * w)[:, None] * u


def _neighbour_sums(skel_m: np.ndarray, cloud_m: np.ndarray, slot: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(m_s, m_o, M) of every row of ``slot`` (docs/metrics.md 3): the means of the slotted skeletal and
    cloud rows and the mean distance from m_s to those cloud rows, in the compiled kernel ``_centroids.c``
    (no (n, k, 3) gather: about 8 x less CPU at 1M points).  The same bits as numpy's
    ``skel_m[slot].mean(axis=1)``, ``cloud_m[slot].mean(axis=1)`` and
    ``np.sqrt(np.einsum("ijk,ijk->ij", d, d)).mean(axis=1)`` of d = the cloud rows - m_s (tested)."""
    n = len(slot)
    m_s, m_o, spread = np.empty((n, 3)), np.empty((n, 3)), np.empty(n)
    _centroids.neighbour_sums(np.ascontiguousarray(skel_m, np.float64), np.ascontiguousarray(cloud_m, np.float64),
                              np.ascontiguousarray(slot, np.int64), m_s, m_o, spread)
    return m_s, m_o, spread


class _CoincidentGroups:
    """Skeletal points grouped by exact position; members of each group in increasing row order."""

    def __init__(self, points: np.ndarray, checkpoint: Checkpoint = no_checkpoint) -> None:
        # lexsort is stable, so each group's members come out in increasing row order; it is also
        # much faster than np.unique(axis=0). -0.0 == 0.0, so both land in one group.
        order = lex_order(points)
        checkpoint(0.0)
        ordered = take_rows(points, order)
        new = np.ones(len(points), dtype=bool)
        new[1:] = np.any(ordered[1:] != ordered[:-1], axis=1)
        checkpoint(0.0)
        self.starts = np.flatnonzero(new)
        self.counts = np.diff(np.append(self.starts, len(points)))
        self.single = bool(len(points)) and int(self.counts.max()) == 1
        self.positions = ordered[self.starts] + 0.0
        self.members = order
        self.group_of = np.empty(len(points), dtype=np.int64)
        self.group_of[order] = np.cumsum(new) - 1

    def k_nearest_slots(self, tree: cKDTree, queries: np.ndarray, k: int, workers: int = -1,
                        publish: Callable | None = None) -> np.ndarray:
        """(len(queries), k) indices into ``members`` (so rows ``members[...]``): the k points nearest
        to each query group's position, equal distances in row order. Whole groups are taken nearest
        first; the last one contributes its lowest-index members. (Distinct positions at exactly
        equal distances keep the tree's order.)  ``publish(queries, distances, groups)`` is handed the
        tree's answers (:meth:`.position_knn.PositionNeighbours.publish`).
        """
        n_q = len(queries)
        k_groups = min(k, len(self.positions))  # every group has >= 1 member, so k groups suffice
        dist, near = tree.query(take_rows(self.positions, queries), k=k_groups, workers=workers)
        near = near.reshape(n_q, k_groups)
        if publish is not None:
            publish(queries, dist.reshape(n_q, k_groups), near)
        if self.single:  # no coincident points: the k nearest groups are the k nearest points
            return self.starts[near]
        cum = np.cumsum(self.counts[near], axis=1)  # >= k in the last column
        # slot[q, t] = first j with cum[q, j] > t: one flat searchsorted with per-row offsets
        stride = int(cum[:, -1].max()) + 1
        row_offset = np.arange(n_q, dtype=np.int64)[:, None] * stride
        t = np.arange(k, dtype=np.int64)[None, :]
        slot = np.searchsorted((cum + row_offset).ravel(), (t + row_offset).ravel(), side="right")
        slot = slot.reshape(n_q, k) - np.arange(n_q, dtype=np.int64)[:, None] * k_groups
        before = np.where(slot > 0, np.take_along_axis(cum, np.maximum(slot - 1, 0), axis=1), 0)
        group = np.take_along_axis(near, slot, axis=1)
        return self.starts[group] + (t - before)


def curve_centeredness(
    cloud: np.ndarray,
    sample_points: np.ndarray,
    sample_directions: np.ndarray,
    *,
    params: Params = Params(),
    checkpoint: Checkpoint = no_checkpoint,
    grid: "_SlabGrid | None" = None,
    span: int | None = None,
) -> np.ndarray:
    """Centeredness of curve samples from the cloud's cross-section (docs/metrics.md 3; paper Eq. 11,
    ``eq.curve_point_centeredness``).

    For sample p with direction u: the slab of cloud points x with |u . (x - p)| < alpha / 2,
    alpha = ``params.slab_factor`` x bounding-box diagonal of ``cloud``; the slab and p projected
    onto two unit vectors orthogonal to u; the ring = slab points sorted by 2-D distance to p, kept
    while each next distance is < ``params.ring_growth`` x the last kept one (isolates the nearest
    cross-section from other branches); then :func:`cross_section_centeredness`.

    Invalid (NaN): a NaN direction (joint vertex), fewer than 3 ring points. The unbounded -> 0
    rule is NOT applied here.

    The slab is a plate spanning the whole cloud, but only its points up to the ring's end matter: a
    compiled kernel takes them from the grid cells (side max(alpha / 2, diagonal / 512)) in growing balls
    around p (the array code, its reference: one kd-tree ball, then the whole slab).  Either way the result
    equals that of testing every cloud point, in the grid's order for equal distances.  Clouds under 50k
    points take the samples in batches of flat arrays, larger ones in spans on threads; both give the
    same bits (docs/performance.md 6.5).
    ``grid``: :func:`slab_grid` of the same cloud and params, when kept from an earlier call. ``span``:
    samples per thread task on large clouds (default 4; an edit's update asks for larger ones: fewer
    batched fits, the same bits).
    """
    cloud = np.asarray(cloud, dtype=float)
    points = np.asarray(sample_points, dtype=float)
    dirs = np.asarray(sample_directions, dtype=float)
    if cloud.ndim != 2 or cloud.shape[1] != 3:
        raise ValueError(f"cloud must be (N, 3), got {cloud.shape}")
    if points.ndim != 2 or points.shape[1] != 3 or dirs.shape != points.shape:
        raise ValueError(f"sample points {points.shape} and directions {dirs.shape} must both be (S, 3)")
    n_samples = len(points)
    out = np.full(n_samples, np.nan)
    if n_samples == 0 or len(cloud) == 0:
        return out
    u = unit_rows(dirs)
    todo = np.flatnonzero(np.all(np.isfinite(u), axis=1) & np.all(np.isfinite(points), axis=1))
    # a kept grid holds the cloud's bounding box: the same bits, without a pass over the cloud (an edit's
    # update scores a few samples against a million points)
    diagonal = bbox_diagonal(cloud) if grid is None else float(np.linalg.norm(grid.hi - grid.lo))
    half = 0.5 * float(params.slab_factor) * diagonal
    if len(todo) == 0 or not half > 0:
        return out  # no direction, or a cloud without extent: every slab is empty
    growth = float(params.ring_growth)
    checkpoint(0.0)
    if grid is None:
        grid = _SlabGrid(cloud, cell=max(half, diagonal / 512.0), checkpoint=checkpoint)
    g, h = _orthonormal_complement(u[todo])

    if len(cloud) < _CURVE_AT_ONCE:
        # small clouds: the samples in batches of flat arrays on this thread (docs/performance.md 6.5); a
        # batch holds about _CURVE_BATCH_PAIRS candidates of the first ball (the kernel's: 256 samples)
        if _COMPILED_RINGS:
            bounds = np.arange(len(todo) + 1) * _KERNEL_SAMPLE_PAIRS
        else:
            first = grid.tree.query_ball_point(points[todo], _ball_radius(np.full(len(todo), _BALL_FIRST * half), half),
                                               return_length=True)
            bounds = np.r_[0, np.cumsum(first)]
        lo = 0
        with grid.ring_buffers() as bufs:
            while lo < len(todo):
                hi = lo + max(1, int(np.searchsorted(bounds[lo:], bounds[lo] + _CURVE_BATCH_PAIRS, side="right")) - 1)
                x, y, starts = _ring_columns(grid, points[todo[lo:hi]], u[todo[lo:hi]], g[lo:hi], h[lo:hi], half,
                                             growth, lambda: checkpoint(lo / len(todo)), bufs)
                out[todo[lo:hi]] = _rings_centeredness(x, y, starts)
                lo = hi
                checkpoint(lo / len(todo))
        return out

    counts = np.zeros(len(todo), np.int64)
    spare_centre, spare_r = np.full((len(todo), 2), np.nan), np.full(len(todo), np.nan)
    parts: list[EllipseSums] = []

    def span_sums(i0: int, i1: int) -> tuple[EllipseSums, np.ndarray, np.ndarray, np.ndarray]:
        # about _RING_CHUNK_ROWS ring points at a time (as many samples as the rings so far say, _RING_CHUNK
        # first) into the grid's kept buffers, which stay that size (each set's sums are its own: the same
        # bits in any grouping)
        found = []
        with grid.ring_buffers() as bufs:
            c1, rows = i0, 0
            while c1 < i1:
                c0 = c1
                c1 = min(i1, c0 + (_RING_CHUNK if c0 == i0 else max(1, _RING_CHUNK_ROWS * (c0 - i0) // max(rows, 1))))
                x, y, starts = _ring_columns(grid, points[todo[c0:c1]], u[todo[c0:c1]], g[c0:c1], h[c0:c1], half,
                                             growth, bufs=bufs)
                sums = ellipse_sums(x, y, starts, bufs)
                unfitted = np.ones(len(starts) - 1, bool)
                unfitted[sums.use] = False
                centre, r = _spare_fits(x, y, starts, np.flatnonzero(unfitted & (np.diff(starts) >= 3)))
                found.append((sums.shifted(c0), np.diff(starts), centre, r))
                rows += int(starts[-1])
        if len(found) == 1:
            return found[0]
        return EllipseSums.joined([f[0] for f in found]), *(np.concatenate(a) for a in list(zip(*found))[1:])

    def store(span_: tuple[int, int], found: tuple) -> None:
        parts.append(found[0])
        counts[span_[0] : span_[1]], spare_centre[span_[0] : span_[1]], spare_r[span_[0] : span_[1]] = found[1:]

    # the samples' slabs are independent and numpy and the kd-tree release the GIL: spans of samples on
    # every core (docs/performance.md 6.3), each span's rings reduced to their fits' sums there (a ring
    # leaves its thread as 36 numbers); the stacked solves of all the sets follow in batches (a set's fit
    # does not depend on the others in its batch), a checkpoint after each (docs/performance.md 4)
    step = max(1, int(span)) if span else _CURVE_SPAN
    on_threads(span_sums, [(i, min(i + step, len(todo))) for i in range(0, len(todo), step)], None,
               checkpoint, store)
    sums = EllipseSums.joined(parts)
    centers, axes = np.full((len(todo), 2), np.nan), np.full((len(todo), 2), np.nan)
    for lo in range(0, len(sums.use), _CURVE_SOLVE_BATCH):
        part = EllipseSums(*(a[lo : lo + _CURVE_SOLVE_BATCH] for a in sums))
        found, semi, _ = ellipses_from_sums(part, len(todo))
        fitted = part.use[~np.isnan(found[part.use, 0])]
        centers[fitted], axes[fitted] = found[fitted], semi[fitted]
        checkpoint(1.0)
    # a set the solve rejected takes the ring's mean and farthest point: its ring found again (rare on real
    # scans; a flat sheet's rings are all collinear, so on threads too)
    redo = np.flatnonzero(np.isnan(centers[:, 0]) & np.isnan(spare_r) & (counts >= 3))

    def span_spares(i0: int, i1: int) -> tuple[np.ndarray, np.ndarray]:
        ids = redo[i0:i1]
        with grid.ring_buffers() as bufs:
            x, y, starts = _ring_columns(grid, points[todo[ids]], u[todo[ids]], g[ids], h[ids], half, growth, bufs=bufs)
            return _spare_fits(x, y, starts, np.arange(len(ids)))

    def keep(span_: tuple[int, int], found: tuple[np.ndarray, np.ndarray]) -> None:
        ids = redo[span_[0] : span_[1]]
        spare_centre[ids], spare_r[ids] = found

    on_threads(span_spares, [(i, min(i + step, len(redo))) for i in range(0, len(redo), step)], None,
               lambda _: checkpoint(1.0), keep)
    out[todo] = _centeredness(centers, axes, counts, spare_centre, spare_r)
    return out


def _ball_radius(reach: np.ndarray, half: float) -> np.ndarray:
    """Radius of the ball around p that holds every slab point within 2-D distance ``reach`` of p:
    sqrt(reach^2 + (alpha / 2)^2), with a margin that absorbs round-off."""
    return np.sqrt(reach * reach + half * half) * (1.0 + _BALL_MARGIN)


def _rings(
    grid: "_SlabGrid", points: np.ndarray, u: np.ndarray, g: np.ndarray, h: np.ndarray, half: float, growth: float,
    tick: Callable[[], None] = lambda: None,
) -> tuple[np.ndarray, np.ndarray]:
    """The rings of :func:`_ring_columns` as (M, 2) ring points and each sample's start in them (the
    kernel's rings in the grid's kept buffers, copied out)."""
    with grid.ring_buffers() as bufs:
        x, y, starts = _ring_columns(grid, points, u, g, h, half, growth, tick, bufs)
        return np.column_stack([x, y]), starts


def _ring_columns(
    grid: "_SlabGrid", points: np.ndarray, u: np.ndarray, g: np.ndarray, h: np.ndarray, half: float, growth: float,
    tick: Callable[[], None] = lambda: None, bufs: "_RingBuffers | None" = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rings of the samples (p, u) with plane axes (g, h): the ring points' plane coordinates x and y
    (p at the origin) sample after sample, and each sample's start in them.

    Only slab points up to the ring's end matter, and a slab point at 2-D distance <= R lies in the ball
    of radius :func:`_ball_radius` (R) around p.  The ball's slab points with distance <= R, sorted by
    (distance, grid row), are the head of the whole slab's sorted list; the ring is final when it breaks
    inside them, when growth x its last distance <= R (the next point, beyond R, breaks it) or when R
    reaches past the cloud's box; otherwise R doubles, and after ``_BALL_ROUNDS`` balls the sample's whole
    slab is taken (:func:`_slab_ring`, ``tick`` after each).  The same candidates' values in the same order
    as testing every grid row: the same rings, bit for bit (docs/performance.md 6.5).  With
    ``_COMPILED_RINGS`` (the default) :func:`_kernel_rings` answers; the array code here is its reference.
    """
    if _COMPILED_RINGS:
        return _kernel_rings(grid, points, u, g, h, half, growth, bufs)
    n = len(points)
    far = np.linalg.norm(np.maximum(np.abs(grid.lo - points), np.abs(grid.hi - points)), axis=1) * (1.0 + _BALL_MARGIN)
    reach = np.full(n, _BALL_FIRST * half)
    todo = np.arange(n)
    none = np.empty(0)
    rings = [(none, none)] * n  # each sample's ring, joined in sample order once (no sort of them all)
    for _ in range(_BALL_ROUNDS):
        if not len(todo):
            break
        r = reach[todo]
        rows, counts = _ball_rows(grid, points[todo], _ball_radius(r, half))
        loc = np.repeat(np.arange(len(todo)), counts)
        sid = todo[loc]
        rel = take_rows(grid.points, rows) - take_rows(points, sid)
        inside = np.abs(_dot3(rel, take_rows(u, sid))) < half
        rel, loc, sid = np.compress(inside, rel, axis=0), loc[inside], sid[inside]
        fx, fy = _dot3(rel, take_rows(g, sid)), _dot3(rel, take_rows(h, sid))
        dist = np.hypot(fx, fy)
        near = dist <= r[loc]
        loc, dist, fx, fy = loc[near], dist[near], fx[near], fy[near]
        starts = np.searchsorted(loc, np.arange(len(todo) + 1))
        order = _order_within(dist, starts)  # stable: equal distances keep the grid's row order
        dist, fx, fy = dist[order], fx[order], fy[order]
        in_ring, ring_len = _leading_rings(loc, dist, starts, growth)
        count = np.diff(starts)
        last = dist[np.maximum(starts[:-1] + ring_len - 1, 0)] if len(dist) else np.zeros(len(todo))
        grown = np.where(count > 0, growth * last, 0.0)
        done = (ring_len < count) | ((count > 0) & (grown <= r)) | (r >= far[todo])
        keep, cut = in_ring & done[loc], np.cumsum(ring_len[done])[:-1]
        for i, rx, ry in zip(todo[done].tolist(), np.split(fx[keep], cut), np.split(fy[keep], cut)):
            rings[i] = (rx, ry)
        reach[todo] = np.maximum(2.0 * r, grown)
        todo = todo[~done]
    if len(todo):  # rings wider than the balls (often a long thin shape's whole slab): the slab by grid cells
        for i in todo.tolist():
            rings[i] = _slab_ring(grid, points[i], u[i], g[i], h[i], half, growth)
            tick()
    return (np.concatenate([ring[0] for ring in rings]), np.concatenate([ring[1] for ring in rings]),
            np.r_[0, np.cumsum([len(ring[0]) for ring in rings])])


def _kernel_rings(
    grid: "_SlabGrid", points: np.ndarray, u: np.ndarray, g: np.ndarray, h: np.ndarray, half: float, growth: float,
    bufs: "_RingBuffers | None" = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_ring_columns` by the compiled kernel ``_rings.c``: the same rings, bit for bit (tested), from
    the grid's cells around p in growing balls (the first of reach ``_BALL_FIRST`` x alpha / 2), without the
    kd-tree or the whole slab's arrays (docs/performance.md 6.5).  The kernel writes the rings into ``bufs``
    (new ones when None), so x and y are views of them, valid until ``bufs`` is written again; where a ring
    does not fit, the buffers grow and the kernel goes on from that sample."""
    n = len(points)
    bufs = _RingBuffers() if bufs is None else bufs
    points, u, g, h = (np.ascontiguousarray(a, np.float64) for a in (points, u, g, h))
    bounds = np.zeros(n + 1, np.int64)
    done = end = 0
    while True:
        step, need = _rings_kernel.rings(grid.columns, grid.keys, grid.starts, grid.counts, grid.lines, grid.centres,
                                         grid.frame, grid.dims, points[done:], u[done:], g[done:], h[done:],
                                         float(half), float(growth), float(_BALL_FIRST * half), bufs.fx, bufs.fy,
                                         bounds[done:], end, _BY_ROOTS)
        done += step
        end = int(bounds[done])
        if done == n:
            return bufs.fx[:end], bufs.fy[:end], bounds
        # the rings so far, per sample, for the samples left, with room to spare
        bufs.grow(end + need + (end // max(done, 1)) * (n - done) * 5 // 4, keep=end)


class _RingBuffers:
    """The compiled rings' output rows (each coordinate's column) and the ellipse fit's design rows, grown as
    needed and kept by the grid (:meth:`_SlabGrid.ring_buffers`): fresh buffers for an edit's 180 moved
    samples at 1M points cost about as much in page faults and copies as the rings themselves
    (docs/performance.md 6.10)."""

    def __init__(self) -> None:
        self.fx, self.fy = np.empty(_RING_ROWS), np.empty(_RING_ROWS)
        self.design = np.empty((0, 6))

    def grow(self, size: int, keep: int = 0) -> None:
        """At least ``size`` rows each, the first ``keep`` rows kept."""
        if len(self.fx) < size:
            fx, fy = np.empty(size), np.empty(size)
            fx[:keep], fy[:keep] = self.fx[:keep], self.fy[:keep]
            self.fx, self.fy = fx, fy


def _ball_rows(grid: "_SlabGrid", points: np.ndarray, radius: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows of ``grid.points`` within ``radius`` of each point, each point's in grid order, and their
    counts: the kd-tree's unsorted lists as arrays, put in order by one sort of (point, row) keys (about
    1.6 x faster than its sorted lists through Python integers)."""
    found = grid.tree.query_ball_point(points, radius, return_sorted=False)
    counts = np.fromiter(map(len, found), np.int64, count=len(found))
    if not counts.sum():
        return np.zeros(0, np.int64), counts
    offset = np.repeat(np.arange(len(found), dtype=np.int64) * len(grid.points), counts)
    key = np.concatenate([np.array(rows, np.int64) for rows in found]) + offset
    key.sort()
    return key - offset, counts


def _slab_ring(
    grid: "_SlabGrid", p: np.ndarray, u: np.ndarray, g: np.ndarray, h: np.ndarray, half: float, growth: float,
) -> tuple[np.ndarray, np.ndarray]:
    """One sample's ring from its whole slab: the points of every grid cell that can meet the slab, in
    grid order, tested, sorted stably by distance and cut (p at the origin).  Coordinates are taken
    column by column (contiguous, about 1.5 x faster than rows of 3), with :func:`_dot3`'s operations in
    its order: the same bits."""
    rows = grid.slab_rows(p, u, half)
    x, y, z = (grid.columns[k].take(rows) - p[k] for k in range(3))
    inside = np.abs(x * u[0] + y * u[1] + z * u[2]) < half
    x, y, z = (np.compress(inside, c) for c in (x, y, z))  # = c[mask], 2 x faster
    fg, fh = x * g[0] + y * g[1] + z * g[2], x * h[0] + y * h[1] + z * h[2]
    dist = np.hypot(fg, fh)
    order = stable_argsort(dist)
    keep = order[: ring_length(dist[order], growth)]
    return fg.take(keep), fh.take(keep)


def _order_within(values: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """The stable order of ``values`` inside each run ``starts[i]:starts[i + 1]`` (runs kept in place):
    ``np.lexsort((values, run))`` by one sort per run, about 5 x faster on runs of 700."""
    order = np.empty(len(values), np.int64)
    for a, b in zip(starts[:-1].tolist(), starts[1:].tolist()):
        if b > a:
            order[a:b] = stable_argsort(values[a:b]) + a
    return order


def _leading_rings(sid: np.ndarray, dist: np.ndarray, starts: np.ndarray, growth: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`ring_length` of every sample at once: ``dist[starts[i]:starts[i + 1]]`` are sample i's
    sorted distances (``sid`` its sample ids).  Returns the mask of the positions kept and each ring's
    length."""
    stop = np.ones(len(dist), dtype=bool)  # stop[j]: the ring ends after position j
    if len(dist) > 1:
        stop[:-1] = ~(dist[1:] < growth * dist[:-1]) | (sid[1:] != sid[:-1])
    ends = np.flatnonzero(stop)
    first, counts = starts[:-1], np.diff(starts)
    first_stop = ends[np.minimum(np.searchsorted(ends, first), len(ends) - 1)] if len(ends) else first
    ring_len = np.where(counts > 0, first_stop - first + 1, 0)
    position = np.arange(len(dist)) - np.repeat(first, counts)
    return position < np.repeat(ring_len, counts), ring_len


def _rings_centeredness(x: np.ndarray, y: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """:func:`cross_section_centeredness` (p_hat at the origin) of the ring ``x[starts[i]:starts[i + 1]]``
    (and y) for every i: one batched fit; the sets it rejects (fewer than 5 points, or no ellipse) take
    the ring mean and the farthest ring point instead.  Set i's value does not depend on the other sets."""
    counts = np.diff(starts)
    sums = ellipse_sums(x, y, starts)
    centers, axes, _ = ellipses_from_sums(sums, len(counts))
    spare_centre, spare_r = _spare_fits(x, y, starts, np.flatnonzero(np.isnan(centers[:, 0]) & (counts >= 3)))
    return _centeredness(centers, axes, counts, spare_centre, spare_r)


def _spare_fits(x: np.ndarray, y: np.ndarray, starts: np.ndarray, which: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The ring mean and the distance of the farthest ring point of the sets ``which`` (NaN for the
    others): the stand-in for a fit the solver rejects."""
    centre, r = np.full((len(starts) - 1, 2), np.nan), np.full(len(starts) - 1, np.nan)
    for i in np.asarray(which).tolist():
        pts = np.column_stack([x[starts[i] : starts[i + 1]], y[starts[i] : starts[i + 1]]])
        centre[i] = pts.mean(axis=0)
        r[i] = np.sqrt(pts[:, 0] ** 2 + pts[:, 1] ** 2).max()
    return centre, r


def _centeredness(centers: np.ndarray, axes: np.ndarray, counts: np.ndarray, spare_centre: np.ndarray,
                  spare_r: np.ndarray) -> np.ndarray:
    """c = max(0, 1 - |centre| / r) of every ring: the fit's centre and mean semi-axis, or where there is
    no fit the ring's mean and farthest point; NaN for fewer than 3 points or r not > 0."""
    r = (axes[:, 0] + axes[:, 1]) / 2.0
    spare = np.isnan(centers[:, 0]) & (counts >= 3)
    centers, r = np.where(spare[:, None], spare_centre, centers), np.where(spare, spare_r, r)
    with np.errstate(invalid="ignore", divide="ignore"):
        c = np.maximum(0.0, 1.0 - np.sqrt(centers[:, 0] ** 2 + centers[:, 1] ** 2) / r)
    c[~(r > 0) | ~np.isfinite(r) | (counts < 3)] = np.nan
    return c


def _dot3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot products of (M, 3) ``a`` with (3,) or (M, 3) ``b`` by element-wise operations, so
    one sample alone and many samples at once round alike."""
    return a[:, 0] * b[..., 0] + a[:, 1] * b[..., 1] + a[:, 2] * b[..., 2]


def slab_grid(cloud: np.ndarray, params: Params = Params()) -> "_SlabGrid":
    """The cloud bucketed as :func:`curve_centeredness` buckets it (kept to score more samples later)."""
    cloud = np.asarray(cloud, dtype=float)
    diagonal = bbox_diagonal(cloud)
    half = 0.5 * float(params.slab_factor) * diagonal
    return _SlabGrid(cloud, cell=max(half, diagonal / 512.0))


class _SlabGrid:
    """Cloud points bucketed in cubic cells (sorted by cell) for slab lookups, and a kd-tree of them
    for ball lookups; the grid order is the order of equal ring distances (the ellipse fit's sums)."""

    def __init__(self, cloud: np.ndarray, cell: float, checkpoint: Checkpoint = no_checkpoint) -> None:
        self.lo, self.hi = bounding_box(cloud)
        ijk = np.floor((cloud - self.lo) / cell).astype(np.int64)
        checkpoint(0.0)
        dims = ijk.max(axis=0) + 1
        key = ijk[:, 0] + dims[0] * (ijk[:, 1] + dims[1] * ijk[:, 2])
        checkpoint(0.0)
        order = np.argsort(key, kind="stable")
        checkpoint(0.0)
        self.points = take_rows(cloud, order)
        srt = key[order]  # already sorted: cell boundaries by one diff, not a second sort (np.unique)
        self.starts = np.flatnonzero(np.r_[True, srt[1:] != srt[:-1]])
        self.counts = np.diff(np.r_[self.starts, len(srt)])
        keys = srt[self.starts]
        cell_ijk = np.column_stack([keys % dims[0], (keys // dims[0]) % dims[1], keys // (dims[0] * dims[1])])
        self.centres = np.ascontiguousarray(self.lo + (cell_ijk + 0.5) * cell, dtype=np.float64)
        self.half_cell = 0.5 * cell
        checkpoint(0.0)
        self.columns = np.ascontiguousarray(self.points.T)  # x, y and z apart: the slab's tests on contiguous arrays
        self.keys, self.dims = np.ascontiguousarray(keys, np.int64), np.ascontiguousarray(dims, np.int64)
        # each line of cells (j, k)'s first occupied cell: the compiled rings' lookups without a search of all keys
        lines = np.arange(int(dims[1] * dims[2]) + 1, dtype=np.int64) * int(dims[0])
        self.lines = np.searchsorted(self.keys, lines).astype(np.int64)
        # the compiled rings' frame: the grid's corner, its cell side and the coordinates' magnitude
        self.frame = np.array([*self.lo, cell, float(np.abs(np.r_[self.lo, self.hi]).max())], dtype=float)
        self._tree: cKDTree | None = None
        self._spare: list[_RingBuffers] = []
        self._lock = threading.Lock()

    @contextmanager
    def ring_buffers(self) -> Iterator[_RingBuffers]:
        """Buffers for the compiled rings, this caller's alone until the block ends, then kept for the next
        (as many as ever ran at once: one per core at most)."""
        with self._lock:
            bufs = self._spare.pop() if self._spare else _RingBuffers()
        try:
            yield bufs
        finally:
            with self._lock:
                self._spare.append(bufs)

    @property
    def tree(self) -> cKDTree:
        """A kd-tree of ``points`` (ball queries in grid order), built on first use: the compiled rings
        look cells up in the grid itself."""
        if self._tree is None:
            self._tree = kd_tree(self.points)
        return self._tree

    def reach(self, u: np.ndarray, half: float) -> np.ndarray:
        """How far from the slab's mid-plane a cell centre may lie for the cell to meet the slab, for
        unit rows ``u``: a cube's extent along u is half_cell x |u|_1; the small margin absorbs round-off."""
        return half + self.half_cell * np.abs(u).sum(axis=-1) * (1 + 1e-9) + 1e-12

    def slab_candidates(self, p: np.ndarray, u: np.ndarray, half: float) -> np.ndarray:
        """Points of every cell that may meet the slab |u . (x - p)| < half (a superset of it)."""
        return take_rows(self.points, self.slab_rows(p, u, half))

    def slab_rows(self, p: np.ndarray, u: np.ndarray, half: float) -> np.ndarray:
        """Rows of ``self.points`` of every cell that may meet the slab, in grid order.  The centres'
        heights as c . u - p . u (one product, no (cells, 3) difference), with a margin for its round-off."""
        size = float(np.abs(self.centres).max(initial=0.0)) + float(np.abs(p).max())
        reach = self.reach(u, half) + 1e-12 * size
        return self.cell_rows(np.flatnonzero(np.abs(self.centres @ u - float(p @ u)) < reach))

    def cell_rows(self, cells: np.ndarray) -> np.ndarray:
        """Rows of ``self.points`` of the given cells, cell after cell, each cell's in grid order."""
        starts, counts = self.starts[cells], self.counts[cells]
        shift = np.repeat(starts - (np.cumsum(counts) - counts), counts)
        return np.arange(int(counts.sum())) + shift


def _orthonormal_complement(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors g, h per unit row of u with (u, g, h) orthonormal."""
    helper = np.zeros_like(u)
    helper[np.arange(len(u)), np.argmin(np.abs(u), axis=1)] = 1.0
    g = np.cross(u, helper)
    g /= np.linalg.norm(g, axis=1, keepdims=True)
    h = np.cross(u, g)
    return g, h


def ring_length(sorted_distances: np.ndarray, growth: float) -> int:
    """Length of the leading run of ``sorted_distances`` in which each next distance is
    < growth x the previous one (the ring isolation of docs/metrics.md 3.2). 0 for an empty array."""
    d = np.asarray(sorted_distances, dtype=float)
    if len(d) == 0:
        return 0
    breaks = np.flatnonzero(~(d[1:] < growth * d[:-1]))
    return int(breaks[0] + 1) if len(breaks) else len(d)


def cross_section_centeredness(ring: np.ndarray, p_hat: np.ndarray | None = None) -> float:
    """c = max(0, 1 - |p_hat - centre| / r) for one cross-section ring (docs/metrics.md 3).

    centre and r from :func:`fit_ellipse` (conic centre, mean semi-axis); with fewer than 5 points
    or no valid ellipse, centre = ring mean and r = largest distance from p_hat to a ring point.
    Fewer than 3 points, or r = 0: NaN. ``p_hat`` defaults to the origin.
    """
    ring = np.asarray(ring, dtype=float).reshape(-1, 2)
    if p_hat is not None:
        ring = ring - np.asarray(p_hat, dtype=float).reshape(2)
    return float(_rings_centeredness(ring[:, 0].copy(), ring[:, 1].copy(), np.array([0, len(ring)]))[0])
