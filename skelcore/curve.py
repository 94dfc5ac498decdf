"""The curve skeleton G_s = (V, E) as loaded and cleaned by SPEC 0."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from .errors import SkelInputError


@dataclass(frozen=True)
class CurveSkeleton:
    """Vertices (V x 3, float) and undirected edges (E x 2, int, each row i < j, unique, no loops).

    Build with :func:`CurveSkeleton.from_raw`, which applies SPEC 0's cleaning rules.
    ``vertex_map[i]`` is the row of the raw vertex array that cleaned vertex i came from.
    """

    vertices: np.ndarray
    edges: np.ndarray
    vertex_map: np.ndarray = field(default=None)  # type: ignore[assignment]

    @classmethod
    def from_raw(cls, vertices: object, edges: object, path: object | None = None) -> "CurveSkeleton":
        """Validate and clean: edge index out of range is an error; self-loops and duplicate edges
        are dropped; NaN vertices and their edges are dropped with a warning (pc-skeletor emits them).
        """
        try:
            v = np.asarray(vertices, dtype=float)
        except (TypeError, ValueError):
            raise SkelInputError("vertex coordinates are not numbers", path) from None
        if v.ndim != 2 or v.shape[1] != 3:
            raise SkelInputError(f"expected vertices as rows of x y z, got shape {v.shape}", path)
        e_raw = np.asarray(edges if edges is not None else np.empty((0, 2)))
        if e_raw.size == 0:
            e_raw = np.empty((0, 2))
        if e_raw.ndim != 2 or e_raw.shape[1] != 2:
            raise SkelInputError(f"expected edges as pairs of vertex indices, got shape {e_raw.shape}", path)
        if not np.all(np.isfinite(e_raw.astype(float))) or np.any(e_raw.astype(float) != np.round(e_raw.astype(float))):
            raise SkelInputError("edge indices must be whole numbers", path)
        e = e_raw.astype(np.int64)
        if len(e) and (e.min() < 0 or e.max() >= len(v)):
            bad = int(e.min()) if e.min() < 0 else int(e.max())
            raise SkelInputError(f"edge index {bad} out of range for {len(v)} vertices", path)
        if np.any(np.isinf(v)):
            raise SkelInputError("vertex coordinates contain inf", path)
        finite = np.all(np.isfinite(v), axis=1)
        keep_map = np.arange(len(v))
        if not finite.all():
            warnings.warn(
                f"{path or 'curve'}: dropped {int((~finite).sum())} vertices with NaN coordinates and their edges",
                stacklevel=2,
            )
            new_index = np.cumsum(finite) - 1
            e = e[finite[e].all(axis=1)]
            e = new_index[e]
            v = v[finite]
            keep_map = keep_map[finite]
        if len(v) == 0:
            raise SkelInputError("curve skeleton has no vertices", path)
        e = np.sort(e, axis=1)
        e = e[e[:, 0] != e[:, 1]]
        e = np.unique(e, axis=0) if len(e) else e.reshape(0, 2)
        return cls(vertices=v, edges=e.astype(np.int64), vertex_map=keep_map)

    @property
    def n_vertices(self) -> int:
        return int(len(self.vertices))

    @property
    def n_edges(self) -> int:
        return int(len(self.edges))

    def degrees(self) -> np.ndarray:
        return np.bincount(self.edges.ravel(), minlength=self.n_vertices)

    def edge_lengths(self) -> np.ndarray:
        return np.linalg.norm(self.vertices[self.edges[:, 1]] - self.vertices[self.edges[:, 0]], axis=1)

    def transformed(self, fn) -> "CurveSkeleton":
        """Same graph with vertices mapped by ``fn`` (e.g. a Normalization's apply)."""
        return CurveSkeleton(vertices=fn(self.vertices), edges=self.edges, vertex_map=self.vertex_map)
