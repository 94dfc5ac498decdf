"""The compiled farthest-point sampling (skelcore/skeleton/_farthest.c) gives the Python loop's samples
and labels, bit for bit: on random clouds, clustered and repeated points, lattices (balls meeting
points at exactly the radius) and a curve far from the origin; and it is cancellable as the loop is."""

import numpy as np
import pytest

from skelcore.skeleton.cao_curve import _farthest_sampling_loop, farthest_sampling_by_sphere


def _same(pts, radius):
    pts = np.ascontiguousarray(pts, float)
    got, want = farthest_sampling_by_sphere(pts, radius), _farthest_sampling_loop(pts, radius)
    assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])
    return got


@pytest.mark.parametrize("seed", range(3))
def test_the_loops_samples_on_random_and_clustered_clouds(seed):
    rng = np.random.default_rng(seed)
    for n in (1, 2, 10, 700):
        _same(rng.normal(size=(n, 3)), 0.3)
    centres = rng.normal(size=(30, 3))
    _same(np.repeat(centres, 40, axis=0) + rng.normal(size=(1200, 3)) * 1e-3, 0.2)
    samples, corresp = _same(np.repeat(centres, 40, axis=0), 0.2)  # repeated points
    assert np.all(corresp >= 0) and len(samples) >= 1


@pytest.mark.parametrize("step", [1.0, 0.1])
def test_the_loops_samples_on_a_lattice_where_balls_meet_points_at_the_radius(step):
    g = np.stack(np.meshgrid(*[np.arange(9)] * 3, indexing="ij"), -1).reshape(-1, 3) * step
    for r in (1.0, 2.0, np.sqrt(2.0), 1.5):
        samples, _ = _same(g, r * step)
        assert 1 < len(samples) < len(g)


def test_the_loops_samples_on_a_curve_far_from_the_origin():
    t = np.linspace(0.0, 10.0, 3000)
    _same(np.column_stack([t, np.sin(t), 0.0 * t]) * 1000.0 + 5e5, 30.0)


def test_the_check_runs_and_cancels():
    pts = np.random.default_rng(3).normal(size=(3000, 3))
    calls = []
    farthest_sampling_by_sphere(pts, 0.05, lambda: calls.append(1))
    assert calls  # every 256 samples tried, as the loop

    def stop():
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        farthest_sampling_by_sphere(pts, 0.05, stop)
