"""Spurious branches on a one-sided scan of a traced neuron (docs/diagnostics.md "Spurious branches",
rule 5): the twigs the sensor did not see have no point of their own and fail the explanation
measure; on a cloud seen from one side they are counted unseen, not judged, and the intact skeleton
is quiet. A cloud scanned all round is not taken for one-sided."""

from __future__ import annotations

import numpy as np
import pytest

from diagnostics_helpers import traced_crop
from skelcore import Params
from skelcore.benchmark.neurons import MeshSampler, load_neuron
from skelcore.benchmark.real_suite import RealCase
from skelcore.benchmark.scan_effects import scan
from skelcore.benchmark.suite import rng_for
from skelcore.curve import CurveSkeleton
from skelcore.diagnostics import find_spurious_branches

#: a tuning neuron and a ball of 1500 units around its node 1990 (about 250 terminal branches)
NEURON, CENTRE, CROP = "1734350788", 1990, 1500.0


@pytest.fixture(scope="module")
def neuron():
    return load_neuron(NEURON)


def _cut(neuron, cloud: np.ndarray):
    """``cloud`` and the traced skeleton cut to the ball (CROP units around node CENTRE)."""
    sk = neuron.skeleton
    centre = sk.vertices[list(neuron.node_ids).index(CENTRE)]
    keep = np.linalg.norm(sk.vertices - centre, axis=1) <= CROP
    e = sk.edges[keep[sk.edges].all(axis=1)]
    used = np.unique(e)
    remap = np.full(len(sk.vertices), -1)
    remap[used] = np.arange(len(used))
    return cloud[np.linalg.norm(cloud - centre, axis=1) <= CROP], CurveSkeleton.from_raw(sk.vertices[used], remap[e])


def test_a_one_sided_scan_leaves_the_unseen_twigs_unjudged(neuron):
    """The suite's one-sided scan (one view, 30k points drawn): without the rule dozens of traced
    twigs are flagged for want of points of their own; with it none, each counted unseen."""
    sk = neuron.skeleton
    case = RealCase(NEURON, 30_000, "views", 1)
    got = scan(MeshSampler(neuron.mesh, sk.vertices, np.asarray(sk.radius, float)), case.effects,
               rng_for(case.seed(0)))
    cloud, curve = _cut(neuron, got.cloud)
    r = find_spurious_branches(cloud, curve)
    assert r.one_sided >= Params().spur_one_sided
    assert not r.branch_spurious.any() and r.warnings() == []
    assert r.unseen is not None and r.to_dict()["unseen"] >= 20
    off = find_spurious_branches(cloud, curve, params=Params(spur_one_sided=1.0))
    assert np.array_equal(off.branch_spurious, r.unseen)  # exactly the twigs set aside


def test_a_cloud_scanned_all_round_is_not_one_sided(neuron):
    """The same ball sampled all round: the directions to the cloud cancel along the curve."""
    cloud, v, e, _, _ = traced_crop(neuron, CENTRE, CROP, 30_000)
    r = find_spurious_branches(cloud, CurveSkeleton.from_raw(v, e))
    assert r.one_sided < 0.5 * Params().spur_one_sided
    assert r.unseen is not None and not r.unseen.any()
