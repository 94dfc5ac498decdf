"""A candidate action applied to the curve for its try (docs/repair.md "The repair's cost"): the curve
``skelcore.edit.apply`` gives entry by entry, to the bit, with each run of ``add_vertex`` /
``add_edge`` entries (a fill's new stretch, a reroute's path) made in one rebuild instead of one per
entry: a fill of a few hundred vertices re-sorted the whole edge list a few hundred times. A run whose
entries :mod:`skelcore.edit` would refuse (an id out of range, an edge already there, an argument it
does not take) is applied entry by entry, so the refusal and its message are the edit's own."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..curve import CurveSkeleton
from ..edit import apply
from ..edit.change import rebuild, vertex_map_of

__all__ = ["tried", "tried_one_by_one"]

#: the operations a run gathers: they only append vertices and edges, so their rebuilds commute
_ADDS = ("add_vertex", "add_edge")


def tried_one_by_one(curve: CurveSkeleton, entries: list[dict[str, Any]], where: str) -> CurveSkeleton:
    """``entries`` applied one after the other by :func:`skelcore.edit.apply` (the reference)."""
    return _one_by_one(curve, entries, 0, len(entries), where)


def _one_by_one(curve: CurveSkeleton, entries: list[dict[str, Any]], i: int, j: int, where: str
                ) -> CurveSkeleton:
    """Entries ``i`` to ``j - 1`` applied one by one, each named by its step in the whole action."""
    for k in range(i, j):
        curve, _ = apply(curve, entries[k], f"{where} step {k}")
    return curve


def _int_id(v: object, n: int) -> bool:
    return isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_)) and 0 <= int(v) < n


def _position(value: object) -> np.ndarray | list[float] | None:
    """The three finite coordinates of ``value`` (None when it has not them): a list of three Python
    floats as it is (what a fill writes; the same values numpy gives), else numpy's conversion."""
    if type(value) is list and len(value) == 3 and all(type(x) is float and math.isfinite(x) for x in value):
        return value
    try:
        p = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        return None
    return p if p.shape == (3,) and np.all(np.isfinite(p)) else None


def _added(curve: CurveSkeleton, run: list[dict[str, Any]]) -> CurveSkeleton | None:
    """``curve`` with the run of adds in one rebuild, or None when some entry is not plainly valid
    (then the edit applies them one by one and says why)."""
    n = curve.n_vertices
    points: list[np.ndarray | list[float]] = []
    pairs: list[tuple[int, int]] = []
    for entry in run:
        args = entry.get("args")
        if not isinstance(args, dict):
            return None
        if entry["op"] == "add_vertex":
            if "position" not in args or set(args) - {"position", "attach_to", "radius"} \
                    or args.get("radius") is not None:
                return None
            p, a = _position(args["position"]), args.get("attach_to")
            if p is None or not (a is None or _int_id(a, n + len(points))):
                return None
            if a is not None:
                pairs.append((int(a), n + len(points)))
            points.append(p)
        else:
            edge = args.get("edge")
            if set(args) != {"edge"} or not isinstance(edge, (list, tuple)) or len(edge) != 2:
                return None
            a, b = edge
            m = n + len(points)
            if not (_int_id(a, m) and _int_id(b, m)) or int(a) == int(b):
                return None
            pairs.append((min(int(a), int(b)), max(int(a), int(b))))
    new = np.array(pairs, np.int64).reshape(-1, 2)
    m = n + len(points)
    codes = new[:, 0] * m + new[:, 1]
    if len(np.unique(codes)) < len(codes):
        return None  # an edge added twice: the edit refuses the second
    if curve.n_edges and np.isin(codes, curve.edges[:, 0].astype(np.int64) * m + curve.edges[:, 1]).any():
        return None  # an edge already there
    vertices = np.vstack([curve.vertices, np.array(points, float).reshape(-1, 3)]) if points else curve.vertices
    radius = curve.radius
    if radius is not None and points:
        radius = np.append(radius, np.full(len(points), np.nan))
    vmap = vertex_map_of(curve)
    if points:
        vmap = np.append(vmap, np.full(len(points), -1))
    return rebuild(curve, vertices, np.vstack([curve.edges, new]), radius, vmap)


def tried(curve: CurveSkeleton, entries: list[dict[str, Any]], where: str) -> CurveSkeleton:
    """``entries`` applied to ``curve``: the curve :func:`tried_one_by_one` gives (the same bits; the
    same SkelInputError when an entry is refused), each run of adds in one rebuild."""
    i = 0
    while i < len(entries):
        j = i
        while j < len(entries) and isinstance(entries[j], dict) and entries[j].get("op") in _ADDS:
            j += 1
        if j - i > 1:
            new = _added(curve, entries[i:j])
            curve = new if new is not None else _one_by_one(curve, entries, i, j, where)
            i = j
        else:
            curve = _one_by_one(curve, entries, i, i + 1, where)
            i += 1
    return curve

