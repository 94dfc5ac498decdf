"""Curve length and skeletal points outside the shape -> ``outside`` (issue 22, item 5;
docs/diagnostics.md "Outside").

A curve sample is outside when it is not bounded (boundedness <= beta*, SPEC 2: the values the
evaluation computed). Each sample stands for its share of its edge (len_e / n_e, SPEC 3's sampling),
so the length outside is summed per edge and per branch and measured in local radii (the median
distance from the curve to the cloud): one edge through the air is a defect even when the overall
boundedness is 0.95. For a skeletal point set, the outside points are grouped into clusters (points
within ``outside_link`` x the cloud's median spacing of each other); one large cluster is a part of
the skeleton that left the shape, scattered single points are not.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from ..curve_sampling import CurveSamples
from ..geometry import Checkpoint, kd_tree, no_checkpoint
from ..params import Params
from ..trust import TrustWarning
from .branches import Branches, decompose_branches
from .interior import cloud_subsample, median_spacing

__all__ = ["OutsideDefects", "find_outside"]

# skeletal points clustered at most (a random subsample beyond; the shares are estimated on it)
_MAX_CLUSTERED = 200_000


@dataclass
class OutsideDefects:
    """Where the skeleton leaves the shape.

    sample_outside : (S,) bool per curve sample. edge_outside_length : (E,) length of each edge
    outside; branch_outside_length : (B,). radius : the local radius the lengths are measured in
    (normalized units). depth : (B,) the largest distance from an outside sample of the branch to the
    cloud, in local radii (0 where none). vertex_flag : (V,) bool, vertices on an edge with a sample
    outside. skeletal_outside : (N_s,) bool or None; skeletal_cluster_share : the largest cluster's
    share of the skeletal set.
    """

    branches: Branches | None
    sample_outside: np.ndarray
    edge_outside_length: np.ndarray
    branch_outside_length: np.ndarray
    radius: float
    depth: np.ndarray
    vertex_flag: np.ndarray
    total_length: float
    skeletal_outside: np.ndarray | None = None
    skeletal_cluster_share: float = 0.0
    skeletal_cluster: np.ndarray | None = None
    params: Params = field(default_factory=Params)
    subsampled: int | None = None

    @property
    def length_share(self) -> float:
        return float(self.edge_outside_length.sum()) / self.total_length if self.total_length > 0 else 0.0

    @property
    def branch_radii(self) -> np.ndarray:
        """Length outside per branch in local radii."""
        return self.branch_outside_length / self.radius if self.radius > 0 else np.zeros_like(self.branch_outside_length)

    def defective_branches(self) -> np.ndarray:
        return np.flatnonzero(self.branch_radii >= self.params.outside_min_radii)

    def warnings(self) -> list[TrustWarning]:
        out: list[TrustWarning] = []
        bad = self.defective_branches()
        if len(bad) or (self.total_length > 0 and self.length_share >= self.params.outside_min_share):
            worst = int(np.argmax(self.branch_radii)) if len(self.branch_radii) else -1
            n_edges = int(np.count_nonzero(self.edge_outside_length > 0))
            out.append(TrustWarning(
                "outside",
                f"the curve skeleton leaves the shape on {len(bad)} branches ({n_edges} edges): "
                f"{self.length_share:.1%} of its length, {self.branch_radii.sum():.2g} local radii, the most on "
                f"branch {worst} ({self.branch_radii[worst]:.2g} radii, up to {self.depth[worst]:.2g} radii out)",
            ))  # fmt: skip
        if self.skeletal_outside is not None and self.skeletal_cluster_share > self.params.outside_skeletal_share:
            out.append(TrustWarning(
                "outside",
                f"{self.skeletal_cluster_share:.1%} of the skeletal points lie outside the shape in one cluster "
                f"({float(np.mean(self.skeletal_outside)):.1%} outside in all)",
            ))  # fmt: skip
        return out

    def to_dict(self) -> dict:
        out = {
            "length_share": self.length_share,
            "radius": float(self.radius),
            "branches": [
                {"id": int(b), "length": float(self.branch_outside_length[b]), "radii": float(self.branch_radii[b]),
                 "depth": float(self.depth[b])}
                for b in np.flatnonzero(self.branch_outside_length > 0)
            ],
        }
        if self.skeletal_outside is not None:
            out["skeletal"] = {"share": float(np.mean(self.skeletal_outside)) if len(self.skeletal_outside) else 0.0,
                               "largest_cluster_share": float(self.skeletal_cluster_share),
                               "subsampled": self.subsampled}
        return out


def _skeletal_clusters(points: np.ndarray, outside: np.ndarray, link: float, seed: int) -> tuple[np.ndarray, float, int | None]:
    """Cluster id per skeletal point (-1 inside) and the largest cluster's share of all points."""
    idx = np.flatnonzero(outside)
    cluster = np.full(len(points), -1, dtype=np.int64)
    if len(idx) == 0:
        return cluster, 0.0, None
    sub = None
    if len(idx) > _MAX_CLUSTERED:
        idx = np.sort(np.random.default_rng(seed).choice(idx, _MAX_CLUSTERED, replace=False))
        sub = _MAX_CLUSTERED
    q = points[idx]
    pairs = cKDTree(q).query_pairs(link, output_type="ndarray")
    g = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(q), len(q)))
    _, lab = connected_components(g, directed=False)
    cluster[idx] = lab
    biggest = np.bincount(lab).max()
    scale = np.count_nonzero(outside) / len(idx)  # the subsample's share stands for the whole
    return cluster, float(biggest * scale / len(points)), sub


def find_outside(
    cloud: np.ndarray,
    curve: CurveSkeleton | None,
    *,
    samples: CurveSamples | None = None,
    sample_boundedness: np.ndarray | None = None,
    skeletal: np.ndarray | None = None,
    skeletal_boundedness: np.ndarray | None = None,
    params: Params = Params(),
    branches: Branches | None = None,
    cloud_tree: cKDTree | None = None,
    checkpoint: Checkpoint = no_checkpoint,
    seed: int = 0,
) -> OutsideDefects:
    """The parts of a skeleton outside the shape, from the boundedness of its curve ``samples``
    (``sample_boundedness``, one per sample) and/or of its ``skeletal`` points, against ``beta_star``
    (SPEC 2), all normalized (SPEC 0). ``branches`` and ``cloud_tree`` may be passed when computed."""
    cloud = np.asarray(cloud, dtype=float)
    beta_star = params.beta_star
    if cloud_tree is None and len(cloud):
        cloud_tree = kd_tree(cloud_subsample(cloud, params.diag_max_points, seed))
    sample_edge = None if samples is None else samples.edge
    sample_points = None if samples is None else samples.points
    if curve is not None and branches is None:
        branches = decompose_branches(curve, cloud=cloud, sample_edge=sample_edge, cloud_tree=cloud_tree)
    nb = len(branches) if branches is not None else 0
    ne = curve.n_edges if curve is not None else 0
    edge_len = np.zeros(ne)
    sample_out = np.zeros(0, bool)
    radius = 0.0
    depth = np.zeros(nb)
    vertex_flag = np.zeros(curve.n_vertices if curve is not None else 0, bool)
    if curve is not None and sample_edge is not None and sample_boundedness is not None and ne:
        se = np.asarray(sample_edge, dtype=np.int64)
        beta = np.asarray(sample_boundedness, dtype=float)
        sample_out = ~(beta > beta_star) & np.isfinite(beta)
        n_e = np.bincount(se, minlength=ne).astype(float)
        share = curve.edge_lengths()[se] / np.maximum(n_e[se], 1.0)
        edge_len = np.bincount(se, weights=share * sample_out, minlength=ne)
        radius = float(np.nanmedian(branches.radius_median)) if np.any(np.isfinite(branches.radius_median)) else 0.0
        if sample_points is not None and cloud_tree is not None and sample_out.any() and radius > 0:
            d, _ = cloud_tree.query(np.asarray(sample_points, float)[sample_out])
            sb = branches.edge_branch[se[sample_out]]
            np.maximum.at(depth, sb, d / radius)
        bad_edges = curve.edges[edge_len > 0]
        vertex_flag[bad_edges.ravel()] = True
    checkpoint(0.5)
    branch_len = np.bincount(branches.edge_branch, weights=edge_len, minlength=nb) if nb and ne else np.zeros(nb)
    sk_out = None
    sk_share = 0.0
    sk_cluster = None
    sub = None
    if skeletal is not None and skeletal_boundedness is not None:
        sb = np.asarray(skeletal_boundedness, dtype=float)
        sk_out = ~(sb > beta_star) & np.isfinite(sb)
        link = params.outside_link * median_spacing(cloud)
        sk_cluster, sk_share, sub = _skeletal_clusters(np.asarray(skeletal, float), sk_out, link, seed)
    checkpoint(1.0)
    return OutsideDefects(
        branches=branches, sample_outside=sample_out, edge_outside_length=edge_len, branch_outside_length=branch_len,
        radius=radius, depth=depth, vertex_flag=vertex_flag,
        total_length=float(curve.edge_lengths().sum()) if curve is not None else 0.0, skeletal_outside=sk_out,
        skeletal_cluster_share=sk_share, skeletal_cluster=sk_cluster, params=params, subsampled=sub,
    )  # fmt: skip
