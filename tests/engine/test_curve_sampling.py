"""Curve sampling and sample directions (docs/metrics.md 3)."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore.curve import CurveSkeleton
from skelcore.metrics.curve_sampling import sample_counts, sample_curve
from skelcore.geometry import matlab_round


def _curve(vertices, edges) -> CurveSkeleton:
    return CurveSkeleton.from_raw(np.asarray(vertices, float), np.asarray(edges))


def _path_1_2_1() -> CurveSkeleton:
    return _curve([[0, 0, 0], [1, 0, 0], [3, 0, 0], [4, 0, 0]], [[0, 1], [1, 2], [2, 3]])


def test_counts_are_proportional_to_edge_length():
    s = sample_curve(_path_1_2_1(), 8)
    assert np.bincount(s.edge).tolist() == [2, 4, 2]
    assert len(s) == 8


def test_fractions_exclude_start_and_include_end():
    s = sample_curve(_path_1_2_1(), 8)
    np.testing.assert_allclose(s.t, [0.5, 1, 0.25, 0.5, 0.75, 1, 0.5, 1])
    np.testing.assert_allclose(s.points[:, 0], [0.5, 1, 1.5, 2, 2.5, 3, 3.5, 4])
    assert not np.any(np.all(s.points == 0, axis=1)), "lowest-index end of a path is never sampled"


def test_fraction_is_measured_from_lower_index_vertex():
    # the edge is given as (1, 0); cleaning stores it as (0, 1)
    c = _curve([[5, 0, 0], [0, 0, 0]], [[1, 0]])
    s = sample_curve(c, 4)
    np.testing.assert_allclose(s.t, [0.25, 0.5, 0.75, 1.0])
    np.testing.assert_allclose(s.points[:, 0], [3.75, 2.5, 1.25, 0.0])


def test_counts_use_matlab_rounding_half_away_from_zero():
    # shares 2.5 and 2.5 (S=5): MATLAB gives 3 and 3, Python's round (half to even) 2 and 2
    counts = sample_counts(np.array([1.0, 1.0]), 5)
    assert counts.tolist() == [matlab_round(2.5), matlab_round(2.5)] == [3, 3]


def test_short_edge_gets_at_least_one_sample():
    counts = sample_counts(np.array([1000.0, 1e-6, 0.0]), 10)
    assert counts.tolist() == [10, 1, 1]


def test_closed_loop_samples_one_vertex_twice():
    square = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    c = _curve(square, [[0, 1], [1, 2], [2, 3], [3, 0]])
    s = sample_curve(c, 4)
    ends = s.points[s.t == 1]
    end_vertex = [int(np.flatnonzero(np.all(np.array(square) == e, axis=1))[0]) for e in ends]
    # edges (0,1), (1,2), (2,3), (0,3): ends 1, 2, 3 and 3 again; vertex 0 never
    assert sorted(end_vertex) == [1, 2, 3, 3]


def test_no_edges_gives_zero_samples():
    c = _curve([[0, 0, 0], [1, 1, 1]], np.empty((0, 2)))
    s = sample_curve(c, 200)
    assert len(s) == 0
    assert s.points.shape == (0, 3) and s.directions.shape == (0, 3)


def test_inside_edge_direction_is_edge_direction():
    c = _curve([[0, 0, 0], [0, 0, 2], [0, 2, 2]], [[0, 1], [1, 2]])
    s = sample_curve(c, 4)
    inner = s.t < 1
    expected = np.where((s.edge[inner] == 0)[:, None], [0, 0, 1.0], [0, 1.0, 0])
    np.testing.assert_allclose(s.directions[inner], expected)


def test_degree_one_end_vertex_uses_edge_direction():
    c = _curve([[0, 0, 0], [3, 4, 0]], [[0, 1]])
    s = sample_curve(c, 3)
    np.testing.assert_allclose(s.directions, np.tile([0.6, 0.8, 0], (3, 1)))


def test_degree_two_vertex_uses_circle_tangent():
    # three points on the unit circle in the xy-plane; tangent at (1, 0) is +-y
    a = [np.cos(-0.7), np.sin(-0.7), 0]
    v = [1.0, 0.0, 0.0]
    b = [np.cos(0.3), np.sin(0.3), 0]
    c = _curve([a, v, b], [[0, 1], [1, 2]])
    s = sample_curve(c, 2)
    at_v = (s.edge == 0) & (s.t == 1)
    np.testing.assert_allclose(s.directions[at_v][0], [0, 1, 0], atol=1e-12)


def test_circle_tangent_in_general_position():
    rng = np.random.default_rng(7)
    centre = rng.normal(size=3)
    e1, e2 = np.linalg.qr(rng.normal(size=(3, 2)))[0].T
    angles = np.array([0.2, 1.1, 2.9])
    pts = centre + 2.5 * (np.cos(angles)[:, None] * e1 + np.sin(angles)[:, None] * e2)
    c = _curve(pts, [[0, 1], [1, 2]])
    d = sample_curve(c, 2).directions[0]
    expected = -np.sin(1.1) * e1 + np.cos(1.1) * e2
    assert abs(abs(d @ expected) - 1) < 1e-12


def test_nearly_collinear_degree_two_vertex_uses_chord():
    c = _curve([[0, 0, 0], [1, 0.001, 0], [3, 0, 0]], [[0, 1], [1, 2]])
    s = sample_curve(c, 3)
    at_v = (s.edge == 0) & (s.t == 1)
    np.testing.assert_allclose(s.directions[at_v][0], [1, 0, 0])


def test_hairpin_counts_as_collinear():
    c = _curve([[0, 0, 0], [1, 0, 0], [0, 0.001, 0]], [[0, 1], [1, 2]])
    d = sample_curve(c, 2).directions[0]
    np.testing.assert_allclose(d, [0, 1, 0])


def test_joint_vertex_direction_is_nan():
    # star: vertex 3 is a joint (degree 3); edges (0,3), (1,3), (2,3) all end there
    c = _curve([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, 0]], [[0, 3], [1, 3], [2, 3]])
    s = sample_curve(c, 6)
    at_joint = s.t == 1
    assert at_joint.sum() == 3
    assert np.all(np.isnan(s.directions[at_joint]))
    assert np.all(np.isfinite(s.directions[~at_joint]))


def test_sign_follows_edge_from_lower_to_higher_index():
    c = _curve([[0, 0, 0], [1, 0, 0], [2, 1, 0]], [[0, 1], [1, 2]])
    s = sample_curve(c, 10)
    forward = (s.points[-1] - s.points[0])
    assert np.all(s.directions @ forward > 0)


def test_zero_length_edge_direction_is_nan_at_a_path_end():
    c = _curve([[0, 0, 0], [1, 0, 0], [1, 0, 0]], [[0, 1], [1, 2]])
    s = sample_curve(c, 4)
    last = s.edge == 1
    assert last.sum() == 1
    assert np.all(np.isnan(s.directions[last]))


def test_degree_two_vertex_at_a_neighbour_uses_chord():
    c = _curve([[0, 0, 0], [0, 0, 0], [0, 2, 0]], [[0, 1], [1, 2]])
    s = sample_curve(c, 4)
    np.testing.assert_allclose(s.directions[s.edge == 0], [[0, 1, 0]])


@pytest.mark.parametrize("bad", [0, -3])
def test_rejects_non_positive_sample_count(bad):
    with pytest.raises(ValueError):
        sample_curve(_path_1_2_1(), bad)
