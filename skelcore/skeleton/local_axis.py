"""A curve skeleton at the cloud's own spacing, for shapes with parts thinner than cao's sampling ball
(docs/skeletonize.md "Thin parts"): each point moves, a few times, to the centroid of its k nearest
cloud neighbours' current positions, the move's component along the neighbourhood's main axis removed
where the neighbourhood is linear (so tubes shrink onto their axis without shortening). The curve of
the moved points is by rings (:mod:`.axis_rings`, the default) or, with ``AxisParams.curve`` "balls",
by balls of a few spacings (:func:`.cao_curve.farthest_sampling_by_sphere`), two samples joined when
their points are near neighbours in the cloud, the minimum spanning forest of that graph. Every length
is in spacings (the median nearest-neighbour distance), none in bounding-box fractions.
:func:`local_thickness` (the median move) tells how thin the parts are."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import minimum_spanning_tree
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from .axis_rings import ring_curve
from .cao_curve import farthest_sampling_by_sphere
from .skeleton_params import AxisParams

__all__ = ["AxisContraction", "axis_contract", "axis_curve", "local_thickness"]

_CHUNK = 32768  # points whose neighbourhoods are held at once (k x 3 x 3 floats each)


@dataclass
class AxisContraction:
    """The moved points (one row per cloud row), the cloud's kNN (self first) and its spacing."""

    points: np.ndarray
    neighbors: np.ndarray
    spacing: float


def _chunk_step(p: np.ndarray, nb: np.ndarray, start: int, linearity: float) -> np.ndarray:
    """The move of points ``start``.. (a chunk): to their neighbours' centroid, less its part along a
    linear neighbourhood's main axis."""
    rows = nb[start:start + _CHUNK]
    q = p[rows]
    c = q.mean(axis=1)
    x = q - c[:, None, :]
    w, v = np.linalg.eigh(np.einsum("nki,nkj->nij", x, x))
    axis = v[:, :, 2]
    linear = (w[:, 2] - w[:, 1]) > linearity * np.maximum(w[:, 2], 1e-300)
    move = c - p[start:start + len(rows)]
    along = np.einsum("ni,ni->n", move, axis)
    return move - (linear * along)[:, None] * axis


def axis_contract(cloud: np.ndarray, params: AxisParams | None = None,
                  check: Callable[[float], None] | None = None) -> AxisContraction:
    """The cloud's points moved onto their local axes (module docstring); ``check(fraction)`` between
    steps may raise to cancel."""
    p_ = params or AxisParams()
    pts = np.asarray(cloud, float)
    k = int(min(p_.neighbors, len(pts) - 1))
    d, nb = cKDTree(pts).query(pts, k=k + 1, workers=-1)
    spacing = float(np.median(d[:, 1])) or float(np.mean(d[:, 1])) or 1.0
    p = pts.copy()
    for it in range(int(p_.iterations)):
        if check is not None:
            check(it / max(int(p_.iterations), 1))
        p = p + np.concatenate([_chunk_step(p, nb, s, p_.linearity) for s in range(0, len(p), _CHUNK)])
    return AxisContraction(p, nb, spacing)


def local_thickness(cloud: np.ndarray, moved: AxisContraction) -> float:
    """The median distance a point moved onto its axis: about the radius of the parts most points lie on."""
    return float(np.median(np.linalg.norm(moved.points - np.asarray(cloud, float), axis=1)))


def axis_curve(moved: AxisContraction, params: AxisParams | None = None,
               cloud: np.ndarray | None = None) -> CurveSkeleton:
    """The curve of the moved points: by rings (:func:`.axis_rings.ring_curve`, the default; given the
    ``cloud`` they were moved from, each ring's centre weights its points by their depth in it) or, with
    ``params.curve`` "balls", ball samples joined along the cloud's kNN, the minimum spanning forest
    of the joins by length (module docstring)."""
    p_ = params or AxisParams()
    if p_.curve == "rings":
        return ring_curve(moved.points, moved.spacing, p_, cloud)
    if p_.curve != "balls":
        raise ValueError(f"axis curve {p_.curve!r}: rings or balls")
    spl, label = farthest_sampling_by_sphere(moved.points, p_.sample_spacings * moved.spacing)
    verts = moved.points[spl]
    m = int(min(p_.connect_neighbors, moved.neighbors.shape[1] - 1))
    a = np.repeat(label, m)
    b = label[moved.neighbors[:, 1:m + 1]].ravel()
    keep = a != b
    pairs = np.unique(np.sort(np.column_stack([a[keep], b[keep]]), axis=1), axis=0)
    if len(pairs) == 0:
        return CurveSkeleton.from_raw(verts, np.zeros((0, 2), np.int64))
    length = np.linalg.norm(verts[pairs[:, 0]] - verts[pairs[:, 1]], axis=1) + 1e-12 * moved.spacing
    graph = coo_matrix((length, (pairs[:, 0], pairs[:, 1])), shape=(len(verts), len(verts))).tocsr()
    tree = minimum_spanning_tree(graph).tocoo()
    return CurveSkeleton.from_raw(verts, np.column_stack([tree.row, tree.col]).astype(np.int64))
