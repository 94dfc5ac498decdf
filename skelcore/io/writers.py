"""Plain writers of point sets (XYZ text, NPY); PLY writers live in :mod:`.ply`. All atomic, and
never over a loaded input (:mod:`.atomic`)."""

from __future__ import annotations

import os
from typing import Iterable

import numpy as np

from .atomic import atomic_open

__all__ = ["write_points_xyz", "write_points_npy"]


def write_points_xyz(
    path: str | os.PathLike, points: np.ndarray, *, inputs: Iterable[str | os.PathLike] = ()
) -> None:
    """``x y z`` per line, full double precision (round-trips exactly)."""
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"points must be N x 3, got shape {pts.shape}")
    with atomic_open(path, "w", inputs=inputs) as fh:
        np.savetxt(fh, pts, fmt="%.17g")


def write_points_npy(
    path: str | os.PathLike, points: np.ndarray, *, inputs: Iterable[str | os.PathLike] = ()
) -> None:
    """(N, 3) float64 ``.npy``."""
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"points must be N x 3, got shape {pts.shape}")
    with atomic_open(path, "wb", inputs=inputs) as fh:
        np.save(fh, pts, allow_pickle=False)
