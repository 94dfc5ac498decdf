"""Re-centring of branches that drift to the surface (docs/repair.md "Actions"): a curve vertex whose
cross-section says it is not centred (c <= c*, docs/metrics.md section 3.3) moves to the centre of
that cross-section, the slab ring's fitted centre exactly as curve centeredness computes it
(docs/metrics.md section 3.2). One action per run of degree-2 vertices between two nodes (a branch),
its vertices moved by ``move_vertex``."""

from __future__ import annotations

from typing import Any, Callable

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..curve import CurveSkeleton
from ..geometry import bbox_diagonal
from ..metrics.centeredness import _BALL_FIRST, _ball_radius, _orthonormal_complement, _rings, slab_grid
from ..metrics.ellipse_fit import fit_ellipses
from ..params import Params
from .proposals import Action

__all__ = ["RECENTRE", "cross_section_centres", "recentre", "settled", "vertex_centeredness"]

#: the defect code of a re-centring in the edit log's ``why`` (the never-worse rule's exception)
RECENTRE = "off_centre"
_BATCH_PAIRS = 2_000_000  # first-ball candidates held at once (about 60 bytes each)
_LAZY_VERTICES = 256  # inner vertices cut at once when only the first actions are wanted


def _tangents(curve: CurveSkeleton, ids: np.ndarray) -> np.ndarray:
    """Unit tangents at degree-2 vertices, through their two neighbours."""
    e = curve.edges
    nb = np.full((curve.n_vertices, 2), -1, np.int64)
    fill = np.zeros(curve.n_vertices, np.int64)
    for a, b in e:
        for x, y in ((a, b), (b, a)):
            if fill[x] < 2:
                nb[x, fill[x]] = y
            fill[x] += 1
    t = curve.vertices[nb[ids, 1]] - curve.vertices[nb[ids, 0]]
    n = np.linalg.norm(t, axis=1, keepdims=True)
    return np.divide(t, n, out=np.full_like(t, np.nan), where=n > 0)


def _runs(curve: CurveSkeleton, deg: np.ndarray) -> np.ndarray:
    """A label per vertex: the runs of degree-2 vertices between nodes (ends, junctions) share one."""
    e = curve.edges
    keep = (deg[e[:, 0]] == 2) & (deg[e[:, 1]] == 2)
    n = curve.n_vertices
    g = coo_matrix((np.ones(int(keep.sum())), (e[keep, 0], e[keep, 1])), shape=(n, n))
    return connected_components(g, directed=False)[1]


def cross_section_centres(cloud: np.ndarray, points: np.ndarray, dirs: np.ndarray, params: Params,
                          grid: Any = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For each point with unit direction: the fitted centre of its slab ring (user units), the
    ring's radius and the point's centeredness c (docs/metrics.md section 3.2); NaN where the ring
    has fewer than 3 points. The rings are curve centeredness's own (its ball-first search, in
    batches of about ``_BATCH_PAIRS`` candidates); ``grid``: :func:`slab_grid` of the cloud, if kept."""
    m = len(points)
    centre, radius, c = np.full((m, 3), np.nan), np.full(m, np.nan), np.full(m, np.nan)
    if m == 0 or len(cloud) == 0:
        return centre, radius, c
    half = 0.5 * float(params.slab_factor) * bbox_diagonal(cloud)
    if not half > 0:
        return centre, radius, c
    grid = slab_grid(cloud, params) if grid is None else grid
    points = np.asarray(points, float)
    u = np.asarray(dirs, float)
    g, h = _orthonormal_complement(u)
    first = grid.tree.query_ball_point(points, _ball_radius(np.full(m, _BALL_FIRST * half), half), return_length=True)
    bounds = np.r_[0, np.cumsum(first)]
    lo = 0
    while lo < m:
        hi = lo + max(1, int(np.searchsorted(bounds[lo:], bounds[lo] + _BATCH_PAIRS, side="right")) - 1)
        ring, starts = _rings(grid, points[lo:hi], u[lo:hi], g[lo:hi], h[lo:hi], half, float(params.ring_growth))
        ctr, axes, _ = fit_ellipses(ring, starts)
        r = (axes[:, 0] + axes[:, 1]) / 2.0
        for j in range(hi - lo):
            pts = ring[starts[j]:starts[j + 1]]
            if len(pts) < 3:
                continue
            if np.isnan(ctr[j, 0]):  # no ellipse: the ring's mean and its farthest point, as the metric does
                ctr[j], r[j] = pts.mean(axis=0), float(np.hypot(pts[:, 0], pts[:, 1]).max())
            if not r[j] > 0:
                continue
            i = lo + j
            centre[i] = points[i] + ctr[j, 0] * g[i] + ctr[j, 1] * h[i]
            radius[i] = r[j]
            c[i] = max(0.0, 1.0 - float(np.hypot(*ctr[j])) / r[j])
        lo = hi
    return centre, radius, c


def _centres_memo(cloud: np.ndarray, points: np.ndarray, dirs: np.ndarray, params: Params,
                  memo: dict | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`cross_section_centres`, each (point, direction) computed once per ``memo`` (a repair's
    rounds change few vertices: the others' cross-sections are looked up, bit for bit the same)."""
    if memo is None:
        return cross_section_centres(cloud, points, dirs, params)
    keys = [p.tobytes() + u.tobytes() for p, u in zip(points, dirs)]
    new = [i for i, k in enumerate(keys) if k not in memo]
    if new:
        if "grid" not in memo:
            memo["grid"] = slab_grid(cloud, params)
        got = cross_section_centres(cloud, points[new], dirs[new], params, memo["grid"])
        for j, i in enumerate(new):
            memo[keys[i]] = (got[0][j], got[1][j], got[2][j])
    rows = [memo[k] for k in keys]
    return (np.array([r[0] for r in rows]).reshape(-1, 3), np.array([r[1] for r in rows], float),
            np.array([r[2] for r in rows], float))


def _on_vertices(curve: CurveSkeleton, sample_edge: np.ndarray, sample_t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The curve samples lying on a vertex (t 0 or 1 along their edge) and that vertex of each."""
    t = np.asarray(sample_t, float)
    at = (t == 0.0) | (t == 1.0)
    e = curve.edges[np.asarray(sample_edge, np.int64)[at]]
    return at, np.where(t[at] == 1.0, e.max(axis=1), e.min(axis=1))


def vertex_centeredness(curve: CurveSkeleton, sample_edge: np.ndarray, sample_t: np.ndarray,
                        sample_c: np.ndarray) -> np.ndarray:
    """Per vertex: the lowest c of the evaluation's curve samples lying on it (NaN where none lies on
    it or none has a ring)."""
    at, v = _on_vertices(curve, sample_edge, sample_t)
    c = np.asarray(sample_c, float)[at]
    out = np.full(curve.n_vertices, np.inf)
    np.minimum.at(out, v[np.isfinite(c)], c[np.isfinite(c)])
    out[np.isinf(out)] = np.nan
    return out


def settled(curve: CurveSkeleton, sample_edge: np.ndarray, sample_t: np.ndarray, sample_c: np.ndarray,
            c_star: float) -> np.ndarray:
    """Per vertex: whether the evaluation's curve samples lying on it all say it needs no cut here:
    each is centred (c > ``c_star``) or has no ring (NaN: fewer than 3 points in its slab ring). A
    vertex no sample lies on is not settled."""
    seen = np.bincount(_on_vertices(curve, sample_edge, sample_t)[1], minlength=curve.n_vertices) > 0
    c = vertex_centeredness(curve, sample_edge, sample_t, sample_c)
    return seen & ~(np.isfinite(c) & ~(c > c_star))


def _moves(curve: CurveSkeleton, cloud: np.ndarray, params: Params, memo: dict | None, inner: np.ndarray,
           run: np.ndarray) -> dict[int, Action]:
    """The re-centring of each branch (label of ``run``) among the inner vertices ``inner``."""
    u = _tangents(curve, inner)
    ok = np.all(np.isfinite(u), axis=1)
    inner, u = inner[ok], u[ok]
    centre, radius, c = _centres_memo(cloud, curve.vertices[inner], u, params, memo)
    shift = np.linalg.norm(centre - curve.vertices[inner], axis=1)
    move = np.isfinite(c) & (c <= float(params.c_star)) & (shift <= radius) & (shift > 0)
    if move.any():  # kept only where the vertex is centred in the cross-section at its new place too
        _, _, c_new = _centres_memo(cloud, centre[move], u[move], params, memo)
        move[np.flatnonzero(move)[~(c_new > float(params.c_star))]] = False
    groups: dict[int, list[int]] = {}
    for i in np.flatnonzero(move):
        groups.setdefault(int(run[inner[i]]), []).append(int(i))
    out = {}
    for b, rows in groups.items():
        entries: list[dict[str, Any]] = [{"op": "move_vertex", "args": {
            "vertex": int(inner[i]), "position": [float(x) for x in centre[i]]}} for i in rows]
        on = np.isin(curve.edges, inner[rows]).any(axis=1)
        first = int(inner[rows].min())
        out[b] = Action(RECENTRE, {"vertex": first, "vertices": len(rows), "mean_c": float(np.mean(c[rows]))},
                        f"{len(rows)} vertices of the branch through vertex {first} off the centre of their "
                        f"cross-sections (mean c {float(np.mean(c[rows])):.3g} <= c*={params.c_star}): moved to "
                        f"the centres, by {float(np.mean(shift[rows])):.3g} on average", entries, np.flatnonzero(on))
    return out


def recentre(curve: CurveSkeleton, cloud: np.ndarray, params: Params, memo: dict | None = None,
             skip: np.ndarray | None = None, vertex_c: np.ndarray | None = None, want: int | None = None,
             fresh: Callable[[Action], bool] | None = None) -> list[Action]:
    """One action per branch holding inner vertices that are not centred (c <= ``params.c_star``):
    each moves to its cross-section's centre when that lies within the ring's radius and the vertex is
    centred (c > c*) in the cross-section cut there again (a ring caught by another branch or a bad
    fit moves nothing); branches with the lowest mean c first (ties by their lowest vertex). ``memo``:
    cross-sections already cut (kept over a repair's rounds); ``skip``: vertices not cut
    (:func:`settled`); ``fresh``: the actions kept. With ``vertex_c`` (:func:`vertex_centeredness`)
    and ``want``, branches are cut in the order of their vertices' mean ``vertex_c`` (no value: c*),
    a batch at a time, until ``want`` actions are found: the first ones, not all."""
    deg = np.bincount(curve.edges.ravel(), minlength=curve.n_vertices)
    inner = np.flatnonzero((deg == 2) if skip is None else (deg == 2) & ~np.asarray(skip, bool))
    if not len(inner) or not len(cloud):
        return []
    cloud = np.asarray(cloud, float)
    run = _runs(curve, deg)
    keep = fresh or (lambda _a: True)
    if vertex_c is None or want is None:
        acts = _moves(curve, cloud, params, memo, inner, run)
        ranked = sorted(acts, key=lambda b: (acts[b].target["mean_c"], acts[b].target["vertex"]))
        return [_public(acts[b]) for b in ranked if keep(acts[b])]
    vc = np.where(np.isfinite(vertex_c[inner]), vertex_c[inner], float(params.c_star))
    labels, where = np.unique(run[inner], return_inverse=True)
    count = np.bincount(where)
    mean = np.bincount(where, weights=vc) / count
    first = np.full(len(labels), np.iinfo(np.int64).max)
    np.minimum.at(first, where, inner)
    out: list[Action] = []
    order = np.lexsort((first, mean))
    lo = 0
    while lo < len(order) and len(out) < want:
        hi, size = lo, 0
        while hi < len(order) and size < _LAZY_VERTICES:
            size += int(count[order[hi]])
            hi += 1
        batch = np.isin(where, order[lo:hi])
        acts = _moves(curve, cloud, params, memo, inner[batch], run)
        out += [_public(acts[int(labels[k])]) for k in order[lo:hi]
                if int(labels[k]) in acts and keep(acts[int(labels[k])])]
        lo = hi
    return out[:want]


def _public(a: Action) -> Action:
    a.target.pop("mean_c", None)
    return a
