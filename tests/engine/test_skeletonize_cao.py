"""skelcore.skeleton, method "cao" (the default): the toolbox's algorithm, its pieces against
independent code, both methods' topology on shapes with known skeletons, and the paper's numbers on
the real scans of resources/scans."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import Delaunay

from skelcore import shapes
from skelcore.curve import CurveSkeleton
from skelcore.errors import Cancelled
from skelcore.skeleton import CaoParams, SkeletonizeParams, skeletonize
from skelcore.skeleton.cao import Rings, cotangent_laplacian
from skelcore.skeleton.cao_curve import connect_by_inherit_neigh, edge_collapse_update, farthest_sampling_by_sphere
from skelcore.skeleton.cao_ring import _neighbours, _project, knn_count, point_rings


def _components(curve: CurveSkeleton) -> int:
    n, e = curve.n_vertices, curve.edges
    adj = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    return int(connected_components(adj, directed=False)[0])


# ---- topology of both methods on shapes with known skeletons ----------------------------------

SHAPES = {
    "cylinder": lambda: shapes.cylinder(3000, seed=1),
    "torus": lambda: shapes.torus(3000, seed=2),
    "y": lambda: shapes.y_shape(5000, seed=3),
}


@pytest.fixture(scope="module", params=["cao", "skelscope"])
def results(request):
    return request.param, {name: (make(), skeletonize(make().cloud, method=request.param)) for name, make in SHAPES.items()}


def test_cylinder_gives_one_path_for_both_methods(results):
    method, res = results
    _shape, (_sk, curve) = res["cylinder"]
    assert curve.n_vertices >= 3, method
    assert _components(curve) == 1 and curve.n_edges == curve.n_vertices - 1, method
    assert curve.degrees().max() <= 2, method


def test_torus_gives_one_cycle_for_both_methods(results):
    method, res = results
    _shape, (_sk, curve) = res["torus"]
    assert _components(curve) == 1 and curve.n_edges == curve.n_vertices, method
    assert np.all(curve.degrees() == 2), method


def test_y_shape_gives_one_junction_for_both_methods(results):
    method, res = results
    _shape, (_sk, curve) = res["y"]
    deg = curve.degrees()
    assert _components(curve) == 1 and curve.n_edges == curve.n_vertices - 1, method
    assert np.count_nonzero(deg >= 3) == 1 and np.count_nonzero(deg == 1) == 3, method


def test_cao_contracts_the_torus_onto_its_core_circle(results):
    method, res = results
    shape, (skeletal, curve) = res["torus"]
    if method != "cao":
        pytest.skip("cao only")
    assert skeletal.shape == shape.cloud.shape
    ring = np.hypot(np.hypot(skeletal[:, 0], skeletal[:, 1]) - 1.0, skeletal[:, 2])
    assert np.median(ring) < 0.1 and np.quantile(ring, 0.99) < 0.3  # tube radius 0.3
    vring = np.hypot(np.hypot(curve.vertices[:, 0], curve.vertices[:, 1]) - 1.0, curve.vertices[:, 2])
    assert vring.max() < 0.3


# ---- the pieces against independent code -----------------------------------------------------

def test_knn_count_is_the_toolboxs():
    assert [knn_count(n) for n in (100, 700, 1000, 2500, 4096, 100000)] == [8, 8, 12, 30, 30, 30]
    assert knn_count(5) == 5


def test_one_rings_are_the_delaunay_stars_qhull_gives(rng):
    pts = shapes.y_shape(1500, seed=4).cloud
    k = knn_count(len(pts))
    indptr, indices, closed = point_rings(pts, k, chunk=500)
    from scipy.spatial import cKDTree

    idx = _neighbours(pts, cKDTree(pts), np.arange(len(pts)), k)
    proj = _project(pts, idx)
    for i in rng.choice(len(pts), 150, replace=False):
        tri = Delaunay(proj[i], qhull_options="Qt Qbb Qc").simplices
        star = tri[np.any(tri == 0, axis=1)]
        ring = indices[indptr[i]:indptr[i + 1]]
        assert set(idx[i, np.unique(star[star != 0])]) == set(ring)
        # consecutive ring entries are the star's triangles
        edges = {frozenset(e) for e in np.sort(star, axis=1)[:, 1:].tolist()}
        local = {int(g): j for j, g in enumerate(idx[i])}
        steps = {frozenset((local[a], local[b])) for a, b in zip(ring[:-1], ring[1:])}
        assert steps <= edges
        assert closed[i] == (ring[0] == ring[-1])
        assert len(steps) == len(edges)


def test_cotangent_weights_match_a_plain_loop():
    pts = shapes.cylinder(400, seed=5).cloud
    indptr, indices, _ = point_rings(pts, knn_count(len(pts)))
    rings = Rings(indptr, indices)
    L = cotangent_laplacian(pts, rings, 1e4).toarray()
    W = np.zeros_like(L)
    for i in range(len(pts)):
        r = indices[indptr[i]:indptr[i + 1]]
        for j, k in zip(r[:-1], r[1:]):
            for a, b in ((j, k), (k, j)):  # W(i,a) += cot of the angle at b
                u, v = pts[b] - pts[i], pts[b] - pts[a]
                W[i, a] += u @ v / np.linalg.norm(np.cross(u, v))
    np.testing.assert_allclose(L, W - np.diag(W.sum(axis=1)), atol=1e-9)


def test_farthest_sampling_covers_every_point_from_a_contracted_point():
    pts = shapes.torus(2000, seed=6).cloud
    samples, corresp = farthest_sampling_by_sphere(pts, 0.1)
    assert np.all(corresp >= 0)
    d = np.linalg.norm(pts - pts[samples[corresp]], axis=1)
    assert d.max() <= 0.1 + 1e-12
    # each point went to its closest sample among the balls that reached it
    from scipy.spatial import cKDTree

    nearest, _ = cKDTree(pts[samples]).query(pts)
    assert np.mean(d <= nearest + 1e-12) > 0.95


def test_edge_collapse_turns_a_triangle_into_an_edge_at_the_midpoint():
    spls = np.array([[0.0, 0, 0], [1.0, 0, 0], [0.0, 2.0, 0], [5.0, 0, 0]])
    A = np.eye(4, dtype=bool)
    for a, b in ((0, 1), (1, 2), (0, 2), (1, 3)):
        A[a, b] = A[b, a] = True
    pos, A2, merged = edge_collapse_update(spls, A)
    # costs: edge (0,2) has mean degree 2 - the lowest; it goes into vertex 2 at the midpoint
    assert np.isnan(pos[0]).all()
    np.testing.assert_allclose(pos[2], [0.0, 1.0, 0.0])
    assert merged[0] == 2
    alive = ~np.isnan(pos[:, 0])
    assert alive.sum() == 3 and A2[2, 1] and A2[1, 3] and not A2[2, 3]


def test_isolated_samples_join_their_nearest_sample():
    spls = np.array([[0.0, 0, 0], [1.0, 0, 0], [3.0, 0, 0]])
    corresp = np.array([0, 0, 1, 1, 2])
    indptr = np.array([0, 1, 2, 3, 4, 5])
    indices = np.array([1, 2, 1, 2, 4])  # point 4 (sample 2) only sees itself
    A = connect_by_inherit_neigh(spls, corresp, Rings(indptr, indices))
    assert A[0, 1] and A[2, 1] and A[1, 2] and not A[0, 2]


# ---- the API ---------------------------------------------------------------------------------

def test_cao_is_the_default_and_params_pick_the_method():
    cloud = shapes.cylinder(800, seed=7).cloud
    *_x, info = skeletonize(cloud, return_info=True)
    assert info.method == "cao" and info.initial_weight > 0
    *_x, info = skeletonize(cloud, SkeletonizeParams(), return_info=True)
    assert info.method == "skelscope"
    with pytest.raises(ValueError, match="takes CaoParams"):
        skeletonize(cloud, SkeletonizeParams(), method="cao")
    with pytest.raises(ValueError, match="unknown skeletonize method"):
        skeletonize(cloud, method="rosa")
    with pytest.raises(ValueError, match="contraction_scale"):
        CaoParams(contraction_scale=0.5)


def test_cao_is_deterministic_and_in_user_units():
    cloud = shapes.y_shape(1500, seed=8).cloud
    sk1, c1 = skeletonize(cloud)
    sk2, c2 = skeletonize(cloud * 40.0 + 7.0)
    np.testing.assert_allclose(sk2, sk1 * 40.0 + 7.0, atol=1e-6 * 40)
    np.testing.assert_array_equal(c1.edges, c2.edges)
    sk3, c3 = skeletonize(cloud)
    np.testing.assert_array_equal(sk1, sk3)
    np.testing.assert_array_equal(c1.vertices, c3.vertices)


def test_cao_iterations_follow_the_toolboxs_stopping_rule():
    _sk, _c, info = skeletonize(shapes.cylinder(1200, seed=9).cloud, return_info=True)
    a = info.ring_ratios
    assert 1 <= info.iterations <= CaoParams().max_iterations
    # every accepted iterate shrank the rings by at least 0.01; the last computed one did not
    assert all(a[t - 1] - a[t] >= 0.01 for t in range(1, info.iterations))
    if info.stop_reason == "one-ring size stopped shrinking":
        assert a[-2] - a[-1] < 0.01 and len(a) == info.iterations + 1


def test_cao_progress_and_cancel():
    seen: list[tuple[float, str]] = []
    skeletonize(shapes.cylinder(1200, seed=10).cloud, progress=lambda f, s: seen.append((f, s)))
    fractions = [f for f, _ in seen]
    assert fractions == sorted(fractions) and fractions[-1] == pytest.approx(1.0)
    assert {"laplacian", "contraction", "curve"} <= {s for _, s in seen}
    for stop_after in (1, 4, 8):
        calls = {"n": 0}

        def cancel() -> bool:
            calls["n"] += 1
            return calls["n"] > stop_after

        with pytest.raises(Cancelled):
            skeletonize(shapes.cylinder(1200, seed=10).cloud, cancel=cancel)


def test_a_cancel_mid_solve_returns_while_the_superlu_factorization_runs():
    import threading

    from scipy.spatial import cKDTree

    from skelcore.skeleton import solve

    n = 8000
    pts = np.random.default_rng(0).random((n, 3))
    _d, nn = cKDTree(pts).query(pts, k=10)
    A = sp.coo_matrix((np.ones(nn.size), (np.repeat(np.arange(n), 10), nn.ravel())), shape=(n, n)).tocsr()
    M = (A.T @ A) + sp.identity(n)  # a random 3-D graph: heavy fill-in, the factorization takes seconds
    started = threading.Event()
    stop = {"flag": False}

    def check() -> None:
        started.set()
        if stop["flag"]:
            raise Cancelled("stop")

    def later() -> None:
        started.wait()
        stop["flag"] = True

    threading.Thread(target=later, daemon=True).start()
    with pytest.raises(Cancelled):
        solve.solve_spd(M, pts, check=check, solver="superlu")
    # the cancel came back while the factorization was still running (it is left to finish alone)
    running = [t for t in solve._abandoned if t.is_alive()]
    assert running
    for t in running:
        t.join()
    small = M[:500, :500]
    x = solve.solve_spd(small, pts[:500], solver="superlu")  # and the solver still works afterwards
    np.testing.assert_allclose(small @ x, pts[:500], atol=1e-8)


# ---- the paper's numbers (its results table), default `rays` estimator -------------------------

def _scores(cloud, method="cao", skeleton=None):
    """The evaluation's summary of the cloud's skeleton (``skeleton``: the (skeletal, curve, info) of
    ``skeletonize(cloud, method=method, return_info=True)`` if already made), its curve and its info."""
    import skelcore

    skeletal, curve, info = skeleton if skeleton is not None else skeletonize(cloud, method=method, return_info=True)
    return skelcore.evaluate(cloud, skeletal, curve).summary(), curve, info


@pytest.fixture(scope="module")
def hammer(scans):
    """The hammer's cloud and its cao skeleton (skeletal, curve, info), made once for the paper's row and
    the fan starts' weight."""
    from skelcore.io import load_cloud

    cloud = load_cloud(scans / "hammer_4096.ply")
    return cloud, skeletonize(cloud, method="cao", return_info=True)


def test_hammer_reproduces_the_papers_row(hammer):
    s, curve, info = _scores(hammer[0], skeleton=hammer[1])
    assert s["topology"]["bottleneck"] == pytest.approx(0.0084, rel=0.05)
    assert s["topology"]["wasserstein"] == pytest.approx(0.0076, rel=0.05)
    assert s["centeredness"]["skeletal"] == pytest.approx(0.530, abs=0.02)
    assert s["smoothness"]["skeletal"] == pytest.approx(0.827, abs=0.02)
    assert abs(curve.n_vertices - 51) <= 5
    assert info.iterations == 3


def test_tree_reproduces_the_papers_row(scans):
    from skelcore.io import load_cloud
    from skelcore.skeleton.degrade import voxel_grid_average

    tree = voxel_grid_average(load_cloud(scans / "apple_tree_22367.ply"), 0.02)[0]
    assert len(tree) == 8936
    s, curve, info = _scores(tree)
    assert s["topology"]["bottleneck"] == pytest.approx(0.00461, rel=0.05)
    assert s["topology"]["wasserstein"] == pytest.approx(0.00483, rel=0.05)
    assert s["boundedness"]["skeletal"] == pytest.approx(0.918, abs=0.02)
    assert s["centeredness"]["skeletal"] == pytest.approx(0.288, abs=0.02)
    assert s["smoothness"]["skeletal"] == pytest.approx(0.903, abs=0.02)
    assert abs(curve.n_vertices - 148) <= 3
    assert info.iterations == 2


# ---- where a closed one-ring starts (docs/skeletonize.md, departure 2) -------------------------

def test_qhull_fan_start_is_the_first_triangle_qhull_lists_around_the_point(rng):
    """fan_start="qhull": a closed ring starts at the lower-ranked other vertex of the first
    triangle around the point in Qhull's output (neighbourhood projected in absolute coordinates,
    as the toolbox's ``neighbor * coefs``) and walks to that triangle's third vertex."""
    from scipy.spatial import cKDTree
    from skelcore.skeleton.cao_ring import _project_with_axes

    pts = shapes.y_shape(1500, seed=4).cloud
    k = knn_count(len(pts))
    indptr, indices, closed = point_rings(pts, k, chunk=500, fan_start="qhull")
    idx = _neighbours(pts, cKDTree(pts), np.arange(len(pts)), k)
    _rel, axes = _project_with_axes(pts, idx)
    checked = 0
    for i in rng.choice(np.flatnonzero(closed), 120, replace=False):
        tri = Delaunay(pts[idx[i]] @ axes[i], qhull_options="Qt Qbb Qc").simplices
        first = np.sort(tri[np.flatnonzero((tri == 0).any(axis=1))[0]])[1:]
        ring = indices[indptr[i]:indptr[i + 1]]
        assert ring[0] == ring[-1]
        assert (ring[0], ring[1]) == (idx[i, first[0]], idx[i, first[1]])
        checked += 1
    assert checked == 120
    # the same neighbour sets as the axis start: only the start and direction differ
    ip2, ind2, closed2 = point_rings(pts, k, chunk=500, fan_start="axis")
    assert np.array_equal(closed, closed2) and np.array_equal(indptr, ip2)
    for i in range(0, len(pts), 7):
        assert set(indices[indptr[i]:indptr[i + 1]]) == set(ind2[ip2[i]:ip2[i + 1]])


def test_fan_start_auto_uses_qhull_up_to_the_threshold():
    p = CaoParams()
    assert p.fan_start_for(4096) == "qhull" and p.fan_start_for(25001) == "axis"
    assert CaoParams(fan_start="axis").fan_start_for(10) == "axis"
    assert CaoParams(qhull_fan_max_points=100).fan_start_for(4096) == "axis"
    with pytest.raises(ValueError, match="fan_start"):
        CaoParams(fan_start="delaunay")
    with pytest.raises(ValueError, match="fan_start"):
        point_rings(np.random.default_rng(0).normal(size=(50, 3)), 8, fan_start="x")


def test_hammer_starts_its_fans_as_the_toolbox_and_gets_its_weight(hammer):
    """With Qhull's fan starts the initial W_L is the toolbox's (17.197 in Octave, docs/skeletonize.md);
    the axis start gave 17.55."""
    _cloud, (_s, curve, info) = hammer
    assert info.fan_start == "qhull"
    assert info.initial_weight == pytest.approx(17.197, abs=0.001)
    assert curve.n_vertices == 51


def test_bundled_cylinder_gets_a_curve_along_most_of_its_length():
    """The axis start gives 5 vertices over z 2.83-3.74 of the 0-4 cylinder; the toolbox's
    own code gives 7 vertices over about 80 % of it, and so does the Qhull start."""
    import skelcore
    from skelcore.io import load_cloud

    from pathlib import Path

    cloud = load_cloud(Path(__file__).resolve().parents[2] / "resources" / "samples" / "cylinder_cloud.ply")
    skeletal, curve = skeletonize(cloud, method="cao")
    z = curve.vertices[:, 2]
    assert z.max() - z.min() > 0.75 * 4.0
    ev = skelcore.evaluate(cloud, skeletal, curve)
    assert not [w for w in ev.warnings if w.code in ("incomplete", "spurious_branches", "outside")]
