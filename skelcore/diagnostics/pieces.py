"""A curve skeleton broken into pieces where the cloud is one -> ``disconnected``
(docs/diagnostics.md "Disconnected").

The curve's pieces are its connected components (edges only; an isolated vertex is no piece, as the
repair's tally counts them). Each piece lies in the cloud piece that most of its vertices' nearest
cloud points (16 per vertex) belong to; the cloud's pieces are its components when each point is
joined to its nearest few within ``components_link`` x the median spacing of the points the
diagnostics' KD-tree holds. Coverage's tau (2 spacings, docs/metrics.md 5.2) is too fine for this: a
random surface sample falls into hundreds of bits at it (the bundled samples: 539-606 pieces), into
one at 4 spacings; the tuning neurons' one-sided and unevenly sampled clouds need 8. A cloud cut too
finely only hides a break (a curve piece in a bit of its own), never invents one. Every cloud piece
holding more than one curve piece is a defect: the skeleton of one part of the shape is broken. A
curve in one piece (the usual case) costs one pass over its edges and no search of the cloud.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from ..geometry import query_workers
from ..params import Params
from .branches import Branches
from .interior import median_spacing
from .trust_warning import TrustWarning

__all__ = ["CurveComponents", "find_components", "curve_pieces", "nearest_other_piece"]

# the last tree's pieces (the tree, its link, the labels): an edit's updates share the evaluation's tree,
# so a curve split by an edit and edited again searches the cloud once (2.4 CPU s at 200,000 points)
_last_pieces: list = []
_VOTERS = 16  # nearest cloud points per curve vertex voting for its cloud piece
_LINKED = 10  # cloud neighbours each point is joined to (within components_link)
_K = 8  # nearest vertices searched first for another piece's (a piece with none among them: its own search)


@dataclass
class CurveComponents:
    """The curve's pieces against the cloud's.

    n_pieces : the curve's components with at least one edge; n_cloud_pieces : the cloud's pieces
    they lie in; extra : n_pieces - n_cloud_pieces (0: sound). extra_branches : the branches of the
    pieces beyond the largest (by length) in each cloud piece, flagged. gap : the largest of those
    pieces' distances to the nearest other piece in their cloud piece, in local radii at its ends
    (the mean of their distances to the cloud; NaN when both lie on cloud points), with
    ``gap_branches`` the branches at its two ends;
    vertex_flag : (V,) bool, the flagged branches' vertices.
    """

    n_pieces: int = 1
    n_cloud_pieces: int = 1
    extra_branches: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    gap: float = 0.0
    gap_branches: tuple[int, int] = (-1, -1)
    vertex_flag: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))

    @property
    def extra(self) -> int:
        return max(self.n_pieces - self.n_cloud_pieces, 0)

    def warnings(self) -> list[TrustWarning]:
        if not self.extra:
            return []
        cloud = "one" if self.n_cloud_pieces == 1 else f"{self.n_cloud_pieces} pieces"
        a, b = self.gap_branches
        radii = f" {self.gap:.2g} local radii" if np.isfinite(self.gap) else ""  # ends on cloud points: no radius
        return [TrustWarning(
            "disconnected",
            f"the curve skeleton is in {self.n_pieces} pieces where the cloud is {cloud}; the largest gap"
            f"{radii} between branch {a} and branch {b}",
        )]  # fmt: skip

    def to_dict(self) -> dict:
        return {"pieces": int(self.n_pieces), "cloud_pieces": int(self.n_cloud_pieces), "extra": int(self.extra),
                "branches": [int(b) for b in self.extra_branches], "gap_radii": float(self.gap) if np.isfinite(self.gap) else None,
                "gap_branches": [int(b) for b in self.gap_branches]}


def curve_pieces(curve: CurveSkeleton) -> tuple[int, np.ndarray]:
    """The number of the curve's pieces and each vertex's piece (-1: an isolated vertex)."""
    n = curve.n_vertices
    e = np.asarray(curve.edges, np.int64).reshape(-1, 2)
    _, lab = connected_components(coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)), directed=False)
    used = np.zeros(n, bool)
    used[e.ravel()] = True
    _, piece = np.unique(np.where(used, lab, -1), return_inverse=True)
    piece = piece.astype(np.int64) - (0 if used.all() else 1)
    piece[~used] = -1
    return int(piece.max(initial=-1)) + 1, piece


def _cloud_pieces(tree: cKDTree, params: Params) -> np.ndarray:
    """Each point of ``tree`` -> its cloud piece: each point joined to its ``_LINKED`` nearest within
    ``components_link`` median spacings (a subgraph of all pairs within it: O(N) memory)."""
    hit = _last_pieces[0] if _last_pieces else None  # one tuple: read whole though another thread writes
    if hit is not None and hit[0] is tree and hit[1] == params.components_link:
        return hit[2]
    pts = tree.data
    n = len(pts)
    k = min(_LINKED + 1, n)
    d, j = tree.query(pts, k=k, distance_upper_bound=params.components_link * median_spacing(pts),
                      workers=query_workers(n))
    d, j = d.reshape(n, k), j.reshape(n, k)
    ok = np.isfinite(d)
    rows = np.repeat(np.arange(n), k).reshape(n, k)
    lab = connected_components(coo_matrix((np.ones(int(ok.sum())), (rows[ok], j[ok])), shape=(n, n)),
                               directed=False)[1]
    lab.flags.writeable = False
    _last_pieces[:] = [(tree, params.components_link, lab)]
    return lab


def nearest_other_piece(v: np.ndarray, piece: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per piece (indexed by ``piece``'s values, -1 left out): its distance to the nearest vertex of
    another piece, and the two vertices (its own, the other's); inf where it is alone."""
    n_p = int(piece.max(initial=-1)) + 1
    gap, own, other = np.full(n_p, np.inf), np.full(n_p, -1, np.int64), np.full(n_p, -1, np.int64)
    used = np.flatnonzero(piece >= 0)
    if n_p < 2:
        return gap, own, other
    tree = cKDTree(v[used])
    k = min(_K, len(used))
    d, j = tree.query(v[used], k=k)
    d, j = d.reshape(len(used), k), used[j.reshape(len(used), k)]
    d = np.where(piece[j] != piece[used][:, None], d, np.inf)
    col = np.argmin(d, axis=1)
    best = d[np.arange(len(used)), col]
    mine_p = piece[used]
    order = np.lexsort((best, mine_p))  # per piece its nearest first
    first = order[np.unique(mine_p[order], return_index=True)[1]]
    p = mine_p[first]
    gap[p], own[p], other[p] = best[first], used[first], j[first, col[first]]
    for q in np.flatnonzero(~np.isfinite(gap)):  # no other piece among any vertex's k nearest
        mine = used[piece[used] == q]
        rest = used[piece[used] != q]
        dd, jj = cKDTree(v[rest]).query(v[mine])
        i = int(np.argmin(dd))
        gap[q], own[q], other[q] = dd[i], mine[i], rest[jj[i]]
    return gap, own, other


def _branch_at(v: int, branches: Branches, curve: CurveSkeleton) -> int:
    b = int(branches.vertex_branch[v])
    if b >= 0:
        return b
    e = np.flatnonzero((curve.edges == v).any(axis=1))  # a junction: the first of its edges' branches
    return int(branches.edge_branch[e[0]]) if len(e) else -1


def find_components(curve: CurveSkeleton, branches: Branches, cloud_tree: cKDTree,
                    params: Params = Params()) -> CurveComponents:
    """The curve's pieces, the cloud pieces they lie in and the pieces beyond one per cloud piece
    (normalized inputs, docs/metrics.md 0; ``cloud_tree``: the diagnostics' KD-tree of the cloud)."""
    nv = curve.n_vertices
    points = sum(k == "point" for k in branches.kind)
    if int(branches.n_components) - points <= 1 or cloud_tree.n == 0:
        return CurveComponents(n_pieces=max(int(branches.n_components) - points, 0),
                               n_cloud_pieces=max(min(int(branches.n_components) - points, 1), 0),
                               vertex_flag=np.zeros(nv, bool))
    n_p, piece = curve_pieces(curve)
    v = np.asarray(curve.vertices, float)
    used = np.flatnonzero(piece >= 0)
    k = min(_VOTERS, cloud_tree.n)
    d, near = cloud_tree.query(v[used], k=k)
    d, near = d.reshape(len(used), k), near.reshape(len(used), k)
    r = d[:, 0]
    cloud_lab = _cloud_pieces(cloud_tree, params)[near]
    # each curve piece's cloud piece: the one most of its vertices' nearest cloud points lie in (a stray
    # point in a tube's hollow, nearer the axis than the surface, is outvoted by the surface's ring)
    pairs, counts = np.unique(np.column_stack([np.repeat(piece[used], k), cloud_lab.ravel()]), axis=0,
                              return_counts=True)
    top = np.lexsort((-counts, pairs[:, 0]))
    first = np.unique(pairs[top, 0], return_index=True)[1]
    home = np.empty(n_p, np.int64)
    home[pairs[top[first], 0]] = pairs[top[first], 1]
    length = np.bincount(piece[curve.edges[:, 0]], weights=curve.edge_lengths(), minlength=n_p)
    # the longest piece of each cloud piece is its skeleton; the others are extra
    by_home = np.lexsort((-length, home))
    keep = by_home[np.r_[True, home[by_home][1:] != home[by_home][:-1]]]
    extra = np.setdiff1d(np.arange(n_p), keep)
    radius = np.zeros(nv)
    radius[used] = r
    # the gaps: per extra piece, to the nearest other piece of the same cloud piece
    gap_r, ends = 0.0, (-1, -1)
    if len(extra):
        gaps, dist = np.full(len(extra), np.nan), np.zeros(len(extra))
        pair = np.zeros((len(extra), 2), np.int64)
        for h in np.unique(home[extra]):
            mine = np.flatnonzero(home == h)
            sub = np.where(np.isin(piece, mine), piece, -1)
            local = np.full(n_p, -1, np.int64)
            local[mine] = np.arange(len(mine))
            sub = np.where(sub >= 0, local[np.maximum(sub, 0)], -1)
            g, own, oth = nearest_other_piece(v, sub)
            at = np.isin(extra, mine)
            lid = local[extra[at]]
            rad = 0.5 * (radius[own[lid]] + radius[oth[lid]])
            gaps[at] = np.where(rad > 0, g[lid] / np.where(rad > 0, rad, 1.0), np.nan)
            dist[at] = g[lid]
            pair[at] = np.column_stack([own[lid], oth[lid]])
        w = int(np.argmax(dist))  # the widest gap, in local radii where they are known
        gap_r = float(gaps[w])
        ends = (_branch_at(int(pair[w, 0]), branches, curve), _branch_at(int(pair[w, 1]), branches, curve))
    vflag = np.isin(piece, extra)
    eb = np.asarray(branches.edge_branch, np.int64)
    extra_branches = np.unique(eb[vflag[curve.edges[:, 0]]]) if len(eb) else np.zeros(0, np.int64)
    return CurveComponents(n_pieces=n_p, n_cloud_pieces=len(keep), extra_branches=extra_branches.astype(np.int64),
                           gap=gap_r, gap_branches=ends, vertex_flag=vflag)
