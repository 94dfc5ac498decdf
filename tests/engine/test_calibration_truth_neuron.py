"""The calibration's truth on a traced neuron of resources/neurons (docs/benchmark.md "The
calibration's truth on a neuron"): a defect under what the cloud resolves is left out, not a miss; a
removed twig of a few traced nodes leaves too little of the cloud to count, half the arbor does; a
spur of 2 radii stays within the cloud's tolerance, one of 15 pointing into the air does not."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from skelcore.benchmark.calibration.skeletons import Made, World, _mesh_depth
from skelcore.benchmark.calibration.truth import (MISS_AREA, MISS_YES, OUT_YES, origin, outside_depth, outside_seen,
                                                  row_truth, uncovered_area, uncovered_radii)
from skelcore.benchmark.calibration.uncovered import visible_removal
from skelcore.benchmark.neurons import MeshSampler, load_neuron

#: a tuning neuron; the twig: SWC nodes 1990 (its junction) - 4354 - 4355 (its tip), radius 10; a
#: degree-2 node of radius 10 (a thin neurite, as most of the calibration's spurs start from)
NEURON, JUNCTION, TWIG, NODE = "1734350788", 1990, (4354, 4355), 2206
CROP = 400.0  # units around the junction kept


@pytest.fixture(scope="module")
def crop():
    """The suite's 30k-point cloud of the whole mesh and the traced skeleton, cut to a ball around the
    junction; every kept node counted as shown by the cloud (the truth's facts)."""
    n = load_neuron(NEURON)
    sk = n.skeleton
    r = np.asarray(sk.radius, float)
    at = {int(i): k for k, i in enumerate(n.node_ids)}
    centre = sk.vertices[at[JUNCTION]]
    got = MeshSampler(n.mesh, sk.vertices, r).sample(30_000, np.random.default_rng(0))
    keep = np.linalg.norm(got.points - centre, axis=1) <= CROP
    kv = np.linalg.norm(sk.vertices - centre, axis=1) <= CROP
    e = sk.edges[kv[sk.edges].all(axis=1)]
    used = np.unique(e)
    remap = np.full(len(sk.vertices), -1)
    remap[used] = np.arange(len(used))
    v = sk.vertices[used]
    facts = SimpleNamespace(outside_radii=np.zeros(len(v)), inside=np.ones(len(v), bool))
    w = World(got.points[keep], got.radius[keep], (v, remap[e], r[used]), _mesh_depth(n.mesh), False, facts)
    return w, {s: int(remap[at[s]]) for s in (JUNCTION, *TWIG, NODE)}


def _truth(made: Made, w: World) -> dict:
    return row_truth(made, w, "clean", set(), {}, first=False)


def test_a_removed_twig_is_left_out_and_half_the_arbor_counts(crop):
    w, ids = crop
    v, e, _ = w.ref
    twig = Made("missing_branch", v, e[~np.isin(e, [ids[TWIG[0]], ids[TWIG[1]]]).any(axis=1)])
    assert uncovered_radii(twig, w) > MISS_YES  # a positive by length alone
    assert uncovered_area(twig, w) < 0.2 * MISS_AREA and _truth(twig, w)["truth_incomplete"] is None
    side = v[:, 0] < np.median(v[:, 0])
    half = Made("truncation", v, e[side[e].all(axis=1)])
    assert uncovered_area(half, w) >= MISS_AREA and _truth(half, w)["truth_incomplete"] == 1


def _spur(v, e, a, length, rad, away):
    """A spur of ``length`` traced radii from node ``a``, perpendicular to its neurite, towards ``away``."""
    nbr = e[(e == a).any(axis=1)].ravel()
    nbr = nbr[nbr != a]
    axis = (v[nbr[1]] - v[nbr[0]]) / np.linalg.norm(v[nbr[1]] - v[nbr[0]])
    side = away - axis * (away @ axis)
    tip = v[a] + np.outer(np.linspace(0.5, 1.0, 2), length * rad[a] * side / np.linalg.norm(side))
    return Made("spurs", np.vstack([v, tip]), np.vstack([e, [[a, len(v)], [len(v), len(v) + 1]]]))


def test_a_spur_within_the_clouds_tolerance_is_left_out(crop):
    w, ids = crop
    v, e, r = w.ref
    a = ids[NODE]
    away = v[a] - v.mean(axis=0)  # away from the crop's centre
    short, long_ = _spur(v, e, a, 2.0, r, away), _spur(v, e, a, 15.0, r, away)
    for made in (short, long_):
        assert outside_depth(made, w, origin(made, v)) >= OUT_YES  # out of the mesh
    assert outside_seen(short, w, origin(short, v)) < OUT_YES and _truth(short, w)["truth_outside"] is None
    assert outside_seen(long_, w, origin(long_, v)) >= OUT_YES and _truth(long_, w)["truth_outside"] == 1


def test_the_removal_drawn_on_a_neuron_is_one_the_cloud_shows(crop):
    """The calibration's removed branch on a neuron holds MISS_AREA of the cloud's surface, or none is
    drawn (on this crop every terminal branch is a twig or cut by the crop)."""
    w, _ = crop
    got = visible_removal(w, np.random.default_rng(0))
    if got is not None:
        assert uncovered_area(Made("missing_branch", *got), w) >= MISS_AREA
    w_big = World(w.cloud, w.local_radius / 3.0, w.ref, w.depth, False, w.facts)  # parts 3 x thinner than said
    got = visible_removal(w_big, np.random.default_rng(0))
    assert got is not None and uncovered_area(Made("missing_branch", *got), w_big) >= MISS_AREA
