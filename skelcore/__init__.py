"""skelcore: the SkelScope metric engine (topological similarity, boundedness, centeredness,
smoothness of point-cloud skeletons; SPEC.md). Never imports Qt or VTK."""

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
    "evaluate",
    "shapes",
    "load_cloud",
    "load_points",
    "load_curve",
    "load_any",
    "skeletonize",
]


def __getattr__(name: str):
    # Loaders on first use, so the CLI's --help stays fast.
    if name in ("load_cloud", "load_points", "load_curve", "load_any", "write_points_ply", "write_curve_ply"):
        from . import io

        return getattr(io, name)
    raise AttributeError(f"module 'skelcore' has no attribute {name!r}")


# Imported eagerly: once imported, the submodule ``skelcore.evaluate``
# would otherwise shadow the function of the same name.
from .evaluate import evaluate  # noqa: E402
from .results import Evaluation  # noqa: E402
from . import shapes  # noqa: E402
from .skeleton import skeletonize  # noqa: E402
