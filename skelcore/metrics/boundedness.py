"""Boundedness beta(q) of skeletal points and curve samples (paper Sec. 2.2, Eqs. 5-6; docs/metrics.md 2).

A skeleton should lie inside its shape: beta(q) is the share of the unit sphere of directions
(p - q)/|p - q| that the cloud covers (Eq. 6); the overall scores (Eqs. 7-8) are taken in
``skelcore.evaluation``.  Estimators, by ``Params.boundedness_method``:

``rays`` (default, rotation invariant): every cloud point p farther than h from q hides the cap of
directions of angular radius asin(h / |p - q|); beta(q) = area of the union of the caps / 4 pi,
h = ``rays_radius_factor`` x median nearest-neighbour spacing.  The union is sampled on the raster of
``_rays.CapRaster`` by the compiled kernel (``rays_kernel``): far caps by one ray cast per sample,
near caps exactly; beyond ``rays_exact_pairs`` pairs, clustered queries share their far field.

``paper``: the reference tool's algorithm (sinusoidal projection, 2-D Delaunay, seam strip, flat
triangle areas with its drop rule), kept to compare with published numbers.
Design, error measurements, timings and rejected alternatives: docs/boundedness.md.
"""

from __future__ import annotations

import hashlib
import threading
import weakref
from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, Delaunay, QhullError

from ..geometry import Checkpoint, bounding_box, no_checkpoint, unique_rows
from ..params import Params
from ._rays import FRAME
from .ray_hints import TABLES_MOST_BYTES, HintTables
from .rays_kernel import BallTree, choose_plan, exact_plan, run_plan

__all__ = ["boundedness", "rays_plan_is_exact", "boundedness_rays", "boundedness_paper", "rays_radius", "paper_triangles", "PaperTriangles",
           "prepared_cloud", "in_raster_frame", "LoneRays"]

def boundedness(
    cloud: np.ndarray,
    queries: np.ndarray,
    *,
    params: Params = Params(),
    checkpoint: Checkpoint = no_checkpoint,
    share_far_field: bool | None = None,
    workers: int | None = None,
    seeds: HintTables | None = None,
    keep: list | None = None,
) -> np.ndarray:
    """beta(q) for every query row with the estimator ``params.boundedness_method`` (docs/metrics.md 2).

    Inputs are in normalized units (docs/metrics.md 0).  Returns one value per query row, in [0, 1] for
    ``rays``.  An empty query set gives an empty array; an empty cloud gives zeros.  ``share_far_field``
    and ``workers`` (threads of the rays kernel, None = all cores; the values do not depend on it),
    ``seeds`` and ``keep`` (the far rays' hint tables, which do not change them either):
    :func:`boundedness_rays`' (None: decided by cost).
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
        share_far_field=share_far_field,
        checkpoint=checkpoint,
        workers=workers,
        seeds=seeds,
        keep=keep,
    )


def rays_plan_is_exact(cloud: np.ndarray, queries: np.ndarray, params: Params = Params()) -> bool:
    """Whether :func:`boundedness` scores ``queries`` with every (query, point) pair, each query on its
    own: then a query's value does not depend on the others asked with it (shared far fields do), so
    values of an earlier call can be kept for the same points. False for the paper's estimator."""
    if params.boundedness_method != "rays":
        return False
    cloud, queries = _as_points("cloud", cloud), _as_points("queries", queries)
    if len(queries) == 0 or len(cloud) == 0:
        return True
    uniq_q = unique_rows(queries, no_checkpoint)[0]
    prepared = _prepared_cloud(cloud, no_checkpoint)
    q_r = _in_frame(uniq_q, prepared.centre)
    h = params.rays_radius_factor * prepared.spacing
    if not h > 0:
        return True
    near = h / params.rays_near_angle
    rows = int(params.rays_rows)
    plan = choose_plan(prepared.tree, q_r, h, near, params.rays_cluster_cell * h, rows * 2 * rows,
                       params.rays_exact_pairs, None)
    return _lone(plan, q_r) and bool(np.all(plan.reach == near))


def rays_radius(cloud: np.ndarray, radius_factor: float = 2.0, checkpoint: Checkpoint = no_checkpoint) -> float:
    """h = radius_factor x the median nearest-neighbour spacing of the cloud (docs/metrics.md 2; copies of a point
    are at distance 0), from the kernel's tree of the distinct points: the h ``boundedness_rays`` uses."""
    cloud = np.asarray(cloud, dtype=float)
    if len(cloud) < 2:
        return 0.0
    return float(radius_factor * _prepared_cloud(cloud, checkpoint).spacing)


@dataclass
class _PreparedCloud:
    """A cloud's distinct points in the kernel's tree (raster frame) and its median spacing; ``digest`` of the
    cloud's bytes, None when the cloud was frozen (:func:`_frozen`) as it was prepared."""

    digest: bytes | None
    centre: np.ndarray
    tree: BallTree
    spacing: float


# the last cloud prepared, reused while the same unchanged array comes back (the skeletal and the
# curve stage of one evaluation share it: at 1M points it saves about 3 s)
_last_prepared: dict = {}
_prepare_lock = threading.Lock()


def prepared_cloud(cloud: np.ndarray, checkpoint: Checkpoint = no_checkpoint) -> "_PreparedCloud":
    """The cloud as ``boundedness_rays`` casts against it: its distinct points in the kernel's tree (raster
    frame, ``centre`` subtracted) and its median spacing; cached for the same unchanged array."""
    return _prepared_cloud(np.asarray(cloud, dtype=float), checkpoint)


def in_raster_frame(points: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """Points in the frame of a :func:`prepared_cloud` with this ``centre``."""
    return _in_frame(np.asarray(points, dtype=float), centre)


def _in_frame(points: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """(points - centre) in the raster frame (FRAME @ (p - centre)), by einsum: 5 x faster than ``@``
    on a million rows (OpenBLAS starts its threads for a 3 x 3 product: 0.29 -> 0.06 s), within an ulp
    of it."""
    return np.einsum("ij,kj->ik", points - centre, FRAME)


def _prepared_cloud(cloud: np.ndarray, checkpoint: Checkpoint) -> _PreparedCloud:
    # one preparation at a time: the skeletal and curve stages may start side by side (the second
    # waits, then finds the first's in the cache); the wait calls the checkpoint every 50 ms (at 1M points
    # the preparation takes seconds, and a cancel must reach this stage too)
    while not _prepare_lock.acquire(timeout=0.05):
        checkpoint(0.0)
    try:
        return _prepare(cloud, checkpoint)
    finally:
        _prepare_lock.release()


def _frozen(cloud: np.ndarray) -> bool:
    """Whether no numpy array can change ``cloud``'s data: it and every base it views are read-only, down to
    an array that owns its data (a read-only view of a writeable array is not frozen).  The evaluation's
    normalized clouds are made so (skelcore.stages.context); only turning the owner writeable again, which
    numpy allows for an array that owns its data, would escape this test."""
    a = cloud
    while isinstance(a, np.ndarray):
        if a.flags.writeable:
            return False
        if a.base is None:
            return bool(a.flags.owndata)
        a = a.base
    return False  # a foreign buffer (bytes, mmap, another library's array): not known to be frozen


def _digest(cloud: np.ndarray) -> bytes:
    return hashlib.blake2b(np.ascontiguousarray(cloud).view(np.uint8), digest_size=16).digest()


def _prepare(cloud: np.ndarray, checkpoint: Checkpoint) -> _PreparedCloud:
    # the cached preparation is reused for the same array while its bytes are the same: a frozen array
    # prepared frozen cannot have changed (no digest: 37 ms at 1M points, on every edit's update,
    # docs/boundedness.md 3.15); any other is hashed and compared
    frozen = _frozen(cloud)
    ref = _last_prepared.get("cloud")
    hit = _last_prepared.get("prepared")
    digest = None
    if ref is not None and ref() is cloud and hit is not None:
        if hit.digest is None and frozen:
            return hit
        if hit.digest is not None:
            digest = _digest(cloud)
            if digest == hit.digest:
                if frozen:  # unchanged since it was prepared, and frozen from now on
                    hit.digest = None
                return hit
    digest = None if frozen else digest or _digest(cloud)
    # identical cloud points have identical caps; the union is unchanged without the copies
    checkpoint(0.0)  # after the digest: a cancel is seen before the sort of a million rows
    pts, _, counts = unique_rows(cloud, lambda f: checkpoint(0.0))
    checkpoint(0.0)
    lo, hi = bounding_box(pts)
    centre = (lo + hi) / 2.0
    pts_r = _in_frame(pts, centre)
    checkpoint(0.0)
    tree = BallTree(pts_r, checkpoint)
    spacing = tree.median_spacing(counts, lambda f: checkpoint(0.0)) if len(cloud) > 1 else 0.0
    prepared = _PreparedCloud(digest, centre, tree, spacing)
    try:
        ref = weakref.ref(cloud, lambda r: _last_prepared.clear() if _last_prepared.get("cloud") is r else None)
        _last_prepared.update(cloud=ref, prepared=prepared)
    except TypeError:  # not weak-referenceable (a view of a foreign buffer): no reuse
        _last_prepared.clear()
    return prepared


def _as_points(name: str, points: np.ndarray) -> np.ndarray:
    arr = np.asarray(points, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must be an (N, 3) array, got shape {arr.shape}")
    return arr


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
    seeds: HintTables | None = None,
    keep: list | None = None,
) -> np.ndarray:
    """Fraction of rays from each query that hit a ball of radius h around a cloud point (docs/metrics.md 2).

    Parameters
    ----------
    cloud : (N, 3) original cloud, normalized (docs/metrics.md 0).
    queries : (Q, 3) skeletal points or curve samples.
    radius_factor : h = radius_factor x median nearest-neighbour spacing of ``cloud``.
    rows, bins : raster size (``bins`` defaults to 2 x rows: cells about square at the equator).
    exact_pairs : up to this many (distinct query, distinct point) pairs, every pair is used.
    near_angle, cluster_cell : beyond that, a query's own near field reaches h / near_angle and
        queries share the far field within cubic cells of side cluster_cell x h, both scaled by the
        same power of 2 (the cheapest estimate; docs/boundedness.md).
    share_far_field : None = decide by cost as above; True = always share; False = every pair.
    workers : threads running the compiled kernel (None = all cores); the values do not depend on it.
    checkpoint : called with the fraction done, about every 0.05 s of work; may raise ``Cancelled``.
    seeds : hint tables kept by an earlier call on lone queries of the same cloud array: each lone
        query here starts its far rays from the nearest one's hits (docs/boundedness.md 3.18).
    keep : when every query is scored on its own (the exact plan) and their tables fit in
        ``TABLES_MOST_BYTES``, the :class:`HintTables` of this call's distinct queries is appended.

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
    given = cloud  # the hint tables' key (HintTables.cloud)
    cloud = _as_points("cloud", cloud)
    queries = _as_points("queries", queries)
    if seeds is not None and seeds.cloud is not given:
        seeds = None
    if not radius_factor > 0:
        raise ValueError(f"radius_factor must be > 0, got {radius_factor!r}")
    if not (0 < near_angle < 1 and cluster_cell > 0):
        raise ValueError(f"need 0 < near_angle < 1 and cluster_cell > 0, got {near_angle!r}, {cluster_cell!r}")
    out = np.zeros(len(queries))
    if len(queries) == 0 or len(cloud) == 0:
        checkpoint(1.0)
        return out
    uniq_q, inverse, _ = unique_rows(queries, lambda f: checkpoint(0.0))
    checkpoint(0.0)
    bins = 2 * rows if bins is None else int(bins)
    if rows < 1 or bins < 1:
        raise ValueError("the raster needs at least one row and one bin")
    prepared = _prepared_cloud(cloud, checkpoint)
    tree, centre = prepared.tree, prepared.centre
    q_r = _in_frame(uniq_q, centre)
    h = radius_factor * prepared.spacing
    if not h > 0:
        checkpoint(1.0)
        return out
    plan = choose_plan(
        tree, q_r, h, h / near_angle, cluster_cell * h, rows * bins, exact_pairs, share_far_field,
        checkpoint,
    )
    beta = _cast(given, tree, plan, q_r, h, rows, bins, workers, checkpoint, seeds,
                 keep if keep is not None and _lone(plan, q_r) else None)
    out[:] = beta[inverse]
    return out


def _cast(given: np.ndarray, tree: BallTree, plan, q_r: np.ndarray, h: float, rows: int, bins: int,
          workers: int | None, checkpoint: Checkpoint, seeds: HintTables | None, keep: list | None,
          nearest: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """beta of the distinct queries ``q_r`` (raster frame) by ``plan``; with ``keep`` (a lone plan) their
    hint tables appended to it when they fit in ``TABLES_MOST_BYTES``."""
    kept = None
    if keep is not None and len(q_r) * 8 * rows * bins <= TABLES_MOST_BYTES:
        kept = np.empty((len(q_r), 2 * rows * bins), np.int32)
    beta = run_plan(tree, plan, q_r, h, rows, bins, workers, checkpoint, seeds=seeds, kept=kept, nearest=nearest)
    if kept is not None:
        keep.append(HintTables.of(given, np.ascontiguousarray(q_r, np.float64), kept))
    return beta


@dataclass(frozen=True)
class LoneRays:
    """The rays estimator for queries of one cloud that it scores each on its own (the exact plan,
    :func:`rays_plan_is_exact`), its setup taken once: the prepared cloud, h, the near reach and the
    raster. A caller that scores such queries in several calls (an edit's moved samples in chunks,
    docs/performance.md 6.10) skips each call's plan choice, its checks and the cloud's lookup; each
    query's beta is :func:`boundedness_rays`' with every pair, the same bits (docs/metrics.md 2)."""

    given: np.ndarray
    tree: BallTree
    centre: np.ndarray
    h: float
    near: float
    rows: int
    bins: int

    @classmethod
    def of(cls, cloud: np.ndarray, params: Params = Params()) -> "LoneRays | None":
        """The setup for ``cloud`` (the array the hint tables are keyed by) and ``params``; None where
        :func:`boundedness` would not cast rays (the paper's estimator, an empty cloud, h = 0)."""
        if params.boundedness_method != "rays":
            return None
        if not params.rays_radius_factor > 0 or not 0 < params.rays_near_angle < 1:
            raise ValueError(f"need radius_factor > 0 and 0 < near_angle < 1, got {params.rays_radius_factor!r}, "
                             f"{params.rays_near_angle!r}")
        points = _as_points("cloud", cloud)
        if len(points) == 0:
            return None
        prepared = _prepared_cloud(points, no_checkpoint)
        h = params.rays_radius_factor * prepared.spacing
        if not h > 0:
            return None
        rows = int(params.rays_rows)
        return cls(cloud, prepared.tree, prepared.centre, h, h / params.rays_near_angle, rows, 2 * rows)

    def __call__(self, queries: np.ndarray, *, workers: int | None = None, seeds: HintTables | None = None,
                 keep: list | None = None) -> np.ndarray:
        """beta of every query row, as ``boundedness(cloud, queries, share_far_field=False, workers=,
        seeds=, keep=)``."""
        queries = _as_points("queries", queries)
        if len(queries) == 0:
            return np.zeros(0)
        uniq_q, inverse, _ = unique_rows(queries)
        seeds = self.seeds(seeds)
        return self.distinct(self.in_frame(uniq_q), workers=workers, seeds=seeds, keep=keep)[inverse]

    def in_frame(self, points: np.ndarray) -> np.ndarray:
        """``points`` in the raster frame (:func:`in_raster_frame` of the prepared cloud's centre)."""
        return _in_frame(np.asarray(points, dtype=float), self.centre)

    def seeds(self, seeds: HintTables | None) -> HintTables | None:
        """``seeds`` when they were kept on this cloud (else None, as :func:`boundedness_rays` drops them)."""
        return seeds if seeds is not None and seeds.cloud is self.given else None

    def distinct(self, q_r: np.ndarray, *, workers: int | None = None, seeds: HintTables | None = None,
                 keep: list | None = None, nearest: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
        """beta of distinct queries in the raster frame (:meth:`in_frame`), cast in the order given (the
        order of the kept tables' rows; :func:`unique_rows`' lexicographic order, as ``boundedness``);
        ``seeds`` from :meth:`seeds`, ``nearest`` their ``nearest(q_r)`` when the caller asked it for
        more queries at once. For a caller that makes its queries distinct once for several calls."""
        if len(q_r) == 0:
            return np.zeros(0)
        plan = exact_plan(q_r, self.near)
        return _cast(self.given, self.tree, plan, q_r, self.h, self.rows, self.bins, workers, no_checkpoint,
                     seeds, keep, nearest)


def _lone(plan, q_r: np.ndarray) -> bool:
    """Whether the plan scores every query on its own at its own position, in the queries' order."""
    n = len(q_r)
    return bool(len(plan.starts) == n + 1 and np.array_equal(plan.starts, np.arange(n + 1))
                and np.array_equal(plan.order, np.arange(n)) and np.array_equal(plan.centres, q_r))


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
    """The reference tool's triangulated-sphere estimator (``paper`` in docs/metrics.md 2; paper Sec. 2.2, Prop. 2).

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
    # a degenerate set (directions on one great circle, many coincident) can leave triangles on qhull's
    # added point at infinity (index len(flat)): they are no part of the sphere
    simplices = tri.simplices[(tri.simplices < len(flat)).all(axis=1)]
    if len(simplices) == 0:
        return None
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
