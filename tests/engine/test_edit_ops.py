"""skelcore.edit: each operation's new curve and Change (ids kept or mapped, radii following their
vertices, one-line refusals), the content hash, the edit log (replay, refusals, atomic write, its
schema) and ``skelcore edit`` through the command line."""

from __future__ import annotations

import json

import numpy as np
import pytest

import skelcore.edit as E
from skelcore import CurveSkeleton, SkelInputError
from skelcore.cli import main
from skelcore.io import load_curve, write_curve_ply
from skelcore.io.atomic import release

# 0 - 1 - 2 - 3 with a spur 1 - 4 - 5 and a triangle 2 - 6 - 7 - 2
V = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0], [1, 1, 0], [1, 2, 0], [2, -1, 0], [3, -1, 0]], float)
EDGES = [[0, 1], [1, 2], [2, 3], [1, 4], [4, 5], [2, 6], [6, 7], [2, 7]]


@pytest.fixture
def curve() -> CurveSkeleton:
    return CurveSkeleton.from_raw(V, EDGES, radius=np.arange(8) + 0.5)


def _edges(c: CurveSkeleton) -> set[tuple[int, int]]:
    return {tuple(map(int, e)) for e in c.edges}


def test_delete_vertex_renumbers_and_says_how(curve):
    new, ch = E.delete_vertex(curve, 4)
    assert ch.op == "delete_vertex" and ch.removed == (4,) and ch.id_map.tolist() == [0, 1, 2, 3, -1, 4, 5, 6]
    assert new.n_vertices == 7 and (1, 4) not in {tuple(ch.id_map[list(e)]) for e in curve.edges} - _edges(new)
    np.testing.assert_array_equal(new.vertices, np.delete(V, 4, axis=0))
    np.testing.assert_array_equal(new.radius, np.delete(np.arange(8) + 0.5, 4))
    assert _edges(new) == {(0, 1), (1, 2), (2, 3), (2, 5), (5, 6), (2, 6)}
    assert curve.n_vertices == 8  # pure: the input is untouched


def test_edge_edits_keep_every_id(curve):
    new, ch = E.delete_edge(curve, (3, 2))
    assert ch.args == {"edge": [2, 3]} and _edges(new) == _edges(curve) - {(2, 3)} and new.n_vertices == 8
    new, ch = E.add_edge(curve, (0, 5))
    assert (0, 5) in _edges(new) and ch.id_map.tolist() == list(range(8))
    new, ch = E.split_edge(curve, (0, 1), 0.25)
    assert ch.added == (8,) and np.allclose(new.vertices[8], [0.25, 0, 0]) and np.isclose(new.radius[8], 0.75)
    assert {(0, 8), (1, 8)} <= _edges(new) and (0, 1) not in _edges(new)
    new, ch = E.cut_cycle(curve, (6, 7))
    assert _edges(new) == _edges(curve) - {(6, 7)}


def test_vertex_edits(curve):
    new, ch = E.move_vertex(curve, 5, [1, 3, 0])
    assert ch.moved == (5,) and np.allclose(new.vertices[5], [1, 3, 0]) and np.array_equal(new.edges, curve.edges)
    new, ch = E.add_vertex(curve, [4, 0, 0], attach_to=3, radius=2.0)
    assert ch.added == (8,) and (3, 8) in _edges(new) and new.radius[8] == 2.0 and new.vertex_map[8] == -1
    new, ch = E.merge_vertices(curve, 4, 5)
    assert ch.removed == (5,) and ch.moved == (4,) and np.allclose(new.vertices[4], [1, 1.5, 0])
    assert new.radius[4] == 5.0 and (1, 4) in _edges(new) and new.n_edges == curve.n_edges - 1


def test_prune_branch_by_the_diagnostics_ids(curve):
    from skelcore.diagnostics.branches import decompose_branches

    b = decompose_branches(curve)
    spur = next(i for i, p in enumerate(b.paths) if set(p.tolist()) == {1, 4, 5})
    new, ch = E.prune_branch(curve, spur)
    assert ch.op == "prune_branch" and ch.removed == (4, 5) and new.n_vertices == 6  # junction 1 stays
    assert ch.id_map.tolist() == [0, 1, 2, 3, -1, -1, 4, 5]
    assert E.delete_branch(curve, spur)[1].op == "delete_branch"


@pytest.mark.parametrize("op, args, message", [
    ("delete_vertex", {"vertex": 8}, "vertex id 8 out of range for 8 vertices"),
    ("delete_vertex", {"vertex": True}, "must be an integer"),
    ("delete_edge", {"edge": [0, 3]}, "(0, 3) is not an edge"),
    ("add_edge", {"edge": [0, 1]}, "already an edge"),
    ("add_edge", {"edge": [2, 2]}, "joins a vertex to itself"),
    ("split_edge", {"edge": [0, 1], "t": 1.0}, "strictly between 0 and 1"),
    ("cut_cycle", {"edge": [0, 1]}, "lies on no cycle"),
    ("prune_branch", {"branch": 99}, "out of range"),
    ("move_vertex", {"vertex": 0, "position": [0, "x", 0]}, "three"),
    ("teleport", {}, "unknown operation 'teleport'"),
    ("delete_edge", {"edge": [0, 1], "why": 1}, "unknown why"),
])
def test_bad_arguments_are_one_line_input_errors(curve, op, args, message):
    with pytest.raises(SkelInputError, match=None) as err:
        E.apply(curve, {"op": op, "args": args})
    assert message in str(err.value) and "\n" not in str(err.value)


def test_an_edit_that_leaves_nothing_is_refused():
    c = CurveSkeleton.from_raw([[0, 0, 0], [1, 0, 0]], [[0, 1]])
    for fn, arg in ((E.delete_edge, (0, 1)), (E.delete_vertex, 0), (E.prune_branch, 0)):
        with pytest.raises(SkelInputError, match="would leave the curve without"):
            fn(c, arg)


def test_content_hash_is_of_the_bytes(curve):
    import hashlib

    expected = hashlib.sha256(V.astype("<f8").tobytes() + curve.edges.astype("<i8").tobytes()).hexdigest()
    assert E.content_hash(curve) == expected
    assert E.content_hash(E.move_vertex(curve, 0, [0, 0, 1e-9])[0]) != expected


def test_the_log_replays_refuses_and_validates(curve, tmp_path):
    steps = [E.prune_branch(curve, 0)]
    steps.append(E.split_edge(steps[-1][0], tuple(steps[-1][0].edges[0])))
    log = E.new_log(curve, [ch for _, ch in steps])
    path = tmp_path / "edits.json"
    E.write_log(path, log)
    again, changes = E.replay(curve, E.read_log(path))
    assert np.array_equal(again.vertices, steps[-1][0].vertices) and [c.op for c in changes] == [
        "prune_branch", "split_edge"]
    with pytest.raises(SkelInputError, match="made for another skeleton"):
        E.replay(steps[0][0], log)
    bad = dict(log, operations=[{"op": "delete_vertex", "args": {"vertex": 50}}])
    with pytest.raises(SkelInputError, match="operation 0 .*out of range"):
        E.replay(curve, bad)
    with pytest.raises(SkelInputError, match="refusing to overwrite an input"):
        E.write_log(path, log, inputs=[path])
    jsonschema = pytest.importorskip("jsonschema")
    from skelcore.io.schemas import validator

    validator("edit_log").validate(json.loads(path.read_text()))
    with pytest.raises(jsonschema.ValidationError):
        validator("edit_log").validate(dict(log, skeleton_hash="abc"))


def test_cli_edit_replays_and_refuses(curve, tmp_path, capsys):
    src, ops, out = tmp_path / "c.ply", tmp_path / "ops.json", tmp_path / "new.ply"
    write_curve_ply(src, curve.vertices, curve.edges)
    loaded = load_curve(src)
    E.write_log(ops, E.new_log(loaded, [E.delete_edge(loaded, (6, 7))[1]]))
    assert main(["edit", str(src), "--ops", str(ops), "--out", str(out)]) == 0
    assert _edges(load_curve(out)) == _edges(curve) - {(6, 7)}
    capsys.readouterr()
    wrong = tmp_path / "wrong.json"
    E.write_log(wrong, E.new_log(load_curve(out), [{"op": "delete_vertex", "args": {"vertex": 0}}]))
    release(out)  # loading protected it in this process; a new one would find it there
    unknown = tmp_path / "unknown.json"
    E.write_log(unknown, E.new_log(loaded, [{"op": "explode", "args": {}}]))
    far = tmp_path / "far.json"
    E.write_log(far, E.new_log(loaded, [{"op": "delete_edge", "args": {"edge": [0, 80]}}]))
    for log, target, says in ((ops, out, "exists"), (ops, src, "input"), (wrong, tmp_path / "a.ply", "another skeleton"),
                              (unknown, tmp_path / "b.ply", "unknown operation"),
                              (far, tmp_path / "c2.ply", "out of range")):
        assert main(["edit", str(src), "--ops", str(log), "--out", str(target)]) == 2
        err = capsys.readouterr().err.strip()
        assert says in err and len(err.splitlines()) == 1, err
        assert str(target if says in ("exists", "input") else log) in err, err  # the file at fault is named
    assert not (tmp_path / "a.ply").exists()
