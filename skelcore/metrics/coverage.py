"""Coverage: how much of the cloud a skeleton's medial balls reconstruct (SkelScope's own, not the
paper's; docs/metrics.md "Coverage").

Each skeleton element x (skeletal point, curve sample) gets the radius r(x) = distance to its
nearest cloud point, its inscribed ball. A cloud point p has the gap g(p) = min_x |p - x| - r(x)
(>= 0: its distance to the union of the balls); ``mean_gap`` and ``max_gap`` (one-sided Hausdorff
distance from the cloud to the balls) summarise it. p is covered when min_x |p - x| - (1 + s) r(x)
<= tau (``Params.coverage_slack`` s, tau = ``coverage_tau_factor`` x median NN spacing): a curve's
balls never fill a shape's ends, so a complete skeleton must not need them to.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..geometry import nearest_neighbor_distances
from ..params import Params

__all__ = ["Coverage", "coverage", "coverage_tau", "min_ball_excess"]

_CHUNK = 8192


@dataclass
class Coverage:
    """Per cloud point ``gap`` and ``covered``; ``fraction``, ``mean_gap``, ``max_gap`` (normalized)."""

    gap: np.ndarray
    covered: np.ndarray
    fraction: float
    mean_gap: float
    max_gap: float
    tau: float
    slack: float
    n_elements: int

    def to_dict(self) -> dict:
        return {"fraction": self.fraction, "mean_gap": self.mean_gap, "max_gap": self.max_gap}


def coverage_tau(cloud: np.ndarray, params: Params = Params()) -> float:
    """tau = coverage_tau_factor x the cloud's median nearest-neighbour spacing."""
    return float(params.coverage_tau_factor * np.median(nearest_neighbor_distances(cloud)))


def min_ball_excess(
    points: np.ndarray, centers: np.ndarray, radii: np.ndarray, k: int = 64, floor: float = -np.inf
) -> np.ndarray:
    """Min over balls of |p - c| - radius for every point p (negative inside a ball), exact where
    it exceeds ``floor`` (elsewhere some value <= floor: enough to clip or threshold at floor).

    Balls are grouped in classes of radii within a factor 2; in each class the k nearest centres
    give a value u (with the best so far); any other centre is at least
    d_k - r_max away, so only points whose d_k - r_max < u (and u > floor) are redone with 4k.
    """
    points = np.asarray(points, dtype=float)
    best = np.full(len(points), np.inf)
    if len(centers) == 0:
        return best
    radii = np.asarray(radii, dtype=float)
    top = float(radii.max())
    level = np.zeros(len(radii), dtype=np.int64)
    if top > 0:
        level = np.clip(np.floor(-np.log2(np.maximum(radii, 1e-300) / top)), 0, 10).astype(np.int64)
    for lv in np.unique(level):
        members = np.flatnonzero(level == lv)
        c, r = centers[members], radii[members]
        rmax = float(r.max())
        tree = cKDTree(c)
        for lo in range(0, len(points), _CHUNK):
            p = points[lo:lo + _CHUNK]
            cur = best[lo:lo + _CHUNK].copy()
            rows = np.arange(len(p))
            kk = int(min(k, len(c)))
            while len(rows):
                # a row is done once its kk-th nearest centre is beyond reach (d - rmax >= cur)
                dist, idx = tree.query(p[rows], k=kk, workers=-1)
                dist, idx = dist.reshape(len(rows), kk), idx.reshape(len(rows), kk)
                cur[rows] = np.minimum(cur[rows], np.min(dist - r[idx], axis=1))
                if kk >= len(c):
                    break
                rows = rows[(dist[:, -1] - rmax < cur[rows]) & (cur[rows] > floor)]
                kk = int(min(4 * kk, len(c)))
            best[lo:lo + _CHUNK] = cur
    return best


def coverage(cloud: np.ndarray, elements: np.ndarray, params: Params = Params(), tau: float | None = None) -> Coverage:
    """Coverage of the (normalized) cloud by the medial balls of the (normalized) skeleton elements."""
    cloud = np.asarray(cloud, dtype=float)
    elements = np.unique(np.asarray(elements, dtype=float), axis=0)
    tau = coverage_tau(cloud, params) if tau is None else float(tau)
    r, _ = cKDTree(cloud).query(elements, k=1, workers=-1)
    gap = np.maximum(min_ball_excess(cloud, elements, r, floor=0.0), 0.0)
    s = float(params.coverage_slack)
    covered = min_ball_excess(cloud, elements, (1.0 + s) * r, floor=tau) <= tau
    return Coverage(
        gap=gap,
        covered=covered,
        fraction=float(covered.mean()),
        mean_gap=float(gap.mean()),
        max_gap=float(gap.max()),
        tau=tau,
        slack=s,
        n_elements=int(len(elements)),
    )
