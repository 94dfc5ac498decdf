"""The curve missing parts stage of an edit's update: the stage's own call
(:mod:`skelcore.stages.catalogue`), with the KD-tree of the points its regions ask about (the
normalized cloud or its kept subsample) kept from one update of an evaluation to the next, which
lets the regions take most neighbours from one search of it (the same bits; docs/performance.md 6.10)."""

from __future__ import annotations

import threading
from typing import Any, Callable

import numpy as np
from scipy.spatial import cKDTree

from ..diagnostics.missing_parts import MissingParts, missing_parts
from ..geometry import Checkpoint, no_checkpoint

__all__ = ["curve_missing_parts"]

#: skelcore.stages.context.EvalContext, not imported: the edits sit below the stages
EvalContext = Any
_LOCK = threading.Lock()
_KEY = "missing parts' cloud tree"


def _cloud_tree(cache: dict[str, Any]) -> Callable[[np.ndarray], cKDTree]:
    """``cKDTree(points)``, kept in ``cache`` with those points: every update of one evaluation asks about
    the same array (its normalized cloud, or above ``missing_max_points`` the subsample that
    :func:`skelcore.metrics.cloud_index.kept_index` keeps); another array replaces it."""

    def get(points: np.ndarray) -> cKDTree:
        # the same memory, shape and strides (missing_parts asks through a new view of the same array);
        # the view kept holds that memory, so no other array can take its place
        key = (points.__array_interface__["data"][0], points.shape, points.strides, points.dtype.str)
        with _LOCK:
            kept = cache.get(_KEY)
            if kept is None or kept[0] != key:
                kept = (key, cKDTree(points), points)
                cache[_KEY] = kept
        return kept[1]

    return get


def curve_missing_parts(ctx: EvalContext, cache: dict[str, Any],
                        checkpoint: Checkpoint = no_checkpoint) -> MissingParts:
    """The curve missing parts stage's result for ``ctx`` (an edit's update), the cloud's tree kept."""
    cov = ctx.results.get("curve coverage")
    return missing_parts(ctx.cloud_n, ctx.curve_n, ctx.params, cov=cov, tau=None if cov is None else cov.tau,
                         what="curve skeleton", to_user=ctx.norm.invert, inside=ctx.solid_test(),
                         cloud_tree=_cloud_tree(cache), checkpoint=checkpoint)
