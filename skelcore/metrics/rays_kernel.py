"""Compiled kernel of the ``rays`` estimator (SPEC 2): occlusion-culled union of caps per query.

The cloud sits in a balanced KD-tree whose nodes carry bounding spheres.  Each query walks the nodes
nearest first (a binary heap); a node of centre c and radius r seen from q at distance d > r + h holds
every cap of its points inside the cone of half-angle asin((r + h) / d), so it is skipped when every
raster sample in that cone is already covered (or the cone holds none), and the walk stops once the
raster is full.  The raster is ``_rays``' equal-area latitude raster (same rows, bins and exact cap
intervals per row) stored as 64-bit words, so a skip is exact: the result equals rasterising every cap.
Numba (``cache=True``) compiles it once per machine; queries run in parallel (``prange``), each on its
own, so results do not depend on threads.  Why numba, measurements: docs/boundedness.md.
"""

from __future__ import annotations

import math
import os
import tempfile

import numpy as np


def _cache_dir_fallback() -> None:
    """Numba caches next to this file, else in the user's cache dir; if neither is writable (a
    read-only site-packages and home), point NUMBA_CACHE_DIR at a temporary directory."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    here = os.path.dirname(os.path.abspath(__file__))
    if os.access(here, os.W_OK):
        return
    home_cache = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    probe = home_cache if os.path.isdir(home_cache) else os.path.dirname(home_cache)
    if os.access(probe, os.W_OK):
        return
    os.environ["NUMBA_CACHE_DIR"] = os.path.join(tempfile.gettempdir(), f"skelscope-numba-{os.getuid()}")


_cache_dir_fallback()

import numba  # noqa: E402
from numba import njit, prange  # noqa: E402

if os.environ.get("NUMBA_CACHE_DIR") and not numba.config.CACHE_DIR:  # numba imported before us
    numba.config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]

LEAF_SIZE = 8  # points per leaf (4..8): smaller leaves cull finer, cost more nodes
_ALL = np.uint64(0xFFFFFFFFFFFFFFFF)
_U1 = np.uint64(1)
_M1 = np.uint64(0x5555555555555555)
_M2 = np.uint64(0x3333333333333333)
_M4 = np.uint64(0x0F0F0F0F0F0F0F0F)
_H01 = np.uint64(0x0101010101010101)


# --------------------------------------------------------------------------------------------------
# the tree: implicit balanced KD-tree, node i has children 2i + 1, 2i + 2; leaves are the last level


def tree_levels(n: int) -> int:
    """Levels below the root so that every leaf holds at most LEAF_SIZE points."""
    levels = 0
    while (n + (1 << levels) - 1) >> levels > LEAF_SIZE:
        levels += 1
    return levels


@njit(cache=True)
def _select(pts, perm, lo, hi, k, axis):  # pragma: no cover - compiled
    """Reorder pts[lo:hi] (and perm) so that pts[k, axis] is the k-th smallest (quickselect)."""
    left, right = lo, hi - 1
    while right > left:
        mid = (left + right) >> 1
        a, b, c = pts[left, axis], pts[mid, axis], pts[right, axis]
        pivot = max(min(a, b), min(max(a, b), c))  # median of three
        i, j = left, right
        while i <= j:
            while pts[i, axis] < pivot:
                i += 1
            while pts[j, axis] > pivot:
                j -= 1
            if i <= j:
                for t in range(3):
                    tmp = pts[i, t]
                    pts[i, t] = pts[j, t]
                    pts[j, t] = tmp
                tp = perm[i]
                perm[i] = perm[j]
                perm[j] = tp
                i += 1
                j -= 1
        if k <= j:
            right = j
        elif k >= i:
            left = i
        else:
            break


@njit(parallel=True, cache=True)
def split_level(pts, perm, lo, hi, first, count):  # pragma: no cover - compiled
    """Split every node first..first+count-1 at its median along its widest axis."""
    for t in prange(count):
        node = first + t
        a, b = lo[node], hi[node]
        if b - a < 2:
            continue
        mn = np.empty(3)
        mx = np.empty(3)
        for k in range(3):
            mn[k] = pts[a, k]
            mx[k] = pts[a, k]
        for i in range(a + 1, b):
            for k in range(3):
                v = pts[i, k]
                if v < mn[k]:
                    mn[k] = v
                if v > mx[k]:
                    mx[k] = v
        axis = 0
        for k in range(1, 3):
            if mx[k] - mn[k] > mx[axis] - mn[axis]:
                axis = k
        _select(pts, perm, a, b, (a + b) >> 1, axis)


@njit(parallel=True, cache=True)
def node_spheres(pts, lo, hi, first, count, centre, radius):  # pragma: no cover - compiled
    """Bounding sphere (box centre, farthest point) of nodes first..first+count-1."""
    for t in prange(count):
        node = first + t
        a, b = lo[node], hi[node]
        if b <= a:
            for k in range(3):
                centre[node, k] = 0.0
            radius[node] = -1.0  # an empty node: never visited
            continue
        mn = np.empty(3)
        mx = np.empty(3)
        for k in range(3):
            mn[k] = pts[a, k]
            mx[k] = pts[a, k]
        for i in range(a + 1, b):
            for k in range(3):
                v = pts[i, k]
                if v < mn[k]:
                    mn[k] = v
                if v > mx[k]:
                    mx[k] = v
        cx, cy, cz = 0.5 * (mn[0] + mx[0]), 0.5 * (mn[1] + mx[1]), 0.5 * (mn[2] + mx[2])
        r2 = 0.0
        for i in range(a, b):
            dx, dy, dz = pts[i, 0] - cx, pts[i, 1] - cy, pts[i, 2] - cz
            d2 = dx * dx + dy * dy + dz * dz
            if d2 > r2:
                r2 = d2
        centre[node, 0], centre[node, 1], centre[node, 2] = cx, cy, cz
        radius[node] = math.sqrt(r2)


def node_ranges(n: int, levels: int) -> tuple[np.ndarray, np.ndarray]:
    """Point range [lo, hi) of every node of the implicit tree (halving at (lo + hi) // 2)."""
    lo = np.zeros(1, np.int64)
    hi = np.full(1, n, np.int64)
    los, his = [lo], [hi]
    for _ in range(levels):
        mid = (lo + hi) >> 1
        lo = np.column_stack([lo, mid]).ravel()
        hi = np.column_stack([mid, hi]).ravel()
        los.append(lo)
        his.append(hi)
    return np.concatenate(los), np.concatenate(his)


# --------------------------------------------------------------------------------------------------
# the raster: rows x bins samples as rows x words 64-bit words, covered samples per row; nfull = full rows


@njit(cache=True, inline="always")
def _popcount(x):  # pragma: no cover - compiled
    x = x - ((x >> _U1) & _M1)
    x = (x & _M2) + ((x >> np.uint64(2)) & _M2)
    x = (x + (x >> np.uint64(4))) & _M4
    return (x * _H01) >> np.uint64(56)


@njit(cache=True)
def _span(bits, count, j, a, b, bins, mark):  # pragma: no cover - compiled
    """Mark (mark=True) or test the bins [a, b) of row j.  Test: 1 if one is not covered.
    Mark: 1 if the row became full."""
    w0 = a >> 6
    w1 = (b - 1) >> 6
    for w in range(w0, w1 + 1):
        s = a - w * 64 if w == w0 else 0
        e = b - w * 64 if w == w1 else 64
        mask = (_ALL >> np.uint64(64 - (e - s))) << np.uint64(s)
        old = bits[j, w]
        if mark:
            new = mask & ~old
            if new:
                bits[j, w] = old | mask
                count[j] += _popcount(new)
        elif (old & mask) != mask:
            return 1
    if mark and count[j] >= bins:
        return 1
    return 0


_SMALL_BINS = 6.0  # caps narrower than this many bins are tested sample by sample (no acos per row)


@njit(cache=True)
def _cap(bits, count, ux, uy, uz, cosa, sina, zrow, srow, cxs, cys, bins, mark):  # pragma: no cover
    """Mark or test the cap of unit centre u and angular radius a (cos a, sin a) on the raster.

    Test -> 1 if a sample inside it is uncovered; mark -> number of rows that became full.  A sample
    (unit vector s) is inside iff s . u >= cos a.  Wide caps: the exact longitude interval of every
    row they meet (law of cosines, one acos per row) marked word by word; narrow ones: that test on
    each sample of their bounding box of rows and longitudes.
    """
    rows = zrow.shape[0]
    rho = math.sqrt(max(0.0, 1.0 - uz * uz))
    mid = uz * cosa
    spread = rho * sina
    zhi = mid + spread
    zlo = mid - spread
    if uz >= cosa:
        zhi = 1.0  # the cap holds the north pole
    if -uz >= cosa:
        zlo = -1.0
    half_rows = 0.5 * rows
    bpr = bins / (2.0 * math.pi)
    phi = math.atan2(uy, ux) * bpr + bins  # in bin units, > 0
    newly = 0
    if sina < rho:
        dl = math.asin(sina / rho) * bpr  # the cap's longitude half-extent, in bins
    else:
        dl = bins  # holds or touches a pole
    if dl * 2.0 <= _SMALL_BINS:
        # rows whose centre height lies in the cap's z range, bins whose centre longitude lies
        # within dl of its centre: a sample outside this box cannot be inside the cap
        first = int(math.floor((zlo + 1.0) * half_rows + 0.5))
        end = int(math.floor((zhi + 1.0) * half_rows + 0.5))
        if first < 0:
            first = 0
        if end > rows:
            end = rows
        k0 = int(math.ceil(phi - dl - 0.5))
        k1 = int(math.floor(phi + dl - 0.5))
        for j in range(first, end):
            if count[j] >= bins:
                continue
            for kk in range(k0, k1 + 1):
                k = kk % bins
                w = k >> 6
                bit = _U1 << np.uint64(k & 63)
                if bits[j, w] & bit:
                    continue
                if cxs[j, k] * ux + cys[j, k] * uy + zrow[j] * uz >= cosa:
                    if not mark:
                        return 1
                    bits[j, w] |= bit
                    count[j] += 1
                    if count[j] >= bins:
                        newly += 1
        return newly
    first = int(math.floor((zlo + 1.0) * half_rows + 0.5))
    end = int(math.floor((zhi + 1.0) * half_rows + 0.5))
    if first < 0:
        first = 0
    if end > rows:
        end = rows
    if end <= first:
        return 0
    rho = max(rho, 1e-30)
    phi += 0.5
    for j in range(first, end):
        if count[j] >= bins:
            continue
        c = (cosa - zrow[j] * uz) / (srow[j] * rho)
        if c <= -1.0:
            start, length = 0, bins
        else:
            if c > 1.0:
                c = 1.0
            half = math.acos(c) * bpr
            start = int(phi - half)
            length = int(phi + half) - start
            if length <= 0:
                continue
            if length > bins:
                length = bins
            if start >= bins:
                start -= bins
        stop = start + length
        if stop > bins:
            if _span(bits, count, j, start, bins, bins, mark):
                if not mark:
                    return 1
                newly += 1
                continue
            if _span(bits, count, j, 0, stop - bins, bins, mark):
                if not mark:
                    return 1
                newly += 1
        elif _span(bits, count, j, start, stop, bins, mark):
            if not mark:
                return 1
            newly += 1
    return newly


_MAX_CAND = 64  # a narrow cone lists at most this many samples (6 x 6 bins box plus margin)


@njit(cache=True)
def _candidates(bits, count, ux, uy, uz, cosa, sina, zrow, cxs, cys, bins, cand_j, cand_k):  # pragma: no cover
    """The uncovered samples inside a narrow cone (s . u >= cos a), into cand_j/cand_k; their number,
    or -1 if the cone is too wide to list (then ``_cap`` tests it)."""
    rows = zrow.shape[0]
    rho = math.sqrt(max(0.0, 1.0 - uz * uz))
    if not sina < rho:
        return -1
    bpr = bins / (2.0 * math.pi)
    dl = math.asin(sina / rho) * bpr
    if dl * 2.0 > _SMALL_BINS:
        return -1
    mid = uz * cosa
    spread = rho * sina
    half_rows = 0.5 * rows
    first = int(math.floor((mid - spread + 1.0) * half_rows + 0.5))
    end = int(math.floor((mid + spread + 1.0) * half_rows + 0.5))
    if first < 0:
        first = 0
    if end > rows:
        end = rows
    phi = math.atan2(uy, ux) * bpr + bins
    k0 = int(math.ceil(phi - dl - 0.5))
    k1 = int(math.floor(phi + dl - 0.5))
    n = 0
    for j in range(first, end):
        if count[j] >= bins:
            continue
        for kk in range(k0, k1 + 1):
            k = kk % bins
            if bits[j, k >> 6] & (_U1 << np.uint64(k & 63)):
                continue
            if cxs[j, k] * ux + cys[j, k] * uy + zrow[j] * uz >= cosa:
                if n >= cand_j.shape[0]:
                    return -1
                cand_j[n] = j
                cand_k[n] = k
                n += 1
    return n


# --------------------------------------------------------------------------------------------------
# one query: nodes nearest first, culled cones, stop when full


@njit(cache=True)
def _walk(
    qx, qy, qz, pts, centre, radius, lo, hi, first_leaf, h, zrow, srow, cxs, cys, bins,
    bits, count, nfull, fx, fy, fz, freach, mode, heap_key, heap_id, cand_j, cand_k,
):  # pragma: no cover - compiled
    """Rasterise the caps seen from q into (bits, count of covered samples per row); returns (full rows, node visits).

    mode 0: every cloud point; 1: only points farther than freach from f (a far field).
    """
    rows = zrow.shape[0]
    h2 = h * h
    fr2 = freach * freach
    visits = 0
    if nfull >= rows:
        return nfull, visits
    size = 1
    heap_key[0] = 0.0
    heap_id[0] = 0
    while size > 0:
        node = heap_id[0]
        # pop the nearest node
        size -= 1
        if size > 0:
            key, nid = heap_key[size], heap_id[size]
            i = 0
            while True:
                c = 2 * i + 1
                if c >= size:
                    break
                if c + 1 < size and heap_key[c + 1] < heap_key[c]:
                    c += 1
                if heap_key[c] >= key:
                    break
                heap_key[i] = heap_key[c]
                heap_id[i] = heap_id[c]
                i = c
            heap_key[i] = key
            heap_id[i] = nid
        visits += 1
        r = radius[node]
        cx, cy, cz = centre[node, 0], centre[node, 1], centre[node, 2]
        if mode != 0:
            gx, gy, gz = cx - fx, cy - fy, cz - fz
            g = math.sqrt(gx * gx + gy * gy + gz * gz)
            if g + r <= freach * (1.0 - 1e-12):
                continue  # wholly inside the near sphere
        dx, dy, dz = cx - qx, cy - qy, cz - qz
        d = math.sqrt(dx * dx + dy * dy + dz * dz)
        reach = (r + h) * (1.0 + 1e-9) + 1e-12  # a hair wider: the test must not miss a sample
        nc = -1
        if d > reach:
            sina = reach / d
            cosa = math.sqrt(1.0 - sina * sina)
            ux, uy, uz = dx / d, dy / d, dz / d
            nc = _candidates(bits, count, ux, uy, uz, cosa, sina, zrow, cxs, cys, bins, cand_j, cand_k)
            if nc == 0:
                continue  # every sample in the node's cone is covered (or it holds none)
            if nc < 0 and _cap(bits, count, ux, uy, uz, cosa, sina, zrow, srow, cxs, cys, bins, False) == 0:
                continue
        if node >= first_leaf:
            for p in range(lo[node], hi[node]):
                px, py, pz = pts[p, 0], pts[p, 1], pts[p, 2]
                if mode != 0:
                    ex, ey, ez = px - fx, py - fy, pz - fz
                    e2 = ex * ex + ey * ey + ez * ez
                    if e2 <= fr2:
                        continue
                ux, uy, uz = px - qx, py - qy, pz - qz
                d2 = ux * ux + uy * uy + uz * uz
                if d2 <= h2:
                    continue  # q is inside this ball (SPEC 2): no cap
                if nc > 0:
                    # a narrow leaf: only its listed samples can be hit; sample s is inside the cap
                    # of p iff s . (p - q) >= |p - q| cos a = sqrt(|p - q|^2 - h^2)
                    t = math.sqrt(d2 - h2)
                    m = 0
                    while m < nc:
                        j, k = cand_j[m], cand_k[m]
                        if cxs[j, k] * ux + cys[j, k] * uy + zrow[j] * uz >= t:
                            bits[j, k >> 6] |= _U1 << np.uint64(k & 63)
                            count[j] += 1
                            if count[j] >= bins:
                                nfull += 1
                            nc -= 1
                            cand_j[m] = cand_j[nc]
                            cand_k[m] = cand_k[nc]
                        else:
                            m += 1
                    if nc == 0:
                        break
                    continue
                dist = math.sqrt(d2)
                sina = h / dist
                cosa = math.sqrt(1.0 - sina * sina)
                nfull += _cap(bits, count, ux / dist, uy / dist, uz / dist, cosa, sina, zrow, srow, cxs, cys, bins, True)
                if nfull >= rows:
                    return nfull, visits
            if nfull >= rows:
                return nfull, visits
            continue
        for child in (2 * node + 1, 2 * node + 2):
            rc = radius[child]
            if rc < 0.0:
                continue
            ex, ey, ez = centre[child, 0] - qx, centre[child, 1] - qy, centre[child, 2] - qz
            key = math.sqrt(ex * ex + ey * ey + ez * ez) - rc
            i = size
            size += 1
            while i > 0:
                parent = (i - 1) >> 1
                if heap_key[parent] <= key:
                    break
                heap_key[i] = heap_key[parent]
                heap_id[i] = heap_id[parent]
                i = parent
            heap_key[i] = key
            heap_id[i] = child
    return nfull, visits


@njit(cache=True)
def _count(bits, bins):  # pragma: no cover - compiled
    total = 0
    nw = bits.shape[1]
    for j in range(bits.shape[0]):
        for w in range(nw):
            e = bins - w * 64 if w == nw - 1 else 64
            total += _popcount(bits[j, w] & (_ALL >> np.uint64(64 - e)))
    return total


_BLOCK = 16  # queries per parallel iteration (one heap allocation each)


@njit(parallel=True, cache=True)
def cover_counts(queries, pts, centre, radius, lo, hi, first_leaf, h, zrow, srow, cxs, cys, bins):  # pragma: no cover
    """Covered samples and node visits per query, every cloud point counted (the exact union)."""
    n = queries.shape[0]
    rows = zrow.shape[0]
    words = (bins + 63) // 64
    counts = np.zeros(n, np.int64)
    visits = np.zeros(n, np.int64)
    n_nodes = centre.shape[0]
    n_blocks = (n + _BLOCK - 1) // _BLOCK
    for blk in prange(n_blocks):
        heap_key = np.empty(n_nodes + 2)
        heap_id = np.empty(n_nodes + 2, np.int64)
        cand_j = np.empty(_MAX_CAND, np.int64)
        cand_k = np.empty(_MAX_CAND, np.int64)
        bits = np.zeros((rows, words), np.uint64)
        count = np.zeros(rows, np.int32)
        for i in range(blk * _BLOCK, min(n, (blk + 1) * _BLOCK)):
            bits[:, :] = 0
            count[:] = 0
            _, v = _walk(
                queries[i, 0], queries[i, 1], queries[i, 2], pts, centre, radius, lo, hi, first_leaf, h,
                zrow, srow, cxs, cys, bins, bits, count, 0, 0.0, 0.0, 0.0, 0.0, 0, heap_key, heap_id,
                cand_j, cand_k,
            )
            visits[i] = v
            total = 0
            for j in range(rows):
                total += count[j]
            counts[i] = total
    return counts, visits


@njit(cache=True)
def _ball(fx, fy, fz, reach, pts, centre, radius, lo, hi, first_leaf, out, stack):  # pragma: no cover
    """Indices of the points within reach of f, into out (if big enough); their number.  With an
    empty ``out`` it only counts, taking nodes wholly inside the ball whole."""
    n = 0
    top = 1
    stack[0] = 0
    r2 = reach * reach
    while top > 0:
        top -= 1
        node = stack[top]
        r = radius[node]
        if r < 0.0:
            continue
        gx, gy, gz = centre[node, 0] - fx, centre[node, 1] - fy, centre[node, 2] - fz
        g = math.sqrt(gx * gx + gy * gy + gz * gz)
        if g - r > reach:
            continue
        if out.shape[0] == 0 and g + r < reach:
            n += hi[node] - lo[node]  # counting only: a node wholly inside counts whole
            continue
        if node >= first_leaf:
            for p in range(lo[node], hi[node]):
                ex, ey, ez = pts[p, 0] - fx, pts[p, 1] - fy, pts[p, 2] - fz
                if ex * ex + ey * ey + ez * ez <= r2:
                    if n < out.shape[0]:
                        out[n] = p
                    n += 1
            continue
        stack[top] = 2 * node + 1
        stack[top + 1] = 2 * node + 2
        top += 2
    return n


@njit(parallel=True, cache=True)
def near_counts(fcentre, freach, pts, centre, radius, lo, hi, first_leaf):  # pragma: no cover - compiled
    """Number of points within freach[c] of fcentre[c], for every c (the cost model's sample)."""
    n = fcentre.shape[0]
    out = np.zeros(n, np.int64)
    empty = np.empty(0, np.int64)
    for i in prange(n):
        stack = np.empty(128, np.int64)
        out[i] = _ball(fcentre[i, 0], fcentre[i, 1], fcentre[i, 2], freach[i], pts, centre, radius, lo, hi,
                       first_leaf, empty, stack)
    return out


@njit(parallel=True, cache=True)
def cluster_counts(
    queries, starts, fcentre, freach, first_cluster, n_clusters, pts, centre, radius, lo, hi, first_leaf, h,
    zrow, srow, cxs, cys, bins,
):  # pragma: no cover - compiled
    """Covered samples of the queries of clusters first..first+n-1 (queries sorted by cluster,
    cluster c = queries[starts[c]:starts[c + 1]]): the far field (points beyond freach[c] of
    fcentre[c]) walked once from fcentre[c], then each member's near field (the points within)
    added cap by cap.  One parallel region for the whole batch."""
    rows = zrow.shape[0]
    words = (bins + 63) // 64
    q0 = starts[first_cluster]
    counts = np.zeros(starts[first_cluster + n_clusters] - q0, np.int64)
    n_nodes = centre.shape[0]
    h2 = h * h
    for t in prange(n_clusters):
        c = first_cluster + t
        heap_key = np.empty(n_nodes + 2)
        heap_id = np.empty(n_nodes + 2, np.int64)
        cand_j = np.empty(_MAX_CAND, np.int64)
        cand_k = np.empty(_MAX_CAND, np.int64)
        far_bits = np.zeros((rows, words), np.uint64)
        far_count = np.zeros(rows, np.int32)
        fx, fy, fz, fr = fcentre[c, 0], fcentre[c, 1], fcentre[c, 2], freach[c]
        far_full, _ = _walk(
            fx, fy, fz, pts, centre, radius, lo, hi, first_leaf, h, zrow, srow, cxs, cys, bins,
            far_bits, far_count, 0, fx, fy, fz, fr, 1, heap_key, heap_id, cand_j, cand_k,
        )
        far_total = 0
        for j in range(rows):
            far_total += far_count[j]
        a, b = starts[c], starts[c + 1]
        if far_full >= rows:
            for i in range(a, b):
                counts[i - q0] = far_total
            continue
        stack = np.empty(128, np.int64)
        m = _ball(fx, fy, fz, fr, pts, centre, radius, lo, hi, first_leaf, np.empty(0, np.int64), stack)
        if m == 0:
            for i in range(a, b):
                counts[i - q0] = far_total
            continue
        near = np.empty(m, np.int64)
        _ball(fx, fy, fz, fr, pts, centre, radius, lo, hi, first_leaf, near, stack)
        bits = np.empty((rows, words), np.uint64)
        count = np.empty(rows, np.int32)
        for i in range(a, b):
            bits[:, :] = far_bits
            count[:] = far_count
            nfull = far_full
            qx, qy, qz = queries[i, 0], queries[i, 1], queries[i, 2]
            for p in near:
                ux, uy, uz = pts[p, 0] - qx, pts[p, 1] - qy, pts[p, 2] - qz
                d2 = ux * ux + uy * uy + uz * uz
                if d2 <= h2:
                    continue
                dist = math.sqrt(d2)
                sina = h / dist
                cosa = math.sqrt(1.0 - sina * sina)
                nfull += _cap(bits, count, ux / dist, uy / dist, uz / dist, cosa, sina, zrow, srow, cxs, cys,
                              bins, True)
                if nfull >= rows:
                    break
            total = 0
            for j in range(rows):
                total += count[j]
            counts[i - q0] = total
    return counts


# --------------------------------------------------------------------------------------------------
# Python side: the tree and the raster constants


class CapTree:
    """The cloud (raster frame, float64) in the implicit KD-tree, with the raster's row constants.

    ``checkpoint`` is called between tree levels (each well under 0.1 s at 1M points).
    """

    def __init__(self, pts: np.ndarray, h: float, rows: int, bins: int, checkpoint=None):
        if rows < 1 or bins < 1:
            raise ValueError("the raster needs at least one row and one bin")
        n = len(pts)
        self.h = float(h)
        self.rows, self.bins = int(rows), int(bins)
        z = -1.0 + (np.arange(self.rows) + 0.5) * (2.0 / self.rows)
        self.zrow = z
        self.srow = np.sqrt(1.0 - z * z)
        lon = (np.arange(self.bins) + 0.5) * (2.0 * np.pi / self.bins)
        self.cxs = np.ascontiguousarray(self.srow[:, None] * np.cos(lon)[None, :])
        self.cys = np.ascontiguousarray(self.srow[:, None] * np.sin(lon)[None, :])
        levels = tree_levels(n)
        self.lo, self.hi = node_ranges(n, levels)
        self.first_leaf = (1 << levels) - 1
        self.pts = np.ascontiguousarray(pts, dtype=np.float64).copy()
        self.perm = np.arange(n, dtype=np.int64)
        for level in range(levels):
            first = (1 << level) - 1
            split_level(self.pts, self.perm, self.lo, self.hi, first, 1 << level)
            if checkpoint is not None:
                checkpoint((level + 1) / (levels + 1))
        n_nodes = len(self.lo)
        self.centre = np.zeros((n_nodes, 3))
        self.radius = np.zeros(n_nodes)
        node_spheres(self.pts, self.lo, self.hi, 0, n_nodes, self.centre, self.radius)
        if checkpoint is not None:
            checkpoint(1.0)

    def _args(self):
        return (self.pts, self.centre, self.radius, self.lo, self.hi, self.first_leaf, self.h,
                self.zrow, self.srow, self.cxs, self.cys, self.bins)

    def every_point(self, queries: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(covered fraction, node visits) of every query, every cloud point counted."""
        counts, visits = cover_counts(np.ascontiguousarray(queries, dtype=np.float64), *self._args())
        return counts / float(self.rows * self.bins), visits

    def clusters(self, queries, starts, centres, reach, first: int, n: int) -> np.ndarray:
        """Covered fraction of the queries of clusters first..first+n-1 (see ``cluster_counts``)."""
        counts = cluster_counts(queries, starts, centres, reach, first, n, *self._args())
        return counts / float(self.rows * self.bins)

    def near_counts(self, centres: np.ndarray, reach: np.ndarray) -> np.ndarray:
        """Number of points within reach[k] of centres[k]."""
        return near_counts(np.ascontiguousarray(centres, np.float64), np.ascontiguousarray(reach, np.float64),
                           self.pts, self.centre, self.radius, self.lo, self.hi, self.first_leaf)
