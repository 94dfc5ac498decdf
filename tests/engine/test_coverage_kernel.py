"""The compiled coverage kernel (``_balls.c``, docs/metrics.md 5.2) gives the brute-force answers exactly.

Brute force here is a plain numpy loop over every (point, element) pair with the same arithmetic
(sqrt of dx^2 + dy^2 + dz^2): the gaps must be equal to float64 rounding, covered and the radii
identical, on random balls, on shapes where the kernel's tighter bounds work (a jittered torus: discs
over the cloud, back spheres over the balls), and on grids full of exact ties and copies.  Also: the
answer does not depend on the chunking or the number of threads, tau is cKDTree's, and a checkpoint
that raises stops a search and a tree build.  No timings are asserted.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from skelcore import Params, shapes
from skelcore.errors import Cancelled
from skelcore.geometry import TimedChunks, nearest_neighbor_distances
from skelcore.metrics import _balls, ball_tree as cov
from skelcore.metrics.coverage import BallTree, coverage, coverage_tau, covered_by_balls, min_ball_excess


def _dist(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    d = a[:, None, :] - b[None, :, :]
    return np.sqrt(d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1] + d[..., 2] * d[..., 2])


def _brute_coverage(cloud: np.ndarray, elements: np.ndarray, params: Params, tau: float):
    """Coverage (docs/metrics.md 5.2) by brute force: r(x), gap, covered (|p - x|^2 - R^2 <= 1e-12 R_max^2, R = (1 + s) r + tau)."""
    x = np.unique(elements, axis=0)
    d = _dist(cloud, x)
    r = d.min(axis=0)
    gap = np.maximum((d - r[None]).min(axis=1), 0.0)
    big = (1.0 + params.coverage_slack) * r + tau
    covered = (d * d - big[None] ** 2 <= 1e-12 * big.max() ** 2).any(axis=1)
    return r, gap, covered


def _torus(n: int, seed: int = 0):
    sh = shapes.torus(n, R=1.0, r=0.3, n_curve=32, seed=seed)
    skel = sh.skeletal + np.random.default_rng(seed).normal(scale=0.01, size=sh.skeletal.shape)
    return sh.cloud, skel, sh


def _grid_case():
    """A grid cloud with copies, elements on grid points and cell centres with copies: exact ties."""
    g = np.stack(np.meshgrid(*[np.arange(6.0)] * 3, indexing="ij"), -1).reshape(-1, 3)
    shell = g[(g == 0).any(axis=1) | (g == 5).any(axis=1)]
    cloud = np.vstack([shell, shell[::7]])  # copies
    inner = g[((g > 0) & (g < 5)).all(axis=1)]
    elements = np.vstack([inner, inner[:20] + 0.5, inner[:5], [[0.0, 0.0, 0.0]]])  # copies, one on the cloud
    return cloud, elements


@pytest.mark.parametrize("case", ["random", "torus", "grid", "half torus"])
def test_coverage_equals_brute_force(case):
    rng = np.random.default_rng(3)
    if case == "random":
        cloud, elements = rng.uniform(-1, 1, (1500, 3)), rng.uniform(-0.8, 0.8, (700, 3))
    elif case == "grid":
        cloud, elements = _grid_case()
    else:
        cloud, elements, _ = _torus(2500)
        if case == "half torus":
            elements = elements[elements[:, 0] > 0.2]
    params = Params()
    tau = coverage_tau(cloud, params)
    got = coverage(cloud, elements, params, tau)
    r, gap, covered = _brute_coverage(cloud, elements, params, tau)
    np.testing.assert_allclose(got.gap, gap, rtol=0, atol=1e-14)
    assert np.array_equal(got.covered, covered)
    assert got.n_elements == len(np.unique(elements, axis=0))
    assert got.max_gap == pytest.approx(gap.max(), abs=1e-14) and got.fraction == covered.mean()
    if case == "half torus":
        assert 0.3 < got.fraction < 0.9 and got.max_gap > 0.1  # both answers occur
    tree = BallTree(cloud, slab=True)
    x = np.unique(elements, axis=0)
    assert np.array_equal(tree.nearest(x), r)  # the radii: identical, also on ties


def test_min_ball_excess_and_covered_by_balls_equal_brute_force():
    rng = np.random.default_rng(4)
    pts = rng.uniform(-1, 1, (2000, 3))
    centers = rng.uniform(-1, 1, (600, 3))
    centers[:50] = centers[50:100]  # copies
    radii = rng.uniform(0.001, 0.3, 600) ** 2 * 3
    d = _dist(pts, centers)
    brute = (d - radii[None]).min(axis=1)
    np.testing.assert_allclose(min_ball_excess(pts, centers, radii), brute, rtol=0, atol=1e-14)
    floored = min_ball_excess(pts, centers, radii, floor=0.02)
    above = brute > 0.02
    np.testing.assert_allclose(floored[above], brute[above], rtol=0, atol=1e-14)
    assert np.all(floored[~above] <= 0.02)
    inside = (d * d - radii[None] ** 2 <= 1e-12 * radii.max() ** 2).any(axis=1)
    got = covered_by_balls(pts, centers, radii)
    assert 0.1 < got.mean() < 0.9 and np.array_equal(got, inside)
    # a point exactly on a sphere is inside (the rounding allowance), as before
    on = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 2.0]])
    assert covered_by_balls(on, np.zeros((1, 3)), np.array([1.0])).tolist() == [True, False]


def test_edge_cases():
    cloud = np.array([[1.0, 0, 0], [0, 3.0, 0], [0, -1, 0]])
    none = coverage(cloud, np.zeros((0, 3)), tau=0.1)
    assert np.all(np.isinf(none.gap)) and not none.covered.any() and none.n_elements == 0
    one = coverage(cloud[:1], np.array([[0.0, 0, 0], [0.0, 0, 0]]), tau=0.0)
    assert one.gap.tolist() == [0.0] and one.covered.tolist() == [True] and one.n_elements == 1
    # an element on a cloud point: radius 0, that point's gap 0 and covered only through tau
    on = coverage(cloud, cloud[:1], Params(coverage_slack=0.0), tau=0.0)
    assert on.gap.tolist() == [0.0, pytest.approx(np.sqrt(10.0)), pytest.approx(np.sqrt(2.0))]
    assert on.covered.tolist() == [True, False, False]
    assert min_ball_excess(np.zeros((0, 3)), cloud, np.ones(3)).shape == (0,)
    assert np.all(np.isinf(min_ball_excess(cloud, np.zeros((0, 3)), np.zeros(0))))


@pytest.mark.parametrize("pts", [
    shapes.torus(3000, seed=1).cloud,
    np.repeat(np.random.default_rng(2).normal(size=(400, 3)), 3, axis=0),  # every point has copies
    np.random.default_rng(3).integers(0, 6, (3000, 3)).astype(float),  # ties everywhere
])
def test_tau_and_nearest_other_equal_ckdtree(pts):
    tree = BallTree(pts)
    mine = np.empty(len(pts))
    mine[tree.perm] = tree.nearest(tree.points, others=True)
    ref = cKDTree(pts).query(pts, k=2)[0][:, 1]
    assert np.array_equal(mine, ref) and np.array_equal(mine, nearest_neighbor_distances(pts))
    assert coverage_tau(pts) == 2.0 * np.median(ref)


def test_answers_do_not_depend_on_chunks_or_threads(monkeypatch):
    cloud, skel, _ = _torus(6000, seed=5)
    ref = coverage(cloud, skel, workers=1)
    monkeypatch.setattr(cov, "TimedChunks", lambda n, first=256, target=0.1, most=65536: TimedChunks(n, 37, 0.0, 600))
    monkeypatch.setattr(cov, "THREAD_ROWS", 16)
    calls: list[float] = []
    got = coverage(cloud, skel, workers=2, checkpoint=calls.append)
    assert np.array_equal(got.gap, ref.gap) and np.array_equal(got.covered, ref.covered)
    assert len(calls) > 100 and all(0.0 <= f <= 1.0 for f in calls)


def test_a_raising_checkpoint_stops_the_search():
    cloud, skel, _ = _torus(4000, seed=6)
    seen = [0]

    def check(_f: float) -> None:
        seen[0] += 1
        if seen[0] == 4:
            raise Cancelled("stop")

    with pytest.raises(Cancelled):
        coverage(cloud, skel, checkpoint=check)
    assert seen[0] == 4


def test_a_large_tree_build_polls_and_stops():
    """Above 65536 points the build runs in a helper thread while the caller polls the checkpoint; a
    cancel sets the kernel's stop flag and is re-raised once the build has returned."""
    pts = np.random.default_rng(7).normal(size=(300_000, 3))
    polls = [0]

    def check(_f: float) -> None:
        polls[0] += 1
        raise Cancelled("stop")

    with pytest.raises(Cancelled):
        BallTree(pts, slab=True, checkpoint=check)
    assert polls[0] == 1
    whole = BallTree(pts, checkpoint=lambda f: None)
    assert np.array_equal(np.sort(whole.perm), np.arange(len(pts)))
    assert np.array_equal(whole.points, pts[whole.perm])
    # the kernel itself gives up when the flag is already set
    nodes = np.empty(2 * len(pts) // 4 + 2, cov.NODE)
    out = _balls.build_tree(pts, np.empty(len(pts), np.int32), np.empty_like(pts), nodes, True, np.ones(1, np.int32))
    assert out == -1


def test_the_tree_does_not_depend_on_build_threads():
    """Big subtrees are built on threads of their own, numbered as the sequential build numbers them."""
    pts = np.random.default_rng(8).normal(size=(200_000, 3))
    built = []
    for threads in (1, 2, 4):
        perm, srt = np.empty(len(pts), np.int32), np.empty_like(pts)
        nodes = np.empty(2 * ((len(pts) + 3) // 4) + 2, cov.NODE)
        m = _balls.build_tree(pts, perm, srt, nodes, True, np.zeros(1, np.int32), cov.LEAF, threads)
        built.append((perm, srt, nodes[:m].tobytes()))
    for perm, srt, raw in built[1:]:
        assert np.array_equal(perm, built[0][0]) and np.array_equal(srt, built[0][1]) and raw == built[0][2]


@pytest.mark.parametrize("case", ["random", "torus", "grid"])
def test_the_blocks_walk_gives_the_walk_per_querys_bits(case):
    """BallTree.balls(blocks=True) (one walk per 16 queries in tree order, _balls.balls_block): the same
    gap bits (exact; clamped at the floor where one is given) and verdicts as the walk per query, gap or
    cover alone, queries near and far from the balls, in tree order and not, a row with a NaN among them."""
    rng = np.random.default_rng(7)
    if case == "random":
        cloud, centers = rng.uniform(-1, 1, (6000, 3)), rng.uniform(-0.5, 0.5, (700, 3))
        centers[:40] = centers[40:80]  # copies
        r = rng.uniform(0.001, 0.2, 700)
    elif case == "torus":
        cloud, centers, _ = _torus(6000)
        r = cKDTree(cloud).query(centers)[0]
    else:
        cloud, centers = _grid_case()
        r = np.full(len(centers), 0.5)
    surface = BallTree(cloud)
    tree = BallTree(centers)
    r = np.asarray(r, float)[tree.perm]
    tree.set_radii(r, 1.1 * r + 0.01)
    far = surface.points + 2.0 * np.ptp(surface.points, axis=0)  # beside the cloud, outside every ball
    nan = surface.points.copy()
    nan[100] = np.nan
    for queries in (surface.points, far, nan, surface.points[rng.permutation(len(cloud))]):
        for floor in (-np.inf, 0.0, 0.05):
            for gap, cover in ((True, True), (True, False), (False, True)):
                g0, c0 = tree.balls(queries, gap=gap, cover=cover, floor=floor)
                g1, c1 = tree.balls(queries, gap=gap, cover=cover, floor=floor, blocks=True)
                if gap:
                    assert np.maximum(g1, floor).tobytes() == np.maximum(g0, floor).tobytes()
                if cover:
                    assert np.array_equal(c0, c1)
        assert not tree.balls(far)[1].any()  # the far rows: no ball covers them
    assert tree.balls(np.zeros((0, 3)), blocks=True)[0].shape == (0,)
