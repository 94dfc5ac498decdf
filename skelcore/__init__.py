"""skelcore: the SkelScope metric engine (topological similarity, boundedness, centeredness,
smoothness of point-cloud skeletons; docs/metrics.md). Never imports Qt or VTK.

``evaluate``, ``Evaluation``, ``shapes``, ``skeletonize`` and the loaders are imported on first use:
the viewer reads a cloud and draws its first frame without scipy's KD-trees and the metric modules.
"""

from __future__ import annotations

from .version import __version__

from .curve import CurveSkeleton
from .errors import Cancelled, SkelInputError
from .params import Params

__all__ = [
    "__version__",
    "CurveSkeleton",
    "Cancelled",
    "SkelInputError",
    "Params",
    "Evaluation",
    "Scores",
    "evaluate",
    "shapes",
    "load_cloud",
    "load_points",
    "load_curve",
    "load_any",
    "skeletonize",
    "show_ab",
    "repair",
    "RepairResult",
]

_LAZY = {"evaluate": ".stages", "Evaluation": ".evaluation", "Scores": ".scores", "shapes": ".shapes", "skeletonize": ".skeleton",
         "show_ab": ".display", "repair": ".skeleton_repair", "RepairResult": ".skeleton_repair",
         **dict.fromkeys(("load_cloud", "load_points", "load_curve", "load_any", "write_points_ply",
                          "write_curve_ply"), ".io")}


def __getattr__(name: str):
    if name not in _LAZY:
        raise AttributeError(f"module 'skelcore' has no attribute {name!r}")
    import importlib

    module = importlib.import_module(_LAZY[name], __name__)
    return module if name == "shapes" else getattr(module, name)

