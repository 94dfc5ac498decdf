"""skelcore.metrics.supports: each element's support on shapes with known answers, and equal to the
engine's own value for that element."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore import Params, shapes
from skelcore.metrics.boundedness import boundedness_paper, boundedness_rays, paper_triangles
from skelcore.metrics.centeredness import curve_centeredness, skeletal_centeredness
from skelcore.metrics.supports import curve_sample_support, direction_map, skeletal_point_support


def test_cylinder_cross_section_is_a_circle_centred_on_the_axis():
    cyl = shapes.cylinder(8000, radius=0.5, length=4.0, seed=3)
    p, u = np.array([0.0, 0.0, 2.0]), np.array([0.0, 0.0, 1.0])
    sup = curve_sample_support(cyl.cloud, p, u)
    assert len(sup.slab) > 20
    # every slab point lies in the slab, and every cloud point in the slab is listed
    inside = np.flatnonzero(np.abs((cyl.cloud - p) @ u) < sup.half_width)
    assert np.array_equal(np.sort(sup.slab), inside)
    ring = sup.flat[sup.ring]
    np.testing.assert_allclose(np.hypot(ring[:, 0], ring[:, 1]), 0.5, atol=1e-9)
    assert len(sup.ring) == len(sup.slab)  # one cross-section only, the caps are far away
    centre, axes, _angle = sup.ellipse
    np.testing.assert_allclose(centre, 0.0, atol=0.02)
    np.testing.assert_allclose(axes, 0.5, atol=0.02)
    assert sup.value > 0.95
    engine = curve_centeredness(cyl.cloud, p[None], u[None])[0]
    assert sup.value == pytest.approx(engine, abs=1e-12)


def test_off_axis_sample_scores_what_the_engine_scores():
    cyl = shapes.cylinder(6000, radius=0.5, length=4.0, seed=1)
    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(-0.3, 0.3, 12), rng.uniform(-0.3, 0.3, 12), rng.uniform(0.5, 3.5, 12)])
    dirs = rng.normal(size=(12, 3)) * [0.2, 0.2, 1.0]
    engine = curve_centeredness(cyl.cloud, pts, dirs)
    mine = [curve_sample_support(cyl.cloud, p, d).value for p, d in zip(pts, dirs)]
    np.testing.assert_allclose(mine, engine, atol=1e-12)
    # the centre moves away from the sample as it leaves the axis
    assert min(mine) < 0.9


def test_joint_sample_has_no_slab():
    cyl = shapes.cylinder(1000)
    sup = curve_sample_support(cyl.cloud, np.zeros(3), np.full(3, np.nan))
    assert len(sup.slab) == 0 and np.isnan(sup.value)


def test_skeletal_support_matches_the_engine_with_ties():
    rng = np.random.default_rng(5)
    cloud = rng.normal(size=(600, 3))
    # 150 generic positions, each taken by 4 skeletal rows: coincident points, ties by row index
    skel = rng.normal(size=(150, 3))[rng.permutation(np.repeat(np.arange(150), 4))]
    params = Params(k_center=12)
    engine = skeletal_centeredness(cloud, skel, params=params)
    for i in (0, 7, 123, 599):
        sup = skeletal_point_support(cloud, skel, i, params=params)
        assert len(sup.neighbours) == 12
        np.testing.assert_allclose(sup.skeletal_centroid, skel[sup.neighbours].mean(axis=0))
        np.testing.assert_allclose(sup.cloud_centroid, cloud[sup.neighbours].mean(axis=0))
        assert sup.value == pytest.approx(engine[i], abs=1e-12)


def test_skeletal_support_on_a_ring_around_its_centre_is_perfect():
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    cloud = np.column_stack([np.cos(t), np.sin(t), np.zeros(40)])
    sup = skeletal_point_support(cloud, np.zeros((40, 3)), 3, params=Params(k_center=40))
    np.testing.assert_allclose(sup.cloud_centroid, 0.0, atol=1e-12)
    assert sup.spread == pytest.approx(1.0) and sup.value == pytest.approx(1.0)


def test_point_outside_a_sphere_covers_about_the_cap_fraction():
    radius, dist = 1.0, 2.0
    cloud = shapes.sphere_surface(6000, radius, seed=2)
    q = np.array([0.0, 0.0, dist])
    dm = direction_map(cloud, q)
    # the sphere seen from q fills a cap of half-angle asin(R / D), inflated by the balls' radius h
    a = np.arcsin((radius + dm.radius) / dist)
    cap = (1.0 - np.cos(a)) / 2.0
    assert dm.fraction == pytest.approx(cap, abs=0.02)
    # the covered directions point at the sphere: the lowest rows (z < 0 means towards the sphere)
    assert dm.covered[0].all() and not dm.covered[-1].any()
    assert dm.fraction == pytest.approx(boundedness_rays(cloud, q[None])[0], abs=0.01)


def test_direction_map_agrees_with_the_engine_inside_a_torus_and_a_cylinder():
    tor = shapes.torus(4000, seed=1)
    queries = tor.skeletal[:5] + [0.0, 0.0, 0.01]
    engine = boundedness_rays(tor.cloud, queries)
    mine = [direction_map(tor.cloud, q).fraction for q in queries]
    np.testing.assert_allclose(mine, engine, atol=0.01)


def test_paper_triangles_sum_to_the_paper_estimator():
    cloud = shapes.sphere_surface(800, 1.0, seed=4)
    for q in ([0.0, 0.0, 0.0], [0.2, -0.1, 0.3], [0.0, 0.0, 2.0]):
        tri = paper_triangles(cloud, np.array(q))
        assert tri.triangles.shape[1] == 3 and tri.triangles.max() < len(tri.directions)
        assert tri.beta == pytest.approx(boundedness_paper(cloud, np.array([q]))[0], abs=1e-14)
    assert paper_triangles(cloud[:2], np.zeros(3)) is None


def test_smoothness_supports_reproduce_the_engines_values():
    """The plain recomputation of one skeletal point's smoothness (its tangent and its
    neighbours') and of one curve vertex's angle agrees with the engine's vectorized values, coincident
    points included (contraction stacks them)."""
    from skelcore.curve import CurveSkeleton
    from skelcore.metrics.smoothness import curve_vertex_smoothness, skeletal_smoothness
    from skelcore.metrics.supports import curve_vertex_support, skeletal_smoothness_support

    rng = np.random.default_rng(5)
    t = np.sort(rng.uniform(0, 4 * np.pi, 600))
    pts = np.column_stack([np.cos(t), np.sin(t), 0.2 * t]) + rng.normal(scale=0.01, size=(600, 3))
    pts[100:104] = pts[100]  # a stack of coincident points
    engine = skeletal_smoothness(pts)
    for i in (0, 50, 101, 300, 599):
        sup = skeletal_smoothness_support(pts, i)
        assert sup.value == pytest.approx(engine[i], abs=1e-9)
        assert sup.scores[sup.worst] == sup.value and np.all(sup.scores[np.isfinite(sup.scores)] >= sup.value)
    curve = CurveSkeleton.from_raw(pts[::20], np.column_stack([np.arange(29), np.arange(1, 30)]))
    s = curve_vertex_smoothness(curve)
    for v in range(curve.n_vertices):
        sup = curve_vertex_support(curve.vertices, curve.edges, v)
        assert (np.isnan(sup.value) and np.isnan(s[v])) or sup.value == pytest.approx(s[v], abs=1e-12)
