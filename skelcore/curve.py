"""The curve skeleton G_s = (V, E) as loaded and cleaned by docs/metrics.md 0."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from .errors import SkelInputError


@dataclass(frozen=True)
class CurveSkeleton:
    """Vertices (V x 3, float) and undirected edges (E x 2, int, each row i < j, unique, no loops).

    Build with :func:`CurveSkeleton.from_raw`, which applies the cleaning rules of docs/metrics.md 0, or
    :func:`CurveSkeleton.coerce` from any supported object (a pair, a LineSet, a networkx graph, ...).
    ``vertex_map[i]`` is the row of the raw vertex array that cleaned vertex i came from.
    ``radius[i]`` is vertex i's radius in the vertices' units (SWC, TreeQSM, PLY ``radius``), or None.
    """

    vertices: np.ndarray
    edges: np.ndarray
    vertex_map: np.ndarray = field(default=None)  # type: ignore[assignment]
    radius: np.ndarray | None = None

    @classmethod
    def coerce(cls, obj: object, name: str = "curve") -> "CurveSkeleton":
        """``obj`` as a CurveSkeleton: itself, a ``(vertices, edges)`` pair, or an object of another
        library (:mod:`skelcore.interop`); anything else is a TypeError naming what is accepted."""
        if isinstance(obj, CurveSkeleton):
            return obj
        from .interop.objects_in import curve_parts

        vertices, edges, radius = curve_parts(obj, name)
        return cls.from_raw(vertices, edges, radius=radius)

    @classmethod
    def from_raw(
        cls, vertices: object, edges: object, path: object | None = None, *, radius: object | None = None
    ) -> "CurveSkeleton":
        """Validate and clean: edge index out of range is an error; self-loops and duplicate edges
        are dropped; NaN vertices and their edges are dropped with a warning (pc-skeletor emits them).
        ``radius`` (one per raw vertex; NaN or negative = unknown) follows its vertex.
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
        r = None if radius is None else _radius(radius, len(v), path)
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
            r = None if r is None else r[finite]
        if len(v) == 0:
            raise SkelInputError("curve skeleton has no vertices", path)
        e = np.sort(e, axis=1)
        e = e[e[:, 0] != e[:, 1]]
        e = np.unique(e, axis=0) if len(e) else e.reshape(0, 2)
        return cls(vertices=v, edges=e.astype(np.int64), vertex_map=keep_map, radius=r)

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

    def transformed(self, fn, radius_scale: float | None = None) -> "CurveSkeleton":
        """Same graph with vertices mapped by ``fn`` (e.g. a Normalization's apply); the radius is
        kept, times ``radius_scale``, only when that scale is given (else it would be in the wrong units)."""
        r = None if self.radius is None or radius_scale is None else self.radius * float(radius_scale)
        return CurveSkeleton(vertices=fn(self.vertices), edges=self.edges, vertex_map=self.vertex_map, radius=r)


def _radius(radius: object, n: int, path: object | None) -> np.ndarray | None:
    """One radius per vertex; NaN or negative means unknown (SWC writers and cloud-volume use -1) and
    becomes NaN; all unknown is None; an infinite radius or a wrong count is a one-line SkelInputError."""
    try:
        r = np.array(radius, dtype=float).ravel()
    except (TypeError, ValueError):
        raise SkelInputError("vertex radii are not numbers", path) from None
    if r.shape != (n,):
        raise SkelInputError(f"{r.size} radii for {n} vertices", path)
    if np.any(np.isinf(r)):
        raise SkelInputError("vertex radii contain inf", path)
    r[r < 0] = np.nan
    return None if np.all(np.isnan(r)) else r
