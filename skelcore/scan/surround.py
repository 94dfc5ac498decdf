"""Which grid points a rim surrounds: the fill test of an opening (docs/metrics.md 6.1, "openings").

A point is surrounded when the largest angle between consecutive directions from it to the rim's
samples is below ``angle`` (:func:`.boundary.largest_angle_gap` in the rim's plane).  The compiled first
pass (``skelcore/metrics/_surround.c``) bins the directions by an approximate angle and decides every
point whose largest gap is clear of ``angle`` by more than the bins' width; the exact test runs only on
the few it leaves undecided, so the answers are those of the exact test everywhere
(docs/performance.md, "The openings' surround test").
"""

from __future__ import annotations

import numpy as np

from ..metrics import _surround
from .boundary import largest_angle_gap

__all__ = ["surrounded", "surrounded_exact"]

#: grid points per batch of the exact test (512 rim samples: about 25 MB of temporaries)
CHUNK = 2048


def surrounded_exact(ring: np.ndarray, grid: np.ndarray, angle: float) -> np.ndarray:
    """(len(grid),) bool: the largest angle gap of the directions from each grid point to the rim
    samples ``ring`` (both (n, 2), in the rim's plane) is below ``angle`` (radians); every angle computed."""
    ring3 = np.column_stack([ring, np.zeros(len(ring))])
    plane = np.eye(3)[None]
    inside = np.zeros(len(grid), bool)
    for i0 in range(0, len(grid), CHUNK):
        g = np.column_stack([grid[i0:i0 + CHUNK], np.zeros(min(CHUNK, len(grid) - i0))])
        vec = ring3[None, :, :] - g[:, None, :]
        inside[i0:i0 + CHUNK] = largest_angle_gap(vec, np.repeat(plane, len(g), axis=0)) < angle
    return inside


def surrounded(ring: np.ndarray, grid: np.ndarray, angle: float) -> np.ndarray:
    """:func:`surrounded_exact`'s answers: the compiled first pass, then the exact test where it is
    undecided."""
    ring = np.ascontiguousarray(ring, dtype=np.float64)
    grid = np.ascontiguousarray(grid, dtype=np.float64)
    state = np.empty(len(grid), np.int8)
    _surround.surround(ring, grid, float(angle), state)
    inside = state == 1
    ask = np.flatnonzero(state < 0)
    if len(ask):
        inside[ask] = surrounded_exact(ring, grid[ask], angle)
    return inside
