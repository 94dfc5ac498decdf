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
    "shapes",
    "load_cloud",
    "load_points",
    "load_curve",
    "load_any",
    "skeletonize",
]


def __getattr__(name: str):
    # Lazy where a submodule and a function share a name would clash otherwise (see below).
    if name in ("load_cloud", "load_points", "load_curve", "load_any", "write_points_ply", "write_curve_ply"):
        from . import io

        return getattr(io, name)
    if name == "skeletonize":
        from .skeletonize import skeletonize as fn

        globals()["skeletonize"] = fn  # the submodule import bound the module here; the function wins
        return fn
    raise AttributeError(f"module 'skelcore' has no attribute {name!r}")


# Imported eagerly: the submodule ``skelcore.evaluate`` would otherwise shadow the function.
from .evaluate import evaluate  # noqa: E402
from .results import Evaluation  # noqa: E402
from . import shapes  # noqa: E402
