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
