"""Eq. 11 from a slab of each sample's own thickness (skelcore/metrics/local_slabs.py, docs/diagnostics.md
"Along the surface"): the paper's slab gives the paper's values, and on a tube a sample moved k of the
radius towards the wall reads c = 1 - k from slabs of one or two local radii."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore import Params, shapes
from skelcore.curve import CurveSkeleton
from skelcore.geometry import Normalization, kd_tree
from skelcore.metrics.centeredness import curve_centeredness
from skelcore.metrics.curve_sampling import sample_curve
from skelcore.metrics.local_slabs import local_slab_centeredness


@pytest.fixture(scope="module")
def tube():
    p = Params()
    sh = shapes.cylinder(3000, radius=0.5, length=4.0, seed=1)
    norm = Normalization.from_cloud(sh.cloud, p.normalize_by, p.normalized_size)
    return sh, norm, norm.apply(sh.cloud)


def _samples(tube, share: float):
    sh, norm, _ = tube
    curve = CurveSkeleton.from_raw(norm.apply(sh.curve_vertices + [0.5 * share, 0.0, 0.0]), sh.curve_edges)
    return sample_curve(curve, Params().curve_samples, collinear_cos=Params().collinear_cos)


def test_the_papers_slab_gives_the_papers_values(tube):
    """A half on the ladder (2^-7, the paper's own for this cloud: slab_factor x diagonal / 2 = 0.0081)
    is not rounded: the same rings and fits as curve_centeredness with that slab."""
    cloud = tube[2]
    s = _samples(tube, 0.3)
    half = 2.0 ** -7
    diag = float(np.linalg.norm(cloud.max(axis=0) - cloud.min(axis=0)))
    paper = curve_centeredness(cloud, s.points, s.directions, params=Params(slab_factor=2 * half / diag))
    local = local_slab_centeredness(cloud, s.points, s.directions, np.full(len(s), half))
    assert np.isfinite(paper).sum() > 150
    np.testing.assert_allclose(local, paper, rtol=0, atol=1e-9)


@pytest.mark.parametrize("share", [0.0, 0.3, 0.7])
@pytest.mark.parametrize("radii", [1.0, 2.0])
def test_a_moved_axis_reads_its_offset(tube, share, radii):
    cloud = tube[2]
    s = _samples(tube, share)
    r = kd_tree(cloud).query(s.points)[0]
    c = local_slab_centeredness(cloud, s.points, s.directions, radii * r)
    middle = np.abs(np.asarray(s.points)[:, 2]) < 0.5 * np.abs(np.asarray(s.points)[:, 2]).max()
    assert np.isfinite(c[middle]).all()
    assert np.median(c[middle]) == pytest.approx(1 - share, abs=0.02)


def test_no_direction_or_no_slab_is_nan(tube):
    cloud = tube[2]
    s = _samples(tube, 0.0)
    dirs = np.asarray(s.directions, float).copy()
    dirs[0] = np.nan
    half = np.full(len(s), 0.01)
    half[1] = 0.0
    c = local_slab_centeredness(cloud, s.points, dirs, half)
    assert np.isnan(c[:2]).all() and np.isfinite(c[2:]).any()
    assert local_slab_centeredness(cloud, np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)).shape == (0,)
