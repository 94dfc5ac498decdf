"""What an adapter returns: the tool's curve skeleton in the cloud's frame and, when the tool maps
the cloud's points to its skeleton, the pointwise skeletal set (one row per cloud row)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..curve import CurveSkeleton

__all__ = ["AdapterResult"]


@dataclass
class AdapterResult:
    """``correspondence`` is what ``evaluate`` is to use: "auto" when ``skeletal`` has one row per
    cloud row (the tool's own map: scored pointwise), "reverse" when the tool maps nothing (each
    cloud point then goes to its nearest point of the curve; docs/metrics.md 5.1). ``info``: sizes
    worth reporting (the voxel adapters: the voxel size used, ``voxel_size_source`` "given",
    "spacing" or "max_voxels", the grid and its solid voxels)."""

    curve: CurveSkeleton
    skeletal: np.ndarray | None = None
    correspondence: str = "reverse"
    info: dict[str, Any] = field(default_factory=dict)
