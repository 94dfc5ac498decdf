"""Curve length and skeletal points outside the shape (skelcore/diagnostics/outside.py)."""

from __future__ import annotations

import numpy as np
import pytest
from diagnostics_helpers import attach_path, normalized

from skelcore import Params, shapes
from skelcore.diagnostics import find_curve_defects, find_outside
from skelcore.geometry import Normalization


@pytest.mark.parametrize("make", [shapes.y_shape, shapes.t_shape, shapes.torus, shapes.genus2, shapes.tree3])
def test_true_skeleton_is_inside(make):
    s = shapes.with_noise(make(n=3000, seed=1), 0.03, seed=1)
    c, curve, samples, beta = normalized(s.cloud, s.curve_vertices, s.curve_edges)
    r = find_outside(c, curve, samples=samples, sample_boundedness=beta)
    assert r.warnings() == []
    assert r.length_share < 0.01 and np.all(r.branch_radii < 0.5)


def test_length_outside_is_measured_along_the_edge():
    """A straight edge from the cylinder's axis out to 2 units sideways (radius 0.5): 1.5 of its 2
    units lie outside. The edge holds several unbounded samples; walked every half voxel, its length
    outside is 1.5 within a voxel or two, and nothing else is outside."""
    s = shapes.cylinder(n=4000, seed=2)
    v, e, ids = attach_path(s.curve_vertices, s.curve_edges, 10, [2.0, 0.0, 2.0], 1)
    c, curve, samples, beta = normalized(s.cloud, v, e)
    r = find_outside(c, curve, samples=samples, sample_boundedness=beta)
    scale = 1.6 / 4.0  # the normalization: the longest side (4) becomes 1.6
    spur = int(np.flatnonzero((curve.edges == [10, ids[0]]).all(axis=1))[0])
    assert r.edge_outside_length[spur] == pytest.approx(1.5 * scale, abs=2 * r.voxel_size)
    assert np.count_nonzero(r.edge_outside_length) == 1
    assert r.length_share == pytest.approx(r.edge_outside_length[spur] / curve.edge_lengths().sum())
    assert r.vertex_flag.sum() == 2
    assert r.depth.max() == pytest.approx(1.5 * scale / r.radius, rel=0.1)
    (w,) = r.warnings()
    assert w.code == "outside"
    # the same edge in the air but its samples given as bounded: nothing is outside
    r = find_outside(c, curve, samples=samples, sample_boundedness=np.ones_like(beta))
    assert r.warnings() == [] and not r.edge_outside_length.any()


def test_unbounded_samples_inside_the_voxels_are_not_outside():
    """Boundedness can be low inside thin or partly scanned parts; a sample whose stretch lies in
    inside voxels is not outside (the apple tree's twigs)."""
    s = shapes.cylinder(n=4000, seed=3)
    c, curve, samples, beta = normalized(s.cloud, s.curve_vertices, s.curve_edges)
    low = np.where(samples.edge == 7, 0.2, beta)
    r = find_outside(c, curve, samples=samples, sample_boundedness=low)
    assert not r.sample_outside.any()
    assert not r.edge_outside_length.any() and r.warnings() == []


def test_one_edge_through_the_air_is_flagged_while_the_boundedness_stays_high():
    """The T's stem tip joined to a bar end by a straight edge through the air."""
    s = shapes.t_shape(n=4000, seed=3)
    v = s.curve_vertices
    a, b = int(np.argmin(v[:, 2])), int(np.argmin(v[:, 0]))
    v2, e2, ids = attach_path(v, s.curve_edges, a, v[b], 1, to=b)
    c, curve, samples, beta = normalized(s.cloud, v2, e2)
    r = find_outside(c, curve, samples=samples, sample_boundedness=beta)
    (w,) = r.warnings()
    assert w.code == "outside"
    e_new = np.flatnonzero((curve.edges == sorted([a, b])).all(axis=1))
    assert r.edge_outside_length[e_new[0]] > 0.5 * curve.edge_lengths()[e_new[0]]
    assert r.depth.max() > 1
    # the overall curve boundedness stays high: one edge is not much of the length
    assert np.mean(beta > 0.75) > 0.6


@pytest.mark.parametrize("out", [1.0, 3.0])
def test_branch_poking_out_is_flagged(out):
    s = shapes.tree3(n=4000, seed=4)
    v = s.curve_vertices
    trunk = np.flatnonzero((np.abs(v[:, 0]) < 1e-12) & (np.abs(v[:, 1]) < 1e-12) & (v[:, 2] > 0.6) & (v[:, 2] < 1.4))
    a = int(trunk[0])
    v2, e2, ids = attach_path(v, s.curve_edges, a, v[a] + [0, (1 + out) * 0.22, 0], 4)
    c, curve, samples, beta = normalized(s.cloud, v2, e2)
    r = find_outside(c, curve, samples=samples, sample_boundedness=beta)
    assert [w.code for w in r.warnings()] == ["outside"]
    bad = r.defective_branches()
    assert r.branches.vertex_branch[ids[-1]] in bad


def test_skeletal_points_outside_in_one_cluster():
    s = shapes.t_shape(n=4000, seed=5)
    norm = Normalization.from_cloud(s.cloud)
    c = norm.apply(s.cloud)
    skel = norm.apply(s.skeletal)
    beta = np.ones(len(skel))
    # scattered: 5 % of the points, far apart from each other -> no warning
    rng = np.random.default_rng(5)
    scattered = rng.choice(len(skel), 200, replace=False)
    skel_a = skel.copy()
    away = rng.normal(size=(200, 3))
    skel_a[scattered] += 3.0 * away / np.linalg.norm(away, axis=1, keepdims=True)
    beta_a = beta.copy()
    beta_a[scattered] = 0.1
    r = find_outside(c, None, skeletal=skel_a, skeletal_boundedness=beta_a)
    assert r.skeletal_outside.sum() == 200 and r.skeletal_cluster_share < 0.01 and r.warnings() == []
    # one cluster of 8 % of the points, 1 unit outside the bar
    skel_b = skel.copy()
    group = rng.choice(len(skel), 320, replace=False)
    skel_b[group] = norm.apply(np.array([[0.0, 1.5, 0.0]])) + rng.normal(scale=0.01, size=(320, 3))
    beta_b = beta.copy()
    beta_b[group] = 0.05
    r = find_outside(c, None, skeletal=skel_b, skeletal_boundedness=beta_b)
    assert r.skeletal_cluster_share == pytest.approx(0.08)
    (w,) = r.warnings()
    assert w.code == "outside" and "8.0%" in w.message
    assert r.to_dict()["skeletal"]["largest_cluster_share"] == pytest.approx(0.08)


def test_curve_defects_share_one_decomposition_and_flag_branches():
    s = shapes.t_shape(n=3000, seed=6)
    v = s.curve_vertices
    a = int(np.argmin(np.abs(v[:, 0] - 1.0) + np.abs(v[:, 2])))
    v2, e2, ids = attach_path(v, s.curve_edges, a, v[a] + [0, 0.1, 0], 1)
    c, curve, samples, beta = normalized(s.cloud, v2, e2)
    d = find_curve_defects(c, curve, samples=samples, sample_boundedness=beta)
    assert d.spurs.branches is d.cycles.branches is d.outside.branches
    assert [w.code for w in d.warnings()] == ["spurious_branches"]
    spur = d.branches.vertex_branch[ids[-1]]
    assert d.branches.flags[spur] == ("spurious_branches",)
    assert d.vertex_flags()["spurious_branches"][ids].all()
    out = d.to_dict()
    assert out["spurious_branches"]["spurious"] == 1 and out["cycles"]["missing"] == 0
    assert set(d.timings) == {"branches", "interior", "spurs", "cycles", "outside", "components", "along_surface"}


def test_cancel_reaches_every_diagnostic():
    from skelcore import Cancelled

    s = shapes.torus(n=3000, seed=7)
    c, curve, samples, beta = normalized(s.cloud, s.curve_vertices, s.curve_edges)
    calls = []

    def stop_after(n):
        def check(f):
            calls.append(f)
            if len(calls) > n:
                raise Cancelled("stop")
        return check

    with pytest.raises(Cancelled):
        find_curve_defects(c, curve, samples=samples, sample_boundedness=beta, checkpoint=stop_after(3))
    calls.clear()
    find_curve_defects(c, curve, samples=samples, sample_boundedness=beta, checkpoint=stop_after(10**6))
    assert calls[-1] == pytest.approx(1.0) and len(calls) > 10
    assert all(b >= a - 1e-12 for a, b in zip(calls, calls[1:]))  # progress never goes back


@pytest.mark.parametrize("change", [{"spur_reach": 0}, {"spur_unique": 1.5}, {"cycles_voxels": 0},
                                    {"outside_min_radii": -1}, {"spur_min_points": -1}])
def test_diagnostic_params_are_validated(change):
    with pytest.raises(ValueError, match=next(iter(change))):
        Params(**change)


def test_hammer_with_our_skeletonizers_has_no_defect(scans):
    import skelcore

    cloud = skelcore.load_cloud(str(scans / "hammer_4096.ply"))
    for method in ("cao", "skelscope"):
        _, raw = skelcore.skeletonize(cloud, method=method)
        c, curve, samples, beta = normalized(cloud, raw.vertices, raw.edges)
        d = find_curve_defects(c, curve, samples=samples, sample_boundedness=beta)
        assert d.warnings() == [], (method, [w.message for w in d.warnings()])
        assert d.branches.kind.count("terminal") == 3 and d.cycles.shape_tunnels == 0


def test_evaluate_tests_a_given_skeletal_set_for_points_outside(tmp_path):
    """The "skeletal outside" stage (no curve needed): the T's true skeletal set is inside; the same
    set with 10 % of its points moved together above the bar gets ``outside``, each moved point is
    flagged in the per-element array and the per-point CSV, and the flags survive a save and load."""
    import csv

    import skelcore
    from skelcore.io.evaluation_files import load_evaluation, save_evaluation

    s = shapes.t_shape(n=4000, seed=5)
    ev = skelcore.evaluate(s.cloud, s.skeletal)
    assert "skeletal outside" in ev.timings
    assert [w for w in ev.warnings if w.code == "outside"] == []
    assert ev.diagnostics.summary["skeletal_outside"]["largest_cluster_share"] < 0.01

    moved = s.skeletal.copy()
    group = np.argsort(moved[:, 0])[-len(moved) // 10:]  # one end of the bar
    moved[group] += np.array([0.0, 0.0, 0.5 * np.ptp(s.cloud, axis=0).max()])
    ev = skelcore.evaluate(s.cloud, moved)
    (w,) = [w for w in ev.warnings if w.code == "outside"]
    assert "skeletal points lie outside the shape in one cluster" in w.message
    flags = ev.diagnostics.arrays["skeletal_point_defects"]
    assert set(np.flatnonzero(flags)) <= set(group.tolist()) and np.count_nonzero(flags) > 0.9 * len(group)

    path = [p for p in ev.write_per_point(str(tmp_path / "t")) if p.endswith("_skeletal.csv")][0]
    with open(path) as fh:
        rows = list(csv.DictReader(fh))
    assert {int(r["index"]) for r in rows if r["defects"] == "outside"} == set(np.flatnonzero(flags).tolist())
    save_evaluation(ev, tmp_path / "t.npz", tmp_path / "t.json")
    back = load_evaluation(tmp_path / "t.npz", tmp_path / "t.json")
    np.testing.assert_array_equal(back.diagnostics.arrays["skeletal_point_defects"], flags)
    assert back.diagnostics.summary["skeletal_outside"] == ev.diagnostics.summary["skeletal_outside"]


def test_a_short_far_spur_is_outside_by_its_reach_alone():
    """A tube's axis with one spur reaching 10 radii out (a few % of the curve's length): ``outside``
    by the per-branch reach, which needs no boundedness (it stands on an open surface); the axis alone
    reaches nowhere (docs/diagnostics.md "Outside")."""
    from diagnostics_helpers import attach_path

    from skelcore.diagnostics import find_outside

    s = shapes.cylinder(n=3000, radius=0.25, length=4.0, seed=2)
    v, e, ids = attach_path(s.curve_vertices, s.curve_edges, 10, s.curve_vertices[10] + [2.75, 0, 0], 2)
    c, curve, samples, beta = normalized(s.cloud, v, e)
    found = find_outside(c, curve, samples=samples, sample_boundedness=beta)
    spur = found.branches.vertex_branch[ids[-1]]
    assert list(found.far_branches()) == [spur] and found.reach[spur] > 8
    assert spur in found.defective_branches(reach_only=True)
    (w,) = found.warnings(reach_only=True)
    assert "reaches more than 8 local radii" in w.message and "nan" not in w.message
    c, curve, samples, beta = normalized(s.cloud, s.curve_vertices, s.curve_edges)
    axis = find_outside(c, curve, samples=samples, sample_boundedness=beta)
    assert not len(axis.far_branches()) and axis.warnings(reach_only=True) == [] and axis.warnings() == []


def test_on_a_traced_neuron_the_coarse_voxels_leave_only_the_reach_test():
    """A traced neuron's neurites are thinner than the interior's voxels (several local radii), which
    cannot tell a neurite from a few radii beside it: the length test stands down (``unchecked`` says
    so), and the traced skeleton with every sample unbounded (what a one-sided scan gives) is not
    ``outside``, where the voxels alone flagged it; a branch reaching far into the air still is, by its
    reach (docs/diagnostics.md "Outside")."""
    from skelcore.benchmark.neurons import MeshSampler, load_neuron
    from skelcore.curve import CurveSkeleton
    from skelcore.metrics.curve_sampling import sample_curve

    neuron = load_neuron("1734350908")
    sk = neuron.skeleton
    radius = np.asarray(sk.radius, float)
    cloud = MeshSampler(neuron.mesh, sk.vertices, radius).sample(6000, np.random.default_rng(0)).points
    p = Params()
    norm = Normalization.from_cloud(cloud, p.normalize_by, p.normalized_size)

    def outside(v: np.ndarray, e: np.ndarray, params: Params = p):
        curve = CurveSkeleton.from_raw(norm.apply(v), e)
        samples = sample_curve(curve, params.curve_samples, collinear_cos=params.collinear_cos)
        return find_outside(norm.apply(cloud), curve, samples=samples, sample_boundedness=np.zeros(len(samples)),
                            params=params)

    v, e = np.asarray(sk.vertices, float), np.asarray(sk.edges, np.int64)
    intact = outside(v, e)
    assert not intact.length_test and intact.voxel_size > p.outside_voxel_radii * intact.radius
    assert intact.warnings() == [] and "outside_voxel_radii" in intact.unchecked
    assert outside(v, e, Params(outside_voxel_radii=100.0)).warnings()  # the voxels alone: a false alarm
    tip = int(np.argmax(v[:, 0]))
    v2, e2, ids = attach_path(v, e, tip, v[tip] + [60.0 * float(np.median(radius)), 0, 0], 6)
    far = outside(v2, e2)
    (w,) = far.warnings()
    assert far.branches.vertex_branch[ids[-1]] in far.far_branches() and "reaches more than 8 local radii" in w.message
