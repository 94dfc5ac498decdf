"""A skeleton's map into its cloud's frame: every coordinate ``* scale + offset``.

Other tools write skeletons in their own units or origin (voxel indices, another scale, a shifted
frame). ``skelcore evaluate --skeleton-scale S --skeleton-offset X Y Z`` and a compare manifest's
``files`` method (``scale = S``, ``offset = [X, Y, Z]``) map them back with this one function, so
both apply the same map (docs/skeletonizers.md, docs/compare.md). The cloud is
never mapped: the metrics (docs/metrics.md 1-4) are computed in the cloud's frame.
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from .curve import CurveSkeleton

__all__ = ["check_mapping", "is_identity", "map_skeleton"]


def check_mapping(scale: Any = 1.0, offset: Any = (0.0, 0.0, 0.0)) -> tuple[float, tuple[float, float, float]]:
    """``(scale, offset)`` as floats; ``ValueError`` with one line unless scale is a finite number
    > 0 and offset three finite numbers."""
    if isinstance(scale, bool) or not isinstance(scale, (int, float, np.integer, np.floating)) \
            or not math.isfinite(scale) or scale <= 0:
        raise ValueError(f"scale must be a finite number > 0, got {scale!r}")
    if isinstance(offset, (str, bytes)) or not isinstance(offset, Sequence) and not isinstance(offset, np.ndarray):
        raise ValueError(f"offset must be three numbers [x, y, z], got {offset!r}")
    values = list(offset)
    if len(values) != 3 or any(isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating))
                               or not math.isfinite(v) for v in values):
        raise ValueError(f"offset must be three finite numbers [x, y, z], got {offset!r}")
    return float(scale), (float(values[0]), float(values[1]), float(values[2]))


def is_identity(scale: float = 1.0, offset: Sequence[float] = (0.0, 0.0, 0.0)) -> bool:
    return float(scale) == 1.0 and all(float(v) == 0.0 for v in offset)


def map_skeleton(skeletal: np.ndarray | None, curve: CurveSkeleton | None, scale: float = 1.0,
                 offset: Sequence[float] = (0.0, 0.0, 0.0)) -> tuple[np.ndarray | None, CurveSkeleton | None]:
    """The skeletal points and the curve's vertices mapped by ``v * scale + offset`` (the curve's
    graph unchanged); the inputs themselves when the map is the identity."""
    if is_identity(scale, offset):
        return skeletal, curve
    off = np.asarray(offset, dtype=float)
    if skeletal is not None:
        skeletal = np.asarray(skeletal, dtype=float) * scale + off
    if curve is not None:
        curve = curve.transformed(lambda v: v * scale + off)
    return skeletal, curve
