"""The local support behind one element's metric value: what the paper's explanatory figures show.

``curve_sample_support``: the slab cut across a curve sample, its cross-section ring and the fitted
ellipse (paper Eq. 11, docs/metrics.md 3; the figure of the two cutting planes). ``skeletal_point_support``:
the k neighbours, their corresponding cloud points and the two centroids of paper Eq. 10.
``direction_map``: the directions from a point that hit a cloud point's ball, on an equal-area
(longitude, z) raster (paper Eq. 5-6, ``rays`` in docs/metrics.md 2); ``paper_triangles``: the triangulated sphere of
the reference tool's estimator. ``skeletal_smoothness_support``: a skeletal point's PCA tangent, its
neighbours' tangents and the angle that sets its value (paper Eq. 13-14); ``curve_vertex_support``: a
degree-2 vertex's two edges and their angle (Eq. 15). Each recomputes one element from scratch with plain numpy (no
shared kernel), so it doubles as an independent check of the engine's value. Inputs are in
normalized units (docs/metrics.md 0), like the metric functions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry import bbox_diagonal
from ..params import Params, k_center_for
from .boundedness import paper_triangles, rays_radius
from .centeredness import cross_section_centeredness, ring_length
from .ellipse_fit import fit_ellipse

__all__ = [
    "SlabSupport",
    "KnnSupport",
    "DirectionMap",
    "curve_sample_support",
    "skeletal_point_support",
    "direction_map",
    "paper_triangles",
    "SmoothnessSupport",
    "skeletal_smoothness_support",
    "curve_vertex_support",
]


@dataclass(frozen=True)
class SlabSupport:
    """A curve sample's cross-section (docs/metrics.md 3), in the plane through p orthogonal to u.

    slab : cloud rows with |u . (x - p)| < alpha / 2.
    flat : (len(slab), 2) those points in the plane's basis (g, h), p at the origin.
    ring : positions in ``slab`` of the ring kept (nearest first).
    ellipse : (centre, semi_axes, angle) fitted to the ring, or None (fewer than 5 points, no fit).
    centre, radius : what the value uses (the ellipse's centre and mean semi-axis, or the fallback).
    value : raw centeredness, NaN where invalid.
    """

    point: np.ndarray
    direction: np.ndarray
    basis: np.ndarray  # (2, 3): g and h
    half_width: float
    slab: np.ndarray
    flat: np.ndarray
    ring: np.ndarray
    ellipse: tuple[np.ndarray, np.ndarray, float] | None
    centre: np.ndarray | None
    radius: float
    value: float


@dataclass(frozen=True)
class KnnSupport:
    """Skeletal point i's neighbourhood in paper Eq. 10: c = max(0, 1 - |m_o - m_s| / M)."""

    index: int
    neighbours: np.ndarray  # skeletal rows, nearest first (ties by row)
    skeletal_centroid: np.ndarray  # m_s
    cloud_centroid: np.ndarray  # m_o
    spread: float  # M: mean distance from m_s to the corresponding cloud points
    value: float


@dataclass(frozen=True)
class DirectionMap:
    """Covered directions on an equal-area raster: rows of equal height in z, bins in longitude."""

    covered: np.ndarray  # (rows, bins) bool; row j centred at z_j, bin k at longitude lon_k
    z: np.ndarray
    longitude: np.ndarray
    radius: float  # h, the balls' radius

    @property
    def fraction(self) -> float:
        """beta of the query: the covered share of the sphere (each cell has the same area)."""
        return float(self.covered.mean()) if self.covered.size else 0.0


def _plane_basis(u: np.ndarray) -> np.ndarray:
    helper = np.zeros(3)
    helper[int(np.argmin(np.abs(u)))] = 1.0
    g = np.cross(u, helper)
    g /= np.linalg.norm(g)
    return np.vstack([g, np.cross(u, g)])


def curve_sample_support(cloud: np.ndarray, point: np.ndarray, direction: np.ndarray, *,
                         params: Params = Params()) -> SlabSupport:
    """Slab, ring and ellipse of one curve sample, exactly as :func:`curve_centeredness` scores it.

    A NaN or zero direction (a joint) has no slab: empty arrays and a NaN value.
    """
    cloud = np.asarray(cloud, dtype=float)
    p = np.asarray(point, dtype=float).reshape(3)
    u = np.asarray(direction, dtype=float).reshape(3)
    half = 0.5 * float(params.slab_factor) * bbox_diagonal(cloud) if len(cloud) else 0.0
    norm = float(np.linalg.norm(u))
    empty = np.empty(0, dtype=np.intp)
    if not (np.isfinite(norm) and norm > 0 and half > 0 and np.all(np.isfinite(p))):
        return SlabSupport(p, u, np.full((2, 3), np.nan), half, empty, np.empty((0, 2)), empty, None,
                           None, float("nan"), float("nan"))
    u = u / norm
    basis = _plane_basis(u)
    rel = cloud - p
    slab = np.flatnonzero(np.abs(rel @ u) < half)
    flat = rel[slab] @ basis.T
    dist = np.hypot(flat[:, 0], flat[:, 1])
    order = np.argsort(dist, kind="stable")
    ring = order[: ring_length(dist[order], float(params.ring_growth))]
    pts = flat[ring]
    ellipse = fit_ellipse(pts) if len(pts) >= 5 else None
    if ellipse is not None:
        centre, radius = ellipse[0], float(ellipse[1].mean())
    elif len(pts) >= 3:
        centre, radius = pts.mean(axis=0), float(np.max(np.linalg.norm(pts, axis=1)))
    else:
        centre, radius = None, float("nan")
    return SlabSupport(p, u, basis, half, slab, flat, ring, ellipse, centre, radius,
                       cross_section_centeredness(pts))


def skeletal_point_support(corresponding_cloud: np.ndarray, skeletal: np.ndarray, index: int, *,
                           params: Params = Params()) -> KnnSupport:
    """The k nearest skeletal points of row ``index`` (ties by row index, as the engine and MATLAB's
    ``knnsearch``), their corresponding cloud rows and both centroids of paper Eq. 10."""
    skel = np.asarray(skeletal, dtype=float)
    cloud = np.asarray(corresponding_cloud, dtype=float)
    if cloud.shape != skel.shape or skel.ndim != 2 or skel.shape[1] != 3:
        raise ValueError(f"skeletal points {skel.shape} and corresponding cloud points {cloud.shape} must match")
    i = int(index)
    if not 0 <= i < len(skel):
        raise IndexError(f"skeletal index {i} out of range 0..{len(skel) - 1}")
    k = min(k_center_for(len(skel), params), len(skel))
    d = np.linalg.norm(skel - skel[i], axis=1)
    near = np.lexsort((np.arange(len(skel)), d))[:k]
    m_s = skel[near].mean(axis=0)
    m_o = cloud[near].mean(axis=0)
    spread = float(np.linalg.norm(cloud[near] - m_s, axis=1).mean())
    value = max(0.0, 1.0 - float(np.linalg.norm(m_o - m_s)) / spread) if spread > 0 else float("nan")
    return KnnSupport(i, near, m_s, m_o, spread, value)


def direction_map(cloud: np.ndarray, query: np.ndarray, *, params: Params = Params(),
                  rows: int | None = None, bins: int | None = None, chunk: int = 65536) -> DirectionMap:
    """Which directions from ``query`` hit a ball of radius h around a cloud point (``rays`` in docs/metrics.md 2).

    The raster is the world frame's (z up), not the engine's rotated one, so its fraction agrees with
    the engine's beta within the raster's sampling error (about 0.004 at 48 rows), not bit for bit.
    Balls that contain the query count for nothing, as in the engine.
    """
    cloud = np.asarray(cloud, dtype=float)
    q = np.asarray(query, dtype=float).reshape(3)
    rows = int(params.rays_rows if rows is None else rows)
    bins = int(2 * rows if bins is None else bins)
    z = -1.0 + (np.arange(rows) + 0.5) * (2.0 / rows)
    lon = -np.pi + (np.arange(bins) + 0.5) * (2.0 * np.pi / bins)
    h = rays_radius(cloud, params.rays_radius_factor)
    marks = np.zeros(rows * (bins + 1) + 1, dtype=np.int64)
    s = np.sqrt(1.0 - z * z)
    step = 2.0 * np.pi / bins
    for lo in range(0, len(cloud), chunk):
        d = cloud[lo:lo + chunk] - q
        dist = np.linalg.norm(d, axis=1)
        keep = dist > h
        d, dist = d[keep], dist[keep]
        if len(d) == 0 or not h > 0:
            continue
        u = d / dist[:, None]
        cos_a = np.sqrt(1.0 - (h / dist) ** 2)
        rho = np.hypot(u[:, 0], u[:, 1])
        phi = np.arctan2(u[:, 1], u[:, 0])
        # direction (s_j cos t, s_j sin t, z_j) is in the cap iff cos(t - phi) >= c
        with np.errstate(divide="ignore", invalid="ignore"):
            c = (cos_a[:, None] - z[None, :] * u[:, 2:3]) / (s[None, :] * rho[:, None])
        c = np.where(np.isnan(c), np.inf, c)  # rho = 0: a pole-centred cap, full or empty by z alone
        pole = rho == 0
        if np.any(pole):
            full_rows = z[None, :] * u[pole, 2:3] >= cos_a[pole, None]
            c[pole] = np.where(full_rows, -np.inf, np.inf)
        pair, row = np.nonzero(c < 1.0)
        half = np.arccos(np.clip(c[pair, row], -1.0, 1.0))
        full = c[pair, row] <= -1.0
        # bins k with centre lon_k in [phi - half, phi + half]
        first = np.ceil((phi[pair] - half + np.pi) / step - 0.5).astype(np.int64)
        last = np.floor((phi[pair] + half + np.pi) / step - 0.5).astype(np.int64)
        first[full], last[full] = 0, bins - 1
        length = np.minimum(last - first + 1, bins)
        ok = length > 0
        first, length, row = first[ok], length[ok], row[ok]
        start = np.mod(first, bins)
        stop = start + length
        wrap = stop > bins
        base = row * (bins + 1)
        # bincount, not np.add.at: ~10x faster, so a viewer thread computing this holds the GIL less
        size = len(marks)
        marks += np.bincount(base + start, minlength=size)
        marks -= np.bincount(base + np.minimum(stop, bins), minlength=size)
        marks += np.bincount(base[wrap], minlength=size)
        marks -= np.bincount(base[wrap] + stop[wrap] - bins, minlength=size)
    covered = np.cumsum(marks[:-1].reshape(rows, bins + 1), axis=1)[:, :bins] > 0
    return DirectionMap(covered=covered, z=z, longitude=lon, radius=h)


@dataclass(frozen=True)
class SmoothnessSupport:
    """What a smoothness value is made of (docs/metrics.md 4): s = |1 - 2 theta / pi| for the angle theta between
    two directions, 1 on a straight line, 0 at a right angle.

    A skeletal point (Eq. 14): ``tangent`` at the point (PCA of its ``tangent_k`` nearest points), the
    ``neighbours`` compared (skeletal rows, one per distinct position among its ``smooth_k`` nearest
    points), their ``neighbour_tangents`` and ``scores``; the value is the smallest score, that of
    neighbour ``worst`` (a position in ``neighbours``). A curve vertex (Eq. 15): ``neighbours`` its two
    adjacent vertices, ``neighbour_tangents`` the unit directions to them, ``tangent`` None, ``worst`` 0.
    ``theta`` is the angle (radians) that sets the value; NaN values (no tangent, not degree 2) keep
    empty or NaN fields.
    """

    point: np.ndarray
    tangent: np.ndarray | None
    neighbours: np.ndarray
    neighbour_tangents: np.ndarray
    scores: np.ndarray
    worst: int
    theta: float
    value: float


def _score(cos: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore"):
        theta = np.arccos(np.clip(cos, -1.0, 1.0))
    return np.abs(1.0 - 2.0 * theta / np.pi)


def _nearest_other(points: np.ndarray, i: int, k: int) -> np.ndarray:
    """The k nearest rows to row i at another position than row i's (nearest first, ties by row)."""
    d = np.linalg.norm(points - points[i], axis=1)
    d[np.all(points == points[i], axis=1)] = np.inf
    order = np.lexsort((np.arange(len(points)), d))
    return order[: min(k, int(np.isfinite(d).sum()))]


def _pca_tangent(points: np.ndarray, i: int, k: int) -> np.ndarray:
    """Prop. 3: the largest eigenvector of (1/k) sum (q_j - q_i)(q_j - q_i)^T over the k nearest points
    at other positions; NaN when there is none."""
    near = _nearest_other(points, i, k)
    if not len(near):
        return np.full(3, np.nan)
    diff = points[near] - points[i]
    cov = diff.T @ diff / k
    return np.linalg.eigh(cov)[1][:, -1]


def skeletal_smoothness_support(skeletal: np.ndarray, index: int, *, params: Params = Params()) -> SmoothnessSupport:
    """Skeletal point ``index``'s tangent, the neighbour positions among its ``smooth_k`` nearest points
    and their tangents, recomputed from scratch with plain numpy (an independent check of
    :func:`skeletal_smoothness`); the value is the smallest |1 - 2 theta / pi| over those neighbours."""
    pts = np.asarray(skeletal, dtype=float)
    i = int(index)
    if not 0 <= i < len(pts):
        raise IndexError(f"skeletal index {i} out of range 0..{len(pts) - 1}")
    kt, ks = int(params.tangent_k), int(params.smooth_k)
    t = _pca_tangent(pts, i, kt)
    near = _nearest_other(pts, i, ks)
    # one neighbour per distinct position (coincident points share one tangent)
    _, first = np.unique(pts[near], axis=0, return_index=True)
    near = near[np.sort(first)]
    tangents = np.array([_pca_tangent(pts, int(j), kt) for j in near]).reshape(-1, 3)
    scores = _score(tangents @ t) if len(near) else np.empty(0)
    finite = np.flatnonzero(np.isfinite(scores))
    if not len(finite) or not np.all(np.isfinite(t)):
        return SmoothnessSupport(pts[i], t, near, tangents, scores, -1, float("nan"), float("nan"))
    worst = int(finite[np.argmin(scores[finite])])
    theta = float(np.arccos(np.clip(tangents[worst] @ t, -1.0, 1.0)))
    return SmoothnessSupport(pts[i], t, near, tangents, scores, worst, theta, float(scores[worst]))


def curve_vertex_support(vertices: np.ndarray, edges: np.ndarray, vertex: int) -> SmoothnessSupport:
    """A curve vertex's two adjacent vertices, the unit directions to them and their angle (Eq. 15);
    a vertex of another degree (or at a neighbour's position) has no angle: NaN."""
    x = np.asarray(vertices, dtype=float)
    e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    v = int(vertex)
    if not 0 <= v < len(x):
        raise IndexError(f"curve vertex {v} out of range 0..{len(x) - 1}")
    nbrs = np.concatenate([e[e[:, 0] == v, 1], e[e[:, 1] == v, 0]])
    dirs = x[nbrs] - x[v]
    lengths = np.linalg.norm(dirs, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        dirs = dirs / lengths[:, None]
    if len(nbrs) != 2 or not np.all(lengths > 0):
        return SmoothnessSupport(x[v], None, nbrs, dirs, np.full(len(nbrs), np.nan), -1, float("nan"), float("nan"))
    cos = float(np.clip(dirs[0] @ dirs[1], -1.0, 1.0))
    value = float(_score(np.array([cos]))[0])
    return SmoothnessSupport(x[v], None, nbrs, dirs, np.array([value, value]), 0, float(np.arccos(cos)), value)
