"""Viewpoint-aware boundedness and centeredness: score what the sensors could have seen
(docs/metrics.md 6.3; SkelScope's extension, the paper's definitions unchanged without a viewpoint).

Given the sensors' positions, boundedness leaves out the escaping directions no sensor could have seen:
beta_seen(q) = |covered| / (|covered| + |uncovered and seen|).  A covered direction was seen (the point it
meets was scanned); an uncovered direction d is seen when e = q + r d (r: q's distance to the cloud)
faces a sensor (d . (v - e) > 0) and no scanned point lies in front of e on the sensor's line of sight
(:class:`DepthImage`).  Several sensors: the union.  Directions are counted on an equal-area raster of
``viewpoint_rows`` x 2 ``viewpoint_rows``; each is cast on its own by the unchanged compiled kernel, its
tree turned so that the direction is the one sample of a 1 x 1 raster; the sensors are asked only about
the uncovered directions, and queries farther than 4 cells (``viewpoint_share_cell`` x h) from the cloud
share their cell centroid's casts (docs/metrics.md 6.3, docs/performance.md 6.8).

Skeletal centeredness (Eq. 10) with viewpoints leaves out the component of m_o - m_s along the mean
viewing direction a(q) turned square to the skeleton, times m(q), the uncovered share of the directions
facing away from the sensors (0 where the back was scanned: a complete cloud keeps the paper's value).
Curve centeredness is unchanged: its ellipse is fitted to the observed arc of a section (Eq. 11).
"""

from __future__ import annotations

import os
import threading
from dataclasses import dataclass

import numpy as np

from ..geometry import Checkpoint, no_checkpoint, unique_rows
from ..metrics.boundedness import in_raster_frame, prepared_cloud
from ..metrics.rays_kernel import ALONE_WITHIN, exact_plan, run_plan_here
from ..parallel import polled_streams
from ..params import Params

__all__ = ["seen_boundedness", "seen_directions", "direction_raster", "DepthImage", "viewing_axes", "depth_axes",
           "check_viewpoints"]

# the kernel's one sample on a 1 x 1 raster: z = 0, longitude pi (_raycast.c raster_init)
_SAMPLE = np.array([-1.0, 0.0, 0.0])


def check_viewpoints(viewpoints) -> np.ndarray:
    """(m, 3) finite float array of sensor positions; ValueError naming the problem."""
    v = np.asarray(viewpoints, dtype=float)
    if v.ndim == 1 and v.size == 3:
        v = v[None, :]
    if v.ndim != 2 or v.shape[1] != 3 or len(v) == 0:
        raise ValueError(f"viewpoints must be one or more x y z positions, got shape {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError("a viewpoint has a NaN or infinite coordinate")
    return v


def direction_raster(rows: int) -> np.ndarray:
    """(rows x 2 rows, 3) unit directions at the cell centres of an equal-area latitude raster (rows of
    equal height in z, Archimedes), the layout of the kernel's raster (docs/metrics.md 2)."""
    bins = 2 * int(rows)
    z = -1.0 + (np.arange(rows) + 0.5) * (2.0 / rows)
    lon = (np.arange(bins) + 0.5) * (2.0 * np.pi / bins)
    zz, ll = np.meshgrid(z, lon, indexing="ij")
    s = np.sqrt(1.0 - zz * zz)
    return np.column_stack([(s * np.cos(ll)).ravel(), (s * np.sin(ll)).ravel(), zz.ravel()])


class DepthImage:
    """The cloud as a depth sensor at ``viewpoint`` records it: a perspective image (axis towards the
    cloud's centre, pixels ``pixel`` wide in the tangent plane at unit distance) holding per pixel the
    distance to the nearest cloud point, each point drawn as a disc of radius ``h`` (at most ``MAX_STAMP``
    pixels)."""

    MAX_STAMP = 4

    def __init__(self, cloud: np.ndarray, viewpoint: np.ndarray, h: float):
        self.v = np.asarray(viewpoint, dtype=float)
        centre = (cloud.min(axis=0) + cloud.max(axis=0)) / 2.0
        axis = centre - self.v
        dist = float(np.linalg.norm(axis))
        axis = axis / dist if dist > 0 else np.array([0.0, 0.0, 1.0])
        e1 = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
        e1 /= np.linalg.norm(e1)
        self.basis = np.stack([e1, np.cross(axis, e1), axis])
        self.pixel = h / max(dist, h)
        uv, depth = self._project(cloud)
        ok = np.isfinite(depth)
        uv, depth = uv[ok], depth[ok]
        self.lo = uv.min(axis=0, initial=0.0) - (self.MAX_STAMP + 1) * self.pixel if len(uv) else np.zeros(2)
        ij = np.floor((uv - self.lo) / self.pixel).astype(np.int64)
        self.shape = tuple(int(x) for x in ij.max(axis=0, initial=0) + self.MAX_STAMP + 2)
        zbuf = np.full(self.shape[0] * self.shape[1], np.inf)
        radius = np.minimum(np.ceil(h / (np.maximum(depth, h) * self.pixel)), self.MAX_STAMP).astype(np.int64)
        for rad in np.unique(radius):
            pick = radius == rad
            off = np.arange(-rad, rad + 1)
            di, dj = np.meshgrid(off, off, indexing="ij")
            disc = di * di + dj * dj <= rad * rad + rad  # the pixels a disc of that radius touches
            ii = (ij[pick, 0][:, None] + di[disc][None, :]).ravel()
            jj = (ij[pick, 1][:, None] + dj[disc][None, :]).ravel()
            np.minimum.at(zbuf, ii * self.shape[1] + jj, np.repeat(depth[pick], int(disc.sum())))
        self.zbuf = zbuf

    def _project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rel = (points - self.v) @ np.ascontiguousarray(self.basis.T)  # a transposed view: 10-30 x slower
        z = rel[:, 2]
        depth = np.linalg.norm(rel, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            uv = rel[:, :2] / z[:, None]
        depth = np.where(z > 1e-12 * (depth + 1.0), depth, np.nan)  # behind the sensor: no pixel
        return uv, depth

    def hidden(self, points: np.ndarray, margin: np.ndarray) -> np.ndarray:
        """True where a cloud point lies on the line of sight from the sensor in front of the point by
        more than ``margin``; points behind the sensor count as hidden."""
        uv, depth = self._project(points)
        out = ~np.isfinite(depth)
        ij = np.floor((uv[~out] - self.lo) / self.pixel).astype(np.int64)
        inside = (ij[:, 0] >= 0) & (ij[:, 1] >= 0) & (ij[:, 0] < self.shape[0]) & (ij[:, 1] < self.shape[1])
        front = np.full(len(ij), np.inf)
        front[inside] = self.zbuf[ij[inside, 0] * self.shape[1] + ij[inside, 1]]
        out[~out] = front < depth[~out] - np.asarray(margin)[~out]
        return out


def seen_directions(queries: np.ndarray, directions: np.ndarray, images: list[DepthImage],
                    radius: np.ndarray) -> np.ndarray:
    """(Q, D) bool: a sensor could have seen the surface in direction d from query q (module docstring):
    e = q + r d faces a sensor (d . (v - e) > 0) that sees e (:meth:`DepthImage.hidden`); ``radius``
    holds r per query."""
    q = np.asarray(queries, dtype=float)
    r = np.asarray(radius, dtype=float)
    out = np.zeros((len(q), len(directions)), bool)
    for k, d in enumerate(np.asarray(directions, dtype=float)):
        out[:, k] = _seen_along(q, r, d, images)
    return out


def _seen_along(q: np.ndarray, r: np.ndarray, d: np.ndarray, images: list[DepthImage]) -> np.ndarray:
    """(Q,) bool: :func:`seen_directions` for one direction ``d``; each sensor's depth test only where
    no sensor before it saw e and e faces it."""
    e = q + r[:, None] * d
    out = np.zeros(len(q), bool)
    for image in images:
        ask = np.flatnonzero(~out & ((image.v - e) @ d > 0))
        if len(ask):
            out[ask] = ~image.hidden(e[ask], 0.5 * r[ask])
    return out


def _rotation_onto(d: np.ndarray, target: np.ndarray = _SAMPLE) -> np.ndarray:
    """The rotation matrix taking unit vector ``d`` onto ``target`` (Rodrigues)."""
    v = np.cross(d, target)
    c = float(d @ target)
    if np.linalg.norm(v) < 1e-12:
        return np.eye(3) if c > 0 else np.diag([-1.0, -1.0, 1.0])  # d = -target: a half turn about z
    vx = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + vx + vx @ vx / (1.0 + c)


@dataclass
class _TurnedTree:
    """A kernel tree turned by a rotation: what ``run_plan_here`` reads."""

    points: np.ndarray
    nodes: np.ndarray
    leaves: np.ndarray


class _Turner:
    """Turns a kernel tree by rotations, its coordinates kept in float64 once."""

    def __init__(self, tree, pad: float):
        self.points = tree.points.astype(np.float64)
        self.leaves = tree.leaves.astype(np.float64)
        self.centres = tree.nodes["c"].astype(np.float64)
        self.nodes = tree.nodes.copy()
        self.nodes["r"] += np.float32(pad)

    def __call__(self, rot: np.ndarray) -> _TurnedTree:
        """The tree's points, leaf blocks (NaN lanes stay NaN) and node centres turned by ``rot``; the
        node radii grown by ``pad`` so that the float32 rounding of the turned points never leaves a
        point outside its node's sphere."""
        rt = np.ascontiguousarray(rot.T)  # OpenBLAS took 10-30 x longer with the transposed view (same bits)
        nodes = self.nodes.copy()
        nodes["c"] = (self.centres @ rt).astype(np.float32)
        return _TurnedTree((self.points @ rt).astype(np.float32),
                           nodes, np.matmul(rot, self.leaves).astype(np.float32))


def seen_boundedness(
    cloud: np.ndarray,
    queries: np.ndarray,
    viewpoints: np.ndarray,
    *,
    params: Params = Params(),
    workers: int | None = None,
    return_missing: bool = False,
    checkpoint: Checkpoint = no_checkpoint,
) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """beta_seen of every query (module docstring): its covered directions over those and the uncovered
    directions a sensor could have seen.

    Parameters
    ----------
    cloud, queries, viewpoints : (N, 3), (Q, 3), (m, 3), normalized (docs/metrics.md 0).
    params : ``rays_radius_factor`` (h), ``viewpoint_rows`` (the direction raster).

    Returns
    -------
    (Q,) in [0, 1]; 0 for a query that counts no direction.  With ``return_missing``, also (Q,) m(q):
    the share of the directions facing away from the sensors (d . a(q) < 0) that the cloud does not
    cover (its back is missing), for :func:`depth_axes`.

    Examples
    --------
    >>> from skelcore.shapes import sphere_surface
    >>> front = sphere_surface(3000)
    >>> front = front[front[:, 0] > 0]                      # the half seen from +x
    >>> q = np.zeros((1, 3))
    >>> beta = seen_boundedness(front, q, np.array([[10.0, 0, 0]]), params=Params(viewpoint_rows=12))
    >>> bool(beta[0] > 0.9)
    True
    """
    cloud = np.asarray(cloud, dtype=float)
    queries = np.asarray(queries, dtype=float)
    viewpoints = check_viewpoints(viewpoints)
    out = np.zeros(len(queries))
    share = np.zeros(len(queries))
    if len(queries) == 0 or len(cloud) < 2:
        checkpoint(1.0)
        return (out, share) if return_missing else out
    uniq, inverse, _ = unique_rows(queries, lambda f: checkpoint(0.0))
    prepared = prepared_cloud(cloud, checkpoint)
    h = float(params.rays_radius_factor) * prepared.spacing
    if not h > 0:
        return (out, share) if return_missing else out
    q_r = in_raster_frame(uniq, prepared.centre)
    v_r = in_raster_frame(viewpoints, prepared.centre)
    # queries in Morton-like order (cells of 4 h): the kernel keeps each direction's last hit as a hint
    cell = np.floor(q_r / (4.0 * h)).astype(np.int64)
    order = np.lexsort(cell.T[::-1])
    q_r = q_r[order]
    # queries far from the cloud share one cast per cell (their centroid's; docs/metrics.md 6.3)
    group, reps, rep_radius = _sharing(q_r, h, float(params.viewpoint_share_cell), prepared.tree)
    checkpoint(0.0)
    points = prepared.tree.points.astype(np.float64)
    images = [DepthImage(points, v, h) for v in v_r]
    checkpoint(0.0)
    directions = direction_raster(int(params.viewpoint_rows))
    pad = 8.0 * float(np.finfo(np.float32).eps) * (float(np.abs(prepared.tree.points).max(initial=0.0)) + 1.0)
    n_dir, n_rep = len(directions), len(reps)
    turn = _Turner(prepared.tree, pad)
    workers = max(1, int(workers or os.cpu_count() or 1))
    n_spans = min(n_dir, 4 * workers)
    bounds = np.linspace(0, n_dir, n_spans + 1).astype(int)
    # every direction is cast: a covered direction was seen (the point it meets was scanned); the
    # sensors' tests only for the directions left uncovered
    hits = np.zeros((n_spans, n_rep), np.int64)  # covered (hence seen)
    miss_seen = np.zeros((n_spans, n_rep), np.int64)
    miss_behind = np.zeros((n_spans, n_rep), np.int64)
    n_behind = np.zeros((n_spans, n_rep), np.int64)
    axes = viewing_axes(reps, v_r)
    done = [0]
    lock = threading.Lock()
    stop = np.zeros(1, np.int32)

    def span(i: int) -> None:
        for k in range(bounds[i], bounds[i + 1]):
            if stop[0]:
                return
            d = directions[k]
            rot = _rotation_onto(d)
            q = reps @ np.ascontiguousarray(rot.T)
            hit = run_plan_here(turn(rot), exact_plan(q, h), q, h, 1, 1, stop) > 0.5
            hits[i] += hit
            behind = axes @ d < 0  # the half of the directions facing away from the sensors
            n_behind[i] += behind
            miss = np.flatnonzero(~hit)
            miss_seen[i, miss[_seen_along(reps[miss], rep_radius[miss], d, images)]] += 1
            miss_behind[i, miss[behind[miss]]] += 1
            with lock:
                done[0] += 1

    polled_streams(span, [(i,) for i in range(n_spans)], workers, checkpoint, lambda: done[0] / n_dir, stop)
    hit_r, miss_r, behind_r = hits.sum(axis=0), miss_seen.sum(axis=0), n_behind.sum(axis=0)
    counted = hit_r + miss_r
    beta_sorted = np.where(counted > 0, hit_r / np.maximum(counted, 1), 0.0)[group]
    missing_sorted = np.where(behind_r > 0, miss_behind.sum(axis=0) / np.maximum(behind_r, 1), 0.0)[group]
    beta_u = np.empty(len(uniq))
    beta_u[order] = beta_sorted
    out[:] = beta_u[inverse]
    missing_u = np.empty(len(uniq))
    missing_u[order] = np.minimum(missing_sorted, 1.0)
    share[:] = missing_u[inverse]
    checkpoint(1.0)
    return (out, share) if return_missing else out


def _sharing(q: np.ndarray, h: float, share: float, tree) -> tuple:
    """Queries farther than ``ALONE_WITHIN`` cells from the cloud share one cast per cubic cell of side
    ``share`` x h, from their centroid (the rays estimator's far-field sharing, here of every
    direction: docs/metrics.md 6.3); the others are cast alone.  Returns each query's group, the
    groups' positions and their distance r to the cloud (at least h), groups in the queries' order.
    Only the groups' r is searched unbounded (from a tube's axis the whole wall is nearly equidistant:
    an unbounded search per query cost more than the casts)."""
    n = len(q)

    def clearance(points: np.ndarray, bound: float = np.inf) -> np.ndarray:
        r = tree.clearance(points, bound)
        return np.where(np.isfinite(r), np.maximum(r, h), h)

    if not share > 0 or n == 0:
        return np.arange(n), q, clearance(q)
    cell = share * h
    bound = ALONE_WITHIN * cell
    radius = tree.clearance(q, bound * (1.0 + 1e-9))
    lone = radius < bound
    radius = np.maximum(radius, h)
    keys = np.column_stack([np.floor(q / cell).astype(np.int64), np.where(lone, np.arange(1, n + 1), 0)])
    by_key = np.lexsort(keys.T[::-1])
    ks = keys[by_key]
    first = np.r_[True, np.any(ks[1:] != ks[:-1], axis=1)]
    group = np.empty(n, np.int64)
    group[by_key] = np.cumsum(first) - 1
    # number the groups in the order of their first query (the queries' Morton-like order)
    n_groups = int(first.sum())
    first_row = np.full(n_groups, n, np.int64)
    np.minimum.at(first_row, group, np.arange(n))
    rank = np.empty(n_groups, np.int64)
    rank[np.argsort(first_row, kind="stable")] = np.arange(n_groups)
    group = rank[group]
    size = np.bincount(group, minlength=n_groups)
    reps = np.column_stack([np.bincount(group, q[:, j], n_groups) for j in range(3)]) / size[:, None]
    alone = size == 1
    one = np.empty(n_groups, np.int64)
    one[group] = np.arange(n)  # a member of each group (the one of a group of one)
    reps[alone] = q[one[alone]]  # a query alone exactly where it is
    rep_radius = np.empty(n_groups)
    near = lone[one]  # groups of a query closer than the bound: its distance is known
    rep_radius[near] = radius[one[near]]
    far = np.flatnonzero(~near)
    if len(far):
        rep_radius[far] = clearance(reps[far])
    return group, reps, rep_radius


def viewing_axes(points: np.ndarray, viewpoints: np.ndarray) -> np.ndarray:
    """a(q) of the module docstring: the mean unit direction from each point to the viewpoints; its
    length says how one-sided the viewpoints are (1: one sensor; 0: sensors on opposite sides)."""
    v = check_viewpoints(viewpoints)
    total = np.zeros((len(points), 3))
    for p in v:
        d = p - points
        n = np.linalg.norm(d, axis=1, keepdims=True)
        total += np.divide(d, n, out=np.zeros_like(d), where=n > 0)
    return total / len(v)


def depth_axes(points: np.ndarray, viewpoints: np.ndarray, missing: np.ndarray) -> np.ndarray:
    """Per point, the unit mean viewing direction a(q) / |a(q)| (:func:`viewing_axes`) scaled by m(q)
    (from :func:`seen_boundedness`): how much of skeletal centeredness' offset along it to leave out."""
    a = viewing_axes(points, viewpoints)
    n = np.linalg.norm(a, axis=1, keepdims=True)
    u = np.divide(a, n, out=np.zeros_like(a), where=n > 1e-9)
    return u * np.asarray(missing, dtype=float)[:, None]
