"""Whether a cloud was seen from one side, read along a curve: the spur test's explanation measure
needs the twig's own points, which a one-sided scan leaves out wherever the sensor did not look.

From curve points one per cell of 4 typical radii (at most ``_ELEMENTS`` of them), the mean unit
direction to the cloud points within two local radii, across the axis (the principal direction of
the 8 nearest curve points, left out: a density changing along a part is no side). On a surface
scanned all round these cancel, point by point and over the curve (at most 0.16 long on the
tuning neurons and the synthetic suite's clouds); seen from one side they all point towards the
sensor (0.21-0.48). The measure is the length of their mean (docs/diagnostics.md "Spurious
branches", rule 5).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["one_sidedness"]

_ELEMENTS = 400  # curve points asked: the mean of this many unit vectors is steady to about 0.05


def one_sidedness(cloud_tree: cKDTree, pts: np.ndarray, r_x: np.ndarray, r_typ: float, seed: int = 0,
                  kept: dict | None = None) -> float:
    """The length of the mean direction from the curve points ``pts`` (local radii ``r_x``) to their
    cloud points across the axis (module docstring); 0 when no curve point has 8 cloud points near.
    ``kept``: each asked point's mean direction by (position, radius), for this ``cloud_tree`` alone
    (an edit's update asks the cloud only at new ones, :mod:`.spur_cache`; the same values)."""
    pts = np.asarray(pts, float)
    if len(pts) < 2 or not r_typ > 0:
        return 0.0
    cell = np.floor(pts / (4.0 * r_typ)).astype(np.int64)
    order = np.lexsort(cell.T[::-1])  # np.unique(cell, axis=0, return_index=True)[1], 4 x faster
    first = np.ones(len(cell), bool)
    first[1:] = np.any(cell[order[1:]] != cell[order[:-1]], axis=1)
    pick = order[first]
    if len(pick) > _ELEMENTS:
        pick = np.sort(np.random.default_rng(seed).choice(pick, _ELEMENTS, replace=False))
    el = pts[pick]
    nb = cKDTree(pts).query(el, k=min(8, len(pts)))[1].reshape(len(el), -1)
    along = pts[nb] - pts[nb].mean(axis=1, keepdims=True)
    axis = np.linalg.eigh(np.matmul(along.transpose(0, 2, 1), along))[1][:, :, 2]
    radius = 2.0 * r_x[pick]
    keys = [e.tobytes() + r.tobytes() for e, r in zip(el, radius)]
    kept = {} if kept is None else kept
    new = [i for i, key in enumerate(keys) if key not in kept]
    if new:
        kept.update(zip((keys[i] for i in new), _mean_directions(cloud_tree, el[new], radius[new])))
    u = []
    for i, key in enumerate(keys):
        m = kept[key]
        if m is not None:
            u.append(m - (m @ axis[i]) * axis[i])
    return float(np.linalg.norm(np.mean(u, axis=0))) if u else 0.0


def _mean_directions(cloud_tree: cKDTree, el: np.ndarray, radius: np.ndarray) -> list[np.ndarray | None]:
    """Per point of ``el``, the mean unit direction to the cloud points within its ``radius`` (None
    with fewer than 8): every ball's unit directions in one array, then each ball's mean of its block
    of rows (``np.add.reduceat`` adds them in another order: not the same bits)."""
    found = cloud_tree.query_ball_point(el, radius)
    counts = np.fromiter(map(len, found), np.int64, len(found))
    out: list[np.ndarray | None] = [None] * len(found)
    big = np.flatnonzero(counts >= 8)
    if not len(big):
        return out
    rows = np.concatenate([np.asarray(found[j], np.int64) for j in big])
    d = cloud_tree.data[rows] - np.repeat(el[big], counts[big], axis=0)
    n = np.linalg.norm(d, axis=1, keepdims=True)
    unit = np.divide(d, n, out=np.zeros_like(d), where=n > 0)
    stops = np.cumsum(counts[big]).tolist()
    for j, start, stop in zip(big.tolist(), [0] + stops[:-1], stops):
        out[j] = np.mean(unit[start:stop], axis=0)
    return out
