"""The toolbox's point one-rings (``compute_point_point_ring``): kNN, then a local 2-D Delaunay fan.

Each point's k nearest neighbours (itself first) are projected on their two principal axes; the
point's one-ring is its star in the Delaunay triangulation of that projection, walked as a fan. A
point inside its neighbourhood gets a closed ring (first vertex repeated at the end), one on its
boundary an open ring from the lower-ranked of its two hull neighbours. The star is found without
triangulating: after inversion about the point, its Delaunay neighbours are the vertices of the
convex hull of the inverted neighbours plus the origin (the origin itself on the hull = open ring),
hull order = fan order. All points at once, vectorized (Jarvis march over the (N, k) block).

Where a closed fan starts is an artefact of Qhull's output order (the toolbox starts at the first
triangle ``delaunayn`` lists around the point). ``fan_start="qhull"`` asks Qhull for it, on the
neighbourhood projected in absolute coordinates as the toolbox projects it (about 0.2 ms a point);
``"axis"`` takes the fan triangle the first principal axis passes through (no Qhull call).
docs/skeletonize.md, departure 2, measures what the choice changes.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["knn_count", "point_rings", "FAN_STARTS"]

FAN_STARTS = ("qhull", "axis")


def knn_count(n: int, min_k: int = 8, max_k: int = 30, fraction: float = 0.012) -> int:
    """``GS.compute_k_knn``: round(0.012 N) neighbours, clamped to [8, 30] (and to N)."""
    k = max(int(min_k), int(np.floor(n * fraction + 0.5)))  # MATLAB round: half away from zero
    return int(min(k, int(max_k), n))


def _neighbours(points: np.ndarray, tree: cKDTree, rows: np.ndarray, k: int) -> np.ndarray:
    """(len(rows), k) kNN indices, each row starting with the point itself (a duplicate point at
    distance 0 could come first; the toolbox's MEX kd-tree returns the query point first)."""
    _d, idx = tree.query(points[rows], k=k, workers=-1)
    idx = np.asarray(idx, np.int64).reshape(len(rows), k)
    not_first = idx[:, 0] != rows
    if np.any(not_first):
        for r in np.flatnonzero(not_first):
            i = int(rows[r])
            order = [i] + [int(j) for j in idx[r] if j != i]
            idx[r] = order[:k]
    return idx


def _project(points: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Neighbourhoods on their two principal axes, relative to the point: (N, k, 2).

    Axes signed as MATLAB's ``pca`` signs its coefficients (largest-magnitude component positive).
    """
    return _project_with_axes(points, idx)[0]


def _project_with_axes(points: np.ndarray, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_project` and the (N, 3, 2) signed axes."""
    nb = points[idx]  # (N, k, 3)
    centred = nb - nb.mean(axis=1, keepdims=True)
    cov = np.matmul(centred.transpose(0, 2, 1), centred)
    _w, vec = np.linalg.eigh(cov)  # ascending: the last two columns are the principal plane
    axes = vec[:, :, [2, 1]]
    big = np.argmax(np.abs(axes), axis=1)  # (N, 2)
    sign = np.sign(np.take_along_axis(axes, big[:, None, :], axis=1))
    axes = axes * np.where(sign == 0, 1.0, sign)
    rel = nb - nb[:, :1, :]
    return np.matmul(rel, axes), axes


def _qhull_fan_starts(points: np.ndarray, idx: np.ndarray, axes: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """(len(rows), 2) candidate ranks (local rank - 1) of the toolbox's closed-fan start and the
    vertex it walks to: the first triangle around the point in Qhull's output (``delaunayn`` with
    Octave's and MATLAB's options ``Qt Qbb Qc``, on ``neighbour * coefs`` as the toolbox projects),
    its lower-ranked other vertex first. -1 where Qhull fails (degenerate neighbourhood)."""
    from scipy.spatial import Delaunay, QhullError

    out = np.full((len(rows), 2), -1, np.int64)
    for j, r in enumerate(rows.tolist()):
        x = points[idx[r]] @ axes[r]
        try:
            tri = Delaunay(x, qhull_options="Qt Qbb Qc").simplices
        except (QhullError, ValueError):
            continue
        around = np.flatnonzero((tri == 0).any(axis=1))
        if len(around):
            other = np.sort(tri[around[0]])[1:]
            out[j] = other - 1
    return out


def _hull_order(z: np.ndarray, valid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Counter-clockwise convex-hull vertices of each row's valid points of ``z`` (N, m, 2).

    Jarvis march for all rows at once; on collinear candidates the farthest is taken (a point in the
    middle of a hull side is not a vertex). Returns (N, m) vertex indices (-1 padded), counts.
    """
    n, m, _ = z.shape
    zx, zy = np.ascontiguousarray(z[..., 0]), np.ascontiguousarray(z[..., 1])
    r2 = np.where(valid, zx * zx + zy * zy, -1.0)
    start = np.argmax(r2, axis=1)
    rows = np.arange(n)
    cur = start.copy()
    # the farthest point is extreme along its own direction: the support line there is perpendicular
    dx, dy = -zy[rows, start], zx[rows, start].copy()
    hull = np.full((n, m + 1), -1, np.int64)
    hull[:, 0] = start
    count = np.ones(n, np.int64)
    active = valid.sum(axis=1) >= 2
    a = np.flatnonzero(active)
    for _step in range(m + 1):
        if len(a) == 0:
            break
        vx = zx[a] - zx[a, cur[a]][:, None]  # (na, m)
        vy = zy[a] - zy[a, cur[a]][:, None]
        ddx, ddy = dx[a][:, None], dy[a][:, None]
        cross = ddx * vy - ddy * vx
        dot = ddx * vx + ddy * vy
        ang = np.arctan2(cross, dot)
        ang = np.where(ang < -1e-12, ang + 2 * np.pi, np.maximum(ang, 0.0))
        dist2 = vx * vx + vy * vy
        ok = valid[a] & (dist2 > 0)
        ang = np.where(ok, ang, np.inf)
        best = ang.min(axis=1, keepdims=True)
        tie = ok & (ang <= best + 1e-12)
        nxt = np.argmax(np.where(tie, dist2, -1.0), axis=1)
        dx[a] = zx[a, nxt] - zx[a, cur[a]]
        dy[a] = zy[a, nxt] - zy[a, cur[a]]
        cur[a] = nxt
        done = (nxt == start[a]) | (count[a] > m)
        go = a[~done]
        hull[go, count[go]] = nxt[~done]
        count[go] += 1
        a = go
    return hull, count


def point_rings(
    points: np.ndarray, k: int, check: Callable[[float], None] | None = None, chunk: int = 2048,
    fan_start: str = "axis",
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One-rings of every point, CSR style: (indptr, indices, closed).

    ``indices[indptr[i]:indptr[i+1]]`` is point i's ring in fan order, global indices; a closed ring
    repeats its first vertex at the end, as the toolbox's rings do. A point whose neighbourhood is
    degenerate (all neighbours on one line in projection) gets its kNN list, nearest first.
    Works ``chunk`` points at a time; ``check(fraction)`` is called between chunks (cancel).
    ``fan_start``: where a closed ring starts, "qhull" (the toolbox's) or "axis" (module docstring).
    """
    if fan_start not in FAN_STARTS:
        raise ValueError(f"fan_start {fan_start!r}: use one of {', '.join(FAN_STARTS)}")
    check = check or (lambda _f: None)
    pts = np.asarray(points, dtype=float)
    n = len(pts)
    k = int(min(k, n))
    tree = cKDTree(pts)
    # rows in the tree's leaf order: consecutive rows are spatial neighbours, so the kNN queries and
    # the neighbourhood gathers stay cache-warm (2.5x faster kNN at 64k); each row's ring is the same
    order = np.asarray(tree.indices, np.int64)
    lens, parts, closed = [], [], []
    for lo in range(0, n, chunk):
        check(lo / n)
        ip, ind, cl = _rings_of(pts, tree, order[lo:lo + chunk], k, fan_start == "qhull")
        lens.append(np.diff(ip))
        parts.append(ind)
        closed.append(cl)
    check(1.0)
    done_len = np.concatenate(lens)  # ring lengths in processing order
    length = np.empty(n, np.int64)
    length[order] = done_len
    indptr = np.concatenate([[0], np.cumsum(length)])
    done_start = np.concatenate([[0], np.cumsum(done_len)[:-1]])
    shift = np.repeat(indptr[order] - done_start, done_len)
    indices = np.empty(int(indptr[-1]), np.int64)
    indices[np.arange(len(indices)) + shift] = np.concatenate(parts)
    is_closed = np.empty(n, bool)
    is_closed[order] = np.concatenate(closed)
    return indptr, indices, is_closed


def _rings_of(pts: np.ndarray, tree: cKDTree, rows: np.ndarray, k: int, qhull_start: bool = False) -> tuple:
    idx = _neighbours(pts, tree, rows, k)
    n = len(rows)
    rel, axes = _project_with_axes(pts, idx)
    rel = rel[:, 1:, :]  # (n, m, 2), m = k - 1 candidates (local ranks 1..m)
    r2 = np.einsum("nmk,nmk->nm", rel, rel)
    scale = np.sqrt(np.max(r2, axis=1, keepdims=True))
    valid = r2 > (1e-12 * scale) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(valid[..., None], rel / np.where(valid, r2, 1.0)[..., None], 0.0)
    m = rel.shape[1]
    z = np.concatenate([inv, np.zeros((n, 1, 2))], axis=1)  # candidate m = the origin (the point)
    zvalid = np.concatenate([valid, np.ones((n, 1), bool)], axis=1)
    hull, cnt = _hull_order(z, zvalid)
    starts = None
    if qhull_start:
        closed = np.flatnonzero(~np.any((np.arange(hull.shape[1])[None, :] < cnt[:, None]) & (hull == m), axis=1)
                                & (cnt >= 3))
        starts = np.full((n, 2), -1, np.int64)
        starts[closed] = _qhull_fan_starts(pts, idx, axes, closed)
    return _assemble(idx, rel, hull, cnt, m, starts)


def _assemble(idx: np.ndarray, rel: np.ndarray, hull: np.ndarray, cnt: np.ndarray, m: int,
              starts: np.ndarray | None = None) -> tuple:
    """Hull orders to toolbox rings (start, direction, closing repeat), all rows at once.

    Open fan (the origin, candidate m, on the hull): from the hull vertex after the origin to the one
    before it, reversed if that ends lower-ranked (the toolbox starts at the lower-ranked end).
    Closed fan: the toolbox starts at the lower-ranked vertex of the first triangle of Qhull's output
    around the point, towards that triangle's other vertex; Qhull's output order is an artefact of
    its incremental construction. In its place: the fan triangle that the first principal axis
    (MATLAB's sign) passes through, a choice of the same kind (docs/skeletonize.md).
    """
    n, width = hull.shape
    col = np.arange(width)[None, :]
    inside = col < cnt[:, None]
    h = np.where(inside, hull, 0)
    is_open = np.any(inside & (hull == m), axis=1)
    c = np.maximum(cnt, 1)[:, None]
    nxt = (col + 1) % c
    rows = np.arange(n)[:, None]
    cand = np.minimum(h, m - 1)
    ang = np.arctan2(rel[rows, cand, 1], rel[rows, cand, 0])
    span = np.mod(np.take_along_axis(ang, nxt, axis=1) - ang, 2 * np.pi)
    off = np.mod(-ang, 2 * np.pi)
    hit = inside & (off < span)
    t = np.where(hit.any(axis=1), np.argmax(hit, axis=1), 0)
    va = h[np.arange(n), t]
    vb = h[np.arange(n), (t + 1) % c[:, 0]]
    first = np.where(va < vb, t, (t + 1) % c[:, 0])
    forward = va < vb  # the lower-ranked vertex first, then the other one: forward iff a is lower
    if starts is not None:  # Qhull's first triangle, where its two vertices are adjacent in the fan
        pos = np.argmax(inside & (h == starts[:, :1]), axis=1)
        found = (starts[:, 0] >= 0) & np.any(inside & (h == starts[:, :1]), axis=1)
        after = h[np.arange(n), (pos + 1) % c[:, 0]] == starts[:, 1]
        before = h[np.arange(n), (pos - 1) % c[:, 0]] == starts[:, 1]
        use = found & (after | before)
        first = np.where(use, pos, first)
        forward = np.where(use, after, forward)
    origin_pos = np.argmax(inside & (hull == m), axis=1)

    good_closed = ~is_open & (cnt >= 3)
    good_open = is_open & (cnt >= 3)
    # open: positions origin+1 .. origin+cnt-1; reversed when the last is lower-ranked than the first
    o_first = h[np.arange(n), (origin_pos + 1) % c[:, 0]]
    o_last = h[np.arange(n), (origin_pos - 1) % c[:, 0]]
    o_rev = o_last < o_first
    length = np.where(good_closed, cnt + 1, np.where(good_open, cnt - 1, idx.shape[1] - 1))
    indptr = np.concatenate([[0], np.cumsum(length)])
    row = np.repeat(np.arange(n), length)
    r = np.arange(indptr[-1]) - indptr[row]
    cc = c[row, 0]
    pos_closed = np.where(forward[row], first[row] + r, first[row] - r) % cc
    pos_open = np.where(o_rev[row], origin_pos[row] - 1 - r, origin_pos[row] + 1 + r) % cc
    local = np.where(good_closed[row], h[row, pos_closed],
                     np.where(good_open[row], h[row, pos_open], r))  # fallback: kNN order
    indices = idx[row, local + 1]
    return indptr, indices.astype(np.int64), good_closed
