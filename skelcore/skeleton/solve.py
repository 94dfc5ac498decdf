"""The contraction's linear solve: ``(W_L^2 L^T L + W_H^2) X = W_H^2 X0``, the normal equations of
``[W_L L; W_H] X = [0; W_H X0]`` (Cao et al. 2010 eq. 2, solved as the toolbox does, ``(A'A) \\ (A'b)``).

The matrix is symmetric positive definite. Two exact (direct) backends, the same solution to
rounding: ``cholmod``, CHOLMOD's supernodal Cholesky as MATLAB's backslash uses it (the library the
cvxopt wheel bundles, called through ctypes: :mod:`.cholmod`; ~9x faster than SuperLU at 64k
points), its symbolic analysis done once per sparsity pattern; ``superlu``, SciPy's SuperLU with a
symmetric ordering and no pivoting. Both release the GIL: the factorization runs in a helper thread
while the caller polls ``check`` every 20 ms, so a cancel is answered mid-factorization (the
abandoned one finishes alone). Measurements: docs/skeletonize.md, "sparse solver".
"""

from __future__ import annotations

import atexit
import threading
from functools import lru_cache
from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["SOLVERS", "solve_spd", "resolve_solver"]

#: linear_solver values: "auto" = cholmod when cvxopt is importable, else superlu
SOLVERS = ("auto", "cholmod", "superlu")
_POLL_S = 0.02
#: factorizations abandoned by a cancel, still running; joined at exit so none dies mid-call
_abandoned: list[threading.Thread] = []


@atexit.register
def _join_abandoned() -> None:
    for t in _abandoned:
        t.join()


@lru_cache(maxsize=1)
def _cvxopt():
    try:
        import cvxopt
        from cvxopt import cholmod
    except ImportError:
        return None
    return cvxopt, cholmod


def _have_cholmod() -> bool:
    from .cholmod import library

    return library() is not None or _cvxopt() is not None


def resolve_solver(name: str) -> str:
    """The backend ``name`` ("auto", "cholmod", "superlu") stands for here; ValueError when it
    names one that is not installed or does not exist."""
    if name not in SOLVERS:
        raise ValueError(f"unknown linear_solver {name!r}: use one of {', '.join(SOLVERS)}")
    if name == "auto":
        return "cholmod" if _have_cholmod() else "superlu"
    if name == "cholmod" and not _have_cholmod():
        raise ValueError("linear_solver 'cholmod' needs the cvxopt package (pip install cvxopt)")
    return name


# ---- CHOLMOD ---------------------------------------------------------------------------------

def _lower(M: sp.spmatrix) -> sp.csc_matrix:
    low = sp.csc_matrix(sp.tril(M, format="csc"))
    low.sum_duplicates()
    low.sort_indices()
    return low


def _cholmod_solve(M: sp.spmatrix, rhs: np.ndarray, cache: dict | None) -> np.ndarray | None:
    """Through ctypes (no GIL); None when the matrix is not positive definite to rounding."""
    from .cholmod import Factor

    low = _lower(M)
    F = cache.get("factor") if cache is not None else None
    if F is None or not F.same_pattern(low):
        F = Factor(low)
        if cache is not None:
            cache["factor"] = F
    if not F.factorize(low.data):
        return None
    return F.solve(rhs)


def _cvxopt_solve(M: sp.spmatrix, rhs: np.ndarray, cache: dict | None) -> np.ndarray:
    """cvxopt's own cholmod module (holds the GIL): when the library cannot be loaded by ctypes."""
    cvxopt, cholmod = _cvxopt()
    low = _lower(M)
    key = (low.shape, low.indptr, low.indices)
    c = cache.get("cholmod") if cache is not None else None
    same = (c is not None and c["key"][0] == key[0] and np.array_equal(c["key"][1], key[1])
            and np.array_equal(c["key"][2], key[2]))
    if same:
        A = c["A"]
        A.V = cvxopt.matrix(low.data)  # CSC with sorted rows is cvxopt's own value order
    else:
        col = np.repeat(np.arange(low.shape[1]), np.diff(low.indptr))
        A = cvxopt.spmatrix(cvxopt.matrix(low.data), cvxopt.matrix(low.indices.astype(np.int64)),
                            cvxopt.matrix(col.astype(np.int64)), size=low.shape)
    saved = dict(cholmod.options)
    cholmod.options.clear()
    cholmod.options.update({"supernodal": 2})  # level-3 BLAS; the "auto" switch may pick simplicial
    try:
        F = c["F"] if same else cholmod.symbolic(A, uplo="L")
        cholmod.numeric(A, F)
        B = cvxopt.matrix(np.asfortranarray(rhs))
        cholmod.solve(F, B)
    finally:
        cholmod.options.clear()
        cholmod.options.update(saved)
    if cache is not None:
        cache["cholmod"] = {"key": key, "A": A, "F": F}
    return np.array(B).reshape(rhs.shape)


# ---- SuperLU (SciPy) -------------------------------------------------------------------------

def _superlu_solve(M: sp.csc_matrix, rhs: np.ndarray, order: dict | None) -> np.ndarray:
    opts = dict(diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    q = None if order is None else order.get("q")
    if q is None or len(q) != M.shape[0]:
        lu = spla.splu(M, permc_spec="MMD_AT_PLUS_A", **opts)
        if order is not None:
            order["q"] = np.argsort(lu.perm_c)  # the columns in factorization order
        return lu.solve(rhs)
    # the contraction's matrices keep one sparsity pattern: reuse the first ordering (no pivoting on
    # an SPD matrix, so any symmetric permutation is exact; this one keeps the fill)
    lu = spla.splu(sp.csc_matrix(M[q][:, q]), permc_spec="NATURAL", **opts)
    out = np.empty_like(rhs)
    out[q] = lu.solve(np.ascontiguousarray(rhs[q]))
    return out


def _polled(fn: Callable[[], np.ndarray | None], check: Callable[[], None] | None) -> np.ndarray | None:
    """``fn()`` in a helper thread while this one calls ``check`` every 20 ms; a raising ``check``
    abandons the helper (it finishes alone; joined at exit)."""
    if check is None:
        return fn()
    out: dict = {}

    def run() -> None:
        try:
            out["x"] = fn()
        except BaseException as exc:  # handed to the caller's thread
            out["error"] = exc

    worker = threading.Thread(target=run, name="skelcore-solve", daemon=True)
    worker.start()
    while worker.is_alive():
        worker.join(_POLL_S)
        if worker.is_alive():
            try:
                check()
            except BaseException:
                _abandoned[:] = [t for t in _abandoned if t.is_alive()] + [worker]
                raise
    if "error" in out:
        raise out["error"]
    return out["x"]


def solve_spd(
    M: sp.spmatrix,
    rhs: np.ndarray,
    *,
    check: Callable[[], None] | None = None,
    order: dict | None = None,
    solver: str = "auto",
) -> np.ndarray:
    """Solve ``M X = rhs`` (M SPD, rhs (n, 3)) with the backend ``solver`` (see :data:`SOLVERS`).
    ``check()`` may raise (e.g. ``Cancelled``) to abandon the solve; it is called before and every
    20 ms during the factorization. ``order``: a dict kept across solves of one sparsity pattern;
    it caches the symbolic analysis (cholmod) or the fill-reducing ordering (superlu, ~40% of a
    factorization) of the first."""
    backend = resolve_solver(solver)
    M = sp.csc_matrix(M)
    rhs = np.ascontiguousarray(rhs, dtype=float)
    if check is not None:
        check()
    if backend == "cholmod":
        from .cholmod import library

        if library() is not None:
            x = _polled(lambda: _cholmod_solve(M, rhs, order), check)
        else:
            try:
                x = _cvxopt_solve(M, rhs, order)
            except ArithmeticError:
                x = None
            if check is not None:
                check()
        if x is not None:
            return x
        # not positive definite to rounding (CHOLMOD stops at the first bad pivot): SuperLU goes on
    return _polled(lambda: _superlu_solve(M, rhs, order), check)
