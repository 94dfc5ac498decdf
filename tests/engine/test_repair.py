"""skelcore.repair (docs/repair.md): a spurious twig pruned, a chord across a torus hole removed, an
outside chord of a broken torus rerouted through the shape, the never-worse rule refusing a harmful
edit, the log replayed by ``skelcore edit`` to the same curve, cancellation, and the one-line
refusals of the command line."""

from __future__ import annotations

import json

import numpy as np
import pytest

import skelcore
from skelcore import Cancelled, CurveSkeleton, Params, SkelInputError, shapes
from skelcore.cli import main
from skelcore.edit import delete_vertex, replay
from skelcore.io import load_curve, write_curve_ply, write_points_ply
from skelcore.skeleton_repair.findings import read_findings
from skelcore.skeleton_repair.guard import verdict

DEFECT_CODES = {"spurious_branches", "spurious_cycles", "missing_cycles", "outside", "incomplete"}


@pytest.fixture(scope="module")
def tube() -> shapes.Shape:
    return shapes.cylinder(3000)


def _twig(s: shapes.Shape) -> tuple[np.ndarray, np.ndarray]:
    """The tube's path with a three-edge twig sideways from its middle, out through the wall."""
    v, e = s.curve_vertices, s.curve_edges
    z = v[10, 2]
    twig = np.array([[0.3, 0, z + 0.1], [0.6, 0, z + 0.2], [0.9, 0, z + 0.3]])
    n = len(v)
    return np.vstack([v, twig]), np.vstack([e, [[10, n], [n, n + 1], [n + 1, n + 2]]])


@pytest.fixture(scope="module")
def twig_repair(tube):
    return skelcore.repair(tube.cloud, _twig(tube))


def test_a_spurious_twig_is_pruned_and_the_tube_is_sound(twig_repair):
    r = twig_repair
    assert r.tally_before["spurious_branches"] == 1
    assert r.stopped == "no defect left" and r.accepted == 1
    ops = r.log["operations"]
    assert [o["op"] for o in ops] == ["prune_branch"]
    why = ops[0]["why"]
    assert why["defect"] == "spurious_branches" and isinstance(why["branch"], int)
    assert why["after"]["centeredness"] > why["before"]["centeredness"]
    assert r.curve.n_vertices == 21 and r.curve.n_edges == 20
    assert not {w.code for w in r.after.warnings} & DEFECT_CODES
    assert r.after.diagnostics.summary["completeness"]["curve"] == pytest.approx(1.0)


def test_the_log_replays_to_the_same_curve(tube, twig_repair):
    start = CurveSkeleton.from_raw(*_twig(tube))
    again, _ = replay(start, json.loads(json.dumps(twig_repair.log)))
    assert np.array_equal(again.vertices, twig_repair.curve.vertices)
    assert np.array_equal(again.edges, twig_repair.curve.edges)


def test_a_chord_across_the_torus_hole_is_removed():
    s = shapes.torus(3000)
    r = skelcore.repair(s.cloud, (s.curve_vertices, np.vstack([s.curve_edges, [[0, 16]]])))
    assert r.before.diagnostics.summary["cycles"]["skeleton"] == 2
    assert r.after.diagnostics.summary["cycles"]["skeleton"] == 1
    assert r.curve.n_edges == len(s.curve_edges)
    assert r.log["operations"][0]["why"]["defect"] == "outside"


def test_an_arc_closed_through_the_hole_is_rerouted_round_the_tube():
    """A 140-degree arc closed by a chord through the hole (what cao makes of the bundled torus): deleting
    the chord would lose the tunnel's cycle (rejected, logged); the chord is rerouted inside instead."""
    s = shapes.torus(3000)
    a = np.radians(np.linspace(0, 140, 7))
    v = np.column_stack([np.cos(a), np.sin(a), 0 * a])
    e = np.array([[i, i + 1] for i in range(6)] + [[0, 6]])
    r = skelcore.repair(s.cloud, (v, e))
    assert r.rejected >= 1 and r.log["rejected"][0]["entries"][0]["op"] == "delete_edge"
    assert r.log["rejected"][0]["why"]["rejected"]
    assert r.tally_after["outside"] == 0 and r.after.diagnostics.summary["cycles"]["linked"] == 1
    m0, m1 = r.log["repair"]["measures_before"], r.log["repair"]["measures_after"]
    assert m1["completeness"] > m0["completeness"] + 0.3
    radius = np.linalg.norm(r.curve.vertices[:, :2], axis=1)
    assert np.all(np.abs(radius - 1.0) < 0.2)  # every new vertex inside the tube, none across the hole


def test_the_never_worse_rule_rejects_a_harmful_edit(tube):
    """Cutting half the tube's path away removes no defect and loses completeness: refused."""
    ev = skelcore.evaluate(tube.cloud, curve=(tube.curve_vertices, tube.curve_edges))
    half = CurveSkeleton.from_raw(tube.curve_vertices, tube.curve_edges)
    for v in range(20, 10, -1):
        half, _ = delete_vertex(half, v)
    why = verdict(read_findings(ev), read_findings(ev.update(half)), Params())
    assert why is not None and why.startswith("worse: completeness")
    assert verdict(read_findings(ev), read_findings(ev), Params()).startswith("no progress")


def test_repair_is_cancellable(tube):
    with pytest.raises(Cancelled):
        skelcore.repair(tube.cloud, _twig(tube), cancel=lambda: True)


def test_too_many_components_are_refused(tube):
    v = np.arange(30, dtype=float)[:, None] * [0.0, 0.0, 0.1]
    e = np.array([[i, i + 1] for i in range(0, 30, 2)])
    with pytest.raises(SkelInputError, match="repair_max_components=10"):
        skelcore.repair(tube.cloud, (v, e), params=Params(repair_max_components=10))


@pytest.fixture(scope="module")
def files(tmp_path_factory, tube):
    d = tmp_path_factory.mktemp("repair")
    write_points_ply(d / "cloud.ply", tube.cloud)
    v, e = _twig(tube)
    write_curve_ply(d / "twig.ply", v, e)
    write_curve_ply(d / "far.ply", v * 100 + 1000, e)
    write_curve_ply(d / "noedge.ply", v, np.zeros((0, 2), np.int64))
    return d


def test_cli_repairs_and_the_log_replays_with_skelcore_edit(files, capsys):
    d = files
    assert main(["repair", str(d / "cloud.ply"), "--curve", str(d / "twig.ply"), "--out-curve",
                 str(d / "fixed.ply"), "--log", str(d / "fixed.json"), "--quiet"]) == 0
    assert "1 action(s) kept" in capsys.readouterr().out
    assert main(["edit", str(d / "twig.ply"), "--ops", str(d / "fixed.json"), "--out", str(d / "again.ply")]) == 0
    a, b = load_curve(d / "fixed.ply"), load_curve(d / "again.ply")
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.edges, b.edges)


@pytest.mark.parametrize("curve, out, match", [
    ("noedge.ply", "x1.ply", "no edges"),
    ("far.ply", "x2.ply", "another frame"),
    ("twig.ply", "twig.ply", "overwrite"),
    ("twig.ply", "cloud.ply", "overwrite"),
    ("twig.ply", "exists.ply", "exists"),
])
def test_cli_refuses_bad_inputs_in_one_line(files, capsys, curve, out, match):
    d = files
    (d / "exists.ply").write_text("x")
    code = main(["repair", str(d / "cloud.ply"), "--curve", str(d / curve), "--out-curve", str(d / out), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and match in err and err.count("\n") == 1


def test_two_pieces_of_a_tube_are_joined_and_a_broken_ring_closes(tube):
    e = tube.curve_edges[np.any(tube.curve_edges != [9, 10], axis=1)]
    r = skelcore.repair(tube.cloud, (tube.curve_vertices, e))
    assert r.tally_before["components"] == 1 and r.tally_after["components"] == 0
    assert r.log["operations"][0] == {**r.log["operations"][0], "op": "add_edge", "args": {"edge": [9, 10]}}
    s = shapes.torus(3000)
    ring = s.curve_edges[np.any(s.curve_edges != [0, 1], axis=1)]
    r = skelcore.repair(s.cloud, (s.curve_vertices, ring))
    assert r.tally_before["missing_cycles"] == 1 and r.tally_after["missing_cycles"] == 0


def test_the_log_meets_the_edit_log_schema(twig_repair):
    pytest.importorskip("jsonschema")
    from skelcore.io.schemas import validator

    validator("edit_log").validate(json.loads(json.dumps(twig_repair.log)))


def test_repair_is_deterministic_and_reports_progress(tube, twig_repair):
    seen = []
    again = skelcore.repair(tube.cloud, _twig(tube), progress=lambda f, what: seen.append((f, what)))
    assert json.dumps(again.log) == json.dumps(twig_repair.log)
    assert seen[0][0] == 0.0 and seen[-1] == (1.0, "done")


def test_a_tip_through_the_cap_is_cut_back_to_the_shape(tube):
    v = tube.curve_vertices.copy()
    v[20, 2] = 4.6  # the last vertex 0.6 beyond the cap at z = 4
    r = skelcore.repair(tube.cloud, (v, tube.curve_edges))
    assert [o["op"] for o in r.log["operations"]] == ["move_vertex"]
    assert r.curve.vertices[20, 2] == pytest.approx(4.0, abs=0.05)
    assert r.tally_after["outside"] == 0


def test_the_repair_says_where_its_time_went(twig_repair):
    """One first evaluation; one first look per candidate tried, a whole update per candidate that
    passed it (the prune kept), the real-scan checks once at most; no phase has negative seconds."""
    ph = twig_repair.phases
    assert ph["first evaluation"]["n"] == 1 and ph["proposals"]["n"] >= 1
    assert ph["first look"]["n"] == twig_repair.accepted + twig_repair.rejected
    passed = sum(1 for r in twig_repair.log["rejected"] if r["why"].get("defects_after") is not None)
    assert ph["whole update"]["n"] == twig_repair.accepted + passed
    assert ph["scan checks"]["n"] <= 1  # the last Evaluation's, when its update left them out
    assert all(v["cpu"] >= 0.0 for v in ph.values())
