"""scikit-image's 3-D thinning (``skimage.morphology.skeletonize``, Lee et al. 1994) of the cloud's
solid, as a curve.

The cloud is voxelized and filled (:mod:`.voxelize`), thinned to one-voxel-thin skeleton voxels,
and those become a graph by their 26-neighbourhood (:mod:`.voxel_graph`); the vertices come back to
the cloud's frame by ``index * voxel_size + origin``. Thinning maps no cloud point, so the skeletal
set is the reverse projection of the cloud onto the curve (docs/metrics.md 5.1).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from .adapter_result import AdapterResult
from .voxel_graph import voxel_edges
from .voxelize import VOXEL_PARAMS, voxelize_solid

__all__ = ["PARAMS", "skeletonize"]

PARAMS = VOXEL_PARAMS


def skeletonize(points: np.ndarray, params: dict[str, Any]) -> AdapterResult:
    """The thinned skeleton of the solid ``points`` bound, with resolved ``params`` (:data:`PARAMS`)."""
    from skimage.morphology import skeletonize as thin

    grid = voxelize_solid(points, params["voxel_size"], closing=params["closing"], max_voxels=params["max_voxels"])
    voxels = np.argwhere(thin(grid.solid))
    if len(voxels) == 0:
        raise SkelInputError(f"scikit-image's thinning left no voxel of the {int(grid.solid.sum())}-voxel solid")
    curve = CurveSkeleton.from_raw(grid.to_cloud_frame(voxels), voxel_edges(voxels))
    return AdapterResult(curve, None, "reverse", grid.info())
