"""Boundedness beta(q) of skeletal points and curve samples (paper Sec. 2.2, Eqs. 5-6; SPEC 2).

A skeleton should lie inside its shape: beta(q) is the share of the unit sphere of directions
(p - q)/|p - q| that the cloud covers (Eq. 6); the overall scores (Eqs. 7-8) are taken in
``skelcore.results``.  Estimators, by ``Params.boundedness_method``:

``rays`` (default, rotation invariant): every cloud point p farther than h from q hides the cap of
directions of angular radius asin(h / |p - q|); beta(q) = area of the union of the caps / 4 pi,
h = ``rays_radius_factor`` x median nearest-neighbour spacing.  The union is rasterised by the
compiled, occlusion-culled kernel ``rays_kernel`` (``_rays.CapRaster`` is its numpy reference); where
a measured cost says so, clustered queries share their far field.

``paper``: the reference tool's algorithm (sinusoidal projection, 2-D Delaunay, seam strip, flat
triangle areas with its drop rule), kept to compare with published numbers.
Design, error measurements, timings and rejected alternatives: docs/boundedness.md.
"""

from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, Delaunay, QhullError

from ..geometry import Checkpoint, chunked_query, kd_tree, nearest_neighbor_distances, no_checkpoint, unique_rows
from ..params import Params
from ._rays import FRAME

__all__ = ["boundedness", "boundedness_rays", "boundedness_paper", "rays_radius", "paper_triangles", "PaperTriangles"]

# queries closer than this many h to the cloud share only in finer cells, or are clusters of their own
_ALONE_WITHIN = 4.0
# near-surface queries share in finer cells (cell / 2^k, down to h / 4) with a near radius this many
# times longer than the usual 10 cells (20 cells); measurements: docs/boundedness.md
_FINER_BOOST = 2.0
# cost model, in node visits of the kernel's walk (docs/boundedness.md): one near-list cap, one query
_NEAR_CAP_COST = 0.3
_QUERY_COST = 3.0
_SAMPLE = 32  # queries walked exactly to measure the cost of a walk
_BATCH_SECONDS = 0.1  # kernel calls are sized to about this long, so checkpoints come often


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


@contextmanager
def _threads(workers: int | None):
    """Run the kernel on ``workers`` threads (None: all of numba's), restoring the count after."""
    import numba

    before = numba.get_num_threads()
    numba.set_num_threads(max(1, min(int(workers or numba.config.NUMBA_NUM_THREADS), numba.config.NUMBA_NUM_THREADS)))
    chunk = numba.set_parallel_chunksize(1)  # iterations handed out one by one: costs vary a lot
    try:
        yield
    finally:
        numba.set_parallel_chunksize(chunk)
        numba.set_num_threads(before)


def _sub(checkpoint: Checkpoint, lo: float, hi: float) -> Checkpoint:
    return lambda f: checkpoint(lo + (hi - lo) * min(max(f, 0.0), 1.0))


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
    exact_pairs : up to this many (distinct query, distinct point) pairs every query is exact.
    near_angle, cluster_cell : beyond that, if the measured cost says so, queries share the far field
        (points beyond h / near_angle) within cubic cells of side cluster_cell x h, both scaled by the
        same power of 2 (docs/boundedness.md).
    share_far_field : None = decide by cost as above; True = always share; False = every query exact.
    workers : kernel threads (None = all numba threads); results do not depend on it.
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
    bins = 2 * rows if bins is None else bins
    if rows < 1 or bins < 1:
        raise ValueError("the raster needs at least one row and one bin")
    out = np.zeros(len(queries))
    checkpoint(0.0)
    if len(queries) == 0 or len(cloud) < 2:
        checkpoint(1.0)
        return out
    tree = kd_tree(cloud)
    checkpoint(0.02)
    h = radius_factor * float(np.median(chunked_query(tree, cloud, 2, checkpoint, 0.02, 0.06)[0][:, 1]))
    if not h > 0:
        checkpoint(1.0)
        return out
    from . import rays_kernel  # numba loads here, not on ``import skelcore``

    uniq_q, inverse, _ = unique_rows(queries)
    # identical cloud points have identical caps; the union is unchanged without the copies
    pts = unique_rows(cloud)[0]
    checkpoint(0.07)
    centre = (pts.min(axis=0) + pts.max(axis=0)) / 2.0
    pts_r = (pts - centre) @ FRAME.T
    q_r = (uniq_q - centre) @ FRAME.T
    with _threads(workers):
        caps = rays_kernel.CapTree(pts_r, h, rows, bins, checkpoint=_sub(checkpoint, 0.07, 0.1))
        def clearance() -> np.ndarray:
            return chunked_query(tree, uniq_q, 1)[0][:, 0]

        plan = _plan(caps, clearance, pts_r, q_r, h, exact_pairs, near_angle, cluster_cell, share_far_field,
                     _sub(checkpoint, 0.1, 0.15))
        if plan is None:
            beta = _run_every_point(caps, q_r, _sub(checkpoint, 0.15, 1.0))
        else:
            beta = plan.run(caps, _sub(checkpoint, 0.15, 1.0))
    checkpoint(1.0)
    out[:] = beta[inverse]
    return out


def _batches(total: int, run, checkpoint: Checkpoint, first: int = 16) -> None:
    """``run(a, b)`` over [0, total) in slices sized to about _BATCH_SECONDS each, checkpoint after each."""
    a, size = 0, max(1, first)
    while a < total:
        b = min(total, a + size)
        t0 = time.perf_counter()
        run(a, b)
        dt = time.perf_counter() - t0
        checkpoint(b / total)
        # grow or shrink towards the target, at most x4 per step
        size = int(min(8 * size, max(1, size * _BATCH_SECONDS / max(dt, 1e-4))))
        a = b


def _run_every_point(caps, q_r: np.ndarray, checkpoint: Checkpoint) -> np.ndarray:
    beta = np.empty(len(q_r))

    def run(a: int, b: int) -> None:
        beta[a:b] = caps.every_point(q_r[a:b])[0]

    _batches(len(q_r), run, checkpoint, first=4)
    return beta


def _plan(caps, clearance, pts, queries, h, exact_pairs, near_angle, cluster_cell, share_far_field, checkpoint):
    """None (every query exact) or the cheapest ``_Clusters`` by a measured cost (docs/boundedness.md).

    ``clearance()`` gives every query's distance to the cloud.  Cost, in node visits: exact = queries x V, V = mean visits of an exact walk on _SAMPLE queries;
    shared at size s = clusters x V (one far walk each) + queries x (near points x _NEAR_CAP_COST +
    _QUERY_COST), the near points counted from 256 sampled queries with reach (near radius + 0.87
    cell) x s.  Sizes: cell and near radius x 1/2, 1, 2, ..., 32.
    """
    n_q = len(queries)
    if share_far_field is False or (share_far_field is None and n_q * len(pts) <= exact_pairs):
        checkpoint(1.0)
        return None
    rng = np.random.default_rng(0)
    sample = queries[np.sort(rng.permutation(n_q)[:_SAMPLE])]
    visits = []
    for a in range(0, len(sample), 4):  # exact walks cost up to ~30 ms each at 1M points
        visits.append(caps.every_point(sample[a : a + 4])[1])
        checkpoint(0.5 * (a + 4) / len(sample))
    visits = float(np.mean(np.concatenate(visits)))
    exact_cost = n_q * visits
    near_sample = queries[np.sort(rng.permutation(n_q)[:256])]
    cell, near_radius = cluster_cell * h, h / near_angle
    best = None
    for scale in 2.0 ** np.arange(-1, 6):
        clusters = _count_cells(queries, cell * scale)
        reach = np.full(len(near_sample), (near_radius + 0.87 * cell) * scale)
        near = float(np.mean(caps.near_counts(near_sample, reach)))
        cost = clusters * visits + n_q * (near * _NEAR_CAP_COST + _QUERY_COST)
        if best is None or cost < best[0]:
            best = (cost, scale)
    checkpoint(1.0)
    if share_far_field is None and best[0] > 0.75 * exact_cost:
        return None  # too spread out to share much
    scale = best[1]
    plan = _Clusters(queries, clearance(), h, near_radius * scale, cell * scale)
    plan.estimated_cost, plan.exact_cost = best[0], exact_cost
    return plan


class _Clusters:
    """Queries grouped to share the far field: exact near field per query, far field once per cluster.

    Queries are grouped by cubic cells of side ``cell``; a query closer to the cloud than 4 h and 4
    cells shares in finer cells, with twice the near radius, or below h is a cluster of its own.  The
    cloud is split once per cluster: the near part (within ``reach`` = near radius + spread of its
    centroid, spread = distance of its farthest query) is rasterised from every query exactly; the
    far part once from the centroid, and OR-ed in.  Every point is in exactly one part (a point in
    both would fill holes twice: a bias).  Seen from a query instead of the centroid, a far cap moves
    by at most spread / near radius radians; errors: tests and docs/boundedness.md.
    """

    def __init__(self, queries: np.ndarray, clearance: np.ndarray, h: float, near_radius: float, cell: float,
                 finer: bool = True):
        self.near_radius = float(near_radius)
        self.cell = float(cell)
        # a query near the surface sees nearly coplanar points at grazing angles, where a small move
        # of the viewpoint swaps the side of the horizon their caps lie on.  Level 0 (cells of
        # ``cell``) takes queries at least 4 h and 4 cells from the cloud; a query closer shares only
        # in level k's cells of cell / 2^k >= h / 4 with clearance >= 4 of them, and stays on its
        # own below that (clearance < h).  ``finer=False``: everything closer than 4 h on its own.
        level = np.zeros(len(queries), np.int64)
        levels = max(0, int(np.floor(np.log2(cell / (h / 4.0))))) if finer else 0
        for k in range(1, levels + 1):
            need = _ALONE_WITHIN * h if k == 1 else 0.0
            level[clearance < max(_ALONE_WITHIN * cell / 2.0 ** (k - 1), need)] = k
        lone = clearance < (_ALONE_WITHIN * cell / 2.0**levels if levels else _ALONE_WITHIN * h)
        level_cell = cell / 2.0**level
        keys = np.floor(queries / level_cell[:, None]).astype(np.int64)
        lone_id = np.where(lone, np.arange(len(queries)) + 1, 0)
        keys = np.column_stack([keys, level, lone_id])
        order = np.lexsort(keys.T[::-1])
        srt = keys[order]
        new = np.ones(len(srt), bool)
        new[1:] = np.any(srt[1:] != srt[:-1], axis=1)
        self.order = order
        self.queries = queries[order]
        self.starts = np.flatnonzero(np.r_[new, True])
        sizes = np.diff(self.starts)
        cid = np.repeat(np.arange(len(sizes)), sizes)
        self.cluster = cid
        # centroid and spread of every cluster: fixed here so results do not depend on the batches
        centres = np.add.reduceat(self.queries, self.starts[:-1], axis=0) / sizes[:, None]
        dist = np.linalg.norm(self.queries - centres[cid], axis=1)
        spreads = np.maximum.reduceat(dist, self.starts[:-1])
        single = sizes == 1
        centres[single] = self.queries[self.starts[:-1][single]]
        spreads[single] = 0.0
        self.centres = centres
        cl_level = level[order][self.starts[:-1]]
        self.reach = near_radius * np.where(cl_level > 0, _FINER_BOOST, 1.0) / 2.0**cl_level + spreads

    def run(self, caps, checkpoint: Checkpoint) -> np.ndarray:
        """beta of every query (in the input order), the clusters in batches with checkpoints."""
        beta_sorted = np.empty(len(self.queries))
        starts = self.starts

        queries = np.ascontiguousarray(self.queries)
        centres = np.ascontiguousarray(self.centres)
        reach = np.ascontiguousarray(self.reach, dtype=np.float64)
        starts = starts.astype(np.int64)

        def run(a: int, b: int) -> None:
            beta_sorted[starts[a] : starts[b]] = caps.clusters(queries, starts, centres, reach, a, b - a)

        _batches(len(starts) - 1, run, checkpoint, first=4)
        beta = np.empty(len(self.queries))
        beta[self.order] = beta_sorted
        return beta


def _count_cells(points: np.ndarray, cell: float) -> int:
    """Number of distinct cubic cells of side ``cell`` holding points (one 1-D unique: ~10x faster
    than ``np.unique(axis=0)``)."""
    keys = np.floor(points.astype(float) / cell).astype(np.int64)
    keys -= keys.min(axis=0)
    span = keys.max(axis=0) + 1
    if float(np.prod(span.astype(float))) >= 2.0**62:  # far-flung queries: no overflow-free 1-D key
        return len(np.unique(keys, axis=0))
    return len(np.unique((keys[:, 0] * span[1] + keys[:, 1]) * span[2] + keys[:, 2]))


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
