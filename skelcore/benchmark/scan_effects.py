"""Scan effects applied to a uniform surface sample, each at graded levels.

In this order: the density (``n_points``, 1k-200k) and its non-uniformity (Bernoulli thinning of
uniform samples with keep probability ratio^-u, u in [0, 1] along a random direction, so density
varies ``nonuniform``-fold across the shape, ``n_points`` kept); one-sided scans (points visible from
any of 1-3 viewpoints: back faces culled, then a z-buffer whose pixels are 2.5 point spacings wide,
empty pixels filled from their 3 x 3 neighbours, a point kept within half its local radius plus one
pixel of the nearest depth); holes (balls of ``hole_radius`` local radii around random surface
points); cropping (the ``crop`` fraction of the points beyond a plane of random normal); Gaussian
noise of ``noise`` local radii per coordinate; outliers (``outliers`` x the points, uniform in the
bounding box grown by 10 % of its diagonal). Selections keep the sampling density, so a one-sided
scan has fewer points than the full one, as a real scanner's. Everything draws from the one
generator given, in a fixed order: the same seed gives the same cloud.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from scipy.ndimage import minimum_filter
from scipy.spatial import cKDTree

from .surface_sampling import SurfacePoints, SurfaceSampler

__all__ = ["ScanEffects", "Scan", "scan", "visible_from"]


@dataclass(frozen=True)
class ScanEffects:
    """One scan's settings; the defaults are a clean, uniform, all-round scan of 5000 points."""

    n_points: int = 5000
    noise: float = 0.0
    nonuniform: float = 1.0
    views: int = 0
    holes: int = 0
    hole_radius: float = 1.0
    outliers: float = 0.0
    crop: float = 0.0

    def __post_init__(self) -> None:
        if self.n_points < 10:
            raise ValueError("n_points must be at least 10")
        if not (self.noise >= 0 and self.nonuniform >= 1 and self.outliers >= 0 and 0 <= self.crop < 1
                and self.hole_radius > 0 and self.holes >= 0 and 0 <= self.views <= 3):
            raise ValueError(f"bad scan effects {self}")

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass
class Scan:
    """The cloud, each cloud point's local radius (NaN for an outlier), the surface points the cloud
    came from (before noise, outliers excluded, in their own order) and what was done."""

    cloud: np.ndarray
    local_radius: np.ndarray
    surface: SurfacePoints
    crop_plane: tuple[np.ndarray, float] | None = None  # (unit normal g, offset): kept where x . g <= offset
    info: dict[str, Any] = field(default_factory=dict)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _spacing(points: np.ndarray) -> float:
    d, _ = cKDTree(points).query(points, k=2, workers=-1)
    return float(np.median(d[:, 1]))


def visible_from(s: SurfacePoints, eye: np.ndarray, target: np.ndarray, spacing: float) -> np.ndarray:
    """Mask of the points a camera at ``eye`` looking at ``target`` sees (z-buffer, module docstring)."""
    f = _unit(target - eye)
    right = _unit(np.cross(f, [0.0, 0.0, 1.0]) if abs(f[2]) < 0.99 else np.cross(f, [1.0, 0.0, 0.0]))
    up = np.cross(right, f)
    q = s.points - eye
    z = q @ f
    facing = np.einsum("ij,ij->i", s.normals, -q) > 0
    if not facing.any():
        return facing
    x, y = (q @ right) / z, (q @ up) / z
    pix = 2.5 * spacing / float(np.linalg.norm(target - eye))
    ix = np.floor((x - x[facing].min()) / pix).astype(np.int64)
    iy = np.floor((y - y[facing].min()) / pix).astype(np.int64)
    ix = np.clip(ix, 0, None)
    iy = np.clip(iy, 0, None)
    shape = (int(ix[facing].max()) + 1, int(iy[facing].max()) + 1)
    ix, iy = np.minimum(ix, shape[0] - 1), np.minimum(iy, shape[1] - 1)
    zbuf = np.full(shape, np.inf)
    np.minimum.at(zbuf, (ix[facing], iy[facing]), z[facing])
    zbuf = np.where(np.isfinite(zbuf), zbuf, minimum_filter(zbuf, size=3, mode="nearest"))
    tol = 0.5 * s.radius + pix * z
    return facing & (z <= zbuf[ix, iy] + tol)


def _nonuniform(sampler: SurfaceSampler, n: int, ratio: float, rng: np.random.Generator) -> tuple[SurfacePoints, dict]:
    g = _unit(rng.normal(size=3))
    first = sampler.sample(n, rng)
    s = first.points @ g
    lo, hi = float(s.min()), float(s.max())
    parts, have, batch = [], 0, first
    while True:
        u = np.clip((batch.points @ g - lo) / max(hi - lo, 1e-12), 0.0, 1.0)
        keep = rng.uniform(0.0, 1.0, len(batch)) < ratio ** (-u)
        parts.append(batch.take(np.flatnonzero(keep)))
        have += int(keep.sum())
        if have >= n:
            break
        batch = sampler.sample(n, rng)
    return SurfacePoints.concat(parts).take(np.arange(n)), {"density_direction": g.tolist()}


def scan(sampler: SurfaceSampler, effects: ScanEffects, rng: np.random.Generator) -> Scan:
    """Apply ``effects`` to a fresh uniform sample of ``sampler``'s shape (module docstring)."""
    info: dict[str, Any] = {}
    if effects.nonuniform > 1.0:
        surf, extra = _nonuniform(sampler, effects.n_points, effects.nonuniform, rng)
        info.update(extra)
    else:
        surf = sampler.sample(effects.n_points, rng)
    n0 = len(surf)
    if effects.views:
        lo, hi = surf.points.min(axis=0), surf.points.max(axis=0)
        target = (lo + hi) / 2
        dist = 2.5 * float(np.linalg.norm(hi - lo))
        spacing = _spacing(surf.points)
        az0 = rng.uniform(0, 2 * np.pi)
        seen = np.zeros(len(surf), bool)
        eyes = []
        for k in range(effects.views):
            az, el = az0 + 2 * np.pi * k / 3, np.radians(rng.uniform(15.0, 45.0))  # 120 degrees apart
            eye = target + dist * np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
            seen |= visible_from(surf, eye, target, spacing)
            eyes.append(eye.tolist())
        surf = surf.take(np.flatnonzero(seen))
        info["viewpoints"] = eyes
    if effects.holes:
        centres = rng.choice(len(surf), size=min(effects.holes, len(surf)), replace=False)
        radii = effects.hole_radius * surf.radius[centres]
        near = cKDTree(surf.points).query_ball_point(surf.points[centres], radii, workers=-1)
        gone = np.unique(np.concatenate([np.asarray(i, dtype=np.int64) for i in near]))
        surf = surf.take(np.setdiff1d(np.arange(len(surf)), gone))
        info["hole_points_removed"] = int(len(gone))
    crop_plane = None
    if effects.crop > 0:
        g = _unit(rng.normal(size=3))
        s = surf.points @ g
        offset = float(np.quantile(s, 1.0 - effects.crop))
        surf = surf.take(np.flatnonzero(s <= offset))
        crop_plane = (g, offset)
        info["crop_plane"] = {"normal": g.tolist(), "offset": offset}
    info["surface_points"] = len(surf)
    info["kept_fraction"] = len(surf) / n0
    pts = surf.points.copy()
    radius = surf.radius.copy()
    if effects.noise > 0:
        pts += rng.normal(size=pts.shape) * (effects.noise * surf.radius)[:, None]
    if effects.outliers > 0:
        k = int(round(effects.outliers * len(pts)))
        lo, hi = surf.points.min(axis=0), surf.points.max(axis=0)
        grow = 0.1 * float(np.linalg.norm(hi - lo))
        pts = np.vstack([pts, rng.uniform(lo - grow, hi + grow, size=(k, 3))])
        radius = np.concatenate([radius, np.full(k, np.nan)])
        info["outlier_points"] = k
    order = rng.permutation(len(pts))
    return Scan(cloud=pts[order], local_radius=radius[order], surface=surf, crop_plane=crop_plane, info=info)
