"""The skeleton's cycles against the shape's tunnels -> ``spurious_cycles``, ``missing_cycles``
(docs/diagnostics.md "Cycles" has the derivation).

The shape X is voxelized (:mod:`.interior`); its tunnels are its first Betti number beta1(X). A
cycle goes around a tunnel when it links a loop outside the shape (Alexander duality), so it is
spurious (shrinkable inside the shape) when it links none. Linking numbers come from the solid angle
Omega_g(p) that cycle g subtends (it changes by 4 pi lk(g, c) once around a loop c): evaluated on a
collar of outside voxels around X' = X plus the voxels near the skeleton, its 4 pi jumps along the
collar's edges, summed around the fundamental loops of a spanning tree, give the matrix K (cycles x
loops) of linking numbers. rank K = the tunnels the cycles go around; taking the basis cycles
shortest first, each whose row of K is in the span of those before is spurious; missing =
beta1(X) - rank K, where beta1(X) counts, once it exceeds rank K, only the firm tunnels
(:func:`.interior.firm_tunnels`: wide, and kept without stray points' voxels and at a stricter inside
share). A cycle partly outside is measured in X' (a cycle through the air around a tunnel still goes
around it; ``outside`` flags its edges).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import breadth_first_order, connected_components, minimum_spanning_tree
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from ..metrics.curve_sampling import CurveSamples
from ..geometry import Checkpoint, no_checkpoint
from ..params import Params
from .trust_warning import TrustWarning
from .branches import Branches, decompose_branches, densify
from .interior import VoxelShape, betti_numbers, firm_tunnels, voxelize_interior

__all__ = ["CycleDefects", "find_cycle_defects", "solid_angle_polygon", "simplify_polygon"]

# collar voxels are at least this many voxel sizes from the skeleton's cycles: along a collar edge of
# one voxel, Omega changes by about 2 / distance < pi, so its 4 pi jumps are read without doubt
_CLEARANCE = 2.0
# collar thickness, in voxels
_COLLAR = 2


@dataclass
class CycleDefects:
    """Cycles of the skeleton against tunnels of the shape.

    n_cycles : the skeleton's cycle rank. shape_tunnels : beta1 of the voxelized shape.
    linked : how many independent tunnels the skeleton's cycles go around (rank K).
    spurious : ids (into ``branches.cycles``) of the basis cycles flagged spurious; missing : the
    count of tunnels no cycle goes around. cycle_linking : per basis cycle, 1 when it goes around
    some tunnel (links a loop outside the shape), 0 when not, -1 when not looked at (the cycles
    after the rank reached the tunnels of the shape with the skeleton are dependent).
    branch_spurious : (B,) bool, the branches of the spurious cycles; vertex_flag (V,), sample_flag
    (S,) or None: on a spurious cycle's branch. voxel_size, grid : the voxelization (normalized
    units); subsampled : always False (every cloud point is binned).
    """

    branches: Branches
    n_cycles: int
    shape_tunnels: int
    linked: int
    spurious: list[int]
    missing: int
    cycle_linking: np.ndarray
    cycle_length: np.ndarray
    branch_spurious: np.ndarray
    vertex_flag: np.ndarray
    sample_flag: np.ndarray | None
    voxel_size: float
    grid: tuple[int, int, int]
    total_length: float
    params: Params = field(default_factory=Params)
    subsampled: bool = False

    @property
    def n_spurious(self) -> int:
        return len(self.spurious)

    def warnings(self) -> list[TrustWarning]:
        out: list[TrustWarning] = []
        if self.n_spurious >= self.params.cycles_warn_spurious:
            share = float(self.branches.length[self.branch_spurious].sum()) / self.total_length if self.total_length > 0 else 0.0
            out.append(TrustWarning(
                "spurious_cycles",
                f"{self.n_spurious} of the curve's {self.n_cycles} cycles go around no tunnel of the shape "
                f"({self.shape_tunnels} tunnels found) and could be shrunk inside it; their branches are "
                f"{share:.1%} of the curve's length",
            ))  # fmt: skip
        if self.missing >= self.params.cycles_warn_missing:
            out.append(TrustWarning(
                "missing_cycles",
                f"the shape has {self.shape_tunnels} tunnels and the curve's {self.n_cycles} cycles go around "
                f"{self.linked}: {self.missing} missing",
            ))  # fmt: skip
        return out

    def to_dict(self) -> dict:
        return {
            "skeleton": self.n_cycles,
            "shape": self.shape_tunnels,
            "linked": self.linked,
            "spurious": self.n_spurious,
            "missing": self.missing,
            "spurious_cycles": [int(i) for i in self.spurious],
            "voxel_size": float(self.voxel_size),
            "grid": [int(g) for g in self.grid],
            "subsampled": bool(self.subsampled),
        }


def solid_angle_triangles(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Signed solid angle of triangles (a, b, c) seen from points p (broadcast), in (-2 pi, 2 pi]
    (Van Oosterom and Strackee 1983)."""
    ra, rb, rc = a - p, b - p, c - p
    la, lb, lc = (np.sqrt(np.einsum("...i,...i->...", r, r)) for r in (ra, rb, rc))
    num = np.einsum("...i,...i->...", ra, np.cross(rb, rc))
    den = (la * lb * lc + np.einsum("...i,...i->...", ra, rb) * lc + np.einsum("...i,...i->...", ra, rc) * lb
           + np.einsum("...i,...i->...", rb, rc) * la)
    return 2.0 * np.arctan2(num, den)


def solid_angle_polygon(p: np.ndarray, polygon: np.ndarray, chunk: int = 8192) -> np.ndarray:
    """Solid angle (mod 4 pi) that the closed polygon subtends at each row of p: the sum over the
    fan of triangles from the polygon's mean (any apex gives the same value mod 4 pi), each by Van
    Oosterom and Strackee's formula, component by component (no (n, m, 3) temporaries)."""
    p = np.asarray(p, dtype=float)
    poly = np.asarray(polygon, dtype=float)
    apex = poly.mean(axis=0)
    nxt = np.roll(poly, -1, axis=0)
    out = np.empty(len(p))
    for s0 in range(0, len(p), chunk):
        q = p[s0:s0 + chunk]
        ax, ay, az = (apex[k] - q[:, k:k + 1] for k in range(3))  # (n, 1)
        la = np.sqrt(ax * ax + ay * ay + az * az)
        bx, by, bz = (poly[None, :, k] - q[:, k:k + 1] for k in range(3))  # (n, m)
        cx, cy, cz = (nxt[None, :, k] - q[:, k:k + 1] for k in range(3))
        lb = np.sqrt(bx * bx + by * by + bz * bz)
        lc = np.sqrt(cx * cx + cy * cy + cz * cz)
        num = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
        den = (la * lb * lc + (ax * bx + ay * by + az * bz) * lc + (ax * cx + ay * cy + az * cz) * lb
               + (bx * cx + by * cy + bz * cz) * la)
        out[s0:s0 + chunk] = 2.0 * np.arctan2(num, den).sum(axis=1)
    return out


def simplify_polygon(polygon: np.ndarray, tol: float) -> np.ndarray:
    """A closed polygon with vertices dropped while every dropped vertex stays within ``tol`` of the
    chord that replaces it (greedy): the cycle moves by at most ``tol``."""
    poly = np.asarray(polygon, dtype=float)
    m = len(poly)
    if m <= 4 or tol <= 0:
        return poly
    keep = [0]
    i = 0
    while i < m - 1:
        j = i + 2
        while j <= m:
            a, b = poly[i], poly[j % m]
            mid = poly[i + 1:j]
            ab = b - a
            L2 = float(ab @ ab)
            t = np.clip(((mid - a) @ ab) / L2, 0, 1) if L2 > 0 else np.zeros(len(mid))
            dev = np.linalg.norm(mid - (a + t[:, None] * ab), axis=1).max()
            if dev > tol:
                break
            j += 1
        i = j - 1
        if i < m:
            keep.append(i)
    keep = sorted(set(k for k in keep if k < m))
    return poly[keep] if len(keep) >= 3 else poly


def _collar_graph(solid: np.ndarray, near: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Collar voxels (outside ``solid``, within ``_COLLAR`` voxels of it, not ``near`` the skeleton)
    as flat indices, and the 6-adjacent pairs among them (rows of positions into that list)."""
    grown = ndimage.binary_dilation(solid, structure=np.ones((3, 3, 3), bool), iterations=_COLLAR)
    collar = grown & ~solid & ~near
    flat = np.flatnonzero(collar.ravel())
    pos = np.full(collar.size, -1, dtype=np.int64)
    pos[flat] = np.arange(len(flat))
    strides = np.array(collar.strides) // collar.itemsize
    pairs = []
    for ax in range(3):
        sl_a = [slice(None)] * 3
        sl_b = [slice(None)] * 3
        sl_a[ax] = slice(None, -1)
        sl_b[ax] = slice(1, None)
        both = collar[tuple(sl_a)] & collar[tuple(sl_b)]
        idx = np.flatnonzero(both.ravel())
        # flat index in the full grid of the lower voxel
        sub = np.unravel_index(idx, both.shape)
        lower = sub[0] * strides[0] + sub[1] * strides[1] + sub[2] * strides[2]
        pairs.append(np.column_stack([pos[lower], pos[lower + strides[ax]]]))
    return flat, np.vstack(pairs) if pairs else np.zeros((0, 2), np.int64)


class _CollarLoops:
    """The fundamental loops of a spanning forest of the collar graph (n nodes, ``edges`` (m, 2)):
    ``linking(jumps)`` sums each cycle's jump cochain (m, c) around every loop (one row per non-tree
    edge), the cycles' linking numbers with the loops."""

    def __init__(self, n: int, edges: np.ndarray):
        self.n = n
        self.edges = edges
        if len(edges) == 0:
            self.non = np.zeros(0, np.int64)
            return
        g = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
        tree = minimum_spanning_tree(g).tocoo()
        t_edges = np.column_stack([tree.row, tree.col])
        # orient the forest from a virtual root tied to one node of every component
        _, lab = connected_components(g, directed=False)
        roots = np.unique(lab, return_index=True)[1]
        rr = np.concatenate([t_edges[:, 0], t_edges[:, 1], np.full(len(roots), n)])
        cc = np.concatenate([t_edges[:, 1], t_edges[:, 0], roots])
        full = coo_matrix((np.ones(len(rr)), (rr, cc)), shape=(n + 1, n + 1)).tocsr()
        _, pred = breadth_first_order(full, n, directed=True, return_predecessors=True)
        pred = pred[:n]
        key = np.minimum(edges[:, 0], edges[:, 1]) * n + np.maximum(edges[:, 0], edges[:, 1])
        srt = np.argsort(key)
        has_parent = (pred >= 0) & (pred < n)
        self.child = np.flatnonzero(has_parent)
        par = pred[self.child]
        kk = np.minimum(par, self.child) * n + np.maximum(par, self.child)
        self.row = srt[np.searchsorted(key[srt], kk)]  # the edge from each child's parent
        self.forward = edges[self.row, 0] == par  # jumps are stored edges[:, 0] -> edges[:, 1]
        self.anc = np.where(has_parent, pred, -1)
        in_tree = np.zeros(len(edges), bool)
        in_tree[self.row] = True
        self.non = np.flatnonzero(~in_tree)

    def linking(self, jumps: np.ndarray) -> np.ndarray:
        c = jumps.shape[1]
        if len(self.non) == 0:
            return np.zeros((0, c), np.int64)
        # potentials m(v) = sum of the jumps from the root down to v, by pointer jumping
        m = np.zeros((self.n, c), np.int64)
        m[self.child] = np.where(self.forward[:, None], jumps[self.row], -jumps[self.row])
        anc = self.anc.copy()
        while np.any(anc >= 0):
            ok = anc >= 0
            m[ok] += m[anc[ok]]
            nxt = np.full(self.n, -1)
            nxt[ok] = anc[anc[ok]]
            anc = nxt
        u, v = self.edges[self.non, 0], self.edges[self.non, 1]
        return m[u] + jumps[self.non] - m[v]


def _add_to_span(basis: list[np.ndarray], row: np.ndarray) -> bool:
    """Add ``row`` to the orthonormal ``basis`` unless it lies in its span; True when added."""
    r = row.astype(float)
    for q in basis:
        r = r - (r @ q) * q
    norm = float(np.linalg.norm(r))
    if norm > 1e-6 * max(1.0, float(np.linalg.norm(row))):
        basis.append(r / norm)
        return True
    return False


def _near_cycles(curve: CurveSkeleton, branches: Branches, vs: VoxelShape, shape: tuple) -> np.ndarray:
    """The voxels whose centres lie within the clearance of the skeleton's cycle edges."""
    h = vs.size
    on_cycle = np.zeros(len(curve.edges), bool)
    for i in range(branches.cycle_rank):
        on_cycle[branches.cycle_edges(i)] = True
    sub = CurveSkeleton(vertices=curve.vertices, edges=curve.edges[on_cycle], vertex_map=curve.vertex_map)
    pts, _ = densify(sub, h / 4)
    ijk = vs.index_of(pts)
    mark = np.zeros(shape, bool)
    mark[ijk[:, 0], ijk[:, 1], ijk[:, 2]] = True
    cand = ndimage.binary_dilation(mark, structure=np.ones((3, 3, 3), bool), iterations=int(np.ceil(_CLEARANCE)) + 1)
    cidx = np.argwhere(cand)
    d, _ = cKDTree(pts).query(vs.centres(cidx), distance_upper_bound=_CLEARANCE * h)
    near = np.zeros(shape, bool)
    close = np.isfinite(d)
    near[cidx[close, 0], cidx[close, 1], cidx[close, 2]] = True
    return near


def _classify(curve: CurveSkeleton, branches: Branches, vs: VoxelShape, solid_x: np.ndarray, near: np.ndarray,
              lengths: np.ndarray, progress: Checkpoint) -> tuple[list[int], np.ndarray, int]:
    """(spurious cycle ids, linking per cycle (1 / 0 / -1 not looked at), rank K): the basis cycles
    shortest first, 16 at a time, until the rank reaches the tunnels of X' (``solid_x``); the rest
    are dependent without a look. A cycle inside a ball that lies in X' is trivial at once (tangles
    of short loops)."""
    nc = branches.cycle_rank
    h = vs.size
    order = np.argsort(lengths, kind="stable")
    linking = np.full(nc, -1, dtype=np.int8)
    spurious: list[int] = []
    basis: list[np.ndarray] = []
    _, tunnels_x, _ = betti_numbers(solid_x)
    done = 0
    if tunnels_x:
        flat, pairs = _collar_graph(solid_x, near)
        loops = _CollarLoops(len(flat), pairs)
        centres = vs.centres(np.column_stack(np.unravel_index(flat, solid_x.shape)))
        nudge = 1e-7 * np.array([np.sqrt(2), np.sqrt(3), np.sqrt(5)])  # keeps the fan's apex off the centres
        depth = ndimage.distance_transform_edt(solid_x)
        while done < nc and len(basis) < tunnels_x:
            ids = order[done:done + 16]
            polys = []
            for i in ids:
                poly = curve.vertices[branches.cycle_polygon(i)]
                centre = (poly.min(axis=0) + poly.max(axis=0)) / 2
                rho = float(np.linalg.norm(poly - centre, axis=1).max())
                inside_ball = depth[tuple(vs.index_of(centre[None])[0])] * h > rho + np.sqrt(3) * h
                polys.append(None if inside_ball else simplify_polygon(poly, 0.5 * h) + nudge)
            look = [j for j, q in enumerate(polys) if q is not None]
            k = np.zeros((len(loops.non), len(ids)), np.int64)
            if look:
                omega = np.empty((len(centres), len(look)))
                for col, j in enumerate(look):
                    omega[:, col] = solid_angle_polygon(centres, polys[j])
                diff = omega[pairs[:, 1]] - omega[pairs[:, 0]]
                jumps = np.rint((np.mod(diff + 2 * np.pi, 4 * np.pi) - 2 * np.pi - diff) / (4 * np.pi)).astype(np.int64)
                k[:, look] = loops.linking(jumps)
            for j, i in enumerate(ids):
                linking[i] = 1 if np.any(k[:, j] != 0) else 0
                if len(basis) < tunnels_x and _add_to_span(basis, k[:, j]):
                    continue
                spurious.append(int(i))
            done += len(ids)
            progress(done / nc)
    spurious.extend(int(i) for i in order[done:])
    return sorted(spurious), linking, len(basis)


def find_cycle_defects(
    cloud: np.ndarray,
    curve: CurveSkeleton,
    *,
    params: Params = Params(),
    branches: Branches | None = None,
    samples: CurveSamples | None = None,
    voxel_shape: VoxelShape | None = None,
    cloud_tree: cKDTree | None = None,
    checkpoint: Checkpoint = no_checkpoint,
) -> CycleDefects:
    """Spurious and missing cycles of ``curve`` in the shape sampled by ``cloud`` (both normalized,
    docs/metrics.md 0). ``branches``, ``voxel_shape`` and ``cloud_tree`` may be passed when computed; ``samples``
    (the curve samples) give the per-sample flags."""
    cloud = np.asarray(cloud, dtype=float)
    if branches is None:
        branches = decompose_branches(curve, cloud=cloud, sample_edge=None if samples is None else samples.edge,
                                      cloud_tree=cloud_tree)
    if voxel_shape is None:
        voxel_shape = voxelize_interior(cloud, voxels=params.cycles_voxels,
                                        min_spacing_factor=params.cycles_voxel_spacing,
                                        inside_share=params.beta_star,
                                        checkpoint=lambda f: checkpoint(0.5 * f))
    solid = voxel_shape.solid()  # shared with the outside test (not written to)
    tunnels = voxel_shape.solid_tunnels()
    checkpoint(0.6)
    nc = branches.cycle_rank
    lengths = np.array([float(sum(branches.length[b] for b, _ in branches.cycles[i])) for i in range(nc)])
    linking = np.full(nc, -1, dtype=np.int8)
    spurious: list[int] = []
    rank = 0
    if nc:
        near = _near_cycles(curve, branches, voxel_shape, solid.shape)
        spurious, linking, rank = _classify(curve, branches, voxel_shape, solid | near, near, lengths,
                                            lambda f: checkpoint(0.7 + 0.25 * f))
    if rank > tunnels:
        # X' gains a tunnel between any two strands of the skeleton that leave X side by side (where a
        # thin part opens the interior): a tunnel that closing X' by a few voxels fills is no tunnel of
        # the shape, and the cycles beyond the rest, the longest first, are spurious
        closed = ndimage.binary_closing(np.pad(solid | near, 2), structure=np.ones((3, 3, 3), bool),
                                        iterations=int(params.cycles_close_voxels))
        most = max(tunnels, betti_numbers(closed)[1])
        kept = [int(i) for i in np.argsort(lengths, kind="stable") if i not in set(spurious)]
        if len(kept) > most:
            spurious = sorted(spurious + kept[most:])
            rank = most
    if tunnels > rank:  # the tunnels no cycle goes around: only the wide ones every interior keeps count
        tunnels = max(rank, firm_tunnels(cloud, voxel_shape, inside_share=params.beta_star,
                                         strict_share=params.cycles_strict_share,
                                         block=params.cycles_support_voxels, min_points=params.cycles_support_points,
                                         share=params.cycles_support_share,
                                         resolved_diameter=params.open_resolved_diameter,
                                         resolved_voxels=params.cycles_resolved_voxels,
                                         checkpoint=lambda f: checkpoint(0.95 + 0.04 * f)))
    missing = max(0, tunnels - rank)
    branch_spurious = np.zeros(len(branches), bool)
    for i in spurious:
        for b, _ in branches.cycles[i]:
            branch_spurious[b] = True
    vb = branches.vertex_branch
    vertex_flag = np.zeros(curve.n_vertices, bool)
    ok = vb >= 0
    vertex_flag[ok] = branch_spurious[vb[ok]]
    for b in np.flatnonzero(branch_spurious):
        vertex_flag[branches.paths[b]] = True
    sample_flag = None
    if branches.sample_branch is not None:
        sample_flag = branch_spurious[branches.sample_branch]
    checkpoint(1.0)
    return CycleDefects(
        branches=branches, n_cycles=nc, shape_tunnels=int(tunnels), linked=int(rank), spurious=spurious,
        missing=int(missing), cycle_linking=linking, cycle_length=lengths, branch_spurious=branch_spurious,
        vertex_flag=vertex_flag, sample_flag=sample_flag, voxel_size=float(voxel_shape.size),
        grid=tuple(int(s) for s in solid.shape), total_length=float(branches.length.sum()), params=params,
    )  # fmt: skip
