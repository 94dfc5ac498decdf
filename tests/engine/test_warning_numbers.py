"""No warning message prints "nan" or "inf" (docs/diagnostics.md "Messages"): degenerate skeletons
(a collapsed star on a cloud point, a one-edge curve, a single vertex) through the evaluation, and
the builders given undefined numbers."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

from skelcore import evaluate, shapes
from skelcore.diagnostics.trust_warning import finite_range

_BAD = re.compile(r"\b(nan|inf|infinity)\b", re.IGNORECASE)


@pytest.fixture(scope="module")
def cloud() -> np.ndarray:
    return shapes.y_shape(n=1500, seed=3).cloud


def _cases(cloud: np.ndarray) -> dict:
    hub = cloud[0]  # on a cloud point: the junction's ball has radius 0
    near = cloud[np.argsort(np.linalg.norm(cloud - hub, axis=1))[1:4]]
    star = np.vstack([hub, hub + 1e-3 * (near - hub)])
    return {
        "collapsed star": dict(curve=(star, np.array([[0, 1], [0, 2], [0, 3]]))),
        "star on cloud points": dict(curve=(np.vstack([hub, near]), np.array([[0, 1], [0, 2], [0, 3]]))),
        "one edge": dict(curve=(np.vstack([hub, cloud[1]]), np.array([[0, 1]]))),
        "single vertex": dict(skeletal=hub[None]),
        "far away": dict(curve=(np.array([[9.0, 9, 9], [9.5, 9, 9]]), np.array([[0, 1]]))),
    }


@pytest.mark.parametrize("name", ["collapsed star", "star on cloud points", "one edge", "single vertex", "far away"])
def test_degenerate_skeletons_say_no_nan(cloud, name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ev = evaluate(cloud, workers=1, **_cases(cloud)[name])
    assert ev.warnings
    for w in ev.warnings:
        assert not _BAD.search(w.message), (w.code, w.message)


def test_builders_leave_undefined_numbers_out():
    from skelcore.diagnostics.missing_parts import depth_clause

    assert finite_range([np.nan, np.nan]) is None
    assert finite_range([np.nan, 0.5, np.inf, 2.0]) == "0.5-2"
    assert finite_range([3.0]) == "3"
    assert depth_clause(np.nan) == "" and "inf" not in depth_clause(np.inf)
