"""Smoothness of a skeletal point set (PCA tangents) and of a curve skeleton (vertex angles), docs/metrics.md 4.

Paper Sec. 2.4: tangents by Prop. 3 (unnumbered covariance), the angle measure D_n of Eq. 13, local
scores Eq. 14 (skeletal points) and Eq. 15 (curve vertices), overall scores Eq. 16 (mean, taken in
:mod:`skelcore.evaluation`) and Eq. 17 (length-weighted, ``curve_smoothness_overall``).  Direction
changes matter for paths and grasps planned along a skeleton.  Both local scores are |1 - 2 theta / pi|
with theta the angle between two directions, so they do not depend on the sign of a tangent:
1 = same line, 0 = perpendicular.  Departures from the paper: docs/metrics.md.
"""

from __future__ import annotations

import math
import os

import numpy as np

from ..curve import CurveSkeleton
from ..geometry import Checkpoint, kd_tree, leaf_order, no_checkpoint, take_rows, unique_rows, unit_rows
from ..parallel import on_threads
from ..params import Params
from .position_knn import position_neighbours

__all__ = ["skeletal_smoothness", "curve_vertex_smoothness", "curve_smoothness_overall"]

_CHUNK = 8192  # distinct positions per block between checkpoints


def _angle_score(cos: np.ndarray) -> np.ndarray:
    """|1 - 2 theta / pi| with theta = arccos(cos); NaN stays NaN."""
    with np.errstate(invalid="ignore"):
        theta = np.arccos(np.clip(cos, -1.0, 1.0))
    return np.abs(1.0 - 2.0 * theta / np.pi)


def _taken(counts_in_order: np.ndarray, k: int) -> np.ndarray:
    """How many of each neighbour position's coincident points fall among the k nearest points."""
    before = np.cumsum(counts_in_order, axis=1) - counts_in_order
    return np.clip(k - before, 0, counts_in_order)


def skeletal_smoothness(
    skeletal: np.ndarray,
    *,
    params: Params = Params(),
    checkpoint: Checkpoint = no_checkpoint,
) -> np.ndarray:
    """Local smoothness s_i of every skeletal point (docs/metrics.md 4); NaN where it cannot be computed.

    Tangent at q_i: eigenvector of the largest eigenvalue of C_i = (1/k) sum (q_j - q_i)(q_j - q_i)^T
    over its k = ``tangent_k`` nearest neighbours, excluding q_i itself and every point at q_i's exact
    position (contraction makes many coincide); centred on q_i as in the paper. s_i = min over its
    ``smooth_k`` nearest neighbours (same exclusion; NaN tangents skipped) of |1 - 2 theta_ij / pi|.

    Coincident points are counted with their multiplicity (they are separate points of the set) but
    share one position, so the work is done once per distinct position. With fewer than k other
    points, all of them are used. A zero C_i (no other position exists) gives NaN.
    """
    pts = np.asarray(skeletal, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"expected an (n, 3) array of points, got shape {pts.shape}")
    n = len(pts)
    out = np.full(n, np.nan)
    if n == 0:
        return out
    checkpoint(0.0)
    uniq, inverse, counts = unique_rows(pts, checkpoint)
    m = len(uniq)
    if m < 2:
        return out  # every C_i is zero: no direction anywhere
    kt, ks = int(params.tangent_k), int(params.smooth_k)
    # each distinct neighbour position holds >= 1 point, so max(kt, ks) positions always suffice
    q = min(m - 1, max(kt, ks))
    checkpoint(0.02)
    # the tree, and the answers skeletal centeredness has found, shared with it (docs/performance.md 6.4)
    shared = position_neighbours(uniq)
    if shared is None:
        tree = kd_tree(uniq, checkpoint, 0.02)
        visit = leaf_order(tree)  # blocks of spatial neighbours: cache-warm queries and gathers
    else:
        tree, visit = shared.tree(uniq, checkpoint, 0.02)
    checkpoint(0.05)
    tangents = np.full((m, 3), np.nan)
    nbr = np.empty((m, q), np.int64)
    spans = [(start, min(m, start + _CHUNK)) for start in range(0, m, _CHUNK)]
    threads = (os.cpu_count() or 1) if len(spans) > 1 else 1
    workers = 1  # chunks on every core, each query on one (docs/performance.md 6.3); the stages run side by side (6.2)

    def tangent_span(start: int, stop: int) -> None:
        rows = visit[start:stop]
        idx = _neighbours(rows, q + 1)[:, 1:]  # column 0 is the position itself
        nbr[rows] = idx
        weight = _taken(counts[idx], kt).astype(float)
        diff = take_rows(uniq, idx) - take_rows(uniq, rows)[:, None, :]
        cov = np.matmul((diff * weight[:, :, None]).transpose(0, 2, 1), diff) / kt
        _, vecs = np.linalg.eigh(cov)
        t = vecs[:, :, -1]  # eigh sorts eigenvalues ascending
        t[~np.any(cov.reshape(len(cov), -1) != 0, axis=1)] = np.nan
        tangents[rows] = t

    def _neighbours(rows: np.ndarray, k: int) -> np.ndarray:
        """The k nearest positions of ``rows``: published by centeredness where its answer fixes them,
        else asked here (the same answers: :mod:`.position_knn`)."""
        if shared is None:
            return tree.query(take_rows(uniq, rows), k=k, workers=workers)[1].reshape(len(rows), k)
        ready, found = shared.reuse(rows, k)
        idx = np.empty((len(rows), k), np.int64)
        idx[ready] = found
        if not ready.all():
            ask = ~ready
            idx[ask] = tree.query(take_rows(uniq, rows[ask]), k=k, workers=workers)[1].reshape(-1, k)
        return idx

    # with a shared index, from the end of the leaf order: centeredness answers from its start, so a
    # stage beside it meets its answers (docs/performance.md 6.4)
    on_threads(tangent_span, spans if shared is None else spans[::-1], threads,
               lambda f: checkpoint(0.05 + 0.75 * f))
    if shared is not None:
        shared.close()
    s_unique = np.empty(m)

    def score_span(start: int, stop: int) -> None:
        rows = visit[start:stop]
        idx = nbr[rows]
        use = _taken(counts[idx], ks) > 0  # neighbour positions holding one of the ks nearest points
        score = _angle_score(np.einsum("na,nja->nj", take_rows(tangents, rows), take_rows(tangents, idx)))
        s_unique[rows] = np.where(use & np.isfinite(score), score, np.inf).min(axis=1)

    on_threads(score_span, spans, threads, lambda f: checkpoint(0.8 + 0.2 * f))
    s_unique[np.isinf(s_unique)] = np.nan  # no neighbour with a tangent, or no tangent here
    return s_unique[inverse]


def _degree2_neighbours(curve: CurveSkeleton) -> tuple[np.ndarray, np.ndarray]:
    """Indices of degree-2 vertices and their two neighbours, shape (m,) and (m, 2)."""
    e = np.asarray(curve.edges, dtype=np.int64).reshape(-1, 2)
    deg = curve.degrees()
    ends = np.concatenate([e[:, 0], e[:, 1]])
    others = np.concatenate([e[:, 1], e[:, 0]])
    order = np.argsort(ends, kind="stable")
    ends, others = ends[order], others[order]
    first = np.searchsorted(ends, np.arange(curve.n_vertices))
    v = np.flatnonzero(deg == 2)
    return v, np.column_stack([others[first[v]], others[first[v] + 1]])


def curve_vertex_smoothness(curve: CurveSkeleton) -> np.ndarray:
    """s_v = |1 - 2 theta / pi| at each degree-2 vertex v with neighbours a, b, theta the angle
    between a - v and b - v (docs/metrics.md 4): straight = 1, right angle = 0. Other degrees: NaN (no value,
    drawn magenta), as is a degree-2 vertex coinciding with a neighbour (no angle).

    Quirk kept from the paper's formula (docs/metrics.md 4): a full hairpin (theta = 0, the path folds back on
    itself) also scores 1, exactly like a straight line.
    """
    s = np.full(curve.n_vertices, np.nan)
    v, ab = _degree2_neighbours(curve)
    if len(v):
        x = curve.vertices
        da = unit_rows(x[ab[:, 0]] - x[v])
        db = unit_rows(x[ab[:, 1]] - x[v])
        s[v] = _angle_score(np.sum(da * db, axis=1))
    return s


def curve_smoothness_overall(curve: CurveSkeleton, s: np.ndarray) -> tuple[float, int]:
    """Length-weighted overall smoothness (docs/metrics.md 4) and the number of vertices it counted.

    S = 1 - sum over degree-2 vertices of w_v (1 - s_v) / sum over all vertices of w_v, w_v = half
    the total length of the edges at v (so the denominator is the total edge length; vertices of
    other degrees count as perfectly smooth, as in the paper). The count is the number of degree-2
    vertices with a finite s_v (a NaN s_v, from a zero-length edge, is left out of the numerator).
    No edges or zero total length: (NaN, 0).
    """
    s = np.asarray(s, dtype=float)
    if s.shape != (curve.n_vertices,):
        raise ValueError(f"expected one smoothness value per vertex ({curve.n_vertices}), got shape {s.shape}")
    lengths = curve.edge_lengths()
    total = float(lengths.sum())
    if curve.n_edges == 0 or not total > 0:
        return math.nan, 0
    w = 0.5 * np.bincount(curve.edges.ravel(), weights=np.repeat(lengths, 2), minlength=curve.n_vertices)
    counted = (curve.degrees() == 2) & np.isfinite(s)
    score = 1.0 - float(np.sum(w[counted] * (1.0 - s[counted]))) / float(w.sum())
    return score, int(counted.sum())
