"""Ground truth on the held reference (docs/metrics.md 5.3.1 "The held reference"): on a piece of a
shipped neuron with its real facts (inside the decimated mesh, distance outside it), the held scores
leave out exactly the nodes more than ``gt_held_radii`` of their radii outside, equal the plain
scores where every node is held, and the facts file is read back (one clear line when it is bad)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import breadth_first_order

from skelcore.benchmark.neurons import (load_neuron, read_outside_radii, surface_distance, winding_numbers,
                                        write_facts_csv, NodeFacts)
from skelcore.curve import CurveSkeleton
from skelcore.errors import SkelInputError
from skelcore.metrics.ground_truth import GroundTruthParams, compare_with_ground_truth

PARAMS = GroundTruthParams(sample_step=0.5)  # coarser samples: a few thousand, the test stays fast


@pytest.fixture(scope="module")
def piece():
    """600 traced nodes of neuron 722817260 (a breadth-first walk from its middle node: twigs, a fifth
    of them more than a radius out of the mesh), their facts against the mesh, and a curve: the nodes
    moved by up to 0.6 of their radii, those more than a radius out by 1.5 (as a curve inside the mesh)."""
    neuron = load_neuron("722817260")
    sk = neuron.skeleton
    n = sk.n_vertices
    adj = coo_matrix((np.ones(len(sk.edges)), (sk.edges[:, 0], sk.edges[:, 1])), shape=(n, n))
    keep = np.sort(breadth_first_order(adj, n // 2, directed=False, return_predecessors=False)[:600])
    remap = np.full(n, -1)
    remap[keep] = np.arange(len(keep))
    e = remap[sk.edges]
    e = e[(e >= 0).all(axis=1)]
    ref = CurveSkeleton(vertices=sk.vertices[keep], edges=e, radius=sk.radius[keep])
    inside = winding_numbers(neuron.mesh, ref.vertices) > 0.5
    outside = np.where(inside, 0.0, surface_distance(neuron.mesh, ref.vertices)) / ref.radius
    rng = np.random.default_rng(5)
    step = rng.normal(size=ref.vertices.shape)
    size = np.where(outside > 1.0, 1.5, rng.uniform(0, 0.6, len(step)))
    step *= (size * ref.radius / np.linalg.norm(step, axis=1))[:, None]
    curve = CurveSkeleton(vertices=ref.vertices + step, edges=ref.edges)
    return ref, outside, curve


def test_all_held_is_the_plain_comparison(piece):
    ref, _, curve = piece
    plain = compare_with_ground_truth(curve, ref, ref.radius, params=PARAMS)
    held = compare_with_ground_truth(curve, ref, ref.radius, params=PARAMS, outside_radii=np.zeros(ref.n_vertices))
    assert (held.held_precision, held.held_recall, held.held_f1) == (plain.precision, plain.recall, plain.f1)
    assert held.held_share == 1.0 and held.held_nodes == (ref.n_vertices, ref.n_vertices)
    assert plain.held_f1 is None and plain.to_dict() == {**held.to_dict(), **{k: None for k in held.to_dict()
                                                                               if k.startswith("held_")}}
    assert type(held).from_dict(held.to_dict()) == held and type(plain).from_dict(plain.to_dict()) == plain


def test_the_held_reference_drops_exactly_the_nodes_outside_the_tolerance(piece):
    ref, outside, curve = piece
    far = outside > PARAMS.held_radii
    assert 0.1 < far.mean() < 0.5  # the data: a real share of these nodes lies beyond a radius out
    got = compare_with_ground_truth(curve, ref, ref.radius, params=PARAMS, outside_radii=outside)
    assert got.held_nodes == (int((~far).sum()), ref.n_vertices)
    # how far beyond the tolerance a dropped node lies does not matter; a held node at it still counts
    moved = compare_with_ground_truth(curve, ref, ref.radius, params=PARAMS,
                                      outside_radii=np.where(far, 10 * outside + 5, np.where(outside > 0, 1.0, 0.0)))
    assert (moved.held_precision, moved.held_recall, moved.held_share) == (got.held_precision, got.held_recall,
                                                                          got.held_share)
    # independently: the reference cut at its edges' midpoints, the dropped nodes' halves taken away
    e = ref.edges
    mid = (ref.vertices[e[:, 0]] + ref.vertices[e[:, 1]]) / 2
    m = ref.n_vertices + np.arange(len(e))
    halves = np.concatenate([np.column_stack([e[:, 0], m]), np.column_stack([e[:, 1], m])])
    own = np.concatenate([e[:, 0], e[:, 1]])
    halves = halves[~far[own]]
    used, inv = np.unique(halves, return_inverse=True)
    allv = np.vstack([ref.vertices, mid])
    allr = np.concatenate([ref.radius, (ref.radius[e[:, 0]] + ref.radius[e[:, 1]]) / 2])
    kept = CurveSkeleton(vertices=allv[used], edges=inv.reshape(-1, 2), radius=allr[used])
    alone = compare_with_ground_truth(curve, kept, kept.radius, params=PARAMS)
    assert got.held_recall == pytest.approx(alone.recall, abs=0.01)
    assert got.held_share == pytest.approx(kept.edge_lengths().sum() / ref.edge_lengths().sum(), abs=0.01)
    assert got.held_recall > got.recall + 0.03  # and the dropped part mattered (0.827 against 0.777)


def test_the_facts_file_is_read_back_and_a_bad_one_named(piece, tmp_path):
    ref, outside, _ = piece
    facts = NodeFacts(outside == 0, (outside == 0).astype(float), outside * ref.radius, outside * ref.radius,
                      outside, ref.radius, 0)

    class Neuron:
        skeleton, node_ids = ref, np.arange(ref.n_vertices)

    path = tmp_path / "n_gt_facts.csv"
    write_facts_csv(path, Neuron, facts)
    back = read_outside_radii(path, ref.n_vertices)
    assert np.allclose(back, outside, rtol=1e-5, atol=1e-9)
    for text, what in (("vertex,x\n0,1\n", "needs the columns"), ("vertex,outside_by_radii\n0,a\n", "numbers"),
                       ("vertex,outside_by_radii\n0,-1\n", ">= 0")):
        bad = tmp_path / "bad.csv"
        bad.write_text(text)
        with pytest.raises(SkelInputError, match=what) as exc:
            read_outside_radii(bad)
        assert str(exc.value).startswith(str(bad)) and "\n" not in str(exc.value)
    with pytest.raises(SkelInputError, match="rows for a reference"):
        read_outside_radii(path, ref.n_vertices + 1)


def test_evaluate_reference_facts_adds_the_held_line(tmp_path, capsys):
    """``skelcore evaluate --reference-facts``: the plain block unchanged, a "held reference" line and
    the ``held_`` fields in the JSON; the facts without a reference are refused (exit 2)."""
    from skelcore import shapes
    from skelcore.cli import main
    from skelcore.io import write_curve_ply, write_points_ply

    sh = shapes.cylinder(1500, radius=0.5, seed=2)
    v, e = sh.curve_vertices, sh.curve_edges
    write_points_ply(tmp_path / "cloud.ply", sh.cloud)
    write_curve_ply(tmp_path / "curve.ply", v, e)
    write_curve_ply(tmp_path / "ref.ply", v + [0.1, 0, 0], e, scalars={"radius": np.full(len(v), 0.5)})
    far = np.arange(len(v)) >= len(v) // 2
    (tmp_path / "facts.csv").write_text("vertex,outside_by_radii\n" + "".join(
        f"{i},{2.0 if far[i] else 0.0}\n" for i in range(len(v))))
    args = ["evaluate", str(tmp_path / "cloud.ply"), "--curve", str(tmp_path / "curve.ply"), "--reference-curve",
            str(tmp_path / "ref.ply"), "--quiet"]
    assert main(args + ["--reference-facts", str(tmp_path / "facts.csv"), "--json", str(tmp_path / "ev.json")]) == 0
    out = capsys.readouterr().out
    assert "precision 0.850, recall 0.850, F1 0.850" in out
    assert f"held reference (nodes at most 1 r outside the cloud's surface: {int((~far).sum())} of {len(v)}" in out
    full = json.loads((tmp_path / "ev.json").read_text())
    pytest.importorskip("jsonschema")
    from skelcore.io.schemas import validator

    assert [e.message for e in validator("evaluation").iter_errors(full)] == []
    doc = full["ground_truth"]
    assert doc["f1"] == pytest.approx(0.85) and doc["held_f1"] == pytest.approx(0.85, abs=0.02)
    assert doc["held_nodes"] == [int((~far).sum()), len(v)] and 0.3 < doc["held_share"] < 0.7
    assert main(args[:4] + ["--reference-facts", str(tmp_path / "facts.csv")]) == 2
    assert "give --reference-curve" in capsys.readouterr().err


def test_bench_repair_rows_carry_the_held_f1_where_the_facts_are_known(tmp_path):
    """A traced case whose record names its facts file gets ``held_f1_*`` (and the summary their
    means); a case without facts gets none."""
    import json as _json

    from skelcore import shapes
    from skelcore.benchmark.repair_bench import _f1, repair_cases
    from skelcore.benchmark.repair_table import summarize
    from skelcore.io import write_curve_ply, write_points_ply

    sh = shapes.cylinder(600, radius=0.5, seed=2)
    v, e = sh.curve_vertices, sh.curve_edges
    for d in ("cases", "clouds", "truth"):
        (tmp_path / d).mkdir()
    write_points_ply(tmp_path / "clouds" / "c.ply", sh.cloud)
    write_curve_ply(tmp_path / "truth" / "c_reference.ply", v, e, scalars={"radius": np.full(len(v), 0.5)})
    (tmp_path / "truth" / "n_gt_facts.csv").write_text("vertex,outside_by_radii\n" + "".join(
        f"{i},{3.0 if i == 0 else 0.0}\n" for i in range(len(v))))
    (tmp_path / "suite.json").write_text(_json.dumps({"seed": 0}))
    files = {"cloud": "clouds/c.ply", "reference": "truth/c_reference.ply"}
    for name, extra in (("a", {"facts": "truth/n_gt_facts.csv"}), ("b", {})):
        (tmp_path / "cases" / f"{name}.json").write_text(_json.dumps(
            {"name": name, "curve_skeleton": "traced", "effect": "clean", "files": {**files, **extra}}))
    with_facts, without = list(repair_cases(tmp_path))
    assert with_facts.outside_radii.tolist() == [3.0] + [0.0] * (len(v) - 1) and without.outside_radii is None
    moved = CurveSkeleton(vertices=v + [0.1, 0, 0], edges=with_facts.reference.edges)
    row = {"case": "a", "job": "x", **_f1(moved, with_facts, "before"), **_f1(moved, with_facts, "after"),
           "seconds_repair": 1.0, "warnings_before": [], "warnings_after": []}
    assert row["f1_before"] == pytest.approx(0.85) and row["held_f1_before"] == pytest.approx(0.85, abs=0.02)
    assert set(_f1(moved, without, "before")) == {"f1_before"}
    assert summarize([row])["x"]["held_f1_after"] == round(row["held_f1_after"], 3)
