"""Simulated partial scans: the points of a cloud that a sensor at a viewpoint sees (docs/metrics.md 6.5).

Hidden point removal (Katz, Tal and Basri, "Direct visibility of point sets", SIGGRAPH 2007; Open3D's
``hidden_point_removal``): the points, seen from the viewpoint C, are flipped spherically about a sphere
of radius R around C (p -> p + 2 (R - |p|) p / |p|, p relative to C); a point is visible when its image
lies on the convex hull of the images and C.  R = the largest |p| x 10^gamma; a larger gamma keeps more
points near the silhouette.  Used by the tests and benchmarks (one-sided scans of shapes with known
skeletons), and by anyone who wants to see what a scanner at a given place would have recorded.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError

__all__ = ["visible_from", "seen_from"]


def visible_from(cloud: np.ndarray, viewpoint: np.ndarray, *, gamma: float = 3.0) -> np.ndarray:
    """Boolean mask of the points of ``cloud`` visible from ``viewpoint`` (hidden point removal).

    Examples
    --------
    >>> from skelcore.shapes import sphere_surface
    >>> s = sphere_surface(4000)
    >>> seen = visible_from(s, np.array([0.0, 0, 10]))
    >>> bool(s[seen, 2].min() > -0.2), bool(0.4 < seen.mean() < 0.55)
    (True, True)
    """
    cloud = np.asarray(cloud, dtype=float)
    c = np.asarray(viewpoint, dtype=float).reshape(3)
    p = cloud - c
    norm = np.linalg.norm(p, axis=1)
    out = np.zeros(len(cloud), bool)
    ok = norm > 0
    if np.count_nonzero(ok) < 4:
        return out
    radius = float(norm.max()) * 10.0**gamma
    flipped = p[ok] + 2.0 * (radius - norm[ok])[:, None] * p[ok] / norm[ok][:, None]
    try:
        hull = ConvexHull(np.vstack([flipped, np.zeros(3)]))
    except QhullError:
        return out
    vertices = hull.vertices[hull.vertices < len(flipped)]
    out[np.flatnonzero(ok)[vertices]] = True
    return out


def seen_from(cloud: np.ndarray, viewpoints, *, gamma: float = 3.0) -> np.ndarray:
    """Mask of the points visible from at least one of the viewpoints (a scan from several places)."""
    mask = np.zeros(len(cloud), bool)
    for v in np.atleast_2d(np.asarray(viewpoints, dtype=float)):
        mask |= visible_from(cloud, v, gamma=gamma)
    return mask
