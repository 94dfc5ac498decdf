"""Completeness counts only the balls of skeleton elements inside the shape (docs/diagnostics.md
"Completeness"): a star whose edges cross a torus's hole explained most of the cloud with balls as
large as the hole; the exact axis stays complete."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from skelcore import evaluate, shapes
from skelcore.curve import CurveSkeleton
from skelcore.diagnostics.interior import voxelize_interior
from skelcore.diagnostics.missing_parts import missing_parts
from skelcore.params import Params


@pytest.fixture(scope="module")
def torus():
    return shapes.torus(n=2000, seed=1)


def _evaluate(cloud, curve):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return evaluate(cloud, curve=curve, workers=1)


def test_a_star_across_the_hole_is_incomplete(torus):
    cloud = torus.cloud
    hub = np.zeros(3)  # the hole's centre
    tips = 0.9 * cloud[[np.argmax(cloud[:, 0]), np.argmin(cloud[:, 0]), np.argmax(cloud[:, 1])]]
    star = CurveSkeleton.from_raw(np.vstack([hub, tips]), np.array([[0, 1], [0, 2], [0, 3]]))
    shape = voxelize_interior(cloud, voxels=Params().cycles_voxels, min_spacing_factor=Params().cycles_voxel_spacing,
                              inside_share=Params().beta_star)

    def inside(points):
        ijk = shape.index_of(points)
        return shape.solid()[ijk[:, 0], ijk[:, 1], ijk[:, 2]]

    every_ball = missing_parts(cloud, star)
    found = missing_parts(cloud, star, inside=inside)
    assert every_ball.completeness > 0.6 and not every_ball.incomplete  # the hole's balls explained it
    assert found.completeness < 0.5 and found.incomplete and found.outside_elements > 0
    assert [w.code for w in found.warnings()] == ["incomplete"]


def test_the_exact_axis_stays_complete(torus):
    ev = _evaluate(torus.cloud, CurveSkeleton.from_raw(torus.curve_vertices, torus.curve_edges))
    assert ev.diagnostics.summary["completeness"]["curve"] > 0.99
    assert "incomplete" not in {w.code for w in ev.warnings}
