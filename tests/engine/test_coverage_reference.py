"""SkelScope's coverage (medial-ball reconstruction) and the comparison with a reference curve, on
shapes with known answers and against brute force."""

import numpy as np
import pytest

from skelcore import Params, evaluate, shapes
from skelcore.curve import CurveSkeleton
from skelcore.metrics.coverage import coverage, min_ball_excess
from skelcore.metrics.reference import compare_with_reference, graph_counts


def test_min_ball_excess_matches_brute_force():
    rng = np.random.default_rng(0)
    pts = rng.uniform(-1, 1, (700, 3))
    centers = rng.uniform(-1, 1, (900, 3))
    radii = rng.uniform(0.001, 0.3, 900) ** 2 * 3  # radii spanning several factor-2 classes
    brute = (np.linalg.norm(pts[:, None] - centers[None], axis=2) - radii[None]).min(axis=1)
    assert np.allclose(min_ball_excess(pts, centers, radii), brute, atol=1e-12)
    floored = min_ball_excess(pts, centers, radii, floor=0.05)
    above = brute > 0.05
    assert np.allclose(floored[above], brute[above]) and np.all(floored[~above] <= 0.05)


def test_gap_is_the_distance_to_the_union_of_balls():
    # one ball of radius 1 at the origin (its nearest cloud point is at distance 1); a cloud point
    # at distance 3 has gap 2
    cloud = np.array([[1.0, 0, 0], [0, 3.0, 0], [0, -1, 0]])
    cov = coverage(cloud, np.zeros((1, 3)), Params(coverage_slack=0.0), tau=0.1)
    assert cov.gap.tolist() == pytest.approx([0.0, 2.0, 0.0])
    assert cov.max_gap == pytest.approx(2.0) and cov.mean_gap == pytest.approx(2 / 3)
    assert cov.covered.tolist() == [True, False, True] and cov.fraction == pytest.approx(2 / 3)


def _curve_cov(sh, verts=None, edges=None):
    ev = evaluate(sh.cloud, curve=(sh.curve_vertices if verts is None else verts,
                                   sh.curve_edges if edges is None else edges))
    return ev.coverage_curve


def test_capped_cylinder_axis_and_torus_circle_cover_the_shape():
    cyl = shapes.cylinder(3000, seed=1)
    tor = shapes.torus(3000, seed=1)
    assert _curve_cov(cyl).fraction > 0.98  # docs/metrics.md 5.2: 1.0 on dense samples
    assert _curve_cov(tor).fraction > 0.98
    no_slack = evaluate(cyl.cloud, curve=(cyl.curve_vertices, cyl.curve_edges), params=Params(coverage_slack=0.0))
    assert 0.7 < no_slack.coverage_curve.fraction < 0.9  # the balls never reach the cap rims


def test_half_axis_or_centroid_cover_far_less():
    cyl = shapes.cylinder(3000, seed=2)
    half = len(cyl.curve_vertices) // 2
    half_cov = _curve_cov(cyl, cyl.curve_vertices[: half + 1], cyl.curve_edges[:half])
    assert 0.5 < half_cov.fraction < 0.7  # docs/metrics.md 5.2: about 0.6
    full = evaluate(cyl.cloud, cyl.skeletal)
    centroid = np.repeat(cyl.cloud.mean(axis=0)[None], len(cyl.cloud), 0)
    centroid += np.random.default_rng(0).normal(scale=1e-9, size=centroid.shape)
    collapsed = evaluate(cyl.cloud, centroid)
    assert full.coverage_skeletal.fraction > 0.9
    assert collapsed.coverage_skeletal.fraction < 0.35  # docs/metrics.md 5.2: about 0.2
    assert collapsed.coverage_skeletal.mean_gap > 5 * full.coverage_skeletal.mean_gap


def test_coverage_json_block_and_per_point_csv(tmp_path):
    sh = shapes.y_shape(1500, seed=3)
    ev = evaluate(sh.cloud, sh.skeletal, (sh.curve_vertices, sh.curve_edges))
    doc = ev.to_json_dict()
    for kind in ("skeletal", "curve"):
        assert set(doc["coverage"][kind]) == {"fraction", "mean_gap", "max_gap"}
    assert doc["coverage"]["slack"] == 0.5
    files = ev.write_per_point(str(tmp_path / "pp"))
    assert str(tmp_path / "pp_cloud.csv") in files
    rows = np.genfromtxt(tmp_path / "pp_cloud.csv", delimiter=",", names=True)
    assert len(rows) == len(sh.cloud)
    assert np.allclose(rows["gap_curve"], ev.coverage_curve.gap)
    assert rows["covered_skeletal"].mean() == pytest.approx(doc["coverage"]["skeletal"]["fraction"])


def test_tau_is_twice_the_median_spacing():
    from scipy.spatial import cKDTree

    from skelcore.metrics.coverage import coverage_tau

    pts = np.random.default_rng(1).random((500, 3))
    d, _ = cKDTree(pts).query(pts, k=2)
    assert coverage_tau(pts) == pytest.approx(2 * np.median(d[:, 1]))
    assert coverage_tau(pts, Params(coverage_tau_factor=3.0)) == pytest.approx(3 * np.median(d[:, 1]))


def test_graph_counts():
    # a triangle (one cycle) with a tail, plus a separate segment and an isolated vertex
    v = np.random.default_rng(0).random((8, 3))
    e = [[0, 1], [1, 2], [2, 0], [2, 3], [4, 5]]
    c = graph_counts(CurveSkeleton.from_raw(v, e))
    assert c == {"junctions": 1, "endpoints": 3, "components": 4, "cycles": 1}


def test_reference_comparison_identity_shift_and_half():
    sh = shapes.cylinder(1000, seed=4)
    curve = CurveSkeleton.from_raw(sh.curve_vertices, sh.curve_edges)
    same = compare_with_reference(curve, curve, tau=0.01)
    assert same.chamfer == 0 and same.hausdorff == 0 and same.f1 == 1.0
    shifted = compare_with_reference(curve.transformed(lambda v: v + [0.5, 0, 0]), curve, tau=0.01)
    assert shifted.chamfer == pytest.approx(0.5) and shifted.hausdorff == pytest.approx(0.5)
    assert shifted.precision == 0 and shifted.recall == 0 and shifted.f1 == 0
    n = len(sh.curve_vertices)
    half = CurveSkeleton.from_raw(sh.curve_vertices[: n // 2 + 1], sh.curve_edges[: n // 2])
    r = compare_with_reference(half, curve, tau=0.01)
    assert r.precision == 1.0 and r.recall == pytest.approx(0.5, abs=0.03)
    assert r.hausdorff == pytest.approx(sh.curve_vertices[-1, 2] - sh.curve_vertices[n // 2, 2], rel=0.01)
    assert r.endpoints == (2, 2) and r.components == (1, 1) and r.cycles == (0, 0)


def test_reference_block_in_json():
    sh = shapes.torus(1500, seed=5)
    ev = evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges),
                  reference_curve=(sh.curve_vertices, sh.curve_edges))
    ref = ev.to_json_dict()["reference"]
    assert set(ref) >= {"chamfer", "hausdorff", "precision", "recall", "f1", "junctions", "endpoints",
                        "components", "cycles"}
    assert ref["cycles"] == [1, 1] and ref["components"] == [1, 1] and ref["f1"] == 1.0


@pytest.mark.parametrize(
    "change", [{"coverage_slack": -0.1}, {"coverage_tau_factor": 0.0}, {"frame_extent_ratio": 1.0},
               {"frame_inside_fraction": 1.5}, {"collapse_extent": 0.0}],
)
def test_new_params_are_validated(change):
    with pytest.raises(ValueError, match=next(iter(change))):
        Params(**change)
    assert Params().coverage_slack == 0.5 and Params().coverage_tau_factor == 2.0
