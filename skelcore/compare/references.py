"""A manifest shape's ``reference`` (its ground-truth curve skeleton), checked when the manifest
is, so that a wrong file costs one line before any job runs: the file exists and reads as a curve, it
has edges, it lies in the cloud's frame and units (its bounding box against the cloud's, as the
``frame`` trust check measures them, docs/metrics.md), and it has no cycle when the shape is declared
a tree (``tree = true``). Its facts (``reference_facts``: how far each of its vertices lies outside
the surface the cloud was drawn from, a real suite's ``truth/{neuron}_gt_facts.csv``) are checked
against it too: one row per vertex of the reference file.
"""

from __future__ import annotations

import os

import numpy as np

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from ..metrics.reference import graph_counts
from ..params import Params
from ..diagnostics.trust import robust_box

__all__ = ["expand_reference", "reference_problem", "load_reference", "facts_problem", "load_reference_outside"]


def expand_reference(template: str, stem: str, base: str | os.PathLike) -> str:
    """The reference file of shape ``stem``: ``{stem}`` replaced, relative to the manifest's folder."""
    path = template.replace("{stem}", stem)
    return path if os.path.isabs(path) else os.path.join(os.fspath(base), path)


def load_reference(path: str) -> CurveSkeleton:
    """The reference curve with its radius when the file has one (:func:`skelcore.io.load_curve`)."""
    from ..io import load_curve

    return load_curve(path)


def load_reference_outside(path: str, reference: CurveSkeleton) -> np.ndarray:
    """The facts' ``outside_by_radii`` per vertex of the loaded ``reference`` (the file's rows are the
    reference file's vertices; the loaded curve's ``vertex_map`` picks them), as ``evaluate``'s
    ``reference_outside`` takes them (docs/metrics.md 5.3.1). A file of another vertex count, or not a
    facts file, is a one-line SkelInputError naming it."""
    from ..benchmark.neurons import read_outside_radii

    rows = int(np.max(reference.vertex_map)) + 1 if reference.vertex_map is not None else reference.n_vertices
    out = read_outside_radii(path, rows)
    return out if reference.vertex_map is None else out[reference.vertex_map]


def facts_problem(path: str, reference_path: str, *, shown: str | None = None) -> str | None:
    """What is wrong with ``path`` as the facts of the reference at ``reference_path`` (one line naming
    it as ``shown``), or None (the reference's own problems are :func:`reference_problem`'s)."""
    shown = shown or path
    if not os.path.isfile(path):
        return f"reference_facts {shown} not found"
    try:
        load_reference_outside(path, load_reference(reference_path))
    except SkelInputError as exc:
        text = str(exc)
        if exc.path and text.startswith(f"{exc.path}: "):
            text = text[len(exc.path) + 2:]  # named once, as the manifest wrote it
        return f"reference_facts {shown}: {text}"
    return None


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
