"""A manifest shape's ``reference`` (its ground-truth curve skeleton), checked when the manifest
is, so that a wrong file costs one line before any job runs: the file exists and reads as a curve, it
has edges, it lies in the cloud's frame and units (its bounding box against the cloud's, as the
``frame`` trust check measures them, docs/metrics.md), and it has no cycle when the shape is declared
a tree (``tree = true``).
"""

from __future__ import annotations

import os

import numpy as np

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from ..metrics.reference import graph_counts
from ..params import Params
from ..diagnostics.trust import robust_box

__all__ = ["expand_reference", "reference_problem", "load_reference"]


def expand_reference(template: str, stem: str, base: str | os.PathLike) -> str:
    """The reference file of shape ``stem``: ``{stem}`` replaced, relative to the manifest's folder."""
    path = template.replace("{stem}", stem)
    return path if os.path.isabs(path) else os.path.join(os.fspath(base), path)


def load_reference(path: str) -> CurveSkeleton:
    """The reference curve with its radius when the file has one (:func:`skelcore.io.load_curve`)."""
    from ..io import load_curve

    return load_curve(path)


def reference_problem(path: str, cloud_path: str, *, tree: bool = False, params: Params = Params(),
                      shown: str | None = None) -> str | None:
    """What is wrong with ``path`` as the reference of the cloud at ``cloud_path`` (one line naming it
    as ``shown``), or None. The frame test: fewer than ``frame_inside_fraction`` of its vertices in the
    cloud's robust bounding box grown by 10 % of its diagonal, or a bounding-box diagonal more than
    ``frame_extent_ratio`` times larger or smaller than the cloud's."""
    from ..io import load_cloud

    shown = shown or path
    if not os.path.isfile(path):
        return f"reference {shown} not found"
    try:
        ref = load_reference(path)
    except SkelInputError as exc:
        text = str(exc)
        if exc.path and text.startswith(f"{exc.path}: "):
            text = text[len(exc.path) + 2:]  # named once, as the manifest wrote it
        return f"reference {shown}: {text}"
    if ref.n_edges == 0:
        return f"reference {shown} is empty: it has no edges (a curve skeleton is needed)"
    if tree:
        cycles = graph_counts(ref)["cycles"]
        if cycles:
            return f"reference {shown} has {cycles} cycle(s) but the shape is declared a tree (tree = true)"
    try:
        cloud = load_cloud(cloud_path)
    except SkelInputError:
        return None  # the job reports the cloud's own problem
    why = _frame_problem(cloud, ref.vertices[np.unique(ref.edges)], params)
    if why:
        return f"reference {shown} is not in the cloud's frame and units: {why}"
    return None


def _frame_problem(cloud: np.ndarray, points: np.ndarray, params: Params) -> str:
    q = float(params.trust_extent_quantile)
    lo, hi = robust_box(cloud, q)
    d_cloud = float(np.linalg.norm(hi - lo))
    margin = 0.1 * d_cloud
    inside = float(np.all((points >= lo - margin) & (points <= hi + margin), axis=1).mean())
    d_ref = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    ratio = d_ref / d_cloud if d_cloud > 0 else np.inf
    why = []
    if inside < params.frame_inside_fraction:
        why.append(f"only {inside:.0%} of its vertices lie inside the cloud's bounding box")
    if ratio > params.frame_extent_ratio or ratio < 1.0 / params.frame_extent_ratio:
        why.append(f"its extent is {ratio:.3g} x the cloud's")
    return "; ".join(why)
