"""skelcore.skeleton, method "skelscope": Laplacian contraction + our curve extraction on shapes with
known skeletons (the toolbox's method "cao": tests/engine/test_skeletonize_cao.py)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from skelcore import shapes
from skelcore.curve import CurveSkeleton
from skelcore.errors import Cancelled, SkelInputError
from skelcore.geometry import Normalization
from skelcore.skeleton import SkeletonizeParams
from skelcore.skeleton import skeletonize as _skeletonize


def skeletonize(cloud, *args, **kwargs):
    return _skeletonize(cloud, *args, method="skelscope", **kwargs)


def _components(curve: CurveSkeleton) -> int:
    n = curve.n_vertices
    e = curve.edges
    adj = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    return int(connected_components(adj, directed=False)[0])


@pytest.fixture(scope="module")
def cylinder_result():
    shape = shapes.cylinder(3000, seed=1)
    return shape, skeletonize(shape.cloud)


@pytest.fixture(scope="module")
def torus_result():
    shape = shapes.torus(3000, seed=2)
    return shape, skeletonize(shape.cloud)


@pytest.fixture(scope="module")
def y_result():
    shape = shapes.y_shape(5000, seed=3)
    return shape, skeletonize(shape.cloud)


def test_cylinder_curve_is_a_single_path(cylinder_result):
    shape, (skeletal, curve) = cylinder_result
    deg = curve.degrees()
    assert curve.n_vertices >= 10
    assert deg.max() <= 2
    assert _components(curve) == 1
    assert curve.n_edges == curve.n_vertices - 1  # connected and acyclic
    # the path runs along the axis for most of the length
    assert np.ptp(curve.vertices[:, 2]) > 0.7 * 4.0
    assert np.all(np.hypot(curve.vertices[:, 0], curve.vertices[:, 1]) < 0.5)


def test_torus_curve_is_a_single_cycle(torus_result):
    shape, (skeletal, curve) = torus_result
    deg = curve.degrees()
    assert np.all(deg == 2)
    assert _components(curve) == 1
    assert curve.n_edges == curve.n_vertices
    # every vertex inside the tube (radius 0.3 around the core circle of radius 1)
    ring = np.hypot(np.hypot(curve.vertices[:, 0], curve.vertices[:, 1]) - 1.0, curve.vertices[:, 2])
    assert ring.max() < 0.3


def test_y_shape_curve_has_exactly_one_junction_and_three_ends(y_result):
    shape, (skeletal, curve) = y_result
    deg = curve.degrees()
    assert _components(curve) == 1
    assert curve.n_edges == curve.n_vertices - 1
    assert np.count_nonzero(deg >= 3) == 1
    assert np.count_nonzero(deg == 1) == 3
    junction = curve.vertices[np.flatnonzero(deg >= 3)[0]]
    assert np.linalg.norm(junction) < 0.25  # the arms' radius; the true junction is the origin


def test_skeletal_points_correspond_pointwise_and_stay_inside(cylinder_result, torus_result):
    for shape, (skeletal, _curve), radius in ((*cylinder_result, 0.5), (*torus_result, 0.3)):
        assert skeletal.shape == shape.cloud.shape
        # distance of each contracted point to the true medial curve, relative to the tube radius
        from scipy.spatial import cKDTree

        dense = shape.skeletal
        d, _ = cKDTree(dense).query(skeletal)
        assert np.median(d) < 0.25 * radius
        assert np.quantile(d, 0.99) < radius


def test_skeletal_points_are_bounded_by_the_rays_estimator(cylinder_result):
    from skelcore.metrics.boundedness import boundedness
    from skelcore.params import Params

    shape, (skeletal, _curve) = cylinder_result
    norm = Normalization.from_cloud(shape.cloud)
    pick = np.arange(0, len(skeletal), 10)
    beta = boundedness(norm.apply(shape.cloud), norm.apply(skeletal[pick]), params=Params())
    assert np.mean(beta > 0.75) > 0.95


def test_result_is_in_user_units_and_invariant_to_scale_and_shift():
    shape = shapes.cylinder(1500, seed=4)
    sk1, c1 = skeletonize(shape.cloud)
    moved = shape.cloud * 250.0 + np.array([1000.0, -20.0, 3.0])
    sk2, c2 = skeletonize(moved)
    np.testing.assert_allclose(sk2, sk1 * 250.0 + np.array([1000.0, -20.0, 3.0]), atol=1e-6 * 250)
    assert c1.n_vertices == c2.n_vertices
    np.testing.assert_array_equal(c1.edges, c2.edges)


def test_same_input_gives_identical_output():
    cloud = shapes.torus(1500, seed=5).cloud
    sk1, c1 = skeletonize(cloud)
    sk2, c2 = skeletonize(cloud)
    np.testing.assert_array_equal(sk1, sk2)
    np.testing.assert_array_equal(c1.vertices, c2.vertices)
    np.testing.assert_array_equal(c1.edges, c2.edges)


def test_progress_rises_to_one_and_names_the_stages():
    seen: list[tuple[float, str]] = []
    skeletonize(shapes.cylinder(1200, seed=6).cloud, progress=lambda f, s: seen.append((f, s)))
    fractions = [f for f, _ in seen]
    assert fractions == sorted(fractions)
    assert fractions[-1] == pytest.approx(1.0)
    assert {"laplacian", "contraction", "curve"} <= {s for _, s in seen}


def test_cancel_stops_at_the_next_checkpoint():
    calls = {"n": 0}

    def cancel() -> bool:
        calls["n"] += 1
        return calls["n"] > 3

    with pytest.raises(Cancelled):
        skeletonize(shapes.cylinder(1200, seed=7).cloud, cancel=cancel)
    assert calls["n"] == 4


def test_info_reports_iterations_and_a_shrinking_ring_ratio():
    _sk, _c, info = skeletonize(shapes.cylinder(1200, seed=8).cloud, return_info=True)
    assert 1 <= info.iterations <= SkeletonizeParams().max_iterations
    assert info.ring_ratios[0] == 1.0 and info.ring_ratios[-1] < 0.6
    assert info.n_samples > 5


@pytest.mark.parametrize(
    "cloud, message",
    [
        (np.zeros((5, 3)), "at least 10 distinct points"),
        (np.full((50, 3), np.nan), "NaN"),
        (np.zeros((50, 2)), "N x 3"),
    ],
)
def test_bad_clouds_raise_one_line_input_errors(cloud, message):
    with pytest.raises(SkelInputError, match=message):
        skeletonize(cloud)


def test_invalid_parameters_fail_loudly():
    with pytest.raises(ValueError, match="contraction_scale"):
        SkeletonizeParams(contraction_scale=0.5)
    with pytest.raises(ValueError, match="unknown"):
        SkeletonizeParams().replace(no_such_thing=1)


def test_real_hammer_gives_a_connected_tree_inside_the_scan(scans):
    from skelcore.io import load_cloud
    from skelcore.metrics.boundedness import boundedness
    from skelcore.params import Params

    cloud = load_cloud(scans / "hammer_4096.ply")
    skeletal, curve = skeletonize(cloud)
    assert _components(curve) == 1
    assert curve.n_edges == curve.n_vertices - 1
    assert 1 <= np.count_nonzero(curve.degrees() >= 3) <= 2  # handle meets head
    norm = Normalization.from_cloud(cloud)
    beta = boundedness(norm.apply(cloud), norm.apply(curve.vertices), params=Params())
    assert np.mean(beta > 0.75) > 0.9


def test_sparse_tree_curve_stays_connected(scans):
    # thin branches of the 1730-point tree hold balls of one or two points: they must not be cut
    from skelcore.skeleton.degrade import voxel_grid_average
    from skelcore.io import load_cloud

    tree = voxel_grid_average(load_cloud(scans / "apple_tree_22367.ply"), 0.05)[0]
    _skeletal, curve = skeletonize(tree)
    assert _components(curve) == 1
    assert np.count_nonzero(curve.degrees() == 1) >= 6  # the tree's branch tips
