"""Terminal branches the shape does not justify -> ``spurious_branches`` (docs/diagnostics.md
"Spurious branches").

A terminal branch (a degree-1 end, a junction at the other) is spurious when either classical
significance measure fails:

- **reach**: its far end stays within ``spur_reach`` x r_J of its junction J (r_J: distance from J
  to the cloud), inside the junction's ball;
- **explanation**: its territory (the cloud points nearest to it) is explained by the rest of the
  skeleton as well (within (1 + ``spur_slack``) r(x) of a curve point x whose ball the shape holds:
  :mod:`.spur_balls`): fewer than ``spur_min_points``, or under ``spur_unique`` of it, is its own.

Not judged: ``unresolved`` (r_J under ``spur_resolved_spacings`` spacings, or an explanation-only
failure ending under ``spur_twig_spacings`` spacings past the junction's ball, its tip not in the air:
:func:`unsampled_twig`);
``stubs`` under ``spur_stub_share`` of the curve's length; ``unseen`` on a cloud seen from one side
(:mod:`.spur_sides`); ``cut_end``, a tip at a break of the curve (:mod:`.spur_cuts`). Size: length in
r_J, share of the length.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import partial

import numpy as np
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from ..metrics.curve_sampling import CurveSamples
from ..geometry import Checkpoint, kd_tree, no_checkpoint
from ..params import Params
from .trust_warning import TrustWarning, finite_range
from .branches import Branches, decompose_branches, densify
from .interior import cloud_subsample
from .spur_pairs import explained_by_balls
from .spur_cache import SpurMemo
from .spur_sides import one_sidedness
from .spur_cuts import cut_ends
from .spur_balls import balls_in_shape
from .interior import VoxelShape

__all__ = ["SpurDefects", "find_spurious_branches", "curve_points", "junction_spacing", "unsampled_twig"]


@dataclass
class SpurDefects:
    """Terminal branches against the cloud.

    terminal : ids of the terminal branches tested. reach : (B,) the far end's distance from the
    junction / r_J (NaN for non-terminal branches). territory, unique : (B,) cloud points nearest to
    the branch and those no other part explains (counts in the cloud used: see ``subsampled``).
    branch_spurious : (B,) bool. vertex_flag : (V,) bool, the vertices of spurious branches (not
    their junction); sample_flag : (S,) bool or None, the curve samples on them.
    length_radii : (B,) length / r_J. subsampled : the number of cloud points used when the cloud
    was subsampled (``diag_max_points``), else None. spacing : (B,) the cloud's spacing at the
    junction; unresolved, stub : (B,) bool, terminal branches not judged (r_J under
    ``spur_resolved_spacings`` spacings, or :func:`unsampled_twig`) and short stubs under
    ``spur_stub_share`` (neither spurious). tip_distance : (B,) the far end's distance to the cloud.
    one_sided : how far the cloud is seen from one side (:mod:`.spur_sides`); unseen : (B,) bool,
    terminal branches failing the explanation measure alone on a one-sided cloud (not judged).
    cut_end : (B,) bool, terminal branches whose tip is a cut in the curve (:mod:`.spur_cuts`; not
    spurious, ``disconnected``'s).
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
    spacing: np.ndarray | None = None
    unresolved: np.ndarray | None = None
    stub: np.ndarray | None = None
    one_sided: float = 0.0
    unseen: np.ndarray | None = None
    tip_distance: np.ndarray | None = None
    cut_end: np.ndarray | None = None

    def _count(self, flags: np.ndarray | None) -> int:
        return int(np.count_nonzero(flags)) if flags is not None else 0

    @property
    def spurious(self) -> np.ndarray:
        return np.flatnonzero(self.branch_spurious)

    @property
    def length_share(self) -> float:
        if not self.total_length > 0:
            return 0.0
        return float(self.branches.length[self.branch_spurious].sum()) / self.total_length

    @property
    def unchecked(self) -> str | None:
        """Which terminal branches were not judged (unresolved, unseen), or None: a check left out in
        part says so (docs/diagnostics.md "Checks not run")."""
        unresolved, unseen = self._count(self.unresolved), self._count(self.unseen)
        if not unresolved + unseen:
            return None
        parts = ([f"{unresolved} in parts the cloud does not resolve (a junction ball under "
                  f"spur_resolved_spacings = {self.params.spur_resolved_spacings:g} spacings, or a twig ending under "
                  f"spur_twig_spacings = {self.params.spur_twig_spacings:g} spacings past it, its tip near the cloud)"]
                 if unresolved else [])
        parts += [f"{unseen} with no point of their own on a cloud seen from one side"] if unseen else []
        return (f"{unresolved + unseen} of the curve's {len(self.terminal)} terminal branches were not judged: "
                + "; ".join(parts))

    def warnings(self) -> list[TrustWarning]:
        n = len(self.spurious)
        if n < self.params.spurs_warn_count:
            return []
        span = finite_range(self.length_radii[self.branch_spurious])  # none on a junction at a cloud point
        long = f", {span} local radii long" if span is not None else ""
        unresolved = self._count(self.unresolved)
        aside = f"; {unresolved} more in parts the cloud does not resolve, not judged" if unresolved else ""
        unseen = self._count(self.unseen)
        aside += f"; {unseen} more with no point of their own on a cloud seen from one side, not judged" if unseen else ""
        cut = self._count(self.cut_end)
        aside += f"; {cut} more ending where the curve is broken, not judged (disconnected)" if cut else ""
        return [TrustWarning(
            "spurious_branches",
            f"{n} of the curve's {len(self.terminal)} terminal branches are spurious (reach no farther than "
            f"their junction's ball or explain no part of the cloud the rest does not): {self.length_share:.1%} "
            f"of the curve's length{long}{aside}",
        )]  # fmt: skip

    def to_dict(self) -> dict:
        def num(x: float) -> float | None:
            return float(x) if np.isfinite(x) else None

        return {
            "terminal": int(len(self.terminal)),
            "spurious": int(len(self.spurious)),
            "length_share": self.length_share,
            "unresolved": self._count(self.unresolved),
            "stubs": self._count(self.stub),
            "unseen": self._count(self.unseen),
            "cut_ends": self._count(self.cut_end),
            "one_sided": float(self.one_sided),
            "branches": [
                {"id": int(b), "reach": num(self.reach[b]), "length_radii": num(self.length_radii[b]),
                 "territory": int(self.territory[b]), "unique": int(self.unique[b]),
                 "spurious": bool(self.branch_spurious[b]),
                 "unresolved": bool(self.unresolved[b]) if self.unresolved is not None else False,
                 "stub": bool(self.stub[b]) if self.stub is not None else False,
                 "unseen": bool(self.unseen[b]) if self.unseen is not None else False,
                 "cut_end": bool(self.cut_end[b]) if self.cut_end is not None else False}
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


_QUERY_CELLS = 1 << 20  # neighbour entries (rows x k) one query of the spur test holds at once
_K_MAX = 256  # beyond, the rows still crowded by their own branch are answered per branch


def _explained_elsewhere(
    pts: np.ndarray, pts_branch: np.ndarray, reach: np.ndarray, queries: np.ndarray, own: np.ndarray,
    query_tree: cKDTree | None = None,
) -> np.ndarray:
    """For each query point, whether some curve point x on another branch than ``own`` explains it
    (|q - x| <= reach(x)). ``query_tree``: the cloud's KD-tree, which the ball pairs' search reads
    when the queries are its points (:func:`.spur_pairs.explained_by_balls`).

    The curve points are grouped by reach in levels of a factor 2 (an edge through the air has balls
    far larger than the shape's: one scale would blind the trees), each level searched by
    :func:`_explained_in_level` while rows remain unexplained. Memory is O(curve points +
    ``_QUERY_CELLS``) whatever the balls' sizes (docs/diagnostics.md "Peak memory")."""
    n = len(queries)
    out = np.zeros(n, bool)
    ok = np.isfinite(reach) & (reach >= 0)
    if not n or not ok.any():
        return out
    few = explained_by_balls(pts, pts_branch, reach, queries, own, query_tree)  # the same answers, when the balls hold few points
    if few is not None:
        return few
    top = float(reach[ok].max())
    level = np.full(len(reach), -1)
    with np.errstate(divide="ignore"):
        level[ok] = np.clip(np.floor(np.log2(top / np.maximum(reach[ok], top * 2.0**-60))), 0, 60).astype(int)
    for lv in np.unique(level[ok])[::-1]:  # the small balls first: most rows end there
        todo = np.flatnonzero(~out)
        if not len(todo):
            break
        sel = np.flatnonzero(level == lv)
        out[todo] = _explained_in_level(pts[sel], pts_branch[sel], reach[sel], queries[todo], own[todo])
    return out


def _explained_in_level(
    pts: np.ndarray, pts_branch: np.ndarray, reach: np.ndarray, queries: np.ndarray, own: np.ndarray
) -> np.ndarray:
    """``_explained_elsewhere`` for curve points of reaches within a factor 2 of each other.

    They are lifted to 4-D, x' = (x, sqrt(R^2 - reach(x)^2)) with R the largest reach, and q to
    (q, 0): |q' - x'|^2 = |q - x|^2 - reach(x)^2 + R^2, so the nearest lifted points are those whose
    balls q enters deepest and none beyond R explains q. The k = 16 nearest first, k doubled up to
    ``_K_MAX`` while a row met only its own branch within R; the rows still crowded (inside many
    balls of their own branch) get a tree of the other branches. Chunks of ``_QUERY_CELLS``
    neighbours."""
    n = len(queries)
    out = np.zeros(n, bool)
    big = float(np.max(reach))
    lifted = np.column_stack([pts, np.sqrt(np.maximum(big * big - reach * reach, 0.0))])
    tree = cKDTree(lifted)
    bound = big * (1.0 + 1e-9) + 1e-300
    q4 = np.column_stack([queries, np.zeros(n)])
    k = 16
    todo = np.arange(n)
    while len(todo) and k <= _K_MAX:
        kk = min(k, tree.n)
        crowded = np.zeros(len(todo), bool)
        rows = max(1, _QUERY_CELLS // kk)
        for a in range(0, len(todo), rows):
            part = todo[a:a + rows]
            d, i = tree.query(q4[part], k=kk, distance_upper_bound=bound)
            valid = np.isfinite(d.reshape(len(part), kk))
            ii = np.where(valid, i.reshape(len(part), kk), 0)
            other = valid & (pts_branch[ii] != own[part, None])
            dist = np.linalg.norm(pts[ii] - queries[part, None, :], axis=2)
            out[part] = (other & (dist <= reach[ii])).any(axis=1)
            # crowded: all k neighbours within R on the own branch (another branch may still explain it)
            crowded[a:a + rows] = ~other.any(axis=1) & valid[:, -1] & (kk < tree.n)
        todo = todo[crowded]
        k *= 2
    for b in np.unique(own[todo]):
        mine = todo[own[todo] == b]
        others = np.flatnonzero(pts_branch != b)
        if not len(others):
            continue
        sub = cKDTree(lifted[others])
        kk = min(4, len(others))
        rows = max(1, _QUERY_CELLS // kk)
        for a in range(0, len(mine), rows):
            part = mine[a:a + rows]
            _, i = sub.query(q4[part], k=kk, distance_upper_bound=bound)
            i = i.reshape(len(part), kk)
            valid = i < len(others)
            x = others[np.where(valid, i, 0)]
            dist = np.linalg.norm(pts[x] - queries[part, None, :], axis=2)
            out[part] = (valid & (dist <= reach[x])).any(axis=1)
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
    search_memo: SpurMemo | None = None,
    voxel_shape: VoxelShape | None = None,
) -> SpurDefects:
    """Spurious terminal branches of ``curve`` in the shape sampled by ``cloud`` (both normalized,
    docs/metrics.md 0). ``branches`` and ``cloud_tree`` (a KD-tree of the cloud, or of its subsample of
    ``diag_max_points``: the local radii come from it) may be passed when computed;
    ``samples`` (the curve samples) give the per-sample flags. ``search_memo``: the nearest-ball search
    kept from an earlier curve of the same cloud and params (an edit's update asks again only the
    points the edit can change, :mod:`.spur_cache`; the same answers). ``voxel_shape``: the cloud's
    voxelized interior; when given, only balls the shape holds explain (:mod:`.spur_balls`)."""
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
    tip_d = np.full(nb, np.nan)
    territory = np.zeros(nb, np.int64)
    unique = np.zeros(nb, np.int64)
    subsampled = int(params.diag_max_points) if len(cloud) > params.diag_max_points else None
    sided = 0.0
    if len(terminal) and len(cloud):
        r_typ = float(np.nanmedian(branches.radius_median)) if np.any(np.isfinite(branches.radius_median)) else 0.0
        total = float(branches.length.sum())
        step = params.diag_step * r_typ if r_typ > 0 else (total / 200 if total > 0 else 1.0)
        step = max(step, total / 200_000 if total > 0 else step)
        pts, pb = curve_points(curve, branches, step)
        memo = search_memo
        r_x = cloud_tree.query(pts)[0] if memo is None else memo.radii(pts, cloud_tree)
        sided = one_sidedness(cloud_tree, pts, r_x, r_typ if r_typ > 0 else step, seed,
                              None if memo is None else memo.sides(cloud_tree))
        checkpoint(0.2)
        use = (cloud_subsample(cloud, params.diag_max_points, seed) if memo is None else
               memo.subsample(cloud, (params.diag_max_points, seed),
                              lambda: cloud_subsample(cloud, params.diag_max_points, seed)))
        explain = (1.0 + params.spur_slack) * r_x  # no tau: see the module's docstring
        if voxel_shape is not None:  # a ball through the air explains nothing
            explain = np.where(balls_in_shape(voxel_shape, pts, r_x), explain, -1.0)
        own = pb[cKDTree(pts).query(use)[1]] if memo is None else memo.own_branch(pts, pb, use)
        is_term = np.zeros(nb + 1, bool)
        is_term[terminal] = True
        in_term = is_term[own]
        q = use if in_term.all() else use[in_term]  # the subsample itself when every point is terminal's
        checkpoint(0.4)
        search = partial(_explained_elsewhere, query_tree=cloud_tree)  # a tree of q when the whole cloud is asked
        if memo is None:
            elsewhere = search(pts, pb, explain, q, own[in_term])
        else:
            elsewhere = memo.search(search, pts, pb, explain, q, np.flatnonzero(in_term), own[in_term], len(use))
        checkpoint(0.9)
        territory = np.bincount(own[in_term], minlength=nb)[:nb]
        unique = np.bincount(own[in_term][~elsewhere], minlength=nb)[:nb]
        deg = curve.degrees()
        ends = [p[0] if deg[p[0]] != 1 else p[-1] for p in (branches.paths[b] for b in terminal)]
        tips = [p[-1] if deg[p[0]] != 1 else p[0] for p in (branches.paths[b] for b in terminal)]
        d_ends = cloud_tree.query(curve.vertices[np.asarray(ends + tips, np.int64)])[0]  # one query, not one per branch
        r_j[terminal], tip_d[terminal] = d_ends[:len(ends)], d_ends[len(ends):]
        for b, j in zip(terminal, ends):
            reach_b = float(np.linalg.norm(curve.vertices[branches.paths[b]] - curve.vertices[j], axis=1).max())
            reach[b] = reach_b / r_j[b] if r_j[b] > 0 else np.inf
    spacing = np.full(nb, np.nan)
    if len(terminal) and len(cloud):
        spacing[terminal] = junction_spacing(cloud_tree, curve, branches, terminal)
    lonely = (unique < params.spur_min_points) | (unique < params.spur_unique * np.maximum(territory, 1))
    cut = np.zeros(nb, bool)  # a tip where the curve is broken: disconnected's, not a spur
    if len(terminal) and len(cloud):
        cut[terminal] = cut_ends(curve, branches, terminal, cloud_tree, params).cut
    with np.errstate(invalid="ignore"):
        short = reach <= params.spur_reach
        unresolved = np.zeros(nb, bool)
        unresolved[terminal] = (~cut & ((r_j < params.spur_resolved_spacings * spacing)
                                        | (lonely & ~short & unsampled_twig(reach, r_j, spacing, params, tip_d))))[terminal]
    total_length = float(branches.length.sum())
    stub = np.zeros(nb, bool)
    stub[terminal] = (short & ~unresolved & ~cut & (branches.length < params.spur_stub_share * total_length))[terminal]
    unseen = np.zeros(nb, bool)
    if sided >= params.spur_one_sided:  # a twig the sensor did not see has no point: not judged
        unseen[terminal] = (lonely & ~short & ~unresolved & ~cut)[terminal]
    branch_spurious = np.zeros(nb, bool)
    branch_spurious[terminal] = ((short | lonely) & ~unresolved & ~stub & ~unseen & ~cut)[terminal]
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
        total_length=total_length, subsampled=subsampled, params=params, spacing=spacing, unresolved=unresolved,
        stub=stub, one_sided=sided, unseen=unseen, tip_distance=tip_d, cut_end=cut,
    )  # fmt: skip


def unsampled_twig(reach: np.ndarray, r_j: np.ndarray, spacing: np.ndarray, params: Params = Params(),
                   tip_distance: np.ndarray | None = None) -> np.ndarray:
    """Per branch, whether its far end reaches under ``spur_twig_spacings`` junction spacings past the
    junction's ball (``spur_reach`` r_J): a real twig that short bulges out of its parent by less than
    the cloud's spacing there, so it has no sample of its own beyond the parent's grown balls and the
    explanation measure cannot tell it from a spur (docs/diagnostics.md "Spurious branches", rule 3).
    Not when ``tip_distance`` (the far end's distance to the cloud) exceeds that part past the ball by
    ``spur_twig_tip_spacings`` spacings: the parent's samples lie within about a spacing of where such
    a twig leaves it, so that tip stands in the air (section "A tip in the air"). ``reach`` in units of
    ``r_j``; NaN gives False."""
    with np.errstate(invalid="ignore"):
        past = (reach - params.spur_reach) * r_j
        short = past < params.spur_twig_spacings * spacing
        if tip_distance is None:
            return short
        return short & ~(tip_distance - past > params.spur_twig_tip_spacings * spacing)


def junction_spacing(cloud_tree: cKDTree, curve: CurveSkeleton, branches: Branches, terminal: np.ndarray) -> np.ndarray:
    """Per terminal branch, the cloud's spacing at its junction: the median nearest-neighbour distance
    among the 16 cloud points nearest the junction (the cloud of ``cloud_tree``, as r_J's)."""
    deg = curve.degrees()
    ends = np.array([p[0] if deg[p[0]] != 1 else p[-1] for p in (branches.paths[b] for b in terminal)], np.int64)
    k = int(min(16, cloud_tree.n))
    if k < 2:
        return np.zeros(len(terminal))
    _, near = cloud_tree.query(curve.vertices[ends], k=k)
    rows = np.unique(near)
    nn = np.zeros(cloud_tree.n)
    nn[rows] = cloud_tree.query(cloud_tree.data[rows], k=2)[0][:, 1]
    return np.median(nn[near], axis=1)
