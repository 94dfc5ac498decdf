"""Laplacian-based contraction (Cao et al. 2010): the skeletal point set in pointwise correspondence.

Each point keeps the one-ring it has in the original cloud (the local-Delaunay neighbours of
``robust_laplacian``'s point-cloud Laplacian); the triangles of those one-rings form a triangle soup
whose cotangent Laplacian is recomputed on the current positions at every iteration
(``robust_laplacian.mesh_laplacian``; its intrinsic mollification keeps nearly collapsed triangles
finite). Each iteration solves the least-squares system ``[W_L L; W_H] X' = [0; W_H X]`` through its
normal equations; ``W_L`` grows by ``contraction_scale`` per iteration and ``W_H`` is each point's
one-ring shrink ratio, as Cao's toolbox does. Iterations stop when the mean one-ring size stops
shrinking. Runs in normalized coordinates (see :mod:`skelcore.skeleton.pipeline`).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .skeleton_params import SkeletonizeParams
from .solve import resolve_solver, solve_spd

__all__ = ["contract"]

def _one_ring_graph(points: np.ndarray, params: SkeletonizeParams) -> sp.csr_matrix:
    """Symmetric 0/1 adjacency of the local-Delaunay one-rings (robust_laplacian's sparsity)."""
    import robust_laplacian

    k = int(min(params.laplacian_neighbors, len(points) - 1))
    L, _ = robust_laplacian.point_cloud_laplacian(points, mollify_factor=params.mollify_factor, n_neighbors=k)
    L = sp.coo_matrix(L)
    off = (L.row != L.col) & (L.data != 0)
    n = len(points)
    adj = sp.coo_matrix((np.ones(int(off.sum())), (L.row[off], L.col[off])), shape=(n, n)).tocsr()
    adj = ((adj + adj.T) > 0).astype(np.int8).tocsr()
    adj.eliminate_zeros()
    return adj


def _triangles(adj: sp.csr_matrix) -> np.ndarray:
    """All 3-cliques (i < j < k) of the one-ring graph: the triangle soup of the one-rings."""
    upper = sp.triu(adj, k=1).tocsr()
    upper.sort_indices()
    indptr, indices = upper.indptr, upper.indices
    rows = np.repeat(np.arange(upper.shape[0]), np.diff(indptr))
    # for every edge (i, j), candidates k among the upper neighbours of i, kept if (j, k) is an edge
    deg = np.diff(indptr)
    tris = []
    n = upper.shape[0]
    keys = rows.astype(np.int64) * n + indices  # sorted: CSR rows in order, sorted indices
    for offset in range(int(deg.max(initial=0))):
        has = deg[rows] > offset
        i = rows[has]
        j = indices[has]
        kk = indices[indptr[i] + offset]
        ok = kk > j
        i, j, kk = i[ok], j[ok], kk[ok]
        q = j.astype(np.int64) * n + kk
        pos = np.searchsorted(keys, q)
        pos = np.minimum(pos, len(keys) - 1)
        hit = keys[pos] == q
        tris.append(np.column_stack([i[hit], j[hit], kk[hit]]))
    if not tris:
        return np.empty((0, 3), np.int64)
    return np.vstack(tris).astype(np.int64)


def _ring_sizes(points: np.ndarray, adj: sp.csr_matrix) -> np.ndarray:
    """Per point, the shortest distance to a one-ring neighbour (toolbox's ``one_ring_size`` type 1)."""
    coo = adj.tocoo()
    d = np.linalg.norm(points[coo.row] - points[coo.col], axis=1)
    out = np.full(len(points), np.inf)
    np.minimum.at(out, coo.row, d)
    out[~np.isfinite(out)] = 0.0
    return out


def _cotan_laplacian(points: np.ndarray, faces: np.ndarray, mollify: float) -> sp.csr_matrix:
    import robust_laplacian

    L, _ = robust_laplacian.mesh_laplacian(np.ascontiguousarray(points), faces, mollify_factor=mollify)
    return sp.csr_matrix(L)


# ---------------------------------------------------------------------------------------------
# contraction


def _robust_extent(points: np.ndarray) -> np.ndarray:
    """Bounding-box sides ignoring the 0.1% most extreme points per side: a few points thrown out by
    a degenerate one-ring must not stop the contraction of everything else (boundedness shows them)."""
    if len(points) < 1000:
        return points.max(axis=0) - points.min(axis=0)
    lo, hi = np.quantile(points, [0.001, 0.999], axis=0)
    return hi - lo


def contract(
    points_n: np.ndarray,
    params: SkeletonizeParams = SkeletonizeParams(),
    *,
    report: Callable[[str, float], None] | None = None,
) -> tuple[np.ndarray, sp.csr_matrix, dict]:
    """Cao et al.'s iterative Laplacian contraction of normalized points.

    Returns (contracted points, one-ring adjacency of the original points, info dict).
    """
    report = report or (lambda _stage, _f: None)
    n = len(points_n)
    report("laplacian", 0.0)
    adj = _one_ring_graph(points_n, params)
    faces = _triangles(adj)
    report("laplacian", 1.0)

    sizes0 = _ring_sizes(points_n, adj)
    coo = adj.tocoo()
    mean_edge = float(np.mean(np.linalg.norm(points_n[coo.row] - points_n[coo.col], axis=1))) if coo.nnz else 1.0
    # Cao's toolbox starts at 1 / (5 h). The Laplacian of a sampled surface scales with the area per
    # point (h^2), so that start contracts a dense cloud far more weakly than a sparse one; scaling it
    # by sqrt(N / reference_points) gives the same first step as the toolbox's on a cloud of the
    # reference size (the paper's 4096) of the same surface, whatever the density. The cap scales alike.
    density = float(np.sqrt(n / params.reference_points))
    if params.contraction_weight is not None:
        wl = float(params.contraction_weight)
    else:
        wl = density / (5.0 * mean_edge)
    wl_max = params.contraction_weight_max * density
    wh = np.full(n, float(params.attraction_weight))
    extent0 = np.maximum(_robust_extent(points_n), 1e-12)
    total0 = float(sizes0.sum()) or 1.0

    backend = resolve_solver(params.linear_solver)
    order: dict = {}  # CHOLMOD's symbolic analysis, one sparsity pattern for every iteration
    current = points_n.copy()
    ratios: list[float] = [1.0]
    stop = "max_iterations"
    iterations = 0
    if len(faces) == 0:
        return current, adj, {"iterations": 0, "ring_ratios": ratios, "stop_reason": "no one-ring triangles"}
    for it in range(int(params.max_iterations)):
        report("contraction", it / params.max_iterations)
        L = _cotan_laplacian(current, faces, params.mollify_factor)
        A = (wl * wl) * (L.T @ L) + sp.diags(wh * wh)
        rhs = (wh * wh)[:, None] * current
        if backend == "cholmod":
            new = solve_spd(A, rhs, order=order, solver="cholmod",
                            check=lambda: report("contraction", it / params.max_iterations))
        else:
            # spsolve (COLAMD, partial pivoting): measured far faster on this matrix than solve_spd's
            # symmetric-mode SuperLU path, whose ordering suits the cao matrix (docs/skeletonize.md)
            new = spla.spsolve(A.tocsc(), rhs)
        new = np.asarray(new).reshape(n, 3)
        if not np.all(np.isfinite(new)):
            stop = "non-finite solve"
            break
        extent = _robust_extent(new)
        # relative to the longest side: a thin axis of a sheet may widen a little without diverging
        if np.any(extent - extent0 > (params.bbox_growth_limit - 1.0) * extent0.max()):
            stop = "bounding box grew"
            break
        sizes = _ring_sizes(new, adj)
        ratio = float(sizes.sum()) / total0
        iterations += 1
        decrease = ratios[-1] - ratio
        current = new
        ratios.append(ratio)
        # the toolbox also stops when nothing has moved yet (a fat part under weak first weights)
        if decrease < params.termination_ratio and ratio < params.started_ratio:
            stop = "one-ring size stopped shrinking"
            break
        wl = min(wl * params.contraction_scale, wl_max)
        with np.errstate(divide="ignore", invalid="ignore"):
            wh = params.attraction_weight * np.where(sizes > 0, sizes0 / sizes, params.attraction_weight_max)
        wh = np.clip(np.nan_to_num(wh, nan=params.attraction_weight), params.attraction_weight, params.attraction_weight_max)
    report("contraction", 1.0)
    return current, adj, {"iterations": iterations, "ring_ratios": ratios, "stop_reason": stop}


# ---------------------------------------------------------------------------------------------
# curve extraction
