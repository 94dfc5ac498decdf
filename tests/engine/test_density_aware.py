"""Density-aware boundedness (docs/metrics.md 6.8): with one half of a torus 10 x sparser the paper's
boundedness of its exact axis falls with the sampling and ``sparse_boundedness`` says so; with
``boundedness_density_aware`` the sparse half is cast against filled points and the axis is bounded
again, while the default stays the paper's and a uniform cloud gets few points."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore.params import Params


@pytest.fixture(scope="module")
def torus():
    from skelcore.benchmark.validity import _shape
    from skelcore.curve import CurveSkeleton

    _, sampler, (v, e, _) = _shape("torus", 0)
    rng = np.random.default_rng(0)
    pts = sampler.sample(6000, rng).points
    axis = int(np.argmax(np.ptp(pts, axis=0)))
    keep = (pts[:, axis] < np.median(pts[:, axis])) | (rng.uniform(size=len(pts)) < 0.1)
    return pts[keep][:2000], sampler.sample(2000, rng).points, CurveSkeleton.from_raw(v, e)


def test_the_sparse_half_is_bounded_again_and_the_default_stays_the_papers(torus):
    from skelcore.stages.orchestrate import evaluate

    half, _, curve = torus
    paper = evaluate(half, curve=curve)
    aware = evaluate(half, curve=curve, params=Params(boundedness_density_aware=True))
    b0, b1 = paper.summary()["boundedness"]["curve"], aware.summary()["boundedness"]["curve"]
    assert b0 < 0.6 and "sparse_boundedness" in {w.code for w in paper.warnings}
    assert b1 > b0 + 0.2
    assert "--density-aware" in next(w.message for w in paper.warnings if w.code == "sparse_boundedness")


def test_a_uniform_cloud_gets_no_filled_points(torus):
    from skelcore.scan.density import density_fill

    half, uniform, _ = torus
    assert len(density_fill(uniform)) < 0.1 * len(uniform)  # a few random gaps: 6 %
    fill = density_fill(half)
    assert len(fill) > len(half)
    assert len(np.unique(fill, axis=0)) == len(fill)  # each segment once: copies made the median spacing 0


def test_the_cli_flag_sets_the_parameter(tmp_path):
    from skelcore.cli.main import build_parser

    args = build_parser().parse_args(["evaluate", "cloud.ply", "--curve", "c.ply", "--density-aware"])
    assert args.density_aware


def test_a_density_gradient_lowers_the_exact_axis_and_the_warning_says_so():
    """The calibration's non-uniform tube (10 x across it, 5000 points): the sparse end leaves 24 % of
    the exact axis unbounded (none on the uniform cloud: the truth, ``truth.sparse_drop``), and
    ``sparse_boundedness`` fires, which the lower-quartile yardstick (1.4 x the median there) never let."""
    from skelcore.benchmark.calibration.skeletons import world
    from skelcore.benchmark.calibration.truth import sparse_drop
    from skelcore.curve import CurveSkeleton
    from skelcore.stages.orchestrate import evaluate

    w = world("synthetic", "tube_a", 5000, "nonuniform", 0)
    assert sparse_drop(w, world("synthetic", "tube_a", 5000, "clean", 0).cloud) > 0.1
    v, e, _ = w.ref
    ev = evaluate(w.cloud, curve=CurveSkeleton.from_raw(np.asarray(v, float), np.asarray(e, np.int64)), workers=1)
    assert "sparse_boundedness" in {x.code for x in ev.warnings}
