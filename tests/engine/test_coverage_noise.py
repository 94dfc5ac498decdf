"""Coverage's radii under noise (docs/metrics.md 5.2 "Noise"): the nearest of many noisy points lies
well inside the surface, so r(x) alone shrinks the balls of an exact axis as the cloud grows; the noise
shortfall gives them back on noisy clouds and leaves clean ones exactly as they were."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from skelcore.benchmark.scan_effects import ScanEffects, scan
from skelcore.benchmark.surface_sampling import SurfaceSampler
from skelcore.benchmark.tubes import BenchShape, Tube, reference_skeleton
from skelcore.metrics.coverage import coverage, noise_shortfall
from skelcore.params import Params


def _helix() -> BenchShape:
    t = np.linspace(0, 2 * 2 * np.pi, 28)
    p = np.column_stack([np.cos(t), np.sin(t), 0.35 * t])
    return BenchShape("helix", "test", np.array([p[0], p[-1]]), (Tube(p, np.full(28, 0.15), start=0, end=1),))


def _sample(shape: BenchShape, n: int, noise: float, seed: int = 0):
    sc = scan(SurfaceSampler(shape), ScanEffects(n_points=n, noise=noise), np.random.default_rng(seed))
    v, e, r = reference_skeleton(shape)
    return sc.cloud, v, r


@pytest.fixture(scope="module")
def noisy():
    return _sample(_helix(), 20000, 0.25)


def test_the_shortfall_gives_a_noisy_axis_its_radius_back(noisy):
    cloud, v, r = noisy
    d1 = cKDTree(cloud).query(v)[0]
    grown = d1 + noise_shortfall(cloud, v, d1, Params().coverage_radius_quantile)
    assert np.median(d1 / r) < 0.6  # the nearest noisy point: about half the radius at 20k points
    assert 0.7 < np.median(grown / r) < 1.0  # the lower quartile of the noisy shell: under the true radius


def test_a_clean_cloud_keeps_its_radii_and_its_coverage_exactly():
    cloud, v, r = _sample(_helix(), 6000, 0.0)
    d1 = cKDTree(cloud).query(v)[0]
    assert not noise_shortfall(cloud, v, d1, Params().coverage_radius_quantile).any()
    a, b = coverage(cloud, v), coverage(cloud, v, Params(coverage_radius_quantile=0.0))
    assert np.array_equal(a.gap, b.gap) and np.array_equal(a.covered, b.covered)


def test_a_noisy_axis_covers_its_cloud_as_a_clean_one_does(noisy):
    cloud, v, _ = noisy
    new = coverage(cloud, v).fraction
    old = coverage(cloud, v, Params(coverage_radius_quantile=0.0)).fraction
    assert old < 0.6 < 0.95 < new  # was under missing_min_completeness: "incomplete" on the exact axis


def test_params_refuse_a_quantile_outside_0_1():
    with pytest.raises(ValueError, match="coverage_radius_quantile"):
        Params(coverage_radius_quantile=1.0)


def test_the_shortfalls_quantiles_from_one_sort_are_the_lexsorts():
    """``_group_quantiles`` (one sort of the values, then a stable one of the groups) gives each group's
    quantiles with the bits of a lexsort per quantile: many equal values, empty groups, a -0.0 (sorted
    as before) and more groups than 16 bits hold."""
    from skelcore.metrics import coverage as C

    rng = np.random.default_rng(9)
    for n_groups, zero in ((40, False), (40, True), (40_000, False)):
        group = rng.integers(0, n_groups, 20_000)
        group[group == 3] = 4  # an empty group
        values = np.maximum(rng.integers(-5, 60, 20_000) * 0.25, 0.0)
        if zero:
            values[::7] = -0.0
        qs = (0.5, 0.1, 0.9, 0.0, 1.0)
        for q, got in zip(qs, C._group_quantiles(values, group, n_groups, qs)):
            assert got.tobytes() == C._group_quantile(values, group, n_groups, q).tobytes()
