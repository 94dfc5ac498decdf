"""Candidate actions, one per defect the judge found (docs/repair.md "Actions"): prune a spurious or
far-reaching terminal branch, delete the edge outside the shape, cut a spurious cycle at its weakest
edge, join two components by their closest vertex pair when the join stays inside the shape. Each
action is a short list of edit-log entries; the order is fixed (deterministic repairs)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from .findings import Findings

__all__ = ["Action", "propose", "component_labels"]

InShape = Callable[[np.ndarray], np.ndarray]
Route = Callable[[CurveSkeleton, int], "np.ndarray | None"]


@dataclass
class Action:
    """What to do (``entries``: ``{"op", "args"}`` of the edit log, applied in order) and why:
    the defect ``code``, its ``target`` (branch or cycle id of the evaluation), a sentence, and the
    edge ids of the current curve it touches (their local scores go into the log)."""

    code: str
    target: dict[str, Any]
    reason: str
    entries: list[dict[str, Any]]
    edges: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))


def component_labels(curve: CurveSkeleton) -> tuple[int, np.ndarray]:
    """Connected components of the curve's graph (isolated vertices count as their own)."""
    n = curve.n_vertices
    e = curve.edges
    g = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    return connected_components(g, directed=False)


def _edge_id(curve: CurveSkeleton, a: int, b: int) -> int:
    lo, hi = min(a, b), max(a, b)
    return int(np.flatnonzero((curve.edges[:, 0] == lo) & (curve.edges[:, 1] == hi))[0])


def _delete_edge_entries(curve: CurveSkeleton, edge: np.ndarray) -> list[dict[str, Any]]:
    """Delete the edge, then the ends it leaves alone (higher id first: the lower ids stay)."""
    a, b = int(edge[0]), int(edge[1])
    deg = np.bincount(curve.edges.ravel(), minlength=curve.n_vertices)
    out: list[dict[str, Any]] = [{"op": "delete_edge", "args": {"edge": [a, b]}}]
    for v in sorted((a, b), reverse=True):
        if deg[v] == 1:
            out.append({"op": "delete_vertex", "args": {"vertex": v}})
    return out


def _prunes(f: Findings, ids: np.ndarray, code: str, why: str) -> list[Action]:
    br = f.defects.branches
    out = []
    for b in ids:
        b = int(b)
        if br.kind[b] != "terminal":
            continue
        out.append(Action(code, {"branch": b}, why, [{"op": "prune_branch", "args": {"branch": b}}],
                          np.flatnonzero(br.edge_branch == b)))
    return out


def _reroute_entries(curve: CurveSkeleton, edge: np.ndarray, inner: np.ndarray) -> list[dict[str, Any]]:
    """Delete the edge, then walk from its lower end through the new points to its higher end."""
    a, b = int(edge[0]), int(edge[1])
    out: list[dict[str, Any]] = [{"op": "delete_edge", "args": {"edge": [a, b]}}]
    prev, n = a, curve.n_vertices
    for i, p in enumerate(inner):
        out.append({"op": "add_vertex", "args": {"position": [float(x) for x in p], "attach_to": prev}})
        prev = n + i
    out.append({"op": "add_edge", "args": {"edge": [min(prev, b), max(prev, b)]}})
    return out


def _trims(curve: CurveSkeleton, f: Findings, ids: np.ndarray, in_shape: InShape | None, step: float
           ) -> list[Action]:
    """A terminal branch leaving the shape loses only its tip: the first vertex outside moves back to
    where its edge leaves the shape, the vertices beyond it go (highest id first: the lower ids stay)."""
    if in_shape is None:
        return []
    br, od = f.defects.branches, f.defects.outside
    length = np.asarray(od.edge_outside_length, float)
    deg = np.bincount(curve.edges.ravel(), minlength=curve.n_vertices)
    key = {(int(a), int(b)): k for k, (a, b) in enumerate(curve.edges)}
    out = []
    for b in ids:
        b = int(b)
        if br.kind[b] not in ("terminal", "path"):
            continue
        path = [int(v) for v in br.paths[b]]
        if br.kind[b] == "terminal" and deg[path[0]] == 1:
            path = path[::-1]  # junction first, free end last
        for way in ([path] if br.kind[b] == "terminal" else [path, path[::-1]]):
            a = _trim(curve, way, b, length, key, in_shape, step)
            if a is not None:
                out.append(a)
                break
    return out


def _trim(curve: CurveSkeleton, path: list[int], b: int, length: np.ndarray, key: dict, in_shape: InShape,
          step: float) -> Action | None:
    """The tip of ``path`` (its last vertex the free end) cut back to where it leaves the shape."""
    i = len(path) - 1
    while i > 0 and length[key[tuple(sorted((path[i - 1], path[i])))]] > 0:
        i -= 1
    if i == len(path) - 1:
        return None  # no edge outside at the tip
    w, prev = path[i + 1], path[i]  # the first vertex beyond the last inside edge
    pa, pb = curve.vertices[prev], curve.vertices[w]
    m = max(2, int(np.ceil(float(np.linalg.norm(pb - pa)) / max(step, 1e-12))) + 1)
    pts = pa + np.linspace(0, 1, m)[:, None] * (pb - pa)
    inside = np.asarray(in_shape(pts), bool)
    if not inside[0]:
        return None
    last = int(np.argmin(inside)) - 1 if not inside.all() else m - 1
    if last <= 0:
        return None
    entries: list[dict[str, Any]] = [{"op": "move_vertex", "args": {"vertex": w,
                                                                   "position": [float(x) for x in pts[last]]}}]
    entries += [{"op": "delete_vertex", "args": {"vertex": v}} for v in sorted(path[i + 2:], reverse=True)]
    edges = np.array([key[tuple(sorted((path[k - 1], path[k])))] for k in range(i + 1, len(path))])
    return Action("outside", {"branch": b}, f"branch {b} leaves the shape at its free end: the tip cut back to "
                  f"where it leaves ({len(path) - i - 2} vertices beyond removed)", entries, edges)


def _splits(curve: CurveSkeleton, edge_ids: np.ndarray) -> bool:
    """Whether removing these edges leaves more components of edges than before."""
    keep = np.ones(curve.n_edges, bool)
    keep[edge_ids] = False
    if not keep.any():
        return True
    deg = np.bincount(curve.edges[keep].ravel(), minlength=curve.n_vertices)
    n0, l0 = component_labels(curve)
    rest = CurveSkeleton(vertices=curve.vertices, edges=curve.edges[keep])
    n1, l1 = component_labels(rest)
    return len(np.unique(l1[deg > 0])) > len(np.unique(l0[np.bincount(curve.edges.ravel(), minlength=curve.n_vertices) > 0]))


def _branch_delete(curve: CurveSkeleton, f: Findings, b: int, code: str, target: dict[str, Any], why: str,
                   on_cycle: bool = False) -> Action | None:
    """Delete branch ``b`` whole (edges and inner vertices) when that splits nothing (``on_cycle``: the
    branch lies on a cycle, so it splits nothing)."""
    br = f.defects.branches
    edges = np.flatnonzero(br.edge_branch == b)
    if br.kind[b] in ("terminal", "path", "cycle", "point") or (not on_cycle and _splits(curve, edges)):
        return None
    return Action(code, {**target, "branch": b}, why, [{"op": "delete_branch", "args": {"branch": b}}], edges)


def _outside_edges(curve: CurveSkeleton, f: Findings, route: Route | None = None) -> list[Action]:
    od, br = f.defects.outside, f.defects.branches
    out = []
    length = np.asarray(od.edge_outside_length, float)
    for b in od.defective_branches():
        b = int(b)
        whole = _branch_delete(curve, f, b, "outside", {}, f"branch {b} (between two junctions) leaves the shape "
                               f"for {float(od.branch_outside_length[b]):.3g}: deleted whole, the rest stays connected")
        if whole is not None:
            out.append(whole)
        on = np.flatnonzero((br.edge_branch == b) & (length > 0))
        if not len(on):
            continue
        k = int(on[np.argmax(length[on])])
        out.append(Action("outside", {"branch": b, "edge": curve.edges[k].tolist()},
                          f"edge {curve.edges[k].tolist()} of branch {b} runs {length[k]:.3g} outside the shape "
                          "(the longest outside stretch of the branch): deleted",
                          _delete_edge_entries(curve, curve.edges[k]), np.array([k])))
        inner = None if route is None else route(curve, k)
        if inner is not None and len(inner):
            out.append(Action("outside", {"branch": b, "edge": curve.edges[k].tolist()},
                              f"edge {curve.edges[k].tolist()} of branch {b} runs {length[k]:.3g} outside the shape: "
                              f"rerouted through the shape ({len(inner)} new vertices)",
                              _reroute_entries(curve, curve.edges[k], inner), np.array([k])))
    return out


class _Local:
    """:meth:`.findings.Findings.local` for many edge sets at once: the samples grouped by edge once
    (a stable sort, so each group keeps the samples' order), each set's samples gathered in the order
    ``np.isin`` would pick them, hence the same means to the bit."""

    def __init__(self, f: Findings) -> None:
        self.f = f
        self.order = np.argsort(f.sample_edge, kind="stable")
        self.sorted = f.sample_edge[self.order]

    def __call__(self, edges: np.ndarray) -> dict[str, float | None]:
        edges = np.unique(np.asarray(edges, np.int64))
        lo = np.searchsorted(self.sorted, edges, "left")
        hi = np.searchsorted(self.sorted, edges, "right")
        if not (hi > lo).any():
            return {"boundedness": None, "centeredness": None}
        on = np.sort(np.concatenate([self.order[a:b] for a, b in zip(lo, hi)]))
        c = self.f.sample_c[on]
        c = c[np.isfinite(c)]
        return {"boundedness": round(float(np.mean(self.f.sample_beta[on])), 4),
                "centeredness": round(float(np.mean(c)), 4) if len(c) else None}


def _weakest_edges(curve: CurveSkeleton, f: Findings, cycle: int, count: int = 2, local: _Local | None = None
                   ) -> list[int]:
    """The cycle's edges, weakest first: the longest outside stretch, then the lowest mean local
    boundedness + centeredness of its samples (an edge without samples: its ends' neighbours' mean)."""
    edges = f.defects.branches.cycle_edges(cycle)
    length = np.asarray(f.defects.outside.edge_outside_length, float)
    local = local or _Local(f)
    keys = []
    for k in edges:
        loc = local(np.array([k]))
        score = sum(v for v in loc.values() if v is not None) if loc["boundedness"] is not None else 2.0
        keys.append((-round(float(length[k]), 9), round(score, 9), int(k)))
    return [k for _, _, k in sorted(keys)[:count]]


def _weakest_branches(f: Findings, cycle: int, local: _Local | None = None) -> list[int]:
    """The cycle's branches, weakest first: the most length outside, then the lowest mean local
    boundedness + centeredness."""
    br, od = f.defects.branches, f.defects.outside
    local = local or _Local(f)
    keys = []
    for b in sorted({int(b) for b, _ in br.cycles[cycle]}):
        loc = local(np.flatnonzero(br.edge_branch == b))
        score = sum(v for v in loc.values() if v is not None) if loc["boundedness"] is not None else 2.0
        keys.append((-round(float(od.branch_outside_length[b]), 9), round(score, 9), b))
    return [b for _, _, b in sorted(keys)]


def _cycle_cuts(curve: CurveSkeleton, f: Findings) -> list[Action]:
    """Per spurious cycle: its weakest branch deleted whole (a branch on a cycle is no bridge: deleting
    it splits nothing, so :func:`_splits` need not be asked), then cuts at its two weakest edges."""
    out = []
    local = _Local(f)
    for i in f.defects.cycles.spurious:
        for b in _weakest_branches(f, int(i), local)[:1]:
            a = _branch_delete(curve, f, b, "spurious_cycles", {"cycle": int(i)},
                               f"cycle {int(i)} goes around no tunnel of the shape: its weakest branch {b} deleted",
                               on_cycle=True)
            if a is not None:
                out.append(a)
        for k in _weakest_edges(curve, f, int(i), local=local):
            e = curve.edges[k].tolist()
            out.append(Action("spurious_cycles", {"cycle": int(i), "edge": e},
                              f"cycle {int(i)} goes around no tunnel of the shape: cut at its weakest edge {e}",
                              [{"op": "cut_cycle", "args": {"edge": e}}], np.array([k])))
    return out


def _joins(curve: CurveSkeleton, f: Findings, in_shape: InShape | None, step: float) -> list[Action]:
    """Each smaller component joined to the rest by its closest vertex pair, when the segment is inside."""
    if in_shape is None:
        return []
    n, labels = component_labels(curve)
    deg = np.bincount(curve.edges.ravel(), minlength=curve.n_vertices)
    sizes = np.bincount(labels, minlength=n)
    real = [c for c in range(n) if deg[labels == c].sum() > 0]
    if len(real) < 2:
        return []
    main = max(real, key=lambda c: (sizes[c], -c))
    out = []
    for c in sorted((c for c in real if c != main), key=lambda c: (sizes[c], c)):
        mine = np.flatnonzero(labels == c)
        rest = np.flatnonzero((labels != c) & (deg > 0))
        d, j = cKDTree(curve.vertices[rest]).query(curve.vertices[mine])
        order = np.lexsort((mine, d))
        for i in order[:3]:  # the three closest pairs: the first whose segment stays inside
            a, b = int(mine[i]), int(rest[j[i]])
            pa, pb = curve.vertices[a], curve.vertices[b]
            if _inside_segment(in_shape, pa, pb, step):
                out.append(Action("components", {"component_vertex": a, "edge": sorted([a, b])},
                                  f"component of vertex {a} ({len(mine)} vertices) joined to the rest at its "
                                  f"closest inside pair ({a}, {b}), {float(d[i]):.3g} apart",
                                  [{"op": "add_edge", "args": {"edge": sorted([a, b])}}]))
                break
    return out


def _inside_segment(in_shape: InShape, pa: np.ndarray, pb: np.ndarray, step: float) -> bool:
    m = max(2, int(np.ceil(float(np.linalg.norm(pb - pa)) / max(step, 1e-12))) + 1)
    return bool(np.all(in_shape(pa + np.linspace(0, 1, m)[:, None] * (pb - pa))))


def _close_gaps(curve: CurveSkeleton, f: Findings, in_shape: InShape | None, step: float) -> list[Action]:
    """A tunnel no cycle goes around: the closest pairs of free ends of one component joined by a
    segment inside the shape (a cycle broken by a gap closes again)."""
    if in_shape is None or f.tally.get("missing_cycles", 0) == 0:
        return []
    deg = np.bincount(curve.edges.ravel(), minlength=curve.n_vertices)
    ends = np.flatnonzero(deg == 1)
    if len(ends) < 2:
        return []
    _, labels = component_labels(curve)
    p = curve.vertices[ends]
    d = np.linalg.norm(p[:, None] - p[None], axis=2)
    i, j = np.triu_indices(len(ends), 1)
    same = labels[ends[i]] == labels[ends[j]]
    i, j = i[same], j[same]
    out = []
    for k in np.lexsort((j, i, d[i, j]))[:3]:
        a, b = int(ends[i[k]]), int(ends[j[k]])
        if _inside_segment(in_shape, curve.vertices[a], curve.vertices[b], step):
            out.append(Action("missing_cycles", {"edge": [a, b]},
                              f"a tunnel no cycle goes around: free ends {a} and {b}, {float(d[i[k], j[k]]):.3g} "
                              "apart, joined inside the shape", [{"op": "add_edge", "args": {"edge": [a, b]}}]))
    return out


def propose(curve: CurveSkeleton, f: Findings, in_shape: InShape | None = None, join_step: float = 0.0,
            route: Route | None = None) -> list[Action]:
    """The candidate actions for ``curve`` from its findings, in the order they are tried: spurious
    branches, the outside tips of terminal branches, far or outside terminal branches, outside edges (deleted, else rerouted by ``route``),
    spurious cycles, components, free ends closing a missing cycle."""
    if f.defects is None:
        return []
    d = f.defects
    acts = _prunes(f, d.spurs.spurious, "spurious_branches",
                   "a spurious terminal branch (explains no part of the cloud the rest does not): pruned")
    seen = {a.target["branch"] for a in acts}
    acts += [a for a in _trims(curve, f, d.outside.defective_branches(), in_shape, join_step) if a.target["branch"] not in seen]
    acts += [a for a in _prunes(f, d.outside.defective_branches(), "outside",
                                "a terminal branch leaving the shape: pruned") if a.target["branch"] not in seen]
    acts += _outside_edges(curve, f, route)
    acts += _cycle_cuts(curve, f)
    acts += _joins(curve, f, in_shape, join_step)
    acts += _close_gaps(curve, f, in_shape, join_step)
    return acts
