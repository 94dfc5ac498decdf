"""The local support behind a picked element's value, from the shown ``Evaluation``.

Which support depends on the element and the metric on screen: boundedness -> the direction map
around the element (paper Eq. 5-6; for the ``paper`` estimator its triangles); centeredness of a
curve sample -> its slab, ring and ellipse (Eq. 11, docs/metrics.md 3); centeredness of a skeletal point -> its
k neighbours and the two centroids (Eq. 10); smoothness of a skeletal point -> its tangent, its
neighbours' tangents and the angle setting the value (Eq. 13-14); of a curve vertex -> its two edges
and their angle (Eq. 15). The engine's :mod:`skelcore.metrics.supports` computes
them in normalized units; this module picks the rows and maps 3-D points back to the user's units.

A support computed in a thread of the window (a direction map over a million points takes seconds) is
given a ``checkpoint`` that raises once the pick is replaced or the window closes: the cloud's tree
(built once per evaluation, with its GIL released) stops at it, and the direction map runs in chunks
of ``DIRECTION_CHUNK`` points, so no numpy call holds the interpreter for long.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

__all__ = ["ElementSupport", "element_support"]


@dataclass
class ElementSupport:
    """What the support panel plots and the 3-D overlay highlights for one element.

    kind: "slab" | "knn" | "directions" | "smoothness" | "none" (``reason`` says why nothing is shown).
    points3d: named (n, 3) arrays in the user's units for the overlay (slab, ring, neighbours, ...).
    lines3d: named (n, 2, 3) segments (or, for "ellipse", an (n, 3) closed polyline) for the overlay.
    detail: the engine's support object (SlabSupport, KnnSupport, DirectionMap, PaperTriangles).
    """

    kind: str
    element: str
    index: int
    metric: str
    value: float = float("nan")
    reason: str = ""
    points3d: dict[str, np.ndarray] = field(default_factory=dict)
    lines3d: dict[str, np.ndarray] = field(default_factory=dict)
    detail: Any = None
    estimator: str = "rays"


_CACHE: dict[int, Any] = {}
_CLOUD: dict[int, Any] = {}

DIRECTION_CHUNK = 8192
"""Cloud points per step of a direction map: each numpy call of a step lasts a few milliseconds, so the
window's thread never waits long for the interpreter while a support computes beside it."""


def _cloud_n(ev: Any) -> np.ndarray:
    """The cloud in normalized units, one array per evaluation: the engine keeps the tree and spacing of
    the last array it prepared, so a second pick on the same result reuses them (seconds at 1M)."""
    key = id(ev)
    hit = _CLOUD.get(key)
    if hit is not None and hit[0] is ev:
        return hit[1]
    cloud_n = np.ascontiguousarray(ev.normalization.apply(ev.cloud), dtype=float)
    _CLOUD.clear()
    _CLOUD[key] = (ev, cloud_n)
    return cloud_n


def _curve_samples_n(ev: Any) -> Any:
    """The curve's samples and directions in normalized units, as evaluate computed them."""
    from skelcore.metrics.curve_sampling import sample_curve

    key = id(ev)
    hit = _CACHE.get(key)
    if hit is not None and hit[0] is ev:
        return hit[1]
    p = ev.params
    curve_n = ev.curve.curve.transformed(ev.normalization.apply)
    samples = sample_curve(curve_n, p.curve_samples, collinear_cos=p.collinear_cos, method=p.curve_sampling)
    _CACHE.clear()
    _CACHE[key] = (ev, samples)
    return samples


def _none(info: dict[str, Any], metric: str, reason: str) -> ElementSupport:
    return ElementSupport("none", info.get("element", ""), int(info.get("index", -1)), metric, reason=reason)


def element_support(ev: Any, info: dict[str, Any] | None, metric: str,
                    checkpoint: Callable[[float], None] | None = None) -> ElementSupport | None:
    """The support of the picked element ``info`` (``Scene.element_info``) for ``metric``;
    ``checkpoint`` (called now and then, it may raise to stop) is for a computation in a thread."""
    if ev is None or info is None:
        return None
    layer, location, i = info["layer"], info["location"], int(info["index"])
    cloud_n = _cloud_n(ev)
    if metric == "smoothness":
        return _smoothness(ev, info)
    if layer == "curve" and location == "vertices":
        return _none(info, metric, f"{metric} lives on the curve samples: pick a sample, not a vertex")
    if layer == "curve":
        if ev.curve is None:
            return _none(info, metric, "no curve result")
        q_user = np.asarray(ev.curve.samples[i], dtype=float)
    elif layer == "skeletal":
        if ev.skeletal is None:
            return _none(info, metric, "no skeletal result")
        q_user = np.asarray(ev.skeletal.points[i], dtype=float)
    else:
        return _none(info, metric, "pick a skeletal point or a curve sample")
    if metric == "boundedness":
        return _boundedness(ev, info, cloud_n, q_user, checkpoint)
    if layer == "curve":
        return _slab(ev, info, cloud_n, i)
    return _knn(ev, info, cloud_n, i)


def _boundedness(ev: Any, info: dict[str, Any], cloud_n: np.ndarray, q_user: np.ndarray,
                 checkpoint: Callable[[float], None] | None) -> ElementSupport:
    from skelcore.metrics.boundedness import paper_triangles, rays_radius
    from skelcore.metrics.supports import direction_map

    p = ev.params
    q_n = ev.normalization.apply(q_user[None])[0]
    values = ev.curve.sample_boundedness if info["layer"] == "curve" else ev.skeletal.boundedness
    out = ElementSupport("directions", info["element"], int(info["index"]), "boundedness",
                         value=float(values[int(info["index"])]), estimator=p.boundedness_method)
    out.points3d["query"] = q_user[None]
    if p.boundedness_method == "paper":
        out.detail = paper_triangles(cloud_n, q_n, plane_threshold=p.paper_plane_threshold,
                                     area_threshold=p.paper_area_threshold)
        if out.detail is None:
            out.reason = "fewer than 3 distinct directions: no triangulation (beta = 0)"
    else:
        if checkpoint is not None:  # the tree and spacing, stoppable; direction_map then finds them kept
            rays_radius(cloud_n, p.rays_radius_factor, checkpoint)
            checkpoint(0.0)
        out.detail = direction_map(cloud_n, q_n, params=p, chunk=DIRECTION_CHUNK)
    return out


def _slab(ev: Any, info: dict[str, Any], cloud_n: np.ndarray, i: int) -> ElementSupport:
    from skelcore.metrics.supports import curve_sample_support

    samples = _curve_samples_n(ev)
    sup = curve_sample_support(cloud_n, samples.points[i], samples.directions[i], params=ev.params)
    out = ElementSupport("slab", info["element"], i, "centeredness", value=sup.value, detail=sup)
    if not len(sup.slab):
        out.reason = "a joint (degree >= 3): no direction, so no slab (NaN)"
    cloud = np.asarray(ev.cloud, dtype=float)
    out.points3d["slab"] = cloud[sup.slab]
    out.points3d["ring"] = cloud[sup.slab[sup.ring]]
    out.points3d["query"] = np.asarray(ev.curve.samples[i], dtype=float)[None]
    if sup.centre is not None:
        centre_n = sup.point + sup.centre @ sup.basis
        out.points3d["centre"] = ev.normalization.invert(centre_n[None])
    if sup.ellipse is not None:  # the fitted ellipse in 3-D too, in the cross-section plane
        centre, axes, angle = sup.ellipse
        t = np.linspace(0.0, 2.0 * np.pi, 97)
        c, s_ = np.cos(angle), np.sin(angle)
        flat = np.column_stack([axes[0] * np.cos(t), axes[1] * np.sin(t)]) @ np.array([[c, s_], [-s_, c]])
        out.lines3d["ellipse"] = ev.normalization.invert(sup.point + (flat + np.asarray(centre)) @ sup.basis)
    return out


def _segments(origin: np.ndarray, directions: np.ndarray, length: float) -> np.ndarray:
    """(n, 2, 3) segments of ``length`` centred on each origin along each direction."""
    origin = np.atleast_2d(origin)
    half = 0.5 * length * np.asarray(directions, dtype=float).reshape(-1, 3)
    return np.stack([origin - half, origin + half], axis=1)


def _smoothness(ev: Any, info: dict[str, Any]) -> ElementSupport:
    """Smoothness: a skeletal point's tangent and its neighbours' (Eq. 13-14), or a curve vertex's two
    edges (Eq. 15); tangents drawn as segments one tenth of the skeleton's extent long."""
    from skelcore.metrics.supports import curve_vertex_support, skeletal_smoothness_support

    layer, location, i = info["layer"], info["location"], int(info["index"])
    if layer == "curve" and location == "samples":
        return _none(info, "smoothness", "smoothness lives on the curve vertices: pick a vertex")
    if layer == "curve":
        if ev.curve is None:
            return _none(info, "smoothness", "no curve result")
        curve = ev.curve.curve
        sup = curve_vertex_support(curve.vertices, curve.edges, i)
        out = ElementSupport("smoothness", info["element"], i, "smoothness", value=sup.value, detail=sup)
        out.points3d["query"] = sup.point[None]
        if not np.isfinite(sup.value):
            out.reason = f"degree {len(sup.neighbours)}: smoothness needs exactly two edges (NaN, magenta)"
            out.detail = None
            return out
        out.points3d["neighbours"] = np.asarray(curve.vertices, dtype=float)[sup.neighbours]
        out.lines3d["edges"] = np.stack([np.repeat(sup.point[None], 2, axis=0), out.points3d["neighbours"]], axis=1)
        return out
    if ev.skeletal is None:
        return _none(info, "smoothness", "no skeletal result")
    pts = np.asarray(ev.skeletal.points, dtype=float)
    sup = skeletal_smoothness_support(pts, i, params=ev.params)
    out = ElementSupport("smoothness", info["element"], i, "smoothness", value=sup.value, detail=sup)
    out.points3d["query"] = pts[i][None]
    out.points3d["neighbours"] = pts[sup.neighbours]
    if sup.worst < 0:
        out.reason = "no tangent here or at its neighbours (all at one position): NaN"
        out.detail = None
        return out
    extent = float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0))) or 1.0
    length = 0.1 * extent
    out.lines3d["tangent"] = _segments(pts[i], sup.tangent, length)
    others = [j for j in range(len(sup.neighbours)) if j != sup.worst]
    out.lines3d["neighbour_tangents"] = _segments(pts[sup.neighbours[others]], sup.neighbour_tangents[others], length)
    out.lines3d["worst_tangent"] = _segments(pts[sup.neighbours[sup.worst]], sup.neighbour_tangents[sup.worst], length)
    out.points3d["worst"] = pts[sup.neighbours[sup.worst]][None]
    return out


def _knn(ev: Any, info: dict[str, Any], cloud_n: np.ndarray, i: int) -> ElementSupport:
    from skelcore.metrics.supports import skeletal_point_support

    s = ev.skeletal
    mode = ev.correspondence
    cloud = np.asarray(ev.cloud, dtype=float)
    skel_user = np.asarray(s.points, dtype=float)
    skel_n = ev.normalization.apply(skel_user)
    if mode == "none" or not s.centeredness_available:
        return _none(info, "centeredness", "no correspondence between the skeletal points and the cloud: "
                     "skeletal centeredness is not computed")
    index = getattr(s, "index", None)
    if mode == "index" and index is None:
        return _none(info, "centeredness", "the skeletal index is not kept with the evaluation: "
                     "its neighbourhood cannot be drawn")
    row = i
    corr_n, corr_user = cloud_n, cloud  # the cloud point of each pointwise skeletal row
    pointwise_n, pointwise_user = skel_n, skel_user
    if mode == "index":  # skeletal row j corresponds to cloud row index[j]
        index = np.asarray(index, dtype=np.int64)
        corr_n, corr_user = cloud_n[index], cloud[index]
    elif mode == "reverse":
        # the pointwise set is (skel[rows], cloud): show the first cloud row projected onto point i
        mapped = np.flatnonzero(np.asarray(s.rows) == i)
        if not len(mapped):
            return _none(info, "centeredness", "no cloud point projects onto this skeletal point (NaN)")
        row = int(mapped[0])
        pointwise_n, pointwise_user = skel_n[s.rows], skel_user[s.rows]
    sup = skeletal_point_support(corr_n, pointwise_n, row, params=ev.params)
    out = ElementSupport("knn", info["element"], i, "centeredness", value=sup.value, detail=sup)
    inv = ev.normalization.invert
    out.points3d["neighbours"] = pointwise_user[sup.neighbours]
    out.points3d["cloud"] = corr_user[sup.neighbours]
    out.points3d["m_s"] = inv(sup.skeletal_centroid[None])
    out.points3d["m_o"] = inv(sup.cloud_centroid[None])
    out.points3d["query"] = skel_user[i][None]
    out.lines3d["links"] = np.stack([out.points3d["neighbours"], out.points3d["cloud"]], axis=1)
    return out
