"""Smoothness (docs/metrics.md 4): PCA-tangent skeletal smoothness and curve vertex smoothness."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skelcore.curve import CurveSkeleton
from skelcore.metrics.smoothness import curve_smoothness_overall, curve_vertex_smoothness, skeletal_smoothness
from skelcore.params import Params
from skelcore.shapes import cylinder


def brute_force_smoothness(points: np.ndarray, tangent_k: int = 8, smooth_k: int = 4) -> np.ndarray:
    """Plain-loop reading of docs/metrics.md 4, one point at a time."""
    n = len(points)
    tangents = np.full((n, 3), np.nan)
    order_of = []
    for i in range(n):
        d = np.linalg.norm(points - points[i], axis=1)
        others = np.flatnonzero(d > 0)  # itself and every point at its exact position excluded
        order = others[np.argsort(d[others], kind="stable")]
        order_of.append(order)
        near = order[:tangent_k]
        c = np.zeros((3, 3))
        for j in near:
            v = points[j] - points[i]
            c += np.outer(v, v)
        c /= tangent_k
        if np.any(c != 0):
            w, vecs = np.linalg.eigh(c)
            tangents[i] = vecs[:, np.argmax(w)]
    s = np.full(n, np.nan)
    for i in range(n):
        if np.isnan(tangents[i, 0]):
            continue
        vals = []
        for j in order_of[i][:smooth_k]:
            if np.isnan(tangents[j, 0]):
                continue
            cos = np.clip(tangents[i] @ tangents[j], -1, 1)
            vals.append(abs(1 - 2 * math.acos(cos) / math.pi))
        if vals:
            s[i] = min(vals)
    return s


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


@pytest.mark.parametrize("tangent_k, smooth_k", [(8, 4), (5, 3), (3, 6)])
def test_skeletal_smoothness_matches_plain_loop_reference_with_duplicates(rng, tangent_k, smooth_k):
    base = np.cumsum(rng.normal(size=(120, 3)) * 0.1, axis=0)  # a noisy random walk: curve-like
    repeats = rng.integers(1, 6, size=len(base))  # contraction piles points up
    pts = np.repeat(base, repeats, axis=0)
    pts = pts[rng.permutation(len(pts))]
    params = Params(tangent_k=tangent_k, smooth_k=smooth_k)
    got = skeletal_smoothness(pts, params=params)
    want = brute_force_smoothness(pts, tangent_k, smooth_k)
    np.testing.assert_allclose(got, want, atol=1e-9)
    assert np.all(np.isfinite(got))


def test_points_sharing_a_position_share_their_smoothness(rng):
    base = rng.normal(size=(50, 3))
    pts = np.vstack([base, base[:10], base[:10]])
    s = skeletal_smoothness(pts)
    np.testing.assert_array_equal(s[50:60], s[:10])
    np.testing.assert_array_equal(s[60:70], s[:10])


def test_heavily_coincident_points_are_not_all_nan():
    # 30 distinct positions along a gentle arc, each holding 40 points: no point has 8 distinct
    # neighbours at other positions within its own pile, which must not make everything NaN.
    t = np.linspace(0, 1, 30)
    arc = np.column_stack([t, 0.1 * t**2, np.zeros_like(t)])
    pts = np.repeat(arc, 40, axis=0)
    s = skeletal_smoothness(pts)
    assert np.all(np.isfinite(s))
    assert s.min() > 0.9


def test_cylinder_axis_points_have_smoothness_one():
    shape = cylinder(2000, seed=3)
    s = skeletal_smoothness(shape.skeletal)
    np.testing.assert_allclose(s, 1.0, atol=1e-7)


def test_two_positions_give_smoothness_one_and_a_single_position_gives_nan():
    two = np.array([[0.0, 0, 0]] * 5 + [[1.0, 2, 3]] * 3)
    np.testing.assert_allclose(skeletal_smoothness(two), 1.0, atol=1e-7)
    one = np.zeros((7, 3))
    assert np.all(np.isnan(skeletal_smoothness(one)))
    assert skeletal_smoothness(np.empty((0, 3))).shape == (0,)


def test_right_angle_corner_of_points_scores_near_zero_and_straight_arms_one():
    # an L of points with unequal spacing on its arms: the corner's tangent follows the y arm
    # (larger spread among its 4 nearest), its nearest neighbour lies on the x arm: theta ~ 90 deg
    x_arm = np.arange(1, 21) * 0.05
    y_arm = np.arange(1, 21) * 0.06
    zeros = np.zeros(20)
    pts = np.vstack([[0, 0, 0], np.column_stack([x_arm, zeros, zeros]), np.column_stack([zeros, y_arm, zeros])])
    s = skeletal_smoothness(pts, params=Params(tangent_k=4, smooth_k=2))
    np.testing.assert_allclose(s[10:20], 1.0, atol=1e-7)  # far along the x arm
    np.testing.assert_allclose(s[30:41], 1.0, atol=1e-7)  # far along the y arm
    assert s[0] < 0.2


def test_skeletal_smoothness_is_rotation_and_scale_invariant(rng):
    pts = np.cumsum(rng.normal(size=(200, 3)), axis=0)
    rot = random_rotation(rng)
    a = skeletal_smoothness(pts)
    b = skeletal_smoothness(3.7 * pts @ rot.T + np.array([5.0, -2, 1]))
    np.testing.assert_allclose(a, b, atol=1e-6)


def test_skeletal_smoothness_reports_progress_and_honours_cancel(rng):
    seen: list[float] = []
    skeletal_smoothness(rng.normal(size=(300, 3)), checkpoint=seen.append)
    assert seen and seen[-1] == 1.0 and all(0 <= f <= 1 for f in seen)

    class Stop(Exception):
        pass

    def cancel(_f: float) -> None:
        raise Stop

    with pytest.raises(Stop):
        skeletal_smoothness(rng.normal(size=(300, 3)), checkpoint=cancel)


# ---- curve skeleton --------------------------------------------------------------------------
def polyline(vertices, closed: bool = False) -> CurveSkeleton:
    v = np.asarray(vertices, dtype=float)
    e = np.column_stack([np.arange(len(v) - 1), np.arange(1, len(v))])
    if closed:
        e = np.vstack([e, [[len(v) - 1, 0]]])
    return CurveSkeleton.from_raw(v, e)


@pytest.mark.parametrize("n", [4, 5, 6, 12, 40])
def test_circle_ngon_vertices_have_smoothness_one_minus_four_over_n(n):
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    curve = polyline(np.column_stack([2.0 * np.cos(a), 2.0 * np.sin(a), np.full(n, 0.3)]), closed=True)
    s = curve_vertex_smoothness(curve)
    np.testing.assert_allclose(s, 1 - 4 / n, atol=1e-12)
    score, count = curve_smoothness_overall(curve, s)
    assert count == n
    assert score == pytest.approx(1 - 4 / n)


def test_right_angle_corner_has_smoothness_zero_and_ends_have_none():
    curve = polyline([[0, 0, 0], [1, 0, 0], [1, 2, 0]])
    s = curve_vertex_smoothness(curve)
    assert np.isnan(s[0]) and np.isnan(s[2])
    assert s[1] == pytest.approx(0.0, abs=1e-12)
    score, count = curve_smoothness_overall(curve, s)
    # corner weight = half of (1 + 2), total length 3: 1 - 1.5 * 1 / 3
    assert (score, count) == (pytest.approx(0.5), 1)


def test_straight_line_has_smoothness_one():
    curve = polyline(np.column_stack([np.linspace(0, 1, 7), np.linspace(0, 2, 7), np.zeros(7)]))
    s = curve_vertex_smoothness(curve)
    np.testing.assert_allclose(s[1:-1], 1.0, atol=1e-7)
    assert curve_smoothness_overall(curve, s) == (pytest.approx(1.0), 5)


def test_hairpin_scores_one_quirk_of_the_paper_formula():
    # the path goes out and folds straight back: theta = 0, |1 - 0| = 1 (kept, docs/metrics.md 4)
    curve = polyline([[0, 0, 0], [1, 0, 0], [0.5, 0, 0]])
    assert curve_vertex_smoothness(curve)[1] == pytest.approx(1.0)


def test_branch_and_end_vertices_have_no_value_and_count_as_smooth_overall():
    star = CurveSkeleton.from_raw(np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]), np.array([[0, 1], [0, 2], [0, 3]]))
    s = curve_vertex_smoothness(star)
    assert np.all(np.isnan(s))
    assert curve_smoothness_overall(star, s) == (1.0, 0)


def test_overall_weights_each_vertex_by_half_its_edge_lengths():
    # two corners: a right angle (s=0) between edges 1 and 3, a straight vertex (s=1) between 3 and 3
    curve = polyline([[0, 0, 0], [1, 0, 0], [1, 3, 0], [1, 6, 0]])
    s = curve_vertex_smoothness(curve)
    np.testing.assert_allclose(s[1:3], [0.0, 1.0], atol=1e-12)
    score, count = curve_smoothness_overall(curve, s)
    assert count == 2
    assert score == pytest.approx(1 - 0.5 * (1 + 3) * 1.0 / 7)


def test_curve_without_edges_has_no_overall_smoothness():
    curve = CurveSkeleton.from_raw(np.array([[0.0, 0, 0], [1, 0, 0]]), np.empty((0, 2)))
    s = curve_vertex_smoothness(curve)
    assert np.all(np.isnan(s))
    score, count = curve_smoothness_overall(curve, s)
    assert math.isnan(score) and count == 0


def test_degree_two_vertex_on_top_of_a_neighbour_has_no_angle():
    curve = polyline([[0, 0, 0], [1, 0, 0], [1, 0, 0], [2, 1, 0]])
    s = curve_vertex_smoothness(curve)
    assert np.isnan(s[1]) and np.isnan(s[2])
