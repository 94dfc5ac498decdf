"""The kept spur search's box scans (diagnostics/spur_cache.py): the subsample's sorted first coordinates
give the rows of a box that a scan of every row gives, and the distances to a few added positions met
one by one are the KD-tree's."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from skelcore.diagnostics import spur_cache as sc


def _index(memo: sc.SpurMemo, q: np.ndarray) -> tuple:
    memo.subsample(q, (len(q), 0), lambda: q)
    return memo.index(q)


def test_a_box_by_the_sorted_first_coordinates_holds_the_rows_a_scan_finds():
    rng = np.random.default_rng(3)
    q = rng.normal(size=(5000, 3))
    q[:50, 0] = q[50:100, 0]  # ties in the sorted coordinate
    index = _index(sc.SpurMemo(), q)
    assert sc.SpurMemo().index(q) is None  # not the memo's subsample
    for _ in range(40):
        c, h = rng.normal(size=3), rng.uniform(0.0, 1.5, 3)
        lo, hi = c - h, c + h
        lo[0] = q[rng.integers(len(q)), 0]  # a bound on a point's coordinate: both ends inclusive
        want = sc._in_box(q, lo, hi)
        got = sc._in_box(q, lo, hi, index)
        assert np.array_equal(np.sort(got), want)
        assert np.array_equal(want, np.flatnonzero(np.all((q >= lo) & (q <= hi), axis=1)))


def test_the_nearest_of_a_few_centres_within_bounds_is_the_kd_trees():
    rng = np.random.default_rng(4)
    q = rng.normal(size=(4000, 3))
    index = _index(sc.SpurMemo(), q)
    bound = np.where(rng.random(len(q)) < 0.2, -1.0, rng.uniform(0.0, 0.8, len(q)))
    for n in (1, 7, sc._FEW, sc._FEW + 5):  # one by one up to _FEW, a KD-tree beyond
        centres = rng.normal(scale=0.5, size=(n, 3))
        d = sc._nearest_within(centres, q, bound, index)
        assert np.array_equal(d, sc._nearest_within(centres, q, bound))
        full = cKDTree(centres).query(q)[0]
        inside = (bound >= 0) & (full <= bound)
        assert np.array_equal(d[inside], full[inside])  # the same bits where it counts
        assert np.all(np.isinf(d[bound < 0]))


def test_rows_matched_by_their_hash_are_those_of_the_byte_sort(monkeypatch):
    """_match finds each new row's old row of the same bits by a hash of the bytes: the byte sort's answer
    (-0.0 is not 0.0; a row differing in one last bit is not matched), also when the hash is weak (rows of
    one first coordinate share it: the bits decide) or the old rows' hashes collide (the sort answers)."""
    rng = np.random.default_rng(5)
    old = rng.random((3000, 3))
    old[:10, 0] = 0.0
    new = np.vstack([old[rng.permutation(3000)[:2000]], rng.random((500, 3)), old[:10] * [-1.0, 1.0, 1.0],
                     np.nextafter(old[20:30], 2.0),
                     np.column_stack([old[40:50, 0], np.nextafter(old[40:50, 1], 2.0), old[40:50, 2]])])
    want = sc._match_sorted(old, new)
    assert (want >= 0).sum() == 2000 and (want[2000:] == -1).all()
    np.testing.assert_array_equal(sc._match(old, new), want)
    # a hash of the first word alone: new rows meet old rows of the same hash and other bits
    monkeypatch.setattr(sc, "row_hash", lambda p: sc.row_words(p)[:, 0] * np.uint64(3))
    weak = sc._match(old[10:], new)
    np.testing.assert_array_equal(weak, sc._match_sorted(old[10:], new))
    assert (weak[-10:] == -1).all() and (weak >= 0).sum() > 1900
    monkeypatch.setattr(sc, "row_hash", lambda p: np.zeros(len(p), np.uint64))  # every old hash shared
    np.testing.assert_array_equal(sc._match(old, new), want)


def test_the_kept_nearest_answers_are_the_ball_trees_for_the_same_rows(monkeypatch):
    """NearestByBalls keeps the answers of its last query sets: a set asked again, in part, shuffled, with
    rows of one last bit or one sign changed, gets the distances and rows a fresh tree gives, also when the
    hash is weak (rows of one first coordinate share it: their bits decide), and writing to an answer
    changes no later one."""
    from skelcore.metrics.ball_tree import BallTree

    rng = np.random.default_rng(8)
    cloud = rng.normal(size=(4000, 3))
    axis = rng.normal(size=(3000, 3)) * 0.3
    axis[:50, 0] = 0.0

    def fresh():
        return sc.NearestByBalls(cKDTree(cloud), lambda: BallTree(cloud, slab=True))

    def check(tree, q):
        d, i = tree.query(q)
        want_d, want_i = fresh().query(q)
        np.testing.assert_array_equal(d, want_d)
        np.testing.assert_array_equal(i, want_i)
        d[:] = -1.0
        i[:] = -1

    tree = fresh()
    nudged = np.column_stack([axis[:, 0], np.nextafter(axis[:, 1], 9.0), axis[:, 2]])
    for q in (axis, axis[rng.permutation(3000)[:2000]], np.vstack([axis[:100] * [-1.0, 1.0, 1.0], nudged[:500]]),
              np.vstack([axis[::2], axis[::3]])):
        check(tree, q)
    assert len(tree._kept) == 4
    monkeypatch.setattr(sc, "row_hash", lambda p: sc.row_words(p)[:, 0].copy())  # rows of one x share a hash
    weak = fresh()
    for q in (axis, nudged, axis[:50] + [0.0, 1e-3, 0.0], axis[:80]):
        check(weak, q)
