"""Tube unions with an exact curve skeleton: the geometry every benchmark family is made of.

A :class:`Tube` is a smooth centre curve c(t), t in [0, 1] (a cubic spline through control points,
periodic when closed), with a radius r(t). A circular tube is a canal surface: the envelope of the
balls B(c(t), r(t)), whose maximal balls are exactly those balls while |dr/ds| < 1 and kappa r < 1
(checked with margins by :func:`check_geometry`), so c is the curve skeleton and r its radius. A
shape is the union of the balls of all its circular tubes (ends and junctions are the end balls),
optionally with one elliptic tube (flattened cross-sections, half-ellipsoid caps; skeleton = the
cross-sections' centres, radius = the minor semi-axis, the largest inscribed ball) or a plate (a thin
disc, where a curve skeleton is ill-posed). :func:`reference_skeleton` samples the centre curves as
a polyline graph (chord error below 0.5 % of the local radius); :func:`signed_distance` measures a
point's distance to the surface, for the tests and the noise statistics.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.spatial import cKDTree

__all__ = ["Tube", "Plate", "BenchShape", "reference_skeleton", "signed_distance", "check_geometry",
           "GeometryError", "ball_centres", "BallUnion"]

_FRAME_SAMPLES = 512
_VERTEX_SPACING = 0.25  # reference polyline: a vertex every 0.25 local radii (chord error < 0.5 % r)


class GeometryError(ValueError):
    """A generated shape breaks the canal conditions or touches itself (the family draws again)."""


@dataclass(frozen=True, eq=False)
class Tube:
    """A branch: control points (K x 3) and radii (K,) joined by cubic splines in chord length.

    ``flatten`` < 1 makes the cross-sections ellipses with semi-axes r(t) and flatten * r(t)
    (only for a shape made of that single tube). ``start`` / ``end`` are node indices of the shape
    (-1 for a closed tube)."""

    points: np.ndarray
    radii: np.ndarray
    closed: bool = False
    flatten: float = 1.0
    start: int = -1
    end: int = -1

    @cached_property
    def _splines(self) -> tuple[CubicSpline, CubicSpline]:
        p = np.asarray(self.points, float)
        r = np.asarray(self.radii, float)
        if self.closed:
            p = np.vstack([p, p[:1]])
            r = np.append(r, r[0])
        chord = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        u = chord / chord[-1]
        bc = "periodic" if self.closed else "not-a-knot"
        if len(p) == 2:
            bc = "natural"
        return CubicSpline(u, p, bc_type=bc), CubicSpline(u, r, bc_type=bc)

    def centre(self, t: np.ndarray, nu: int = 0) -> np.ndarray:
        return self._splines[0](np.asarray(t, float), nu)

    def radius(self, t: np.ndarray, nu: int = 0) -> np.ndarray:
        return self._splines[1](np.asarray(t, float), nu)

    def inscribed_radius(self, t: np.ndarray) -> np.ndarray:
        """Radius of the largest inscribed ball centred on c(t): r for a circular tube, flatten * r else."""
        return self.radius(t) * min(1.0, self.flatten)

    @cached_property
    def _frame_table(self) -> tuple[np.ndarray, np.ndarray]:
        """Rotation-minimizing normals on a fine grid (double reflection, Wang et al. 2008)."""
        t = np.linspace(0.0, 1.0, _FRAME_SAMPLES)
        x = self.centre(t)
        tan = self.tangent(t)
        n = np.empty_like(x)
        a = np.array([1.0, 0.0, 0.0]) if abs(tan[0, 0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        n[0] = np.cross(tan[0], a)
        n[0] /= np.linalg.norm(n[0])
        for i in range(len(t) - 1):  # a recurrence: each normal is the previous one reflected twice
            v1 = x[i + 1] - x[i]
            c1 = v1 @ v1
            rl = n[i] - (2.0 / c1) * (v1 @ n[i]) * v1
            tl = tan[i] - (2.0 / c1) * (v1 @ tan[i]) * v1
            v2 = tan[i + 1] - tl
            c2 = v2 @ v2
            n[i + 1] = rl - (2.0 / c2) * (v2 @ rl) * v2 if c2 > 1e-30 else rl
        return t, n

    def tangent(self, t: np.ndarray) -> np.ndarray:
        d = self.centre(t, 1)
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    def frame(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Unit tangent T, normal N and binormal B at parameters t (N interpolated from the table)."""
        t = np.asarray(t, float)
        tt, nn = self._frame_table
        T = self.tangent(t)
        N = np.stack([np.interp(t, tt, nn[:, k]) for k in range(3)], axis=-1)
        N -= np.sum(N * T, axis=-1, keepdims=True) * T
        N /= np.linalg.norm(N, axis=-1, keepdims=True)
        return T, N, np.cross(T, N)

    def arc_lengths(self, t: np.ndarray) -> np.ndarray:
        """Arc length from t = 0 to each (sorted) t, by the trapezoid rule on a fine grid."""
        grid = np.linspace(0.0, 1.0, 4097)
        speed = np.linalg.norm(self.centre(grid, 1), axis=1)
        s = np.concatenate([[0.0], np.cumsum((speed[1:] + speed[:-1]) / 2 * np.diff(grid))])
        return np.interp(t, grid, s)

    @property
    def length(self) -> float:
        return float(self.arc_lengths(np.array([1.0]))[0])

    def vertex_parameters(self) -> np.ndarray:
        """Parameters of the reference polyline's vertices: a vertex every 0.25 local radii."""
        grid = np.linspace(0.0, 1.0, 4097)
        s = self.arc_lengths(grid)
        r = self.inscribed_radius(grid)
        steps = np.concatenate([[0.0], np.cumsum(np.diff(s) / (_VERTEX_SPACING * np.minimum(r[1:], r[:-1])))])
        n = max(int(np.ceil(steps[-1])), 3 if self.closed else 1)
        return np.interp(np.linspace(0.0, steps[-1], n + 1), steps, grid)


@dataclass(frozen=True)
class Plate:
    """A disc of radius ``radius`` and half thickness ``half_thickness`` in the plane z = 0, centred at
    the origin (its rim is a closed tube of the same shape)."""

    radius: float
    half_thickness: float


@dataclass(frozen=True, eq=False)
class BenchShape:
    """A benchmark shape: nodes (junctions and ends, J x 3), tubes between them, an optional plate.

    ``ill_posed`` says why a curve skeleton is not well defined (None when it is); ``params`` are
    the family's parameters, written to suite.json."""

    name: str
    family: str
    nodes: np.ndarray
    tubes: tuple[Tube, ...]
    plate: Plate | None = None
    ill_posed: str | None = None
    params: dict[str, Any] = field(default_factory=dict)

    @property
    def circular(self) -> tuple[Tube, ...]:
        return tuple(t for t in self.tubes if t.flatten >= 1.0)


def reference_skeleton(shape: BenchShape) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(vertices V x 3, edges E x 2, radius V): each tube's centre sampled every 0.25 local radii,
    tubes joined at their shared nodes; a node's radius is the largest of its tubes' end radii."""
    verts = [np.asarray(shape.nodes, float)]
    rad = [np.zeros(len(shape.nodes))]
    edges = []
    count = len(shape.nodes)
    for tube in shape.tubes:
        t = tube.vertex_parameters()
        r = tube.inscribed_radius(t)
        if tube.closed:
            inner = tube.centre(t[:-1])
            ids = np.arange(count, count + len(inner))
            verts.append(inner)
            rad.append(r[:-1])
            count += len(inner)
            edges.append(np.column_stack([ids, np.roll(ids, -1)]))
            continue
        inner = tube.centre(t[1:-1])
        ids = np.concatenate([[tube.start], np.arange(count, count + len(inner)), [tube.end]])
        verts.append(inner)
        rad.append(r[1:-1])
        count += len(inner)
        edges.append(np.column_stack([ids[:-1], ids[1:]]))
        for node, value in ((tube.start, r[0]), (tube.end, r[-1])):
            rad[0][node] = max(rad[0][node], float(value))
    return np.vstack(verts), np.vstack(edges).astype(np.int64), np.concatenate(rad)


def ball_centres(shape: BenchShape, spacing: float = 0.1) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Centres, radii, tube index and arc length of balls along every circular tube, ``spacing`` x the
    tube's smallest radius apart (their union is inside the shape, within spacing^2 / 8 radii of it)."""
    cs, rs, ids, ss = [], [], [], []
    for k, tube in enumerate(shape.tubes):
        if tube.flatten < 1.0:
            continue
        grid = np.linspace(0.0, 1.0, 1025)
        s = tube.arc_lengths(grid)
        rmin = float(tube.radius(grid).min())
        n = max(int(np.ceil(s[-1] / (spacing * rmin))), 2)
        t = np.interp(np.linspace(0.0, s[-1], n + 1), s, grid)
        cs.append(tube.centre(t))
        rs.append(tube.radius(t))
        ids.append(np.full(len(t), k))
        ss.append(np.linspace(0.0, s[-1], n + 1))
    if not cs:
        return np.empty((0, 3)), np.empty(0), np.empty(0, dtype=np.int64), np.empty(0)
    return np.vstack(cs), np.concatenate(rs), np.concatenate(ids), np.concatenate(ss)


class BallUnion:
    """The union of the balls along a shape's circular tubes (:func:`ball_centres`), queried tube by
    tube: within a tube the radius changes slowly (|dr/ds| <= 0.5), so the ball realizing
    min_i |x - c_i| - r_i is among the nearest ``k`` centres, k covering 2.5 of its largest radii."""

    def __init__(self, shape: "BenchShape", spacing: float) -> None:
        c, r, ids, _ = ball_centres(shape, spacing)
        self.parts = []
        for k in np.unique(ids):
            sel = ids == k
            rk = r[sel]
            reach = int(np.ceil(2.5 * rk.max() / (spacing * rk.min()))) + 4
            self.parts.append((cKDTree(c[sel]), rk, min(reach, int(sel.sum())), float(rk.max())))

    def distance(self, points: np.ndarray, reach: float = 0.0) -> np.ndarray:
        """Signed distance to the union (< 0 inside), exact up to the balls' spacing for points
        within ``reach`` x the largest radius outside a tube; +inf beyond."""
        out = np.full(len(points), np.inf)
        for tree, radii, k, rmax in self.parts:
            bound = rmax * (1.0 + reach)
            d1, _ = tree.query(points, k=1, distance_upper_bound=bound, workers=-1)
            near = np.flatnonzero(np.isfinite(d1))  # most points are far from most tubes
            if len(near) == 0:
                continue
            d, idx = tree.query(points[near], k=k, distance_upper_bound=bound, workers=-1)
            d, idx = d.reshape(len(near), k), idx.reshape(len(near), k)
            ok = np.isfinite(d)
            gap = np.where(ok, d - radii[np.where(ok, idx, 0)], np.inf)
            out[near] = np.minimum(out[near], gap.min(axis=1))
        return out


def _elliptic_distance(tube: Tube, points: np.ndarray) -> np.ndarray:
    """Approximate signed distance to an elliptic tube with half-ellipsoid caps (exact on the cross-
    section ellipse's axes; within a few % of the radius elsewhere, enough for noise statistics)."""
    t = np.linspace(0.0, 1.0, 4097)
    c = tube.centre(t)
    _, near = cKDTree(c).query(points, k=1, workers=-1)
    tq = t[near]
    T, N, B = tube.frame(tq)
    q = points - tube.centre(tq)
    a = tube.radius(tq)
    b = tube.flatten * a
    x, y, z = np.sum(q * N, 1), np.sum(q * B, 1), np.sum(q * T, 1)
    at_end = ((tq == 0.0) & (z < 0)) | ((tq == 1.0) & (z > 0))
    z = np.where(at_end, z, 0.0)
    # distance of (x, y, z) to the ellipsoid (a, b, b) along the ray from the centre, scaled to b
    g = np.sqrt((x / a) ** 2 + (y / b) ** 2 + (z / b) ** 2)
    rho = np.sqrt(x**2 + y**2 + z**2)
    return np.where(g > 0, rho * (1.0 - 1.0 / np.maximum(g, 1e-300)), -b)


def signed_distance(shape: BenchShape, points: np.ndarray, spacing: float = 0.02) -> np.ndarray:
    """Signed distance of ``points`` to the shape's surface (< 0 inside), from balls ``spacing`` radii
    apart along the circular tubes (error <= spacing^2 / 8 radii), the elliptic tube and the plate;
    +inf for points more than two radii away from every tube."""
    points = np.asarray(points, float)
    d = BallUnion(shape, spacing).distance(points, reach=2.0)
    for tube in shape.tubes:
        if tube.flatten < 1.0:
            d = np.minimum(d, _elliptic_distance(tube, points))
    if shape.plate is not None:
        p = shape.plate
        rho = np.hypot(points[:, 0], points[:, 1])
        d = np.minimum(d, np.maximum(np.abs(points[:, 2]) - p.half_thickness, rho - p.radius))
    return d


def check_geometry(shape: BenchShape, *, max_slope: float = 0.5, max_bend: float = 0.5, margin: float = 0.25) -> None:
    """Raise :class:`GeometryError` unless every tube is a regular canal surface (|dr/ds| <= max_slope,
    kappa r <= max_bend) and no two parts of the shape touch except tubes meeting at a node."""
    grid = np.linspace(0.0, 1.0, 2049)
    for k, tube in enumerate(shape.tubes):
        d1, d2 = tube.centre(grid, 1), tube.centre(grid, 2)
        speed = np.linalg.norm(d1, axis=1)
        kappa = np.linalg.norm(np.cross(d1, d2), axis=1) / speed**3
        r = tube.radius(grid)
        if np.any(r <= 0):
            raise GeometryError(f"tube {k}: radius <= 0")
        if np.max(np.abs(tube.radius(grid, 1)) / speed) > max_slope:
            raise GeometryError(f"tube {k}: radius changes too fast")
        if np.max(kappa * r) > max_bend:
            raise GeometryError(f"tube {k}: bends tighter than its radius allows")
    c, r, ids, s = ball_centres(shape, 0.25)
    if len(c) == 0:
        return
    pairs = cKDTree(c).query_pairs(2.0 * float(r.max()) * (1 + margin), output_type="ndarray")
    if len(pairs) == 0:
        return
    i, j = pairs[:, 0], pairs[:, 1]
    dist = np.linalg.norm(c[i] - c[j], axis=1)
    touch = dist < (r[i] + r[j]) + margin * np.minimum(r[i], r[j])
    same = ids[i] == ids[j]
    length = np.array([shape.tubes[k].length for k in range(len(shape.tubes))])
    gap = np.abs(s[i] - s[j])
    if len(shape.tubes):
        gap = np.where(same & np.array([shape.tubes[k].closed for k in ids[i]]), np.minimum(gap, length[ids[i]] - gap), gap)
    near_self = same & (gap <= 2.0 * (r[i] + r[j]))
    near_node = np.zeros(len(i), bool)
    for n_id, node in enumerate(np.asarray(shape.nodes, float)):
        members = [k for k, t in enumerate(shape.tubes) if n_id in (t.start, t.end)]
        if len(members) < 2:
            continue
        reach = 3.0 * max(float(shape.tubes[k].radius(np.array([0.0 if shape.tubes[k].start == n_id else 1.0]))[0])
                          for k in members)
        at = np.isin(ids[i], members) & np.isin(ids[j], members)
        near_node |= at & (np.linalg.norm(c[i] - node, axis=1) < reach) & (np.linalg.norm(c[j] - node, axis=1) < reach)
    bad = touch & ~near_self & ~near_node
    if np.any(bad):
        raise GeometryError(f"{int(bad.sum())} pairs of tube parts touch")
