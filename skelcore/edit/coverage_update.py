"""The curve's coverage after an edit (docs/metrics.md section 5.2), updated by difference: the same
values as :func:`skelcore.metrics.coverage.coverage` of the edited curve's elements, to the bit. An
element's radius depends on its position alone (its nearest cloud point) while the noise shortfall
keeps its ratio, so kept elements keep their radii; a cloud point's gap is a minimum and its verdict an
"any" over the balls, so only the points a removed ball could have decided are asked again of every
ball, and the others take the minimum of their old gap and the added balls' (the cover test's rounding
allowance reads the largest ball: when it changes, or the shortfall's ratio does, all is asked again,
as above ``coverage_exact_points`` where coverage is estimated on a subsample)."""

from __future__ import annotations

import threading
import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np

from scipy.spatial import cKDTree

from ..geometry import kd_tree, no_checkpoint, unique_rows
from ..metrics.ball_tree import COVER_EPS, BallTree
from ..metrics.coverage import (NOISE_MIN_POINTS, SAMPLE_SEED, Coverage, _noise_sample, _summary, coverage,
                                curve_elements, noise_shortfall)
from ..metrics.point_passes import near_box, nearest_two

__all__ = ["CoverageMemo", "curve_coverage", "coverage_from", "link_contexts", "carry_memo"]

#: skelcore.stages.context.EvalContext, not imported: the edits sit below the stages (only the
#: edit update, skelcore.edit.incremental, imports them)
EvalContext = Any
_LOCK = threading.Lock()
_KEEP = 8  # memos kept per evaluation's cache (the last few curves: an undo comes back to one)
# the removed balls' own search is skipped when a probe of every REDO_PROBE-th point near them finds at
# least REDO_SHARE of them decided by a removed ball (a pruned arm: all its points are asked again of
# every ball either way; docs/performance.md 6.10)
REDO_PROBE = 32
REDO_SHARE = 0.5


@dataclass
class CoverageMemo:
    """One curve's coverage in the cloud's surface-tree order: its elements (unique rows, ``elements``)
    and, per element, the nearest cloud distance r0, the ball radii r and R, the nearest point's tree position;
    per cloud point the gap and the verdict; per point of the noise shortfall's sample its nearest
    element's distance and row and whether two were as near (None when the shortfall reads none)."""

    r0: np.ndarray
    r: np.ndarray
    big_r: np.ndarray
    contact: np.ndarray
    gap_t: np.ndarray
    cov_t: np.ndarray
    elements: np.ndarray
    near: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    queries: tuple | None = None  # _queries: the positions searched (gap_t, cov_t are theirs)


def _elements(ctx: EvalContext) -> tuple[np.ndarray, float]:
    """The curve's coverage elements (:func:`skelcore.metrics.coverage.curve_elements`, as the curve
    coverage stage takes them) and tau."""
    tau = ctx.tau(no_checkpoint)
    return curve_elements(ctx.curve_n, tau, ctx.params), tau


def _store(cache: dict[str, Any], ctx: EvalContext, memo: Any, name: str = "coverage memos") -> None:
    """Keep ``memo`` for ``ctx`` in ``cache[name]`` (the last ``_KEEP``), while ``ctx`` lives."""
    with _LOCK:
        kept = cache.setdefault(name, {})
        kept[id(ctx)] = (weakref.ref(ctx), memo)
        while len(kept) > _KEEP:
            kept.pop(next(iter(kept)))


def _memo(cache: dict[str, Any], ctx: EvalContext | None, name: str = "coverage memos") -> Any:
    """The memo :func:`_store` keeps for ``ctx`` in ``cache[name]``, None when none."""
    with _LOCK:
        kept = cache.get(name, {})
        hit = kept.pop(id(ctx), None)
        if hit is not None:
            kept[id(ctx)] = hit  # the last asked stays longest (each edit of one curve asks for its memo)
    return hit[1] if hit is not None and hit[0]() is ctx else None


def link_contexts(cache: dict[str, Any], child: EvalContext, parent: EvalContext) -> None:
    """Remember that ``child`` (an update's context) was edited from ``parent``, for its second phase."""
    with _LOCK:
        links = cache.setdefault("coverage parents", {})
        links[id(child)] = (weakref.ref(child), weakref.ref(parent))
        while len(links) > _KEEP:
            links.pop(next(iter(links)))


def carry_memo(cache: dict[str, Any], done: EvalContext, to: EvalContext) -> None:
    """Keep ``done``'s coverage memo for ``to`` too, a context of the same curve (an update's first
    look completed: the next edits of that curve start from it instead of computing it whole again)."""
    memo = _memo(cache, done)
    if memo is not None:
        _store(cache, to, memo)


def parent_of(cache: dict[str, Any], child: EvalContext) -> EvalContext | None:
    """The context ``child`` was edited from (:func:`link_contexts`), None when not known; the link
    asked stays longest (a first phase completed again and again keeps its parent)."""
    with _LOCK:
        links = cache.get("coverage parents", {})
        hit = links.pop(id(child), None)
        if hit is not None:
            links[id(child)] = hit
    return hit[1]() if hit is not None and hit[0]() is child else None


def coverage_from(view: Any, old: CoverageMemo | None, elements: np.ndarray,
                  tau: float) -> tuple[Coverage, CoverageMemo | None]:
    """:func:`coverage` of ``elements`` (distinct rows) in the cloud of ``view`` (``params``, ``cloud_n``
    and its ``cloud_index``), by difference from ``old`` (a memo of the same cloud and tau) when it
    can, else whole; with its memo (None when coverage was computed as is)."""
    out = None if old is None else _by_difference(view, old, elements, tau)
    return out if out is not None else _full(view, elements, tau, old)


def _full(ctx: EvalContext, elements: np.ndarray, tau: float,
          old: CoverageMemo | None = None) -> tuple[Coverage, CoverageMemo | None]:
    """:func:`coverage` (the same steps; above ``coverage_exact_points`` its estimate on the same
    subsample) with the memo of what it computed; the elements ``old`` holds keep their nearest cloud
    distance."""
    p, cloud, index = ctx.params, ctx.cloud_n, ctx.cloud_index
    queries = _queries(ctx, elements, old)
    if queries is None:
        return coverage(cloud, elements, p, tau, index=index), None
    s = float(p.coverage_slack)
    surface = index.surface()
    balls = BallTree(elements)
    at, r0, contact = _nearest(surface, balls.points, old)
    near = _sample_nearest(ctx, balls.points, old, at)
    add = noise_shortfall(cloud, balls.points, r0, float(p.coverage_radius_quantile),
                          nearest=None if near is None else near[:2])
    r = r0 + add if add.any() else r0
    big_r = (1.0 + s) * r + tau
    balls.set_radii(r, big_r, None if add.any() else surface.points[contact])
    rest = np.ones(len(cloud), bool)
    rest[contact] = False
    ask = rest[queries[0]]
    g, c = balls.balls(surface.points[queries[0][ask]], floor=0.0, blocks=None)
    gap_q, cov_q = np.zeros(len(queries[0])), np.ones(len(queries[0]), bool)
    gap_q[ask], cov_q[ask] = np.maximum(g, 0.0), c
    memo = CoverageMemo(r0, r, big_r, contact, gap_q, cov_q, balls.points, near, queries)
    return _to_cloud(ctx, memo, tau, s), memo


def _queries(ctx: EvalContext, elements: np.ndarray, old: CoverageMemo | None) -> tuple | None:
    """(the surface-tree positions whose gaps coverage searches, each tree position's row among them
    or -1, the sampled cloud rows or None): every point, or above ``coverage_exact_points`` the
    subsample of :func:`coverage`'s estimate (the same seed); None when coverage is computed as is
    (no elements, no cloud index, more elements than that subsample)."""
    p, cloud, index = ctx.params, ctx.cloud_n, ctx.cloud_index
    n, m = len(cloud), int(p.coverage_exact_points)
    if len(elements) == 0 or index is None or len(elements) > m:
        return None
    if old is not None and old.queries is not None and len(old.queries[1]) == n:
        return old.queries
    perm = index.surface().perm
    if n <= m:
        return np.arange(n), np.arange(n), None
    sample_rows = np.sort(np.random.default_rng(SAMPLE_SEED).choice(n, m, replace=False))
    in_sample = np.zeros(n, bool)
    in_sample[sample_rows] = True
    at = np.flatnonzero(in_sample[perm])
    row = np.full(n, -1, np.int64)
    row[at] = np.arange(len(at))
    return at, row, sample_rows


def _nearest(surface: BallTree, pts: np.ndarray, old: CoverageMemo | None) -> tuple[np.ndarray, ...]:
    """(each element's row in ``old``, -1 if new; its nearest cloud distance; that point's tree
    position): the kept elements' from ``old``, the others asked of the cloud's tree."""
    if old is None:
        r0, contact = surface.nearest(pts, return_index=True)
        return np.full(len(pts), -1, np.int64), r0, contact
    at = _rows_in(old.elements, pts)
    kept = at >= 0
    r0 = np.empty(len(pts))
    contact = np.empty(len(pts), dtype=old.contact.dtype)
    r0[kept], contact[kept] = old.r0[at[kept]], old.contact[at[kept]]
    if (~kept).any():
        r0[~kept], contact[~kept] = surface.nearest(pts[~kept], return_index=True)
    return at, r0, contact


def _rows_in(old: np.ndarray, new: np.ndarray) -> np.ndarray:
    """For each row of ``new``, the row of ``old`` (distinct rows) with the same bits, or -1: one sort
    of both rows' bytes (a dict of 40k rows' bytes took as long as the rest of a first look's coverage)."""
    if not len(old) or not len(new):
        return np.full(len(new), -1, np.int64)
    rows = np.ascontiguousarray(np.vstack([old, new]), dtype=np.float64)
    _, key = np.unique(rows.view(np.dtype((np.void, 8 * rows.shape[1])))[:, 0], return_inverse=True)
    key = np.ravel(key)
    at = np.full(int(key.max()) + 1, -1, np.int64)
    at[key[:len(old)]] = np.arange(len(old))
    return at[key[len(old):]]


def _to_cloud(ctx: EvalContext, memo: CoverageMemo, tau: float, s: float) -> Coverage:
    """The Coverage of the memo's gaps and verdicts (searched at its query positions; every other
    point, above ``coverage_exact_points``, takes its nearest sampled point's)."""
    surface = ctx.cloud_index.surface()
    at, row, sample_rows = memo.queries
    gap_t, cov_t = memo.gap_t, memo.cov_t
    if sample_rows is not None:
        j = row[ctx.cloud_index.nearest_sampled(at)]
        gap_t, cov_t = gap_t[j], cov_t[j]
    perm = surface.perm
    gap, covered = np.empty(len(perm)), np.empty(len(perm), bool)
    gap[perm], covered[perm] = gap_t, cov_t
    return _summary(gap, covered, tau, s, len(memo.elements), sample_rows)


def _near_box(points: np.ndarray, centers: np.ndarray, reach: np.ndarray, cover_reach: float) -> np.ndarray:
    """Points that a ball of ``centers`` could reach: within max radius + ``reach`` (per point) or
    ``cover_reach`` of the centers' bounding box (a superset, by a relative 1e-9): one compiled pass
    (:func:`skelcore.metrics.point_passes.near_box`, the distance to the box as np.linalg.norm sums it;
    the 100k points around a pruned arm 10.2 -> 2.8 ms, docs/performance.md 6.10)."""
    return near_box(points, centers.min(axis=0), centers.max(axis=0), reach, cover_reach)


def _decided_by_removed(points: np.ndarray, gap: np.ndarray, old: CoverageMemo, gone: np.ndarray) -> np.ndarray:
    """Which of ``points`` (their old gaps ``gap``) a removed ball (``gone`` of ``old``'s) may have
    decided: inside its cover radius, or its gap no larger than the point's. All of them, unasked, when
    a probe of every ``REDO_PROBE``-th finds at least ``REDO_SHARE`` so: asking every ball again gives
    a point's answer whether a removed ball decided it or not (the same bits), and the removed balls'
    search of every point would cost about as much as that (after a prune, 40k of 100k points)."""
    tree = _sub_tree(old.elements[gone], old.r[gone], old.big_r[gone])
    top = float(old.big_r.max())
    if len(points) >= 4 * REDO_PROBE:
        g, c = tree.balls(points[::REDO_PROBE], top=top)
        if np.count_nonzero(c | (g <= gap[::REDO_PROBE])) >= REDO_SHARE * len(g):
            return np.ones(len(points), bool)
    g, c = tree.balls(points, top=top)
    return c | (g <= gap)


def _sub_tree(points: np.ndarray, r: np.ndarray, big_r: np.ndarray) -> BallTree:
    tree = BallTree(points)
    tree.set_radii(r[tree.perm], big_r[tree.perm])
    return tree


def curve_coverage(ctx: EvalContext, parent: EvalContext | None, cache: dict[str, Any]) -> Coverage:
    """The curve coverage stage's result for ``ctx``, by difference from ``parent``'s when its memo
    is kept (made here once for a parent without one); its own memo kept for the next edit."""
    elements, tau = _elements(ctx)
    old = _memo(cache, parent)
    if old is None and parent is not None and parent.curve_n is not None:
        old_el, old_tau = _elements(parent)
        if old_tau == tau:
            old = _full(parent, unique_rows(np.asarray(old_el, float))[0], tau)[1]
            if old is not None:
                _store(cache, parent, old)
    elements = unique_rows(np.asarray(elements, dtype=float))[0]
    out = None if old is None else _by_difference(ctx, old, elements, tau)
    if out is None:
        out = _full(ctx, elements, tau)
    if out[1] is not None:
        _store(cache, ctx, out[1])
    return out[0]


def _by_difference(ctx: EvalContext, old: CoverageMemo, elements: np.ndarray,
                   tau: float) -> tuple[Coverage, CoverageMemo] | None:
    """The coverage of ``elements`` from ``old``'s, None when computed as is (:func:`_queries`)."""
    p, cloud, index = ctx.params, ctx.cloud_n, ctx.cloud_index
    queries = _queries(ctx, elements, old)
    if queries is None or old.queries is not queries:
        return None
    s = float(p.coverage_slack)
    surface = index.surface()
    balls = BallTree(elements)
    pts = balls.points
    at, r0, contact = _nearest(surface, pts, old)
    kept = at >= 0
    sample_near = _sample_nearest(ctx, pts, old, at)
    add = noise_shortfall(cloud, pts, r0, float(p.coverage_radius_quantile),
                          nearest=None if sample_near is None else sample_near[:2])
    r = r0 + add if add.any() else r0
    big_r = (1.0 + s) * r + tau
    if not (np.array_equal(r[kept], old.r[at[kept]]) and big_r.max() == old.big_r.max()):
        return _full(ctx, elements, tau, old)  # the shortfall's ratio or the allowance changed: all again
    balls.set_radii(r, big_r, None if add.any() else surface.points[contact])
    eps = COVER_EPS * max(float(big_r.max()) ** 2, 1e-300)
    gap_t, cov_t = old.gap_t.copy(), old.cov_t.copy()  # per query position
    points = surface.points if queries[2] is None else surface.points[queries[0]]  # every point: in order
    gone = np.ones(len(old.r), bool)
    gone[at[kept]] = False
    redo = np.zeros(len(points), bool)
    if gone.any():  # points a removed ball may have decided: asked again of every ball
        near = np.flatnonzero(_near_box(points, old.elements[gone], old.r[gone].max() + gap_t,
                                        float(np.sqrt(old.big_r[gone].max() ** 2 + eps))))
        if len(near):
            redo[near] = _decided_by_removed(points[near], gap_t[near], old, gone)
    if (~kept).any():  # the others: their old answer or an added ball's
        near = np.flatnonzero(_near_box(points, pts[~kept], r[~kept].max() + gap_t,
                                        float(np.sqrt(big_r[~kept].max() ** 2 + eps))) & ~redo)
        if len(near):
            tree = _sub_tree(pts[~kept], r[~kept], big_r[~kept])
            g, c = tree.balls(points[near], floor=0.0, top=float(big_r.max()), blocks=None)
            gap_t[near] = np.minimum(gap_t[near], np.maximum(g, 0.0))
            cov_t[near] |= c
    touching = queries[1][contact]
    touching = touching[touching >= 0]
    redo[touching] = False
    ask = np.flatnonzero(redo)
    if len(ask):  # in tree order, many per ball: blocks of 16 share a walk (a pruned arm's 40k, 13 -> 7 ms)
        g, c = balls.balls(points[ask], floor=0.0, blocks=None)
        gap_t[ask], cov_t[ask] = np.maximum(g, 0.0), c
    gap_t[touching], cov_t[touching] = 0.0, True
    memo = CoverageMemo(r0, r, big_r, contact, gap_t, cov_t, pts, sample_near, queries)
    return _to_cloud(ctx, memo, tau, s), memo


def _two_nearest(elements: np.ndarray, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``kd_tree(elements).query(pts, k=2)``'s two distances and a nearest element (the only one where they
    differ), the same bits: by the compiled blocks of :func:`skelcore.metrics.point_passes.nearest_two`
    (``elements`` in the ball tree's order, its blocks' boxes small) when every coordinate is finite. A pruned
    arm's 6,595 sampled points, their nearest element removed, are far from every element left, where the
    tree visits most of its nodes near the junction (8.8 -> 2 ms, docs/performance.md 6.10)."""
    if np.isfinite(elements).all() and np.isfinite(pts).all():
        return nearest_two(pts, elements)
    d, i = kd_tree(elements).query(pts, k=2)
    return d[:, 0], i[:, 0], d[:, 1]


def _sample_nearest(ctx: EvalContext, elements: np.ndarray, old: CoverageMemo | None,
                    at: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Each point of the noise shortfall's sample: its nearest element's distance and row, and whether
    two were as near, as the shortfall finds them (its two nearest of ``geometry.kd_tree``, the
    balanced tree's answer for a tie); by difference from ``old`` (``at``: each element's row in it)
    where the old nearest is kept and was no tie: the added elements' nearest when nearer, a tie when
    as near. None when the shortfall reads no sample."""
    p, cloud = ctx.params, ctx.cloud_n
    if not float(p.coverage_radius_quantile) > 0 or len(elements) < 2 or len(cloud) < 2 * NOISE_MIN_POINTS:
        return None
    pts = _noise_sample(cloud)[0]
    if old is None or old.near is None:
        redo = np.ones(len(pts), bool)
        dist, owner = np.empty(len(pts)), np.empty(len(pts), np.int64)
    else:
        back = np.full(len(old.r), -1, np.int64)
        back[at[at >= 0]] = np.flatnonzero(at >= 0)
        dist, owner = old.near[0].copy(), back[old.near[1]]
        redo = (owner < 0) | old.near[2]
    tie = np.zeros(len(pts), bool)
    added = np.flatnonzero(at < 0)
    ok = np.flatnonzero(~redo)
    if len(added) and len(ok):  # only the points whose old distance reaches the added elements' box
        ok = ok[_near_box(pts[ok], elements[added], dist[ok], 0.0)]
    if len(added) and len(ok):
        d, i = cKDTree(elements[added]).query(pts[ok], k=2 if len(added) > 1 else 1)
        d, i = d.reshape(len(ok), -1), i.reshape(len(ok), -1)
        nearer = d[:, 0] < dist[ok]
        dist[ok[nearer]], owner[ok[nearer]] = d[nearer, 0], added[i[nearer, 0]]
        tie[ok] = (d[:, 0] == dist[ok]) & ~nearer
        if d.shape[1] > 1:
            tie[ok] |= nearer & (d[:, 0] == d[:, 1])
    if redo.any():  # the same distances as the shortfall's kd_tree(elements).query(k=2), its nearest where no tie
        d0, i0, d1 = _two_nearest(elements, pts[redo])
        dist[redo], owner[redo] = d0, i0
        tie[redo] = d0 == d1
    if tie.any():
        dist[tie], owner[tie] = cKDTree(elements).query(pts[tie])
    return dist, owner, tie
