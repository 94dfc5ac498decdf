"""skelcore.skeleton.solve: the contraction's SPD solve. CHOLMOD (ctypes, and cvxopt's module as the
fallback) against SuperLU and a dense solve, its cached symbolic analysis, its fallback on a matrix
that is not positive definite, a cancel mid-factorization, and the whole skeletonizer giving the same
skeleton with either backend."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from skelcore import shapes
from skelcore.errors import Cancelled
from skelcore.skeleton import CaoParams, skeletonize
from skelcore.skeleton import solve
from skelcore.skeleton.cao import Rings, cotangent_laplacian
from skelcore.skeleton.cao_ring import knn_count, point_rings

pytest.importorskip("cvxopt")


def _contraction_matrix(n: int = 1500, wl: float = 40.0, seed: int = 3):
    """A real contraction system: the cao Laplacian of a normalized cylinder, W_H varying."""
    pts = shapes.cylinder(n, seed=seed).cloud
    pts = (pts - pts.min(axis=0)) * (1.6 / np.ptp(pts, axis=0).max())
    indptr, indices, _ = point_rings(pts, knn_count(len(pts)))
    L = cotangent_laplacian(pts, Rings(indptr, indices), 1e4)
    wh = 1.0 + np.random.default_rng(seed).random(n) * 5.0
    M = (wl * wl) * (L.T @ L) + sp.diags(wh * wh)
    return M.tocsc(), (wh * wh)[:, None] * pts, pts


def test_cholmod_and_superlu_solve_the_contraction_system_as_a_dense_solve_does():
    M, rhs, _pts = _contraction_matrix()
    dense = np.linalg.solve(M.toarray(), rhs)
    scale = np.abs(dense).max()
    for name in ("cholmod", "superlu"):
        x = solve.solve_spd(M, rhs, solver=name)
        assert np.abs(x - dense).max() < 1e-9 * scale, name
    assert solve.resolve_solver("auto") == "cholmod"


def test_the_cached_analysis_serves_new_values_and_a_new_pattern_is_analysed_afresh():
    M, rhs, _pts = _contraction_matrix()
    cache: dict = {}
    solve.solve_spd(M, rhs, solver="cholmod", order=cache)
    F = cache["factor"]
    M2 = (M * 3.0 + sp.identity(M.shape[0])).tocsc()  # same pattern, new values
    x2 = solve.solve_spd(M2, rhs, solver="cholmod", order=cache)
    assert cache["factor"] is F
    np.testing.assert_allclose(M2 @ x2, rhs, atol=1e-8 * np.abs(rhs).max())
    M3 = sp.diags(np.arange(1.0, M.shape[0] + 1.0)).tocsc()  # another pattern
    x3 = solve.solve_spd(M3, rhs, solver="cholmod", order=cache)
    assert cache["factor"] is not F
    np.testing.assert_allclose(x3, rhs / np.arange(1.0, M.shape[0] + 1.0)[:, None], rtol=1e-12)


def test_a_matrix_cholmod_rejects_is_solved_by_superlu():
    # symmetric, not positive definite: CHOLMOD stops at the negative pivot, SuperLU goes on
    n = 50
    d = np.linspace(1.0, 2.0, n)
    d[10] = -1.0
    M = sp.diags(d) + sp.diags([0.1] * (n - 1), 1) + sp.diags([0.1] * (n - 1), -1)
    b = np.ones((n, 3))
    x = solve.solve_spd(M, b, solver="cholmod")
    np.testing.assert_allclose(M @ x, b, atol=1e-10)


def test_a_cancel_raised_during_the_cholmod_factorization_returns_before_it_ends():
    import threading

    from scipy.spatial import cKDTree

    n = 16000
    pts = np.random.default_rng(0).random((n, 3))
    _d, nn = cKDTree(pts).query(pts, k=10)
    A = sp.coo_matrix((np.ones(nn.size), (np.repeat(np.arange(n), 10), nn.ravel())), shape=(n, n)).tocsr()
    M = (A.T @ A) + sp.identity(n)  # a random 3-D graph: heavy fill-in, CHOLMOD takes ~1 s
    polls = {"n": 0}

    def check() -> None:  # the first call comes before the helper starts, then every 20 ms
        polls["n"] += 1
        if polls["n"] >= 3:
            raise Cancelled("stop")

    with pytest.raises(Cancelled):
        solve.solve_spd(M, pts, check=check, solver="cholmod")
    # the cancel came back while CHOLMOD was still working (no GIL held: the polls ran meanwhile)
    running = [t for t in solve._abandoned if t.is_alive()]
    assert running
    for t in running:
        t.join()
    x = solve.solve_spd(M, pts, solver="cholmod")  # and the solver still works afterwards
    np.testing.assert_allclose(M @ x, pts, atol=1e-8)


def test_without_the_ctypes_library_cvxopts_module_solves(monkeypatch):
    from skelcore.skeleton import cholmod

    M, rhs, _pts = _contraction_matrix()
    want = solve.solve_spd(M, rhs, solver="superlu")
    monkeypatch.setattr(cholmod, "library", lambda: None)
    cache: dict = {}
    for scale in (1.0, 2.0):  # the second solve reuses cvxopt's symbolic analysis
        x = solve.solve_spd(M * scale, rhs, solver="cholmod", order=cache)
        np.testing.assert_allclose(x * scale, want, atol=1e-9 * np.abs(want).max())
    assert "cholmod" in cache


def test_a_cancel_mid_contraction_stops_skeletonize_with_either_solver():
    cloud = shapes.cylinder(3000, seed=4).cloud
    for name in ("cholmod", "superlu"):
        seen: list[str] = []

        def progress(_f: float, stage: str) -> None:
            seen.append(stage)

        def cancel() -> bool:  # raised once the contraction has started
            return "contraction" in seen

        with pytest.raises(Cancelled, match="contraction"):
            skeletonize(cloud, CaoParams(linear_solver=name), progress=progress, cancel=cancel)


def test_both_solvers_give_the_same_skeleton():
    for shape in (shapes.cylinder(2500, seed=5), shapes.torus(2500, seed=6), shapes.y_shape(3000, seed=7)):
        cloud = shape.cloud
        diag = float(np.linalg.norm(np.ptp(cloud, axis=0)))
        sk_c, cu_c, info_c = skeletonize(cloud, CaoParams(linear_solver="cholmod"), return_info=True)
        sk_s, cu_s, info_s = skeletonize(cloud, CaoParams(linear_solver="superlu"), return_info=True)
        assert info_c.iterations == info_s.iterations
        np.testing.assert_allclose(info_c.ring_ratios, info_s.ring_ratios, atol=1e-9)
        assert np.linalg.norm(sk_c - sk_s, axis=1).max() < 1e-7 * diag
        np.testing.assert_array_equal(cu_c.edges, cu_s.edges)
        assert np.abs(cu_c.vertices - cu_s.vertices).max() < 1e-7 * diag


def test_solver_names_are_checked(monkeypatch):
    with pytest.raises(ValueError, match="linear_solver"):
        CaoParams(linear_solver="umfpack")
    with pytest.raises(ValueError, match="unknown linear_solver"):
        solve.resolve_solver("umfpack")
    from skelcore.skeleton import cholmod

    monkeypatch.setattr(solve, "_cvxopt", lambda: None)  # as without cvxopt installed
    monkeypatch.setattr(cholmod, "library", lambda: None)
    assert solve.resolve_solver("auto") == "superlu"
    with pytest.raises(ValueError, match="needs the cvxopt package"):
        solve.resolve_solver("cholmod")


def test_skelscope_gives_the_same_skeleton_with_either_solver():
    from skelcore.skeleton import SkeletonizeParams

    cloud = shapes.y_shape(3000, seed=8).cloud
    diag = float(np.linalg.norm(np.ptp(cloud, axis=0)))
    sk_c, cu_c, info_c = skeletonize(cloud, SkeletonizeParams(linear_solver="cholmod"), return_info=True)
    sk_s, cu_s, info_s = skeletonize(cloud, SkeletonizeParams(linear_solver="superlu"), return_info=True)
    assert info_c.iterations == info_s.iterations
    assert np.linalg.norm(sk_c - sk_s, axis=1).max() < 1e-7 * diag
    np.testing.assert_array_equal(cu_c.edges, cu_s.edges)
    with pytest.raises(ValueError, match="linear_solver"):
        SkeletonizeParams(linear_solver="spsolve")


def test_cholmod_is_told_not_to_print():
    import struct

    from skelcore.skeleton import cholmod

    M = sp.csc_matrix(sp.tril(sp.diags(np.arange(1.0, 11.0))))
    F = cholmod.Factor(M)
    assert struct.unpack_from("i", F._common.raw, cholmod._PRINT_OFFSET)[0] == 0
    assert F.factorize(M.data)
    np.testing.assert_allclose(F.solve(np.ones((10, 3)))[:, 0], 1.0 / np.arange(1.0, 11.0))
