"""Shared small geometry: the normalization transform, kNN helpers, MATLAB-compatible rounding.

Every metric works in normalized space (SPEC 0); everything written out goes back to user units.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.spatial import cKDTree

Checkpoint = Callable[[float], None]
"""``checkpoint(fraction_done_in_stage)``: reports progress and raises ``Cancelled`` to stop."""


def no_checkpoint(_fraction: float) -> None:
    """Default checkpoint: does nothing."""


def matlab_round(x: float) -> int:
    """Round half away from zero, as MATLAB's ``round`` (Python's ``round`` rounds half to even)."""
    return int(np.sign(x) * np.floor(abs(x) + 0.5))


@dataclass(frozen=True)
class Normalization:
    """``normalized = (x - center) * scale``; built from the cloud's axis-aligned bounding box."""

    center: np.ndarray
    scale: float

    @classmethod
    def from_cloud(cls, cloud: np.ndarray, by: str = "longest_side", size: float = 1.6) -> "Normalization":
        lo = cloud.min(axis=0)
        hi = cloud.max(axis=0)
        extent = hi - lo
        measure = float(np.linalg.norm(extent)) if by == "diagonal" else float(extent.max())
        if not measure > 0:
            raise ValueError("all points coincide: the bounding box has no extent")
        return cls(center=(lo + hi) / 2.0, scale=size / measure)

    def apply(self, points: np.ndarray) -> np.ndarray:
        return (np.asarray(points, dtype=float) - self.center) * self.scale

    def invert(self, points: np.ndarray) -> np.ndarray:
        return np.asarray(points, dtype=float) / self.scale + self.center


def nearest_neighbor_distances(points: np.ndarray, tree: cKDTree | None = None) -> np.ndarray:
    """Distance from each point to its nearest *other* point (0 for duplicates)."""
    points = np.asarray(points, dtype=float)
    if len(points) < 2:
        return np.zeros(len(points))
    tree = cKDTree(points) if tree is None else tree
    dist, _ = tree.query(points, k=2, workers=-1)
    return dist[:, 1]


def knn(points: np.ndarray, queries: np.ndarray, k: int, tree: cKDTree | None = None) -> tuple[np.ndarray, np.ndarray]:
    """k nearest neighbours of each query among ``points`` (query itself included if present).

    Returns (distances, indices), each (len(queries), min(k, len(points))), always 2-D.
    """
    points = np.asarray(points, dtype=float)
    k = int(min(k, len(points)))
    tree = cKDTree(points) if tree is None else tree
    dist, idx = tree.query(np.asarray(queries, dtype=float), k=k, workers=-1)
    if k == 1:
        dist, idx = dist[:, None], idx[:, None]
    return dist, idx


def unique_rows(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(unique points, inverse, counts), comparing values (so -0.0 equals 0.0).

    Contraction stacks many skeletal points at one position; metrics work once per position.
    Faster than ``np.unique(axis=0)``, which compares bytes.
    """
    points = np.asarray(points, dtype=float)
    order = np.lexsort(points.T[::-1])
    srt = points[order]
    new = np.ones(len(srt), bool)
    if len(srt) > 1:
        new[1:] = np.any(srt[1:] != srt[:-1], axis=1)
    group = np.cumsum(new) - 1
    inverse = np.empty(len(points), np.int64)
    inverse[order] = group
    return srt[new], inverse, np.bincount(group, minlength=int(new.sum()))


def as_points(name: str, points: object) -> np.ndarray:
    """Validate user points as a finite, non-empty (N, 3) float array, else a one-line SkelInputError."""
    from .errors import SkelInputError

    try:
        arr = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise SkelInputError(f"{name}: coordinates are not numbers") from None
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise SkelInputError(f"{name}: expected an N x 3 array of points, got shape {arr.shape}")
    if len(arr) == 0:
        raise SkelInputError(f"{name}: no points")
    if not np.all(np.isfinite(arr)):
        raise SkelInputError(f"{name}: coordinates contain NaN or inf")
    return arr


def bbox_diagonal(points: np.ndarray) -> float:
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


def unit_rows(vectors: np.ndarray) -> np.ndarray:
    """Rows scaled to unit length; zero rows become NaN (an undefined direction is invalid)."""
    vectors = np.asarray(vectors, dtype=float)
    norms = np.linalg.norm(vectors, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = vectors / norms
    out[np.broadcast_to(norms == 0, out.shape)] = np.nan
    return out
