"""The contraction's linear solve: ``(W_L^2 L^T L + W_H^2) X = W_H^2 X0``, the normal equations of
``[W_L L; W_H] X = [0; W_H X0]`` (Cao et al. 2010 eq. 2, solved as the toolbox does, ``(A'A) \\ (A'b)``).

The matrix is symmetric positive definite: SuperLU with a symmetric ordering (minimum degree on
A^T + A) and no pivoting, the Cholesky-like path MATLAB's backslash takes for it, several times
faster than ``spsolve``'s default (COLAMD, partial pivoting). SuperLU releases the GIL, so the
factorization runs in a helper thread while the caller's thread polls ``check`` every 20 ms: a
cancel is answered within that, mid-factorization; the abandoned factorization finishes on its
own and is dropped (docs/skeletonize.md, "sparse solver"). Measured against CG: docs/skeletonize.md.
"""

from __future__ import annotations

import atexit
import threading
from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["solve_spd"]

_POLL_S = 0.02
#: factorizations abandoned by a cancel, still running; joined at exit so none dies mid-call
_abandoned: list[threading.Thread] = []


@atexit.register
def _join_abandoned() -> None:
    for t in _abandoned:
        t.join()


def _factor_solve(M: sp.csc_matrix, rhs: np.ndarray, order: dict | None) -> np.ndarray:
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


def solve_spd(
    M: sp.spmatrix, rhs: np.ndarray, *, check: Callable[[], None] | None = None, order: dict | None = None
) -> np.ndarray:
    """Solve ``M X = rhs`` (M SPD, rhs (n, 3)). ``check()`` is called every 20 ms while the
    factorization runs and may raise (e.g. ``Cancelled``), which abandons the solve at once.
    ``order``: a dict kept across solves of one sparsity pattern; it caches the fill-reducing
    ordering of the first (computing it is ~40% of a factorization)."""
    M = sp.csc_matrix(M)
    rhs = np.ascontiguousarray(rhs, dtype=float)
    if check is None:
        return _factor_solve(M, rhs, order)
    check()
    out: dict = {}

    def run() -> None:
        try:
            out["x"] = _factor_solve(M, rhs, order)
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
