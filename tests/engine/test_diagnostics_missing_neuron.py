"""Missing parts on a traced neuron of resources/neurons (docs/diagnostics.md "Completeness"): one
branch of an arbor is a small share of its cloud, so a removed branch is found by its area and its
depth, not its share; the intact traced skeleton stays complete."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore.benchmark.neurons import MeshSampler, load_neuron
from skelcore.benchmark.skeleton_defects import _drop_isolated, _terminal_branches, drop_vertices
from skelcore.curve import CurveSkeleton
from skelcore.diagnostics.missing_parts import missing_parts
from skelcore.geometry import Normalization
from skelcore.params import Params

#: a tuning neuron (docs/diagnostics.md "Precision and recall per warning") at 12,000 points
NEURON, POINTS = "1734350788", 12_000


@pytest.fixture(scope="module")
def arbor():
    n = load_neuron(NEURON)
    sk = n.skeleton
    cloud = MeshSampler(n.mesh, sk.vertices, np.asarray(sk.radius, float)).sample(
        POINTS, np.random.default_rng(0)).points
    norm = Normalization.from_cloud(cloud)
    return norm.apply(cloud), norm.apply(sk.vertices), np.asarray(sk.edges)


def test_the_intact_traced_neuron_is_complete(arbor):
    cloud, v, e = arbor
    assert not missing_parts(cloud, CurveSkeleton.from_raw(v, e)).incomplete


@pytest.mark.parametrize("rank", [0, 1])
def test_a_removed_long_branch_is_found_though_a_small_share(arbor, rank):
    """The two longest terminal branches (about 80 median radii each), removed one at a time: a
    region of under 1 % of the cloud (under ``missing_min_share``, so the share rule alone misses
    it), more than ``missing_small_depth`` border radii deep."""
    cloud, v, e = arbor
    branch = sorted(_terminal_branches(v, e), key=lambda t: -t[2])[rank]
    drop = np.zeros(len(v), bool)
    drop[branch[1]] = True
    curve = CurveSkeleton.from_raw(*_drop_isolated(*drop_vertices(v, e, drop)))
    got = missing_parts(cloud, curve)
    assert got.incomplete and got.counted
    part = got.counted[0]
    assert part.share < Params().missing_min_share and part.depth >= Params().missing_small_depth
    # the removed branch's own points: the counted region lies around its nodes
    near = np.linalg.norm(cloud[got.missing][:, None] - v[branch[1]][None], axis=2).min(axis=1)
    assert np.median(near) < 0.05
    assert not missing_parts(cloud, curve, Params(missing_min_area=1e9)).incomplete
