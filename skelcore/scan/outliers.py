"""Stray points: background returns far from the scanned surface (docs/metrics.md 6.4).

One stray point sets the normalization every metric runs in (docs/metrics.md 0), so strays change
d_B and centeredness. A point is an outlier when it fails both of PCL's and Open3D's tests (a point in
a sparse but real part fails at most one): the radius test (fewer than ``outlier_min_neighbours``
others within ``outlier_radius`` x the median spacing) and the statistical test (its mean distance to
its ``outlier_k`` nearest neighbours more than ``outlier_std_ratio`` robust deviations above the
cloud's). Both yardsticks are also taken locally (:func:`local_spacing`, the lower quartile of the
spacings of its ``outlier_local_k`` nearest points), so a part sampled 10 x more sparsely keeps its
points. Last, a stray lies off the surface along its normal, where a lone sample of a one-sided scan
lies in a gap of it (:mod:`.off_surface`); and a point within the radius of one that is kept is kept
(:func:`border_rows`, DBSCAN's border points); a point the surface encloses is no return from the air
(:mod:`.enclosed`); on a one-sided scan, a point along the view axis from its nearest surface points
lies in their shadow (:mod:`.view_axis`). A skeletal set in pointwise correspondence is held to the
radius test alone with the cloud's spacing (:func:`isolated_rows`): contraction stacks skeletal points, so their own spacing says nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..geometry import Checkpoint, Normalization, kd_tree, leaf_order, no_checkpoint, query_workers, timed_query
from ..params import Params
from .enclosed import enclosed
from .off_surface import beyond_box, off_surface
from .view_axis import along_axis, view_axis

__all__ = ["Outliers", "find_outliers", "border_rows", "isolated_rows", "sparse_rows", "local_spacing"]

#: the quantile of the nearest-neighbour distances around a point taken as its local spacing: the
#: lower quarter, so that strays among a point's neighbours (5-20 % of a cloud in the benchmark's
#: outliers effect) do not widen the yardstick that finds them
LOCAL_QUANTILE = 0.25

#: points whose nearest-neighbour distances give the spacing and the statistical test's yardstick (a
#: random sample of this many beyond)
REFERENCE_SAMPLE = 20_000


@dataclass(frozen=True)
class Outliers:
    """The stray points of a cloud and what they do to its normalization."""

    rows: np.ndarray  # cloud rows of the outliers, increasing
    n_points: int  # points in the cloud
    scale_ratio: float  # the normalization's measure (longest side or diagonal) with them / without them
    centre_shift: float  # how far they move the bounding box's centre, in units of that measure without them
    spacing: float = 0.0  # the cloud's median nearest-neighbour distance (the radius test's yardstick)

    @property
    def count(self) -> int:
        return int(len(self.rows))

    def to_dict(self) -> dict:
        return {"count": self.count, "rows": [int(r) for r in self.rows], "scale_ratio": float(self.scale_ratio),
                "centre_shift": float(self.centre_shift), "spacing": float(self.spacing)}


def find_outliers(cloud: np.ndarray, params: Params = Params(), *, checkpoint: Checkpoint = no_checkpoint,
                  tree: cKDTree | None = None) -> Outliers:
    """The outliers of ``cloud`` (module docstring) and how far they move the normalization of docs/metrics.md 0.

    The spacing (median nearest-neighbour distance) and the statistical test's yardstick come from at
    most ``REFERENCE_SAMPLE`` random points (every point below that; seed 0), the yardstick only when
    some row is sparse; the radius test asks only the rows no crowded cell vouches for
    (:func:`sparse_rows`, exact).  At 1M points
    ~1.2 CPU s (a kNN pass over every row and an exact median took 2-4; docs/performance.md 6.6).

    Examples
    --------
    >>> from skelcore.shapes import sphere_surface
    >>> cloud = np.vstack([sphere_surface(2000), [[30.0, 0, 0]]])
    >>> o = find_outliers(cloud)
    >>> o.rows.tolist(), round(o.scale_ratio, 1)
    ([2000], 15.5)
    """
    cloud = np.asarray(cloud, dtype=float)
    n = len(cloud)
    m = int(params.outlier_min_neighbours)
    k = int(params.outlier_k)
    if n <= max(m, k) + 1:
        return Outliers(np.zeros(0, np.int64), n, 1.0, 0.0)
    if tree is None:  # sliding midpoint: half the build time, the same distances
        tree = kd_tree(cloud, checkpoint, 0.0)
    checkpoint(0.1)
    sample = np.arange(n) if n <= REFERENCE_SAMPLE else np.random.default_rng(0).choice(n, REFERENCE_SAMPLE, replace=False)
    # the nearest other point first: a clean cloud has no sparse row, and the statistical test's
    # yardstick (k + 1 neighbours, twice the query) is asked only when some row is (the same distances)
    spacing = float(np.median(tree.query(cloud[sample], k=2, workers=query_workers(len(sample)))[0][:, 1]))
    checkpoint(0.2)
    none = Outliers(np.zeros(0, np.int64), n, 1.0, 0.0, spacing)
    if not spacing > 0:
        return none
    candidates = sparse_rows(cloud, float(params.outlier_radius) * spacing, m, lambda f: checkpoint(0.2 + 0.6 * f),
                             tree=tree)
    checkpoint(0.8)
    if len(candidates) == 0:
        return none
    near = tree.query(cloud[sample], k=k + 1, workers=query_workers(len(sample)))[0]
    ref = near[:, 1:].mean(axis=1)
    centre = float(np.median(ref))
    sigma = 1.4826 * float(np.median(np.abs(ref - centre)))
    mean_d = tree.query(cloud[candidates], k=k + 1, workers=query_workers(len(candidates)))[0][:, 1:].mean(axis=1)
    rows = candidates[mean_d > centre + float(params.outlier_std_ratio) * sigma]
    if len(rows):  # and isolated by the spacing around them, not only the cloud's
        local = local_spacing(cloud, cloud[rows], int(params.outlier_local_k), tree)
        d_m = tree.query(cloud[rows], k=m + 1, workers=query_workers(len(rows)))[0][:, m]
        rows = rows[d_m > float(params.outlier_radius) * local]
    surface = np.ones(n, bool)
    surface[candidates] = False
    if len(rows):  # and off the surface, not in a gap of it (.off_surface)
        rows = rows[off_surface(cloud, rows, surface, params, float(params.outlier_radius) * spacing, spacing)]
    if len(rows):  # and linked to no point that is kept (a sliver of the surface, not a stray)
        beyond = beyond_box(cloud, rows, cloud[surface])
        rows = rows[~border_rows(cloud, rows, float(params.outlier_radius) * spacing, tree, stays=beyond)]
    if len(rows):  # and in the air, not enclosed by the surface (.enclosed)
        base = cloud[surface]
        base_tree = cKDTree(base)
        rows = rows[~enclosed(cloud[rows], base, base_tree, spacing, params)]
        axis = view_axis(cloud, params) if len(rows) else None
        if axis is not None:  # and not in the shadow of a one-sided scan's front (.view_axis)
            near = base_tree.query(cloud[rows], k=int(params.outlier_surface_points))[1]
            near = near.reshape(len(rows), -1)
            rows = rows[~along_axis(cloud[rows], base, near, axis, params) | beyond_box(cloud, rows, base)]
    checkpoint(0.9)
    if len(rows) == 0 or len(rows) >= n - 1:
        return none
    keep = np.ones(n, bool)
    keep[rows] = False
    with_them = Normalization.from_cloud(cloud, params.normalize_by, params.normalized_size)
    try:
        without = Normalization.from_cloud(cloud[keep], params.normalize_by, params.normalized_size)
    except ValueError:  # all the others coincide: nothing to normalize by
        return none
    # scale = normalized_size / measure, so measure ratio = inverse scale ratio
    ratio = without.scale / with_them.scale
    shift = float(np.linalg.norm(with_them.center - without.center) * without.scale / params.normalized_size)
    return Outliers(rows.astype(np.int64), n, float(ratio), shift, spacing)


def border_rows(cloud: np.ndarray, rows: np.ndarray, radius: float, tree: cKDTree,
                stays: np.ndarray | None = None) -> np.ndarray:
    """(len(rows),) bool: the flagged point at each row lies within ``radius`` of a point not flagged, or
    of a flagged point that is itself such a border point (to a fixed point): DBSCAN's border points.
    A stray falls in the volume independently of the surface, so the points within the radius test's
    reach of it are strays too, or none; a lone sample of a one-sided scan is the visible sliver of a
    part (the 100k one-sided neuron scans: pairs 5 spacings apart, one of them kept), linked to it.
    ``stays``: rows never linked (beyond the surface points' box, as in :mod:`.off_surface`: the
    strays that set the normalization)."""
    rows = np.asarray(rows, np.int64)
    flagged = np.zeros(len(cloud), bool)
    flagged[rows] = True
    linked = np.zeros(len(rows), bool)
    fixed = np.zeros(len(rows), bool) if stays is None else np.asarray(stays, bool)
    while True:
        ask = np.flatnonzero(~linked & ~fixed)
        near = tree.query_ball_point(cloud[rows[ask]], radius) if len(ask) else []
        new = ask[np.array([not flagged[nb].all() for nb in near], bool).reshape(-1)]
        if len(new) == 0:
            return linked
        linked[new] = True
        flagged[rows[new]] = False


def isolated_rows(points: np.ndarray, spacing: float, params: Params = Params(),
                  checkpoint: Checkpoint = no_checkpoint, cloud: np.ndarray | None = None,
                  cloud_tree: cKDTree | None = None) -> np.ndarray:
    """Rows of ``points`` (a skeletal set) with fewer than ``outlier_min_neighbours`` other points within
    ``outlier_skeletal_radius`` x ``spacing`` (the radius test with the cloud's spacing as yardstick) and,
    given the ``cloud`` in pointwise correspondence, also within that many x the cloud's local spacing at
    its row (:func:`local_spacing`; a sparsely sampled part contracts to a sparse skeletal set), and that
    lies no farther from its cloud row than the other skeletal points do (else the contraction flung a
    surface point off: the skeleton's defect, which the diagnostics judge, not a stray of the scan).
    ``cloud_tree``: the cloud's kd-tree when the caller has one (:func:`find_outliers`' own)."""
    points = np.asarray(points, dtype=float)
    m = int(params.outlier_min_neighbours)
    if len(points) <= m or not spacing > 0:
        return np.zeros(0, np.int64)
    radius = float(params.outlier_skeletal_radius) * spacing
    rows, skel_tree = _sparse_rows_and_tree(points, radius, m, checkpoint)  # a contracted set: ~8 % asked
    if len(rows) and cloud is not None and len(cloud) == len(points):
        cloud = np.asarray(cloud, dtype=float)
        tree = kd_tree(cloud, checkpoint, 0.0) if cloud_tree is None else cloud_tree
        local = local_spacing(cloud, cloud[rows], int(params.outlier_local_k), tree)
        d_m = skel_tree.query(points[rows], k=m + 1, workers=-1)[0][:, m]
        moved = np.linalg.norm(points[rows] - cloud[rows], axis=1)
        to_skeleton = skel_tree.query(cloud[rows], k=2, workers=-1)[0]  # its own image may be the nearest
        to_others = np.where(np.isclose(to_skeleton[:, 0], moved), to_skeleton[:, 1], to_skeleton[:, 0])
        far = float(params.outlier_skeletal_radius) * local
        # a stray's image stays with its point; a surface point that the contraction flung farther than
        # the rest of the skeleton is from it is the skeleton's defect (the diagnostics judge it), not a stray
        rows = rows[(d_m > far) & (moved <= to_others)]
    return rows


def local_spacing(cloud: np.ndarray, at: np.ndarray, k: int, tree: cKDTree | None = None,
                  quantile: float = LOCAL_QUANTILE) -> np.ndarray:
    """The cloud's spacing around each point of ``at``: the lower quartile (``LOCAL_QUANTILE``) of the
    nearest-neighbour distances of its ``k`` nearest cloud points (docs/metrics.md 6.4).  A stray's nearest cloud points are mostly the surface's,
    so its own isolation does not widen its yardstick.  ``quantile`` 0.5: the sampling's own spacing
    there (``sparse_boundedness``: the lower quartile reads a density gradient's denser side)."""
    tree = cKDTree(cloud) if tree is None else tree
    k = int(min(k, len(cloud) - 1))
    near = tree.query(np.asarray(at, float), k=k, workers=-1)[1]
    nn = tree.query(cloud[near.ravel()], k=2, workers=-1)[0][:, 1].reshape(near.shape)
    return np.quantile(nn, quantile, axis=1)


def sparse_rows(points: np.ndarray, radius: float, others: int, checkpoint: Checkpoint = no_checkpoint,
                tree: cKDTree | None = None) -> np.ndarray:
    """Rows of ``points`` with fewer than ``others`` other points within ``radius``, exact (``tree``: the
    points' kd-tree, if the caller has one).

    Cubic cells of side radius / sqrt(3) (less a rounding margin) first: any two points of a cell are
    within ``radius``, so a row whose cell holds ``others`` more is not sparse.  Only the rest are asked
    of the tree: on a clean 1M-point scan about 5 % of the rows, on a contracted set 8 %, so a kNN pass
    over every row (~1.5 CPU s) becomes a sort, the tree's build and a short pass.  Every row is asked
    where the cells cannot be numbered in 63 bits (a stray point very far away)."""
    return _sparse_rows_and_tree(points, radius, others, checkpoint, tree)[0]


def _sparse_rows_and_tree(points: np.ndarray, radius: float, others: int, checkpoint: Checkpoint = no_checkpoint,
                          tree: cKDTree | None = None) -> tuple[np.ndarray, cKDTree | None]:
    """:func:`sparse_rows` and the points' kd-tree it built or was given (None: no row needed it)."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    ask = np.flatnonzero(~_crowded(points, radius, others, checkpoint))
    checkpoint(0.0)
    if len(ask) == 0:
        return np.zeros(0, np.int64), tree
    tree = kd_tree(points, checkpoint, 0.0) if tree is None else tree  # polled: 1M points held a cancel 0.6 s
    checkpoint(0.0)
    order = leaf_order(tree) if len(ask) == len(points) else None  # cache-warm when every row is asked
    d, _ = timed_query(tree, points[ask], others + 1, checkpoint, order=order)
    return ask[d[:, others] > radius].astype(np.int64), tree


def _crowded(points: np.ndarray, radius: float, others: int, checkpoint: Checkpoint = no_checkpoint) -> np.ndarray:
    """Rows sharing a cell of diameter ``radius`` with ``others`` more (:func:`sparse_rows`); a
    checkpoint between the passes (1M rows: ~0.1 s each)."""
    out = np.zeros(len(points), bool)
    cell = radius / np.sqrt(3.0) * (1.0 - 1e-9)
    if len(points) == 0 or not cell > 0:
        return out
    lo = points.min(axis=0)
    span = (points.max(axis=0) - lo) / cell
    if not np.all(np.isfinite(span)) or float(np.prod(span + 1.0)) >= 2.0**62:
        return out
    ijk = np.floor((points - lo) / cell).astype(np.int64)
    dims = ijk.max(axis=0) + 1
    key = ijk[:, 0] + dims[0] * (ijk[:, 1] + dims[1] * ijk[:, 2])
    checkpoint(0.0)
    order = np.argsort(key)
    checkpoint(0.0)
    sorted_key = key[order]
    starts = np.flatnonzero(np.r_[True, sorted_key[1:] != sorted_key[:-1]])
    counts = np.diff(np.r_[starts, len(key)])
    out[order] = np.repeat(counts >= others + 1, counts)
    return out
