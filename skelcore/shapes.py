"""Analytic test shapes with known skeletons: dense uniform surface samples.

Used by the tests (docs/metrics.md 5.6), the benchmarks and ``scripts/make_samples.py``. Each function returns a
``Shape`` with the cloud, the skeletal point set in pointwise correspondence (each surface point
projected onto the true medial curve) and the true curve skeleton as a polyline graph.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Shape:
    """A generated shape and its exact skeletons: ``cloud`` (N, 3) surface samples, ``skeletal`` (N, 3)
    each cloud point projected onto the medial curve (pointwise correspondence, docs/metrics.md 0), and the true
    curve skeleton as ``curve_vertices`` (V, 3) and ``curve_edges`` (E, 2)."""

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


# --- unions of tubes: shapes whose curve skeleton is known exactly (the diagnostics' validation) ---
#
# A shape is a set of branches, each a polyline between two nodes with a constant tube radius; its
# solid is the union of the tubes (points within the radius of the branch) and of a ball at every
# branch end. The medial curve of such a union is the branches themselves, so the curve skeleton and
# each surface point's skeletal point (the curve point it was generated from) are exact.


@dataclass
class _Branch:
    points: np.ndarray  # (m, 3) dense polyline from its start node to its end node
    radius: float
    nodes: tuple[int, int]


def _resample(points: np.ndarray, spacing: float) -> np.ndarray:
    """The polyline re-sampled at about ``spacing`` by arc length, ends kept."""
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    m = max(2, int(np.ceil(s[-1] / spacing)) + 1)
    t = np.linspace(0.0, s[-1], m)
    return np.column_stack([np.interp(t, s, points[:, k]) for k in range(3)])


def _random_perpendicular(tangent: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    g = rng.normal(size=tangent.shape)
    g -= np.sum(g * tangent, axis=1, keepdims=True) * tangent
    return g / np.linalg.norm(g, axis=1, keepdims=True)


def _tube_candidates(b: _Branch, count: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Area-uniform samples of the tube around ``b`` (side only): the area element of a tube of
    radius r around a curve is r (1 - r kappa.u) ds da, so points are accepted with that weight."""
    p = b.points
    seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    tan = np.gradient(p, s, axis=0)
    tan /= np.linalg.norm(tan, axis=1, keepdims=True)
    kappa = np.gradient(tan, s, axis=0)
    q = rng.uniform(0.0, s[-1], count)
    c = np.column_stack([np.interp(q, s, p[:, k]) for k in range(3)])
    t = np.column_stack([np.interp(q, s, tan[:, k]) for k in range(3)])
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    kv = np.column_stack([np.interp(q, s, kappa[:, k]) for k in range(3)])
    u = _random_perpendicular(t, rng)
    w = 1.0 - b.radius * np.sum(kv * u, axis=1)
    wmax = 1.0 + b.radius * float(np.max(np.linalg.norm(kappa, axis=1)))
    keep = rng.uniform(0.0, wmax, count) < w
    return c[keep] + b.radius * u[keep], c[keep]


def _tube_union(
    branches: list[_Branch],
    node_xyz: np.ndarray,
    n: int,
    n_curve_spacing: float,
    rng: np.random.Generator,
) -> Shape:
    """Sample the boundary of the union of the branches' tubes and the balls at their nodes."""
    r_min = min(b.radius for b in branches)
    h = r_min / 8.0
    for b in branches:
        b.points = _resample(b.points, h)
    # balls at the nodes, of the largest radius meeting there
    node_r = np.zeros(len(node_xyz))
    for b in branches:
        for nd in b.nodes:
            node_r[nd] = max(node_r[nd], b.radius)
    # the signed distance to the union: one KD-tree per radius (branches and balls of that radius)
    from scipy.spatial import cKDTree

    by_radius: dict[float, list[np.ndarray]] = {}
    for b in branches:
        by_radius.setdefault(b.radius, []).append(b.points)
    for nd, r in enumerate(node_r):
        by_radius.setdefault(float(r), []).append(node_xyz[nd : nd + 1])
    trees = [(r, cKDTree(np.vstack(ps))) for r, ps in by_radius.items()]

    def outside_others(x: np.ndarray, r_own: np.ndarray) -> np.ndarray:
        phi = np.full(len(x), np.inf)
        for r, tree in trees:
            d, _ = tree.query(x)
            phi = np.minimum(phi, d - r)
        return phi > -1e-3 * r_own

    seg_len = [float(np.sum(np.linalg.norm(np.diff(b.points, axis=0), axis=1))) for b in branches]
    areas = np.array([2 * np.pi * b.radius * L for b, L in zip(branches, seg_len)] + list(4 * np.pi * node_r**2))
    probs = areas / areas.sum()
    clouds, skels = [], []
    got = 0
    while got < n:
        counts = rng.multinomial(int(1.6 * (n - got)) + 64, probs)
        for k, cnt in enumerate(counts):
            if cnt == 0:
                continue
            if k < len(branches):
                x, c = _tube_candidates(branches[k], int(cnt), rng)
                r_own = np.full(len(x), branches[k].radius)
            else:
                nd = k - len(branches)
                v = rng.normal(size=(int(cnt), 3))
                v /= np.linalg.norm(v, axis=1, keepdims=True)
                x = node_xyz[nd] + node_r[nd] * v
                c = np.repeat(node_xyz[nd : nd + 1], len(x), axis=0)
                r_own = np.full(len(x), node_r[nd])
            ok = outside_others(x, r_own)
            clouds.append(x[ok])
            skels.append(c[ok])
            got += int(ok.sum())
    cloud = np.vstack(clouds)
    skel = np.vstack(skels)
    pick = rng.permutation(len(cloud))[:n]
    # the curve: the nodes, then each branch's interior vertices at about n_curve_spacing
    verts = [node_xyz]
    edges = []
    base = len(node_xyz)
    for b in branches:
        inner = _resample(b.points, n_curve_spacing)[1:-1]
        ids = [b.nodes[0], *range(base, base + len(inner)), b.nodes[1]]
        verts.append(inner)
        base += len(inner)
        edges.extend(zip(ids[:-1], ids[1:]))
    return Shape(cloud[pick], skel[pick], np.vstack(verts), np.array(edges, dtype=np.int64))


def t_shape(
    n: int = 6000,
    bar_radius: float = 0.3,
    stem_radius: float = 0.15,
    bar_length: float = 4.0,
    stem_length: float = 2.0,
    *,
    curve_spacing: float = 0.2,
    seed: int | np.random.Generator | None = 0,
) -> Shape:
    """A T with unequal radii: a bar along x (``bar_radius``) and a thinner stem down -z from its
    middle, both with rounded ends. The curve skeleton is the bar's axis (a degree-3 junction at the
    origin) and the stem's axis; its ends are the centres of the end balls."""
    rng = _rng(seed)
    half = bar_length / 2
    nodes = np.array([[-half, 0, 0], [0, 0, 0], [half, 0, 0], [0, 0, -stem_length]], float)
    br = [
        _Branch(nodes[[0, 1]], bar_radius, (0, 1)),
        _Branch(nodes[[1, 2]], bar_radius, (1, 2)),
        _Branch(nodes[[1, 3]], stem_radius, (1, 3)),
    ]
    return _tube_union(br, nodes, n, curve_spacing, rng)


def genus2(
    n: int = 8000,
    radius: float = 0.25,
    width: float = 2.4,
    height: float = 1.0,
    *,
    curve_spacing: float = 0.12,
    seed: int | np.random.Generator | None = 0,
) -> Shape:
    """A thickened figure-eight (genus 2): a tube of ``radius`` around Gerono's lemniscate
    x = width cos t, y = height sin 2t in the xy-plane. The curve skeleton is the two loops, joined at
    the crossing (one vertex of degree 4); its cycle rank is 2, the shape's two tunnels."""
    rng = _rng(seed)
    t1 = np.linspace(-np.pi / 2, np.pi / 2, 800)  # right loop, from the crossing back to it
    t2 = np.linspace(np.pi / 2, 3 * np.pi / 2, 800)  # left loop
    loop = lambda t: np.column_stack([width * np.cos(t), height * np.sin(2 * t), np.zeros_like(t)])  # noqa: E731
    nodes = np.zeros((1, 3))
    p1, p2 = loop(t1), loop(t2)
    p1[[0, -1]] = 0.0
    p2[[0, -1]] = 0.0
    br = [_Branch(p1, radius, (0, 0)), _Branch(p2, radius, (0, 0))]
    return _tube_union(br, nodes, n, curve_spacing, rng)


def tree3(
    n: int = 8000,
    radii: tuple[float, float, float] = (0.22, 0.14, 0.09),
    lengths: tuple[float, float, float] = (2.0, 1.4, 0.9),
    *,
    angle: float = 0.6,
    curve_spacing: float = 0.15,
    seed: int | np.random.Generator | None = 0,
) -> Shape:
    """A tree of three levels: a trunk up z, two branches at +-``angle`` in the xz-plane from its top,
    and two twigs from each branch's end, spread in the plane across it. Radii and lengths per level;
    7 branches, 3 junctions of degree 3, 4 tips and the root."""
    rng = _rng(seed)
    nodes = [np.zeros(3), np.array([0.0, 0.0, lengths[0]])]
    br: list[_Branch] = [_Branch(np.array(nodes[:2]), radii[0], (0, 1))]
    up = np.array([0.0, 0.0, 1.0])
    for s1 in (-1, 1):
        d1 = np.cos(angle) * up + s1 * np.sin(angle) * np.array([1.0, 0.0, 0.0])
        tip1 = nodes[1] + lengths[1] * d1
        nodes.append(tip1)
        j = len(nodes) - 1
        br.append(_Branch(np.array([nodes[1], tip1]), radii[1], (1, j)))
        for s2 in (-1, 1):
            d2 = np.cos(angle) * d1 + s2 * np.sin(angle) * np.array([0.0, 1.0, 0.0])
            tip2 = tip1 + lengths[2] * d2
            nodes.append(tip2)
            br.append(_Branch(np.array([tip1, tip2]), radii[2], (j, len(nodes) - 1)))
    return _tube_union(br, np.array(nodes), n, curve_spacing, rng)


def local_radius(shape: Shape) -> np.ndarray:
    """Per cloud point, the local radius of the shape: the largest distance from a cloud point to its
    skeletal point among the points whose skeletal points lie near its own (a grid of cells of half
    the median radius, the cell and its 26 neighbours). Robust on flat caps, whose points lie closer
    to their skeletal point than the radius."""
    r = np.linalg.norm(shape.cloud - shape.skeletal, axis=1)
    cell = max(float(np.median(r)) / 2, 1e-12)
    key = np.floor((shape.skeletal - shape.skeletal.min(axis=0)) / cell).astype(np.int64) + 1
    dims = key.max(axis=0) + 2
    flat = (key[:, 0] * dims[1] + key[:, 1]) * dims[2] + key[:, 2]
    cells, inv = np.unique(flat, return_inverse=True)
    cell_max = np.zeros(len(cells))
    np.maximum.at(cell_max, inv, r)
    out = np.zeros(len(r))
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for dz in (-1, 0, 1):
                nb = flat + (dx * dims[1] + dy) * dims[2] + dz
                i = np.clip(np.searchsorted(cells, nb), 0, len(cells) - 1)
                hit = cells[i] == nb
                out[hit] = np.maximum(out[hit], cell_max[i[hit]])
    return out


def with_noise(shape: Shape, level: float, *, seed: int | np.random.Generator | None = 0) -> Shape:
    """The shape with Gaussian noise on its cloud: each coordinate gets a normal deviate of standard
    deviation ``level`` x the local radius (``level`` 0.01-0.05 for 1-5 % noise). The skeletal set
    and the curve are the clean shape's."""
    if not level >= 0:
        raise ValueError(f"noise level must be >= 0, got {level}")
    rng = _rng(seed)
    sigma = level * local_radius(shape)
    cloud = shape.cloud + rng.normal(size=shape.cloud.shape) * sigma[:, None]
    return Shape(cloud, shape.skeletal.copy(), shape.curve_vertices.copy(), shape.curve_edges.copy())
def branching_tree(
    n: int = 8000,
    radii: tuple[float, float, float] = (0.25, 0.16, 0.1),
    lengths: tuple[float, float, float] = (2.0, 1.4, 0.8),
    *,
    angle: float = 0.6,
    curve_step: float = 0.2,
    seed: int | np.random.Generator | None = 0,
) -> Shape:
    """The tree of :func:`tree3` (a trunk up z, two branches at +-``angle`` in the xz-plane from its
    top, two twigs from each branch's end), with these radii and lengths and curve vertices about
    ``curve_step`` apart: one tube-union builder for both (kept for its callers' parameter names)."""
    return tree3(n, radii, lengths, angle=angle, curve_spacing=curve_step, seed=seed)
