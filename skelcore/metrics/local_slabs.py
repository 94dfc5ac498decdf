"""Eq. 11's cross-section centeredness from a slab of each sample's own thickness (docs/diagnostics.md
"Along the surface", "Local sections").

The paper's slab (docs/metrics.md 3.2) is ``slab_factor`` x the cloud's diagonal thick whatever the part:
on a traced neuron that is 6-17 local radii, so its "section" is a slanted stretch of neurite. The
along-the-surface check reads, there, a slab of half-thickness ``half[i]`` per sample (a few of its local
radii) with the same rings (:func:`.centeredness._ring_columns`, the compiled ``_rings.c``) and the same
ellipse fit; the paper's metric is not changed.
"""

from __future__ import annotations

import numpy as np

from ..geometry import bbox_diagonal, unit_rows
from ..params import Params
from .centeredness import _orthonormal_complement, _ring_columns, _rings_centeredness, _SlabGrid

__all__ = ["local_slab_centeredness"]


_LADDER = 8  # slab halves per factor 2: each is rounded down to 2^(j / _LADDER) (at most 8 % thinner)


def local_slab_centeredness(cloud: np.ndarray, sample_points: np.ndarray, sample_directions: np.ndarray,
                            half: np.ndarray, growth: float | None = None, params: Params = Params()) -> np.ndarray:
    """c = max(0, 1 - |p - centre| / r) per sample (Eq. 11) from the slab |u . (x - p)| < ``half[i]``
    instead of the paper's alpha / 2; rings cut by ``growth`` (default ``params.ring_growth``). NaN: no
    direction, no positive half, fewer than 3 ring points (as :func:`.centeredness.curve_centeredness`).
    The halves are rounded down to a ladder of ``_LADDER`` steps per factor 2 so that the samples of one
    step share one call of the ring kernel (one call per sample costs about 0.5 ms of set-up)."""
    cloud = np.asarray(cloud, dtype=float)
    points = np.asarray(sample_points, dtype=float).reshape(-1, 3)
    half = np.asarray(half, dtype=float).reshape(-1)
    out = np.full(len(points), np.nan)
    if not len(points) or not len(cloud):
        return out
    u = unit_rows(np.asarray(sample_directions, dtype=float).reshape(-1, 3))
    todo = np.flatnonzero(np.all(np.isfinite(u), axis=1) & np.all(np.isfinite(points), axis=1) & (half > 0)
                          & np.isfinite(half))
    if not len(todo):
        return out
    growth = float(params.ring_growth if growth is None else growth)
    step = np.floor(np.log2(half[todo]) * _LADDER)
    half = np.exp2(step / _LADDER)
    # cells about a slab thick (the kernel's balls start at half a slab), no finer than the paper's floor
    grid = _SlabGrid(cloud, cell=max(float(np.median(half)), bbox_diagonal(cloud) / 512.0))
    g, h = _orthonormal_complement(u[todo])
    order = np.argsort(step, kind="stable")
    cut = np.flatnonzero(np.diff(step[order])) + 1
    with grid.ring_buffers() as bufs:
        for run in np.split(order, cut):  # one slab thickness per call
            i = todo[run]
            x, y, starts = _ring_columns(grid, points[i], u[i], g[run], h[run], float(half[run[0]]), growth,
                                         bufs=bufs)
            out[i] = _rings_centeredness(x, y, starts)
    return out
