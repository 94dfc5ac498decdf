"""A curve skeleton cut into branches and a cycle basis (docs/diagnostics.md
"Branches").

A branch is a maximal path whose inner vertices have degree 2, between two "nodes" (vertices of
degree 1, 0 or >= 3); a component with no node is a pure cycle and one branch of its own. The
defects (spurious branches, cycles, leaving the shape) are found and reported per branch, so every
curve vertex, edge and sample gets a branch id. The cycle basis lives on the branch graph (nodes
joined by branches): a minimum-length basis (Horton), so that a short spurious loop is one basis
cycle; its size is the curve's cycle rank E - V + C.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components, depth_first_order
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from ..geometry import Checkpoint, group_min_median_max, kd_tree, no_checkpoint

__all__ = ["Branches", "decompose_branches", "branch_paths", "densify", "JUNCTION"]

#: branch id of a junction vertex (degree >= 3), which lies on several branches
JUNCTION = -1
# the chains of the last few edge sets kept (a repair's round prunes branches of one curve, which its
# evaluation decomposed, once per candidate); keyed by the vertex count and the edges' bytes
_CHAINS_KEPT = 4
_chains_kept: OrderedDict = OrderedDict()
_chains_lock = threading.Lock()


@dataclass(frozen=True)
class Branches:
    """The branches of a curve skeleton (vertex ids are rows of ``curve.vertices``).

    paths : per branch, its vertex ids in order, both ends included (a pure cycle starts and ends at
        its lowest vertex; a branch from a node back to itself, a "loop", starts and ends there).
    kind : per branch, "terminal" (a degree-1 end and a junction), "internal" (two junction ends),
        "loop" (one junction at both ends), "path" (a component that is one path: two degree-1
        ends), "cycle" (a component that is one cycle), "point" (an isolated vertex).
    ends, end_degrees : (B, 2) the end vertices and their degrees.
    length : (B,) summed edge lengths.
    edge_branch : (E,) the branch of each edge; vertex_branch : (V,) the branch of each vertex,
        :data:`JUNCTION` (-1) for a vertex of degree >= 3; sample_branch : the branch of each curve
        sample (None unless ``sample_edge`` was given).
    radius_min, radius_median, radius_max : (B,) the local radius along the branch, i.e. the
        distance from its points (every ``step``) to the nearest cloud point (NaN without a cloud).
    cycles : the cycle basis, each a list of (branch, direction +1 / -1) pairs, branches followed
        along (+1) or against (-1) their path: a minimum-length basis up to 64 cycles (beyond, the
        fundamental cycles of a minimum spanning forest).
    flags : per branch, the defect codes found on it (empty until a diagnostic adds its own).
    """

    paths: list[np.ndarray]
    kind: list[str]
    ends: np.ndarray
    end_degrees: np.ndarray
    length: np.ndarray
    edge_branch: np.ndarray
    vertex_branch: np.ndarray
    sample_branch: np.ndarray | None
    radius_min: np.ndarray
    radius_median: np.ndarray
    radius_max: np.ndarray
    cycles: list[list[tuple[int, int]]]
    n_components: int
    flags: tuple[tuple[str, ...], ...] = field(default=())

    def __post_init__(self) -> None:
        if len(self.flags) != len(self.paths):
            object.__setattr__(self, "flags", tuple(() for _ in self.paths))

    def __len__(self) -> int:
        return len(self.paths)

    @property
    def cycle_rank(self) -> int:
        return len(self.cycles)

    def terminal(self) -> np.ndarray:
        """Ids of the terminal branches (one end of degree 1, the other a junction)."""
        return np.array([i for i, k in enumerate(self.kind) if k == "terminal"], dtype=np.int64)

    def cycle_polygon(self, i: int) -> np.ndarray:
        """The vertex ids of basis cycle ``i`` in order, as a closed polygon (first id not repeated)."""
        out: list[int] = []
        for b, sign in self.cycles[i]:
            path = self.paths[b] if sign > 0 else self.paths[b][::-1]
            out.extend(path[:-1].tolist())
        return np.array(out, dtype=np.int64)

    def cycle_edges(self, i: int) -> np.ndarray:
        """The edge ids of basis cycle ``i``."""
        bs = [b for b, _ in self.cycles[i]]
        return np.flatnonzero(np.isin(self.edge_branch, bs))

    def flagged(self, code: str, ids) -> "Branches":
        """A copy with ``code`` added to the flags of branches ``ids``."""
        ids = set(int(i) for i in np.atleast_1d(ids))
        flags = tuple(f + (code,) if i in ids and code not in f else f for i, f in enumerate(self.flags))
        return replace(self, flags=flags)

    def to_dict(self) -> dict:
        """JSON: one entry per branch and the cycle basis (lengths in the curve's units)."""
        def num(x: float) -> float | None:
            return float(x) if np.isfinite(x) else None

        return {
            "n_branches": len(self),
            "n_components": int(self.n_components),
            "cycle_rank": self.cycle_rank,
            "branches": [
                {
                    "id": i,
                    "kind": self.kind[i],
                    "vertices": [int(v) for v in self.paths[i]],
                    "length": float(self.length[i]),
                    "end_degrees": [int(d) for d in self.end_degrees[i]],
                    "radius": {"min": num(self.radius_min[i]), "median": num(self.radius_median[i]),
                               "max": num(self.radius_max[i])},
                    "flags": list(self.flags[i]),
                }
                for i in range(len(self))
            ],
            "cycles": [[[int(b), int(s)] for b, s in c] for c in self.cycles],
        }


def densify(curve: CurveSkeleton, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Points every <= ``step`` along each edge (both ends included) and the edge of each; an
    isolated vertex is one point with edge -1."""
    v, e = curve.vertices, curve.edges
    deg = curve.degrees()
    iso = np.flatnonzero(deg == 0)
    if len(e) == 0:
        return v[iso].copy(), np.full(len(iso), -1, dtype=np.int64)
    a, b = v[e[:, 0]], v[e[:, 1]]
    n = np.maximum(np.ceil(np.linalg.norm(b - a, axis=1) / step).astype(np.int64), 1) + 1
    edge = np.repeat(np.arange(len(e)), n)
    start = np.concatenate([[0], np.cumsum(n)[:-1]])
    t = (np.arange(len(edge)) - start[edge]) / (n[edge] - 1)
    pts = a[edge] + t[:, None] * (b - a)[edge]
    return np.vstack([pts, v[iso]]), np.concatenate([edge, np.full(len(iso), -1, dtype=np.int64)])


def _chains(curve: CurveSkeleton, deg: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """Vertex paths of the branches and the branch of each edge, without a Python loop over vertices:
    the degree-2 vertices joined by their edges form chains (paths or pure cycles); one depth-first
    walk from a virtual root tied to one end of every chain lists each chain's vertices in order."""
    nv, e = curve.n_vertices, curve.edges
    two = deg == 2
    inner = two[e[:, 0]] & two[e[:, 1]]  # edges between two degree-2 vertices
    ie = e[inner]
    chain_deg = np.bincount(ie.ravel(), minlength=nv)
    g = coo_matrix((np.ones(len(ie)), (ie[:, 0], ie[:, 1])), shape=(nv, nv)).tocsr()
    _, label = connected_components(g, directed=False)
    chain_vertices = np.flatnonzero(two)
    comps = np.unique(label[chain_vertices])
    # a chain is open when some vertex has fewer than 2 chain edges; its start: the lowest such vertex
    open_end = two & (chain_deg < 2)
    start = np.full(nv, nv, dtype=np.int64)  # per component label: start vertex
    np.minimum.at(start, label[open_end], np.flatnonzero(open_end))
    is_cycle = np.zeros(nv, bool)
    cyc_labels = comps[start[comps] == nv]
    is_cycle[cyc_labels] = True
    low = np.full(nv, nv, dtype=np.int64)
    np.minimum.at(low, label[chain_vertices], chain_vertices)
    start[cyc_labels] = low[cyc_labels]
    # cut each pure cycle at its start: drop one of the start's two chain edges
    cut = np.zeros(len(ie), bool)
    if len(cyc_labels):
        s = start[cyc_labels]
        rows = np.flatnonzero(np.isin(ie[:, 0], s) | np.isin(ie[:, 1], s))
        # first edge found per start vertex
        owner = np.where(np.isin(ie[rows, 0], s), ie[rows, 0], ie[rows, 1])
        _, first = np.unique(owner, return_index=True)
        cut[rows[first]] = True
    walk = ie[~cut]
    root = nv
    starts = start[comps]
    rr = np.concatenate([walk[:, 0], walk[:, 1], np.full(len(starts), root)])
    cc = np.concatenate([walk[:, 1], walk[:, 0], starts])
    gg = coo_matrix((np.ones(len(rr)), (rr, cc)), shape=(nv + 1, nv + 1)).tocsr()
    order = depth_first_order(gg, root, directed=True, return_predecessors=False)[1:]
    # the walk lists chain after chain: cut it where the component changes
    lab = label[order]
    cuts = np.flatnonzero(np.diff(lab)) + 1
    pieces = np.split(order, cuts) if len(order) else []

    # node neighbours of each chain end: the edges from a node (degree != 2) to a degree-2 vertex
    node_edge = two[e[:, 0]] ^ two[e[:, 1]]
    ne = e[node_edge]
    ne_two = np.where(two[ne[:, 0]], ne[:, 0], ne[:, 1])
    ne_node = np.where(two[ne[:, 0]], ne[:, 1], ne[:, 0])
    by_two: dict[int, list[int]] = {}
    for t, nd in zip(ne_two.tolist(), ne_node.tolist()):
        by_two.setdefault(t, []).append(nd)
    paths: list[np.ndarray] = []
    for piece in pieces:
        comp = label[piece[0]]
        if is_cycle[comp]:
            paths.append(np.concatenate([piece, piece[:1]]))
            continue
        a_end, b_end = int(piece[0]), int(piece[-1])
        if a_end == b_end:  # one degree-2 vertex between two nodes
            na, nb = by_two[a_end]
        else:
            na, nb = by_two[a_end][0], by_two[b_end][0]
        paths.append(np.concatenate([[na], piece, [nb]]))
    # node-node edges: a branch of one edge each
    nn = e[~two[e[:, 0]] & ~two[e[:, 1]]]
    paths.extend(np.array(p, dtype=np.int64) for p in nn)
    # isolated vertices: a branch of one point
    paths.extend(np.array([v], dtype=np.int64) for v in np.flatnonzero(deg == 0))
    # the branch of every edge: look the edge up by its sorted vertex pair
    edge_branch = np.full(len(e), -1, dtype=np.int64)
    if len(e):
        bid = np.concatenate([np.full(max(len(p) - 1, 0), i) for i, p in enumerate(paths)]).astype(np.int64)
        pa = np.concatenate([p[:-1] for p in paths])
        pb = np.concatenate([p[1:] for p in paths])
        key_path = np.minimum(pa, pb) * nv + np.maximum(pa, pb)
        key_edge = e[:, 0] * nv + e[:, 1]
        srt = np.argsort(key_path)
        pos = np.searchsorted(key_path[srt], key_edge)
        edge_branch = bid[srt[pos]]
    return paths, edge_branch


def branch_paths(curve: CurveSkeleton) -> tuple[list[np.ndarray], np.ndarray]:
    """The branches' vertex paths and the branch of each edge (:func:`decompose_branches`' ``paths``
    and ``edge_branch``), which depend on the edges alone: kept for the last few edge sets (the same
    arrays' copies), so that deleting a branch of a curve just decomposed does not walk it again."""
    edges = np.ascontiguousarray(curve.edges, dtype=np.int64)
    key = (int(curve.n_vertices), edges.shape, edges.tobytes())
    with _chains_lock:
        kept = _chains_kept.get(key)
        if kept is not None:
            _chains_kept.move_to_end(key)
    if kept is None:
        kept = _chains(curve, curve.degrees())
        with _chains_lock:
            _chains_kept[key] = kept
            while len(_chains_kept) > _CHAINS_KEPT:
                _chains_kept.popitem(last=False)
    paths, edge_branch = kept
    return [p.copy() for p in paths], edge_branch.copy()


def _kind(path: np.ndarray, deg: np.ndarray) -> str:
    if len(path) == 1:
        return "point"
    d0, d1 = deg[path[0]], deg[path[-1]]
    if d0 == 2:
        return "cycle"
    if path[0] == path[-1]:
        return "loop"
    if d0 == 1 and d1 == 1:
        return "path"
    if d0 == 1 or d1 == 1:
        return "terminal"
    return "internal"


def _cycle_basis(paths: list[np.ndarray], kinds: list[str], lengths: np.ndarray,
                 max_horton: int = 64, max_horton_nodes: int = 1024) -> list[list[tuple[int, int]]]:
    """A cycle basis of the branch graph (nodes = branch ends, one edge per branch): every pure cycle
    and loop by itself, then a minimum-length basis of the rest (Horton's candidates: for every node
    v and branch x-y, the shortest paths v-x and y-v closed by the branch, taken shortest first while
    independent over GF(2)), on the graph's 2-core (the branches on some cycle: the trees hanging
    off it take part in none). Beyond ``max_horton`` cycles or ``max_horton_nodes`` nodes of the core
    (Horton keeps a nodes x nodes distance table), the fundamental cycles of a minimum spanning forest
    (same count, not the shortest)."""
    cycles: list[list[tuple[int, int]]] = []
    graph_ids: list[int] = []
    for i, k in enumerate(kinds):
        if k in ("cycle", "loop"):
            cycles.append([(i, 1)])
        elif k != "point":
            graph_ids.append(i)
    graph_ids = _two_core(paths, graph_ids)
    if not graph_ids:
        return cycles
    nodes = sorted({int(paths[i][0]) for i in graph_ids} | {int(paths[i][-1]) for i in graph_ids})
    at = {v: j for j, v in enumerate(nodes)}
    a = np.array([at[int(paths[i][0])] for i in graph_ids])
    b = np.array([at[int(paths[i][-1])] for i in graph_ids])
    nn = len(nodes)
    ncomp = connected_components(coo_matrix((np.ones(len(a)), (a, b)), shape=(nn, nn)), directed=False)[0]
    rank = len(graph_ids) - nn + ncomp
    if rank == 0:
        return cycles
    if rank > max_horton or nn > max_horton_nodes:
        return cycles + _fundamental_cycles(paths, graph_ids, lengths)
    from scipy.sparse.csgraph import dijkstra

    w = np.maximum(lengths[graph_ids], 1e-12)
    # the shortest branch between each pair of nodes carries the shortest paths
    best: dict[tuple[int, int], int] = {}
    for j in range(len(graph_ids)):
        key = (min(a[j], b[j]), max(a[j], b[j]))
        if key not in best or w[j] < w[best[key]]:
            best[key] = j
    sel = np.array(sorted(best.values()))
    g = coo_matrix((np.concatenate([w[sel], w[sel]]), (np.concatenate([a[sel], b[sel]]), np.concatenate([b[sel], a[sel]]))),
                   shape=(nn, nn)).tocsr()
    dist, pred = dijkstra(g, directed=False, return_predecessors=True)
    pair_edge = {(int(a[j]), int(b[j])): j for j in sel} | {(int(b[j]), int(a[j])): j for j in sel}
    cands: dict[int, float] = {}
    for v in range(nn):
        # bitset of the branches on the shortest path from v to every node, along the tree
        order = np.argsort(dist[v])
        bits = [0] * nn
        for x in order:
            px = pred[v, x]
            if px >= 0:
                bits[x] = bits[px] | (1 << int(pair_edge[(int(px), int(x))]))
        for j in range(len(graph_ids)):
            x, y = int(a[j]), int(b[j])
            if not (np.isfinite(dist[v, x]) and np.isfinite(dist[v, y])):
                continue
            if bits[x] & bits[y] or (bits[x] | bits[y]) >> j & 1:
                continue  # not a simple cycle through v
            c = bits[x] | bits[y] | (1 << j)
            if c not in cands:
                cands[c] = float(dist[v, x] + dist[v, y] + w[j])
    pivots: dict[int, int] = {}
    chosen: list[int] = []
    for c, _ in sorted(cands.items(), key=lambda kv: kv[1]):
        r = c
        while r:
            top = r.bit_length() - 1
            if top in pivots:
                r ^= pivots[top]
            else:
                pivots[top] = r
                chosen.append(c)
                break
        if len(chosen) == rank:
            break
    if len(chosen) < rank:  # cannot happen (Horton); kept safe
        return cycles + _fundamental_cycles(paths, graph_ids, lengths)
    for c in chosen:
        members = [j for j in range(len(graph_ids)) if c >> j & 1]
        cycles.append(_ordered_cycle(members, a, b, graph_ids))
    return cycles


def _two_core(paths: list[np.ndarray], graph_ids: list[int]) -> list[int]:
    """The branches of ``graph_ids`` on some cycle of the branch graph: those with an end of no other
    branch are dropped until none is left (the order kept)."""
    if not graph_ids:
        return graph_ids
    ends = np.array([[int(paths[i][0]), int(paths[i][-1])] for i in graph_ids])
    _, inv = np.unique(ends, return_inverse=True)
    inv = inv.reshape(-1, 2)
    keep = np.ones(len(graph_ids), bool)
    while True:
        deg = np.bincount(inv[keep].ravel(), minlength=int(inv.max()) + 1)
        drop = keep & ((deg[inv[:, 0]] == 1) | (deg[inv[:, 1]] == 1))
        if not drop.any():
            return [g for g, k in zip(graph_ids, keep) if k]
        keep &= ~drop


def _ordered_cycle(members: list[int], a: np.ndarray, b: np.ndarray, graph_ids: list[int]) -> list[tuple[int, int]]:
    """The branches of a simple cycle (indices into ``graph_ids``) in order, each with its direction."""
    left = set(members[1:])
    first = members[0]
    out = [(graph_ids[first], 1)]
    node, start = int(b[first]), int(a[first])
    while left:
        for j in list(left):
            if int(a[j]) == node:
                out.append((graph_ids[j], 1))
                node = int(b[j])
            elif int(b[j]) == node:
                out.append((graph_ids[j], -1))
                node = int(a[j])
            else:
                continue
            left.discard(j)
            break
        else:  # not one simple cycle: keep the order found
            out.extend((graph_ids[j], 1) for j in left)
            break
    return out


def _fundamental_cycles(paths: list[np.ndarray], graph_ids: list[int], lengths: np.ndarray) -> list[list[tuple[int, int]]]:
    """Fundamental cycles of a minimum spanning forest of the branch graph (by branch length): in a
    geometric graph its tree paths stay local, so most of these cycles are short."""
    from scipy.sparse.csgraph import breadth_first_order, minimum_spanning_tree

    ends = np.array([[int(paths[i][0]), int(paths[i][-1])] for i in graph_ids])
    nodes, inv = np.unique(ends, return_inverse=True)
    inv = inv.reshape(-1, 2)
    nn = len(nodes)
    w = np.maximum(lengths[graph_ids], 1e-12)
    # the shortest branch between two nodes may join the tree; the others close cycles
    order = np.lexsort((w, inv.max(axis=1), inv.min(axis=1)))
    lo, hi = inv.min(axis=1)[order], inv.max(axis=1)[order]
    first = np.ones(len(order), bool)
    first[1:] = (lo[1:] != lo[:-1]) | (hi[1:] != hi[:-1])
    simple = order[first]
    g = coo_matrix((w[simple], (inv[simple, 0], inv[simple, 1])), shape=(nn, nn))
    t = minimum_spanning_tree(g).tocoo()
    tree_pairs = {(min(a, b), max(a, b)) for a, b in zip(t.row.tolist(), t.col.tolist())}
    in_tree = {int(j) for j in simple if (int(inv[j].min()), int(inv[j].max())) in tree_pairs}
    # parents from a breadth-first walk of the forest (a virtual root tied to every component)
    _, lab = connected_components(g, directed=False)
    roots = np.unique(lab, return_index=True)[1]
    tj = np.array(sorted(in_tree), dtype=np.int64)
    rr = np.concatenate([inv[tj, 0], inv[tj, 1], np.full(len(roots), nn)])
    cc = np.concatenate([inv[tj, 1], inv[tj, 0], roots])
    full = coo_matrix((np.ones(len(rr)), (rr, cc)), shape=(nn + 1, nn + 1)).tocsr()
    walk, pred = breadth_first_order(full, nn, directed=True, return_predecessors=True)
    depth = np.zeros(nn + 1, np.int64)
    for x in walk[1:]:
        depth[x] = depth[pred[x]] + 1
    via = {}
    for j in tj.tolist():
        a, b = int(inv[j, 0]), int(inv[j, 1])
        via[(a, b)] = (graph_ids[j], 1)  # walking a -> b follows the path
        via[(b, a)] = (graph_ids[j], -1)
    cycles: list[list[tuple[int, int]]] = []
    for j in range(len(graph_ids)):
        if j in in_tree:
            continue
        a, b = int(inv[j, 0]), int(inv[j, 1])
        # the branch a -> b, then the tree path b -> a through their lowest common ancestor
        up_b: list[tuple[int, int]] = []
        down_a: list[tuple[int, int]] = []
        x, y = b, a
        while depth[x] > depth[y]:
            up_b.append(via[(x, int(pred[x]))])
            x = int(pred[x])
        while depth[y] > depth[x]:
            down_a.append(via[(int(pred[y]), y)])
            y = int(pred[y])
        while x != y:
            up_b.append(via[(x, int(pred[x]))])
            x = int(pred[x])
            down_a.append(via[(int(pred[y]), y)])
            y = int(pred[y])
        cycles.append([(graph_ids[j], 1)] + up_b + down_a[::-1])
    return cycles


def decompose_branches(
    curve: CurveSkeleton,
    *,
    cloud: np.ndarray | None = None,
    sample_edge: np.ndarray | None = None,
    step: float | None = None,
    cloud_tree: cKDTree | None = None,
    checkpoint: Checkpoint = no_checkpoint,
) -> Branches:
    """Cut ``curve`` into branches and give its cycle basis.

    ``cloud`` (same frame as the curve) gives each branch its local radius, the distance from its
    points every ``step`` (default: 1/200 of the curve's length) to the nearest cloud point
    (``cloud_tree``: a KD-tree of it, when built).
    ``sample_edge`` (the edge of each curve sample, ``CurveSamples.edge``) gives each sample the
    branch of its edge. Junction vertices (degree >= 3) get the branch id :data:`JUNCTION`.
    """
    deg = curve.degrees()
    paths, edge_branch = branch_paths(curve)
    checkpoint(0.3)
    kinds = [_kind(p, deg) for p in paths]
    nb = len(paths)
    vertex_branch = np.full(curve.n_vertices, JUNCTION, dtype=np.int64)
    if len(curve.edges):
        # a vertex of degree 1 or 2 lies on exactly one branch: that of any edge at it
        vertex_branch[curve.edges[:, 0]] = edge_branch
        vertex_branch[curve.edges[:, 1]] = edge_branch
    vertex_branch[deg >= 3] = JUNCTION
    for i, p in enumerate(paths):
        if kinds[i] == "point":
            vertex_branch[p[0]] = i
    lengths = np.bincount(edge_branch, weights=curve.edge_lengths(), minlength=nb) if len(edge_branch) else np.zeros(nb)
    ends = np.array([[p[0], p[-1]] for p in paths], dtype=np.int64).reshape(-1, 2)
    end_degrees = deg[ends] if nb else np.zeros((0, 2), dtype=np.int64)
    rmin = np.full(nb, np.nan)
    rmed = np.full(nb, np.nan)
    rmax = np.full(nb, np.nan)
    if cloud is not None and len(cloud) and nb:
        if step is None:
            total = float(lengths.sum())
            step = total / 200 if total > 0 else 1.0
        pts, pe = densify(curve, step)
        pb = np.where(pe >= 0, edge_branch[np.maximum(pe, 0)] if len(edge_branch) else -1, -1)
        iso = pe < 0
        if iso.any():
            pb[iso] = vertex_branch[np.flatnonzero(deg == 0)]
        tree = cloud_tree if cloud_tree is not None else kd_tree(np.asarray(cloud, float))
        r, _ = tree.query(pts)
        checkpoint(0.8)
        rmin, rmed, rmax = group_min_median_max(r, pb, nb)  # per branch its radii's min, median, max
    sample_branch = None
    if sample_edge is not None:
        se = np.asarray(sample_edge, dtype=np.int64)
        sample_branch = edge_branch[se] if len(se) else np.zeros(0, dtype=np.int64)
    n_comp = connected_components(
        coo_matrix((np.ones(len(curve.edges)), (curve.edges[:, 0], curve.edges[:, 1])),
                   shape=(curve.n_vertices, curve.n_vertices)), directed=False)[0]
    checkpoint(1.0)
    return Branches(
        paths=paths, kind=kinds, ends=ends, end_degrees=end_degrees, length=lengths, edge_branch=edge_branch,
        vertex_branch=vertex_branch, sample_branch=sample_branch, radius_min=rmin, radius_median=rmed,
        radius_max=rmax, cycles=_cycle_basis(paths, kinds, lengths), n_components=int(n_comp),
    )  # fmt: skip
