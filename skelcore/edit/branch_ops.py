"""Delete (prune) a whole branch, by its id in the curve's branch decomposition
(:func:`skelcore.diagnostics.branches.decompose_branches`, the ids the diagnostics report)."""

from __future__ import annotations

import numpy as np

from ..curve import CurveSkeleton
from ..diagnostics.branches import branch_paths
from ..errors import SkelInputError
from .change import Change, keep_vertices

__all__ = ["delete_branch", "prune_branch"]


def delete_branch(curve: CurveSkeleton, branch: int, *, _op: str = "delete_branch") -> tuple[CurveSkeleton, Change]:
    """Remove branch ``branch``: its edges, its inner vertices and its ends that lie on no other branch
    (a junction end stays); the remaining ids close up (``change.id_map``)."""
    if isinstance(branch, (bool, np.bool_)) or not isinstance(branch, (int, np.integer)):
        raise SkelInputError(f"branch id must be an integer, got {branch!r}")
    paths, edge_branch = branch_paths(curve)  # the decomposition's, kept when it was just made
    if not 0 <= int(branch) < len(paths):
        raise SkelInputError(f"branch id {int(branch)} out of range for {len(paths)} branches")
    k = int(branch)
    edges = curve.edges[edge_branch != k] if curve.n_edges else curve.edges
    path = np.unique(paths[k])
    still_used = np.zeros(curve.n_vertices, dtype=bool)
    still_used[edges.ravel()] = True
    gone = path[~still_used[path]]
    keep = np.ones(curve.n_vertices, dtype=bool)
    keep[gone] = False
    new, id_map = keep_vertices(curve, keep, edges)
    return new, Change(_op, {"branch": k}, removed=tuple(int(v) for v in gone), id_map=id_map, curve=new)


def prune_branch(curve: CurveSkeleton, branch: int) -> tuple[CurveSkeleton, Change]:
    """The same as :func:`delete_branch` (the proofreader's word for a spur)."""
    return delete_branch(curve, branch, _op="prune_branch")
