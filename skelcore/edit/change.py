"""The record of one edit (:class:`Change`), the curve's content hash, and the checks and rebuild the
operations share: every operation returns a new curve and a Change saying what it did."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..curve import CurveSkeleton
from ..errors import SkelInputError

__all__ = ["Change", "content_hash"]


@dataclass(frozen=True)
class Change:
    """What one edit did: the operation's name and arguments (as the edit log writes them), the old
    vertex ids removed, the new ids added and moved, and ``id_map[old] = new`` (-1: removed).
    ``curve`` is the edited curve (what :meth:`skelcore.Evaluation.update` needs)."""

    op: str
    args: dict[str, Any]
    removed: tuple[int, ...] = ()
    added: tuple[int, ...] = ()
    moved: tuple[int, ...] = ()
    id_map: np.ndarray = field(default=None, repr=False, compare=False)  # type: ignore[assignment]
    curve: CurveSkeleton = field(default=None, repr=False, compare=False)  # type: ignore[assignment]

    def to_dict(self) -> dict[str, Any]:
        """The edit log's entry: ``{"op": ..., "args": {...}}``."""
        return {"op": self.op, "args": dict(self.args)}


def content_hash(curve: CurveSkeleton) -> str:
    """sha256 (hex) of the vertices as little-endian float64 bytes followed by the edges as
    little-endian int64 bytes, both row-major: what an edit log names the curve it starts from by."""
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(curve.vertices, dtype="<f8").tobytes())
    h.update(np.ascontiguousarray(np.asarray(curve.edges).reshape(-1, 2), dtype="<i8").tobytes())
    return h.hexdigest()


# ---- shared by the operations ---------------------------------------------------------------------

def vertex_id(curve: CurveSkeleton, v: object, what: str = "vertex") -> int:
    """``v`` as a vertex id of ``curve``, else a one-line SkelInputError."""
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)):
        raise SkelInputError(f"{what} id must be an integer, got {v!r}")
    if not 0 <= int(v) < curve.n_vertices:
        raise SkelInputError(f"{what} id {int(v)} out of range for {curve.n_vertices} vertices")
    return int(v)


def edge_pair(curve: CurveSkeleton, edge: object, *, existing: bool = True) -> tuple[int, int]:
    """``edge`` as (lower id, higher id); it must be an edge of ``curve`` (``existing``) or not yet one."""
    try:
        a, b = edge  # type: ignore[misc]
    except (TypeError, ValueError):
        raise SkelInputError(f"an edge is a pair of vertex ids, got {edge!r}") from None
    a, b = vertex_id(curve, a), vertex_id(curve, b)
    if a == b:
        raise SkelInputError(f"edge ({a}, {b}) joins a vertex to itself")
    lo, hi = min(a, b), max(a, b)
    found = bool(np.any((curve.edges[:, 0] == lo) & (curve.edges[:, 1] == hi))) if curve.n_edges else False
    if existing and not found:
        raise SkelInputError(f"({lo}, {hi}) is not an edge of the curve")
    if not existing and found:
        raise SkelInputError(f"({lo}, {hi}) is already an edge of the curve")
    return lo, hi


def position(value: object, what: str = "position") -> np.ndarray:
    """Three finite coordinates, else a one-line SkelInputError."""
    try:
        p = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise SkelInputError(f"{what} must be three numbers, got {value!r}") from None
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise SkelInputError(f"{what} must be three finite numbers, got {value!r}")
    return p


def rebuild(curve: CurveSkeleton, vertices: np.ndarray, edges: np.ndarray, radius: np.ndarray | None,
            vertex_map: np.ndarray) -> CurveSkeleton:
    """The edited curve, edges canonical as :meth:`CurveSkeleton.from_raw` leaves them (rows i < j,
    unique, sorted); refuses a result without edges (an edit that leaves nothing to score)."""
    e = np.sort(np.asarray(edges, dtype=np.int64).reshape(-1, 2), axis=1)
    e = e[e[:, 0] != e[:, 1]]
    if len(e) == 0:
        raise SkelInputError("this edit would leave the curve without edges")
    e = np.unique(e, axis=0)
    return CurveSkeleton(vertices=np.asarray(vertices, dtype=float), edges=e.astype(np.int64),
                         vertex_map=np.asarray(vertex_map, dtype=np.int64), radius=radius)


def keep_vertices(curve: CurveSkeleton, keep: np.ndarray, edges: np.ndarray | None = None
                  ) -> tuple[CurveSkeleton, np.ndarray]:
    """``curve`` restricted to the vertices where ``keep`` is True (their order kept, ids closed up) and
    the given old-id ``edges`` (default: the curve's) between kept vertices; returns (curve, id_map)."""
    keep = np.asarray(keep, dtype=bool)
    if not keep.any():
        raise SkelInputError("this edit would leave the curve without vertices")
    id_map = np.full(curve.n_vertices, -1, dtype=np.int64)
    id_map[keep] = np.arange(int(keep.sum()))
    e = curve.edges if edges is None else np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    e = id_map[e[keep[e].all(axis=1)]]
    vmap = np.arange(curve.n_vertices) if curve.vertex_map is None else np.asarray(curve.vertex_map)
    r = None if curve.radius is None else curve.radius[keep]
    return rebuild(curve, curve.vertices[keep], e, r, vmap[keep]), id_map


def same_ids(curve: CurveSkeleton) -> np.ndarray:
    """The id map of an edit that renumbers nothing."""
    return np.arange(curve.n_vertices, dtype=np.int64)


def vertex_map_of(curve: CurveSkeleton) -> np.ndarray:
    return np.arange(curve.n_vertices) if curve.vertex_map is None else np.asarray(curve.vertex_map)
