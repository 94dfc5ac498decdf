"""Topological similarity (docs/metrics.md 1): H0 barcodes, eps*, K, exact bottleneck and Wasserstein."""

from __future__ import annotations

import math

import gudhi
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import skelcore.metrics.topology as topology
from skelcore.geometry import Normalization
from skelcore.metrics.topology import (
    bottleneck_h0,
    compared_bar_count,
    eps_star,
    h0_barcode,
    topological_similarity,
    wasserstein_h0,
)
from skelcore.params import Params
from skelcore.shapes import torus


def gudhi_h0_deaths(points: np.ndarray) -> np.ndarray:
    st_ = gudhi.RipsComplex(points=points).create_simplex_tree(max_dimension=1)
    deaths = np.array([d for dim, (_, d) in st_.persistence() if dim == 0])
    return np.sort(deaths)[::-1]


def point_sets(rng: np.random.Generator):
    n = 250
    yield "gaussian", rng.normal(size=(n, 3))
    yield "duplicates", np.vstack([g := rng.normal(size=(n, 3)), g[rng.integers(0, n, 120)], g[:5]])
    yield "collinear", np.outer(rng.normal(size=n), [0.3, -1.0, 2.0]) + [1.0, 2.0, 3.0]
    yield "coplanar", rng.normal(size=(n, 2)) @ np.array([[1.0, 0.5, -0.2], [0.0, 1.0, 0.7]])
    yield "near_collinear", np.outer(rng.normal(size=n), [1.0, 1.0, 0.0]) + rng.normal(size=(n, 3)) * 1e-7
    yield "clusters", np.vstack([rng.normal(size=(150, 3)) * 0.05 + c for c in ([0, 0, 0], [3, 0, 0], [0, 9, 1])])
    yield "grid_ties", np.stack(np.meshgrid(*[np.arange(6.0)] * 3), -1).reshape(-1, 3)
    yield "contracted", np.round(rng.normal(size=(n, 3)) * [1, 0.05, 0.05], 1)


@pytest.mark.parametrize("name", [name for name, _ in point_sets(np.random.default_rng(0))])
def test_h0_barcode_equals_gudhi_rips(name):
    points = dict(point_sets(np.random.default_rng(7)))[name]
    bars = h0_barcode(points)
    want = gudhi_h0_deaths(points)
    assert bars.shape == (len(want), 2)
    assert np.all(bars[:, 0] == 0)
    assert bars[0, 1] == math.inf and want[0] == math.inf
    np.testing.assert_allclose(bars[1:, 1], want[1:], rtol=0, atol=1e-9)
    assert np.all(np.diff(bars[1:, 1]) <= 0)  # longest first


def _kernel_emst(points: np.ndarray, threads: int, stop: int = 0) -> tuple[int, np.ndarray, np.ndarray]:
    from skelcore.metrics import _emst

    pts = np.ascontiguousarray(points, dtype=float)
    lengths, nn = np.full(len(pts) - 1, np.nan), np.full(len(pts), np.nan)
    m = _emst.emst(pts, lengths, nn, np.array([stop], np.int32), np.zeros(1, np.int64), threads)
    return m, lengths, nn


def test_emst_kernel_does_not_depend_on_its_threads(rng):
    # above 16k points the searches of a round run on several threads; lattice ties give many equal
    # candidates, so threads could pick different edges: the lengths (and nearest distances) may not differ
    grid = np.stack(np.meshgrid(*[np.arange(28.0)] * 3), -1).reshape(-1, 3)  # 21952 points, all ties
    blobs = rng.normal(size=(40000, 3)) * 0.01 + rng.uniform(-1, 1, size=(16, 3))[np.arange(40000) % 16]
    for points in (grid, np.unique(blobs, axis=0)):
        m1, len1, nn1 = _kernel_emst(points, 1)
        m4, len4, nn4 = _kernel_emst(points, 4)
        assert m1 == m4 == len(points) - 1
        assert np.array_equal(np.sort(len1), np.sort(len4)) and np.array_equal(nn1, nn4)
    assert np.all(np.sort(_kernel_emst(grid, 2)[1]) == 1.0)  # a unit lattice: every EMST edge is 1


def test_emst_kernel_nearest_distances_equal_a_kd_tree_query(rng):
    from scipy.spatial import cKDTree

    points = np.unique(np.round(rng.normal(size=(30000, 3)), 2), axis=0)
    _, _, nn = _kernel_emst(points, 2)
    assert np.array_equal(nn, cKDTree(points).query(points, 2)[0][:, 1])


def test_emst_kernel_stops_on_its_flag_and_topology_leaves_no_thread_on_cancel():
    import threading

    points = np.random.default_rng(3).normal(size=(5000, 3))
    assert _kernel_emst(points, 2, stop=1)[0] == -1  # the flag is read before every block of searches
    # above _THREADED_EMST the kernel runs in a polled thread; 200k points keep it busy for far longer
    # than one 50 ms poll on any machine (40k finished within one poll on a fast minute: no poll saw it)
    many = np.random.default_rng(4).normal(size=(200_000, 3))
    seen = []

    def emst_threads() -> list:
        return [t for t in threading.enumerate() if t.name.startswith("skelscope-emst")]

    class Stop(Exception):
        pass

    def cancel(f: float) -> None:
        if emst_threads():  # a poll while the kernel runs
            seen.append(f)
            raise Stop

    with pytest.raises(Stop):
        topology._emst_lengths(many, cancel)
    assert seen and not emst_threads()


def test_h0_barcode_equals_dense_minimum_spanning_tree_on_larger_sets(rng):
    from scipy.sparse.csgraph import minimum_spanning_tree
    from scipy.spatial.distance import pdist, squareform

    cloud, skel = normalized_torus(1500)
    blobs = rng.normal(size=(1500, 3)) * 0.002 + rng.uniform(-0.8, 0.8, size=(30, 3))[np.arange(1500) % 30]
    contracted = np.round(skel + rng.normal(size=skel.shape) * 0.01, 2)  # many coincide
    for points in (cloud, blobs, contracted):
        distinct = np.unique(points, axis=0)
        want = np.sort(minimum_spanning_tree(squareform(pdist(distinct))).data)[::-1]
        np.testing.assert_allclose(h0_barcode(points)[1:, 1], want, rtol=0, atol=1e-12)


def test_emst_kernel_lengths_are_a_dense_minimum_spanning_trees_bits(rng):
    # the first round keeps each point's nearest few and later rounds take their candidates from that
    # list where it reaches outside the component: the lengths must still be the exact EMST's, bit for
    # bit (weights in the kernel's arithmetic), also with fewer points than the list and with ties
    from scipy.sparse.csgraph import minimum_spanning_tree

    def dense(points):
        d = points[:, None, :] - points[None, :, :]
        return np.sort(minimum_spanning_tree(np.sqrt(d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1]
                                                     + d[..., 2] * d[..., 2])).data)

    sets = [rng.normal(size=(n, 3)) for n in range(2, 10)]
    sets += [np.stack(np.meshgrid(*[np.arange(7.0)] * 3), -1).reshape(-1, 3) * 0.1,  # all ties
             np.unique(np.round(rng.normal(size=(2500, 3)) * 0.3, 1), axis=0),
             rng.normal(size=(2000, 3)) * 0.001 + rng.uniform(-1, 1, size=(12, 3))[np.arange(2000) % 12]]
    for points in sets:
        want = dense(points)
        for threads in (1, 2):
            m, lengths, _ = _kernel_emst(points, threads)
            assert m == len(points) - 1 and np.sort(lengths).tobytes() == want.tobytes()


def test_emst_kernel_first_round_from_another_search_gives_the_same_bits(rng):
    # topology hands the kernel centeredness' k nearest positions as its first round: the lengths and
    # nearest distances must be those of its own searches, with ties (a lattice, rounded points) and
    # threads; lists that are not sorted or name the point itself are searched instead
    from scipy.spatial import cKDTree

    sets = [np.stack(np.meshgrid(*[np.arange(28.0)] * 3), -1).reshape(-1, 3) * 0.1,  # 21952, all ties
            np.unique(np.round(rng.normal(size=(20000, 3)), 1), axis=0), rng.normal(size=(3000, 3))]
    for points in sets:
        pts = np.ascontiguousarray(points)
        own_len, own_nn = topology._emst_lengths(pts)
        near = cKDTree(pts).query(pts, 7)[1]
        assert np.array_equal(near[:, 0], np.arange(len(pts)))
        for first in (near[:, 1:], near[:, :0:-1], near[:, :6]):  # given, reversed, with the point itself
            lengths, nn = topology._emst_lengths(pts, first=first)
            assert np.sort(lengths).tobytes() == np.sort(own_len).tobytes() and nn.tobytes() == own_nn.tobytes()


def test_hammer_scan_barcode_equals_dense_minimum_spanning_tree(scans):
    from scipy.sparse.csgraph import minimum_spanning_tree
    from scipy.spatial.distance import pdist, squareform

    from skelcore.io import load_cloud

    cloud = load_cloud(scans / "hammer_4096.ply")
    part = Normalization.from_cloud(cloud).apply(cloud)[::2]  # 2048 points keep the dense MST quick
    want = np.sort(minimum_spanning_tree(squareform(pdist(np.unique(part, axis=0)))).data)[::-1]
    np.testing.assert_allclose(h0_barcode(part)[1:, 1], want, rtol=0, atol=1e-12)


def test_h0_barcode_of_degenerate_sets():
    assert h0_barcode(np.empty((0, 3))).shape == (0, 2)
    np.testing.assert_array_equal(h0_barcode(np.ones((1, 3))), [[0, np.inf]])
    np.testing.assert_array_equal(h0_barcode(np.ones((9, 3))), [[0, np.inf]])
    np.testing.assert_allclose(h0_barcode(np.array([[0.0, 0, 0], [-0.0, 0, 0], [0, 3, 4]])), [[0, np.inf], [0, 5]])
    np.testing.assert_allclose(h0_barcode(np.array([[0.0, 0, 0], [1, 0, 0], [3, 0, 0]]))[:, 1], [np.inf, 2, 1])
    with pytest.raises(ValueError):
        h0_barcode(np.array([[0.0, np.nan, 0]]))


def matlab_prctile(x: np.ndarray, q: float) -> float:
    """MATLAB prctile: sorted x_i sits at percentile 100 (i - 0.5) / n, linear in between, clamped."""
    x = np.sort(x)
    pos = (np.arange(1, len(x) + 1) - 0.5) / len(x)
    return float(np.interp(q, pos, x))


def test_eps_star_is_matlab_prctile_of_nearest_neighbour_distances(rng):
    line = np.column_stack([[0.0, 1, 3, 6], np.zeros(4), np.zeros(4)])  # NN distances 1, 1, 2, 3
    assert eps_star(line, 0.5) == pytest.approx(1.5)
    assert eps_star(line, 0.6) == pytest.approx(1.9)
    assert eps_star(line, 0.99) == pytest.approx(3.0)
    assert eps_star(line, 1.0) == pytest.approx(3.0)  # the paper's max
    cloud = rng.normal(size=(500, 3))
    nn = np.sort(np.linalg.norm(cloud[:, None] - cloud[None], axis=2), axis=1)[:, 1]
    assert eps_star(cloud, 0.99) == pytest.approx(matlab_prctile(nn, 0.99))
    assert eps_star(cloud, 1.0) == pytest.approx(nn.max())
    with pytest.raises(ValueError):
        eps_star(cloud, 0.0)


def bars_of(*deaths: float) -> np.ndarray:
    return np.column_stack([np.zeros(len(deaths)), deaths])


def test_compared_bar_count_counts_bars_longer_than_eps_star_strictly():
    bars = bars_of(np.inf, 5, 4, 3, 1.0, 0.5, 0.2)
    assert compared_bar_count(bars, 1.0, 60) == 4  # inf, 5, 4, 3; the bar equal to eps* is out
    assert compared_bar_count(bars, 0.3, 100) == 6  # 6 >= 0.05 * 100: no fallback


def test_compared_bar_count_falls_back_like_the_reference_tool():
    bars = bars_of(np.inf, 5, 4, 3)
    assert compared_bar_count(bars, 1.0, 100) == 100 - 95 + 1  # 4 < 5 bars
    # 0.95 * 30 = 28.5 rounds half away from zero (MATLAB) to 29, not to even (Python) 28
    assert compared_bar_count(bars_of(np.inf), 1.0, 30) == 30 - 29 + 1
    assert compared_bar_count(bars, 1.0, 100, params=Params(min_bar_fraction=0.01)) == 4
    assert compared_bar_count(bars, 1.0, 100, params=Params(fallback_fraction=0.9)) == 100 - 90 + 1


def random_diagram(rng: np.random.Generator, n: int, n_inf: int = 1) -> np.ndarray:
    deaths = np.round(rng.exponential(size=n), int(rng.integers(1, 4)))  # rounding makes ties
    return bars_of(*([np.inf] * n_inf), *deaths)


def test_bottleneck_equals_gudhi_exact_bottleneck(rng):
    for _ in range(150):
        a = random_diagram(rng, int(rng.integers(0, 25)))
        b = random_diagram(rng, int(rng.integers(0, 25)))
        if rng.random() < 0.3:
            b = np.vstack([b, a[1:] + [0, 0.01]])
        assert bottleneck_h0(a, b) == pytest.approx(gudhi.bottleneck_distance(a, b, e=0), rel=1e-12, abs=1e-15)


def test_wasserstein_equals_gudhi_optimal_transport(rng):
    gw = pytest.importorskip("gudhi.wasserstein", exc_type=ImportError)
    pytest.importorskip("ot")
    for _ in range(150):
        a = random_diagram(rng, int(rng.integers(0, 25)))
        b = random_diagram(rng, int(rng.integers(0, 25)))
        if rng.random() < 0.3:
            b = np.vstack([b, a[1:] + [0, 0.01]])
        want = gw.wasserstein_distance(a, b, order=1, internal_p=np.inf)
        assert wasserstein_h0(a, b) == pytest.approx(want, rel=1e-9, abs=1e-12)


def dp_reference(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """O(n m) dynamic programme over sorted deaths (matched pairs in sorted order): (W1, bottleneck)."""
    a, b = np.sort(a), np.sort(b)
    w = np.full((len(a) + 1, len(b) + 1), np.inf)
    bn = np.full_like(w, np.inf)
    w[0, 0] = bn[0, 0] = 0.0
    for i in range(len(a) + 1):
        for j in range(len(b) + 1):
            if i:
                w[i, j] = min(w[i, j], w[i - 1, j] + a[i - 1] / 2)
                bn[i, j] = min(bn[i, j], max(bn[i - 1, j], a[i - 1] / 2))
            if j:
                w[i, j] = min(w[i, j], w[i, j - 1] + b[j - 1] / 2)
                bn[i, j] = min(bn[i, j], max(bn[i, j - 1], b[j - 1] / 2))
            if i and j:
                c = abs(a[i - 1] - b[j - 1])
                w[i, j] = min(w[i, j], w[i - 1, j - 1] + c)
                bn[i, j] = min(bn[i, j], max(bn[i - 1, j - 1], c))
    return float(w[-1, -1]), float(bn[-1, -1])


def test_distances_match_a_quadratic_dynamic_programme_on_random_small_diagrams(rng):
    # runs without POT too; ties from rounding exercise equal deaths on both sides
    for _ in range(150):
        a = np.round(rng.exponential(size=int(rng.integers(0, 15))), int(rng.integers(1, 3)))
        b = np.round(rng.exponential(size=int(rng.integers(0, 15))), int(rng.integers(1, 3)))
        w, bn = dp_reference(a, b)
        assert wasserstein_h0(a, b) == pytest.approx(w, rel=1e-10, abs=1e-12)
        assert bottleneck_h0(a, b) == pytest.approx(bn, rel=1e-12, abs=1e-15)


def test_distances_match_a_quadratic_dynamic_programme_on_larger_diagrams(rng):
    a = rng.exponential(size=150)
    b = np.concatenate([a[:100] * rng.uniform(0.8, 1.2, 100), rng.exponential(size=70) * 0.3])
    w, bn = dp_reference(a, b)
    assert wasserstein_h0(a, b) == pytest.approx(w, rel=1e-10)
    assert bottleneck_h0(a, b) == pytest.approx(bn, rel=1e-12)


def test_distance_edge_cases():
    empty = np.empty((0, 2))
    inf_only = bars_of(np.inf)
    assert bottleneck_h0(empty, empty) == 0.0 and wasserstein_h0(empty, empty) == 0.0
    assert bottleneck_h0(inf_only, inf_only) == 0.0 and wasserstein_h0(inf_only, inf_only) == 0.0
    assert bottleneck_h0(bars_of(np.inf, 4.0), inf_only) == 2.0  # to the diagonal: d / 2
    assert wasserstein_h0(bars_of(np.inf, 4.0, 1.0), inf_only) == 2.5
    assert bottleneck_h0(bars_of(np.inf, 4.0), bars_of(np.inf, 3.0)) == 1.0
    assert wasserstein_h0(bars_of(4.0, 1.0), bars_of(3.0)) == 1.5
    assert bottleneck_h0(inf_only, empty) == math.inf  # unmatched infinite bar, as gudhi
    assert wasserstein_h0(inf_only, empty) == math.inf
    assert wasserstein_h0(np.array([4.0, 1.0]), np.array([3.0])) == 1.5  # 1-D deaths accepted
    with pytest.raises(ValueError):
        bottleneck_h0(np.array([[1.0, 2.0]]), empty)  # H0 bars are born at 0


def normalized_torus(n: int = 1500, seed: int = 2):
    shape = torus(n, seed=seed)
    norm = Normalization.from_cloud(shape.cloud)
    return norm.apply(shape.cloud), norm.apply(shape.skeletal)


def test_identical_inputs_have_zero_distance():
    cloud, _ = normalized_torus()
    result = topological_similarity(cloud, cloud)
    assert result.bottleneck == 0.0 and result.wasserstein == 0.0
    np.testing.assert_array_equal(result.cloud_barcode, result.skeletal_barcode)


def test_eps_star_of_the_metric_counts_duplicate_cloud_points_as_distance_zero(rng):
    cloud = rng.normal(size=(300, 3))
    cloud = np.vstack([cloud, cloud[:40]])  # 80 points with a twin: nearest-neighbour distance 0
    r = topological_similarity(cloud, cloud * 0.5)
    assert r.eps_star == pytest.approx(eps_star(cloud, 0.99), rel=1e-15)
    assert topological_similarity(cloud, cloud, params=Params(eps_quantile=0.2)).eps_star == 0.0


def test_topological_similarity_compares_the_k_longest_bars():
    cloud, skel = normalized_torus()
    skel = skel + np.random.default_rng(0).normal(size=skel.shape) * 0.01
    r = topological_similarity(cloud, skel)
    eps = eps_star(cloud, 0.99)
    assert r.eps_star == eps
    assert r.n_bars == compared_bar_count(r.cloud_barcode, eps, len(cloud))
    k = r.n_bars
    a, b = r.cloud_barcode[:k], r.skeletal_barcode[:k]
    assert r.bottleneck == pytest.approx(gudhi.bottleneck_distance(a, b, e=0), rel=1e-12)
    assert r.wasserstein == pytest.approx(wasserstein_h0(a, b) / k)
    assert r.cloud_barcode.shape == (len(cloud), 2)  # every bar, not only the K compared
    assert r.skeletal_barcode.shape == (len(skel), 2)
    assert r.bottleneck > 0 and r.wasserstein > 0


def test_skeletal_diagram_with_fewer_than_k_bars_is_compared_whole():
    cloud, _ = normalized_torus(400)
    skel = np.repeat(np.array([[0.0, 0, 0], [0.5, 0, 0], [0.5, 0.4, 0]]), [200, 100, 100], axis=0)
    r = topological_similarity(cloud, skel)
    assert len(r.skeletal_barcode) == 3 < r.n_bars
    a = r.cloud_barcode[: r.n_bars]
    assert r.bottleneck == pytest.approx(gudhi.bottleneck_distance(a, r.skeletal_barcode, e=0), rel=1e-12)
    w, _ = dp_reference(a[1:, 1], r.skeletal_barcode[1:, 1])
    assert r.wasserstein == pytest.approx(w / r.n_bars)


@settings(max_examples=20, deadline=None)
@given(
    shift=st.tuples(*[st.floats(-1e3, 1e3)] * 3),
    scale=st.floats(1e-3, 1e3),
    seed=st.integers(0, 2**16),
)
def test_distances_are_invariant_to_translation_and_scaling_after_normalization(shift, scale, seed):
    rng = np.random.default_rng(seed)
    cloud = rng.normal(size=(120, 3)) * [1.0, 0.3, 0.2]
    skel = cloud * [1.0, 0.1, 0.1] + rng.normal(size=cloud.shape) * 0.01

    def run(c: np.ndarray, s: np.ndarray):
        norm = Normalization.from_cloud(c)
        return topological_similarity(norm.apply(c), norm.apply(s))

    ref = run(cloud, skel)
    moved = run(cloud * scale + shift, skel * scale + shift)
    assert moved.n_bars == ref.n_bars
    assert moved.bottleneck == pytest.approx(ref.bottleneck, rel=1e-6, abs=1e-9)
    assert moved.wasserstein == pytest.approx(ref.wasserstein, rel=1e-6, abs=1e-9)


def test_topological_similarity_reports_progress_and_honours_cancel():
    cloud, skel = normalized_torus(600)
    seen: list[float] = []
    topological_similarity(cloud, skel, checkpoint=seen.append)
    assert seen[-1] == 1.0 and all(0 <= f <= 1 for f in seen)
    assert all(b >= a for a, b in zip(seen, seen[1:]))

    class Stop(Exception):
        pass

    def cancel(_f: float) -> None:
        raise Stop

    with pytest.raises(Stop):
        topological_similarity(cloud, skel, checkpoint=cancel)


def test_topology_gives_the_cloud_index_the_spacings_it_would_search(rng):
    # the cloud's EMST's first round is each row's nearest other distance: the shared index takes it
    # instead of its own search, so every value must be its search's bits (copies at 0, rounded ties)
    from skelcore.metrics.cloud_index import CloudIndex

    cloud = np.round(rng.normal(size=(20000, 3)), 2)
    cloud = np.vstack([cloud, cloud[:50]])
    given = CloudIndex(cloud)
    topological_similarity(cloud, cloud[::3] * 0.5, cloud_spacings=given.offer_spacings)
    searched = CloudIndex(cloud).spacings()
    assert given._spacings is not None and given.spacings() is given._spacings
    assert given.spacings().tobytes() == searched.tobytes()
    kept = given.spacings()
    given.offer_spacings(np.zeros(len(cloud)))  # known already: not replaced
    assert given.spacings() is kept


def test_bottleneck_bisection_from_the_least_feasible_candidate_ends_where_the_hall_test_ends_it(rng, monkeypatch):
    # the shortcut answers the bisection by comparing with the least feasible float: the same end, the same bits
    from skelcore.metrics import topology

    fast = 0
    for trial in range(300):
        n, m = (int(v) for v in rng.integers(0, 60, 2))
        kind = trial % 3
        draw = [lambda k: rng.random(k), lambda k: np.round(rng.random(k), 2), lambda k: rng.exponential(size=k)][kind]
        xa, xb = np.sort(draw(n)), np.sort(draw(m))
        if kind == 1 and n and m:  # shared deaths: ties between the diagrams
            xb[: min(n, m) // 2] = xa[: min(n, m) // 2]
            xb = np.sort(xb)
        if not (len(xa) or len(xb)) or topology._bottleneck_feasible(xa, xb, 0.0):
            continue
        hi = max(xa[-1] if len(xa) else 0.0, xb[-1] if len(xb) else 0.0) / 2.0
        plain = topology._bisection_end(hi, lambda t: topology._bottleneck_feasible(xa, xb, t))
        least = topology._least_feasible(xa, xb, hi)
        if least is not None:
            fast += 1
            assert topology._bottleneck_feasible(xa, xb, least)
            assert topology._bisection_end(hi, lambda t: t >= least) == plain
        a, b = np.column_stack([np.zeros(n), xa]), np.column_stack([np.zeros(m), xb])
        with monkeypatch.context() as mp:
            mp.setattr(topology, "_least_feasible", lambda *args: None)
            alone = bottleneck_h0(a, b)
        assert np.float64(bottleneck_h0(a, b)).tobytes() == np.float64(alone).tobytes()
    assert fast > 150
