"""The contraction's linear solve: ``(W_L^2 L^T L + W_H^2) X = W_H^2 X0``, the normal equations of
``[W_L L; W_H] X = [0; W_H X0]`` (Cao et al. 2010 eq. 2, solved as the toolbox does, ``(A'A) \\ (A'b)``).

The matrix is symmetric positive definite. Small systems are factorized (SuperLU with a symmetric
ordering and no pivoting: the Cholesky-like path MATLAB's backslash takes for SPD matrices). Large
ones are solved by conjugate gradients warm-started from the current positions, preconditioned by
an incomplete LU of the same matrix, to a relative residual of ``rtol``; the iteration checks the
cancel callback every step, so a solve stops within one CG step (milliseconds) of a cancel. The
residual tolerance keeps the result within rounding of the direct solve for what the metrics see
(docs/skeletonize.md, "sparse solver").
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["solve_spd", "DIRECT_MAX"]

#: systems up to this many unknowns are factorized; above, preconditioned CG (measured crossover)
DIRECT_MAX = 20000


def solve_spd(
    M: sp.spmatrix,
    rhs: np.ndarray,
    x0: np.ndarray,
    *,
    check: Callable[[], None] | None = None,
    rtol: float = 1e-10,
    direct_max: int = DIRECT_MAX,
) -> np.ndarray:
    """Solve ``M X = rhs`` (M SPD, rhs (n, 3)); ``check()`` is called often and may raise."""
    check = check or (lambda: None)
    n = M.shape[0]
    M = sp.csc_matrix(M)
    if n <= direct_max:
        check()
        lu = spla.splu(M, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
        check()
        return lu.solve(np.ascontiguousarray(rhs, dtype=float))
    check()
    try:
        ilu = spla.spilu(M, drop_tol=1e-4, fill_factor=10, permc_spec="MMD_AT_PLUS_A",
                         diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        precond = spla.LinearOperator(M.shape, ilu.solve)
    except RuntimeError:  # singular incomplete factor: fall back on Jacobi
        dinv = 1.0 / M.diagonal()
        precond = spla.LinearOperator(M.shape, lambda v: dinv * v)
    check()
    out = np.empty_like(rhs, dtype=float)
    for c in range(rhs.shape[1]):
        b = rhs[:, c]
        x, info = spla.cg(M, b, x0=x0[:, c], rtol=rtol, atol=0.0, maxiter=4 * n, M=precond,
                          callback=lambda _xk: check())
        if info != 0:  # not converged: finish with the factorization (rare; slow but exact)
            check()
            x = spla.spsolve(M, b)
        out[:, c] = x
    return out
