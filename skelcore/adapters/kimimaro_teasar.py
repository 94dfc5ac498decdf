"""kimimaro's TEASAR skeleton (Sato et al. 2000, as kimimaro implements it) of the cloud's solid.

The cloud is voxelized and filled (:mod:`.voxelize`); kimimaro runs with ``anisotropy = (1, 1, 1)``
so its vertices are voxel indices and its ``scale`` / ``const`` are in voxels (every TEASAR
parameter is passed: a partial ``teasar_params`` leaves ``trace``'s weaker centring penalty); the vertices come
back to the cloud's frame by ``index * voxel_size + origin`` (origin: the centre of voxel 0), the
radii by ``* voxel_size``. kimimaro maps no cloud point to its skeleton, so the skeletal set is the
reverse projection of the cloud onto the curve (docs/metrics.md 5.1).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from .adapter_params import Param
from .adapter_result import AdapterResult
from .voxelize import VOXEL_PARAMS, voxelize_solid

__all__ = ["PARAMS", "skeletonize"]

PARAMS = VOXEL_PARAMS + (
    Param("scale", "float", 1.5, "TEASAR invalidation ball: scale x distance to the boundary + const", minimum=0.0,
          positive=True),
    Param("const", "float", 4.0, "TEASAR invalidation ball's constant, in voxels", minimum=0.0),
    Param("pdrf_scale", "float", 100000.0, "TEASAR's penalty for leaving the centre (kimimaro's default)",
          minimum=0.0, positive=True),
    Param("pdrf_exponent", "int", 4, "exponent of that penalty (kimimaro's default)", minimum=1),
    Param("dust_threshold", "int", 10, "drop connected pieces of fewer voxels", minimum=0),
    Param("fix_branching", "bool", True, "kimimaro's fix_branching (better junctions, slower)"),
)


def skeletonize(points: np.ndarray, params: dict[str, Any]) -> AdapterResult:
    """kimimaro's skeleton of the solid ``points`` bound, with resolved ``params`` (:data:`PARAMS`)."""
    import kimimaro

    grid = voxelize_solid(points, params["voxel_size"], closing=params["closing"], max_voxels=params["max_voxels"])
    skels = kimimaro.skeletonize(
        np.asfortranarray(grid.solid.astype(np.uint32)),
        teasar_params={k: params[k] for k in ("scale", "const", "pdrf_scale", "pdrf_exponent")},
        anisotropy=(1, 1, 1), dust_threshold=params["dust_threshold"], fix_branching=params["fix_branching"],
        progress=False, parallel=1)
    sk = skels.get(1)
    if sk is None or len(sk.vertices) == 0:
        raise SkelInputError(f"kimimaro found no skeleton in the {int(grid.solid.sum())}-voxel solid "
                             f"(voxel_size {grid.size:.4g}; lower dust_threshold or voxel_size)")
    radius = np.asarray(sk.radii, dtype=float) * grid.size if getattr(sk, "radii", None) is not None else None
    curve = CurveSkeleton.from_raw(grid.to_cloud_frame(sk.vertices), np.asarray(sk.edges, dtype=np.int64),
                                   radius=radius)
    return AdapterResult(curve, None, "reverse", grid.info())
