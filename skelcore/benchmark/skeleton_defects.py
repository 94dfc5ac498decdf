"""Controlled defects of a curve skeleton at graded sizes (docs/validity.md).

Each defect takes a curve as arrays (vertices V x 3, edges E x 2) with the local radius r per
vertex (the benchmark's exact radius, or the distance to the cloud) and returns a new pair; sizes
are in local radii or shares of a branch, so that one level means the same on a thin twig and a
thick trunk. :data:`DEFECTS` lists the ten the validity study applies, each with three levels; a
defect that does not apply to a shape (truncation of a torus, a broken cycle on a tree) returns
None. Random choices come from the generator passed in (deterministic from a seed).

The spur, chord, shortcut-chain and out-branch generators were the diagnostics calibration's
(docs/diagnostics.md "Calibration"), moved here unchanged from its script, as were
``collapse_points`` and ``drop_vertices`` from its cases module.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components, dijkstra
from scipy.spatial import cKDTree

__all__ = ["Defect", "DEFECTS", "apply_defect", "inner_vertices", "tangent", "vertex_tangents", "perpendicular", "polyline",
           "add_spurs", "add_chord", "join", "out_branch", "collapse_points", "drop_vertices", "truncate",
           "drop_branches", "add_shortcuts", "break_cycle", "cut_edges", "skeleton_noise", "offset", "oversmooth"]

Graph = tuple[np.ndarray, np.ndarray]
Inside = Callable[[np.ndarray], np.ndarray]  # points -> signed distance to the shape's surface (< 0 inside)


# ---- helpers (moved from the diagnostics calibration's script) -----------------------------------

def _degrees(n: int, e: np.ndarray) -> np.ndarray:
    return np.bincount(np.asarray(e, np.int64).ravel(), minlength=n)


def tangent(verts: np.ndarray, edges: np.ndarray, v: int) -> np.ndarray:
    """The unit tangent of the curve at vertex ``v`` (through its two neighbours, or to its one)."""
    nb = np.concatenate([edges[edges[:, 0] == v, 1], edges[edges[:, 1] == v, 0]])
    t = verts[nb[1]] - verts[nb[0]] if len(nb) >= 2 else verts[nb[0]] - verts[v]
    return t / np.linalg.norm(t)


def vertex_tangents(verts: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """(V, 3) the unit tangent at every vertex: the sum of its edges' unit directions (0 where none)."""
    d = verts[edges[:, 1]] - verts[edges[:, 0]]
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
    t = np.zeros_like(verts, dtype=float)
    np.add.at(t, edges[:, 0], d)
    np.add.at(t, edges[:, 1], d)
    return t / np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-300)


def perpendicular(t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A random unit vector perpendicular to the unit vector ``t``."""
    g = rng.normal(size=3)
    g -= (g @ t) * t
    return g / np.linalg.norm(g)


def inner_vertices(v: np.ndarray, e: np.ndarray, r: np.ndarray, away: float = 1.5) -> np.ndarray:
    """Degree-2 vertices at least ``away`` local radii from every node (end or junction)."""
    deg = _degrees(len(v), e)
    nodes = v[deg != 2]
    ok = deg == 2
    if len(nodes):
        d, _ = cKDTree(nodes).query(v)
        ok &= d >= away * r
    return np.flatnonzero(ok)


def polyline(a: np.ndarray, b: np.ndarray, step: float) -> np.ndarray:
    """Points from a (excluded) to b (included) at most ``step`` apart."""
    n = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
    return a + np.linspace(0, 1, n + 1)[1:, None] * (b - a)


def _attach(v: np.ndarray, e: np.ndarray, a: int, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """A chain of new vertices ``pts`` hung from vertex ``a``: (vertices, edges, id of the last)."""
    ids = np.arange(len(v), len(v) + len(pts))
    return (np.vstack([v, pts]), np.vstack([e, np.column_stack([np.concatenate([[a], ids[:-1]]), ids])]),
            int(ids[-1]))


def add_spurs(v: np.ndarray, e: np.ndarray, r: np.ndarray, k: int, length: float,
              rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """``k`` spurs of ``length`` local radii from distinct inner vertices, sideways; returns
    (vertices, edges, ids of the new tip vertices)."""
    v, e = v.copy(), e.copy()
    cand = inner_vertices(v, e, r)
    pick = rng.choice(cand, size=min(k, len(cand)), replace=False)
    tips = []
    for a in pick:
        u = perpendicular(tangent(v, e, a), rng)
        v, e, tip = _attach(v, e, a, polyline(v[a], v[a] + length * r[a] * u, 0.5 * r[a]))
        tips.append(tip)
    return v, e, tips


def add_chord(v: np.ndarray, e: np.ndarray, r: np.ndarray, span: float, rng: np.random.Generator) -> Graph:
    """A chord closing a loop inside the shape: from an inner vertex a to the vertex b about ``span``
    local radii further along the curve, through a new vertex 0.5 r sideways of their midpoint."""
    v, e = v.copy(), e.copy()
    cand = inner_vertices(v, e, r, away=span + 1.0)
    if not len(cand):
        cand = inner_vertices(v, e, r, away=0.0)
    a = int(rng.choice(cand))
    ra = r[a]
    adj = defaultdict(list)
    for x, y in e:
        adj[x].append(y)
        adj[y].append(x)
    prev, cur, walked = -1, a, 0.0
    while walked < span * ra:
        nxt = [w for w in adj[cur] if w != prev]
        if not nxt:
            break
        walked += np.linalg.norm(v[nxt[0]] - v[cur])
        prev, cur = cur, nxt[0]
    b = cur
    m = (v[a] + v[b]) / 2 + 0.5 * ra * perpendicular(tangent(v, e, a), rng)
    v = np.vstack([v, m])
    k = len(v) - 1
    return v, np.vstack([e, [[a, k], [k, b]]])


def join(v: np.ndarray, e: np.ndarray, a: int, b: int, step: float) -> Graph:
    """A straight chain of edges at most ``step`` long from vertex a to vertex b."""
    pts = polyline(v[a], v[b], step)[:-1]
    ids = np.arange(len(v), len(v) + len(pts))
    chain = np.concatenate([[a], ids, [b]])
    return np.vstack([v, pts]), np.vstack([e, np.column_stack([chain[:-1], chain[1:]])])


def out_branch(v: np.ndarray, e: np.ndarray, r: np.ndarray, out_radii: float, rng: np.random.Generator) -> Graph:
    """A terminal branch from an inner vertex straight out of the shape, ``out_radii`` local radii
    beyond its surface (sideways: 1 + out_radii local radii long)."""
    a = int(rng.choice(inner_vertices(v, e, r)))
    u = perpendicular(tangent(v, e, a), rng)
    v2, e2, _ = _attach(v.copy(), e.copy(), a, polyline(v[a], v[a] + (1.0 + out_radii) * r[a] * u, 0.5 * r[a]))
    return v2, e2


def collapse_points(points: np.ndarray, f: float) -> np.ndarray:
    """The points moved a share ``f`` of the way to their centroid (1: all at the centroid)."""
    c = points.mean(axis=0)
    return c + (points - c) * (1.0 - f)


def drop_vertices(v: np.ndarray, e: np.ndarray, drop: np.ndarray) -> Graph:
    """The curve without the vertices where ``drop`` is True and their edges (indices renumbered)."""
    keep = ~np.asarray(drop, bool)
    new = -np.ones(len(keep), np.int64)
    new[keep] = np.arange(int(keep.sum()))
    e2 = e[keep[e].all(axis=1)]
    return v[keep], new[e2].reshape(-1, 2)


def _drop_isolated(v: np.ndarray, e: np.ndarray) -> Graph:
    return drop_vertices(v, e, _degrees(len(v), e) == 0) if len(e) else (v, e)


# ---- the validity study's defects ---------------------------------------------------------------

def _lengths_graph(v: np.ndarray, e: np.ndarray):
    w = np.linalg.norm(v[e[:, 1]] - v[e[:, 0]], axis=1)
    w = np.maximum(w, 1e-12)
    n = len(v)
    return coo_matrix((np.r_[w, w], (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])), shape=(n, n)).tocsr()


def _terminal_branches(v: np.ndarray, e: np.ndarray) -> list[tuple[int, np.ndarray, float]]:
    """Every terminal branch as (its free end, its vertices without the node at the other end, its
    length): the chain of degree-2 vertices from a degree-1 vertex to the first node."""
    deg = _degrees(len(v), e)
    g = _lengths_graph(v, e)
    out = []
    for end in np.flatnonzero(deg == 1):
        path, prev, cur, length = [int(end)], -1, int(end), 0.0
        while True:
            nb = [int(x) for x in g.indices[g.indptr[cur]:g.indptr[cur + 1]] if x != prev]
            if not nb:
                break
            length += float(np.linalg.norm(v[nb[0]] - v[cur]))
            prev, cur = cur, nb[0]
            if deg[cur] != 2:
                break
            path.append(cur)
        out.append((int(end), np.array(path), length))
    return out


def truncate(v: np.ndarray, e: np.ndarray, share: float) -> Graph | None:
    """Every free end cut back by ``share`` of its terminal branch's length (along the curve): a
    skeletonizer that stops short. None without a free end (a torus)."""
    branches = _terminal_branches(v, e)
    if not branches:
        return None
    ends = np.array([b[0] for b in branches])
    limit = np.array([share * b[2] for b in branches])
    d = dijkstra(_lengths_graph(v, e), indices=ends, limit=float(limit.max()) * 1.001)
    drop = (d < limit[:, None]).any(axis=0)
    if drop.all():
        return None
    return _drop_isolated(*drop_vertices(v, e, drop))


def drop_branches(v: np.ndarray, e: np.ndarray, count: int, rng: np.random.Generator) -> Graph | None:
    """``count`` terminal branches removed whole, up to their junction (a missed limb). None when the
    curve has fewer than ``count`` + 1 terminal branches or no junction."""
    deg = _degrees(len(v), e)
    branches = _terminal_branches(v, e)
    if not (deg >= 3).any() or len(branches) < count + 1:
        return None
    pick = rng.choice(len(branches), size=count, replace=False)
    drop = np.zeros(len(v), bool)
    for i in pick:
        drop[branches[i][1]] = True
    return _drop_isolated(*drop_vertices(v, e, drop))


def add_shortcuts(v: np.ndarray, e: np.ndarray, r: np.ndarray, count: int, rng: np.random.Generator,
                  surface: Inside, tries: int = 400) -> Graph | None:
    """``count`` straight edges through the air: between two vertices more than two local radii
    apart whose segment leaves the shape by at least half the local radius (``surface`` is the
    shape's signed distance), no two sharing an end. None when there are not enough such pairs (a
    straight tube)."""
    n = len(v)
    a = rng.integers(0, n, tries)
    b = rng.integers(0, n, tries)
    chord = np.linalg.norm(v[b] - v[a], axis=1)
    ok = (a != b) & (chord > 2 * np.minimum(r[a], r[b]))
    a, b, chord = a[ok], b[ok], chord[ok]
    if not len(a):
        return None
    t = np.linspace(0.0, 1.0, 21)[1:-1]
    pts = v[a][:, None, :] + t[None, :, None] * (v[b] - v[a])[:, None, :]
    depth = surface(pts.reshape(-1, 3)).reshape(len(a), len(t)).max(axis=1)
    ok = depth >= 0.5 * np.minimum(r[a], r[b])
    idx = np.flatnonzero(ok)
    if len(idx) < count:
        return None
    pick = idx[rng.permutation(len(idx))]
    used: list[tuple[int, int]] = []
    for i in pick:  # distinct pairs, no shared end
        if all(len({int(a[i]), int(b[i])} & set(p)) == 0 for p in used):
            used.append((int(a[i]), int(b[i])))
        if len(used) == count:
            break
    if len(used) < count:
        return None
    for x, y in used:
        v, e = join(v, e, x, y, float(r[x]))
    return v, e


def break_cycle(v: np.ndarray, e: np.ndarray, r: np.ndarray, gap: float, rng: np.random.Generator) -> Graph | None:
    """A gap of ``gap`` local radii (along the curve) cut into one of its cycles, around a random
    edge that lies on a cycle. None without a cycle."""
    n = len(v)
    for i in rng.permutation(len(e))[:200]:
        rest = np.delete(e, i, axis=0)
        g = coo_matrix((np.ones(len(rest)), (rest[:, 0], rest[:, 1])), shape=(n, n))
        _, c2 = connected_components(g, directed=False)
        if c2[e[i, 0]] != c2[e[i, 1]]:
            continue  # a bridge: not on a cycle
        x, y = e[i]
        half = 0.5 * gap * float(r[x])
        d = dijkstra(_lengths_graph(v, e), indices=[x, y], limit=half * 1.001).min(axis=0)
        drop_e = (d[e] <= half).all(axis=1)
        drop_e[i] = True
        v2, e2 = _drop_isolated(v, e[~drop_e])
        return v2, e2
    return None


def _pieces(n: int, e: np.ndarray) -> int:
    """Connected components with at least one edge (an isolated vertex is no piece)."""
    if not len(e):
        return 0
    _, lab = connected_components(coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)), directed=False)
    return len(np.unique(lab[e.ravel()]))


def cut_edges(v: np.ndarray, e: np.ndarray, count: int, rng: np.random.Generator) -> Graph | None:
    """``count`` random edges deleted whose ends both have degree >= 2 (a cut inside the curve, not a
    tip dropped; isolated vertices go): the broken curve of docs/diagnostics.md "Disconnected". None
    when there are fewer such edges or the curve did not split (two cuts on one ring)."""
    deg = _degrees(len(v), e)
    inner = np.flatnonzero((deg[e[:, 0]] >= 2) & (deg[e[:, 1]] >= 2))
    if len(inner) < count:
        return None
    rest = np.delete(e, rng.choice(inner, size=count, replace=False), axis=0)
    if _pieces(len(v), rest) <= _pieces(len(v), e):
        return None
    return _drop_isolated(v, rest)


def skeleton_noise(v: np.ndarray, e: np.ndarray, r: np.ndarray, sigma: float, rng: np.random.Generator) -> Graph:
    """Gaussian noise on every vertex, ``sigma`` local radii per coordinate (a jagged skeleton)."""
    return v + rng.normal(size=v.shape) * (sigma * r)[:, None], e.copy()


def offset(v: np.ndarray, e: np.ndarray, r: np.ndarray, shift: float, rng: np.random.Generator) -> Graph:
    """Every vertex moved ``shift`` local radii in one random direction (off the centre, same topology)."""
    d = rng.normal(size=3)
    d /= np.linalg.norm(d)
    return v + (shift * r)[:, None] * d, e.copy()


def oversmooth(v: np.ndarray, e: np.ndarray, iterations: int, lam: float = 0.5) -> Graph:
    """``iterations`` steps of umbrella (Laplacian) smoothing with weight ``lam``, ends and junctions
    fixed: bends are cut short (a skeletonizer smoothing too much); a pure cycle shrinks."""
    n = len(v)
    deg = _degrees(n, e)
    a = coo_matrix((np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])), shape=(n, n)).tocsr()
    move = (deg == 2).astype(float)[:, None] * lam
    inv = 1.0 / np.maximum(deg, 1)[:, None]
    x = v.copy()
    for _ in range(int(iterations)):
        x = x + move * (a @ x * inv - x)
    return x, e.copy()


@dataclass(frozen=True)
class Defect:
    """One defect of the study: its levels (mild to strong), their unit, and how to apply one."""

    name: str
    levels: tuple[Any, ...]
    unit: str
    what: str
    apply: Callable[..., Graph | None]

    def label(self, level: Any) -> str:
        if isinstance(level, tuple):
            return "x".join(f"{x:g}" for x in level)
        return f"{level:g}"


def _spurs(v, e, r, level, rng, surface):
    k, length = level
    return add_spurs(v, e, r, int(k), float(length), rng)[:2]


DEFECTS: dict[str, Defect] = {d.name: d for d in (
    Defect("truncation", (0.1, 0.2, 0.3), "share of each terminal branch",
           "every free end cut back by this share of its branch", lambda v, e, r, lv, rng, s: truncate(v, e, lv)),
    Defect("missing_branch", (1, 2, 3), "terminal branches", "this many terminal branches removed whole",
           lambda v, e, r, lv, rng, s: drop_branches(v, e, int(lv), rng)),
    Defect("spurs", ((1, 1.0), (3, 2.0), (6, 3.0)), "count x local radii",
           "this many spurs of this many local radii, sideways from inner vertices", _spurs),
    Defect("shortcut", (1, 2, 3), "edges", "this many straight edges through the air",
           lambda v, e, r, lv, rng, s: add_shortcuts(v, e, r, int(lv), rng, s)),
    Defect("chord_cycle", (1.0, 2.0, 4.0), "local radii spanned",
           "a chord inside the shape closing a loop over this span",
           lambda v, e, r, lv, rng, s: add_chord(v, e, r, lv, rng)),
    Defect("broken_cycle", (0.5, 2.0, 8.0), "local radii", "a gap this long cut into a cycle",
           lambda v, e, r, lv, rng, s: break_cycle(v, e, r, lv, rng)),
    Defect("collapse", (0.2, 0.5, 0.9), "share of the way to the centroid",
           "every vertex moved this share of the way to the centroid",
           lambda v, e, r, lv, rng, s: (collapse_points(v, lv), e.copy())),
    Defect("noise", (0.1, 0.25, 0.5), "local radii (sigma)", "Gaussian noise on every vertex",
           lambda v, e, r, lv, rng, s: skeleton_noise(v, e, r, lv, rng)),
    Defect("offset", (0.25, 0.5, 0.8), "local radii", "the whole skeleton shifted off the centre",
           lambda v, e, r, lv, rng, s: offset(v, e, r, lv, rng)),
    Defect("oversmoothing", (10, 100, 1000), "iterations", "Laplacian smoothing, ends and junctions fixed",
           lambda v, e, r, lv, rng, s: oversmooth(v, e, int(lv))),
)}


def apply_defect(name: str, level: Any, vertices: np.ndarray, edges: np.ndarray, radius: np.ndarray,
                 rng: np.random.Generator, surface: Inside) -> Graph | None:
    """Defect ``name`` at ``level`` applied to the curve (vertices, edges) with local radius
    ``radius`` per vertex; ``surface(points)`` is the shape's signed distance (shortcuts). None when
    the defect does not apply to this curve."""
    d = DEFECTS[name]
    v = np.asarray(vertices, float)
    e = np.asarray(edges, np.int64).reshape(-1, 2)
    r = np.asarray(radius, float)
    return d.apply(v, e, r, tuple(level) if isinstance(level, list) else level, rng, surface)
