"""A curve skeleton from a skeletal set alone, for ``skelcore repair CLOUD --skeletal S`` without a
curve (docs/repair.md "A skeletal set alone"): the curve step of the ``cao`` skeletonizer run on the
given skeletal set instead of its own contraction, so a skeletal set is read as ``skelcore
skeletonize`` reads the one it makes. Farthest-point balls of ``sample_radius_factor`` x the
normalized cloud's diagonal, connected where the cloud's one-rings connect their points, triangles
collapsed (:func:`skelcore.skeleton.cao_curve.cao_curve`)."""

from __future__ import annotations

import numpy as np

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from ..geometry import Normalization, as_points

__all__ = ["curve_from_skeletal", "HOW"]

#: how the curve was made, for the command's stderr line and the log's ``repair`` block
HOW = ("the curve step of the cao skeletonizer (farthest-point balls of 0.02 x the cloud's diagonal on "
       "the skeletal points, joined where the cloud's one-rings join their points, triangles collapsed)")


def curve_from_skeletal(cloud: np.ndarray, skeletal: np.ndarray) -> CurveSkeleton:
    """The curve of ``skeletal`` (one row per cloud row, row i where cloud row i went) by the ``cao``
    skeletonizer's curve step, in the user's units; SkelInputError when the rows do not match or
    no edge comes out."""
    from ..skeleton.cao import Rings
    from ..skeleton.cao_curve import cao_curve
    from ..skeleton.cao_ring import knn_count, point_rings
    from ..skeleton.skeleton_params import CaoParams

    pts = as_points("cloud", cloud)
    skel = as_points("skeletal", skeletal)
    if len(skel) != len(pts):
        raise SkelInputError(f"a curve is extracted from a skeletal set with one row per cloud row: "
                             f"{len(skel)} skeletal rows, {len(pts)} cloud rows")
    if len(pts) < 10:
        raise SkelInputError("at least 10 points are needed to extract a curve from the skeletal set")
    p = CaoParams()
    norm = Normalization.from_cloud(pts, "longest_side", 1.6)
    pts_n = norm.apply(pts)
    k = knn_count(len(pts_n), p.min_neighbors, p.max_neighbors, p.neighbor_fraction)
    indptr, indices, _closed = point_rings(pts_n, k, fan_start=p.fan_start_for(len(pts_n)))
    radius = p.sample_radius_factor * float(np.linalg.norm(pts_n.max(axis=0) - pts_n.min(axis=0)))
    verts, edges, _labels, _n = cao_curve(norm.apply(skel), Rings(indptr, indices), radius)
    curve = CurveSkeleton.from_raw(norm.invert(verts), edges)
    if curve.n_edges == 0:
        raise SkelInputError("the curve extracted from the skeletal set has no edges: nothing to repair")
    return curve
