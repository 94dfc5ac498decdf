"""``disconnected`` (docs/diagnostics.md "Disconnected"): a curve skeleton broken into more pieces
than the cloud holds is named, its extra pieces' branches flagged; the intact Y and a traced neuron are
not; an edit that splits the curve raises it after the update as in a fresh evaluation."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import skelcore
import skelcore.edit as E
from skelcore.benchmark.neurons import MeshSampler, load_neuron
from skelcore.curve import CurveSkeleton
from skelcore.diagnostics.branches import decompose_branches
from skelcore.diagnostics.pieces import curve_pieces, find_components
from skelcore.diagnostics.record import DEFECT_BITS
from skelcore.geometry import Normalization, kd_tree

SAMPLES = Path(__file__).resolve().parents[2] / "resources" / "samples"


def _without(curve: CurveSkeleton, *pairs: tuple[int, int]) -> CurveSkeleton:
    e = np.sort(np.asarray(curve.edges), axis=1)
    drop = np.zeros(len(e), bool)
    for a, b in pairs:
        drop |= (e == sorted((a, b))).all(axis=1)
    assert drop.sum() == len(pairs)
    return CurveSkeleton.from_raw(curve.vertices, np.asarray(curve.edges)[~drop])


@pytest.fixture(scope="module")
def y():
    return skelcore.load_cloud(SAMPLES / "yshape_cloud.ply"), skelcore.load_curve(SAMPLES / "yshape_curve.ply")


def _codes(ev) -> set[str]:
    return {w.code for w in ev.warnings}


def test_the_broken_y_is_named_and_its_extra_pieces_flagged(y):
    cloud, curve = y
    broken = _without(curve, (3, 4), (14, 15))
    ev = skelcore.evaluate(cloud, None, broken)
    w = [w for w in ev.warnings if w.code == "disconnected"]
    assert len(w) == 1 and "in 3 pieces where the cloud is one" in w[0].message and "nan" not in w[0].message
    part = ev.diagnostics.part("components")
    assert part["pieces"] == 3 and part["cloud_pieces"] == 1 and part["extra"] == 2
    # the two shorter pieces' edges carry the bit, the longest piece's do not
    n, piece = curve_pieces(broken)
    bits = (ev.diagnostics.arrays["curve_edge_defects"] & DEFECT_BITS["disconnected"]) != 0
    length = np.bincount(piece[broken.edges[:, 0]], weights=broken.edge_lengths(), minlength=n)
    on = piece[broken.edges[:, 0]]
    assert not bits[on == np.argmax(length)].any() and bits[on != np.argmax(length)].all()
    flags = [b["flags"] for b in ev.diagnostics.part("branches")["branches"]]
    assert {b for b, f in enumerate(flags) if "disconnected" in f} == set(part["branches"])


def test_the_intact_y_and_an_isolated_vertex_are_not(y):
    cloud, curve = y
    assert "disconnected" not in _codes(skelcore.evaluate(cloud, None, curve))
    # a vertex no edge uses is no piece (the repair's tally leaves them out too)
    v = np.vstack([curve.vertices, curve.vertices[:1] + 0.01])
    assert "disconnected" not in _codes(skelcore.evaluate(cloud, None, CurveSkeleton.from_raw(v, curve.edges)))


def test_two_objects_each_with_its_own_piece_are_not():
    """Two Y clouds side by side, far apart, each with its own curve: two pieces where the cloud is two."""
    cloud, curve = skelcore.load_cloud(SAMPLES / "yshape_cloud.ply"), skelcore.load_curve(SAMPLES / "yshape_curve.ply")
    shift = np.array([10.0 * float(np.ptp(cloud, axis=0).max()), 0.0, 0.0])
    two = np.vstack([cloud, cloud + shift])
    v = np.vstack([curve.vertices, curve.vertices + shift])
    e = np.vstack([curve.edges, curve.edges + curve.n_vertices])
    ev = skelcore.evaluate(two, None, CurveSkeleton.from_raw(v, e))
    assert "disconnected" not in _codes(ev)
    assert ev.diagnostics.part("components")["cloud_pieces"] == 2


def test_three_thousand_fragments_are_named():
    cloud = skelcore.load_cloud(SAMPLES / "cylinder_cloud.ply")
    axis = skelcore.load_curve(SAMPLES / "cylinder_curve.ply").vertices
    t = np.linspace(0.0, 1.0, 6000)
    v = np.column_stack([np.interp(t * (len(axis) - 1), np.arange(len(axis)), axis[:, k]) for k in range(3)])
    e = np.arange(6000).reshape(-1, 2)
    ev = skelcore.evaluate(cloud, None, CurveSkeleton.from_raw(v, e))
    w = [w for w in ev.warnings if w.code == "disconnected"]
    assert len(w) == 1 and "in 3000 pieces where the cloud is one" in w[0].message
    assert ev.diagnostics.part("components")["extra"] == 2999


def test_a_traced_neuron_is_not():
    """A report neuron's traced skeleton on a 12,000-point sample of its mesh."""
    n = load_neuron("722817260")
    sk = n.skeleton
    cloud = MeshSampler(n.mesh, sk.vertices, np.asarray(sk.radius, float)).sample(
        12_000, np.random.default_rng(0)).points
    norm = Normalization.from_cloud(cloud)
    curve = CurveSkeleton.from_raw(norm.apply(sk.vertices), np.asarray(sk.edges))
    tree = kd_tree(norm.apply(cloud))
    got = find_components(curve, decompose_branches(curve), tree)
    assert got.extra == 0 and not got.warnings()


def test_an_edit_that_splits_the_curve_raises_it_after_the_update(y):
    cloud, curve = y
    ev = skelcore.evaluate(cloud, None, curve)
    new, change = E.delete_edge(ev.curve.curve, (14, 15))
    updated = ev.update(change)
    fresh = skelcore.evaluate(cloud, None, new)
    assert "disconnected" in _codes(updated) and _codes(updated) == _codes(fresh)
    assert updated.diagnostics.part("components") == fresh.diagnostics.part("components")
    np.testing.assert_array_equal(updated.diagnostics.arrays["curve_edge_defects"],
                                  fresh.diagnostics.arrays["curve_edge_defects"])
