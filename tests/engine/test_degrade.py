"""skelcore.skeleton.degrade: noise models, downsamplers and the paper's voxel-grid counts."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore import shapes
from skelcore.skeleton.degrade import add_noise, farthest_point_downsample, random_downsample, voxel_grid_average
from skelcore.errors import SkelInputError


@pytest.fixture
def cloud() -> np.ndarray:
    return shapes.cylinder(4000, seed=3).cloud + np.array([2.0, -1.0, 0.5])


def test_reference_noise_sigma_is_ratio_times_each_coordinate(cloud):
    noisy = add_noise(cloud, 0.05, seed=1)
    z = (noisy - cloud) / (0.05 * cloud)  # standard normal draws when sigma = 0.05 * x
    assert abs(z.mean()) < 0.05
    assert z.std() == pytest.approx(1.0, abs=0.03)


def test_reference_noise_leaves_a_point_at_the_origin_in_place():
    pts = np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]])
    noisy = add_noise(pts, 0.1, seed=0)
    np.testing.assert_array_equal(noisy[0], 0.0)
    assert not np.allclose(noisy[1], pts[1])


def test_isotropic_noise_sigma_is_ratio_times_rms_distance_to_box_centre(cloud):
    centre = (cloud.min(axis=0) + cloud.max(axis=0)) / 2
    rms = np.sqrt(np.mean(np.sum((cloud - centre) ** 2, axis=1)))
    delta = add_noise(cloud, 0.02, model="isotropic", seed=2) - cloud
    assert delta.std() == pytest.approx(0.02 * rms, rel=0.03)
    # same for every axis: frame independent
    np.testing.assert_allclose(delta.std(axis=0), 0.02 * rms, rtol=0.06)


def test_isotropic_noise_does_not_depend_on_where_the_origin_is(cloud):
    a = add_noise(cloud, 0.05, model="isotropic", seed=5) - cloud
    b = add_noise(cloud + 100.0, 0.05, model="isotropic", seed=5) - (cloud + 100.0)
    np.testing.assert_allclose(a, b, atol=1e-9)


def test_the_same_seed_repeats_every_random_degradation(cloud):
    np.testing.assert_array_equal(add_noise(cloud, 0.05, seed=7), add_noise(cloud, 0.05, seed=7))
    assert not np.array_equal(add_noise(cloud, 0.05, seed=7), add_noise(cloud, 0.05, seed=8))
    np.testing.assert_array_equal(random_downsample(cloud, 100, seed=3)[1], random_downsample(cloud, 100, seed=3)[1])
    np.testing.assert_array_equal(
        farthest_point_downsample(cloud, 50, seed=3)[1], farthest_point_downsample(cloud, 50, seed=3)[1]
    )


def test_random_downsample_keeps_n_distinct_rows_in_input_order(cloud):
    pts, idx = random_downsample(cloud, 1024, seed=0)
    assert pts.shape == (1024, 3)
    assert len(np.unique(idx)) == 1024 and np.all(np.diff(idx) > 0)
    np.testing.assert_array_equal(pts, cloud[idx])


def test_farthest_point_downsample_spreads_points_evenly(cloud):
    pts, idx = farthest_point_downsample(cloud, 200, seed=0)
    np.testing.assert_array_equal(pts, cloud[idx])
    assert len(np.unique(idx)) == 200
    from scipy.spatial import cKDTree

    # covering radius of FPS is far smaller than that of a random subset of the same size
    fps_cover = cKDTree(pts).query(cloud)[0].max()
    rnd_cover = cKDTree(random_downsample(cloud, 200, seed=0)[0]).query(cloud)[0].max()
    assert fps_cover < 0.8 * rnd_cover


def test_voxel_grid_average_is_the_mean_of_each_cell():
    pts = np.array([[0.0, 0, 0], [0.5, 0.5, 0.5], [1.5, 0, 0], [1.9, 0.2, 0], [0.0, 3.0, 0]])
    centres, voxel = voxel_grid_average(pts, 1.0)
    assert len(centres) == 3
    np.testing.assert_allclose(centres[voxel[0]], [0.25, 0.25, 0.25])
    np.testing.assert_allclose(centres[voxel[2]], [1.7, 0.1, 0.0])
    assert voxel[0] == voxel[1] and voxel[2] == voxel[3] and len(set(voxel)) == 3


def test_voxel_grid_boundary_in_decimal_is_not_split_by_binary_rounding():
    # (0.3 - 0) / 0.1 is 2.9999999999999996 in binary; the point belongs to cell 3 with 0.35
    assert 0.3 / 0.1 < 3
    pts = np.array([[0.0, 0, 0], [0.3, 0, 0], [0.35, 0, 0], [0.29, 0, 0]])
    centres, voxel = voxel_grid_average(pts, 0.1)
    assert voxel[1] == voxel[2]
    assert voxel[1] != voxel[3]


def test_voxel_grid_counts_on_the_papers_apple_tree(scans):
    from skelcore.io import load_cloud

    tree = load_cloud(scans / "apple_tree_22367.ply")
    assert len(voxel_grid_average(tree, 0.02)[0]) == 8936
    assert len(voxel_grid_average(tree, 0.05)[0]) == 1730


@pytest.mark.parametrize(
    "call",
    [
        lambda c: random_downsample(c, 0),
        lambda c: random_downsample(c, 10**6),
        lambda c: farthest_point_downsample(c, 2.5),
        lambda c: voxel_grid_average(c, 0.0),
        lambda c: add_noise(c, -0.1),
    ],
)
def test_bad_arguments_raise_input_errors(cloud, call):
    with pytest.raises(SkelInputError):
        call(cloud)


def test_unknown_noise_model_fails_loudly(cloud):
    with pytest.raises(ValueError, match="noise model"):
        add_noise(cloud, 0.05, model="salt")


def test_voxel_grid_cells_come_in_matlabs_linear_index_order_x_fastest():
    # cells (i, j, k) = (1,0,0), (0,1,0), (0,0,1), (0,0,0): MATLAB's order is by i + nx (j + ny k)
    pts = np.array([[1.5, 0.5, 0.5], [0.5, 1.5, 0.5], [0.5, 0.5, 1.5], [0.5, 0.5, 0.5], [1.5, 1.5, 1.5]])
    pts = np.vstack([pts, [[0.0, 0.0, 0.0], [2.0, 2.0, 2.0]]])  # fix the grid's corner and extent
    centres, voxel = voxel_grid_average(pts, 1.0)
    ijk = np.floor(centres).astype(int)
    linear = ijk[:, 0] + 3 * (ijk[:, 1] + 3 * ijk[:, 2])
    assert np.all(np.diff(linear) > 0)
    np.testing.assert_array_equal(np.floor(centres[voxel]), np.floor(pts))  # each row's own cell
