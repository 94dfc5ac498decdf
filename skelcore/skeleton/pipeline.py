"""``skeletonize``: from a bare cloud to both skeletal representations the metrics score.

Normalizes the cloud (SPEC 0 transform, longest side 1.6, like the reference toolbox's
``GS.normalize``), contracts it (:mod:`.contraction`), extracts the curve (:mod:`.curve_extraction`)
and returns both in the user's units. Deterministic: no randomness.
"""

from __future__ import annotations

import time
from typing import Callable

import numpy as np

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from ..geometry import Normalization, as_points, unique_rows
from .contraction import contract
from .curve_extraction import extract_curve
from .params import Progress, Reporter, SkeletonizeInfo, SkeletonizeParams

__all__ = ["skeletonize"]

def skeletonize(
    cloud: np.ndarray,
    params: SkeletonizeParams = SkeletonizeParams(),
    progress: Progress | None = None,
    cancel: Callable[[], bool] | None = None,
    *,
    return_info: bool = False,
):
    """Skeletonize a point cloud by Laplacian-based contraction (Cao et al. 2010).

    Parameters
    ----------
    cloud : (N, 3) points in the user's units (at least 10 distinct points).
    params : :class:`SkeletonizeParams`.
    progress : ``progress(fraction, stage)``; stages "laplacian", "contraction", "curve".
    cancel : returning True makes the next checkpoint raise :class:`~skelcore.errors.Cancelled`.
    return_info : also return a :class:`SkeletonizeInfo`.

    Returns
    -------
    skeletal : (N, 3) contracted points, row i is where cloud row i went (pointwise correspondence).
    curve : :class:`~skelcore.curve.CurveSkeleton` in the user's units.

    Examples
    --------
    >>> from skelcore import shapes
    >>> skeletal, curve = skeletonize(shapes.cylinder(2048).cloud)      # doctest: +SKIP
    >>> int(curve.degrees().max())                                       # doctest: +SKIP
    2
    """
    t0 = time.perf_counter()
    pts = as_points("cloud", cloud)
    if len(unique_rows(pts)[0]) < 10:
        raise SkelInputError("cloud: at least 10 distinct points are needed to skeletonize")
    norm = Normalization.from_cloud(pts, "longest_side", 1.6)
    pts_n = norm.apply(pts)
    report = Reporter(progress, cancel)

    t = time.perf_counter()
    contracted, adj, info = contract(pts_n, params, report=report)
    t_contract = time.perf_counter() - t
    diag = float(np.linalg.norm(pts_n.max(axis=0) - pts_n.min(axis=0)))
    radius = params.sample_radius_factor * diag
    t = time.perf_counter()
    verts, edges, _labels = extract_curve(contracted, adj, radius, params, original_n=pts_n, report=report)
    t_curve = time.perf_counter() - t

    skeletal = norm.invert(contracted)
    curve = CurveSkeleton.from_raw(norm.invert(verts), edges)
    if not return_info:
        return skeletal, curve
    sk_info = SkeletonizeInfo(
        iterations=info["iterations"],
        ring_ratios=[float(r) for r in info["ring_ratios"]],
        stop_reason=info["stop_reason"],
        sample_radius=radius / norm.scale,
        n_samples=int(curve.n_vertices),
        timings={"contraction": t_contract, "curve": t_curve, "total": time.perf_counter() - t0},
    )
    return skeletal, curve, sk_info
