"""Unexplained regions beside a branch: the far wall of a tube whose skeleton runs off its centre line,
the wide sides of a flat part (docs/diagnostics.md "Missing parts", "Beside a branch").

A missing part reaches away from the skeleton: a missing arm or a cut end lies several local radii
beyond any branch. What an off-centre or flat-sided curve leaves unexplained lies within the branch's own
cross-section, at most about a local diameter from the skeleton. The local radius is read off the cloud
alone, not off the skeleton's balls (an off-centre axis has small ones): half the chord across the shape
along a point's inward normal (the shape diameter), its median over the cloud points whose nearest
skeleton point lies near the region point's. A region whose ``missing_beside_quantile`` distance to the
skeleton is at most ``missing_beside_radii`` such radii is beside the skeleton, not missing from it: it
keeps its share in the completeness (the paper's number), and does not make the skeleton ``incomplete``.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..geometry import query_workers
from .chord_cache import ChordCache

__all__ = ["BESIDE_SAMPLES", "CLOUD_SAMPLES", "half_chords", "local_radii", "beside_ratios", "beside_regions"]

#: points of a region measured (evenly spread over its rows)
BESIDE_SAMPLES = 64
#: the most (centre, point) pairs whose distances are held at once (:func:`_within`)
WITHIN_BLOCK = 1 << 20
#: cloud points whose half chords give the local radii (evenly spread over the cloud)
CLOUD_SAMPLES = 1024
#: cloud neighbours of a point whose principal axes give its normal
NORMAL_K = 12
#: a chord's march starts this many spacings inside (past the point's own wall) ...
MARCH_START = 2.0
#: ... a cloud point within this many spacings of the march ends it (the opposite wall) ...
HIT_RADIUS = 1.5
#: ... and it gives up after this many spacings (the chord then counts as unknown); it steps by the
#: distance to the cloud less the hit radius (nothing nearer can be met on the way), at least this many spacings
MARCH_MAX = 200
MIN_STEP = 0.5
#: the march's search for the nearest cloud point stops at this many spacings (a point deep inside a tube
#: sees a ring of cloud points about as near, and an unbounded search visits most of them)
STEP_SEARCH = 8.0
#: a skeleton point is an end when the elements near it lie to one side: their mean offset over this share
#: of their mean distance ...
END_SIDE = 0.5
#: ... and a cloud point within this angle (degrees) of the way out lies beyond it
END_ANGLE = 60.0


def half_chords(pts: np.ndarray, tree: cKDTree, rows: np.ndarray, toward: np.ndarray, spacing: float,
                kept: ChordCache | None = None) -> np.ndarray:
    """Half the chord across the shape from each cloud row of ``rows`` along its normal (the least
    principal axis of its ``NORMAL_K`` nearest cloud points), turned towards ``toward`` (a point inside
    for each row): the first place, from ``MARCH_START`` spacings on, within ``HIT_RADIUS`` spacings of a
    cloud point, marched by the distance to the cloud. NaN where no wall is met within ``MARCH_MAX``
    spacings or inside the cloud's box. ``kept``: the normals and chords of earlier calls on the same
    cloud and rows (:class:`.chord_cache.ChordCache`), a direction marched only on its first need (the
    same bits); None: all computed here."""
    rows = np.asarray(rows, np.int64)
    if not len(rows) or not spacing > 0 or tree.n < 3:
        return np.full(len(rows), np.nan)
    p = pts[rows]
    if kept is None:
        normal = _normals(pts, tree, p)
        flip = np.einsum("ni,ni->n", toward - p, normal) < 0
        normal[flip] *= -1
        return _march(pts, tree, p, normal, spacing)
    with kept.lock:
        if not kept.holds(pts, rows, spacing):
            kept.start(pts, rows, spacing, _normals(pts, tree, p))
        side = (np.einsum("ni,ni->n", toward - p, kept.normal) < 0).astype(np.int64)
        ask = np.flatnonzero(~kept.done[np.arange(len(rows)), side])
        if len(ask):
            normal = kept.normal[ask].copy()
            normal[side[ask] == 1] *= -1
            kept.chords[ask, side[ask]] = _march(pts, tree, p[ask], normal, spacing)
            kept.done[ask, side[ask]] = True
        return kept.chords[np.arange(len(rows)), side]


def _normals(pts: np.ndarray, tree: cKDTree, p: np.ndarray) -> np.ndarray:
    """The least principal axis of the ``NORMAL_K`` nearest cloud points of each of ``p``, as found."""
    _, nb = tree.query(p, k=min(NORMAL_K, tree.n), workers=query_workers(len(p)))
    q = pts[nb] - pts[nb].mean(axis=1, keepdims=True)
    return np.linalg.eigh(np.einsum("nki,nkj->nij", q, q))[1][:, :, 0]


def _march(pts: np.ndarray, tree: cKDTree, p: np.ndarray, normal: np.ndarray, spacing: float) -> np.ndarray:
    """Each ray from ``p`` along ``normal`` marched to the opposite wall (:func:`half_chords`): half its
    length, NaN where none is met."""
    out = np.full(len(p), np.nan)
    # a ray out of the cloud's box (grown by the hit radius) never comes back into it: it is closed there
    lo, hi = pts.min(axis=0) - HIT_RADIUS * spacing, pts.max(axis=0) + HIT_RADIUS * spacing
    hit_at = HIT_RADIUS * spacing
    t = np.full(len(p), MARCH_START * spacing)
    open_ = np.ones(len(p), bool)
    while open_.any():
        idx = np.flatnonzero(open_)
        at = p[idx] + t[idx, None] * normal[idx]
        gone = ~np.all((at >= lo) & (at <= hi), axis=1) | (t[idx] > MARCH_MAX * spacing)
        open_[idx[gone]] = False
        idx, at = idx[~gone], at[~gone]
        d, _ = tree.query(at, distance_upper_bound=STEP_SEARCH * spacing, workers=query_workers(len(idx)))
        d = np.minimum(d, STEP_SEARCH * spacing)  # none within the search: that far is free
        hit = d <= hit_at
        out[idx[hit]] = 0.5 * (t[idx[hit]] + hit_at)  # the march stops about a hit radius short of the wall
        open_[idx[hit]] = False
        # no cloud point lies within d of the ray's point: the ray may go d - the hit radius on unmet
        t[idx[~hit]] += np.maximum(d[~hit] - hit_at, MIN_STEP * spacing)
    return out


def local_radii(pts: np.ndarray, tree: cKDTree, elements: np.ndarray, element_tree: cKDTree, spacing: float,
                kept: ChordCache | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The feet (nearest of ``elements``) and :func:`half_chords` of ``CLOUD_SAMPLES`` cloud points spread
    evenly, those with a chord only: what :func:`beside_ratios` reads the local radius from."""
    sample = np.unique(np.linspace(0, len(pts) - 1, min(CLOUD_SAMPLES, len(pts))).astype(np.int64))
    _, js = element_tree.query(pts[sample], workers=query_workers(len(sample)))
    radius = half_chords(pts, tree, sample, elements[js], spacing, kept)
    ok = np.isfinite(radius)
    return elements[js[ok]], radius[ok]


def beside_ratios(pts: np.ndarray, tree: cKDTree, rows: np.ndarray, elements: np.ndarray, spacing: float,
                  kept: ChordCache | None = None, radii: tuple[np.ndarray, np.ndarray] | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Per cloud row of ``rows``: (its distance to the nearest of ``elements`` over the local radius there,
    whether it lies beyond the skeleton's end). The local radius: the median :func:`half_chords` of the
    cloud points (``CLOUD_SAMPLES`` of them, spread evenly) whose nearest element lies within that
    distance (at least two spacings) of the row's; NaN when none of them has a chord. Beyond the end:
    the elements within that distance of the nearest one lie to one side of it (their mean offset is
    over ``END_SIDE`` of their mean distance) and the row lies on the other, within ``END_ANGLE`` of the
    way out (a cut branch's stump, a head past a handle's end). ``kept``: :func:`half_chords`'; ``radii``:
    :func:`local_radii` of these elements when already made."""
    rows = np.asarray(rows, np.int64)
    ratio, beyond = np.full(len(rows), np.nan), np.zeros(len(rows), bool)
    if not len(rows) or not len(elements):
        return ratio, beyond
    element_tree = cKDTree(elements)
    dist, j = element_tree.query(pts[rows], workers=query_workers(len(rows)))
    reach = np.maximum(dist, 2.0 * spacing)
    cos_out = np.cos(np.radians(END_ANGLE))
    got, owner = _within(elements[j], reach, elements)
    off = elements[got] - elements[j[owner]]
    count = np.bincount(owner, minlength=len(rows))
    mean = _group_sums(off, owner, len(rows)) / np.maximum(count, 1)[:, None]
    size = np.sqrt(np.einsum("ij,ij->i", mean, mean))
    spread = np.bincount(owner, np.sqrt(np.einsum("ij,ij->i", off, off)), minlength=len(rows)) / np.maximum(count, 1)
    side = (size > END_SIDE * spread) & (dist > 0)
    out_dot = -np.einsum("ij,ij->i", pts[rows] - elements[j], mean)
    beyond[side] = out_dot[side] > cos_out * dist[side] * size[side]
    feet, radius = radii if radii is not None else local_radii(pts, tree, elements, element_tree, spacing, kept)
    if not len(radius):
        return ratio, beyond
    got, owner = _within(elements[j], reach, feet)
    middle = _group_medians(radius[got], owner, len(rows))
    has = np.isfinite(middle)
    ratio[has] = dist[has] / np.maximum(middle[has], 1e-12)
    return ratio, beyond


def beside_regions(pts: np.ndarray, tree: cKDTree, region: np.ndarray, ids: np.ndarray, elements: np.ndarray,
                   spacing: float, quantile: float, radii: float, end_radii: float, beyond_share: float,
                   kept: ChordCache | None = None) -> np.ndarray:
    """Per region id of ``ids`` (``region``: each row's id, -1 explained), True when, over up to
    ``BESIDE_SAMPLES`` of its points spread evenly over its rows, the ``quantile`` of their distance to
    the skeleton in local radii (:func:`beside_ratios`; a point without a local radius counts as far) is
    at most ``radii`` and at most ``beyond_share`` of them lie beyond an end by more than ``end_radii``
    (a cut branch, a head past a handle's end; a rounded cap stays within about one). ``kept``: the
    chords of earlier calls on the same cloud (:func:`half_chords`)."""
    ids = np.asarray(ids, np.int64)
    out = np.zeros(len(ids), bool)
    if not len(ids) or not len(elements):
        return out
    picked, owner = [], []
    for i, c in enumerate(ids):
        members = np.flatnonzero(region == c)
        if len(members):
            take = np.unique(np.linspace(0, len(members) - 1, min(BESIDE_SAMPLES, len(members))).astype(np.int64))
            picked.append(members[take])
            owner.append(np.full(len(take), i))
    if not picked:
        return out
    rows, owner = np.concatenate(picked), np.concatenate(owner)
    element_tree = cKDTree(elements)
    radii_made = local_radii(pts, tree, elements, element_tree, spacing, kept)
    if not len(radii_made[1]):
        return out  # no local radius anywhere: every point counts as far
    # a row's local radius is a median of these radii, so its ratio is at least its distance over their
    # largest: a region whose quantile of that floor is over ``radii`` is not beside, and its pairs are not
    # searched (a removed arm reaching far from the skeleton; the same verdicts)
    dist = element_tree.query(pts[rows], workers=query_workers(len(rows)))[0]
    floor = dist / max(float(radii_made[1].max()), 1e-12)
    maybe = np.array([bool((owner == i).any()) and float(np.quantile(floor[owner == i], quantile,
                                                                     method="higher")) <= radii
                      for i in range(len(ids))], bool)
    ask = maybe[owner]
    if not ask.any():
        return out
    rows, owner = rows[ask], owner[ask]
    ratio, beyond = beside_ratios(pts, tree, rows, elements, spacing, kept, radii_made)
    ratio = np.where(np.isfinite(ratio), ratio, np.inf)
    for i in np.flatnonzero(maybe):
        mine = owner == i
        past = beyond[mine] & (ratio[mine] > end_radii)
        out[i] = (bool(mine.any()) and float(np.quantile(ratio[mine], quantile, method="higher")) <= radii
                  and float(past.mean()) <= beyond_share)
    return out


def _within(centres: np.ndarray, reach: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rows of ``points`` within ``reach`` of each centre (squared distances summed x, y, z against
    reach squared, as ``cKDTree.query_ball_point`` does), in ascending order per centre, and the centre
    each belongs to; in blocks of at most ``WITHIN_BLOCK`` pairs, so memory stays bounded."""
    step = max(1, WITHIN_BLOCK // max(len(points), 1))
    got, owner = [], []
    for lo in range(0, len(centres), step):
        c = centres[lo:lo + step]
        d2 = (c[:, None, 0] - points[None, :, 0]) ** 2
        d2 += (c[:, None, 1] - points[None, :, 1]) ** 2
        d2 += (c[:, None, 2] - points[None, :, 2]) ** 2
        i, k = np.nonzero(d2 <= reach[lo:lo + step, None] ** 2)
        got.append(k)
        owner.append(i + lo)
    if not got:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(got), np.concatenate(owner)


def _group_sums(values: np.ndarray, owner: np.ndarray, n: int) -> np.ndarray:
    """Per group of ``owner`` (sorted, 0..n-1), the sum of its rows of ``values``."""
    out = np.zeros((n, values.shape[1]))
    for c in range(values.shape[1]):
        out[:, c] = np.bincount(owner, values[:, c], minlength=n)
    return out


def _group_medians(values: np.ndarray, owner: np.ndarray, n: int) -> np.ndarray:
    """Per group of ``owner`` (0..n-1), the median of its ``values`` (the mean of the two middle ones
    for an even count); NaN for an empty group."""
    out = np.full(n, np.nan)
    if not len(values):
        return out
    order = np.lexsort((values, owner))
    v, o = values[order], owner[order]
    count = np.bincount(o, minlength=n)
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    has = count > 0
    lo = start[has] + (count[has] - 1) // 2
    hi = start[has] + count[has] // 2
    out[has] = (v[lo] + v[hi]) / 2.0
    return out
