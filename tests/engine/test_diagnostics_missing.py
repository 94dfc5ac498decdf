"""Missing parts and completeness (skelcore.diagnostics.missing_parts): shapes with
known skeletons, intact, stopped a radius short and with controlled defects; the hammer scan."""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from skelcore import Params, shapes, skeletonize
from skelcore.correspondence import densify_curve
from skelcore.curve import CurveSkeleton
from skelcore.diagnostics import missing_parts
from skelcore.errors import Cancelled
from skelcore.geometry import Normalization
from skelcore.metrics.coverage import coverage, coverage_tau

P = Params()


def normalized(sh):
    norm = Normalization.from_cloud(sh.cloud)
    return norm, norm.apply(sh.cloud)


def curve_of(sh, norm, keep=None):
    v, e = sh.curve_vertices, sh.curve_edges
    if keep is not None:
        idx = np.flatnonzero(keep)
        new = -np.ones(len(v), np.int64)
        new[idx] = np.arange(len(idx))
        e = new[e[keep[e].all(axis=1)]]
        v = v[idx]
    return CurveSkeleton.from_raw(norm.apply(v), e)


def test_true_and_contraction_skeletons_of_a_y_are_complete():
    sh = shapes.y_shape(2000, seed=1)
    norm, cloud = normalized(sh)
    skel, curve = skeletonize(sh.cloud, method="cao")
    for sk in (curve_of(sh, norm), norm.apply(sh.skeletal), curve.transformed(norm.apply), norm.apply(skel)):
        mp = missing_parts(cloud, sk, P)
        assert not mp.incomplete and mp.warnings() == []
        assert mp.completeness > 0.97 and not mp.missing.any()


def test_an_arm_removed_is_one_missing_part_where_the_arm_was():
    sh = shapes.y_shape(3000, seed=2)
    norm, cloud = normalized(sh)
    arm = np.array([0.0, 1.0, 0.0])  # the first arm points along +y
    on_arm = (sh.curve_vertices @ arm > 1e-9) & (np.abs(sh.curve_vertices[:, 0]) < 1e-9)
    mp = missing_parts(cloud, curve_of(sh, norm, ~on_arm), P, to_user=norm.invert)
    assert mp.incomplete and len(mp.counted) == 1
    part = mp.counted[0]
    # the flagged cloud points are the removed arm's (their true skeletal point lies on it, past the
    # other arms' radius 0.25 at the junction), most of them, and the region's numbers say so
    along = sh.skeletal @ arm
    assert along[mp.missing].min() > 0.25 and mp.missing.sum() > 0.7 * np.sum(along > 0.6)
    assert part.share == pytest.approx(mp.missing.mean()) and part.depth > 3
    assert np.allclose(part.centroid, sh.cloud[mp.missing].mean(axis=0), atol=1e-9)  # user units
    (w,) = mp.warnings()
    assert w.code == "incomplete" and f"{part.share:.1%}" in w.message and f"{mp.completeness:.3f}" in w.message
    # the counted regions' ids per point (the diagnostics' cloud array): the region where it counts, -1
    # elsewhere; with a second, uncounted region among the explained points to leave out
    region = mp.region.copy()
    region[np.flatnonzero(mp.region < 0)[:40]] = 1
    two = replace(mp, region=region, regions=[part, replace(part, id=1, counted=False)])
    for m in (mp, two):
        want = np.where(np.isin(m.region, [r.id for r in m.counted]), m.region, -1)
        assert m.missing_region().dtype == np.int64 and np.array_equal(m.missing_region(), want)
        assert np.array_equal(m.missing, want >= 0)
    assert (two.missing_region() == -1).sum() == (mp.region == -1).sum()


def test_stopping_a_radius_short_is_not_missing_but_half_a_cylinder_is():
    sh = shapes.cylinder(3000, seed=3)  # radius 0.5, length 4, flat caps; true curve along z
    norm, cloud = normalized(sh)
    z = sh.curve_vertices[:, 2]
    short = missing_parts(cloud, curve_of(sh, norm, (z >= 0.5 - 1e-9) & (z <= 3.5 + 1e-9)), P)
    assert not short.incomplete and all(not r.depth >= 1.0 for r in short.regions)
    half = missing_parts(cloud, curve_of(sh, norm, z <= 1.6 + 1e-9), P)
    assert half.incomplete and len(half.counted) == 1 and half.counted[0].depth > 2.5
    assert 0.3 < half.counted[0].share < 0.55 and half.completeness < 0.7
    # the missing points are the far end's
    assert sh.cloud[half.missing, 2].min() > 1.6


def test_a_torus_circle_is_complete_and_cut_open_by_a_third_is_not():
    sh = shapes.torus(3000, seed=4)
    norm, cloud = normalized(sh)
    assert not missing_parts(cloud, curve_of(sh, norm), P).incomplete
    ang = np.arctan2(sh.skeletal[:, 1], sh.skeletal[:, 0])
    cut = missing_parts(cloud, norm.apply(sh.skeletal[ang < np.pi / 3]), P)  # 2/3 of the ring kept
    assert cut.incomplete and cut.counted[0].depth > P.missing_depth


def test_a_skeleton_collapsed_into_the_hole_of_a_ring_is_incomplete():
    sh = shapes.torus(3000, seed=5)
    norm, cloud = normalized(sh)
    centre = np.repeat(sh.cloud.mean(axis=0)[None], 50, axis=0)  # one wide ball, the ring's outer half left
    mp = missing_parts(cloud, norm.apply(centre), P)
    assert mp.incomplete and mp.completeness < 0.6
    assert mp.counted[0].share >= P.missing_large_share


def test_completeness_and_per_point_flags_are_the_coverages():
    sh = shapes.t_shape(3000, seed=6)
    norm, cloud = normalized(sh)
    stem_cut = curve_of(sh, norm, sh.curve_vertices[:, 2] > -0.8)  # the stem's lower part removed
    tau = coverage_tau(cloud, P)
    pts, _ = densify_curve(stem_cut, tau / P.coverage_tau_factor)
    cov = coverage(cloud, np.vstack([pts, stem_cut.vertices]), P, tau)
    mp = missing_parts(cloud, stem_cut, P, tau=tau)
    assert mp.completeness == pytest.approx(cov.fraction)
    assert np.array_equal(mp.explained, cov.covered)
    assert np.all((mp.region == -1) == cov.covered)
    # given the evaluation's coverage, the same answer
    given = missing_parts(cloud, stem_cut, P, cov=cov)
    assert np.array_equal(given.region, mp.region) and given.incomplete == mp.incomplete
    assert mp.incomplete and np.all(sh.cloud[mp.missing, 2] < -0.8)


def test_skeletal_points_and_curves_get_the_same_verdict():
    sh = shapes.tree3(4000, seed=7)
    norm, cloud = normalized(sh)
    low = sh.curve_vertices[:, 2] < 2.6  # the twigs and the branches' upper ends removed
    curve = curve_of(sh, norm, low)
    pts, _ = densify_curve(curve, 0.002)
    a, b = missing_parts(cloud, curve, P), missing_parts(cloud, pts, P)
    assert a.incomplete and b.incomplete
    assert np.mean(a.missing == b.missing) > 0.98


def test_a_subsample_above_missing_max_points_keeps_the_verdict():
    sh = shapes.y_shape(6000, seed=8)
    norm, cloud = normalized(sh)
    no_arm = curve_of(sh, norm, ~((sh.curve_vertices[:, 1] > 1e-9) & (np.abs(sh.curve_vertices[:, 0]) < 1e-9)))
    full = missing_parts(cloud, no_arm, P)
    sub = missing_parts(cloud, no_arm, P.replace(missing_max_points=2000))
    assert full.subsample is None and sub.subsample == 2000 and sub.to_dict()["subsample"] == 2000
    assert full.incomplete and sub.incomplete and len(sub.counted) == len(full.counted) == 1
    assert np.mean(full.missing == sub.missing) > 0.97
    assert sub.counted[0].share == pytest.approx(full.counted[0].share, abs=0.02)
    assert "sampled cloud points" in sub.warnings()[0].message
    assert len(sub.region) == len(cloud)


def test_balls_of_points_outside_the_shape_explain_it_unless_left_out():
    # points far beside the T's stem: their balls reach it from outside; ``keep`` leaves them out
    sh = shapes.t_shape(3000, seed=11)
    norm, cloud = normalized(sh)
    bar = sh.skeletal[sh.skeletal[:, 2] > -0.2]
    beside = np.column_stack([np.zeros(20), np.full(20, 1.2), np.linspace(-2.0, -0.3, 20)])
    skel = norm.apply(np.vstack([bar, beside]))
    assert not missing_parts(cloud, skel, P).incomplete
    inside = np.arange(len(skel)) < len(bar)
    assert missing_parts(cloud, skel, P, keep=inside).incomplete


def test_no_skeleton_explains_nothing():
    sh = shapes.cylinder(1000, seed=9)
    norm, cloud = normalized(sh)
    mp = missing_parts(cloud, np.empty((0, 3)), P)
    assert mp.completeness == 0.0 and mp.incomplete and np.isinf(mp.counted[0].depth)


def test_to_dict_is_json_and_the_checkpoint_cancels():
    sh = shapes.y_shape(1500, seed=10)
    norm, cloud = normalized(sh)
    mp = missing_parts(cloud, curve_of(sh, norm, sh.curve_vertices[:, 1] < 0.5), P)
    doc = json.loads(json.dumps(mp.to_dict()))
    assert doc["incomplete"] is True and doc["n_missing_parts"] == 1 and doc["regions"][0]["counted"] is True
    assert set(doc["thresholds"]) >= {"missing_depth", "missing_min_share", "missing_large_share"}
    calls = []

    def stop(fraction):
        calls.append(fraction)
        if len(calls) > 2:
            raise Cancelled()

    with pytest.raises(Cancelled):
        missing_parts(cloud, norm.apply(sh.skeletal), P, checkpoint=stop)


def test_thresholds_are_one_documented_params_block():
    src = (Path(__file__).resolve().parents[2] / "skelcore" / "params.py").read_text()
    head = "# diagnostics: missing parts (docs/diagnostics.md)"
    assert src.count(head) == 1
    block = src.split(head)[1].split("\n\n")[0]
    names = [ln.split(":")[0].strip() for ln in block.strip().splitlines()]
    assert names and all(n.startswith("missing_") for n in names)
    assert {f for f in P.to_dict() if f.startswith("missing_")} == set(names)
    doc = Params.__doc__
    assert all(n in doc for n in names)
    with pytest.raises(ValueError):
        Params(missing_depth=0.0)
    with pytest.raises(ValueError):
        Params(missing_min_share=1.5)


@pytest.mark.parametrize("method", ["cao", "skelscope"])
def test_hammer_intact_is_complete_cut_handle_and_headless_are_not(scans, method):
    from skelcore import load_cloud

    cloud = load_cloud(scans / "hammer_4096.ply")
    norm = Normalization.from_cloud(cloud)
    c = norm.apply(cloud)
    skel, curve = skeletonize(cloud, method=method)
    y = curve.vertices[:, 1]  # the handle runs along y from -199 to about 80, the head beyond

    def cut(keep):
        idx = np.flatnonzero(keep)
        new = -np.ones(len(keep), np.int64)
        new[idx] = np.arange(len(idx))
        return CurveSkeleton.from_raw(curve.vertices[idx], new[curve.edges[keep[curve.edges].all(axis=1)]])

    assert not missing_parts(c, curve.transformed(norm.apply), P).incomplete
    assert not missing_parts(c, norm.apply(skel), P).incomplete
    half = missing_parts(c, cut(y > -60).transformed(norm.apply), P, to_user=norm.invert)
    assert half.incomplete and half.counted[0].centroid[1] < -60
    headless = missing_parts(c, norm.apply(skel[skel[:, 1] < 85]), P, to_user=norm.invert)
    assert headless.incomplete and headless.counted[0].centroid[1] > 85


def test_each_regions_farthest_point_is_the_last_of_its_largest_gaps():
    """``_last_largest`` (a region's deepest point) gives the last row of each label's largest value,
    as sorting by label then value gives it: gaps with many ties, one with NaN (sorted then)."""
    import sys

    mp = sys.modules["skelcore.diagnostics.missing_parts"]
    rng = np.random.default_rng(7)
    for nan in (False, True):
        label = rng.integers(0, 9, 5000)
        gap = rng.integers(0, 30, 5000).astype(float)
        if nan:
            gap[17] = np.nan
        order = np.lexsort((gap, label))
        want = np.zeros(9, np.int64)
        want[label[order]] = order
        np.testing.assert_array_equal(mp._last_largest(gap, label, 9), want)


@pytest.mark.parametrize("shape", ["ring", "lattice", "cloud"])
def test_the_depth_quantile_searched_near_its_rank_is_the_whole_searchs(shape):
    """``_quantile_distance``: the quantile of each point's distance to its nearest border point, the
    distances searched only near the quantile's rank, equals ``np.quantile`` of them all searched (the
    same bits), for several quantiles: a tube's end cap and its ring of border points, a lattice (many
    equal distances), a random cloud and border."""
    import sys

    from scipy.spatial import cKDTree

    mp = sys.modules["skelcore.diagnostics.missing_parts"]
    rng = np.random.default_rng(11)
    if shape == "ring":
        t = rng.random(6000) * 2 * np.pi
        pts = np.c_[np.cos(t), np.sin(t), rng.random(6000) * 5.0]
        border = pts[pts[:, 2] < 0.05]
    elif shape == "lattice":
        pts = np.stack(np.meshgrid(np.arange(30), np.arange(30), np.arange(6), indexing="ij"), -1).reshape(-1, 3) * 0.1
        border = pts[pts[:, 0] == 0]
    else:
        pts, border = rng.random((4000, 3)), rng.random((300, 3))
    assert len(pts) >= mp.QUANTILE_FEWEST and len(border) >= 2 * mp.QUANTILE_CENTRES
    whole = cKDTree(border).query(pts)[0]
    for q in (0.0, 0.5, 0.9, 0.95, 0.999, 1.0):
        assert mp._quantile_distance(border, pts, q) == np.quantile(whole, q)


def test_the_area_rules_kept_element_distances_are_the_trees(monkeypatch):
    """The area rule's cloud distances of a curve's elements (every ``step``-th) are kept per tree: a
    next curve's subsample, shifted by an edit, with elements moved by a last bit or added, gets the
    distances a fresh query gives, also with a weak hash (elements of one x share it: their bits decide)."""
    import importlib

    from scipy.spatial import cKDTree

    mp = importlib.import_module("skelcore.diagnostics.missing_parts")
    sc = importlib.import_module("skelcore.diagnostics.spur_cache")
    rng = np.random.default_rng(3)
    tree = cKDTree(rng.normal(size=(3000, 3)))
    first = rng.normal(size=(4000, 3)) * 0.5
    first[:40, 0] = 0.25
    moved = first.copy()
    moved[100:200, 1] = np.nextafter(moved[100:200, 1], 9.0)
    sets = [(first, 2), (first[1:], 2), (np.vstack([first[:50], rng.normal(size=(30, 3)), first[51:]]), 2),
            (moved, 2), (first, 3), (np.vstack([first[:40] + [0.0, 1e-3, 0.0], first]), 2)]

    def run(tree):
        monkeypatch.setattr(mp, "_SMALL_KEPT", [])
        for elements, step in sets:
            got = mp._element_distances(tree, elements, step)
            np.testing.assert_array_equal(got, tree.query(elements[::step])[0])
        assert any(k[0] is tree and len(k[3]) >= len(first) for k in mp._SMALL_KEPT)

    run(tree)
    monkeypatch.setattr(mp, "row_hash", lambda p: sc.row_words(p)[:, 0].copy())
    run(cKDTree(rng.normal(size=(3000, 3))))
