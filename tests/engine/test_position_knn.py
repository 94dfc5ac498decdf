"""Work shared between stages (docs/performance.md 6.4, 6.6) gives the bits each stage gives alone:
skeletal centeredness and smoothness over one index of the distinct positions, and coverage's noise
shortfall's nearest elements."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from skelcore.metrics import centeredness, coverage, position_knn, smoothness
from skelcore.geometry import kd_tree
from skelcore.metrics.centeredness import skeletal_centeredness
from skelcore.metrics.smoothness import skeletal_smoothness
from skelcore.params import Params


def _lattice_set() -> np.ndarray:
    """70k distinct positions (more than position_knn.SHARED_FROM): half a unit lattice, whose
    neighbours tie everywhere, half of it jittered (no ties), and coincident copies of some rows."""
    g = np.stack(np.meshgrid(np.arange(46), np.arange(46), np.arange(33), indexing="ij"), -1).reshape(-1, 3) * 0.1
    g = g.astype(float)
    half = len(g) // 2
    g[half:] += np.random.default_rng(0).normal(scale=0.02, size=(len(g) - half, 3))
    return np.concatenate([g, g[:1500], g[-1500:]])


def test_shared_positions_give_each_stage_its_own_bits(monkeypatch):
    skel = _lattice_set()
    assert len(np.unique(skel, axis=0)) >= position_knn.SHARED_FROM
    cloud = skel + np.random.default_rng(1).normal(scale=0.05, size=skel.shape)
    params = Params(k_center=position_knn.HEAD + 2)  # enough columns to publish, a quicker query
    reused = []
    reuse = position_knn.PositionNeighbours.reuse

    def counting(self, rows, k):
        ready, found = reuse(self, rows, k)
        reused.append(int(ready.sum()))
        return ready, found

    monkeypatch.setattr(position_knn.PositionNeighbours, "reuse", counting)
    s_points = skel.copy()  # one array for both stages, as an evaluation hands them
    c = skeletal_centeredness(cloud, s_points, params=params)
    s = skeletal_smoothness(s_points, params=params)
    # the jittered half is taken from centeredness' answers, the tied lattice asked again
    assert 0.3 * len(s_points) < sum(reused) < 0.8 * len(s_points)
    with monkeypatch.context() as m:
        m.setattr(centeredness, "position_neighbours", lambda positions: None)
        m.setattr(smoothness, "position_neighbours", lambda positions: None)
        alone_c = skeletal_centeredness(cloud, skel.copy(), params=params)
        alone_s = skeletal_smoothness(skel.copy(), params=params)
    assert c.tobytes() == alone_c.tobytes()
    assert s.tobytes() == alone_s.tobytes()


def test_noise_shortfall_nearest_element_is_the_balanced_trees_answer():
    rng = np.random.default_rng(2)
    lattice = np.stack(np.meshgrid(*[np.arange(12.0)] * 3, indexing="ij"), -1).reshape(-1, 3)
    for elements, pts in ((lattice[::3], lattice + 0.5), (rng.normal(size=(5000, 3)), rng.normal(size=(3000, 3))),
                          (lattice[:1], lattice)):
        dist, owner = coverage._nearest_element(elements, pts)
        ref_d, ref_i = cKDTree(elements).query(pts)
        assert dist.tobytes() == ref_d.tobytes()
        assert np.array_equal(owner, ref_i)


def test_noise_cells_are_labelled_as_np_unique_labels_them():
    rng = np.random.default_rng(3)
    for cells in (rng.integers(0, 40, (20000, 3)), rng.integers(0, 2, (50, 3)), np.zeros((1, 3), np.int64),
                  np.array([[0, 0, 2**40], [2**40, 0, 0], [0, 2**40, 0]])):
        want = np.unique(cells, axis=0, return_inverse=True)[1].reshape(-1)
        assert np.array_equal(coverage._row_labels(cells), want)


def test_published_others_are_the_heads_without_the_position_itself():
    # topology's EMST takes them as its first round: only when every row is published, only for the
    # very array the index was made for, never making an index
    pts = np.random.default_rng(2).normal(size=(position_knn.SHARED_FROM, 3))
    pts.flags.writeable = False
    assert position_knn.published_others(pts, 6) is None  # no index for it yet
    index = position_knn.position_neighbours(pts)
    dist, near = cKDTree(pts).query(pts, 12)
    index.publish(np.arange(len(pts) - 1), dist[:-1], near[:-1])
    assert position_knn.published_others(pts, 6) is None  # the last row is not published
    index.publish(np.arange(len(pts) - 1, len(pts)), dist[-1:], near[-1:])
    assert np.array_equal(position_knn.published_others(pts, 6), near[:, 1:7])
    assert position_knn.published_others(pts.copy(), 6) is None
    index.close()
    assert position_knn.published_others(pts, 6) is None


def test_exact_knn_gives_the_kd_trees_answers_bit_for_bit():
    # the compiled kNN answers where the k + 1 squared distances rise strictly; rows with equal ones (a
    # lattice ties everywhere, rounded points often) take the kd-tree's own answer: the same bits either way
    rng = np.random.default_rng(4)
    lattice = np.stack(np.meshgrid(*[np.arange(16.0)] * 3, indexing="ij"), -1).reshape(-1, 3) * 0.1
    half = len(lattice) // 2
    lattice[half:] += rng.normal(scale=0.02, size=(len(lattice) - half, 3))
    for pts, tied in ((lattice, True), (np.round(rng.normal(size=(3000, 3)), 2), True),
                      (rng.normal(size=(3000, 3)) * 1e-3 + 5.0, False), (rng.normal(size=(12, 3)), False)):
        pts = np.unique(pts, axis=0)
        exact = position_knn.ExactKnn.build(pts)
        tree = kd_tree(pts)
        ask = pts[rng.permutation(len(pts))[:1500]]
        for k in sorted({2, 9, 30, min(len(pts), 64), len(pts)}):
            if k > len(pts) or k > 255:
                continue
            d, i = exact.query(ask, k=k, workers=1)
            want_d, want_i = tree.query(ask, k=k, workers=1)
            assert d.tobytes() == want_d.tobytes() and np.array_equal(i, want_i), (len(pts), k)
        assert (exact._scipy is not None) == tied  # the kd-tree is built only for rows that tie
        assert sorted(exact.indices.tolist()) == list(range(len(pts)))
    assert position_knn.ExactKnn.build(np.array([[0.0, 0.0, np.nan]])) is None


def test_a_small_set_shares_the_index_with_each_stages_bits(monkeypatch):
    # from SHARED_FROM (below the hammer's 4,096 positions) an evaluation's skeletal stages share it
    g = np.stack(np.meshgrid(np.arange(16), np.arange(16), np.arange(12), indexing="ij"), -1).reshape(-1, 3) * 0.1
    g[len(g) // 2:] += np.random.default_rng(4).normal(scale=0.02, size=(len(g) - len(g) // 2, 3))
    skel = np.concatenate([g, g[:200], g[-200:]])
    assert position_knn.SHARED_FROM <= len(g) < 65536
    cloud = skel + np.random.default_rng(5).normal(scale=0.05, size=skel.shape)
    reused = []
    reuse = position_knn.PositionNeighbours.reuse
    monkeypatch.setattr(position_knn.PositionNeighbours, "reuse",
                        lambda self, rows, k: reused.append(int(reuse(self, rows, k)[0].sum())) or reuse(self, rows, k))
    s_points = skel.copy()
    c = skeletal_centeredness(cloud, s_points, params=Params())
    s = skeletal_smoothness(s_points, params=Params())
    assert sum(reused) > 0.3 * len(g)
    with monkeypatch.context() as m:
        m.setattr(centeredness, "position_neighbours", lambda positions: None)
        m.setattr(smoothness, "position_neighbours", lambda positions: None)
        alone_c = skeletal_centeredness(cloud, skel.copy(), params=Params())
        alone_s = skeletal_smoothness(skel.copy(), params=Params())
    assert c.tobytes() == alone_c.tobytes()
    assert s.tobytes() == alone_s.tobytes()
