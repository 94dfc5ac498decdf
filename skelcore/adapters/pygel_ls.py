"""PyGEL3D's local-separator skeleton (Baerentzen & Rotenberg 2021) of the cloud's kNN graph.

The cloud (optionally thinned to one point per cube of side ``spacing``) becomes a graph: every
point joined to its ``k`` nearest neighbours (each pair once). ``graph.LS_skeleton_and_map`` returns
the skeleton graph and, for every graph node, its skeleton node, so the skeletal set is pointwise:
cloud row i gets the skeleton node of its graph node (of its nearest kept point when thinned).
PyGEL has no bulk constructor: nodes and edges are added one call each (a few microseconds).
On surface samples the separators are often small patches of the surface: docs/skeletonizers.md
has what it achieves on the generated shapes.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from .adapter_params import Param
from .adapter_result import AdapterResult

__all__ = ["PARAMS", "skeletonize", "knn_edges", "grid_thin"]

PARAMS = (
    Param("k", "int", 10, "neighbours of each point in the kNN graph", minimum=2),
    Param("spacing", "float", 0.0, "thin the cloud to one point per cube of this side first (cloud units; "
          "0: every point)", minimum=0.0),
    Param("sampling", "bool", False, "PyGEL's sampled separator seeds: faster, but PyGEL draws them from "
          "its own unseeded random numbers, so the skeleton differs from run to run"),
)


def grid_thin(points: np.ndarray, spacing: float) -> np.ndarray:
    """Rows of ``points`` kept by a grid of cubes of side ``spacing``: the first point of each cube."""
    key = np.floor((points - points.min(axis=0)) / spacing).astype(np.int64)
    _, first = np.unique(key, axis=0, return_index=True)
    return np.sort(first)


def knn_edges(points: np.ndarray, k: int) -> np.ndarray:
    """Each point joined to its ``k`` nearest others, every pair once (E x 2, i < j)."""
    k = min(k, len(points) - 1)
    nb = cKDTree(points).query(points, k=k + 1, workers=-1)[1][:, 1:]
    pairs = np.sort(np.column_stack([np.repeat(np.arange(len(points)), k), nb.ravel()]), axis=1)
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    return np.unique(pairs, axis=0)


def skeletonize(points: np.ndarray, params: dict[str, Any]) -> AdapterResult:
    """The LS skeleton of ``points`` (N x 3) with resolved ``params`` (:data:`PARAMS`)."""
    from pygel3d import graph

    pts = np.asarray(points, dtype=np.float64)
    if len(pts) < 3:
        raise SkelInputError(f"pygel needs at least 3 points, got {len(pts)}")
    keep = grid_thin(pts, params["spacing"]) if params["spacing"] > 0 else np.arange(len(pts))
    if len(keep) < 3:
        raise SkelInputError(f"pygel: spacing {params['spacing']:g} leaves {len(keep)} points (make it smaller)")
    sub = pts[keep]
    g = graph.Graph()
    for p in sub:
        g.add_node(p)
    for i, j in knn_edges(sub, params["k"]).tolist():
        g.connect_nodes(i, j)
    skel, node_of = graph.LS_skeleton_and_map(g, sampling=params["sampling"])
    ids = np.asarray(list(skel.nodes()), dtype=np.int64)
    if len(ids) == 0:
        raise SkelInputError("pygel returned an empty skeleton")
    row = np.full(int(ids.max()) + 1, -1, dtype=np.int64)
    row[ids] = np.arange(len(ids))
    positions = np.asarray(skel.positions(), dtype=np.float64)[ids]
    edges = np.array([(row[n], row[q]) for n in ids.tolist() for q in skel.neighbors(n) if n < q],
                     dtype=np.int64).reshape(-1, 2)
    mapped = np.asarray(list(node_of), dtype=np.int64)
    if len(mapped) != len(sub) or mapped.min() < 0 or mapped.max() >= len(row) or (row[mapped] < 0).any():
        raise SkelInputError("pygel's node map does not name a skeleton node for every point")
    node_rows = row[mapped]
    if len(keep) < len(pts):  # every cloud row takes the node of its nearest kept point
        node_rows = node_rows[cKDTree(sub).query(pts, k=1, workers=-1)[1]]
    curve = CurveSkeleton.from_raw(positions, edges)
    return AdapterResult(curve, positions[node_rows], "auto",
                         {"graph_nodes": int(len(sub)), "skeleton_nodes": int(len(ids))})
