"""Cases for the diagnostics' calibration (benchmarks/bench_diagnostics_missing.py): generated shapes
with known skeletons, the skeletons a user would score (the true one, cao's, skelscope's) and
controlled defects applied to any of them by geometry (which part of the TRUE skeleton each element
stands for), so a contraction skeleton can be truncated exactly like the true one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from skelcore import shapes
from skelcore.benchmark.skeleton_defects import collapse_points as collapse  # noqa: F401 (the calibration's collapse)
from skelcore.benchmark.skeleton_defects import drop_vertices
from skelcore.curve import CurveSkeleton

SHAPES = {
    "cylinder": lambda n, seed: shapes.cylinder(n, seed=seed),
    "y": lambda n, seed: shapes.y_shape(n, seed=seed),
    "torus": lambda n, seed: shapes.torus(n, seed=seed),
    "t": lambda n, seed: shapes.t_shape(n, seed=seed),
    "genus2": lambda n, seed: shapes.genus2(n, seed=seed),
    "tree3": lambda n, seed: shapes.tree3(n, seed=seed),
}


@dataclass
class Branch:
    """A branch of the true curve: dense points from its free end (or, on a loop, its start), arc length."""

    points: np.ndarray
    s: np.ndarray
    terminal: bool


def true_branches(shape: shapes.Shape, step: float = 0.01) -> list[Branch]:
    """Maximal paths of the true curve between vertices of degree != 2 (a pure cycle: one loop),
    densified; a terminal branch starts at its free end."""
    v, e = shape.curve_vertices, shape.curve_edges
    deg = np.bincount(e.ravel(), minlength=len(v))
    adj: list[list[int]] = [[] for _ in v]
    for a, b in e:
        adj[a].append(b)
        adj[b].append(a)
    seen_edges: set[tuple[int, int]] = set()
    paths = []
    starts = [i for i in range(len(v)) if deg[i] != 2] or [0]
    for s0 in starts:
        for nb in adj[s0]:
            if (min(s0, nb), max(s0, nb)) in seen_edges:
                continue
            path = [s0, nb]
            seen_edges.add((min(s0, nb), max(s0, nb)))
            while deg[path[-1]] == 2 and path[-1] != s0:
                cur, prev = path[-1], path[-2]
                nxt = [x for x in adj[cur] if x != prev and (min(cur, x), max(cur, x)) not in seen_edges]
                if not nxt:
                    break
                seen_edges.add((min(cur, nxt[0]), max(cur, nxt[0])))
                path.append(nxt[0])
            paths.append(path)
    out = []
    for path in paths:
        if deg[path[-1]] == 1 and deg[path[0]] != 1:
            path = path[::-1]
        pts = v[path]
        dense = [pts[0:1]]
        for a, b in zip(pts[:-1], pts[1:]):
            m = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
            dense.append(a + (b - a) * (np.arange(1, m + 1) / m)[:, None])
        d = np.vstack(dense)
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(d, axis=0), axis=1))])
        out.append(Branch(d, s, bool(deg[path[0]] == 1)))
    return out


def defect_branch(name: str, branches: list[Branch]) -> int:
    """The branch a truncation cuts: the stem of the T, a twig of the tree, else the first terminal
    branch (cylinder: the axis from one end; Y: an arm) or, without any, the first loop."""
    if name == "t":  # the thin stem: its free end is the lowest point
        return int(np.argmin([b.points[0, 2] if b.terminal else np.inf for b in branches]))
    if name == "tree3":  # the shortest terminal branch: a twig
        return int(np.argmin([b.s[-1] if b.terminal else np.inf for b in branches]))
    term = [i for i, b in enumerate(branches) if b.terminal]
    return term[0] if term else 0


def cut_mask(points: np.ndarray, branches: list[Branch], k: int, frac: float) -> np.ndarray:
    """Elements standing for the first ``frac`` of branch ``k`` (from its free end; on a loop, an arc
    of that share centred on the point farthest from its start): their nearest true-curve point lies there."""
    all_pts = np.vstack([b.points for b in branches])
    owner = np.concatenate([np.full(len(b.points), i) for i, b in enumerate(branches)])
    arc = np.concatenate([b.s for b in branches])
    _, j = cKDTree(all_pts).query(points)
    b = branches[k]
    length = b.s[-1]
    if b.terminal:
        lo, hi = -1.0, frac * length
    else:
        mid = length / 2
        lo, hi = mid - frac * length / 2, mid + frac * length / 2
    return (owner[j] == k) & (arc[j] >= lo) & (arc[j] <= hi)


def drop_curve_vertices(curve: CurveSkeleton, drop: np.ndarray) -> CurveSkeleton | None:
    if drop.all():
        return None
    return CurveSkeleton.from_raw(*drop_vertices(curve.vertices, curve.edges, drop))


def true_curve_radius(shape: shapes.Shape, branches: list[Branch]) -> list[np.ndarray]:
    """The local radius at every dense point of every true branch: the median local radius
    (``shapes.local_radius``) of the cloud points whose skeletal points are its 10 nearest."""
    lr = shapes.local_radius(shape)
    tree = cKDTree(shape.skeletal)
    out = []
    for b in branches:
        _, j = tree.query(b.points, k=10)
        out.append(np.median(lr[j], axis=1))
    return out


def missed_radii(elements: np.ndarray, branches: list[Branch], radii: list[np.ndarray]) -> float:
    """Ground truth for a contraction skeleton: the length of the true curve farther than two local
    radii from every skeleton element, in local radii (the arc length over the radius, summed)."""
    if len(elements) == 0:
        return float("inf")
    tree = cKDTree(elements)
    total = 0.0
    for b, r in zip(branches, radii):
        d, _ = tree.query(b.points)
        ds = np.diff(b.s, prepend=b.s[0])
        total += float(np.sum((ds / r)[d > 2 * r]))
    return total


def off_centre(elements: np.ndarray, branches: list[Branch], radii: list[np.ndarray]) -> float:
    """How far a skeleton sits from the true curve: the median over its elements of the distance to
    the true curve in the local radius there."""
    pts = np.vstack([b.points for b in branches])
    r = np.concatenate(radii)
    d, j = cKDTree(pts).query(elements)
    return float(np.median(d / r[j]))
