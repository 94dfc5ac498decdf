"""Analytic test shapes with known skeletons: dense uniform surface samples.

Used by the tests (SPEC 6), the benchmarks and ``scripts/make_samples.py``. Each function returns a
``Shape`` with the cloud, the skeletal point set in pointwise correspondence (each surface point
projected onto the true medial curve) and the true curve skeleton as a polyline graph.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Shape:
    cloud: np.ndarray
    skeletal: np.ndarray
    curve_vertices: np.ndarray
    curve_edges: np.ndarray


def _rng(seed: int | np.random.Generator | None) -> np.random.Generator:
    return seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)


def _path_edges(n: int, closed: bool = False) -> np.ndarray:
    e = np.column_stack([np.arange(n - 1), np.arange(1, n)])
    if closed:
        e = np.vstack([e, [[n - 1, 0]]])
    return e


def cylinder(
    n: int = 4096,
    radius: float = 0.5,
    length: float = 4.0,
    *,
    capped: bool = True,
    n_curve: int = 21,
    seed: int | np.random.Generator | None = 0,
) -> Shape:
    """Closed cylinder along z from 0 to ``length``: side and (if capped) disc caps, area-uniform."""
    rng = _rng(seed)
    side = 2 * np.pi * radius * length
    cap = np.pi * radius**2 if capped else 0.0
    total = side + 2 * cap
    kind = rng.choice(3, size=n, p=[side / total, cap / total, cap / total])
    theta = rng.uniform(0, 2 * np.pi, n)
    z = rng.uniform(0, length, n)
    r = np.full(n, radius)
    on_cap = kind > 0
    r[on_cap] = radius * np.sqrt(rng.uniform(0, 1, on_cap.sum()))
    z[kind == 1] = 0.0
    z[kind == 2] = length
    cloud = np.column_stack([r * np.cos(theta), r * np.sin(theta), z])
    skeletal = np.column_stack([np.zeros(n), np.zeros(n), z])
    verts = np.column_stack([np.zeros(n_curve), np.zeros(n_curve), np.linspace(0, length, n_curve)])
    return Shape(cloud, skeletal, verts, _path_edges(n_curve))


def torus(
    n: int = 4096,
    R: float = 1.0,
    r: float = 0.3,
    *,
    n_curve: int = 32,
    seed: int | np.random.Generator | None = 0,
) -> Shape:
    """Torus around the z axis, area-uniform (rejection on the tube angle); skeleton = the core circle."""
    rng = _rng(seed)
    phis: list[np.ndarray] = []
    count = 0
    while count < n:
        phi = rng.uniform(0, 2 * np.pi, 2 * n)
        keep = rng.uniform(0, R + r, 2 * n) < R + r * np.cos(phi)
        phis.append(phi[keep])
        count += int(keep.sum())
    phi = np.concatenate(phis)[:n]
    theta = rng.uniform(0, 2 * np.pi, n)
    ring = R + r * np.cos(phi)
    cloud = np.column_stack([ring * np.cos(theta), ring * np.sin(theta), r * np.sin(phi)])
    skeletal = np.column_stack([R * np.cos(theta), R * np.sin(theta), np.zeros(n)])
    a = np.linspace(0, 2 * np.pi, n_curve, endpoint=False)
    verts = np.column_stack([R * np.cos(a), R * np.sin(a), np.zeros(n_curve)])
    return Shape(cloud, skeletal, verts, _path_edges(n_curve, closed=True))


def sphere_surface(n: int = 4096, radius: float = 1.0, *, seed: int | np.random.Generator | None = 0) -> np.ndarray:
    """Uniform samples of a sphere's surface centred at the origin."""
    rng = _rng(seed)
    v = rng.normal(size=(n, 3))
    return radius * v / np.linalg.norm(v, axis=1, keepdims=True)


def y_shape(
    n: int = 6000,
    radius: float = 0.25,
    arm: float = 2.0,
    *,
    n_curve_per_arm: int = 11,
    seed: int | np.random.Generator | None = 0,
) -> Shape:
    """Three capped cylinders meeting at the origin in the xy-plane, 120 degrees apart.

    Surface points inside another arm are removed, so the cloud samples the union's boundary.
    The true curve skeleton has one vertex of degree 3 at the origin.
    """
    rng = _rng(seed)
    dirs = np.array([[np.cos(a), np.sin(a), 0.0] for a in (np.pi / 2, np.pi / 2 + 2 * np.pi / 3, np.pi / 2 + 4 * np.pi / 3)])
    clouds, skels = [], []
    per = int(np.ceil(n * 1.3 / 3))
    for d in dirs:
        c = cylinder(per, radius, arm, capped=True, n_curve=2, seed=rng)
        # cylinder is along z; rotate z -> d with an orthonormal frame
        u = np.cross(d, [0.0, 0.0, 1.0])
        u /= np.linalg.norm(u)
        w = np.cross(d, u)
        frame = np.stack([u, w, d])  # rows: images of x, y, z
        clouds.append(c.cloud @ frame)
        skels.append(c.skeletal @ frame)
    cloud = np.vstack(clouds)
    skel = np.vstack(skels)
    # drop points strictly inside another arm (distance to that arm's axis segment < radius)
    inside = np.zeros(len(cloud), bool)
    owner = np.repeat(np.arange(3), per)
    for k, d in enumerate(dirs):
        t = np.clip(cloud @ d, 0, arm)
        dist = np.linalg.norm(cloud - t[:, None] * d, axis=1)
        inside |= (owner != k) & (dist < radius * 0.999)
    cloud, skel = cloud[~inside], skel[~inside]
    pick = rng.permutation(len(cloud))[: min(n, len(cloud))]
    cloud, skel = cloud[pick], skel[pick]
    verts = [np.zeros(3)]
    edges = []
    for d in dirs:
        prev = 0
        for t in np.linspace(arm / (n_curve_per_arm - 1), arm, n_curve_per_arm - 1):
            verts.append(t * d)
            edges.append([prev, len(verts) - 1])
            prev = len(verts) - 1
    return Shape(cloud, skel, np.array(verts), np.array(edges))


def branching_tree(
    n: int = 8000,
    radii: tuple[float, float, float] = (0.25, 0.16, 0.1),
    lengths: tuple[float, float, float] = (2.0, 1.4, 0.8),
    *,
    angle: float = 0.6,
    curve_step: float = 0.2,
    seed: int | np.random.Generator | None = 0,
) -> Shape:
    """A tree of capped cylinders: a trunk up z, two branches at +-``angle`` in the xz-plane from its top,
    two twigs from each branch's end spread across the branch's plane (radii and lengths per level).

    As :func:`y_shape`, the cloud samples the union's boundary (points inside another tube removed),
    each point's skeletal point is its projection onto its own tube's axis, and the curve skeleton is
    the axes (junctions of degree 3 at the branch points), vertices about ``curve_step`` apart.
    """
    rng = _rng(seed)
    up, side, across = np.array([0.0, 0, 1]), np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
    top = lengths[0] * up
    segments = [(np.zeros(3), top, radii[0])]
    for s1 in (-1, 1):
        d1 = np.cos(angle) * up + s1 * np.sin(angle) * side
        tip = top + lengths[1] * d1
        segments.append((top, tip, radii[1]))
        for s2 in (-1, 1):
            d2 = np.cos(angle) * d1 + s2 * np.sin(angle) * across
            segments.append((tip, tip + lengths[2] * d2, radii[2]))
    areas = np.array([2 * np.pi * r * np.linalg.norm(b - a) + 2 * np.pi * r**2 for a, b, r in segments])
    per = np.ceil(1.3 * n * areas / areas.sum()).astype(int)
    clouds, skels, owner = [], [], []
    for k, ((a, b, r), m) in enumerate(zip(segments, per)):
        d = (b - a) / np.linalg.norm(b - a)
        c = cylinder(int(m), r, float(np.linalg.norm(b - a)), capped=True, n_curve=2, seed=rng)
        u = np.cross(d, [0.0, 0.0, 1.0]) if abs(d[2]) < 0.99 else np.cross(d, [1.0, 0.0, 0.0])
        u /= np.linalg.norm(u)
        frame = np.stack([u, np.cross(d, u), d])  # rows: images of x, y, z
        clouds.append(c.cloud @ frame + a)
        skels.append(c.skeletal @ frame + a)
        owner.append(np.full(len(c.cloud), k))
    cloud, skel, owner = np.vstack(clouds), np.vstack(skels), np.concatenate(owner)
    inside = np.zeros(len(cloud), bool)
    for k, (a, b, r) in enumerate(segments):
        length = float(np.linalg.norm(b - a))
        d = (b - a) / length
        t = (cloud - a) @ d
        dist = np.linalg.norm(cloud - a - np.clip(t, 0, length)[:, None] * d, axis=1)
        inside |= (owner != k) & (dist < r * 0.999) & (t > -1e-9) & (t < length + 1e-9)
    cloud, skel = cloud[~inside], skel[~inside]
    pick = rng.permutation(len(cloud))[: min(n, len(cloud))]
    verts: list[np.ndarray] = []
    index: dict[tuple, int] = {}
    edges = []

    def vertex(p: np.ndarray) -> int:
        key = tuple(np.round(p, 9))
        if key not in index:
            index[key] = len(verts)
            verts.append(p)
        return index[key]

    for a, b, _r in segments:
        steps = max(1, int(np.ceil(np.linalg.norm(b - a) / curve_step)))
        ids = [vertex(a + (b - a) * i / steps) for i in range(steps + 1)]
        edges.extend(zip(ids[:-1], ids[1:]))
    return Shape(cloud[pick], skel[pick], np.array(verts), np.array(edges, dtype=np.int64))
