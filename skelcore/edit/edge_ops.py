"""Edits of edges: delete, add, split, and cut a cycle at an edge. Each returns ``(new_curve, change)``;
no vertex id changes (a split adds its vertex at the next id)."""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from .change import Change, edge_pair, rebuild, same_ids, vertex_map_of

__all__ = ["delete_edge", "add_edge", "split_edge", "cut_cycle"]


def _without(curve: CurveSkeleton, lo: int, hi: int) -> np.ndarray:
    e = curve.edges
    return e[~((e[:, 0] == lo) & (e[:, 1] == hi))]


def delete_edge(curve: CurveSkeleton, edge: tuple[int, int]) -> tuple[CurveSkeleton, Change]:
    """Remove the edge ``(a, b)``; both vertices stay (an end left alone is an isolated vertex)."""
    lo, hi = edge_pair(curve, edge)
    new = rebuild(curve, curve.vertices, _without(curve, lo, hi), curve.radius, vertex_map_of(curve))
    return new, Change("delete_edge", {"edge": [lo, hi]}, id_map=same_ids(curve), curve=new)


def add_edge(curve: CurveSkeleton, edge: tuple[int, int]) -> tuple[CurveSkeleton, Change]:
    """Join vertices ``a`` and ``b`` (not yet joined)."""
    lo, hi = edge_pair(curve, edge, existing=False)
    new = rebuild(curve, curve.vertices, np.vstack([curve.edges, [[lo, hi]]]), curve.radius, vertex_map_of(curve))
    return new, Change("add_edge", {"edge": [lo, hi]}, id_map=same_ids(curve), curve=new)


def split_edge(curve: CurveSkeleton, edge: tuple[int, int], t: float = 0.5) -> tuple[CurveSkeleton, Change]:
    """Put a new vertex on the edge ``(a, b)`` at fraction ``t`` (0 < t < 1) from its lower id, joined to
    both ends in its place; its radius (when the curve has radii) interpolated the same way."""
    lo, hi = edge_pair(curve, edge)
    try:
        t = float(t)
    except (TypeError, ValueError):
        raise SkelInputError(f"t must be a number between 0 and 1, got {t!r}") from None
    if not 0.0 < t < 1.0:
        raise SkelInputError(f"t must lie strictly between 0 and 1, got {t!r}")
    n = curve.n_vertices
    p = curve.vertices[lo] + t * (curve.vertices[hi] - curve.vertices[lo])
    r = None if curve.radius is None else np.append(curve.radius, (1 - t) * curve.radius[lo] + t * curve.radius[hi])
    edges = np.vstack([_without(curve, lo, hi), [[lo, n], [hi, n]]])
    new = rebuild(curve, np.vstack([curve.vertices, p]), edges, r, np.append(vertex_map_of(curve), -1))
    return new, Change("split_edge", {"edge": [lo, hi], "t": t}, added=(n,), id_map=same_ids(curve), curve=new)


def cut_cycle(curve: CurveSkeleton, edge: tuple[int, int]) -> tuple[CurveSkeleton, Change]:
    """Remove the edge ``(a, b)`` of a cycle: refused when the edge lies on no cycle (removing it would
    split its component)."""
    lo, hi = edge_pair(curve, edge)
    rest = _without(curve, lo, hi)
    n = curve.n_vertices
    graph = coo_matrix((np.ones(len(rest)), (rest[:, 0], rest[:, 1])), shape=(n, n))
    labels = connected_components(graph, directed=False)[1]
    if labels[lo] != labels[hi]:
        raise SkelInputError(f"edge ({lo}, {hi}) lies on no cycle: removing it would split the curve")
    new = rebuild(curve, curve.vertices, rest, curve.radius, vertex_map_of(curve))
    return new, Change("cut_cycle", {"edge": [lo, hi]}, id_map=same_ids(curve), curve=new)
