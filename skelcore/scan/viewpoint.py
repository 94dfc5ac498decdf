"""Viewpoint-aware boundedness and centeredness: score what the sensors could have seen
(docs/metrics.md 6.3; SkelScope's extension, the paper's definitions unchanged without a viewpoint).

Given the sensors' positions, boundedness leaves out the escaping directions no sensor could have seen:
beta_seen(q) = |covered| / (|covered| + |uncovered and seen|).  A covered direction was seen (the point it
meets was scanned); an uncovered direction d is seen when e = q + r d (r: q's distance to the cloud)
faces a sensor (d . (v - e) > 0) and no scanned point lies in front of e on the sensor's line of sight
(:class:`DepthImage`).  Several sensors: the union.  Directions are counted on an equal-area raster of
``viewpoint_rows`` x 2 ``viewpoint_rows``; each is cast on its own by the unchanged compiled kernel, its
tree turned so that the direction is the one sample of a 1 x 1 raster.

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
from ..metrics.rays_kernel import exact_plan, run_plan_here
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
    equal height in z, Archimedes), the layout of the kernel's raster (SPEC 2)."""
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
        rel = (points - self.v) @ self.basis.T
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
    chunk = max(1, 2_000_000 // max(1, len(directions)))
    for i0 in range(0, len(q), chunk):
        sl = slice(i0, i0 + chunk)
        e = q[sl][:, None, :] + r[sl][:, None, None] * directions[None, :, :]
        margin = np.repeat(0.5 * r[sl], len(directions))
        for image in images:
            facing = np.einsum("dk,qdk->qd", directions, image.v - e) > 0
            out[sl] |= facing & ~image.hidden(e.reshape(-1, 3), margin).reshape(facing.shape)
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


def _turned(tree, rot: np.ndarray, pad: float) -> _TurnedTree:
    """The tree's points, leaf blocks and node centres turned by ``rot``; node radii grown by ``pad`` so that
    the float32 rounding of the turned points never leaves a point outside its node's sphere."""
    points = (tree.points.astype(np.float64) @ rot.T).astype(np.float32)
    leaves = np.einsum("ij,ljk->lik", rot, tree.leaves.astype(np.float64)).astype(np.float32)  # NaN lanes stay NaN
    nodes = tree.nodes.copy()
    nodes["c"] = (nodes["c"].astype(np.float64) @ rot.T).astype(np.float32)
    nodes["r"] += np.float32(pad)
    return _TurnedTree(points, nodes, leaves)


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
    cloud, queries, viewpoints : (N, 3), (Q, 3), (m, 3), normalized (SPEC 0).
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
    points = prepared.tree.points.astype(np.float64)
    radius = prepared.tree.clearance(q_r, np.inf)
    radius = np.where(np.isfinite(radius), np.maximum(radius, h), h)
    images = [DepthImage(points, v, h) for v in v_r]
    checkpoint(0.0)
    directions = direction_raster(int(params.viewpoint_rows))
    seen = seen_directions(q_r, directions, images, radius)
    checkpoint(0.0)
    pad = 8.0 * float(np.finfo(np.float32).eps) * (float(np.abs(prepared.tree.points).max(initial=0.0)) + 1.0)
    n_dir = len(directions)
    workers = max(1, int(workers or os.cpu_count() or 1))
    n_spans = min(n_dir, 4 * workers)
    bounds = np.linspace(0, n_dir, n_spans + 1).astype(int)
    # every direction is cast: a covered direction was seen (the point it meets was scanned)
    hit_seen = np.zeros((n_spans, len(q_r)), np.int64)  # covered (hence seen)
    miss_seen = np.zeros((n_spans, len(q_r)), np.int64)
    miss_behind = np.zeros((n_spans, len(q_r)), np.int64)
    axes = viewing_axes(q_r, v_r)
    behind = (axes @ directions.T) < 0  # (Q, D): the half of the directions facing away from the sensors
    done = [0]
    lock = threading.Lock()
    stop = np.zeros(1, np.int32)

    def span(i: int) -> None:
        for k in range(bounds[i], bounds[i + 1]):
            if stop[0]:
                return
            rot = _rotation_onto(directions[k])
            q = q_r @ rot.T
            hit = run_plan_here(_turned(prepared.tree, rot, pad), exact_plan(q, h), q, h, 1, 1, stop) > 0.5
            hit_seen[i] += hit
            miss_seen[i] += ~hit & seen[:, k]
            miss_behind[i] += ~hit & behind[:, k]
            with lock:
                done[0] += 1

    polled_streams(span, [(i,) for i in range(n_spans)], workers, checkpoint, lambda: done[0] / n_dir, stop)
    hits, misses, missed_behind = hit_seen.sum(axis=0), miss_seen.sum(axis=0), miss_behind.sum(axis=0)
    counted = hits + misses
    beta_sorted = np.where(counted > 0, hits / np.maximum(counted, 1), 0.0)
    n_behind = behind.sum(axis=1)
    missing_sorted = np.where(n_behind > 0, missed_behind / np.maximum(n_behind, 1), 0.0)
    beta_u = np.empty(len(uniq))
    beta_u[order] = beta_sorted
    out[:] = beta_u[inverse]
    missing_u = np.empty(len(uniq))
    missing_u[order] = np.minimum(missing_sorted, 1.0)
    share[:] = missing_u[inverse]
    checkpoint(1.0)
    return (out, share) if return_missing else out


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
