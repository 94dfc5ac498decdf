"""skelcore: the SkelScope metric engine (topological similarity, boundedness, centeredness,
smoothness of point-cloud skeletons; SPEC.md). Never imports Qt or VTK."""

from __future__ import annotations

__version__ = "0.1.0"

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
    "evaluate",
]


def __getattr__(name: str):
    # Lazy, so `import skelcore` stays cheap for the viewer's start-up and the CLI's --help.
    if name == "evaluate":
        from .evaluate import evaluate

        return evaluate
    if name == "Evaluation":
        from .results import Evaluation

        return Evaluation
    if name in ("load_cloud", "load_points", "load_curve", "write_points_ply", "write_curve_ply"):
        from . import io

        return getattr(io, name)
    if name in ("skeletonize",):
        from .skeletonize import skeletonize

        return skeletonize
    if name in ("degrade",):
        from . import degrade

        return degrade
    raise AttributeError(f"module 'skelcore' has no attribute {name!r}")
