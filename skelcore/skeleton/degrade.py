"""Controlled degradations of a cloud for the paper's study: noise, random / farthest-point
downsampling and voxel-grid averaging (paper, Results: "5% noise", "1024 pts", grid-averaged tree
and cave).

Every function works in the cloud's own units and frame and is repeatable: the random ones take a
``seed`` (an int, or a ``numpy.random.Generator`` to draw from), the voxel grid is deterministic.
Downsamplers return the kept rows' indices too, so a caller can keep the correspondence with the
input.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from ..errors import SkelInputError
from ..geometry import as_points

__all__ = ["add_noise", "random_downsample", "farthest_point_downsample", "voxel_grid_average"]

Seed = int | np.random.Generator | None


def _rng(seed: Seed) -> np.random.Generator:
    return seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)


def _cloud(cloud: object) -> np.ndarray:
    return as_points("cloud", cloud)


def add_noise(
    cloud: np.ndarray,
    ratio: float,
    *,
    model: Literal["reference", "isotropic"] = "reference",
    seed: Seed = None,
) -> np.ndarray:
    """Gaussian noise; row i of the result is row i of the input moved (the correspondence is kept).

    model ``"reference"`` (the paper's toolbox, ``demo/example.m``): every coordinate gets its own
    sigma = ``ratio`` x that coordinate's value, in the input frame, so the noise depends on where the
    origin is (a point at the origin does not move). ``"isotropic"``: one sigma = ``ratio`` x the RMS
    distance of the points to their bounding-box centre, the same for every point and axis (frame
    independent).

    >>> noisy = add_noise(cloud, 0.05, seed=0)          # doctest: +SKIP
    """
    pts = _cloud(cloud)
    if not (np.isfinite(ratio) and ratio >= 0):
        raise SkelInputError(f"noise ratio must be a number >= 0, got {ratio!r}")
    rng = _rng(seed)
    if model == "reference":
        sigma = ratio * pts
    elif model == "isotropic":
        centre = (pts.min(axis=0) + pts.max(axis=0)) / 2.0
        sigma = ratio * float(np.sqrt(np.mean(np.sum((pts - centre) ** 2, axis=1))))
    else:
        raise ValueError(f"noise model must be 'reference' or 'isotropic', got {model!r}")
    return pts + rng.standard_normal(pts.shape) * sigma


def _check_n(n: int, n_points: int) -> int:
    if isinstance(n, bool) or int(n) != n or n < 1:
        raise SkelInputError(f"number of points to keep must be a positive integer, got {n!r}")
    if n > n_points:
        raise SkelInputError(f"cannot keep {int(n)} points: the cloud has only {n_points}")
    return int(n)


def random_downsample(cloud: np.ndarray, n: int, *, seed: Seed = None) -> tuple[np.ndarray, np.ndarray]:
    """``n`` rows drawn uniformly without replacement; returns (points, indices), indices ascending
    (the input's order is kept)."""
    pts = _cloud(cloud)
    n = _check_n(n, len(pts))
    idx = np.sort(_rng(seed).choice(len(pts), size=n, replace=False))
    return pts[idx], idx


def farthest_point_downsample(cloud: np.ndarray, n: int, *, seed: Seed = None) -> tuple[np.ndarray, np.ndarray]:
    """Greedy farthest-point sampling of ``n`` rows from a seeded random start; returns (points,
    indices) in the order picked. Keeps thin parts that random sampling would thin out."""
    pts = _cloud(cloud)
    n = _check_n(n, len(pts))
    start = int(_rng(seed).integers(len(pts)))
    idx = np.empty(n, np.int64)
    idx[0] = start
    dist = np.linalg.norm(pts - pts[start], axis=1)
    for i in range(1, n):
        nxt = int(np.argmax(dist))  # first of ties: deterministic
        idx[i] = nxt
        np.minimum(dist, np.linalg.norm(pts - pts[nxt], axis=1), out=dist)
    return pts[idx], idx


def voxel_grid_average(cloud: np.ndarray, cell: float) -> tuple[np.ndarray, np.ndarray]:
    """Average the points of each occupied cubic cell; returns (centroids, voxel of each input row).

    The grid is anchored at the bounding box's minimum corner: a point's cell is
    ``floor((x - min) / cell)`` per axis (MATLAB ``pcdownsample(..., "gridAverage", cell)``). A
    quotient within 1e-9 of a whole number is taken as that number, so a coordinate that lies on a
    cell boundary in decimal (0.06 / 0.02) is not pushed into the cell below by binary rounding.
    Output rows are in MATLAB's order: by linear cell index with x fastest (z, then y, then x), so
    order-dependent skeletonizers (the toolbox's sampling, ours) see the paper's input. On the
    paper's apple tree (22367 points) cells of 0.02 and 0.05 give 8936 and 1730 points.
    """
    pts = _cloud(cloud)
    if not (np.isfinite(cell) and cell > 0):
        raise SkelInputError(f"grid cell size must be a number > 0, got {cell!r}")
    q = (pts - pts.min(axis=0)) / float(cell)
    near = np.round(q)
    q = np.where(np.abs(q - near) < 1e-9, near, q)
    ijk = np.floor(q).astype(np.int64)
    # unique rows of (k, j, i): sorted with i (x) fastest, the linear-index order of MATLAB's grid
    _, voxel, counts = np.unique(ijk[:, ::-1], axis=0, return_inverse=True, return_counts=True)
    voxel = voxel.ravel()
    sums = np.zeros((len(counts), 3))
    np.add.at(sums, voxel, pts)
    return sums / counts[:, None], voxel
