"""Passes over a set of points against a box or a few centres, compiled (``_point_passes.c``): one loop over
the coordinates instead of numpy's chains of temporaries, the same bits as the numpy expressions they
replace (docs/performance.md 6.10, "The non-ray stages of a pruned branch, compiled")."""

from __future__ import annotations

import numpy as np

from . import _point_passes

__all__ = ["near_box", "nearest_squared", "nearest_two"]


def _points(points: np.ndarray) -> np.ndarray:
    out = np.ascontiguousarray(points, dtype=np.float64)
    if out.ndim != 2 or out.shape[1] != 3:
        raise ValueError(f"points must be (n, 3), not {out.shape}")
    return out


def near_box(points: np.ndarray, lo: np.ndarray, hi: np.ndarray, reach: np.ndarray, cover: float) -> np.ndarray:
    """Which ``points`` lie within ``bound = max(reach, cover) * (1 + 1e-9) + 1e-12`` (per point) of the box
    ``lo`` .. ``hi``: the distance to the box ``sqrt((tx^2 + ty^2) + tz^2)``, ``t = max(lo - x, x - hi, 0)``
    per coordinate, as numpy sums it (a point farther than ``bound * (1 + 1e-9)`` in one coordinate is not
    near)."""
    pts = _points(points)
    reach = np.ascontiguousarray(np.broadcast_to(np.asarray(reach, dtype=np.float64), (len(pts),)))
    out = np.empty(len(pts), bool)
    _point_passes.near_box(pts, np.ascontiguousarray(lo, dtype=np.float64), np.ascontiguousarray(hi, dtype=np.float64),
                           reach, float(cover), out)
    return out


def nearest_squared(points: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """Each point's squared distance to its nearest of ``centres``, ``(dx * dx + dy * dy) + dz * dz``
    (inf without centres)."""
    pts = _points(points)
    out = np.empty(len(pts))
    _point_passes.nearest_squared(pts, _points(np.reshape(centres, (-1, 3))), out)
    return out


def nearest_two(points: np.ndarray, centres: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each point's two nearest of ``centres`` (at least two; finite coordinates): the distances
    ``d0 <= d1`` (``cKDTree(centres).query(points, k=2)``'s, the same bits: square roots of
    ``(dx^2 + dy^2) + dz^2``) and a centre at ``d0`` (the only one where ``d0 < d1``). The centres are
    searched in blocks of their order, a block skipped when its box is no nearer than the second found:
    give them in a tree's order (the boxes small)."""
    pts, cen = _points(points), _points(centres)
    d0, d1, i0 = np.empty(len(pts)), np.empty(len(pts)), np.empty(len(pts), np.int64)
    _point_passes.nearest_two(pts, cen, d0, i0, d1)
    return d0, i0, d1
