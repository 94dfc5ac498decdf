"""Openings of a scanned surface: where the cloud's boundary points enclose a region with no points
(docs/metrics.md 6.1).

The paper's boundedness assumes a closed surface (it capped its cave "to ensure a closed shape"); a
scan seen from one side, or a tube cut open, lets the rays of a perfect skeleton escape.  An opening is
a connected group of boundary points (:mod:`.boundary`, linked within ``open_link`` median spacings)
whose rim encloses missing surface: its plane, centre and radius from the rim's PCA; its *fill*, grid
points on the rim's surface (the plane lifted by the rim's own offsets) that the rim surrounds and that
lie ``open_empty`` spacings from every cloud point (fewer than ``open_min_fill``: a sampling gap, not an
opening); its *dome*, the fill bulged away from the cloud as a half-cylinder over a long cut or a
hemisphere over a round one (the surface the scan would plausibly have had: ``open_surface`` counts the
rays it stops); its kind, an open tube ``end`` when the rim is flat, round and goes round its centre,
else a missing ``side``.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..geometry import Checkpoint, no_checkpoint
from ..params import Params
from .boundary import boundary_mask, largest_angle_gap
from .surround import surrounded

__all__ = ["Opening", "find_openings", "thin_parts", "median_spacing", "fill_rim"]

#: rim points used by the surround test of the fill (evenly spread); enough for gaps well under 90 degrees
RIM_SAMPLE = 512
#: grid points of one opening's fill at most (the grid step grows beyond)
MAX_FILL = 200_000
_MEMO_RIMS = 4096  # rims' openings a memo keeps (emptied beyond)


@dataclass
class Opening:
    """One opening; coordinates in the units of the cloud it was found in."""

    rows: np.ndarray  # cloud rows of its rim (boundary points)
    centre: np.ndarray  # (3,) the rim's centroid
    normal: np.ndarray  # (3,) unit normal of the rim's plane, pointing away from the cloud
    radius: float  # mean distance of the rim from its centre, in the plane
    extent: float  # twice the largest such distance
    flatness: float  # RMS distance of the rim from its plane / radius
    roundness: float  # coefficient of variation of the rim's distances from the centre
    surrounds: bool  # the rim goes all round its centre
    kind: str  # "end" (open tube end) | "side" (missing side)
    fill: np.ndarray  # (m, 3) the empty part of the flat fill (what --cap-openings adds)
    dome: np.ndarray  # (m', 3) the fill bulged away from the cloud, where it is empty
    spacing: float  # the grid step of the fill and the dome (2 x the median spacing near the rim)
    local_radius: float = float("nan")  # the shape's radius at the rim (from a skeleton, set later)
    rim_spacing: float = float("nan")  # median nearest-neighbour distance of the rim's points
    notes: dict = field(default_factory=dict)

    @property
    def area(self) -> float:
        """Area of the missing surface: the flat fill's cells."""
        return float(len(self.fill)) * self.spacing**2

    @property
    def size(self) -> float:
        """The opening's extent in local radii (an open tube end: about 2); NaN without a local radius."""
        return self.extent / self.local_radius if self.local_radius > 0 else float("nan")

    def to_dict(self, transform=None) -> dict:
        """JSON-ready summary; ``transform`` maps points to other units (positions and lengths)."""
        scale = 1.0
        centre = self.centre
        if transform is not None:
            centre, scale = transform(self.centre[None, :])[0], transform.scale
        return {
            "kind": self.kind,
            "n_rim": int(len(self.rows)),
            "centre": [float(x) for x in centre],
            "normal": [float(x) for x in self.normal],
            "radius": float(self.radius * scale),
            "extent": float(self.extent * scale),
            "area": float(self.area * scale**2),
            "n_fill": int(len(self.fill)),
            "flatness": float(self.flatness),
            "roundness": float(self.roundness),
            "local_radius": float(self.local_radius * scale),
            "rim_spacing": float(self.rim_spacing * scale),
            "size": float(self.size),
        }


def median_spacing(cloud: np.ndarray, tree: cKDTree | None = None) -> float:
    """Median distance from a point to its nearest other point (copies count as 0)."""
    if len(cloud) < 2:
        return 0.0
    tree = cKDTree(cloud) if tree is None else tree
    d, _ = tree.query(cloud, k=2, workers=-1)
    return float(np.median(d[:, 1]))


def find_openings(
    cloud: np.ndarray,
    params: Params = Params(),
    *,
    checkpoint: Checkpoint = no_checkpoint,
    diameter: Callable[[np.ndarray], np.ndarray] | None = None,
    thin_rows: list | None = None,
    memo: dict | None = None,
) -> list[Opening]:
    """The openings of ``cloud`` (module docstring), largest fill first.

    ``diameter`` (points -> the shape's local diameter there, e.g. twice the distance to a skeleton)
    marks the boundary points of parts fewer than ``open_resolved_diameter`` of their spacings across
    as thin: there the k nearest neighbours wrap round the part and the angle test sees gaps in any
    sampling (docs/metrics.md 6.1), when their neighbours are curved too (smallest / middle eigenvalue
    of their covariance above ``open_thin_planarity``). Thin points join no opening; their cloud rows are
    appended to ``thin_rows``.

    Above ``open_max_points`` points the boundary test runs on a random subsample of that many (fixed
    seed); ``rows`` then index the full cloud all the same.  A closed, evenly sampled surface has none.
    ``memo`` (a dict kept along an evaluation's updates) keeps the boundary test of the same cloud array
    and each rim's opening: after an edit only the rims whose thin points changed are looked at again.

    Examples
    --------
    >>> from skelcore.shapes import cylinder
    >>> [o.kind for o in find_openings(cylinder(4000, capped=False).cloud)]
    ['end', 'end']
    >>> find_openings(cylinder(4000).cloud)
    []
    """
    cloud = np.asarray(cloud, dtype=float)
    n = len(cloud)
    if n < max(int(params.open_k) + 1, 8):
        return []
    prefix = memo.get("boundary") if memo is not None else None
    if prefix is None or prefix[0] is not cloud or prefix[1] != params:
        prefix = (cloud, params, *_boundary(cloud, params, checkpoint))
        if memo is not None:
            memo.clear()
            memo["boundary"] = prefix
    rows, pts, tree, nn, spacing, rim = prefix[2:]
    k = int(min(params.open_k, len(pts) - 1))
    thin = np.zeros(len(rim), bool)
    if diameter is not None and len(rim):
        thin = np.asarray(diameter(pts[rim]), float) < float(params.open_resolved_diameter) * nn[rim]
        if thin.any():  # ... and curved at the scale of its neighbours (a flat cap's centre is on the skeleton)
            nb = pts[tree.query(pts[rim[thin]], k=k + 1, workers=-1)[1]]
            nb = nb - nb.mean(axis=1, keepdims=True)
            ev = np.linalg.eigvalsh(np.matmul(nb.transpose(0, 2, 1), nb))
            thin[np.flatnonzero(thin)] = ev[:, 0] > float(params.open_thin_planarity) * ev[:, 1]
    if thin_rows is not None:
        thin_rows.extend(rows[rim[thin]].tolist())
    rim = rim[~thin]
    if len(rim) < 3 or not spacing > 0:
        return []
    # the rays of boundedness are h = rays_radius_factor x the cloud's median spacing wide: a gap narrower
    # than a few of those spacings lets none through, however dense the rim (a crumpled, self-overlapping
    # mesh is sampled many times more densely than the cloud, and "gaps" there are the cloud's spacing)
    floor = spacing * float(np.sqrt(len(pts) / n))
    pairs = cKDTree(pts[rim]).query_pairs(float(params.open_link) * spacing, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(rim), len(rim)))
    n_groups, label = connected_components(graph, directed=False)
    sizes = np.bincount(label, minlength=n_groups)
    out = []
    candidates = [g for g in np.argsort(-sizes) if sizes[g] >= 5]
    kept = memo.setdefault("rims", {}) if memo is not None else {}
    if len(kept) > _MEMO_RIMS:
        kept.clear()
    for i, g in enumerate(candidates):
        members = rim[label == g]
        key = members.tobytes()
        if key not in kept:
            local = float(np.median(nn[members]))
            opening = _opening(pts, members, tree, local if local > 0 else spacing, params, floor)
            if opening is not None:
                opening.rows = rows[members]
                opening.rim_spacing = local if local > 0 else spacing
            kept[key] = opening
        if kept[key] is not None:
            out.append(copy.deepcopy(kept[key]))  # callers set local radii and notes on theirs
        checkpoint(0.65 + 0.35 * (i + 1) / len(candidates))
    out = _without_nested(out)
    out.sort(key=lambda o: -len(o.fill))
    return out


def _boundary(cloud: np.ndarray, params: Params, checkpoint: Checkpoint) -> tuple:
    """The skeleton-free part of :func:`find_openings`: (rows tested, their points, their tree, each
    point's spacing from its k-th neighbour, the median spacing, the rim's indices into the points)."""
    n = len(cloud)
    rows = np.arange(n)
    if n > int(params.open_max_points):
        rows = np.sort(np.random.default_rng(0).choice(n, int(params.open_max_points), replace=False))
    pts = cloud[rows]
    tree = cKDTree(pts)
    nn = np.empty(len(pts))
    reach = np.empty(len(pts))
    k = int(min(params.open_k, len(pts) - 1))
    checkpoint(0.05)
    on_rim = boundary_mask(pts, k=k, angle=np.radians(params.open_angle), tree=tree,
                           spacing_out=nn, reach_out=reach, checkpoint=lambda f: checkpoint(0.05 + 0.6 * f))
    spacing = float(np.median(nn))
    rim = np.flatnonzero(on_rim)
    if len(rows) < n and len(rim):  # the spacing near a rim is the full cloud's, not the subsample's
        reach[rim] = cKDTree(cloud).query(pts[rim], k=k + 1, workers=-1)[0][:, k]
    # a rim point's spacing from its k-th neighbour (the half disc its k neighbours cover): the median
    # nearest distance of a uniform sample is sqrt(ln 2 / 2k) x that; its own nearest neighbour may be
    # the far side of a sheet thinner than the sampling, which made rims of dense crumples
    nn = reach * np.sqrt(np.log(2.0) / (2 * k))
    return rows, pts, tree, nn, spacing, rim


def thin_parts(cloud: np.ndarray, rows: np.ndarray, params: Params = Params()) -> dict | None:
    """The boundary points left out as parts too thin for their sampling (:func:`find_openings`'s
    ``thin_rows``), linked within ``open_link`` of their median spacings into parts of at least 5: their
    count, points and box (the cloud's units); None when they are fewer than ``thin_min_share`` of the
    cloud (a few twigs do not change a score; docs/metrics.md 6.1)."""
    cloud = np.asarray(cloud, dtype=float)
    rows = np.unique(np.asarray(rows, np.int64))
    if len(rows) < max(5, float(params.thin_min_share) * len(cloud)):
        return None
    pts = cloud[rows]
    tree = cKDTree(pts)
    link = float(params.open_link) * float(np.median(cKDTree(cloud).query(pts, k=2, workers=-1)[0][:, 1]))
    pairs = tree.query_pairs(link, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(pts), len(pts)))
    n_groups, label = connected_components(graph, directed=False)
    sizes = np.bincount(label, minlength=n_groups)
    keep = np.isin(label, np.flatnonzero(sizes >= 5))
    if not keep.any():
        return None
    lo, hi = pts[keep].min(axis=0), pts[keep].max(axis=0)
    return {"parts": int(np.count_nonzero(sizes >= 5)), "points": int(keep.sum()), "share": float(len(rows) / len(cloud)),
            "box": [[float(x) for x in lo], [float(x) for x in hi]]}


def _without_nested(openings: list[Opening]) -> list[Opening]:
    """Drop an opening whose missing surface is mostly another's: the outer rim of a flat annulus fills
    the hole its inner rim already bounds (rims by size, the smaller kept)."""
    kept: list[Opening] = []
    for o in sorted(openings, key=lambda o: len(o.rows)):
        if kept and len(o.fill):
            others = cKDTree(np.vstack([k.fill for k in kept]))
            d, _ = others.query(o.fill, k=1, workers=-1)
            if np.mean(d <= o.spacing) > 0.5:
                continue
        kept.append(o)
    return kept


def _opening(pts: np.ndarray, members: np.ndarray, tree: cKDTree, spacing: float, params: Params,
             floor: float = 0.0) -> Opening | None:
    rim = pts[members]
    centre = rim.mean(axis=0)
    _, sv, vt = np.linalg.svd(rim - centre, full_matrices=False)
    e1, e2, normal = vt[0], vt[1], vt[2]
    uv = (rim - centre) @ np.column_stack([e1, e2])
    off = (rim - centre) @ normal
    dist = np.linalg.norm(uv, axis=1)
    radius = float(dist.mean())
    if not radius > 0:
        return None
    flatness = float(np.sqrt(np.mean(off**2)) / radius)
    roundness = float(dist.std() / radius)
    surrounds = bool(largest_angle_gap((rim - centre)[None], np.stack([e1, e2, normal])[None])[0]
                     < np.radians(params.open_angle))
    flat, d_rim, step = fill_rim(uv, off, 2.0 * spacing, np.radians(params.open_angle))
    if len(flat) == 0:
        return None
    basis = np.stack([e1, e2, normal])
    fill3 = centre + flat @ basis
    empty = float(params.open_empty) * max(spacing, floor)
    fill_d, _ = tree.query(fill3, k=1, workers=-1)
    fill = fill3[fill_d > empty]
    if len(fill) < int(params.open_min_fill):
        return None
    # the cloud near the opening lies on one side of its plane: the dome bulges to the other
    near = tree.query_ball_point(centre, r=max(dist.max(), spacing) * 1.5)
    side = float(np.mean((pts[near] - centre) @ normal)) if near else 0.0
    if side > 0:
        normal = -normal
    d_max = float(d_rim.max())
    height = np.sqrt(np.maximum(d_max**2 - (d_max - d_rim) ** 2, 0.0))
    dome3 = fill3 + height[:, None] * normal
    dome_d, _ = tree.query(dome3, k=1, workers=-1)
    dome = dome3[dome_d > empty]
    end = flatness < params.open_end_flatness and roundness < params.open_end_roundness and surrounds
    return Opening(rows=members, centre=centre, normal=normal, radius=radius, extent=2.0 * float(dist.max()),
                   flatness=flatness, roundness=roundness, surrounds=surrounds, kind="end" if end else "side",
                   fill=fill, dome=dome, spacing=step)


def fill_rim(uv: np.ndarray, off: np.ndarray, spacing: float, angle: float) -> tuple[np.ndarray, np.ndarray, float]:
    """The grid points (in-plane u, v, offset) that the rim ``uv`` (with offsets ``off`` from the plane)
    surrounds, their distance to the rim, and the grid step (``spacing``, larger for a huge rim)."""
    lo, hi = uv.min(axis=0), uv.max(axis=0)
    step = spacing
    cells = np.prod(np.floor((hi - lo) / step) + 1)
    if cells > MAX_FILL:
        step *= float(np.sqrt(cells / MAX_FILL))
    gu = np.arange(lo[0] + step / 2, hi[0], step)
    gv = np.arange(lo[1] + step / 2, hi[1], step)
    if len(gu) == 0 or len(gv) == 0:
        return np.empty((0, 3)), np.empty(0), step
    grid = np.column_stack([np.repeat(gu, len(gv)), np.tile(gv, len(gu))])
    pick = np.linspace(0, len(uv) - 1, min(len(uv), RIM_SAMPLE)).astype(int)
    grid = grid[surrounded(uv[pick], grid, angle)]
    if len(grid) == 0:
        return np.empty((0, 3)), np.empty(0), step
    rim_tree = cKDTree(uv)
    k = min(8, len(uv))
    d, idx = rim_tree.query(grid, k=k, workers=-1)
    d = d.reshape(len(grid), k)
    idx = idx.reshape(len(grid), k)
    w = 1.0 / np.maximum(d, 1e-12 * spacing) ** 2
    lift = (w * off[idx]).sum(axis=1) / w.sum(axis=1)
    return np.column_stack([grid, lift]), d[:, 0], step
