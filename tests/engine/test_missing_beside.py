"""Regions beside a branch (skelcore.diagnostics.beside): the far wall an off-centre axis leaves and the
wide sides of a flat tube are unexplained but not missing; a removed arm or a cut end still is
(docs/diagnostics.md "Missing parts", "Beside a branch")."""

import functools

import numpy as np
import pytest

from skelcore import Params
from skelcore.benchmark.calibration.skeletons import make_kind, world
from skelcore.curve import CurveSkeleton
from skelcore.diagnostics import missing_parts
from skelcore.geometry import Normalization

P = Params()


@functools.lru_cache(maxsize=None)
def clean(shape: str):
    return world("synthetic", shape, 5000, "clean", 0)


def judged(shape: str, kind: str, params: Params = P):
    w = clean(shape)
    made = make_kind(kind, w, f"{shape}/5000/clean", 0)
    norm = Normalization.from_cloud(w.cloud)
    return missing_parts(norm.apply(w.cloud), CurveSkeleton.from_raw(norm.apply(made.vertices), made.edges), params)


@pytest.mark.parametrize("shape,kind", [("tube_a", "offset"), ("elliptic", "intact")])
def test_an_off_centre_axis_and_a_flat_tube_leave_regions_beside_not_missing(shape, kind):
    mp = judged(shape, kind)
    # the cloud left unexplained lies beside the branches: no missing part, no warning ...
    assert not mp.incomplete and mp.counted == [] and mp.warnings() == []
    # ... though it is large (the paper's completeness keeps it)
    assert mp.completeness < 0.6 and mp.beside_share > 0.4
    assert all(r["beside"] for r in mp.to_dict()["regions"][:1])
    # without the test (a zero radius: nothing is beside) the same skeleton was incomplete
    assert judged(shape, kind, Params(missing_beside_radii=0.0)).incomplete


@pytest.mark.parametrize("shape,kind", [("junction_y", "missing_branch"), ("tube_a", "truncation")])
def test_a_removed_arm_and_a_cut_end_stay_missing(shape, kind):
    mp = judged(shape, kind)
    assert mp.incomplete and mp.counted and not any(r.beside for r in mp.counted)
    assert mp.warnings()[0].code == "incomplete"


def test_the_chords_are_kept_per_cloud_and_give_the_same_result(monkeypatch):
    """An edit's second update on the same cloud marches no chord (the evaluation's ChordCache), and a
    kept chord gives what a fresh march gives (skelcore.diagnostics.chord_cache)."""
    import skelcore.diagnostics.beside as beside
    import skelcore.edit as edit
    from skelcore import evaluate, shapes
    from skelcore.diagnostics.chord_cache import ChordCache

    marched = []
    march = beside._march
    monkeypatch.setattr(beside, "_march", lambda *a: marched.append(len(a[2])) or march(*a))
    sh = shapes.y_shape(5000, seed=0)
    ev = evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges))
    _, change = edit.prune_branch(ev.curve.curve, 0)
    first = ev.update(change, diagnostics=True)
    assert marched  # the pruned Y asks beside a branch
    done = len(marched)
    second = ev.update(change, diagnostics=True)
    assert len(marched) == done
    key = "curve missing parts"
    assert first.source.ctx.results[key].to_dict() == second.source.ctx.results[key].to_dict()
    # the same cloud asked again with the chords kept: nothing marched, the same regions as without them
    w = clean("tube_a")
    made = make_kind("offset", w, "tube_a/5000/clean", 0)
    norm = Normalization.from_cloud(w.cloud)
    cloud, curve = norm.apply(w.cloud), CurveSkeleton.from_raw(norm.apply(made.vertices), made.edges)
    kept = ChordCache()
    alone = missing_parts(cloud, curve, P).to_dict()
    assert missing_parts(cloud, curve, P, chords=kept).to_dict() == alone
    done = len(marched)
    assert missing_parts(cloud, curve, P, chords=kept).to_dict() == alone and len(marched) == done


def test_the_pairs_within_reach_and_the_groups_medians_match_scipys_and_numpys(monkeypatch):
    """The beside test's pairs (centre, point) within each centre's reach: the same rows in the same
    order as ``cKDTree.query_ball_point``, in one block or many; its per-centre medians: ``np.median``'s."""
    from scipy.spatial import cKDTree

    import skelcore.diagnostics.beside as beside

    rng = np.random.default_rng(3)
    points = rng.random((400, 3))
    centres = np.vstack([points[:5], rng.random((45, 3))])  # some centres on a point: distance 0
    reach = rng.uniform(0.0, 0.4, len(centres))
    reach[:2] = 0.0  # a centre on a point with no reach: that point alone
    lists = cKDTree(points).query_ball_point(centres, reach)
    want = np.concatenate([np.asarray(g, np.int64) for g in lists])
    for block in (1 << 20, 1000, 1):
        monkeypatch.setattr(beside, "WITHIN_BLOCK", block)
        got, owner = beside._within(centres, reach, points)
        assert np.array_equal(got, want)
        assert np.array_equal(owner, np.repeat(np.arange(len(centres)), [len(g) for g in lists]))
    values = rng.random(len(got))
    middle = beside._group_medians(values, owner, len(centres) + 1)  # the last group empty
    for i, g in enumerate(lists):
        assert (middle[i] == np.median(values[owner == i])) if g else np.isnan(middle[i])
    assert np.isnan(middle[-1])


def test_a_region_far_beyond_every_local_radius_is_refused_before_its_pairs_are_searched(monkeypatch):
    """A region whose distances to the skeleton, over the largest local radius, already put its quantile
    over the cut is not beside, and its pairs are not searched; the rows' full ratios say the same."""
    from scipy.spatial import cKDTree

    import skelcore.diagnostics.beside as beside

    rng = np.random.default_rng(0)  # a tube of radius 0.5 along x from 0 to 40, its axis drawn to x = 5 only
    x, a = rng.uniform(0.0, 40.0, 6000), rng.uniform(0.0, 2 * np.pi, 6000)
    pts = np.column_stack([x, 0.5 * np.cos(a), 0.5 * np.sin(a)])
    axis = np.column_stack([np.linspace(0.0, 5.0, 26), np.zeros(26), np.zeros(26)])
    tree = cKDTree(pts)
    spacing = float(np.median(tree.query(pts, k=2)[0][:, 1]))
    largest = beside.local_radii(pts, tree, axis, cKDTree(axis), spacing)[1].max()
    assert largest < 1.0  # the tube's chords: about its radius
    far = pts[:, 0] > 20.0
    region = np.where(far, 0, -1).astype(np.int64)
    calls = []
    real = beside._within
    monkeypatch.setattr(beside, "_within", lambda *a: calls.append(1) or real(*a))
    got = beside.beside_regions(pts, tree, region, np.array([0]), axis, spacing, 0.95, 3.0, 1.5, 0.15)
    assert not got[0] and not calls
    ratio, _ = beside.beside_ratios(pts, tree, np.flatnonzero(far), axis, spacing)
    assert calls and np.quantile(np.where(np.isfinite(ratio), ratio, np.inf), 0.95, method="higher") > 3.0
