"""The inputs a repair refuses, each in one line (docs/repair.md "Refused inputs"): a curve without
edges, a curve of more components than ``Params.repair_max_components``, and a skeleton in another
frame than the cloud (the ``frame`` warning, with its suggestion)."""

from __future__ import annotations

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from ..evaluation import Evaluation
from ..params import Params
from .proposals import component_labels

__all__ = ["check_curve", "check_frame"]


def check_curve(curve: CurveSkeleton, params: Params) -> None:
    """Refuse a curve the repair cannot work on, before any evaluation."""
    if curve.n_edges == 0:
        raise SkelInputError("the curve skeleton has no edges: nothing to repair")
    n, _labels = component_labels(curve)
    if n > params.repair_max_components:
        raise SkelInputError(f"the curve has {n} components, more than repair_max_components="
                             f"{params.repair_max_components}: skeletonize again rather than repair")


def check_frame(ev: Evaluation) -> None:
    """Refuse a skeleton the trust checks find in another frame (the warning says what to do)."""
    for w in ev.warnings:
        if w.code == "frame":
            raise SkelInputError(f"refusing to repair: {w.message}")
