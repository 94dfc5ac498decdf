"""Curve length and skeletal points outside the shape -> ``outside``
(docs/diagnostics.md "Outside").

A curve sample is unbounded when its boundedness <= beta* (docs/metrics.md 2, the values the evaluation
computed). Each stands for its stretch of its edge (the sampling of docs/metrics.md 3.2); 200 samples are coarse on a
long curve (one may stand for many local radii), so the edges holding an unbounded sample are walked
every half voxel and a point counts as outside when its sample is unbounded, its voxel is not
inside the shape (:mod:`.interior`, the cycle test's voxels) and its nearest cloud points lie on one
side (a half-scanned tube's axis sees a half ring): thin or partly scanned parts stay inside. Voxels
coarser than ``outside_voxel_radii`` local radii cannot tell (a traced neuron): then only the reach
test runs. The length outside is summed per edge and per branch and measured in local radii: one
edge through the air is a defect even when the overall boundedness is 0.95. Skeletal points outside
(unbounded and not in an inside voxel) are grouped into clusters (within ``outside_link`` x the
cloud's median spacing); one large cluster is a part of the skeleton that left the shape, scattered
single points are not.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from ..metrics.curve_sampling import CurveSamples
from ..geometry import Checkpoint, kd_tree, no_checkpoint
from ..params import Params
from .trust_warning import TrustWarning
from .branches import Branches, decompose_branches, densify
from .interior import VoxelShape, cloud_subsample, median_spacing, voxelize_interior

__all__ = ["OutsideDefects", "find_outside"]

# skeletal points clustered at most (a random subsample beyond; the shares are estimated on it)
_MAX_CLUSTERED = 200_000


@dataclass
class OutsideDefects:
    """Where the skeleton leaves the shape.

    sample_outside : (S,) bool per curve sample: unbounded, and part of its stretch in no inside voxel. edge_outside_length : (E,) length of each edge
    outside; branch_outside_length : (B,). radius : the local radius the lengths are measured in
    (normalized units). depth : (B,) the largest distance from an outside sample of the branch to the
    cloud, in local radii (0 where none). vertex_flag : (V,) bool, vertices on an edge with a sample
    outside. skeletal_outside : (N_s,) bool or None; skeletal_cluster_share : the largest cluster's
    share of the skeletal set. voxel_size : of the interior that confirms "outside".
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
    voxel_size: float = 0.0
    reach: np.ndarray = field(default_factory=lambda: np.zeros(0))
    length_test: bool = True

    @property
    def unchecked(self) -> str | None:
        """Why the length test did not run (its voxels coarser than the parts), or None."""
        if self.length_test:
            return None
        return (f"the shape's interior voxels ({self.voxel_size / self.radius:.2g} local radii) are coarser than "
                f"outside_voxel_radii = {self.params.outside_voxel_radii:g}: they cannot tell a part's inside from a "
                f"few radii beyond it; only the branches reaching more than outside_reach = "
                f"{self.params.outside_reach:g} local radii out were looked for")

    @property
    def length_share(self) -> float:
        return float(self.edge_outside_length.sum()) / self.total_length if self.total_length > 0 else 0.0

    @property
    def branch_radii(self) -> np.ndarray:
        """Length outside per branch in local radii."""
        return self.branch_outside_length / self.radius if self.radius > 0 else np.zeros_like(self.branch_outside_length)

    def far_branches(self) -> np.ndarray:
        """Branches reaching more than ``outside_reach`` local radii out of the shape (``reach``)."""
        return np.flatnonzero(self.reach > self.params.outside_reach) if len(self.reach) else np.zeros(0, np.int64)

    def defective_branches(self, reach_only: bool = False) -> np.ndarray:
        """Branches with ``outside_min_radii`` of length outside, or reaching too far (only those
        with ``reach_only``: boundedness cannot tell outside on an open surface)."""
        far = self.far_branches()
        if reach_only or not self.length_test:
            return far
        return np.union1d(np.flatnonzero(self.branch_radii >= self.params.outside_min_radii), far).astype(np.int64)

    def warnings(self, reach_only: bool = False) -> list[TrustWarning]:
        """``outside``; with ``reach_only`` only for the branches reaching too far (docs/diagnostics.md "Outside")."""
        out: list[TrustWarning] = []
        if reach_only or not self.length_test:
            far = self.far_branches()
            if len(far):
                worst = int(far[np.argmax(self.reach[far])])
                out.append(TrustWarning(
                    "outside",
                    f"{len(far)} branch{'es' if len(far) > 1 else ''} of the curve skeleton reach{'' if len(far) > 1 else 'es'} "
                    f"more than {self.params.outside_reach:g} local radii out of the shape, the farthest branch {worst} "
                    f"({self.reach[worst]:.2g} radii)",
                ))  # fmt: skip
            if reach_only:
                return out
            return out + self._skeletal_warnings()
        bad = self.defective_branches()
        if len(bad) or (self.total_length > 0 and self.length_share >= self.params.outside_min_share):
            n_edges = int(np.count_nonzero(self.edge_outside_length > 0))
            if self.radius > 0 and len(self.branch_radii):  # lengths in local radii only when one is known
                worst = int(np.argmax(self.branch_radii))
                most = (f", {self.branch_radii.sum():.2g} local radii, the most on branch {worst} "
                        f"({self.branch_radii[worst]:.2g} radii, up to {self.depth[worst]:.2g} radii out)")
            else:
                most = ""
            far = self.far_branches()
            reach = (f"; {len(far)} reach{'' if len(far) > 1 else 'es'} more than {self.params.outside_reach:g} "
                     f"local radii out (up to {float(self.reach[far].max()):.2g})") if len(far) else ""
            out.append(TrustWarning(
                "outside",
                f"the curve skeleton leaves the shape on {len(bad)} branches ({n_edges} edges): "
                f"{self.length_share:.1%} of its length{most}{reach}",
            ))  # fmt: skip
        return out + self._skeletal_warnings()

    def _skeletal_warnings(self) -> list[TrustWarning]:
        out: list[TrustWarning] = []
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
                 "depth": float(self.depth[b]), "reach": float(self.reach[b]) if len(self.reach) else 0.0}
                for b in np.flatnonzero((self.branch_outside_length > 0) | (self.reach > self.params.outside_reach)
                                        if len(self.reach) else self.branch_outside_length > 0)
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


def _outside_stretches(curve: CurveSkeleton, samples: CurveSamples, sample_out: np.ndarray, in_shape,
                       step: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Points every ``step`` along the edges holding an unbounded sample, their edge, and whether each
    is outside: its sample (the one whose stretch (t_prev, t] holds it, the sampling of docs/metrics.md 3.2) is
    unbounded and ``in_shape`` rejects it; and that sample."""
    bad = np.unique(samples.edge[sample_out])
    lengths = curve.edge_lengths()[bad]
    m = np.maximum(np.ceil(lengths / step).astype(np.int64), 2)
    pe = np.repeat(bad, m)
    start = np.concatenate([[0], np.cumsum(m)[:-1]])
    t = (np.arange(len(pe)) - np.repeat(start, m) + 0.5) / np.repeat(m, m)
    v = curve.vertices
    a, b = v[curve.edges[pe, 0]], v[curve.edges[pe, 1]]
    pts = a + t[:, None] * (b - a)
    # the covering sample: the first on the same edge at or beyond t (every edge has one at t = 1)
    key_s = samples.edge + 0.5 * np.asarray(samples.t, float)
    order = np.argsort(key_s, kind="stable")
    pos = np.searchsorted(key_s[order], pe + 0.5 * t, side="left")
    cover = order[np.clip(pos, 0, len(order) - 1)]
    out = sample_out[cover] & (samples.edge[cover] == pe)
    if out.any():
        out[out] = ~in_shape(pts[out])
    return pts, pe, out, cover


_ONE_SIDED_K = 16  # cloud points whose directions tell one-sided from surrounded


def branch_reach(curve: CurveSkeleton, branches: Branches, cloud_tree: cKDTree, radius: float,
                 params: Params) -> np.ndarray:
    """(B,) how far each branch reaches out of the shape, in local radii: the largest distance to the
    cloud (less coverage's tau) of its points (every half local radius) whose nearest cloud points lie on one side
    (``outside_one_sided``), over the radius where it attaches (at a junction the largest median
    local radius of the branches meeting there; for an internal branch its smaller end's; the
    median local radius otherwise);
    0 where no point is farther than ``outside_reach`` such radii (docs/diagnostics.md "Outside").
    Memory O(curve points)."""
    nb = len(branches)
    out = np.zeros(nb)
    if not nb or curve.n_edges == 0 or not radius > 0 or cloud_tree.n == 0:
        return out
    total = float(curve.edge_lengths().sum())
    pts, pe = densify(curve, max(0.5 * radius, total / 200_000))
    keep = pe >= 0
    pts, pb = pts[keep], branches.edge_branch[pe[keep]]
    deg = curve.degrees()
    # the radius at a junction: the largest median radius of the branches meeting there (a traced
    # node may lie on the surface, its own distance to the cloud says nothing)
    at: dict[int, list[tuple[float, int]]] = {}
    med = np.where(np.isfinite(branches.radius_median), branches.radius_median, 0.0)
    for b, path in enumerate(branches.paths):
        for v in {int(path[0]), int(path[-1])}:
            if deg[v] >= 3:
                at.setdefault(v, []).append((float(med[b]), b))
    ref = np.full(nb, radius)
    for b, (path, kind) in enumerate(zip(branches.paths, branches.kind)):
        if kind not in ("terminal", "internal"):
            continue
        # the others meeting at its junctions: a branch in the air has a large radius of its own
        ends = [max((m for m, o in at[int(v)] if o != b), default=0.0) for v in {int(path[0]), int(path[-1])} if int(v) in at]
        ends = [e for e in ends if e > 0]
        if ends:
            ref[b] = min(ends)
    ref = np.where(ref > 0, ref, radius)
    # a sparse cloud leaves gaps of its spacing on a thin part: the coverage's tolerance tau first
    tau = params.coverage_tau_factor * median_spacing(cloud_tree.data)
    d, _ = cloud_tree.query(pts)
    d = np.maximum(d - tau, 0.0)
    far = np.flatnonzero(d > params.outside_reach * ref[pb])
    if not len(far):
        return out
    side = one_sided(cloud_tree, pts[far], params.outside_one_sided)
    np.maximum.at(out, pb[far[side]], d[far[side]] / ref[pb[far[side]]])
    return out


def one_sided(cloud_tree: cKDTree, points: np.ndarray, threshold: float) -> np.ndarray:
    """Whether the 16 nearest cloud points of each point lie on one side of it: the mean of the unit
    vectors to them is at least ``threshold`` long (a point outside a surface; inside a tube or a
    ball, even half a tube, they surround it more: 2 / pi for a half ring). 65 536 points at a time."""
    out = np.zeros(len(points), bool)
    k = min(_ONE_SIDED_K, cloud_tree.n)
    if not k:
        return out
    for a in range(0, len(points), 65536):
        part = points[a:a + 65536]
        _, j = cloud_tree.query(part, k=k)
        u = cloud_tree.data[j.reshape(len(part), k)] - part[:, None, :]
        u /= np.maximum(np.linalg.norm(u, axis=2, keepdims=True), 1e-300)
        out[a:a + 65536] = np.linalg.norm(u.mean(axis=1), axis=1) >= threshold
    return out


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
    voxel_shape: VoxelShape | None = None,
    checkpoint: Checkpoint = no_checkpoint,
    seed: int = 0,
) -> OutsideDefects:
    """The parts of a skeleton outside the shape, from the boundedness of its curve ``samples``
    (``sample_boundedness``, one per sample) and/or of its ``skeletal`` points, against ``beta_star``
    (docs/metrics.md 2), all normalized (docs/metrics.md 0), confirmed by the voxelized interior (``voxel_shape``, as the
    cycle test's); ``branches``, ``cloud_tree`` and ``voxel_shape`` may be passed when computed."""
    cloud = np.asarray(cloud, dtype=float)
    beta_star = params.beta_star
    if cloud_tree is None and len(cloud) and curve is not None:  # only the curve's parts read it
        cloud_tree = kd_tree(cloud_subsample(cloud, params.diag_max_points, seed))
    if voxel_shape is None:
        voxel_shape = voxelize_interior(cloud, voxels=params.cycles_voxels,
                                        min_spacing_factor=params.cycles_voxel_spacing, inside_share=beta_star)
    solid = voxel_shape.solid()

    def in_shape(points: np.ndarray) -> np.ndarray:
        ijk = voxel_shape.index_of(points)
        return solid[ijk[:, 0], ijk[:, 1], ijk[:, 2]]

    def in_shape_seen(points: np.ndarray) -> np.ndarray:
        """Inside by the voxels, or surrounded by the cloud (docs/diagnostics.md "Outside")."""
        got = in_shape(points)
        if cloud_tree is not None and not got.all():
            got[~got] = ~one_sided(cloud_tree, points[~got], params.outside_one_sided)
        return got

    sample_edge = None if samples is None else samples.edge
    if curve is not None and branches is None:
        branches = decompose_branches(curve, cloud=cloud, sample_edge=sample_edge, cloud_tree=cloud_tree)
    nb = len(branches) if branches is not None else 0
    ne = curve.n_edges if curve is not None else 0
    edge_len = np.zeros(ne)
    sample_out = np.zeros(0, bool)
    radius = 0.0
    depth = np.zeros(nb)
    vertex_flag = np.zeros(curve.n_vertices if curve is not None else 0, bool)
    if nb:
        radius = float(np.nanmedian(branches.radius_median)) if np.any(np.isfinite(branches.radius_median)) else 0.0
    # voxels coarser than a few local radii: one holds a thin part and its surroundings alike
    length_test = not (radius > 0 and voxel_shape.size > params.outside_voxel_radii * radius)
    if length_test and curve is not None and samples is not None and sample_boundedness is not None and ne \
            and len(samples):
        beta = np.asarray(sample_boundedness, dtype=float)
        unbounded = ~(beta > beta_star) & np.isfinite(beta)
        sample_out = np.zeros(len(beta), bool)
        if unbounded.any():
            pts, pe, out, cover = _outside_stretches(curve, samples, unbounded, in_shape_seen, 0.5 * voxel_shape.size)
            sample_out[cover[out]] = True
            edge_len = np.bincount(pe, weights=out * (curve.edge_lengths()[pe] / np.bincount(pe, minlength=ne)[pe]),
                                   minlength=ne)
            if out.any() and radius > 0 and cloud_tree is not None:
                d, _ = cloud_tree.query(pts[out])
                np.maximum.at(depth, branches.edge_branch[pe[out]], d / radius)
        vertex_flag[curve.edges[edge_len > 0].ravel()] = True
    reach = np.zeros(nb)
    if curve is not None and branches is not None and cloud_tree is not None and ne:
        if not radius > 0:
            radius = float(np.nanmedian(branches.radius_median)) if np.any(np.isfinite(branches.radius_median)) else 0.0
        reach = branch_reach(curve, branches, cloud_tree, radius, params)
        for b in np.flatnonzero(reach > params.outside_reach):
            vertex_flag[branches.paths[b]] = True
    checkpoint(0.5)
    branch_len = np.bincount(branches.edge_branch, weights=edge_len, minlength=nb) if nb and ne else np.zeros(nb)
    sk_out = None
    sk_share = 0.0
    sk_cluster = None
    sub = None
    if skeletal is not None and skeletal_boundedness is not None:
        sb = np.asarray(skeletal_boundedness, dtype=float)
        sk = np.asarray(skeletal, float)
        sk_out = ~(sb > beta_star) & np.isfinite(sb)
        if sk_out.any():
            sk_out[sk_out] = ~in_shape(sk[sk_out])
        link = params.outside_link * median_spacing(cloud)
        sk_cluster, sk_share, sub = _skeletal_clusters(sk, sk_out, link, seed)
    checkpoint(1.0)
    return OutsideDefects(
        branches=branches, sample_outside=sample_out, edge_outside_length=edge_len, branch_outside_length=branch_len,
        radius=radius, depth=depth, vertex_flag=vertex_flag,
        total_length=float(curve.edge_lengths().sum()) if curve is not None else 0.0, skeletal_outside=sk_out,
        skeletal_cluster_share=sk_share, skeletal_cluster=sk_cluster, params=params, subsampled=sub,
        voxel_size=float(voxel_shape.size), reach=reach, length_test=length_test,
    )  # fmt: skip
