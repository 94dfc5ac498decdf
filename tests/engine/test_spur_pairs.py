"""The spur test's ball search of few pairs (diagnostics.spur_pairs) gives the level search's answers
bit for bit, and leaves the large or degenerate searches to it."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from skelcore.diagnostics import spur_pairs, spurs
from skelcore.geometry import kd_tree


def _levels(monkeypatch, pts, pb, reach, q, own):
    with monkeypatch.context() as m:
        m.setattr(spur_pairs, "CELLS_MAX", -1)  # the ball search declines: the levels answer
        return spurs._explained_elsewhere(pts, pb, reach, q, own)


def test_ball_search_matches_the_level_search(monkeypatch):
    """Random curves and queries, some queries on curve points, some balls NaN or infinite."""
    rng = np.random.default_rng(7)
    answered = 0
    for t in range(30):
        p, n = int(rng.integers(1, 150)), int(rng.integers(1, 800))
        pts = rng.normal(size=(p, 3))
        q = rng.normal(size=(n, 3)) * rng.uniform(0.5, 2.0)
        if t % 3 == 0:
            m = min(p // 2, n)
            q[:m] = pts[:m]
        reach = rng.uniform(0.0, 0.6, p) * rng.choice([0.1, 1.0, 3.0], p) + 1e-3
        reach[rng.random(p) < 0.05] = np.nan
        reach[rng.random(p) < 0.02] = np.inf
        pb, own = rng.integers(-1, 5, p), rng.integers(-1, 5, n)
        got = spur_pairs.explained_by_balls(pts, pb, reach, q, own)
        if got is None:
            continue
        answered += 1
        np.testing.assert_array_equal(got, _levels(monkeypatch, pts, pb, reach, q, own))
        # the caller's tree of the queries (another build: the same pairs), and one of other points (not used)
        for tree in (kd_tree(q), kd_tree(q[::-1]), cKDTree(q + 1.0)):
            np.testing.assert_array_equal(spur_pairs.explained_by_balls(pts, pb, reach, q, own, tree), got)
        with monkeypatch.context() as m:  # the pairs counted before they are listed
            m.setattr(spur_pairs, "CELLS_LISTED", 0)
            np.testing.assert_array_equal(spur_pairs.explained_by_balls(pts, pb, reach, q, own), got)
    assert answered > 20


def test_ball_search_declines_large_and_degenerate_searches(monkeypatch):
    rng = np.random.default_rng(8)
    pts, q = rng.uniform(0, 1, (50, 3)), rng.uniform(0, 1, (400, 3))
    pb, own = rng.integers(0, 3, 50), rng.integers(0, 3, 400)
    reach = np.full(50, 0.1)
    assert spur_pairs.explained_by_balls(pts, pb, reach, q, own) is not None
    # a curve point on a cloud point (a zero ball): the level search's bound decides there
    zero = reach.copy()
    zero[3] = 0.0
    assert spur_pairs.explained_by_balls(pts, pb, zero, q, own) is None
    # balls holding more pairs than PAIRS_MAX: the level search (its memory bound)
    monkeypatch.setattr(spur_pairs, "PAIRS_MAX", 100)
    assert spur_pairs.explained_by_balls(pts, pb, np.full(50, 2.0), q, own) is None
    monkeypatch.setattr(spur_pairs, "CELLS_LISTED", 0)  # counted before they are listed: the same refusal
    assert spur_pairs.explained_by_balls(pts, pb, np.full(50, 2.0), q, own) is None
    np.testing.assert_array_equal(spurs._explained_elsewhere(pts, pb, np.full(50, 2.0), q, own),
                                  _levels(monkeypatch, pts, pb, np.full(50, 2.0), q, own))
