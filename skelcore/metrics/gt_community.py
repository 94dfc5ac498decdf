"""The ground-truth metrics other communities publish, beside those of :mod:`.ground_truth`
(docs/metrics.md 5.3.2 defines each one exactly).

- P / R / F1 at absolute thresholds, 1, 2 and 5 % of the reference's bounding-box diagonal, and the
  Chamfer distance over that diagonal (the units of DiffTS and PyNeval tables);
- branch-level P / R / F1 (a branch is found when more than 80 % of its length is covered), a
  duplicate-aware precision, Betti-0 / Betti-1 errors and the radius error on matched points (the
  vessel and airway benchmarks' metrics);
- ESA / DSA / PDS, the spatial distances of Vaa3D's neuron comparison (Peng et al.);
- path-level (root-to-leaf) P / R / F1 (swclib's fibre metric, one-to-one matching).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_matrix, csr_matrix
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from ..correspondence import project_onto_curve
from ..curve import CurveSkeleton
from ..errors import SkelInputError
from ..params import Params
from .ground_truth import _MAX_SAMPLES, _at_projection, _edges_only, branch_labels, curve_samples
from .reference import graph_counts

__all__ = ["CommunityParams", "community_metrics", "root_to_leaf_paths", "DIAG_KEYS"]


def _diag_thresholds(text: str) -> tuple[float, ...]:
    try:
        out = tuple(float(x) for x in str(text).replace(",", " ").split())
    except ValueError:
        raise ValueError(f"gt_diag_thresholds={text!r}: expected shares of the diagonal, e.g. '0.01 0.02 0.05'") from None
    if not out or not all(0 < t for t in out):
        raise ValueError(f"gt_diag_thresholds={text!r}: every share must be > 0")
    return out


@dataclass(frozen=True)
class CommunityParams:
    """The constants of docs/metrics.md 5.3.2, from :class:`skelcore.Params` (``gt_`` fields)."""

    diag_thresholds: tuple[float, ...] = _diag_thresholds(Params.gt_diag_thresholds)
    cover_share: float = Params.gt_cover_share
    substantial: float = Params.gt_substantial
    tolerance: float = Params.gt_threshold_max
    sample_step: float = Params.gt_sample_step

    @classmethod
    def from_params(cls, params: Params) -> "CommunityParams":
        """The ``gt_`` fields of a :class:`skelcore.Params`."""
        return cls(_diag_thresholds(params.gt_diag_thresholds), float(params.gt_cover_share),
                   float(params.gt_substantial), float(params.gt_threshold_max), float(params.gt_sample_step))


def _pct(t: float) -> str:
    return f"{100 * t:g}".replace(".", "p")


#: the keys of the absolute-threshold metrics at the default thresholds (1, 2, 5 % of the diagonal)
DIAG_KEYS = tuple(f"diag_{m}_{_pct(t)}" for t in CommunityParams().diag_thresholds for m in ("precision", "recall", "f1"))


def _f1(p: float, r: float) -> float:
    if np.isnan(p) or np.isnan(r):
        return float("nan")
    return 2 * p * r / (p + r) if p + r > 0 else 0.0


def _wmean(x: np.ndarray, w: np.ndarray) -> float:
    return float(np.sum(x * w) / np.sum(w)) if np.sum(w) > 0 else float("nan")


def root_to_leaf_paths(curve: CurveSkeleton, root: int) -> list[np.ndarray]:
    """Edge indices of the shortest path (by length) from ``root`` to every vertex of degree 1 but
    the root reachable from it, leaves in vertex order (a tree's root-to-leaf paths)."""
    n, e = curve.n_vertices, curve.edges
    if len(e) == 0:
        return []
    w = np.maximum(curve.edge_lengths(), 1e-300)
    g = csr_matrix(coo_matrix((np.r_[w, w], (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])), shape=(n, n)))
    dist, pred = dijkstra(g, indices=int(root), return_predecessors=True)
    edge_of = {(int(a), int(b)): i for i, (a, b) in enumerate(e)}
    edge_of.update({(int(b), int(a)): i for i, (a, b) in enumerate(e)})
    paths = []
    for leaf in np.flatnonzero(curve.degrees() == 1):
        if leaf == root or not np.isfinite(dist[leaf]):
            continue
        out, v = [], int(leaf)
        while v != root:
            u = int(pred[v])
            out.append(edge_of[(u, v)])
            v = u
        paths.append(np.array(out[::-1], dtype=np.int64))
    return paths


def _membership(paths: list[np.ndarray], n_edges: int) -> csr_matrix:
    rows = np.repeat(np.arange(len(paths)), [len(p) for p in paths])
    cols = np.concatenate(paths) if paths else np.empty(0, np.int64)
    return csr_matrix((np.ones(len(cols)), (rows, cols)), shape=(len(paths), n_edges))


def _overlap(a_pts, a_w, a_edge, a_reach, a_paths, b_pts, b_edge, b_paths, n_a_edges, n_b_edges) -> np.ndarray:
    """Length of each path of A (rows) lying near each path of B (columns): a sample of A is covered
    by B's path Q when its nearest sample of B lies within its reach and on an edge of Q."""
    d, j = cKDTree(b_pts).query(a_pts, k=1)
    ok = d <= a_reach * (1 + 1e-9)
    w = csr_matrix((a_w[ok], (a_edge[ok], b_edge[j[ok]])), shape=(n_a_edges, n_b_edges))
    return np.asarray((_membership(a_paths, n_a_edges) @ w @ _membership(b_paths, n_b_edges).T).todense())


def _path_scores(curve, reference, root_point, ours, ref, share) -> tuple[float, float, float, int, int]:
    our_pts, our_w, our_edge, our_reach = ours
    ref_pts, ref_w, ref_edge, ref_reach = ref
    root_r = int(cKDTree(reference.vertices).query(root_point)[1])
    p_ref = root_to_leaf_paths(reference, root_r)
    if not p_ref:
        return float("nan"), float("nan"), float("nan"), 0, 0
    if curve.n_edges == 0:
        return float("nan"), 0.0, 0.0, 0, len(p_ref)
    used = np.unique(curve.edges)
    root_o = int(used[cKDTree(curve.vertices[used]).query(root_point)[1]])
    p_our = root_to_leaf_paths(curve, root_o)
    if not p_our:
        return float("nan"), 0.0, 0.0, 0, len(p_ref)
    len_ref = _membership(p_ref, reference.n_edges) @ np.bincount(ref_edge, ref_w, reference.n_edges)
    len_our = _membership(p_our, curve.n_edges) @ np.bincount(our_edge, our_w, curve.n_edges)
    c_ref = _overlap(ref_pts, ref_w, ref_edge, ref_reach, p_ref, our_pts, our_edge, p_our,
                     reference.n_edges, curve.n_edges) / len_ref[:, None]
    c_our = _overlap(our_pts, our_w, our_edge, our_reach, p_our, ref_pts, ref_edge, p_ref,
                     curve.n_edges, reference.n_edges) / len_our[:, None]
    score = np.minimum(c_ref, c_our.T)
    rows, cols = linear_sum_assignment(-score)
    tp = int(np.count_nonzero(score[rows, cols] > share))
    p, r = tp / len(p_our), tp / len(p_ref)
    return p, r, _f1(p, r), len(p_our), len(p_ref)


def community_metrics(curve: CurveSkeleton, reference: CurveSkeleton, reference_radius: np.ndarray, *,
                      curve_radius: np.ndarray | None = None, root: int = 0,
                      params: CommunityParams | None = None) -> dict[str, float]:
    """Score ``curve`` against ``reference`` (same frame) with the metrics of docs/metrics.md 5.3.2;
    ``reference_radius`` per reference vertex, ``curve_radius`` per vertex of ours (else the curve's
    own; without one the radius error is NaN), ``root`` the reference vertex paths start from."""
    p = params or CommunityParams()
    if reference.n_edges == 0:
        raise SkelInputError("the reference curve has no edges")
    radius = np.asarray(reference_radius, float).ravel()
    if radius.shape != (reference.n_vertices,) or not np.all(np.isfinite(radius) & (radius > 0)):
        raise SkelInputError("reference radius must be finite and > 0, one per reference vertex")
    root_point = reference.vertices[int(root)]
    diag = float(np.linalg.norm(np.ptp(reference.vertices, axis=0)))
    radius = radius[np.unique(reference.edges)]
    reference = _edges_only(reference)
    own = curve.radius if curve_radius is None else np.asarray(curve_radius, float).ravel()

    total = (float(curve.edge_lengths().sum()) if curve.n_edges else 0.0) + float(reference.edge_lengths().sum())
    step = max(p.sample_step * float(radius.min()), total / _MAX_SAMPLES)
    ref_pts, ref_w, ref_edge, ref_r = curve_samples(reference, step, radius)
    our_pts, our_w, our_edge, our_own_r = curve_samples(curve, step, own)
    q, qe = project_onto_curve(our_pts, reference)
    d_ours = np.linalg.norm(q - our_pts, axis=1)
    r_ours = _at_projection(reference, radius, q, qe)
    d_ref = np.linalg.norm(project_onto_curve(ref_pts, _edges_only(curve))[0] - ref_pts, axis=1)
    out: dict[str, float] = {}

    for t in p.diag_thresholds:  # absolute thresholds, shares of the diagonal
        pr, rc = _wmean(d_ours <= t * diag, our_w), _wmean(d_ref <= t * diag, ref_w)
        out.update({f"diag_precision_{_pct(t)}": pr, f"diag_recall_{_pct(t)}": rc, f"diag_f1_{_pct(t)}": _f1(pr, rc)})
    esa_o, esa_r = _wmean(d_ours, our_w), _wmean(d_ref, ref_w)
    out["chamfer_diag"] = out["esa"] = (esa_o + esa_r) / 2 / diag
    s = p.substantial * diag
    far_o, far_r = d_ours > s, d_ref > s
    dsa = [_wmean(d[f], w[f]) if f.any() else 0.0 for d, w, f in ((d_ours, our_w, far_o), (d_ref, ref_w, far_r))]
    out["dsa"] = (dsa[0] + dsa[1]) / 2 / diag
    out["pds"] = float((our_w[far_o].sum() + ref_w[far_r].sum()) / (our_w.sum() + ref_w.sum()))

    near_o, near_r = d_ours <= p.tolerance * r_ours * (1 + 1e-9), d_ref <= p.tolerance * ref_r * (1 + 1e-9)
    lab_r, n_r = branch_labels(reference)
    len_b = np.bincount(lab_r[ref_edge], ref_w, n_r)
    found = np.bincount(lab_r[ref_edge], ref_w * near_r, n_r) > p.cover_share * len_b
    out["branch_recall"] = float(found.mean())
    if curve.n_edges:
        lab_o, n_o = branch_labels(curve)
        len_c = np.bincount(lab_o[our_edge], our_w, n_o)
        kept = np.bincount(lab_o[our_edge], our_w * near_o, n_o) > p.cover_share * len_c
        out["branch_precision"] = float(kept.mean())
        # duplicate-aware: a reference branch vouches for at most its length plus the tolerance at both ends
        mean_r = np.bincount(lab_r[ref_edge], ref_w * ref_r, n_r) / len_b
        mapped = np.bincount(lab_r[qe[near_o]], our_w[near_o], n_r)
        out["dup_precision"] = float(np.minimum(mapped, len_b + 2 * p.tolerance * mean_r).sum() / our_w.sum())
    else:
        out["branch_precision"] = out["dup_precision"] = float("nan")
    out["branch_f1"] = _f1(out["branch_precision"], out["branch_recall"]) if curve.n_edges else 0.0

    g_o, g_r = graph_counts(curve), graph_counts(reference)
    out["betti0_error"] = float(g_o["components"] - g_r["components"])
    out["betti1_error"] = float(g_o["cycles"] - g_r["cycles"])
    if our_own_r is not None and near_o.any() and np.isfinite(our_own_r[near_o]).any():
        ok = near_o & np.isfinite(our_own_r)
        out["radius_error"] = _wmean(np.abs(our_own_r[ok] - r_ours[ok]) / r_ours[ok], our_w[ok])
    else:
        out["radius_error"] = float("nan")

    pp, pr_, pf, n_po, n_pr = _path_scores(
        curve, reference, root_point, (our_pts, our_w, our_edge, p.tolerance * r_ours),
        (ref_pts, ref_w, ref_edge, p.tolerance * ref_r), p.cover_share)
    out.update({"path_precision": pp, "path_recall": pr_, "path_f1": pf, "paths": float(n_po),
                "paths_reference": float(n_pr)})
    return out
