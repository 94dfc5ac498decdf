"""The generated shapes with known skeletons (skelcore/shapes.py): tube unions, noise."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from skelcore import shapes


def _dense_curve(s: shapes.Shape, step: float = 0.005) -> np.ndarray:
    v, e = s.curve_vertices, s.curve_edges
    pts = []
    for a, b in e:
        m = max(2, int(np.ceil(np.linalg.norm(v[b] - v[a]) / step)) + 1)
        pts.append(v[a] + np.linspace(0, 1, m)[:, None] * (v[b] - v[a]))
    return np.vstack(pts)


def _cycle_rank(s: shapes.Shape) -> int:
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    nv, e = len(s.curve_vertices), s.curve_edges
    g = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(nv, nv))
    return len(e) - nv + connected_components(g, directed=False)[0]


@pytest.mark.parametrize(
    "make, degrees, rank",
    [
        (shapes.t_shape, {1: 3, 3: 1}, 0),
        (shapes.genus2, {4: 1}, 2),
        (shapes.tree3, {1: 5, 3: 3}, 0),
    ],
)
def test_tube_shapes_have_their_skeleton_graph(make, degrees, rank):
    s = make(n=3000, seed=1)
    deg = np.bincount(s.curve_edges.ravel())
    assert {d: int((deg == d).sum()) for d in degrees} == degrees
    assert int(((deg != 2) & (deg > 0)).sum()) == sum(degrees.values())
    assert _cycle_rank(s) == rank
    assert s.cloud.shape == s.skeletal.shape == (3000, 3)


@pytest.mark.parametrize("make", [shapes.t_shape, shapes.genus2, shapes.tree3])
def test_tube_shape_points_lie_on_the_union_boundary(make):
    """Each cloud point lies on its own tube (one radius from its skeletal point, which is on the
    curve) and inside no other: its distance to every curve point c away from the junctions is at
    least c's radius (that of the skeletal points near c), up to the coarse curve's chords (2 %)."""
    s = make(n=4000, seed=2)
    r = np.linalg.norm(s.cloud - s.skeletal, axis=1)
    dense = _dense_curve(s)
    ds, _ = cKDTree(dense).query(s.skeletal)
    assert ds.max() < 0.01
    deg = np.bincount(s.curve_edges.ravel())
    d_junction, _ = cKDTree(s.curve_vertices[deg >= 3]).query(dense)
    dense = dense[d_junction > r.max()][::2]
    near = cKDTree(s.skeletal).query_ball_point(dense, 0.03)
    r_curve = np.array([r[i].min() if len(i) else 0.0 for i in near])
    dist = np.linalg.norm(s.cloud[:, None, :] - dense[None, :, :], axis=2)
    assert np.all(dist - r_curve[None, :] > -0.02 * r.max())


def test_t_shape_has_unequal_radii_and_area_uniform_sampling():
    s = shapes.t_shape(n=20000, bar_radius=0.3, stem_radius=0.15, bar_length=4.0, stem_length=2.0, seed=3)
    r = np.linalg.norm(s.cloud - s.skeletal, axis=1)
    on_stem = s.skeletal[:, 2] < -1e-9
    assert np.allclose(r[on_stem & (s.skeletal[:, 2] > -1.99)], 0.15)
    assert np.allclose(r[np.abs(s.skeletal[:, 2]) < 1e-12][np.abs(s.skeletal[np.abs(s.skeletal[:, 2]) < 1e-12, 0]) < 1.99], 0.3)
    # the share of the cloud on the stem matches its share of the area (stem side outside the bar,
    # plus the half ball at its end), within 3 standard errors
    a_bar = 2 * np.pi * 0.3 * 4.0 + 4 * np.pi * 0.3**2
    a_stem = 2 * np.pi * 0.15 * (2.0 - np.sqrt(0.3**2 - 0.15**2 / 2)) + 2 * np.pi * 0.15**2
    p = a_stem / (a_bar + a_stem)
    share = on_stem.mean()
    assert abs(share - p) < 3 * np.sqrt(p * (1 - p) / len(r)) + 0.01


def test_tube_sampling_weights_the_outer_side_of_a_bend_like_a_torus():
    """A torus built as a tube union has the analytic torus's area element (R + r cos phi): the outer
    half of the tube holds (pi R + 2 r) / (2 pi R) of the points."""
    rng = np.random.default_rng(4)
    R, r = 1.0, 0.3
    a = np.linspace(0, 2 * np.pi, 400)
    ring = np.column_stack([R * np.cos(a), R * np.sin(a), np.zeros_like(a)])
    ring[-1] = ring[0]
    s = shapes._tube_union([shapes._Branch(ring, r, (0, 0))], ring[:1].copy(), 40000, 0.2, rng)
    outer = np.linalg.norm(s.cloud[:, :2], axis=1) > R
    p = (np.pi * R + 2 * r) / (2 * np.pi * R)
    assert abs(outer.mean() - p) < 3 * np.sqrt(p * (1 - p) / 40000)
    # uniform around the ring
    theta = np.arctan2(s.cloud[:, 1], s.cloud[:, 0])
    counts = np.histogram(theta, bins=8, range=(-np.pi, np.pi))[0]
    assert counts.min() > 0.9 * counts.mean()


def test_shapes_are_seedable():
    a, b, c = shapes.tree3(n=500, seed=7), shapes.tree3(n=500, seed=7), shapes.tree3(n=500, seed=8)
    assert np.array_equal(a.cloud, b.cloud) and not np.array_equal(a.cloud, c.cloud)
    assert np.array_equal(a.curve_vertices, c.curve_vertices)


def test_noise_is_relative_to_the_local_radius():
    s = shapes.t_shape(n=8000, seed=5)
    noisy = shapes.with_noise(s, 0.05, seed=5)
    r = shapes.local_radius(s)
    dev = noisy.cloud - s.cloud
    stem = s.skeletal[:, 2] < -0.5
    bar = (np.abs(s.skeletal[:, 2]) < 1e-12) & (np.abs(s.skeletal[:, 0]) > 0.5)
    assert np.allclose(r[stem], 0.15) and np.allclose(r[bar], 0.3)
    # per-coordinate standard deviation is level x radius on each part
    assert abs(dev[stem].std() / 0.15 - 0.05) < 0.005
    assert abs(dev[bar].std() / 0.3 - 0.05) < 0.005
    assert np.array_equal(noisy.skeletal, s.skeletal)
    assert np.array_equal(shapes.with_noise(s, 0.0).cloud, s.cloud)
    with pytest.raises(ValueError):
        shapes.with_noise(s, -0.01)


def test_local_radius_on_a_flat_capped_cylinder_is_the_radius():
    s = shapes.cylinder(n=4000, radius=0.5, seed=6)
    assert np.allclose(shapes.local_radius(s), 0.5)
