"""A task's world (cloud, reference skeleton, the shape's facts) and the skeleton kinds made from
the reference: the intact one, the injected defects of :mod:`..skeleton_defects` at one level each,
and three kinds for the input checks (another frame, nodes only, a skeletal set without
correspondence)."""

from __future__ import annotations

import functools
import zlib
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ..skeleton_defects import add_chord, add_shortcuts, add_spurs, break_cycle, collapse_points, cut_edges, \
    drop_branches, offset, truncate
from .uncovered import visible_removal

__all__ = ["World", "Made", "world", "make_kind", "nodes_only", "LEVELS"]

#: the one level of each injected defect (docs/validity.md's middle level; collapse its strongest)
LEVELS: dict[str, Any] = {"spurs": (3, 2.0), "shortcut": 1, "chord_cycle": 2.0, "broken_cycle": 2.0,
                          "missing_branch": 1, "truncation": 0.3, "collapse": 0.9, "frame": 100.0, "broken": 2,
                          "offset": 0.8}


@dataclass
class World:
    """The cloud and what the suite knows: the reference (vertices, edges, radius), each cloud point's
    local radius (NaN for a stray point), ``depth(points)`` = how far out of the shape (units, < 0
    inside), the surface's closedness, and for a neuron its per-node facts and ``surface_part(points)``
    (the connected part of its mesh nearest each point: the cloud's true pieces)."""

    cloud: np.ndarray
    local_radius: np.ndarray
    ref: tuple[np.ndarray, np.ndarray, np.ndarray]
    depth: Callable[[np.ndarray], np.ndarray]
    closed: bool
    facts: Any = None
    surface_part: Callable[[np.ndarray], np.ndarray] | None = None


@dataclass
class Made:
    """A skeleton kind: its curve, an optional skeletal set, and how it was made."""

    kind: str
    vertices: np.ndarray
    edges: np.ndarray
    skeletal: np.ndarray | None = None
    level: Any = None


def _shape(name: str, suite_seed: int):
    """The suite's shape, its sampler and exact skeleton: the validity study's, cached there."""
    from ..validity import _shape as validity_shape

    return validity_shape(name, suite_seed)


@functools.lru_cache(maxsize=1)
def _neuron(nid: str):
    from ..neurons import MeshSampler, load_neuron, node_facts

    n = load_neuron(nid)
    r = np.asarray(n.skeleton.radius, float)
    return n, MeshSampler(n.mesh, n.skeleton.vertices, r), node_facts(n)


def _mesh_depth(mesh) -> Callable[[np.ndarray], np.ndarray]:
    from ..neurons import inside_mesh, surface_distance

    def depth(points: np.ndarray) -> np.ndarray:
        points = np.asarray(points, float)
        if not len(points):
            return np.zeros(0)
        d = surface_distance(mesh, points)
        return np.where(inside_mesh(mesh, points), -d, d)
    return depth


def _mesh_parts(mesh) -> Callable[[np.ndarray], np.ndarray]:
    """Each point -> the connected part (shared edges) of ``mesh`` its nearest mesh vertex lies in."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    f = np.asarray(mesh.faces, np.int64)
    n = len(mesh.vertices)
    e = np.vstack([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    _, part = connected_components(coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)), directed=False)
    tree = cKDTree(np.asarray(mesh.vertices, float))
    return lambda points: part[tree.query(np.asarray(points, float).reshape(-1, 3))[1]]


def world(suite: str, shape: str, size: int, condition: str, suite_seed: int) -> World:
    """The cloud of ``shape`` under ``condition`` as ``skelcore bench make`` draws it, and its facts."""
    from ..real_suite import RealCase
    from ..scan_effects import scan
    from ..suite import _case, rng_for
    from ..tubes import signed_distance
    from .grid import CONDITIONS

    effect, level = CONDITIONS[condition]
    if suite == "real":
        neuron, sampler, facts = _neuron(shape)
        case = RealCase(shape, size, effect, level)
        got = scan(sampler, case.effects, rng_for(case.seed(suite_seed)))
        sk = neuron.skeleton
        ref = (sk.vertices, sk.edges, np.asarray(sk.radius, float))
        closed = neuron.mesh.boundary_edges() == 0
        return World(got.cloud, got.local_radius, ref, _mesh_depth(neuron.mesh), closed and effect != "views",
                     facts, _mesh_parts(neuron.mesh))
    bench, sampler, ref = _shape(shape, suite_seed)
    case = _case(shape, effect, level, size)
    got = scan(sampler, case.effects, rng_for(case.seed(suite_seed)))
    return World(got.cloud, got.local_radius, ref, lambda p: signed_distance(bench, p, spacing=0.1),
                 effect != "views")


def nodes_only(v: np.ndarray, e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every chain of degree-2 vertices replaced by one edge between its end nodes (a pure cycle
    keeps three of its vertices): a curve with nothing for smoothness to measure."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = len(v)
    deg = np.bincount(e.ravel(), minlength=n)
    inner = deg == 2
    inner_e = e[inner[e[:, 0]] & inner[e[:, 1]]]
    g = coo_matrix((np.ones(len(inner_e)), (inner_e[:, 0], inner_e[:, 1])), shape=(n, n))
    _, chain = connected_components(g, directed=False)
    out: set[tuple[int, int]] = set()
    for x, y in e[~inner[e[:, 0]] & ~inner[e[:, 1]]]:
        out.add((min(x, y), max(x, y)))
    ends: dict[int, list[int]] = {}
    for x, y in e:
        for a, b in ((x, y), (y, x)):
            if inner[a] and not inner[b]:
                ends.setdefault(int(chain[a]), []).append(int(b))
    for c, nodes in ends.items():
        if len(nodes) == 2:
            out.add((min(nodes), max(nodes)))
    for c in set(chain[inner].tolist()) - set(ends):  # a pure cycle
        ids = np.flatnonzero(inner & (chain == c))
        k = ids[[0, len(ids) // 3, 2 * len(ids) // 3]]
        out.update({(k[0], k[1]), (k[1], k[2]), (k[0], k[2])})
    edges = np.array(sorted(out), np.int64).reshape(-1, 2)
    used = np.unique(edges)
    remap = np.full(n, -1, np.int64)
    remap[used] = np.arange(len(used))
    return v[used], remap[edges]


def make_kind(kind: str, w: World, key: str, suite_seed: int) -> Made | None:
    """Skeleton ``kind`` on world ``w`` (None when the defect does not apply to this shape)."""
    v, e, r = (np.asarray(x) for x in w.ref)
    v, e, r = v.astype(float), e.astype(np.int64), r.astype(float)
    rng = np.random.default_rng(np.random.SeedSequence([suite_seed, zlib.crc32(f"calib/{key}/{kind}".encode())]))
    level = LEVELS.get(kind)
    got: tuple[np.ndarray, np.ndarray] | None
    if kind == "intact":
        got = (v, e)
    elif kind == "spurs":
        got = add_spurs(v, e, r, int(level[0]), float(level[1]), rng)[:2]
    elif kind == "shortcut":
        got = add_shortcuts(v, e, r, int(level), rng, w.depth)
    elif kind == "chord_cycle":
        got = add_chord(v, e, r, float(level), rng)
    elif kind == "broken_cycle":
        got = break_cycle(v, e, r, float(level), rng)
    elif kind == "missing_branch" and w.facts is not None:  # a neuron: a branch its cloud can show missing
        got = visible_removal(w, rng)
    elif kind == "missing_branch":
        got = drop_branches(v, e, int(level), rng)
    elif kind == "truncation":
        got = truncate(v, e, float(level))
    elif kind == "offset":  # every vertex moved off the axis (along_surface)
        got = offset(v, e, r, float(level), rng)
    elif kind == "collapse":
        got = (collapse_points(v, float(level)), e)
    elif kind == "frame":
        got = (v * float(level) + 10.0 * float(level) * np.ptp(v, axis=0), e)
    elif kind == "broken":
        got = cut_edges(v, e, int(level), rng)
    elif kind == "nodes_only":
        got = nodes_only(v, e)
    elif kind == "no_correspondence":
        return Made(kind, v, e, skeletal=v.copy())
    else:
        raise ValueError(f"unknown kind {kind!r}")
    if got is None or len(got[1]) == 0:
        return None
    return Made(kind, np.asarray(got[0], float), np.asarray(got[1], np.int64), level=level)
