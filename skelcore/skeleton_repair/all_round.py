"""Whether a missing region is seen all round (docs/repair.md "A thick part's fill"): the share of the
cloud's cross-sections through the region that is the region's own. The region is cut in slabs across
its main axis (those of the slabs' centroids, :func:`.fill._slab_line`); in each slab the cloud points
within :data:`REACH` times the region's farthest point from the slab's centroid (across the axis) are
the cross-section. A tube's end or a whole thick part cut off is its cross-sections whole (share near
1); the unexplained side of a tube the curve runs along shares them with the explained side (half a
ring: 0.51; 0.34-0.89 on the tuning neurons' cao curves at 30k points); a whole missing thin branch is
whole too (0.99-1.0; docs/repair.md "A thick part's fill")."""

from __future__ import annotations

import numpy as np

__all__ = ["all_round_share", "SLAB_FEWEST", "REACH"]

#: a slab with fewer region points than this is no cross-section (left out)
SLAB_FEWEST = 8
#: the cross-section's radius in the region's farthest point from the slab's centroid: half a ring of
#: radius r has its centroid 2r/pi off the axis, its farthest point 1.19 r away and the ring's far side
#: 1.64 r; at 1 the cross-section would miss most of the far side (a half tube's share 0.95)
REACH = 1.5


def all_round_share(cloud: np.ndarray, in_region: np.ndarray, step: float) -> float | None:
    """The share of the cloud points in the region's cross-sections (slabs ``step`` wide across its main
    axis) that belong to the region (``in_region``, per cloud point), the slabs weighted by their region
    points; None when no slab holds :data:`SLAB_FEWEST` of them."""
    cloud = np.asarray(cloud, float)
    inside = np.asarray(in_region, bool)
    pts = cloud[inside]
    if len(pts) < SLAB_FEWEST or not step > 0:
        return None
    c = pts.mean(axis=0)
    axes = np.linalg.svd(pts - c, full_matrices=False)[2]
    t = (cloud - c) @ axes[0]
    t0, t1 = t[inside].min(), t[inside].max()
    rows = np.flatnonzero((t >= t0) & (t <= t1))
    slab = np.floor((t[rows] - t0) / step).astype(np.int64)
    own = inside[rows]
    n_slabs = int(slab.max()) + 1
    n_own = np.bincount(slab[own], minlength=n_slabs)
    across = cloud[rows] @ axes[1:].T  # (x, y) across the main axis
    centre = np.stack([np.bincount(slab[own], weights=across[own, j], minlength=n_slabs) for j in (0, 1)], axis=1)
    centre /= np.maximum(n_own, 1)[:, None]
    r = np.linalg.norm(across - centre[slab], axis=1)
    reach = np.zeros(n_slabs)
    np.maximum.at(reach, slab[own], r[own])
    near = r <= REACH * reach[slab]
    n_near = np.bincount(slab[near], minlength=n_slabs)
    n_near_own = np.bincount(slab[near & own], minlength=n_slabs)
    ok = n_own >= SLAB_FEWEST
    if not ok.any():
        return None
    return float(np.average(n_near_own[ok] / n_near[ok], weights=n_own[ok]))
