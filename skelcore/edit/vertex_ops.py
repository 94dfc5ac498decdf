"""Edits of vertices: delete, add, move, merge. Each returns ``(new_curve, change)``; ids are kept
where they can be (an added vertex takes the next id; a deleted one closes the ids up, as the
change's ``id_map`` says)."""

from __future__ import annotations

import numpy as np

from ..curve import CurveSkeleton
from .change import Change, edge_pair, keep_vertices, position, rebuild, same_ids, vertex_id, vertex_map_of

__all__ = ["delete_vertex", "add_vertex", "move_vertex", "merge_vertices"]


def delete_vertex(curve: CurveSkeleton, vertex: int) -> tuple[CurveSkeleton, Change]:
    """Remove ``vertex`` and its edges; the higher ids move down by one (``change.id_map``)."""
    v = vertex_id(curve, vertex)
    keep = np.ones(curve.n_vertices, dtype=bool)
    keep[v] = False
    new, id_map = keep_vertices(curve, keep)
    return new, Change("delete_vertex", {"vertex": v}, removed=(v,), id_map=id_map, curve=new)


def add_vertex(curve: CurveSkeleton, position_: object, attach_to: int | None = None,
               radius: float | None = None) -> tuple[CurveSkeleton, Change]:
    """Add a vertex at ``position_`` (id: the vertex count), joined to ``attach_to`` when given;
    ``radius`` is its radius when the curve has radii (NaN: unknown)."""
    p = position(position_)
    a = None if attach_to is None else vertex_id(curve, attach_to, "attach_to")
    n = curve.n_vertices
    r = None
    if curve.radius is not None:
        r = np.append(curve.radius, np.nan if radius is None else float(radius))
    edges = curve.edges if a is None else np.vstack([curve.edges, [[a, n]]])
    new = rebuild(curve, np.vstack([curve.vertices, p]), edges, r, np.append(vertex_map_of(curve), -1))
    args = {"position": p.tolist(), "attach_to": a, "radius": None if radius is None else float(radius)}
    return new, Change("add_vertex", args, added=(n,), id_map=same_ids(curve), curve=new)


def move_vertex(curve: CurveSkeleton, vertex: int, position_: object) -> tuple[CurveSkeleton, Change]:
    """Move ``vertex`` to ``position_``; the graph and every id stay."""
    v = vertex_id(curve, vertex)
    p = position(position_)
    vertices = curve.vertices.copy()
    vertices[v] = p
    new = CurveSkeleton(vertices=vertices, edges=curve.edges, vertex_map=curve.vertex_map, radius=curve.radius)
    return new, Change("move_vertex", {"vertex": v, "position": p.tolist()}, moved=(v,), id_map=same_ids(curve),
                       curve=new)


def merge_vertices(curve: CurveSkeleton, keep: int, remove: int) -> tuple[CurveSkeleton, Change]:
    """Merge ``remove`` into ``keep``: ``keep`` moves to their midpoint and takes ``remove``'s edges (an
    edge between them disappears), its radius the mean of the known ones; ``remove``'s id goes."""
    a, b = vertex_id(curve, keep, "keep"), vertex_id(curve, remove, "remove")
    if a == b:
        edge_pair(curve, (a, b))  # the one-line "joins a vertex to itself"
    e = curve.edges.copy()
    e[e == b] = a
    vertices = curve.vertices.copy()
    vertices[a] = 0.5 * (curve.vertices[a] + curve.vertices[b])
    radius = None
    if curve.radius is not None:
        radius = curve.radius.copy()
        pair = radius[[a, b]]
        radius[a] = float(np.mean(pair[np.isfinite(pair)])) if np.isfinite(pair).any() else np.nan
    moved = CurveSkeleton(vertices=vertices, edges=curve.edges, vertex_map=curve.vertex_map, radius=radius)
    mask = np.ones(curve.n_vertices, dtype=bool)
    mask[b] = False
    new, id_map = keep_vertices(moved, mask, e)
    change = Change("merge_vertices", {"keep": a, "remove": b}, removed=(b,), moved=(int(id_map[a]),),
                    id_map=id_map, curve=new)
    return new, change
