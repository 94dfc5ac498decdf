"""Boundedness alone (docs/metrics.md 2; docs/boundedness.md), the rays estimator with the default parameters, in
normalized space (docs/metrics.md 0): the reference torus at 65,536 points with its skeletal set as the queries;
and plain against viewpoint-aware boundedness (docs/metrics.md 6.3) of the same elements: the front half
(y > 0) of a 131,072-point cylinder with its axis as the skeletal set, one viewpoint in front."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore import Params, shapes
from skelcore.geometry import Normalization
from skelcore.metrics.boundedness import boundedness
from skelcore.scan.viewpoint import seen_boundedness


def test_boundedness_torus_65536(measure, benchmark, torus):
    p = Params()
    cloud, skeletal, _curve = torus(65_536)
    norm = Normalization.from_cloud(cloud, p.normalize_by, p.normalized_size)
    c, q = norm.apply(cloud), norm.apply(skeletal)
    beta = measure(lambda: boundedness(c, q, params=p), rounds=5)
    benchmark.extra_info.update(n_points=len(c), n_queries=len(q), score=round(float(np.mean(beta > p.beta_star)), 4))


@pytest.fixture(scope="module")
def half_cylinder():
    p = Params()
    cyl = shapes.cylinder(2 * 65_536)
    keep = cyl.cloud[:, 1] > 0
    norm = Normalization.from_cloud(cyl.cloud[keep], p.normalize_by, p.normalized_size)
    return p, norm.apply(cyl.cloud[keep]), norm.apply(cyl.skeletal[keep]), norm.apply(np.array([[0.0, 40.0, 2.0]]))


@pytest.mark.parametrize("kind", ["plain", "viewpoint"])
def test_boundedness_half_cylinder(measure, benchmark, half_cylinder, kind):
    p, cloud, queries, viewpoint = half_cylinder
    if kind == "plain":
        beta = measure(lambda: boundedness(cloud, queries, params=p), rounds=5)
    else:
        beta = measure(lambda: seen_boundedness(cloud, queries, viewpoint, params=p, return_missing=True)[0], rounds=5)
    benchmark.extra_info.update(n_points=len(cloud), n_queries=len(queries),
                                score=round(float(np.mean(beta > p.beta_star)), 4))
