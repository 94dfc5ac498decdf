"""Coverage alone (docs/metrics.md 5.2): the cloud's coverage by the medial balls of the
skeletal set, and of the curve densified as the evaluation does, in normalized space (docs/metrics.md 0), tau
computed apart (untimed). Cases: the hammer with the built-in skeleton, the reference torus at 65,536
points."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore.correspondence import densify_curve
from skelcore.curve import CurveSkeleton
from skelcore.geometry import Normalization
from skelcore.metrics.coverage import coverage, coverage_tau
from skelcore.params import Params


def _coverage(benchmark, measure, cloud, skeletal, curve, which: str, rounds: int) -> None:
    p = Params()
    if not isinstance(curve, CurveSkeleton):
        curve = CurveSkeleton(*curve)
    norm = Normalization.from_cloud(cloud, p.normalize_by, p.normalized_size)
    c = norm.apply(cloud)
    tau = coverage_tau(c, p)
    if which == "skeletal":
        elements = norm.apply(skeletal)
    else:
        cv = curve.transformed(norm.apply)
        step = max(tau / p.coverage_tau_factor, float(cv.edge_lengths().sum()) / 200_000)
        elements = np.vstack([densify_curve(cv, step)[0], cv.vertices])
    cov = measure(lambda: coverage(c, elements, p, tau), rounds=rounds)
    benchmark.extra_info.update(n_points=len(cloud), n_elements=int(cov.n_elements), fraction=round(cov.fraction, 4))


@pytest.mark.parametrize("which", ["skeletal", "curve"])
def test_coverage_hammer(measure, benchmark, hammer, hammer_skeleton, which):
    _coverage(benchmark, measure, hammer, *hammer_skeleton, which, rounds=15)


@pytest.mark.parametrize("which", ["skeletal", "curve"])
def test_coverage_torus_65536(measure, benchmark, torus, which):
    _coverage(benchmark, measure, *torus(65_536), which, rounds=3)
