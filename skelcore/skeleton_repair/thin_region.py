"""A large missing region thinned out before its ``skelscope`` skeletonization (docs/repair.md "The
repair's cost"): the mean of its points in each cell of the finest cubic grid that leaves at most
``Params.repair_fill_points`` cells. That skeletonization's cost grows with the points (robust_laplacian's
Laplacians, docs/skeletonize.md "Speed"), while its curve samples balls of a fiftieth of the region's
diagonal, which a few thousand points spread evenly fill; its contraction weights follow the point
count (:func:`skelcore.skeleton.contraction.contract`), so a thinned region contracts alike.

Not :func:`skelcore.skeleton.degrade.voxel_grid_average`: the bisection counts a grid's cells some 15
times, which one integer key per cell does in a 1-d unique (that function's row unique took about 1 s on
46,000 points), and the means come in the cells' lexicographic order, which the measured fills used."""

from __future__ import annotations

import numpy as np

__all__ = ["thinned", "cells"]

#: at most this many bisection steps on the cell side (log scale); they stop once it is known within 1 %
_STEPS = 40


def cells(pts: np.ndarray, side: float) -> tuple[np.ndarray, int]:
    """(each point's cell label, the number of cells) of the grid of ``side`` anchored at the points'
    lower corner; labels follow the cells' lexicographic order."""
    ijk = np.floor((pts - pts.min(axis=0)) / side).astype(np.int64)
    dims = ijk.max(axis=0, initial=0) + 1
    if float(np.prod(dims.astype(float))) < 2.0 ** 62:  # one integer key per cell: a fast 1-d unique
        _, label = np.unique((ijk[:, 0] * dims[1] + ijk[:, 1]) * dims[2] + ijk[:, 2], return_inverse=True)
    else:
        _, label = np.unique(ijk, axis=0, return_inverse=True)
    label = label.reshape(-1)
    return label, int(label.max()) + 1 if len(label) else 0


def thinned(pts: np.ndarray, cap: int) -> np.ndarray:
    """``pts`` itself when it holds at most ``cap`` points, else the means of its points per cell of
    the finest grid (bisected on the cell's side) with at most ``cap`` occupied cells, in the cells'
    order. Deterministic; the means lie in the region's bounding box."""
    pts = np.asarray(pts, float)
    if len(pts) <= cap:
        return pts
    lo_side = 0.0  # too fine: more than cap cells
    hi_side = float(np.max(np.ptp(pts, axis=0))) * 1.000001 or 1.0  # one cell per axis: few cells
    area = float(np.prod(np.sort(np.ptp(pts, axis=0))[1:])) or hi_side * hi_side
    side = min(np.sqrt(area / cap), hi_side)  # a first guess: a surface's cells
    for _ in range(_STEPS):
        n = cells(pts, side)[1]
        if n > cap:
            lo_side = side
        else:
            hi_side = side
        side = np.sqrt(lo_side * hi_side) if lo_side > 0 else hi_side / 2.0
        if lo_side > 0 and hi_side / lo_side < 1.01:
            break
    label, n = cells(pts, hi_side)
    counts = np.bincount(label, minlength=n).astype(float)
    return np.column_stack([np.bincount(label, weights=pts[:, d], minlength=n) / counts for d in range(3)])
