"""``method="cao"``: the contraction of Cao et al. 2010 as its authors' toolbox runs it.

Step by step ``contraction_by_mesh_laplacian.m`` with ``USING_POINT_RING``: the one-rings of the
normalized cloud (:mod:`.cao_ring`) stay fixed; each iteration recomputes the cotangent weights of
each point's own fan on the current positions (``compute_point_weight_dcp``: row-capped, not
symmetrized, ``L = W - diag(W 1)``), solves ``(A'A) X = A'b`` with ``A = [W_L L; diag(W_H)]``,
``b = [0; W_H X]`` (:mod:`.solve`), then ``W_L <- min(s_L W_L, 2048)`` and ``W_H = WC x size0 /
size`` (min one-ring edge, capped at 10000). It stops, keeping the previous iterate, when the
ratio sum(size) / sum(size0) fell by less than 0.01 (or is NaN) or the bounding box grew beyond 1.2x
on an axis; ``t`` counts the accepted solves, at most 20.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.sparse as sp

from .skeleton_params import CaoParams
from .solve import solve_spd

__all__ = ["Rings", "cao_contract", "cotangent_laplacian"]


class Rings:
    """The one-rings in flat arrays: ``owner[p]`` is the point whose ring holds ``member[p]``."""

    def __init__(self, indptr: np.ndarray, indices: np.ndarray) -> None:
        self.n = len(indptr) - 1
        self.indptr = np.asarray(indptr, np.int64)
        self.member = np.asarray(indices, np.int64)
        self.owner = np.repeat(np.arange(self.n), np.diff(self.indptr))
        # fan triangles (i, ring[t], ring[t+1]) of every ring
        last = np.zeros(len(self.member), bool)
        ends = self.indptr[1:] - 1
        last[ends[ends >= self.indptr[:-1]]] = True
        p = np.flatnonzero(~last)
        self.tri = (self.owner[p], self.member[p], self.member[p + 1])

    def relabel(self, perm: np.ndarray) -> "Rings":
        """The same rings with point ``perm[q]`` renamed ``q`` (rows and members alike)."""
        inv = np.empty_like(perm)
        inv[perm] = np.arange(len(perm))
        lens = np.diff(self.indptr)[perm]
        indptr = np.concatenate([[0], np.cumsum(lens)])
        src = np.repeat(self.indptr[perm] - indptr[:-1], lens) + np.arange(int(indptr[-1]))
        return Rings(indptr, inv[self.member[src]])

    def sizes(self, pts: np.ndarray, kind: str) -> np.ndarray:
        """``GS.one_ring_size``: per point the min ("min") or mean ("mean") distance to its ring
        entries (a closed ring's repeated first vertex counts twice in the mean, as there)."""
        d = np.linalg.norm(pts[self.member] - pts[self.owner], axis=1)
        out = np.zeros(self.n)
        counts = np.diff(self.indptr)
        has = counts > 0
        if kind == "min":
            out[has] = np.minimum.reduceat(d, self.indptr[:-1][has])
        else:
            out[has] = np.add.reduceat(d, self.indptr[:-1][has]) / counts[has]
        return out


def _laplacian_pattern(rings: Rings) -> tuple:
    """The CSR pattern shared by every iteration's Laplacian (the fan entries (i, j), (i, k) of
    each triangle plus the diagonal) and where each triangle's two weights land in it."""
    i, j, k = rings.tri
    n = rings.n
    rows = np.concatenate([i, i, np.arange(n)])
    cols = np.concatenate([j, k, np.arange(n)])
    key = rows * n + cols
    uniq, where = np.unique(key, return_inverse=True)
    indptr = np.searchsorted(uniq, np.arange(n + 1) * n).astype(np.int64)
    indices = (uniq % n).astype(np.int64)
    ntri = len(i)
    return indptr, indices, where[: 2 * ntri], where[2 * ntri:], np.repeat(np.arange(n), np.diff(indptr))


def cotangent_laplacian(pts: np.ndarray, rings: Rings, row_cap: float) -> sp.csr_matrix:
    """``-compute_point_laplacian(pts, 'conformal', rings)`` = W - diag(W 1), W from each point's fan:
    W(i, j) += cot of the angle at k, W(i, k) += cot of the angle at j, per fan triangle (i, j, k);
    rows with |sum| > row_cap scaled to row_cap. One sparsity pattern for all positions (cached on
    ``rings``: the iterations only fill in values)."""
    pattern = getattr(rings, "_lap_pattern", None)
    if pattern is None:
        pattern = rings._lap_pattern = _laplacian_pattern(rings)
    indptr, indices, where, diag, row_of = pattern
    i, j, k = rings.tri
    x, y, z = (np.ascontiguousarray(pts[:, c], dtype=float) for c in range(3))

    def cot(a: int | np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
        # cot of the angle at a in triangle (a, b, c): (b - a).(c - a) / |(b - a) x (c - a)|
        ux, uy, uz = x[b] - x[a], y[b] - y[a], z[b] - z[a]
        vx, vy, vz = x[c] - x[a], y[c] - y[a], z[c] - z[a]
        cx, cy, cz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
        cr = np.sqrt(cx * cx + cy * cy + cz * cz)
        # a zero-area triangle: the toolbox divides by zero; a tiny floor keeps it finite and the
        # row cap then bounds the row as the toolbox intends
        return (ux * vx + uy * vy + uz * vz) / np.maximum(cr, 1e-300)

    n = rings.n
    w = np.bincount(where, weights=np.concatenate([cot(k, i, j), cot(j, i, k)]), minlength=len(indices))
    s = np.bincount(row_of, weights=w, minlength=n)
    big = np.abs(s) > row_cap
    if np.any(big):
        f = np.ones(n)
        f[big] = row_cap / np.abs(s[big])
        w *= f[row_of]
        s = s * f
    w[diag] -= s
    return sp.csr_matrix((w, indices, indptr), shape=(n, n))


def cao_contract(
    pts: np.ndarray,
    rings: Rings,
    params: CaoParams = CaoParams(),
    *,
    report: Callable[[str, float], None] | None = None,
) -> tuple[np.ndarray, dict]:
    """Contract normalized points; returns (contracted points, info) with info "iterations" (the
    toolbox's t), "initial_weight", "ring_ratios" (its ``a``), "stop_reason".

    Works on the points in the kd-tree's leaf order (spatial neighbours next to each other: the
    sparse products and gathers of every iteration stay cache-local, 2-4x faster on a shuffled
    cloud) and returns them in the caller's order; the same result to rounding."""
    from scipy.spatial import cKDTree

    perm = np.asarray(cKDTree(pts).indices, np.int64)
    cpts, info = _contract(np.ascontiguousarray(pts[perm]), rings.relabel(perm), params, report)
    out = np.empty_like(cpts)
    out[perm] = cpts
    return out, info


def _contract(pts: np.ndarray, rings: Rings, params: CaoParams, report: Callable[[str, float], None] | None
              ) -> tuple[np.ndarray, dict]:
    report = report or (lambda _stage, _f: None)
    n = len(pts)
    bbox0 = pts.max(axis=0) - pts.min(axis=0)
    wl = (float(params.contraction_weight) if params.contraction_weight is not None
          else 1.0 / (5.0 * float(np.mean(rings.sizes(pts, "mean")))))
    init_wl = wl
    wc = float(params.attraction_weight)
    wh = np.full(n, wc)
    sizes0 = rings.sizes(pts, "min")
    total0 = float(sizes0.sum())

    order: dict = {}  # one sparsity pattern for every iteration: its ordering is computed once

    def check_for(it: int) -> Callable[[], None]:
        return lambda: report("contraction", it / params.max_iterations)

    def step(current: np.ndarray, wl: float, wh: np.ndarray, it: int) -> np.ndarray:
        check = check_for(it)
        L = cotangent_laplacian(current, rings, params.weight_row_cap)
        check()  # between the steps too: each is ~0.1 s per 64k points
        LtL = L.T @ L
        check()
        M = ((wl * wl) * LtL + sp.diags(wh * wh)).tocsc()
        rhs = (wh * wh)[:, None] * current
        return solve_spd(M, rhs, check=check, order=order, solver=params.linear_solver)

    report("contraction", 0.0)
    cpts = step(pts, wl, wh, 0)
    t = 1
    size_new = rings.sizes(cpts, "min")
    a = [float(size_new.sum()) / total0]
    stop = "max_iterations"
    while t < params.max_iterations:
        wl = min(params.contraction_scale * wl, params.contraction_weight_max)
        with np.errstate(divide="ignore", invalid="ignore"):
            wh = wc * (sizes0 / size_new)
        # 0/0 (a point duplicated in the cloud): the toolbox's NaN would poison the whole solve; the cap
        # holds such a point instead (docs/skeletonize.md)
        wh = np.where(np.isnan(wh), np.inf, wh)
        wh = np.minimum(wh, params.attraction_weight_max)
        tmp = step(cpts, wl, wh, t)
        size_new = rings.sizes(tmp, "min")
        a.append(float(size_new.sum()) / total0)
        box = tmp.max(axis=0) - tmp.min(axis=0)
        if np.any(box > bbox0 * params.bbox_growth_limit):
            stop = "bounding box grew"
            break
        if a[t - 1] - a[-1] < params.termination_ratio or np.isnan(a[-1]):
            stop = "one-ring size stopped shrinking"
            break
        cpts = tmp
        t += 1
    report("contraction", 1.0)
    return cpts, {"iterations": t, "initial_weight": init_wl, "ring_ratios": a, "stop_reason": stop}
