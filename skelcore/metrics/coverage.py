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

__all__ = ["Coverage", "coverage", "coverage_tau", "min_ball_excess", "covered_by_balls"]

_PAIRS = 2_000_000


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


def _lifted(centers: np.ndarray, radii: np.ndarray) -> tuple[cKDTree, float]:
    """A 4-D tree of (x, sqrt(R^2 - r^2)): |(p, 0) - lifted x|^2 - R^2 = |p - x|^2 - r(x)^2, the
    power distance, so nearest neighbours in 4-D are the balls of least power distance."""
    top = float(radii.max()) if len(radii) else 0.0
    w = np.sqrt(np.maximum(top * top - radii * radii, 0.0))
    return cKDTree(np.column_stack([centers, w])), top


def min_ball_excess(
    points: np.ndarray, centers: np.ndarray, radii: np.ndarray, k: int = 16, floor: float = -np.inf,
    class_ratio: float = 1.25,
) -> np.ndarray:
    """Min over balls of |p - c| - radius for every point p (negative inside a ball), exact where
    it exceeds ``floor`` (elsewhere some value <= floor: enough to clip or threshold at floor).

    A first value u per point comes from its k nearest centres. Then, per class of radii within
    ``class_ratio`` (top radius R), candidates come by least power distance (4-D lifting,
    :func:`_lifted`), kk = 1, 4, 16, ...: a ball doing better than u has d < u + r, so its power
    distance is below u^2 + 2 u R (u > 0; u^2 when u <= 0), and a point is done with the class once
    its kk-th candidate's power distance reaches that bound.
    """
    points = np.asarray(points, dtype=float)
    centers = np.asarray(centers, dtype=float)
    radii = np.asarray(radii, dtype=float)
    best = np.full(len(points), np.inf)
    if len(centers) == 0:
        return best
    kk0 = int(min(k, len(centers)))
    d, idx = cKDTree(centers).query(points, k=kk0, workers=1)
    best = np.min(d.reshape(len(points), kk0) - radii[idx.reshape(len(points), kk0)], axis=1)
    top = float(radii.max())
    level = np.zeros(len(radii), dtype=np.int64)
    if top > 0:
        steps = np.floor(-np.log(np.maximum(radii, 1e-300) / top) / np.log(class_ratio))
        level = np.clip(steps, 0, 30).astype(np.int64)
    lifted_p = np.column_stack([points, np.zeros(len(points))])
    for lv in np.unique(level):
        members = np.flatnonzero(level == lv)
        c, r = centers[members], radii[members]
        tree, rtop = _lifted(c, r)
        rows = np.flatnonzero(best > floor)
        kk = 1
        while len(rows):
            keep = []
            step = max(1, _PAIRS // kk)  # bounds the (rows x kk x 3) candidate array
            for lo in range(0, len(rows), step):
                r_ = rows[lo:lo + step]
                d4, ix = tree.query(lifted_p[r_], k=kk, workers=1)
                d4, ix = d4.reshape(len(r_), kk), ix.reshape(len(r_), kk)
                d3 = np.linalg.norm(points[r_][:, None, :] - c[ix], axis=2)
                u = np.minimum(best[r_], np.min(d3 - r[ix], axis=1))
                best[r_] = u
                bound = np.where(u > 0, u * u + 2 * u * rtop, u * u)
                keep.append(r_[(u > floor) & (d4[:, -1] ** 2 - rtop * rtop < bound)])
            if kk >= len(c):
                break
            rows = np.concatenate(keep)
            kk = int(min(4 * kk, len(c)))
    return best


def covered_by_balls(points: np.ndarray, centers: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Is each point inside some ball: min power distance |p - c|^2 - radius^2 <= 0 (one 4-D query)."""
    if len(centers) == 0:
        return np.zeros(len(points), dtype=bool)
    tree, top = _lifted(np.asarray(centers, dtype=float), np.asarray(radii, dtype=float))
    d4, _ = tree.query(np.column_stack([points, np.zeros(len(points))]), k=1, workers=-1)
    return d4 * d4 - top * top <= 1e-12 * max(top * top, 1e-300)


def coverage(cloud: np.ndarray, elements: np.ndarray, params: Params = Params(), tau: float | None = None) -> Coverage:
    """Coverage of the (normalized) cloud by the medial balls of the (normalized) skeleton elements."""
    cloud = np.asarray(cloud, dtype=float)
    elements = np.unique(np.asarray(elements, dtype=float), axis=0)
    tau = coverage_tau(cloud, params) if tau is None else float(tau)
    r, _ = cKDTree(cloud).query(elements, k=1, workers=-1)
    gap = np.maximum(min_ball_excess(cloud, elements, r, floor=0.0), 0.0)
    s = float(params.coverage_slack)
    # |p - x| - (1 + s) r <= tau  <=>  p lies in the ball of radius (1 + s) r + tau
    covered = covered_by_balls(cloud, elements, (1.0 + s) * r + tau)
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
