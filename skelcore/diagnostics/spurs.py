"""Terminal branches the shape does not justify -> ``spurious_branches``
(docs/diagnostics.md "Spurious branches").

A terminal branch (a degree-1 end, a junction at the other) is spurious when either of the two
classical significance measures fails:

- **reach**: its far end stays within ``spur_reach`` x r_J of its junction J, r_J the radius of
  the medial ball at J (distance from J to the cloud): it does not leave the junction's ball;
- **explanation**: the cloud points nearest to it (its territory) are explained by the rest of the
  skeleton as well: a point is explained by an element x (curve point, every ``diag_step`` local
  radii) when it lies within (1 + ``spur_slack``) r(x) + tau of it (coverage's rule, docs/metrics.md 5.2). The
  branch is spurious when fewer than ``spur_min_points`` of its territory, or less than
  ``spur_unique`` of it, are explained by nothing else.

Its size: length in multiples of r_J and share of the curve's length.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from ..metrics.curve_sampling import CurveSamples
from ..geometry import Checkpoint, kd_tree, no_checkpoint
from ..params import Params
from .trust_warning import TrustWarning
from .branches import Branches, decompose_branches, densify
from .interior import cloud_subsample, median_spacing

__all__ = ["SpurDefects", "find_spurious_branches", "curve_points"]


@dataclass
class SpurDefects:
    """Terminal branches against the cloud.

    terminal : ids of the terminal branches tested. reach : (B,) the far end's distance from the
    junction / r_J (NaN for non-terminal branches). territory, unique : (B,) cloud points nearest to
    the branch and those no other part explains (counts in the cloud used: see ``subsampled``).
    branch_spurious : (B,) bool. vertex_flag : (V,) bool, the vertices of spurious branches (not
    their junction); sample_flag : (S,) bool or None, the curve samples on them.
    length_radii : (B,) length / r_J. subsampled : the number of cloud points used when the cloud
    was subsampled (``diag_max_points``), else None.
    """

    branches: Branches
    terminal: np.ndarray
    reach: np.ndarray
    junction_radius: np.ndarray
    territory: np.ndarray
    unique: np.ndarray
    branch_spurious: np.ndarray
    vertex_flag: np.ndarray
    sample_flag: np.ndarray | None
    length_radii: np.ndarray
    total_length: float
    subsampled: int | None = None
    params: Params = field(default_factory=Params)

    @property
    def spurious(self) -> np.ndarray:
        return np.flatnonzero(self.branch_spurious)

    @property
    def length_share(self) -> float:
        if not self.total_length > 0:
            return 0.0
        return float(self.branches.length[self.branch_spurious].sum()) / self.total_length

    def warnings(self) -> list[TrustWarning]:
        n = len(self.spurious)
        if n < self.params.spurs_warn_count:
            return []
        lr = self.length_radii[self.branch_spurious]
        return [TrustWarning(
            "spurious_branches",
            f"{n} of the curve's {len(self.terminal)} terminal branches are spurious (reach no farther than "
            f"their junction's ball or explain no part of the cloud the rest does not): {self.length_share:.1%} "
            f"of the curve's length, {np.nanmin(lr):.2g}-{np.nanmax(lr):.2g} local radii long",
        )]  # fmt: skip

    def to_dict(self) -> dict:
        def num(x: float) -> float | None:
            return float(x) if np.isfinite(x) else None

        return {
            "terminal": int(len(self.terminal)),
            "spurious": int(len(self.spurious)),
            "length_share": self.length_share,
            "branches": [
                {"id": int(b), "reach": num(self.reach[b]), "length_radii": num(self.length_radii[b]),
                 "territory": int(self.territory[b]), "unique": int(self.unique[b]),
                 "spurious": bool(self.branch_spurious[b])}
                for b in self.terminal
            ],
            "subsampled": self.subsampled,
        }


def curve_points(curve: CurveSkeleton, branches: Branches, step: float) -> tuple[np.ndarray, np.ndarray]:
    """The curve every ``step`` (both ends of every edge) and the branch of each point."""
    pts, pe = densify(curve, step)
    deg = curve.degrees()
    pb = np.where(pe >= 0, branches.edge_branch[np.maximum(pe, 0)] if len(branches.edge_branch) else -1, -1)
    if np.any(pe < 0):
        pb[pe < 0] = branches.vertex_branch[np.flatnonzero(deg == 0)]
    return pts, pb


def _explained_elsewhere(
    tree: cKDTree, pts_branch: np.ndarray, reach: np.ndarray, queries: np.ndarray, own: np.ndarray, bound: float
) -> np.ndarray:
    """For each query point, whether some curve point on another branch than ``own`` explains it
    (|q - x| <= reach(x)). The k = 16 nearest first, k doubled for the rows that only met their own
    branch within ``bound``."""
    n = len(queries)
    done = np.zeros(n, bool)
    out = np.zeros(n, bool)
    k = 16
    todo = np.arange(n)
    while len(todo):
        kk = min(k, tree.n)
        d, i = tree.query(queries[todo], k=kk, distance_upper_bound=bound)
        d = d.reshape(len(todo), kk)
        i = i.reshape(len(todo), kk)
        valid = np.isfinite(d)
        ii = np.where(valid, i, 0)
        other = valid & (pts_branch[ii] != own[todo, None])
        hit = other & (d <= reach[ii])
        out[todo] = hit.any(axis=1)
        # unresolved: every neighbour found was on the own branch and the search was cut by k
        unresolved = ~out[todo] & valid[:, -1] & (kk < tree.n)
        done[todo[~unresolved]] = True
        todo = todo[unresolved]
        k *= 2
    return out


def find_spurious_branches(
    cloud: np.ndarray,
    curve: CurveSkeleton,
    *,
    params: Params = Params(),
    branches: Branches | None = None,
    samples: CurveSamples | None = None,
    cloud_tree: cKDTree | None = None,
    checkpoint: Checkpoint = no_checkpoint,
    seed: int = 0,
) -> SpurDefects:
    """Spurious terminal branches of ``curve`` in the shape sampled by ``cloud`` (both normalized,
    docs/metrics.md 0). ``branches`` and ``cloud_tree`` (a KD-tree of the cloud, or of its subsample of
    ``diag_max_points``: the local radii come from it) may be passed when computed;
    ``samples`` (the curve samples) give the per-sample flags."""
    cloud = np.asarray(cloud, dtype=float)
    if cloud_tree is None and len(cloud):
        cloud_tree = kd_tree(cloud_subsample(cloud, params.diag_max_points, seed), checkpoint)
    if branches is None:
        branches = decompose_branches(curve, cloud=cloud, sample_edge=None if samples is None else samples.edge,
                                      cloud_tree=cloud_tree)
    nb = len(branches)
    terminal = branches.terminal()
    reach = np.full(nb, np.nan)
    r_j = np.full(nb, np.nan)
    territory = np.zeros(nb, np.int64)
    unique = np.zeros(nb, np.int64)
    subsampled = int(params.diag_max_points) if len(cloud) > params.diag_max_points else None
    if len(terminal) and len(cloud):
        r_typ = float(np.nanmedian(branches.radius_median)) if np.any(np.isfinite(branches.radius_median)) else 0.0
        total = float(branches.length.sum())
        step = params.diag_step * r_typ if r_typ > 0 else (total / 200 if total > 0 else 1.0)
        step = max(step, total / 200_000 if total > 0 else step)
        pts, pb = curve_points(curve, branches, step)
        r_x, _ = cloud_tree.query(pts)
        checkpoint(0.2)
        use = cloud_subsample(cloud, params.diag_max_points, seed)
        tau = params.coverage_tau_factor * median_spacing(cloud)
        explain = (1.0 + params.spur_slack) * r_x + tau
        ptree = cKDTree(pts)
        _, near = ptree.query(use)
        own = pb[near]
        is_term = np.zeros(nb + 1, bool)
        is_term[terminal] = True
        in_term = is_term[own]
        q = use[in_term]
        checkpoint(0.4)
        elsewhere = _explained_elsewhere(ptree, pb, explain, q, own[in_term], float(explain.max()))
        checkpoint(0.9)
        territory = np.bincount(own[in_term], minlength=nb)[:nb]
        unique = np.bincount(own[in_term][~elsewhere], minlength=nb)[:nb]
        deg = curve.degrees()
        for b in terminal:
            path = branches.paths[b]
            j = path[0] if deg[path[0]] != 1 else path[-1]
            far = curve.vertices[path]
            reach_b = float(np.linalg.norm(far - curve.vertices[j], axis=1).max())
            rj, _ = cloud_tree.query(curve.vertices[j])
            r_j[b] = rj
            reach[b] = reach_b / rj if rj > 0 else np.inf
    short = reach <= params.spur_reach
    lonely = (unique < params.spur_min_points) | (unique < params.spur_unique * np.maximum(territory, 1))
    branch_spurious = np.zeros(nb, bool)
    branch_spurious[terminal] = (short | lonely)[terminal]
    with np.errstate(divide="ignore", invalid="ignore"):
        length_radii = np.where(r_j > 0, branches.length / r_j, np.nan)
    vertex_flag = np.zeros(curve.n_vertices, bool)
    vb = branches.vertex_branch
    ok = vb >= 0
    vertex_flag[ok] = branch_spurious[vb[ok]]
    sample_flag = None if branches.sample_branch is None else branch_spurious[branches.sample_branch]
    checkpoint(1.0)
    return SpurDefects(
        branches=branches, terminal=terminal, reach=reach, junction_radius=r_j, territory=territory, unique=unique,
        branch_spurious=branch_spurious, vertex_flag=vertex_flag, sample_flag=sample_flag, length_radii=length_radii,
        total_length=float(branches.length.sum()), subsampled=subsampled, params=params,
    )  # fmt: skip
