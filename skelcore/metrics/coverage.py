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

from ..geometry import Checkpoint, TimedChunks, kd_tree, nearest_neighbor_distances, no_checkpoint, timed_query, unique_rows
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


def coverage_tau(cloud: np.ndarray, params: Params = Params(), checkpoint: Checkpoint = no_checkpoint) -> float:
    """tau = coverage_tau_factor x the cloud's median nearest-neighbour spacing."""
    return float(params.coverage_tau_factor * np.median(nearest_neighbor_distances(cloud, checkpoint=checkpoint)))


def _scaled(checkpoint: Checkpoint, lo: float, hi: float) -> Checkpoint:
    return lambda f: checkpoint(lo + (hi - lo) * min(max(f, 0.0), 1.0))


def _lifted(centers: np.ndarray, radii: np.ndarray, checkpoint: Checkpoint | None = None) -> tuple[cKDTree, float]:
    """A 4-D tree of (x, sqrt(R^2 - r^2)): |(p, 0) - lifted x|^2 - R^2 = |p - x|^2 - r(x)^2, the
    power distance, so nearest neighbours in 4-D are the balls of least power distance."""
    top = float(radii.max()) if len(radii) else 0.0
    w = np.sqrt(np.maximum(top * top - radii * radii, 0.0))
    return kd_tree(np.column_stack([centers, w]), checkpoint), top


def min_ball_excess(
    points: np.ndarray, centers: np.ndarray, radii: np.ndarray, k: int = 16, floor: float = -np.inf,
    class_ratio: float = 1.25, checkpoint: Checkpoint = no_checkpoint,
) -> np.ndarray:
    """Min over balls of |p - c| - radius for every point p (negative inside a ball), exact where
    it exceeds ``floor`` (elsewhere some value <= floor: enough to clip or threshold at floor).

    A first value u per point comes from its k nearest centres. Then, per class of radii within
    ``class_ratio`` (top radius R), candidates come by least power distance (4-D lifting,
    :func:`_lifted`), kk = 1, 4, 16, ...: a ball doing better than u has d < u + r, so its power
    distance is below u^2 + 2 u R (u > 0; u^2 when u <= 0), and a point is done with the class once
    its kk-th candidate's power distance reaches that bound.  Every query is made in chunks of
    about 0.1 s with a ``checkpoint`` after each (progress 0 -> 1 over the radius classes).
    """
    points = np.asarray(points, dtype=float)
    centers = np.asarray(centers, dtype=float)
    radii = np.asarray(radii, dtype=float)
    best = np.full(len(points), np.inf)
    if len(centers) == 0:
        return best
    kk0 = int(min(k, len(centers)))
    tree0 = kd_tree(centers, checkpoint)
    d, idx = timed_query(tree0, points, kk0, _scaled(checkpoint, 0.0, 0.3))
    best = np.min(d - radii[idx], axis=1)
    del tree0, d, idx
    top = float(radii.max())
    level = np.zeros(len(radii), dtype=np.int64)
    if top > 0:
        steps = np.floor(-np.log(np.maximum(radii, 1e-300) / top) / np.log(class_ratio))
        level = np.clip(steps, 0, 30).astype(np.int64)
    lifted_p = np.column_stack([points, np.zeros(len(points))])
    levels = np.unique(level)
    for n_lv, lv in enumerate(levels):
        members = np.flatnonzero(level == lv)
        c, r = centers[members], radii[members]
        tree, rtop = _lifted(c, r, checkpoint)
        rows = np.flatnonzero(best > floor)
        kk = 1
        tick = _scaled(checkpoint, 0.3 + 0.7 * n_lv / len(levels), 0.3 + 0.7 * (n_lv + 1) / len(levels))
        while len(rows):
            keep = []
            step = max(1, _PAIRS // kk)  # bounds the (rows x kk x 3) candidate array
            for lo, hi in TimedChunks(len(rows), most=step):
                r_ = rows[lo:hi]
                d4, ix = tree.query(lifted_p[r_], k=kk, workers=-1)
                d4, ix = d4.reshape(len(r_), kk), ix.reshape(len(r_), kk)
                d3 = np.linalg.norm(points[r_][:, None, :] - c[ix], axis=2)
                u = np.minimum(best[r_], np.min(d3 - r[ix], axis=1))
                best[r_] = u
                bound = np.where(u > 0, u * u + 2 * u * rtop, u * u)
                keep.append(r_[(u > floor) & (d4[:, -1] ** 2 - rtop * rtop < bound)])
                tick(0.0)
            if kk >= len(c):
                break
            rows = np.concatenate(keep)
            kk = int(min(4 * kk, len(c)))
        tick(1.0)
    return best


def covered_by_balls(
    points: np.ndarray, centers: np.ndarray, radii: np.ndarray, checkpoint: Checkpoint = no_checkpoint
) -> np.ndarray:
    """Is each point inside some ball: min power distance |p - c|^2 - radius^2 <= 0 (4-D queries,
    in chunks of about 0.1 s with a ``checkpoint`` after each).

    A first, approximate query (cKDTree ``eps=1``: it returns some ball, cheaply, even where many
    balls are nearly tangent) settles every point it finds inside a ball: the exact nearest ball is
    no farther.  Only the others get the exact query, so the answer is the same as asking every
    point exactly."""
    if len(centers) == 0:
        return np.zeros(len(points), dtype=bool)
    tree, top = _lifted(np.asarray(centers, dtype=float), np.asarray(radii, dtype=float), checkpoint)
    lifted = np.column_stack([points, np.zeros(len(points))])
    limit = 1e-12 * max(top * top, 1e-300)
    d4, _ = timed_query(tree, lifted, 1, _scaled(checkpoint, 0.0, 0.5), eps=1.0)
    inside = d4[:, 0] * d4[:, 0] - top * top <= limit
    rest = np.flatnonzero(~inside)
    if len(rest):
        d4, _ = timed_query(tree, lifted[rest], 1, _scaled(checkpoint, 0.5, 1.0))
        inside[rest] = d4[:, 0] * d4[:, 0] - top * top <= limit
    return inside


def coverage(
    cloud: np.ndarray, elements: np.ndarray, params: Params = Params(), tau: float | None = None,
    checkpoint: Checkpoint = no_checkpoint,
) -> Coverage:
    """Coverage of the (normalized) cloud by the medial balls of the (normalized) skeleton elements.

    Every KD-tree build and query checks ``checkpoint`` (cancel) at least every ~0.1 s of work."""
    cloud = np.asarray(cloud, dtype=float)
    elements = unique_rows(np.asarray(elements, dtype=float))[0]  # as np.unique(axis=0), 10 x faster
    checkpoint(0.0)
    tau = coverage_tau(cloud, params, _scaled(checkpoint, 0.0, 0.05)) if tau is None else float(tau)
    tree = kd_tree(cloud, checkpoint, 0.05)
    # r(x): a medial point's nearest surface point costs many node visits (docs/performance.md), so
    # the chunks are timed
    r = timed_query(tree, elements, 1, _scaled(checkpoint, 0.05, 0.25))[0][:, 0]
    del tree
    gap = np.maximum(min_ball_excess(cloud, elements, r, floor=0.0, checkpoint=_scaled(checkpoint, 0.25, 0.8)), 0.0)
    s = float(params.coverage_slack)
    # |p - x| - (1 + s) r <= tau  <=>  p lies in the ball of radius (1 + s) r + tau
    covered = covered_by_balls(cloud, elements, (1.0 + s) * r + tau, _scaled(checkpoint, 0.8, 1.0))
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
