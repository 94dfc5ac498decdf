"""Evaluation.update against a fresh evaluate: random sequences of one to four edits on small shapes,
every score, local value, coverage, diagnostic and warning equal to 1e-12 (the JSON document and the
local arrays); diagnostics=False keeps the four metrics exact; a pickled Evaluation evaluates again."""

from __future__ import annotations

import math
import os
import pickle
from functools import lru_cache

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import skelcore.edit as E
from skelcore import SkelInputError, evaluate, shapes

TOL = 1e-12


@lru_cache(maxsize=None)
def _base(name: str):
    """(cloud, skeletal set or None, Evaluation) of a small shape, made once."""
    if name == "y":
        sh = shapes.y_shape(400, seed=2, n_curve_per_arm=6)
        cloud, skeletal = sh.cloud, sh.skeletal
    else:  # a torus: one cycle to cut, no skeletal set
        sh = shapes.torus(500, n_curve=16, seed=1)
        cloud, skeletal = sh.cloud, None
    return cloud, skeletal, evaluate(cloud, skeletal, (sh.curve_vertices, sh.curve_edges))


def _close(a, b, where="") -> None:
    """Nested documents equal, numbers to TOL (NaN and None alike)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), where
        for k in set(a) - {"timings_s", "timings"}:  # seconds differ run to run
            _close(a[k], b[k], f"{where}/{k}")
    elif isinstance(a, (list, tuple)):
        assert isinstance(b, (list, tuple)) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            _close(x, y, f"{where}/{i}")
    elif isinstance(a, float) and isinstance(b, float):
        assert (math.isnan(a) and math.isnan(b)) or a == b or abs(a - b) <= TOL, (where, a, b)
    else:
        assert a == b, (where, a, b)


def _same(updated, fresh) -> None:
    _close(updated.to_json_dict(), fresh.to_json_dict())
    a, b = updated.curve, fresh.curve
    for name in ("samples", "sample_edge", "sample_t", "sample_boundedness", "sample_centeredness_raw",
                 "vertex_degree", "vertex_smoothness"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=0, atol=TOL, err_msg=name)
    assert np.array_equal(a.curve.edges, b.curve.edges) and np.array_equal(a.curve.vertices, b.curve.vertices)
    if fresh.coverage_curve is not None:  # kept by difference (edit/coverage_update.py): the same bits
        np.testing.assert_array_equal(updated.coverage_curve.gap, fresh.coverage_curve.gap)
        np.testing.assert_array_equal(updated.coverage_curve.covered, fresh.coverage_curve.covered)
    if fresh.skeletal is not None:
        for name in ("boundedness", "centeredness_raw", "smoothness"):
            np.testing.assert_allclose(getattr(updated.skeletal, name), getattr(fresh.skeletal, name), rtol=0,
                                       atol=TOL, err_msg=name)


@st.composite
def _edit(draw, curve):
    """One edit's (function name, arguments) for ``curve``; some are refused (then skipped)."""
    op = draw(st.sampled_from(["delete_vertex", "delete_edge", "prune_branch", "add_vertex", "add_edge",
                               "split_edge", "merge_vertices", "move_vertex", "cut_cycle"]))
    v = draw(st.integers(0, curve.n_vertices - 1))
    edge = tuple(int(x) for x in curve.edges[draw(st.integers(0, curve.n_edges - 1))])
    offset = np.array(draw(st.tuples(*[st.floats(-0.2, 0.2)] * 3)))
    if op in ("delete_vertex",):
        return op, {"vertex": v}
    if op in ("delete_edge", "cut_cycle", "split_edge"):
        return op, ({"edge": edge, "t": draw(st.floats(0.1, 0.9))} if op == "split_edge" else {"edge": edge})
    if op == "prune_branch":
        return op, {"branch": draw(st.integers(0, 6))}
    if op == "add_vertex":
        return op, {"position": (curve.vertices[v] + offset).tolist(), "attach_to": v}
    if op == "add_edge":
        return op, {"edge": (v, draw(st.integers(0, curve.n_vertices - 1)))}
    if op == "merge_vertices":
        return op, {"keep": edge[0], "remove": edge[1]}
    return op, {"vertex": v, "position": (curve.vertices[v] + offset).tolist()}


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(["y", "torus"]), st.data())
def test_update_equals_a_fresh_evaluation(name, data):
    cloud, skeletal, ev = _base(name)
    curve, changes = ev.curve.curve, []
    for _ in range(data.draw(st.integers(1, 4))):
        op, args = data.draw(_edit(curve))
        try:
            curve, change = E.apply(curve, {"op": op, "args": args})
        except SkelInputError:
            continue
        changes.append(change)
        ev = ev.update(change)
    fresh = evaluate(cloud, skeletal, curve)
    _same(ev, fresh)


def test_without_diagnostics_the_metrics_stay_exact_and_the_rest_is_named():
    cloud, skeletal, ev = _base("y")
    new, change = E.prune_branch(ev.curve.curve, 0)
    quick = ev.update(change, diagnostics=False)
    fresh = evaluate(cloud, skeletal, new)
    for key in ("boundedness", "centeredness", "smoothness", "topology"):
        _close(quick.summary()[key], fresh.summary()[key], key)
    np.testing.assert_array_equal(quick.curve.sample_centeredness_raw, fresh.curve.sample_centeredness_raw)
    assert quick.coverage_curve is None and set(quick.not_computed) >= {"curve coverage", "curve defects"}
    assert quick.timings["update"] > 0


def test_a_pickled_evaluation_evaluates_again_and_an_unkept_one_refuses():
    cloud, skeletal, ev = _base("torus")
    copy = pickle.loads(pickle.dumps(ev))
    assert copy.source.ctx is None
    new, change = E.delete_edge(ev.curve.curve, tuple(ev.curve.curve.edges[0]))
    _same(copy.update(change), evaluate(cloud, skeletal, new))
    copy.source = None
    with pytest.raises(SkelInputError, match="keeps no record"):
        copy.update(new)


@pytest.mark.parametrize("options", [{"reference_curve": "self"}, {"remove_outliers": True},
                                     {"correspondence": "reverse"}])
def test_update_with_a_reference_a_scan_option_or_reverse_correspondence(options):
    """The reference comparison is made again; a scan option or the curve's projections evaluate again."""
    sh = shapes.y_shape(400, seed=3, n_curve_per_arm=6)
    curve = (sh.curve_vertices, sh.curve_edges)
    if options.get("reference_curve") == "self":
        options = {"reference_curve": curve}
    skeletal = None if options.get("correspondence") == "reverse" else sh.skeletal
    ev = evaluate(sh.cloud, skeletal, curve, **options)
    new, change = E.prune_branch(ev.curve.curve, 1)
    _same(ev.update(change), evaluate(sh.cloud, skeletal, new, **options))


def test_the_missing_parts_subsample_index_is_kept_across_updates_and_dropped_with_the_cloud():
    """Above missing_max_points (and without coverage) the missing parts search a subsample: its tree and
    spacings are made once and kept while the evaluation's cloud lives; an update using them equals a
    fresh evaluate; the context keeps of the curve's stages only the samples' values and what the repair
    reads (the defects, the missing parts)."""
    import gc

    from skelcore import Params
    from skelcore.metrics import cloud_index

    sh = shapes.y_shape(3000, seed=4, n_curve_per_arm=6)
    params = Params(missing_max_points=1000, coverage_max_points=500)
    base = evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges), params=params).curve.curve
    new, change = E.move_vertex(base, 3, base.vertices[3] + np.array([0.0, 0.02, 0.0]))
    fresh = evaluate(sh.cloud, curve=new, params=params)
    ev = evaluate(sh.cloud, curve=base, params=params)
    kept = cloud_index._kept.get("index")
    assert kept is not None and len(kept.cloud) == 1000
    assert {"curve defects", "curve missing parts"} <= set(ev.source.ctx.results)
    assert "curve coverage" not in ev.source.ctx.results
    updated = ev.update(change)
    assert cloud_index._kept.get("index") is kept
    assert "cloud_missing_curve" in updated.diagnostics.arrays
    _same(updated, fresh)
    np.testing.assert_array_equal(updated.diagnostics.arrays["cloud_missing_curve"],
                                  fresh.diagnostics.arrays["cloud_missing_curve"])
    del ev, updated
    gc.collect()
    assert not cloud_index._kept


@pytest.mark.parametrize("name,edit", [("y", "prune_branch"), ("y", "move_vertex"), ("torus", "delete_edge")])
def test_the_two_phases_equal_one_update_and_a_fresh_evaluation(name, edit):
    """update(diagnostics=False) then complete_update() equals update() and a fresh evaluate; the first
    phase is left as it was, names what it left out, and a cancel stops the second."""
    from skelcore.errors import Cancelled

    cloud, skeletal, ev = _base(name)
    curve = ev.curve.curve
    new, change = {"prune_branch": lambda: E.prune_branch(curve, 0),
                   "move_vertex": lambda: E.move_vertex(curve, 3, curve.vertices[3] + np.array([0.0, 0.03, 0.0])),
                   "delete_edge": lambda: E.delete_edge(curve, tuple(curve.edges[0]))}[edit]()
    quick = ev.update(change, diagnostics=False)
    assert quick.diagnostics_left_out and not ev.diagnostics_left_out
    before = quick.to_json_dict()
    with pytest.raises(Cancelled):
        quick.complete_update(cancel=lambda: True)
    full = quick.complete_update()
    assert not full.diagnostics_left_out and full.complete_update() is full
    _same(full, ev.update(change))
    _same(full, evaluate(cloud, skeletal, new))
    _close(quick.to_json_dict(), before)
    assert quick.diagnostics_left_out
    with pytest.raises(SkelInputError, match="keeps no record"):
        pickle.loads(pickle.dumps(quick)).complete_update()
    newer, change2 = E.delete_edge(new, tuple(new.edges[-1]))
    _same(quick.update(change2), evaluate(cloud, skeletal, newer))  # a first phase updates like any


def test_the_cloud_only_values_the_diagnostics_ask_again_are_kept_per_array():
    """The cloud's spacing is kept for a few arrays at once (the diagnostics ask of the cloud and of
    its subsample's tree data; one entry made them evict each other at every update), the coverage's
    noise sample for the last cloud; equal to computing them afresh, dropped with their array."""
    import gc

    from skelcore.diagnostics import interior
    from skelcore.metrics import coverage

    rng = np.random.default_rng(5)
    a, b = rng.random((3000, 3)), rng.random((500, 3))
    first = interior.median_spacing(a), interior.median_spacing(b)
    assert (interior.median_spacing(a), interior.median_spacing(b)) == first
    assert first[0] == interior.median_spacing(a.copy())  # a fresh array: computed again, the same
    big = rng.random((coverage.NOISE_SAMPLE + 10, 3))
    for cloud in (a, big):
        pts, spacing = coverage._noise_sample(cloud)
        assert coverage._noise_sample(cloud)[0] is pts and coverage._noise_sample(cloud.copy())[1] == spacing
        assert coverage._noise_sample(cloud)[1] == spacing
    del a, b, big, cloud, pts
    gc.collect()
    assert not coverage._last_noise and len(interior._last_spacing) <= interior._SPACINGS_KEPT


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from(["move", "split", "merge", "drop", "renumber", "prune"]))
def test_the_kept_spur_search_answers_as_a_search_of_the_whole_curve(seed, how):
    """The spur test's search kept from one curve (diagnostics/spur_cache.py) answers the next curve's
    points, nearest branches and cloud distances as asking them all again does, for points moved,
    removed, branches split or merged, renumbered or pruned (the branches after it renumbered), and
    asks fewer than all when little changed: none again when only the numbers changed."""
    from scipy.spatial import cKDTree

    from skelcore.diagnostics.spur_cache import SpurMemo
    from skelcore.diagnostics.spurs import _explained_elsewhere

    rng = np.random.default_rng(seed)
    use = rng.random((1500, 3))
    tree = cKDTree(use)
    pts = rng.random((120, 3))
    labels = np.repeat(np.arange(40), 3)  # more branches than the pairs tested one by one (_PAIRS_MAX)
    pts[15] = pts[30]  # a junction: one position, two branches

    def run(memo, pts, labels, skip=3):
        reach = 1.25 * memo.radii(pts, tree) + 0.05
        own = memo.own_branch(pts, labels, use)
        rows = np.flatnonzero(own != skip)
        got = memo.search(_explained_elsewhere, pts, labels, reach, use[rows], rows, own[rows], len(use))
        want_own = labels[cKDTree(pts).query(use)[1]]
        want = _explained_elsewhere(pts, labels, reach, use[rows], want_own[rows])
        np.testing.assert_array_equal(own, want_own)
        np.testing.assert_array_equal(got, want)
        np.testing.assert_array_equal(reach, 1.25 * tree.query(pts)[0] + 0.05)
        kept = memo.current  # its distinct positions' rows, which the next update reads instead of sorting again
        assert kept.pos[kept.inverse].tobytes() == np.ascontiguousarray(pts).tobytes()
        assert kept.pos.tobytes() == np.ascontiguousarray(pts)[kept.first].tobytes()

    first = SpurMemo()
    run(first, pts, labels)
    new_pts, new_labels, skip = pts.copy(), labels.copy(), 3
    if how == "move":
        new_pts[rng.integers(0, 120)] += rng.normal(0, 0.05, 3)
    elif how == "split":
        new_labels[20:30] = 47
    elif how == "merge":
        new_labels[new_labels == 2] = 1
    elif how == "renumber":
        order = rng.permutation(40)
        new_labels, skip = order[labels], order[3]
    elif how == "prune":  # branch 0 gone, the others numbered one lower
        new_pts, new_labels, skip = new_pts[3:], new_labels[3:] - 1, 2
    else:
        new_pts, new_labels = new_pts[5:], new_labels[5:]
    memo = first.next()
    run(memo, new_pts, new_labels, skip)
    assert memo.previous is first.current and memo.current is not None
    assert 0 <= memo.asked[0] <= memo.asked[1]
    if how == "renumber":
        assert memo.asked[0] == 0


def test_an_edit_update_asks_the_spur_test_again_only_near_the_edit():
    cloud, skeletal, ev = _base("y")
    curve = ev.curve.curve
    new, change = E.move_vertex(curve, 3, curve.vertices[3] + np.array([0.0, 0.01, 0.0]))
    updated = ev.update(change)
    asked, of = updated.source.ctx.spur_memo.asked
    assert updated.source.ctx.spur_memo.previous is ev.source.ctx.spur_memo.current
    assert of > 0 and asked < of


def test_the_moved_samples_boundedness_in_parts_gives_the_same_bits(monkeypatch):
    """An update scores its moved samples' boundedness, while the stages beside it run, a third of those
    left at a time in one stream, then the rest at once (each sample on its own): the same bits as a
    fresh evaluation either way, every moved sample asked once."""
    import threading

    import skelcore.edit.incremental as inc

    cloud, skeletal, ev = _base("y")
    new, change = E.prune_branch(ev.curve.curve, 0)
    fresh = evaluate(cloud, skeletal, new).curve.sample_boundedness
    up = ev.update(change, diagnostics=False)
    np.testing.assert_array_equal(up.curve.sample_boundedness, fresh)
    calls = []
    real = inc.LoneRays.distinct

    def counted(self, points, **kw):
        calls.append((len(points), kw.get("workers")))
        return real(self, points, **kw)

    monkeypatch.setattr(inc.LoneRays, "distinct", counted)
    monkeypatch.setattr(inc, "_RAYS_CHUNK", 4)
    old = {p.tobytes() for p in ev.curve.samples}
    moved = sum(p.tobytes() not in old for p in up.curve.samples)
    assert moved > 50
    running, done = threading.Event(), threading.Event()
    done.set()
    for beside in (running, done, None):
        calls.clear()
        got = inc._sample_boundedness(ev.source.ctx, up.source.ctx, ev.source.cache, beside)
        np.testing.assert_array_equal(got, fresh)
        assert sum(n for n, _ in calls) == moved
        if beside is running:  # thirds while the others run (one stream on two cores), the last few at once
            want, left = [], moved
            while left > 8:
                want.append((max(4, left // 3), max(1, (os.cpu_count() or 1) - 1)))
                left -= want[-1][0]
            assert calls == want + [(left, None)]
        else:
            assert calls == [(moved, None)]
    calls.clear()  # one lane (workers=1): nothing runs beside, the moved samples in one call
    ev1 = evaluate(cloud, skeletal, ev.curve.curve, workers=1)
    np.testing.assert_array_equal(ev1.update(change).curve.sample_boundedness, fresh)
    assert calls == [(moved, None)]


def test_curve_centeredness_in_larger_spans_gives_the_same_bits():
    """An update asks curve centeredness for one span of samples per core (``span=``): the same bits as
    the default spans of 4, on a cloud above the size where the samples go in spans."""
    from skelcore import Params
    from skelcore.curve import CurveSkeleton
    from skelcore.metrics import centeredness as C
    from skelcore.metrics.curve_sampling import sample_curve

    sh = shapes.y_shape(C._CURVE_AT_ONCE + 2000, seed=6, n_curve_per_arm=6)
    s = sample_curve(CurveSkeleton(sh.curve_vertices, sh.curve_edges), 24)
    p = Params()
    grid = C.slab_grid(sh.cloud, p)
    base = C.curve_centeredness(sh.cloud, s.points, s.directions, params=p, grid=grid)
    assert np.isfinite(base).sum() > 12
    for span in (1, 7, len(s.points)):
        got = C.curve_centeredness(sh.cloud, s.points, s.directions, params=p, grid=grid, span=span)
        np.testing.assert_array_equal(got, base)


def test_a_tie_between_two_nearest_curve_points_is_asked_again():
    """Two vertices added on vertices of the torus' curve: its samples meet at one place from two
    branches, and a cloud point has two nearest curve points at one distance; the spur search's kept
    answer for it must be the one the whole curve's search gives."""
    cloud, skeletal, ev = _base("torus")
    curve = ev.curve.curve
    for op, args in (("add_vertex", {"position": curve.vertices[0].tolist(), "attach_to": 0}),
                     ("add_vertex", {"position": curve.vertices[4].tolist(), "attach_to": 4}),
                     ("delete_vertex", {"vertex": 0})):
        curve, change = E.apply(curve, {"op": op, "args": args})
        ev = ev.update(change)
    _same(ev, evaluate(cloud, skeletal, curve))


def test_the_kept_one_sidedness_gives_the_same_value():
    """The spur test's one-sidedness reads each asked curve point's mean direction from the kept ones
    (``one_sidedness(..., kept=)``, shared along an evaluation's updates): the same value as asking the
    cloud at every point, for a curve with points kept, moved and added."""
    from scipy.spatial import cKDTree

    from skelcore.diagnostics.spur_sides import one_sidedness

    sh = shapes.y_shape(3000, seed=4, n_curve_per_arm=6)
    tree = cKDTree(sh.cloud)
    pts = np.vstack([np.linspace(v, w, 12) for v, w in zip(sh.curve_vertices[:-1], sh.curve_vertices[1:])])
    r_x = tree.query(pts)[0]
    kept: dict = {}
    first = one_sidedness(tree, pts, r_x, float(np.median(r_x)), kept=kept)
    assert first == one_sidedness(tree, pts, r_x, float(np.median(r_x))) and kept
    moved = np.vstack([pts[::2], pts[1::4] + 0.01])
    r_m = tree.query(moved)[0]
    n_kept = len(kept)
    assert one_sidedness(tree, moved, r_m, float(np.median(r_x)), kept=kept) == \
        one_sidedness(tree, moved, r_m, float(np.median(r_x)))
    assert len(kept) > n_kept


def test_the_ball_tree_answers_the_diagnostics_nearest_distances_to_the_bit():
    """An update's diagnostics ask their one-nearest distances of the cloud index's ball tree
    (``spur_cache.NearestByBalls``): the KD-tree's bits, from a tube's axis, off it and from the cloud's
    own points; other queries are the KD-tree's own."""
    from scipy.spatial import cKDTree

    from skelcore.diagnostics.spur_cache import NearestByBalls, same_tree
    from skelcore.metrics.ball_tree import BallTree
    from skelcore.metrics.cloud_index import CloudIndex

    sh = shapes.y_shape(5000, seed=3, n_curve_per_arm=6)
    kd = cKDTree(sh.cloud)
    tree = NearestByBalls(kd, CloudIndex(sh.cloud).surface)
    sub = sh.cloud[::3]  # a subsample's tree and its own ball tree
    kd_sub = cKDTree(sub)
    tree_sub = NearestByBalls(kd_sub, lambda: BallTree(sub, slab=True))
    rng = np.random.default_rng(0)
    axis = np.vstack([np.linspace(v, w, 50) for v, w in zip(sh.curve_vertices[:-1], sh.curve_vertices[1:])])
    for q in (axis, axis + rng.normal(0, 0.05, axis.shape), sh.cloud[::7]):
        for t, k, pts in ((tree, kd, sh.cloud), (tree_sub, kd_sub, sub)):
            d, i = t.query(q)
            np.testing.assert_array_equal(d, k.query(q)[0])
            np.testing.assert_array_equal(np.linalg.norm(pts[i] - q, axis=1), d)
    np.testing.assert_array_equal(tree.query(axis, k=3)[1], kd.query(axis, k=3)[1])
    assert tree.n == kd.n and same_tree(tree, kd) and not same_tree(tree, cKDTree(sh.cloud))


def test_an_update_on_a_subsampled_cloud_equals_a_fresh_evaluation():
    """Above ``diag_max_points`` the diagnostics read a subsample's tree, and an update asks its
    one-nearest distances of a ball tree of that subsample (made once): the fresh evaluation's values."""
    from skelcore import Params
    from skelcore.diagnostics.spur_cache import NearestByBalls

    sh = shapes.y_shape(1200, seed=5, n_curve_per_arm=6)
    p = Params(diag_max_points=500)
    ev = evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges), params=p)
    curve = ev.curve.curve
    for op, args in (("move_vertex", {"vertex": 3, "position": (curve.vertices[3] + 0.02).tolist()}),
                     ("delete_edge", {"edge": tuple(int(x) for x in curve.edges[4])})):
        curve, change = E.apply(curve, {"op": op, "args": args})
        ev = ev.update(change)
        _same(ev, evaluate(sh.cloud, curve=curve, params=p))
    assert isinstance(ev.source.ctx.diag_tree(), NearestByBalls)
