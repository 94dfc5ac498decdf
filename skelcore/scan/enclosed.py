"""Whether an isolated point lies inside the sampled surface (docs/metrics.md 6.4).

A stray point is a return from the air: the sensor saw through free space to it.  A point the
surface encloses on every side (bounded in the sense of docs/metrics.md 2, the paper's beta above
``beta_star``) cannot be one: a clean sample of a neuron mesh shows such points, samples of small
fragments the mesh keeps inside its soma, 10-12 spacings from the soma's wall.  The rays test is
asked only where a first ray, from the point straight away from its nearest surface point, is
stopped (:func:`free_rays`): a stray in the air leaves that way at once.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..geometry import Normalization
from ..metrics.boundedness import boundedness
from ..params import Params

__all__ = ["enclosed", "free_rays"]

#: the farthest a ray's step looks for the nearest point, in ``radius``: a bounded query (an unbounded
#: one from far off a thin shape visits most of its tree: 1 ms a query at 300k points)
REACH = 16.0

#: the nearest points a step of a ray with ``beyond`` asks (those of the start's patch among them)
STOP_K = 8


def free_rays(start: np.ndarray, way: np.ndarray, radius: float, tree: cKDTree, lo: np.ndarray,
              hi: np.ndarray, beyond: float | None = None) -> np.ndarray:
    """(len(start),) bool: the ray from each start along its unit ``way`` leaves the box [lo, hi]
    (widened by ``radius``) with no point of ``tree`` within ``radius`` of the points taken along it:
    the first just past the start (which it does not hold), then every ``radius``, or farther where the
    nearest point is farther (sphere tracing, up to ``REACH`` radii: what lies between is certainly clear).
    ``beyond``: only points more than that far past the start along the ray stop it (of the
    ``STOP_K`` nearest each step): a ray from a surface point is not stopped by its own patch."""
    start = np.asarray(start, float).reshape(-1, 3)
    free = np.ones(len(start), bool)
    if len(start) == 0 or not radius > 0:
        return free
    lo, hi = np.asarray(lo, float) - radius, np.asarray(hi, float) + radius
    alive = np.arange(len(start))
    t = np.full(len(start), radius * (1.0 + 1e-6))
    while len(alive):
        at = start[alive] + t[alive, None] * way[alive]
        inside = np.all((at >= lo) & (at <= hi), axis=1)
        alive, at = alive[inside], at[inside]
        if len(alive) == 0:
            break
        if beyond is None:
            d = np.minimum(tree.query(at, k=1, distance_upper_bound=REACH * radius)[0], REACH * radius)
            hit = d <= radius
        else:
            dk, ik = tree.query(at, k=STOP_K, distance_upper_bound=REACH * radius)
            near = dk <= radius
            past = np.einsum("ikj,ij->ik", tree.data[np.where(near, ik, 0)] - start[alive, None, :], way[alive])
            hit = np.any(near & (past > beyond), axis=1)
            d = np.minimum(dk[:, 0], REACH * radius)
        free[alive[hit]] = False
        alive, d = alive[~hit], d[~hit]
        t[alive] += np.maximum(d - radius, radius)
    return free


def enclosed(points: np.ndarray, base: np.ndarray, tree: cKDTree, spacing: float,
             params: Params = Params()) -> np.ndarray:
    """(len(points),) bool: each point lies inside the surface sampled by ``base`` (``tree`` its
    kd-tree, ``spacing`` its median nearest-neighbour distance): the ray away from its nearest
    surface point is stopped within the surface's box, and its boundedness against ``base``
    (``params.boundedness_method``, in the normalization of docs/metrics.md 0) exceeds ``beta_star``."""
    points = np.asarray(points, float).reshape(-1, 3)
    out = np.zeros(len(points), bool)
    if len(points) == 0 or len(base) < 4 or not spacing > 0:
        return out
    _, near = tree.query(points, k=1, workers=-1)
    way = points - base[near]
    way /= np.maximum(np.linalg.norm(way, axis=1, keepdims=True), 1e-300)
    ask = np.flatnonzero(~free_rays(points, way, float(params.rays_radius_factor) * spacing, tree,
                                    base.min(axis=0), base.max(axis=0)))
    if len(ask):
        norm = Normalization.from_cloud(base, params.normalize_by, params.normalized_size)
        out[ask] = boundedness(norm.apply(base), norm.apply(points[ask]), params=params) > float(params.beta_star)
    return out
