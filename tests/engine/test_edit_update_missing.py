"""The missing parts of an edit's update (skelcore/edit/missing_update.py): with the cloud's tree kept,
the regions' neighbours come mostly from one search of it, the others searched as before; the same
regions, depths and points as without it, on a lattice cloud with repeated points (ties and zero
distances everywhere, the searches it must fall back on), through a pruned Y's update, and on the kept
subsample above missing_max_points."""

from __future__ import annotations

import sys
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial import cKDTree

import skelcore.edit as E
from skelcore import evaluate, shapes
import skelcore.diagnostics.missing_parts  # noqa: F401  (the package exports a function of that name)

MP = sys.modules["skelcore.diagnostics.missing_parts"]


def _same(a, b) -> None:
    assert np.array_equal(a[0], b[0])
    assert len(a[1]) == len(b[1])
    for x, y in zip(a[1], b[1]):
        for key in x:
            assert np.array_equal(np.asarray(x[key]), np.asarray(y[key]), equal_nan=True), key


def _regions(pts, cov, spacing, params, tree):
    return MP._regions(pts, cov, spacing, params, lambda f: None, tree=tree, small=lambda t: 30.0)


@pytest.fixture(scope="module")
def pruned():
    sh = shapes.y_shape(4000, seed=0, n_curve_per_arm=8)
    ev = evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges))
    new, change = E.prune_branch(ev.curve.curve, 0)
    return ev, change


def test_kept_tree_gives_the_same_regions_on_a_lattice_with_repeats(pruned):
    ev, _ = pruned
    params = ev.source.ctx.params
    rng = np.random.default_rng(1)
    grid = np.stack(np.meshgrid(np.arange(24), np.arange(24), np.arange(5), indexing="ij"), -1).reshape(-1, 3)
    grid = np.vstack([grid, grid[rng.choice(len(grid), 400)]]) * 0.01
    tree = cKDTree(grid)
    for share in (0.3, 0.6):
        covered = rng.random(len(grid)) > share
        covered[: len(grid) // 3] = True
        c = SimpleNamespace(covered=covered, gap=rng.random(len(grid)))  # what the regions read
        for spacing in (0.005, 0.01, 0.013):
            _same(_regions(grid, c, spacing, params, None), _regions(grid, c, spacing, params, lambda: tree))


def test_update_keeps_the_tree_and_equals_a_fresh_evaluation(pruned, monkeypatch):
    ev, change = pruned
    calls = []
    real = MP._from_kept
    monkeypatch.setattr(MP, "_from_kept", lambda *a: calls.append(1) or real(*a))
    up = ev.update(change)
    tree = ev.source.cache["missing parts' cloud tree"][1]
    ev.update(change)
    assert ev.source.cache["missing parts' cloud tree"][1] is tree  # built once per evaluation
    fresh = evaluate(ev.source.args["cloud"], curve=change.curve)
    assert calls, "the update did not take the kept tree's path"
    a, b = up.source.ctx.results["curve missing parts"], fresh.source.ctx.results["curve missing parts"]
    assert any(r.counted for r in a.regions)  # the pruned arm is missing
    assert np.array_equal(a.region, b.region) and np.array_equal(a.explained, b.explained)
    assert [r.to_dict() for r in a.regions] == [r.to_dict() for r in b.regions]


def test_above_missing_max_points_the_subsample_tree_is_kept():
    """Without the curve's coverage and above ``missing_max_points`` the regions are found on the kept
    subsample: its tree is kept (the same array), and a pruned branch's update equals a fresh evaluation."""
    from skelcore import Params

    sh = shapes.y_shape(3000, seed=4, n_curve_per_arm=6)
    params = Params(missing_max_points=1000, coverage_max_points=500)
    ev = evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges), params=params)
    new, change = E.prune_branch(ev.curve.curve, 0)
    first = ev.update(change)
    tree = ev.source.cache["missing parts' cloud tree"][1]
    second = ev.update(change)
    kept = ev.source.cache["missing parts' cloud tree"]
    assert kept[1] is tree
    assert len(kept[2]) == 1000 and kept[1].n == 1000
    fresh = evaluate(sh.cloud, curve=new, params=params)
    for up in (first, second):
        a, b = up.source.ctx.results["curve missing parts"], fresh.source.ctx.results["curve missing parts"]
        assert a.subsample == 1000 and any(r.counted for r in a.regions)
        assert np.array_equal(a.region, b.region) and np.array_equal(a.explained, b.explained)
        assert [r.to_dict() for r in a.regions] == [r.to_dict() for r in b.regions]


def test_a_first_phase_completed_again_and_again_keeps_its_parent(pruned):
    """Each completion links its own context; the first phase's link to the curve it was edited from
    stays (else after eight completions its coverage was computed whole, not by difference)."""
    from skelcore.edit import coverage_update as CU

    ev, change = pruned
    quick = ev.update(change, diagnostics=False)
    for _ in range(CU._KEEP + 3):
        quick.complete_update()
    assert CU.parent_of(quick.source.cache, quick.source.ctx) is ev.source.ctx


def test_the_missing_parts_coverage_by_difference_equals_it_computed_whole(monkeypatch):
    """Above ``coverage_max_points`` the missing parts compute their own coverage of the kept
    subsample: an update takes it by difference from the curve edited (skelcore/edit/missing_update.py),
    each gap and verdict those of ``coverage`` of the same elements, along a chain of edits."""
    from skelcore import Params
    from skelcore.edit import coverage_update as CU
    from skelcore.edit import missing_update as MU
    from skelcore.metrics.coverage import coverage

    sh = shapes.y_shape(3000, seed=4, n_curve_per_arm=6)
    params = Params(missing_max_points=1000, coverage_max_points=500)
    ev = evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges), params=params)
    seen, differences = [], []
    real_from, real_diff = MU.coverage_from, CU._by_difference
    monkeypatch.setattr(MU, "coverage_from", lambda *a: seen.append((a, real_from(*a))) or seen[-1][1])
    monkeypatch.setattr(CU, "_by_difference", lambda *a: differences.append(1) or real_diff(*a))
    curve = first = ev.curve.curve
    for edit in ("prune", "move", "delete", "undo"):
        if edit == "prune":
            curve, change = E.prune_branch(curve, 0)
        elif edit == "move":
            curve, change = E.move_vertex(curve, 3, curve.vertices[3] + np.array([0.0, 0.02, 0.0]))
        elif edit == "delete":
            curve, change = E.delete_edge(curve, tuple(curve.edges[2]))
        else:  # back to the first curve: the pruned arm's balls added again
            curve = change = first
        ev = ev.update(change)
        fresh = evaluate(sh.cloud, curve=curve, params=params)
        a, b = ev.source.ctx.results["curve missing parts"], fresh.source.ctx.results["curve missing parts"]
        assert np.array_equal(a.region, b.region) and np.array_equal(a.explained, b.explained)
        assert [r.to_dict() for r in a.regions] == [r.to_dict() for r in b.regions]
    assert len(differences) >= 4  # each edit's coverage by difference (the first's parent memo made whole)
    for (view, old, elements, tau), (cov, _) in seen:
        whole = coverage(view.cloud_n, elements, params, tau, index=view.cloud_index)
        assert np.array_equal(cov.gap, whole.gap) and np.array_equal(cov.covered, whole.covered)
        assert cov.n_elements == whole.n_elements
    assert sum(old is not None for (_, old, _, _), _ in seen) >= 4


def test_the_spread_from_kept_nearest_samples_equals_the_searched_one():
    """The spread reads each cloud point's kept nearest sample: the same regions and verdicts as its
    search, with cloud points at the bound of ``SPREAD`` spacings (on a lattice: exact distances) and
    points whose nearest sample is explained but an unexplained one lies within the bound."""
    rng = np.random.default_rng(3)
    pts = np.stack(np.meshgrid(np.arange(30), np.arange(30), np.arange(3), indexing="ij"), -1).reshape(-1, 3) * 0.5
    spacing = 0.5
    bound = MP.SPREAD * spacing  # 2.0: lattice points at 2.0 and offsets that land on the bound exactly
    cloud = np.vstack([pts + rng.normal(0, 0.2, pts.shape), pts + [0.0, 0.0, bound], pts + [0.25, 0.0, 0.0],
                       rng.uniform(-3, 18, (3000, 3))])
    tree = cKDTree(pts)
    kept = tree.query(cloud)
    for share in (0.3, 0.9, 0.995):
        explained_s = rng.random(len(pts)) > share
        region_s = np.where(explained_s, -1, rng.integers(0, 5, len(pts)))
        searched = MP._spread(cloud, pts, region_s, explained_s, spacing)
        read = MP._spread(cloud, pts, region_s, explained_s, spacing, nearest=lambda c, p, f: kept)
        assert np.array_equal(searched[0], read[0]) and np.array_equal(searched[1], read[1])
        assert (~searched[1]).any() and searched[1].any()


def test_the_kept_neighbours_give_the_same_regions_as_searching(pruned):
    """The regions' search of the kept tree answered from each point's kept answer
    (missing_update._neighbours): the same regions as without the tree, on a lattice with repeats, the
    unexplained points of one call partly those of the next; a changed link searches anew."""
    from skelcore.edit import missing_update as MU

    ev, _ = pruned
    params = ev.source.ctx.params
    rng = np.random.default_rng(2)
    grid = np.stack(np.meshgrid(np.arange(24), np.arange(24), np.arange(5), indexing="ij"), -1).reshape(-1, 3)
    grid = np.vstack([grid, grid[rng.choice(len(grid), 400)]]) * 0.01
    tree, cache, asked = cKDTree(grid), {}, []
    kept = MU._neighbours(cache)

    def neighbours(t, rows, k, link):
        asked.append(len(rows))
        return kept(t, rows, k, link)

    for spacing in (0.002, 0.013):
        for share in (0.3, 0.5, 0.6):
            covered = rng.random(len(grid)) > share
            c = SimpleNamespace(covered=covered, gap=rng.random(len(grid)))
            with_kept = MP._regions(grid, c, spacing, params, lambda f: None, tree=lambda: tree,
                                    small=lambda t: 30.0, neighbours=neighbours)
            _same(_regions(grid, c, spacing, params, None), with_kept)
    assert len(asked) == 6 and cache[MU._NEIGHBOURS][2].sum() < len(grid)  # some rows never asked


def test_the_subsample_its_index_and_tau_are_made_once_per_evaluation(monkeypatch):
    """Above ``missing_max_points`` without the curve's coverage, an evaluation's updates draw the
    subsample, check its index and find its tau once (missing_update keeps them), and each update's
    missing parts equal a fresh evaluation's (a wrong row or tau kept would move the regions)."""
    from skelcore import Params
    from skelcore.edit import missing_update as MU

    sh = shapes.y_shape(3000, seed=2, n_curve_per_arm=6)
    params = Params(missing_max_points=1200, coverage_max_points=500)
    ev = evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges), params=params)
    made, taus = [], []

    def sampled(cloud, p, f=MP.sampled_points):
        sub, index, tau = f(cloud, p)
        made.append(sub)
        return sub, index, lambda c: (taus.append(1), tau(c))[1]

    monkeypatch.setattr(MU, "sampled_points", sampled)
    curve = ev.curve.curve
    for new, change in (E.prune_branch(curve, 0), E.delete_edge(curve, tuple(curve.edges[4])),
                        E.prune_branch(curve, 0)):
        up = ev.update(change)
        fresh = evaluate(sh.cloud, curve=new, params=params)
        a, b = up.source.ctx.results["curve missing parts"], fresh.source.ctx.results["curve missing parts"]
        assert a.subsample == 1200 and a.completeness == b.completeness
        assert np.array_equal(a.region, b.region) and np.array_equal(a.explained, b.explained)
        assert repr([r.to_dict() for r in a.regions]) == repr([r.to_dict() for r in b.regions])  # NaN depths
    assert len(made) == 1 and len(taus) == 1
    assert np.array_equal(made[0], np.sort(np.random.default_rng(MP.SUBSAMPLE_SEED).choice(3000, 1200, replace=False)))


@pytest.mark.parametrize("lattice", [True, False])
def test_the_rows_searched_among_the_near_unexplained_points_find_the_whole_trees_sets(lattice):
    """``_near_rows``: each row's neighbours searched in a tree of the unexplained points within the
    link of the rows asked are those of a tree of all unexplained points (the same distances and
    sets), except the rows it leaves (a tie at the k-th, a point as near as the row itself): on a
    lattice with repeated points, where it must leave some, and on a random cloud."""
    rng = np.random.default_rng(3)
    if lattice:
        pts = np.stack(np.meshgrid(np.arange(20), np.arange(20), np.arange(6), indexing="ij"), -1).reshape(-1, 3)
        pts = np.vstack([pts, pts[rng.choice(len(pts), 300)]]) * 0.01
    else:
        pts = rng.random((3000, 3)) * 0.2
    miss = np.flatnonzero(rng.random(len(pts)) < 0.5)
    up = pts[miss]
    for link in (0.011, 0.02, 0.035):
        rows = rng.choice(len(up), 150, replace=False)
        d, j, left = MP._near_rows(up, rows, 9, link, cKDTree(pts), miss)
        rd, rj = cKDTree(up).query(up[rows], k=9, distance_upper_bound=link)
        ok = np.flatnonzero(~left)
        assert len(ok) > (30 if lattice else 140) and (left.any() if lattice else True)
        np.testing.assert_array_equal(d[ok], rd[ok])
        for a, b in zip(j[ok], rj[ok]):
            assert sorted(a) == sorted(b)
