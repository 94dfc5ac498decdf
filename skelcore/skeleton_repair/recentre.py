"""Re-centring of branches that drift to the surface (docs/repair.md "Actions"): a curve vertex whose
cross-section says it is not centred (c <= c*, docs/metrics.md section 3.3) moves to the centre of
that cross-section, the slab ring's fitted centre exactly as curve centeredness computes it
(docs/metrics.md section 3.2). One action per run of degree-2 vertices between two nodes (a branch),
its vertices moved by ``move_vertex``."""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..curve import CurveSkeleton
from ..geometry import bbox_diagonal, stable_argsort
from ..metrics.centeredness import ring_length, slab_grid
from ..metrics.ellipse_fit import fit_ellipses
from ..params import Params
from .proposals import Action

__all__ = ["RECENTRE", "cross_section_centres", "recentre"]

#: the defect code of a re-centring in the edit log's ``why`` (the never-worse rule's exception)
RECENTRE = "off_centre"


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


def cross_section_centres(cloud: np.ndarray, points: np.ndarray, dirs: np.ndarray, params: Params
                          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For each point with unit direction: the fitted centre of its slab ring (user units), the
    ring's radius and the point's centeredness c (docs/metrics.md section 3.2); NaN where the ring
    has fewer than 3 points."""
    m = len(points)
    centre, radius, c = np.full((m, 3), np.nan), np.full(m, np.nan), np.full(m, np.nan)
    if m == 0 or len(cloud) == 0:
        return centre, radius, c
    grid = slab_grid(cloud, params)
    half = 0.5 * float(params.slab_factor) * bbox_diagonal(cloud)
    flats, frames = [], []
    for p, u in zip(points, dirs):
        g = np.cross(u, [1.0, 0, 0] if abs(u[0]) < 0.9 else [0, 1.0, 0])
        g /= np.linalg.norm(g)
        h = np.cross(u, g)
        rel = grid.slab_candidates(p, u, half) - p
        rel = rel[np.abs(rel @ u) < half]
        flat = np.column_stack([rel @ g, rel @ h])
        dist = np.hypot(flat[:, 0], flat[:, 1])
        order = stable_argsort(dist)
        flats.append(flat[order[: ring_length(dist[order], float(params.ring_growth))]])
        frames.append((g, h))
    starts = np.r_[0, np.cumsum([len(f) for f in flats])]
    ring = np.concatenate(flats).reshape(-1, 2)
    ctr, axes, _ = fit_ellipses(ring, starts)
    r = (axes[:, 0] + axes[:, 1]) / 2.0
    for i in range(m):
        pts = ring[starts[i]:starts[i + 1]]
        if len(pts) < 3:
            continue
        if np.isnan(ctr[i, 0]):  # no ellipse: the ring's mean and its farthest point, as the metric does
            ctr[i], r[i] = pts.mean(axis=0), float(np.hypot(pts[:, 0], pts[:, 1]).max())
        if not r[i] > 0:
            continue
        g, h = frames[i]
        centre[i] = points[i] + ctr[i, 0] * g + ctr[i, 1] * h
        radius[i] = r[i]
        c[i] = max(0.0, 1.0 - float(np.hypot(*ctr[i])) / r[i])
    return centre, radius, c


def recentre(curve: CurveSkeleton, cloud: np.ndarray, params: Params) -> list[Action]:
    """One action per branch holding inner vertices that are not centred (c <= ``params.c_star``):
    each moves to its cross-section's centre when that lies within the ring's radius and the vertex is
    centred (c > c*) in the cross-section cut there again (a ring caught by another branch or a bad
    fit moves nothing); branches with the lowest mean c first (ties by their lowest vertex)."""
    deg = np.bincount(curve.edges.ravel(), minlength=curve.n_vertices)
    inner = np.flatnonzero(deg == 2)
    if not len(inner) or not len(cloud):
        return []
    u = _tangents(curve, inner)
    ok = np.all(np.isfinite(u), axis=1)
    inner, u = inner[ok], u[ok]
    centre, radius, c = cross_section_centres(np.asarray(cloud, float), curve.vertices[inner], u, params)
    shift = np.linalg.norm(centre - curve.vertices[inner], axis=1)
    move = np.isfinite(c) & (c <= float(params.c_star)) & (shift <= radius) & (shift > 0)
    if move.any():  # kept only where the vertex is centred in the cross-section at its new place too
        _, _, c_new = cross_section_centres(np.asarray(cloud, float), centre[move], u[move], params)
        move[np.flatnonzero(move)[~(c_new > float(params.c_star))]] = False
    if not move.any():
        return []
    run = _runs(curve, deg)
    groups: dict[int, list[int]] = {}
    for i in np.flatnonzero(move):
        groups.setdefault(int(run[inner[i]]), []).append(int(i))
    out = []
    for b in sorted(groups, key=lambda b: (float(np.mean(c[groups[b]])), int(inner[groups[b]].min()))):
        rows = groups[b]
        entries: list[dict[str, Any]] = [{"op": "move_vertex", "args": {
            "vertex": int(inner[i]), "position": [float(x) for x in centre[i]]}} for i in rows]
        on = np.isin(curve.edges, inner[rows]).any(axis=1)
        first = int(inner[rows].min())
        out.append(Action(RECENTRE, {"vertex": first, "vertices": len(rows)},
                          f"{len(rows)} vertices of the branch through vertex {first} off the centre of their "
                          f"cross-sections (mean c {float(np.mean(c[rows])):.3g} <= c*={params.c_star}): moved to "
                          f"the centres, by {float(np.mean(shift[rows])):.3g} on average", entries, np.flatnonzero(on)))
    return out
