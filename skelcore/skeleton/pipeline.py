"""``skeletonize``: from a bare cloud to both skeletal representations the metrics score.

Normalizes the cloud (the transform of docs/metrics.md 0, longest side 1.6, like the reference toolbox's
``GS.normalize``), contracts it and extracts the curve, returns both in the user's units.
``method="cao"`` (default) is the toolbox's own algorithm (:mod:`.cao_ring`, :mod:`.cao`,
:mod:`.cao_curve`); ``method="skelscope"`` is our variant with its clean-up steps
(:mod:`.contraction`, :mod:`.curve_extraction`). Deterministic: no randomness.
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
from .skeleton_params import CaoParams, Progress, Reporter, SkeletonizeInfo, SkeletonizeParams

__all__ = ["skeletonize", "METHODS"]

#: the built-in skeletonizers, default first
METHODS = ("cao", "skelscope")


def _method_and_params(method: str | None, params: object) -> tuple[str, object]:
    if method is None:
        method = "skelscope" if isinstance(params, SkeletonizeParams) else "cao"
    if method not in METHODS:
        raise ValueError(f"unknown skeletonize method {method!r}: use one of {', '.join(METHODS)}")
    want = CaoParams if method == "cao" else SkeletonizeParams
    if params is None:
        params = want()
    elif not isinstance(params, want):
        raise ValueError(f"method {method!r} takes {want.__name__}, got {type(params).__name__}")
    return method, params


def _skeletonize_cao(pts_n: np.ndarray, params: CaoParams, report: Reporter) -> tuple:
    from .cao import Rings, cao_contract
    from .cao_curve import cao_curve
    from .cao_ring import knn_count, point_rings

    report("laplacian", 0.0)
    k = knn_count(len(pts_n), params.min_neighbors, params.max_neighbors, params.neighbor_fraction)
    fan_start = params.fan_start_for(len(pts_n))
    indptr, indices, _closed = point_rings(pts_n, k, check=lambda f: report("laplacian", f), fan_start=fan_start)
    rings = Rings(indptr, indices)
    report("laplacian", 1.0)
    t = time.perf_counter()
    cpts, info = cao_contract(pts_n, rings, params, report=report)
    t_contract = time.perf_counter() - t
    lo, hi = pts_n.min(axis=0), pts_n.max(axis=0)
    radius = params.sample_radius_factor * float(np.linalg.norm(hi - lo))
    t = time.perf_counter()
    verts, edges, _labels, n_samples = cao_curve(cpts, rings, radius, check=lambda: report("curve", 0.5))
    report("curve", 1.0)
    info["n_samples_before_collapse"] = n_samples
    info["fan_start"] = fan_start
    return cpts, verts, edges, radius, info, t_contract, time.perf_counter() - t

def skeletonize(
    cloud: np.ndarray,
    params: CaoParams | SkeletonizeParams | None = None,
    progress: Progress | None = None,
    cancel: Callable[[], bool] | None = None,
    *,
    method: str | None = None,
    return_info: bool = False,
):
    """Skeletonize a point cloud by Laplacian-based contraction (Cao et al. 2010).

    Parameters
    ----------
    cloud : (N, 3) points in the user's units (at least 10 distinct points).
    params : :class:`CaoParams` for ``method="cao"``, :class:`SkeletonizeParams` for "skelscope";
        None = the method's defaults.
    method : "cao" (the toolbox's algorithm, the default) or "skelscope"; None = "skelscope" when
        ``params`` is a :class:`SkeletonizeParams`, else "cao".
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
    method, params = _method_and_params(method, params)
    norm = Normalization.from_cloud(pts, "longest_side", 1.6)
    pts_n = norm.apply(pts)
    report = Reporter(progress, cancel)

    if method == "cao":
        contracted, verts, edges, radius, info, t_contract, t_curve = _skeletonize_cao(pts_n, params, report)
    else:
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
        method=method,
        initial_weight=info.get("initial_weight"),
        fan_start=info.get("fan_start"),
    )
    return skeletal, curve, sk_info
