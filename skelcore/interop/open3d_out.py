"""The evaluated curve skeleton as an Open3D LineSet coloured like the viewer (``Evaluation.to_open3d``).

The colours come from :mod:`skelcore.colors` (the viewer's maps over the metrics' range [0, 1], NaN
magenta, docs/metrics.md 5.5). As in the viewer, boundedness and centeredness colour each edge along its samples
(a vertex takes its nearest sample's value) and smoothness colours it from its two vertices; Open3D
colours whole segments, so every segment is halved and each half takes the value of its nearer end.
Open3D is imported only here, when asked; :func:`curve_lines` gives the same arrays without it.
"""

from __future__ import annotations

import numpy as np

from ..colors import map_to_rgb

__all__ = ["LINE_METRICS", "curve_lines", "to_open3d"]

LINE_METRICS = ("centeredness", "boundedness", "smoothness")


def _polylines(verts, edges, values, samples=None, sample_edge=None, sample_t=None):
    """(points, point values, segments): per-vertex values give one segment per edge; per-sample values
    give each edge a polyline through its samples in order of t."""
    if samples is None:
        return verts, values, edges
    from scipy.spatial import cKDTree

    n_edges = len(edges)
    vertex_value = values[cKDTree(samples).query(verts)[1]] if len(samples) else np.full(len(verts), np.nan)
    order = np.lexsort((sample_t, sample_edge))
    se = sample_edge[order]
    per_edge = np.bincount(se, minlength=n_edges)
    n_pts = per_edge + 2
    start = np.cumsum(n_pts) - n_pts
    total = int(n_pts.sum())
    pts = np.empty((total, 3))
    vals = np.empty(total)
    pts[start], vals[start] = verts[edges[:, 0]], vertex_value[edges[:, 0]]
    last = start + n_pts - 1
    pts[last], vals[last] = verts[edges[:, 1]], vertex_value[edges[:, 1]]
    rank = np.arange(len(se)) - (np.cumsum(per_edge) - per_edge)[se]
    slot = start[se] + 1 + rank
    pts[slot], vals[slot] = samples[order], values[order]
    inner = np.ones(total, bool)
    inner[last] = False
    a = np.flatnonzero(inner)
    return pts, vals, np.column_stack([a, a + 1])


def curve_lines(ev: "object", metric: str = "centeredness", *, cmap: str = "viridis",
                beta_star: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(points (P, 3), lines (L, 2), colours (L, 3) uint8) of the coloured curve, in user units."""
    if metric not in LINE_METRICS:
        raise ValueError(f"metric must be one of {', '.join(LINE_METRICS)}, got {metric!r}")
    cv = ev.curve
    if cv is None:
        raise ValueError("this evaluation has no curve skeleton")
    b_star = ev.params.beta_star if beta_star is None else float(beta_star)
    verts = np.asarray(cv.curve.vertices, dtype=np.float64)
    edges = np.asarray(cv.curve.edges, dtype=np.int64).reshape(-1, 2)
    if metric == "smoothness":
        pts, vals, segs = _polylines(verts, edges, np.asarray(cv.vertex_smoothness, dtype=np.float64))
    else:
        values = cv.sample_boundedness if metric == "boundedness" else cv.sample_centeredness(b_star)
        pts, vals, segs = _polylines(verts, edges, np.asarray(values, dtype=np.float64), np.asarray(cv.samples),
                                     np.asarray(cv.sample_edge, dtype=np.int64), np.asarray(cv.sample_t))
    mid = 0.5 * (pts[segs[:, 0]] + pts[segs[:, 1]])
    m = len(pts) + np.arange(len(segs))
    points = np.vstack([pts, mid])
    lines = np.vstack([np.column_stack([segs[:, 0], m]), np.column_stack([m, segs[:, 1]])])
    colours = map_to_rgb(np.concatenate([vals[segs[:, 0]], vals[segs[:, 1]]]), 0.0, 1.0, cmap)
    return points, lines, colours


def to_open3d(ev: "object", metric: str = "centeredness", *, cmap: str = "viridis", beta_star: float | None = None):
    """An ``open3d.geometry.LineSet`` of the curve coloured by ``metric`` (magenta = invalid)."""
    try:
        import open3d as o3d
    except ImportError:
        raise ImportError("Evaluation.to_open3d needs Open3D: pip install open3d (or pip install '.[interop]')") from None
    points, lines, colours = curve_lines(ev, metric, cmap=cmap, beta_star=beta_star)
    ls = o3d.geometry.LineSet()
    ls.points = o3d.utility.Vector3dVector(points)
    ls.lines = o3d.utility.Vector2iVector(lines.astype(np.int32))
    ls.colors = o3d.utility.Vector3dVector(colours.astype(np.float64) / 255.0)
    return ls
