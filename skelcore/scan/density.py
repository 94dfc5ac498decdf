"""Density-aware boundedness (``Params.boundedness_density_aware``, ``--density-aware``; docs/metrics.md
6.8): where a cloud is sampled more sparsely than its median, the rays of the
paper's boundedness (2 median spacings wide) pass between its samples and an exact axis scores 0.37-0.50
with one half of its cloud 10 x sparser.  Each such point is joined to its ``FILL_K`` nearest cloud
points by segments sampled at the median spacing; the points on them enter boundedness only (as the
caps of ``--cap-openings`` do), so that every part is cast against as densely as the median.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..geometry import Checkpoint, no_checkpoint
from ..params import Params

__all__ = ["density_fill"]

#: a point is in a sparse part when the median distance of its FILL_K nearest points (the median of it
#: over itself and them) exceeds this many x the cloud's median of it (one half 10 x sparser: 3.2 x)
FILL_RATIO = 1.5
#: neighbours each sparse point is joined to (a fan around it: the segments cross its gaps)
FILL_K = 6
#: a segment is filled when at most this many x the median distance of the point's FILL_K neighbours
FILL_REACH = 1.25
#: points per segment at most (a part 64 x sparser than the median is filled to 1/4 of its gaps)
MAX_STEPS = 16


def density_fill(cloud: np.ndarray, params: Params = Params(), checkpoint: Checkpoint = no_checkpoint) -> np.ndarray:
    """The points added to ``cloud`` (normalized) for density-aware boundedness: on the segments from
    every point of a sparse part (``FILL_RATIO``) to those of its ``FILL_K`` nearest points that are no
    farther than ``FILL_REACH`` x its spacing (not across a tube), every median nearest-neighbour
    spacing.  Empty when no part is sparse."""
    cloud = np.asarray(cloud, dtype=float).reshape(-1, 3)
    if len(cloud) <= FILL_K + 1:
        return np.zeros((0, 3))
    tree = cKDTree(cloud)
    d, j = tree.query(cloud, k=FILL_K + 1, workers=-1)
    median = float(np.median(d[:, 1]))
    checkpoint(0.3)
    if not median > 0:
        return np.zeros((0, 3))
    # a point's spacing: the median distance of its FILL_K nearest points, against the cloud's median of it
    own = np.median(d[:, 1:], axis=1)
    part = np.median(own[j], axis=1)  # and its neighbours': a sparse part, not a random gap
    sparse = np.flatnonzero(part > FILL_RATIO * float(np.median(own)))
    checkpoint(0.7)
    if len(sparse) == 0:
        return np.zeros((0, 3))
    a = np.repeat(sparse, FILL_K)
    b = j[sparse, 1:].ravel()
    length = d[sparse, 1:].ravel()
    steps = np.minimum(np.ceil(length / median).astype(np.int64), MAX_STEPS)
    # a segment across a tube (its far side among the neighbours) would put points near the axis
    reach = FILL_REACH * own[sparse]
    keep = (steps >= 2) & (length <= np.repeat(reach, FILL_K))
    # each segment once (two sparse neighbours list each other: the same points twice, and copies of a
    # point would make the filled cloud's median spacing 0)
    pair, first_at = np.unique(np.sort(np.column_stack([a[keep], b[keep]]), axis=1), axis=0, return_index=True)
    a, b, steps = pair[:, 0], pair[:, 1], steps[keep][first_at]
    # the inner points of each segment: t = 1 / m, ..., (m - 1) / m
    seg = np.repeat(np.arange(len(a)), steps - 1)
    first = np.concatenate([[0], np.cumsum(steps - 1)[:-1]])
    k = np.arange(len(seg)) - first[seg] + 1
    t = (k / steps[seg])[:, None]
    checkpoint(1.0)
    return cloud[a[seg]] + t * (cloud[b[seg]] - cloud[a[seg]])
