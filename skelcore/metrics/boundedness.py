"""Boundedness beta(q) of skeletal points and curve samples (paper Sec. 2.2, Eqs. 5-6; SPEC 2).

A skeleton should lie inside its shape: beta(q) is the share of the unit sphere of directions
(p - q)/|p - q| that the cloud covers (Eq. 6); the overall scores (Eqs. 7-8) are taken in
``skelcore.results``.  Estimators, by ``Params.boundedness_method``:

``rays`` (default, rotation invariant): every cloud point p farther than h from q hides the cap of
directions of angular radius asin(h / |p - q|); beta(q) = area of the union of the caps / 4 pi,
h = ``rays_radius_factor`` x median nearest-neighbour spacing.  The union is rasterised by
``_rays.CapRaster``; beyond ``rays_exact_pairs`` pairs, clustered queries share their far field.

``paper``: the reference tool's algorithm (sinusoidal projection, 2-D Delaunay, seam strip, flat
triangle areas with its drop rule), kept to compare with published numbers.
Design, error measurements, timings and rejected alternatives: docs/boundedness.md.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, Delaunay, QhullError, cKDTree

from ..geometry import Checkpoint, nearest_neighbor_distances, no_checkpoint
from ..params import Params
from ._rays import FRAME, CapRaster

__all__ = ["boundedness", "boundedness_rays", "boundedness_paper", "rays_radius", "paper_triangles", "PaperTriangles"]

# pairs per kernel call: small enough to stay in cache, big enough to amortise numpy's per-call
# overhead (measurements: docs/boundedness.md)
_PAIRS_PER_CALL = 4096
_FAR_PAIRS_PER_CALL = 16384
# pairs per pool task: one checkpoint per finished task, so this bounds their spacing (~10 ms)
_PAIRS_PER_TASK = 65536
# queries closer than this many h to the cloud are clusters of their own (exact)
_ALONE_WITHIN = 4.0
# near-surface queries share in finer cells (cell / 2^k, down to h / 4) with a near radius this many
# times longer than the usual 10 cells (20 cells); measurements: docs/boundedness.md
_FINER_BOOST = 2.0


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
        exact_pairs=params.rays_exact_pairs,
        near_angle=params.rays_near_angle,
        cluster_cell=params.rays_cluster_cell,
        checkpoint=checkpoint,
    )


def rays_radius(cloud: np.ndarray, radius_factor: float = 2.0, checkpoint: Checkpoint = no_checkpoint) -> float:
    """h = radius_factor x the median nearest-neighbour spacing of the cloud (SPEC 2)."""
    cloud = np.asarray(cloud, dtype=float)
    if len(cloud) < 2:
        return 0.0
    return float(radius_factor * np.median(nearest_neighbor_distances(cloud, checkpoint=checkpoint)))


def _as_points(name: str, points: np.ndarray) -> np.ndarray:
    arr = np.asarray(points, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must be an (N, 3) array, got shape {arr.shape}")
    return arr


def _keep_freed_memory() -> None:
    """Allocate and free one 16 MiB block so glibc raises its mmap/trim thresholds and reuses the
    kernel's temporaries from the heap (glibc only; elsewhere harmless).  See docs/boundedness.md.
    """
    block = np.empty(16 << 20, dtype=np.uint8)
    del block


def boundedness_rays(
    cloud: np.ndarray,
    queries: np.ndarray,
    *,
    radius_factor: float = 2.0,
    rows: int = 48,
    bins: int | None = None,
    exact_pairs: int = 4_000_000,
    near_angle: float = 0.1,
    cluster_cell: float = 1.0,
    share_far_field: bool | None = None,
    workers: int | None = 1,
    checkpoint: Checkpoint = no_checkpoint,
) -> np.ndarray:
    """Fraction of rays from each query that hit a ball of radius h around a cloud point (SPEC 2).

    Parameters
    ----------
    cloud : (N, 3) original cloud, normalized (SPEC 0).
    queries : (Q, 3) skeletal points or curve samples.
    radius_factor : h = radius_factor x median nearest-neighbour spacing of ``cloud``.
    rows, bins : raster size (``bins`` defaults to 2 x rows: cells about square at the equator).
    exact_pairs : up to this many (distinct query, distinct point) pairs, every pair is used.
    near_angle, cluster_cell : beyond that, a query's own near field reaches h / near_angle and
        queries share the far field within cubic cells of side cluster_cell x h, both scaled by the
        same power of 2 (the cheapest estimate; docs/boundedness.md).
    share_far_field : None = decide by cost as above; True = always share; False = every pair.
    workers : threads (None = 1); one is the default because more were slower (docs/boundedness.md).
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
    if not (0 < near_angle < 1 and cluster_cell > 0):
        raise ValueError(f"need 0 < near_angle < 1 and cluster_cell > 0, got {near_angle!r}, {cluster_cell!r}")
    out = np.zeros(len(queries))
    if len(queries) == 0 or len(cloud) == 0:
        checkpoint(1.0)
        return out
    h = rays_radius(cloud, radius_factor, lambda f: checkpoint(0.0))
    if not h > 0:
        checkpoint(1.0)
        return out
    _keep_freed_memory()
    raster = CapRaster(rows, 2 * rows if bins is None else bins)
    uniq_q, inverse = np.unique(queries, axis=0, return_inverse=True)
    # identical cloud points have identical caps; the union is unchanged without the copies
    pts = np.unique(cloud, axis=0)
    centre = (pts.min(axis=0) + pts.max(axis=0)) / 2.0
    pts_r = ((pts - centre) @ FRAME.T).astype(np.float32)
    q_r = ((uniq_q - centre) @ FRAME.T).astype(np.float32)
    job = _choose_job(raster, pts_r, q_r, h, exact_pairs, near_angle, cluster_cell, share_far_field)
    beta = np.empty(len(q_r))
    order = getattr(job, "order", slice(None))
    beta[order] = _run(job, len(q_r), max(1, int(workers or 1)), checkpoint)
    out[:] = beta[inverse.ravel()]
    return out


def _choose_job(
    raster: CapRaster, pts: np.ndarray, queries: np.ndarray, h: float, exact_pairs: int, near_angle: float,
    cluster_cell: float, share_far_field: bool | None,
) -> "_DenseJob | _ClusteredJob":
    """Every pair when that is small or cheaper; else the shared far field (docs/boundedness.md)."""
    every_pair = len(pts) * len(queries)
    if share_far_field is False or (share_far_field is None and every_pair <= exact_pairs):
        return _DenseJob(raster, pts, queries, h)
    job = _ClusteredJob.sized(raster, pts, queries, h, h / near_angle, cluster_cell * h)
    # every pair costs the same near caps (x 3, as in ``sized``) plus all the others once
    every_pair_cost = every_pair + 2.0 * len(queries) * job.estimated_near
    if share_far_field is None and job.estimated_cost > 0.75 * every_pair_cost:
        return _DenseJob(raster, pts, queries, h)  # too spread out to share much
    return job


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
        self.qidx = np.repeat(np.arange(self.per_call, dtype=np.int32), min(n, _FAR_PAIRS_PER_CALL))

    def __call__(self, lo: int, hi: int) -> np.ndarray:
        out = np.empty(hi - lo)
        n = len(self.cols[0])
        if n > _FAR_PAIRS_PER_CALL:  # a big cloud: one query at a time, the cloud in slices
            zeros = np.zeros(_FAR_PAIRS_PER_CALL, np.int32)
            for i in range(lo, hi):
                q = self.queries[i]
                covered = np.zeros((self.raster.rows, self.raster.bins), dtype=bool)
                for s in range(0, n, _FAR_PAIRS_PER_CALL):
                    dx, dy, dz = (col[s : s + _FAR_PAIRS_PER_CALL] - q[k] for k, col in enumerate(self.cols))
                    covered |= self.raster.covered(1, zeros[: len(dx)], dx, dy, dz, self.h)[0]
                out[i - lo] = covered.mean()
            return out
        for a in range(lo, hi, self.per_call):
            b = min(a + self.per_call, hi)
            q = self.queries[a:b]
            c = b - a
            dx, dy, dz = ((col[None, :] - q[:, k : k + 1]).ravel() for k, col in enumerate(self.cols))
            out[a - lo : b - lo] = self.raster.union_fraction(c, self.qidx[: c * n], dx, dy, dz, self.h)
        return out


class _ClusteredJob:
    """Exact near field per query; the far field rasterised once per cluster of nearby queries.

    Queries are grouped by cubic cells of side ``cell``; a query closer to the cloud than 4 h and 4
    cells shares in finer cells (``__init__``), with twice the near radius, or below h is a cluster
    of its own.  The cloud is split once per cluster: the near part (within
    ``near_radius + spread`` of its centroid, spread = distance of its farthest query) is rasterised
    from every query exactly; the far part, once from the centroid, and OR-ed in.  Every point is in
    exactly one part (a point in both would fill holes twice: a bias).  Seen from a query instead of
    the centroid, a far cap moves by at most spread / near_radius radians; the error against
    every-pair evaluation is measured in the tests and docs/boundedness.md.
    """

    def __init__(
        self, raster: CapRaster, pts: np.ndarray, queries: np.ndarray, h: float, near_radius: float, cell: float,
        tree: cKDTree | None = None, finer: bool = True,
    ):
        self.raster = raster
        self.cols = [np.ascontiguousarray(pts[:, k]) for k in range(3)]
        self.h = np.float32(h)
        self.near_radius = float(near_radius)
        tree = cKDTree(pts) if tree is None else tree
        # a query near the surface sees nearly coplanar points at grazing angles, where a small move
        # of the viewpoint swaps the side of the horizon their caps lie on.  Level 0 (cells of
        # ``cell``) takes queries at least 4 h and 4 cells from the cloud; a query closer shares only
        # in level k's cells of cell / 2^k >= h / 4 with clearance >= 4 of them (no cluster member
        # can then be on the other side of a surface), and stays on its own below that (clearance
        # < h).  ``finer=False``: everything closer than 4 h on its own (the scheme before levels).
        clearance = tree.query(queries, k=1)[0]
        level = np.zeros(len(queries), np.int64)
        levels = max(0, int(np.floor(np.log2(cell / (h / 4.0))))) if finer else 0
        for k in range(1, levels + 1):
            need = _ALONE_WITHIN * h if k == 1 else 0.0
            level[clearance < max(_ALONE_WITHIN * cell / 2.0 ** (k - 1), need)] = k
        lone = clearance < (_ALONE_WITHIN * cell / 2.0**levels if levels else _ALONE_WITHIN * h)
        level_cell = cell / 2.0**level
        keys = np.floor(queries.astype(float) / level_cell[:, None]).astype(np.int64)
        keys = np.column_stack([keys, level, np.zeros(len(keys), np.int64)])
        lone = np.flatnonzero(lone)
        keys[lone, 4] = lone + 1
        _, cid = np.unique(keys, axis=0, return_inverse=True)
        cid = cid.ravel()
        self.order = np.argsort(cid, kind="stable")
        self.queries = queries[self.order]
        cid = cid[self.order]
        self.starts = np.flatnonzero(np.r_[True, cid[1:] != cid[:-1], True])
        # centroid and spread of every cluster: fixed here so results do not depend on the tasks
        sizes = np.diff(self.starts)
        q64 = self.queries.astype(float)
        centres = np.add.reduceat(q64, self.starts[:-1], axis=0) / sizes[:, None]
        cid_sorted = np.repeat(np.arange(len(sizes)), sizes)
        dist = np.linalg.norm(q64 - centres[cid_sorted], axis=1)
        spreads = np.maximum.reduceat(dist, self.starts[:-1])
        single = sizes == 1
        centres[single] = q64[self.starts[:-1][single]]
        spreads[single] = 0.0
        self.centres = centres.astype(np.float32)
        self.spreads = spreads
        cl_level = level[self.order][self.starts[:-1]]
        self.reach = near_radius * np.where(cl_level > 0, _FINER_BOOST, 1.0) / 2.0**cl_level + spreads
        # tasks: ranges of the sorted queries of about _PAIRS_PER_TASK pairs; a cluster whose near
        # part is large is split, so checkpoints stay ~10 ms apart
        n_near = tree.query_ball_point(centres, self.reach, return_length=True)
        self.tasks = []
        lo, acc = 0, 0
        for k in range(len(sizes)):
            a, b = int(self.starts[k]), int(self.starts[k + 1])
            step = max(1, _PAIRS_PER_TASK // max(1, int(n_near[k])))
            for s0 in range(a, b, step):
                s1 = min(s0 + step, b)
                acc += len(pts) + (s1 - s0) * int(n_near[k])
                if acc >= _PAIRS_PER_TASK:
                    self.tasks.append((lo, s1))
                    lo, acc = s1, 0
        if lo < len(self.queries):
            self.tasks.append((lo, len(self.queries)))

    @classmethod
    def sized(
        cls, raster: CapRaster, pts: np.ndarray, queries: np.ndarray, h: float, near_radius: float, cell: float
    ) -> "_ClusteredJob":
        """The cheapest of seven sizes: cell and near radius x 1/2, 1, 2, ..., 32 (same ratio, same shift).

        Estimated cost = clusters x N (far pairs) + 3 x queries x near points (near caps span several
        rows each).  Why x 1/2 and the factor 3: docs/boundedness.md.
        """
        tree = cKDTree(pts)
        sample = queries[np.random.default_rng(0).permutation(len(queries))[:256]].astype(float)
        costs = []
        scales = 2.0 ** np.arange(-1, 6)
        for scale in scales:
            clusters = _count_cells(queries, cell * scale)
            reach = (near_radius + 0.87 * cell) * scale
            near = float(np.mean(tree.query_ball_point(sample, reach, return_length=True)))
            costs.append((clusters * len(pts) + 3.0 * len(queries) * near, near))
        pick = int(np.argmin([c[0] for c in costs]))
        job = cls(raster, pts, queries, h, near_radius * scales[pick], cell * scales[pick], tree=tree)
        job.estimated_cost, job.estimated_near = costs[pick]
        return job

    def _bitmaps(
        self, n_queries: int, qidx: np.ndarray, dx: np.ndarray, dy: np.ndarray, dz: np.ndarray, per_call: int
    ) -> np.ndarray:
        out = np.zeros((n_queries, self.raster.rows, self.raster.bins), dtype=bool)
        for a in range(0, len(qidx), per_call):
            b = a + per_call
            out |= self.raster.covered(n_queries, qidx[a:b], dx[a:b], dy[a:b], dz[a:b], self.h)
        return out

    def __call__(self, lo: int, hi: int) -> np.ndarray:
        out = np.empty(hi - lo)
        x, y, z = self.cols
        k = int(np.searchsorted(self.starts, lo, side="right")) - 1
        while k < len(self.starts) - 1 and self.starts[k] < hi:
            a, b = max(int(self.starts[k]), lo), min(int(self.starts[k + 1]), hi)
            centre, reach = self.centres[k], float(self.reach[k])
            k += 1
            dx, dy, dz = x - centre[0], y - centre[1], z - centre[2]
            d2 = dx * dx
            d2 += dy * dy
            d2 += dz * dz
            far = d2 > np.float32(reach * reach)
            # far caps are small (few rows each): bigger calls amortise numpy's per-call overhead
            n_far = int(np.count_nonzero(far))
            far_map = self._bitmaps(
                1, np.zeros(n_far, np.int32), dx[far], dy[far], dz[far], _FAR_PAIRS_PER_CALL
            )[0]
            near = ~far
            cand = [x[near], y[near], z[near]]
            m = len(cand[0])
            if m == 0:
                out[a - lo : b - lo] = np.count_nonzero(far_map) / far_map.size
                continue
            step = max(1, _PAIRS_PER_CALL // m)
            for s0 in range(a, b, step):
                s1 = min(s0 + step, b)
                qs = self.queries[s0:s1]
                d = [(cand[j][None, :] - qs[:, j : j + 1]).ravel() for j in range(3)]
                qi = np.repeat(np.arange(s1 - s0, dtype=np.int32), m)
                maps = self._bitmaps(s1 - s0, qi, d[0], d[1], d[2], _PAIRS_PER_CALL)
                maps |= far_map
                out[s0 - lo : s1 - lo] = maps.reshape(s1 - s0, -1).mean(axis=1)
        return out


def _count_cells(points: np.ndarray, cell: float) -> int:
    """Number of distinct cubic cells of side ``cell`` holding points (one 1-D unique: ~10x faster
    than ``np.unique(axis=0)``)."""
    keys = np.floor(points.astype(float) / cell).astype(np.int64)
    keys -= keys.min(axis=0)
    span = keys.max(axis=0) + 1
    if float(np.prod(span.astype(float))) >= 2.0**62:  # far-flung queries: no overflow-free 1-D key
        return len(np.unique(keys, axis=0))
    return len(np.unique((keys[:, 0] * span[1] + keys[:, 1]) * span[2] + keys[:, 2]))


def _run(job, n_queries: int, workers: int, checkpoint: Checkpoint) -> np.ndarray:
    """Run ``job(lo, hi)`` over its tasks (ranges of its query order) on a pool; checkpoint after each.

    Returns the values in the job's query order.
    """
    tasks = getattr(job, "tasks", None)
    if tasks is None:
        step = job.per_task
        tasks = [(lo, min(lo + step, n_queries)) for lo in range(0, n_queries, step)]
    out = np.empty(n_queries)
    checkpoint(0.0)
    if workers <= 1 or len(tasks) == 1:
        for i, (lo, hi) in enumerate(tasks):
            out[lo:hi] = job(lo, hi)
            checkpoint((i + 1) / len(tasks))
        return out
    pool = ThreadPoolExecutor(max_workers=workers)
    try:
        # a short queue, so that a cancel stops within about one task per worker
        pending: list = []
        it = iter(tasks)
        for lo, hi in it:
            pending.append((lo, hi, pool.submit(job, lo, hi)))
            if len(pending) >= 2 * workers:
                break
        done = 0
        while pending:
            lo, hi, fut = pending.pop(0)
            out[lo:hi] = fut.result()
            done += 1
            checkpoint(done / len(tasks))
            nxt = next(it, None)
            if nxt is not None:
                pending.append((nxt[0], nxt[1], pool.submit(job, nxt[0], nxt[1])))
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
    """The reference tool's triangulated-sphere estimator (SPEC 2 ``paper``; paper Sec. 2.2, Prop. 2).

    Directions u = (q - p)/|q - p| (the reference tool's sign; cloud points at q itself are skipped)
    are projected by the sinusoidal projection (lon cos lat, lat) and triangulated in 2-D (Delaunay);
    the free-boundary loop is closed by the reference tool's strip (``_zip_seam``), applied whether or
    not the loop reaches the seam at lon = +-pi, as the reference does.  Each triangle counts with the
    area of the flat 3-D triangle between its unit vectors, unless (signed distance from the centre to
    its plane) < plane_threshold and (mean |p - q| of its corners)^2 x area < area_threshold.
    beta = sum / (4 pi).  Fewer than 3 distinct directions give 0.  The sum is not clipped to 1 (as the
    reference tool).  Seam rule as read in the reference code, values on analytic shapes:
    docs/boundedness.md.
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
    tri = paper_triangles(cloud, q, plane_threshold=plane_threshold, area_threshold=area_threshold)
    return float(tri.area[tri.counted].sum() / (4.0 * np.pi)) if tri is not None else 0.0


@dataclass(frozen=True)
class PaperTriangles:
    """The reference tool's triangulated sphere around one query (``paper`` estimator)."""

    directions: np.ndarray  # (m, 3) unit q - p of the cloud points kept
    triangles: np.ndarray  # (t, 3) rows of ``directions``: the 2-D Delaunay ones, then the seam strip
    area: np.ndarray  # (t,) flat 3-D area of each
    counted: np.ndarray  # (t,) bool: not dropped by the plane/area rule

    @property
    def beta(self) -> float:
        return float(self.area[self.counted].sum() / (4.0 * np.pi))


def paper_triangles(cloud: np.ndarray, q: np.ndarray, *, plane_threshold: float = 0.8,
                    area_threshold: float = 1e-4) -> "PaperTriangles | None":
    """The triangles :func:`boundedness_paper` sums for query ``q``; None when fewer than 3 distinct
    directions or a degenerate set leave no triangulation (beta = 0)."""
    d = q - cloud  # the reference tool's sign (q - p): it puts the seam behind the cloud, see _zip_seam
    dist = np.sqrt(np.einsum("ij,ij->i", d, d))
    keep = dist > 0
    d, dist = d[keep], dist[keep]
    if len(d) < 3:
        return None
    u = d / dist[:, None]
    lon = np.arctan2(u[:, 1], u[:, 0])
    rxy = np.hypot(u[:, 0], u[:, 1])
    lat = np.arctan2(u[:, 2], rxy)
    flat = np.column_stack([lon * rxy, lat])  # rxy = cos(lat)
    try:
        tri = Delaunay(flat)
        hull = ConvexHull(flat).vertices  # the free-boundary loop, counter-clockwise
    except QhullError:
        return None  # all directions on one great circle through the poles, or coincident
    simplices = tri.simplices
    # orient counter-clockwise in the chart (as MATLAB's delaunayTriangulation): outward on the sphere
    a, b, c = flat[simplices[:, 0]], flat[simplices[:, 1]], flat[simplices[:, 2]]
    cw = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) < 0
    simplices[cw] = simplices[cw][:, [0, 2, 1]]
    seam = _zip_seam(hull, lat)
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
    return PaperTriangles(directions=u, triangles=tris, area=area, counted=~drop)


def _zip_seam(loop: np.ndarray, lat: np.ndarray) -> np.ndarray:
    """The reference tool's seam strip over the whole free-boundary loop (m vertices -> m - 2 triangles).

    Visit order: the loop's lowest vertex, its successor, then the two sides (onward from the
    successor, backward from the lowest) merged by latitude: the side whose next vertex is lower
    advances (a tie advances the backward side).  Each new vertex makes a triangle with the TWO
    PREVIOUSLY VISITED vertices, in that order, not re-oriented (so the drop rule sees alternating
    signs).  Where the sides alternate this is the usual zipper between them; where one side
    advances twice in a row, the triangle is three consecutive loop vertices (a sliver) and the
    zipper triangle is skipped.  The reference applies it unconditionally, also to loops that do not
    reach the seam (the values this gives: docs/boundedness.md).
    """
    m = len(loop)
    if m < 3:
        return np.empty((0, 3), dtype=np.intp)
    loop_lat = lat[loop]
    bottom = int(np.argmin(loop_lat))
    order = [bottom, (bottom + 1) % m]
    back, fwd = (bottom - 1) % m, (bottom + 2) % m
    for _ in range(m - 2):
        if loop_lat[back] > loop_lat[fwd]:
            order.append(fwd)
            fwd = (fwd + 1) % m
        else:
            order.append(back)
            back = (back - 1) % m
    visit = loop[np.array(order)]
    return np.column_stack([visit[:-2], visit[1:-1], visit[2:]])
