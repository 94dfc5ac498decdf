"""Boundedness beta(q) of skeletal points and curve samples (SPEC 2, paper Def. 5 and Prop. 1).

Two estimators, chosen by ``Params.boundedness_method``:

``rays`` (default, rotation invariant).  Every cloud point p farther than h from q hides the cap of
directions of angular radius asin(h / |p - q|) around (p - q) / |p - q|; beta(q) = area of the union
of the caps / 4 pi, i.e. the fraction of rays from q that hit a ball of radius h around some cloud
point.  h = ``rays_radius_factor`` x median nearest-neighbour spacing of the cloud.

How it is computed, and why (measured on this project's 2-core machine; see benchmarks/):

* The union is rasterised on an equal-area latitude grid (``_rays.CapRaster``): exact longitude
  intervals per row, a difference array and one ``bincount`` per batch.  ``rays_rows = 48`` rows and
  96 longitude bins keep the error within 0.004 of the exact area on every test configuration (dense
  brute-force direction grid, tests/test_boundedness.py); 64 rows halve it for ~40 % more time.  The
  grid is turned by a fixed generic rotation so shape edges never run along its rows.
* All work is vectorised over flat (query, point) pair arrays in float32, a few thousand pairs per
  batch (measured optimum: the batch stays in the CPU cache), batches spread over a thread pool
  (numpy releases the GIL).  Exact duplicate queries (contracted skeletal points coincide by the
  hundreds) and duplicate cloud points (identical caps) are computed once.
* Clouds up to ``rays_lod_points`` points use every (query, point) pair: the estimate is the exact
  union up to the raster error.  Larger clouds use a level-of-detail far field: level L is a fixed
  random subset of N / 4^L points with ball radius 2^L h (the same expected coverage of the surface,
  since point density x ball area is unchanged), used for the points whose caps would be smaller
  than ``rays_lod_angle``; every cap actually rasterised then has angular radius >= that angle, so
  the work per query no longer grows with N.  Near points (distance < h / rays_lod_angle) are always
  exact.  The far field is then right in expectation for randomly sampled surfaces, not pointwise;
  its error against brute force is measured in benchmarks/bench_boundedness.py.

``paper`` (the reference tool's algorithm, SPEC 2): sinusoidal projection of the unit directions,
2-D Delaunay, the seam at lon = +-pi zipped from the free-boundary loop, flat 3-D triangle areas with
the reference tool's drop rule, sum / 4 pi.  One Delaunay per query: slow, kept for comparison with
published numbers.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from scipy.spatial import ConvexHull, Delaunay, QhullError, cKDTree

from ..geometry import Checkpoint, nearest_neighbor_distances, no_checkpoint
from ..params import Params
from ._rays import FRAME, CapRaster

__all__ = ["boundedness", "boundedness_rays", "boundedness_paper", "rays_radius"]

# pairs per kernel call: small enough to stay in cache (measured optimum ~4k), big enough that
# numpy's per-call overhead stays below ~10 %
_PAIRS_PER_CALL = 4096
# pairs per pool task: one checkpoint per finished task, so this bounds their spacing (~10 ms)
_PAIRS_PER_TASK = 65536
# levels of detail stop when a level would have fewer points than this
_LOD_MIN_POINTS = 1024


def boundedness(
    cloud: np.ndarray,
    queries: np.ndarray,
    *,
    params: Params = Params(),
    checkpoint: Checkpoint = no_checkpoint,
) -> np.ndarray:
    """beta(q) for every query row with the estimator ``params.boundedness_method`` (SPEC 2).

    Inputs are in normalized units (SPEC 0).  Returns one value per query row, in [0, 1] for
    ``rays``.  An empty query set gives an empty array; an empty cloud gives zeros.
    """
    if params.boundedness_method == "paper":
        return boundedness_paper(
            cloud,
            queries,
            plane_threshold=params.paper_plane_threshold,
            area_threshold=params.paper_area_threshold,
            checkpoint=checkpoint,
        )
    return boundedness_rays(
        cloud,
        queries,
        radius_factor=params.rays_radius_factor,
        rows=params.rays_rows,
        lod_points=params.rays_lod_points,
        lod_angle=params.rays_lod_angle,
        checkpoint=checkpoint,
    )


def rays_radius(cloud: np.ndarray, radius_factor: float = 2.0) -> float:
    """h = radius_factor x the median nearest-neighbour spacing of the cloud (SPEC 2)."""
    cloud = np.asarray(cloud, dtype=float)
    if len(cloud) < 2:
        return 0.0
    return float(radius_factor * np.median(nearest_neighbor_distances(cloud)))


def _as_points(name: str, points: np.ndarray) -> np.ndarray:
    arr = np.asarray(points, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must be an (N, 3) array, got shape {arr.shape}")
    return arr


def _workers() -> int:
    return max(1, min(2, os.cpu_count() or 1))


def boundedness_rays(
    cloud: np.ndarray,
    queries: np.ndarray,
    *,
    radius_factor: float = 2.0,
    rows: int = 48,
    bins: int | None = None,
    lod_points: int = 16384,
    lod_angle: float = 0.05,
    workers: int | None = None,
    checkpoint: Checkpoint = no_checkpoint,
) -> np.ndarray:
    """Fraction of rays from each query that hit a ball of radius h around a cloud point (SPEC 2).

    Parameters
    ----------
    cloud : (N, 3) original cloud, normalized (SPEC 0).
    queries : (Q, 3) skeletal points or curve samples.
    radius_factor : h = radius_factor x median nearest-neighbour spacing of ``cloud``.
    rows, bins : raster size (``bins`` defaults to 2 x rows: cells about square at the equator).
    lod_points : clouds with more (distinct) points use the level-of-detail far field.
    lod_angle : caps smaller than this (radians) come from the coarser levels.
    workers : threads (default: up to 2).
    checkpoint : called with the fraction done, at least every ~0.1 s; may raise ``Cancelled``.

    Returns
    -------
    (Q,) beta in [0, 1].  A query closer than h to every cloud point gets 0 (no cap counts).

    Examples
    --------
    >>> from skelcore.shapes import sphere_surface
    >>> beta = boundedness_rays(sphere_surface(2000, 0.8), np.array([[0.0, 0, 0], [1.6, 0, 0]]))
    >>> bool(beta[0] > 0.9), bool(0.05 < beta[1] < 0.12)
    (True, True)
    """
    cloud = _as_points("cloud", cloud)
    queries = _as_points("queries", queries)
    if not radius_factor > 0:
        raise ValueError(f"radius_factor must be > 0, got {radius_factor!r}")
    if not lod_angle > 0:
        raise ValueError(f"lod_angle must be > 0, got {lod_angle!r}")
    out = np.zeros(len(queries))
    if len(queries) == 0 or len(cloud) == 0:
        checkpoint(1.0)
        return out
    h = rays_radius(cloud, radius_factor)
    if not h > 0:
        checkpoint(1.0)
        return out
    raster = CapRaster(rows, 2 * rows if bins is None else bins)
    uniq_q, inverse = np.unique(queries, axis=0, return_inverse=True)
    # identical cloud points have identical caps; the union is unchanged without the copies
    pts = np.unique(cloud, axis=0)
    centre = (pts.min(axis=0) + pts.max(axis=0)) / 2.0
    pts_r = ((pts - centre) @ FRAME.T).astype(np.float32)
    q_r = ((uniq_q - centre) @ FRAME.T).astype(np.float32)
    if len(pts_r) > lod_points:
        job = _LodJob(raster, pts_r, q_r, h, lod_angle)
    else:
        job = _DenseJob(raster, pts_r, q_r, h)
    beta = _run(job, len(q_r), workers or _workers(), checkpoint)
    out[:] = beta[inverse.ravel()]
    return out


class _DenseJob:
    """Every (query, cloud point) pair: exact up to the raster error."""

    def __init__(self, raster: CapRaster, pts: np.ndarray, queries: np.ndarray, h: float):
        self.raster = raster
        self.cols = [np.ascontiguousarray(pts[:, k]) for k in range(3)]
        self.queries = queries
        self.h = np.float32(h)
        n = len(pts)
        self.per_call = max(1, _PAIRS_PER_CALL // n)
        self.per_task = max(self.per_call, (_PAIRS_PER_TASK // n) // self.per_call * self.per_call)
        self.qidx = np.repeat(np.arange(self.per_call, dtype=np.int32), n)

    def __call__(self, lo: int, hi: int) -> np.ndarray:
        out = np.empty(hi - lo)
        n = len(self.cols[0])
        for a in range(lo, hi, self.per_call):
            b = min(a + self.per_call, hi)
            q = self.queries[a:b]
            c = b - a
            dx, dy, dz = ((col[None, :] - q[:, k : k + 1]).ravel() for k, col in enumerate(self.cols))
            out[a - lo : b - lo] = self.raster.union_fraction(c, self.qidx[: c * n], dx, dy, dz, self.h)
        return out


class _LodJob:
    """Exact near field plus random-subset levels of detail for the far field (module docstring)."""

    def __init__(self, raster: CapRaster, pts: np.ndarray, queries: np.ndarray, h: float, lod_angle: float):
        self.raster = raster
        self.queries = queries
        order = np.random.default_rng(20240607).permutation(len(pts))
        self.levels: list[tuple[np.ndarray, cKDTree | None, float, float, float]] = []
        inner = 0.0
        level = 0
        while True:
            size = len(pts) // 4**level
            last = size // 4 < _LOD_MIN_POINTS
            sub = pts[order[:size]] if level else pts
            radius = h * 2**level
            outer = np.inf if last else radius / lod_angle
            tree = None if last else cKDTree(sub)
            self.levels.append((sub, tree, radius, inner, outer))
            if last:
                break
            inner = outer
            level += 1
        # per task: roughly _PAIRS_PER_TASK pairs, estimated from the coarsest (dense) level
        self.per_task = max(1, _PAIRS_PER_TASK // (4 * len(self.levels[-1][0]) + 1))

    def _pairs(self, q: np.ndarray):
        """Yield (qidx, dx, dy, dz, h) for one batch of queries, level by level."""
        for sub, tree, radius, inner, outer in self.levels:
            if tree is None:
                qi = np.repeat(np.arange(len(q), dtype=np.int32), len(sub))
                pi = np.tile(np.arange(len(sub)), len(q))
            else:
                found = tree.query_ball_point(q, np.float64(outer), return_sorted=False)
                lens = np.fromiter((len(f) for f in found), dtype=np.int64, count=len(found))
                if lens.sum() == 0:
                    continue
                qi = np.repeat(np.arange(len(q), dtype=np.int32), lens)
                pi = np.concatenate([np.asarray(f, dtype=np.intp) for f in found if f])
            d = sub[pi] - q[qi]
            if inner > 0:
                keep = np.einsum("ij,ij->i", d, d) > np.float32(inner * inner)
                qi, d = qi[keep], d[keep]
            yield qi, d, radius

    def __call__(self, lo: int, hi: int) -> np.ndarray:
        q = self.queries[lo:hi]
        parts = list(self._pairs(q))
        qi = np.concatenate([p[0] for p in parts])
        d = np.concatenate([p[1] for p in parts])
        hh = np.concatenate([np.full(len(p[0]), p[2], dtype=np.float32) for p in parts])
        # kernel calls over runs of queries holding ~_PAIRS_PER_CALL pairs each
        order = np.argsort(qi, kind="stable")
        qi, d, hh = qi[order], d[order], hh[order]
        starts = np.searchsorted(qi, np.arange(len(q) + 1))
        out = np.empty(len(q))
        a = 0
        while a < len(q):
            b = int(np.searchsorted(starts, starts[a] + _PAIRS_PER_CALL, side="right")) - 1
            b = min(max(b, a + 1), len(q))
            s, e = starts[a], starts[b]
            dd = d[s:e]
            out[a:b] = self.raster.union_fraction(
                b - a, qi[s:e] - a, np.ascontiguousarray(dd[:, 0]), np.ascontiguousarray(dd[:, 1]),
                np.ascontiguousarray(dd[:, 2]), hh[s:e],
            )
            a = b
        return out


def _run(job, n_queries: int, workers: int, checkpoint: Checkpoint) -> np.ndarray:
    """Run ``job(lo, hi)`` over task-sized query ranges on a pool; checkpoint after each task."""
    step = job.per_task
    ranges = [(lo, min(lo + step, n_queries)) for lo in range(0, n_queries, step)]
    out = np.empty(n_queries)
    checkpoint(0.0)
    if workers <= 1 or len(ranges) == 1:
        for i, (lo, hi) in enumerate(ranges):
            out[lo:hi] = job(lo, hi)
            checkpoint((i + 1) / len(ranges))
        return out
    pool = ThreadPoolExecutor(max_workers=workers)
    try:
        # keep a short queue so a cancel stops within one task per worker
        pending: list = []
        it = iter(enumerate(ranges))
        for i, (lo, hi) in it:
            pending.append((lo, hi, pool.submit(job, lo, hi)))
            if len(pending) >= 2 * workers:
                break
        done = 0
        while pending:
            lo, hi, fut = pending.pop(0)
            out[lo:hi] = fut.result()
            done += 1
            checkpoint(done / len(ranges))
            nxt = next(it, None)
            if nxt is not None:
                _, (nlo, nhi) = nxt
                pending.append((nlo, nhi, pool.submit(job, nlo, nhi)))
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    return out


# --------------------------------------------------------------------------------------------------
# the reference tool's estimator


def boundedness_paper(
    cloud: np.ndarray,
    queries: np.ndarray,
    *,
    plane_threshold: float = 0.8,
    area_threshold: float = 1e-4,
    checkpoint: Checkpoint = no_checkpoint,
) -> np.ndarray:
    """The reference tool's triangulated-sphere estimator (SPEC 2 ``paper``; paper Sec. 3.2).

    Directions u = (p - q)/|p - q| (cloud points at q itself are skipped) are projected by the
    sinusoidal projection (lon cos lat, lat) and triangulated in 2-D (Delaunay); the free-boundary
    loop is zipped across the seam at lon = +-pi (from its lowest-latitude vertex, always advancing
    the side whose next vertex is lower).  Each triangle counts with the area of the flat 3-D triangle
    between its unit vectors, unless (signed distance from the centre to its plane) < plane_threshold
    and (mean |p - q| of its corners)^2 x area < area_threshold.  beta = sum / (4 pi).  Fewer than 3
    distinct directions give 0.  The sum is not clipped to 1 (as the reference tool).
    """
    cloud = _as_points("cloud", cloud)
    queries = _as_points("queries", queries)
    out = np.zeros(len(queries))
    checkpoint(0.0)
    uniq_q, inverse = np.unique(queries, axis=0, return_inverse=True)
    vals = np.empty(len(uniq_q))
    for i, q in enumerate(uniq_q):
        vals[i] = _paper_one(cloud, q, plane_threshold, area_threshold)
        checkpoint((i + 1) / len(uniq_q))
    if len(queries):
        out[:] = vals[inverse.ravel()]
    return out


def _paper_one(cloud: np.ndarray, q: np.ndarray, plane_threshold: float, area_threshold: float) -> float:
    d = cloud - q
    dist = np.sqrt(np.einsum("ij,ij->i", d, d))
    keep = dist > 0
    d, dist = d[keep], dist[keep]
    if len(d) < 3:
        return 0.0
    u = d / dist[:, None]
    lon = np.arctan2(u[:, 1], u[:, 0])
    lat = np.arctan2(u[:, 2], np.hypot(u[:, 0], u[:, 1]))
    flat = np.column_stack([lon * np.cos(lat), lat])
    try:
        tri = Delaunay(flat)
        hull = ConvexHull(flat).vertices  # the free-boundary loop, counter-clockwise
    except QhullError:
        return 0.0  # all directions on one great circle through the poles, or coincident
    simplices = tri.simplices
    # orient counter-clockwise in the chart (= outward on the sphere: east right, north up)
    a, b, c = flat[simplices[:, 0]], flat[simplices[:, 1]], flat[simplices[:, 2]]
    cw = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) < 0
    simplices[cw] = simplices[cw][:, [0, 2, 1]]
    seam = _zip_seam(hull, lat, lon)
    tris = np.vstack([simplices, seam]) if len(seam) else simplices
    v1, v2, v3 = u[tris[:, 0]], u[tris[:, 1]], u[tris[:, 2]]
    cross = np.cross(v2 - v1, v3 - v1)
    norm = np.linalg.norm(cross, axis=1)
    area = 0.5 * norm
    with np.errstate(invalid="ignore", divide="ignore"):
        plane = np.einsum("ij,ij->i", cross, v1) / norm
    plane = np.where(norm > 0, plane, 1.0)
    mean_dist = dist[tris].mean(axis=1)
    drop = (plane < plane_threshold) & (mean_dist**2 * area < area_threshold)
    return float(area[~drop].sum() / (4.0 * np.pi))


def _zip_seam(loop: np.ndarray, lat: np.ndarray, lon: np.ndarray) -> np.ndarray:
    """Triangles closing the seam: zip the loop's two sides from its lowest to its highest vertex.

    ``loop`` is counter-clockwise, so from the bottom it first climbs the east side (lon near +pi)
    and comes back down the west side (lon near -pi).  Triangles are oriented counter-clockwise in the
    chart unwrapped across the seam (west side shifted by 2 pi), i.e. outward on the sphere.
    """
    k = len(loop)
    if k < 3:
        return np.empty((0, 3), dtype=np.intp)
    bottom = int(np.argmin(lat[loop]))
    top = int(np.argmax(lat[loop]))
    east = loop[np.arange(bottom, bottom + ((top - bottom) % k) + 1) % k]
    west = loop[np.arange(bottom, bottom - ((bottom - top) % k) - 1, -1) % k]
    tris = []
    i = j = 0
    while i < len(east) - 1 or j < len(west) - 1:
        go_east = j >= len(west) - 1 or (i < len(east) - 1 and lat[east[i + 1]] <= lat[west[j + 1]])
        if go_east:
            tris.append((east[i], east[i + 1], west[j]))
            i += 1
        else:
            tris.append((west[j], east[i], west[j + 1]))
            j += 1
    tris_arr = np.array(tris, dtype=np.intp)
    # orient counter-clockwise in the unwrapped chart (x = lon, west side + 2 pi)
    x = np.where(lon < 0, lon + 2 * np.pi, lon)
    p, r, s = tris_arr[:, 0], tris_arr[:, 1], tris_arr[:, 2]
    orient = (x[r] - x[p]) * (lat[s] - lat[p]) - (lat[r] - lat[p]) * (x[s] - x[p])
    flip = orient < 0
    tris_arr[flip] = tris_arr[flip][:, [0, 2, 1]]
    return tris_arr
