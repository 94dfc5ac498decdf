"""Chunked and reordered work gives the same answers as the plain calls, and its checkpoints stop it.

The stages of an evaluation split KD-tree builds and queries so that a cancel is seen within
~0.5 s at 1M points (docs/performance.md "Stages at 1M"); these tests check that the splitting changes
no result (chunked == unchunked, leaf order == row order, eps-first == exact) and that a checkpoint
raising in the middle of the work stops it.  No timings are asserted.
"""

from __future__ import annotations

import threading

import numpy as np
import pytest
from scipy.spatial import cKDTree

from skelcore import geometry, shapes
from skelcore.errors import Cancelled
from skelcore.geometry import TimedChunks, chunked_query, kd_tree, leaf_order, lex_order, timed_query, unique_rows
from skelcore.metrics import ball_tree, centeredness, smoothness
from skelcore.metrics.coverage import coverage as coverage_of, covered_by_balls, min_ball_excess
from skelcore.shapes import torus


def _raise_at(n: int):
    """A checkpoint that raises Cancelled at its n-th call, and counts calls."""
    calls = [0]

    def check(_fraction: float) -> None:
        calls[0] += 1
        if calls[0] >= n:
            raise Cancelled("stop")

    return check, calls


@pytest.mark.parametrize("seed", range(4))
def test_lex_order_is_numpys_lexsort(seed):
    rng = np.random.default_rng(seed)
    pts = rng.integers(-2, 3, size=(3000, 3)).astype(float)  # many equal x, many equal rows
    pts[rng.random(3000) < 0.2] *= -1.0  # and -0.0 next to 0.0
    pts[:500] = rng.normal(size=(500, 3))
    assert np.array_equal(lex_order(pts), np.lexsort(pts.T[::-1]))
    u, inv, counts = unique_rows(pts)
    assert np.array_equal(u[inv], pts + 0.0) and counts.sum() == len(pts)
    assert np.all(np.diff(np.lexsort(u.T[::-1])) == 1)  # unique rows come sorted


@pytest.mark.parametrize("seed", range(4))
def test_stable_argsort_is_numpys_stable_argsort(seed):
    """Ties (many, few, none), NaN and -0.0 == 0.0: the same permutation as kind="stable"."""
    from skelcore.geometry import stable_argsort

    rng = np.random.default_rng(seed)
    for n in (0, 1, 2, 7, 1000, 9000):
        for values in (rng.integers(0, 4, n).astype(float), rng.random(n), rng.integers(0, 50, n)):
            if n > 3 and values.dtype.kind == "f":
                values[rng.integers(0, n, 3)] = np.nan
                values[rng.integers(0, n, 2)] = -0.0
                values[rng.integers(0, n, 2)] = 0.0
            assert np.array_equal(stable_argsort(values), np.argsort(values, kind="stable"))


def test_take_rows_is_fancy_indexing():
    from skelcore.geometry import take_rows

    a = np.random.default_rng(1).random((500, 3))
    for index in (np.arange(500)[::-1], np.random.default_rng(2).integers(0, 500, (40, 7)), np.zeros(0, int)):
        assert np.array_equal(take_rows(a, index), a[index])
    with pytest.raises(IndexError):
        take_rows(a, np.array([500]))


def test_unique_rows_match_numpy_unique():
    """coverage() used np.unique(axis=0); unique_rows gives the same rows (-0.0 equal to 0.0)."""
    rng = np.random.default_rng(1)
    pts = rng.integers(-1, 2, size=(6000, 3)).astype(float)
    pts[::7] = -0.0
    assert np.array_equal(unique_rows(pts)[0], np.unique(pts, axis=0))


def test_chunked_and_timed_queries_equal_one_query():
    rng = np.random.default_rng(2)
    pts = rng.normal(size=(20000, 3))
    queries = rng.normal(size=(9000, 3))
    tree = kd_tree(pts)
    d0, i0 = tree.query(queries, k=5)
    calls = []
    d1, i1 = chunked_query(tree, queries, 5, calls.append, chunk=1000, order=rng.permutation(len(queries)))
    assert np.array_equal(d0, d1) and np.array_equal(i0, i1)
    assert len(calls) == 9 and calls[-1] == 1.0
    d2, i2 = timed_query(tree, queries, 5)
    assert np.array_equal(d0, d2) and np.array_equal(i0, i2)
    order = leaf_order(tree)
    assert np.array_equal(np.sort(order), np.arange(len(pts)))


def test_timed_chunks_cover_every_row_once():
    spans = list(TimedChunks(100_000, first=7))
    assert spans[0] == (0, 7)
    assert all(a[1] == b[0] for a, b in zip(spans, spans[1:])) and spans[-1][1] == 100_000


def test_threaded_build_polls_the_checkpoint_and_stops_on_cancel(monkeypatch):
    """The build runs in a helper thread (held here until the checkpoint has been called 3 times):
    the calling thread keeps calling the checkpoint, and a raising checkpoint ends the call."""
    pts = np.random.default_rng(3).normal(size=(5000, 3))
    release = threading.Event()

    def slow_tree(points, **kwargs):
        release.wait(10.0)
        return cKDTree(points, **kwargs)

    monkeypatch.setattr(geometry, "THREADED_BUILD", 1000)
    monkeypatch.setattr(geometry, "_POLL", 0.005)
    monkeypatch.setattr(geometry, "cKDTree", slow_tree)
    calls = [0]

    def check(_fraction: float) -> None:
        calls[0] += 1
        if calls[0] == 3:
            release.set()

    tree = kd_tree(pts, check)
    assert calls[0] >= 3
    assert np.array_equal(tree.query(pts[:50], k=3)[1], cKDTree(pts).query(pts[:50], k=3)[1])

    release.clear()
    check, calls = _raise_at(2)
    with pytest.raises(Cancelled):
        kd_tree(pts, check)
    release.set()  # let the abandoned build finish
    assert calls[0] == 2


def _torus_case(n=6000, seed=5):
    sh = torus(n, 1.0, 0.3, n_curve=32, seed=seed)
    skel = sh.skeletal + np.random.default_rng(seed).normal(scale=0.01, size=sh.skeletal.shape)
    skel[::5] = skel[::5].round(2)  # coincident points, as contraction makes
    return sh.cloud, skel


def test_skeletal_stages_do_not_depend_on_the_chunk(monkeypatch):
    cloud, skel = _torus_case()
    c_ref = centeredness.skeletal_centeredness(cloud, skel)
    s_ref = smoothness.skeletal_smoothness(skel)
    monkeypatch.setattr(centeredness, "_SKELETAL_CHUNK", 97)
    monkeypatch.setattr(smoothness, "_CHUNK", 101)
    calls = []
    assert np.array_equal(centeredness.skeletal_centeredness(cloud, skel, checkpoint=calls.append), c_ref, equal_nan=True)
    assert len(calls) > 50
    calls.clear()
    assert np.array_equal(smoothness.skeletal_smoothness(skel, checkpoint=calls.append), s_ref, equal_nan=True)
    assert len(calls) > 50
    for fn in (lambda ck: centeredness.skeletal_centeredness(cloud, skel, checkpoint=ck),
               lambda ck: smoothness.skeletal_smoothness(skel, checkpoint=ck)):
        check, calls = _raise_at(20)
        with pytest.raises(Cancelled):
            fn(check)
        assert calls[0] == 20


def test_curve_centeredness_at_once_equals_per_sample_on_threads(monkeypatch):
    """Curve samples are scored all at once in flat arrays (small clouds, in batches) or one by one in
    spans on a thread pool (large clouds): the same values bit for bit, NaNs included;
    a cancel raised in the middle stops either."""
    cloud, _ = _torus_case()
    t = np.linspace(0, 2 * np.pi, 41, endpoint=False)
    pts = np.column_stack([np.cos(t), np.sin(t), 0.02 * np.cos(3 * t)])
    dirs = np.column_stack([-np.sin(t), np.cos(t), 0 * t])
    dirs[7] = np.nan  # a joint vertex: NaN, wherever its span runs
    pts[11] = [5.0, 5.0, 5.0]  # far outside the cloud: an empty slab, NaN
    monkeypatch.setattr(centeredness, "_CURVE_AT_ONCE", 0)
    calls = []
    one = centeredness.curve_centeredness(cloud, pts, dirs, checkpoint=calls.append)
    assert np.isnan(one[7]) and np.isnan(one[11]) and np.isfinite(one).sum() == 39 and len(calls) >= 10
    check, calls = _raise_at(5)
    with pytest.raises(Cancelled):
        centeredness.curve_centeredness(cloud, pts, dirs, checkpoint=check)
    assert calls[0] == 5
    monkeypatch.setattr(centeredness, "_CURVE_AT_ONCE", 10**12)
    for batch in (10**9, 500):  # one batch, and a batch of about one sample
        monkeypatch.setattr(centeredness, "_CURVE_BATCH_PAIRS", batch)
        calls = []
        at_once = centeredness.curve_centeredness(cloud, pts, dirs, checkpoint=calls.append)
        assert np.array_equal(at_once, one, equal_nan=True)
    assert len(calls) >= 10
    check, calls = _raise_at(5)
    with pytest.raises(Cancelled):
        centeredness.curve_centeredness(cloud, pts, dirs, checkpoint=check)
    assert calls[0] == 5


def test_curve_centeredness_at_once_equals_per_sample_on_ties_and_branches(monkeypatch):
    """Rings by a stable sort: a lattice cloud (exact distance ties, rings cut inside a tie run) and a
    branching shape with random directions give the same NaNs and values either way."""
    rng = np.random.default_rng(4)
    # a square tube on an integer lattice: distances from lattice samples tie exactly
    side = [(x, y) for x in range(-4, 5) for y in range(-4, 5) if max(abs(x), abs(y)) == 4]
    lattice = np.array([(x, y, z) for z in range(20) for x, y in side], dtype=float)
    branch = shapes.y_shape(6000, seed=2).cloud
    for cloud, pts, dirs in (
        (lattice, np.column_stack([rng.integers(-2, 3, (60, 2)), rng.integers(1, 19, 60)]), np.tile([0.0, 0.0, 1.0], (60, 1))),
        (lattice, np.column_stack([rng.integers(-2, 3, (60, 2)), rng.integers(1, 19, 60)]), rng.normal(size=(60, 3)) * [0.1, 0.1, 1]),
        (branch, branch[rng.choice(len(branch), 80)] * 0.5, rng.normal(size=(80, 3))),
    ):
        monkeypatch.setattr(centeredness, "_CURVE_AT_ONCE", 0)
        one = centeredness.curve_centeredness(cloud, pts, dirs)
        monkeypatch.setattr(centeredness, "_CURVE_AT_ONCE", 10**12)
        at_once = centeredness.curve_centeredness(cloud, pts, dirs)
        assert np.array_equal(at_once, one, equal_nan=True)  # bit for bit
        assert np.isfinite(one).sum() > 10


def test_covered_by_balls_matches_brute_force():
    rng = np.random.default_rng(6)
    pts = rng.uniform(-1, 1, (3000, 3))
    centers = rng.uniform(-1, 1, (400, 3))
    radii = rng.uniform(0.01, 0.2, 400)
    brute = (np.linalg.norm(pts[:, None] - centers[None], axis=2) ** 2 - radii[None] ** 2).min(axis=1) <= 1e-12
    got = covered_by_balls(pts, centers, radii)
    assert 0.1 < got.mean() < 0.9  # both answers occur
    assert np.array_equal(got, brute)


def test_coverage_checks_often_and_stops_in_the_middle(monkeypatch):
    cloud, skel = _torus_case(4000)
    ref = coverage_of(cloud, skel)
    monkeypatch.setattr(ball_tree, "TimedChunks", lambda n, first=256, target=0.1, most=65536: TimedChunks(n, 64, 0.0, 64))
    monkeypatch.setattr(geometry, "TimedChunks", lambda n, first=256, target=0.1, most=65536: TimedChunks(n, 64, 0.0, 64))
    calls = []
    got = coverage_of(cloud, skel, checkpoint=calls.append)
    assert len(calls) > 100 and all(0.0 <= f <= 1.0 for f in calls)
    assert np.array_equal(got.gap, ref.gap) and np.array_equal(got.covered, ref.covered)
    assert (got.fraction, got.mean_gap, got.max_gap, got.tau) == (ref.fraction, ref.mean_gap, ref.max_gap, ref.tau)
    check, n_calls = _raise_at(len(calls) // 2)
    with pytest.raises(Cancelled):
        coverage_of(cloud, skel, checkpoint=check)
    assert n_calls[0] == len(calls) // 2


def test_min_ball_excess_chunked_equals_brute_force(monkeypatch):
    monkeypatch.setattr(ball_tree, "TimedChunks", lambda n, first=256, target=0.1, most=65536: TimedChunks(n, 50, 0.0, 50))
    rng = np.random.default_rng(7)
    pts = rng.uniform(-1, 1, (900, 3))
    centers = rng.uniform(-1, 1, (700, 3))
    radii = rng.uniform(0.001, 0.3, 700) ** 2 * 3
    brute = (np.linalg.norm(pts[:, None] - centers[None], axis=2) - radii[None]).min(axis=1)
    calls = []
    assert np.allclose(min_ball_excess(pts, centers, radii, checkpoint=calls.append), brute, atol=1e-12)
    assert len(calls) > 20


@pytest.mark.parametrize("n", [1, 255, 256, 257, 5000])
def test_bounding_box_equals_min_max(n):
    pts = np.random.default_rng(n).normal(size=(n, 3))
    for arr in (pts, pts[::2] if n > 1 else pts):  # also a non-contiguous view
        lo, hi = geometry.bounding_box(arr)
        assert np.array_equal(lo, arr.min(axis=0)) and np.array_equal(hi, arr.max(axis=0))


def test_centeredness_fast_path_without_coincident_points(monkeypatch):
    """Without coincident points the k nearest groups are taken as they come; the general path
    (counts and searchsorted) gives the same rows."""
    cloud, skel = _torus_case(5000, seed=8)
    skel = skel + np.random.default_rng(8).normal(scale=1e-6, size=skel.shape)  # no two equal
    fast = centeredness.skeletal_centeredness(cloud, skel)
    original = centeredness._CoincidentGroups.__init__

    def general(self, points, *args):
        original(self, points, *args)
        assert self.single
        self.single = False

    monkeypatch.setattr(centeredness._CoincidentGroups, "__init__", general)
    assert np.array_equal(centeredness.skeletal_centeredness(cloud, skel), fast, equal_nan=True)
