"""The compiled passes over points (skelcore/metrics/point_passes.py, region_links.py) give the bits of the
numpy expressions they replace (docs/performance.md 6.10), NaN and infinite coordinates included."""

import numpy as np
import pytest

from skelcore.metrics.point_passes import near_box, nearest_squared


def _near_box_numpy(points, lo, hi, reach, cover):
    bound = np.maximum(reach, cover) * (1 + 1e-9) + 1e-12
    loose = bound * (1 + 1e-9)
    inside = np.all((points >= lo - loose[:, None]) & (points <= hi + loose[:, None]), axis=1)
    t = np.maximum(np.maximum(lo - points, points - hi), 0.0)
    d = np.sqrt((t[:, 0] * t[:, 0] + t[:, 1] * t[:, 1]) + t[:, 2] * t[:, 2])
    return inside & (d <= bound)


def _nearest_squared_numpy(points, centres):
    out = np.full(len(points), np.inf)
    for c in centres:
        d = points - c
        out = np.minimum(out, (d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1]) + d[:, 2] * d[:, 2])
    return out


def _cases(rng, n):
    pts = rng.normal(size=(n, 3)) * rng.uniform(2, 6)
    centres = rng.normal(size=(int(rng.integers(1, 40)), 3))
    return pts, centres


@pytest.mark.parametrize("seed", range(6))
def test_near_box_is_numpy_s_test(seed):
    rng = np.random.default_rng(seed)
    pts, centres = _cases(rng, 2000 + seed)
    reach = np.abs(rng.normal(size=len(pts))) * rng.uniform(0.1, 1)
    if seed % 2:
        reach[::5], pts[::9] = np.nan, np.nan
    lo, hi = centres.min(axis=0), centres.max(axis=0)
    for cover in (0.0, 0.7):
        got = near_box(pts, lo, hi, reach, cover)
        want = _near_box_numpy(pts, lo, hi, reach, cover)
        assert np.array_equal(got, want)
        assert 0 < np.count_nonzero(got) < len(pts)  # the cases test both answers
    # a point exactly on the bound (a box of one point, a point at distance 1 along x) is near
    one = np.zeros((1, 3))
    assert near_box(np.array([[1.0, 0, 0]]), one[0], one[0], np.array([1.0]), 0.0)[0]
    assert not near_box(np.array([[1.0 + 1e-6, 0, 0]]), one[0], one[0], np.array([1.0]), 0.0)[0]


@pytest.mark.parametrize("seed", range(6))
def test_nearest_squared_is_numpy_s_minimum(seed):
    rng = np.random.default_rng(100 + seed)
    pts, centres = _cases(rng, 1001 + 7 * seed)  # not a whole number of the kernel's blocks
    if seed % 3 == 1:
        pts[::9] = np.nan
    if seed % 3 == 2:
        pts[::13, 1], centres[::3, 2] = np.inf, -np.inf
    got = nearest_squared(pts, centres)
    assert np.array_equal(got.view(np.int64), _nearest_squared_numpy(pts, centres).view(np.int64))
    assert np.array_equal(nearest_squared(pts, np.zeros((0, 3))), np.full(len(pts), np.inf))


def test_sizes_are_checked():
    with pytest.raises(ValueError):
        near_box(np.zeros((4, 2)), np.zeros(3), np.zeros(3), np.zeros(4), 0.0)
    with pytest.raises(ValueError):
        near_box(np.zeros((4, 3)), np.zeros(3), np.zeros(3), np.zeros(5), 0.0)


def test_region_links_read_the_kept_answers_as_numpy_did():
    """The missing regions' compiled pass (skelcore/metrics/region_links.py) against the numpy reading it
    replaced, on a lattice with repeated points (ties and zero distances: rows unsettled and unsure)."""
    from scipy.spatial import cKDTree

    from skelcore.metrics.region_links import region_links

    rng = np.random.default_rng(5)
    grid = np.stack(np.meshgrid(np.arange(12), np.arange(12), np.arange(4), indexing="ij"), -1).reshape(-1, 3)
    grid = np.vstack([grid, grid[rng.choice(len(grid), 100)]]).astype(float)
    n, width, k, kk = len(grid), 10, 9, 9
    covered = rng.random(n) > 0.5
    miss = np.flatnonzero(~covered)
    d, j = cKDTree(grid).query(grid, k=width, distance_upper_bound=1.5)
    at = np.full(n + 1, -1, np.int32)
    at[miss] = np.arange(len(miss))
    heads, tails, unsettled, border, unsure = region_links(d, j, miss, at, covered, k, kk)
    fd, fj = d[miss], j[miss]
    fu = at[fj]

    def unique_first(c):
        return ~np.isfinite(fd[:, c - 1]) | (fd[:, c] > fd[:, c - 1])

    found = np.isfinite(fd[:, :k])
    clean = unique_first(k) & ((fu[:, :k] >= 0) | ~found).all(axis=1) & (fd[:, 1] > 0)
    assert np.array_equal(unsettled, ~clean) and clean.any() and (~clean).any()
    ok = np.isfinite(fd[:, 1:k]) & clean[:, None]
    assert np.array_equal(heads, np.repeat(np.arange(len(miss)), ok.sum(axis=1)))
    assert np.array_equal(tails, fu[:, 1:k][ok])
    explained = np.concatenate([covered, [False]])
    assert np.array_equal(border, explained[np.where(np.isfinite(fd[:, :kk]), fj[:, :kk], n)].any(axis=1))
    assert np.array_equal(unsure, ~unique_first(kk)) and unsure.any()
    with pytest.raises(ValueError):  # a cloud row beyond n in a row read
        bad = j.copy()
        bad[miss[0], 3] = n + 1
        region_links(d, bad, miss, at, covered, k, kk)


@pytest.mark.parametrize("seed", range(4))
def test_the_border_distance_pair_by_pair_is_the_trees(seed, monkeypatch):
    """A missing region's distances to its border taken pair by pair (missing_parts._border_distance) are
    cKDTree's to the bit (its squared distance summed in the same order, its root last), at any scale,
    and the tree's beyond BORDER_PAIRS."""
    import sys

    from scipy.spatial import cKDTree

    import skelcore.diagnostics.missing_parts  # noqa: F401  (the package exports a function of that name)

    MP = sys.modules["skelcore.diagnostics.missing_parts"]
    rng = np.random.default_rng(200 + seed)
    for _ in range(40):
        s = 10.0 ** rng.uniform(-6, 6)
        border = rng.normal(size=(int(rng.integers(1, 300)), 3)) * s + rng.normal(size=3) * s * rng.uniform(0, 100)
        pts = rng.normal(size=(400, 3)) * s * rng.uniform(0.1, 10)
        want = cKDTree(border).query(pts)[0]
        assert np.array_equal(MP._border_distance(border, pts).view(np.int64), want.view(np.int64))
    monkeypatch.setattr(MP, "BORDER_PAIRS", 10)
    assert np.array_equal(MP._border_distance(border, pts), want)


@pytest.mark.parametrize("seed", range(4))
def test_nearest_two_are_the_kd_trees_two_nearest(seed):
    """The two nearest centres by blocks (point_passes.nearest_two) against ``kd_tree(centres).query(k=2)``:
    the same distance bits, the same nearest where the two differ, on repeated centres and ties too, the
    centres in any order or a ball tree's."""
    from skelcore.geometry import kd_tree
    from skelcore.metrics.ball_tree import BallTree
    from skelcore.metrics.point_passes import nearest_two

    rng = np.random.default_rng(300 + seed)
    ties = 0
    for t in range(30):
        s = 10.0 ** rng.uniform(-5, 5)
        centres = rng.normal(size=(int(rng.integers(2, 600)), 3)) * s
        pts = rng.normal(size=(300, 3)) * s * rng.uniform(0.2, 5)
        if t % 3 == 0:  # on a lattice: repeats and ties
            centres, pts = np.round(centres / s * 4) * s / 4, np.round(pts / s * 4) * s / 4
        if t % 2:
            centres = BallTree(centres).points
        d, i = kd_tree(centres).query(pts, k=2)
        d0, i0, d1 = nearest_two(pts, centres)
        assert np.array_equal(d0.view(np.int64), d[:, 0].view(np.int64))
        assert np.array_equal(d1.view(np.int64), d[:, 1].view(np.int64))
        alone = d0 < d1
        assert np.array_equal(i0[alone], i[alone, 0])
        ties += int(np.count_nonzero(~alone))
    assert ties > 0
