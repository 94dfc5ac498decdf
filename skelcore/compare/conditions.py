"""A condition applied to a cloud: the paper's degradations (Results: "5% noise", "1024 pts", the
grid-averaged tree and cave) composed in one fixed order, repeatable from the seed.

Order: ``base_grid`` (voxel-grid average), then ``grid`` / ``sparse`` (random rows) / ``fps``
(farthest-point rows), then ``noise``. The noise and the downsampling draw from two independent
streams of the seed, so a condition's sparse rows do not change when noise is added to it, and
``skelcore study`` (which uses the same streams) reproduces its table.
"""

from __future__ import annotations

import numpy as np

from .manifest import ConditionSpec

__all__ = ["degrade"]


def degrade(cloud: np.ndarray, condition: ConditionSpec, seed: int) -> np.ndarray:
    """The degraded copy of ``cloud`` under ``condition`` (the cloud itself for "normal")."""
    from ..skeleton.degrade import add_noise, farthest_point_downsample, random_downsample, voxel_grid_average

    noise_rng, sparse_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(2))
    pts = cloud
    if condition.base_grid is not None:
        pts = voxel_grid_average(pts, condition.base_grid)[0]
    if condition.grid is not None:
        pts = voxel_grid_average(pts, condition.grid)[0]
    elif condition.sparse is not None:
        if condition.sparse < len(pts):
            pts = random_downsample(pts, condition.sparse, seed=sparse_rng)[0]
    elif condition.fps is not None:
        if condition.fps < len(pts):
            pts = farthest_point_downsample(pts, condition.fps, seed=sparse_rng)[0]
    if condition.noise:
        pts = add_noise(pts, condition.noise, model=condition.model, seed=noise_rng)  # type: ignore[arg-type]
    return pts
