"""Uniform samples of a benchmark shape's surface, each with its outward normal and local radius.

The surface of a union is the part of its pieces' surfaces outside every other piece. So every piece
is sampled at the same density (the canal surface of each circular tube, the ball at each tube end,
which also closes the gaps at junctions; the elliptic tube's body and half-ellipsoid caps; the plate's
two faces), points inside the union (balls every 0.1 radii along the tubes, the plate's slab) are
dropped, and a uniform subset of the requested size is kept. A parametric piece p(u, v) is sampled
exactly uniformly by rejection on its area element |p_u x p_v| (central differences), so the points
lie on the exact surface. The local radius is the tube's inscribed radius there (the half thickness
on the plate), the scale of the noise and of the scan effects (:mod:`.scan_effects`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .tubes import BallUnion, BenchShape, Tube

__all__ = ["SurfacePoints", "SurfaceSampler"]

_EPS = 1e-6
_Fn = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class SurfacePoints:
    """Points on the surface (N x 3), outward unit normals (N x 3), local radius (N,)."""

    points: np.ndarray
    normals: np.ndarray
    radius: np.ndarray

    def __len__(self) -> int:
        return len(self.points)

    def take(self, index: np.ndarray) -> "SurfacePoints":
        return SurfacePoints(self.points[index], self.normals[index], self.radius[index])

    @staticmethod
    def concat(parts: list["SurfacePoints"]) -> "SurfacePoints":
        if not parts:
            return SurfacePoints(np.empty((0, 3)), np.empty((0, 3)), np.empty(0))
        return SurfacePoints(np.vstack([p.points for p in parts]), np.vstack([p.normals for p in parts]),
                             np.concatenate([p.radius for p in parts]))


class _Piece:
    """One piece of surface: its area and a uniform sampler."""

    def __init__(self, area: float, draw: Callable[[int, np.random.Generator], SurfacePoints]) -> None:
        self.area = area
        self.draw = draw


def _parametric(fn: _Fn, lo: tuple[float, float], hi: tuple[float, float]) -> _Piece:
    """A piece p(u, v) on [lo, hi]: area by a midpoint rule, samples by rejection on |p_u x p_v|."""
    def jacobian(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        u0, u1 = np.clip(u - _EPS, lo[0], hi[0]), np.clip(u + _EPS, lo[0], hi[0])
        v0, v1 = v - _EPS, v + _EPS
        pu = (fn(u1, v)[0] - fn(u0, v)[0]) / (u1 - u0)[:, None]
        pv = (fn(u, v1)[0] - fn(u, v0)[0]) / (v1 - v0)[:, None]
        return np.linalg.norm(np.cross(pu, pv), axis=1)

    gu = lo[0] + (np.arange(256) + 0.5) / 256 * (hi[0] - lo[0])
    gv = lo[1] + (np.arange(24) + 0.5) / 24 * (hi[1] - lo[1])
    uu, vv = (a.ravel() for a in np.meshgrid(gu, gv, indexing="ij"))
    jac = jacobian(uu, vv)
    mean = float(jac.mean())
    area = mean * (hi[0] - lo[0]) * (hi[1] - lo[1])
    bound = [1.25 * float(jac.max())]

    def draw(n: int, rng: np.random.Generator) -> SurfacePoints:
        parts, have = [], 0
        while have < n:
            m = max(64, int(1.3 * (n - have) * bound[0] / max(mean, 1e-300)))
            u = rng.uniform(lo[0], hi[0], m)
            v = rng.uniform(lo[1], hi[1], m)
            j = jacobian(u, v)
            if j.max() > bound[0]:  # the grid missed a peak: a larger bound, start again
                bound[0] = 1.25 * float(j.max())
                parts, have = [], 0
                continue
            keep = rng.uniform(0.0, bound[0], m) < j
            p, nrm, r = fn(u[keep], v[keep])
            parts.append(SurfacePoints(p, nrm, r))
            have += int(keep.sum())
        return SurfacePoints.concat(parts).take(np.arange(n))

    return _Piece(area, draw)


def _canal(tube: Tube) -> _Piece:
    """Envelope of the balls B(c(t), r(t)): p = c + r (-rho T + sqrt(1 - rho^2)(cos v N + sin v B)),
    rho = dr/ds; its normal is (p - c) / r."""
    def fn(t, v):
        c = tube.centre(t)
        T, N, B = tube.frame(t)
        r = tube.radius(t)
        rho = tube.radius(t, 1) / np.linalg.norm(tube.centre(t, 1), axis=1)
        q = -rho[:, None] * T + np.sqrt(1 - rho**2)[:, None] * (np.cos(v)[:, None] * N + np.sin(v)[:, None] * B)
        return c + r[:, None] * q, q, r
    return _parametric(fn, (0.0, 0.0), (1.0, 2 * np.pi))


def _elliptic(tube: Tube) -> _Piece:
    def fn(t, v):
        c = tube.centre(t)
        T, N, B = tube.frame(t)
        a = tube.radius(t)
        b = tube.flatten * a
        cv, sv = np.cos(v)[:, None], np.sin(v)[:, None]
        p = c + a[:, None] * cv * N + b[:, None] * sv * B
        n = b[:, None] * cv * N + a[:, None] * sv * B
        return p, n / np.linalg.norm(n, axis=1, keepdims=True), b
    return _parametric(fn, (0.0, 0.0), (1.0, 2 * np.pi))


def _cap(tube: Tube, end: int) -> _Piece:
    """Half ellipsoid (semi-axes a, b along N, B and b along the tangent) closing an elliptic tube."""
    t_end = float(end)
    sign = 1.0 if end == 1 else -1.0

    def fn(phi, v):
        t = np.full(len(phi), t_end)
        c = tube.centre(t)
        T, N, B = tube.frame(t)
        a = tube.radius(t)
        b = tube.flatten * a
        x, y, z = a * np.sin(phi) * np.cos(v), b * np.sin(phi) * np.sin(v), b * np.cos(phi)
        p = c + x[:, None] * N + y[:, None] * B + sign * z[:, None] * T
        n = (x / a**2)[:, None] * N + (y / b**2)[:, None] * B + sign * (z / b**2)[:, None] * T
        return p, n / np.linalg.norm(n, axis=1, keepdims=True), b
    return _parametric(fn, (0.0, 0.0), (np.pi / 2, 2 * np.pi))


def _sphere(centre: np.ndarray, r: float) -> _Piece:
    def draw(n: int, rng: np.random.Generator) -> SurfacePoints:
        q = rng.normal(size=(n, 3))
        q /= np.linalg.norm(q, axis=1, keepdims=True)
        return SurfacePoints(centre + r * q, q, np.full(n, r))
    return _Piece(4 * np.pi * r * r, draw)


def _disc(radius: float, z: float, half_thickness: float) -> _Piece:
    def draw(n: int, rng: np.random.Generator) -> SurfacePoints:
        rho = radius * np.sqrt(rng.uniform(0, 1, n))
        a = rng.uniform(0, 2 * np.pi, n)
        p = np.column_stack([rho * np.cos(a), rho * np.sin(a), np.full(n, z)])
        nrm = np.zeros((n, 3))
        nrm[:, 2] = np.sign(z)
        return SurfacePoints(p, nrm, np.full(n, half_thickness))
    return _Piece(np.pi * radius * radius, draw)


class SurfaceSampler:
    """Uniform samples of ``shape``'s surface: ``sample(n, rng)`` returns exactly n points."""

    def __init__(self, shape: BenchShape) -> None:
        self.shape = shape
        pieces: list[_Piece] = []
        ends: dict[tuple, float] = {}
        for tube in shape.tubes:
            if tube.flatten < 1.0:
                pieces += [_elliptic(tube), _cap(tube, 0), _cap(tube, 1)]
                continue
            pieces.append(_canal(tube))
            if not tube.closed:
                for node, t in ((tube.start, 0.0), (tube.end, 1.0)):
                    r = float(tube.radius(np.array([t]))[0])
                    ends.setdefault((node, round(r, 12)), r)
        for (node, _), r in sorted(ends.items()):
            pieces.append(_sphere(np.asarray(shape.nodes[node], float), r))
        if shape.plate is not None:
            h = shape.plate.half_thickness
            pieces += [_disc(shape.plate.radius, h, h), _disc(shape.plate.radius, -h, h)]
        self.pieces = pieces
        self.area = float(sum(p.area for p in pieces))
        self._balls = BallUnion(shape, 0.1)
        scale = float(np.max(np.ptp(shape.nodes, axis=0))) if len(shape.nodes) > 1 else 1.0
        self._tol = 1e-9 * max(scale, 1.0)

    def _outside(self, pts: np.ndarray) -> np.ndarray:
        keep = self._balls.distance(pts) > -self._tol
        if self.shape.plate is not None:
            p = self.shape.plate
            inside = (np.abs(pts[:, 2]) < p.half_thickness - self._tol) & (np.hypot(pts[:, 0], pts[:, 1]) < p.radius)
            keep &= ~inside
        return keep

    def sample(self, n: int, rng: np.random.Generator) -> SurfacePoints:
        """Exactly ``n`` points, uniform on the surface of the union, in random order."""
        areas = np.array([p.area for p in self.pieces])
        got: list[SurfacePoints] = []
        have, kept = 0, 0.8
        while have < n:
            m = int(np.ceil((n - have) / kept * 1.1)) + 16
            counts = rng.multinomial(m, areas / areas.sum())
            raw = SurfacePoints.concat([p.draw(int(k), rng) for p, k in zip(self.pieces, counts) if k])
            keep = self._outside(raw.points)
            kept = max(0.05, float(keep.mean()))
            got.append(raw.take(np.flatnonzero(keep)))
            have += int(keep.sum())
        pts = SurfacePoints.concat(got)
        return pts.take(rng.choice(len(pts), size=n, replace=False))
