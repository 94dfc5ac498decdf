"""Scan effects of the benchmark: point counts, noise levels relative to the local radius, one-sided
scans, holes, outliers, cropping, non-uniform density, determinism (skelcore.benchmark.scan_effects)."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore.benchmark import ScanEffects, SurfaceSampler, make_shape, scan, signed_distance
from skelcore.benchmark.generate import clip_curve
from skelcore.benchmark.scan_effects import visible_from
from skelcore.benchmark.surface_sampling import SurfacePoints
from skelcore.benchmark.tubes import reference_skeleton


@pytest.fixture(scope="module")
def y_shape():
    shape = make_shape("y", "junction", 0, kind="y")
    return shape, SurfaceSampler(shape)


def _scan(sampler, seed=0, **kw):
    return scan(sampler, ScanEffects(**{"n_points": 3000, **kw}), np.random.default_rng(seed))


def test_clean_scan_has_exactly_the_points_asked_for(y_shape):
    shape, sampler = y_shape
    for n in (1000, 3000):
        s = _scan(sampler, n_points=n)
        assert s.cloud.shape == (n, 3)
        assert np.max(np.abs(signed_distance(shape, s.cloud) / s.local_radius)) < 2e-3


@pytest.mark.parametrize("level", [0.02, 0.05, 0.2])
def test_noise_is_relative_to_the_local_radius(y_shape, level):
    """Per coordinate sigma = level x r, so the offset along the normal has the same spread: the
    signed distance over the local radius has standard deviation ~ level, on thick and thin arms."""
    shape, sampler = y_shape
    s = _scan(sampler, n_points=20000, noise=level)
    rel = signed_distance(shape, s.cloud) / s.local_radius
    assert np.std(rel) == pytest.approx(level, rel=0.05)
    thin = s.local_radius < 0.15
    assert np.std(rel[thin]) == pytest.approx(level, rel=0.1)  # the 0.12 arm: same relative noise


def test_outliers_are_added_as_a_fraction_of_the_points(y_shape):
    shape, sampler = y_shape
    s = _scan(sampler, outliers=0.05)
    assert len(s.cloud) == 3000 + 150
    assert np.count_nonzero(np.isnan(s.local_radius)) == 150
    far = signed_distance(shape, s.cloud[np.isnan(s.local_radius)])
    assert np.mean(np.abs(far) > 0.01) > 0.9  # uniform in the box: almost all off the surface


def test_crop_removes_the_fraction_beyond_a_plane_and_clips_the_reference(y_shape):
    shape, sampler = y_shape
    s = _scan(sampler, crop=0.25)
    g, offset = s.crop_plane
    assert len(s.cloud) == 2250
    assert np.all(s.surface.points @ g <= offset + 1e-12)
    v, e, r = reference_skeleton(shape)
    cv, ce, cr = clip_curve(v, e, r, g, offset)
    assert np.all(cv @ g <= offset + 1e-9)
    assert len(cv) < len(v) and np.all(cr > 0)
    on_plane = np.isclose(cv @ g, offset)
    assert on_plane.any()  # edges crossing the plane end on it


def test_clip_curve_cuts_an_edge_at_the_plane():
    v = np.array([[0.0, 0, 0], [2.0, 0, 0], [4.0, 0, 0]])
    e = np.array([[0, 1], [1, 2]])
    cv, ce, cr = clip_curve(v, e, np.array([1.0, 2.0, 3.0]), np.array([1.0, 0, 0]), 3.0)
    assert cv.tolist() == [[0, 0, 0], [2, 0, 0], [3, 0, 0]]
    assert ce.tolist() == [[0, 1], [1, 2]] and cr.tolist() == [1.0, 2.0, 2.5]


def test_holes_remove_balls_around_surface_points(y_shape):
    _, sampler = y_shape
    s = _scan(sampler, holes=6, hole_radius=0.8)
    assert 2700 < len(s.cloud) < 3000
    assert s.info["hole_points_removed"] == 3000 - len(s.cloud)


def test_one_sided_scans_see_less_with_fewer_viewpoints(y_shape):
    _, sampler = y_shape
    counts = [len(_scan(sampler, views=k, seed=1).cloud) for k in (1, 2, 3)]
    assert 0.35 * 3000 < counts[0] < 0.6 * 3000  # a tube shows about half of itself to one eye
    assert counts[0] < counts[1] < counts[2] <= 3000


def test_visibility_hides_the_far_side_and_what_is_behind():
    """Two parallel tubes seen along the line joining them: the near tube's front half is seen,
    its back half and all of the far tube are not."""
    rng = np.random.default_rng(0)
    n = 20000
    a = rng.uniform(0, 2 * np.pi, n)
    x = rng.uniform(-1, 1, n)
    ring = np.column_stack([np.zeros(n), np.cos(a), np.sin(a)])
    pts = np.vstack([ring * 0.3 + np.column_stack([x, np.zeros(n), np.zeros(n)]),
                     ring * 0.3 + np.column_stack([x, np.zeros(n), np.full(n, -2.0)])])
    s = SurfacePoints(pts, np.vstack([ring, ring]), np.full(2 * n, 0.3))
    seen = visible_from(s, np.array([0.0, 0.0, 20.0]), np.array([0.0, 0.0, -1.0]), spacing=0.02)
    near, far = seen[:n], seen[n:]
    assert far.sum() == 0
    assert np.all(~near[ring[:, 2] < 0])
    assert near[ring[:, 2] > 0.3].mean() > 0.95


def test_nonuniform_density_varies_by_the_ratio_along_its_direction():
    shape = make_shape("tube", "elliptic", 0, flatten=0.999, bend=0.0)
    sampler = SurfaceSampler(shape)
    s = scan(sampler, ScanEffects(n_points=40000, nonuniform=10.0), np.random.default_rng(2))
    g = np.array(s.info["density_direction"])
    u = s.cloud @ g
    ref = sampler.sample(40000, np.random.default_rng(3)).points @ g
    lo, hi = ref.min(), ref.max()
    first = np.mean(u < lo + 0.2 * (hi - lo)) / np.mean(ref < lo + 0.2 * (hi - lo))
    last = np.mean(u > hi - 0.2 * (hi - lo)) / np.mean(ref > hi - 0.2 * (hi - lo))
    assert len(s.cloud) == 40000
    assert first / last == pytest.approx(10 ** 0.8, rel=0.15)  # slab means 0.1 and 0.9 along g


def test_same_seed_same_scan_other_seed_other_scan(y_shape):
    _, sampler = y_shape
    kw = dict(noise=0.05, views=2, holes=3, outliers=0.01, crop=0.1)
    a, b, c = _scan(sampler, 7, **kw), _scan(sampler, 7, **kw), _scan(sampler, 8, **kw)
    assert np.array_equal(a.cloud, b.cloud)
    assert a.cloud.shape != c.cloud.shape or not np.allclose(a.cloud, c.cloud)


def test_bad_effects_are_refused():
    with pytest.raises(ValueError):
        ScanEffects(views=4)
    with pytest.raises(ValueError):
        ScanEffects(crop=1.0)
